//! # faceanim-media: where capture's frames come from
//!
//! One [`FrameSource`] for every input a user points capture at: a still image (PNG, JPEG,
//! WebP, or a phone's HEIF — HEIC, AVIF — through libheif's `heif-dec`; told apart by their
//! bytes, not their names; turned upright as their EXIF or HEIF says), a folder of images (in
//! name order, as an image sequence), or a video file, decoded by Debian's `ffmpeg` program through a pipe.
//! Every frame comes out as 8-bit RGB, upright (a phone's rotated video is turned as a player
//! shows it). Video is resampled to a constant frame rate (the rate ffmpeg takes as the
//! stream's own) so that frame `i` is always at `i / fps` seconds: a dropped or duplicated
//! frame in the file never shifts the timeline.
//!
//! Raw frames from a caller (the studio's webcam, as packed RGB or the camera's own YUV) are
//! turned into the same [`Image`] by [`raw`].
#![deny(missing_docs)]

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

pub mod ffmpeg;
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
        png_bytes(self.width, self.height, png::ColorType::Rgb, &self.rgb)
    }
}

/// `pixels` (`width`×`height` of `color`, 8 bits a channel) as PNG bytes, fast compression.
fn png_bytes(
    width: usize,
    height: usize,
    color: png::ColorType,
    pixels: &[u8],
) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let width = u32::try_from(width).map_err(|e| e.to_string())?;
    let height = u32::try_from(height).map_err(|e| e.to_string())?;
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(pixels).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
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
    /// A HEIF photo (HEIC, as iPhones save them; AVIF), and no program here to decode it.
    #[error(
        "{path}: a HEIF photo (HEIC, as iPhones save them, or AVIF): reading it needs libheif's \
         heif-dec or heif-convert, which was not found. Install it (Debian/Ubuntu: `sudo apt-get \
         install libheif-examples`; macOS: `brew install libheif`), or save the photo as JPEG"
    )]
    HeifDecoderMissing {
        /// The photo.
        path: PathBuf,
    },
    /// A folder holds no photos.
    #[error("{path}: the folder has no PNG, JPEG, WebP or HEIF images")]
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
        /// What ffmpeg said, or what is missing.
        message: String,
    },
    /// `ffmpeg` is not installed.
    #[error(
        "{path}: reading video needs the ffmpeg program, which was not found ({program}: {source}). \
         Install it (Debian/Ubuntu: `sudo apt-get install ffmpeg`; macOS: `brew install ffmpeg`), \
         or give a folder of PNG/JPEG frames instead"
    )]
    FfmpegMissing {
        /// The input.
        path: PathBuf,
        /// The program: `ffmpeg`.
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
    } else if head.len() >= 12 && head.starts_with(b"RIFF") && &head[8..12] == b"WEBP" {
        Some("webp")
    } else if head.starts_with(&KTX2_MAGIC) {
        Some("ktx2")
    } else {
        None
    }
}

/// The first bytes of every KTX2 file: «KTX 20», CR LF, EOF, LF.
const KTX2_MAGIC: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// Decodes a PNG, JPEG, WebP (lossy or lossless, the first frame of an animation) or KTX2
/// (Basis Universal, ETC1S or UASTC, its largest level: `KHR_texture_basisu`) held in memory —
/// the textures avatars ship — alpha dropped; `path` is only for messages.
///
/// # Errors
/// [`MediaError::BadImage`] for anything that is not a complete PNG, JPEG, WebP or Basis
/// Universal KTX2.
pub fn decode_image(path: &Path, bytes: &[u8]) -> Result<Image, MediaError> {
    decode_image_alpha(path, bytes).map(|(image, _)| image)
}

/// [`decode_image`], with the image's alpha (one byte a pixel) when it has one: a PNG, WebP or
/// KTX2 texture that cuts lashes, brows or hair out.
///
/// # Errors
/// As [`decode_image`].
pub fn decode_image_alpha(
    path: &Path,
    bytes: &[u8],
) -> Result<(Image, Option<Vec<u8>>), MediaError> {
    let bad = |message: String| MediaError::BadImage {
        path: path.to_owned(),
        message,
    };
    match image_kind(bytes) {
        Some("png") => decode_png(bytes).map_err(bad),
        Some("webp") => decode_webp(bytes).map_err(bad),
        Some("ktx2") => decode_ktx2(bytes).map_err(bad),
        Some(_) => decode_jpeg(bytes).map(|image| (image, None)).map_err(bad),
        None => Err(bad("neither PNG, JPEG, WebP nor KTX2".into())),
    }
}

