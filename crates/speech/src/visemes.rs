//! Phones become visemes (the 15 of Oculus/OpenXR), timed as animators time them:
//!
//! - **anticipation**: the mouth shapes a sound before it is heard — lips close for P/B/M and
//!   bite for F/V [`LIP_LEAD`] early, other shapes [`LEAD`] early; closed lips stay closed
//!   until their release ([`RELEASE`]);
//! - **a minimum hold**: a shape held for less than [`MIN_HOLD`] is not drawn (it would flicker)
//!   — except a P/B/M closure, which always closes the lips, for at least that long;
//! - **pauses**: in a short pause (under [`LONG_PAUSE`]) the mouth relaxes towards rest but
//!   does not close; in a long one it closes, within [`CLOSE`] of the last sound;
//! - **coarticulation**: each shape blends from the previous one over up to [`BLEND`].
//!
//! Only sound is mouthed: a phone the recogniser put where the recording is quiet
//! ([`Sound::voice_activity`](crate::audio::Sound::voice_activity)) is silence, so silence,
//! hum and steady noise give a closed mouth — except a short consonant beside a heard sound,
//! whose quiet is its own (the lips held shut before a P's release, the hold of a T).

use faceanim_rig::names::Viseme;

use crate::phones::Phone;

/// How early most shapes lead their sound, seconds.
pub const LEAD: f32 = 0.04;
/// How early closed lips (P, B, M) and the lip bite (F, V) lead theirs.
pub const LIP_LEAD: f32 = 0.06;
/// The shortest shape drawn, seconds: a frame at 30 fps (shorter ones merge into a neighbour;
/// the blends keep a short one from flickering).
pub const MIN_HOLD: f32 = 0.03;
/// A pause at least this long closes the mouth; a shorter one relaxes it.
pub const LONG_PAUSE: f32 = 0.25;
/// The longest blend from one shape to the next.
pub const BLEND: f32 = 0.08;
/// The longest quiet a consonant makes itself (a stop's closure, a P's lips held shut): one
/// quiet for longer is a pause the recogniser put a consonant in.
pub const CLOSURE: f32 = 0.15;
/// How long the mouth takes to close when the sound stops for a long pause (a speaker's
/// mouth comes to rest within a couple of frames of the last sound).
pub const CLOSE: f32 = 0.05;
/// The shape after closed lips starts forming this long before the lips' release.
pub const RELEASE: f32 = 0.02;
/// How far a short pause relaxes the mouth: the previous shape's weight is kept at this.
pub const RELAXED: f32 = 0.3;

/// The viseme of a phone — ARPAbet (upper case, no stress: the recogniser's) or IPA (any
/// language's: eSpeak NG's) — ; `Sil` for silence and anything unknown.
#[must_use]
pub fn viseme_of(phone: &str) -> Viseme {
    if phone.is_empty() || !phone.bytes().all(|b| b.is_ascii_uppercase()) {
        return viseme_of_ipa(phone);
    }
    match phone {
        "P" | "B" | "M" => Viseme::PP,
        "F" | "V" => Viseme::FF,
        "TH" | "DH" => Viseme::TH,
        "T" | "D" => Viseme::DD,
        "K" | "G" | "NG" => Viseme::Kk,
        "CH" | "JH" | "SH" | "ZH" => Viseme::CH,
        "S" | "Z" => Viseme::SS,
        "N" | "L" => Viseme::Nn,
        "R" | "ER" => Viseme::RR,
        "AA" | "AE" | "AH" | "AY" | "AW" => Viseme::Aa,
        "EH" | "EY" => Viseme::E,
        "IH" | "IY" | "Y" => Viseme::Ih,
        "AO" | "OW" | "OY" => Viseme::Oh,
        "UH" | "UW" | "W" => Viseme::Ou,
        // HH takes the shape of the vowel it breathes into (see `segments`).
        _ => Viseme::Sil,
    }
}

/// Whether a viseme is a vowel's (open, spread or round).
#[must_use]
pub fn is_vowel(viseme: Viseme) -> bool {
    matches!(
        viseme,
        Viseme::Aa | Viseme::E | Viseme::Ih | Viseme::Oh | Viseme::Ou
    )
}

