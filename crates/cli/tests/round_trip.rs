//! What faceanim writes opens again (issue 48): a take exported as a GLB into a full-body
//! avatar that Blender built and wrote (`tools/blender_avatar.py`), opened by `faceanim
//! studio` on that file, plays its frames as a take; the studio's own GLB and Live Link Face
//! CSV downloads open again as takes with the same weights; a second export replaces the
//! animation it remakes instead of piling up copies; files that are no take are named.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use faceanim_testdata::producers::blender_avatar_path;
use support::{export_with_clip, faceanim_ok, output_dir, request, request_bytes, start_on};

/// The clip's columns: ARKit names the avatar has as its own (`eyeBlink_L` is ICT's
/// spelling), and one of its VRoid-style shapes that no ARKit channel names.
const COLUMNS: [&str; 4] = ["jawOpen", "eyeBlink_L", "mouthSmile_R", "Fcl_MTH_A"];
const FRAMES: usize = 40;

fn weight(column: usize, frame: usize) -> f32 {
    let t = frame as f32 / (FRAMES - 1) as f32;
    let phase = column as f32 * 0.9;
    (0.5 + 0.45 * (std::f32::consts::TAU * t + phase).sin()).clamp(0.0, 1.0)
}

/// The open take's weights of `name` as it plays, one per frame.
fn take_column(state: &serde_json::Value, name: &str) -> Vec<f64> {
    let names = support::strings(&state["blendshapes"]);
    let at = names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no {name} in {names:?}"));
    state["take"]["weights"]
        .as_array()
        .unwrap_or_else(|| panic!("no take: {state}"))
        .iter()
        .map(|row| row[at].as_f64().unwrap())
        .collect()
}

