//! The 52 ARKit blendshapes of the default head, as displacement fields.
//!
//! Each left-side shape (`…Left`) is written once; its right partner is its exact mirror image
//! through the vertex mirror map. Centred shapes are symmetrised the same way. Magnitudes follow
//! a real face: the jaw opens 22°, a blink closes the lids fully, a smile lifts the corners
//! 7 mm and draws them back.

use glam::{Quat, Vec3};

use crate::field::{LEFT_EYE, MOUTH_Y, bump, left, smoothstep};
use crate::mesh::{MOUTH_HALF_WIDTH, Mesh, Part, eye_angles, eye_point, lid_lines};

/// Jaw hinge (an axis along X through this point).
const HINGE: Vec3 = Vec3::new(0.0, -0.010, -0.020);
/// How far `jawOpen` turns the jaw.
const JAW_ANGLE: f32 = 0.384;
const EYE_HALF_WIDTH: f32 = 1.15;

/// What the shapes need to know per vertex, computed once.
struct Context<'a> {
    mesh: &'a Mesh,
    jaw: Vec<f32>,
    upper_lip: Vec<f32>,
    lower_lip: Vec<f32>,
    corner: Vec3,
}

fn reflect(d: Vec3) -> Vec3 {
    Vec3::new(-d.x, d.y, d.z)
}

/// The height of the mouth line at `x` (it curves down slightly towards the corners).
fn mouth_line(x: f32) -> f32 {
    let t = (x / MOUTH_HALF_WIDTH).min(1.5);
    MOUTH_Y - 0.0015 * t * t
}

impl Context<'_> {
    fn new(mesh: &Mesh) -> Context<'_> {
        let n = mesh.vertices.len();
        let mut jaw = vec![0.0; n];
        let mut upper_lip = vec![0.0; n];
        let mut lower_lip = vec![0.0; n];
        for (i, v) in mesh.vertices.iter().enumerate() {
            let p = left(v.p);
            match v.part {
                Part::Skin => {
                    // Below the mouth line, sharply between the lips, gradually beside them.
                    let width = 0.0015 + 0.02 * smoothstep(0.018, 0.045, p.x);
                    let line = mouth_line(p.x);
                    let mut below = smoothstep(line + width, line - width, p.y);
                    if v.lower_lip_copy {
                        below = 1.0;
                    } else if v.upper_lip_edge {
                        below = 0.0;
                    }
                    let front = smoothstep(-0.065, 0.030, p.z);
                    let neck = smoothstep(-0.185, -0.100, p.y);
                    jaw[i] = below * front * neck;
                    let lips = bump(
                        p,
                        Vec3::new(0.0, MOUTH_Y, 0.088),
                        Vec3::new(0.030, 0.014, 0.030),
                    );
                    let lower_side = v.lower_lip_copy || (!v.upper_lip_edge && p.y < line);
                    if lower_side {
                        lower_lip[i] = lips;
                    } else {
                        upper_lip[i] = lips;
                    }
                }
                Part::LowerTeeth | Part::Tongue => jaw[i] = 1.0,
                Part::Cavity => jaw[i] = smoothstep(-0.056, -0.068, p.y),
                Part::UpperTeeth | Part::Eye(_) => {}
            }
        }
        let corner = Vec3::new(MOUTH_HALF_WIDTH, mouth_line(MOUTH_HALF_WIDTH), 0.078);
        Context {
            mesh,
            jaw,
            upper_lip,
            lower_lip,
            corner,
        }
    }

    fn is_skin(&self, i: usize) -> bool {
        self.mesh.vertices[i].part == Part::Skin
    }

    /// Rotation of the jaw by `angle` × its weight, about the hinge.
    fn jaw_turn(&self, i: usize, angle: f32) -> Vec3 {
        let p = self.mesh.vertices[i].p;
        let turn = Quat::from_rotation_x(angle * self.jaw[i]);
        turn * (p - HINGE) + HINGE - p
    }

    /// Skin around the left eye sliding over the eyeball: the upper lid's rim turns by
    /// `upper(u)` radians of pitch, the lower lid's by `lower(u)`, fading with distance.
    fn lids(&self, i: usize, upper: impl Fn(f32) -> f32, lower: impl Fn(f32) -> f32) -> Vec3 {
        let v = &self.mesh.vertices[i];
        if v.part != Part::Skin || v.p.x <= 0.0 {
            return Vec3::ZERO;
        }
        let (u, pitch, r) = eye_angles(v.p);
        if r > 0.035 || v.p.z < LEFT_EYE.z - 0.004 {
            return Vec3::ZERO;
        }
        let (top, bottom) = lid_lines(u.clamp(-EYE_HALF_WIDTH, EYE_HALF_WIDTH));
        let across = 1.0 - smoothstep(EYE_HALF_WIDTH, EYE_HALF_WIDTH + 0.35, u.abs());
        // Only skin lying on the eyeball moves with the lid; the brow above it stays.
        let on_eye = 1.0 - smoothstep(0.0008, 0.006, r - crate::field::LID_RADIUS);
        let uc = u.clamp(-EYE_HALF_WIDTH, EYE_HALF_WIDTH);
        let turn = if pitch >= 0.5 * (top + bottom) {
            upper(uc) * (1.0 - smoothstep(0.0, 0.55, pitch - top))
        } else {
            lower(uc) * (1.0 - smoothstep(0.0, 0.45, bottom - pitch))
        } * across
            * on_eye;
        eye_point(u, pitch + turn, r) - v.p
    }

    /// The left eyeball turned by `rotation` about its centre.
    fn gaze(&self, i: usize, rotation: Quat) -> Vec3 {
        let v = &self.mesh.vertices[i];
        if v.part != Part::Eye(true) {
            return Vec3::ZERO;
        }
        rotation * (v.p - LEFT_EYE) + LEFT_EYE - v.p
    }
}

