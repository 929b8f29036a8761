//! Alignment by synthesis: a transcript in any language eSpeak NG speaks, timed on a recording
//! of it without a recogniser (the approach of aeneas).
//!
//! 1. eSpeak NG speaks the transcript in the recording's language ([`faceanim_espeak_sys`]),
//!    which gives its phones (IPA) and when each is said in that spoken version;
//! 2. both sounds become the same features — 12 cepstra every 10 ms, normalised over each
//!    recording (so that the voices' own colour cancels), their change, and loudness; the
//!    recording's are heard through an adult's vocal tract, a child's and a deeper one, and
//!    the one it follows a rendition clearly most sharply through is kept;
//! 3. dynamic time warping finds the cheapest path between the two (a band around the
//!    diagonal bounds the work; a diagonal step costs what the others do, which keeps the two
//!    voices moving together; a recording of minutes is warped coarse to fine, so that its
//!    length never costs it its transcript);
//! 4. each phone's start in the spoken version is carried along the path onto the recording,
//!    and stretches where the recording is quiet for a while become silence.
//!
//! Recognition needs no model of the language: what eSpeak NG can say, this can time.

use faceanim_espeak_sys::{PAUSE, Spoken};

use crate::audio::{SAMPLE_RATE, Sound};
use crate::features::{CEPSTRA, Frontend, HOP, WINDOW};
use crate::phones::{Phone, PhoneError};
use crate::visemes::{LONG_PAUSE, is_held_stop, is_stop};

/// Features per frame: cepstra, their change, loudness.
const DIMS: usize = 2 * CEPSTRA + 1;
/// The band's half-width as a share of the longer recording's frames, and its bounds.
const BAND_SHARE: f32 = 0.3;
const BAND_MIN: usize = 60;
/// The most cells one warping visits (about 200 MB of path at one byte each): a line of
/// dialogue needs a tiny part of it; a longer recording is warped coarse to fine.
const MAX_CELLS: usize = 200_000_000;
/// A quiet stretch at least this long inside a phone's time is a pause, not a stop closure.
const PAUSE_SECONDS: f32 = 0.15;

/// The phones of `text` timed on `sound`, spoken as `language` (an eSpeak NG voice: `en-us`,
/// `es`, `ja`, …) says them; labels are IPA, pauses `SIL`.
///
/// # Errors
/// [`PhoneError::Synthesis`] when eSpeak NG is missing or does not know the language. A
/// recording of any length is aligned (minutes or an hour: warped coarse to fine).
pub fn align(sound: &Sound, text: &str, language: &str) -> Result<Vec<Phone>, PhoneError> {
    timed_by_synthesis(sound, &sound.voice_activity(), text, language, false).map(|t| t.phones)
}

/// A transcript's phones timed by synthesis ([`align`]), and how sharply the synthesiser's
/// own rendition matched the recording along the warping.
#[derive(Debug, Clone)]
pub(crate) struct Timed {
    /// The phones, IPA; pauses `SIL`. Empty when either sound holds no speech.
    pub(crate) phones: Vec<Phone>,
    /// How far the frames of the recording a few frames either side of the warping path are
    /// from the rendition's, against the frames on it ([`sharpness`]); 0 with no speech.
    pub(crate) sharpness: f32,
    /// How many times as many frames of voice the recording holds as the rendition: about 1
    /// for a transcript that says the whole recording (more for a slow speaker), 2 or more for
    /// one that says half of it; 0 with no speech.
    pub(crate) voice_ratio: f32,
}

/// [`align`], with the warping's [`sharpness`]; `voiced` is `sound`'s
/// [`Sound::voice_activity`]. The transcript is spoken in each of `language`'s [`accents`],
/// each in a man's and a woman's register; the recording is heard through each of
/// [`HEARD_THROUGH`]'s vocal tracts, and is timed through an adult's unless it follows a
/// rendition [`SHARPER`] times as sharply through another. There, the accent whose renditions the recording
/// follows most sharply times it, through its own voice's rendition, and the sharpest of them
/// all says how closely the recording follows a synthesiser's voice. Without `judged` (where
/// nothing asks that), no woman's register is spoken.
pub(crate) fn timed_by_synthesis(
    sound: &Sound,
    voiced: &[bool],
    text: &str,
    language: &str,
    judged: bool,
) -> Result<Timed, PhoneError> {
    // The recording's side of every warping, read once per vocal tract: the first frame of its
    // speech, and its speech's features (only speech is warped onto speech: the silence a
    // recording starts and ends with is its own, however long). Loudness is the same through
    // every tract, so where its speech lies is too.
    let plain = Frontend::cepstra(&sound.samples);
    let span = speech(&plain);
    let recordings: Vec<Recording> = HEARD_THROUGH
        .iter()
        .enumerate()
        .map(|(k, &warp)| Recording {
            warp,
            speech: span.map(|span| {
                if k == ADULT {
                    Speech::within(&plain, span)
                } else {
                    Speech::within(&Frontend::cepstra_heard_through(&sound.samples, warp), span)
                }
            }),
        })
        .collect();
    // Every rendition: each accent's own, and its woman's register as a judge.
    let mut renditions = Vec::new();
    for accent in accents(language) {
        let own = render(text, &accent)?;
        let judge = if judged && !accent.contains('+') {
            // Only a judge: an install without the variant times the line as before.
            render(text, &format!("{accent}+{WOMAN}")).ok()
        } else {
            None
        };
        renditions.push((accent, own, judge));
    }
    // Each recording warped onto every rendition: each accent's own and its judge.
    let mut follows: Vec<Vec<(Option<Followed>, Option<Followed>)>> = recordings
        .iter()
        .map(|recording| {
            renditions
                .iter()
                .map(|(_, own, judge)| {
                    let speech = recording.speech.as_ref();
                    let judged = judge
                        .as_ref()
                        .and_then(|j| follow(speech, j.speech.as_ref()));
                    (follow(speech, own.speech.as_ref()), judged)
                })
                .collect()
        })
        .collect();
    // The vocal tract the recording follows a rendition most sharply through: an adult's
    // unless another is clearly sharper.
    let sharpest = |k: usize| {
        follows[k]
            .iter()
            .flat_map(|(own, judge)| [own, judge])
            .flatten()
            .map(|f| f.sharpness)
            .fold(0.0f32, f32::max)
    };
    let adults = sharpest(ADULT);
    let (mut chosen, mut best_sharpness) = (ADULT, adults);
    for (k, candidate) in recordings.iter().enumerate() {
        let sharpness = sharpest(k);
        tracing::debug!(
            warp = candidate.warp,
            sharpness,
            "the recording heard through a vocal tract"
        );
        if sharpness > best_sharpness.max(adults * SHARPER) {
            (chosen, best_sharpness) = (k, sharpness);
        }
    }
    let (recording, warp) = (recordings[chosen].speech.as_ref(), recordings[chosen].warp);
    let mut best: Option<Timed> = None;
    for ((accent, own, _), (own_followed, judge_followed)) in
        renditions.iter().zip(std::mem::take(&mut follows[chosen]))
    {
        let mut timed = timed_by(sound, recording, voiced, own, own_followed)?;
        tracing::debug!(voice = %accent, warp, sharpness = timed.sharpness, "a rendition of the transcript");
        if let Some(other) = judge_followed {
            tracing::debug!(voice = %format!("{accent}+{WOMAN}"), sharpness = other.sharpness, "a rendition of the transcript");
            timed.sharpness = timed.sharpness.max(other.sharpness);
        }
        if best.as_ref().is_none_or(|b| timed.sharpness > b.sharpness) {
            best = Some(timed);
        }
    }
    best.ok_or(PhoneError::EmptyTranscript)
}

