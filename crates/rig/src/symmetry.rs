//! Left/right symmetry: the mirror plane, each vertex's mirror partner, and blendshape pairs.
//!
//! Real faces are never exactly symmetric, so everything here is approximate and robust:
//!
//! - **The plane.** The three axis planes through the head's middle are tried first; one that
//!   maps nearly every vertex onto another within 0.2 % of the size (a mirrored model) is kept
//!   as it is. Otherwise the best of them is refined by *reflective iterative closest points*:
//!   reflect a sample of vertices, take each one's nearest vertex, drop the worst fifth of the
//!   pairs, and fit the plane that maps the rest onto each other (its normal from the pairs'
//!   differences, its offset the median of their midpoints), until it settles. A tilted scan
//!   or a face a few millimetres lopsided gets the plane that fits it best.
//! - **The correspondence.** Each vertex's mirror is the vertex nearest its reflection, kept
//!   when it is within a tolerance grown from the fit's own residuals (four times their median,
//!   between 0.5 % and 5 % of the size): a real face's counterpart is found even where it is a
//!   few millimetres off, while parts with no counterpart (an asymmetric accessory) get none.
//! - **Blendshape pairs** come first from names (see [`crate::names::sided`]); for the others,
//!   from their displacement fields: one shape's field reflected across the plane and read at
//!   the mirrored vertices is compared with the other's, blurred over a few millimetres, by
//!   normalised correlation, so that a left smile that is stronger, a little wider or a little
//!   higher than the right one still matches it. Pairs are made one to one, strongest first,
//!   from matches that are strong enough and better than either shape's match with itself
//!   (`jawOpen` mirrors onto itself and pairs with nothing).
//!
//! Orientation: glTF characters face +Z with +Y up, so the character's left is +X. The plane's
//! normal points to the character's left (the positive side of its dominant axis).

use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::bounds::Aabb;

use crate::blendshape::{Blendshape, BlendshapeId};
use crate::names::{self, Side};

/// An axis plane that maps this fraction of the vertices onto other vertices within
/// [`EXACT_TOLERANCE`] of the size is an exact mirror plane and is kept as it is.
const EXACT_FRACTION: f32 = 0.9;
/// The tolerance of an exactly mirrored model, as a fraction of the size.
const EXACT_TOLERANCE: f32 = 2e-3;
/// A plane is a symmetry plane when at least this fraction of the sampled vertices mirror onto
/// another vertex within [`MAX_TOLERANCE`].
const MIN_MIRRORED_FRACTION: f32 = 0.6;
/// The largest and smallest distance, as a fraction of the size, at which a vertex's mirror
/// counts as its partner.
const MAX_TOLERANCE: f32 = 0.05;
/// See [`MAX_TOLERANCE`].
const MIN_TOLERANCE: f32 = 0.005;
/// The fraction of the worst pairs the plane fit ignores at each step.
const TRIM: f32 = 0.2;
/// Two blendshapes can be geometric partners when one's reflected field correlates with the
/// other's at least this well (1 is a perfect mirror; a real face's blink pair scores about 0.5).
const PAIR_CORRELATION: f32 = 0.35;
/// The radius, as a fraction of the size, over which a field is blurred before it is compared
/// with another's mirror image (about 5 mm on a head).
const BLUR: f32 = 0.012;
/// At most this many vertices make one blurred value.
const BLUR_NEIGHBOURS: usize = 24;

/// Averages a dense field over each mirrored vertex's neighbourhood, for the vertices that some
/// candidate's moved vertex mirrors onto.
struct Blur {
    /// For each mirrored vertex, the vertices within the radius (itself included).
    neighbourhoods: Vec<(u32, Vec<u32>)>,
}

impl Blur {
    fn new(
        positions: &[Vec3],
        tree: &ImmutableKdTree<f32, 3>,
        shapes: &[Blendshape],
        candidates: &[usize],
        mirror: &[Option<u32>],
        radius: f32,
    ) -> Blur {
        let mut targets: Vec<u32> = candidates
            .iter()
            .flat_map(|&c| shapes[c].indices().iter())
            .filter_map(|&v| mirror.get(v as usize).copied().flatten())
            .collect();
        targets.sort_unstable();
        targets.dedup();
        let neighbourhoods = targets
            .into_iter()
            .map(|t| {
                let near = tree
                    .nearest_n::<SquaredEuclidean>(
                        &positions[t as usize].to_array(),
                        std::num::NonZero::new(BLUR_NEIGHBOURS)
                            .unwrap_or(std::num::NonZero::<usize>::MIN),
                    )
                    .into_iter()
                    .filter(|n| n.distance <= radius * radius)
                    .map(|n| n.item as u32)
                    .collect();
                (t, near)
            })
            .collect();
        Blur { neighbourhoods }
    }