/// Where a blink's lids meet: a third of the way up the opening.
fn meet(u: f32) -> f32 {
    let (top, bottom) = lid_lines(u);
    bottom + 0.3 * (top - bottom)
}

/// The deltas of the 52 ARKit blendshapes, in ARKit's order, one per vertex each.
#[must_use]
pub fn blendshapes(mesh: &Mesh) -> Vec<(&'static str, Vec<Vec3>)> {
    let c = Context::new(mesh);
    let n = mesh.vertices.len();
    let field = |f: &dyn Fn(usize, Vec3) -> Vec3| -> Vec<Vec3> {
        (0..n).map(|i| f(i, mesh.vertices[i].p)).collect()
    };
    let skin = |i: usize, d: Vec3| if c.is_skin(i) { d } else { Vec3::ZERO };
    let side = |p: Vec3| smoothstep(-0.008, 0.012, p.x);

    // Left-side shapes; right partners are mirrored below.
    // The lids overlap a little where they meet, so no seam shows the eye through them.
    let eye_blink = field(&|i, _| {
        c.lids(
            i,
            |u| meet(u) - 0.04 - lid_lines(u).0,
            |u| meet(u) + 0.04 - lid_lines(u).1,
        )
    });
    let eye_look_down =
        field(&|i, _| c.gaze(i, Quat::from_rotation_x(0.65)) + c.lids(i, |_| -0.36, |_| -0.10));
    let eye_look_in = field(&|i, _| c.gaze(i, Quat::from_rotation_y(-0.70)));
    let eye_look_out = field(&|i, _| c.gaze(i, Quat::from_rotation_y(0.70)));
    let eye_look_up =
        field(&|i, _| c.gaze(i, Quat::from_rotation_x(-0.75)) + c.lids(i, |_| 0.55, |_| 0.18));
    let eye_squint = field(&|i, p| {
        let cheek = skin(
            i,
            Vec3::new(0.0, 0.0025, 0.001)
                * bump(
                    p,
                    Vec3::new(0.034, -0.006, 0.070),
                    Vec3::new(0.020, 0.014, 0.020),
                ),
        );
        c.lids(
            i,
            |u| 0.40 * (meet(u) - lid_lines(u).0),
            |u| 1.00 * (meet(u) - lid_lines(u).1),
        ) + cheek
    });
    let eye_wide = field(&|i, _| c.lids(i, |_| 0.50, |_| -0.15));
    let jaw_left = field(&|i, _| Vec3::new(0.016, 0.0, 0.0) * c.jaw[i]);
    let corner = |p: Vec3, radii: Vec3| bump(p, c.corner, radii);
    let mouth_smile = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.003, 0.007, -0.004) * corner(p, Vec3::new(0.020, 0.016, 0.025))
                + Vec3::new(0.001, 0.003, 0.002)
                    * bump(
                        p,
                        Vec3::new(0.040, -0.030, 0.070),
                        Vec3::new(0.022, 0.020, 0.025),
                    ),
        )
    });
    let mouth_frown = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.002, -0.016, -0.001) * corner(p, Vec3::new(0.020, 0.018, 0.025)),
        )
    });
    let mouth_dimple = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.005, -0.001, -0.007) * corner(p, Vec3::new(0.018, 0.015, 0.022)),
        )
    });
    let mouth_stretch = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.014, -0.007, -0.004) * corner(p, Vec3::new(0.026, 0.022, 0.030))
                + Vec3::new(0.0, -0.0015, 0.0) * c.lower_lip[i] * side(p),
        )
    });
    let mouth_press = field(&|i, p| {
        let lips = (c.upper_lip[i] + c.lower_lip[i]) * side(p);
        Vec3::new(0.0, -0.9 * (p.y - mouth_line(p.x.abs())), -0.004) * lips
    });
    let mouth_lower_down = field(&|i, p| Vec3::new(0.0, -0.014, 0.0008) * c.lower_lip[i] * side(p));
    let mouth_upper_up = field(&|i, p| Vec3::new(0.0, 0.013, 0.001) * c.upper_lip[i] * side(p));
    let mouth_left = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.016, 0.0, 0.0)
                * bump(
                    p,
                    Vec3::new(0.0, MOUTH_Y, 0.088),
                    Vec3::new(0.045, 0.028, 0.040),
                ),
        )
    });
    let brow_down = field(&|i, p| {
        skin(
            i,
            Vec3::new(-0.004, -0.013, 0.001)
                * bump(
                    p,
                    Vec3::new(0.028, 0.030, 0.080),
                    Vec3::new(0.030, 0.020, 0.035),
                ),
        )
    });
    let brow_outer_up = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.0, 0.014, 0.0)
                * bump(
                    p,
                    Vec3::new(0.046, 0.034, 0.077),
                    Vec3::new(0.024, 0.022, 0.030),
                ),
        )
    });
    let cheek_squint = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.0, 0.007, 0.002)
                * bump(
                    p,
                    Vec3::new(0.040, -0.012, 0.068),
                    Vec3::new(0.022, 0.018, 0.025),
                ),
        )
    });
    let nose_sneer = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.0015, 0.007, 0.0008)
                * bump(
                    p,
                    Vec3::new(0.013, -0.025, 0.088),
                    Vec3::new(0.014, 0.022, 0.020),
                ),
        )
    });

    // Centred shapes (symmetrised below).
    let jaw_forward = field(&|i, _| Vec3::new(0.0, 0.0, 0.013) * c.jaw[i]);
    let jaw_open = field(&|i, _| c.jaw_turn(i, JAW_ANGLE));
    let mouth_close = field(&|i, p| {
        let v = &mesh.vertices[i];
        let lower = if v.part == Part::Skin {
            c.lower_lip[i]
        } else {
            0.0
        };
        let turn = Quat::from_rotation_x(-JAW_ANGLE * 0.85 * lower);
        (turn * (p - HINGE) + HINGE - p) + Vec3::new(0.0, -0.0015, 0.0) * c.upper_lip[i]
    });
    let mouth_funnel = field(&|i, p| {
        let lips = c.upper_lip[i] + c.lower_lip[i];
        Vec3::new(
            -0.35 * p.x * lips,
            0.005 * c.upper_lip[i] - 0.007 * c.lower_lip[i],
            0.010 * lips,
        )
    });
    let mouth_pucker = field(&|i, p| {
        let lips = c.upper_lip[i] + c.lower_lip[i];
        Vec3::new(
            -0.60 * p.x * lips,
            -0.0005 * c.upper_lip[i] + 0.0005 * c.lower_lip[i],
            0.013 * lips,
        )
    });
    let mouth_roll_lower = field(&|i, _| Vec3::new(0.0, 0.006, -0.014) * c.lower_lip[i]);
    let mouth_roll_upper = field(&|i, _| Vec3::new(0.0, -0.0055, -0.014) * c.upper_lip[i]);
    let mouth_shrug_lower = field(&|i, p| {
        let chin = skin(
            i,
            Vec3::ONE
                * bump(
                    left(p),
                    Vec3::new(0.0, -0.090, 0.075),
                    Vec3::new(0.025, 0.020, 0.025),
                ),
        );
        Vec3::new(0.0, 0.010, 0.005) * (c.lower_lip[i] + chin.x)
    });
    let mouth_shrug_upper = field(&|i, _| Vec3::new(0.0, 0.009, 0.005) * c.upper_lip[i]);
    let brow_inner_up = field(&|i, p| {
        skin(
            i,
            Vec3::new(0.0, 0.011, 0.0)
                * bump(
                    left(p),
                    Vec3::new(0.012, 0.032, 0.082),
                    Vec3::new(0.020, 0.022, 0.030),
                ),
        )
    });
    let cheek_puff = field(&|i, p| {
        let q = left(p);
        let out = Vec3::new(q.x, 0.0, q.z - 0.02).normalize_or_zero();
        let d = 0.008
            * out
            * bump(
                q,
                Vec3::new(0.042, -0.048, 0.058),
                Vec3::new(0.030, 0.030, 0.040),
            );
        skin(i, if p.x < 0.0 { reflect(d) } else { d })
    });
    let tongue_out = field(&|i, _| {
        let v = &mesh.vertices[i];
        if v.part == Part::Tongue {
            Vec3::new(0.0, -0.004, 0.032)
        } else {
            Vec3::new(0.0, -0.004, 0.001) * c.lower_lip[i]
                + Vec3::new(0.0, 0.0015, 0.0) * c.upper_lip[i]
        }
    });

    let mirror = |d: &[Vec3]| -> Vec<Vec3> {
        (0..n)
            .map(|i| reflect(d[mesh.mirror[i] as usize]))
            .collect()
    };
    let symmetric = |d: Vec<Vec3>| -> Vec<Vec3> {
        (0..n)
            .map(|i| 0.5 * (d[i] + reflect(d[mesh.mirror[i] as usize])))
            .collect()
    };

    let mut out: Vec<(&'static str, Vec<Vec3>)> = Vec::with_capacity(52);
    let mut pair = |left_name: &'static str, right_name: &'static str, d: Vec<Vec3>| {
        let r = mirror(&d);
        out.push((left_name, d));
        out.push((right_name, r));
    };
    pair("eyeBlinkLeft", "eyeBlinkRight", eye_blink);
    pair("eyeLookDownLeft", "eyeLookDownRight", eye_look_down);
    pair("eyeLookInLeft", "eyeLookInRight", eye_look_in);
    pair("eyeLookOutLeft", "eyeLookOutRight", eye_look_out);
    pair("eyeLookUpLeft", "eyeLookUpRight", eye_look_up);
    pair("eyeSquintLeft", "eyeSquintRight", eye_squint);
    pair("eyeWideLeft", "eyeWideRight", eye_wide);
    pair("jawLeft", "jawRight", jaw_left);
    pair("mouthLeft", "mouthRight", mouth_left);
    pair("mouthSmileLeft", "mouthSmileRight", mouth_smile);
    pair("mouthFrownLeft", "mouthFrownRight", mouth_frown);
    pair("mouthDimpleLeft", "mouthDimpleRight", mouth_dimple);
    pair("mouthStretchLeft", "mouthStretchRight", mouth_stretch);
    pair("mouthPressLeft", "mouthPressRight", mouth_press);
    pair(
        "mouthLowerDownLeft",
        "mouthLowerDownRight",
        mouth_lower_down,
    );
    pair("mouthUpperUpLeft", "mouthUpperUpRight", mouth_upper_up);
    pair("browDownLeft", "browDownRight", brow_down);
    pair("browOuterUpLeft", "browOuterUpRight", brow_outer_up);
    pair("cheekSquintLeft", "cheekSquintRight", cheek_squint);
    pair("noseSneerLeft", "noseSneerRight", nose_sneer);
    for (name, d) in [
        ("jawForward", jaw_forward),
        ("jawOpen", jaw_open),
        ("mouthClose", mouth_close),
        ("mouthFunnel", mouth_funnel),
        ("mouthPucker", mouth_pucker),
        ("mouthRollLower", mouth_roll_lower),
        ("mouthRollUpper", mouth_roll_upper),
        ("mouthShrugLower", mouth_shrug_lower),
        ("mouthShrugUpper", mouth_shrug_upper),
        ("browInnerUp", brow_inner_up),
        ("cheekPuff", cheek_puff),
        ("tongueOut", tongue_out),
    ] {
        out.push((name, symmetric(d)));
    }
    // ARKit's documented order.
    out.sort_by_key(|(name, _)| {
        faceanim_rig::names::ARKIT_52
            .iter()
            .position(|n| n == name)
            .unwrap_or(usize::MAX)
    });
    out
}
