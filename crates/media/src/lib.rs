//! # faceanim-media: where capture's frames come from
//!
//! One [`FrameSource`] for every input a user points capture at: a still image (PNG or JPEG,
//! told apart by their bytes, not their names), a folder of images (in name order, as an
//! image sequence), or a video file, decoded by Debian's `ffmpeg` program through a pipe.
//! Every frame comes out as 8-bit RGB. Video is resampled to a constant frame rate (its own
//! average rate) so that frame `i` is always at `i / fps` seconds: a dropped or duplicated
//! frame in the file never shifts the timeline.
//!
//! Raw frames from a caller (the studio's webcam, as packed RGB or the camera's own YUV) are
//! turned into the same [`Image`] by [`raw`].
#![deny(missing_docs)]

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

pub mod raw;

/// An RGB image, 8 bits per channel, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width × height × 3` bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A copy no taller than `max_height` pixels (each output pixel the mean of the input
    /// pixels it covers), for previews; the image itself when it is small enough.
    #[must_use]
    pub fn preview(&self, max_height: usize) -> Image {
        if self.height <= max_height || max_height == 0 || self.width == 0 {
            return self.clone();
        }
        let height = max_height;
        let width = (self.width * height).div_ceil(self.height).max(1);
        let mut rgb = vec![0u8; width * height * 3];
        // Each output pixel averages the input block it covers (at least one pixel).
        let span = |i: usize, out: usize, input: usize| {
            let start = i * input / out;
            (start, ((i + 1) * input / out).clamp(start + 1, input))
        };
        for y in 0..height {
            let (y0, y1) = span(y, height, self.height);
            for x in 0..width {
                let (x0, x1) = span(x, width, self.width);
                let mut sum = [0u32; 3];
                for sy in y0..y1 {
                    let row = &self.rgb[(sy * self.width + x0) * 3..(sy * self.width + x1) * 3];
                    for pixel in row.chunks_exact(3) {
                        for (s, &v) in sum.iter_mut().zip(pixel) {
                            *s += u32::from(v);
                        }
                    }
                }
                let n = ((y1 - y0) * (x1 - x0)) as u32;
                let d = (y * width + x) * 3;
                for (out, s) in rgb[d..d + 3].iter_mut().zip(sum) {
                    *out = (s / n) as u8;
                }
            }
        }
        Image { width, height, rgb }
    }

    /// The image as PNG bytes (fast compression: previews are made while capturing).
    ///
    /// # Errors
    /// The encoder's message when the buffer does not match the size.
    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        let width = u32::try_from(self.width).map_err(|e| e.to_string())?;
        let height = u32::try_from(self.height).map_err(|e| e.to_string())?;
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer
            .write_image_data(&self.rgb)
            .map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())?;
        Ok(out)
    }
}

/// Why an input cannot be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MediaError {
    /// The file or folder could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The input.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The bytes are not a usable image.
    #[error("{path}: not a readable image: {message}")]
    BadImage {
        /// The input.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A folder holds no PNG or JPEG files.
    #[error("{path}: the folder has no PNG or JPEG images")]
    EmptyFolder {
        /// The folder.
        path: PathBuf,
    },
    /// Images of a sequence differ in size.
    #[error("{path}: {width}×{height}, but the sequence started at {first_width}×{first_height}")]
    SizeChanged {
        /// The odd image.
        path: PathBuf,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
        /// The first image's width.
        first_width: usize,
        /// The first image's height.
        first_height: usize,
    },
    /// The file is neither an image nor a video ffmpeg can read, or its video is empty.
    #[error("{path}: not an image or a video: {message}")]
    NotVideo {
        /// The input.
        path: PathBuf,
        /// What ffprobe/ffmpeg said, or what is missing.
        message: String,
    },
    /// `ffmpeg`/`ffprobe` are not installed.
    #[error(
        "{path}: reading video needs the ffmpeg program, which was not found ({program}: {source}). \
         Install it (Debian/Ubuntu: `sudo apt-get install ffmpeg`; macOS: `brew install ffmpeg`), \
         or give a folder of PNG/JPEG frames instead"
    )]
    FfmpegMissing {
        /// The input.
        path: PathBuf,
        /// `ffmpeg` or `ffprobe`.
        program: &'static str,
        /// Why it could not start.
        source: std::io::Error,
    },
    /// ffmpeg stopped with an error part-way.
    #[error("{path}: ffmpeg failed after {frames} frames: {message}")]
    Decode {
        /// The input.
        path: PathBuf,
        /// Frames delivered before the failure.
        frames: usize,
        /// ffmpeg's own message.
        message: String,
    },
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// What kind of picture file the first bytes say this is.
fn image_kind(head: &[u8]) -> Option<&'static str> {
    if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("png")
    } else if head.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("jpeg")
    } else {
        None
    }
}

