//! Stop holds a recogniser heard as silence, placed by their release.
//!
//! A formant synthesiser's stops, or a whisper's, are often heard without their words as a
//! short silence inside speech and then a vowel: the hold, and a release the acoustic model
//! did not know. Which stop it was, the acoustic model cannot say either (asked to choose among
//! P, T, K, B, D, G, M, N for each such silence, it chose the lips as often for a T as for a P).
//! The release can, by two cues (Blumstein and Stevens, 1979; Kewley-Port, 1982):
//! - the burst: the lips open on one whose energy lies low, the tongue's tip and back on one
//!   that is high or compact;
//! - the transition into the next sound: opening the lips lengthens the vocal tract's front,
//!   so the resonances of the second formant's region rise out of a bilabial (from a locus
//!   near 1 kHz), where they fall or stay out of a velar or an alveolar.
//!
//! A hold whose burst is low, or middling and followed by a rising transition, becomes a P,
//! so that the lips close there; any other stays a silence (the mouth relaxes).
//!
//! The recogniser's silence is not always silent: between an S and an L ("slid", "sleeve"),
//! before a W or inside a vowel it hears a sonorant it has no phone for as a pause, and the
//! L's onset, low and rising, reads as a bilabial's release. A hold closes the lips only
//! where the lips can be shut: it is quiet above 1 kHz (a stop's closure), or its sound is a
//! nasal murmur (an M: its energy under 300 Hz, the nasal resonance; an L's, a W's or a
//! vowel's first formant lies above it — Mermelstein, 1977).
//!
//! Some voices' stops, and the sounds between them, are heard as one longer silence ("big
//! purple", "map to"): such a silence is searched for its closures, runs of frames as quiet as
//! a stop's, and each the lips release becomes a P inside it.

use crate::audio::{SAMPLE_RATE, Sound};
use crate::phones::Phone;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex32;

/// The longest silence inside speech that may be a stop's hold, seconds.
const LONGEST_HOLD: f32 = 0.2;

/// The release's spectral centroid (Hz, over [`BURST_BAND`]) under which the lips made it,
/// for a voice heard as it is (an adult man's); a woman's or a child's is higher by its warp.
/// Chosen on eSpeak NG's m3, f2 and whisperf: bilabial releases lie at 0.7–1.7 kHz (a few
/// to 2.8), other stops' at 2.1–5.5 kHz (one at 0.8).
const GRAVE: f32 = 2000.0;

/// The release's centroid under which the lips may have made it when the transition after
/// it rises ([`RISING`]), for a man's voice (scaled by the warp as [`GRAVE`] is). A P before
/// a front vowel or an L bursts higher than one before a back vowel (eSpeak NG's m3: 2.4–2.7
/// kHz in "purple", "ample", "up eat"), as high as a K's (2.3–3.0 kHz); their transitions part
/// them. Chosen on the holds of eSpeak NG's m3, f2 and whisperf and flite's slt, rms and awb
/// (`scripts/bench-lipsync.py`, audio alone, and twelve more lines of stops): 2.5 kHz gained
/// nothing, 2.8 to 3.2 kHz the same.
const GRAVE_IF_RISING: f32 = 2800.0;

/// How much the centroid of the second formant's region ([`TRANSITION_BAND`]) must rise,
/// Hz, from just after the release ([`ONSET`]) to the sound settled after it ([`SETTLED`])
/// for a middling burst to be the lips' (for a man's voice; scaled by the warp). On the same
/// holds a bilabial's rises by −180 to +1,200 Hz (most by 20 to 600), a K's or T's by −1,300
/// to +360 (most fall by 50 to 1,000). On the bench, audio alone, P/B/M closed went from 0.72
/// to 0.83 on m3 and from 0.24 to 0.45 on whisperf, with one and two more closures where no
/// lips close; flite's voices were unchanged. 0 closed as many and falsely two more; 150
/// closed fewer.
const RISING: f32 = 60.0;

/// The window the release is read in, seconds, from just before the hold ends.
const RELEASE: (f32, f32) = (-0.005, 0.015);

