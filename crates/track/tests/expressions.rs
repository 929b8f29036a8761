//! From picture to expression: the shared renders of the ICT head, cropped around the face,
//! through the landmark and blendshape models, give the expression they show. Thresholds are the
//! capture issue's; MediaPipe's own runtime reads jawOpen 0.74, smiles 0.85/0.87, blinks
//! 0.71/0.74 and under 0.1 on the neutral render.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

use std::collections::HashMap;

use faceanim_track::FaceModels;

/// The render's middle 72% (where the face is), resized to 256×256 (nearest), values in [0, 1].
fn face_crop(name: &str) -> Vec<f32> {
    let path = faceanim_testdata::shared(&format!("images/{name}"));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    let (x0, x1, y0, y1) = (
        (0.14 * w as f32) as usize,
        (0.86 * w as f32) as usize,
        (0.14 * h as f32) as usize,
        (0.86 * h as f32) as usize,
    );
    let mut out = Vec::with_capacity(256 * 256 * 3);
    for j in 0..256 {
        for i in 0..256 {
            let (x, y) = (x0 + i * (x1 - x0) / 256, y0 + j * (y1 - y0) / 256);
            let p = (y * w + x) * channels;
            out.extend(buf[p..p + 3].iter().map(|&b| f32::from(b) / 255.0));
        }
    }
    out
}

fn expression(models: &FaceModels, image: &str) -> HashMap<&'static str, f32> {
    let landmarks = models.landmarks(&face_crop(image)).unwrap();
    assert!(
        landmarks.presence > 0.9,
        "{image}: face presence {}",
        landmarks.presence
    );
    models
        .expression(&landmarks.points)
        .unwrap()
        .into_iter()
        .collect()
}

#[test]
fn renders_of_the_ict_head_read_as_their_expressions() {
    let models = FaceModels::load().unwrap();
    let neutral = expression(&models, "ict-face-neutral.png");
    let open = expression(&models, "ict-face-jawopen.png");
    let smile = expression(&models, "ict-face-smile.png");
    let blink = expression(&models, "ict-face-blink.png");
    eprintln!(
        "neutral jaw {:.2} smile {:.2}/{:.2} blink {:.2}/{:.2}; jawOpen {:.2}; smile {:.2}/{:.2}; blink {:.2}/{:.2}",
        neutral["jawOpen"],
        neutral["mouthSmileLeft"],
        neutral["mouthSmileRight"],
        neutral["eyeBlinkLeft"],
        neutral["eyeBlinkRight"],
        open["jawOpen"],
        smile["mouthSmileLeft"],
        smile["mouthSmileRight"],
        blink["eyeBlinkLeft"],
        blink["eyeBlinkRight"]
    );
    assert!(open["jawOpen"] > 0.5);
    assert!(smile["mouthSmileLeft"] > 0.4 && smile["mouthSmileRight"] > 0.4);
    assert!(blink["eyeBlinkLeft"] > 0.4 && blink["eyeBlinkRight"] > 0.4);
    for name in [
        "jawOpen",
        "mouthSmileLeft",
        "mouthSmileRight",
        "eyeBlinkLeft",
        "eyeBlinkRight",
    ] {
        assert!(neutral[name] < 0.15, "neutral {name} = {}", neutral[name]);
    }
}
