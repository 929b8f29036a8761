//! Frames tracked together on worker threads come back in order, each with its own frame's
//! face, and the tracker does what it does frame by frame: the detector where there is no
//! face to follow (the first frame, and after a face is lost), nowhere else.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

use std::sync::Arc;

use faceanim_track::{FaceModels, Found, SharedFrame, Tracker, TrackingMode, Workers};

/// N = the ICT head neutral, O = its jaw open, B = a blank frame with no face.
const STORY: &str = "BNONOONB";

fn frames() -> Vec<SharedFrame> {
    let read = |name: &str| {
        faceanim_media::read_image(&faceanim_testdata::shared(&format!("images/{name}"))).unwrap()
    };
    let (neutral, open) = (read("ict-face-neutral.png"), read("ict-face-jawopen.png"));
    let blank = vec![40u8; neutral.rgb.len()];
    let share = |rgb: &[u8]| SharedFrame {
        width: neutral.width,
        height: neutral.height,
        rgb: Arc::new(rgb.to_vec()),
    };
    STORY
        .chars()
        .map(|c| match c {
            'N' => share(&neutral.rgb),
            'O' => share(&open.rgb),
            _ => share(&blank),
        })
        .collect()
}

fn jaw(face: &faceanim_track::Face) -> f32 {
    face.scores.iter().find(|s| s.0 == "jawOpen").unwrap().1
}

#[test]
fn frames_done_together_match_frames_done_one_by_one() {
    let models = FaceModels::load().unwrap();
    let frames = frames();

    let mut alone = Tracker::new(&models, TrackingMode::Track);
    let one_by_one: Vec<_> = frames
        .iter()
        .map(|f| alone.next_frame(&f.frame()).unwrap())
        .collect();

    // Three workers beside this thread: four frames at a time, so the first batch starts
    // on a blank, and the second ends on one.
    let workers = Workers::start(&models, 3).unwrap();
    assert_eq!(workers.count(), 3);
    let mut together = Tracker::new(&models, TrackingMode::Track);
    let mut batched = Vec::new();
    for batch in frames.chunks(4) {
        batched.extend(together.next_frames(batch, &workers).unwrap());
    }

    assert_eq!(batched.len(), STORY.len());
    for (i, ((c, a), b)) in STORY.chars().zip(&one_by_one).zip(&batched).enumerate() {
        match (c, a, b) {
            ('B', None, None) => {}
            ('N' | 'O', Some((a, found_a)), Some((b, found_b))) => {
                assert_eq!(found_a, found_b, "frame {i}");
                let expected = if c == 'O' {
                    jaw(b) > 0.5
                } else {
                    jaw(b) < 0.15
                };
                assert!(expected, "frame {i} ({c}): jawOpen {}", jaw(b));
                // Within what a region a frame or two older gives (the batch after a detection
                // reads from the detector's region, not the landmarks').
                assert!(
                    (jaw(a) - jaw(b)).abs() < 0.1,
                    "frame {i}: {} vs {}",
                    jaw(a),
                    jaw(b)
                );
            }
            _ => panic!("frame {i} ({c}): one by one {a:?}, together {b:?}"),
        }
    }
    assert_eq!(batched[1].as_ref().unwrap().1, Found::Detected);
    assert_eq!(together.stats(), alone.stats());
    assert_eq!(together.stats().detector_runs, 3);
}

#[test]
fn frames_detected_together_match_frames_detected_one_by_one() {
    let models = FaceModels::load().unwrap();
    let frames = frames();

    let mut alone = Tracker::new(&models, TrackingMode::DetectEveryFrame);
    let one_by_one: Vec<_> = frames
        .iter()
        .map(|f| alone.next_frame(&f.frame()).unwrap())
        .collect();

    // Two workers beside this thread, five frames at a time: the batches have more frames
    // than threads (the rest done on this thread after), and the last one is a single frame.
    let workers = Workers::start(&models, 2).unwrap();
    let mut together = Tracker::new(&models, TrackingMode::DetectEveryFrame);
    let mut batched = Vec::new();
    for batch in frames.chunks(5) {
        batched.extend(together.next_frames(batch, &workers).unwrap());
    }

    assert_eq!(batched.len(), STORY.len());
    for (i, ((c, a), b)) in STORY.chars().zip(&one_by_one).zip(&batched).enumerate() {
        match (c, a, b) {
            ('B', None, None) => {}
            ('N' | 'O', Some((a, found_a)), Some((b, found_b))) => {
                assert_eq!((*found_a, *found_b), (Found::Detected, Found::Detected));
                // Each frame on its own, whichever thread read it: the same face.
                assert_eq!(a.landmarks, b.landmarks, "frame {i}");
                assert_eq!(a.scores, b.scores, "frame {i}");
            }
            _ => panic!("frame {i} ({c}): one by one {a:?}, together {b:?}"),
        }
    }
    assert_eq!(together.stats(), alone.stats());
    assert_eq!(together.stats().detector_runs, STORY.len());
    assert_eq!(together.stats().no_face, 2);
}
