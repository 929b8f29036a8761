//! The speaker's vocal tract, as the recogniser hears it (vocal tract length normalisation).
//!
//! The US English acoustic model was trained on adults, and hears a voice best whose
//! resonances (formants) lie where an adult man's do: a woman's lie some 15–20 % higher, a
//! child's 30–50 % higher. Recognised as they are, flite's `slt` (a woman) agrees with her
//! phones at 0.87 from the audio alone, and the same lines raised 40 % (a child's voice) at
//! 0.53. A higher voice is therefore heard slowed, every frequency divided by its warp, and
//! read at fewer frames a second with each window as much longer, so that its frames and
//! their times stay the sound's own 10 ms ([`faceanim_sphinx_sys::Search::warped`]).
//!
//! The warp follows the voice's median pitch, which rises with the resonances from man to
//! woman to child: none up to 150 Hz (men), 1.2 from 170 to 250 Hz (women), 1.45 from 290 Hz
//! (children), and in between a ramp, so that a voice near a boundary is not heard one way on
//! one line and another on the next. Chosen on the tuning voices (flite `slt`, `rms`, `awb`;
//! eSpeak NG `en-us` `+m3`, `+f1`, `+f2`, `+f3`, `+f5`; the flite voices raised 40 %): warping
//! a man's voice costs more (`rms` 0.93 → 0.69 at 1.2) than leaving a woman's unwarped does,
//! and a warp that grows on with the pitch through women's voices (as a power of it) suited
//! `slt` but not eSpeak NG's women, whose resonances rise less with their pitch. A whisper
//! has no pitch and is not warped, unless the user says whose tract it is; told or not, it is
//! recognised as a whisper.

use std::borrow::Cow;

use faceanim_sphinx_sys::{
    FRAME_RATE, Recogniser, Search, Segment, SphinxError, Transform, frame_shift,
};

use crate::audio::{SAMPLE_RATE, Sound};

/// The warp of a voice of each median pitch (Hz), linear between them: a man's, a woman's, a
/// child's.
const WARPS: [(f32, f32); 4] = [(150.0, 1.0), (170.0, 1.2), (250.0, 1.2), (290.0, 1.45)];

/// Whose vocal tract the recogniser hears a voice through.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Voice {
    /// As its pitch says: a man's, a woman's or a child's.
    #[default]
    Auto,
    /// This warp: every frequency divided by it (1: as it is; a woman's 1.2, a child's 1.45;
    /// under 1 for a voice deeper than a man's, lowered by an effect, say).
    Warp(f32),
    /// Found by listening: the warp its pitch says, unless the acoustic model hears the voice
    /// clearly better through another (for a voice whose pitch and resonances were moved
    /// together: an effect, a voice changer, a recording played fast or slow). Costs a phone
    /// loop over the line's first seconds at each warp tried
    /// (`faceanim_speech::recognition`'s search).
    Search,
}

impl Voice {
    /// The lowest and highest warp given by hand.
    pub const WARPS: std::ops::RangeInclusive<f32> = 0.6..=1.8;
}

impl std::str::FromStr for Voice {
    type Err = String;

    /// `auto`, `search`, `man` (1), `woman` (1.2), `child` (1.45) or a warp from 0.6 to 1.8.
    fn from_str(text: &str) -> Result<Voice, String> {
        let warp = match text.trim().to_ascii_lowercase().as_str() {
            "auto" => return Ok(Voice::Auto),
            "search" => return Ok(Voice::Search),
            "man" => 1.0,
            "woman" => 1.2,
            "child" => 1.45,
            other => other.parse::<f32>().map_err(|_| {
                format!(
                    "'{text}' is not a voice: auto, search, man, woman, child, or a warp such as 0.8"
                )
            })?,
        };
        if !Voice::WARPS.contains(&warp) {
            return Err(format!(
                "a warp of {warp} is outside {}–{}",
                Voice::WARPS.start(),
                Voice::WARPS.end()
            ));
        }
        Ok(Voice::Warp(warp))
    }
}

