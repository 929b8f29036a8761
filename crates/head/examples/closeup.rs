//! Renders close-ups of the default head (for working on its geometry):
//! `cargo run -p faceanim-head --example closeup -- OUT_DIR`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use faceanim_render::{Appearance, Camera, render};
use glam::{Mat4, Vec3};

fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| ".".into()));
    let head = faceanim_head::default_character();
    let colours = Appearance::of(&head);
    let views = [
        (
            "eye",
            Vec3::new(0.031, 0.015, 0.06),
            0.05,
            Vec3::new(0.0, 0.0, 1.0),
        ),
        (
            "mouth",
            Vec3::new(0.0, -0.06, 0.08),
            0.07,
            Vec3::new(0.0, 0.0, 1.0),
        ),
        (
            "profile",
            Vec3::new(0.0, -0.02, 0.0),
            0.32,
            Vec3::new(1.0, 0.0, 0.0),
        ),
        (
            "threequarter",
            Vec3::new(0.0, 0.0, 0.02),
            0.30,
            Vec3::new(0.7, 0.1, 0.7),
        ),
    ];
    let poses: [(&str, &[(&str, f32)]); 4] = [
        ("neutral", &[]),
        ("blink", &[("eyeBlinkLeft", 1.0)]),
        ("open", &[("jawOpen", 1.0)]),
        (
            "smile",
            &[("mouthSmileLeft", 1.0), ("mouthSmileRight", 1.0)],
        ),
    ];
    for (view, target, extent, from) in views {
        let fov = 30f32.to_radians();
        let distance = 0.5 * extent / (0.5 * fov).tan() + 0.1;
        let eye = target + from.normalize() * distance;
        let camera = Camera {
            view_projection: Mat4::perspective_rh_gl(fov, 1.0, 0.01, 2.0)
                * Mat4::look_at_rh(eye, target, Vec3::Y),
            eye,
        };
        for (name, weights) in poses {
            let mut w = vec![0.0; head.blendshapes().len()];
            for (n, v) in weights {
                w[head.find_blendshape(n).unwrap().index()] = *v;
            }
            let image = render(&head, &head.pose(&w), &camera, &colours, 400);
            std::fs::write(
                dir.join(format!("{view}-{name}.png")),
                image.to_png().unwrap(),
            )
            .unwrap();
        }
    }
}
