//! Still images through the whole per-frame pipeline (detector, region, landmarks, scores):
//! the capture issue's thresholds.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

use std::collections::HashMap;

use faceanim_track::{FaceModels, Frame};

/// A shared image, decoded as capture decodes pictures.
fn decode(name: &str) -> faceanim_media::Image {
    let path = faceanim_testdata::shared(&format!("images/{name}"));
    faceanim_media::decode_image(&path, &std::fs::read(&path).unwrap()).unwrap()
}

fn scores(models: &FaceModels, name: &str) -> HashMap<&'static str, f32> {
    let faceanim_media::Image { width, height, rgb } = decode(name);
    let face = models
        .find_face(&Frame::new(width, height, &rgb))
        .unwrap()
        .unwrap_or_else(|| panic!("{name}: no face"));
    assert!(
        face.presence > 0.9 && face.detection_score > 0.5,
        "{name}: {} / {}",
        face.presence,
        face.detection_score
    );
    // Every face found has a head pose: a plausible one for these near-frontal portraits.
    let pose = face.pose.unwrap_or_else(|| panic!("{name}: no pose"));
    eprintln!("{name}: pose {pose:?}");
    assert!(
        pose.yaw.abs() < 30.0 && pose.pitch.abs() < 30.0 && pose.roll.abs() < 25.0,
        "{name}: {pose:?}"
    );
    // A head in a portrait is a few tens of centimetres to a couple of metres from the camera.
    assert!(
        (-2.5..-0.15).contains(&pose.translation[2]),
        "{name}: {pose:?}"
    );
    face.scores.into_iter().collect()
}

#[test]
fn a_smiling_photograph_and_the_ict_renders() {
    let models = FaceModels::load().unwrap();
    let astronaut = scores(&models, "astronaut.png");
    let open = scores(&models, "ict-face-jawopen.png");
    let smile = scores(&models, "ict-face-smile.png");
    let blink = scores(&models, "ict-face-blink.png");
    let neutral = scores(&models, "ict-face-neutral.png");
    eprintln!(
        "astronaut smile {:.2}/{:.2}; ict jawOpen {:.2}, smile {:.2}/{:.2}, blink {:.2}/{:.2}; neutral {:.2} {:.2}/{:.2} {:.2}/{:.2}",
        astronaut["mouthSmileLeft"],
        astronaut["mouthSmileRight"],
        open["jawOpen"],
        smile["mouthSmileLeft"],
        smile["mouthSmileRight"],
        blink["eyeBlinkLeft"],
        blink["eyeBlinkRight"],
        neutral["jawOpen"],
        neutral["mouthSmileLeft"],
        neutral["mouthSmileRight"],
        neutral["eyeBlinkLeft"],
        neutral["eyeBlinkRight"]
    );
    assert!(astronaut["mouthSmileLeft"] > 0.6 && astronaut["mouthSmileRight"] > 0.6);
    assert!(open["jawOpen"] > 0.5);
    assert!(smile["mouthSmileLeft"] > 0.4 && smile["mouthSmileRight"] > 0.4);
    assert!(blink["eyeBlinkLeft"] > 0.4 && blink["eyeBlinkRight"] > 0.4);
    for name in [
        "jawOpen",
        "mouthSmileLeft",
        "mouthSmileRight",
        "eyeBlinkLeft",
        "eyeBlinkRight",
    ] {
        assert!(neutral[name] < 0.15, "neutral {name} = {}", neutral[name]);
    }
}

#[test]
fn a_frame_without_a_face_is_none_and_a_wrong_size_is_an_error() {
    let models = FaceModels::load().unwrap();
    let grey = vec![128u8; 320 * 240 * 3];
    assert!(
        models
            .find_face(&Frame {
                width: 320,
                height: 240,
                rgb: &grey
            })
            .unwrap()
            .is_none()
    );
    let err = models
        .find_face(&Frame {
            width: 320,
            height: 240,
            rgb: &grey[..100],
        })
        .unwrap_err()
        .to_string();
    assert_eq!(err, "frame: 320×240 frame with 100 bytes");
}
