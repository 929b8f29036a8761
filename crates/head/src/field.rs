//! The head's shape as a signed distance field: smooth unions of ellipsoids (cranium, face,
//! cheekbones, nose, brow ridge, lips, chin, ears) and a neck cylinder, with the eye sockets
//! carved out. Every primitive is symmetric about x = 0.

use Place::{Middle, Mirrored};
use glam::Vec3;

/// Eye centre of the character's left eye (+X).
pub const LEFT_EYE: Vec3 = Vec3::new(0.031, 0.012, 0.068);
/// Eyeball radius.
pub const EYE_RADIUS: f32 = 0.012;
/// Radius of the shell the eyelids slide on, just outside the eyeball.
pub const LID_RADIUS: f32 = 0.0128;
/// Height of the line where the lips meet.
pub const MOUTH_Y: f32 = -0.0595;

/// Approximate distance to an ellipsoid (exact on the surface, good near it).
fn ellipsoid(p: Vec3, centre: Vec3, radii: Vec3) -> f32 {
    let q = p - centre;
    let k0 = (q / radii).length();
    let k1 = (q / (radii * radii)).length();
    if k1 <= 0.0 {
        -radii.min_element()
    } else {
        k0 * (k0 - 1.0) / k1
    }
}

/// Polynomial smooth minimum with blend width `k`.
fn smin(a: f32, b: f32, k: f32) -> f32 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// Smooth subtraction of `b` from `a`.
fn smax(a: f32, b: f32, k: f32) -> f32 {
    -smin(-a, -b, k)
}

/// `p` mirrored onto the character's left (+X) side: everything is built for the left and
/// mirrored, so the head is exactly symmetric.
#[must_use]
pub fn left(p: Vec3) -> Vec3 {
    Vec3::new(p.x.abs(), p.y, p.z)
}

/// Where an ellipsoid of [`BLOBS`] stands: on the middle of the face, or on its left (+X)
/// and mirrored onto the right.
#[derive(Debug, Clone, Copy)]
enum Place {
    Middle,
    Mirrored,
}

/// The ellipsoids joined to the cranium, in order: where each stands, its centre, its radii
/// and the width over which it blends in ([`smin`]).
#[rustfmt::skip]
const BLOBS: [(Place, [f32; 3], [f32; 3], f32); 10] = [
    // Face and cheekbones.
    (Middle, [0.0, -0.040, 0.022], [0.060, 0.075, 0.068], 0.030),
    (Mirrored, [0.042, -0.008, 0.045], [0.028, 0.024, 0.030], 0.020),
    // Nose: bridge, tip and wings.
    (Middle, [0.0, -0.010, 0.080], [0.0095, 0.030, 0.016], 0.010),
    (Middle, [0.0, -0.031, 0.094], [0.0115, 0.0105, 0.0115], 0.008),
    (Mirrored, [0.0125, -0.0355, 0.086], [0.0080, 0.0070, 0.0085], 0.005),
    // Brow ridge, lips, chin.
    (Middle, [0.0, 0.032, 0.070], [0.058, 0.011, 0.020], 0.015),
    (Middle, [0.0, -0.0535, 0.0830], [0.0235, 0.0065, 0.0110], 0.006),
    (Middle, [0.0, -0.0660, 0.0810], [0.0215, 0.0075, 0.0110], 0.006),
    (Middle, [0.0, -0.0920, 0.0680], [0.0220, 0.0170, 0.0170], 0.015),
    // Ears.
    (Mirrored, [0.075, 0.000, -0.012], [0.011, 0.027, 0.016], 0.008),
];

/// Signed distance to the head (negative inside).
#[must_use]
pub fn head(p: Vec3) -> f32 {
    let m = left(p);
    let mut d = ellipsoid(
        p,
        Vec3::new(0.0, 0.025, -0.010),
        Vec3::new(0.074, 0.098, 0.095),
    );
    for &(place, centre, radii, blend) in &BLOBS {
        let at = match place {
            Middle => p,
            Mirrored => m,
        };
        d = smin(
            d,
            ellipsoid(at, Vec3::from_array(centre), Vec3::from_array(radii)),
            blend,
        );
    }
    // Neck: a capped vertical cylinder.
    let q = Vec3::new(p.x, 0.0, p.z + 0.012);
    let side = q.length() - 0.052;
    let caps = (p.y - (-0.140)).abs() - 0.080;
    let neck = side.max(caps).min(0.0) + Vec3::new(side.max(0.0), caps.max(0.0), 0.0).length();
    d = smin(d, neck, 0.030);
    // Eye sockets, and the lids wrapping the eyeballs inside them.
    let from_eye = (m - LEFT_EYE).length();
    d = smax(d, -(from_eye - 0.0165), 0.006);
    d = smin(d, from_eye - LID_RADIUS, 0.004);
    d
}

/// The outermost surface point along the ray from `origin` in direction `dir` (unit).
#[must_use]
pub fn cast(origin: Vec3, dir: Vec3) -> Vec3 {
    // March inwards from outside with steps bounded by the field, then bisect the crossing.
    let mut t = 0.40f32;
    let mut previous = t;
    for _ in 0..400 {
        let d = head(origin + dir * t);
        if d < 0.0 {
            break;
        }
        previous = t;
        t -= (0.8 * d).max(0.0003);
        if t <= 0.0 {
            t = 0.0;
            break;
        }
    }
    let (mut inside, mut outside) = (t, previous);
    for _ in 0..40 {
        let mid = 0.5 * (inside + outside);
        if head(origin + dir * mid) < 0.0 {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    origin + dir * (0.5 * (inside + outside))
}

/// `smoothstep` from `edge0` to `edge1` (either order).
#[must_use]
pub fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// 1 at `centre`, fading smoothly to 0 at the ellipsoid of `radii` around it.
#[must_use]
pub fn bump(p: Vec3, centre: Vec3, radii: Vec3) -> f32 {
    1.0 - smoothstep(0.0, 1.0, ((p - centre) / radii).length())
}
