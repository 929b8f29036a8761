//! Time spent per operator type in a face model (tract), to find what to optimise:
//! `cargo run --release -p faceanim-track --example op_profile [landmarks|blendshapes|detector]`;
//! with `BY_NODE=1` each node apart, with its shape and tract's choice of kernel.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use std::collections::HashMap;
use std::io::Read as _;
use std::time::Instant;
use tract_tflite::internal::*;
use tract_tflite::prelude::tract_ndarray::Dimension as _;

fn main() {
    let bundle = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/face_landmarker.task"
    ))
    .unwrap();
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bundle)).unwrap();
    let mut bytes = Vec::new();
    let which = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "landmarks".into());
    let (file, shape): (&str, &[usize]) = match which.as_str() {
        "blendshapes" => ("face_blendshapes.tflite", &[1, 146, 2]),
        "detector" => ("face_detector.tflite", &[1, 128, 128, 3]),
        _ => ("face_landmarks_detector.tflite", &[1, 256, 256, 3]),
    };
    archive
        .by_name(file)
        .unwrap()
        .read_to_end(&mut bytes)
        .unwrap();
    let model = tract_tflite::tflite()
        .model_for_read(&mut std::io::Cursor::new(bytes))
        .unwrap()
        .into_optimized()
        .unwrap();
    let plan = model.into_runnable().unwrap();
    let input: Tensor = tract_ndarray::ArrayD::<f32>::from_shape_fn(shape, |index| {
        (index.slice().iter().sum::<usize>() % 251) as f32 / 251.0 * 100.0
    })
    .into();
    let by_node = std::env::var_os("BY_NODE").is_some();
    let mut state = SimpleState::new(&plan).unwrap();
    let mut times: HashMap<String, (f64, usize)> = HashMap::new();
    for round in 0..30 {
        state
            .run_plan_with_eval(tvec!(input.clone().into()), |ctx, st, node, inputs| {
                let t = Instant::now();
                let r = tract_core::plan::eval(ctx, st, node, inputs);
                if round >= 10 {
                    let key = if by_node {
                        format!(
                            "{} {:?} {}",
                            node.op().name(),
                            node.outputs[0].fact.shape,
                            node.op().info().unwrap_or_default().join(" ")
                        )
                    } else {
                        node.op().name().to_string()
                    };
                    let e = times.entry(key).or_default();
                    e.0 += t.elapsed().as_secs_f64() * 1000.0 / 20.0;
                    e.1 += 1;
                }
                r
            })
            .unwrap();
    }
    let mut v: Vec<_> = times.into_iter().collect();
    v.sort_by(|a, b| b.1.0.total_cmp(&a.1.0));
    let total: f64 = v.iter().map(|x| x.1.0).sum();
    println!("total {total:.2} ms");
    for (k, (ms, n)) in v {
        println!("{k:40} {ms:7.2} ms  x{}", n / 20);
    }
}
