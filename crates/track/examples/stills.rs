//! The whole per-frame pipeline (detector, region, landmarks, scores) on still PNGs, as JSON:
//! `{path: {width, height, landmarks: [[x, y, z]…] (image pixels), scores: {name: score},
//! region}}`, `null` where no face was found: for looking into a difference from MediaPipe's
//! own runtime on some pictures (`tools/record_mediapipe_stills.py` records what it finds;
//! `tests/mediapipe_stills.rs` compares).
//!
//! `cargo run --release -p faceanim-track --example stills -- A.png B.png …`
#![allow(clippy::print_stdout, reason = "an example that prints its result")]

use std::collections::BTreeMap;

use faceanim_track::{FaceModels, Frame};
use serde_json::{Value, json};

fn decode(path: &str) -> Result<(usize, usize, Vec<u8>), String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{path}: {e}"))?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| format!("{path}: {e}"))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{path}: too large"))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{path}: {e}"))?;
    let channels = info.color_type.samples();
    if info.bit_depth != png::BitDepth::Eight || channels < 3 {
        return Err(format!("{path}: only 8-bit RGB or RGBA PNGs"));
    }
    let rgb = buf
        .chunks(channels)
        .take((info.width * info.height) as usize)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok((info.width as usize, info.height as usize, rgb))
}

fn main() -> Result<(), String> {
    let models = FaceModels::load().map_err(|e| e.to_string())?;
    let mut out = BTreeMap::new();
    for path in std::env::args().skip(1) {
        let (width, height, rgb) = decode(&path)?;
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
