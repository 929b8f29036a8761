//! The per-frame solve: the character's free shapes `x` (each in 0..=1) that best reproduce
//! the geometric channels' combined displacement `Σ v_c D_c`, in the region-weighted least
//! squares the map was made with, with a small price on every shape used so that few do:
//!
//! ```text
//! minimise ½ xᵀ G x − xᵀ H v + λ Σ_k √G_kk x_k   subject to 0 ≤ x ≤ 1
//! ```
//!
//! `G` is the shapes' Gram matrix and `H` their products with the channels' displacements
//! (both scaled so that `G`'s mean diagonal is 1): the price of a shape is its size, so one
//! shape that makes a combination costs less than the two it combines. Projected coordinate descent from zero:
//! deterministic, a fraction of a millisecond for a hundred shapes. The price chooses which
//! shapes move; their weights are then solved again without it (a relaxed lasso), so that a
//! channel a shape reproduces exactly reaches its full weight.

use serde::{Deserialize, Serialize};

/// Sweeps at most; most frames settle in a few dozen.
const SWEEPS: usize = 200;
/// A sweep that moves no weight by more than this ends the solve.
const SETTLED: f32 = 1e-5;

/// The per-frame solve's data. See the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solve {
    /// The character's shapes it may use (names).
    pub shapes: Vec<String>,
    /// The channels it matches (ARKit names), the columns of `projections`.
    pub channels: Vec<String>,
    /// `G`: the shapes' products with each other, one row per shape.
    pub gram: Vec<Vec<f32>>,
    /// `H`: each shape's products with each channel's displacement, one row per shape.
    pub projections: Vec<Vec<f32>>,
    /// `λ`: the price of using a shape, per unit of its size.
    pub sparsity: f32,
}

impl Solve {
    /// The shapes' weights for the channels' `values` (in [`Solve::channels`]' order).
    #[must_use]
    pub fn weights(&self, values: &[f32]) -> Vec<f32> {
        let k = self.shapes.len();
        let b: Vec<f32> = self
            .projections
            .iter()
            .map(|row| row.iter().zip(values).map(|(h, v)| h * v).sum())
            .collect();
        // Nothing asked: nothing moves (and no sweep is spent).
        if b.iter().all(|v| *v <= 0.0) {
            return vec![0.0; k];
        }
        self.solve_for(&b, &vec![true; k])
    }

    /// The weights of the shapes marked `allowed` (the others stay 0) for the channels'
    /// `values`: how one channel's own row is fitted, from the shapes of its region.
    #[must_use]
    pub fn weights_among(&self, values: &[f32], allowed: &[bool]) -> Vec<f32> {
        let b: Vec<f32> = self
            .projections
            .iter()
            .map(|row| row.iter().zip(values).map(|(h, v)| h * v).sum())
            .collect();
        self.solve_for(&b, allowed)
    }

    /// The price chooses the shapes among `allowed`, then their weights are solved again
    /// without it.
    fn solve_for(&self, b: &[f32], allowed: &[bool]) -> Vec<f32> {
        let k = self.shapes.len();
        if b.iter().all(|v| *v <= 0.0) {
            return vec![0.0; k];
        }
        let chosen = self.minimise(b, vec![0.0; k], self.sparsity, allowed);
        let active: Vec<bool> = chosen.iter().map(|x| *x > 0.0).collect();
        self.minimise(b, chosen, 0.0, &active)
    }

    /// Projected coordinate descent on `½ xᵀGx − bᵀx + λ Σ √G_kk x_k` from `x`, over the shapes
    /// marked `free` (the others keep their value).
    fn minimise(&self, b: &[f32], mut x: Vec<f32>, sparsity: f32, free: &[bool]) -> Vec<f32> {
        for _ in 0..SWEEPS {
            let mut moved = 0.0f32;
            for i in (0..x.len()).filter(|&i| free[i]) {
                let g = &self.gram[i];
                let diagonal = g[i];
                if diagonal <= 0.0 {
                    continue;
                }
                let others: f32 =
                    g.iter().zip(&x).map(|(gij, xj)| gij * xj).sum::<f32>() - diagonal * x[i];
                let next =
                    ((b[i] - sparsity * diagonal.sqrt() - others) / diagonal).clamp(0.0, 1.0);
                moved = moved.max((next - x[i]).abs());
                x[i] = next;
            }
            if moved < SETTLED {
                break;
            }
        }
        x
    }

    /// Every problem of the solve's data against the character's `blendshapes`, with its
    /// path.
    pub(crate) fn problems(&self, blendshapes: &[String]) -> Vec<String> {
        let mut problems = Vec::new();
        let k = self.shapes.len();
        for (i, name) in self.shapes.iter().enumerate() {
            if !blendshapes.contains(name) {
                problems.push(format!(
                    "solve.shapes[{i}]: no shape '{}'",
                    faceanim_rig::excerpt(name)
                ));
            }
        }
        for (i, c) in self.channels.iter().enumerate() {
            if crate::channel_index(c).is_none() {
                problems.push(format!(
                    "solve.channels[{i}]: '{}' is not an ARKit channel",
                    faceanim_rig::excerpt(c)
                ));
            }
        }
        if self.gram.len() != k || self.gram.iter().any(|r| r.len() != k) {
            problems.push(format!("solve.gram: must be {k} rows of {k}"));
        }
        if self.projections.len() != k
            || self
                .projections
                .iter()
                .any(|r| r.len() != self.channels.len())
        {
            problems.push(format!(
                "solve.projections: must be {k} rows of {}",
                self.channels.len()
            ));
        }
        let finite = |m: &Vec<Vec<f32>>| m.iter().flatten().all(|v| v.is_finite() && v.abs() < 1e9);
        if !finite(&self.gram) || !finite(&self.projections) {
            problems.push("solve: every number must be finite".into());
        }
        if !(0.0..=1.0).contains(&self.sparsity) {
            problems.push(format!("solve.sparsity: {} is outside 0..1", self.sparsity));
        }
        problems
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two orthogonal shapes and one that is both at once: a channel that is the sum finds the
    /// combined shape (one shape is cheaper than two); each alone finds its own.
    #[test]
    fn the_solve_matches_combinations_with_few_shapes() {
        // Shapes: a = (1,0), b = (0,1), ab = (1,1). Channels: a, b.
        let shapes = [[1.0f32, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let channels = [[1.0f32, 0.0], [0.0, 1.0]];
        let dot = |p: &[f32; 2], q: &[f32; 2]| p[0] * q[0] + p[1] * q[1];
        let solve = Solve {
            shapes: vec!["a".into(), "b".into(), "ab".into()],
            channels: vec!["jawOpen".into(), "mouthFunnel".into()],
            gram: shapes
                .iter()
                .map(|s| shapes.iter().map(|t| dot(s, t)).collect())
                .collect(),
            projections: shapes
                .iter()
                .map(|s| channels.iter().map(|c| dot(s, c)).collect())
                .collect(),
            sparsity: 0.05,
        };
        let both = solve.weights(&[1.0, 1.0]);
        assert!(both[2] > 0.9 && both[0] < 0.1 && both[1] < 0.1, "{both:?}");
        let one = solve.weights(&[0.8, 0.0]);
        assert!((one[0] - 0.8).abs() < 1e-3 && one[2] < 0.05, "{one:?}");
        assert_eq!(solve.weights(&[0.0, 0.0]), vec![0.0; 3]);
        assert!(
            solve
                .problems(&["a".into(), "b".into(), "ab".into()])
                .is_empty()
        );
    }
}
