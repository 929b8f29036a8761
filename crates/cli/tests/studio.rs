//! The studio: its HTTP safety rules, and the whole page in a real browser (Debian's chromium
//! driven by playwright-core, `tools/studio-e2e.mjs`) on the ICT head: draw a stroke, drag the
//! arrow, undo/redo, symmetry, save and reopen, a broken upload, in the full viewport, and on the
//! built-in head in `?fast`'s. Screenshots go to `test-output/studio/` and
//! `test-output/studio-head-fast/`.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests"
)]

mod support;

use std::process::Command;

use support::{Studio, assert_valid_gltf, output_dir, repo, request, start_on};

fn start(project: &std::path::Path) -> Studio {
    start_with(project, &[])
}

fn start_with(project: &std::path::Path, more: &[&std::ffi::OsStr]) -> Studio {
    start_on(
        Some(&faceanim_testdata::shared("characters/ict-face.glb")),
        project,
        more,
    )
}

/// Runs `tools/SCRIPT URL OUT ARGUMENTS…` (playwright-core driving Debian's chromium) against
/// `studio` and returns the JSON line of measurements it prints last; fails with its output.
/// Sends `rgb` (`width`×`height`, three bytes a pixel) to the studio at `port` as one live
/// webcam frame, as the page sends it (RGBX); returns the answer.
fn live_frame(port: u16, width: usize, height: usize, rgb: &[u8]) -> serde_json::Value {
    let rgbx: Vec<u8> = rgb
        .chunks(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let (width, height) = (width.to_string(), height.to_string());
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/live/frame",
        &[
            ("x-width", &width),
            ("x-height", &height),
            ("x-pixel-format", "RGBX"),
        ],
        &rgbx,
    );
    assert_eq!(status, 200, "{body}");
    serde_json::from_str(&body).unwrap()
}

fn browser_script(
    script: &str,
    studio: &Studio,
    query: &str,
    out: &std::path::Path,
    arguments: &[std::ffi::OsString],
) -> serde_json::Value {
    assert!(
        repo().join("tools/node_modules/playwright-core").exists(),
        "playwright-core is not installed: run scripts/setup.sh"
    );
    let run = Command::new("node")
        .arg(repo().join("tools").join(script))
        .arg(format!("http://127.0.0.1:{}/{query}", studio.port))
        .arg(out)
        .args(arguments)
        .output()
        .expect("node");
    let stdout = String::from_utf8_lossy(&run.stdout);
    eprintln!("{stdout}");
    assert!(
        run.status.success(),
        "{}\n{}",
        stdout,
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_str(stdout.lines().last().unwrap()).unwrap()
}

#[test]
fn only_its_own_host_and_origin_are_served() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("p.json"));
    let port = studio.port;
    assert_eq!(request(port, "GET", "/api/state", &[], b"").0, 200);
    let own = format!("localhost:{port}");
    assert_eq!(
        request(port, "GET", "/api/state", &[("Host", &own)], b"").0,
        200
    );
    // DNS rebinding: a page on another name resolving to 127.0.0.1.
    let (status, body) = request(
        port,
        "GET",
        "/api/state",
        &[("Host", "attacker.example:80")],
        b"",
    );
    assert_eq!(status, 403, "{body}");
    // Another site's page posting to the studio.
    let (status, _) = request(
        port,
        "POST",
        "/api/undo",
        &[("Origin", "http://attacker.example")],
        b"",
    );
    assert_eq!(status, 403);
    let origin = format!("http://127.0.0.1:{port}");
    assert_eq!(
        request(port, "POST", "/api/undo", &[("Origin", &origin)], b"").0,
        200
    );
    // The page is embedded: paths outside it do not reach the file system.
    assert_eq!(request(port, "GET", "/../../Cargo.toml", &[], b"").0, 404);
    assert_eq!(
        request(port, "GET", "/%2e%2e/%2e%2e/Cargo.toml", &[], b"").0,
        404
    );
    // Bad JSON gets a message naming what was wrong.
    let (status, body) = request(
        port,
        "POST",
        "/api/strokes",
        &[("Content-Type", "application/json")],
        b"{\"samples\": 3}",
    );
    assert_eq!(status, 400);
    assert!(body.contains("stroke"), "{body}");
    // Oversized JSON is refused before it is read.
    let big = vec![b' '; 17 * 1024 * 1024];
    assert_eq!(request(port, "PUT", "/api/project", &[], &big).0, 413);
}

#[test]
fn an_animator_session_in_a_real_browser() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("session.faceanim.json"));
    let measured = browser_script("studio-e2e.mjs", &studio, "", &output_dir("studio"), &[]);
    assert!(measured["smile_weight"].as_f64().unwrap() > 0.5);
    // Where a slow display is sent: this page with `?fast`.
    let hint = &measured["slow_hint"];
    let href = hint["href"].as_str().unwrap();
    assert!(href.ends_with("/?fast"), "{hint}");
    eprintln!(
        "the slow-display hint was {}shown",
        if hint["shown"] == true { "" } else { "not " }
    );
    // The project was saved where the studio was pointed, and nowhere else.
    assert!(dir.path().join("session.faceanim.json").exists());
}

/// The same session on the built-in head (the README's run command opens it), whose names are
/// ARKit's own (`mouthSmileLeft`), not the ICT head the page was developed on, in the viewport
/// the README recommends without a GPU (`?fast`: morph targets blended on the CPU, lighting per
/// vertex).
#[test]
fn an_animator_session_on_the_built_in_head_in_the_viewport_for_machines_without_a_gpu() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start_on(None, &dir.path().join("head.faceanim.json"), &[]);
    let measured = browser_script(
        "studio-e2e.mjs",
        &studio,
        "?fast",
        &output_dir("studio-head-fast"),
        &[],
    );
    assert!(measured["smile_weight"].as_f64().unwrap() > 0.5);
    // The fast viewport is the one the slow-display hint points to: it never shows it.
    assert_eq!(measured["slow_hint"]["shown"], false, "{measured}");
}

#[test]
fn capture_mode_refuses_bad_input_with_a_reason() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("p.json"));
    let port = studio.port;
    let json = [("Content-Type", "application/json")];
    // Nothing open yet: edits say what to do first.
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/correct",
        &json,
        br#"{"frame": 0, "name": "jawOpen", "value": 0.5}"#,
    );
    assert_eq!(status, 400);
    assert!(body.contains("open a video"), "{body}");
    let (status, body) = support::open_path(port, std::path::Path::new("/no/such/video.mp4"));
    assert_eq!(status, 400);
    assert!(body.contains("/no/such/video.mp4"), "{body}");
    // A file that is no video: the job ends with ffmpeg's reason, naming the upload.
    let (status, _) = request(
        port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", "notes.mp4")],
        b"this is not a video",
    );
    assert_eq!(status, 200);
    let mut job = serde_json::Value::Null;
    for _ in 0..100 {
        let (_, body) = request(port, "GET", "/api/capture/state", &[], b"");
        job = serde_json::from_str::<serde_json::Value>(&body).unwrap()["job"].clone();
        if job["running"] == false {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let error = job["error"].as_str().unwrap_or_default();
    assert!(error.contains("notes.mp4"), "{job}");
    // A session file must be one, and of this character.
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", "notes.json")],
        br#"{"title": "my notes"}"#,
    );
    assert_eq!(status, 400);
    assert!(body.contains("notes.json: not a session file"), "{body}");
    let other = br#"{"version": 1, "source": "x.mp4", "character": "robot",
        "blendshapes": ["beep", "boop"], "fingerprint": {"topology": "t", "geometry": "g"},
        "fps": 30, "keyframe_every": 5,
        "frames": [{"name": "f1", "time": 0, "presence": 1, "head": null,
                    "head_position": null, "expression": null, "estimate": [0.1, 0.2]}]}"#;
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", "robot.session.json")],
        other,
    );
    assert_eq!(status, 400);
    assert!(
        body.contains("robot.session.json: a session of robot with 2 blendshapes")
            && body.contains("not of ict-face with 53 (it lacks 53:"),
        "{body}"
    );
    let (_, body) = request(port, "GET", "/api/capture/state", &[], b"");
    assert!(
        body.contains("\"take\":null"),
        "a refused session left a take: {body}"
    );
    // A clip JSON (what `track -o take.json` or the Clip JSON download wrote) opens as a take of
    // its frames, by name, with its head pose; one naming nothing of this character is refused.
    let upload = |name: &str, bytes: &[u8]| support::upload(port, name, bytes);
    let (status, body) = upload(
        "take.json",
        br#"{"fps": 30, "blendshapes": ["jawOpen", "EyeBlinkLeft"],
        "frames": [[0.5, 1.0], [0.25, 0.0], [0.0, 0.0]], "head": [[10, 0, 0], [5, 0, 0], [0, 0, 0]]}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    let take = &state["take"];
    assert_eq!(take["frames"], 3, "{take}");
    let names = support::strings(&state["blendshapes"]);
    let at = |name: &str| names.iter().position(|n| n == name).unwrap();
    assert_eq!(take["estimates"][0][at("jawOpen")], 0.5, "{take}");
    assert_eq!(take["estimates"][0][at("eyeBlink_L")], 1.0, "{take}");
    assert_eq!(take["estimates"][1][at("jawOpen")], 0.25, "{take}");
    assert_eq!(take["head"][0][0], 10.0, "{take}");
    let (status, body) = upload(
        "robot.json",
        br#"{"fps": 30, "blendshapes": ["beep"], "frames": [[1.0]]}"#,
    );
    assert_eq!(status, 400);
    assert!(
        body.contains("robot.json") && body.contains("beep"),
        "{body}"
    );
    // Live frames must be the size they claim.
    let (_, body) = request(port, "POST", "/api/capture/live/start", &[], b"");
    assert!(body.contains("\"live\""), "{body}");
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/live/frame",
        &[("x-width", "4"), ("x-height", "4")],
        &[0u8; 10],
    );
    assert_eq!(status, 400);
    assert!(body.contains("4×4 RGBA"), "{body}");
    // The camera's own YUV: its size is checked too, and an unknown format is named.
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/live/frame",
        &[
            ("x-width", "4"),
            ("x-height", "4"),
            ("x-pixel-format", "I420"),
        ],
        &[0u8; 64],
    );
    assert_eq!(status, 400);
    assert!(body.contains("4×4 I420 frame (24 bytes)"), "{body}");
    for (header, value) in [
        ("x-pixel-format", "P010"),
        ("x-yuv-matrix", "bt2020"),
        ("x-yuv-range", "tv"),
    ] {
        let (status, body) = request(
            port,
            "POST",
            "/api/capture/live/frame",
            &[("x-width", "4"), ("x-height", "4"), (header, value)],
            &[0u8; 64],
        );
        assert_eq!(status, 400);
        assert!(body.contains(header) && body.contains(value), "{body}");
    }
    // A frame still on its way when live mode stops is dropped, not an error.
    request(port, "POST", "/api/capture/live/stop", &[], b"");
    let (status, body) = request(
        port,
        "POST",
        "/api/capture/live/frame",
        &[("x-width", "4"), ("x-height", "4")],
        &[0u8; 64],
    );
    assert_eq!(status, 200, "{body}");
    assert!(body.contains("\"live\":false"), "{body}");
    let (status, body) = request(
        port,
        "PUT",
        "/api/capture/filtering",
        &json,
        br#"{"keyframe_every": 0, "smoothing": null}"#,
    );
    assert_eq!(status, 400);
    assert!(body.contains("keyframe_every"), "{body}");
}

