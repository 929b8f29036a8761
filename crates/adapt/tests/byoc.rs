//! Bring your own character, end to end on the ICT heads: the training set from renders, the
//! adapter, its file and its checks, another identity of the rig, a rig whose names say
//! nothing, and fine-tuning from corrections.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use faceanim_adapt::sampling::{ExclusionReason, exclusive_pairs};
use faceanim_adapt::{
    Adapter, Augmentation, Control, Correction, Dataset, DatasetOptions, FaceCamera, Fit, Framing,
    Loss, Reading, TrainOptions, finetune, train,
};
use faceanim_rig::Character;
use faceanim_track::FaceModels;

/// Enough samples for a test to show the adapter learns (the product renders
/// [`faceanim_adapt::DEFAULT_SAMPLES`]).
const SAMPLES: usize = 2000;

fn dataset(character: &Character, models: &FaceModels, samples: usize, seed: u64) -> Dataset {
    let camera = FaceCamera::frame(character, models).unwrap();
    assert_eq!(camera.framing, Framing::Detected, "the head is found");
    let options = DatasetOptions {
        samples,
        seed,
        exclusive: exclusive_pairs(character, &[]).unwrap(),
        augmentation: Augmentation::Randomised,
    };
    Dataset::generate(character, models, &camera, &options, Control::silent()).unwrap()
}