/// Decodes a PNG or JPEG held in memory; `path` is only for messages.
///
/// # Errors
/// [`MediaError::BadImage`] for anything that is not a complete PNG or JPEG.
pub fn decode_image(path: &Path, bytes: &[u8]) -> Result<Image, MediaError> {
    let bad = |message: String| MediaError::BadImage {
        path: path.to_owned(),
        message,
    };
    match image_kind(bytes) {
        Some("png") => decode_png(bytes).map_err(bad),
        Some(_) => decode_jpeg(bytes).map_err(bad),
        None => Err(bad("neither PNG nor JPEG".into())),
    }
}

/// Images larger than this (in pixels) are refused rather than allocated.
const MAX_PIXELS: usize = 8192 * 8192;

fn decode_png(bytes: &[u8]) -> Result<Image, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // 16-bit to 8, palettes and low bit depths to whole bytes.
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let (width, height) = {
        let info = reader.info();
        (info.width as usize, info.height as usize)
    };
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_PIXELS {
        return Err(format!("{width}×{height} pixels is not a size we read"));
    }
    let size = reader
        .output_buffer_size()
        .ok_or("image too large for memory")?;
    let mut buffer = vec![0; size];
    let frame = reader.next_frame(&mut buffer).map_err(|e| e.to_string())?;
    let channels = frame.color_type.samples();
    let row = frame.line_size;
    let mut rgb = Vec::with_capacity(width * height * 3);
    for y in 0..height {
        let line = &buffer[y * row..y * row + width * channels];
        for pixel in line.chunks_exact(channels) {
            match channels {
                1 | 2 => rgb.extend([pixel[0]; 3]),
                _ => rgb.extend(&pixel[..3]),
            }
        }
    }
    Ok(Image { width, height, rgb })
}

fn decode_jpeg(bytes: &[u8]) -> Result<Image, String> {
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_max_width(8192)
        .set_max_height(8192);
    let mut decoder =
        zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    let rgb = decoder.decode().map_err(|e| e.to_string())?;
    let (width, height) = decoder
        .dimensions()
        .ok_or("no image dimensions in the file")?;
    if rgb.len() != width * height * 3 {
        return Err(format!(
            "decoded {} bytes for {width}×{height} RGB",
            rgb.len()
        ));
    }
    Ok(Image { width, height, rgb })
}

/// Reads and decodes a PNG or JPEG file.
///
/// # Errors
/// [`MediaError::Io`] or [`MediaError::BadImage`].
pub fn read_image(path: &Path) -> Result<Image, MediaError> {
    let bytes = std::fs::read(path).map_err(|source| MediaError::Io {
        path: path.to_owned(),
        source,
    })?;
    decode_image(path, &bytes)
}

/// Facts about a source, known before its frames are read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceInfo {
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// Frames per second (a still image or a folder: the rate it was opened with).
    pub fps: f32,
    /// How many frames there will be, when known in advance.
    pub frames: Option<usize>,
}

/// Frames from an image, a folder of images or a video. See the crate docs.
#[derive(Debug)]
pub struct FrameSource {
    path: PathBuf,
    info: SourceInfo,
    kind: Kind,
    delivered: usize,
    /// File names of an image or image sequence, in frame order.
    image_names: Vec<String>,
}

#[derive(Debug)]
enum Kind {
    Images(std::vec::IntoIter<PathBuf>, Option<Image>),
    /// ffmpeg, and a thread collecting what it says on stderr (drained as it comes, so a
    /// chatty ffmpeg can never block on a full pipe).
    Video(Child, Option<std::thread::JoinHandle<String>>),
}

