//! Small mesh helpers: edges, normals, closest points on triangles, connected pieces, small
//! holes.

use glam::Vec3;

/// Each undirected edge of `triangles` once, `(low, high)`.
pub(crate) fn edges(triangles: &[[u32; 3]], vertices: usize) -> Vec<(u32, u32)> {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| a != b && (a as usize) < vertices && (b as usize) < vertices)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Area-weighted vertex normals of `positions` (zero for a vertex on no triangle).
pub(crate) fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = (b - a).cross(c - a);
        for &v in t {
            normals[v as usize] += n;
        }
    }
    for n in &mut normals {
        *n = n.normalize_or_zero();
    }
    normals
}

/// Each vertex's place: the first vertex at its position, to the bit, as the rig welds its
/// seams ([`EdgeGraph::weld_representative`]).
///
/// [`EdgeGraph::weld_representative`]: faceanim_rig::EdgeGraph::weld_representative
pub(crate) fn places(character: &faceanim_rig::Character) -> Vec<u32> {
    let graph = character.graph();
    (0..character.vertex_count() as u32)
        .map(|v| graph.weld_representative(v))
        .collect()
}

/// For each vertex, the first vertex of its part at its place (see [`places`]):
/// exporters split a primitive into copies of a vertex along its UV seams and hard edges (a
/// flat-shaded one has three of its own per triangle). Parts (`character`'s glTF primitives)
/// are not joined: a VRoid face's lashes and eye whites are primitives of their own whose
/// borders lie on the skin's.
pub(crate) fn copies_in_parts(character: &faceanim_rig::Character) -> Vec<u32> {
    let place = places(character);
    let mut part = vec![0; place.len()];
    let triangles = character.triangles();
    for (k, p) in character.parts().iter().enumerate() {
        for t in triangles.get(p.triangles.clone()).unwrap_or_default() {
            for &v in t {
                part[v as usize] = k;
            }
        }
    }
    first_in_group(&place, &part)
}

/// For each vertex, the first vertex with its place and group.
fn first_in_group(place: &[u32], group: &[usize]) -> Vec<u32> {
    let mut seen = std::collections::HashMap::with_capacity(place.len());
    place
        .iter()
        .zip(group)
        .enumerate()
        .map(|(v, key)| *seen.entry(key).or_insert(v as u32))
        .collect()
}

/// [`vertex_normals`] with the vertices at one place (`place`, see [`places`]) taken as one: each
/// has the normal of every triangle around the place, not only of its own side's.
pub(crate) fn welded_vertex_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    place: &[u32],
) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = (b - a).cross(c - a);
        for &v in t {
            sums[place[v as usize] as usize] += n;
        }
    }
    place
        .iter()
        .map(|&f| sums[f as usize].normalize_or_zero())
        .collect()
}

/// The triangles around each vertex.
pub(crate) fn vertex_triangles(triangles: &[[u32; 3]], vertices: usize) -> Vec<Vec<u32>> {
    let mut around = vec![Vec::new(); vertices];
    for (i, t) in triangles.iter().enumerate() {
        for &v in t {
            around[v as usize].push(i as u32);
        }
    }
    around
}

/// The connected piece each vertex belongs to (pieces numbered from 0), and how many there are.
/// The copies of a vertex (`first`, see [`copies_in_parts`]) are one: a face split along its seams
/// is still one skin.
pub(crate) fn pieces(triangles: &[[u32; 3]], first: &[u32]) -> (Vec<u32>, usize) {
    let vertices = first.len();
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for (v, &f) in first.iter().enumerate() {
        let (a, b) = (root(&mut parent, f), root(&mut parent, v as u32));
        if a != b {
            parent[b as usize] = a;
        }
    }
    for t in triangles {
        let a = root(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = root(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut number = vec![u32::MAX; vertices];
    let mut count = 0;
    let mut piece = vec![0; vertices];
    for v in 0..vertices as u32 {
        let r = root(&mut parent, v) as usize;
        if number[r] == u32::MAX {
            number[r] = count;
            count += 1;
        }
        piece[v as usize] = number[r];
    }
    (piece, count as usize)
}

/// The point of triangle `abc` nearest `p`, as barycentric weights (Ericson, Real-Time
/// Collision Detection, 5.1.5).
pub(crate) fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let (ab, ac) = (b - a, c - a);
    // How far `p`, seen from each corner, lies along the two edges from `a`.
    let along = |corner: Vec3| (ab.dot(p - corner), ac.dot(p - corner));
    let ((d1, d2), (d3, d4), (d5, d6)) = (along(a), along(b), along(c));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denominator = va + vb + vc;
    if denominator.abs() < f32::MIN_POSITIVE {
        return [1.0, 0.0, 0.0];
    }
    let (v, w) = (vb / denominator, vc / denominator);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "corner weights are exactly 0 or 1")]
mod tests {
    use super::*;

    #[test]
    fn closest_points_inside_on_edges_and_corners() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let inside = closest_on_triangle(Vec3::new(0.25, 0.25, 1.0), a, b, c);
        assert!((inside[1] - 0.25).abs() < 1e-6 && (inside[2] - 0.25).abs() < 1e-6);
        assert_eq!(
            closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c),
            [1.0, 0.0, 0.0]
        );
        let edge = closest_on_triangle(Vec3::new(0.5, -1.0, 0.0), a, b, c);
        assert!((edge[1] - 0.5).abs() < 1e-6 && edge[2] == 0.0);
    }

    #[test]
    fn two_triangles_apart_are_two_pieces_and_a_seam_is_not_a_cut() {
        let at = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let mut positions = vec![
            at(0.0, 0.0),
            at(1.0, 0.0),
            at(0.0, 1.0),
            at(5.0, 0.0),
            at(6.0, 0.0),
            at(5.0, 1.0),
            at(1.0, 1.0),
        ];
        // The places of the seven vertices, and of the two copies added below.
        let place: Vec<u32> = vec![0, 1, 2, 3, 4, 5, 6, 1, 2];
        let (piece, count) = pieces(&[[0, 1, 2], [3, 4, 5], [2, 1, 6]], &place[..7]);
        assert_eq!(count, 2);
        assert_eq!(piece[6], piece[0]);
        assert_ne!(piece[3], piece[0]);
        // The third triangle split off along a seam: its own copies of vertices 1 and 2.
        positions.extend([at(1.0, 0.0), at(0.0, 1.0)]);
        let split = [[0, 1, 2], [3, 4, 5], [8, 7, 6]];
        let (piece, count) = pieces(&split, &place);
        assert_eq!(count, 2);
        assert_eq!(piece[6], piece[0]);
        let normals = welded_vertex_normals(&positions, &split, &place);
        assert_eq!(normals[1], normals[7]);
        // The same triangle as a part of its own (a lash on the lid's border) stays apart.
        let parts = [0, 0, 0, 0, 0, 0, 1, 1, 1];
        let (piece, count) = pieces(&split, &first_in_group(&place, &parts));
        assert_eq!(count, 3);
        assert_ne!(piece[6], piece[0]);
        assert_eq!(edges(&[[0, 1, 2], [2, 1, 3]], 4).len(), 5);
    }
}

