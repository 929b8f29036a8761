//! `faceanim generate-shapes` on a full-body avatar whose face was never rigged: the Blender
//! avatar (an ICT-FaceKit head on a skinned body, many primitives and materials, two skins)
//! exported by Blender's own glTF exporter without any shape keys. The file written must
//! validate, keep everything the avatar had, carry the 52 ARKit shapes where Blender and
//! faceanim read them, and the avatar's own file must be untouched.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use serde_json::Value;
use std::path::Path;
use support::{
    assert_valid_gltf, blender_report, faceanim, faceanim_ok, output_dir, request, start_on,
};

fn info(file: &Path) -> Value {
    serde_json::from_str(&faceanim_ok(&["info", file.to_str().unwrap(), "--json"])).unwrap()
}

fn count(doc: &Value, key: &str) -> usize {
    doc[key].as_array().map_or(0, Vec::len)
}

#[test]
fn a_bare_avatar_gets_the_52_shapes_and_keeps_everything() {
    let out = output_dir("generate-shapes");
    let bare = out.join("bare.glb");
    std::fs::copy(
        faceanim_testdata::producers::blender_bare_avatar_path(),
        &bare,
    )
    .unwrap();
    let before = std::fs::read(&bare).unwrap();
    assert_eq!(info(&bare)["blendshapes"].as_array().unwrap().len(), 0);

    let rigged = out.join("rigged.glb");
    let report: Value = serde_json::from_str(
        faceanim_ok(&[
            "generate-shapes",
            bare.to_str().unwrap(),
            "-o",
            rigged.to_str().unwrap(),
            "--json",
        ])
        .trim(),
    )
    .unwrap();
    eprintln!("{report:#}");
    let made: Vec<&str> = report["shapes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    for name in faceanim_rig::names::ARKIT_52 {
        assert!(made.contains(&name), "{name} was not made: {made:?}");
    }
    assert_eq!(
        std::fs::read(&bare).unwrap(),
        before,
        "the input file changed"
    );

    // The file validates, and faceanim reads every shape back as the channel it is.
    assert_valid_gltf(&rigged);
    let read = info(&rigged);
    assert_eq!(
        read["undriven_channels"].as_array().unwrap().len(),
        0,
        "{}",
        read["undriven_channels"]
    );

    // The file says which shapes were generated, and faceanim says so.
    let generated = &read["file"]["generated"];
    assert_eq!(
        generated["shapes"].as_array().unwrap().len(),
        52,
        "{generated}"
    );
    assert!(
        generated["template"]
            .as_str()
            .unwrap()
            .contains("ict-facekit"),
        "{generated}"
    );
    let text = faceanim_ok(&["info", rigged.to_str().unwrap()]);
    assert!(
        text.contains("52 blendshapes made by faceanim generate-shapes"),
        "{text}"
    );

    // Everything the avatar had is still there.
    let (was, _) = faceanim_testdata::glb::parts(&before);
    let (now, _) = faceanim_testdata::glb::parts(&std::fs::read(&rigged).unwrap());
    for key in [
        "nodes",
        "meshes",
        "skins",
        "materials",
        "textures",
        "images",
        "samplers",
        "scenes",
    ] {
        assert_eq!(count(&was, key), count(&now, key), "{key}");
    }
    for (a, b) in was["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .zip(now["nodes"].as_array().unwrap())
    {
        assert_eq!(a["name"], b["name"]);
        assert_eq!(a["skin"], b["skin"]);
        assert_eq!(a["children"], b["children"]);
    }
    for (a, b) in was["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .zip(now["meshes"].as_array().unwrap())
    {
        let (pa, pb) = (
            a["primitives"].as_array().unwrap(),
            b["primitives"].as_array().unwrap(),
        );
        assert_eq!(pa.len(), pb.len());
        for (x, y) in pa.iter().zip(pb) {
            assert_eq!(x["material"], y["material"]);
            let keys = |p: &Value| {
                p["attributes"]
                    .as_object()
                    .unwrap()
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
            };
            assert_eq!(keys(x), keys(y));
        }
    }

    // Blender opens it with the shapes as shape keys on the face.
    let blender = blender_report(&rigged);
    let face = blender["objects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["shape_keys"].as_array().is_some_and(|k| k.len() >= 52))
        .unwrap_or_else(|| panic!("no mesh with the shapes in Blender: {blender:#}"));
    eprintln!(
        "Blender: {} has {} shape keys",
        face["name"],
        face["shape_keys"].as_array().unwrap().len()
    );

    // Asking again makes nothing (the head has them all), and mistakes are named.
    let again = faceanim(&[
        "generate-shapes",
        rigged.to_str().unwrap(),
        "-o",
        out.join("again.glb").to_str().unwrap(),
    ]);
    assert!(!again.status.success());
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("none of the shapes"),
        "{again:?}"
    );
    let over = faceanim(&[
        "generate-shapes",
        bare.to_str().unwrap(),
        "-o",
        bare.to_str().unwrap(),
    ]);
    assert!(
        String::from_utf8_lossy(&over.stderr).contains("replace the input"),
        "{over:?}"
    );
    let wrong = faceanim(&[
        "generate-shapes",
        bare.to_str().unwrap(),
        "-o",
        out.join("x.glb").to_str().unwrap(),
        "--only",
        "eyeBlinkLeft,blinkish",
    ]);
    assert!(
        String::from_utf8_lossy(&wrong.stderr).contains("blinkish"),
        "{wrong:?}"
    );
}

#[test]
fn the_studio_generates_shapes_for_a_character_without_any() {
    let out = output_dir("generate-shapes-studio");
    let bare = out.join("bare.glb");
    std::fs::copy(
        faceanim_testdata::producers::blender_bare_avatar_path(),
        &bare,
    )
    .unwrap();
    let before = std::fs::read(&bare).unwrap();
    let studio = start_on(Some(&bare), &out.join("bare.faceanim.json"), &[]);
    let character = |port| -> Value {
        serde_json::from_str(&request(port, "GET", "/api/character", &[], b"").1).unwrap()
    };
    let shown = character(studio.port);
    assert_eq!(shown["blendshapes"].as_array().unwrap().len(), 0);
    assert!(shown.get("generated").is_none());

    let (status, body) = request(
        studio.port,
        "POST",
        "/api/character/generate-shapes",
        &[("content-type", "application/json")],
        b"{}",
    );
    assert_eq!(status, 200, "{body}");
    let answer: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(answer["shapes"].as_array().unwrap().len(), 52);
    let written = Path::new(answer["written"].as_str().unwrap());
    assert_eq!(written, out.join("bare.shapes.glb"));
    assert_valid_gltf(written);
    assert_eq!(
        std::fs::read(&bare).unwrap(),
        before,
        "the user's file changed"
    );

    // The studio now works on the new character, and says its shapes were generated.
    let shown = character(studio.port);
    assert_eq!(shown["name"], "bare.shapes");
    assert_eq!(shown["blendshapes"].as_array().unwrap().len(), 52);
    assert_eq!(shown["generated"]["count"], 52, "{shown}");
}
