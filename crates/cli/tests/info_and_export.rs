//! `faceanim info` and `faceanim export` as a user runs them, with every exported file checked
//! by the Khronos glTF-Validator, and an export opened in real Blender (Debian's `blender` 3.4,
//! headless): every shape key arrives with its name and displacement, and the animation
//! arrives as an action.
#![allow(clippy::unwrap_used, reason = "tests panic to fail")]

mod support;

use std::fmt::Write as _;

use faceanim_testdata::shared;
use serde_json::Value;
use support::{
    assert_refused, assert_valid_gltf, blender_report, faceanim, faceanim_ok, output_dir,
};

#[test]
fn info_json_on_the_ict_head() {
    let ict = shared("characters/ict-face.glb");
    let report: Value =
        serde_json::from_str(&faceanim_ok(&["info", ict.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(report["vertices"], 24_591);
    assert_eq!(report["triangles"], 48_836);
    let shapes = report["blendshapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 53);
    let jaw = shapes.iter().find(|b| b["name"] == "jawOpen").unwrap();
    assert!(jaw["moved"].as_u64().unwrap() > 10_000);
    assert!(
        (0.03..0.06).contains(&jaw["max_displacement"].as_f64().unwrap()),
        "{jaw}"
    );
    let pairs = report["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 22);
    assert!(pairs.contains(&serde_json::json!(["jawLeft", "jawRight"])));
    assert_eq!(report["arkit"].as_array().unwrap().len(), 49);
    let min = report["bbox"]["min"].as_array().unwrap();
    let max = report["bbox"]["max"].as_array().unwrap();
    assert_eq!((min.len(), max.len()), (3, 3));
    assert!(max[1].as_f64().unwrap() > min[1].as_f64().unwrap());

    // The text form names the same things for people.
    let text = faceanim_ok(&["info", ict.to_str().unwrap()]);
    assert!(
        text.contains("symmetric pairs  22")
            && text
                .contains("ARKit names  49 blendshapes spell an ARKit channel; 51 of 52 channels"),
        "{text}"
    );
}

#[test]
fn bad_files_fail_with_the_file_and_the_problem() {
    let dir = output_dir("bad-files");
    let cases: [(&str, &[u8], &str); 3] = [
        (
            "notes.glb",
            b"hello, this is not a model",
            "not a glTF file",
        ),
        (
            "cut.glb",
            &std::fs::read(shared("characters/ict-face.glb")).unwrap()[..5000],
            "truncated",
        ),
        (
            "empty.gltf",
            b"{\"asset\": {\"version\": \"2.0\"}}",
            "no triangle meshes",
        ),
    ];
    for (name, bytes, problem) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = faceanim(&["info", path.to_str().unwrap()]);
        assert_refused(&out, &path, problem, name);
    }
    let missing = faceanim(&["info", "/no/such/head.glb"]);
    assert_eq!(
        String::from_utf8_lossy(&missing.stderr),
        "error: /no/such/head.glb: No such file or directory (os error 2)\n"
    );
}

#[test]
fn export_with_a_clip_passes_the_validator() {
    let dir = output_dir("export-clip");
    let ict = shared("characters/ict-face.glb");
    // A one-second clip that opens the jaw and smiles, in ARKit spelling (the rig says _L/_R).
    let mut frames = String::new();
    for f in 0..=30 {
        let w = (std::f32::consts::PI * f as f32 / 30.0).sin();
        let _ = write!(
            frames,
            "{}[{w}, {}, {}]",
            if f > 0 { "," } else { "" },
            w * 0.5,
            w * 0.5
        );
    }
    let clip = format!(
        r#"{{"fps": 30, "blendshapes": ["jawOpen", "mouthSmileLeft", "mouthSmileRight"], "frames": [{frames}]}}"#
    );
    let clip_path = dir.join("smile.json");
    std::fs::write(&clip_path, clip).unwrap();
    let out_path = dir.join("ict-smile.glb");
    support::export_with_clip(&ict, &out_path, &clip_path);
    let report = assert_valid_gltf(&out_path);
    assert_eq!(report["info"]["animationCount"], 1);
    assert_eq!(report["info"]["hasMorphTargets"], true);
    assert_eq!(report["info"]["totalVertexCount"], 24_591);

    // A clip naming nothing on the character is an error, not an empty animation.
    let stray = dir.join("stray.json");
    std::fs::write(
        &stray,
        r#"{"fps": 30, "blendshapes": ["wag_tail"], "frames": [[1.0]]}"#,
    )
    .unwrap();
    let out = faceanim(&[
        "export",
        ict.to_str().unwrap(),
        "-o",
        dir.join("x.glb").to_str().unwrap(),
        "--clip",
        stray.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("none of the clip's blendshapes exist"));
    assert!(!dir.join("x.glb").exists(), "nothing is written on failure");
}

#[test]
fn gltf_with_external_bin_on_disk() {
    // Split an export into .gltf + .bin, as many tools write it, with a space in the file name.
    let dir = output_dir("external-bin");
    let ict = shared("characters/ict-face.glb");
    let glb_path = dir.join("ict.glb");
    faceanim_ok(&[
        "export",
        ict.to_str().unwrap(),
        "-o",
        glb_path.to_str().unwrap(),
    ]);
    let glb = std::fs::read(&glb_path).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut root: Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = &glb[20 + json_len + 8..];
    root["buffers"][0]["uri"] = Value::from("ict%20data.bin");
    std::fs::write(dir.join("ict data.bin"), bin).unwrap();
    let gltf_path = dir.join("ict.gltf");
    std::fs::write(&gltf_path, serde_json::to_vec(&root).unwrap()).unwrap();
    assert_valid_gltf(&gltf_path);
    let report: Value = serde_json::from_str(&faceanim_ok(&[
        "info",
        gltf_path.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    assert_eq!(report["blendshapes"].as_array().unwrap().len(), 53);
    std::fs::remove_file(dir.join("ict data.bin")).unwrap();
    let out = faceanim(&["info", gltf_path.to_str().unwrap()]);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("buffer 0 ('ict%20data.bin') is missing"),
        "{:?}",
        out
    );
}

#[test]
fn an_obj_folder_like_ict_facekit_imports_and_exports() {
    // Write the ICT head the way ICT-FaceKit ships it: neutral.obj plus one OBJ per expression.
    let dir = output_dir("obj-folder").join("ict-obj");
    std::fs::create_dir_all(&dir).unwrap();
    let ict = faceanim_testdata::ict();
    let write_obj = |name: &str, positions: &[faceanim_rig::glam::Vec3], faces: bool| {
        let mut text = String::with_capacity(positions.len() * 40);
        for p in positions {
            let _ = writeln!(text, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
        }
        if faces {
            for t in ict.triangles() {
                let _ = writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
            }
        }
        std::fs::write(dir.join(name), text).unwrap();
    };
    write_obj("neutral.obj", ict.positions(), true);
    let mut dense = vec![faceanim_rig::glam::Vec3::ZERO; ict.vertex_count()];
    for shape in ict.blendshapes() {
        shape.write_dense(&mut dense);
        let moved: Vec<faceanim_rig::glam::Vec3> = ict
            .positions()
            .iter()
            .zip(&dense)
            .map(|(p, d)| *p + *d)
            .collect();
        write_obj(&format!("{}.obj", shape.name()), &moved, false);
    }
    let report: Value =
        serde_json::from_str(&faceanim_ok(&["info", dir.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(report["vertices"], 24_591);
    assert_eq!(report["blendshapes"].as_array().unwrap().len(), 53);
    assert_eq!(report["pairs"].as_array().unwrap().len(), 22);
    let glb = dir.parent().unwrap().join("from-obj.glb");
    faceanim_ok(&["export", dir.to_str().unwrap(), "-o", glb.to_str().unwrap()]);
    assert_valid_gltf(&glb);
}

#[test]
fn blender_opens_an_animated_export_with_all_shape_keys() {
    let dir = output_dir("blender");
    let ict = shared("characters/ict-face.glb");
    let clip = dir.join("blink.json");
    std::fs::write(&clip, r#"{"fps": 24, "blendshapes": ["eyeBlinkLeft", "eyeBlinkRight"], "frames": [[0,0],[1,1],[0,0]]}"#).unwrap();
    let glb = dir.join("ict-blink.glb");
    support::export_with_clip(&ict, &glb, &clip);

    let report = blender_report(&glb);
    assert!(
        report["blender"].as_str().unwrap().starts_with("3."),
        "{}",
        report["blender"]
    );
    let objects = report["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 1);
    assert_eq!(objects[0]["vertices"], 24_591);
    assert_eq!(objects[0]["polygons"], 48_836);

    let ours: Value =
        serde_json::from_str(&faceanim_ok(&["info", ict.to_str().unwrap(), "--json"])).unwrap();
    let keys = objects[0]["shape_keys"].as_array().unwrap();
    let shapes = ours["blendshapes"].as_array().unwrap();
    assert_eq!(keys.len(), shapes.len());
    for (key, shape) in keys.iter().zip(shapes) {
        assert_eq!(key["name"], shape["name"]);
        let (theirs, mine) = (
            key["max_displacement"].as_f64().unwrap(),
            shape["max_displacement"].as_f64().unwrap(),
        );
        assert!(
            (theirs - mine).abs() < 1e-6,
            "{}: Blender {theirs} vs faceanim {mine}",
            shape["name"]
        );
    }
    let actions = report["actions"].as_array().unwrap();
    assert_eq!(actions.len(), 1, "{actions:?}");
    assert_eq!(actions[0]["fcurves"], 53, "one curve per shape key");
}
