//! Vertex normals of the neutral mesh and of each blendshape.
//!
//! glTF players blend normals the way they blend positions (neutral + Σ wᵢ·Δnᵢ, then
//! normalise), so every blendshape carries sparse normal deltas. They are computed here when the
//! source file did not provide them: the blendshape at weight 1 re-normalled around the vertices
//! it moves, minus the neutral normals computed the same way.

use glam::Vec3;

use crate::character::Blendshape;
use crate::graph::EdgeGraph;

/// Normal changes below this length are not stored (normals are unit vectors).
const NORMAL_DELTA_THRESHOLD: f32 = 1e-6;

/// Sparse normal deltas of one blendshape at weight 1.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NormalDeltas {
    /// Vertices whose normal changes, strictly increasing.
    pub indices: Vec<u32>,
    /// The change of each one's normal.
    pub deltas: Vec<Vec3>,
}

impl NormalDeltas {
    pub(crate) fn check(&self, vertex_count: usize) -> Result<(), String> {
        if self.indices.len() != self.deltas.len() {
            return Err(format!("{} normal indices but {} normal deltas", self.indices.len(), self.deltas.len()));
        }
        if self.indices.windows(2).any(|w| w[0] >= w[1]) {
            return Err("normal delta indices are not strictly increasing".into());
        }
        if self.indices.last().is_some_and(|&v| v as usize >= vertex_count) {
            return Err("a normal delta names a vertex that does not exist".into());
        }
        if self.deltas.iter().any(|d| !d.is_finite()) {
            return Err("a normal delta is not a finite number".into());
        }
        Ok(())
    }
}

/// Area-weighted vertex normals, shared across coincident (welded) vertices.
#[must_use]
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]], graph: &EdgeGraph) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let face = face_normal(positions, a, b, c);
        for v in [a, b, c] {
            sums[graph.weld_representative(v) as usize] += face;
        }
    }
    (0..positions.len() as u32)
        .map(|v| unit_or_up(sums[graph.weld_representative(v) as usize]))
        .collect()
}

/// The normal deltas of `shape`: only vertices on triangles that the shape moves can change.
#[must_use]
pub fn blendshape_normal_deltas(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    graph: &EdgeGraph,
    shape: &Blendshape,
) -> NormalDeltas {
    let mut affected: Vec<u32> = Vec::new();
    for &moved in shape.indices() {
        for &t in graph.triangles_of(moved) {
            affected.extend_from_slice(&triangles[t as usize]);
        }
    }
    // Welded mates share the normal, so they change together.
    let mates: Vec<u32> = affected
        .iter()
        .flat_map(|&v| {
            let rep = graph.weld_representative(v);
            graph.neighbours(v).iter().copied().filter(move |&n| graph.weld_representative(n) == rep)
        })
        .collect();
    affected.extend(mates);
    affected.sort_unstable();
    affected.dedup();

    let moved_position = |v: u32| positions[v as usize] + shape.delta_of(v);
    let mut out = NormalDeltas::default();
    for &v in &affected {
        let mut before = Vec3::ZERO;
        let mut after = Vec3::ZERO;
        for_each_welded_triangle(graph, v, |t| {
            let [a, b, c] = triangles[t as usize];
            before += face_normal(positions, a, b, c);
            let (pa, pb, pc) = (moved_position(a), moved_position(b), moved_position(c));
            after += (pb - pa).cross(pc - pa);
        });
        let delta = unit_or_up(after) - unit_or_up(before);
        if delta.length_squared() > NORMAL_DELTA_THRESHOLD * NORMAL_DELTA_THRESHOLD {
            out.indices.push(v);
            out.deltas.push(delta);
        }
    }
    out
}

/// Calls `f` for every triangle of `vertex` and of the vertices welded to it.
fn for_each_welded_triangle(graph: &EdgeGraph, vertex: u32, mut f: impl FnMut(u32)) {
    for &t in graph.triangles_of(vertex) {
        f(t);
    }
    let rep = graph.weld_representative(vertex);
    for &n in graph.neighbours(vertex) {
        if n != vertex && graph.weld_representative(n) == rep {
            for &t in graph.triangles_of(n) {
                f(t);
            }
        }
    }
}

fn face_normal(positions: &[Vec3], a: u32, b: u32, c: u32) -> Vec3 {
    let (pa, pb, pc) = (positions[a as usize], positions[b as usize], positions[c as usize]);
    (pb - pa).cross(pc - pa)
}

/// Normalises, falling back to +Y for a degenerate sum so no NaN ever reaches a file.
pub(crate) fn unit_or_up(v: Vec3) -> Vec3 {
    let n = v.normalize_or_zero();
    if n == Vec3::ZERO { Vec3::Y } else { n }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_square_faces_up() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, -1.0)];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let graph = EdgeGraph::build(&positions, &triangles);
        for n in vertex_normals(&positions, &triangles, &graph) {
            assert!((n - Vec3::Y).length() < 1e-6, "{n}");
        }
    }

    #[test]
    fn lifting_a_corner_tilts_its_normals() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, -1.0)];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let graph = EdgeGraph::build(&positions, &triangles);
        let shape = Blendshape::from_sparse("lift", vec![1], vec![Vec3::new(0.0, 1.0, 0.0)]);
        let deltas = blendshape_normal_deltas(&positions, &triangles, &graph, &shape);
        // Vertex 3 only touches the flat triangle, so it keeps its normal.
        assert_eq!(deltas.indices, vec![0, 1, 2]);
        assert!(deltas.deltas.iter().all(|d| d.length() > 0.1));
    }
}
