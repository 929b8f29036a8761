//! The whole per-frame pipeline (detector, region, landmarks, scores) on still pictures (PNG or
//! JPEG, decoded as capture decodes them), as JSON: `{path: {width, height, landmarks:
//! [[x, y, z]…] (image pixels), scores: {name: score}, region}}`, `null` where no face was
//! found: for looking into a difference from MediaPipe's own runtime on some pictures
//! (`tools/record_mediapipe_stills.py` records what it finds; `tests/mediapipe_stills.rs`
//! compares).
//!
//! `cargo run --release -p faceanim-track --example stills -- A.png B.png …`
#![allow(clippy::print_stdout, reason = "an example that prints its result")]

use std::collections::BTreeMap;

use faceanim_track::{FaceModels, Frame};
use serde_json::{Value, json};

fn main() -> Result<(), String> {
    let models = FaceModels::load().map_err(|e| e.to_string())?;
    let mut out = BTreeMap::new();
    for path in std::env::args().skip(1) {
        let bytes = std::fs::read(&path).map_err(|e| format!("{path}: {e}"))?;
        let faceanim_media::Image { width, height, rgb } =
            faceanim_media::decode_image(std::path::Path::new(&path), &bytes)
                .map_err(|e| e.to_string())?;
        let face = models
            .find_face(&Frame {
                width,
                height,
                rgb: &rgb,
            })
            .map_err(|e| format!("{path}: {e}"))?;
        let value = face.map_or(Value::Null, |face| {
            json!({
                "width": width,
                "height": height,
                "landmarks": face.landmarks,
                "scores": face.scores.iter().map(|&(n, s)| (n, s)).collect::<BTreeMap<_, _>>(),
                "region": [face.region.cx, face.region.cy, face.region.size, face.region.rotation],
            })
        });
        out.insert(path, value);
    }
    println!("{}", Value::Object(out.into_iter().collect()));
    Ok(())
}
