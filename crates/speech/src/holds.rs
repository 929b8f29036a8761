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

/// `phones` (recognised without a transcript) with each short silence between two phones
/// whose release is the lips' made a P (see the module's docs); the voice heard through a
/// vocal tract `warp` times the acoustic model's.
pub(crate) fn lips_held(sound: &Sound, mut phones: Vec<Phone>, warp: f32) -> Vec<Phone> {
    let warp = warp.clamp(0.5, 2.0);
    // One planner for the line: every window of a kind is the same length, so its transform
    // is planned once.
    let mut planner = FftPlanner::new();
    for k in 1..phones.len().saturating_sub(1) {
        let (before, hold, after) = (&phones[k - 1], &phones[k], &phones[k + 1]);
        if hold.label != "SIL"
            || hold.end - hold.start > LONGEST_HOLD
            || before.label == "SIL"
            || after.label == "SIL"
        {
            continue;
        }
        let mut read = |window: (f32, f32), band| {
            centroid(
                sound,
                &mut planner,
                hold.end + window.0,
                hold.end + window.1,
                band,
            )
        };
        let burst = read(RELEASE, BURST_BAND);
        let rise = read(SETTLED, TRANSITION_BAND)
            .zip(read(ONSET, TRANSITION_BAND))
            .map(|(settled, onset)| settled - onset);
        tracing::trace!(start = hold.start, end = hold.end, ?burst, ?rise, "a hold");
        let labial = burst.is_some_and(|c| {
            c < GRAVE * warp
                || (c < GRAVE_IF_RISING * warp && rise.is_some_and(|r| r > RISING * warp))
        });
        if labial {
            phones[k].label = "P".into();
        }
    }
    phones
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
    let bin = rate / size as f32;
    let (mut weighted, mut total) = (0.0f64, 0.0f64);
    for (i, c) in buffer.iter().enumerate().take(size / 2 + 1) {
        let frequency = i as f32 * bin;
        if (band.0..=band.1).contains(&frequency) {
            let power = f64::from(c.norm_sqr());
            weighted += power * f64::from(frequency);
            total += power;
        }
    }
    (total > 0.0).then(|| (weighted / total) as f32)
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
