//! Position interpolation (section 3.4): the beautified arc and how each vertex follows it.
//!
//! The arc is the circle through the stroke's first sample A, middle sample B and end C (or the
//! moved handles). The reference vertex rotates about the centre `c` by the arc angle θ; every
//! other moving vertex `j` rotates about its own centre `c_j = c + (S_j − A)` (a full 3D
//! translation) by `θ_j = κ_j·θ`, where `κ_j ∈ [0, 1]` is the share of the reference vertex's
//! motion that `j` makes (its motion projected on the reference's, clamped). A residual that
//! grows linearly with progress lands every vertex exactly on its target. Vertices that share
//! the reference's motion swing along the arc; vertices that barely move barely swing — the role
//! the paper gives to its per-vertex law-of-cosines angle, without its degenerate cases.
//!
//! Written relative to straight (linear) interpolation, the arc adds to vertex `j` at progress
//! `s` the deviation `u·f(θ_j, s) + v·g(θ_j, s)`, with `u = A − c`, `v = n × u` and
//! `f(θ, s) = cos θs − 1 − s(cos θ − 1)`, `g(θ, s) = sin θs − s·sin θ` — two shared vectors
//! scaled per vertex, which is what the glTF export bakes.

use glam::{DVec3, Vec3};

/// A circular arc from A through B to C.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arc {
    /// The circle's centre.
    pub center: Vec3,
    /// Unit normal of the arc's plane; the arc turns counter-clockwise about it.
    pub axis: Vec3,
    /// `A − center`.
    pub radius_vector: Vec3,
    /// Angle from A to C through B, in (0, 2π).
    pub angle: f32,
}

/// The trajectory shape of an action: an arc, or straight when B sits on the chord.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Path {
    /// Linear interpolation (the middle handle is green).
    Straight,
    /// Circular (the middle handle is yellow).
    Arc(Arc),
}

impl Path {
    /// The path through `a`, `b`, `c`: straight when `b` is within `snap` of the chord's midpoint
    /// or the points are (nearly) collinear.
    #[must_use]
    pub fn through(a: Vec3, b: Vec3, c: Vec3, snap: f32) -> Path {
        if (b - (a + c) * 0.5).length() <= snap {
            return Path::Straight;
        }
        Arc::through(a, b, c).map_or(Path::Straight, Path::Arc)
    }

    /// The point at progress `s ∈ [0, 1]` along the path from `a` to `c` (for drawing it).
    #[must_use]
    pub fn point(&self, a: Vec3, c: Vec3, s: f32) -> Vec3 {
        match self {
            Path::Straight => a.lerp(c, s),
            Path::Arc(arc) => arc.point(s),
        }
    }

    /// Whether the path is straight.
    #[must_use]
    pub fn is_straight(&self) -> bool {
        matches!(self, Path::Straight)
    }
}

impl Arc {
    /// The circle through three points, or `None` when they are collinear (within 1e-6 of the
    /// chord's length squared).
    #[must_use]
    pub fn through(a: Vec3, b: Vec3, c: Vec3) -> Option<Arc> {
        let (a64, b64, c64) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
        let ab = b64 - a64;
        let ac = c64 - a64;
        let normal = ab.cross(ac);
        let n2 = normal.length_squared();
        let scale = ab.length_squared().max(ac.length_squared());
        if scale <= 0.0 || n2 <= 1e-12 * scale * scale {
            return None;
        }
        // Circumcentre of triangle ABC.
        let center = a64
            + (normal.cross(ab) * ac.length_squared() + ac.cross(normal) * ab.length_squared())
                / (2.0 * n2);
        // Travelling A → B → C turns counter-clockwise about (B − A) × (C − B).
        let axis = (b64 - a64).cross(c64 - b64).normalize();
        let u = a64 - center;
        let w = c64 - center;
        let mut angle = f64::atan2(u.cross(w).dot(axis), u.dot(w));
        if angle <= 0.0 {
            angle += std::f64::consts::TAU;
        }
        Some(Arc {
            center: center.as_vec3(),
            axis: axis.as_vec3(),
            radius_vector: u.as_vec3(),
            angle: angle as f32,
        })
    }