/// The label of a stretch where nothing is said, whatever is heard there: between a subtitle's
/// cues (music, effects, another language's dub). A voice heard in a pause (`SIL`) opens the
/// mouth, as a word the recogniser did not make out; heard in this, it does not.
pub const NOTHING_SAID: &str = "NSN";

/// Whether a phone is breath (`HH`, IPA `h`, `ɦ`), which takes the shape of the vowel after it.
#[must_use]
pub fn is_breath(phone: &str) -> bool {
    matches!(phone, "HH" | "h" | "ɦ" | "hʲ" | "ħ")
}

/// Marks an IPA phone carries that do not change the mouth's shape: stress, length, tone,
/// nasality, devoicing, aspiration, syllabicity, tone letters and eSpeak NG's `-`.
fn is_modifier(c: char) -> bool {
    matches!(
        c,
        'ˈ' | 'ˌ'
            | 'ː'
            | 'ˑ'
            | 'ʰ'
            | 'ʲ'
            | 'ʷ'
            | 'ˠ'
            | 'ˤ'
            | '-'
            | '˥'
            | '˦'
            | '˧'
            | '˨'
            | '˩'
            | '\''
    ) || ('\u{0300}'..='\u{036F}').contains(&c)
        || c.is_ascii_digit()
}

/// Whether an IPA phone is a stop (a plosive or an affricate): the lips, the tongue or the
/// glottis closed, then released (ARPAbet's upper-case names are not IPA).
pub(crate) fn is_stop(phone: &str) -> bool {
    phone.starts_with([
        'p', 'b', 't', 'd', 'k', 'g', 'ɡ', 'c', 'ɟ', 'q', 'ʔ', 'ʈ', 'ɖ',
    ])
}

/// What eSpeak NG 1.51 writes for a phoneme it has no IPA for. On the bench's lines in 19
/// languages (`scripts/bench-lipsync.py`) and a few more in Dutch and the Scandinavian
/// languages, only German's `UR` (`ʊɐ̯`, the vowel of "wurde", "durch", "Turm") is written
/// so; read as a pause, it shut the mouth inside those words.
pub const UNWRITTEN: &str = "??";

/// Whether an IPA phone is a held (long, geminate) stop, marked long (`tː` of Italian
/// "latte", `kː` of Finnish "Pekka"): its closure, silent, lasts two or three times a single
/// stop's.
pub(crate) fn is_held_stop(phone: &str) -> bool {
    is_stop(phone) && phone.contains('ː')
}

