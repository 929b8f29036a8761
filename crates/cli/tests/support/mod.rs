//! Running the `faceanim` binary and the external tools the tests check its files with.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "each test binary uses part of it; it panics to fail a test"
)]

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// The ICT head's path (`characters/ict-face.glb` of the shared material), as an argument.
pub fn ict() -> String {
    faceanim_testdata::shared("characters/ict-face.glb")
        .display()
        .to_string()
}

/// `shapes` renamed `shape_0`, `shape_1`… in their order (names that say nothing), each delta
/// turned by `turn`.
pub fn renamed_shapes(
    shapes: &[faceanim_rig::Blendshape],
    turn: glam::Quat,
) -> Vec<faceanim_rig::Blendshape> {
    shapes
        .iter()
        .enumerate()
        .map(|(k, b)| {
            faceanim_rig::Blendshape::from_sparse(
                format!("shape_{k}"),
                b.indices().to_vec(),
                b.deltas().iter().map(|d| turn * *d).collect(),
            )
        })
        .collect()
}

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where tests leave files worth looking at (`test-output/` in the repository, git-ignored).
pub fn output_dir(test: &str) -> PathBuf {
    let dir = repo().join("test-output").join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// [`output_dir`] emptied first: nothing an earlier run left (a retarget map beside a
/// character) is read again.
pub fn fresh_output_dir(test: &str) -> PathBuf {
    let dir = repo().join("test-output").join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Renders `poses` of `model` with three.js (`tools/heldout-stills.mjs`) into `dir`: the stills
/// and truth.json.
pub fn three_js_stills(model: &Path, poses: &serde_json::Value, dir: &Path) {
    let poses_path = dir.with_extension("poses.json");
    std::fs::write(&poses_path, poses.to_string()).unwrap();
    let tool = repo().join("tools/heldout-stills.mjs");
    let out = Command::new("node")
        .arg(&tool)
        .arg(model)
        .arg(&poses_path)
        .arg(dir)
        .output()
        .expect("node runs");
    succeeded("heldout-stills.mjs", out);
}

/// Renders `poses` of `model` with Blender's Cycles (`tools/blender_stills.py`: an
/// orthographic camera, one sun, flat shading) into `dir`: the stills and truth.json.
pub fn blender_stills(model: &Path, poses: &serde_json::Value, dir: &Path) {
    let poses_path = dir.with_extension("poses.json");
    std::fs::write(&poses_path, poses.to_string()).unwrap();
    let out = Command::new("blender")
        .args(["-b", "--factory-startup", "--python"])
        .arg(repo().join("tools/blender_stills.py"))
        .arg("--")
        .arg(model)
        .arg(&poses_path)
        .arg(dir)
        .output()
        .expect("Blender is needed for this test: run scripts/setup.sh");
    succeeded("blender_stills.py", out);
}

/// The strings of a JSON array (a clip's `blendshapes`).
pub fn strings(value: &serde_json::Value) -> Vec<String> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_owned())
        .collect()
}

/// A stroke (the studio's `POST /api/strokes` body) from just off the vertex that `shape` of
/// `character` moves most to where the shape takes it: `steps` samples `dt` seconds apart.
pub fn stroke_along(
    character: &faceanim_rig::Character,
    shape: &str,
    steps: u32,
    dt: f32,
) -> String {
    let id = character.find_blendshape(shape).unwrap();
    let shape = character.blendshape(id).unwrap();
    let (v, delta) = shape.peak().map(|(v, d)| (v as usize, d)).unwrap();
    let start = character.positions()[v] + character.normals()[v] * 0.001;
    let end = character.positions()[v] + delta;
    let samples: Vec<serde_json::Value> = (0..=steps)
        .map(|i| {
            let p = start.lerp(end, i as f32 / steps as f32);
            serde_json::json!({ "t": i as f32 * dt, "p": [p.x, p.y, p.z] })
        })
        .collect();
    serde_json::json!({ "samples": samples }).to_string()
}

/// MediaPipe's own runtime's scores on `video` (`crates/cli/tests/reference`, recorded by
/// `tools/record_footage_scores.py` from the very file the tests fetch).
pub fn footage_reference(video: faceanim_testdata::producers::Footage) -> serde_json::Value {
    let path = repo().join(format!(
        "crates/cli/tests/reference/{}.mediapipe.json",
        video.stem()
    ));
    let reference: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(
        reference["sha256"],
        video.sha256,
        "{} was recorded from this very file",
        path.display()
    );
    reference
}

