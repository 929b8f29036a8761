//! tract's outputs of MediaPipe's three models against the reference runtime (LiteRT 2.3.0),
//! recorded by `tools/record_reference_outputs.py` on crops of the shared ICT renders.
//! Tolerances from the capture issue: landmarks within 0.5 px of the 256 px crop, scores within
//! 0.02.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

use std::path::Path;
use std::sync::OnceLock;

use faceanim_track::FaceModels;
use serde_json::Value;

fn models() -> &'static FaceModels {
    static MODELS: OnceLock<FaceModels> = OnceLock::new();
    MODELS.get_or_init(|| FaceModels::load().unwrap())
}

fn reference() -> &'static Value {
    static REFERENCE: OnceLock<Value> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/outputs.json");
        serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
    })
}

fn floats(v: &Value) -> Vec<f32> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect()
}

fn input(case: &str, which: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("tests/reference/{case}-{which}-input.rgb")),
    )
    .unwrap()
}

fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

const CASES: [&str; 3] = ["neutral", "jawopen", "smile"];

#[test]
fn landmarks_match_within_half_a_pixel() {
    for case in CASES {
        let rgb: Vec<f32> = input(case, "landmarks")
            .iter()
            .map(|&b| f32::from(b) / 255.0)
            .collect();
        let out = models().landmarks(&rgb).unwrap();
        let ours: Vec<f32> = out.points.iter().flatten().copied().collect();
        let expected = &reference()["cases"][case];
        let error = largest_difference(&ours, &floats(&expected["landmarks"]));
        assert!(error < 0.5, "{case}: landmarks differ by up to {error} px");
        let presence = 1.0 / (1.0 + (-expected["presence_logit"].as_f64().unwrap() as f32).exp());
        assert!(
            (out.presence - presence).abs() < 0.02,
            "{case}: presence {} vs {presence}",
            out.presence
        );
        eprintln!("{case}: landmarks within {error:.4} px");
    }
}

#[test]
fn detector_matches() {
    for case in CASES {
        let rgb: Vec<f32> = input(case, "detector")
            .iter()
            .map(|&b| f32::from(b) / 127.5 - 1.0)
            .collect();
        let (regressors, logits) = models().detect(&rgb).unwrap();
        let expected = &reference()["cases"][case];
        let box_error = largest_difference(&regressors, &floats(&expected["detector_regressors"]));
        let logit_error = largest_difference(&logits, &floats(&expected["detector_logits"]));
        assert!(
            box_error < 0.25,
            "{case}: regressors differ by up to {box_error} px of 128"
        );
        assert!(
            logit_error < 0.05,
            "{case}: logits differ by up to {logit_error}"
        );
        eprintln!(
            "{case}: detector boxes within {box_error:.4} px, logits within {logit_error:.5}"
        );
    }
}

#[test]
fn blendshape_scores_match_within_0_02() {
    for case in CASES {
        let expected = &reference()["cases"][case];
        let points: Vec<[f32; 2]> = floats(&expected["blendshape_points"])
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let scores = models().blendshapes(&points).unwrap();
        let error = largest_difference(&scores, &floats(&expected["blendshape_scores"]));
        assert!(error < 0.02, "{case}: scores differ by up to {error}");
        eprintln!("{case}: scores within {error:.6}");
    }
}
