//! Which of the adapter's inputs each of the character's shapes reads.
//!
//! A single network over every input learns whatever goes together in the character's renders,
//! and a person moves in ways no render did. ICT's eyeSquint lifts the lower lid by a hundredth
//! of the face; a person talking moves the mouth's landmarks a hundred times as far, and a
//! network that reads all of them read that talking as a squint: its squint followed
//! MediaPipe's at −0.26 and −0.39 on real footage, where each shape's own inputs give +0.4 to
//! +0.5 (`crates/cli/tests/heldout.rs`).
//!
//! [`Locality::PerShape`] gives each shape its own part of the hidden layer, which reads only
//! the inputs that shape moves in the training set: the landmarks it moves, with those nearby
//! (within [`NEARBY`] in the [rigid frame](crate::features::LandmarkFrame::Rigid): the rest of
//! the eye for a lid, the rest of the lips for a corner), and the scores it moves. "Moves" is
//! measured, not named, so any rig works: a least-squares fit of every input on every shape's
//! weight over the training split, and an input counts when the shape's coefficient is large
//! against what the fit leaves unexplained ([`SIGNAL`], [`SIGNIFICANT`]) and against the
//! shape's own strongest input ([`OF_STRONGEST`]). A shape that moves nothing measurably reads
//! everything, as before.
//!
//! The network stays two dense layers: the parts are zeros in its weight matrices, kept at zero
//! in training by masks, so an adapter file and its inference are unchanged.

use serde::{Deserialize, Serialize};

use crate::features::FeatureSet;

/// Which inputs feed each output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Locality {
    /// One hidden layer over every input for every shape (the seed's; adapters from before).
    #[default]
    Global,
    /// Each shape has `width` hidden units of its own, reading only the inputs it moves.
    PerShape {
        /// Hidden units per shape.
        width: usize,
    },
}

impl Locality {
    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Locality::Global => "global",
            Locality::PerShape { .. } => "per_shape",
        }
    }
}

/// How near (in the rigid frame, where the rigid landmarks' spread is 1 and an eye is about
/// 0.46 wide) a landmark must be to one the shape moves to be read with it.
pub const NEARBY: f64 = 0.25;
/// An input counts when the shape's coefficient, times the spread of the shape's weight, is at
/// least this fraction of the input's unexplained spread: the signal one sample carries,
/// whatever the number of samples.
pub const SIGNAL: f64 = 0.09;
/// ... and when that coefficient is this many of its standard errors from zero.
pub const SIGNIFICANT: f64 = 4.0;
/// ... and when its signal is at least this fraction of the shape's strongest input's (of the
/// same kind: scores apart from landmarks).
pub const OF_STRONGEST: f64 = 0.25;

/// Per output (shape), whether it reads each input: `inputs` are the training split's rows as
/// the adapter reads them, `targets` their weights, `neutral` a neutral face's input (where
/// the landmarks are, for [`NEARBY`]).
#[must_use]
pub fn reads(
    features: FeatureSet,
    neutral: &[f32],
    inputs: &[Vec<f32>],
    targets: &[Vec<f32>],
) -> Vec<Vec<bool>> {
    let outputs = targets.first().map_or(0, Vec::len);
    let width = features.len();
    let Some(fit) = Fit::of(inputs, targets, width) else {
        return vec![vec![true; width]; outputs];
    };
    let scores = features.scores();
    let points: Vec<glam::DVec3> = neutral
        .get(scores..)
        .unwrap_or_default()
        .chunks_exact(3)
        .map(|p| glam::DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])))
        .collect();
    (0..outputs)
        .map(|o| {
            // One signal per score, one per landmark (its three coordinates together).
            let score_signal: Vec<f64> = (0..scores).map(|k| fit.signal(o, &[k])).collect();
            let point_signal: Vec<f64> = (0..points.len())
                .map(|p| {
                    let k = scores + 3 * p;
                    fit.signal(o, &[k, k + 1, k + 2])
                })
                .collect();
            let moved = fit.counted(&point_signal);
            if !moved.iter().any(|m| *m) {
                return vec![true; width];
            }
            let mut read = fit.counted(&score_signal);
            for p in &points {
                let near = points
                    .iter()
                    .zip(&moved)
                    .any(|(q, m)| *m && p.distance(*q) <= NEARBY);
                read.extend([near; 3]);
            }
            read
        })
        .collect()
}