/// The viseme of an IPA phone, by how it is articulated: the place of a consonant (lips,
/// lip and teeth, teeth, tongue tip, the back of the tongue, palate), the height, backness and
/// rounding of a vowel (a diphthong by the vowel it starts from). Affricates go by their
/// release (`tʃ` as `ʃ`, `ts` as `s`); Spanish `β` (a `b` between vowels) brings the lips
/// together as `b` does, Japanese `ɸ` (`fu`) only narrows them, as `f` does.
///
/// eSpeak NG writes one phoneme of its German as `??` ([`UNWRITTEN`]): the `ur` of "wurde",
/// "durch", "Sturm" (its `UR`, `ʊɐ̯`), a rounded vowel.
#[must_use]
pub fn viseme_of_ipa(phone: &str) -> Viseme {
    let sound: String = phone.chars().filter(|c| !is_modifier(*c)).collect();
    if sound == UNWRITTEN {
        return Viseme::Ou;
    }
    let mut chars = sound.chars();
    let Some(first) = chars.next() else {
        return Viseme::Sil;
    };
    let second = chars.next();
    let class = |c: char| match c {
        'p' | 'b' | 'm' | 'ɓ' | 'ʙ' | 'β' => Viseme::PP,
        'f' | 'v' | 'ɱ' | 'ʋ' | 'ɸ' => Viseme::FF,
        'θ' | 'ð' => Viseme::TH,
        't' | 'd' | 'ʈ' | 'ɖ' | 'ɗ' | 'c' | 'ɟ' => Viseme::DD,
        'n' | 'ɳ' | 'ɲ' | 'l' | 'ɭ' | 'ʎ' | 'ɫ' | 'ɬ' | 'ɮ' | 'ʟ' | 'ɺ' => Viseme::Nn,
        'k' | 'g' | 'ɡ' | 'ŋ' | 'q' | 'ɢ' | 'x' | 'ɣ' | 'χ' | 'ʁ' | 'ɰ' | 'ʔ' | 'ʕ' | 'ɴ' => {
            Viseme::Kk
        }
        'ʃ' | 'ʒ' | 'ɕ' | 'ʑ' | 'ʂ' | 'ʐ' | 'ç' | 'ʝ' => Viseme::CH,
        's' | 'z' => Viseme::SS,
        'r' | 'ɾ' | 'ɹ' | 'ɻ' | 'ɽ' | 'ʀ' | 'ɚ' | 'ɝ' => Viseme::RR,
        'a' | 'ɑ' | 'ɐ' | 'æ' | 'ä' | 'ɶ' | 'ʌ' | 'ə' | 'ᵻ' => Viseme::Aa,
        'e' | 'ɛ' | 'ɜ' | 'ɘ' | 'ɤ' => Viseme::E,
        'i' | 'ɪ' | 'ɨ' | 'j' => Viseme::Ih,
        'o' | 'ɔ' | 'ɒ' | 'ɵ' | 'ø' | 'œ' => Viseme::Oh,
        'u' | 'ʊ' | 'ʉ' | 'y' | 'ʏ' | 'ɯ' | 'w' | 'ʍ' | 'ɥ' => Viseme::Ou,
        _ => Viseme::Sil,
    };
    match (first, second.map(class)) {
        // Affricates: a stop released into a fricative looks like the fricative.
        ('t' | 'd' | 'ʈ' | 'ɖ', Some(release @ (Viseme::CH | Viseme::SS))) => release,
        _ => class(first),
    }
}

/// A viseme's index in [`Viseme::ALL`].
#[must_use]
pub fn index(viseme: Viseme) -> usize {
    Viseme::ALL.iter().position(|v| *v == viseme).unwrap_or(0)
}

/// One shape held from `start` (the moment it is fully formed) until the next shape starts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Key {
    /// Seconds.
    pub start: f32,
    /// Which viseme (`Sil`: the mouth at rest or closed).
    #[serde(serialize_with = "viseme_name")]
    pub viseme: Viseme,
    /// How strongly, 0..1 (a relaxed pause keeps the previous shape weakly).
    pub weight: f32,
}

fn viseme_name<S: serde::Serializer>(v: &Viseme, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(v.name())
}

/// Visemes over time.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Track {
    /// Keys in time order.
    pub keys: Vec<Key>,
    /// The sound's length, seconds.
    pub seconds: f32,
}

/// The shortest voice heard inside a silence the recogniser found that opens the mouth,
/// seconds: longer than a click or a breath's edge, shorter than a syllable.
pub const UNMADE_OUT: f32 = 0.12;

/// Where `p` is heard (per `voiced`, one flag per 10 ms) for at least `shortest` seconds in a
/// row: (start, end) in seconds.
fn heard_stretches(p: &Phone, voiced: &[bool], shortest: f32) -> Vec<(f32, f32)> {
    let first = p.first_frame(voiced.len());
    let time = |f: usize| ((first + f) as f32 / 100.0).clamp(p.start, p.end);
    let frames = (shortest * 100.0).round() as usize;
    crate::audio::runs(p.frames(voiced), true, frames)
        .into_iter()
        .map(|r| (time(r.start), time(r.end)))
        .collect()
}