/// The largest difference between two curves, frame by frame.
fn worst_gap(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn assert_same(state: &serde_json::Value, columns: &[&str], what: &str) {
    assert_eq!(state["take"]["frames"], FRAMES, "{what}: {}", state["take"]);
    for name in columns {
        let c = COLUMNS.iter().position(|n| n == name).unwrap();
        let written: Vec<f64> = (0..FRAMES).map(|f| f64::from(weight(c, f))).collect();
        let worst = worst_gap(&take_column(state, name), &written);
        assert!(
            worst < 1e-3,
            "{what}: {name} is {worst} away from what was written"
        );
    }
}

/// Asserts the capture state's `notice` says `words`, failing with `what` and the notice.
fn assert_notice(state: &serde_json::Value, words: &str, what: &str) {
    assert!(
        state["notice"].as_str().is_some_and(|n| n.contains(words)),
        "{what}: {}",
        state["notice"]
    );
}

#[test]
fn a_take_exported_into_the_users_avatar_opens_again_plays_and_exports_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let out = output_dir("round_trip");
    let avatar = blender_avatar_path();
    let clip = serde_json::json!({
        "fps": 30,
        "blendshapes": COLUMNS,
        "frames": (0..FRAMES).map(|f| (0..COLUMNS.len()).map(|c| weight(c, f)).collect::<Vec<_>>()).collect::<Vec<_>>(),
    });
    let clip_path = dir.path().join("take.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    let take = out.join("take.glb");
    export_with_clip(&avatar, &take, &clip_path);

    // `info` lists the animation.
    let info: serde_json::Value =
        serde_json::from_str(&faceanim_ok(&["info", take.to_str().unwrap(), "--json"])).unwrap();
    let animations = info["file"]["animations"]
        .as_array()
        .unwrap_or_else(|| panic!("{info}"));
    assert_eq!(animations.len(), 1, "{animations:?}");
    assert!(
        (animations[0]["seconds"].as_f64().unwrap() - (FRAMES - 1) as f64 / 30.0).abs() < 1e-3,
        "{animations:?}"
    );

    // The studio on the exported file opens its animation as the take.
    let project = dir.path().join("project");
    let studio = start_on(Some(&take), &project, &[]);
    let port = studio.port;
    let (status, body) = request(port, "GET", "/api/capture/state", &[], b"");
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_same(&state, &COLUMNS, "the studio on take.glb");
    assert_notice(
        &state,
        "animation",
        "the page is not told where the take came from",
    );

    // A correction (the mouth shut at frame 10), then its GLB download: it holds the take once
    // (the export replaces the animation it came from) and opens again (uploaded, as the
    // page's file picker sends it) to the corrected weights.
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/correct",
        &[],
        br#"{"frame": 10, "name": "jawOpen", "value": 0.05}"#,
    );
    assert_eq!(status, 200, "{body}");
    let corrected: serde_json::Value = serde_json::from_str(&body).unwrap();
    let corrected_jaw = take_column(&corrected, "jawOpen");
    assert!((corrected_jaw[10] - 0.05).abs() < 1e-3, "{corrected_jaw:?}");
    let (status, glb) = request_bytes(port, "GET", "/api/capture/export.glb", &[], b"");
    assert_eq!(status, 200);
    let again = out.join("again.glb");
    std::fs::write(&again, &glb).unwrap();
    support::assert_valid_gltf(&again);
    let info: serde_json::Value =
        serde_json::from_str(&faceanim_ok(&["info", again.to_str().unwrap(), "--json"])).unwrap();
    let names: Vec<&str> = info["file"]["animations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["take"], "the take is not in the file once");
    let (status, body) = support::upload(port, "again.glb", &glb);
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    for name in COLUMNS {
        let worst = worst_gap(&take_column(&state, name), &take_column(&corrected, name));
        assert!(
            worst < 1e-3,
            "the studio's GLB reopened: {name} is {worst} from the corrected take"
        );
    }

    // Its Live Link Face CSV opens again: the ARKit channels come back (of the take opened
    // last, the uncorrected file's, which `assert_same` knows).
    let (status, body) = support::upload(port, "take.glb", &std::fs::read(&take).unwrap());
    assert_eq!(status, 200, "{body}");
    let (status, csv) = request_bytes(port, "GET", "/api/capture/export.csv", &[], b"");
    assert_eq!(status, 200);
    let (status, body) = support::upload(port, "take.csv", &csv);
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_same(
        &state,
        &["jawOpen", "eyeBlink_L", "mouthSmile_R"],
        "the Live Link CSV reopened",
    );

    // What is no take is named, and the take stays.
    for (name, bytes, says) in [
        ("broken.glb", b"glTF not really".to_vec(), "broken.glb"),
        (
            "avatar.glb",
            std::fs::read(&avatar).unwrap(),
            "no animation of morph targets",
        ),
        (
            "notes.csv",
            b"name,value\nx,1\n".to_vec(),
            "not a Live Link Face CSV",
        ),
        (
            "short.csv",
            b"Timecode,BlendShapeCount,JawOpen\n00:00:00:00.000,1\n".to_vec(),
            "short.csv: line 2: 2 values for 3 columns",
        ),
    ] {
        let (status, body) = support::upload(port, name, &bytes);
        assert_eq!(status, 400, "{name}: {body}");
        assert!(body.contains(says), "{name}: {body}");
    }
    let (_, body) = request(port, "GET", "/api/capture/state", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        state["take"]["frames"], FRAMES,
        "a refused file closed the take"
    );
}

/// An animation an animator keyed in Blender (shape keys on its timeline, Bezier curves at
/// 24 fps, written by Blender's own glTF exporter) opens as a take at its own rate, every
/// frame as Blender played it.
#[test]
fn an_animation_keyed_in_blender_opens_as_a_take() {
    let dir = tempfile::tempdir().unwrap();
    let keyed = output_dir("round_trip").join("keyed-in-blender.glb");
    let avatar = blender_avatar_path();
    let report = support::blender_script(
        "blender_keyed.py",
        &[avatar.as_os_str(), keyed.as_os_str()],
        "FACEANIM_KEYED ",
    );
    let studio = start_on(None, &dir.path().join("project"), &[]);
    let (status, body) = support::upload(
        studio.port,
        "keyed-in-blender.glb",
        &std::fs::read(&keyed).unwrap(),
    );
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["fps"], 24.0, "{}", state["take"]["fps"]);
    assert_eq!(state["take"]["frames"], 25, "{}", state["take"]["frames"]);
    // Onto the built-in head by name: ICT's `eyeBlink_L` is ARKit's `eyeBlinkLeft`.
    for (name, ours) in [("jawOpen", "jawOpen"), ("eyeBlink_L", "eyeBlinkLeft")] {
        let blender: Vec<f64> = report["curves"][name]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let got = take_column(&state, ours);
        let worst = worst_gap(&got, &blender);
        assert!(
            worst < 1e-3,
            "{name}: {worst} from Blender's curve\n{got:?}\n{blender:?}"
        );
    }
    // The head the animator turned comes back as the take's head pose, frame by frame as
    // Blender played it (its world holds glTF's +Y as +Z: a turn there is C·q·C⁻¹, C = Rx(90°)).
    let reopened = faceanim_export::reopen::clip_of_file(
        "keyed-in-blender.glb",
        &std::fs::read(&keyed).unwrap(),
    )
    .unwrap();
    let poses = reopened.clip.head.expect("the head's turn was not read");
    let c = glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    let blender = report["head"].as_array().unwrap();
    assert_eq!(poses.len(), blender.len());
    let mut largest = 0.0f32;
    for (k, (pose, q)) in poses.iter().zip(blender).enumerate() {
        let q = glam::Quat::from_xyzw(
            q[1].as_f64().unwrap() as f32,
            q[2].as_f64().unwrap() as f32,
            q[3].as_f64().unwrap() as f32,
            q[0].as_f64().unwrap() as f32,
        );
        let want = c.inverse() * q * c;
        let got = glam::Quat::from_array(faceanim_anim::head_rotation(*pose));
        let apart = 2.0 * got.dot(want).abs().min(1.0).acos().to_degrees();
        assert!(
            apart < 0.5,
            "frame {k}: head {pose:?} is {apart}° from Blender's"
        );
        largest = largest.max(2.0 * want.w.abs().min(1.0).acos().to_degrees());
    }
    assert!(largest > 15.0, "the head hardly turned: {largest}°");
}