#[test]
fn a_take_and_its_corrections_survive_closing_the_studio() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("jaw.mp4");
    let jaw: Vec<f32> = (0..12).map(|i| i as f32 / 12.0).collect();
    support::encode_h264(&video, 256, 24, &support::ict_jaw_frames(&jaw, 256));
    let project = dir.path().join("take.faceanim.json");
    let json = [("Content-Type", "application/json")];
    // The studio's own temporary folder, holding what a studio killed outright left: its
    // scratch folder, with a recording, whose lock no process holds.
    let temp = dir.path().join("tmp");
    let left = temp.join("faceanim-studio-left");
    std::fs::create_dir_all(&left).unwrap();
    std::fs::write(left.join("running.lock"), b"").unwrap();
    std::fs::write(left.join("microphone.wav"), b"RIFF").unwrap();
    let mut studio = support::start_on_env(
        Some(&faceanim_testdata::shared("characters/ict-face.glb")),
        &project,
        &[],
        &[("TMPDIR", temp.as_os_str())],
    );
    let state = support::open_and_settle(studio.port, &video);
    assert_eq!(state["take"]["frames"], 12, "{}", state["job"]);
    // Swept before the studio answered anything.
    assert!(!left.exists(), "a killed studio's scratch folder was kept");
    // The frames' previews are in the studio's scratch folder, the only thing it made there.
    let made: Vec<_> = std::fs::read_dir(&temp).unwrap().flatten().collect();
    assert_eq!(made.len(), 1, "{made:?}");
    assert!(
        made[0]
            .file_name()
            .to_string_lossy()
            .starts_with("faceanim-studio-")
            && std::fs::read_dir(made[0].path()).unwrap().count() >= 2,
        "{made:?}"
    );
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/capture/correct",
        &json,
        br#"{"frame": 3, "name": "jawOpen", "value": 0.875}"#,
    );
    assert_eq!(status, 200, "{body}");
    // Linked left and right: one correction sets both sides, in one edit.
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/capture/correct",
        &json,
        br#"{"frame": 5, "name": "mouthSmile_L", "value": 0.5, "mirror": true}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        state["take"]["corrections"]["5"]["mouthSmile_R"], 0.5,
        "{body}"
    );
    let (_, body) = request(studio.port, "POST", "/api/capture/undo", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(
        state["take"]["corrections"]["5"].is_null(),
        "one undo takes both sides back: {body}"
    );
    // Stopped as Ctrl-C or a service manager stops it, the studio ends cleanly and takes its
    // scratch folder (the previews, any upload or recording) with it.
    let stopped = studio.stop();
    assert!(stopped.is_some_and(|s| s.success()), "{stopped:?}");
    let kept: Vec<_> = std::fs::read_dir(&temp).unwrap().flatten().collect();
    assert!(kept.is_empty(), "the stopped studio left {kept:?}");
    drop(studio);

    // A new studio on the same project reopens the take with the correction.
    let studio = start(&project);
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["frames"], 12, "{body}");
    assert_eq!(state["take"]["corrections"]["3"]["jawOpen"], 0.875);
    // Its input is not kept: frames have no preview, and say so.
    assert_eq!(
        request(studio.port, "GET", "/api/capture/frame/0.png", &[], b"").0,
        404
    );
    // Closing the take removes it for good.
    request(studio.port, "POST", "/api/capture/close", &[], b"");
    drop(studio);
    let studio = start(&project);
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    assert!(body.contains("\"take\":null"), "{body}");
}

/// The jawOpen of frame `i` of the capture test's video: shut, open to 0.8, shut, twice.
fn jaw_curve(i: usize) -> f32 {
    let t = i as f32 / 47.0;
    0.8 * (2.0 * std::f32::consts::PI * t).sin().powi(2)
}

/// Capture mode as a newcomer uses it, in a real browser (`tools/capture-e2e.mjs`): pick a few
/// photos, then upload a video of the ICT head with a known jawOpen curve, see the estimate
/// follow it, correct one frame, apply the preference, export every format, train and
/// fine-tune the adapter from the page (and cancel a training), then the webcam — Chromium's
/// fake camera playing a rendered face that opens its mouth — in live mode, and a recorded take.
/// Screenshots go to `test-output/capture/`.
#[test]
fn capture_mode_in_a_real_browser() {
    let dir = tempfile::tempdir().unwrap();
    let out = output_dir("capture");
    let video = dir.path().join("jaw.mp4");
    let truth: Vec<f32> = (0..48).map(jaw_curve).collect();
    support::encode_h264(&video, 320, 24, &support::ict_jaw_frames(&truth, 320));
    // The webcam: shut for half a second, open for a second, looping (Chromium replays it).
    let webcam: Vec<f32> = (0..45).map(|i| if i < 15 { 0.0 } else { 0.9 }).collect();
    let y4m = dir.path().join("webcam.y4m");
    let frames = support::ict_jaw_frames(&webcam, 480);
    faceanim_testdata::encode_video(
        &y4m,
        (480, 480),
        30,
        &["-pix_fmt", "yuv420p"],
        frames.iter().map(Vec::as_slice),
    );
    // Three photos, the jaw wider in each: a sequence picked together in the page.
    let photos: Vec<std::path::PathBuf> = support::ict_jaw_frames(&[0.0, 0.35, 0.7], 256)
        .into_iter()
        .enumerate()
        .map(|(i, rgb)| {
            let path = dir.path().join(format!("photo_{i}.png"));
            let image = faceanim_render::Image {
                width: 256,
                height: 256,
                rgb,
            };
            std::fs::write(&path, image.to_png().unwrap()).unwrap();
            path
        })
        .collect();
    let adapter = dir.path().join("ict.adapter.safetensors");
    let studio = start_with(
        &dir.path().join("capture.faceanim.json"),
        &["--adapter".as_ref(), adapter.as_os_str()],
    );
    let truth_json = serde_json::to_string(&truth).unwrap();
    // Real speech to lip-sync (Debian's pocketsphinx-testdata: a LibriVox reading).
    let speech = std::path::PathBuf::from(
        "/usr/share/pocketsphinx/test/data/librivox/sense_and_sensibility_01_austen_64kb-0920.wav",
    );
    assert!(
        speech.exists(),
        "pocketsphinx-testdata is needed: run scripts/setup.sh"
    );
    // The microphone: a synthetic voice (flite's rms) reads the calibration passage, then
    // three lines with pauses between them.
    let microphone = dir.path().join("microphone.wav");
    let mut parts = vec![(faceanim_speech::listen::PASSAGE, 1.0)];
    parts.extend([
        (
            "We often go fishing with our father in the early morning.",
            0.6,
        ),
        ("Please bring me my blue map before the bus leaves.", 0.6),
        ("She sells sea shells by the sea shore on Thursday.", 0.6),
    ]);
    let mut spoken: Vec<u8> = Vec::new();
    for (k, (text, pause)) in parts.iter().enumerate() {
        let part = dir.path().join(format!("part{k}.wav"));
        support::flite("rms", text, &part);
        let bytes = std::fs::read(&part).unwrap();
        let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
        spoken.extend_from_slice(&bytes[data..]);
        spoken.resize(spoken.len() + (pause * 32_000.0) as usize, 0);
    }
    let samples: Vec<i16> = spoken
        .chunks_exact(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .collect();
    std::fs::write(
        &microphone,
        faceanim_speech::audio::wav_bytes(&samples, 16_000, 1),
    )
    .unwrap();
    let mut arguments = vec![
        video.into_os_string(),
        y4m.into_os_string(),
        truth_json.into(),
        speech.into_os_string(),
        microphone.into_os_string(),
    ];
    arguments.extend(photos.into_iter().map(std::path::PathBuf::into_os_string));
    let measured = browser_script("capture-e2e.mjs", &studio, "", &out, &arguments);
    assert!(
        measured["live_max_jaw_open"].as_f64().unwrap() > 0.4,
        "{measured}"
    );
    // The page's downloads are real files in the formats users open elsewhere.
    let glb = out.join("download.glb");
    assert_valid_gltf(&glb);
    let clip: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("download.clip.json")).unwrap()).unwrap();
    assert_eq!(clip["frames"].as_array().unwrap().len(), truth.len());
    let csv = std::fs::read_to_string(out.join("download.csv")).unwrap();
    assert!(
        csv.starts_with("Timecode,BlendShapeCount,"),
        "{}",
        &csv[..80.min(csv.len())]
    );
    assert_eq!(csv.lines().count(), truth.len() + 1);
    // The adapter trained from the page was saved where the studio was told.
    assert!(adapter.exists());
}

/// The studio's live link (`GET /api/capture/vmc`).
fn live_view(studio: &Studio) -> serde_json::Value {
    let (status, body) = request(studio.port, "GET", "/api/capture/vmc", &[], b"");
    assert_eq!(status, 200, "{body}");
    serde_json::from_str(&body).unwrap()
}

/// Starts (`true`) or stops recording what arrives over the live link; the capture state.
fn record_live(studio: &Studio, on: bool) -> serde_json::Value {
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/capture/vmc/record",
        &[("Content-Type", "application/json")],
        format!("{{\"on\": {on}}}").as_bytes(),
    );
    assert_eq!(status, 200, "{body}");
    serde_json::from_str(&body).unwrap()
}

/// The live link's state once `frames` are recorded (or after five seconds).
fn recorded(studio: &Studio, frames: usize) -> serde_json::Value {
    live_view_at(studio, "recording", frames)
}

