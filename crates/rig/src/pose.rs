//! Evaluating a character at blendshape weights: positions and normals, as glTF players do.
//!
//! `positions = neutral + Σ wᵢ·Δᵢ` over the sparse deltas, `normals = normalise(n₀ + Σ wᵢ·Δnᵢ)`.
//! Work is proportional to the vertices the active blendshapes move, plus one pass to
//! normalise, so a 25k-vertex head evaluates in a fraction of a millisecond.

use glam::Vec3;

use crate::character::Character;

/// A deformed mesh: positions and unit normals per vertex.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Pose {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
}

impl Character {
    /// The pose at `weights` (one per blendshape; missing weights count as 0, extra ones are
    /// ignored).
    #[must_use]
    pub fn pose(&self, weights: &[f32]) -> Pose {
        let mut pose = Pose::default();
        self.pose_into(weights, &mut pose);
        pose
    }

    /// Like [`Character::pose`], reusing `pose`'s buffers (no allocation after the first call).
    pub fn pose_into(&self, weights: &[f32], pose: &mut Pose) {
        pose.positions.clear();
        pose.positions.extend_from_slice(self.positions());
        pose.normals.clear();
        pose.normals.extend_from_slice(self.normals());
        for ((shape, normal_deltas), &w) in self.blendshapes().iter().zip(self.normal_deltas()).zip(weights) {
            if w == 0.0 || !w.is_finite() {
                continue;
            }
            for (&i, &d) in shape.indices().iter().zip(shape.deltas()) {
                pose.positions[i as usize] += w * d;
            }
            for (&i, &d) in normal_deltas.indices.iter().zip(&normal_deltas.deltas) {
                pose.normals[i as usize] += w * d;
            }
        }
        for n in &mut pose.normals {
            *n = crate::normals::unit_or_up(*n);
        }
    }
}
