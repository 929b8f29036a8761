//! The whole per-frame pipeline on the same pixels as MediaPipe's own runtime (issue 17, item
//! 5): detector, face region, crop, landmarks and scores on ten stills of a realistic head,
//! against what MediaPipe 0.10.21's Face Landmarker found on them in IMAGE mode
//! (`tools/record_mediapipe_stills.py`, `tests/reference/stills/`). Landmarks within 0.1 px
//! and every score within 0.01 (the issue asks for 0.05; the port measures 0.006 px and
//! 0.0008). The stills include a rolled head, a crop that runs off the frame's edge and a
//! small face.
use std::path::{Path, PathBuf};

use faceanim_track::{FaceModels, Frame};
use serde_json::Value;

fn stills() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/stills")
}

#[test]
fn landmarks_and_scores_match_mediapipe_on_the_same_pixels() {
    let models = FaceModels::load().unwrap();
    let record: Value =
        serde_json::from_slice(&std::fs::read(stills().join("stills.json")).unwrap()).unwrap();
    let recorded = record["stills"].as_object().unwrap();
    assert_eq!(recorded.len(), 10);
    let (mut worst_point, mut worst_score) = (0.0f32, (0.0f32, String::new()));
    for (name, theirs) in recorded {
        let path = stills().join(name);
        let faceanim_media::Image { width, height, rgb } =
            faceanim_media::decode_image(&path, &std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(
            (width, height),
            (
                theirs["width"].as_u64().unwrap() as usize,
                theirs["height"].as_u64().unwrap() as usize
            )
        );
        let face = models
            .find_face(&Frame::new(width, height, &rgb))
            .unwrap()
            .unwrap_or_else(|| panic!("{name}: no face, where MediaPipe found one"));
        let points = theirs["landmarks"].as_array().unwrap();
        assert_eq!(points.len(), face.landmarks.len());
        for (ours, theirs) in face.landmarks.iter().zip(points) {
            for axis in 0..2 {
                let d = (ours[axis] - theirs[axis].as_f64().unwrap() as f32).abs();
                worst_point = worst_point.max(d);
            }
        }
        for &(shape, score) in &face.scores {
            let d = (score - theirs["scores"][shape].as_f64().unwrap() as f32).abs();
            if d > worst_score.0 {
                worst_score = (d, format!("{name} {shape}"));
            }
        }
    }
    eprintln!(
        "largest differences: landmark {worst_point:.4} px, score {:.4} ({})",
        worst_score.0, worst_score.1
    );
    assert!(
        worst_point < 0.1,
        "a landmark {worst_point} px from MediaPipe's"
    );
    assert!(
        worst_score.0 < 0.01,
        "{} differs from MediaPipe by {}",
        worst_score.1,
        worst_score.0
    );
}