/// Column `column` of a clip's `frames` beside MediaPipe's scores `theirs` of every
/// `reference["every"]`th frame (1 where it is not said), over the frames where MediaPipe found a
/// face; then their correlation.
pub fn follows(
    frames: &[serde_json::Value],
    column: usize,
    reference: &serde_json::Value,
    theirs: &[serde_json::Value],
) -> f64 {
    let every = reference["every"].as_u64().unwrap_or(1).max(1) as usize;
    let (mut ours, mut mediapipe) = (Vec::new(), Vec::new());
    for (row, score) in frames.iter().step_by(every).zip(theirs) {
        if let Some(score) = score.as_f64() {
            ours.push(row[column].as_f64().unwrap());
            mediapipe.push(score);
        }
    }
    correlation(&ours, &mediapipe)
}

/// Pearson's correlation of two series of the same length.
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt().max(f64::MIN_POSITIVE)
}

/// `out` of a program run for `what`, which must have succeeded (else its output is shown).
pub fn succeeded(what: &str, out: Output) -> Output {
    assert!(
        out.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Writes `glb` to `out` with its morph targets renamed `shape_1`, `shape_2`… by
/// `tools/rename_targets.py`: a rig whose names say nothing.
pub fn rename_targets(glb: &Path, out: &Path) {
    succeeded(
        "rename_targets.py",
        Command::new("python3")
            .arg(repo().join("tools/rename_targets.py"))
            .arg(glb)
            .arg(out)
            .output()
            .unwrap(),
    );
}

pub fn faceanim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args(args)
        .output()
        .unwrap()
}

pub fn faceanim_ok(args: &[&str]) -> String {
    let out = succeeded(&format!("faceanim {args:?}"), faceanim(args));
    String::from_utf8(out.stdout).unwrap()
}

/// A JSON array of numbers as `f32`s (a quaternion, a frame's weights).
pub fn f32s(value: &serde_json::Value) -> Vec<f32> {
    value
        .as_array()
        .unwrap_or_else(|| panic!("not an array: {value}"))
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect()
}

/// The values of channel `name` in every frame of clip JSON `clip`.
pub fn column(clip: &serde_json::Value, name: &str) -> Vec<f64> {
    let names = clip["blendshapes"].as_array().unwrap();
    let k = names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no channel {name} in {names:?}"));
    clip["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| row[k].as_f64().unwrap())
        .collect()
}

/// Checks that a command refused the file at `path` as a user should see it: exit code 1, an
/// error starting with the file's path and saying `problem`, and no panic. `case` names the
/// case in the failure.
pub fn assert_refused(out: &Output, path: &Path, problem: &str, case: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{case}: {stderr}");
    assert!(
        stderr.starts_with(&format!("error: {}: ", path.display())),
        "{case}: {stderr}"
    );
    assert!(stderr.contains(problem), "{case}: {stderr}");
    assert!(!stderr.contains("panicked"), "{case}: {stderr}");
}

/// `faceanim export CHARACTER -o OUT --clip CLIP`, which must succeed.
pub fn export_with_clip(character: &Path, out: &Path, clip: &Path) {
    export_with_clip_and(character, out, clip, &[]);
}

/// [`export_with_clip`] with `more` arguments (`--uncompressed`); returns what it said (its
/// notes, on standard error).
pub fn export_with_clip_and(character: &Path, out: &Path, clip: &Path, more: &[&str]) -> String {
    let mut args = vec![
        "export",
        character.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--clip",
        clip.to_str().unwrap(),
    ];
    args.extend_from_slice(more);
    let out = succeeded(&format!("faceanim {args:?}"), faceanim(&args));
    String::from_utf8(out.stderr).unwrap()
}

/// `faceanim track INPUT --character CHARACTER [MORE…]`, which must succeed; returns the
/// summary it printed.
pub fn track_summary(input: &Path, character: &Path, more: &[&str]) -> serde_json::Value {
    let run = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .arg("track")
        .arg(input)
        .arg("--character")
        .arg(character)
        .args(more)
        .output()
        .unwrap();
    serde_json::from_slice(&succeeded("faceanim track", run).stdout).unwrap()
}

/// `seconds` of real `footage` from `start` seconds in, cut by ffmpeg into `out` (no sound).
pub fn cut_footage(
    footage: faceanim_testdata::producers::Footage,
    start: u32,
    seconds: u32,
    out: &Path,
) {
    let cut = Command::new("ffmpeg")
        .args(["-y", "-v", "error", "-ss", &start.to_string(), "-i"])
        .arg(faceanim_testdata::producers::footage(footage))
        .args(["-t", &seconds.to_string(), "-an"])
        .arg(out)
        .output()
        .expect("ffmpeg");
    succeeded("ffmpeg", cut);
}

/// `faceanim track INPUT --character CHARACTER [MORE…] -o OUT`, which must succeed; returns the
/// clip it wrote, as JSON.
pub fn track_clip(input: &Path, character: &Path, more: &[&str], out: &Path) -> serde_json::Value {
    let mut more = more.to_vec();
    more.extend(["-o", out.to_str().unwrap()]);
    track_summary(input, character, &more);
    serde_json::from_slice(&std::fs::read(out).unwrap()).unwrap()
}

/// Opens `file` in three.js (the studio's own copy) in Chromium (`tools/threejs-render.mjs`),
/// plays its first animation to `time` seconds, saves a screenshot beside it and returns the
/// report of what loaded, which must hold no page error.
pub fn threejs_render(file: &Path, time: &str) -> serde_json::Value {
    let run = Command::new("node")
        .arg(repo().join("tools/threejs-render.mjs"))
        .arg(file)
        .arg(file.with_extension("png"))
        .arg(time)
        .output()
        .expect("node is needed for this test");
    let run = succeeded("threejs-render.mjs", run);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert!(report.get("pageErrors").is_none(), "{report}");
    report
}

/// Opens `path` in the studio's capture mode, waits for it to be read and returns the capture
/// state.
pub fn open_and_settle(port: u16, path: &Path) -> serde_json::Value {
    let open = serde_json::json!({ "path": path }).to_string();
    let json = [("Content-Type", "application/json")];
    let (status, body) = request(port, "POST", "/api/capture/open", &json, open.as_bytes());
    assert_eq!(status, 200, "{body}");
    settled(port, 60)
}

/// Plays VRM Animation `animation` on VRM `avatar` with pixiv's three-vrm and
/// three-vrm-animation (`tools/vrma-play.mjs`) and returns what the avatar does at each key.
pub fn vrma_played(avatar: &Path, animation: &Path) -> serde_json::Value {
    let run = Command::new("node")
        .arg(repo().join("tools/vrma-play.mjs"))
        .arg(avatar)
        .arg(animation)
        .output()
        .expect("node is needed for this test");
    let run = succeeded("vrma-play.mjs", run);
    serde_json::from_slice(&run.stdout).unwrap()
}

/// Checks a [`threejs_render`] report of a full-body avatar: at least `skinned` skinned meshes,
/// exactly `bones` bones, a texture, the face moving (some morph influence above 0.5) and
/// at least `pixels` pixels drawn.
pub fn assert_avatar_drawn(report: &serde_json::Value, skinned: u64, bones: u64, pixels: u64) {
    assert!(
        report["skinnedMeshes"].as_u64().unwrap() >= skinned,
        "{report}"
    );
    assert_eq!(report["bones"], bones, "{report}");
    assert!(
        report["texturedMaterials"].as_u64().unwrap() >= 1,
        "{report}"
    );
    assert!(report["maxInfluence"].as_f64().unwrap() > 0.5, "{report}");
    assert!(
        report["pixels"]["nonBackground"].as_u64().unwrap() > pixels,
        "{report}"
    );
}

/// Runs the Khronos glTF-Validator (npm `gltf-validator`, installed by scripts/setup.sh) and
/// returns its report.
pub fn validate_gltf(file: &Path) -> serde_json::Value {
    let script = repo().join("tools/validate-gltf.mjs");
    assert!(
        repo().join("tools/node_modules/gltf-validator").exists(),
        "the glTF-Validator is not installed: run scripts/setup.sh (npm ci in tools/)"
    );
    let out = Command::new("node")
        .arg(&script)
        .arg(file)
        .output()
        .expect("node is needed to run the glTF-Validator");
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "validator crashed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Opens `file` in real Blender (Debian's 3.4, headless) with `tools/blender_shape_keys.py` and
/// returns its report: the Blender version, each mesh object with its shape keys, the armatures
/// and the actions.
pub fn blender_report(file: &Path) -> serde_json::Value {
    blender_script(
        "blender_shape_keys.py",
        &[file.as_os_str()],
        "FACEANIM_REPORT ",
    )
}

/// Runs `tools/SCRIPT -- ARGUMENTS…` in Blender (headless) and returns the JSON it printed
/// after `prefix`.
pub fn blender_script(
    script: &str,
    arguments: &[&std::ffi::OsStr],
    prefix: &str,
) -> serde_json::Value {
    let out = Command::new("blender")
        .args(["-b", "--factory-startup", "--python"])
        .arg(repo().join("tools").join(script))
        .arg("--")
        .args(arguments)
        .output()
        .expect("Blender is needed for this test: run scripts/setup.sh (apt-get install blender python3-numpy)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix(prefix))
        .unwrap_or_else(|| {
            panic!(
                "Blender printed no report:\n{stdout}\n{}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
    serde_json::from_str(line).unwrap()
}

/// Asserts the validator reports no errors, printing the first messages if it does.
pub fn assert_valid_gltf(file: &Path) -> serde_json::Value {
    let report = validate_gltf(file);
    let errors = report["issues"]["numErrors"].as_u64().unwrap();
    assert_eq!(
        errors,
        0,
        "{}: glTF-Validator errors: {:#}",
        file.display(),
        report["issues"]["messages"]
    );
    report
}

/// The ICT head from the front, `size` pixels square, one frame per jawOpen value (every other
/// weight 0): footage whose true jawOpen curve the tests know.
pub fn ict_jaw_frames(jaw: &[f32], size: u32) -> Vec<Vec<u8>> {
    let character = faceanim_testdata::ict();
    let camera = faceanim_render::Camera::front(&character.bounds(), 0.75);
    let appearance = faceanim_render::Appearance::of(character);
    let column = character.find_blendshape("jawOpen").unwrap().index();
    jaw.iter()
        .map(|&value| {
            let mut weights = vec![0.0; character.blendshapes().len()];
            weights[column] = value;
            faceanim_render::render(
                character,
                &character.pose(&weights),
                &camera,
                &appearance,
                size,
            )
            .rgb
        })
        .collect()
}

/// `frames` (RGB, `size` square) as an H.264 video at `fps`, as a phone or x264 delivers them.
pub fn encode_h264(path: &Path, size: u32, fps: u32, frames: &[Vec<u8>]) {
    let codec = ["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "12"];
    faceanim_testdata::encode_video(
        path,
        (size as usize, size as usize),
        fps,
        &codec,
        frames.iter().map(Vec::as_slice),
    );
}

/// The independent VMC peer (`tools/vmc_peer.py`, PyPI's python-osc) receiving on a free
/// loopback port until `count` frames arrived or `timeout` seconds passed: returns the running
/// peer and its port; its JSON report goes to `out` when it ends.
pub fn vmc_receiver(count: usize, timeout: f32, out: &Path) -> (std::process::Child, u16) {
    use std::io::BufRead as _;
    let mut child = Command::new("python3")
        .arg(repo().join("tools/vmc_peer.py"))
        .args([
            "receive",
            "--count",
            &count.to_string(),
            "--timeout",
            &timeout.to_string(),
            "--out",
        ])
        .arg(out)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("python3 with python-osc (scripts/setup.sh installs it)");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .trim()
        .strip_prefix("PORT ")
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("the VMC peer did not say its port: {line:?}"));
    (child, port)
}

/// `text` spoken by flite's `voice` (a synthetic voice no line of faceanim made) into `wav`;
/// flite's own phone timings ("pau:0.164 hh:0.255 …", `-psdur`).
pub fn flite(voice: &str, text: &str, wav: &Path) -> String {
    let made = Command::new("flite")
        .args(["-voice", voice, "-t", text, "-psdur", "-o"])
        .arg(wav)
        .output()
        .expect("flite is needed: run scripts/setup.sh");
    assert!(made.status.success(), "{made:?}");
    String::from_utf8(made.stdout).unwrap()
}

/// Waits for the VMC peer of [`vmc_receiver`] to finish; every value it received for the
/// blendshape `name`, in order.
pub fn vmc_values(peer: &mut std::process::Child, report: &Path, name: &str) -> Vec<f64> {
    vmc_numbers(peer, report, "/VMC/Ext/Blend/Val", name)
        .into_iter()
        .map(|args| args[0])
        .collect()
}

/// Waits for the VMC peer of [`vmc_receiver`] to finish; the numbers after the name of every
/// message it received at `address` naming `name` (a blendshape's value, a bone's position
/// and rotation), in order.
pub fn vmc_numbers(
    peer: &mut std::process::Child,
    report: &Path,
    address: &str,
    name: &str,
) -> Vec<Vec<f64>> {
    assert!(peer.wait().unwrap().success());
    let received: serde_json::Value =
        serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap();
    received["datagrams"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|d| d["messages"].as_array().unwrap().iter())
        .filter(|m| m["address"] == address && m["args"][0][1] == name)
        .map(|m| {
            let args = m["args"].as_array().unwrap();
            args[1..].iter().map(|a| a[1].as_f64().unwrap()).collect()
        })
        .collect()
}

/// From the report of the VMC peer of [`vmc_receiver`] (once it ended), every frame that
/// carried both a `JawOpen` value and a `Jaw` bone: the value, and the bone's turn in degrees.
pub fn vmc_jaw_pairs(report: &Path) -> Vec<(f64, f64)> {
    let received: serde_json::Value =
        serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap();
    let find = |messages: &[serde_json::Value], address: &str, name: &str| {
        messages
            .iter()
            .find(|m| m["address"] == address && m["args"][0][1] == name)
            .map(|m| m["args"].clone())
    };
    let mut pairs = Vec::new();
    for datagram in received["datagrams"].as_array().unwrap() {
        let Some(messages) = datagram["messages"].as_array() else {
            continue;
        };
        let value = find(messages, "/VMC/Ext/Blend/Val", "JawOpen");
        let bone = find(messages, "/VMC/Ext/Bone/Pos", "Jaw");
        if let (Some(value), Some(bone)) = (value, bone) {
            let turned = 2.0 * bone[4][1].as_f64().unwrap().asin().to_degrees();
            pairs.push((value[1][1].as_f64().unwrap(), turned));
        }
    }
    pairs
}

/// The independent VMC peer sending `frames` frames of known ARKit weights, head turns and
/// gaze (`"eyes"`: yaw and pitch of both eye bones) to
/// 127.0.0.1:`port` at `fps` but those in `lose` (kept back, as a Wi-Fi network loses them),
/// then `garbage` bad datagrams; returns every frame, the lost ones marked `"lost": true`.
pub fn vmc_send(
    port: u16,
    frames: usize,
    fps: f32,
    garbage: usize,
    lose: std::ops::Range<usize>,
    out: &Path,
) -> serde_json::Value {
    let lose = format!("{}:{}", lose.start, lose.end);
    let garbage = garbage.to_string();
    peer_send(
        port,
        frames,
        fps,
        &["--garbage", &garbage, "--lose", &lose],
        out,
    )
}

/// [`vmc_send`] of every frame, none lost, no garbage.
pub fn vmc_send_arkit(port: u16, frames: usize, fps: f32, out: &Path) -> serde_json::Value {
    vmc_send(port, frames, fps, 0, 0..0, out)
}

/// [`vmc_send`]'s curves sent as VRM 0.x's presets (`A`, `Blink`, `Joy`), as VSeeFace and
/// VMagicMirror send without perfect sync; every frame, its values under those names.
pub fn vmc_send_vrm_presets(port: u16, frames: usize, fps: f32, out: &Path) -> serde_json::Value {
    peer_send(port, frames, fps, &["--names", "vrm"], out)
}

fn peer_send(port: u16, frames: usize, fps: f32, more: &[&str], out: &Path) -> serde_json::Value {
    let run = Command::new("python3")
        .arg(repo().join("tools/vmc_peer.py"))
        .args([
            "send",
            "--to",
            &port.to_string(),
            "--frames",
            &frames.to_string(),
            "--fps",
            &fps.to_string(),
        ])
        .args(more)
        .arg("--out")
        .arg(out)
        .output()
        .expect("python3 with python-osc (scripts/setup.sh installs it)");
    succeeded("vmc_peer.py", run);
    serde_json::from_slice(&std::fs::read(out).unwrap()).unwrap()
}

/// A UDP port free on loopback just now.
pub fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A running studio, stopped when dropped (as [`Studio::stop`] stops it).
pub struct Studio {
    pub child: Child,
    pub port: u16,
}

impl Studio {
    /// Asks the studio to stop as a service manager or `kill` does (SIGTERM) and waits for it
    /// to end; one still running after 10 s is killed. How it ended (`None` when killed).
    pub fn stop(&mut self) -> Option<std::process::ExitStatus> {
        if let Ok(Some(status)) = self.child.try_wait() {
            return Some(status);
        }
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while std::time::Instant::now() < deadline {
            if let Ok(Some(status)) = self.child.try_wait() {
                return Some(status);
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        None
    }
}

impl Drop for Studio {
    fn drop(&mut self) {
        self.stop();
    }
}

/// A studio on `character` (the built-in head with `None`).
pub fn start_on(
    character: Option<&std::path::Path>,
    project: &std::path::Path,
    more: &[&std::ffi::OsStr],
) -> Studio {
    start_on_env(character, project, more, &[])
}

/// [`start_on`], with environment variables `env` set for the studio.
pub fn start_on_env(
    character: Option<&std::path::Path>,
    project: &std::path::Path,
    more: &[&std::ffi::OsStr],
    env: &[(&str, &std::ffi::OsStr)],
) -> Studio {
    let mut child = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .arg("studio")
        .args(character)
        .args(["--port", "0", "--project"])
        .arg(project)
        .args(more)
        .envs(env.iter().copied())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    // "faceanim studio: http://127.0.0.1:PORT/  (…)"
    let port = line
        .split("127.0.0.1:")
        .nth(1)
        .and_then(|rest| rest.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no URL in the studio's first line: {line}"));
    Studio { child, port }
}

/// `POST /api/capture/upload` of `bytes` as a file called `name`; the status and body.
pub fn upload(port: u16, name: &str, bytes: &[u8]) -> (u16, String) {
    request(
        port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", name)],
        bytes,
    )
}

/// `POST /api/capture/open` of the file at `path` (a video, photo, clip, recording or take)
/// as the capture's take; the status and body.
pub fn open_path(port: u16, path: &Path) -> (u16, String) {
    let body = serde_json::json!({ "path": path }).to_string();
    request(
        port,
        "POST",
        "/api/capture/open",
        &[("content-type", "application/json")],
        body.as_bytes(),
    )
}

/// One raw HTTP/1.1 request; returns the status code and body.
pub fn request(
    port: u16,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> (u16, String) {
    let (status, body) = request_bytes(port, method, path, headers, body);
    (status, String::from_utf8_lossy(&body).into_owned())
}

/// A `GET`'s head (status line and headers) and its body as bytes (a GLB is not text), failing
/// on any status but 200.
pub fn get_with_head(port: u16, path: &str) -> (String, Vec<u8>) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    let head =
        format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n");
    stream.write_all(head.as_bytes()).unwrap();
    let mut response = Vec::new();
    stream.read_to_end(&mut response).unwrap();
    let split = response.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&response[..split]).into_owned();
    assert!(head.starts_with("HTTP/1.1 200"), "{path}: {head}");
    // The studio answers with a Content-Length body (no chunking).
    (head, response[split + 4..].to_vec())
}

/// One raw HTTP/1.1 request; returns the status code and the body's bytes (a GLB download).
pub fn request_bytes(
    port: u16,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> (u16, Vec<u8>) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    let mut text = format!(
        "{method} {path} HTTP/1.1\r\nConnection: close\r\nContent-Length: {}\r\n",
        body.len()
    );
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        text.push_str(&format!("Host: 127.0.0.1:{port}\r\n"));
    }
    for (k, v) in headers {
        text.push_str(&format!("{k}: {v}\r\n"));
    }
    // A large body waits for the server's go-ahead (`Expect: 100-continue`), as curl sends
    // one: a server that refuses it (413) answers at once and closes without reading it.
    let expect = body.len() > 1 << 20;
    if expect {
        text.push_str("Expect: 100-continue\r\n");
    }
    text.push_str("\r\n");
    stream.write_all(text.as_bytes()).unwrap();
    let mut response = Vec::new();
    let go_ahead = !expect || {
        let mut byte = [0u8; 1];
        while !response.ends_with(b"\r\n\r\n") && stream.read(&mut byte).unwrap() == 1 {
            response.push(byte[0]);
        }
        let continued = response.starts_with(b"HTTP/1.1 100");
        if continued {
            response.clear();
        }
        continued
    };
    // A server that refuses the body part way (its limit) may close before all of it is
    // sent: its answer is still there to read.
    if go_ahead && let Err(error) = stream.write_all(body) {
        assert!(
            matches!(
                error.kind(),
                std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::ConnectionReset
            ),
            "{error}"
        );
    }
    if let Err(error) = stream.read_to_end(&mut response) {
        assert_eq!(error.kind(), std::io::ErrorKind::ConnectionReset, "{error}");
    }
    let split = response
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or(response.len());
    let head = String::from_utf8_lossy(&response[..split]);
    let status = head.split(' ').nth(1).and_then(|s| s.parse().ok()).unwrap();
    (
        status,
        response.get(split + 4..).unwrap_or_default().to_vec(),
    )
}

/// `video` captured once by `faceanim track … --session` onto the built-in head, every frame
/// kept (no keyframes): its frames' expressions, for tests to read through any character's
/// estimator (`Session::for_character`). Cached in `target/test-fixtures` for this build of
/// faceanim, so that the tests of one run capture each video once.
pub fn captured_session(video: faceanim_testdata::producers::Footage) -> faceanim_take::Session {
    let binary = std::fs::metadata(env!("CARGO_BIN_EXE_faceanim")).unwrap();
    let built = binary
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs());
    let dir = repo().join("target/test-fixtures");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!(
        "captured-{}-{built}-{}.session.json",
        video.stem(),
        binary.len()
    ));
    // One test process captures; the others (nextest runs tests side by side) wait for it.
    let lock = path.with_extension("lock");
    let started = std::time::Instant::now();
    while !path.exists() {
        match std::fs::File::create_new(&lock) {
            Ok(_) => {
                let partial = dir.join(format!("{}.{}.partial", video.stem(), std::process::id()));
                let captured = std::panic::catch_unwind(|| {
                    faceanim_ok(&[
                        "track",
                        faceanim_testdata::producers::footage(video)
                            .to_str()
                            .unwrap(),
                        "--filter",
                        "none",
                        "--by-name",
                        "--session",
                        partial.to_str().unwrap(),
                    ])
                });
                if captured.is_ok() {
                    std::fs::rename(&partial, &path).unwrap();
                }
                std::fs::remove_file(&lock).unwrap();
                if let Err(e) = captured {
                    std::panic::resume_unwind(e);
                }
            }
            Err(_) => {
                assert!(
                    started.elapsed().as_secs() < 1200,
                    "{} was held for 20 minutes",
                    lock.display()
                );
                std::thread::sleep(std::time::Duration::from_millis(250));
            }
        }
    }
    faceanim_take::Session::from_json(&std::fs::read(&path).unwrap()).unwrap()
}

/// Waits (at most `seconds`) for the studio's capture job to end; returns the capture state.
pub fn settled(port: u16, seconds: u64) -> serde_json::Value {
    let started = std::time::Instant::now();
    loop {
        let (status, body) = request(port, "GET", "/api/capture/state", &[], b"");
        assert_eq!(status, 200, "{body}");
        let state: serde_json::Value = serde_json::from_str(&body).unwrap();
        if state["job"]["running"] != true {
            return state;
        }
        assert!(
            started.elapsed().as_secs() < seconds,
            "the capture job did not end in {seconds} s: {state}"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

/// The studio's `answer` (`body`, status 200) started making the character's retarget map
/// (a `making_map` job); waits until it ends without error, and returns the state then.
pub fn map_made(port: u16, status: u16, body: &str) -> serde_json::Value {
    assert_eq!(status, 200, "{body}");
    let answer: serde_json::Value = serde_json::from_str(body).unwrap();
    assert_eq!(answer["job"]["kind"], "making_map", "{}", answer["job"]);
    let state = settled(port, 300);
    assert!(state["job"]["error"].is_null(), "{}", state["job"]);
    state
}

/// Whether MediaPipe's scores of a channel on some footage move: they span at least
/// `at_least` between their 5th and 95th percentiles (a channel that never changes by that
/// much is noise around a constant).
pub fn moves(scores: &[serde_json::Value], at_least: f64) -> bool {
    let mut s: Vec<f64> = scores
        .iter()
        .filter_map(serde_json::Value::as_f64)
        .collect();
    s.sort_by(f64::total_cmp);
    !s.is_empty() && s[s.len() * 95 / 100] - s[s.len() * 5 / 100] >= at_least
}