    /// The point at progress `s` (angle `s·θ` from A).
    #[must_use]
    pub fn point(&self, s: f32) -> Vec3 {
        (self.center.as_dvec3()
            + rotate(
                self.radius_vector.as_dvec3(),
                self.axis.as_dvec3(),
                f64::from(self.angle * s),
            ))
        .as_vec3()
    }

    /// `v = axis × u`, the second basis vector of the deviation.
    #[must_use]
    pub fn tangent_vector(&self) -> Vec3 {
        self.axis.cross(self.radius_vector)
    }

    /// The deviation from straight interpolation of a vertex making share `kappa` of the
    /// reference's motion, at progress `s` (see the module docs).
    #[must_use]
    pub fn deviation(&self, kappa: f32, s: f32) -> Vec3 {
        let (f, g) = deviation_coefficients(f64::from(self.angle * kappa), f64::from(s));
        (self.radius_vector.as_dvec3() * f + self.tangent_vector().as_dvec3() * g).as_vec3()
    }
}

/// `(f, g)` of the module docs for angle `theta` at progress `s`.
#[must_use]
pub fn deviation_coefficients(theta: f64, s: f64) -> (f64, f64) {
    let f = (theta * s).cos() - 1.0 - s * (theta.cos() - 1.0);
    let g = (theta * s).sin() - s * theta.sin();
    (f, g)
}

fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    // Rodrigues; `v` need not be perpendicular to the axis.
    let (sin, cos) = angle.sin_cos();
    v * cos + axis.cross(v) * sin + axis * axis.dot(v) * (1.0 - cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_through_three_points() {
        let (a, b, c) = (
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.0),
        );
        let arc = Arc::through(a, b, c).unwrap_or_else(|| panic!("not collinear"));
        assert!(arc.center.length() < 1e-6);
        assert!((arc.angle - std::f32::consts::PI).abs() < 1e-5);
        assert!((arc.point(0.5) - b).length() < 1e-5, "{}", arc.point(0.5));
        assert!((arc.point(1.0) - c).length() < 1e-5);
        // The other way round goes through B too.
        let back = Arc::through(c, b, a).unwrap_or_else(|| panic!("not collinear"));
        assert!((back.point(0.5) - b).length() < 1e-5);
    }

    #[test]
    fn arcs_longer_than_half_a_turn() {
        // B behind the chord: the arc from A to C through B is 270°.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let (a, b, c) = (
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-s, -s, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        );
        let arc = Arc::through(a, b, c).unwrap_or_else(|| panic!("not collinear"));
        assert!(
            (arc.angle - 1.5 * std::f32::consts::PI).abs() < 1e-4,
            "{}",
            arc.angle
        );
        assert!((arc.point(0.5) - b).length() < 1e-4);
    }

    #[test]
    fn collinear_or_snapped_is_straight() {
        let (a, c) = (Vec3::ZERO, Vec3::X);
        assert_eq!(
            Path::through(a, Vec3::new(0.3, 0.0, 0.0), c, 0.0),
            Path::Straight
        );
        assert_eq!(
            Path::through(a, Vec3::new(0.5, 0.01, 0.0), c, 0.02),
            Path::Straight
        );
        assert!(!Path::through(a, Vec3::new(0.5, 0.1, 0.0), c, 0.02).is_straight());
    }

    #[test]
    fn the_reference_vertex_rides_the_arc_and_others_land_on_target() {
        let arc =
            Arc::through(Vec3::X, Vec3::Y, -Vec3::X).unwrap_or_else(|| panic!("not collinear"));
        // Reference: S = A, motion C − A; at s the position is straight + deviation = arc point.
        for s in [0.0, 0.25, 0.5, 0.9, 1.0] {
            let straight = Vec3::X.lerp(-Vec3::X, s);
            assert!((straight + arc.deviation(1.0, s) - arc.point(s)).length() < 1e-5);
        }
        // Any vertex: no deviation at either end, none at all for κ = 0.
        for kappa in [0.0, 0.3, 1.0] {
            assert!(arc.deviation(kappa, 0.0).length() < 1e-6);
            assert!(arc.deviation(kappa, 1.0).length() < 1e-5);
        }
        assert_eq!(arc.deviation(0.0, 0.5), Vec3::ZERO);
    }
}
