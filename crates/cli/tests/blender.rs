//! An export opened in real Blender (Debian's `blender` 3.4, headless): every shape key arrives
//! with its name and displacement, and the animation arrives as an action.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests panic to fail, and compare exact zeros (a zero delta means: does not move)"
)]

mod support;

use faceanim_testdata::shared;
use serde_json::Value;
use support::{blender_report, faceanim_ok, output_dir};

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
