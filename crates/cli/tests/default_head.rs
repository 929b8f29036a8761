//! The built-in default head from the command line: export, info, contact sheet.
mod support;

use serde_json::Value;
use support::{assert_valid_gltf, faceanim, faceanim_ok, output_dir, three_js_stills};

#[test]
fn export_default_is_valid_and_deterministic() {
    let dir = output_dir("default-head");
    let (a, b) = (dir.join("a.glb"), dir.join("b.glb"));
    faceanim_ok(&["export-default", "-o", a.to_str().unwrap()]);
    faceanim_ok(&["export-default", "-o", b.to_str().unwrap()]);
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "same bytes twice"
    );
    let report = assert_valid_gltf(&a);
    assert_eq!(
        report["issues"]["numWarnings"], 0,
        "{:#}",
        report["issues"]["messages"]
    );
    // The file imports like any user character.
    let info: Value =
        serde_json::from_str(&faceanim_ok(&["info", a.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(info["arkit"].as_array().unwrap().len(), 52);
    assert_eq!(info["pairs"].as_array().unwrap().len(), 20);
}

#[test]
fn info_without_a_character_describes_the_default_head() {
    let info: Value = serde_json::from_str(&faceanim_ok(&["info", "--json"])).unwrap();
    assert!(info["vertices"].as_u64().unwrap() >= 5000);
    assert_eq!(info["blendshapes"].as_array().unwrap().len(), 52);
    assert_eq!(info["arkit"].as_array().unwrap().len(), 52);
    assert_eq!(info["pairs"].as_array().unwrap().len(), 20);
}

#[test]
fn render_writes_a_contact_sheet_and_single_poses() {
    let dir = output_dir("default-head");
    let sheet = dir.join("contact-sheet.png");
    faceanim_ok(&[
        "render",
        "--sheet",
        "--size",
        "128",
        "-o",
        sheet.to_str().unwrap(),
    ]);
    let bytes = std::fs::read(&sheet).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // 53 cells (neutral + 52) in an 8-column grid of 128-pixel cells with 20-pixel labels.
    let (width, height) = (
        u32::from_be_bytes(bytes[16..20].try_into().unwrap()),
        u32::from_be_bytes(bytes[20..24].try_into().unwrap()),
    );
    assert_eq!((width, height), (8 * 128, 7 * (128 + 20)));

    let smile = dir.join("smile.png");
    faceanim_ok(&[
        "render",
        "--weights",
        "mouthSmile_L=1,mouthSmileRight=1,jawOpen=0.3",
        "--size",
        "256",
        "-o",
        smile.to_str().unwrap(),
    ]);
    assert!(std::fs::metadata(&smile).unwrap().len() > 1000);
    let neutral = dir.join("neutral.png");
    faceanim_ok(&["render", "--size", "256", "-o", neutral.to_str().unwrap()]);
    assert!(
        std::fs::read(&smile).unwrap() != std::fs::read(&neutral).unwrap(),
        "weights change the picture"
    );

    let out = faceanim(&[
        "render",
        "--weights",
        "wiggleEars=1",
        "-o",
        dir.join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains(
            "'wiggleEars' is neither a blendshape of faceanim-default nor an ARKit channel"
        )
    );

    // A name that is no PNG's is refused before anything is drawn, and nothing is written.
    let jpeg = dir.join("x.jpg");
    let out = faceanim(&["render", "-o", jpeg.to_str().unwrap()]);
    support::assert_refused(&out, &jpeg, "name it .png", "a .jpg");
    assert!(!jpeg.exists());

    // An ARKit channel that a head has as two halves (ICT's browInnerUp_L and _R) poses both,
    // as `info` says it drives them.
    let ict = faceanim_testdata::shared("characters/ict-face.glb");
    let render = |weights: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args = vec!["render", ict.to_str().unwrap(), "--size", "128"];
        args.extend(weights);
        args.extend(["-o", out.to_str().unwrap()]);
        faceanim_ok(&args);
        std::fs::read(out).unwrap()
    };
    let by_channel = render(&["--weights", "browInnerUp=1"], "brows-channel.png");
    let by_halves = render(
        &["--weights", "browInnerUp_L=1,browInnerUp_R=1"],
        "brows-halves.png",
    );
    assert_eq!(by_channel, by_halves);
    assert_ne!(by_channel, render(&[], "ict-neutral.png"));
}

/// The face model reads the built-in head's shapes when another renderer draws them (issue 17,
/// item 6): three.js in Chromium (`tools/heldout-stills.mjs`, its own lens, lights and PBR
/// materials, a face about 100 px across) renders the neutral head and each of the 51 shapes
/// MediaPipe names at weight 1, front on; `faceanim track` reads every still on its own (the
/// detector each time, no filter); a shape counts when its own score rises by at least 0.15 over
/// the neutral still's. Measured 21 of 51 (the head before this issue: 15; the realistic ICT
/// head: 17 of 49); a newer Chromium may draw a few pixels differently, hence 19.
#[test]
fn the_face_model_reads_the_default_heads_shapes_in_another_renderer() {
    let dir = output_dir("default-head-legible");
    let model = dir.join("head.glb");
    faceanim_ok(&["export-default", "-o", model.to_str().unwrap()]);
    let names: Vec<&str> = faceanim_track::BLENDSHAPE_NAMES[1..].to_vec();
    let mut frames = vec![serde_json::json!({ "image": "00-neutral.png", "weights": {} })];
    for (k, name) in names.iter().enumerate() {
        frames.push(serde_json::json!({
            "image": format!("{:02}-{name}.png", k + 1),
            "weights": { *name: 1.0 },
        }));
    }
    let stills = dir.join("stills");
    three_js_stills(
        &model,
        &serde_json::json!({ "frames": frames, "view": { "yaw": 0, "pitch": 0 } }),
        &stills,
    );

    let raw = dir.join("raw.json");
    faceanim_ok(&[
        "track",
        stills.to_str().unwrap(),
        "--detect-every-frame",
        "--filter",
        "none",
        "--raw",
        raw.to_str().unwrap(),
        "-o",
        dir.join("clip.json").to_str().unwrap(),
    ]);
    let raw: Value = serde_json::from_slice(&std::fs::read(&raw).unwrap()).unwrap();
    let read = |frame: usize, name: &str| -> f64 {
        let scores = raw["frames"][frame]["scores"]
            .as_array()
            .unwrap_or_else(|| panic!("still {frame}: no face"));
        scores
            .iter()
            .find(|pair| pair[0] == name)
            .and_then(|pair| pair[1].as_f64())
            .unwrap()
    };
    assert_eq!(raw["frames"].as_array().unwrap().len(), 52);
    let mut report = Vec::new();
    let mut legible = 0;
    for (k, name) in names.iter().enumerate() {
        let rise = read(k + 1, name) - read(0, name);
        report.push(format!("{name} {rise:+.2}"));
        legible += usize::from(rise >= 0.15);
    }
    eprintln!("{legible} of 51 legible: {}", report.join(", "));
    assert!(legible >= 19, "only {legible} of 51: {}", report.join(", "));
}
