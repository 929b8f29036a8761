//! Small mesh helpers: edges, normals, closest points on triangles, connected pieces.

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
pub(crate) fn pieces(triangles: &[[u32; 3]], vertices: usize) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
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
    fn two_triangles_apart_are_two_pieces() {
        let (piece, count) = pieces(&[[0, 1, 2], [3, 4, 5], [2, 1, 6]], 7);
        assert_eq!(count, 2);
        assert_eq!(piece[6], piece[0]);
        assert_ne!(piece[3], piece[0]);
        assert_eq!(edges(&[[0, 1, 2], [2, 1, 3]], 4).len(), 5);
    }
}