/// The live link's state once its `count` (`frames` arrived, `recording`) is `n` (or after five
/// seconds).
fn live_view_at(studio: &Studio, count: &str, n: usize) -> serde_json::Value {
    let mut state = live_view(studio);
    for _ in 0..100 {
        if state[count] == n {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        state = live_view(studio);
    }
    state
}

/// The recorded take of `capture` keeps the time of what was `sent` (every frame with its time
/// on the sender's clock, those marked `"lost"` never arriving): it lasts as long, and each of
/// its frames, at `k / fps` from the first, lies between the two sent frames around its time
/// — a blend of them, or across a long loss the one before — in the weights and the head's
/// yaw (`yaw` of a sent frame). `slack` widens "around" by seconds either side, for a take
/// timed by arrival (the network's delays), not by the sender's clock.
fn take_follows(
    capture: &serde_json::Value,
    sent: &serde_json::Value,
    yaw: impl Fn(&serde_json::Value) -> f64,
    slack: f64,
) {
    let take = &capture["take"];
    let names = support::strings(&capture["blendshapes"]);
    let column = |name: &str| names.iter().position(|n| *n == name).unwrap();
    let arrived: Vec<&serde_json::Value> = sent["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["lost"] != true)
        .collect();
    let time =
        |f: &serde_json::Value| f["time"].as_f64().unwrap() - arrived[0]["time"].as_f64().unwrap();
    let fps = take["fps"].as_f64().unwrap();
    let frames = take["estimates"].as_array().unwrap();
    let span = time(arrived[arrived.len() - 1]);
    assert!(
        (frames.len() as f64 - 1.0 - span * fps).abs() <= 1.0 + slack * fps,
        "frames sent over {span} s, a take of {} at {fps} fps",
        frames.len()
    );
    for (k, estimate) in frames.iter().enumerate() {
        let t = k as f64 / fps;
        let before = arrived.iter().rposition(|&f| time(f) <= t).unwrap_or(0);
        let after = (before + 1).min(arrived.len() - 1);
        let (from, to) = (time(arrived[before]) - slack, time(arrived[after]) + slack);
        let around: Vec<&serde_json::Value> = arrived
            .iter()
            .copied()
            .filter(|&f| (from..=to).contains(&time(f)))
            .collect();
        let within = |want: &dyn Fn(&serde_json::Value) -> f64, got: f64, tolerance: f64| {
            let wants = || around.iter().map(|&f| want(f));
            let (low, high) = (
                wants().fold(f64::INFINITY, f64::min),
                wants().fold(f64::NEG_INFINITY, f64::max),
            );
            assert!(
                low - tolerance <= got && got <= high + tolerance,
                "take frame {k} at {t:.3} s: {got}, sent {low} to {high} from {from:.3} to {to:.3} s"
            );
        };
        for (sent_name, own) in [
            ("JawOpen", "jawOpen"),
            ("EyeBlinkLeft", "eyeBlink_L"),
            ("MouthSmileLeft", "mouthSmile_L"),
        ] {
            let got = estimate[column(own)].as_f64().unwrap();
            within(&|f| f["values"][sent_name].as_f64().unwrap(), got, 1e-5);
        }
        within(&yaw, take["head"][k][0].as_f64().unwrap(), 1e-2);
    }
}

/// VMC in: a phone tracker (an independent python-osc sender) plays 300 frames of ARKit
/// weights and head turns at 60 Hz; the studio records them as a take whose frames are what
/// was sent, with their arrival times, and that exports like a webcam take; then a flood of bad
/// datagrams is counted and survived.
#[test]
fn a_phone_trackers_vmc_stream_becomes_a_take() {
    let dir = tempfile::tempdir().unwrap();
    let port = support::free_udp_port();
    let listen = format!("127.0.0.1:{port}");
    let studio = start_with(
        &dir.path().join("vmc.faceanim.json"),
        &["--vmc-listen".as_ref(), listen.as_ref()],
    );
    let vmc = live_view;
    assert_eq!(vmc(&studio)["listening"], listen.as_str());
    record_live(&studio, true);
    // A sixth of a second lost on the way, as Wi-Fi loses datagrams: the frames after it keep
    // their time (kept one after another, they would come ten frames early).
    let sent = support::vmc_send(port, 300, 60.0, 0, 120..130, &dir.path().join("sent.json"));
    recorded(&studio, 290);
    let state = record_live(&studio, false);
    let take = &state["take"];
    assert_eq!(take["estimator"], "received");
    take_follows(&state, &sent, |frame| frame["yaw"].as_f64().unwrap(), 0.0);
    // A steady 60 fps from the first arrival.
    let (_, body) = request(studio.port, "GET", "/api/capture/session.json", &[], b"");
    let session: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(session["fps"], 60.0);
    for (k, frame) in session["frames"].as_array().unwrap().iter().enumerate() {
        let time = frame["time"].as_f64().unwrap();
        assert!(
            (time - k as f64 / 60.0).abs() < 1e-4,
            "frame {k} at {time} s"
        );
    }
    // It exports like any take.
    let (status, glb) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{glb}");
    let glb_path = dir.path().join("vmc.glb");
    let (_, glb) = support::get_with_head(studio.port, "/api/capture/export.glb");
    std::fs::write(&glb_path, glb).unwrap();
    assert_valid_gltf(&glb_path);

    // A flood of garbage: counted, dropped, and the next good frame still arrives.
    let before = vmc(&studio);
    support::vmc_send(port, 0, 60.0, 700, 0..0, &dir.path().join("garbage.json"));
    support::vmc_send(port, 1, 60.0, 0, 0..0, &dir.path().join("one.json"));
    let mut after = vmc(&studio);
    for _ in 0..100 {
        if after["frames"].as_u64() > before["frames"].as_u64() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        after = vmc(&studio);
    }
    assert_eq!(
        after["frames"].as_u64().unwrap(),
        before["frames"].as_u64().unwrap() + 1,
        "{after}"
    );
    for counter in ["malformed", "unknown", "oversized"] {
        assert!(
            after[counter].as_u64().unwrap() > 0,
            "no {counter} datagram was counted: {after}"
        );
    }
    // Loopback may lose a datagram of a burst in the kernel; what arrived was counted.
    let arrived = after["packets"].as_u64().unwrap() - before["packets"].as_u64().unwrap();
    assert!(
        arrived >= 630,
        "only {arrived} of 701 datagrams were counted: {after}"
    );
    assert_eq!(request(studio.port, "GET", "/api/state", &[], b"").0, 200);
}

/// VMC out: with `--vmc-send`, each live webcam frame's face goes to the marionette (an
/// independent python-osc receiver) as soon as it is tracked, in ARKit's names, and so does
/// each frame the page plays.
#[test]
fn the_live_webcam_face_goes_out_over_vmc() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("received.json");
    let (mut peer, port) = support::vmc_receiver(4, 60.0, &report);
    let to = format!("127.0.0.1:{port}");
    let studio = start_with(
        &dir.path().join("out.faceanim.json"),
        &[
            "--vmc-send".as_ref(),
            to.as_ref(),
            "--vmc-names".as_ref(),
            "arkit".as_ref(),
        ],
    );
    let open =
        faceanim_media::read_image(&faceanim_testdata::shared("images/ict-face-jawopen.png"))
            .unwrap();
    let (status, body) = request(studio.port, "POST", "/api/capture/live/start", &[], b"");
    assert_eq!(status, 200, "{body}");
    for _ in 0..3 {
        let result = live_frame(studio.port, open.width, open.height, &open.rgb);
        assert_eq!(result["found"], true, "{result}");
    }
    // A frame the page plays: the ICT head's weights with jawOpen at 0.3, the head turned 10°.
    let (_, body) = request(studio.port, "GET", "/api/character", &[], b"");
    let character: serde_json::Value = serde_json::from_str(&body).unwrap();
    let names = character["blendshapes"].as_array().unwrap();
    let mut weights = vec![0.0f32; names.len()];
    weights[names.iter().position(|n| n == "jawOpen").unwrap()] = 0.3;
    let json = [("Content-Type", "application/json")];
    let send = |frame: serde_json::Value| {
        let frame = frame.to_string();
        request(
            studio.port,
            "POST",
            "/api/capture/vmc/send",
            &json,
            frame.as_bytes(),
        )
    };
    let (status, body) = send(serde_json::json!({ "weights": weights, "head": [10.0, 0.0, 0.0] }));
    assert_eq!(status, 200, "{body}");
    let (status, body) = send(serde_json::json!({ "weights": [0.5] }));
    assert!(status == 400 && body.contains("weights"), "{status} {body}");
    let (status, body) = send(serde_json::json!({ "weights": weights, "jaw": 1.5 }));
    assert!(status == 400 && body.contains("jaw"), "{status} {body}");
    assert!(peer.wait().unwrap().success());
    let received: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let datagrams = received["datagrams"].as_array().unwrap();
    assert_eq!(datagrams.len(), 4, "{received}");
    let played = datagrams[3]["messages"].as_array().unwrap();
    assert!(
        played.iter().any(|m| m["address"] == "/VMC/Ext/Blend/Val"
            && m["args"][0][1] == "JawOpen"
            && (m["args"][1][1].as_f64().unwrap() - 0.3).abs() < 1e-6),
        "{played:?}"
    );
    // The 10° turn, half on the neck and half on the head.
    for bone in ["Neck", "Head"] {
        let pose = played
            .iter()
            .find(|m| m["address"] == "/VMC/Ext/Bone/Pos" && m["args"][0][1] == bone)
            .unwrap();
        let qy = pose["args"][5][1].as_f64().unwrap();
        assert!((qy + 2.5f64.to_radians().sin()).abs() < 1e-5, "{pose}");
    }
    let jaw: Vec<f64> = datagrams[0]["messages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["address"] == "/VMC/Ext/Blend/Val" && m["args"][0][1] == "JawOpen")
        .map(|m| m["args"][1][1].as_f64().unwrap())
        .collect();
    assert!(
        jaw.len() == 1 && jaw[0] > 0.4,
        "the open jaw went out as {jaw:?}"
    );
    assert!(
        datagrams[0]["messages"]
            .as_array()
            .unwrap()
            .iter()
            .any(|m| m["address"] == "/VMC/Ext/Bone/Pos")
    );
}

/// A photo becomes a take whose 0 → peak → 0 animation is what plays and exports, and its
/// length is set before export (undoably).
#[test]
fn a_photos_ramp_is_shown_and_set_before_export() {
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("photo.faceanim.json"));
    let json = [("Content-Type", "application/json")];
    let photo = faceanim_testdata::shared("images/ict-face-jawopen.png");
    let state = support::open_and_settle(studio.port, &photo);
    assert_eq!(state["take"]["frames"], 1, "{}", state["job"]);
    assert_eq!(state["take"]["still"], 30);
    assert_eq!(state["take"]["ramp"].as_array().unwrap().len(), 30);
    let (status, body) = request(
        studio.port,
        "PUT",
        "/api/capture/still",
        &json,
        br#"{"frames": 45}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["ramp"].as_array().unwrap().len(), 45);
    let (_, body) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    let clip: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        clip["frames"].as_array().unwrap().len(),
        45,
        "the export is what the page plays"
    );
    // A stroke drawn over the take is in the export, unless the take is asked for alone.
    let (_, body) = request(studio.port, "GET", "/api/character/anchors", &[], b"");
    let anchors: serde_json::Value = serde_json::from_str(&body).unwrap();
    let stroke =
        serde_json::json!({ "samples": straight_stroke(&anchors, "mouthSmile_L", 10, 0.5) });
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/strokes",
        &json,
        stroke.to_string().as_bytes(),
    );
    assert_eq!(status, 200, "{body}");
    let get_clip = |query: &str| -> serde_json::Value {
        let (status, body) = request(
            studio.port,
            "GET",
            &format!("/api/capture/export.json{query}"),
            &[],
            b"",
        );
        assert_eq!(status, 200, "{body}");
        serde_json::from_str(&body).unwrap()
    };
    let smile = |clip: &serde_json::Value| support::column(clip, "mouthSmile_L");
    let peak = |v: Vec<f64>| v.into_iter().fold(0.0, f64::max);
    assert!(
        peak(smile(&get_clip(""))) > peak(smile(&clip)) + 0.3,
        "the stroke is layered"
    );
    assert_eq!(get_clip("?sketch=false"), clip, "the take alone");
    let (status, body) = request(
        studio.port,
        "GET",
        "/api/capture/export.json?sketch=maybe",
        &[],
        b"",
    );
    assert_eq!(status, 400, "{body}");
    let (status, body) = request(
        studio.port,
        "PUT",
        "/api/capture/still",
        &json,
        br#"{"frames": 0}"#,
    );
    assert!(status == 400 && body.contains("still_frames"), "{body}");
    let (_, body) = request(studio.port, "POST", "/api/capture/undo", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["still"], 30, "{body}");
}