impl FrameSource {
    /// Opens `path`: a folder is an image sequence (PNG and JPEG files in name order), a PNG or
    /// JPEG file one frame, anything else a video for ffmpeg. `sequence_fps` is the frame
    /// rate given to images and folders (videos carry their own).
    ///
    /// # Errors
    /// A [`MediaError`] naming the input and the problem: unreadable, not an image or a
    /// video, an empty folder or video, or ffmpeg missing.
    pub fn open(path: &Path, sequence_fps: f32) -> Result<FrameSource, MediaError> {
        let io = |source| MediaError::Io {
            path: path.to_owned(),
            source,
        };
        let metadata = std::fs::metadata(path).map_err(io)?;
        if metadata.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(path)
                .map_err(io)?
                .filter_map(Result::ok)
                .map(|entry| entry.path())
                .filter(|p| {
                    p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                        matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg")
                    })
                })
                .collect();
            files.sort();
            let image_names = files.iter().map(|f| file_name(f)).collect();
            let Some(first_path) = files.first() else {
                return Err(MediaError::EmptyFolder {
                    path: path.to_owned(),
                });
            };
            let first = read_image(first_path)?;
            let info = SourceInfo {
                width: first.width,
                height: first.height,
                fps: sequence_fps,
                frames: Some(files.len()),
            };
            let mut rest = files.into_iter();
            rest.next();
            return Ok(FrameSource {
                path: path.to_owned(),
                info,
                kind: Kind::Images(rest, Some(first)),
                delivered: 0,
                image_names,
            });
        }
        let mut head = [0u8; 8];
        let read = std::fs::File::open(path)
            .and_then(|mut f| f.read(&mut head))
            .map_err(io)?;
        if image_kind(&head[..read]).is_some() {
            let image = read_image(path)?;
            return Ok(FrameSource {
                path: path.to_owned(),
                info: SourceInfo {
                    width: image.width,
                    height: image.height,
                    fps: sequence_fps,
                    frames: Some(1),
                },
                kind: Kind::Images(Vec::new().into_iter(), Some(image)),
                delivered: 0,
                image_names: vec![file_name(path)],
            });
        }
        open_video(path)
    }

    /// Size, frame rate and (when known) frame count.
    #[must_use]
    pub fn info(&self) -> SourceInfo {
        self.info
    }

    /// True for a single still image (not a sequence, not a video).
    #[must_use]
    pub fn is_still(&self) -> bool {
        matches!(self.kind, Kind::Images(..)) && self.image_names.len() == 1 && !self.path.is_dir()
    }

    /// A name for frame `index`: the image's file name, or for a video the video's name and
    /// the frame number from 1 (`take_000001.png`), as the seed's CSV lists frames.
    #[must_use]
    pub fn frame_name(&self, index: usize) -> String {
        self.image_names.get(index).cloned().unwrap_or_else(|| {
            let stem = self
                .path
                .file_stem()
                .map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
            format!("{stem}_{:06}.png", index + 1)
        })
    }

    /// The next frame, or `None` at the end.
    ///
    /// # Errors
    /// A [`MediaError`] if an image of a sequence is unreadable or of another size, or ffmpeg
    /// fails part-way.
    pub fn next_frame(&mut self) -> Result<Option<Image>, MediaError> {
        let SourceInfo { width, height, .. } = self.info;
        let frame = match &mut self.kind {
            Kind::Images(rest, first) => {
                if let Some(image) = first.take() {
                    Some(image)
                } else if let Some(next) = rest.next() {
                    let image = read_image(&next)?;
                    if (image.width, image.height) != (width, height) {
                        return Err(MediaError::SizeChanged {
                            path: next,
                            width: image.width,
                            height: image.height,
                            first_width: width,
                            first_height: height,
                        });
                    }
                    Some(image)
                } else {
                    None
                }
            }
            Kind::Video(child, stderr) => {
                read_video_frame(&self.path, child, stderr, width, height, self.delivered)?
            }
        };
        if frame.is_some() {
            self.delivered += 1;
        }
        Ok(frame)
    }
}

