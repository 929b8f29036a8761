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

use faceanim_track::{Face, FaceModels, Found, SharedFrame, Tracker, TrackingMode, Workers};

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

fn jaw(face: &Face) -> f32 {
    face.scores.iter().find(|s| s.0 == "jawOpen").unwrap().1
}

/// What one tracker in `mode` finds frame by frame, and another `at_once` frames at a time
/// (`workers_wanted` threads beside this one), with each one's counts.
struct Runs {
    one_by_one: Vec<Option<(Face, Found)>>,
    batched: Vec<Option<(Face, Found)>>,
    alone: faceanim_track::TrackerStats,
    together: faceanim_track::TrackerStats,
}

impl Runs {
    /// `check(frame, story letter, one by one, together)` on each frame with a face; a blank
    /// must have none either way, and a face must be found both ways.
    fn each_face(&self, check: impl Fn(usize, char, (&Face, Found), (&Face, Found))) {
        let frames = STORY.chars().zip(&self.one_by_one).zip(&self.batched);
        for (i, ((c, a), b)) in frames.enumerate() {
            match (c, a, b) {
                ('B', None, None) => {}
                ('N' | 'O', Some((a, found_a)), Some((b, found_b))) => {
                    check(i, c, (a, *found_a), (b, *found_b));
                }
                _ => panic!("frame {i} ({c}): one by one {a:?}, together {b:?}"),
            }
        }
    }
}

fn runs(mode: TrackingMode, workers_wanted: usize, at_once: usize) -> Runs {
    let models = FaceModels::load().unwrap();
    let frames = frames();
    let mut alone = Tracker::new(&models, mode);
    let one_by_one = frames
        .iter()
        .map(|f| alone.next_frame(&f.frame()).unwrap())
        .collect();
    let workers = Workers::start(&models, workers_wanted).unwrap();
    assert_eq!(workers.count(), workers_wanted);
    let mut together = Tracker::new(&models, mode);
    let mut batched = Vec::new();
    for batch in frames.chunks(at_once) {
        batched.extend(together.next_frames(batch, &workers).unwrap());
    }
    assert_eq!(batched.len(), STORY.len());
    Runs {
        one_by_one,
        batched,
        alone: alone.stats(),
        together: together.stats(),
    }
}

#[test]
fn frames_done_together_match_frames_done_one_by_one() {
    // Three workers beside this thread: four frames at a time, so the first batch starts
    // on a blank, and the second ends on one.
    let run = runs(TrackingMode::Track, 3, 4);
    run.each_face(|i, c, (a, found_a), (b, found_b)| {
        assert_eq!(found_a, found_b, "frame {i}");
        let expected = if c == 'O' {
            jaw(b) > 0.5
        } else {
            jaw(b) < 0.15
        };
        assert!(expected, "frame {i} ({c}): jawOpen {}", jaw(b));
        // Within what a region a frame or two older gives (the batch after a detection reads
        // from the detector's region, not the landmarks').
        assert!(
            (jaw(a) - jaw(b)).abs() < 0.1,
            "frame {i}: {} vs {}",
            jaw(a),
            jaw(b)
        );
    });
    assert_eq!(run.batched[1].as_ref().unwrap().1, Found::Detected);
    assert_eq!(run.together, run.alone);
    assert_eq!(run.together.detector_runs, 3);
}

#[test]
fn frames_detected_together_match_frames_detected_one_by_one() {
    // Two workers beside this thread, five frames at a time: the batches have more frames
    // than threads (the rest done on this thread after), and the last one is a single frame.
    let run = runs(TrackingMode::DetectEveryFrame, 2, 5);
    run.each_face(|i, _, (a, found_a), (b, found_b)| {
        assert_eq!((found_a, found_b), (Found::Detected, Found::Detected));
        // Each frame on its own, whichever thread read it: the same face.
        assert_eq!(a.landmarks, b.landmarks, "frame {i}");
        assert_eq!(a.scores, b.scores, "frame {i}");
    });
    assert_eq!(run.together, run.alone);
    assert_eq!(run.together.detector_runs, STORY.len());
    assert_eq!(run.together.no_face, 2);
}
