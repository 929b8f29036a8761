//! Vertex normals of the neutral mesh and of each blendshape.
//!
//! glTF players blend normals the way they blend positions (neutral + Σ wᵢ·Δnᵢ, then
//! normalise), so every blendshape carries sparse normal deltas. They are computed here when the
//! source file did not provide them: the blendshape at weight 1 re-normalled around the vertices
//! it moves, minus the neutral normals computed the same way.

use glam::Vec3;

use crate::blendshape::Blendshape;
use crate::graph::EdgeGraph;

/// Normal changes below this length are not stored. Normals are unit vectors, so 1e-4 is a turn
/// of 0.006°, far below what shading can show (an 8-bit colour step needs about 0.2°); on the ICT
/// head it drops 12% of the entries, which pose evaluation would otherwise add every frame.
const NORMAL_DELTA_THRESHOLD: f32 = 1e-4;

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
            return Err(format!(
                "{} normal indices but {} normal deltas",
                self.indices.len(),
                self.deltas.len()
            ));
        }
        if self.indices.windows(2).any(|w| w[0] >= w[1]) {
            return Err("normal delta indices are not strictly increasing".into());
        }
        if self
            .indices
            .last()
            .is_some_and(|&v| v as usize >= vertex_count)
        {
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

/// The normal deltas of every blendshape.
///
/// Neutral face normals are computed once; for each blendshape only the triangles touching a
/// moved vertex are re-evaluated, and their change is added to the per-vertex sums of their
/// (welded) corners. Work per blendshape is proportional to the region it moves.
#[must_use]
pub fn blendshape_normal_deltas(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    graph: &EdgeGraph,
    shapes: &[Blendshape],
) -> Vec<NormalDeltas> {
    let n = positions.len();
    let face_before: Vec<Vec3> = triangles
        .iter()
        .map(|&[a, b, c]| face_normal(positions, a, b, c))
        .collect();
    let mut sum_before = vec![Vec3::ZERO; n];
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        for v in [a, b, c] {
            sum_before[graph.weld_representative(v) as usize] += face_before[t];
        }
    }
    // Blendshapes are independent: share them among the cores, each with its own scratch.
    let threads = std::thread::available_parallelism()
        .map_or(1, std::num::NonZero::get)
        .min(8);
    let chunk = shapes.len().div_ceil(threads).max(1);
    let context = DeltaContext {
        positions,
        triangles,
        graph,
        face_before: &face_before,
        sum_before: &sum_before,
    };
    if threads == 1 || shapes.len() < 4 {
        return context.deltas_of(shapes);
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> = shapes
            .chunks(chunk)
            .map(|part| scope.spawn(|| context.deltas_of(part)))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|payload| std::panic::resume_unwind(payload))
            })
            .collect()
    })
}

/// What every blendshape's normal deltas are computed against.
struct DeltaContext<'a> {
    positions: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    graph: &'a EdgeGraph,
    face_before: &'a [Vec3],
    sum_before: &'a [Vec3],
}

impl DeltaContext<'_> {
    fn deltas_of(&self, shapes: &[Blendshape]) -> Vec<NormalDeltas> {
        let (positions, triangles, graph) = (self.positions, self.triangles, self.graph);
        let n = positions.len();
        // Scratch reused across blendshapes; stamps avoid clearing whole arrays.
        let mut delta = vec![Vec3::ZERO; n];
        let mut sum_after = vec![Vec3::ZERO; n];
        let mut rep_stamp = vec![u32::MAX; n];
        let mut tri_stamp = vec![u32::MAX; triangles.len()];
        let mut touched_tris: Vec<u32> = Vec::new();
        let mut touched_reps: Vec<u32> = Vec::new();
        shapes
            .iter()
            .enumerate()
            .map(|(k, shape)| {
                let stamp = k as u32;
                for (v, d) in shape.moves() {
                    delta[v as usize] = d;
                }
                touched_tris.clear();
                for &v in shape.indices() {
                    for &t in graph.triangles_of(v) {
                        if std::mem::replace(&mut tri_stamp[t as usize], stamp) != stamp {
                            touched_tris.push(t);
                        }
                    }
                }
                touched_reps.clear();
                for &t in &touched_tris {
                    let [a, b, c] = triangles[t as usize];
                    let moved = |v: u32| positions[v as usize] + delta[v as usize];
                    let (pa, pb, pc) = (moved(a), moved(b), moved(c));
                    let change = (pb - pa).cross(pc - pa) - self.face_before[t as usize];
                    for v in [a, b, c] {
                        let rep = graph.weld_representative(v) as usize;
                        if std::mem::replace(&mut rep_stamp[rep], stamp) != stamp {
                            sum_after[rep] = self.sum_before[rep];
                            touched_reps.push(rep as u32);
                        }
                        sum_after[rep] += change;
                    }
                }
                let mut out: Vec<(u32, Vec3)> = Vec::new();
                for &rep in &touched_reps {
                    let r = rep as usize;
                    let d = unit_or_up(sum_after[r]) - unit_or_up(self.sum_before[r]);
                    if d.length_squared() <= NORMAL_DELTA_THRESHOLD * NORMAL_DELTA_THRESHOLD {
                        continue;
                    }
                    out.push((rep, d));
                    // Vertices welded to this one share its normal.
                    for &m in graph.neighbours(rep) {
                        if m != rep && graph.weld_representative(m) == rep {
                            out.push((m, d));
                        }
                    }
                }
                for &v in shape.indices() {
                    delta[v as usize] = Vec3::ZERO;
                }
                out.sort_unstable_by_key(|(v, _)| *v);
                let (indices, deltas) = out.into_iter().unzip();
                NormalDeltas { indices, deltas }
            })
            .collect()
    }
}

fn face_normal(positions: &[Vec3], a: u32, b: u32, c: u32) -> Vec3 {
    let (pa, pb, pc) = (
        positions[a as usize],
        positions[b as usize],
        positions[c as usize],
    );
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

    /// A unit square in the XZ plane, facing up: positions, triangles and their edges.
    fn square() -> (Vec<Vec3>, Vec<[u32; 3]>, EdgeGraph) {
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, -1.0),
        ];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let graph = EdgeGraph::build(&positions, &triangles);
        (positions, triangles, graph)
    }

    #[test]
    fn flat_square_faces_up() {
        let (positions, triangles, graph) = square();
        for n in vertex_normals(&positions, &triangles, &graph) {
            assert!((n - Vec3::Y).length() < 1e-6, "{n}");
        }
    }

    #[test]
    fn lifting_a_corner_tilts_its_normals() {
        let (positions, triangles, graph) = square();
        let shape = Blendshape::from_sparse("lift", vec![1], vec![Vec3::new(0.0, 1.0, 0.0)]);
        let deltas =
            blendshape_normal_deltas(&positions, &triangles, &graph, std::slice::from_ref(&shape))
                .remove(0);
        // Vertex 3 only touches the flat triangle, so it keeps its normal.
        assert_eq!(deltas.indices, vec![0, 1, 2]);
        assert!(deltas.deltas.iter().all(|d| d.length() > 0.1));
    }
}