/// The vocal tracts a recording is heard through when it is timed by synthesis, as multiples
/// of the frequencies of an adult man's resonances ([`Frontend::heard_through`]): a voice
/// deeper than a man's (an effect, a monster's), an adult's, a child's. A woman's voice is
/// followed through an adult's: in English its rendition in a woman's register judges it, and
/// heard through a woman's tract (1.2), eSpeak NG's f2 in Spanish and f3 in German followed
/// their renditions more sharply (1.7 → 2.0, 1.2 → 1.9–2.4) but were timed less exactly
/// (0.984 → 0.968, 0.979 → 0.971).
const HEARD_THROUGH: [f32; 3] = [0.8, 1.0, 1.4];
/// Where the adult's tract is in [`HEARD_THROUGH`].
const ADULT: usize = 1;

/// A recording heard through a vocal tract `warp` times shorter than a man's: its speech
/// (`None` without speech).
struct Recording {
    warp: f32,
    speech: Option<Speech>,
}

/// A sound's speech, the part that is warped: the frame it starts at, and each frame's
/// features from there to its last frame of speech.
struct Speech {
    first: usize,
    features: Vec<[f32; DIMS]>,
}

impl Speech {
    /// The speech of `cepstra` ([`speech`]); `None` without speech.
    fn of(cepstra: &[([f32; CEPSTRA], f32)]) -> Option<Speech> {
        speech(cepstra).map(|span| Speech::within(cepstra, span))
    }

    /// The speech of `cepstra` from the first to the last frame of `span` ([`speech`]).
    fn within(cepstra: &[([f32; CEPSTRA], f32)], (first, last): (usize, usize)) -> Speech {
        let last = last.min(cepstra.len() - 1);
        Speech {
            first,
            features: features(&cepstra[first..=last]),
        }
    }
}

/// How much more sharply a recording must follow a rendition through another vocal tract than
/// through an adult's to be heard through it: a child's voice (eSpeak NG's f2 and m3, pitch
/// and resonances raised 40 %) follows one 2.2–2.7 times as sharply through a child's tract,
/// a deepened one 3.2 times through a deeper tract; a woman's voice in German at most 1.06
/// times through a child's.
const SHARPER: f32 = 1.5;

/// eSpeak NG's variant whose register a woman's voice follows best among its own (chosen on
/// the tuning voices, below): `f1`.
const WOMAN: &str = "f1";

/// The eSpeak NG voices, one per accent, that a transcript in `language` is timed against:
/// the language's own, and for English given without its country (`en`, British in eSpeak NG)
/// American English too. A voice given with its variant (`en-us+f3`) is the only one, in its
/// own register only.
///
/// Why a woman's register as well, and why it only says how sharply the voice is followed
/// (chosen on the tuning voices, `scripts/bench-lipsync.py` with their transcripts): eSpeak
/// NG's f2 follows the default American rendition at a sharpness of 1.6–1.8, under
/// [`crate::recognition`]'s threshold, and was timed by the recogniser (0.865 agreement); its
/// rendition in `+f1` is followed at 2.3–2.7 (`+f3` 1.9, `+f4` 2.0), and timed by synthesis the
/// line reaches 0.991 through the default rendition, 0.986 through `+f1`'s. In Spanish, German,
/// French and Japanese, f2 timed through `+f1` lost 0.002–0.013 against the default's timing.
/// Flite's slt stays at 1.2–1.4 with every rendition, LibriVox readers at 1.2–1.4. The accent
/// matters to the timing: American voices timed through the British rendition reach 0.93–0.95,
/// through the American 0.99.
fn accents(language: &str) -> Vec<String> {
    let mut voices = vec![language.to_owned()];
    if language.eq_ignore_ascii_case("en") {
        voices.push("en-us".to_owned());
    }
    voices
}