/// A texture as a browser shows it without a transcoder: a KTX2 image (see [`decode_image`])
/// as PNG (with its alpha when it has one); `None` for any other image, which browsers show
/// as it is.
///
/// # Errors
/// [`MediaError::BadImage`] for a KTX2 image that does not decode.
pub fn browser_image(path: &Path, bytes: &[u8]) -> Result<Option<Vec<u8>>, MediaError> {
    if image_kind(bytes) != Some("ktx2") {
        return Ok(None);
    }
    let (image, alpha) = decode_image_alpha(path, bytes)?;
    let png = match alpha {
        None => image.to_png(),
        Some(alpha) => rgba_png(&image, &alpha),
    };
    png.map(Some).map_err(|message| MediaError::BadImage {
        path: path.to_owned(),
        message,
    })
}

/// `image` with `alpha` as an RGBA PNG (fast compression).
fn rgba_png(image: &Image, alpha: &[u8]) -> Result<Vec<u8>, String> {
    let rgba: Vec<u8> = image
        .rgb
        .chunks_exact(3)
        .zip(alpha)
        .flat_map(|(p, &a)| [p[0], p[1], p[2], a])
        .collect();
    png_bytes(image.width, image.height, png::ColorType::Rgba, &rgba)
}

/// A Basis Universal KTX2 (ETC1S or UASTC LDR, the supercompressions `KHR_texture_basisu`
/// allows), its largest level transcoded to RGBA by the `basisu` crate (a port of Binomial's
/// reference transcoder, byte for byte). The transcoder is young: a panic inside it becomes
/// this image's error, never the program's end.
fn decode_ktx2(bytes: &[u8]) -> Result<(Image, Option<Vec<u8>>), String> {
    use basisu::{DecodeFlags, TargetFormat, Transcoder};
    let decoded = std::panic::catch_unwind(|| {
        let texture = Transcoder::new(bytes).map_err(|e| format!("KTX2: {e:?}"))?;
        let (width, height) = texture.base_dimensions();
        let (width, height) = (width as usize, height as usize);
        check_size(width, height)?;
        let rgba = texture
            .transcode(0, TargetFormat::Rgba32, DecodeFlags::NONE)
            .map_err(|e| format!("KTX2 ({:?}): {e:?}", texture.source_format()))?;
        if rgba.len() != width * height * 4 {
            return Err(format!(
                "KTX2: {} bytes for {width}×{height} RGBA",
                rgba.len()
            ));
        }
        Ok((width, height, rgba, texture.has_alpha()))
    })
    .map_err(|_| "KTX2: the Basis Universal transcoder failed on this file".to_owned())?;
    let (width, height, rgba, has_alpha) = decoded?;
    let rgb = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let alpha = has_alpha.then(|| rgba.chunks_exact(4).map(|p| p[3]).collect());
    Ok((Image { width, height, rgb }, alpha))
}

/// Images larger than this (in pixels) are refused rather than allocated.
const MAX_PIXELS: usize = 8192 * 8192;

/// Refuses an image of no pixels, or of more than [`MAX_PIXELS`], before it is allocated.
fn check_size(width: usize, height: usize) -> Result<(), String> {
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_PIXELS {
        return Err(format!("{width}×{height} pixels is not a size we read"));
    }
    Ok(())
}

fn decode_png(bytes: &[u8]) -> Result<(Image, Option<Vec<u8>>), String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // 16-bit to 8, palettes and low bit depths to whole bytes.
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let (width, height) = {
        let info = reader.info();
        (info.width as usize, info.height as usize)
    };
    check_size(width, height)?;
    let size = reader
        .output_buffer_size()
        .ok_or("image too large for memory")?;
    let mut buffer = vec![0; size];
    let frame = reader.next_frame(&mut buffer).map_err(|e| e.to_string())?;
    let channels = frame.color_type.samples();
    let row = frame.line_size;
    let mut rgb = Vec::with_capacity(width * height * 3);
    let mut alpha = matches!(channels, 2 | 4).then(|| Vec::with_capacity(width * height));
    for y in 0..height {
        let line = &buffer[y * row..y * row + width * channels];
        for pixel in line.chunks_exact(channels) {
            match channels {
                1 | 2 => rgb.extend([pixel[0]; 3]),
                _ => rgb.extend(&pixel[..3]),
            }
            if let Some(alpha) = alpha.as_mut() {
                alpha.push(pixel[channels - 1]);
            }
        }
    }
    Ok((Image { width, height, rgb }, alpha))
}