/// Every input fitted as a linear function of every shape's weight.
struct Fit {
    /// (shapes + 1) × inputs: each shape's coefficient, then the constant.
    coefficients: Vec<f64>,
    /// Per input, the mean square of what the fit leaves.
    residual: Vec<f64>,
    /// Per shape, the spread (standard deviation) of its weight.
    spread: Vec<f64>,
    inputs: usize,
    samples: f64,
}

impl Fit {
    /// `None` without samples or when the normal equations are singular.
    fn of(inputs: &[Vec<f32>], targets: &[Vec<f32>], width: usize) -> Option<Fit> {
        let shapes = targets.first()?.len();
        let terms = shapes + 1;
        let samples = inputs.len() as f64;
        let row =
            |t: &[f32]| -> Vec<f64> { t.iter().map(|v| f64::from(*v)).chain([1.0]).collect() };
        // Normal equations AᵀA·B = AᵀX, A = [weights, 1].
        let mut normal = vec![0.0f64; terms * terms];
        let mut right = vec![0.0f64; terms * width];
        for (x, t) in inputs.iter().zip(targets) {
            let a = row(t);
            for i in 0..terms {
                for j in 0..terms {
                    normal[i * terms + j] += a[i] * a[j];
                }
                for (k, v) in x.iter().enumerate().take(width) {
                    right[i * width + k] += a[i] * f64::from(*v);
                }
            }
        }
        // Gauss–Jordan; the normal matrix is symmetric positive definite when every shape
        // varies, so no pivoting is needed. A touch of ridge keeps a constant shape solvable.
        for i in 0..shapes {
            normal[i * terms + i] += 1e-9 * samples;
        }
        for c in 0..terms {
            let pivot = normal[c * terms + c];
            if pivot.abs() < 1e-12 {
                return None;
            }
            for r in (0..terms).filter(|&r| r != c) {
                let f = normal[r * terms + c] / pivot;
                if f == 0.0 {
                    continue;
                }
                for k in 0..terms {
                    normal[r * terms + k] -= f * normal[c * terms + k];
                }
                for k in 0..width {
                    right[r * width + k] -= f * right[c * width + k];
                }
            }
        }
        let coefficients: Vec<f64> = (0..terms)
            .flat_map(|o| (0..width).map(move |k| (o, k)))
            .map(|(o, k)| right[o * width + k] / normal[o * terms + o])
            .collect();
        let mut residual = vec![0.0f64; width];
        for (x, t) in inputs.iter().zip(targets) {
            let a = row(t);
            for (k, v) in x.iter().enumerate().take(width) {
                let fitted: f64 = (0..terms).map(|o| a[o] * coefficients[o * width + k]).sum();
                residual[k] += (f64::from(*v) - fitted).powi(2) / samples;
            }
        }
        let spread = (0..shapes)
            .map(|o| {
                let mean = targets.iter().map(|t| f64::from(t[o])).sum::<f64>() / samples;
                (targets
                    .iter()
                    .map(|t| (f64::from(t[o]) - mean).powi(2))
                    .sum::<f64>()
                    / samples)
                    .sqrt()
            })
            .collect();
        Some(Fit {
            coefficients,
            residual,
            spread,
            inputs: width,
            samples,
        })
    }

    /// How strongly shape `o` moves the inputs `ks` together: the length of its coefficients
    /// times its weight's spread, over the length of what the fit leaves of them.
    fn signal(&self, o: usize, ks: &[usize]) -> f64 {
        let moved: f64 = ks
            .iter()
            .map(|&k| self.coefficients[o * self.inputs + k].powi(2))
            .sum::<f64>()
            .sqrt();
        let left: f64 = ks.iter().map(|&k| self.residual[k]).sum::<f64>().sqrt();
        moved * self.spread[o] / left.max(1e-12)
    }

