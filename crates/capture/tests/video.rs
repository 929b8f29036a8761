//! A video made here with the real ffmpeg, from renders of the ICT head (mouth shut, mouth
//! open, and a blank frame with no face), through the whole capture pipeline.
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    reason = "tests: exact rates compare exactly"
)]

use faceanim_capture::{Filtering, capture};
use faceanim_media::{FrameSource, read_image};
use faceanim_track::{FaceModels, TrackingMode, Workers};

/// The frames' story: N = neutral, O = jaw open, B = blank (no face).
const STORY: &str = "NNNOOONNBBNNOOON";
const FPS: u32 = 25;

/// The story as a video in a folder of its own (gone when the folder is dropped).
fn ict_video() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ict.mp4");
    let neutral = read_image(&faceanim_testdata::shared("images/ict-face-neutral.png")).unwrap();
    let open = read_image(&faceanim_testdata::shared("images/ict-face-jawopen.png")).unwrap();
    let (width, height) = (neutral.width, neutral.height);
    let blank = vec![40u8; width * height * 3];
    let frames = STORY.chars().map(|c| match c {
        'N' => neutral.rgb.as_slice(),
        'O' => open.rgb.as_slice(),
        _ => blank.as_slice(),
    });
    let codec = ["-c:v", "libx264", "-pix_fmt", "yuv444p", "-qp", "4"];
    faceanim_testdata::encode_video(&path, (width, height), FPS, &codec, frames);
    (dir, path)
}

/// Captures the video at `path`, `at_once` frames together.
fn capture_file(
    models: &FaceModels,
    path: &std::path::Path,
    mode: TrackingMode,
    at_once: usize,
) -> faceanim_capture::Capture {
    let workers = Workers::start(models, at_once - 1).unwrap();
    let mut source = FrameSource::open(path, 30.0).unwrap();
    capture(models, &workers, &mut source, mode, |_| {}).unwrap()
}

#[test]
fn a_video_keeps_its_frames_timing_and_marks_the_faceless_ones() {
    let (_dir, path) = ict_video();
    let models = FaceModels::load().unwrap();
    // Two frames at once (what `faceanim track` does on two cores).
    let workers = Workers::start(&models, 1).unwrap();
    let mut source = FrameSource::open(&path, 30.0).unwrap();
    let mut reported = 0;
    let result = capture(&models, &workers, &mut source, TrackingMode::Track, |n| {
        reported = n
    })
    .unwrap();
    assert_eq!(result.frames.len(), STORY.len());
    assert_eq!(reported, STORY.len());
    assert_eq!(result.fps, FPS as f32);
    let clip = result.clip(Filtering::default()).unwrap();
    assert_eq!(clip.frames.len(), STORY.len());
    assert_eq!(clip.fps, FPS as f32);
    let jaw = clip.column("jawOpen").unwrap();
    let presence = clip.presence.as_ref().unwrap();
    for (i, c) in STORY.chars().enumerate() {
        let record = &result.frames[i];
        assert!((record.time - i as f32 / FPS as f32).abs() < 1e-6);
        let w = clip.frames[i][jaw];
        match c {
            'B' => {
                assert_eq!(record.found, None, "frame {i}");
                assert_eq!(presence[i], 0.0);
            }
            'O' => assert!(w > 0.5 && presence[i] > 0.9, "frame {i}: jawOpen {w}"),
            _ => assert!(w < 0.15 && presence[i] > 0.9, "frame {i}: jawOpen {w}"),
        }
    }
    // Tracking: the detector ran on the first frame, on the blanks and when the face came back,
    // not on every frame.
    assert!(
        result.detector_runs <= 4,
        "{} detector runs",
        result.detector_runs
    );
    let every = capture_file(&models, &path, TrackingMode::DetectEveryFrame, 1);
    assert_eq!(every.detector_runs, STORY.len());
    // Frame by frame, each frame's region from the one before: the same story, the same
    // detector runs as two at a time.
    let single = capture_file(&models, &path, TrackingMode::Track, 1);
    assert_eq!(single.detector_runs, result.detector_runs);
    let single_clip = single.clip(Filtering::default()).unwrap();
    for (a, b) in clip.frames.iter().zip(&single_clip.frames) {
        assert!((a[jaw] - b[jaw]).abs() < 0.05, "{} vs {}", a[jaw], b[jaw]);
    }
    // Both modes agree on the expression.
    let every_clip = every.clip(Filtering::default()).unwrap();
    for (a, b) in clip.frames.iter().zip(&every_clip.frames) {
        assert!((a[jaw] - b[jaw]).abs() < 0.1, "{} vs {}", a[jaw], b[jaw]);
    }
    // Blank frames are bridged from their neighbours, not zeroed: the timeline has no hole.
    let blank = STORY.find('B').unwrap();
    assert!((clip.frames[blank][jaw] - clip.frames[blank - 1][jaw]).abs() < 0.1);
    // A still, frontal render: the head pose is near zero.
    let head = clip.head.as_ref().unwrap();
    assert!(head[0].iter().all(|a| a.abs() < 12.0), "{:?}", head[0]);
}

#[test]
fn keyframes_every_five_are_interpolated_and_smoothing_is_separate() {
    let (_dir, path) = ict_video();
    let models = FaceModels::load().unwrap();
    let result = capture_file(&models, &path, TrackingMode::Track, 2);
    let raw = result.clip(Filtering::default()).unwrap();
    let keyed = result
        .clip(Filtering {
            keyframe_every: Some(5),
            one_euro: None,
        })
        .unwrap();
    let jaw = raw.column("jawOpen").unwrap();
    for k in [0, 5, 10, 15] {
        assert_eq!(keyed.frames[k][jaw], raw.frames[k][jaw], "key {k}");
    }
    let expected = raw.frames[5][jaw] + (raw.frames[10][jaw] - raw.frames[5][jaw]) * 0.4;
    assert!((keyed.frames[7][jaw] - expected).abs() < 1e-5);
    let smooth = result
        .clip(Filtering {
            one_euro: Some(Default::default()),
            keyframe_every: None,
        })
        .unwrap();
    assert_eq!(smooth.frames.len(), raw.frames.len());
    assert!(
        faceanim_anim::metrics::jitter(&smooth.frames)
            < faceanim_anim::metrics::jitter(&raw.frames)
    );
}