#[test]
fn the_ict_head_gets_an_adapter_that_reads_its_expressions() {
    let models = FaceModels::load().unwrap();
    let ict = faceanim_testdata::ict();
    let pairs = exclusive_pairs(ict, &[]).unwrap();
    let names: Vec<(&str, &str)> = pairs
        .iter()
        .map(|p| (ict.blendshapes()[p.a].name(), ict.blendshapes()[p.b].name()))
        .collect();
    let has = |a: &str, b: &str| {
        names
            .iter()
            .any(|&(x, y)| (x, y) == (a, b) || (y, x) == (a, b))
    };
    assert!(has("jawLeft", "jawRight"), "{names:?}");
    assert!(has("mouthLeft", "mouthRight"), "{names:?}");
    assert!(
        pairs.iter().any(|p| p.reason == ExclusionReason::Opposite),
        "opposites are found from the geometry: {names:?}"
    );

    let started = std::time::Instant::now();
    let at = |what: &str| eprintln!("byoc: {what} at {:.0} s", started.elapsed().as_secs_f64());
    let data = dataset(ict, &models, SAMPLES, 1);
    at("dataset");
    assert!(data.len() >= SAMPLES * 99 / 100, "{} kept", data.len());
    // The cache round-trips exactly.
    assert_eq!(
        Dataset::from_bytes(&data.to_bytes().unwrap()).unwrap(),
        data
    );

    let adapter = train(&data, &TrainOptions::default(), Control::silent()).unwrap();
    at("trained");
    let report = adapter.report.clone();
    eprintln!("ICT, {SAMPLES} samples: {report:?}");
    // Randomised renders are harder than the front ones, measured on their own.
    assert!(report.mae_test < 0.1, "test MAE {}", report.mae_test);
    let front = report.mae_test_front.unwrap();
    assert!(front < 0.07, "test MAE on the front renders {front}");
    assert!(report.best_epoch > 1 && report.best_epoch <= report.epochs);

    // The file keeps everything and is bound to its character.
    let bytes = adapter.to_bytes().unwrap();
    let back = Adapter::from_bytes(&bytes).unwrap();
    assert_eq!(back, adapter);
    assert_eq!(back.check(ict).unwrap(), Fit::Exact);
    let other = faceanim_head::default_character();
    let refused = back.check(&other).unwrap_err().to_string();
    assert!(
        refused.contains("52") && refused.contains("53") && refused.contains("faceanim adapt"),
        "{refused}"
    );
    let broken = Adapter::from_bytes(&bytes[..bytes.len() / 2]).unwrap_err();
    assert!(broken.to_string().contains("safetensors"), "{broken}");

    // A known expression comes back: the jaw open at 0.7, the rest of the face still.
    let camera = FaceCamera::frame(ict, &models).unwrap();
    let mut weights = vec![0.0; ict.blendshapes().len()];
    let jaw = ict.find_blendshape("jawOpen").unwrap().index();
    weights[jaw] = 0.7;
    let (expression, presence) = camera
        .expression(ict, &models, &weights, &mut faceanim_rig::Pose::default())
        .unwrap();
    assert!(presence > 0.5);
    let neutral = camera
        .expression(ict, &models, &[], &mut faceanim_rig::Pose::default())
        .unwrap()
        .0;
    let estimate = adapter.predict(&expression.unwrap(), neutral.as_ref());
    assert!(
        (estimate[jaw] - 0.7).abs() < 0.2,
        "jawOpen {}",
        estimate[jaw]
    );
    let others = estimate
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != jaw)
        .map(|(_, w)| w)
        .sum::<f32>()
        / (estimate.len() - 1) as f32;
    assert!(
        others < 0.1,
        "the other shapes average {others}: {estimate:?}"
    );

    // Every shape shown alone and read back: the jaw is read, and the seed's adapter (one
    // layer over every input, squared error through the clamp), trained on the same set,
    // leaves no fewer shapes that capture never drives (an output below 0 gets no gradient
    // through the clamp, even where its shape is active).
    let readings = camera.readings(ict, &models, &adapter).unwrap();
    assert_eq!(readings.len(), ict.blendshapes().len());
    assert!(
        readings
            .iter()
            .all(|r| r.reading == Reading::of(r.at_full) && (0.0..=1.0).contains(&r.at_half))
    );
    assert_eq!(readings[jaw].name, "jawOpen");
    // Another character's shapes are refused, not read through this adapter.
    let refused = camera
        .readings(&faceanim_head::default_character(), &models, &adapter)
        .unwrap_err();
    assert!(
        matches!(refused, faceanim_adapt::AdaptError::Mismatch { .. }),
        "{refused}"
    );
    assert_eq!(readings[jaw].reading, Reading::Read, "{:?}", readings[jaw]);
    let seed_loss = train(
        &data,
        &TrainOptions {
            architecture: faceanim_adapt::Architecture::global(),
            loss: Loss::SquaredClamped,
            ..TrainOptions::default()
        },
        Control::silent(),
    )
    .unwrap();
    at("seed's trained");
    let seed_readings = camera.readings(ict, &models, &seed_loss).unwrap();
    let unseen = |r: &[faceanim_adapt::ShapeReading]| faceanim_adapt::readings::unseen(r).len();
    eprintln!(
        "shapes capture cannot drive: {} with the default adapter, {} with the seed's (test MAE {:.4} and {:.4})",
        unseen(&readings),
        unseen(&seed_readings),
        adapter.report.mae_test,
        seed_loss.report.mae_test
    );
    // The default reads about as many shapes as the seed's (within two), and errs less. (On 2,000 samples
    // of the varied renders the seed's leaves 37 of 53 unseen from the front, the default 35;
    // the seed's loss through per-shape parts reads more, 27, at a test MAE of 0.092 against
    // the default's 0.081: it reads them by reading everything higher.)
    // Which shapes sit just under the threshold moves with the order floating-point sums run in
    // on a given machine (38 against 39 was seen on CI), so a tie within two shapes counts.
    assert!(
        unseen(&readings) <= unseen(&seed_readings) + 2,
        "default: {readings:?}\nseed's: {seed_readings:?}"
    );
    assert!(adapter.report.mae_test < seed_loss.report.mae_test);

    // Another identity of the same rig: the adapter is accepted with a warning, and works.
    let id7 = faceanim_testdata::ict_id7();
    assert_eq!(adapter.check(id7).unwrap(), Fit::OtherShape);
    let id7_data = dataset(id7, &models, 300, 7);
    let id7_mae = adapter.mean_absolute_error(&id7_data);
    eprintln!("ict-face-id7 with ict-face's adapter: MAE {id7_mae:.4}");
    assert!(id7_mae < 0.1, "id7 MAE {id7_mae}");

    // Offline fine-tuning: a user corrects 30 frames of the other identity to their true
    // weights. The error on those frames drops; the test MAE rises by at most 10%. (A dozen
    // epochs here, of the product's 40: the drop shows within them, and CI's time is shared.)
    let corrections: Vec<Correction> = id7_data
        .expressions
        .iter()
        .zip(&id7_data.targets)
        .enumerate()
        .take(30)
        .map(|(k, (e, t))| Correction {
            expression: e.clone(),
            neutral: Some(id7_data.neutral(k).clone()),
            target: t.clone(),
        })
        .collect();
    let (tuned, outcome) = finetune(
        &adapter,
        &data,
        &corrections,
        &TrainOptions {
            max_epochs: 12,
            ..TrainOptions::default()
        },
        Control::silent(),
    )
    .unwrap();
    at("fine-tuned");
    eprintln!("fine-tuning on 30 corrected id7 frames: {outcome:?}");
    assert!(
        outcome.corrected_after < outcome.corrected_before * 0.9,
        "{outcome:?}"
    );
    assert!(
        outcome.test_after <= outcome.test_before * 1.1,
        "{outcome:?}"
    );
    assert_eq!(tuned.report.corrections, 30);
}