/// The band a burst's centroid is read over, Hz.
const BURST_BAND: (f32, f32) = (300.0, 7000.0);

/// The band the transition is read over, Hz: the second formant's region (its loci lie at
/// about 1 kHz for the lips, 1.8 kHz for the tongue's tip, higher for its back before a
/// front vowel), above most voices' first formant.
const TRANSITION_BAND: (f32, f32) = (700.0, 3000.0);

/// The transition's start, seconds after the hold ends: past most of the burst.
const ONSET: (f32, f32) = (0.015, 0.045);

/// The sound settled after a release, seconds after the hold ends.
const SETTLED: (f32, f32) = (0.06, 0.09);

/// The band a closure is quiet in, Hz (for a man's voice; scaled by the warp): over a
/// voiced closure's murmur and a nasal's first resonance, where a fricative, an L or a vowel
/// still sounds.
const HUSH_BAND: (f32, f32) = (1000.0, 6000.0);

/// How far (dB) a hold's quietest 10 ms must lie under the line's loud frames (the level 95 in
/// 100 of its frames lie under) in [`HUSH_BAND`] to be a closure. On the holds the phone
/// route read as the lips' release on the tuning voices (eSpeak NG en, en-us and its m1, m2,
/// m3, m7, klatt, f2 and whisperf; flite slt, rms, awb; 24 lines), the stops' closures lie
/// 50 dB or more under (eSpeak NG's are exact zeros), the sonorants heard as silence 16–39 dB
/// (the silence between "s" and "l" in "slid": 20–27).
const HUSHED_UNDER_LOUD_DB: f32 = 40.0;

/// A hold as quiet as the line's floor (the level 5 in 100 of its frames lie under) plus this
/// in [`HUSH_BAND`], dB, is a closure however near the loud frames the floor lies: in noise
/// (pink noise 15 dB under the voice), a closure is as loud as the noise.
const HUSHED_OVER_FLOOR_DB: f32 = 10.0;

/// A hold must lie at least this far (dB) under the line's loud frames in [`HUSH_BAND`] to be
/// a closure by [`HUSHED_OVER_FLOOR_DB`]: a line without quiet frames (a few seconds of voice
/// cut to its words) has its floor among its voiced sounds.
const HUSHED_UNDER_LOUD_MIN_DB: f32 = 15.0;

/// A nasal murmur's band and the band over it, Hz (for a man's voice; scaled by the warp).
const MURMUR_BANDS: [(f32, f32); 2] = [(60.0, 300.0), (300.0, 800.0)];

/// A hold that is not hushed is an M's murmur when its energy over [`MURMUR_BANDS`]' first
/// band lies under this (dB) relative to the first: on the same holds an M's lay at −15 to
/// −4 dB (4 of 30 higher), an L's, a W's or a vowel's at −3 to +16 (4 of 44 lower). With
/// both checks, 39 of the 135 holds read as the lips' where no bilabial was said stay
/// silences, and 3 of the 263 at a bilabial do.
const MURMUR_DB: f32 = -3.5;

/// The longest silence inside speech searched for the closures in it, seconds: a recogniser
/// hears some voices' stops and the sounds between them as one silence ("map to", "big
/// purple": 0.2–0.45 s on eSpeak NG's voices), a longer one is a pause.
const LONGEST_HELD_SILENCE: f32 = 0.5;

/// A closure found inside a longer silence lasts at least this, seconds: three 10 ms frames
/// (a gap of one or two is more likely a fricative's or a vowel's quiet edge than a stop).
const SHORTEST_CLOSURE: f32 = 0.03;

