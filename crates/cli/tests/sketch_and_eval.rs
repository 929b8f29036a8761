//! `faceanim sketch` and `faceanim eval` as a user runs them.
#![allow(clippy::unwrap_used, reason = "tests panic to fail")]

mod support;

use faceanim_rig::glam::Vec3;
use faceanim_testdata::shared;
use serde_json::{Value, json};
use support::{assert_refused, assert_valid_gltf, column, faceanim, faceanim_ok, output_dir};

/// A stroke from the vertex a blendshape moves most to where it moves it, bowed, at 90 Hz.
fn stroke_for(character: &faceanim_rig::Character, shape: &str, seconds: f32, bow: f32) -> Value {
    let id = character.find_blendshape(shape).unwrap();
    let b = character.blendshape(id).unwrap();
    let k = (0..b.moved())
        .max_by(|&x, &y| b.deltas()[x].length().total_cmp(&b.deltas()[y].length()))
        .unwrap();
    let v = b.indices()[k];
    let start = character.positions()[v as usize];
    let end = start + b.deltas()[k];
    let side = (end - start).cross(Vec3::Z).normalize_or_zero() * bow;
    let n = (seconds * 90.0) as usize;
    let samples: Vec<Value> = (0..=n)
        .map(|i| {
            let s = i as f32 / n as f32;
            let p = start.lerp(end, s) + side * 4.0 * s * (1.0 - s);
            json!({"t": i as f32 / 90.0, "p": [p.x, p.y, p.z]})
        })
        .collect();
    json!({ "samples": samples })
}

/// `faceanim eval A B --json`'s answer.
fn eval_json(a: &std::path::Path, b: &std::path::Path) -> Value {
    serde_json::from_str(&faceanim_ok(&[
        "eval",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
    ]))
    .unwrap()
}

/// A strokes file for the ICT head in `dir`: a smile (mirrored), a jaw, and a stroke two metres
/// from the face.
fn smile_and_jaw(dir: &std::path::Path) -> std::path::PathBuf {
    let ict = faceanim_testdata::ict();
    let strokes = json!({
        "version": 1, "fps": 30,
        "settings": {"symmetry": true, "falloff": "smooth"},
        "strokes": [
            stroke_for(ict, "mouthSmile_L", 0.6, 0.004),
            stroke_for(ict, "jawOpen", 0.8, 0.01),
            {"samples": [{"t": 0.0, "p": [0.0, 0.0, 2.0]}, {"t": 0.1, "p": [0.0, 0.1, 2.0]}]}
        ]
    });
    let strokes_path = dir.join("take.strokes.json");
    std::fs::write(&strokes_path, serde_json::to_vec_pretty(&strokes).unwrap()).unwrap();
    strokes_path
}