/// A rendition of a transcript: what eSpeak NG said, its voice's frames, and its speech
/// (`None` without speech).
struct Rendition {
    spoken: Spoken,
    voice_frames: f32,
    speech: Option<Speech>,
}

/// `text` spoken by eSpeak NG's `voice`.
fn render(text: &str, voice: &str) -> Result<Rendition, PhoneError> {
    let spoken = faceanim_espeak_sys::speak(text, &voice_for(text, voice), None)?;
    if spoken.phones.iter().all(|p| p.ipa == PAUSE) {
        return Err(PhoneError::EmptyTranscript);
    }
    // eSpeak NG speaks at 22,050 Hz: brought to the recording's 16 kHz as a recording is
    // (band-limited, so nothing above 8 kHz folds into the cepstra).
    let synthetic = crate::audio::resample_pcm(&spoken.samples, spoken.sample_rate);
    let speech = Speech::of(&Frontend::cepstra(&synthetic));
    let voice_frames = Sound { samples: synthetic }
        .voice_activity()
        .iter()
        .filter(|&&v| v)
        .count() as f32;
    Ok(Rendition {
        spoken,
        voice_frames,
        speech,
    })
}

/// How a recording follows a rendition: the warping path between their speech, and how
/// sharply it follows.
struct Followed {
    path: Vec<(usize, usize)>,
    sharpness: f32,
}

/// The warping of a recording's speech onto a rendition's, however long ([`warp_any`]);
/// `None` where either has none.
fn follow(recording: Option<&Speech>, rendition: Option<&Speech>) -> Option<Followed> {
    let (theirs, ours) = (&recording?.features, &rendition?.features);
    let path = warp_any(theirs, ours);
    let sharpness = sharpness(&path, theirs, ours);
    Some(Followed { path, sharpness })
}

/// [`timed_by_synthesis`] against one rendition; `recording` is `sound`'s speech, `None`
/// without speech; `followed`, how it follows the rendition ([`follow`]).
fn timed_by(
    sound: &Sound,
    recording: Option<&Speech>,
    voiced: &[bool],
    rendition: &Rendition,
    followed: Option<Followed>,
) -> Result<Timed, PhoneError> {
    let (Some(recording), Some(rendition_speech), Some(Followed { path, sharpness })) =
        (recording, rendition.speech.as_ref(), followed)
    else {
        return Ok(Timed {
            phones: Vec::new(),
            sharpness: 0.0,
            voice_ratio: 0.0,
        });
    };
    let (a0, b0, ours) = (
        recording.first,
        rendition_speech.first,
        &rendition_speech.features,
    );
    let carried = Carried::along(&path, a0, b0, ours.len());
    let phones = timed(&rendition.spoken, sound.seconds(), |ms| {
        carried.on_recording(ms as f32 / 1000.0)
    });
    let heard = voiced.iter().filter(|&&v| v).count() as f32;
    let voice_ratio = heard / rendition.voice_frames.max(1.0);
    Ok(Timed {
        phones: carve_pauses(phones, voiced),
        sharpness,
        voice_ratio,
    })
}

/// A warping path between a recording's speech (from its frame `a0`) and a rendition's (from
/// `b0`), as a map of the rendition's times onto the recording's.
struct Carried {
    /// Where each frame of the rendition's speech starts on the recording's.
    first: Vec<usize>,
    a0: usize,
    b0: usize,
}

impl Carried {
    fn along(path: &[(usize, usize)], a0: usize, b0: usize, frames: usize) -> Carried {
        let mut first = vec![usize::MAX; frames];
        for &(i, j) in path {
            first[j] = first[j].min(i);
        }
        Carried { first, a0, b0 }
    }

    /// The recording's time, seconds, for the rendition's `seconds` (before its speech, as
    /// far before the recording's).
    fn on_recording(&self, seconds: f32) -> f32 {
        let j = frame_of(seconds);
        if j < self.b0 {
            return time_of(self.a0) - time_of(self.b0 - j) + time_of(0);
        }
        let j = (j - self.b0).min(self.first.len() - 1);
        time_of(self.a0 + self.first[j])
    }
}

/// Where a recording passes from one of a transcript's `pieces` to the next, seconds (one
/// fewer than the pieces, in order): each piece spoken by eSpeak NG's `voice` in turn, the
/// recording warped onto them all ([`warp_any`]), each seam between two renditions carried
/// onto the recording and moved to the middle of the longest pause within [`SEAM_REACH`]
/// (`voiced`: [`Sound::voice_activity`]), where a reader pauses between sentences. `None`
/// where either sound holds no speech.
///
/// # Errors
/// [`PhoneError::Synthesis`] when eSpeak NG cannot speak a piece.
pub(crate) fn seams(
    sound: &Sound,
    voiced: &[bool],
    pieces: &[String],
    voice: &str,
) -> Result<Option<Vec<f32>>, PhoneError> {
    let mut samples = Vec::new();
    let mut ends = Vec::with_capacity(pieces.len());
    let mut rate = SAMPLE_RATE;
    for piece in pieces {
        let spoken = faceanim_espeak_sys::speak(piece, &voice_for(piece, voice), None)?;
        rate = spoken.sample_rate;
        samples.extend_from_slice(&spoken.samples);
        ends.push(samples.len() as f32 / rate as f32);
    }
    let rendition = Speech::of(&Frontend::cepstra(&crate::audio::resample_pcm(
        &samples, rate,
    )));
    let recording = Speech::of(&Frontend::cepstra(&sound.samples));
    let (Some(rendition), Some(recording)) = (rendition, recording) else {
        return Ok(None);
    };
    let path = warp_any(&recording.features, &rendition.features);
    let carried = Carried::along(
        &path,
        recording.first,
        rendition.first,
        rendition.features.len(),
    );
    let mut seams: Vec<f32> = Vec::with_capacity(pieces.len());
    for &end in &ends[..ends.len().saturating_sub(1)] {
        let at = in_a_pause(carried.on_recording(end), voiced);
        let after = seams.last().copied().unwrap_or(0.0);
        seams.push(at.clamp(after, sound.seconds()));
    }
    Ok(Some(seams))
}

