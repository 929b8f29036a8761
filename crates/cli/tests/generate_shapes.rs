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

/// The bare avatar copied into `out` as `bare.glb`, and its bytes (to check it is never
/// written).
fn bare_avatar(out: &Path) -> (std::path::PathBuf, Vec<u8>) {
    let bare = out.join("bare.glb");
    std::fs::copy(
        faceanim_testdata::producers::blender_bare_avatar_path(),
        &bare,
    )
    .unwrap();
    let bytes = std::fs::read(&bare).unwrap();
    (bare, bytes)
}

/// `faceanim generate-shapes INPUT -o OUTPUT --json`: its report, every ARKit shape made, the
/// file valid.
fn generate(input: &Path, output: &Path) -> Value {
    let report = faceanim_ok(&[
        "generate-shapes",
        input.to_str().unwrap(),
        "-o",
        output.to_str().unwrap(),
        "--json",
    ]);
    eprintln!("{report}");
    let report: Value = serde_json::from_str(report.trim()).unwrap();
    let made = support::strings(&report["shapes"]);
    for name in faceanim_rig::names::ARKIT_52 {
        assert!(
            made.iter().any(|m| m == name),
            "{name} was not made: {made:?}"
        );
    }
    assert_valid_gltf(output);
    report
}

#[test]
fn a_bare_avatar_gets_the_52_shapes_and_keeps_everything() {
    let out = output_dir("generate-shapes");
    let (bare, before) = bare_avatar(&out);
    assert_eq!(info(&bare)["blendshapes"].as_array().unwrap().len(), 0);
    // Reading it says what moves it already, and what gives its face shapes.
    let read = faceanim(&["info", bare.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&read.stderr);
    assert!(
        said.contains("turn its head, eye and jaw bones") && said.contains("generate-shapes"),
        "{said}"
    );

    let rigged = out.join("rigged.glb");
    generate(&bare, &rigged);
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
    faceanim_testdata::glb::assert_kept(&was, &now, "the rigged avatar");

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
    let again = out.join("again.glb");
    let x = out.join("x.glb");
    for (input, output, more, says) in [
        (&rigged, &again, &[][..], "already has every shape"),
        (&bare, &bare, &[][..], "replace the input"),
        (
            &bare,
            &x,
            &["--only", "eyeBlinkLeft,blinkish"][..],
            "blinkish",
        ),
    ] {
        let mut args = vec![
            "generate-shapes",
            input.to_str().unwrap(),
            "-o",
            output.to_str().unwrap(),
        ];
        args.extend(more);
        let run = faceanim(&args);
        assert!(!run.status.success());
        assert!(
            String::from_utf8_lossy(&run.stderr).contains(says),
            "{run:?}"
        );
    }
}

/// The studio on a body with no shapes: a capture moves its bones (its jaw opens with the
/// face's), and Generate blendshapes gives it the 52.
#[test]
fn the_studio_captures_onto_and_generates_shapes_for_a_character_without_any() {
    let out = output_dir("generate-shapes-studio");
    let (bare, before) = bare_avatar(&out);
    let studio = start_on(Some(&bare), &out.join("bare.faceanim.json"), &[]);
    let character = |port| -> Value {
        serde_json::from_str(&request(port, "GET", "/api/character", &[], b"").1).unwrap()
    };
    let shown = character(studio.port);
    assert_eq!(shown["blendshapes"].as_array().unwrap().len(), 0);
    assert!(shown.get("generated").is_none());

    // A face opening its mouth, captured: the take turns the view's jaw bone (the skeleton's
    // last joint) as the jaw opens; it was refused ("no ARKit-named blendshapes").
    let video = out.join("jaw.mp4");
    let jaw: Vec<f32> = (0..12).map(|i| i as f32 / 11.0).collect();
    support::encode_h264(&video, 256, 24, &support::ict_jaw_frames(&jaw, 256));
    let state = support::open_and_settle(studio.port, &video);
    let take = &state["take"];
    assert_eq!(take["frames"], 12, "{}", state["job"]);
    let bones = take["bones"].as_array().unwrap();
    assert_eq!(bones.len(), 12, "{take}");
    let jaw_turn = |frame: &Value| {
        let joints = frame.as_array().unwrap();
        let q = glam::Quat::from_slice(&support::f32s(joints.last().unwrap()));
        q.angle_between(glam::Quat::IDENTITY).to_degrees()
    };
    let (shut, open) = (jaw_turn(&bones[0]), jaw_turn(&bones[11]));
    assert!(
        open > shut + 3.0,
        "the jaw turned {shut}° shut and {open}° open"
    );
    // A clip JSON of ARKit names opens as a take of the same bones (it was refused: "none of
    // the clip's blendshapes exist").
    let (status, body) = support::upload(
        studio.port,
        "jaw.json",
        br#"{"fps": 30, "blendshapes": ["jawOpen"], "frames": [[0.0], [1.0]]}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state: Value = serde_json::from_str(&body).unwrap();
    let bones = state["take"]["bones"].as_array().unwrap();
    let (shut, open) = (jaw_turn(&bones[0]), jaw_turn(&bones[1]));
    assert!(
        shut < 0.01 && open > 10.0,
        "the jaw turned {shut}° and {open}°"
    );

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

#[test]
fn a_scanned_head_as_one_obj_gets_the_shapes() {
    // A head as a scanner or a sculpting tool hands it over: one OBJ, no blendshapes, no
    // materials, written by Blender's own OBJ exporter (ICT-FaceKit identity 7, which no
    // template is made from).
    let out = output_dir("generate-shapes-obj");
    let scan = out.join("scan.obj");
    let made = std::process::Command::new("blender")
        .args(["-b", "--factory-startup", "--python"])
        .arg(support::repo().join("tools/blender_bare.py"))
        .arg("--")
        .arg(faceanim_testdata::shared("characters/ict-face-id7.glb"))
        .arg(&scan)
        .output()
        .expect("Blender is needed for this test: run scripts/setup.sh");
    support::succeeded("blender_bare.py", made);
    let rigged = out.join("scan.glb");
    generate(&scan, &rigged);
    assert_eq!(
        info(&rigged)["undriven_channels"].as_array().unwrap().len(),
        0
    );
    // The same scan with one face in fifty lost (a damaged export, a scan with gaps): the
    // holes would show the background through the face and hide it from the face model; the
    // render closes them, and the shapes are made on the triangles that are there.
    let text = std::fs::read_to_string(&scan).unwrap();
    let mut faces = 0;
    let holed: Vec<&str> = text
        .lines()
        .filter(|line| {
            if !line.starts_with("f ") {
                return true;
            }
            faces += 1;
            faces % 50 != 17
        })
        .collect();
    let holed_scan = out.join("holed.obj");
    std::fs::write(&holed_scan, holed.join("\n")).unwrap();
    let rigged = out.join("holed.glb");
    generate(&holed_scan, &rigged);
    assert_eq!(
        info(&rigged)["undriven_channels"].as_array().unwrap().len(),
        0
    );
}