/// A sketch exported as a GLB (strokes drawn through the studio's API on the Blender avatar)
/// opens again in `faceanim studio` as its strokes, ready to edit, baking to the same weights,
/// and its export opens as the strokes again (the animation replaced, not added); the same
/// file without its strokes opens as a take that plays the sketch's frames.
#[test]
fn a_sketched_glb_opens_again_as_its_strokes_and_exports_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let out = output_dir("round_trip");
    let avatar = blender_avatar_path();
    let character = faceanim_testdata::producers::blender_avatar_character();
    let studio = start_on(Some(&avatar), &dir.path().join("sketch.json"), &[]);
    let mut targets = Vec::new();
    for (shape, start) in [("jawOpen", 0), ("mouthSmile_L", 20)] {
        let mut stroke: serde_json::Value =
            serde_json::from_str(&support::stroke_along(&character, shape, 30, 1.0 / 60.0))
                .unwrap();
        stroke["start_frame"] = start.into();
        let stroke = stroke.to_string();
        let (status, body) = request(studio.port, "POST", "/api/strokes", &[], stroke.as_bytes());
        assert_eq!(status, 200, "{body}");
        let sketch: serde_json::Value = serde_json::from_str(&body).unwrap();
        let actions = sketch["actions"].as_array().unwrap();
        targets.push(
            actions[actions.len() - 1]["sides"][0]["target"]
                .as_str()
                .unwrap()
                .to_owned(),
        );
    }
    let (_, glb) = support::get_with_head(studio.port, "/api/export.glb");
    let (_, baked) = support::get_with_head(studio.port, "/api/export.json");
    drop(studio);
    let sketched = out.join("sketched.glb");
    std::fs::write(&sketched, &glb).unwrap();
    let baked: serde_json::Value = serde_json::from_slice(&baked).unwrap();
    let frames = baked["frames"].as_array().unwrap().len();
    assert!(frames > 10, "{frames} frames");

    // It opens again as its two strokes (kept in the animation's extras), ready to edit, and
    // not also as a take; its sketch bakes to the same weights and exports the same again.
    let studio = start_on(Some(&sketched), &dir.path().join("again.json"), &[]);
    let (_, body) = request(studio.port, "GET", "/api/state", &[], b"");
    let sketch: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(sketch["actions"].as_array().unwrap().len(), 2, "{body}");
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let capture: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(capture["take"].is_null(), "{}", capture["take"]);
    assert_notice(
        &capture,
        "Sketch tab",
        "the page is not told where the sketch went",
    );
    let (status, rebaked) = request_bytes(studio.port, "GET", "/api/export.json", &[], b"");
    assert_eq!(status, 200);
    let rebaked: serde_json::Value = serde_json::from_slice(&rebaked).unwrap();
    let (status, again) = request_bytes(studio.port, "GET", "/api/export.glb", &[], b"");
    assert_eq!(status, 200);
    drop(studio);
    let again_path = out.join("sketched-again.glb");
    std::fs::write(&again_path, &again).unwrap();
    let info: serde_json::Value = serde_json::from_str(&faceanim_ok(&[
        "info",
        again_path.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    let animations = info["file"]["animations"].as_array().unwrap();
    assert_eq!(
        animations.len(),
        1,
        "the re-export replaces the sketch's animation"
    );
    assert_eq!(animations[0]["strokes"], 2, "{animations:?}");
    let studio = start_on(Some(&again_path), &dir.path().join("third.json"), &[]);
    let (_, body) = request(studio.port, "GET", "/api/state", &[], b"");
    let third: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(third["actions"].as_array().unwrap().len(), 2, "{body}");
    drop(studio);

    // The same file without its strokes (as another tool may write it back) opens as a take of
    // the same weights.
    let (mut doc, bin) = faceanim_testdata::glb::parts(&glb);
    for animation in doc["animations"].as_array_mut().unwrap() {
        if let Some(ours) = animation.pointer_mut("/extras/faceanim") {
            ours.as_object_mut().unwrap().remove("strokes");
        }
    }
    let plain = out.join("sketched-plain.glb");
    std::fs::write(&plain, faceanim_testdata::glb::assemble(&doc, &bin)).unwrap();
    let studio = start_on(Some(&plain), &dir.path().join("plain.json"), &[]);
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["frames"], frames, "{}", state["take"]);
    assert_eq!(targets[0], "jawOpen");
    for name in &targets {
        let want = support::column(&baked, name);
        assert!(
            want.iter().fold(0.0, |a: f64, b| a.max(*b)) > 0.5,
            "{name}: {want:?}"
        );
        let worst = worst_gap(&support::column(&rebaked, name), &want);
        assert!(
            worst < 1e-3,
            "the sketch reopened: {name} is {worst} from the sketch"
        );
        let worst = worst_gap(&take_column(&state, name), &want);
        assert!(
            worst < 1e-3,
            "the file without its strokes: {name} is {worst} from the sketch"
        );
    }
}

/// A VRM's expression binds the file's own morph target (`aa` binds `Fcl_MTH_A`): a take of it
/// exported, reopened and exported again gives the target the same weight, not twice it.
#[test]
fn a_vrm_take_reopens_without_counting_a_target_twice() {
    use faceanim_testdata::avatar::VrmKind;
    let dir = tempfile::tempdir().unwrap();
    let vrm = dir.path().join("avatar.vrm");
    std::fs::write(
        &vrm,
        faceanim_testdata::producers::with_vrm(
            &std::fs::read(blender_avatar_path()).unwrap(),
            VrmKind::V1,
        ),
    )
    .unwrap();
    let clip = dir.path().join("aa.json");
    std::fs::write(
        &clip,
        r#"{"fps": 30, "blendshapes": ["aa"], "frames": [[0.0], [0.5], [1.0], [0.25]]}"#,
    )
    .unwrap();
    let first = dir.path().join("first.vrm");
    export_with_clip(&vrm, &first, &clip);
    let studio = start_on(Some(&first), &dir.path().join("project.json"), &[]);
    let (status, again) = request_bytes(studio.port, "GET", "/api/capture/export.glb", &[], b"");
    assert_eq!(status, 200);
    drop(studio);
    let read = |name: &str, bytes: &[u8]| {
        support::column(
            &serde_json::to_value(
                faceanim_export::reopen::clip_of_file(name, bytes)
                    .unwrap()
                    .clip,
            )
            .unwrap(),
            "Fcl_MTH_A",
        )
    };
    let (once, twice) = (
        read("first.vrm", &std::fs::read(&first).unwrap()),
        read("again.vrm", &again),
    );
    assert!((once[1] - 0.5).abs() < 1e-3, "{once:?}");
    assert!(worst_gap(&once, &twice) < 1e-3, "{once:?} became {twice:?}");
}