/// How far from where the warping puts a seam between two pieces a pause is looked for,
/// seconds.
const SEAM_REACH: f32 = 0.75;

/// The middle of the longest pause (frames not `voiced`) within [`SEAM_REACH`] of `seconds`;
/// `seconds` where there is none.
fn in_a_pause(seconds: f32, voiced: &[bool]) -> f32 {
    let rate = crate::audio::FRAME_RATE as f32;
    let frame = |t: f32| ((t * rate).round().max(0.0) as usize).min(voiced.len());
    let (from, to) = (frame(seconds - SEAM_REACH), frame(seconds + SEAM_REACH));
    let mut best: Option<(usize, usize)> = None;
    let mut k = from;
    while k < to {
        if voiced[k] {
            k += 1;
            continue;
        }
        let start = k;
        while k < voiced.len() && !voiced[k] {
            k += 1;
        }
        if best.is_none_or(|(a, b)| k - start > b - a) {
            best = Some((start, k));
        }
    }
    best.map_or(seconds, |(a, b)| (a + b) as f32 / 2.0 / rate)
}

/// Frames of the rendition either side of the warping path that [`sharpness`] compares with
/// the one on it.
const BESIDE: [usize; 2] = [8, 15];

/// How sharply `path` matches the recording `a` to the rendition `b`: the mean cepstral
/// distance from each of its recording's frames to the rendition's frames [`BESIDE`] the path
/// (either side, 80 and 150 ms off), over the mean distance to the frames on it. Each voice's
/// own colour is normalised away before this ([`features`]), so it says how closely the sounds
/// follow each other more than how alike the voices sound. eSpeak NG's m3, at another rate than
/// the rendition's (and in a noisy room): 2.8–3.6; its f2 1.6–1.8 and whisperf 1.4–1.6; flite's
/// diphone voices, clean, noisy, raised or lowered, 1.1–1.6; LibriVox readers 1.2–1.3.
fn sharpness(path: &[(usize, usize)], a: &[[f32; DIMS]], b: &[[f32; DIMS]]) -> f32 {
    let cepstral = |i: usize, j: usize| {
        a[i][..CEPSTRA]
            .iter()
            .zip(&b[j][..CEPSTRA])
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f32>()
            .sqrt()
    };
    let (mut on, mut off, mut beside) = (0.0f32, 0.0f32, 0usize);
    for &(i, j) in path {
        on += cepstral(i, j);
        for k in BESIDE {
            for other in [j.checked_sub(k), Some(j + k).filter(|&o| o < b.len())]
                .into_iter()
                .flatten()
            {
                off += cepstral(i, other);
                beside += 1;
            }
        }
    }
    if path.is_empty() || beside == 0 {
        return 0.0;
    }
    let on = on / path.len() as f32;
    let off = off / beside as f32;
    off / on.max(1e-6)
}

/// The phones of `spoken`, each starting where `on_recording` places its start and ending
/// where the next starts (the last at the end of the recording's speech); labels cleaned.
fn timed(spoken: &Spoken, seconds: f32, on_recording: impl Fn(u32) -> f32) -> Vec<Phone> {
    let mut phones: Vec<Phone> = Vec::with_capacity(spoken.phones.len() + 1);
    let owned = closures_owned(spoken);
    let starts: Vec<f32> = owned.iter().map(|&(ms, _)| on_recording(ms)).collect();
    let spoken_end = spoken.samples.len() as f32 * 1000.0 / spoken.sample_rate as f32;
    let end_of_speech = on_recording(spoken_end as u32).min(seconds);
    for (k, phone) in spoken.phones.iter().enumerate() {
        // eSpeak NG marks a switch of language as a phone "(en)": not a sound.
        if phone.ipa.starts_with('(') {
            continue;
        }
        let start = starts[k].clamp(0.0, seconds);
        let end = starts
            .get(k + 1)
            .copied()
            .unwrap_or(end_of_speech)
            .clamp(start, seconds);
        let label = if phone.ipa == PAUSE {
            "SIL".to_owned()
        } else if owned[k].1 && !phone.ipa.contains('ː') {
            // A held stop, marked long as IPA writes it (`tː`).
            format!("{}ː", phone.ipa)
        } else {
            phone.ipa.clone()
        };
        phones.push(Phone { label, start, end });
    }
    if let Some(first) = phones.first()
        && first.start > 0.0
    {
        let start = first.start;
        phones.insert(
            0,
            Phone {
                label: "SIL".into(),
                start: 0.0,
                end: start,
            },
        );
    }
    if let Some(last) = phones.last()
        && last.end < seconds
    {
        let end = last.end;
        phones.push(Phone {
            label: "SIL".into(),
            start: end,
            end: seconds,
        });
    }
    phones.retain(|p| p.end > p.start);
    phones
}

/// The loudest sample (of 32,767) a synthesiser's stop closure holds: eSpeak NG makes the
/// closure of a stop exact silence.
const CLOSED: i32 = 8;
/// The shortest closure that is a held (long, geminate) stop's, milliseconds: eSpeak NG closes
/// a single stop for at most 55 ms (English, Spanish, German, French, Japanese, Korean,
/// Italian, Portuguese, Finnish, Polish, Hindi, Arabic lines), a held one (Italian "latte",
/// Finnish "Pekka", Arabic shadda) for 110–170 ms.
const HELD_MS: u32 = 80;
/// The longest: a silence longer than this before a stop is a pause (eSpeak NG marks its
/// own pauses, and a stop after one is left alone).
const HELD_MOST_MS: u32 = 250;
/// The least of the phone before a stop that keeps its sound, milliseconds.
const KEPT_MS: u32 = 20;

