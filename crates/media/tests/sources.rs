//! Images, folders and videos (made here with the real ffmpeg) as frame sources, and the
//! errors a user sees for inputs that are not any of them.
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    reason = "tests: exact rates compare exactly"
)]

use std::path::Path;
use std::process::Command;

use faceanim_media::{FrameSource, MediaError, read_image};

/// A frame whose colour encodes its index, so order and count can be checked after a lossy
/// codec: the red channel is 20 × index.
fn frame(index: usize, width: usize, height: usize) -> Vec<u8> {
    (0..width * height)
        .flat_map(|_| [(index * 20) as u8, 128, 255 - (index * 20) as u8])
        .collect()
}

/// Encodes `count` frames at `fps` into `path` with ffmpeg.
fn make_video(path: &Path, count: usize, fps: u32, codec: &[&str]) {
    let (width, height) = (64, 48);
    let frames: Vec<Vec<u8>> = (0..count).map(|i| frame(i, width, height)).collect();
    faceanim_testdata::encode_video(
        path,
        (width, height),
        fps,
        codec,
        frames.iter().map(Vec::as_slice),
    );
}

/// Runs the real ffmpeg quietly with `args`, overwriting its output; it must succeed.
fn ffmpeg(args: &[&str]) {
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(args)
        .status()
        .unwrap();
    assert!(status.success(), "ffmpeg {args:?}");
}

fn read_all(source: &mut FrameSource) -> Vec<faceanim_media::Image> {
    let mut frames = Vec::new();
    while let Some(f) = source.next_frame().unwrap() {
        frames.push(f);
    }
    frames
}

#[test]
fn a_video_keeps_its_frame_count_order_and_rate() {
    let dir = tempfile::tempdir().unwrap();
    for (name, fps, codec) in [
        (
            "clip.mp4",
            25,
            &["-c:v", "libx264", "-pix_fmt", "yuv444p", "-qp", "0"][..],
        ),
        ("clip.avi", 30, &["-c:v", "mjpeg", "-q:v", "2"][..]),
        ("clip.mkv", 24, &["-c:v", "ffv1"][..]),
    ] {
        let path = dir.path().join(name);
        make_video(&path, 12, fps, codec);
        let mut source = FrameSource::open(&path, 30.0).unwrap();
        let info = source.info();
        assert_eq!((info.width, info.height), (64, 48), "{name}");
        assert!(
            (info.fps - fps as f32).abs() < 1e-3,
            "{name}: {} fps",
            info.fps
        );
        assert_eq!(info.frames, Some(12), "{name}");
        let frames = read_all(&mut source);
        assert_eq!(frames.len(), 12, "{name}");
        for (i, f) in frames.iter().enumerate() {
            let red = f.rgb[(24 * 64 + 32) * 3];
            assert!(
                (i32::from(red) - (i * 20) as i32).abs() <= 6,
                "{name} frame {i}: red {red}"
            );
        }
    }
}

#[test]
fn a_video_read_into_frames_given_back_is_the_same_video() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("clip.mkv");
    make_video(&path, 6, 25, &["-c:v", "ffv1"]);
    let fresh = read_all(&mut FrameSource::open(&path, 30.0).unwrap());
    let mut source = FrameSource::open(&path, 30.0).unwrap();
    // Bytes given back are recognised by their spare capacity (a fresh frame has none); a
    // spare of another size is not written into.
    let bytes = 64 * 48 * 3;
    let given_back = || {
        let mut spare = Vec::with_capacity(bytes + 100);
        spare.resize(bytes, 7u8);
        spare
    };
    let first = source
        .next_frame_reusing(Some(vec![7u8; 10]))
        .unwrap()
        .unwrap();
    assert_eq!(first, fresh[0]);
    assert_eq!(first.rgb.capacity(), bytes, "the odd-sized spare was used");
    let mut read = 1;
    while let Some(frame) = source.next_frame_reusing(Some(given_back())).unwrap() {
        assert_eq!(frame, fresh[read], "frame {read}");
        assert_eq!(
            frame.rgb.capacity(),
            bytes + 100,
            "frame {read} was not read into the spare"
        );
        read += 1;
    }
    assert_eq!(read, fresh.len());
}