/// VMC out from playback: the page plays the sketch and the studio sends each shown frame to the
/// marionette (an independent python-osc receiver).
/// A stroke of `steps` straight steps over `seconds`, from the anchor of `name` (the vertex its
/// blendshape moves most, in `/api/character/anchors`) to where the blendshape takes it.
fn straight_stroke(
    anchors: &serde_json::Value,
    name: &str,
    steps: usize,
    seconds: f64,
) -> Vec<serde_json::Value> {
    let anchor = anchors
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == name)
        .unwrap_or_else(|| panic!("no anchor for {name}: {anchors}"));
    let point = |c: usize, i: usize| {
        let rest = anchor["rest"][c].as_f64().unwrap();
        let target = anchor["target"][c].as_f64().unwrap();
        rest + (target - rest) * i as f64 / steps as f64
    };
    (0..=steps)
        .map(|i| {
            let t = i as f64 * seconds / steps as f64;
            serde_json::json!({ "t": t, "p": [point(0, i), point(1, i), point(2, i)] })
        })
        .collect()
}

#[test]
fn the_page_plays_its_animation_out_over_vmc() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("played.json");
    let (mut peer, port) = support::vmc_receiver(5, 90.0, &report);
    let to = format!("127.0.0.1:{port}");
    let studio = start_on(
        None,
        &dir.path().join("play.faceanim.json"),
        &["--vmc-send".as_ref(), to.as_ref()],
    );
    // A jawOpen stroke of the built-in head, from the vertex it moves most to its target.
    let (_, body) = request(studio.port, "GET", "/api/character/anchors", &[], b"");
    let anchors: serde_json::Value = serde_json::from_str(&body).unwrap();
    let samples = straight_stroke(&anchors, "jawOpen", 10, 1.0);
    let stroke = serde_json::json!({ "samples": samples }).to_string();
    let json = [("Content-Type", "application/json")];
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/strokes",
        &json,
        stroke.as_bytes(),
    );
    assert_eq!(status, 200, "{body}");
    let measured = browser_script(
        "vmc-play-e2e.mjs",
        &studio,
        "",
        &output_dir("vmc-play"),
        &[],
    );
    // The transport bar says where the frames go, and how many went.
    let shown = measured["shown"].as_str().unwrap_or_default();
    assert!(
        shown.starts_with(&format!("VMC out → {to}: ")) && shown.ends_with(" frames sent"),
        "{measured}"
    );
    let jaw_values = support::vmc_values(&mut peer, &report, "jawOpen");
    assert!(
        jaw_values.iter().any(|&w| w > 0.05),
        "the played jawOpen never went out: {jaw_values:?}"
    );
    // And as the Jaw bone, turned down (about Unity's X) by jawOpen × 20°, as the webcam's goes.
    let jaw_bone = support::vmc_numbers(&mut peer, &report, "/VMC/Ext/Bone/Pos", "Jaw");
    let opened: Vec<f64> = jaw_bone
        .iter()
        .map(|pose| 2.0 * pose[3].asin().to_degrees())
        .collect();
    let widest = jaw_values.iter().copied().fold(0.0, f64::max);
    assert!(
        opened.iter().any(|d| (d - widest * 20.0).abs() < 0.01),
        "no Jaw bone went out at {widest} × 20°: {opened:?}"
    );
}

/// A full-body avatar in the studio (the ICT head on a skinned, textured body, built in code):
/// the default distances come from its head, so a stroke drawn through the API from the vertex
/// each of four blendshapes moves most to where weight 1 takes it picks that blendshape at
/// full weight, as on the bare head; the camera's box is the head; the GLB download is the
/// user's own file (every node kept) with the animation, while the page's view is one mesh.
#[test]
fn a_full_body_avatar_in_the_studio_api() {
    let dir = tempfile::tempdir().unwrap();
    let avatar = dir.path().join("avatar.glb");
    let bytes = faceanim_testdata::avatar::full_body_glb(
        faceanim_testdata::ict(),
        faceanim_testdata::avatar::VrmKind::None,
        &[],
    );
    std::fs::write(&avatar, &bytes).unwrap();
    let studio = start_on(Some(&avatar), &dir.path().join("avatar.faceanim.json"), &[]);
    let port = studio.port;
    let (_, body) = request(port, "GET", "/api/character", &[], b"");
    let character: serde_json::Value = serde_json::from_str(&body).unwrap();
    let height =
        |b: &serde_json::Value| b["max"][1].as_f64().unwrap() - b["min"][1].as_f64().unwrap();
    assert!(height(&character["bounds"]) > 1.5, "{character}");
    assert!(
        height(&character["head"]) < 0.5,
        "the camera frames the head: {character}"
    );
    let (_, body) = request(port, "GET", "/api/character/anchors", &[], b"");
    let anchors: serde_json::Value = serde_json::from_str(&body).unwrap();
    let json = [("Content-Type", "application/json")];
    for (k, name) in ["jawOpen", "eyeBlink_L", "mouthSmile_L", "browInnerUp_L"]
        .iter()
        .enumerate()
    {
        let samples = straight_stroke(&anchors, name, 20, 0.5);
        let stroke = serde_json::json!({ "samples": samples, "start_frame": 40 * k }).to_string();
        let (status, body) = request(port, "POST", "/api/strokes", &json, stroke.as_bytes());
        assert_eq!(status, 200, "{name}: {body}");
        let state: serde_json::Value = serde_json::from_str(&body).unwrap();
        let action = state["actions"].as_array().unwrap().last().unwrap();
        assert_eq!(action["sides"][0]["target"], *name, "{name}: {action}");
        assert!(
            action["sides"][0]["weight"].as_f64().unwrap() >= 0.8,
            "{name}: {action}"
        );
    }
    let (_, download) = support::get_with_head(port, "/api/export.glb");
    let nodes_in = |glb: &[u8]| {
        faceanim_testdata::glb::json(glb)["nodes"]
            .as_array()
            .unwrap()
            .len()
    };
    assert_eq!(
        nodes_in(&download),
        nodes_in(&bytes),
        "the download is the user's file"
    );
    let (_, view) = support::get_with_head(port, "/api/view.glb");
    let view = faceanim_testdata::glb::json(&view);
    assert_eq!(
        view["meshes"].as_array().unwrap().len(),
        1,
        "the page's view is one mesh"
    );
    // Skinned to the face's bones only: the mesh's node and its small skeleton.
    let joints: Vec<&str> = view["nodes"].as_array().unwrap()[1..]
        .iter()
        .map(|n| n["name"].as_str().unwrap())
        .collect();
    assert!(
        joints.contains(&"faceanim_head") && joints.iter().all(|n| n.starts_with("faceanim_")),
        "{joints:?}"
    );
}

/// The seed's own setting: an emulated Meta Quest 3 (npm iwer) in headless Chromium enters VR
/// on the ICT head (not the head the page is tuned on), draws strokes in the air with the right
/// trigger from the vertex each of three blendshapes moves most to its target (each picks that
/// blendshape at full weight and lasts as long as it was drawn, by the XRFrame clock), flicks
/// the left thumbstick four ways, grabs and moves the arrow, slides the sphere, navigates, drags
/// an action's start handle on the timeline panel, slides a setting and saves on the settings
/// panel, and a second, desktop page of the studio sees the strokes; no console errors.
///
/// Both pages open with `?fast`, the viewport for machines without a GPU, as this machine
/// should open them: a headset draws every frame twice, and SwiftShader on two cores drew the
/// morphing head at about 3 XR frames a second with the full renderer and 12 with this one
/// (the interactions are the same code either way; the full renderer is the desktop tests').
#[test]
fn immersive_sketching_in_an_emulated_headset() {
    assert!(
        repo().join("tools/node_modules/iwer").exists(),
        "iwer is not installed: run scripts/setup.sh"
    );
    let dir = tempfile::tempdir().unwrap();
    let studio = start(&dir.path().join("vr.faceanim.json"));
    let measured = browser_script(
        "xr-e2e.mjs",
        &studio,
        "?fast",
        &output_dir("studio-xr"),
        &["jawOpen,mouthSmile_L,eyeBlink_L".into()],
    );
    assert_eq!(measured["entered"], true, "{measured}");
    let strokes = measured["strokes"].as_array().unwrap();
    assert_eq!(strokes.len(), 3, "{measured}");
    for stroke in strokes {
        assert_eq!(stroke["target"], stroke["name"], "{measured}");
        assert!(stroke["weight"].as_f64().unwrap() >= 0.8, "{measured}");
        let (drawn, lasts) = (
            stroke["seconds"].as_f64().unwrap(),
            stroke["duration"].as_f64().unwrap(),
        );
        assert!((lasts - drawn).abs() <= 0.5 * drawn, "{measured}");
    }
    assert_eq!(measured["desktopSees"], 3, "{measured}");
    for step in ["flicks", "arrowMoved", "sphereSlid"] {
        assert_eq!(measured[step], true, "{step}: {measured}");
    }
    assert!(
        (measured["navigated"].as_f64().unwrap() - 0.1).abs() < 0.02,
        "{measured}"
    );
    // Dragging the first action's start handle on the timeline panel moved its start.
    let moved = measured["timelineStart"].as_array().unwrap();
    assert!(moved[1].as_f64() > moved[0].as_f64(), "{measured}");
    // The settings panel's pen-distance slider set the setting, and its Save wrote the project.
    let pen = measured["penDistance"].as_array().unwrap();
    assert!(pen[1].as_f64().is_some() && pen[1] != pen[0], "{measured}");
    assert_eq!(measured["saved"], true, "{measured}");
    assert!(dir.path().join("vr.faceanim.json").exists());
    assert!(
        measured["errors"].as_array().unwrap().is_empty(),
        "{measured}"
    );
    eprintln!(
        "XR: {} frames, page's frame handling {} ms (median of 100)",
        measured["frames"], measured["frameMs"]
    );
}

/// A VRM avatar's GLB download is its own VRM file with the animation, and is named `.vrm` (VRM
/// apps look for that ending); it keeps the VRM extension.
#[test]
fn a_vrm_avatars_download_is_a_vrm() {
    let dir = tempfile::tempdir().unwrap();
    let avatar = dir.path().join("avatar.vrm");
    std::fs::write(
        &avatar,
        faceanim_testdata::avatar::full_body_glb(
            faceanim_testdata::ict(),
            faceanim_testdata::avatar::VrmKind::V1,
            faceanim_testdata::avatar::ICT_EXPRESSIONS,
        ),
    )
    .unwrap();
    let studio = start_on(Some(&avatar), &dir.path().join("vrm.faceanim.json"), &[]);
    let (head, body) = support::get_with_head(studio.port, "/api/export.glb");
    let headers = head.to_ascii_lowercase();
    assert!(
        headers.contains("filename=\"vrm.faceanim.vrm\"")
            && headers.contains("filename*=utf-8''vrm.faceanim.vrm"),
        "{headers}"
    );
    let json = faceanim_testdata::glb::json(&body);
    assert!(json["extensions"]["VRMC_vrm"].is_object(), "still a VRM");
}