/// When each of `spoken`'s phones starts, milliseconds, with a held stop's closure its own,
/// and whether it is a held stop.
///
/// eSpeak NG reports a stop when its lips or tongue release it, and the silence it held them
/// closed for falls in the phone before: the `a` of Italian "latte" holds the 120 ms closure
/// of its `tː`, and a mouth timed so would stay open through that silence and shut only as
/// the sound returns. A single stop's closure is short enough for the shape's own lead
/// ([`crate::visemes::LEAD`]); a held one ([`HELD_MS`] or longer) starts the stop, as
/// speech is annotated (Festival's and flite's voices time their stops so).
fn closures_owned(spoken: &Spoken) -> Vec<(u32, bool)> {
    let per_ms = spoken.sample_rate as f32 / 1000.0;
    let silent_ms = |ms: u32| {
        let a = (ms as f32 * per_ms) as usize;
        let b = (((ms + 1) as f32 * per_ms) as usize).min(spoken.samples.len());
        a < b
            && spoken.samples[a..b]
                .iter()
                .all(|s| i32::from(*s).abs() <= CLOSED)
    };
    let mut starts: Vec<(u32, bool)> = spoken.phones.iter().map(|p| (p.start_ms, false)).collect();
    for k in 1..spoken.phones.len() {
        let phone = &spoken.phones[k];
        if !is_stop(&phone.ipa) || spoken.phones[k - 1].ipa == PAUSE {
            continue;
        }
        let floor = starts[k - 1].0 + KEPT_MS;
        let mut start = phone.start_ms;
        while start > floor && silent_ms(start - 1) {
            start -= 1;
        }
        if (HELD_MS..=HELD_MOST_MS).contains(&(phone.start_ms - start)) {
            starts[k] = (start, true);
        }
    }
    starts
}

/// Marks as silence every quiet stretch of at least [`PAUSE_SECONDS`] (one flag per 10 ms in
/// `voiced`): the phone it fell in keeps its heard part (a pause the transcript did not mark,
/// or one the voice made longer than the synthesiser did).
fn carve_pauses(phones: Vec<Phone>, voiced: &[bool]) -> Vec<Phone> {
    let shortest = (PAUSE_SECONDS * 100.0).round() as usize;
    // A few frames in from each edge: the ends of the words either side stay theirs.
    let pauses: Vec<(f32, f32, f32)> = crate::audio::runs(voiced, false, shortest)
        .into_iter()
        .map(|r| {
            (
                (r.start + 3) as f32 / 100.0,
                r.end.saturating_sub(3) as f32 / 100.0,
                r.len() as f32 / 100.0,
            )
        })
        .collect();
    let mut out = Vec::with_capacity(phones.len() + 2 * pauses.len());
    for phone in phones {
        let mut rest = Some(phone);
        for &(a, b, seconds) in &pauses {
            let Some(p) = rest.take() else { break };
            // A held stop's closure (Italian "latte": 110–250 ms) is the stop's own.
            let closure = is_held_stop(&p.label) && seconds < LONG_PAUSE;
            if b <= p.start || a >= p.end || p.label == "SIL" || closure {
                rest = Some(p);
                continue;
            }
            if a > p.start {
                out.push(Phone {
                    end: a,
                    ..p.clone()
                });
            }
            out.push(Phone {
                label: "SIL".into(),
                start: a.max(p.start),
                end: b.min(p.end),
            });
            if b < p.end {
                rest = Some(Phone { start: b, ..p });
            }
        }
        out.extend(rest);
    }
    // One silence for a pause that crossed a phone's end.
    out.dedup_by(|next, kept| {
        let merge = next.label == "SIL" && kept.label == "SIL";
        if merge {
            kept.end = next.end;
        }
        merge
    });
    out
}

/// The eSpeak NG voice that reads `text` in `language`. Its Mandarin voice (`cmn`, also
/// named `zh` and `zh-cmn`) turns Chinese characters into numbered pinyin and reads that, as it
/// reads any Latin letters, as English (eSpeak NG 1.51: "妈妈买了" spoken "ma one ma one mei
/// three le five"), so that a line in characters would be aligned to English phones; its pinyin
/// voice, `cmn-latn-pinyin`, reads the characters and pinyin alike as Mandarin. A line holding
/// a Chinese character is read by that voice, with the variant asked for (`zh+f2`).
fn voice_for<'a>(text: &str, language: &'a str) -> std::borrow::Cow<'a, str> {
    let (base, variant) = language
        .split_once('+')
        .map_or((language, None), |(b, v)| (b, Some(v)));
    if crate::chinese::is_mandarin(base) && text.chars().any(crate::script::is_han) {
        let voice = match variant {
            Some(variant) => format!("cmn-latn-pinyin+{variant}"),
            None => "cmn-latn-pinyin".to_owned(),
        };
        tracing::debug!(%voice, "a Mandarin line in characters, spoken by eSpeak NG's pinyin voice");
        std::borrow::Cow::Owned(voice)
    } else {
        std::borrow::Cow::Borrowed(language)
    }
}

/// The first and last frames of speech in `frames`: louder than 30 dB under the loudest.
fn speech(frames: &[([f32; CEPSTRA], f32)]) -> Option<(usize, usize)> {
    let loudest = frames.iter().map(|f| f.1).fold(f32::MIN, f32::max);
    let loud = |f: &&([f32; CEPSTRA], f32)| f.1 > loudest - 30.0;
    let first = frames.iter().position(|f| loud(&f))?;
    let last = frames.iter().rposition(|f| loud(&f))?;
    Some((first, last))
}

