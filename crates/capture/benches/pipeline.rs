//! The whole capture pipeline on a 640×480 video: frames per second with one and two
//! threads (inside the models, or two frames at once as `faceanim track` does), detector on
//! every frame versus tracking; and the stages the models' own benchmark
//! (crates/track/benches/models.rs) does not cover: cropping with landmarks, and the head pose.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use faceanim_track::{FaceModels, Frame, SharedFrame, Tracker, TrackingMode, Workers};

const FRAMES: usize = 30;

/// 640×480 frames of a moving face: the astronaut photograph scaled to 400 px and drifting
/// by a pixel a frame, over a grey background.
fn video() -> Vec<Vec<u8>> {
    let photo =
        faceanim_media::read_image(&faceanim_testdata::shared("images/astronaut.png")).unwrap();
    (0..FRAMES)
        .map(|f| {
            let mut rgb = vec![90u8; 640 * 480 * 3];
            let (ox, oy) = (120.0 + f as f32, 40.0 + 0.5 * f as f32);
            for y in 0..400 {
                for x in 0..400 {
                    let (sx, sy) = (
                        ((x as f32 * 512.0 / 400.0) as usize).min(511),
                        ((y as f32 * 512.0 / 400.0) as usize).min(511),
                    );
                    let (tx, ty) = (x + ox as usize, y + oy as usize);
                    if tx < 640 && ty < 480 {
                        let s = (sy * 512 + sx) * 3;
                        let t = (ty * 640 + tx) * 3;
                        rgb[t..t + 3].copy_from_slice(&photo.rgb[s..s + 3]);
                    }
                }
            }
            rgb
        })
        .collect()
}

fn run(models: &FaceModels, frames: &[Vec<u8>], mode: TrackingMode) -> usize {
    let mut tracker = Tracker::new(models, mode);
    let mut found = 0;
    for rgb in frames {
        let frame = Frame {
            width: 640,
            height: 480,
            rgb,
        };
        found += usize::from(tracker.next_frame(&frame).unwrap().is_some());
    }
    found
}

/// Tracking frames together, one on this thread and one on each worker.
fn run_at_once(models: &FaceModels, workers: &Workers, frames: &[SharedFrame]) -> usize {
    let mut tracker = Tracker::new(models, TrackingMode::Track);
    let mut found = 0;
    for batch in frames.chunks(workers.count() + 1) {
        found += tracker
            .next_frames(batch, workers)
            .unwrap()
            .iter()
            .filter(|f| f.is_some())
            .count();
    }
    found
}

fn benches(c: &mut Criterion) {
    let frames = video();
    {
        let models = FaceModels::load().unwrap();
        let workers = Workers::start(&models, 1).unwrap();
        let shared: Vec<SharedFrame> = frames
            .iter()
            .map(|rgb| SharedFrame {
                width: 640,
                height: 480,
                rgb: std::sync::Arc::new(rgb.clone()),
            })
            .collect();
        assert_eq!(
            run_at_once(&models, &workers, &shared),
            FRAMES,
            "the face must be found"
        );
        let mut group = c.benchmark_group("capture 640x480, two frames at once");
        group.throughput(Throughput::Elements(FRAMES as u64));
        group.sample_size(10);
        group.bench_function("tracking", |b| {
            b.iter(|| black_box(run_at_once(&models, &workers, &shared)));
        });
        group.finish();
    }
    for threads in [1, 2] {
        let models = FaceModels::load_with_threads(threads).unwrap();
        assert_eq!(
            run(&models, &frames, TrackingMode::Track),
            FRAMES,
            "the face must be found"
        );
        let mut group = c.benchmark_group(format!("capture 640x480, {threads} thread(s)"));
        group.throughput(Throughput::Elements(FRAMES as u64));
        group.sample_size(10);
        group.bench_function("tracking", |b| {
            b.iter(|| black_box(run(&models, &frames, TrackingMode::Track)));
        });
        group.bench_function("detector every frame", |b| {
            b.iter(|| black_box(run(&models, &frames, TrackingMode::DetectEveryFrame)));
        });
        group.finish();
    }
    let models = FaceModels::load().unwrap();
    let frame = Frame {
        width: 640,
        height: 480,
        rgb: &frames[0],
    };
    let face = models.find_face(&frame).unwrap().unwrap();
    let mut group = c.benchmark_group("capture stages (1 thread)");
    group.bench_function(
        "find_face (detector + crop + landmarks + scores + pose)",
        |b| {
            b.iter(|| black_box(models.find_face(black_box(&frame)).unwrap()));
        },
    );
    group.bench_function("face_in_region (crop + landmarks + scores + pose)", |b| {
        b.iter(|| {
            black_box(
                models
                    .face_in_region(black_box(&frame), face.region, 1.0)
                    .unwrap(),
            )
        });
    });
    group.bench_function("head pose fit", |b| {
        b.iter(|| {
            black_box(
                models
                    .canonical_face()
                    .fit(black_box(&face.landmarks), 640, 480),
            )
        });
    });
    group.finish();
}

criterion_group!(pipeline, benches);
criterion_main!(pipeline);
