//! Time of each face model on one input (tract, the default backend), for the capture issue's
//! per-stage figures.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_track::FaceModels;

fn benches(c: &mut Criterion) {
    let models = FaceModels::load().unwrap();
    let crop: Vec<f32> = (0..256 * 256 * 3)
        .map(|i| (i % 251) as f32 / 251.0)
        .collect();
    let small: Vec<f32> = (0..128 * 128 * 3)
        .map(|i| (i % 241) as f32 / 120.5 - 1.0)
        .collect();
    let landmarks = models.landmarks(&crop).unwrap();
    let mut group = c.benchmark_group("face models (tract, one thread)");
    group.bench_function("detector 128x128", |b| {
        b.iter(|| black_box(models.detect(black_box(&small)).unwrap()))
    });
    group.bench_function("landmarks 256x256", |b| {
        b.iter(|| black_box(models.landmarks(black_box(&crop)).unwrap()))
    });
    group.bench_function("blendshapes from 478 landmarks", |b| {
        b.iter(|| black_box(models.expression(black_box(&landmarks.points)).unwrap()));
    });
    group.finish();
}

criterion_group!(models, benches);
criterion_main!(models);