/// `phones` (recognised without a transcript) with each short silence between two phones
/// whose release is the lips' made a P (see the module's docs), and each longer silence
/// between two phones ([`LONGEST_HELD_SILENCE`]) split at the closures in it, those the lips
/// release made a P; the voice heard through a vocal tract `warp` times the acoustic model's.
pub(crate) fn lips_held(sound: &Sound, phones: Vec<Phone>, warp: f32) -> Vec<Phone> {
    let mut line = Line {
        sound,
        warp: warp.clamp(0.5, 2.0),
        planner: FftPlanner::new(),
        levels: None,
    };
    let mut held = Vec::with_capacity(phones.len());
    for (k, phone) in phones.iter().enumerate() {
        let inside = phone.label == "SIL"
            && k > 0
            && k + 1 < phones.len()
            && phones[k - 1].label != "SIL"
            && phones[k + 1].label != "SIL";
        let length = phone.end - phone.start;
        if inside && length <= LONGEST_HOLD {
            let lips = line.released_by_lips(phone.end) && line.shut((phone.start, phone.end));
            held.push(Phone {
                label: if lips { "P" } else { "SIL" }.into(),
                ..phone.clone()
            });
        } else if inside && length <= LONGEST_HELD_SILENCE {
            held.extend(line.split(phone));
        } else {
            held.push(phone.clone());
        }
    }
    held
}

/// A line's sound, read for its holds.
struct Line<'a> {
    sound: &'a Sound,
    /// The vocal tract's length against the acoustic model's.
    warp: f32,
    /// One planner for the line: every window of a kind is the same length, so its
    /// transform is planned once.
    planner: FftPlanner<f32>,
    /// The line's loud level and floor in the hush band, read when a hold first needs them
    /// ([`Line::levels`]).
    levels: Option<Option<(f32, f32)>>,
}

impl Line<'_> {
    /// The spectral centroid over `band` from `window.0` to `window.1` seconds after `at`.
    fn centroid(&mut self, at: f32, window: (f32, f32), band: (f32, f32)) -> Option<f32> {
        centroid(
            self.sound,
            &mut self.planner,
            at + window.0,
            at + window.1,
            band,
        )
    }

    /// Whether the release at `end` (seconds) is the lips' by its burst and the transition
    /// after it (the module's docs).
    fn released_by_lips(&mut self, end: f32) -> bool {
        let burst = self.centroid(end, RELEASE, BURST_BAND);
        let rise = self
            .centroid(end, SETTLED, TRANSITION_BAND)
            .zip(self.centroid(end, ONSET, TRANSITION_BAND))
            .map(|(settled, onset)| settled - onset);
        tracing::trace!(end, ?burst, ?rise, "a release");
        let warp = self.warp;
        burst.is_some_and(|c| {
            c < GRAVE * warp
                || (c < GRAVE_IF_RISING * warp && rise.is_some_and(|r| r > RISING * warp))
        })
    }

    /// The level (dB) in the hush band ([`hush_band`]) of each frame from `span`'s start to
    /// its end, `hop` seconds apart.
    fn hush_levels(&mut self, span: (f32, f32), hop: f32) -> Vec<f32> {
        band_levels(
            self.sound,
            &mut self.planner,
            span,
            hush_band(self.warp),
            hop,
        )
    }

    /// The line's loud level and its floor in the hush band (dB; see
    /// [`HUSHED_UNDER_LOUD_DB`], [`HUSHED_OVER_FLOOR_DB`]), read once; `None` for a line
    /// shorter than a frame.
    fn levels(&mut self) -> Option<(f32, f32)> {
        if let Some(levels) = self.levels {
            return levels;
        }
        let mut levels = self.hush_levels((0.0, self.sound.seconds()), FRAME);
        levels.sort_by(f32::total_cmp);
        let at = |percent: usize| levels[(levels.len() * percent / 100).min(levels.len() - 1)];
        let read = (!levels.is_empty()).then(|| (at(95), at(5)));
        self.levels = Some(read);
        read
    }

    /// Whether the lips may be shut through `hold` (start, end: seconds): hushed above 1 kHz,
    /// as a stop's closure is, or a nasal murmur (the module's docs).
    fn shut(&mut self, hold: (f32, f32)) -> bool {
        // Past the sound before the hold: the recogniser's boundary is a frame or so late.
        let span = (hold.0 + FRAME, hold.1);
        let quietest = self
            .hush_levels(span, FRAME / 2.0)
            .into_iter()
            .reduce(f32::min);
        let (Some(quietest), Some((loud, floor))) = (quietest, self.levels()) else {
            // Too short to tell: as the burst says.
            return true;
        };
        if hushed(quietest, loud, floor) {
            return true;
        }
        let warp = self.warp;
        let bands = MURMUR_BANDS.map(|(a, b)| (a * warp, b * warp));
        match band_powers(self.sound, &mut self.planner, span, bands) {
            Some([low, over]) if low > 0.0 => {
                10.0 * (over.max(f64::MIN_POSITIVE) / low).log10() < f64::from(MURMUR_DB)
            }
            _ => false,
        }
    }

    /// `silence` split at the closures in it: each run of hushed frames from
    /// [`SHORTEST_CLOSURE`] to [`LONGEST_HOLD`] long whose release is the lips' becomes a
    /// P, the rest stays silence.
    fn split(&mut self, silence: &Phone) -> Vec<Phone> {
        let Some((loud, floor)) = self.levels() else {
            return vec![silence.clone()];
        };
        let hop = FRAME / 2.0;
        let hushed: Vec<bool> = self
            .hush_levels((silence.start, silence.end), hop)
            .into_iter()
            .map(|l| hushed(l, loud, floor))
            .collect();
        let mut pieces = Vec::new();
        let mut from = silence.start;
        for run in crate::audio::runs(&hushed, true, 1) {
            // A run of frames `hop` apart, each a frame long: from its first frame's start
            // to its last frame's end.
            let start = silence.start + run.start as f32 * hop;
            let end = (silence.start + (run.end - 1) as f32 * hop + FRAME).min(silence.end);
            if end - start < SHORTEST_CLOSURE
                || end - start > LONGEST_HOLD
                || !self.released_by_lips(end)
            {
                continue;
            }
            if start > from {
                pieces.push(Phone {
                    label: "SIL".into(),
                    start: from,
                    end: start,
                });
            }
            pieces.push(Phone {
                label: "P".into(),
                start,
                end,
            });
            from = end;
        }
        if from < silence.end {
            pieces.push(Phone {
                label: "SIL".into(),
                start: from,
                end: silence.end,
            });
        }
        pieces
    }
}

