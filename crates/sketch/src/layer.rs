//! What one chain of strokes contributes to the face at a moment: blendshape weights plus
//! free-form offsets (exaggerations), both sparse. Chains are layers: their contributions add.

use faceanim_rig::{BlendshapeId, Character};
use glam::Vec3;

/// Sparse per-vertex offsets, indices strictly increasing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Offsets {
    indices: Vec<u32>,
    values: Vec<Vec3>,
}

impl Offsets {
    /// Offsets from (vertex, value) pairs in any order; repeated vertices add up.
    #[must_use]
    pub fn from_pairs(mut pairs: Vec<(u32, Vec3)>) -> Offsets {
        pairs.sort_unstable_by_key(|p| p.0);
        let mut out = Offsets::default();
        for (v, d) in pairs {
            if out.indices.last() == Some(&v) {
                if let Some(last) = out.values.last_mut() {
                    *last += d;
                }
            } else {
                out.indices.push(v);
                out.values.push(d);
            }
        }
        out
    }

    /// Moved vertices.
    #[must_use]
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Their offsets.
    #[must_use]
    pub fn values(&self) -> &[Vec3] {
        &self.values
    }

    /// Whether nothing moves.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The offset of `vertex` (zero if it does not move).
    #[must_use]
    pub fn get(&self, vertex: u32) -> Vec3 {
        self.indices
            .binary_search(&vertex)
            .map_or(Vec3::ZERO, |k| self.values[k])
    }

    /// Adds `scale` times these offsets into a dense buffer.
    pub fn add_scaled_to(&self, scale: f32, out: &mut [Vec3]) {
        if scale == 0.0 {
            return;
        }
        for (&v, &d) in self.indices.iter().zip(&self.values) {
            if let Some(slot) = out.get_mut(v as usize) {
                *slot += scale * d;
            }
        }
    }
}

/// A chain's contribution: weights of some blendshapes and exaggeration offsets.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Layer {
    /// Non-zero weights, by blendshape.
    pub weights: Vec<(BlendshapeId, f32)>,
    /// Exaggeration offsets.
    pub offsets: Offsets,
}

impl Layer {
    /// The weight of `id` in this layer.
    #[must_use]
    pub fn weight(&self, id: BlendshapeId) -> f32 {
        self.weights
            .iter()
            .find(|(b, _)| *b == id)
            .map_or(0.0, |(_, w)| *w)
    }

    /// This layer's displacement of `vertex` from the neutral face.
    #[must_use]
    pub fn displacement(&self, character: &Character, vertex: u32) -> Vec3 {
        let mut d = self.offsets.get(vertex);
        for &(id, w) in &self.weights {
            if let Some(shape) = character.blendshape(id) {
                d += w * shape.delta_of(vertex);
            }
        }
        d
    }

    /// Adds `scale` × this layer's weights into a dense weight vector.
    pub fn add_weights_to(&self, scale: f32, out: &mut [f32]) {
        for &(id, w) in &self.weights {
            if let Some(slot) = out.get_mut(id.index()) {
                *slot += scale * w;
            }
        }
    }

    /// Whether the layer leaves the face neutral.
    #[must_use]
    pub fn is_neutral(&self) -> bool {
        self.weights.iter().all(|(_, w)| *w == 0.0) && self.offsets.is_empty()
    }
}