    /// `dense` blurred at the mirrored vertices, into `out` (which keeps zeros elsewhere).
    fn apply(&self, dense: &[Vec3], out: &mut [Vec3]) {
        for (t, near) in &self.neighbourhoods {
            let sum: Vec3 = near.iter().map(|&v| dense[v as usize]).sum();
            out[*t as usize] = sum / near.len().max(1) as f32;
        }
    }
}

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

    fn unit(self) -> Vec3 {
        match self {
            Axis::X => Vec3::X,
            Axis::Y => Vec3::Y,
            Axis::Z => Vec3::Z,
        }
    }
}

/// The mirror plane `normal · p = offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorPlane {
    /// The plane's unit normal, pointing to the character's left (the positive side of its
    /// dominant axis).
    pub normal: Vec3,
    /// Where it cuts the normal's line through the origin.
    pub offset: f32,
}

impl MirrorPlane {
    /// The plane `p[axis] = offset`.
    #[must_use]
    pub fn axis_aligned(axis: Axis, offset: f32) -> MirrorPlane {
        MirrorPlane {
            normal: axis.unit(),
            offset,
        }
    }

    /// The coordinate axis closest to the normal.
    #[must_use]
    pub fn axis(&self) -> Axis {
        let a = self.normal.abs();
        if a.x >= a.y && a.x >= a.z {
            Axis::X
        } else if a.y >= a.z {
            Axis::Y
        } else {
            Axis::Z
        }
    }

    /// How far the normal leans from [`MirrorPlane::axis`], in degrees.
    #[must_use]
    pub fn tilt_degrees(&self) -> f32 {
        self.normal
            .dot(self.axis().unit())
            .abs()
            .min(1.0)
            .acos()
            .to_degrees()
    }

    /// Mirrors a point across the plane.
    #[must_use]
    pub fn reflect_point(&self, p: Vec3) -> Vec3 {
        p - 2.0 * (self.normal.dot(p) - self.offset) * self.normal
    }

    /// Mirrors a direction (a delta) across the plane.
    #[must_use]
    pub fn reflect_vector(&self, v: Vec3) -> Vec3 {
        v - 2.0 * self.normal.dot(v) * self.normal
    }

    /// The component of a direction across the plane, positive towards the character's left.
    #[must_use]
    pub fn across(&self, v: Vec3) -> f32 {
        self.normal.dot(v)
    }