/// [`HUSH_BAND`] scaled by `warp`, under the Nyquist frequency.
fn hush_band(warp: f32) -> (f32, f32) {
    let nyquist = SAMPLE_RATE as f32 / 2.0;
    (
        HUSH_BAND.0 * warp,
        (HUSH_BAND.1 * warp).min(nyquist - 100.0),
    )
}

/// Whether a frame at `level` (dB, in the hush band) is as quiet as a closure in a line whose
/// loud level and floor are `loud` and `floor`.
fn hushed(level: f32, loud: f32, floor: f32) -> bool {
    level < loud - HUSHED_UNDER_LOUD_DB
        || (level < floor + HUSHED_OVER_FLOOR_DB && level < loud - HUSHED_UNDER_LOUD_MIN_DB)
}

/// One frame's length, seconds.
const FRAME: f32 = 0.01;

/// The level (dB) in `band` of each [`FRAME`] of `sound` from `span`'s start to its end,
/// `hop` seconds apart.
fn band_levels(
    sound: &Sound,
    planner: &mut FftPlanner<f32>,
    span: (f32, f32),
    band: (f32, f32),
    hop: f32,
) -> Vec<f32> {
    let mut levels = Vec::new();
    let mut start = span.0;
    while start + FRAME <= span.1 + 1e-4 {
        if let Some([power]) = band_powers(sound, planner, (start, start + FRAME), [band]) {
            levels.push(
                (10.0 * (power / f64::from(FRAME * SAMPLE_RATE as f32) + 1e-3).log10()) as f32,
            );
        }
        start += hop;
    }
    levels
}