/// Each frame's features, normalised over the recording: cepstra to zero mean and unit
/// deviation over its loud frames, their change, and loudness below the loudest frame.
fn features(frames: &[([f32; CEPSTRA], f32)]) -> Vec<[f32; DIMS]> {
    if frames.is_empty() {
        return Vec::new();
    }
    let loudest = frames.iter().map(|f| f.1).fold(f32::MIN, f32::max);
    let loud: Vec<&[f32; CEPSTRA]> = frames
        .iter()
        .filter(|f| f.1 > loudest - 35.0)
        .map(|f| &f.0)
        .collect();
    let n = loud.len().max(1) as f32;
    let mut mean = [0.0f32; CEPSTRA];
    let mut deviation = [0.0f32; CEPSTRA];
    for c in &loud {
        for k in 0..CEPSTRA {
            mean[k] += c[k] / n;
        }
    }
    for c in &loud {
        for k in 0..CEPSTRA {
            deviation[k] += (c[k] - mean[k]).powi(2) / n;
        }
    }
    for d in &mut deviation {
        *d = d.sqrt().max(1e-3);
    }
    let normal: Vec<[f32; CEPSTRA]> = frames
        .iter()
        .map(|(c, _)| std::array::from_fn(|k| (c[k] - mean[k]) / deviation[k]))
        .collect();
    (0..frames.len())
        .map(|t| {
            let before = &normal[t.saturating_sub(1)];
            let after = &normal[(t + 1).min(frames.len() - 1)];
            let mut v = [0.0f32; DIMS];
            v[..CEPSTRA].copy_from_slice(&normal[t]);
            for k in 0..CEPSTRA {
                v[CEPSTRA + k] = (after[k] - before[k]) * 0.5;
            }
            // Silence against speech is the strongest cue a warping has: weigh it well.
            v[DIMS - 1] = ((frames[t].1 - loudest) / 6.0).clamp(-8.0, 0.0);
            v
        })
        .collect()
}

/// The band's half-width for recordings of `n` and `m` frames.
fn band(n: usize, m: usize) -> usize {
    let longer = n.max(m) as f32;
    ((longer * BAND_SHARE) as usize)
        .max(BAND_MIN)
        .max(n.abs_diff(m) + BAND_MIN)
}

/// The cheapest warping path from (0, 0) to the two ends, as (frame of `a`, frame of `b`)
/// pairs in order, within `band` frames of the diagonal ([`warp_within`]).
fn warp(a: &[[f32; DIMS]], b: &[[f32; DIMS]], band: usize) -> Vec<(usize, usize)> {
    let (n, m) = (a.len(), b.len());
    let centre = |i: usize| (i * m) / n.max(1);
    let rows: Vec<(usize, usize)> = (0..n)
        .map(|i| {
            (
                centre(i).saturating_sub(band),
                (centre(i) + band).min(m - 1),
            )
        })
        .collect();
    warp_within(a, b, &rows)
}

/// The warping of `a` onto `b` however long they are: within [`band`] of the diagonal where
/// that is at most [`MAX_CELLS`] cells (every line of dialogue), else coarse to fine, as
/// FastDTW does — both halved (each pair of frames averaged), the halves warped so, and the
/// whole warped again only within [`RADIUS`] frames of that path, so that a recording of
/// minutes or an hour keeps its transcript at a few cells per frame.
fn warp_any(a: &[[f32; DIMS]], b: &[[f32; DIMS]]) -> Vec<(usize, usize)> {
    coarse_to_fine(a, b, MAX_CELLS)
}

/// [`warp_any`], warping within the diagonal's band where that is at most `most` cells.
fn coarse_to_fine(a: &[[f32; DIMS]], b: &[[f32; DIMS]], most: usize) -> Vec<(usize, usize)> {
    let (n, m) = (a.len(), b.len());
    let band = band(n, m);
    if n.saturating_mul(2 * band + 1) <= most || n < 2 || m < 2 {
        return warp(a, b, band);
    }
    let coarse = coarse_to_fine(&halved(a), &halved(b), most);
    warp_within(a, b, &around(&coarse, n, m))
}

/// How far either side of a coarse path, in frames, the finer warping looks ([`warp_any`]):
/// 0.2 s, where the halves' path may have placed a phone a frame or two off.
const RADIUS: usize = 20;

/// Each pair of frames averaged (a last odd frame kept).
fn halved(a: &[[f32; DIMS]]) -> Vec<[f32; DIMS]> {
    a.chunks(2)
        .map(|pair| {
            std::array::from_fn(|k| pair.iter().map(|f| f[k]).sum::<f32>() / pair.len() as f32)
        })
        .collect()
}

/// The columns each of `n` rows may visit around `coarse`, a path between the halves of `n`
/// and `m` frames ([`halved`]): the frames its cells stand for, [`RADIUS`] either side.
/// Every row's range starts and ends no earlier than the row before's, and reaches the next
/// row's start, so a path runs through them from (0, 0) to (`n` − 1, `m` − 1).
fn around(coarse: &[(usize, usize)], n: usize, m: usize) -> Vec<(usize, usize)> {
    let mut rows = vec![(usize::MAX, 0usize); n];
    for &(i, j) in coarse {
        for row in [2 * i, 2 * i + 1].into_iter().filter(|&r| r < n) {
            let (lo, hi) = &mut rows[row];
            *lo = (*lo).min(2 * j);
            *hi = (*hi).max((2 * j + 1).min(m - 1));
        }
    }
    rows.iter()
        .map(|&(lo, hi)| (lo.saturating_sub(RADIUS), (hi + RADIUS).min(m - 1)))
        .collect()
}