/// A sound as the recogniser hears it: slowed by the speaker's warp, and the frame rate that
/// reads it at the sound's own 10 ms frames.
#[derive(Debug)]
pub(crate) struct Heard<'a> {
    samples: Cow<'a, [i16]>,
    frame_rate: u32,
    /// The model adapted to this voice ([`crate::adapt`]), once a first pass has said how.
    adaptation: Option<Transform>,
}

/// The least voice (10 ms frames) without a pitch that is a whisper, not a word too short to
/// find a pitch in.
const WHISPER: usize = 50;

impl<'a> Heard<'a> {
    /// `sound` as it is.
    pub(crate) fn plain(sound: &'a Sound) -> Heard<'a> {
        Heard {
            samples: audible(Cow::Borrowed(&sound.samples)),
            frame_rate: FRAME_RATE,
            adaptation: None,
        }
    }

    /// `sound` heard as `hearing` decided (for this sound: [`Hearing::of`]).
    pub(crate) fn as_decided(sound: &'a Sound, hearing: Hearing) -> Heard<'a> {
        Heard::warped(sound, hearing.frame_rate)
    }

    /// `sound` slowed to about `frame_rate / 100` of its speed, every frequency divided as
    /// much ([`slowed_rate`]), so that each of the recogniser's frames at `frame_rate` is
    /// 10 ms of the sound.
    pub(crate) fn warped(sound: &'a Sound, frame_rate: u32) -> Heard<'a> {
        if frame_rate == FRAME_RATE {
            return Heard::plain(sound);
        }
        Heard {
            samples: audible(Cow::Owned(sound.played_at(slowed_rate(frame_rate)).samples)),
            frame_rate,
            adaptation: None,
        }
    }

    /// Whether this sound is decoded by a model adapted to its voice.
    pub(crate) fn is_adapted(&self) -> bool {
        self.adaptation.is_some()
    }

    /// This sound decoded from now on by the model adapted with `adaptation`.
    pub(crate) fn adapted(self, adaptation: Option<Transform>) -> Heard<'a> {
        Heard { adaptation, ..self }
    }

    /// The samples the recogniser reads.
    pub(crate) fn samples(&self) -> &[i16] {
        &self.samples
    }

    /// The frames a second the recogniser reads [`Heard::samples`] at.
    pub(crate) fn frame_rate(&self) -> u32 {
        self.frame_rate
    }

    /// How much longer a vocal tract than the acoustic model's the sound is heard through: 1
    /// for a sound heard as it is, 1.2 for a woman's voice.
    pub(crate) fn warp(&self) -> f32 {
        FRAME_RATE as f32 / self.frame_rate as f32
    }

    /// The sound decoded with `search` (read at this sound's frame rate), by `loaded` where
    /// it was loaded for this search at this sound's frame rate, else by a recogniser loaded
    /// now. Segments' frames are the sound's 10 ms frames.
    pub(crate) fn decode(
        &self,
        search: Search,
        loaded: Option<Loaded>,
    ) -> Result<Vec<Segment>, SphinxError> {
        let mut recogniser = self.recogniser(search, loaded)?;
        if let Some(adaptation) = &self.adaptation {
            recogniser.adapt(adaptation)?;
        }
        recogniser.decode(&self.samples)
    }

    /// `loaded` where it was loaded for this sound's frame rate, else `search`'s recogniser
    /// loaded now.
    pub(crate) fn recogniser(
        &self,
        search: Search,
        loaded: Option<Loaded>,
    ) -> Result<Recogniser, SphinxError> {
        match loaded {
            Some(Loaded {
                recogniser,
                frame_rate,
            }) if frame_rate == self.frame_rate => Ok(recogniser),
            _ => Recogniser::load(&search.warped(self.frame_rate)),
        }
    }
}

/// How the recogniser hears a voice, decided once per sound: the frame rate its warp reads
/// it at, and whether it is a whisper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Hearing {
    /// Frames a second: [`FRAME_RATE`] for a voice heard as it is, fewer for a longer tract.
    pub(crate) frame_rate: u32,
    /// Whether the voice is heard for at least [`WHISPER`] without a pitch (for any
    /// [`Voice`]).
    pub(crate) whispered: bool,
}

impl Hearing {
    /// How `voice` says `sound` is heard: by hand, or as its pitch says ([`warp`]).
    pub(crate) fn of(sound: &Sound, voice: Voice) -> Hearing {
        // Whether it is whispered is the sound's, whatever tract the user says it has: a
        // whisper told to be a woman's is still recognised by its phones.
        let voiced = sound.voice_activity();
        let pitch = median_pitch(sound, &voiced);
        let whispered = pitch.is_none() && voiced.iter().filter(|&&v| v).count() >= WHISPER;
        let warp = match voice {
            Voice::Warp(warp) if warp.is_finite() => {
                warp.clamp(*Voice::WARPS.start(), *Voice::WARPS.end())
            }
            Voice::Warp(_) => 1.0,
            // The search starts from the pitch's warp (and is made where the recogniser is).
            Voice::Auto | Voice::Search => pitch.map_or(1.0, warp),
        };
        let frame_rate = frame_rate_of(warp);
        tracing::debug!(
            ?pitch,
            warp,
            frame_rate,
            whispered,
            "the voice as the recogniser hears it"
        );
        Hearing {
            frame_rate,
            whispered,
        }
    }
}

/// The rate a sound is played as ([`Sound::played_at`]) to be read at `frame_rate` frames a
/// second 10 ms at a time: each frame moves on by [`frame_shift`] samples of the slowed
/// sound, which must be 160 of the sound's own (16,000 × 160 / 193 = 13,264 for 83 frames a
/// second; within 0.2 s an hour). Played at 160 × `frame_rate` (13,280), a line after 120 s of
/// hiss, heard as a woman's, was placed 0.14 s early (0.12 %, as 193 against 192.77 samples
/// says), and flite's slt reading a paragraph with its transcript fell from 0.94 agreement in
/// its first half minute to 0.49 in its fourth (the bench's Harvard lines read ten times over
/// did not drift; why the one alignment held and the other did not is not known).
pub(crate) fn slowed_rate(frame_rate: u32) -> u32 {
    let shift = frame_shift(frame_rate);
    (SAMPLE_RATE * (SAMPLE_RATE / FRAME_RATE) + shift / 2) / shift
}

/// The frames a second a sound heard through `warp` is read at: a whole number, so that the
/// frames stay exactly 10 ms of the sound.
pub(crate) fn frame_rate_of(warp: f32) -> u32 {
    (FRAME_RATE as f32 / warp).round() as u32
}

/// A recogniser loaded ahead, and the frame rate it reads at: only a sound heard at that
/// rate is decoded by it ([`Heard::decode`]).
#[derive(Debug)]
pub(crate) struct Loaded {
    pub(crate) recogniser: Recogniser,
    pub(crate) frame_rate: u32,
}

/// The shortest run of digital silence (exact zeros) [`audible`] fills, samples: 100 ms.
/// Shorter runs (a synthesiser's stop closures) stay silent.
const DIGITAL_SILENCE: usize = (SAMPLE_RATE / 10) as usize;

/// `samples` with every run of digital silence of [`DIGITAL_SILENCE`] or longer filled with
/// noise of one least significant bit, from a fixed seed (the same sound is always heard
/// alike). The recogniser's features of exact zeros have no energy to take a logarithm of,
/// and throw the running mean it normalises by far off: four lines of an eSpeak NG whisper,
/// each padded with half a second of zeros, were aligned to their transcripts at 0.81
/// agreement unfilled, 0.96 filled.
fn audible(samples: Cow<'_, [i16]>) -> Cow<'_, [i16]> {
    let runs: Vec<(usize, usize)> = {
        let mut runs = Vec::new();
        let mut k = 0;
        while k < samples.len() {
            if samples[k] != 0 {
                k += 1;
                continue;
            }
            let start = k;
            while k < samples.len() && samples[k] == 0 {
                k += 1;
            }
            if k - start >= DIGITAL_SILENCE {
                runs.push((start, k));
            }
        }
        runs
    };
    if runs.is_empty() {
        return samples;
    }
    let mut samples = samples.into_owned();
    let mut state: u32 = 0x9E37_79B9;
    for (start, end) in runs {
        for sample in &mut samples[start..end] {
            // xorshift32: -1, 0 or 1.
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            *sample = (state % 3) as i16 - 1;
        }
    }
    Cow::Owned(samples)
}

/// How much longer a vocal tract than the acoustic model's adult man's a voice of median
/// `pitch` (Hz) has, as [`WARPS`] says.
fn warp(pitch: f32) -> f32 {
    let (first, last) = (WARPS[0], WARPS[WARPS.len() - 1]);
    if !pitch.is_finite() || pitch <= first.0 {
        return first.1;
    }
    if pitch >= last.0 {
        return last.1;
    }
    let k = WARPS
        .iter()
        .position(|w| w.0 >= pitch)
        .unwrap_or(WARPS.len() - 1);
    let ((a, wa), (b, wb)) = (WARPS[k - 1], WARPS[k]);
    wa + (wb - wa) * (pitch - a) / (b - a)
}

/// The lowest and highest pitch looked for, Hz.
const PITCHES: std::ops::RangeInclusive<f32> = 60.0..=500.0;
/// How alike a window must be to itself one period later to be voiced (normalised
/// correlation).
const PERIODIC: f32 = 0.6;
/// Voiced windows needed for a median.
const FEWEST: usize = 10;
/// Voiced windows enough for a median (20 s of voice): a long recording is not read to its end.
const ENOUGH: usize = 1000;

/// The median pitch (Hz) of `sound`'s voiced 40 ms windows, every 20 ms where a voice is
/// heard ([`Sound::voice_activity`]): each window's period is the shortest lag whose normalised
/// correlation comes within 10 % of its best (so the period, not a multiple of it), read at
/// 8 kHz; at most the first [`ENOUGH`] voiced windows. `None` without [`FEWEST`] voiced
/// windows (a whisper, noise, silence).
pub(crate) fn median_pitch(sound: &Sound, voiced: &[bool]) -> Option<f32> {
    const RATE: usize = 8000;
    // Pairs averaged: 8 kHz, enough for any voice's period.
    let samples: Vec<f32> = sound
        .samples
        .chunks_exact(2)
        .map(|pair| (f32::from(pair[0]) + f32::from(pair[1])) / 2.0)
        .collect();
    let window = RATE / 25;
    let hop = RATE / 50;
    let shortest = (RATE as f32 / PITCHES.end()).floor() as usize;
    let longest = (RATE as f32 / PITCHES.start()).ceil() as usize;
    let mut pitches = Vec::new();
    let mut at = 0;
    while at + window + longest <= samples.len() && pitches.len() < ENOUGH {
        // The 10 ms frame at the window's centre.
        let frame = (at + window / 2) * 100 / RATE;
        if voiced.get(frame).copied().unwrap_or(false)
            && let Some(period) = period(
                &samples[at..at + window + longest],
                window,
                shortest..=longest,
            )
        {
            pitches.push(RATE as f32 / period);
        }
        at += hop;
    }
    if pitches.len() < FEWEST {
        return None;
    }
    pitches.sort_by(f32::total_cmp);
    Some(pitches[pitches.len() / 2])
}

/// The period (samples) of the first `window` samples of `x`, among `lags`: the shortest lag
/// whose normalised correlation with the window is a local best within 10 % of the best of
/// all, and at least [`PERIODIC`]; `None` when none is.
fn period(x: &[f32], window: usize, lags: std::ops::RangeInclusive<usize>) -> Option<f32> {
    let head = &x[..window];
    let mean = head.iter().sum::<f32>() / window as f32;
    let centred: Vec<f32> = x.iter().map(|v| v - mean).collect();
    let a = &centred[..window];
    let energy_a: f32 = a.iter().map(|v| v * v).sum();
    if energy_a <= f32::EPSILON {
        return None;
    }
    let correlations: Vec<f32> = lags
        .clone()
        .map(|lag| {
            let b = &centred[lag..lag + window];
            let cross: f32 = a.iter().zip(b).map(|(p, q)| p * q).sum();
            let energy_b: f32 = b.iter().map(|v| v * v).sum();
            cross / (energy_a * energy_b).sqrt().max(f32::EPSILON)
        })
        .collect();
    let best = correlations.iter().copied().fold(f32::MIN, f32::max);
    if best < PERIODIC {
        return None;
    }
    let k = (1..correlations.len().saturating_sub(1)).find(|&k| {
        correlations[k] >= 0.9 * best
            && correlations[k] >= correlations[k - 1]
            && correlations[k] >= correlations[k + 1]
    })?;
    // The peak between its neighbours (a parabola through the three).
    let (l, c, r) = (correlations[k - 1], correlations[k], correlations[k + 1]);
    let bend = l - 2.0 * c + r;
    let offset = if bend.abs() > f32::EPSILON {
        (0.5 * (l - r) / bend).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    Some((lags.start() + k) as f32 + offset)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `sound`'s median pitch, where its own voice activity says a voice is heard.
    fn pitch_of(sound: &Sound) -> Option<f32> {
        median_pitch(sound, &sound.voice_activity())
    }

    /// A voice-like buzz: harmonics of `pitch` Hz falling 6 dB an octave, `seconds` long,
    /// between two stretches of silence.
    pub(crate) fn buzz(pitch: f32, seconds: f32) -> Sound {
        let rate = SAMPLE_RATE as f32;
        let quiet = vec![0i16; 4000];
        let voiced = (0..(seconds * rate) as usize).map(|n| {
            let t = n as f32 / rate;
            let v: f32 = (1..=20)
                .filter(|h| *h as f32 * pitch < 7000.0)
                .map(|h| (std::f32::consts::TAU * h as f32 * pitch * t).sin() / h as f32)
                .sum();
            (v * 6000.0) as i16
        });
        Sound {
            samples: quiet
                .iter()
                .copied()
                .chain(voiced)
                .chain(quiet.iter().copied())
                .collect(),
        }
    }

    #[test]
    fn digital_silence_is_filled_with_the_least_noise_and_nothing_else_changes() {
        let long = DIGITAL_SILENCE;
        let samples: Vec<i16> = std::iter::repeat_n(0, long)
            .chain([5, -3])
            .chain(std::iter::repeat_n(0, long - 1))
            .chain([7])
            .chain(std::iter::repeat_n(0, 2 * long))
            .collect();
        let heard = audible(Cow::Borrowed(&samples));
        assert_eq!(heard.len(), samples.len());
        for (k, (&was, &now)) in samples.iter().zip(heard.iter()).enumerate() {
            let filled = k < long || k >= 2 * long + 2;
            match filled {
                true => assert!((-1..=1).contains(&now), "sample {k}: {now}"),
                // Speech, and digital silence too short to throw the features off.
                false => assert_eq!(now, was, "sample {k}"),
            }
        }
        // Noise, not a constant; the same every time.
        assert!(heard[..long].iter().any(|&s| s != 0) && heard[..long].iter().any(|&s| s != 1));
        assert_eq!(audible(Cow::Borrowed(&samples)), heard);
        // A sound without long digital silence is heard as it is, uncopied.
        let speech = [3i16; 8000];
        assert!(matches!(audible(Cow::Borrowed(&speech)), Cow::Borrowed(_)));
    }

    #[test]
    fn a_voices_pitch_is_found_not_its_octave() {
        for pitch in [85.0, 120.0, 170.0, 230.0, 320.0] {
            let found = pitch_of(&buzz(pitch, 1.0)).unwrap();
            assert!(
                (found / pitch - 1.0).abs() < 0.03,
                "{pitch} Hz found as {found}"
            );
        }
        // Silence and noise have none.
        assert_eq!(
            pitch_of(&Sound {
                samples: vec![0; 16000]
            }),
            None
        );
        let mut seed = 1u32;
        let noise: Vec<i16> = (0..32000)
            .map(|n| {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let loud = if (8000..24000).contains(&n) {
                    8000
                } else {
                    100
                };
                ((seed >> 16) as i32 % loud) as i16
            })
            .collect();
        assert_eq!(pitch_of(&Sound { samples: noise }), None, "a whisper");
    }

    #[test]
    #[allow(clippy::float_cmp, reason = "the table's own values, exactly")]
    fn men_are_not_warped_women_and_children_more() {
        assert_eq!(warp(100.0), 1.0);
        assert_eq!(warp(150.0), 1.0);
        assert!((warp(160.0) - 1.1).abs() < 1e-5, "{}", warp(160.0));
        assert_eq!(warp(210.0), 1.2);
        assert!((warp(270.0) - 1.325).abs() < 1e-5, "{}", warp(270.0));
        assert_eq!(warp(400.0), 1.45);
        assert_eq!(warp(f32::NAN), 1.0);
        // Never a step: neighbouring pitches, neighbouring warps.
        for p in 100..400 {
            let p = p as f32;
            assert!((warp(p + 1.0) - warp(p)).abs() < 0.011, "{p}");
        }
    }

    #[test]
    fn voices_are_named_or_given_by_their_warp() {
        assert_eq!("auto".parse(), Ok(Voice::Auto));
        assert_eq!("Search".parse(), Ok(Voice::Search));
        assert_eq!("Woman".parse(), Ok(Voice::Warp(1.2)));
        assert_eq!(" child ".parse(), Ok(Voice::Warp(1.45)));
        assert_eq!("0.8".parse(), Ok(Voice::Warp(0.8)));
        let outside = "3".parse::<Voice>().unwrap_err();
        assert!(outside.contains("outside"), "{outside}");
        let unknown = "robot".parse::<Voice>().unwrap_err();
        assert!(
            unknown.contains("'robot'") && unknown.contains("woman") && unknown.contains("search"),
            "{unknown}"
        );
        assert!("NaN".parse::<Voice>().is_err());
    }

    #[test]
    fn a_warped_sound_is_slowed_as_its_frame_rate_says() {
        let sound = buzz(200.0, 1.0);
        let heard = Heard::warped(&sound, 80);
        assert_ne!(heard.frame_rate, FRAME_RATE);
        let ratio = heard.samples.len() as f32 / sound.samples.len() as f32;
        assert!((ratio - 1.25).abs() < 0.01, "{ratio}");
        // Each of the recogniser's frames is 10 ms of the sound, whole samples as they are:
        // at 83 frames a second a frame moves on 193 samples, not 192.77.
        for frame_rate in 60..=100 {
            let stretch = f64::from(SAMPLE_RATE) / f64::from(slowed_rate(frame_rate));
            let per_frame = f64::from(frame_shift(frame_rate)) / stretch / f64::from(SAMPLE_RATE);
            // Off by at most the rate's rounding: half a sample a second.
            let most = 0.5 / f64::from(slowed_rate(frame_rate));
            assert!(
                (per_frame / 0.01 - 1.0).abs() <= most,
                "{frame_rate}: {per_frame}"
            );
        }
        // Its pitch is lowered as much.
        let slowed = Sound {
            samples: heard.samples.into_owned(),
        };
        let pitch = pitch_of(&slowed).unwrap();
        assert!((pitch - 160.0).abs() < 5.0, "{pitch}");
        assert_eq!(Heard::warped(&sound, 100).frame_rate, FRAME_RATE);
        let rate = |pitch: f32, voice: Voice| Hearing::of(&buzz(pitch, 1.0), voice).frame_rate;
        assert_eq!(
            rate(110.0, Voice::Auto),
            FRAME_RATE,
            "a man's voice as it is"
        );
        assert_eq!(
            rate(230.0, Voice::Auto),
            83,
            "a woman's voice warped by 1.2"
        );
        assert_eq!(rate(230.0, Voice::Warp(1.0)), FRAME_RATE);
        assert_eq!(rate(230.0, Voice::Warp(f32::NAN)), FRAME_RATE);
    }
}
