//! Sketch engine benchmarks on the ICT head from `../shared` (issue 4's targets):
//! a 90-sample stroke to a finished action ≤ 5 ms, a handle-drag re-solve ≤ 5 ms, one frame of
//! a 10-action animation ≤ 1 ms.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_rig::{Character, Pose};
use faceanim_sketch::engine::Input;
use faceanim_sketch::evaluate::FramePose;
use faceanim_sketch::project::{Sample, Stroke};
use faceanim_sketch::{ActionId, Settings, Sketch};
use glam::Vec3;

/// A bowed 90-sample stroke (1 s at 90 Hz) from the vertex `shape` moves most to its target.
fn stroke(c: &Character, shape: &str, start_frame: f32) -> Input {
    let b = c.blendshape(c.find_blendshape(shape).unwrap()).unwrap();
    let k = (0..b.moved())
        .max_by(|&x, &y| b.deltas()[x].length().total_cmp(&b.deltas()[y].length()))
        .unwrap();
    let start = c.positions()[b.indices()[k] as usize];
    let end = start + b.deltas()[k];
    let bulge = (end - start).cross(Vec3::Z).normalize_or_zero() * 0.004;
    let samples = (0..90)
        .map(|i| {
            let s = i as f32 / 89.0;
            Sample {
                t: i as f32 / 90.0,
                p: start.lerp(end, s) + bulge * 4.0 * s * (1.0 - s),
            }
        })
        .collect();
    Input {
        stroke: Stroke::new(samples, "bench").unwrap(),
        start_frame: Some(start_frame),
        duration: None,
        end: None,
        mid: None,
        ease: None,
        symmetry: None,
    }
}

fn benches(c: &mut Criterion) {
    let character = faceanim_testdata::ict();
    let settings = Settings {
        symmetry: true,
        ..Settings::default()
    };
    let mut group = c.benchmark_group("sketch on ict-face");

    // A stroke becoming an action: selection, weight, exaggeration, per-vertex arcs, keyframes.
    let mut sketch = Sketch::new(character, settings.clone(), 30.0);
    let (id, _) = sketch.add(stroke(character, "mouthSmile_L", 0.0));
    let smile = stroke(character, "mouthSmile_L", 0.0);
    group.bench_function("stroke (90 samples) to action", |b| {
        b.iter(|| {
            sketch.edit(id, black_box(smile.clone()));
        });
    });

    // Dragging the end handle: the same action re-solved with a new end, beyond the target.
    let mut dragged = smile.clone();
    let side = sketch.action(id).unwrap().sides[0].clone();
    let mut k = 0u32;
    group.bench_function("handle drag re-solve", |b| {
        b.iter(|| {
            k = (k + 1) % 16;
            dragged.end = Some(side.c + (side.c - side.start_position) * (0.02 * k as f32));
            sketch.edit(id, black_box(dragged.clone()));
        });
    });

    // Ten actions: five strokes, mirrored by symmetry into both sides, staggered in time.
    let mut ten = Sketch::new(character, settings, 30.0);
    for (i, shape) in [
        "mouthSmile_L",
        "browOuterUp_L",
        "eyeBlink_L",
        "jawOpen",
        "cheekSquint_L",
        "mouthFrown_L",
        "noseSneer_L",
        "mouthDimple_L",
        "mouthUpperUp_L",
        "browInnerUp_L",
    ]
    .iter()
    .enumerate()
    {
        let _ = ten.add(stroke(character, shape, i as f32 * 2.0));
    }
    let live = ten.actions().count();
    let reasons: Vec<String> = ten
        .results()
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.as_ref().err().map(|e| format!("stroke {i}: {e}")))
        .collect();
    assert_eq!(live, 10, "ten actions: {reasons:?}");
    // The tenth stroke, drawn over the nine before it (their pose at its frame is evaluated).
    let tenth = ActionId(9);
    let tenth_input = ten.inputs()[9].clone().unwrap();
    group.bench_function("stroke to action over 9 others", |b| {
        b.iter(|| ten.edit(tenth, black_box(tenth_input.clone())));
    });
    let frame = 20.0;
    let mut pose = FramePose::new(character);
    group.bench_function("frame of 10 actions: weights and offsets", |b| {
        b.iter(|| ten.frame_into(black_box(frame), &mut pose));
    });
    let mut positions = Pose::default();
    group.bench_function("frame of 10 actions: vertex positions and normals", |b| {
        b.iter(|| {
            ten.frame_into(black_box(frame), &mut pose);
            pose.positions_into(character, &mut positions);
        });
    });
    group.finish();
}

criterion_group!(sketch, benches);
criterion_main!(sketch);
