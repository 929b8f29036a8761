//! Benchmarks of the character model on the ICT head from `../shared` (24,591 vertices, 53
//! blendshapes): importing the 17 MB GLB, and evaluating a pose with every weight non-zero.
//! Targets (issue 2): import ≤ 150 ms, pose ≤ 1 ms.
//!
//! And a full-body avatar as people download them (the ICT head on a skinned, textured body,
//! compressed by npm gltfpack with meshopt and quantization, 3 MB): importing it, and
//! exporting it with a 10-second animation into the user's own file. Targets (issue 16):
//! ≤ 200 ms each.
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
        b.iter(|| black_box(faceanim_export::glb::export_glb(&character, &[]).unwrap()))
    });
    group.finish();

    let avatar = faceanim_testdata::gltfpack(
        &faceanim_testdata::avatar::full_body_glb_textured(
            faceanim_testdata::ict(),
            faceanim_testdata::avatar::VrmKind::None,
            &[],
            1152,
        ),
        &["-cc", "-kn"],
    );
    eprintln!("meshopt avatar: {:.2} MB", avatar.len() as f64 / 1e6);
    let mut group = c.benchmark_group("avatar-meshopt-3MB");
    group.sample_size(20);
    group.bench_function("import", |b| {
        b.iter(|| black_box(import_gltf(&avatar, "avatar.glb", &NoExternalResources).unwrap()));
    });
    let character = import_gltf(&avatar, "avatar.glb", &NoExternalResources)
        .unwrap()
        .character;
    let n = character.blendshapes().len();
    let animation = faceanim_rig::animation::MorphAnimation {
        name: "ten seconds".into(),
        times: (0..300).map(|f| f as f32 / 30.0).collect(),
        weights: (0..300)
            .map(|f| (0..n).map(|s| ((f + 7 * s) % 30) as f32 / 30.0).collect())
            .collect(),
        rotations: Some(
            (0..300)
                .map(|f| glam::Quat::from_rotation_y(0.01 * f as f32).to_array())
                .collect(),
        ),
    };
    group.bench_function("export into the file with a 10 s animation", |b| {
        b.iter(|| {
            black_box(
                faceanim_export::glb::export_into_source(
                    &character,
                    std::slice::from_ref(&animation),
                )
                .unwrap(),
            )
        });
    });
    group.finish();
}

criterion_group!(rig, benches);
criterion_main!(rig);