/// The neutral face: a take's is each part of the face at its calmest frame until the user
/// says which is neutral (kept with the take); live, Calibrate takes the next face, and a face held still
/// becomes the neutral on its own.
#[test]
fn the_neutral_face_of_a_take_and_of_the_live_webcam() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("jaw.mp4");
    // Open, then shut: the mouth is calmest in the shut frames.
    let jaw: Vec<f32> = (0..10).map(|i| 0.8 * (1.0 - i as f32 / 9.0)).collect();
    support::encode_h264(&video, 256, 24, &support::ict_jaw_frames(&jaw, 256));
    let project = dir.path().join("neutral.faceanim.json");
    let json = [("Content-Type", "application/json")];
    let studio = start(&project);
    let state = support::open_and_settle(studio.port, &video);
    let neutral = &state["take"]["neutral"];
    assert_eq!(neutral["chosen"], "automatic", "{neutral}");
    assert!(neutral["frame"].as_u64().unwrap() >= 7, "{neutral}");
    assert_eq!(neutral["frame"], neutral["parts"]["mouth"], "{neutral}");
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/capture/neutral",
        &json,
        br#"{"frame": 40}"#,
    );
    assert_eq!(status, 400);
    assert!(body.contains("frame 40 is past the end"), "{body}");
    let (status, body) = request(
        studio.port,
        "POST",
        "/api/capture/neutral",
        &json,
        br#"{"frame": 6}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        state["take"]["neutral"],
        serde_json::json!({"frame": 6, "chosen": "user",
            "parts": {"lids": 6, "gaze": 6, "brows": 6, "mouth": 6}})
    );
    drop(studio);
    let studio = start(&project);
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["take"]["neutral"]["frame"], 6, "kept with the take");

    // Live: the same still picture again and again is a face held still.
    let face = support::ict_jaw_frames(&[0.0], 256).remove(0);
    let frame = |port: u16| live_frame(port, 256, 256, &face);
    let (status, _) = request(studio.port, "POST", "/api/capture/live/calibrate", &[], b"");
    assert_eq!(status, 400, "calibrating needs live mode");
    request(studio.port, "POST", "/api/capture/live/start", &[], b"");
    let first = frame(studio.port);
    assert_eq!(first["found"], true, "{first}");
    assert!(first["neutral"].is_null(), "{first}");
    let mut automatic = None;
    // At most 400 frames: the face must stay still for 1.5 s of the studio's clock.
    for k in 0..400 {
        if frame(studio.port)["neutral"] == "automatic" {
            automatic = Some(k);
            break;
        }
    }
    assert!(automatic.is_some(), "a still face never became the neutral");
    let (_, body) = request(studio.port, "POST", "/api/capture/live/calibrate", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["live"]["calibrating"], true, "{body}");
    assert_eq!(frame(studio.port)["neutral"], "user");
    let (_, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["live"]["calibrating"], false, "{body}");
    assert_eq!(state["live"]["neutral"], "user", "{body}");
}

/// The studio on the ICT head listening to a Live Link Face phone on `port`, its settings
/// (the neutral) kept in `settings`, with `more` arguments.
fn start_with_live_link_face(
    project: &std::path::Path,
    port: u16,
    settings: &std::path::Path,
    more: &[&std::ffi::OsStr],
) -> Studio {
    let ict = faceanim_testdata::shared("characters/ict-face.glb");
    start_on_live_link_face(&ict, project, port, settings, more)
}

/// [`start_with_live_link_face`] on `character`.
fn start_on_live_link_face(
    character: &std::path::Path,
    project: &std::path::Path,
    port: u16,
    settings: &std::path::Path,
    more: &[&std::ffi::OsStr],
) -> Studio {
    let port = port.to_string();
    let mut arguments: Vec<&std::ffi::OsStr> = vec![
        "--phone".as_ref(),
        "live-link-face".as_ref(),
        "--phone-port".as_ref(),
        port.as_ref(),
        "--phone-settings".as_ref(),
        settings.as_os_str(),
    ];
    arguments.extend_from_slice(more);
    start_on(Some(character), project, &arguments)
}

/// `frames` of Live Link Face at 60 fps sent to `port` by PyPI's pylivelinkface
/// (`tools/livelinkface_send.py`); what was sent, with each frame's time (kept in `dir`).
fn send_live_link_face(port: u16, frames: usize, dir: &std::path::Path) -> serde_json::Value {
    let sent_path = dir.join("sent.json");
    support::succeeded(
        "livelinkface_send.py",
        Command::new("python3")
            .arg(repo().join("tools/livelinkface_send.py"))
            .args(["--to", &port.to_string(), "--frames", &frames.to_string()])
            .args(["--fps", "60", "--out"])
            .arg(&sent_path)
            .output()
            .expect("python3 with pylivelinkface (scripts/setup.sh installs it)"),
    );
    serde_json::from_slice(&std::fs::read(&sent_path).unwrap()).unwrap()
}

/// A phone tracker in its own protocol: PyPI's pylivelinkface (not faceanim's packet code)
/// plays ten seconds of Live Link Face at 60 fps to the studio (`--phone live-link-face`), which
/// shows it, records it as a take and sends every frame on over VMC as it arrives, to
/// python-osc standing in for a VTuber app: no frame is lost, and each frame's delay from
/// datagram in to VMC out is reported. The neutral the page's button takes is kept.
#[test]
fn a_live_link_face_phone_drives_the_studio_and_goes_out_over_vmc() {
    const FRAMES: usize = 600;
    let dir = tempfile::tempdir().unwrap();
    let port = support::free_udp_port();
    let (mut app, app_port) = support::vmc_receiver(FRAMES, 120.0, &dir.path().join("app.json"));
    let settings = dir.path().join("settings/phone.json");
    let studio = start_with_live_link_face(
        &dir.path().join("phone.faceanim.json"),
        port,
        &settings,
        &[
            "--vmc-send".as_ref(),
            format!("127.0.0.1:{app_port}").as_ref(),
            "--vmc-names".as_ref(),
            "arkit".as_ref(),
        ],
    );
    let neutral = |studio: &Studio| {
        let json = [("Content-Type", "application/json")];
        request(
            studio.port,
            "POST",
            "/api/capture/vmc/neutral",
            &json,
            b"{}",
        )
    };
    let view = live_view;
    let before = view(&studio);
    assert_eq!(before["source"], "Live Link Face");
    assert_eq!(before["listening"], format!("0.0.0.0:{port}"));
    assert_eq!(before["neutral"], false);
    // Neutral before any face: refused with the reason.
    let (status, body) = neutral(&studio);
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("no face has arrived"), "{body}");
    record_live(&studio, true);
    let sent = send_live_link_face(port, FRAMES, dir.path());
    let state = recorded(&studio, FRAMES);
    assert_eq!(state["packets"], FRAMES, "{state}");
    assert_eq!(state["frames"], FRAMES, "{state}");
    assert_eq!(
        state["malformed"].as_u64().unwrap() + state["foreign"].as_u64().unwrap(),
        0
    );
    let forwarded = &state["forwarded"];
    assert_eq!(forwarded["frames"], FRAMES, "{state}");
    assert_eq!(forwarded["dropped"], 0, "{state}");
    eprintln!(
        "{FRAMES} Live Link Face frames at 60 fps over {:.1} s: datagram in to VMC out median {:.3} ms, 95th percentile {:.3} ms",
        sent["seconds"].as_f64().unwrap(),
        forwarded["median_ms"].as_f64().unwrap(),
        forwarded["p95_ms"].as_f64().unwrap()
    );
    let capture = record_live(&studio, false);
    // The app's radians, in degrees.
    // pylivelinkface's frame numbers count milliseconds as frames (they go back every second):
    // the take goes by arrival, which loopback delays a little.
    take_follows(
        &capture,
        &sent,
        |frame| frame["values"]["HeadYaw"].as_f64().unwrap().to_degrees(),
        0.1,
    );
    // The VTuber app had every frame, as it arrived.
    assert!(app.wait().unwrap().success());
    let received: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("app.json")).unwrap()).unwrap();
    let applied: Vec<&serde_json::Value> = received["datagrams"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| {
            d["messages"]
                .as_array()
                .is_some_and(|m| m.iter().any(|m| m["address"] == "/VMC/Ext/Blend/Apply"))
        })
        .collect();
    assert_eq!(applied.len(), FRAMES);
    // Values that moved are sent (and every one on every 30th frame): the jaw of each frame
    // that sent one is the phone's.
    let mut jaws = 0;
    for (k, datagram) in applied.iter().enumerate() {
        let jaw = datagram["messages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["address"] == "/VMC/Ext/Blend/Val" && m["args"][0][1] == "JawOpen");
        if let Some(m) = jaw {
            let got = m["args"][1][1].as_f64().unwrap();
            let want = sent["frames"][k]["values"]["JawOpen"].as_f64().unwrap();
            assert!(
                (got - want).abs() < 1e-4,
                "frame {k}: JawOpen {got}, sent {want}"
            );
            jaws += 1;
        }
    }
    assert!(jaws > FRAMES / 2, "{jaws} frames sent the jaw");
    // And the jaw bone, for avatars that open their mouth with one: turned down as far as the
    // phone's JawOpen says, on every frame.
    for (k, datagram) in applied.iter().enumerate() {
        let bone = datagram["messages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["address"] == "/VMC/Ext/Bone/Pos" && m["args"][0][1] == "Jaw")
            .unwrap_or_else(|| panic!("frame {k} has no Jaw bone: {datagram}"));
        let w = bone["args"][7][1].as_f64().unwrap();
        let degrees = 2.0 * w.clamp(-1.0, 1.0).acos().to_degrees();
        let want = f64::from(faceanim_live::JAW_DEGREES)
            * sent["frames"][k]["values"]["JawOpen"].as_f64().unwrap();
        assert!(
            (degrees - want).abs() < 0.05,
            "frame {k}: the jaw bone turned {degrees:.3}°, for {want:.3}°"
        );
    }
    // Neutral: taken from the last face and kept for the next run.
    let (status, body) = neutral(&studio);
    assert_eq!(status, 200, "{body}");
    assert_eq!(view(&studio)["neutral"], true);
    let kept: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&settings).unwrap()).unwrap();
    assert_eq!(kept["head_unit"], "radians");
    let neutral_yaw = kept["neutral"]["head"][0].as_f64().unwrap();
    let last_yaw = sent["frames"][FRAMES - 1]["values"]["HeadYaw"]
        .as_f64()
        .unwrap()
        .to_degrees();
    assert!((neutral_yaw - last_yaw).abs() < 1e-3);
}

