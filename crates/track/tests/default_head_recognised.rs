//! The built-in head's blendshapes are recognised by the face model (issue 3): rendered at
//! weight 1, a blendshape's own score rises by at least 0.15 over its score on the neutral
//! render for at least 20 of the 51 names the model outputs. (On the realistic ICT head 17 of
//! 49 pass; the model is blind to some shapes.)
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

use faceanim_render::{Camera, render, vertex_colours};
use faceanim_track::{BLENDSHAPE_NAMES, FaceModels};
use glam::{Mat4, Vec3};

/// A 256×256 portrait of the face (as the landmark model expects a face crop), values in [0, 1].
fn portrait(head: &faceanim_rig::Character, weights: &[f32]) -> Vec<f32> {
    let target = Vec3::new(0.0, -0.015, 0.06);
    let fov = 30f32.to_radians();
    let eye = target + Vec3::new(0.0, 0.0, 0.17 / (0.5 * fov).tan());
    let camera = Camera {
        view_projection: Mat4::perspective_rh_gl(fov, 1.0, 0.05, 2.0)
            * Mat4::look_at_rh(eye, target, Vec3::Y),
        eye,
    };
    let image = render(
        head,
        &head.pose(weights),
        &camera,
        &vertex_colours(head),
        256,
    );
    image.rgb.iter().map(|&b| f32::from(b) / 255.0).collect()
}

#[test]
#[ignore = "issue 3's capture check, due when capture lands: the built-in head reaches 10 of 20 so far (run with --ignored to see each shape's rise)"]
fn at_least_20_of_51_shapes_raise_their_own_score() {
    let models = FaceModels::load().unwrap();
    let head = faceanim_head::default_character();
    let scores = |weights: &[f32]| {
        let landmarks = models.landmarks(&portrait(&head, weights)).unwrap();
        assert!(
            landmarks.presence > 0.5,
            "no face found: presence {}",
            landmarks.presence
        );
        models.expression(&landmarks.points).unwrap()
    };
    let neutral = scores(&vec![0.0; 52]);
    let mut passed = Vec::new();
    let mut report = Vec::new();
    for (k, name) in BLENDSHAPE_NAMES.iter().enumerate().skip(1) {
        // On an unmirrored image the model's sides are the subject's own (measured: swapping
        // them drops this count from 9 to 4).
        let id = head.find_blendshape(name).unwrap();
        let mut w = vec![0.0; 52];
        w[id.index()] = 1.0;
        let rise = scores(&w)[k].1 - neutral[k].1;
        report.push(format!("{name} {rise:+.2}"));
        if rise >= 0.15 {
            passed.push(*name);
        }
    }
    eprintln!("{} of 51 pass: {}", passed.len(), report.join(", "));
    assert!(
        passed.len() >= 20,
        "only {} of 51: {passed:?}",
        passed.len()
    );
}
