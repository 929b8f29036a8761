//! Mesh connectivity: which vertices share an edge, and which triangles touch each vertex.
//!
//! Vertices at exactly the same position (split along UV seams or material borders) are joined
//! by zero-length edges, so that distances over the surface — the exaggeration falloff of the
//! sketch engine — flow across seams the way an animator sees the surface.

use std::collections::HashMap;

use glam::Vec3;

/// Compressed adjacency lists: vertex neighbours and vertex→triangle incidence.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeGraph {
    neighbour_start: Vec<u32>,
    neighbours: Vec<u32>,
    triangle_start: Vec<u32>,
    triangles: Vec<u32>,
    /// Smallest index of the vertices sharing this vertex's position.
    weld: Vec<u32>,
}

impl EdgeGraph {
    /// Builds the graph of `triangles` over `positions` (indices are assumed valid).
    #[must_use]
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> EdgeGraph {
        let n = positions.len();
        let weld = weld_map(positions);

        let mut pairs: Vec<u64> = Vec::with_capacity(triangles.len() * 6 + n);
        let key = |a: u32, b: u32| (u64::from(a) << 32) | u64::from(b);
        for &[a, b, c] in triangles {
            for (x, y) in [(a, b), (b, c), (c, a)] {
                if x != y {
                    pairs.push(key(x, y));
                    pairs.push(key(y, x));
                }
            }
        }
        for (v, &w) in weld.iter().enumerate() {
            let v = v as u32;
            if w != v {
                pairs.push(key(v, w));
                pairs.push(key(w, v));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let (neighbour_start, neighbours) =
            compress(n, pairs.iter().map(|&p| ((p >> 32) as u32, p as u32)));

        let mut incidence: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 3);
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                incidence.push((v, t as u32));
            }
        }
        incidence.sort_unstable();
        incidence.dedup();
        let (triangle_start, triangles) = compress(n, incidence.into_iter());

        EdgeGraph {
            neighbour_start,
            neighbours,
            triangle_start,
            triangles,
            weld,
        }
    }

    /// Vertices sharing an edge with `vertex` (including coincident seam vertices).
    #[must_use]
    pub fn neighbours(&self, vertex: u32) -> &[u32] {
        row(&self.neighbour_start, &self.neighbours, vertex)
    }

    /// Triangles that use `vertex`.
    #[must_use]
    pub fn triangles_of(&self, vertex: u32) -> &[u32] {
        row(&self.triangle_start, &self.triangles, vertex)
    }

    /// The representative (smallest index) of the vertices at `vertex`'s exact position.
    #[must_use]
    pub fn weld_representative(&self, vertex: u32) -> u32 {
        self.weld.get(vertex as usize).copied().unwrap_or(vertex)
    }

    /// Number of undirected edges (seam joins included).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.neighbours.len() / 2
    }
}

/// For each vertex, the smallest index with bit-identical position.
fn weld_map(positions: &[Vec3]) -> Vec<u32> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // +0.0 and -0.0 are the same place.
            let bits = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f32::to_bits);
            *first.entry(bits).or_insert(i as u32)
        })
        .collect()
}

/// Builds CSR arrays from (row, value) pairs sorted by row.
fn compress(rows: usize, sorted: impl Iterator<Item = (u32, u32)>) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; rows + 1];
    let mut values = Vec::new();
    for (row, value) in sorted {
        start[row as usize + 1] += 1;
        values.push(value);
    }
    for i in 0..rows {
        start[i + 1] += start[i];
    }
    (start, values)
}

/// Row `vertex` of a compressed table: `items[starts[vertex]..starts[vertex + 1]]` (empty for
/// a vertex past the end).
fn row<'a>(starts: &[u32], items: &'a [u32], vertex: u32) -> &'a [u32] {
    let v = vertex as usize;
    match (starts.get(v), starts.get(v + 1)) {
        (Some(&s), Some(&e)) => &items[s as usize..e as usize],
        _ => &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_with_a_seam() {
        // Two triangles sharing edge 1-2, and vertex 4 duplicating vertex 3's position.
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE, Vec3::ONE];
        let triangles = vec![[0, 1, 2], [1, 3, 2], [1, 4, 0]];
        let g = EdgeGraph::build(&positions, &triangles);
        assert_eq!(g.neighbours(0), &[1, 2, 4]);
        assert_eq!(g.neighbours(3), &[1, 2, 4]);
        assert_eq!(g.neighbours(4), &[0, 1, 3]);
        assert_eq!(g.triangles_of(1), &[0, 1, 2]);
        assert_eq!(g.weld_representative(4), 3);
        assert_eq!(g.neighbours(99), &[] as &[u32]);
    }
}
