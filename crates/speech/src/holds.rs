//! Stop holds a recogniser heard as silence, placed by their release.
//!
//! A formant synthesiser's stops, or a whisper's, are often heard without their words as a
//! short silence inside speech and then a vowel: the hold, and a release the acoustic model
//! did not know. Which stop it was, the acoustic model cannot say either (asked to choose among
//! P, T, K, B, D, G, M, N for each such silence, it chose the lips as often for a T as for a P).
//! The release can: the lips open on a burst whose energy lies low, the tongue's tip and back
//! on one that is high or compact (Blumstein and Stevens, 1979). A hold whose release is low
//! becomes a P, so that the lips close there; any other stays a silence (the mouth relaxes).

use crate::audio::{SAMPLE_RATE, Sound};
use crate::phones::Phone;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex32;

/// The longest silence inside speech that may be a stop's hold, seconds.
const LONGEST_HOLD: f32 = 0.2;

/// The release's spectral centroid (Hz, 300 Hz to 7 kHz) under which the lips made it, for
/// a voice heard as it is (an adult man's); a woman's or a child's is higher by its warp.
/// Chosen on eSpeak NG's m3, f2 and whisperf: bilabial releases lie at 0.7–1.7 kHz (a few
/// to 2.8), other stops' at 2.1–5.5 kHz (one at 0.8).
const GRAVE: f32 = 2000.0;

/// The window the release is read in, seconds, from just before the hold ends.
const RELEASE: (f32, f32) = (-0.005, 0.015);

/// `phones` (recognised without a transcript) with each short silence between two phones
/// whose release is grave made a P (see the module's docs); the voice heard through a vocal
/// tract `warp` times the acoustic model's.
pub(crate) fn lips_held(sound: &Sound, mut phones: Vec<Phone>, warp: f32) -> Vec<Phone> {
    let grave = GRAVE * warp.clamp(0.5, 2.0);
    // One planner for the line: every release window is the same length, so its transform is
    // planned once.
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
        let centroid = centroid(
            sound,
            &mut planner,
            hold.end + RELEASE.0,
            hold.end + RELEASE.1,
        );
        tracing::trace!(start = hold.start, end = hold.end, ?centroid, "a hold");
        if centroid.is_some_and(|c| c < grave) {
            phones[k].label = "P".into();
        }
    }
    phones
}

/// The spectral centroid (Hz) between 300 Hz and 7 kHz of `sound` from `start` to `end`
/// (seconds) under a Hann window, transformed by a plan from `planner`; `None` where the
/// stretch is cut short or silent.
fn centroid(sound: &Sound, planner: &mut FftPlanner<f32>, start: f32, end: f32) -> Option<f32> {
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
        if (300.0..=7000.0).contains(&frequency) {
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
        let rate = SAMPLE_RATE as f32;
        let tone = |hz: f32, seconds: f32, gain: f32| {
            (0..(seconds * rate) as usize)
                .map(move |n| (gain * (std::f32::consts::TAU * hz * n as f32 / rate).sin()) as i16)
        };
        let vowel = || {
            (0..(0.3 * rate) as usize).map(|n| {
                let t = n as f32 / rate;
                let v: f32 = (1..=8)
                    .map(|h| (std::f32::consts::TAU * 120.0 * h as f32 * t).sin() / h as f32)
                    .sum();
                (v * 5000.0) as i16
            })
        };
        let samples = vowel()
            .chain(std::iter::repeat_n(0, (hold * rate) as usize))
            .chain(tone(burst, 0.02, 4000.0))
            .chain(vowel())
            .collect();
        Sound { samples }
    }

    #[test]
    fn a_release_is_as_high_as_its_sound() {
        let sound = stop(0.1, 1000.0);
        // The burst: 0.4 to 0.42 s.
        let mut planner = FftPlanner::new();
        let found = centroid(&sound, &mut planner, 0.402, 0.418).unwrap();
        assert!((found - 1000.0).abs() < 100.0, "{found}");
        assert_eq!(centroid(&sound, &mut planner, 0.31, 0.39), None, "silence");
        assert_eq!(
            centroid(&sound, &mut planner, 0.9, 1.1),
            None,
            "past the end"
        );
        // A window of another length, planned by the same planner.
        let found = centroid(&sound, &mut planner, 0.4, 0.42).unwrap();
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
}