    /// Signed distance of `p` from the plane, positive on the character's left.
    #[must_use]
    pub fn side_of(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
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
        let sample = sample_near(positions, bounds);
        let fit = find_plane(positions, &sample, bounds, &tree, size);
        let plane = fit.map(|f| f.plane);
        let mirror = match fit {
            Some(fit) => mirror_map(positions, &tree, fit.plane, fit.tolerance),
            None => vec![None; positions.len()],
        };
        let mut pairs = pairs_by_name(shapes);
        if let Some(plane) = plane {
            pairs.extend(pairs_by_geometry(
                positions, &tree, shapes, &pairs, plane, &mirror, size,
            ));
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

/// A fitted plane and the distance within which a vertex's mirror counts as its partner.
#[derive(Debug, Clone, Copy)]
struct Fit {
    plane: MirrorPlane,
    tolerance: f32,
}

/// Up to about 4,000 vertices inside the head box (all of them when none is), evenly spread.
/// The whole head, not only the parts that move: its shape holds the plane steady where a
/// real face's features are lopsided.
fn sample_near(positions: &[Vec3], bounds: &Aabb) -> Vec<Vec3> {
    let margin = 0.05 * bounds.diagonal();
    let inside: Vec<Vec3> = positions
        .iter()
        .copied()
        .filter(|p| {
            p.cmpge(bounds.min - Vec3::splat(margin)).all()
                && p.cmple(bounds.max + Vec3::splat(margin)).all()
        })
        .collect();
    let pool = if inside.is_empty() {
        positions.to_vec()
    } else {
        inside
    };
    let step = (pool.len() / 4000).max(1);
    pool.into_iter().step_by(step).collect()
}

/// The distance from each sample's reflection to its nearest vertex.
fn residuals(sample: &[Vec3], tree: &ImmutableKdTree<f32, 3>, plane: MirrorPlane) -> Vec<f32> {
    sample
        .iter()
        .map(|&p| {
            tree.nearest_one::<SquaredEuclidean>(&plane.reflect_point(p).to_array())
                .distance
                .sqrt()
        })
        .collect()
}

fn median(values: &mut [f32]) -> f32 {
    if values.is_empty() {
        return f32::INFINITY;
    }
    values.sort_by(f32::total_cmp);
    values[values.len() / 2]
}

/// The symmetry plane of the sampled vertices, if they have one. See the module docs.
fn find_plane(
    positions: &[Vec3],
    sample: &[Vec3],
    bounds: &Aabb,
    tree: &ImmutableKdTree<f32, 3>,
    size: f32,
) -> Option<Fit> {
    if sample.is_empty() {
        return None;
    }
    let center = bounds.center();
    let within = |r: &[f32], tolerance: f32| {
        r.iter().filter(|&&d| d <= tolerance).count() as f32 / r.len() as f32
    };
    // The axis planes, each with its offset from the matched pairs' midpoints.
    let mut best: Option<(f32, MirrorPlane)> = None;
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let mut plane = MirrorPlane::axis_aligned(axis, center[axis.index()]);
        // Twice: the box centre can be off when one side carries an extra part.
        for _ in 0..2 {
            let tolerance = MAX_TOLERANCE * size;
            let mut midpoints = Vec::new();
            for &p in sample {
                let hit = tree.nearest_one::<SquaredEuclidean>(&plane.reflect_point(p).to_array());
                if hit.distance <= tolerance * tolerance {
                    let partner = positions[hit.item as usize];
                    midpoints.push(0.5 * (p[axis.index()] + partner[axis.index()]));
                }
            }
            if midpoints.is_empty() {
                break;
            }
            plane.offset = median(&mut midpoints);
        }
        // Judged by how closely the sample mirrors, not only how much of it does.
        let mut r = residuals(sample, tree, plane);
        let score = median(&mut r);
        if best.is_none_or(|(s, _)| score < s) {
            best = Some((score, plane));
        }
    }
    let (_, axis_plane) = best?;
    let r = residuals(sample, tree, axis_plane);
    if within(&r, EXACT_TOLERANCE * size) >= EXACT_FRACTION {
        return Some(Fit {
            plane: axis_plane,
            tolerance: EXACT_TOLERANCE * size,
        });
    }
    let plane = refine(sample, positions, tree, axis_plane);
    let mut r = residuals(sample, tree, plane);
    if within(&r, MAX_TOLERANCE * size) < MIN_MIRRORED_FRACTION {
        return None;
    }
    let tolerance = (4.0 * median(&mut r)).clamp(MIN_TOLERANCE * size, MAX_TOLERANCE * size);
    Some(Fit { plane, tolerance })
}

/// Reflective iterative closest points from `start`: reflect, pair with the nearest vertex,
/// drop the worst pairs, refit the plane; until the normal and offset settle.
fn refine(
    sample: &[Vec3],
    positions: &[Vec3],
    tree: &ImmutableKdTree<f32, 3>,
    start: MirrorPlane,
) -> MirrorPlane {
    let mut plane = start;
    for _ in 0..30 {
        let mut pairs: Vec<(f32, Vec3, Vec3)> = sample
            .iter()
            .map(|&p| {
                let hit = tree.nearest_one::<SquaredEuclidean>(&plane.reflect_point(p).to_array());
                (hit.distance, p, positions[hit.item as usize])
            })
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        pairs.truncate(((1.0 - TRIM) * pairs.len() as f32).ceil() as usize);
        // Each pair's difference runs along the normal (a vertex and its mirror); the ones far
        // from the plane say the most about its direction.
        let mut direction = Vec3::ZERO;
        for &(_, p, q) in &pairs {
            let d = p - q;
            direction += if d.dot(plane.normal) >= 0.0 { d } else { -d };
        }
        let normal = oriented(direction.normalize_or_zero()).unwrap_or(plane.normal);
        let mut midpoints: Vec<f32> = pairs
            .iter()
            .map(|&(_, p, q)| normal.dot(0.5 * (p + q)))
            .collect();
        let next = MirrorPlane {
            normal,
            offset: median(&mut midpoints),
        };
        let settled = next.normal.dot(plane.normal) > 1.0 - 1e-9
            && (next.offset - plane.offset).abs() < 1e-7 * (1.0 + plane.offset.abs());
        plane = next;
        if settled {
            break;
        }
    }
    plane
}

/// `n` turned so that its dominant component is positive; `None` for a zero vector.
fn oriented(n: Vec3) -> Option<Vec3> {
    if n == Vec3::ZERO || !n.is_finite() {
        return None;
    }
    let a = n.abs();
    let dominant = if a.x >= a.y && a.x >= a.z {
        n.x
    } else if a.y >= a.z {
        n.y
    } else {
        n.z
    };
    Some(if dominant < 0.0 { -n } else { n })
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
    tree: &ImmutableKdTree<f32, 3>,
    shapes: &[Blendshape],
    named: &[BlendshapePair],
    plane: MirrorPlane,
    mirror: &[Option<u32>],
    size: f32,
) -> Vec<BlendshapePair> {
    let paired = |i: usize| {
        named
            .iter()
            .any(|p| p.left.index() == i || p.right.index() == i)
    };
    // Only shapes without a partner by name that move something.
    let candidates: Vec<usize> = (0..shapes.len())
        .filter(|&i| !paired(i) && shapes[i].moved() > 0)
        .collect();
    // A real face's mirror image lands a few millimetres off its counterpart, often on another
    // layer (an eyelid's mirror on the eyeball): each shape's field is compared after blurring
    // the other's over the vertices within BLUR of the mirrored point.
    let blur = Blur::new(positions, tree, shapes, &candidates, mirror, BLUR * size);
    // similarity[a][b]: a's field reflected, against b's; the diagonal is how well a mirrors
    // onto itself (jawOpen does, and must not pair with a look-alike).
    let n = candidates.len();
    let mut similarity = vec![f32::NEG_INFINITY; n * n];
    let mut dense = vec![Vec3::ZERO; positions.len()];
    let mut blurred = vec![Vec3::ZERO; positions.len()];
    for (kb, &b) in candidates.iter().enumerate() {
        shapes[b].write_dense(&mut dense);
        blur.apply(&dense, &mut blurred);
        let norm_b: f32 = shapes[b].deltas().iter().map(|d| d.length_squared()).sum();
        for (ka, &a) in candidates.iter().enumerate() {
            similarity[ka * n + kb] =
                reflected_correlation(&shapes[a], &blurred, norm_b, plane, mirror);
        }
    }
    // Symmetrised, so that a pair's score does not depend on which one is reflected.
    let score = |ka: usize, kb: usize| 0.5 * (similarity[ka * n + kb] + similarity[kb * n + ka]);
    // One-to-one, strongest matches first: a lid's blink and its downward look both close the
    // eye a little, and the look's own partner is the better match for it.
    let mut offers: Vec<(f32, usize, usize)> = Vec::new();
    for ka in 0..n {
        for kb in ka + 1..n {
            let s = score(ka, kb);
            if s >= PAIR_CORRELATION && s > similarity[ka * n + ka] && s > similarity[kb * n + kb] {
                offers.push((s, ka, kb));
            }
        }
    }
    offers.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut taken = vec![false; n];
    let mut pairs = Vec::new();
    for (_, ka, kb) in offers {
        if taken[ka] || taken[kb] {
            continue;
        }
        taken[ka] = true;
        taken[kb] = true;
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
    pairs
}

/// The normalised correlation between `a`'s displacements reflected across the plane and the
/// displacements `b` (blurred; the unblurred sum of squares `norm_b`) at the mirrored vertices: 1 when `b` is
/// `a`'s mirror image up to strength, 0 when they are unrelated, −1 when they are opposite.
/// A moved vertex without a mirror contributes its motion to `a`'s norm and nothing to the
/// agreement.
fn reflected_correlation(
    a: &Blendshape,
    b: &[Vec3],
    norm_b: f32,
    plane: MirrorPlane,
    mirror: &[Option<u32>],
) -> f32 {
    let norm_a: f32 = a.deltas().iter().map(|d| d.length_squared()).sum();
    if norm_a <= 0.0 || norm_b <= 0.0 {
        return f32::NEG_INFINITY;
    }
    let mut agreement = 0.0f64;
    for (v, d) in a.moves() {
        if let Some(bm) = mirror
            .get(v as usize)
            .copied()
            .flatten()
            .and_then(|m| b.get(m as usize))
        {
            agreement += f64::from(plane.reflect_vector(d).dot(*bm));
        }
    }
    (agreement / (f64::from(norm_a) * f64::from(norm_b)).sqrt()) as f32
}

/// Which side a blendshape acts on (positive = the character's left).
///
/// Most sided shapes move vertices on one side (`mouthSmile_L`): there the location decides.
/// Some move a symmetric region sideways (`jawLeft`): there the direction of motion decides.
fn motion_side(positions: &[Vec3], shape: &Blendshape, plane: MirrorPlane) -> f32 {
    let mut signed = 0.0;
    let mut unsigned = 0.0;
    let mut sideways = 0.0;
    for (v, d) in shape.moves() {
        let side = plane.side_of(positions[v as usize]);
        signed += d.length() * side;
        unsigned += d.length() * side.abs();
        sideways += plane.across(d);
    }
    let located = unsigned > 0.0 && (signed / unsigned).abs() > 0.5;
    if located { signed } else { sideways }
}