#[test]
fn a_phone_video_turned_on_its_side_comes_out_upright() {
    // A phone records landscape pixels and says "turn me 90°" in the file; players, and
    // MediaPipe's users, see it upright. Here ffmpeg writes such a file: frames whose left
    // quarter is green, then the same stream with the rotation set.
    let dir = tempfile::tempdir().unwrap();
    let (width, height) = (64, 48);
    let frame: Vec<u8> = (0..width * height)
        .flat_map(|i| [0, if i % width < 16 { 250 } else { 0 }, 128])
        .collect();
    let plain = dir.path().join("plain.mp4");
    faceanim_testdata::encode_video(
        &plain,
        (width, height),
        30,
        &["-c:v", "libx264", "-pix_fmt", "yuv444p", "-qp", "0"],
        std::iter::repeat_n(frame.as_slice(), 5),
    );
    let turned = dir.path().join("portrait.mp4");
    let (plain_name, turned_name) = (plain.to_str().unwrap(), turned.to_str().unwrap());
    ffmpeg(&[
        "-i",
        plain_name,
        "-c",
        "copy",
        "-metadata:s:v:0",
        "rotate=90",
        turned_name,
    ]);
    let mut source = FrameSource::open(&turned, 30.0).unwrap();
    let info = source.info();
    assert_eq!((info.width, info.height), (48, 64));
    let frames = read_all(&mut source);
    assert_eq!(frames.len(), 5);
    // As ffmpeg's own player shows it (ffprobe reads the file's rotation as 90°
    // counter-clockwise): the left quarter is now the bottom quarter.
    let green = |x: usize, y: usize| frames[0].rgb[(y * 48 + x) * 3 + 1];
    assert!(
        green(24, 60) > 200 && green(24, 4) < 50 && green(24, 40) < 50,
        "{} {} {}",
        green(24, 60),
        green(24, 4),
        green(24, 40)
    );
}

#[test]
fn an_ntsc_rate_is_kept_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ntsc.mp4");
    let source = "testsrc=s=64x48:r=30000/1001:d=1";
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        source,
        "-c:v",
        "libx264",
        path.to_str().unwrap(),
    ]);
    let mut source = FrameSource::open(&path, 12.0).unwrap();
    let info = source.info();
    assert!(
        (f64::from(info.fps) - 30000.0 / 1001.0).abs() < 1e-4,
        "{}",
        info.fps
    );
    assert_eq!(info.frames, Some(read_all(&mut source).len()));
}

#[test]
fn images_and_folders_in_name_order() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("v.mkv");
    make_video(&video, 3, 10, &["-c:v", "ffv1"]);
    // Split into a PNG and JPEG sequence with ffmpeg, then read the folder back.
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for (ext, start) in [("png", 0), ("jpg", 3)] {
        let start = start.to_string();
        let pattern = frames.join(format!("f%03d.{ext}"));
        let (input, output) = (video.to_str().unwrap(), pattern.to_str().unwrap());
        ffmpeg(&["-i", input, "-start_number", &start, output]);
    }
    std::fs::write(frames.join("notes.txt"), "not a frame").unwrap();
    let mut source = FrameSource::open(&frames, 12.0).unwrap();
    assert_eq!(source.info().frames, Some(6));
    assert_eq!(source.info().fps, 12.0);
    let images = read_all(&mut source);
    let reds: Vec<u8> = images.iter().map(|f| f.rgb[(24 * 64 + 32) * 3]).collect();
    for (i, red) in reds.iter().enumerate() {
        let expected = (i % 3) * 20;
        assert!((i32::from(*red) - expected as i32).abs() <= 6, "{reds:?}");
    }
    let jpeg = read_image(&frames.join("f004.jpg")).unwrap();
    assert_eq!(
        (jpeg.width, jpeg.height, jpeg.rgb.len()),
        (64, 48, 64 * 48 * 3)
    );
    // A single image is one frame.
    let mut one = FrameSource::open(&frames.join("f001.png"), 30.0).unwrap();
    assert_eq!(read_all(&mut one).len(), 1);
}

#[test]
fn inputs_that_are_not_frames_get_errors_that_name_them() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("notes.mp4");
    std::fs::write(&text, "this is text, not a video").unwrap();
    let empty = dir.path().join("empty.mp4");
    std::fs::write(&empty, b"").unwrap();
    let broken_png = dir.path().join("broken.png");
    std::fs::write(&broken_png, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").unwrap();
    let empty_folder = dir.path().join("nothing");
    std::fs::create_dir(&empty_folder).unwrap();

    for (path, check) in [
        (&text, "not an image or a video"),
        (&empty, "not an image or a video"),
        (&broken_png, "not a readable image"),
        (&empty_folder, "has no PNG, JPEG, WebP or HEIF"),
    ] {
        let err = FrameSource::open(path, 30.0).unwrap_err();
        let message = err.to_string();
        assert!(message.contains(&path.display().to_string()), "{message}");
        assert!(message.contains(check), "{message}");
    }
    let missing = FrameSource::open(&dir.path().join("missing.mp4"), 30.0).unwrap_err();
    assert!(matches!(missing, MediaError::Io { .. }), "{missing}");
}

#[test]
fn a_video_with_no_frames_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("zero.mkv");
    make_video(&path, 0, 25, &["-c:v", "ffv1"]);
    if !path.exists() {
        // ffmpeg may refuse to write a file with no frames at all; then there is nothing to test.
        return;
    }
    let message = match FrameSource::open(&path, 30.0) {
        Err(e) => e.to_string(),
        Ok(mut source) => source.next_frame().unwrap_err().to_string(),
    };
    assert!(
        message.contains("zero.mkv") && message.contains("no"),
        "{message}"
    );
}