/// The visemes of `phones`, heard where `voiced` (one flag per 10 ms) says, in a sound of
/// `seconds`.
#[must_use]
pub fn track(phones: &[Phone], voiced: &[bool], seconds: f32) -> Track {
    // Phone by phone: its viseme, silenced where nothing is heard.
    let heard = |p: &Phone| {
        let frames = p.frames(voiced);
        frames.iter().filter(|v| **v).count() * 3 >= frames.len().max(1)
    };
    // How long a phone is quiet, seconds.
    let quiet = |p: &Phone| p.frames(voiced).iter().filter(|v| !**v).count() as f32 / 100.0;
    // A consonant is often quiet itself — the lips of a P held shut, the hold of a T — and is
    // said when a sound beside it is heard: a phone, or a voice the recogniser heard as
    // silence (mouthed below; a closure found inside such a silence lies between two).
    // A held stop's closure (Italian "latte", Finnish "Pekka") lasts longer than a single
    // one's: between two heard sounds, a quiet up to a long pause is its own.
    let said = |k: usize| {
        let p = &phones[k];
        let viseme = viseme_of(&p.label);
        let before = k.checked_sub(1).is_some_and(|j| heard(&phones[j]));
        let after = phones.get(k + 1).is_some_and(heard);
        heard(p)
            || (viseme != Viseme::Sil
                && !is_vowel(viseme)
                && (quiet(p) <= CLOSURE && (before || after)
                    || is_held_stop(&p.label) && quiet(p) < LONG_PAUSE && before && after))
    };
    let mut runs: Vec<(Viseme, f32, f32)> = Vec::new();
    let mut extend = |viseme: Viseme, start: f32, end: f32| {
        let empty = runs.is_empty();
        match runs.last_mut() {
            Some(last) if last.0 == viseme => last.2 = end,
            _ if end > start || empty => runs.push((viseme, start, end)),
            _ => {}
        }
    };
    for (k, p) in phones.iter().enumerate() {
        if p.label == NOTHING_SAID {
            extend(Viseme::Sil, p.start, p.end);
            continue;
        }
        if viseme_of(&p.label) == Viseme::Sil && !is_breath(&p.label) {
            // A voice heard where the recogniser found silence (a word it did not make out: a
            // formant synthesiser, a whisper, a name out of its vocabulary) still moves the
            // mouth: each stretch heard for long enough opens it; the rest stays at rest.
            let mut at = p.start;
            for (a, b) in heard_stretches(p, voiced, UNMADE_OUT) {
                extend(Viseme::Sil, at, a);
                extend(Viseme::Aa, a, b);
                at = b;
            }
            extend(Viseme::Sil, at, p.end);
            continue;
        }
        let mut viseme = if said(k) {
            viseme_of(&p.label)
        } else {
            Viseme::Sil
        };
        if is_breath(&p.label) && heard(p) {
            viseme = phones
                .get(k + 1)
                .map_or(Viseme::Sil, |next| viseme_of(&next.label));
            if viseme == Viseme::Sil {
                viseme = Viseme::Aa;
            }
        }
        extend(viseme, p.start, p.end);
    }
    // Minimum hold: short shapes merge into the longer neighbour; closures stay, lengthened.
    let mut held: Vec<(Viseme, f32, f32)> = Vec::new();
    for run in runs {
        let short = run.2 - run.1 < MIN_HOLD;
        if short && run.0 != Viseme::PP && run.0 != Viseme::Sil && !held.is_empty() {
            if let Some(last) = held.last_mut() {
                last.2 = run.2;
            }
            continue;
        }
        match held.last_mut() {
            Some(last) if last.0 == run.0 => last.2 = run.2,
            _ => held.push(run),
        }
    }
    let mut closure: Option<f32> = None;
    let mut keys = Vec::with_capacity(held.len() + 1);
    keys.push(Key {
        start: 0.0,
        viseme: Viseme::Sil,
        weight: 1.0,
    });
    for (k, &(viseme, start, end)) in held.iter().enumerate() {
        if viseme == Viseme::Sil {
            let previous = keys.last().copied();
            if end - start >= LONG_PAUSE || k == 0 || k + 1 == held.len() {
                // A long pause (or before the first or after the last word): close as the
                // sound stops, over [`CLOSE`].
                push(&mut keys, start, Viseme::Sil, 1.0);
            } else if let Some(previous) = previous {
                push(&mut keys, start, previous.viseme, RELAXED * previous.weight);
            }
            continue;
        }
        let lead = if matches!(viseme, Viseme::PP | Viseme::FF) {
            LIP_LEAD
        } else {
            LEAD
        };
        // Short unstressed vowels are not opened fully.
        let weight = if is_vowel(viseme) && end - start < 0.08 {
            0.75
        } else {
            1.0
        };
        // Closed lips open only at their release: what follows a P/B/M starts then.
        let mut begin = (start - lead).max(0.0);
        if let Some(release) = closure.take() {
            begin = begin.max(release - RELEASE);
        }
        push(&mut keys, begin, viseme, weight);
        if viseme == Viseme::PP {
            closure = Some(end);
        }
    }
    Track { keys, seconds }
}

