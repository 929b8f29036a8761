//! Left/right symmetry: the mirror plane, each vertex's mirror partner, and blendshape pairs.
//!
//! The plane is found from the geometry (the axis-aligned plane through the mesh's middle that
//! maps the most vertices onto other vertices), as a robust fit: real faces are never exactly
//! symmetric, so the match tolerance grows from 0.2 % of the size (a mirrored model) to 2.5 %
//! (a scanned or sculpted face, a few millimetres on a head) until most vertices find a partner,
//! and the plane's offset is the median of the matched pairs' midpoints. Blendshape partners
//! come first from names (see [`crate::names::sided`]) and, for blendshapes whose names say
//! nothing, from geometry: two blendshapes that are each other's best mirror, and mirror onto
//! each other better than either mirrors onto itself.
//!
//! Orientation: glTF characters face +Z with +Y up, so the character's left is +X. For a plane
//! on another axis, "left" is the positive side of that axis.

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::character::{Aabb, Blendshape, BlendshapeId};
use crate::names::{self, Side};

/// Vertices closer than one of these fractions of the size to a mirrored vertex count as its
/// partner: the first at which the plane is found is used. A mirrored model matches at the
/// first; scanned and sculpted heads are symmetric to a few millimetres, not to float precision.
const MIRROR_TOLERANCES: [f32; 4] = [2e-3, 6e-3, 1.2e-2, 2.5e-2];
/// A plane is a symmetry plane when at least this fraction of vertices have a partner.
const MIN_MIRRORED_FRACTION: f32 = 0.6;
/// Two blendshapes can be geometric partners when the mirrored deltas of one differ from the
/// other's by less than this fraction of their magnitude (sum of squares); a sculpted face's
/// left and right shapes differ in strength and extent, so this is loose, and the pairing also
/// asks that each is the other's best mirror and that neither mirrors onto itself as well.
const PAIR_RELATIVE_ERROR: f32 = 0.35;

/// A coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// X.
    X,
    /// Y.
    Y,
    /// Z.
    Z,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// The mirror plane `p[axis] = offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorPlane {
    /// The plane's normal axis.
    pub axis: Axis,
    /// Where it cuts that axis.
    pub offset: f32,
}

impl MirrorPlane {
    /// Mirrors a point across the plane.
    #[must_use]
    pub fn reflect_point(&self, p: Vec3) -> Vec3 {
        let mut q = p;
        let i = self.axis.index();
        q[i] = 2.0 * self.offset - p[i];
        q
    }

    /// Mirrors a direction (a delta) across the plane.
    #[must_use]
    pub fn reflect_vector(&self, v: Vec3) -> Vec3 {
        let mut q = v;
        let i = self.axis.index();
        q[i] = -v[i];
        q
    }

    /// The component of a direction across the plane, positive towards the character's left.
    #[must_use]
    pub fn across(&self, v: Vec3) -> f32 {
        v[self.axis.index()]
    }

    /// Signed distance of `p` from the plane, positive on the character's left.
    #[must_use]
    pub fn side_of(&self, p: Vec3) -> f32 {
        p[self.axis.index()] - self.offset
    }
}

/// How a blendshape pair was recognised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairSource {
    /// Their names differ only by side.
    Names,
    /// One's mirrored deltas match the other's.
    Geometry,
}

/// Two blendshapes that mirror each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlendshapePair {
    /// The one acting on the character's left.
    pub left: BlendshapeId,
    /// The one acting on the character's right.
    pub right: BlendshapeId,
    /// How the pair was found.
    pub source: PairSource,
}

/// The symmetry of a character. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct Symmetry {
    plane: Option<MirrorPlane>,
    mirror: Vec<Option<u32>>,
    pairs: Vec<BlendshapePair>,
}

