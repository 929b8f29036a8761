//! Multi-blendshape strokes: direct-manipulation blendshapes (Lewis & Anjyo 2010).
//!
//! All weights are solved at once so the pinned vertices reach their goals, by bounded least
//! squares with a regulariser towards the chain's current weights:
//! `min Σ_pins |base + Σ_b w_b·δ_b(v) − goal|² + λ·Σ_b (w_b − w⁰_b)²` with `0 ≤ w ≤ 1`,
//! solved by projected Gauss–Seidel (a handful of variables: the blendshapes that move a pin).

use faceanim_rig::{BlendshapeId, Character};
use glam::Vec3;

use crate::layer::Layer;

/// λ relative to the mean squared displacement of the variables at the pins: small enough that
/// the goal is met when the blendshapes can meet it, large enough to pick the nearest solution.
const REGULARISATION: f32 = 1e-3;
const SWEEPS: usize = 200;

/// Solves the weights for `pins` `(vertex, base position, goal)`; returns the non-zero ones.
#[must_use]
pub fn direct_manipulation(
    character: &Character,
    pins: &[(u32, Vec3, Vec3)],
    current: &Layer,
) -> Vec<(BlendshapeId, f32)> {
    let variables: Vec<(BlendshapeId, Vec<Vec3>)> = character
        .blendshape_ids()
        .filter_map(|id| {
            let shape = character.blendshape(id)?;
            let deltas: Vec<Vec3> = pins.iter().map(|&(v, _, _)| shape.delta_of(v)).collect();
            deltas
                .iter()
                .any(|d| d.length_squared() > 0.0)
                .then_some((id, deltas))
        })
        .collect();
    if variables.is_empty() {
        return Vec::new();
    }
    let scale: f32 = variables
        .iter()
        .flat_map(|(_, d)| d.iter())
        .map(|d| d.length_squared())
        .sum::<f32>()
        / variables.len() as f32;
    let lambda = REGULARISATION * scale.max(f32::MIN_POSITIVE);
    let prior: Vec<f32> = variables
        .iter()
        .map(|(id, _)| current.weight(*id))
        .collect();
    let mut w = prior.clone();
    // Residual per pin: base + Σ w δ − goal.
    let mut residual: Vec<Vec3> = pins
        .iter()
        .enumerate()
        .map(|(k, &(_, base, goal))| {
            base + variables
                .iter()
                .zip(&w)
                .map(|((_, d), &wb)| wb * d[k])
                .sum::<Vec3>()
                - goal
        })
        .collect();
    for _ in 0..SWEEPS {
        let mut change = 0.0f32;
        for (b, (_, deltas)) in variables.iter().enumerate() {
            let diag: f32 = deltas.iter().map(|d| d.length_squared()).sum::<f32>() + lambda;
            let grad: f32 = deltas
                .iter()
                .zip(&residual)
                .map(|(d, r)| d.dot(*r))
                .sum::<f32>()
                + lambda * (w[b] - prior[b]);
            let new = (w[b] - grad / diag).clamp(0.0, 1.0);
            let step = new - w[b];
            if step != 0.0 {
                for (r, d) in residual.iter_mut().zip(deltas) {
                    *r += step * *d;
                }
                w[b] = new;
                change = change.max(step.abs());
            }
        }
        if change < 1e-6 {
            break;
        }
    }
    variables
        .iter()
        .zip(w)
        .filter(|(_, w)| *w > 1e-4)
        .map(|((id, _), w)| (*id, w))
        .collect()
}
