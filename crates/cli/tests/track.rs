//! `faceanim track` end to end: a video made here with ffmpeg from renders of the ICT head
//! (mouth shut, open, shut) animates the ICT character by name, written as clip JSON, a GLB the
//! glTF-Validator accepts and a Live Link Face CSV; and inputs that are not footage fail with
//! messages that name them.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests (exact frame rates and copied keys compare exactly)"
)]

mod support;

use support::{assert_valid_gltf, faceanim, output_dir};

/// 10 frames at 24 fps: 3 shut, 4 open, 3 shut.
fn make_video(path: &std::path::Path) {
    let read = |name: &str| {
        faceanim_media::read_image(&faceanim_testdata::shared(&format!("images/{name}"))).unwrap()
    };
    let (neutral, open) = (read("ict-face-neutral.png"), read("ict-face-jawopen.png"));
    let frames = (0..10).map(|i| {
        if (3..7).contains(&i) {
            open.rgb.as_slice()
        } else {
            neutral.rgb.as_slice()
        }
    });
    let codec = ["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "12"];
    faceanim_testdata::encode_video(path, (neutral.width, neutral.height), 24, &codec, frames);
}

#[test]
fn a_video_animates_an_arkit_named_character_in_three_formats() {
    let dir = output_dir("track");
    let video = dir.join("jaw.mp4");
    make_video(&video);
    let (json, glb, csv, raw) = (
        dir.join("jaw.json"),
        dir.join("jaw.glb"),
        dir.join("jaw.csv"),
        dir.join("jaw.raw.json"),
    );
    let [json_path, glb_path, csv_path, raw_path] =
        [&json, &glb, &csv, &raw].map(|p| p.to_str().unwrap());
    let outputs = ["-o", json_path, "-o", glb_path, "-o", csv_path];
    let more = [&outputs[..], &["--raw", raw_path, "--filter", "none"]].concat();
    let summary = support::track_summary(&video, std::path::Path::new(&support::ict()), &more);
    assert_eq!(summary["frames"], 10);
    assert_eq!(summary["faces_found"], 10);
    assert!(
        summary["blendshapes_driven"].as_u64().unwrap() >= 45,
        "{summary}"
    );

    // The clip is in the character's own names and keeps the video's frames and rate.
    let clip = faceanim_anim::Clip::from_json(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(clip.fps, 24.0);
    assert_eq!(clip.frames.len(), 10);
    assert_eq!(clip.blendshapes.len(), 53);
    let jaw = clip.column("jawOpen").unwrap();
    for (i, row) in clip.frames.iter().enumerate() {
        if (3..7).contains(&i) {
            assert!(row[jaw] > 0.5, "frame {i}: {}", row[jaw]);
        } else {
            assert!(row[jaw] < 0.15, "frame {i}: {}", row[jaw]);
        }
    }
    assert_eq!(clip.presence.as_ref().unwrap().len(), 10);
    assert_eq!(clip.head.as_ref().unwrap().len(), 10);

    // The GLB: valid, one animation with weights and the head's rotation.
    let report = assert_valid_gltf(&glb);
    assert_eq!(report["info"]["animationCount"], 1, "{report:#}");
    let document = gltf::Gltf::from_slice(&std::fs::read(&glb).unwrap()).unwrap();
    let animation = document.animations().next().unwrap();
    let paths: Vec<String> = animation
        .channels()
        .map(|c| format!("{:?}", c.target().property()))
        .collect();
    assert_eq!(paths, ["MorphTargetWeights", "Rotation"]);

    // Live Link Face: header, 10 rows, jawOpen in its column.
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 11);
    let header: Vec<&str> = lines[0].split(',').collect();
    let column = header.iter().position(|h| *h == "JawOpen").unwrap();
    let value: f32 = lines[5].split(',').nth(column).unwrap().parse().unwrap();
    assert!(value > 0.5, "{}", lines[5]);

    // The raw record keeps the 478 landmarks of every frame.
    let raw: serde_json::Value = serde_json::from_slice(&std::fs::read(&raw).unwrap()).unwrap();
    assert_eq!(raw["frames"].as_array().unwrap().len(), 10);
    assert_eq!(raw["frames"][0]["landmarks"].as_array().unwrap().len(), 478);
}

#[test]
fn footage_problems_are_reported_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    let out = dir.path().join("out.json");
    let run = faceanim(&["track", text.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("notes.txt") && stderr.contains("not an image or a video"),
        "{stderr}"
    );
    assert!(!out.exists());

    let bad_extension = faceanim(&["track", text.to_str().unwrap(), "-o", "take.mov"]);
    assert!(String::from_utf8_lossy(&bad_extension.stderr).contains("take.mov"));

    // An output the character cannot take (a VRM Animation of the built-in head, which is no
    // VRM) is refused once the character is read, before the footage is, and nothing is
    // written.
    let [glb, vrma] = ["glb", "vrma"].map(|e| dir.path().join(format!("take.{e}")));
    let (notes, glb_path, vrma_path) = (
        text.to_str().unwrap(),
        glb.to_str().unwrap(),
        vrma.to_str().unwrap(),
    );
    let run = faceanim(&["track", notes, "-o", glb_path, "-o", vrma_path]);
    support::assert_refused(
        &run,
        &vrma,
        "is no VRM avatar",
        "a VRM Animation of the head",
    );
    assert!(!glb.exists());

    // A picture with no face: one frame, marked, with a warning, not an error.
    let blank = dir.path().join("blank.png");
    let image = faceanim_render::Image::filled(64, 48, [30, 30, 30]);
    std::fs::write(&blank, image.to_png().unwrap()).unwrap();
    let run = faceanim(&[
        "track",
        blank.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stderr).contains("no face"));
    let clip = faceanim_anim::Clip::from_json(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(clip.frames.len(), 1);
    assert_eq!(clip.presence, Some(vec![0.0]));
}