/// The ICT head on a skinned, textured full body (built in code), as a full-body avatar is.
fn avatar() -> Character {
    let bytes = faceanim_testdata::avatar::full_body_glb(
        faceanim_testdata::ict(),
        faceanim_testdata::avatar::VrmKind::None,
        &[],
    );
    faceanim_rig::import::import_gltf(
        &bytes,
        "avatar.glb",
        &faceanim_rig::import::NoExternalResources,
    )
    .unwrap()
    .character
}

/// A full-body avatar whose blendshape names say nothing: the renders are framed on its face
/// (the face model finds it in nearly all of them) and the adapter learns it as well as the
/// bare head.
#[test]
fn a_full_body_rig_whose_names_say_nothing_adapts_as_well() {
    let models = FaceModels::load().unwrap();
    let (shuffled, order) = faceanim_testdata::renamed_and_shuffled(&avatar(), 5);
    assert!(
        shuffled
            .blendshapes()
            .iter()
            .all(|b| b.name().starts_with("shape_"))
    );
    let pairs = exclusive_pairs(&shuffled, &[]).unwrap();
    // Where ICT's shape `name` went in the shuffled rig.
    let moved = |name: &str| {
        let original = faceanim_testdata::ict()
            .find_blendshape(name)
            .unwrap()
            .index();
        order.iter().position(|&i| i == original).unwrap()
    };
    let (jaw_left, jaw_right) = (moved("jawLeft"), moved("jawRight"));
    assert!(
        pairs
            .iter()
            .any(|p| (p.a, p.b) == (jaw_left.min(jaw_right), jaw_left.max(jaw_right))),
        "jawLeft/jawRight are opposites by geometry alone"
    );
    let data = dataset(&shuffled, &models, SAMPLES, 1);
    assert!(
        data.len() * 100 >= SAMPLES * 95,
        "the face is found in {} of {SAMPLES} renders",
        data.len()
    );
    let adapter = train(&data, &TrainOptions::default(), Control::silent()).unwrap();
    eprintln!(
        "renamed and shuffled ICT on a full body, {SAMPLES} samples: {:?}",
        adapter.report
    );
    // Randomised renders (other cameras, lights, picture quality) are harder than the front
    // ones, which are measured on their own.
    let report = &adapter.report;
    assert!(report.mae_test < 0.1, "test MAE {}", report.mae_test);
    let front = report.mae_test_front.unwrap();
    assert!(front < 0.075, "test MAE on the front renders {front}");
    assert_eq!(adapter.blendshapes[0], "shape_1");
    assert_eq!(adapter.check(&shuffled).unwrap(), Fit::Exact);
    // The ICT adapter's names are not these: refused, naming the difference.
    let message = adapter
        .check(faceanim_testdata::ict())
        .unwrap_err()
        .to_string();
    assert!(message.contains("shape_"), "{message}");
}