fn decode_webp(bytes: &[u8]) -> Result<(Image, Option<Vec<u8>>), String> {
    let mut decoder =
        image_webp::WebPDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let (width, height) = decoder.dimensions();
    let (width, height) = (width as usize, height as usize);
    check_size(width, height)?;
    let size = decoder
        .output_buffer_size()
        .ok_or("image too large for memory")?;
    let mut buffer = vec![0; size];
    decoder.read_image(&mut buffer).map_err(|e| e.to_string())?;
    let (rgb, alpha) = if decoder.has_alpha() {
        (
            buffer
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect(),
            Some(buffer.chunks_exact(4).map(|p| p[3]).collect()),
        )
    } else {
        (buffer, None)
    };
    Ok((Image { width, height, rgb }, alpha))
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

/// Reads and decodes a photo or frame (PNG, JPEG, WebP, KTX2, or HEIF through libheif's own
/// program), upright as a viewer shows it: a JPEG whose EXIF says how it is turned (a phone's
/// portrait photo, its pixels stored sideways) is turned so, a HEIF as its own rotation says. Textures are read with [`decode_image`], as glTF uses them: never
/// turned.
///
/// # Errors
/// [`MediaError::Io`] or [`MediaError::BadImage`].
pub fn read_image(path: &Path) -> Result<Image, MediaError> {
    let bytes = std::fs::read(path).map_err(|source| MediaError::Io {
        path: path.to_owned(),
        source,
    })?;
    if heif_still(&bytes) {
        return read_heif(path, &bytes);
    }
    let image = decode_image(path, &bytes)?;
    Ok(match exif_orientation(&bytes) {
        Some(orientation) => image.oriented(orientation),
        None => image,
    })
}

/// Whether `bytes` are a HEIF still image (ISO/IEC 23008-12): an ISO media file whose brand
/// says HEVC-coded (`heic`, `heix`: iPhones' photos since iOS 11), the general image brand
/// (`mif1`) or AVIF.
fn heif_still(bytes: &[u8]) -> bool {
    bytes.get(4..8) == Some(b"ftyp")
        && matches!(
            bytes.get(8..12),
            Some(b"heic" | b"heix" | b"heim" | b"heis" | b"mif1" | b"avif")
        )
}

/// A HEIF photo, decoded by libheif's own program (`heif-dec`, called `heif-convert` before
/// libheif 1.17) into a JPEG beside the system's temporary files, which is read and removed.
/// libheif turns the picture as the file's rotation and mirroring say (HEIF keeps them in its
/// own boxes, not in EXIF), so it comes out upright; of several top-level images (a burst),
/// the first.
fn read_heif(path: &Path, photo: &[u8]) -> Result<Image, MediaError> {
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    // JPEG at high quality, not PNG: libheif's PNG writer fails on the colour profiles phones
    // embed (Display P3) and still exits 0.
    let out = std::env::temp_dir().join(format!("faceanim-heif-{}-{n}.jpg", std::process::id()));
    let bad = |message: String| MediaError::BadImage {
        path: path.to_owned(),
        message,
    };
    let mut ran = None;
    for program in ["heif-dec", "heif-convert"] {
        match Command::new(program)
            .args(["-q", "95"])
            .arg(path)
            .arg(&out)
            .stdin(Stdio::null())
            .output()
        {
            Ok(output) => {
                ran = Some((program, output));
                break;
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => {
                return Err(MediaError::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        }
    }
    let Some((program, output)) = ran else {
        return Err(MediaError::HeifDecoderMissing {
            path: path.to_owned(),
        });
    };
    // Several top-level images are written numbered from 1.
    let stem = out
        .file_stem()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned();
    let numbered = |k: usize| out.with_file_name(format!("{stem}-{k}.jpg"));
    let written = [out.clone(), numbered(1)].into_iter().find(|p| p.exists());
    let bytes = written.map(std::fs::read);
    // Every file it wrote goes.
    let _ = std::fs::remove_file(&out);
    let mut k = 1;
    while std::fs::remove_file(numbered(k)).is_ok() {
        k += 1;
    }
    match bytes {
        Some(Ok(decoded)) if output.status.success() && !decoded.is_empty() => {
            let image = decode_image(path, &decoded)?;
            // A HEIF that says its rotation only in EXIF (as some encoders write it, libheif
            // 1.15's own heif-enc among them) is turned as a JPEG would be; one with HEIF's own
            // rotation or mirroring was turned by libheif, and its EXIF (which iPhones keep in
            // step) is not read again.
            Ok(match heif_exif_orientation(photo) {
                Some(orientation) => image.oriented(orientation),
                None => image,
            })
        }
        _ => {
            let said = String::from_utf8_lossy(&output.stderr);
            let said = said
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("no image written");
            Err(bad(format!("HEIF: {program}: {}", said.trim())))
        }
    }
}

/// The EXIF orientation (2 to 8) of a HEIF photo that has no rotation or mirroring of HEIF's
/// own (`irot`, `imir` among its item properties, `meta` → `iprp` → `ipco`): its Exif item's.
fn heif_exif_orientation(bytes: &[u8]) -> Option<u8> {
    let meta = iso_box(bytes, b"meta")?;
    // `meta` is a full box: a version and flags before its boxes.
    let properties = iso_box(meta.get(4..)?, b"iprp").and_then(|p| iso_box(p, b"ipco"))?;
    if iso_box(properties, b"irot").is_some() || iso_box(properties, b"imir").is_some() {
        return None;
    }
    // An Exif item is the offset of its TIFF header past these four bytes, then the EXIF:
    // the header at once (0, as libheif writes it) or after `Exif\0\0` (6, as cameras do).
    let tiff = [&b"\0\0\0\0"[..], b"\0\0\0\x06Exif\0\0"]
        .iter()
        .find_map(|prefix| {
            [&b"MM\0*"[..], b"II*\0"].iter().find_map(|header| {
                let marked = [*prefix, *header].concat();
                bytes
                    .windows(marked.len())
                    .position(|w| w == marked)
                    .map(|at| at + prefix.len())
            })
        })?;
    tiff_orientation(&bytes[tiff..]).filter(|o| (2..=8).contains(o))
}

/// The contents of the first ISO media box of type `kind` among those `bytes` hold, one level
/// down (each box a big-endian length that counts its own eight bytes, and its type; a length
/// of 1 says a 64-bit one follows, 0 that the box runs to the end).
fn iso_box<'a>(bytes: &'a [u8], kind: &[u8; 4]) -> Option<&'a [u8]> {
    let mut at = 0usize;
    while at + 8 <= bytes.len() {
        let size = u32::from_be_bytes(bytes[at..at + 4].try_into().ok()?);
        let (header, size) = match size {
            0 => (8, bytes.len() - at),
            1 => {
                let large = u64::from_be_bytes(bytes.get(at + 8..at + 16)?.try_into().ok()?);
                (16, usize::try_from(large).ok()?)
            }
            n => (8, usize::try_from(n).ok()?),
        };
        if size < header {
            return None;
        }
        let contents = bytes.get(at + header..at.checked_add(size)?)?;
        if &bytes[at + 4..at + 8] == kind {
            return Some(contents);
        }
        at += size;
    }
    None
}

/// The EXIF orientation (2 to 8: 1 is upright) of a JPEG's first `Exif` segment, from its first
/// image directory's tag 0x0112; `None` for any other image, upright ones, or EXIF that does
/// not hold one where it says.
#[must_use]
pub fn exif_orientation(bytes: &[u8]) -> Option<u8> {
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    let mut at = 2;
    // The segments before the image's data: each a marker and a big-endian length that counts
    // itself.
    while at + 4 <= bytes.len() && bytes[at] == 0xFF {
        let marker = bytes[at + 1];
        if marker == 0xDA || marker == 0xD9 {
            return None;
        }
        let length = usize::from(u16::from_be_bytes([bytes[at + 2], bytes[at + 3]]));
        let segment = bytes.get(at + 4..at + 2 + length)?;
        if marker == 0xE1
            && let Some(tiff) = segment.strip_prefix(b"Exif\0\0")
        {
            return tiff_orientation(tiff).filter(|o| (2..=8).contains(o));
        }
        at += 2 + length;
    }
    None
}

/// Tag 0x0112 of a TIFF header's first directory.
fn tiff_orientation(tiff: &[u8]) -> Option<u8> {
    let little = match tiff.get(..4)? {
        [b'I', b'I', 42, 0] => true,
        [b'M', b'M', 0, 42] => false,
        _ => return None,
    };
    let u16_at = |at: usize| -> Option<u16> {
        let pair: [u8; 2] = tiff.get(at..at + 2)?.try_into().ok()?;
        Some(if little {
            u16::from_le_bytes(pair)
        } else {
            u16::from_be_bytes(pair)
        })
    };
    let quad: [u8; 4] = tiff.get(4..8)?.try_into().ok()?;
    let directory = usize::try_from(if little {
        u32::from_le_bytes(quad)
    } else {
        u32::from_be_bytes(quad)
    })
    .ok()?;
    let entries = usize::from(u16_at(directory)?);
    (0..entries).find_map(|k| {
        let entry = directory.checked_add(2 + 12 * k)?;
        // A SHORT (type 3), one of it, held in the entry itself.
        (u16_at(entry)? == 0x0112 && u16_at(entry + 2)? == 3)
            .then(|| u16_at(entry + 8))
            .flatten()
            .and_then(|o| u8::try_from(o).ok())
    })
}

impl Image {
    /// The image as a viewer shows it when its EXIF orientation is `orientation` (1 to 8):
    /// mirrored (2, 4), turned half round (3), or turned a quarter (6 clockwise, 8
    /// anticlockwise) and mirrored across a diagonal (5, 7). Any other value leaves it as it
    /// is.
    #[must_use]
    pub fn oriented(self, orientation: u8) -> Image {
        if !(2..=8).contains(&orientation) {
            return self;
        }
        let (w, h) = (self.width, self.height);
        let (width, height) = if orientation >= 5 { (h, w) } else { (w, h) };
        let mut rgb = vec![0u8; self.rgb.len()];
        for y in 0..height {
            for x in 0..width {
                // Where the shown pixel (x, y) is stored.
                let (sx, sy) = match orientation {
                    2 => (w - 1 - x, y),
                    3 => (w - 1 - x, h - 1 - y),
                    4 => (x, h - 1 - y),
                    5 => (y, x),
                    6 => (y, h - 1 - x),
                    7 => (w - 1 - y, h - 1 - x),
                    _ => (w - 1 - y, x),
                };
                let (d, s) = ((y * width + x) * 3, (sy * w + sx) * 3);
                rgb[d..d + 3].copy_from_slice(&self.rgb[s..s + 3]);
            }
        }
        Image { width, height, rgb }
    }
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
    /// How many frames there will be, when known in advance: exact for images, from the
    /// duration for a video (about right; for a progress bar, not a promise).
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
                        matches!(
                            e.to_ascii_lowercase().as_str(),
                            "png" | "jpg" | "jpeg" | "webp" | "heic" | "heif" | "avif"
                        )
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
        let mut head = [0u8; 12];
        let read = std::fs::File::open(path)
            .and_then(|mut f| f.read(&mut head))
            .map_err(io)?;
        if image_kind(&head[..read]).is_some() || heif_still(&head[..read]) {
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
        self.next_frame_reusing(None)
    }

    /// [`FrameSource::next_frame`], a video's frame read into `spare` (the bytes of a frame
    /// the caller is done with) when it is of this source's size: a long video then allocates
    /// and clears no frame-sized memory per frame (190 MB a second at 1080p and 30 fps).
    ///
    /// # Errors
    /// As [`FrameSource::next_frame`].
    pub fn next_frame_reusing(
        &mut self,
        spare: Option<Vec<u8>>,
    ) -> Result<Option<Image>, MediaError> {
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
                let bytes = width * height * 3;
                let rgb = spare
                    .filter(|spare| spare.len() == bytes)
                    .unwrap_or_else(|| vec![0; bytes]);
                let frame = Image { width, height, rgb };
                read_video_frame(&self.path, child, stderr, frame, self.delivered)?
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

/// The error of a failed start of ffmpeg on `path`: missing, or another input/output error.
fn spawn_error(path: &Path, source: std::io::Error) -> MediaError {
    if source.kind() == std::io::ErrorKind::NotFound {
        MediaError::FfmpegMissing {
            path: path.to_owned(),
            program: "ffmpeg",
            source,
        }
    } else {
        MediaError::Io {
            path: path.to_owned(),
            source,
        }
    }
}

/// Opens a video with one ffmpeg process, which decodes it and says on stderr what it writes.
///
/// Each run of ffmpeg costs about 60 ms before it reads a byte (Debian's build loads some 200
/// libraries), so the video is not probed first by a second program: ffmpeg's own account of
/// the stream it writes (its `[info]` header, tagged by `-v level+info`) gives the frame size
/// after rotation (a phone's portrait video is turned upright) and the constant rate it writes
/// at; the input's duration gives the frame count, approximately. Everything else ffmpeg says
/// is kept for the messages of errors.
fn open_video(path: &Path) -> Result<FrameSource, MediaError> {
    let mut child = Command::new("ffmpeg")
        .args([
            "-v",
            "level+info",
            "-nostats",
            "-hide_banner",
            "-nostdin",
            "-i",
        ])
        .arg(path)
        .args(["-map", "0:v:0", "-an", "-sn", "-dn", "-fps_mode", "cfr"])
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|source| spawn_error(path, source))?;
    widen_pipe(&child);
    let Some(stderr) = child.stderr.take() else {
        return Err(MediaError::Io {
            path: path.to_owned(),
            source: std::io::Error::other("ffmpeg's error output was not opened"),
        });
    };
    let mut log = std::io::BufReader::new(stderr);
    let header = match read_header(&mut log) {
        Ok(header) => header,
        Err(said) => {
            // ffmpeg ended (or its stream line was not understood): reap it, then say why.
            let _ = child.kill();
            let _ = child.wait();
            return Err(MediaError::NotVideo {
                path: path.to_owned(),
                message: said,
            });
        }
    };
    let stderr = std::thread::spawn(move || {
        let mut errors = String::new();
        let _ = read_log(&mut log, |error, text| {
            if error {
                errors.push_str(text);
                errors.push('\n');
            }
            std::ops::ControlFlow::Continue(())
        });
        errors
    });
    Ok(FrameSource {
        path: path.to_owned(),
        info: SourceInfo {
            width: header.width,
            height: header.height,
            fps: header.fps,
            frames: header.frames,
        },
        kind: Kind::Video(child, Some(stderr)),
        delivered: 0,
        image_names: Vec::new(),
    })
}

/// A Linux pipe holds 64 KiB: a 1080p frame (6 MB) then crosses in about a hundred turns of
/// ffmpeg writing and this process reading, each a pair of wake-ups. Raised to 1 MiB (an
/// unprivileged process's limit) it takes a few. Where the system refuses, the pipe stays as
/// it was.
#[cfg(target_os = "linux")]
fn widen_pipe(child: &Child) {
    if let Some(stdout) = child.stdout.as_ref() {
        let _ = rustix::pipe::fcntl_setpipe_size(stdout, 1 << 20);
    }
}

#[cfg(not(target_os = "linux"))]
fn widen_pipe(_: &Child) {}

/// Reads ffmpeg's `-v level+…` log line by line, calling `line` with whether the line's tag
/// says an error (`[panic]`, `[fatal]`, `[error]`) and its text without the tag, until the
/// log ends or `line` breaks.
fn read_log(
    log: &mut impl std::io::BufRead,
    mut line: impl FnMut(bool, &str) -> std::ops::ControlFlow<()>,
) -> std::io::Result<()> {
    let mut bytes = Vec::new();
    loop {
        bytes.clear();
        if log.read_until(b'\n', &mut bytes)? == 0 {
            return Ok(());
        }
        let text = String::from_utf8_lossy(&bytes);
        let text = text.trim_end();
        let (error, rest) = match text.strip_prefix('[').and_then(|t| t.split_once("] ")) {
            Some((tag, rest)) => (matches!(tag, "panic" | "fatal" | "error"), rest),
            None => (false, text),
        };
        if line(error, rest).is_break() {
            return Ok(());
        }
    }
}

/// What ffmpeg's header says of the video it is about to write.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Header {
    width: usize,
    height: usize,
    fps: f32,
    frames: Option<usize>,
}

/// Reads ffmpeg's log up to the line describing its output's video stream. On failure, what
/// to tell the user: ffmpeg's errors, or what was missing.
fn read_header(log: &mut impl std::io::BufRead) -> Result<Header, String> {
    let mut errors: Vec<String> = Vec::new();
    let mut duration = None;
    let mut output = false;
    let mut stream: Option<Result<(usize, usize, f32), String>> = None;
    read_log(log, |error, text| {
        if error {
            errors.push(text.to_owned());
        } else if output {
            if text.trim_start().starts_with("Stream #") && text.contains(" Video: ") {
                stream = Some(output_stream(text));
                return std::ops::ControlFlow::Break(());
            }
        } else if text.starts_with("Output #") {
            output = true;
        } else if let Some(rest) = text.trim_start().strip_prefix("Duration: ") {
            duration = duration.or_else(|| parse_duration(rest));
        }
        std::ops::ControlFlow::Continue(())
    })
    .map_err(|e| format!("reading ffmpeg's messages: {e}"))?;
    match stream {
        Some(Ok((width, height, fps))) => Ok(Header {
            width,
            height,
            fps,
            frames: duration
                .map(|seconds| (seconds * f64::from(fps)).round())
                .filter(|n| (1.0..1e9).contains(n))
                .map(|n| n as usize),
        }),
        Some(Err(message)) => Err(message),
        None if errors.iter().any(|e| e.contains("matches no streams")) => {
            Err("it has no video stream".into())
        }
        None if errors.is_empty() => Err("the video has no frames".into()),
        None => Err(ffmpeg::explain(&errors.join("\n"))),
    }
}

/// The frame size and rate in ffmpeg's line for the video stream it writes, such as `Stream
/// #0:0: Video: rawvideo (RGB[24] / 0x18424752), rgb24(pc, progressive), 400x300 [SAR 1:1 DAR
/// 4:3], q=2-31, 72000 kb/s, 29.97 fps, 30k tbn`.
fn output_stream(line: &str) -> Result<(usize, usize, f32), String> {
    // What is in brackets (codec tags, colour details) is not a field of its own.
    let mut depth = 0usize;
    let flat: String = line
        .chars()
        .filter(|&c| {
            match c {
                '(' => depth += 1,
                ')' => depth = depth.saturating_sub(1),
                _ => return depth == 0,
            }
            false
        })
        .collect();
    let fields: Vec<&str> = flat.split(',').map(str::trim).collect();
    let size = fields.iter().find_map(|field| {
        let (w, h) = field.split_whitespace().next()?.split_once('x')?;
        let dimension = |text: &str| text.parse::<usize>().ok().filter(|&v| v > 0 && v <= 8192);
        Some((dimension(w)?, dimension(h)?))
    });
    let Some((width, height)) = size else {
        return Err(format!(
            "the video stream has no usable frame size ({line})"
        ));
    };
    let fps = fields
        .iter()
        .find_map(|field| parse_rate(field.strip_suffix(" fps")?))
        .ok_or_else(|| format!("the video stream has no frame rate ({line})"))?;
    Ok((width, height, fps))
}

/// A rate as ffmpeg prints one: `25`, `29.97` (two decimals: the NTSC rates, `N/1.001`, are
/// taken as such), `1k`.
fn parse_rate(text: &str) -> Option<f32> {
    let (number, scale) = match text.strip_suffix('k') {
        Some(n) => (n, 1000.0),
        None => (text, 1.0),
    };
    let printed = number.parse::<f64>().ok()? * scale;
    let ntsc = (printed * 1.001).round() / 1.001;
    let fps = if number.contains('.') && (ntsc - printed).abs() < 0.006 {
        ntsc
    } else {
        printed
    };
    (fps.is_finite() && fps > 0.0 && fps <= 1000.0).then_some(fps as f32)
}

/// Seconds from ffmpeg's `HH:MM:SS.cc, start: …`; `None` for `N/A`.
fn parse_duration(text: &str) -> Option<f64> {
    let clock = text.split(',').next()?.trim();
    let mut parts = clock.split(':');
    let (h, m, s) = (parts.next()?, parts.next()?, parts.next()?);
    let seconds =
        h.parse::<f64>().ok()? * 3600.0 + m.parse::<f64>().ok()? * 60.0 + s.parse::<f64>().ok()?;
    (seconds.is_finite() && seconds > 0.0).then_some(seconds)
}

/// Reads the next frame of the video into `frame`'s bytes: `None` at its clean end.
fn read_video_frame(
    path: &Path,
    child: &mut Child,
    stderr: &mut Option<std::thread::JoinHandle<String>>,
    mut frame: Image,
    delivered: usize,
) -> Result<Option<Image>, MediaError> {
    let Some(stdout) = child.stdout.as_mut() else {
        return Ok(None);
    };
    let mut filled = 0;
    while filled < frame.rgb.len() {
        match stdout.read(&mut frame.rgb[filled..]) {
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
    if filled == frame.rgb.len() {
        return Ok(Some(frame));
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
                ffmpeg::explain(&message)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_webp_with_alpha_decodes_to_its_colours() {
        // Lossless WebP, written by image-webp's own encoder: a red half and a blue half, the
        // blue one transparent (its colour kept, its alpha given apart).
        let (width, height) = (8u32, 4u32);
        let rgba: Vec<u8> = (0..width * height)
            .flat_map(|i| {
                if i % width < 4 {
                    [255, 0, 0, 255]
                } else {
                    [0, 0, 255, 0]
                }
            })
            .collect();
        let mut webp = Vec::new();
        image_webp::WebPEncoder::new(&mut webp)
            .encode(&rgba, width, height, image_webp::ColorType::Rgba8)
            .unwrap();
        let (image, alpha) = decode_image_alpha(Path::new("texture.webp"), &webp).unwrap();
        assert_eq!((image.width, image.height), (8, 4));
        let alpha = alpha.unwrap();
        assert_eq!((alpha[0], alpha[7]), (255, 0));
        assert_eq!(&image.rgb[..3], &[255, 0, 0]);
        assert_eq!(&image.rgb[7 * 3..8 * 3], &[0, 0, 255]);
        let broken = decode_image(Path::new("broken.webp"), &webp[..webp.len() / 2]).unwrap_err();
        assert!(broken.to_string().contains("broken.webp"), "{broken}");
    }

    /// ffmpeg 5.1's log for a 400×300 H.264 clip, as `-v level+info` prints it.
    const LOG: &str = "[info] Input #0, mov,mp4,m4a,3gp,3g2,mj2, from 'clip.mp4':
[info]   Metadata:
[info]     encoder         : Lavf59.27.100
[info]   Duration: 00:00:03.60, start: 0.000000, bitrate: 189 kb/s
[info]   Stream #0:0[0x1](und): Video: h264 (High) (avc1 / 0x31637661), yuv420p(progressive), 640x360 [SAR 1:1 DAR 4:3], 185 kb/s, 24 fps, 24 tbr, 12800 tbn (default)
[info] Stream mapping:
[info]   Stream #0:0 -> #0:0 (h264 (native) -> rawvideo (native))
[info] Output #0, rawvideo, to 'pipe:':
[info]   Metadata:
[info]     encoder         : Lavf59.27.100
[info]   Stream #0:0(und): Video: rawvideo (RGB[24] / 0x18424752), rgb24(pc, gbr/unknown/unknown, progressive), 400x300 [SAR 1:1 DAR 4:3], q=2-31, 72000 kb/s, 25 fps, 25 tbn (default)
[info]     Metadata:
";

    #[test]
    fn a_broken_ktx2_is_an_error_naming_the_file() {
        let path = Path::new("face.ktx2");
        // A KTX2 header and nothing, then a header with bytes no encoder wrote (a 64×64
        // image claimed, its index and data pointing anywhere).
        let mut noise = KTX2_MAGIC.to_vec();
        noise.extend((0u32..400).map(|k| (k.wrapping_mul(2_654_435_761) >> 13) as u8));
        for bytes in [KTX2_MAGIC.to_vec(), noise] {
            let error = decode_image(path, &bytes).unwrap_err().to_string();
            assert!(
                error.contains("face.ktx2") && error.contains("KTX2"),
                "{error}"
            );
            assert!(browser_image(path, &bytes).is_err());
        }
        // Other images go to the page as they are.
        assert!(matches!(
            browser_image(path, b"\x89PNG\r\n\x1a\n"),
            Ok(None)
        ));
    }

    #[test]
    fn the_header_is_the_output_streams_not_the_inputs() {
        let header = read_header(&mut LOG.as_bytes()).unwrap();
        assert_eq!(
            header,
            Header {
                width: 400,
                height: 300,
                fps: 25.0,
                frames: Some(90)
            }
        );
    }

    #[test]
    fn rates_as_ffmpeg_prints_them() {
        let ntsc = |n: f64| (n / 1.001) as f32;
        assert_eq!(parse_rate("29.97"), Some(ntsc(30.0)));
        assert_eq!(parse_rate("23.98"), Some(ntsc(24.0)));
        assert_eq!(parse_rate("59.94"), Some(ntsc(60.0)));
        assert_eq!(parse_rate("12.50"), Some(12.5));
        assert_eq!(parse_rate("25"), Some(25.0));
        assert_eq!(parse_rate("1k"), Some(1000.0));
        assert_eq!(parse_rate("0"), None);
        assert_eq!(parse_rate("many"), None);
        assert_eq!(parse_duration("01:02:03.50, start: 0.0"), Some(3723.5));
        assert_eq!(parse_duration("N/A, bitrate: N/A"), None);
    }

    #[test]
    fn what_ffmpeg_says_when_it_stops_is_the_message() {
        let none = "[info] Input #0, matroska,webm, from 'a.mkv':\n[error] Stream map '0:v:0' matches no streams.\n[fatal] To ignore this, add a trailing '?' to the map.\n";
        assert_eq!(
            read_header(&mut none.as_bytes()).unwrap_err(),
            "it has no video stream"
        );
        let text = "[error] notes.mp4: Invalid data found when processing input\n";
        assert_eq!(
            read_header(&mut text.as_bytes()).unwrap_err(),
            "not a video, sound or picture that ffmpeg can read (damaged, or another kind of file)"
        );
        assert_eq!(
            read_header(&mut "".as_bytes()).unwrap_err(),
            "the video has no frames"
        );
        let odd = "[info] Output #0, rawvideo, to 'pipe:':\n[info]   Stream #0:0: Video: rawvideo, rgb24, 25 fps\n";
        assert!(
            read_header(&mut odd.as_bytes())
                .unwrap_err()
                .contains("no usable frame size")
        );
    }
}
