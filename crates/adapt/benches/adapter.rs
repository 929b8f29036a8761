//! The adapter's costs on the ICT head: one sample of the training set (pose the mesh, render
//! the 256×256 crop, landmarks, scores), the render alone, one epoch of training on 1,000
//! samples, and inference per frame (the part `faceanim track --adapter` adds to capture).
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_adapt::sampling::{WeightSampler, exclusive_pairs};
use faceanim_adapt::{Control, Dataset, DatasetOptions, FaceCamera, TrainOptions, train};
use faceanim_track::FaceModels;

fn benches(c: &mut Criterion) {
    let models = FaceModels::load().unwrap();
    let ict = faceanim_testdata::ict();
    let camera = FaceCamera::frame(ict, &models).unwrap();
    let pairs = exclusive_pairs(ict, &[]).unwrap();
    let draws = WeightSampler::new(ict.blendshapes().len(), &pairs).draw(64, 3);
    let mut pose = faceanim_rig::Pose::default();

    let mut group = c.benchmark_group("adapt");
    group.sample_size(20);
    let mut k = 0;
    group.bench_function("training sample (pose, render, landmarks, scores)", |b| {
        b.iter(|| {
            k = (k + 1) % draws.len();
            black_box(
                camera
                    .expression(ict, &models, &draws[k], &mut pose)
                    .unwrap(),
            )
        });
    });
    group.bench_function("render 256x256 crop", |b| {
        ict.pose_into(&draws[0], &mut pose);
        b.iter(|| black_box(camera.crop(ict, &pose)));
    });

    let options = DatasetOptions {
        samples: 1000,
        seed: 1,
        exclusive: pairs,
    };
    let dataset = Dataset::generate(ict, &models, &camera, &options, Control::silent()).unwrap();
    group.sample_size(10);
    group.bench_function("train one epoch, 1000 samples", |b| {
        b.iter(|| {
            let one_epoch = TrainOptions {
                max_epochs: 1,
                ..TrainOptions::default()
            };
            black_box(train(&dataset, &one_epoch, Control::silent()).unwrap())
        });
    });
    let adapter = train(&dataset, &TrainOptions::default(), Control::silent()).unwrap();
    group.sample_size(100);
    let mut out = vec![0.0; adapter.blendshapes.len()];
    let input = adapter.architecture.features.input(&dataset.expressions[0]);
    group.bench_function("adapter inference per frame", |b| {
        b.iter(|| adapter.predict_into(black_box(&input), &mut out));
    });
    group.finish();
}

criterion_group!(adapt, benches);
criterion_main!(adapt);
