//! The built-in default head from the command line: export, info, contact sheet.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

mod support;

use serde_json::Value;
use support::{assert_valid_gltf, faceanim, faceanim_ok, output_dir};

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
        String::from_utf8_lossy(&out.stderr)
            .contains("'wiggleEars' is not a blendshape of faceanim-default")
    );
}