/// A Live Link Face phone (pylivelinkface) recorded onto a body with no blendshapes (the
/// Blender avatar exported without shape keys): the take keeps the phone's ARKit values, so the
/// body's jaw bone opens as far as the phone's JawOpen says at every frame of the take and its
/// Clip JSON holds them. The recording kept only the head before: the jaw stayed shut.
#[test]
fn a_phone_recorded_onto_a_body_with_no_shapes_opens_its_jaw() {
    const FRAMES: usize = 120;
    let dir = tempfile::tempdir().unwrap();
    let port = support::free_udp_port();
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let project = dir.path().join("bare.faceanim.json");
    let settings = dir.path().join("phone.json");
    let studio = start_on_live_link_face(&bare, &project, port, &settings, &[]);
    record_live(&studio, true);
    let sent = send_live_link_face(port, FRAMES, dir.path());
    assert_eq!(recorded(&studio, FRAMES)["recording"], FRAMES);
    jaw_follows_what_was_sent(&studio, &sent);
}

/// A VMC tracker naming ARKit's channels ("perfect sync", python-osc standing in) recorded
/// onto the same body: as a phone's, its JawOpen opens the take's jaw bone at every frame and
/// its Clip JSON holds the values; the gaze it sends as eye bones (Unity's convention, written
/// by the peer itself) is the take's eyeLook values. The marionette kept ARKit values from
/// phones alone and read no eye bones before: the jaw stayed shut and the eyes still.
#[test]
fn a_vmc_tracker_recorded_onto_a_body_with_no_shapes_opens_its_jaw_and_turns_its_eyes() {
    let dir = tempfile::tempdir().unwrap();
    let (studio, sent) = bare_body_recording(dir.path(), support::vmc_send_arkit);
    jaw_follows_what_was_sent(&studio, &sent);
    // Each frame of the take's Clip JSON looks where the eye bones sent around its time did.
    let (_, clip) = support::get_with_head(studio.port, "/api/capture/export.json");
    let clip: serde_json::Value = serde_json::from_slice(&clip).unwrap();
    let names = support::strings(&clip["blendshapes"]);
    let column = |name: &str| {
        let found = names.iter().position(|n| n == name);
        found.unwrap_or_else(|| panic!("no {name} in the take's Clip JSON: {names:?}"))
    };
    let fps = clip["fps"].as_f64().unwrap();
    let range = faceanim_rig::bones::EYE_RANGE.map(f64::from);
    let sent = sent["frames"].as_array().unwrap();
    let mut widest: f64 = 0.0;
    for (k, row) in clip["frames"].as_array().unwrap().iter().enumerate() {
        let value = |name: &str| row[column(name)].as_f64().unwrap();
        let looked = [
            (value("eyeLookOutLeft") - value("eyeLookInLeft")) * range[0],
            (value("eyeLookUpLeft") - value("eyeLookDownLeft")) * range[1],
        ];
        let t = k as f64 / fps;
        for (axis, got) in looked.into_iter().enumerate() {
            let (low, high) = sent_around(sent, t, |f| f["eyes"][axis].as_f64().unwrap());
            assert!(
                low - 0.05 <= got && got <= high + 0.05,
                "take frame {k} at {t:.3} s: the left eye at {got:.2}° on axis {axis}, the bones said {low:.2}° to {high:.2}°"
            );
        }
        widest = widest.max(looked[0].abs());
    }
    assert!(widest > 19.0, "the eyes turned at most {widest}°");
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    played_out_over_vmc(studio, &bare, &dir.path().join("bare.faceanim.json"));
}

/// The frames of a VMC tracker (python-osc: `send` to a port, a frame count, a rate and where
/// it writes what it sent) recorded at 60 Hz onto the Blender-exported body with no shape keys,
/// by a studio with its project in `dir`: the studio, still recording, and what was sent.
fn bare_body_recording(
    dir: &std::path::Path,
    send: fn(u16, usize, f32, &std::path::Path) -> serde_json::Value,
) -> (Studio, serde_json::Value) {
    const FRAMES: usize = 120;
    let port = support::free_udp_port();
    let listen = format!("127.0.0.1:{port}");
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let studio = start_on(
        Some(&bare),
        &dir.join("bare.faceanim.json"),
        &["--vmc-listen".as_ref(), listen.as_ref()],
    );
    record_live(&studio, true);
    let sent = send(port, FRAMES, 60.0, &dir.join("sent.json"));
    // Loopback may drop a datagram: what arrived is recorded.
    assert!(recorded(&studio, FRAMES)["recording"].as_u64() > Some(100));
    (studio, sent)
}

/// The take `studio` recorded on `bare` (no shapes), reopened from its autosave by a studio
/// that sends VMC, played by the page in a real browser: every frame goes out with the take's
/// gaze and jaw as `LeftEye`, `RightEye` and `Jaw` bones. The page sent nothing before for a
/// character without morph targets, and the weights it sent carried no gaze for one whose
/// shapes have none.
fn played_out_over_vmc(studio: Studio, bare: &std::path::Path, project: &std::path::Path) {
    const PLAYED: usize = 20;
    // The take's gaze and jaw, from its Clip JSON's ARKit values.
    let (_, clip) = support::get_with_head(studio.port, "/api/capture/export.json");
    let clip: serde_json::Value = serde_json::from_slice(&clip).unwrap();
    let names = support::strings(&clip["blendshapes"]);
    let range = faceanim_rig::bones::EYE_RANGE.map(f64::from);
    let opened = f64::from(faceanim_export::bones::DEFAULT_JAW_DEGREES);
    let taken: Vec<[f64; 3]> = clip["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            let value = |name: &str| {
                let c = names.iter().position(|n| n == name).unwrap();
                row[c].as_f64().unwrap()
            };
            [
                (value("eyeLookOutLeft") - value("eyeLookInLeft")) * range[0],
                (value("eyeLookUpLeft") - value("eyeLookDownLeft")) * range[1],
                value("jawOpen") * opened,
            ]
        })
        .collect();
    drop(studio);
    let report = project.with_file_name("played.json");
    let (mut peer, port) = support::vmc_receiver(PLAYED, 90.0, &report);
    let to = format!("127.0.0.1:{port}");
    let send: [&std::ffi::OsStr; 4] = [
        "--vmc-send".as_ref(),
        to.as_ref(),
        "--vmc-names".as_ref(),
        "arkit".as_ref(),
    ];
    let studio = start_on(Some(bare), project, &send);
    let measured = browser_script(
        "vmc-play-e2e.mjs",
        &studio,
        "",
        &output_dir("vmc-play-bare"),
        &["take".into(), PLAYED.to_string().into()],
    );
    assert!(
        measured["frames_sent"].as_u64() >= Some(PLAYED as u64),
        "{measured}"
    );
    // Each bone as VMC sends it (Unity's frame): an eye turned by yaw then pitch is
    // (-cos y·sin p, -sin y·cos p, -sin y·sin p, cos y·cos p) of the half angles.
    let left = support::vmc_numbers(&mut peer, &report, "/VMC/Ext/Bone/Pos", "LeftEye");
    let jaws = support::vmc_numbers(&mut peer, &report, "/VMC/Ext/Bone/Pos", "Jaw");
    assert!(
        left.len() >= PLAYED && jaws.len() >= PLAYED,
        "{} LeftEye and {} Jaw bones went out for {PLAYED} frames",
        left.len(),
        jaws.len()
    );
    let degrees = |half: f64| 2.0 * half.to_degrees();
    let mut widest: f64 = 0.0;
    for pose in &left {
        let (x, y, w) = (pose[3], pose[4], pose[6]);
        let looked = [degrees((-y).atan2(w)), degrees((-x).atan2(w))];
        assert!(
            taken
                .iter()
                .any(|t| (t[0] - looked[0]).abs() < 0.05 && (t[1] - looked[1]).abs() < 0.05),
            "a LeftEye bone at {looked:?}° is no frame's gaze of the take"
        );
        widest = widest.max(looked[1].abs());
    }
    assert!(widest > 5.0, "the eyes went out turned at most {widest}°");
    for pose in &jaws {
        let turned = degrees(pose[3].asin());
        assert!(
            taken.iter().any(|t| (t[2] - turned).abs() < 0.05),
            "a Jaw bone turned {turned}° is no frame's jawOpen × {opened}° of the take"
        );
    }
    // In ARKit's names the take's own values go out (the body has no shapes to make them):
    // each frame's JawOpen is its Jaw bone's turn.
    let by_name = support::vmc_jaw_pairs(&report);
    assert!(
        by_name.len() >= PLAYED / 2,
        "JawOpen went out in {} frames",
        by_name.len()
    );
    for (value, turned) in by_name {
        assert!(
            (value * opened - turned).abs() < 0.01,
            "JawOpen {value} went out with the Jaw bone turned {turned}°"
        );
    }
}

/// What VSeeFace and VMagicMirror send without perfect sync, VRM's presets (python-osc
/// standing in: `A`, `Blink`, `Joy`), recorded onto the body with no shapes: `A` opens the
/// take's jaw bone at every frame, as `JawOpen` does. Presets drove nothing on a character
/// without shapes of those names before. `Blink` and `Joy`, which nothing on the body takes,
/// are named as such in the live link's state (the Capture tab shows them); `A` is not.
#[test]
fn a_vmc_tracker_sending_vrm_presets_opens_the_jaw_of_a_body_with_no_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let (studio, sent) = bare_body_recording(dir.path(), support::vmc_send_vrm_presets);
    // The presets nothing on the body takes are named for the page; `A`, which its jaw bone
    // shows, is not.
    let state = live_view(&studio);
    let mut lost = support::strings(&state["unmatched_names"]);
    lost.sort();
    assert_eq!(lost, ["Blink", "Joy"], "{state}");
    jaw_follows(&studio, &sent, "A");
}

/// Stops `studio`'s recording and checks that each take frame's jaw (the view skeleton's last
/// joint, turned from the head) opened as far as the `JawOpen` `sent` around its time (a tenth
/// of a second either side: the take goes by arrival), widest over 90 % of the jaw's range, and
/// that the take's Clip JSON holds jawOpen.
fn jaw_follows_what_was_sent(studio: &Studio, sent: &serde_json::Value) {
    jaw_follows(studio, sent, "JawOpen");
}

/// [`jaw_follows_what_was_sent`], the jaw sent under the name `sent_as`.
fn jaw_follows(studio: &Studio, sent: &serde_json::Value, sent_as: &str) {
    let capture = record_live(studio, false);
    let take = &capture["take"];
    let fps = take["fps"].as_f64().unwrap();
    let bones = take["bones"].as_array().unwrap();
    let sent = sent["frames"].as_array().unwrap();
    let degrees = f64::from(faceanim_export::bones::DEFAULT_JAW_DEGREES);
    let mut widest: f64 = 0.0;
    for (k, joints) in bones.iter().enumerate() {
        let joints = joints.as_array().unwrap();
        let jaw = glam::Quat::from_slice(&support::f32s(joints.last().unwrap()));
        let opened = f64::from(jaw.angle_between(glam::Quat::IDENTITY).to_degrees());
        let t = k as f64 / fps;
        let (low, high) = sent_around(sent, t, |f| {
            f["values"][sent_as].as_f64().unwrap() * degrees
        });
        assert!(
            low - 0.05 <= opened && opened <= high + 0.05,
            "take frame {k} at {t:.3} s: the jaw {opened:.2}° open, the sender said {low:.2}° to {high:.2}°"
        );
        widest = widest.max(opened);
    }
    assert!(widest > 0.9 * degrees, "the jaw opened at most {widest}°");
    // The take's Clip JSON holds the sender's ARKit values, which its bones follow.
    let (_, clip) = support::get_with_head(studio.port, "/api/capture/export.json");
    let clip: serde_json::Value = serde_json::from_slice(&clip).unwrap();
    let names = support::strings(&clip["blendshapes"]);
    assert!(names.iter().any(|n| n == "jawOpen"), "{names:?}");
}

