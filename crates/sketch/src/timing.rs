//! Time interpolation (section 3.5) and the easing handle (section 3.6, Eq. 4).
//!
//! An action lasts as long as its stroke took to draw. A keyframe every `subsample` samples
//! records the share of the stroke's length drawn by then, so slow drawing gives gentle changes
//! and fast drawing steep ones. The easing handle α remaps the keyframe *times* with `y = x^p`
//! (`p` from Eq. 4); the progress values stay, so easing composes with the drawn timing instead
//! of replacing it (the authors' code replaced it).

use crate::project::Stroke;

/// Progress of an action over its normalised time, as keyframes.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// `(time, progress)`, both in [0, 1], times strictly increasing from 0 to 1, progress
    /// non-decreasing from 0 to 1.
    keys: Vec<(f32, f32)>,
}

impl Timing {
    /// The timing of `stroke` with a keyframe every `subsample` samples and easing exponent `p`.
    #[must_use]
    pub fn from_stroke(stroke: &Stroke, subsample: usize, p: f32) -> Timing {
        let samples = stroke.samples();
        let lengths = stroke.cumulative_length();
        let total_length = lengths[lengths.len() - 1];
        let duration = stroke.duration();
        let last = samples.len() - 1;
        let mut indices: Vec<usize> = (0..last).step_by(subsample.max(1)).collect();
        indices.push(last);
        let mut keys: Vec<(f32, f32)> = indices
            .into_iter()
            .map(|i| {
                let x = samples[i].t / duration;
                let progress = if total_length > 0.0 {
                    lengths[i] / total_length
                } else {
                    x
                };
                (x.clamp(0.0, 1.0).powf(p), progress.clamp(0.0, 1.0))
            })
            .collect();
        keys.dedup_by(|b, a| b.0 <= a.0);
        if let Some(first) = keys.first_mut() {
            *first = (0.0, 0.0);
        }
        if let Some(end) = keys.last_mut() {
            *end = (1.0, 1.0);
        }
        if keys.len() < 2 {
            keys = vec![(0.0, 0.0), (1.0, 1.0)];
        }
        Timing { keys }
    }

    /// Progress at normalised time `x` (clamped to [0, 1]).
    #[must_use]
    pub fn progress(&self, x: f32) -> f32 {
        let x = x.clamp(0.0, 1.0);
        let i = self.keys.partition_point(|k| k.0 <= x);
        if i == 0 {
            return self.keys[0].1;
        }
        if i >= self.keys.len() {
            return self.keys[self.keys.len() - 1].1;
        }
        let (x0, p0) = self.keys[i - 1];
        let (x1, p1) = self.keys[i];
        p0 + (p1 - p0) * (x - x0) / (x1 - x0)
    }

    /// The keyframes, `(time, progress)` in [0, 1].
    #[must_use]
    pub fn keys(&self) -> &[(f32, f32)] {
        &self.keys
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "these values are exact by construction")]
mod tests {
    use super::*;
    use crate::project::Sample;
    use glam::Vec3;

    /// A stroke along x whose speed doubles halfway in time.
    fn accelerating() -> Stroke {
        let mut samples = Vec::new();
        let mut x = 0.0;
        for i in 0..=90 {
            samples.push(Sample {
                t: i as f32 / 90.0,
                p: Vec3::new(x, 0.0, 0.0),
            });
            x += if i < 45 { 0.001 } else { 0.002 };
        }
        Stroke::new(samples, "s").unwrap_or_else(|e| panic!("{e:?}"))
    }

    #[test]
    fn drawing_speed_becomes_the_progress_curve() {
        let timing = Timing::from_stroke(&accelerating(), 3, 1.0);
        // Half the time covers a third of the length (speed 1 then 2).
        assert!(
            (timing.progress(0.5) - 1.0 / 3.0).abs() < 0.02,
            "{}",
            timing.progress(0.5)
        );
        assert_eq!(timing.progress(0.0), 0.0);
        assert_eq!(timing.progress(1.0), 1.0);
    }

    #[test]
    fn easing_composes_with_the_drawn_timing() {
        let drawn = Timing::from_stroke(&accelerating(), 3, 1.0);
        let eased = Timing::from_stroke(&accelerating(), 3, 2.0);
        // With p = 2 a key at time x moves to x²: the eased curve at x² equals the drawn one at x.
        for x in [0.2f32, 0.5, 0.8] {
            assert!((eased.progress(x * x) - drawn.progress(x)).abs() < 0.02);
        }
    }
}
