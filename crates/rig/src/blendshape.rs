//! One blendshape, stored sparsely, and its index within a character.

use glam::Vec3;

/// Index of a blendshape within its [`Character`](crate::Character).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BlendshapeId(pub u32);

impl BlendshapeId {
    /// The index as `usize`, for slices of per-blendshape values (weights).
    #[must_use]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Deltas whose length is below this fraction of the bounding-box diagonal are not stored.
///
/// 1e-6 of the size is about 16 f32 ulps of a coordinate of that size: below it a "delta" is
/// rounding noise from the tool that wrote the file, not a deformation. For a 0.35 m head the
/// threshold is 0.35 µm, so a round trip through faceanim changes no delta by more than that.
pub const SPARSE_DELTA_THRESHOLD: f32 = 1e-6;

/// One blendshape: the displacement of each moved vertex at weight 1, stored sparsely.
#[derive(Debug, Clone, PartialEq)]
pub struct Blendshape {
    name: String,
    /// Moved vertices, strictly increasing.
    indices: Vec<u32>,
    /// Displacement of `indices[k]` at weight 1.
    deltas: Vec<Vec3>,
}

impl Blendshape {
    /// A blendshape from dense per-vertex deltas, keeping the vertices that move by more than
    /// `threshold` (an absolute length, see [`SPARSE_DELTA_THRESHOLD`]).
    #[must_use]
    pub fn from_dense(name: impl Into<String>, dense: &[Vec3], threshold: f32) -> Blendshape {
        let mut indices = Vec::new();
        let mut deltas = Vec::new();
        let threshold_sq = threshold * threshold;
        for (index, delta) in dense.iter().enumerate() {
            if delta.length_squared() > threshold_sq {
                indices.push(index as u32);
                deltas.push(*delta);
            }
        }
        Blendshape {
            name: name.into(),
            indices,
            deltas,
        }
    }

    /// A blendshape from sparse parts. `indices` must be strictly increasing and as long as
    /// `deltas`; [`Character::new`](crate::Character::new) checks this against the vertex count.
    #[must_use]
    pub fn from_sparse(
        name: impl Into<String>,
        indices: Vec<u32>,
        deltas: Vec<Vec3>,
    ) -> Blendshape {
        Blendshape {
            name: name.into(),
            indices,
            deltas,
        }
    }

    /// The blendshape's name as the file gave it.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Moved vertices, strictly increasing.
    #[must_use]
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Displacements at weight 1, parallel to [`Blendshape::indices`].
    #[must_use]
    pub fn deltas(&self) -> &[Vec3] {
        &self.deltas
    }

    /// Each moved vertex with its displacement at weight 1, in vertex order.
    pub fn moves(&self) -> impl ExactSizeIterator<Item = (u32, Vec3)> + '_ {
        self.indices
            .iter()
            .copied()
            .zip(self.deltas.iter().copied())
    }

    /// The vertex this blendshape moves farthest and its displacement at weight 1 (of equals,
    /// the last); `None` when it moves none.
    #[must_use]
    pub fn peak(&self) -> Option<(u32, Vec3)> {
        self.moves()
            .max_by(|a, b| a.1.length_squared().total_cmp(&b.1.length_squared()))
    }

    /// Number of moved vertices.
    #[must_use]
    pub fn moved(&self) -> usize {
        self.indices.len()
    }

    /// The largest displacement of any vertex at weight 1.
    #[must_use]
    pub fn max_displacement(&self) -> f32 {
        self.deltas.iter().map(|d| d.length()).fold(0.0, f32::max)
    }

    /// The displacement of `vertex` at weight 1 (zero where it does not move).
    #[must_use]
    pub fn delta_of(&self, vertex: u32) -> Vec3 {
        match self.indices.binary_search(&vertex) {
            Ok(k) => self.deltas[k],
            Err(_) => Vec3::ZERO,
        }
    }

    /// Writes the deltas into a dense buffer (zero elsewhere); `out` must have one entry per vertex.
    pub fn write_dense(&self, out: &mut [Vec3]) {
        out.fill(Vec3::ZERO);
        for (&i, &d) in self.indices.iter().zip(&self.deltas) {
            if let Some(slot) = out.get_mut(i as usize) {
                *slot = d;
            }
        }
    }

    pub(crate) fn renamed(&self, name: String) -> Blendshape {
        Blendshape {
            name,
            indices: self.indices.clone(),
            deltas: self.deltas.clone(),
        }
    }
}