/// Triangles that close every hole of at most `longest` edges (a triangle or a few missing
/// from a scan or a damaged export), each a fan over the hole's border, facing as its
/// neighbours do, with the index of a triangle beside the hole (for its material). Larger
/// openings (the neck, the eyes' and mouth's openings) and borders that touch themselves are
/// left alone.
pub(crate) fn small_hole_fill(triangles: &[[u32; 3]], longest: usize) -> Vec<(usize, [u32; 3])> {
    use std::collections::{HashMap, HashSet};
    let mut directed: HashMap<(u32, u32), usize> = HashMap::with_capacity(triangles.len() * 3);
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            directed.insert((t[k], t[(k + 1) % 3]), i);
        }
    }
    // A border edge has no triangle on its other side; around a hole they run one way.
    let mut next: HashMap<u32, u32> = HashMap::new();
    let mut tangled: HashSet<u32> = HashSet::new();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) && next.insert(a, b).is_some() {
            tangled.insert(a);
        }
    }
    let mut seen: HashSet<u32> = HashSet::new();
    let mut fill = Vec::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        if seen.contains(&start) {
            continue;
        }
        let mut ring = vec![start];
        let mut at = start;
        let closed = loop {
            seen.insert(at);
            let Some(&n) = next.get(&at) else { break false };
            if n == start {
                break true;
            }
            if seen.contains(&n) || ring.len() > longest {
                break false;
            }
            ring.push(n);
            at = n;
        };
        if !closed
            || ring.len() < 3
            || ring.len() > longest
            || ring.iter().any(|v| tangled.contains(v))
        {
            continue;
        }
        // The border runs along its neighbours' edges; the fill runs against them.
        let beside = directed[&(ring[0], ring[1])];
        for k in 1..ring.len() - 1 {
            fill.push((beside, [ring[0], ring[k + 1], ring[k]]));
        }
    }
    fill
}

#[cfg(test)]
mod hole_tests {
    use super::small_hole_fill;

    /// A square of three by three quads (18 triangles, counter-clockwise), 4×4 vertices.
    fn grid() -> Vec<[u32; 3]> {
        let mut t = Vec::new();
        for y in 0..3u32 {
            for x in 0..3u32 {
                let a = y * 4 + x;
                t.push([a, a + 1, a + 5]);
                t.push([a, a + 5, a + 4]);
            }
        }
        t
    }

    #[test]
    fn a_missing_triangle_is_closed_facing_as_its_neighbours() {
        let whole = grid();
        // The outer border (12 edges) is an opening, not a hole.
        assert!(small_hole_fill(&whole, 8).is_empty());
        for gone in [8, 9] {
            // The centre quad's triangles: every vertex of them is inside.
            let mut holed = whole.clone();
            let removed = holed.remove(gone);
            let fill = small_hole_fill(&holed, 8);
            assert_eq!(fill.len(), 1, "{fill:?}");
            let [a, b, c] = fill[0].1;
            let turns = [[a, b, c], [b, c, a], [c, a, b]];
            assert!(turns.contains(&removed), "{:?} for {removed:?}", fill[0].1);
            let beside = holed[fill[0].0];
            assert!(beside.iter().filter(|v| removed.contains(v)).count() == 2);
        }
        // The whole centre quad: one hole of four edges, two triangles.
        let mut holed = whole.clone();
        holed.drain(8..10);
        assert_eq!(small_hole_fill(&holed, 8).len(), 2);
        assert!(small_hole_fill(&holed, 3).is_empty(), "longer than allowed");
    }
}
