//! Queries on the character's surface: the vertex nearest a pen position on the displayed pose
//! (a k-d tree over the neutral mesh, corrected for how far the pose moved vertices), and
//! distances along the mesh's edges for the exaggeration falloff.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use faceanim_rig::Character;
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Spatial index of a character's neutral vertices.
pub struct Surface {
    tree: ImmutableKdTree<f32, 3>,
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Surface").finish_non_exhaustive()
    }
}

impl Surface {
    /// Indexes `character`'s neutral positions.
    #[must_use]
    pub fn new(character: &Character) -> Surface {
        let points: Vec<[f32; 3]> = character.positions().iter().map(|p| p.to_array()).collect();
        Surface {
            tree: ImmutableKdTree::new_from_slice(&points),
        }
    }

    /// The vertex of the posed mesh nearest `query`, and its distance.
    ///
    /// `neutral` and `posed` are the vertex positions at rest and in the displayed pose;
    /// `max_offset` bounds how far any vertex moved. The nearest posed vertex lies within
    /// `d₀ + 2·max_offset` of the query in the neutral mesh (d₀: distance to the neutral nearest),
    /// so only those are checked.
    #[must_use]
    pub fn nearest(
        &self,
        query: Vec3,
        neutral: &[Vec3],
        posed: &[Vec3],
        max_offset: f32,
    ) -> Option<(u32, f32)> {
        let q = query.to_array();
        let first = self.tree.nearest_one::<SquaredEuclidean>(&q);
        let start = first.item as usize;
        if max_offset <= 0.0 {
            return Some((start as u32, (neutral.get(start)?.distance(query))));
        }
        let d0 = posed.get(start)?.distance(query);
        let radius = d0 + 2.0 * max_offset;
        let mut best = (start as u32, d0);
        for hit in self
            .tree
            .within_unsorted::<SquaredEuclidean>(&q, radius * radius)
        {
            let v = hit.item as usize;
            if let Some(p) = posed.get(v) {
                let d = p.distance(query);
                if d < best.1 {
                    best = (v as u32, d);
                }
            }
        }
        Some(best)
    }
}

#[derive(PartialEq)]
struct Entry(f32, u32);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    // Reversed, so the BinaryHeap pops the smallest distance first.
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// Shortest distances along the mesh's edges (neutral lengths) from `source`, for every vertex
/// closer than `radius` (Dijkstra; seam vertices are joined by zero-length edges).
#[must_use]
pub fn edge_distances(character: &Character, source: u32, radius: f32) -> Vec<(u32, f32)> {
    let positions = character.positions();
    let graph = character.graph();
    let mut best: HashMap<u32, f32> = HashMap::new();
    let mut heap = BinaryHeap::new();
    best.insert(source, 0.0);
    heap.push(Entry(0.0, source));
    let mut out = Vec::new();
    while let Some(Entry(d, v)) = heap.pop() {
        if best.get(&v).is_some_and(|&b| d > b) {
            continue;
        }
        out.push((v, d));
        for &n in graph.neighbours(v) {
            let nd = d + positions[v as usize].distance(positions[n as usize]);
            if nd < radius && best.get(&n).is_none_or(|&b| nd < b) {
                best.insert(n, nd);
                heap.push(Entry(nd, n));
            }
        }
    }
    out
}
