//! `faceanim adapt`, `faceanim track --adapter` and `faceanim session` end to end, as a user
//! runs them: train the ICT head's adapter, animate it from a video rendered here with a known
//! jawOpen curve and from a photo, correct a frame, apply the preference, fine-tune, export;
//! and an adapter given to the wrong character is refused with a message saying why.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use std::path::Path;

use support::{assert_valid_gltf, column, faceanim, faceanim_ok, output_dir};

/// `faceanim track INPUT --adapter ADAPTER MORE… -o OUTPUT…`, as it ended.
fn track(input: &Path, adapter: &str, more: &[&str], outputs: &[&Path]) -> std::process::Output {
    let mut args = vec!["track", input.to_str().unwrap(), "--adapter", adapter];
    args.extend_from_slice(more);
    for output in outputs {
        args.extend(["-o", output.to_str().unwrap()]);
    }
    faceanim(&args)
}

/// The jawOpen of frame `i` of the test video: shut, a smooth open to 0.8, shut.
fn jaw_curve(i: usize) -> f32 {
    let t = i as f32 / 23.0;
    0.8 * (std::f32::consts::PI * t).sin().powi(2)
}

/// 24 frames at 24 fps of the ICT head rendered with `jaw_curve`, as x264 would deliver them.
fn make_video(path: &Path) {
    let jaw: Vec<f32> = (0..24).map(jaw_curve).collect();
    support::encode_h264(path, 320, 24, &support::ict_jaw_frames(&jaw, 320));
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// `faceanim session SESSION show --json`.
fn show(session: &str) -> serde_json::Value {
    serde_json::from_str(faceanim_ok(&["session", session, "show", "--json"]).trim()).unwrap()
}

#[test]
fn adapt_then_track_correct_and_fine_tune() {
    let dir = tempfile::tempdir().unwrap();
    let out = output_dir("adapt");
    let adapter = dir.path().join("ict.adapter.safetensors");
    let adapter_arg = adapter.to_str().unwrap();

    // Train (few samples: the test checks the plumbing; the library test checks accuracy).
    let summary = faceanim_ok(&[
        "adapt",
        &support::ict(),
        "-o",
        adapter_arg,
        "--samples",
        "1000",
        "--json",
    ]);
    let summary: serde_json::Value = serde_json::from_str(summary.trim()).unwrap();
    for key in ["mae_test", "mae_val", "samples", "members", "seconds"] {
        assert!(summary[key].is_number(), "{key} missing: {summary}");
    }
    assert!(summary["samples"].as_u64().unwrap() >= 990);
    assert!(summary["mae_test"].as_f64().unwrap() < 0.15, "{summary}");
    assert_eq!(summary["loss"], "censored_absolute", "{summary}");
    // Every shape shown alone and read back; the jaw is driven.
    let shapes = summary["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 53, "{summary}");
    let jaw = shapes.iter().find(|s| s["name"] == "jawOpen").unwrap();
    assert_eq!(jaw["reading"], "read", "{jaw}");
    assert!(dir.path().join("ict.dataset.safetensors").exists());

    // Track a video through the adapter, with a session and a user keyframe.
    let video = dir.path().join("jaw.mp4");
    make_video(&video);
    let clip_path = out.join("jaw.json");
    let session = dir.path().join("jaw.session.json");
    let seed_csv = out.join("jaw.byoc.csv");
    let glb = out.join("jaw.glb");
    let live_link = out.join("jaw.csv");
    let ict_path = support::ict();
    let more = [
        "--character",
        &ict_path,
        "--session",
        session.to_str().unwrap(),
        "--keyframe",
        "7",
        "--neutral-frame",
        "0",
    ];
    let tracked = track(
        &video,
        adapter_arg,
        &more,
        &[&clip_path, &seed_csv, &glb, &live_link],
    );
    let printed: serde_json::Value =
        serde_json::from_slice(&support::succeeded("faceanim track", tracked).stdout).unwrap();
    assert_eq!(printed["frames"], 24);
    assert_eq!(
        printed["neutral"],
        serde_json::json!({"frame": 0, "chosen": "user",
            "parts": {"lids": 0, "gaze": 0, "brows": 0, "mouth": 0}})
    );
    // Reported, not judged: timing is for benchmarks (crates/adapt/benches), not a shared
    // machine's tests.
    assert!(printed["adapter_ms_per_frame"].as_f64().unwrap() >= 0.0);
    let clip = read_json(&clip_path);
    assert_eq!(clip["blendshapes"].as_array().unwrap().len(), 53);
    let jaw = column(&clip, "jawOpen");
    assert_eq!(jaw.len(), 24);
    // The estimated curve follows the rendered one.
    let truth: Vec<f64> = (0..24).map(|i| f64::from(jaw_curve(i))).collect();
    let error: f64 = jaw
        .iter()
        .zip(&truth)
        .map(|(a, b)| (a - b).abs())
        .sum::<f64>()
        / 24.0;
    assert!(error < 0.15, "jawOpen {jaw:?} against {truth:?}");
    assert!(jaw[11] > 0.5 && jaw[0] < 0.2 && jaw[23] < 0.2, "{jaw:?}");
    assert!(clip["head"].is_array(), "head pose goes with the clip");
    // The seed's CSV: one line per frame, the name then 53 weights.
    let csv = std::fs::read_to_string(&seed_csv).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 24);
    assert!(lines[0].starts_with("jaw_000001.png,"), "{}", lines[0]);
    assert_eq!(lines[0].split(',').count(), 54);
    assert!(
        std::fs::read_to_string(&live_link)
            .unwrap()
            .starts_with("Timecode,BlendShapeCount,EyeBlinkLeft")
    );
    assert_valid_gltf(&glb);

    // The session: frame 7 is a keyframe (asked for), and so are 0, 5, 10, 15, 20 and 23.
    let session_arg = session.to_str().unwrap();
    // `faceanim session SESSION ARGS…`.
    let edit = |args: &[&str]| faceanim(&[&["session", session_arg][..], args].concat());
    let edit_ok = |args: &[&str]| faceanim_ok(&[&["session", session_arg][..], args].concat());
    let shown = show(session_arg);
    let keys: Vec<u64> = shown["keyframes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k.as_u64().unwrap())
        .collect();
    assert_eq!(keys, vec![0, 5, 7, 10, 15, 20, 23]);
    assert_eq!(
        shown["neutral"],
        serde_json::json!({"frame": 0, "chosen": "user",
            "parts": {"lids": 0, "gaze": 0, "brows": 0, "mouth": 0}})
    );
    // Saying the open-mouthed frame 11 is neutral reads every other frame against it: frame
    // 11 itself becomes rest. `auto` goes back to each part's calmest frame: the mouth's is a shut one.
    edit_ok(&["neutral", "11", "--adapter", adapter_arg]);
    let shown = show(session_arg);
    assert_eq!(
        shown["neutral"],
        serde_json::json!({"frame": 11, "chosen": "user",
            "parts": {"lids": 11, "gaze": 11, "brows": 11, "mouth": 11}})
    );
    let against_open = dir.path().join("against-open.json");
    edit_ok(&["export", "-o", against_open.to_str().unwrap()]);
    let against_open = column(&read_json(&against_open), "jawOpen");
    assert!(against_open[11] < 0.2, "{against_open:?}");
    edit_ok(&["neutral", "auto", "--adapter", adapter_arg]);
    let shown = show(session_arg);
    assert_eq!(shown["neutral"]["chosen"], "automatic", "{shown}");
    let auto_frame = shown["neutral"]["frame"].as_u64().unwrap() as usize;
    assert!(jaw_curve(auto_frame) < 0.1, "{shown}");
    let refused = edit(&["neutral", "99", "--adapter", adapter_arg]);
    assert!(!refused.status.success());
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("frame 99 is past the end"),
        "{}",
        String::from_utf8_lossy(&refused.stderr)
    );

    // Correct jawOpen on frame 20, apply the preference: every other frame shifts by the same
    // amount (clamped to 0..1), and the corrected frame holds the value set.
    let before = dir.path().join("before.json");
    edit_ok(&[
        "export",
        "-o",
        before.to_str().unwrap(),
        "--character",
        &support::ict(),
    ]);
    let before_jaw = column(&read_json(&before), "jawOpen");
    edit_ok(&["correct", "20", "jawOpen=0.6"]);
    edit_ok(&["apply-preference"]);
    let after = out.join("preferred.json");
    edit_ok(&["export", "-o", after.to_str().unwrap()]);
    let after_jaw = column(&read_json(&after), "jawOpen");
    assert!((after_jaw[20] - 0.6).abs() < 1e-6);
    let shift = 0.6 - before_jaw[20];
    assert!(shift > 0.2, "frame 20 was {}", before_jaw[20]);
    for k in [0usize, 5, 7, 10, 15] {
        let expected = (before_jaw[k] + shift).clamp(0.0, 1.0);
        assert!(
            (after_jaw[k] - expected).abs() < 1e-4,
            "frame {k}: {} → {}, expected {expected}",
            before_jaw[k],
            after_jaw[k]
        );
    }
    // Clearing the preference restores every frame but the corrected one.
    edit_ok(&["clear-preference"]);
    let cleared = dir.path().join("cleared.json");
    edit_ok(&["export", "-o", cleared.to_str().unwrap()]);
    let cleared_jaw = column(&read_json(&cleared), "jawOpen");
    assert!((cleared_jaw[5] - before_jaw[5]).abs() < 1e-6);

    // Bad edits name the problem.
    let bad = edit(&["correct", "99", "jawOpen=0.5"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("frame 99 is past the end"));
    let bad = edit(&["correct", "2", "noSuchShape=0.5"]);
    assert!(String::from_utf8_lossy(&bad.stderr).contains("noSuchShape"));

    // Offline fine-tuning from the session's corrections.
    let tuned = dir.path().join("tuned.adapter.safetensors");
    let result: serde_json::Value = serde_json::from_str(
        faceanim_ok(&[
            "adapt",
            &support::ict(),
            "-o",
            tuned.to_str().unwrap(),
            "--from",
            adapter_arg,
            "--dataset",
            dir.path().join("ict.dataset.safetensors").to_str().unwrap(),
            "--finetune",
            session.to_str().unwrap(),
            "--json",
        ])
        .trim(),
    )
    .unwrap();
    assert_eq!(result["corrected_frames"], 1);
    assert!(
        result["mae_corrected_after"].as_f64().unwrap()
            < result["mae_corrected_before"].as_f64().unwrap(),
        "{result}"
    );
    assert!(
        result["mae_test"].as_f64().unwrap() <= 1.1 * result["mae_test_before"].as_f64().unwrap(),
        "{result}"
    );
    edit_ok(&["reestimate", "--adapter", tuned.to_str().unwrap()]);

    // A photo becomes 0 → peak → 0.
    let photo = faceanim_testdata::shared("images/ict-face-jawopen.png");
    let still = dir.path().join("still.json");
    let more = ["--character", &ict_path, "--image-frames", "21"];
    support::succeeded(
        "faceanim track",
        track(&photo, adapter_arg, &more, &[&still]),
    );
    let jaw = column(&read_json(&still), "jawOpen");
    assert_eq!(jaw.len(), 21);
    assert!(jaw[0] == 0.0 && jaw[20] == 0.0, "{jaw:?}");
    assert!(
        jaw[10] > 0.4 && jaw[10] >= jaw[5] && jaw[5] > 0.0,
        "{jaw:?}"
    );

    // The adapter on the wrong character is refused, saying why and what to do.
    let refused = track(&photo, adapter_arg, &[], &[&still]);
    assert!(!refused.status.success());
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(
        message.contains("cannot drive") && message.contains("faceanim adapt"),
        "{message}"
    );
    // More networks than training samples to share out is refused before anything is rendered.
    for members in ["0", "17"] {
        let refused = faceanim(&[
            "adapt",
            &support::ict(),
            "--samples",
            "20",
            "--members",
            members,
        ]);
        assert!(!refused.status.success());
        let message = String::from_utf8_lossy(&refused.stderr);
        assert!(
            message.contains("--members must be between 1 and the 16 training samples"),
            "{message}"
        );
    }
    // A hold on the map below 0 is refused, naming the option.
    let refused = faceanim(&["adapt", &support::ict(), "--stay=-1"]);
    assert!(!refused.status.success());
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(message.contains("--stay must be 0 or more"), "{message}");
    let garbage = dir.path().join("garbage.safetensors");
    std::fs::write(&garbage, b"not an adapter").unwrap();
    let refused = track(
        &photo,
        garbage.to_str().unwrap(),
        &["--character", &ict_path],
        &[&still],
    );
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(
        message.contains("garbage.safetensors") && message.contains("safetensors"),
        "{message}"
    );
}