impl Symmetry {
    /// Finds the plane, the vertex partners and the blendshape pairs.
    ///
    /// `bounds` is the region the size is measured on (the head of a full-body character).
    #[must_use]
    pub fn detect(positions: &[Vec3], bounds: &Aabb, shapes: &[Blendshape]) -> Symmetry {
        let points: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
        let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&points);
        let size = bounds.diagonal().max(f32::MIN_POSITIVE);
        let found = MIRROR_TOLERANCES.iter().find_map(|fraction| {
            let tolerance = fraction * size;
            find_plane(positions, bounds, &tree, tolerance).map(|plane| (plane, tolerance))
        });
        let plane = found.map(|(plane, _)| plane);
        let mirror = match found {
            Some((plane, tolerance)) => mirror_map(positions, &tree, plane, tolerance),
            None => vec![None; positions.len()],
        };
        let mut pairs = pairs_by_name(shapes);
        if let Some(plane) = plane {
            pairs.extend(pairs_by_geometry(positions, shapes, &pairs, plane, &mirror));
        }
        pairs.sort_by_key(|p| p.left.min(p.right));
        Symmetry {
            plane,
            mirror,
            pairs,
        }
    }

    /// The mirror plane, if the mesh is symmetric.
    #[must_use]
    pub fn plane(&self) -> Option<MirrorPlane> {
        self.plane
    }

    /// The vertex at `vertex`'s mirrored position (itself on the plane), if there is one.
    #[must_use]
    pub fn mirror_vertex(&self, vertex: u32) -> Option<u32> {
        self.mirror.get(vertex as usize).copied().flatten()
    }

    /// Fraction of vertices that have a mirror partner.
    #[must_use]
    pub fn mirrored_fraction(&self) -> f32 {
        if self.mirror.is_empty() {
            return 0.0;
        }
        self.mirror.iter().filter(|m| m.is_some()).count() as f32 / self.mirror.len() as f32
    }

    /// Left/right blendshape pairs.
    #[must_use]
    pub fn pairs(&self) -> &[BlendshapePair] {
        &self.pairs
    }

    /// The blendshape that mirrors `id`, if any.
    #[must_use]
    pub fn partner(&self, id: BlendshapeId) -> Option<BlendshapeId> {
        self.pairs.iter().find_map(|p| {
            if p.left == id {
                Some(p.right)
            } else if p.right == id {
                Some(p.left)
            } else {
                None
            }
        })
    }
}

/// Tries the three axis planes through the middle on a sample of vertices, refines the best
/// plane's offset from the matched pairs, and keeps it if enough vertices mirror.
fn find_plane(
    positions: &[Vec3],
    bounds: &Aabb,
    tree: &ImmutableKdTree<f32, 3>,
    tolerance: f32,
) -> Option<MirrorPlane> {
    let step = (positions.len() / 2000).max(1);
    let sample: Vec<Vec3> = positions.iter().step_by(step).copied().collect();
    let center = bounds.center();
    let mut best: Option<(f32, MirrorPlane)> = None;
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let mut plane = MirrorPlane {
            axis,
            offset: center[axis.index()],
        };
        // Twice: the box centre can be off when one side carries an extra part.
        for _ in 0..2 {
            let mut midpoints = Vec::new();
            for &p in &sample {
                let q = plane.reflect_point(p);
                let hit = tree.nearest_one::<SquaredEuclidean>(&q.to_array());
                if hit.distance <= tolerance * tolerance {
                    let partner = positions[hit.item as usize];
                    midpoints.push(0.5 * (p[axis.index()] + partner[axis.index()]));
                }
            }
            if midpoints.is_empty() {
                break;
            }
            midpoints.sort_by(f32::total_cmp);
            plane.offset = midpoints[midpoints.len() / 2];
            let fraction = midpoints.len() as f32 / sample.len() as f32;
            if best.is_none_or(|(f, _)| fraction > f) {
                best = Some((fraction, plane));
            }
        }
    }
    best.filter(|(fraction, _)| *fraction >= MIN_MIRRORED_FRACTION)
        .map(|(_, plane)| plane)
}

fn mirror_map(
    positions: &[Vec3],
    tree: &ImmutableKdTree<f32, 3>,
    plane: MirrorPlane,
    tolerance: f32,
) -> Vec<Option<u32>> {
    positions
        .iter()
        .map(|&p| {
            let hit = tree.nearest_one::<SquaredEuclidean>(&plane.reflect_point(p).to_array());
            (hit.distance <= tolerance * tolerance).then_some(hit.item as u32)
        })
        .collect()
}

fn pairs_by_name(shapes: &[Blendshape]) -> Vec<BlendshapePair> {
    let sided: Vec<_> = shapes.iter().map(|s| names::sided(s.name())).collect();
    let mut pairs = Vec::new();
    let mut used = vec![false; shapes.len()];
    for (i, a) in sided.iter().enumerate() {
        let Some(a) = a else { continue };
        if used[i] || a.side != Side::Left {
            continue;
        }
        let partner = sided.iter().enumerate().position(|(j, b)| {
            !used[j]
                && b.as_ref()
                    .is_some_and(|b| b.side == Side::Right && b.stem == a.stem)
        });
        if let Some(j) = partner {
            used[i] = true;
            used[j] = true;
            pairs.push(BlendshapePair {
                left: BlendshapeId(i as u32),
                right: BlendshapeId(j as u32),
                source: PairSource::Names,
            });
        }
    }
    pairs
}