/// A phone's portrait photo stores its pixels as the sensor read them and says in its EXIF
/// how to turn them: a photo of a real face (`astronaut.png`) turned each of the seven ways by
/// ffmpeg and marked so by ExifTool reads back upright, as the photo not turned does (within
/// the JPEG's own noise), and as a capture source too. Before, `faceanim track` read the face
/// as stored: turned a quarter, the character's head rolled 85°; turned half round, its 52
/// scores were off the upright photo's by 0.186 on average (the gaze down and the lower lip
/// 0.88 where the upright photo gives 0.17 and 0.07). Now 0.004 and 0.001, the roll under 1°
/// from the upright photo's.
#[test]
fn a_phone_photo_is_read_upright_as_its_exif_says() {
    let dir = tempfile::tempdir().unwrap();
    let face = faceanim_testdata::shared("images/astronaut.png");
    let upright = dir.path().join("upright.jpg");
    ffmpeg(&[
        "-i",
        face.to_str().unwrap(),
        "-q:v",
        "2",
        upright.to_str().unwrap(),
    ]);
    let shown = read_image(&upright).unwrap();
    assert_eq!(
        faceanim_media::exif_orientation(&std::fs::read(&upright).unwrap()),
        None
    );
    // The filter that stores the upright picture as a camera turned that way would.
    for (orientation, stored) in [
        (2, "hflip"),
        (3, "hflip,vflip"),
        (4, "vflip"),
        (5, "transpose=0"),
        (6, "transpose=2"),
        (7, "transpose=3"),
        (8, "transpose=1"),
    ] {
        let path = dir.path().join(format!("turned-{orientation}.jpg"));
        stored_turned(&face, stored, orientation, &path);
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(
            faceanim_media::exif_orientation(&bytes),
            Some(orientation),
            "{stored}"
        );
        let read = read_image(&path).unwrap();
        assert_eq!((read.width, read.height), (shown.width, shown.height));
        let error = mean_difference(&read, &shown);
        assert!(
            error < 3.0,
            "orientation {orientation}: {error:.2} a channel"
        );
        // Not turned, the same pixels are far off (a face is not symmetric enough to pass).
        let unturned = faceanim_media::decode_image(&path, &bytes).unwrap();
        let off = mean_difference(&unturned, &shown);
        assert!(off > 10.0, "orientation {orientation}: {off:.2}");
        let mut source = FrameSource::open(&path, 30.0).unwrap();
        assert_eq!(read_all(&mut source), [read]);
    }
}

/// An iPhone's photo is HEIC (HEIF with HEVC), which before was refused as "not an image or a
/// video … damaged, or another kind of file". Photos encoded by libheif's own encoder (upright,
/// and stored turned with the turn said in EXIF, as the encoders that write no HEIF rotation
/// do) read back upright, as the photo itself; in a folder and as a capture source too.
#[test]
fn a_heif_photo_is_read_upright() {
    let dir = tempfile::tempdir().unwrap();
    let face = faceanim_testdata::shared("images/astronaut.png");
    let shown = read_image(&face).unwrap();
    let heif = |input: &Path, output: &Path| {
        let made = Command::new("heif-enc")
            .args(["-q", "90"])
            .arg(input)
            .arg("-o")
            .arg(output)
            .output()
            .expect("libheif's heif-enc is needed: run scripts/setup.sh");
        assert!(made.status.success(), "{made:?}");
    };
    let upright = dir.path().join("upright.heic");
    heif(&face, &upright);
    // Stored turned a quarter, the turn said in EXIF.
    let sideways = dir.path().join("sideways.jpg");
    stored_turned(&face, "transpose=2", 6, &sideways);
    let turned = dir.path().join("turned.HEIC");
    heif(&sideways, &turned);
    for path in [&upright, &turned] {
        let read = read_image(path).unwrap();
        assert_eq!((read.width, read.height), (shown.width, shown.height));
        let error = mean_difference(&read, &shown);
        assert!(error < 4.0, "{}: {error:.2} a channel", path.display());
        let mut source = FrameSource::open(path, 30.0).unwrap();
        assert!(source.is_still());
        assert_eq!(read_all(&mut source), [read]);
    }
    // A folder of them, as a phone's photos are copied off it.
    let folder = FrameSource::open(dir.path(), 30.0).unwrap();
    assert_eq!(folder.info().frames, Some(3));
}

/// `face` as a camera turned by EXIF `orientation` stores it: its pixels turned by ffmpeg's
/// `filter`, as a JPEG at `path` that ExifTool marks with the orientation.
fn stored_turned(face: &Path, filter: &str, orientation: u8, path: &Path) {
    ffmpeg(&[
        "-i",
        face.to_str().unwrap(),
        "-vf",
        filter,
        "-q:v",
        "2",
        path.to_str().unwrap(),
    ]);
    let marked = Command::new("exiftool")
        .args([
            "-q",
            "-overwrite_original",
            &format!("-Orientation#={orientation}"),
        ])
        .arg(path)
        .status();
    assert!(
        marked.as_ref().is_ok_and(std::process::ExitStatus::success),
        "ExifTool is needed: run scripts/setup.sh ({marked:?})"
    );
}

/// The mean difference of two images' channels, out of 255.
fn mean_difference(a: &faceanim_media::Image, b: &faceanim_media::Image) -> f64 {
    a.rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| f64::from(x.abs_diff(*y)))
        .sum::<f64>()
        / b.rgb.len() as f64
}
