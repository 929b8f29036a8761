//! Head pose directions on renders of the ICT head turned by known angles: the signs a user
//! relies on when the pose drives a character's root (yaw towards the subject's own left,
//! pitch chin up, roll anticlockwise as seen by the camera, all positive).
use faceanim_render::{Appearance, Camera, render};
use faceanim_track::{FaceModels, Frame};
use glam::Quat;

#[test]
fn turned_heads_give_the_angles_they_were_turned_by() {
    let models = FaceModels::load().unwrap();
    let ict = faceanim_testdata::ict();
    let bounds = ict.bounds();
    let camera = Camera::front(&bounds, 0.75);
    let colours = Appearance::of(ict);
    let rest = ict.pose(&vec![0.0; ict.blendshapes().len()]);
    let centre = bounds.center();
    // (yaw, pitch, roll) in the documented convention, and the rotation that makes them.
    for (yaw, pitch, roll) in [
        (20.0f32, 0.0f32, 0.0f32),
        (-20.0, 0.0, 0.0),
        (0.0, 15.0, 0.0),
        (0.0, -15.0, 0.0),
        (0.0, 0.0, 15.0),
    ] {
        let rotation = Quat::from_rotation_y(yaw.to_radians())
            * Quat::from_rotation_x(-pitch.to_radians())
            * Quat::from_rotation_z(roll.to_radians());
        let mut pose = rest.clone();
        for (p, n) in pose.positions.iter_mut().zip(pose.normals.iter_mut()) {
            *p = centre + rotation * (*p - centre);
            *n = rotation * *n;
        }
        let image = render(ict, &pose, &camera, &colours, 384);
        let face = models
            .find_face(&Frame {
                width: 384,
                height: 384,
                rgb: &image.rgb,
            })
            .unwrap()
            .unwrap_or_else(|| panic!("no face at {yaw}/{pitch}/{roll}"));
        let got = face.pose.unwrap();
        eprintln!(
            "turned {yaw}/{pitch}/{roll}: measured {:.1}/{:.1}/{:.1}",
            got.yaw, got.pitch, got.roll
        );
        for (want, have, what) in [
            (yaw, got.yaw, "yaw"),
            (pitch, got.pitch, "pitch"),
            (roll, got.roll, "roll"),
        ] {
            assert!(
                (want - have).abs() < 7.0,
                "{what}: turned {want}, measured {have}"
            );
        }
    }
}