/// The cheapest warping path from (0, 0) to the two ends, as (frame of `a`, frame of `b`)
/// pairs in order, row `i` of `a` visiting only the columns of `b` in `rows[i]` (an inclusive
/// range; neither end falls from one row to the next, the first row's holds 0 and the last's
/// `b`'s last frame). Every step costs the distance of the
/// pair it reaches, a diagonal one too: the path keeps both voices moving together unless
/// they clearly part (against a diagonal step weighted twice, as symmetric warping does,
/// phones aligned between flite's voices and eSpeak NG's went from 0.84 to 0.91 within
/// ±40 ms).
fn warp_within(
    a: &[[f32; DIMS]],
    b: &[[f32; DIMS]],
    rows: &[(usize, usize)],
) -> Vec<(usize, usize)> {
    let (n, m) = (a.len(), b.len());
    let distance = |i: usize, j: usize| {
        a[i].iter()
            .zip(&b[j])
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f32>()
            .sqrt()
    };
    // Where each row's cells start in `steps`.
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    for &(l, h) in rows {
        offsets.push(offsets.last().copied().unwrap_or(0) + (h + 1 - l));
    }
    let widest = rows.iter().map(|&(l, h)| h + 1 - l).max().unwrap_or(0);
    let mut previous = vec![f32::INFINITY; widest];
    let mut current = vec![f32::INFINITY; widest];
    // 0: diagonal, 1: from the row above, 2: from the left.
    let mut steps = vec![0u8; offsets[n]];
    let (mut previous_lo, mut previous_hi) = (0usize, 0usize);
    for (i, &(l, h)) in rows.iter().enumerate() {
        current.fill(f32::INFINITY);
        for j in l..=h {
            let d = distance(i, j);
            let above = |jj: usize| -> f32 {
                if i == 0 || jj < previous_lo || jj > previous_hi {
                    f32::INFINITY
                } else {
                    previous[jj - previous_lo]
                }
            };
            let (cost, step) = if i == 0 && j == 0 {
                (d, 0u8)
            } else {
                let diagonal = if j > 0 {
                    above(j - 1) + d
                } else {
                    f32::INFINITY
                };
                let vertical = above(j) + d;
                let horizontal = if j > l {
                    current[j - 1 - l] + d
                } else {
                    f32::INFINITY
                };
                if diagonal <= vertical && diagonal <= horizontal {
                    (diagonal, 0)
                } else if vertical <= horizontal {
                    (vertical, 1)
                } else {
                    (horizontal, 2)
                }
            };
            current[j - l] = cost;
            steps[offsets[i] + (j - l)] = step;
        }
        std::mem::swap(&mut previous, &mut current);
        (previous_lo, previous_hi) = (l, h);
    }
    // Back from the end.
    let mut path = Vec::with_capacity(n + m);
    let (mut i, mut j) = (n - 1, m - 1);
    loop {
        path.push((i, j));
        if i == 0 && j == 0 {
            break;
        }
        match steps[offsets[i] + (j - rows[i].0)] {
            0 if i > 0 && j > 0 => {
                i -= 1;
                j -= 1;
            }
            1 if i > 0 => i -= 1,
            _ if j > 0 => j -= 1,
            _ => i -= 1,
        }
    }
    path.reverse();
    path
}

/// The frame whose window is centred nearest `seconds`.
fn frame_of(seconds: f32) -> usize {
    let centre = WINDOW as f32 / 2.0 / SAMPLE_RATE as f32;
    ((seconds - centre) * SAMPLE_RATE as f32 / HOP as f32)
        .round()
        .max(0.0) as usize
}