/// The lowest and highest `value` of the `sent` frames around `t` seconds after the first:
/// those within a tenth of a second either side (the take goes by arrival where the sender's
/// clock is not sound), and the last sent before `t` and the first after it, which a take frame
/// blends however far apart a stalled sender put them.
fn sent_around(
    sent: &[serde_json::Value],
    t: f64,
    value: impl Fn(&serde_json::Value) -> f64,
) -> (f64, f64) {
    let start = sent[0]["time"].as_f64().unwrap();
    let at = |f: &serde_json::Value| f["time"].as_f64().unwrap() - start;
    let before = sent.iter().rev().find(|f| at(f) <= t);
    let after = sent.iter().find(|f| at(f) >= t);
    let near = sent.iter().filter(|f| (at(f) - t).abs() <= 0.1);
    near.chain(before)
        .chain(after)
        .map(value)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), v| {
            (low.min(v), high.max(v))
        })
}

/// The Capture tab's phone panel in a real browser (`tools/phone-panel-e2e.mjs`): it says what
/// the studio listens to and where the phone should send; live, a Live Link Face phone
/// (pylivelinkface) moves the character's mouth in the viewport while the panel counts its
/// packets per second and the age of the last one; Neutral is taken and kept.
#[test]
fn the_phone_panel_in_a_real_browser() {
    let dir = tempfile::tempdir().unwrap();
    let port = support::free_udp_port();
    let settings = dir.path().join("settings/phone.json");
    let studio = start_with_live_link_face(
        &dir.path().join("panel.faceanim.json"),
        port,
        &settings,
        &[],
    );
    let measured = browser_script(
        "phone-panel-e2e.mjs",
        &studio,
        "",
        &output_dir("phone-panel"),
        &[
            port.to_string().into(),
            repo().join("tools/livelinkface_send.py").into(),
        ],
    );
    eprintln!("the phone panel: {measured}");
    // The neutral the page took is kept for the next run.
    let kept: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&settings).unwrap()).unwrap();
    assert!(kept["neutral"].is_object(), "{kept}");
}

/// iFacialMocap from the command line: the studio sends the app's handshake to the phone
/// address given, and the phone's text frames (written here from the published grammar, as
/// MeowFace sends them) drive the character; a protocol that must ask the phone without its
/// address is refused with what to give.
#[test]
fn an_ifacialmocap_phone_is_asked_and_drives_the_studio() {
    let dir = tempfile::tempdir().unwrap();
    let refused = support::faceanim(&["studio", "--port", "0", "--phone", "vtube-studio"]);
    assert!(!refused.status.success());
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(said.contains("--phone-address"), "{said}");

    let phone = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    phone
        .set_read_timeout(Some(std::time::Duration::from_secs(20)))
        .unwrap();
    let port = support::free_udp_port();
    let address = phone.local_addr().unwrap().to_string();
    // On a full-body avatar (Blender's): the phone's head turns its spine, neck and head.
    let studio = start_on(
        Some(&faceanim_testdata::producers::blender_avatar_path()),
        &dir.path().join("ifm.faceanim.json"),
        &[
            "--phone".as_ref(),
            "ifacialmocap".as_ref(),
            "--phone-address".as_ref(),
            address.as_ref(),
            "--phone-port".as_ref(),
            port.to_string().as_ref(),
            "--phone-settings".as_ref(),
            dir.path().join("phone.json").as_os_str(),
        ],
    );
    let mut buffer = [0u8; 512];
    let (length, studio_side) = phone.recv_from(&mut buffer).unwrap();
    let handshake = String::from_utf8_lossy(&buffer[..length]);
    assert!(handshake.starts_with("iFacialMocap_"), "{handshake}");
    assert_eq!(
        studio_side.port(),
        port,
        "the studio asks from the port it listens on"
    );
    for k in 0..30 {
        let frame = format!(
            "jawOpen&{}|eyeBlink_L&{}|=head#0,{},0,0,0,0|",
            k * 2,
            if k % 10 < 3 { 100 } else { 0 },
            k
        );
        phone.send_to(frame.as_bytes(), studio_side).unwrap();
    }
    let state = live_view_at(&studio, "frames", 30);
    assert_eq!(state["source"], "iFacialMocap");
    assert_eq!(state["phone"], address.as_str());
    assert_eq!(state["frames"], 30, "{state}");
    let names = support::strings(&live_view_names(&studio));
    let jaw = names.iter().position(|n| n == "jawOpen").unwrap();
    assert!(
        (state["weights"][jaw].as_f64().unwrap() - 0.58).abs() < 1e-6,
        "{state}"
    );
    assert!(
        (state["head"][0].as_f64().unwrap() - 29.0).abs() < 1e-4,
        "{state}"
    );
    // The view's bones (rest, head, neck, upper spine, eyes, jaw): spine, neck and head share the
    // 29° turn as the export shares it, and the jaw opens with jawOpen.
    let bone = |k: usize| glam::Quat::from_slice(&support::f32s(&state["bones"][k]));
    let [head, neck, spine, jaw] = [1, 2, 3, 6].map(bone);
    let whole = spine * neck * head;
    let asked = glam::Quat::from_rotation_y(29f32.to_radians());
    assert!(whole.angle_between(asked) < 1e-3, "{state}");
    let yaw = |q: glam::Quat| q.to_euler(glam::EulerRot::YXZ).0.to_degrees();
    assert!((yaw(spine) - 0.2 * 29.0).abs() < 1e-2, "{state}");
    assert!((yaw(neck) - yaw(head)).abs() < 1e-2, "{state}");
    assert!(
        jaw.angle_between(glam::Quat::IDENTITY) > 1f32.to_radians(),
        "{state}"
    );
}