/// Adds a key, keeping keys in order (a key that would start before the last one replaces it
/// from its start).
fn push(keys: &mut Vec<Key>, start: f32, viseme: Viseme, weight: f32) {
    let start = keys.last().map_or(start, |last| start.max(last.start));
    let several = keys.len() > 1;
    if let Some(last) = keys.last_mut()
        && (last.start - start).abs() < 1e-4
        && several
    {
        *last = Key {
            start,
            viseme,
            weight,
        };
        return;
    }
    keys.push(Key {
        start,
        viseme,
        weight,
    });
}

impl Track {
    /// The 15 viseme weights at `time`: the key's shape, blended from the previous key's over
    /// up to [`BLEND`] (half the key's length at most).
    #[must_use]
    pub fn weights_at(&self, time: f32) -> [f32; 15] {
        let mut out = [0.0f32; 15];
        // Keys are in time order: the last one started by `time`, found by halving.
        let Some(k) = self
            .keys
            .partition_point(|key| key.start <= time)
            .checked_sub(1)
        else {
            return out;
        };
        let key = self.keys[k];
        let end = self.keys.get(k + 1).map_or(self.seconds, |n| n.start);
        let longest = if key.viseme == Viseme::Sil && key.weight >= 1.0 {
            CLOSE
        } else {
            BLEND
        };
        let blend = longest.min(0.5 * (end - key.start)).max(1e-3);
        let t = ((time - key.start) / blend).clamp(0.0, 1.0);
        let mut add = |v: Viseme, w: f32| {
            if v != Viseme::Sil {
                out[index(v)] += w;
            }
        };
        add(key.viseme, key.weight * t);
        if k > 0 && t < 1.0 {
            let previous = self.keys[k - 1];
            add(previous.viseme, previous.weight * (1.0 - t));
        }
        out
    }

