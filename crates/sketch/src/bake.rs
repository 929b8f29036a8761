//! Baking a sketch for glTF: what any glTF player must see to reproduce the engine's vertex
//! positions at every frame.
//!
//! Blendshape weights go out as they are. Arcs and exaggerations are not weights, so they
//! become extra morph targets with animated weights:
//! - each action's exaggeration offsets are one target, weighted by how much of that action's
//!   target pose is present (fading in during the action, out during the next one of its chain);
//! - each arc's swing, `u·f(θκ_j, s) + v·g(θκ_j, s)` per vertex (see [`crate::arc`]), is a
//!   function of the frame and of the vertex's share κ_j. It is factored as
//!   `Σ_k c_k(frame)·D_k[j]` by pivoted Gram–Schmidt over the action's frames, adding basis
//!   vectors until the error is below [`ARC_TOLERANCE`]; each `D_k` is a target, `c_k` its
//!   weight track.
//!
//! At every frame, positions from the exported targets and weights match the engine's within
//! [`EXPORT_TOLERANCE`] × the character's size (tested frame by frame).

use std::collections::HashMap;

use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::{Blendshape, Character, ModelError};
use glam::Vec3;

use crate::arc::deviation_coefficients;
use crate::engine::{ActionId, Sketch};
use crate::evaluate::{FramePose, active};

/// Largest error of one arc's factored swing, relative to the character's size.
pub const ARC_TOLERANCE: f32 = 2e-6;
/// Largest difference between the engine's and an exported animation's vertex positions at any
/// frame, relative to the character's size (10 µm on a 0.47 m head).
pub const EXPORT_TOLERANCE: f32 = 2e-5;
/// At most this many basis targets per arc (the error bound usually needs 3 to 6).
const MAX_ARC_BASIS: usize = 16;

/// A character extended with the baked targets, and the animation that drives them.
#[derive(Debug, Clone)]
pub struct Baked {
    /// The character's blendshapes followed by the extra targets.
    pub character: Character,
    /// One key per frame for every target.
    pub animation: MorphAnimation,
}

/// One extra target and its weight at each frame.
struct Extra {
    shape: Blendshape,
    weights: Vec<f32>,
}

impl Sketch<'_> {
    /// Bakes the sketch for export (see the module docs).
    ///
    /// # Errors
    /// A [`ModelError`] if an extra target is inconsistent (a bug, reported rather than hidden).
    pub fn bake(&self, name: &str) -> Result<Baked, ModelError> {
        let character = self.character();
        let last = self.last_frame().ceil() as usize;
        let frames = last + 1;
        let mut extras: Vec<Extra> = Vec::new();

        // Exaggerations: one target per action whose target pose has offsets.
        let mut exaggeration_slot: HashMap<ActionId, usize> = HashMap::new();
        for (id, action) in self.actions() {
            if !action.to.offsets.is_empty() {
                exaggeration_slot.insert(id, extras.len());
                extras.push(Extra {
                    shape: Blendshape::from_sparse(
                        format!("faceanim:exaggeration:{}", id.0),
                        action.to.offsets.indices().to_vec(),
                        action.to.offsets.values().to_vec(),
                    ),
                    weights: vec![0.0; frames],
                });
            }
        }
        for f in 0..frames {
            for (id, action) in active(self.actions(), f as f32) {
                let s = action.progress(f as f32);
                if let Some(&slot) = exaggeration_slot.get(&id) {
                    extras[slot].weights[f] += s;
                }
                if let Some(&slot) = action.previous.and_then(|p| exaggeration_slot.get(&p)) {
                    extras[slot].weights[f] += 1.0 - s;
                }
            }
        }

        // Arcs: a factored basis per side that swings.
        let tolerance = f64::from(ARC_TOLERANCE * character.size());
        for (id, action) in self.actions() {
            let inside: Vec<usize> = (0..frames)
                .filter(|&f| (f as f32) > action.start_frame && (f as f32) < action.end_frame())
                .collect();
            if inside.is_empty() {
                continue;
            }
            let progress: Vec<f64> = inside
                .iter()
                .map(|&f| f64::from(action.progress(f as f32)))
                .collect();
            for side in 0..action.sides.len() as u8 {
                let Some(arc) = Sketch::arc(action, side) else {
                    continue;
                };
                let members: Vec<(u32, f32)> = action
                    .swing
                    .iter()
                    .filter(|(_, _, s)| *s == side)
                    .map(|&(v, k, _)| (v, k))
                    .collect();
                if members.is_empty() {
                    continue;
                }
                let u = arc.radius_vector.as_dvec3();
                let v = arc.tangent_vector().as_dvec3();
                let radius = u.length().max(f64::MIN_POSITIVE);
                let theta = f64::from(arc.angle);
                let basis = factor(&members, theta, &progress, tolerance / radius);
                for (
                    k,
                    ArcBasis {
                        frame_weights,
                        coefficients,
                    },
                ) in basis.into_iter().enumerate()
                {
                    let mut weights = vec![0.0; frames];
                    for (&f, &c) in inside.iter().zip(&frame_weights) {
                        weights[f] = c as f32;
                    }
                    let deltas: Vec<Vec3> = coefficients
                        .iter()
                        .map(|&(alpha, beta)| (u * alpha + v * beta).as_vec3())
                        .collect();
                    let (indices, deltas): (Vec<u32>, Vec<Vec3>) = members
                        .iter()
                        .map(|&(vertex, _)| vertex)
                        .zip(deltas)
                        .filter(|(_, d)| *d != Vec3::ZERO)
                        .unzip();
                    extras.push(Extra {
                        shape: Blendshape::from_sparse(
                            format!("faceanim:arc:{}:{side}:{k}", id.0),
                            indices,
                            deltas,
                        ),
                        weights,
                    });
                }
            }
        }

        let extended =
            character.with_extra_blendshapes(extras.iter().map(|e| e.shape.clone()).collect())?;
        let mut pose = FramePose::new(character);
        let mut weights = Vec::with_capacity(frames);
        for f in 0..frames {
            self.frame_into(f as f32, &mut pose);
            let mut row = pose.weights.clone();
            row.extend(extras.iter().map(|e| e.weights[f]));
            weights.push(row);
        }
        let times = (0..frames).map(|f| f as f32 / self.fps()).collect();
        let times = if frames == 1 { vec![0.0] } else { times };
        Ok(Baked {
            character: extended,
            animation: MorphAnimation {
                name: name.to_owned(),
                times,
                weights,
                rotations: None,
            },
        })
    }
}