/// The power spectrum of `sound` from `start` to `end` (seconds) under a Hann window,
/// transformed by a plan from `planner`, with its bins' spacing in Hz; `None` where the
/// stretch is cut short.
fn spectrum(
    sound: &Sound,
    planner: &mut FftPlanner<f32>,
    start: f32,
    end: f32,
) -> Option<(Vec<f32>, f32)> {
    let rate = SAMPLE_RATE as f32;
    let a = (start * rate).round().max(0.0) as usize;
    let b = ((end * rate).round().max(0.0) as usize).min(sound.samples.len());
    if b <= a || b - a < ((end - start) * rate * 0.75) as usize {
        return None;
    }
    let n = b - a;
    let size = n.next_power_of_two().max(512);
    let mut buffer: Vec<Complex32> = sound.samples[a..b]
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let hann = 0.5 - 0.5 * (std::f32::consts::TAU * i as f32 / (n - 1).max(1) as f32).cos();
            Complex32::new(f32::from(s) * hann, 0.0)
        })
        .chain(std::iter::repeat(Complex32::new(0.0, 0.0)))
        .take(size)
        .collect();
    planner.plan_fft_forward(size).process(&mut buffer);
    let powers = buffer
        .iter()
        .take(size / 2 + 1)
        .map(|c| c.norm_sqr())
        .collect();
    Some((powers, rate / size as f32))
}

/// The spectral centroid (Hz) between `band`'s two frequencies of `sound` from `start` to
/// `end` (seconds) under a Hann window, transformed by a plan from `planner`; `None` where the
/// stretch is cut short or silent.
fn centroid(
    sound: &Sound,
    planner: &mut FftPlanner<f32>,
    start: f32,
    end: f32,
    band: (f32, f32),
) -> Option<f32> {
    let (powers, bin) = spectrum(sound, planner, start, end)?;
    let (mut weighted, mut total) = (0.0f64, 0.0f64);
    for (i, &power) in powers.iter().enumerate() {
        let frequency = i as f32 * bin;
        if (band.0..=band.1).contains(&frequency) {
            weighted += f64::from(power) * f64::from(frequency);
            total += f64::from(power);
        }
    }
    (total > 0.0).then(|| (weighted / total) as f32)
}