#[test]
fn sketch_writes_a_valid_animated_glb_and_a_clip() {
    let dir = output_dir("sketch-cli");
    let ict_path = shared("characters/ict-face.glb");
    let strokes_path = smile_and_jaw(&dir);
    let glb = dir.join("take.glb");
    let clip = dir.join("take.json");
    let out = faceanim(&[
        "sketch",
        ict_path.to_str().unwrap(),
        strokes_path.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
        "--clip",
        clip.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The stroke two metres from the face is skipped with a warning that names it.
    assert!(
        stderr.contains("strokes[2]: skipped, it starts"),
        "{stderr}"
    );
    assert!(stderr.contains("2 actions"), "{stderr}");

    let report = assert_valid_gltf(&glb);
    assert_eq!(report["info"]["animationCount"], 1);
    let baked: Value = serde_json::from_slice(&std::fs::read(&clip).unwrap()).unwrap();
    assert_eq!(baked["fps"], 30.0);
    assert_eq!(baked["blendshapes"].as_array().unwrap().len(), 53);
    let frames = baked["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 25, "0.8 s at 30 fps: frames 0..=24");
    let (smile_l, smile_r) = (
        column(&baked, "mouthSmile_L"),
        column(&baked, "mouthSmile_R"),
    );
    assert!(
        smile_l[24] > 0.9 && smile_r[24] > 0.9,
        "symmetry mirrored the smile"
    );

    // eval: a clip against itself, and against a delayed copy.
    let same: Value = eval_json(&clip, &clip);
    assert_eq!(
        same,
        json!({"dtw": 0.0, "dtw_per_frame": 0.0, "jitter_a": same["jitter_a"], "jitter_b": same["jitter_a"], "jitter_diff": 0.0, "mae": 0.0})
    );
    let mut delayed = baked.clone();
    let rows = delayed["frames"].as_array_mut().unwrap();
    let first = rows[0].clone();
    for _ in 0..10 {
        rows.insert(0, first.clone());
    }
    let delayed_path = dir.join("delayed.json");
    std::fs::write(&delayed_path, serde_json::to_vec(&delayed).unwrap()).unwrap();
    let shifted: Value = eval_json(&delayed_path, &clip);
    assert_eq!(shifted["mae"], Value::Null, "different frame counts");
    assert!(
        shifted["dtw"].as_f64().unwrap() < 1e-6,
        "DTW absorbs a pure delay: {shifted}"
    );
    assert!(shifted["jitter_a"].as_f64().unwrap() < same["jitter_a"].as_f64().unwrap());
}

#[test]
fn a_sketch_goes_out_in_the_format_its_name_asks_for() {
    let dir = output_dir("sketch-formats");
    let ict_path = shared("characters/ict-face.glb");
    let strokes = smile_and_jaw(&dir);
    let sketch_and = |out: &std::path::Path, more: &[&str]| {
        let mut args = vec![
            "sketch",
            ict_path.to_str().unwrap(),
            strokes.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(more);
        faceanim(&args)
    };
    let sketch = |out: &std::path::Path| sketch_and(out, &[]);
    // The clip: what `--clip` writes beside the GLB.
    let (glb, beside, alone) = (
        dir.join("take.glb"),
        dir.join("beside.json"),
        dir.join("alone.json"),
    );
    let out = sketch_and(&glb, &["--clip", beside.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = sketch(&alone);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let read = |p: &std::path::Path| -> Value {
        serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
    };
    assert_eq!(read(&alone)["frames"], read(&beside)["frames"]);
    assert_eq!(read(&alone)["blendshapes"], read(&beside)["blendshapes"]);
    assert!(
        !stderr.contains("extra targets for"),
        "a clip has no extra targets: {stderr}"
    );

    // Live Link Face: the smile's curve rises on both sides (symmetry), the jaw's too.
    let csv = dir.join("take.csv");
    let out = sketch(&csv);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The bowed strokes' arcs are extra targets, which only a GLB carries: said, not dropped.
    assert!(stderr.contains("are only in a .glb"), "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f32>> = lines
        .map(|l| l.split(',').skip(2).map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 25, "{text}");
    for curve in ["MouthSmileLeft", "MouthSmileRight", "JawOpen"] {
        let at = header.iter().position(|h| *h == curve).unwrap() - 2;
        let peak = rows.iter().map(|r| r[at]).fold(0.0, f32::max);
        assert!(peak > 0.5, "{curve} peaks at {peak}");
        assert!(rows[0][at] < 0.05, "{curve} starts at {}", rows[0][at]);
    }

    // What cannot be written is refused before anything is, naming the file.
    for (name, expected) in [
        ("take.vrma", "is no VRM avatar"),
        ("take.gltf", "name it .glb"),
        ("take.txt", "the name must end in"),
        ("take.byoc.csv", "needs a capture's session"),
    ] {
        let path = dir.join(name);
        let out = sketch(&path);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(name) && stderr.contains(expected),
            "{name}: {stderr}"
        );
        assert!(!path.exists(), "{name} was written");
    }
    // A head that is no VRM written under a VRM's name is written, with a warning.
    let vrm = dir.join("take.vrm");
    let out = sketch(&vrm);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("is no VRM avatar"), "{stderr}");
    assert_valid_gltf(&vrm);
    let out = faceanim(&[
        "export-default",
        "-o",
        dir.join("head.json").to_str().unwrap(),
    ]);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("writes the built-in head as a .glb"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.join("head.json").exists());
}

#[test]
fn malformed_strokes_files_name_the_file_and_field() {
    let dir = output_dir("sketch-bad");
    let ict_path = shared("characters/ict-face.glb");
    let cases = [
        (
            "unknown.json",
            r#"{"version": 1, "strokes": [{"samples": [], "pressure": 1}]}"#,
            "unknown field `pressure`",
        ),
        (
            "backwards.json",
            r#"{"version": 1, "strokes": [{"samples": [{"t": 0.5, "p": [0,0,0]}, {"t": 0.1, "p": [0,0,0]}]}]}"#,
            "strokes[0].samples[1].t: time must increase",
        ),
        (
            "version.json",
            r#"{"version": 7, "strokes": []}"#,
            "version: faceanim reads version 1, found 7",
        ),
        ("notjson.json", "strokes: yes", "not a strokes file"),
    ];
    for (name, text, expected) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = faceanim(&[
            "sketch",
            ict_path.to_str().unwrap(),
            path.to_str().unwrap(),
            "-o",
            dir.join("x.glb").to_str().unwrap(),
        ]);
        assert_refused(&out, &path, expected, name);
    }
    assert!(!dir.join("x.glb").exists());
}