/// One basis vector of a factored swing: its weight at each frame, and per member vertex the
/// coefficients `(α, β)` of the shared vectors `u` and `v`.
struct ArcBasis {
    frame_weights: Vec<f64>,
    coefficients: Vec<(f64, f64)>,
}

/// Factors the swing coefficients `f(θκ, s)`, `g(θκ, s)` of `members` over the frames'
/// progress values: returns for each basis vector its per-frame weights and, per member,
/// the `(α, β)` such that `f ≈ Σ α·c` and `g ≈ Σ β·c`, with error below `tolerance` (in units
/// of the arc's radius; `f` and `g` errors each get half).
fn factor(members: &[(u32, f32)], theta: f64, progress: &[f64], tolerance: f64) -> Vec<ArcBasis> {
    let frames = progress.len();
    // Columns depend on κ only; share them between vertices with (nearly) equal κ.
    let mut keys: Vec<u32> = members.iter().map(|&(_, k)| (k * 1e6) as u32).collect();
    keys.sort_unstable();
    keys.dedup();
    let column = |kappa: f64| -> (Vec<f64>, Vec<f64>) {
        progress
            .iter()
            .map(|&s| deviation_coefficients(theta * kappa, s))
            .unzip()
    };
    let mut residuals: Vec<Vec<f64>> = Vec::with_capacity(keys.len() * 2);
    for &key in &keys {
        let (f, g) = column(f64::from(key) / 1e6);
        residuals.push(f);
        residuals.push(g);
    }
    let norm = |c: &[f64]| c.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    while basis.len() < MAX_ARC_BASIS.min(frames) {
        let Some((pivot, largest)) = residuals
            .iter()
            .enumerate()
            .map(|(i, c)| (i, norm(c)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            break;
        };
        if largest <= 0.5 * tolerance {
            break;
        }
        let c: Vec<f64> = residuals[pivot].iter().map(|x| x / largest).collect();
        for r in &mut residuals {
            let dot: f64 = r.iter().zip(&c).map(|(a, b)| a * b).sum();
            r.iter_mut().zip(&c).for_each(|(a, b)| *a -= dot * b);
        }
        basis.push(c);
    }
    let coefficients: Vec<Vec<(f64, f64)>> = members
        .iter()
        .map(|&(_, kappa)| {
            let (f, g) = column(f64::from(kappa));
            basis
                .iter()
                .map(|c| {
                    (
                        f.iter().zip(c).map(|(a, b)| a * b).sum(),
                        g.iter().zip(c).map(|(a, b)| a * b).sum(),
                    )
                })
                .collect()
        })
        .collect();
    basis
        .into_iter()
        .enumerate()
        .map(|(k, c)| ArcBasis {
            frame_weights: c,
            coefficients: coefficients.iter().map(|per| per[k]).collect(),
        })
        .collect()
}