impl Drop for FrameSource {
    fn drop(&mut self) {
        if let Kind::Video(child, _) = &mut self.kind {
            // Stopped early (an error downstream, or the caller had enough): don't leave
            // ffmpeg running or a zombie behind.
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// `program` (`ffmpeg` or `ffprobe`) with its quiet options. It is not run here: each run of
/// either costs tens of milliseconds of start-up, so a missing program is told from the error
/// of the run itself ([`spawn_error`]).
fn ffmpeg_command(program: &'static str) -> Command {
    let mut command = Command::new(program);
    command.args(["-v", "error", "-hide_banner"]);
    if program == "ffmpeg" {
        command.arg("-nostdin");
    }
    command
}

/// The error of a failed start of `program` on `path`: missing, or another input/output error.
fn spawn_error(program: &'static str, path: &Path, source: std::io::Error) -> MediaError {
    if source.kind() == std::io::ErrorKind::NotFound {
        MediaError::FfmpegMissing {
            path: path.to_owned(),
            program,
            source,
        }
    } else {
        MediaError::Io {
            path: path.to_owned(),
            source,
        }
    }
}

fn open_video(path: &Path) -> Result<FrameSource, MediaError> {
    let not_video = |message: String| MediaError::NotVideo {
        path: path.to_owned(),
        message,
    };
    let mut probe = ffmpeg_command("ffprobe");
    probe.args([
        "-select_streams",
        "v:0",
        "-count_packets",
        "-show_entries",
        "stream=width,height,avg_frame_rate,r_frame_rate,nb_read_packets",
        "-of",
        "json",
    ]);
    let output = probe
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|source| spawn_error("ffprobe", path, source))?;
    if !output.status.success() {
        let message = String::from_utf8_lossy(&output.stderr).trim().to_owned();
        return Err(not_video(if message.is_empty() {
            "ffprobe could not read it".into()
        } else {
            message
        }));
    }
    let json: serde_json::Value = serde_json::from_slice(&output.stdout)
        .map_err(|e| not_video(format!("unexpected ffprobe output: {e}")))?;
    let Some(stream) = json["streams"].as_array().and_then(|s| s.first()) else {
        return Err(not_video("it has no video stream".into()));
    };
    let dimension = |key: &str| {
        stream[key]
            .as_u64()
            .and_then(|v| usize::try_from(v).ok())
            .filter(|&v| v > 0 && v <= 8192)
    };
    let (Some(width), Some(height)) = (dimension("width"), dimension("height")) else {
        return Err(not_video(
            "the video stream has no usable frame size".into(),
        ));
    };
    let rate = |key: &str| {
        let text = stream[key].as_str()?;
        let (n, d) = text.split_once('/').unwrap_or((text, "1"));
        let (n, d): (f64, f64) = (n.parse().ok()?, d.parse().ok()?);
        let fps = n / d;
        (fps.is_finite() && fps > 0.0 && fps <= 1000.0).then_some(fps as f32)
    };
    let Some(fps) = rate("avg_frame_rate").or_else(|| rate("r_frame_rate")) else {
        return Err(not_video("the video stream has no frame rate".into()));
    };
    let packets = stream["nb_read_packets"]
        .as_str()
        .and_then(|n| n.parse::<usize>().ok());
    if packets == Some(0) {
        return Err(not_video("the video has no frames".into()));
    }
    let mut decode = ffmpeg_command("ffmpeg");
    decode
        .arg("-i")
        .arg(path)
        .args(["-map", "0:v:0", "-an", "-sn", "-fps_mode", "cfr"])
        .args(["-r", &format!("{fps}")])
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = decode
        .spawn()
        .map_err(|source| spawn_error("ffmpeg", path, source))?;
    let stderr = child.stderr.take().map(|mut pipe| {
        std::thread::spawn(move || {
            let mut text = String::new();
            let _ = pipe.read_to_string(&mut text);
            text
        })
    });
    Ok(FrameSource {
        path: path.to_owned(),
        info: SourceInfo {
            width,
            height,
            fps,
            frames: packets,
        },
        kind: Kind::Video(child, stderr),
        delivered: 0,
        image_names: Vec::new(),
    })
}

fn read_video_frame(
    path: &Path,
    child: &mut Child,
    stderr: &mut Option<std::thread::JoinHandle<String>>,
    width: usize,
    height: usize,
    delivered: usize,
) -> Result<Option<Image>, MediaError> {
    let Some(stdout) = child.stdout.as_mut() else {
        return Ok(None);
    };
    let mut rgb = vec![0u8; width * height * 3];
    let mut filled = 0;
    while filled < rgb.len() {
        match stdout.read(&mut rgb[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(source) => {
                return Err(MediaError::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        }
    }
    if filled == rgb.len() {
        return Ok(Some(Image { width, height, rgb }));
    }
    // End of the pipe: a clean end, or ffmpeg failed.
    child.stdout = None;
    let status = child.wait().map_err(|source| MediaError::Io {
        path: path.to_owned(),
        source,
    })?;
    let message = stderr
        .take()
        .and_then(|reader| reader.join().ok())
        .unwrap_or_default();
    if !status.success() || filled != 0 {
        return Err(MediaError::Decode {
            path: path.to_owned(),
            frames: delivered,
            message: if message.trim().is_empty() {
                format!("{status}, {filled} bytes of a partial frame")
            } else {
                message.trim().to_owned()
            },
        });
    }
    if delivered == 0 {
        return Err(MediaError::NotVideo {
            path: path.to_owned(),
            message: "the video has no frames".into(),
        });
    }
    Ok(None)
}