/// The power of `sound` between each of `bands`' two frequencies over `span` (seconds), from
/// one spectrum as [`spectrum`] reads it; `None` where the span is cut short.
fn band_powers<const N: usize>(
    sound: &Sound,
    planner: &mut FftPlanner<f32>,
    span: (f32, f32),
    bands: [(f32, f32); N],
) -> Option<[f64; N]> {
    let (powers, bin) = spectrum(sound, planner, span.0, span.1)?;
    Some(bands.map(|band| {
        powers
            .iter()
            .enumerate()
            .filter(|(i, _)| (band.0..band.1).contains(&(*i as f32 * bin)))
            .map(|(_, &p)| f64::from(p))
            .sum()
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phones::tests::phones;

    /// 0.3 s of a vowel-like buzz (120 Hz harmonics under 1 kHz), a hold of `hold` seconds
    /// of silence, then a 20 ms burst of `burst` Hz and 0.3 s more of the buzz.
    fn stop(hold: f32, burst: f32) -> Sound {
        stop_into(hold, burst, None)
    }

    /// [`stop`], with a resonance in the vowel after the burst that glides from `glide`'s
    /// first frequency to its second over 60 ms and stays there: the transition.
    fn stop_into(hold: f32, burst: f32, glide: Option<(f32, f32)>) -> Sound {
        let rate = SAMPLE_RATE as f32;
        let tone = |hz: f32, seconds: f32, gain: f32| {
            (0..(seconds * rate) as usize)
                .map(move |n| (gain * (std::f32::consts::TAU * hz * n as f32 / rate).sin()) as i16)
        };
        let buzz = |t: f32| -> f32 {
            (1..=8)
                .map(|h| (std::f32::consts::TAU * 120.0 * h as f32 * t).sin() / h as f32)
                .sum()
        };
        let vowel = || (0..(0.3 * rate) as usize).map(|n| (buzz(n as f32 / rate) * 5000.0) as i16);
        let mut phase = 0.0f32;
        let after = (0..(0.3 * rate) as usize).map(move |n| {
            let t = n as f32 / rate;
            let resonance = glide.map_or(0.0, |(from, to)| {
                let hz = from + (to - from) * (t / 0.06).min(1.0);
                phase += std::f32::consts::TAU * hz / rate;
                phase.sin()
            });
            (buzz(t) * 5000.0 + resonance * 6000.0) as i16
        });
        let samples = vowel()
            .chain(std::iter::repeat_n(0, (hold * rate) as usize))
            .chain(tone(burst, 0.02, 4000.0))
            .chain(after)
            .collect();
        Sound { samples }
    }

    /// A stretch of a line in [`spoken`].
    #[derive(Clone, Copy)]
    enum Part {
        /// A vowel: a 120 Hz voice with harmonics up to 3.6 kHz, this many seconds.
        Vowel(f32),
        /// Exact silence, seconds.
        Quiet(f32),
        /// A 20 ms burst of this many Hz.
        Burst(f32),
        /// A nasal murmur: the voice's first two harmonics (under 300 Hz) and a little over
        /// 1 kHz, none between.
        Murmur(f32),
        /// A lateral or a vowel's edge: the voice with its first formant (360–480 Hz) strong.
        Lateral(f32),
    }

    /// A line made of `parts`, one after another.
    fn spoken(parts: &[Part]) -> Sound {
        let rate = SAMPLE_RATE as f32;
        let voice = |seconds: f32, gain: fn(usize) -> f32| {
            (0..(seconds * rate) as usize).map(move |n| {
                let t = n as f32 / rate;
                let v: f32 = (1..=30)
                    .map(|h| gain(h) * (std::f32::consts::TAU * 120.0 * h as f32 * t).sin())
                    .sum();
                (v * 4000.0) as i16
            })
        };
        let mut samples = Vec::new();
        for part in parts {
            match *part {
                Part::Vowel(s) => samples.extend(voice(s, |h| 1.0 / h as f32)),
                Part::Quiet(s) => samples.extend(std::iter::repeat_n(0, (s * rate) as usize)),
                Part::Burst(hz) => samples.extend((0..(0.02 * rate) as usize).map(|n| {
                    (4000.0 * (std::f32::consts::TAU * hz * n as f32 / rate).sin()) as i16
                })),
                Part::Murmur(s) => samples.extend(voice(s, |h| match h {
                    1 | 2 => 1.0,
                    9..=20 => 0.05,
                    _ => 0.0,
                })),
                Part::Lateral(s) => samples.extend(voice(s, |h| match h {
                    3 | 4 => 1.0,
                    _ => 1.0 / h as f32,
                })),
            }
        }
        Sound { samples }
    }

    #[test]
    fn a_silence_the_lips_cannot_make_stays_silence() {
        use Part::{Burst, Lateral, Murmur, Quiet, Vowel};
        let heard = |hold: Part| {
            let sound = spoken(&[Vowel(0.3), hold, Burst(900.0), Vowel(0.3)]);
            lips_held(&sound, phones("AA 0 0.3, SIL 0.3 0.38, AA 0.38 0.7"), 1.0)[1]
                .label
                .clone()
        };
        // A low release after a closure, or after a nasal murmur: the lips.
        assert_eq!(heard(Quiet(0.08)), "P");
        assert_eq!(heard(Murmur(0.08)), "P");
        // After a sound whose first formant is over the murmur's ("s-l-id"), heard as a
        // silence: no closure.
        assert_eq!(heard(Lateral(0.08)), "SIL");
    }

    #[test]
    fn a_closure_inside_a_longer_silence_is_found() {
        use Part::{Burst, Lateral, Quiet, Vowel};
        // "…ur-p-…" heard as one 0.35 s silence: a voice, a 60 ms closure, its release.
        let held = |burst: f32| {
            let sound = spoken(&[
                Vowel(0.3),
                Lateral(0.15),
                Quiet(0.06),
                Burst(burst),
                Vowel(0.4),
            ]);
            lips_held(&sound, phones("AA 0 0.3, SIL 0.3 0.65, AA 0.65 0.93"), 1.0)
        };
        let found = held(900.0);
        let labels: Vec<&str> = found.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["AA", "SIL", "P", "SIL", "AA"], "{found:?}");
        let closure = &found[2];
        assert!((closure.start - 0.45).abs() < 0.015, "{closure:?}");
        assert!((closure.end - 0.51).abs() < 0.015, "{closure:?}");
        assert!(
            found
                .windows(2)
                .all(|w| (w[0].end - w[1].start).abs() < 1e-6)
        );
        // Released by the tongue: the silence stays whole.
        let found = held(4500.0);
        assert_eq!(found, phones("AA 0 0.3, SIL 0.3 0.65, AA 0.65 0.93"));
        // A longer silence is a pause, not searched.
        let sound = spoken(&[
            Vowel(0.3),
            Lateral(0.4),
            Quiet(0.06),
            Burst(900.0),
            Vowel(0.4),
        ]);
        let pause = phones("AA 0 0.3, SIL 0.3 0.9, AA 0.9 1.1");
        assert_eq!(lips_held(&sound, pause.clone(), 1.0), pause);
    }

    #[test]
    fn a_release_is_as_high_as_its_sound() {
        let sound = stop(0.1, 1000.0);
        // The burst: 0.4 to 0.42 s.
        let mut planner = FftPlanner::new();
        let found = centroid(&sound, &mut planner, 0.402, 0.418, BURST_BAND).unwrap();
        assert!((found - 1000.0).abs() < 100.0, "{found}");
        assert_eq!(
            centroid(&sound, &mut planner, 0.31, 0.39, BURST_BAND),
            None,
            "silence"
        );
        assert_eq!(
            centroid(&sound, &mut planner, 0.9, 1.1, BURST_BAND),
            None,
            "past the end"
        );
        // A window of another length, planned by the same planner.
        let found = centroid(&sound, &mut planner, 0.4, 0.42, BURST_BAND).unwrap();
        assert!((found - 1000.0).abs() < 100.0, "{found}");
    }

    #[test]
    fn a_hold_released_low_closes_the_lips_and_one_released_high_does_not() {
        let heard = |hold: f32, burst: f32, warp: f32| {
            let end = 0.3 + hold;
            let line = format!("AA 0 0.3, SIL 0.3 {end}, AA {end} 1.0");
            lips_held(&stop(hold, burst), phones(&line), warp)[1]
                .label
                .clone()
        };
        assert_eq!(heard(0.1, 900.0, 1.0), "P", "the lips");
        assert_eq!(heard(0.1, 4500.0, 1.0), "SIL", "the tongue");
        // A release between the two is the lips' in a woman's voice, whose every
        // resonance is higher, and not in a man's.
        assert_eq!(heard(0.1, 2200.0, 1.0), "SIL");
        assert_eq!(heard(0.1, 2200.0, 1.2), "P");
        // Longer than a stop's hold: a pause.
        assert_eq!(heard(0.3, 900.0, 1.0), "SIL");
        // A silence at either end of the line is no hold.
        let edges = phones("SIL 0 0.3, AA 0.3 0.4, SIL 0.4 0.5");
        assert_eq!(lips_held(&stop(0.1, 900.0), edges.clone(), 1.0), edges);
    }

    #[test]
    fn a_middling_release_closes_the_lips_when_the_resonances_rise_after_it() {
        let heard = |burst: f32, glide: (f32, f32), warp: f32| {
            let line = "AA 0 0.3, SIL 0.3 0.4, AA 0.4 1.0";
            lips_held(&stop_into(0.1, burst, Some(glide)), phones(line), warp)[1]
                .label
                .clone()
        };
        // A burst as high as a K's, then the second formant rising out of the lips' locus.
        assert_eq!(heard(2500.0, (1000.0, 1800.0), 1.0), "P");
        // The same burst into a falling or a level transition: the tongue.
        assert_eq!(heard(2500.0, (1800.0, 1000.0), 1.0), "SIL");
        assert_eq!(heard(2500.0, (1400.0, 1400.0), 1.0), "SIL");
        // A burst as high as a T's is the tongue's whatever follows it.
        assert_eq!(heard(4500.0, (1000.0, 1800.0), 1.0), "SIL");
        // In a woman's voice, every resonance higher, a burst a man's would leave middling.
        assert_eq!(heard(3200.0, (1200.0, 2200.0), 1.0), "SIL");
        assert_eq!(heard(3200.0, (1200.0, 2200.0), 1.2), "P");
    }
}
