//! Running the `faceanim` binary and the external tools the tests check its files with.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests panic to fail, and compare exact zeros (a zero delta means: does not move)"
)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Where tests leave files worth looking at (`test-output/` in the repository, git-ignored).
pub fn output_dir(test: &str) -> PathBuf {
    let dir = repo().join("test-output").join(test);
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
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

pub fn faceanim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args(args)
        .output()
        .unwrap()
}

pub fn faceanim_ok(args: &[&str]) -> String {
    let out = faceanim(args);
    assert!(
        out.status.success(),
        "faceanim {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
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
    let out = Command::new("blender")
        .args(["-b", "--factory-startup", "--python"])
        .arg(repo().join("tools/blender_shape_keys.py"))
        .arg("--")
        .arg(file)
        .output()
        .expect("Blender is needed for this test: run scripts/setup.sh (apt-get install blender python3-numpy)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("FACEANIM_REPORT "))
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

/// The independent VMC peer sending `frames` frames of known ARKit weights and head turns to
/// 127.0.0.1:`port` at `fps`, then `garbage` bad datagrams; returns what it sent.
pub fn vmc_send(
    port: u16,
    frames: usize,
    fps: f32,
    garbage: usize,
    out: &Path,
) -> serde_json::Value {
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
            "--garbage",
            &garbage.to_string(),
            "--out",
        ])
        .arg(out)
        .output()
        .expect("python3 with python-osc (scripts/setup.sh installs it)");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
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