/// The centre of frame `k`, seconds.
fn time_of(k: usize) -> f32 {
    (k * HOP) as f32 / SAMPLE_RATE as f32 + WINDOW as f32 / 2.0 / SAMPLE_RATE as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mandarin_line_in_characters_is_read_by_the_pinyin_voice() {
        assert_eq!(voice_for("妈妈每天买面包。", "zh"), "cmn-latn-pinyin");
        assert_eq!(
            voice_for("妈妈每天买面包。", "CMN+f2"),
            "cmn-latn-pinyin+f2"
        );
        assert_eq!(voice_for("ma1 ma1 mai3", "zh"), "zh");
        assert_eq!(voice_for("まいにち", "ja"), "ja");
        assert_eq!(voice_for("妈妈", "yue"), "yue");
    }

    #[test]
    fn a_stretched_copy_warps_onto_its_original() {
        // A ramp of "sounds", and the same ramp with every frame said twice.
        let a: Vec<[f32; DIMS]> = (0..50).map(|k| [k as f32; DIMS]).collect();
        let b: Vec<[f32; DIMS]> = (0..100).map(|k| [(k / 2) as f32; DIMS]).collect();
        let path = warp(&b, &a, band(b.len(), a.len()));
        assert_eq!(path.first(), Some(&(0, 0)));
        assert_eq!(path.last(), Some(&(99, 49)));
        for &(i, j) in &path {
            assert_eq!(i / 2, j, "{path:?}");
        }
    }

    #[test]
    fn a_long_warping_coarse_to_fine_finds_the_banded_one() {
        // Two "recordings" of the same 600 sounds, each held for its own number of frames (a
        // speaker's pace and a synthesiser's), with a little noise of their own.
        let mut seed = 7u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let sounds: Vec<[f32; DIMS]> = (0..600)
            .map(|_| std::array::from_fn(|_| next() * 4.0))
            .collect();
        let mut said = |pace: f32| {
            let mut frames = Vec::new();
            for sound in &sounds {
                for _ in 0..(1 + (next() * pace) as usize) {
                    frames.push(std::array::from_fn(|k| sound[k] + next() * 0.2));
                }
            }
            frames
        };
        let (a, b): (Vec<[f32; DIMS]>, Vec<[f32; DIMS]>) = (said(8.0), said(6.0));
        let banded = warp(&a, &b, band(a.len(), b.len()));
        // Few enough cells that the halves are halved again.
        let fine = coarse_to_fine(&a, &b, a.len() * 50);
        assert!(a.len() > 2000 && b.len() > 1500);
        assert_eq!(fine, banded);
    }

    #[test]
    fn a_held_stops_closure_is_its_own() {
        use faceanim_espeak_sys::PhoneEvent;
        // At 1,000 samples a second: sound, then `silent` ms of zeros before each release.
        let spoken = |phones: &[(&str, u32)], silences: &[(u32, u32)]| {
            let end = phones.last().map_or(0, |p| p.1) + 100;
            let samples = (0..end)
                .map(|ms| {
                    if silences.iter().any(|&(a, b)| (a..b).contains(&ms)) {
                        0
                    } else {
                        1000 * if ms % 2 == 0 { 1 } else { -1 }
                    }
                })
                .collect();
            Spoken {
                samples,
                sample_rate: 1000,
                phones: phones
                    .iter()
                    .map(|&(ipa, start_ms)| PhoneEvent {
                        ipa: ipa.into(),
                        start_ms,
                        word: 0,
                    })
                    .collect(),
                words_ms: vec![0],
            }
        };
        // Italian "latte": the `a` holds 120 ms of the `t`'s closure, which becomes the t's.
        let latte = spoken(
            &[("l", 0), ("a", 60), ("t", 300), ("e", 330)],
            &[(180, 300)],
        );
        let starts = |spoken: &Spoken| -> Vec<u32> {
            closures_owned(spoken).iter().map(|&(ms, _)| ms).collect()
        };
        assert_eq!(
            closures_owned(&latte),
            [(0, false), (60, false), (180, true), (330, false)]
        );
        // A single stop's 40 ms closure stays in the vowel: the shape's lead covers it.
        let lato = spoken(
            &[("l", 0), ("a", 60), ("t", 200), ("o", 230)],
            &[(160, 200)],
        );
        assert_eq!(starts(&lato), [0, 60, 200, 230]);
        // A silence after a pause is the pause's; one too long is a pause eSpeak NG left
        // unmarked; a phone quiet all through keeps its first 20 ms.
        let after_pause = spoken(&[("a", 0), (PAUSE, 100), ("t", 300)], &[(100, 300)]);
        assert_eq!(starts(&after_pause), [0, 100, 300]);
        let long = spoken(&[("a", 0), ("t", 500)], &[(100, 500)]);
        assert_eq!(starts(&long), [0, 500]);
        let quiet = spoken(&[("n", 0), ("ʔ", 150), ("a", 170)], &[(0, 150)]);
        assert_eq!(starts(&quiet), [0, 20, 170]);
        // Only stops own a closure: a silence before an `m` is not moved.
        let m = spoken(&[("a", 0), ("m", 300)], &[(150, 300)]);
        assert_eq!(starts(&m), [0, 300]);
    }

    #[test]
    fn quiet_stretches_inside_phones_become_silence() {
        let phone = |label: &str, start: f32, end: f32| Phone {
            label: label.into(),
            start,
            end,
        };
        // Heard for 0.3 s, quiet for 0.4 s, heard again.
        let voiced: Vec<bool> = (0..100).map(|k| !(30..70).contains(&k)).collect();
        let carved = carve_pauses(vec![phone("a", 0.0, 0.6), phone("b", 0.6, 1.0)], &voiced);
        let labels: Vec<&str> = carved.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["a", "SIL", "b"]);
        assert!(
            carved
                .iter()
                .any(|p| p.label == "SIL" && p.start <= 0.34 && p.end >= 0.6)
        );
        // A short closure (under PAUSE_SECONDS) is left alone.
        let voiced: Vec<bool> = (0..100).map(|k| !(30..38).contains(&k)).collect();
        let kept = carve_pauses(vec![phone("p", 0.0, 1.0)], &voiced);
        assert_eq!(kept.len(), 1);
        // So is a held stop's (0.2 s, under a long pause), but not a vowel's.
        let voiced: Vec<bool> = (0..100).map(|k| !(30..50).contains(&k)).collect();
        let held = carve_pauses(vec![phone("a", 0.0, 0.3), phone("tː", 0.3, 1.0)], &voiced);
        assert_eq!(held.len(), 2);
        let vowel = carve_pauses(vec![phone("a", 0.0, 1.0)], &voiced);
        assert_eq!(vowel.len(), 3);
    }

    #[test]
    fn a_warping_onto_its_own_sound_is_sharper_than_onto_another() {
        // A sound whose frames change steadily, a copy of it with a little noise, and a sound
        // that repeats one frame: the copy's path is far sharper than the dull one's.
        let frame = |k: usize| -> [f32; DIMS] {
            std::array::from_fn(|d| ((k as f32 * 0.37 + d as f32 * 1.3).sin()) * 2.0)
        };
        let a: Vec<[f32; DIMS]> = (0..200).map(frame).collect();
        let copy: Vec<[f32; DIMS]> = (0..200)
            .map(|k| {
                let mut f = frame(k);
                f[0] += ((k * 7919) % 13) as f32 * 0.01;
                f
            })
            .collect();
        let dull: Vec<[f32; DIMS]> = (0..200).map(|_| frame(0)).collect();
        let sharp = sharpness(&warp(&a, &copy, band(200, 200)), &a, &copy);
        let flat = sharpness(&warp(&a, &dull, band(200, 200)), &a, &dull);
        assert!(sharp > 10.0, "{sharp}");
        // Every frame of the dull sound is as far from each of the other's as any: about 1
        // (the path's ends have fewer frames beside them).
        assert!((flat - 1.0).abs() < 0.05, "{flat}");
        assert!(sharpness(&[], &a, &copy).abs() < f32::EPSILON);
    }
}