/// The character's blendshape names, as the capture state lists them.
fn live_view_names(studio: &Studio) -> serde_json::Value {
    let (status, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    assert_eq!(status, 200, "{body}");
    serde_json::from_str::<serde_json::Value>(&body).unwrap()["blendshapes"].clone()
}

/// A face the face model cannot read, marked by hand in a real browser
/// (`tools/face-marks-e2e.mjs`): an ICT head (identity 48) with its shapes renamed so its rig
/// needs a map, upside down (a file written Z-up) so that no face is found on it. Making the map
/// says so and asks for the marks; ten clicks (and an undo) later the map is made from them,
/// and the marks are kept beside the character where a user clicked them. Two photos are then
/// read through that map, and the page lets the user choose the neutral face they are read
/// against.
#[test]
fn a_face_is_marked_by_hand_when_none_is_found() {
    use faceanim_fit::{FaceLandmarks, FacePoint};
    let dir = tempfile::tempdir().unwrap();
    let original = faceanim_testdata::ict_identity("ict-face-id48.glb");
    let flip = glam::Quat::from_rotation_z(std::f32::consts::PI);
    let mut parts = original.to_parts();
    parts.name = "upside-down".into();
    parts.positions = parts.positions.iter().map(|p| flip * *p).collect();
    parts.normals = None;
    parts.normal_deltas = None;
    parts.blendshapes = support::renamed_shapes(&parts.blendshapes, flip);
    let head = faceanim_rig::Character::new(parts).unwrap();
    let path = dir.path().join("upside-down.glb");
    std::fs::write(&path, faceanim_export::view_glb(&head, None).unwrap()).unwrap();
    // Where a user would click: MediaPipe's points on the head the right way up, turned.
    let models = faceanim_track::FaceModels::load().unwrap();
    let found = FaceLandmarks::find(original, &models).unwrap();
    let points: serde_json::Map<String, serde_json::Value> = FacePoint::ALL
        .iter()
        .map(|p| {
            let at = found.points[p.landmark()]
                .unwrap()
                .on(original.triangles(), original.positions());
            (
                p.key().to_owned(),
                serde_json::json!((flip * at).to_array()),
            )
        })
        .collect();
    let studio = start_on(Some(&path), &dir.path().join("marks.faceanim.json"), &[]);
    let measured = browser_script(
        "face-marks-e2e.mjs",
        &studio,
        "",
        &output_dir("face-marks"),
        &[
            serde_json::Value::Object(points.clone()).to_string().into(),
            serde_json::json!(
                ["neutral", "smile"]
                    .map(|p| faceanim_testdata::shared(&format!("images/ict-face-{p}.png")))
            )
            .to_string()
            .into(),
        ],
    );
    eprintln!("marked by hand: {measured}");
    assert!(
        measured["geometry_rows"].as_u64().unwrap() >= 40,
        "{measured}"
    );
    // Kept beside the character, each within 2 % of the eyes' span of where it was clicked.
    let kept = faceanim_fit::FacePoints::from_json(
        &std::fs::read(dir.path().join("upside-down.face-points.json")).unwrap(),
    )
    .unwrap();
    let given = |p: FacePoint| {
        let v = &points[p.key()];
        glam::Vec3::from_array(std::array::from_fn(|i| v[i].as_f64().unwrap() as f32))
    };
    let span = given(FacePoint::RightEyeOuter).distance(given(FacePoint::LeftEyeOuter));
    for p in FacePoint::ALL {
        let off = kept.at(p).distance(given(p));
        assert!(off < 0.02 * span, "{}: {off} from the click", p.key());
    }
}

/// The face's bones in the studio's view, in a real browser (`tools/bones-view-e2e.mjs`): the
/// Blender avatar with a take that turns the head, looks aside and opens the jaw (exported into
/// the file, opened by `faceanim studio` on it); the view is skinned to spine, neck, head, eyes
/// and jaw, each turned as the take's `bones` say, on the GPU path and with `?fast`; a jawOpen
/// stroke turns the jaw joint in the Sketch tab.
#[test]
fn the_studio_turns_neck_head_eyes_and_jaw_on_the_avatars_bones() {
    let dir = tempfile::tempdir().unwrap();
    let avatar = faceanim_testdata::producers::blender_avatar_path();
    let frames = 6;
    let clip = serde_json::json!({
        "fps": 30,
        "blendshapes": ["eyeLookOutLeft", "eyeLookInRight", "jawOpen"],
        "frames": (0..frames).map(|f| { let t = f as f64 / (frames - 1) as f64; vec![t, t, 0.8 * t] }).collect::<Vec<_>>(),
        "head": (0..frames).map(|f| { let t = f as f64 / (frames - 1) as f64; [30.0 * t, -10.0 * t, 5.0 * t] }).collect::<Vec<_>>(),
    });
    let clip_path = dir.path().join("turn.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    let take = dir.path().join("turn.glb");
    support::export_with_clip(&avatar, &take, &clip_path);
    let studio = start_on(Some(&take), &dir.path().join("project"), &[]);
    let (status, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    let bones = state["take"]["bones"]
        .as_array()
        .unwrap_or_else(|| panic!("no bones: {}", state["take"]));
    assert_eq!(bones.len(), frames, "one pose per frame");
    // A sketch on top: one jawOpen stroke (its jaw joint shows in the Sketch tab).
    let character = faceanim_testdata::producers::blender_avatar_character();
    let stroke = support::stroke_along(&character, "jawOpen", 30, 1.0 / 60.0);
    let (status, body) = request(studio.port, "POST", "/api/strokes", &[], stroke.as_bytes());
    assert_eq!(status, 200, "{body}");
    // The skinned view (with the stroke's jaw on its joint) is valid glTF (the Khronos validator: no joint listed without a share).
    let (status, view) = support::request_bytes(studio.port, "GET", "/api/view.glb", &[], b"");
    assert_eq!(status, 200);
    let view_path = dir.path().join("view.glb");
    std::fs::write(&view_path, view).unwrap();
    let report = assert_valid_gltf(&view_path);
    let joint_warnings = report["issues"]["messages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["code"] == "ACCESSOR_JOINTS_USED_ZERO_WEIGHT")
        .count();
    assert_eq!(joint_warnings, 0, "joints listed without a share");
    let measured = browser_script(
        "bones-view-e2e.mjs",
        &studio,
        "",
        &output_dir("bones-view"),
        &[(frames - 1).to_string().into(), "40".into()],
    );
    eprintln!("the face's bones in the view: {measured}");
}

/// The ICT head with every shape renamed `shape_N` (names that say nothing), written as
/// `unnamed.glb` in `dir`; with the index of the shape that is ICT's jawOpen.
fn unnamed_ict(dir: &std::path::Path) -> (std::path::PathBuf, usize) {
    let mut parts = faceanim_testdata::ict().to_parts();
    let jaw = parts
        .blendshapes
        .iter()
        .position(|b| b.name() == "jawOpen")
        .unwrap();
    parts.blendshapes = support::renamed_shapes(&parts.blendshapes, glam::Quat::IDENTITY);
    let character = faceanim_rig::Character::new(parts).unwrap();
    let glb = dir.join("unnamed.glb");
    std::fs::write(&glb, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    (glb, jaw)
}

/// The live webcam on the ICT head with names that say nothing ([`unnamed_ict`]): starting it
/// makes the rig's retarget map (a job the page shows), and once the map is there the same
/// open-mouthed frame opens the shape that is ICT's jawOpen.
#[test]
fn the_live_webcam_on_a_rig_whose_names_say_nothing_goes_through_the_map_made_when_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    let (glb, jaw) = unnamed_ict(dir.path());
    let studio = start_on(Some(&glb), &dir.path().join("unnamed.faceanim.json"), &[]);
    let open =
        faceanim_media::read_image(&faceanim_testdata::shared("images/ict-face-jawopen.png"))
            .unwrap();
    let (status, body) = request(studio.port, "POST", "/api/capture/live/start", &[], b"");
    let state = support::map_made(studio.port, status, &body);
    assert_eq!(state["retarget"]["in_use"], true, "{}", state["retarget"]);
    assert!(dir.path().join("unnamed.retarget.json").exists());
    let result = live_frame(studio.port, open.width, open.height, &open.rgb);
    assert_eq!(result["found"], true, "{result}");
    let opened = support::f32s(&result["weights"])[jaw];
    assert!(opened > 0.2, "shape_{jaw} (ICT's jawOpen) at {opened}");
}

/// A Live Link Face phone listened to (`--phone live-link-face`) for the ICT head with names
/// that say nothing ([`unnamed_ict`]): the studio makes the rig's retarget map when it starts,
/// and then what pylivelinkface sends (JawOpen, EyeBlinkLeft, MouthSmileLeft) reaches its
/// shapes: nothing is listed as reaching nothing.
#[test]
fn a_phone_listened_to_for_a_rig_whose_names_say_nothing_goes_through_the_map_made_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let (glb, _) = unnamed_ict(dir.path());
    let port = support::free_udp_port();
    let studio = start_on_live_link_face(
        &glb,
        &dir.path().join("unnamed.faceanim.json"),
        port,
        &dir.path().join("phone.json"),
        &[],
    );
    let (status, body) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state = support::map_made(studio.port, status, &body);
    assert_eq!(state["retarget"]["in_use"], true, "{}", state["retarget"]);
    send_live_link_face(port, 60, dir.path());
    let view = live_view_at(&studio, "frames", 60);
    assert_eq!(view["frames"], 60, "{view}");
    assert_eq!(view["unmatched"], 0, "{view}");
    assert_eq!(view["unmatched_names"], serde_json::json!([]), "{view}");
}

/// Blender's remeshed full body copied into `dir` as `body.glb` (the studio saves the map
/// beside the character: never beside the shared fixture).
fn remeshed_body(dir: &std::path::Path) -> std::path::PathBuf {
    let avatar = dir.join("body.glb");
    std::fs::copy(
        faceanim_testdata::producers::blender_remeshed_avatar_path(),
        &avatar,
    )
    .unwrap();
    avatar
}

/// A retarget map beside the character that cannot be read (a user's edit gone wrong) is never
/// written over unasked: a Live Link Face recording opened on the rig goes on by name, the
/// notice of the map says why it is not used, and the file is as it was.
#[test]
fn a_broken_map_beside_the_character_is_not_written_over_by_a_clip() {
    let dir = tempfile::tempdir().unwrap();
    let avatar = remeshed_body(dir.path());
    let broken = dir.path().join("body.retarget.json");
    let mine = br#"{"character": "body", "rows": [ oops"#;
    std::fs::write(&broken, mine).unwrap();
    let studio = start_on(Some(&avatar), &dir.path().join("project.json"), &[]);
    let puff = faceanim_anim::Clip::of_weights(
        30.0,
        &["CheekPuff", "EyeBlinkLeft"],
        vec![vec![0.0, 0.0], vec![0.8, 1.0]],
    );
    let csv = faceanim_export::livelink::to_csv(&puff);
    let (status, body) = support::upload(studio.port, "puff.csv", csv.as_bytes());
    assert_eq!(status, 200, "{body}");
    let state: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert!(state["job"].is_null(), "{}", state["job"]);
    assert_eq!(state["take"]["frames"], 2, "{}", state["take"]);
    let note = state["retarget"]["note"].as_str().unwrap_or_default();
    assert!(
        note.contains("body.retarget.json") && note.contains("Make map writes a new one"),
        "{}",
        state["retarget"]
    );
    assert_eq!(std::fs::read(&broken).unwrap(), mine);
}

/// A Live Link Face recording opened in the studio on Blender's remeshed full body, whose
/// VRoid-style names leave ARKit channels without a shape and whose eyes are bones with no
/// eyeLook shapes: the character's retarget map is made first (as `faceanim export --clip`
/// makes it), its pucker reaches the mouth through it; its gaze turns the eye bones as the
/// recording's export turns them (`BoneKeys::from_clip`), and the notice does not list the
/// eyeLook channels as left out.
#[test]
fn a_recordings_gaze_turns_the_eye_bones_of_a_body_without_eyelook_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let avatar = remeshed_body(dir.path());
    let character = faceanim_files::load_character(&avatar).unwrap().character;
    let frames = 6;
    let ramp = |f: usize, top: f32| top * f as f32 / (frames - 1) as f32;
    let gaze = faceanim_anim::Clip::of_weights(
        30.0,
        &[
            "EyeLookOutLeft",
            "EyeLookInRight",
            "EyeLookUpLeft",
            "EyeBlinkLeft",
            "MouthPucker",
        ],
        (0..frames)
            .map(|f| {
                vec![
                    ramp(f, 0.9),
                    ramp(f, 0.9),
                    ramp(f, 0.4),
                    ramp(f, 1.0),
                    ramp(f, 0.8),
                ]
            })
            .collect(),
    );
    let studio = start_on(Some(&avatar), &dir.path().join("project.json"), &[]);
    let csv = faceanim_export::livelink::to_csv(&gaze);
    let (status, body) = support::upload(studio.port, "gaze.csv", csv.as_bytes());
    let state = support::map_made(studio.port, status, &body);
    assert_eq!(state["retarget"]["in_use"], true, "{}", state["retarget"]);
    assert!(
        dir.path().join("body.retarget.json").exists(),
        "{}",
        state["retarget"]
    );
    // The pucker reaches the shapes of its row of the map.
    let rows = state["retarget"]["rows"].as_array().unwrap();
    let pucker = rows.iter().find(|r| r["channel"] == "mouthPucker").unwrap();
    let shapes: Vec<&str> = pucker["shapes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|pair| pair[0].as_str())
        .collect();
    assert!(!shapes.is_empty(), "{pucker}");
    let names = support::strings(&state["blendshapes"]);
    let last = support::f32s(&state["take"]["weights"][frames - 1]);
    let reached = shapes.iter().any(|shape| {
        names
            .iter()
            .position(|n| n == shape)
            .is_some_and(|k| last[k] > 0.1)
    });
    assert!(reached, "{pucker}: {names:?} {last:?}");
    let notice = state["notice"].as_str().unwrap_or_default();
    assert!(
        !notice.contains("eyeLook") && !notice.contains("EyeLook"),
        "{notice}"
    );
    let bones = state["take"]["bones"]
        .as_array()
        .unwrap_or_else(|| panic!("no bones: {}", state["take"]));
    assert_eq!(bones.len(), frames, "one pose per frame");

    // The export's rule on the same values: the view's eye joints turn so at every frame.
    let skeleton = faceanim_export::bones::ViewRig::of(&character, None).unwrap();
    let keys = faceanim_export::bones::BoneKeys::from_clip(&gaze);
    let want = skeleton.poses(gaze.fps, &vec![None; frames], &keys);
    let eyes: Vec<usize> = (0..skeleton.joints.len())
        .filter(|&j| {
            matches!(
                skeleton.joints[j].bone,
                Some(faceanim_rig::bones::Bone::LeftEye | faceanim_rig::bones::Bone::RightEye)
            )
        })
        .collect();
    assert_eq!(eyes.len(), 2, "{:?}", skeleton.joints);
    for (k, (got, want)) in bones.iter().zip(&want).enumerate() {
        for &j in &eyes {
            let got = glam::Quat::from_slice(&support::f32s(&got[j]));
            let want = glam::Quat::from_array(want[j]);
            assert!(
                got.angle_between(want).to_degrees() < 0.2,
                "eye joint {j} at frame {k}: {got:?} for {want:?}"
            );
        }
    }
    let last = glam::Quat::from_array(want[frames - 1][eyes[0]]);
    assert!(
        last.angle_between(glam::Quat::IDENTITY).to_degrees() > 5.0,
        "the eyes look aside at the end: {last:?}"
    );
}
