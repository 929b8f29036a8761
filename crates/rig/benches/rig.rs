//! Benchmarks of the character model on the ICT head from `../shared` (24,591 vertices, 53
//! blendshapes): importing the 17 MB GLB, and evaluating a pose with every weight non-zero.
//! Targets (issue 2): import ≤ 150 ms, pose ≤ 1 ms.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_rig::Pose;
use faceanim_rig::import::{NoExternalResources, import_gltf};

fn benches(c: &mut Criterion) {
    let path = faceanim_testdata::shared("characters/ict-face.glb");
    let mut group = c.benchmark_group("ict-face");
    group.sample_size(20);
    group.bench_function("import (read file + parse + derive)", |b| {
        b.iter(|| {
            let bytes = std::fs::read(&path).unwrap();
            black_box(import_gltf(&bytes, "ict-face.glb", &NoExternalResources).unwrap())
        });
    });
    let character = import_gltf(
        &std::fs::read(&path).unwrap(),
        "ict-face.glb",
        &NoExternalResources,
    )
    .unwrap()
    .character;
    group.sample_size(100);
    let weights: Vec<f32> = (0..character.blendshapes().len())
        .map(|i| 0.1 + 0.8 * (i as f32 / 53.0))
        .collect();
    let mut pose = Pose::default();
    group.bench_function("pose: 53 weights to positions and normals", |b| {
        b.iter(|| {
            character.pose_into(black_box(&weights), &mut pose);
            black_box(&pose);
        });
    });
    group.bench_function("export GLB", |b| {
        b.iter(|| black_box(faceanim_rig::export::export_glb(&character, &[]).unwrap()))
    });
    group.finish();
}

criterion_group!(rig, benches);
criterion_main!(rig);