    /// The weights at `fps` frames per second over the whole sound (one frame more than whole
    /// frames fit, so the clip lasts as long as the sound).
    #[must_use]
    pub fn sample(&self, fps: f32) -> Vec<[f32; 15]> {
        let frames = (self.seconds * fps).ceil() as usize + 1;
        (0..frames)
            .map(|f| self.weights_at(f as f32 / fps))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::phones::tests::phones;

    #[test]
    fn lips_close_early_and_pauses_relax_or_close() {
        // "ma ... pa": a short pause between, a long one after.
        let phones = phones(
            "SIL 0 0.3, M 0.3 0.38, AA 0.38 0.6, SIL 0.6 0.72, P 0.72 0.8, AA 0.8 1, SIL 1 2",
        );
        // Heard while speaking, quiet in the pauses.
        let voiced: Vec<bool> = (0..200)
            .map(|f| (30..60).contains(&f) || (72..100).contains(&f))
            .collect();
        let track = track(&phones, &voiced, 2.0);
        let pp = index(Viseme::PP);
        let aa = index(Viseme::Aa);
        // Closed before the M is heard, and fully closed during it.
        assert!(track.weights_at(0.3)[pp] > 0.5, "{:?}", track.keys);
        assert!(
            track.weights_at(0.35)[pp] > 0.99,
            "{:?} {:?}",
            track.keys,
            track.weights_at(0.35)
        );
        assert!(track.weights_at(0.5)[aa] > 0.99);
        // The short pause relaxes without closing.
        let relaxed = track.weights_at(0.7)[aa];
        assert!(relaxed > 0.1 && relaxed < 0.5, "{relaxed}");
        // The long pause closes.
        assert!(track.weights_at(1.5).iter().all(|w| *w < 1e-6));
        assert_eq!(track.sample(30.0).len(), 61);
    }

    #[test]
    fn a_voice_heard_where_the_recogniser_found_silence_still_moves_the_mouth() {
        // "…" the recogniser did not make out (0.5–1.0 s, heard), a click (1.3–1.35 s, heard
        // for 50 ms) and a real pause (1.5–2 s, quiet), all within its silences.
        let phones = phones("M 0 0.2, AA 0.2 0.5, SIL 0.5 2");
        let voiced: Vec<bool> = (0..200)
            .map(|f| f < 100 || (130..135).contains(&f))
            .collect();
        let track = track(&phones, &voiced, 2.0);
        let aa = index(Viseme::Aa);
        assert!(track.weights_at(0.75)[aa] > 0.9, "{:?}", track.keys);
        assert!(
            track.weights_at(1.32).iter().all(|w| *w < 0.2),
            "{:?}",
            track.keys
        );
        assert!(
            track.weights_at(1.8).iter().all(|w| *w < 1e-6),
            "{:?}",
            track.keys
        );
    }

    #[test]
    fn a_closure_inside_a_voice_heard_as_silence_closes_the_lips() {
        // "…p…" the recogniser heard as one silence, a P's closure found inside it (quiet,
        // 0.45–0.51 s) between two stretches of voice.
        let phones = phones("AA 0 0.3, SIL 0.3 0.45, P 0.45 0.51, SIL 0.51 0.65, AA 0.65 1");
        let voiced: Vec<bool> = (0..100).map(|f| !(45..51).contains(&f)).collect();
        let track = track(&phones, &voiced, 1.0);
        let pp = index(Viseme::PP);
        assert!(track.weights_at(0.49)[pp] > 0.9, "{:?}", track.keys);
        // The same quiet between two silences that are quiet too is a pause, not a P.
        let quiet: Vec<bool> = (0..100).map(|f| !(30..65).contains(&f)).collect();
        let paused = super::track(&phones, &quiet, 1.0);
        assert!(paused.weights_at(0.49)[pp] < 0.1, "{:?}", paused.keys);
    }

    #[test]
    fn a_held_stop_between_two_sounds_holds_its_shape() {
        // Italian "cappa": the held P's lips shut for 0.2 s between two heard vowels.
        let cappa = phones("SIL 0 0.2, k 0.2 0.25, a 0.25 0.4, pː 0.4 0.6, a 0.6 0.9, SIL 0.9 1.5");
        let voiced: Vec<bool> = (0..150)
            .map(|f| (20..90).contains(&f) && !(40..60).contains(&f))
            .collect();
        let held = track(&cappa, &voiced, 1.5);
        let pp = index(Viseme::PP);
        assert!(held.weights_at(0.5)[pp] > 0.9, "{:?}", held.keys);
        // A single stop as quiet is a pause the recogniser put a stop in: the mouth relaxes.
        let capa = phones("SIL 0 0.2, k 0.2 0.25, a 0.25 0.4, p 0.4 0.6, a 0.6 0.9, SIL 0.9 1.5");
        let single = track(&capa, &voiced, 1.5);
        assert!(single.weights_at(0.5)[pp] < 0.1, "{:?}", single.keys);
        // A quiet as long after the last sound is a pause: the mouth closes to rest.
        let at = phones("SIL 0 0.2, AA 0.2 0.4, T 0.4 0.6, SIL 0.6 1.5");
        let voiced: Vec<bool> = (0..150).map(|f| (20..40).contains(&f)).collect();
        let paused = track(&at, &voiced, 1.5);
        assert!(
            paused.weights_at(0.55).iter().all(|w| *w < 0.1),
            "{:?}",
            paused.keys
        );
    }

    #[test]
    fn a_flicker_is_not_drawn_and_the_unheard_is_silence() {
        let phones = phones("AA 0 0.3, T 0.3 0.32, AA 0.32 0.6, S 0.6 1");
        let mut voiced = vec![true; 100];
        voiced[60..].iter_mut().for_each(|v| *v = false);
        let track = track(&phones, &voiced, 1.0);
        assert!(
            track.keys.iter().all(|k| k.viseme != Viseme::DD),
            "{:?}",
            track.keys
        );
        assert!(
            track.keys.iter().all(|k| k.viseme != Viseme::SS),
            "{:?}",
            track.keys
        );
        assert!(track.weights_at(0.9).iter().all(|w| *w < 1e-6));
    }
}