fn pairs_by_geometry(
    positions: &[Vec3],
    shapes: &[Blendshape],
    named: &[BlendshapePair],
    plane: MirrorPlane,
    mirror: &[Option<u32>],
) -> Vec<BlendshapePair> {
    let paired = |i: usize| {
        named
            .iter()
            .any(|p| p.left.index() == i || p.right.index() == i)
    };
    // Only shapes without a partner by name that move something.
    let mut dense = vec![Vec3::ZERO; positions.len()];
    let candidates: Vec<usize> = (0..shapes.len())
        .filter(|&i| !paired(i) && shapes[i].moved() > 0)
        .collect();
    // error[a][b]: a mirrored against b; the diagonal is how well a mirrors onto itself (jawOpen
    // does, and must not pair with a look-alike).
    let n = candidates.len();
    let mut error = vec![f32::INFINITY; n * n];
    for (kb, &b) in candidates.iter().enumerate() {
        shapes[b].write_dense(&mut dense);
        let norm_b: f32 = shapes[b].deltas().iter().map(|d| d.length_squared()).sum();
        for (ka, &a) in candidates.iter().enumerate() {
            error[ka * n + kb] = mirrored_error(&shapes[a], &dense, norm_b, plane, mirror);
        }
    }
    // Symmetrised, so that a pair's error does not depend on which one is mirrored.
    let pair_error = |ka: usize, kb: usize| 0.5 * (error[ka * n + kb] + error[kb * n + ka]);
    let best_of = |ka: usize| {
        (0..n)
            .filter(|&kb| kb != ka)
            .map(|kb| (pair_error(ka, kb), kb))
            .min_by(|x, y| x.0.total_cmp(&y.0))
    };
    let mut pairs = Vec::new();
    for ka in 0..n {
        let Some((e, kb)) = best_of(ka) else { continue };
        let mutual = best_of(kb).is_some_and(|(_, back)| back == ka);
        let beats_self = e < error[ka * n + ka] && e < error[kb * n + kb];
        if ka < kb && mutual && beats_self && e < PAIR_RELATIVE_ERROR {
            let (a, b) = (candidates[ka], candidates[kb]);
            let (left, right) = if motion_side(positions, &shapes[a], plane) >= 0.0 {
                (a, b)
            } else {
                (b, a)
            };
            pairs.push(BlendshapePair {
                left: BlendshapeId(left as u32),
                right: BlendshapeId(right as u32),
                source: PairSource::Geometry,
            });
        }
    }
    pairs
}

/// Relative squared error between `a` mirrored across the plane and the dense deltas `b`, whose
/// sum of squares is `norm_b`.
fn mirrored_error(
    a: &Blendshape,
    b: &[Vec3],
    norm_b: f32,
    plane: MirrorPlane,
    mirror: &[Option<u32>],
) -> f32 {
    let norm_a: f32 = a.deltas().iter().map(|d| d.length_squared()).sum();
    let scale = norm_a.max(norm_b);
    if scale <= 0.0 {
        return f32::INFINITY;
    }
    // Σ|m(a) − b|² = Σ|b|² + Σ over a's mirrored vertices of (|m(a)|² − 2 m(a)·b).
    let mut error = norm_b;
    for (&v, &d) in a.indices().iter().zip(a.deltas()) {
        match mirror.get(v as usize).copied().flatten() {
            Some(m) => {
                let md = plane.reflect_vector(d);
                error += md.length_squared() - 2.0 * md.dot(b[m as usize]);
            }
            // A moved vertex with no mirror partner: that motion has no counterpart.
            None => error += d.length_squared(),
        }
    }
    error.max(0.0) / scale
}

/// Which side a blendshape acts on (positive = the character's left).
///
/// Most sided shapes move vertices on one side (`mouthSmile_L`): there the location decides.
/// Some move a symmetric region sideways (`jawLeft`): there the direction of motion decides.
fn motion_side(positions: &[Vec3], shape: &Blendshape, plane: MirrorPlane) -> f32 {
    let mut signed = 0.0;
    let mut unsigned = 0.0;
    let mut sideways = 0.0;
    for (&v, d) in shape.indices().iter().zip(shape.deltas()) {
        let side = plane.side_of(positions[v as usize]);
        signed += d.length() * side;
        unsigned += d.length() * side.abs();
        sideways += plane.across(*d);
    }
    let located = unsigned > 0.0 && (signed / unsigned).abs() > 0.5;
    if located { signed } else { sideways }
}