    /// Which of `signals` count (see the module's rule).
    fn counted(&self, signals: &[f64]) -> Vec<bool> {
        let strongest = signals.iter().copied().fold(0.0, f64::max);
        let bar = SIGNAL
            .max(SIGNIFICANT / self.samples.sqrt())
            .max(OF_STRONGEST * strongest);
        signals.iter().map(|s| *s >= bar).collect()
    }
}

/// The masks of a [`Locality::PerShape`] network of `width` units per shape: hidden × inputs
/// and outputs × hidden, 1 where a weight may be non-zero.
#[must_use]
pub fn masks(reads: &[Vec<bool>], width: usize) -> (Vec<f32>, Vec<f32>) {
    let outputs = reads.len();
    let inputs = reads.first().map_or(0, Vec::len);
    let hidden = width * outputs;
    let mut hidden_mask = vec![0.0f32; hidden * inputs];
    let mut output_mask = vec![0.0f32; outputs * hidden];
    for (o, read) in reads.iter().enumerate() {
        for unit in o * width..(o + 1) * width {
            for (k, &r) in read.iter().enumerate() {
                if r {
                    hidden_mask[unit * inputs + k] = 1.0;
                }
            }
            output_mask[o * hidden + unit] = 1.0;
        }
    }
    (hidden_mask, output_mask)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::SCORES;

    /// Rows of a face whose shape 0 raises score 3 and moves landmark 10, and whose shape 1
    /// moves landmark 100, over noise everywhere; landmarks 10 and 11 sit close together,
    /// 100 far from both.
    fn example() -> (Vec<f32>, Vec<Vec<f32>>, Vec<Vec<f32>>) {
        let width = FeatureSet::Both.len();
        let mut neutral = vec![0.0f32; width];
        for p in 0..(width - SCORES) / 3 {
            neutral[SCORES + 3 * p] = p as f32;
        }
        neutral[SCORES + 3 * 11] = 10.1;
        let mut state = 7u64;
        let mut noise = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            ((state >> 33) as f32 / (1u64 << 31) as f32 - 0.5) * 0.01
        };
        let (mut inputs, mut targets) = (Vec::new(), Vec::new());
        for k in 0..2000 {
            let t = [(k % 7) as f32 / 6.0, (k % 5) as f32 / 4.0];
            let mut x: Vec<f32> = (0..width).map(|_| noise()).collect();
            x[3] += 0.3 * t[0];
            x[SCORES + 3 * 10 + 1] += 0.05 * t[0];
            x[SCORES + 3 * 100] += 0.2 * t[1];
            inputs.push(x);
            targets.push(t.to_vec());
        }
        (neutral, inputs, targets)
    }

    #[test]
    fn each_shape_reads_what_it_moves_and_what_is_near_it() {
        let (neutral, inputs, targets) = example();
        let reads = reads(FeatureSet::Both, &neutral, &inputs, &targets);
        let points = |o: usize| -> Vec<usize> {
            (0..(reads[o].len() - SCORES) / 3)
                .filter(|p| reads[o][SCORES + 3 * p])
                .collect()
        };
        let scores = |o: usize| -> Vec<usize> { (0..SCORES).filter(|k| reads[o][*k]).collect() };
        assert_eq!(points(0), [10, 11]);
        assert_eq!(scores(0), [3]);
        assert_eq!(points(1), [100]);
        assert!(scores(1).is_empty());
    }

    #[test]
    fn a_shape_that_moves_nothing_reads_everything() {
        let (neutral, inputs, mut targets) = example();
        for (t, k) in targets.iter_mut().zip(0..) {
            t.push((k % 3) as f32 / 2.0);
        }
        let reads = reads(FeatureSet::Both, &neutral, &inputs, &targets);
        assert!(reads[2].iter().all(|r| *r));
    }

    #[test]
    fn masks_give_each_shape_its_own_units() {
        let (hidden, output) = masks(&[vec![true, false], vec![false, true]], 2);
        assert_eq!(hidden, [1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0]);
        assert_eq!(output, [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]);
    }
}
