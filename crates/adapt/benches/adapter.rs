//! The adapter's costs on the ICT head: one sample of the training set (pose the mesh, render
//! the 256×256 crop, landmarks, scores), the render alone, one epoch of training on 1,000
//! samples, and inference per frame (the part `faceanim track --adapter` adds to capture).
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_adapt::augment::{Condition, Jitter};
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
    // A randomised sample: its condition's camera, light and picture quality, then the
    // models (the neutral of its group adds one such read per eight samples).
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(5);
    let conditions: Vec<Condition> = (0..64).map(|_| Condition::draw(&mut rng)).collect();
    group.bench_function(
        "randomised training sample (pose, render, degrade, models)",
        |b| {
            b.iter(|| {
                k = (k + 1) % draws.len();
                ict.pose_into(&draws[k], &mut pose);
                let picture = camera.picture(ict, &pose, &conditions[k], Jitter::NONE, &mut rng);
                black_box(
                    models
                        .face_in_region(
                            &faceanim_track::Frame {
                                width: 256,
                                height: 256,
                                rgb: &picture.rgb,
                            },
                            faceanim_track::Region {
                                cx: 128.0,
                                cy: 128.0,
                                size: 256.0,
                                rotation: 0.0,
                            },
                            1.0,
                        )
                        .unwrap(),
                )
            });
        },
    );
    group.bench_function("render 256x256 crop", |b| {
        ict.pose_into(&draws[0], &mut pose);
        b.iter(|| black_box(camera.crop(ict, &pose)));
    });

    let options = DatasetOptions {
        samples: 1000,
        seed: 1,
        exclusive: pairs,
        augmentation: faceanim_adapt::Augmentation::Randomised,
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
    let input = adapter.input(&dataset.expressions[0], Some(dataset.neutral(0)));
    group.bench_function("adapter inference per frame", |b| {
        b.iter(|| adapter.predict_into(black_box(&input), None, &mut out));
    });
    group.finish();
}

criterion_group!(adapt, benches);
criterion_main!(adapt);
