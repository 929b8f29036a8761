//! Raw camera frames as a caller hands them over (the studio's webcam, straight from the
//! browser's `VideoFrame`): packed RGB with a fourth byte, or planar YUV 4:2:0 as cameras
//! produce it. Sending YUV as it comes saves the browser a conversion and the wire 60 % of the
//! bytes; this module turns each layout into an [`Image`].

use crate::Image;

/// Which colour matrix turned RGB into YUV (the camera says; browsers report it per frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YuvMatrix {
    /// ITU-R BT.601 (SMPTE 170M, BT.470 BG): standard-definition cameras and most webcams.
    Bt601,
    /// ITU-R BT.709: high-definition cameras.
    Bt709,
}

/// How YUV samples use the byte range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YuvRange {
    /// Luma 16–235, chroma 16–240 (video, "TV" range).
    Limited,
    /// 0–255 for all three (JPEG, "PC" range).
    Full,
}

/// The byte layout of a raw frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelLayout {
    /// 4 bytes per pixel: red, green, blue, then alpha or padding (ignored).
    Rgbx,
    /// 4 bytes per pixel: blue, green, red, then alpha or padding (ignored).
    Bgrx,
    /// Planar 4:2:0: the luma plane, then the U plane, then the V plane, each tightly packed;
    /// chroma planes are `⌈width/2⌉ × ⌈height/2⌉`.
    I420(YuvMatrix, YuvRange),
    /// Semi-planar 4:2:0: the luma plane, then one plane of interleaved U, V pairs.
    Nv12(YuvMatrix, YuvRange),
}

impl PixelLayout {
    /// The layout a browser's `VideoFrame.format` names (`RGBA`, `RGBX`, `BGRA`, `BGRX`,
    /// `I420`, `NV12`), with the frame's colour matrix and range for YUV.
    ///
    /// # Errors
    /// A message naming the unsupported format.
    pub fn from_names(format: &str, matrix: YuvMatrix, range: YuvRange) -> Result<Self, String> {
        Ok(match format.to_ascii_uppercase().as_str() {
            "RGBA" | "RGBX" => PixelLayout::Rgbx,
            "BGRA" | "BGRX" => PixelLayout::Bgrx,
            "I420" => PixelLayout::I420(matrix, range),
            "NV12" => PixelLayout::Nv12(matrix, range),
            other => {
                return Err(format!(
                    "pixel format {other:?} is not supported (RGBA, RGBX, BGRA, BGRX, I420, NV12 are)"
                ));
            }
        })
    }

    /// The layout's name in messages (the packed ones by their alpha spelling, as browsers
    /// send them).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            PixelLayout::Rgbx => "RGBA",
            PixelLayout::Bgrx => "BGRA",
            PixelLayout::I420(..) => "I420",
            PixelLayout::Nv12(..) => "NV12",
        }
    }

    /// The number of bytes a `width × height` frame takes.
    #[must_use]
    pub fn frame_bytes(self, width: usize, height: usize) -> usize {
        match self {
            PixelLayout::Rgbx | PixelLayout::Bgrx => width * height * 4,
            PixelLayout::I420(..) | PixelLayout::Nv12(..) => {
                width * height + 2 * width.div_ceil(2) * height.div_ceil(2)
            }
        }
    }
}

/// Converts a raw frame to RGB.
///
/// # Errors
/// A message when the byte count does not match the layout and size.
pub fn raw_to_image(
    layout: PixelLayout,
    width: usize,
    height: usize,
    bytes: &[u8],
) -> Result<Image, String> {
    let expected = layout.frame_bytes(width, height);
    if bytes.len() != expected {
        return Err(format!(
            "{} bytes is not a {width}×{height} {} frame ({expected} bytes)",
            bytes.len(),
            layout.name()
        ));
    }
    let mut rgb = vec![0u8; width * height * 3];
    match layout {
        PixelLayout::Rgbx => {
            for (out, pixel) in rgb.chunks_exact_mut(3).zip(bytes.chunks_exact(4)) {
                out.copy_from_slice(&pixel[..3]);
            }
        }
        PixelLayout::Bgrx => {
            for (out, pixel) in rgb.chunks_exact_mut(3).zip(bytes.chunks_exact(4)) {
                out.copy_from_slice(&[pixel[2], pixel[1], pixel[0]]);
            }
        }
        PixelLayout::I420(matrix, range) | PixelLayout::Nv12(matrix, range) => {
            let to_rgb = YuvToRgb::new(matrix, range);
            let (luma, chroma) = bytes.split_at(width * height);
            let chroma_width = width.div_ceil(2);
            let plane = chroma_width * height.div_ceil(2);
            let interleaved = matches!(layout, PixelLayout::Nv12(..));
            for (y, row) in rgb.chunks_exact_mut(width * 3).enumerate() {
                let chroma_row = (y / 2) * chroma_width;
                for (x, out) in row.chunks_exact_mut(3).enumerate() {
                    let c = chroma_row + x / 2;
                    let (u, v) = if interleaved {
                        (chroma[2 * c], chroma[2 * c + 1])
                    } else {
                        (chroma[c], chroma[plane + c])
                    };
                    out.copy_from_slice(&to_rgb.pixel(luma[y * width + x], u, v));
                }
            }
        }
    }
    Ok(Image { width, height, rgb })
}

/// One matrix and range's coefficients, scaled for the byte range once.
struct YuvToRgb {
    luma_offset: f32,
    luma_scale: f32,
    chroma_scale: f32,
    red_from_v: f32,
    green_from_u: f32,
    green_from_v: f32,
    blue_from_u: f32,
}

impl YuvToRgb {
    fn new(matrix: YuvMatrix, range: YuvRange) -> Self {
        // Luma weights of red and blue; the rest follows from them.
        let (kr, kb) = match matrix {
            YuvMatrix::Bt601 => (0.299_f32, 0.114_f32),
            YuvMatrix::Bt709 => (0.2126, 0.0722),
        };
        let kg = 1.0 - kr - kb;
        let (luma_offset, luma_scale, chroma_scale) = match range {
            YuvRange::Limited => (16.0, 255.0 / 219.0, 255.0 / 224.0),
            YuvRange::Full => (0.0, 1.0, 1.0),
        };
        Self {
            luma_offset,
            luma_scale,
            chroma_scale,
            red_from_v: 2.0 * (1.0 - kr),
            green_from_u: 2.0 * (1.0 - kb) * kb / kg,
            green_from_v: 2.0 * (1.0 - kr) * kr / kg,
            blue_from_u: 2.0 * (1.0 - kb),
        }
    }

    fn pixel(&self, y: u8, u: u8, v: u8) -> [u8; 3] {
        let y = (f32::from(y) - self.luma_offset) * self.luma_scale;
        let u = (f32::from(u) - 128.0) * self.chroma_scale;
        let v = (f32::from(v) - 128.0) * self.chroma_scale;
        // `as u8` saturates, and the clamp keeps rounding in range.
        let byte = |c: f32| (c.clamp(0.0, 255.0) + 0.5) as u8;
        [
            byte(y + self.red_from_v * v),
            byte(y - self.green_from_u * u - self.green_from_v * v),
            byte(y + self.blue_from_u * u),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RGB → YUV by the textbook formulas, to check the inverse against.
    fn encode(rgb: [u8; 3], matrix: YuvMatrix, range: YuvRange) -> [u8; 3] {
        let (kr, kb) = match matrix {
            YuvMatrix::Bt601 => (0.299_f32, 0.114_f32),
            YuvMatrix::Bt709 => (0.2126, 0.0722),
        };
        let [r, g, b] = rgb.map(|c| f32::from(c) / 255.0);
        let y = kr * r + (1.0 - kr - kb) * g + kb * b;
        let u = (b - y) / (2.0 * (1.0 - kb));
        let v = (r - y) / (2.0 * (1.0 - kr));
        let (y, u, v) = match range {
            YuvRange::Limited => (16.0 + 219.0 * y, 128.0 + 224.0 * u, 128.0 + 224.0 * v),
            YuvRange::Full => (255.0 * y, 128.0 + 255.0 * u, 128.0 + 255.0 * v),
        };
        [y, u, v].map(|c| c.round().clamp(0.0, 255.0) as u8)
    }

    const COLOURS: [[u8; 3]; 6] = [
        [255, 0, 0],
        [0, 255, 0],
        [0, 0, 255],
        [128, 128, 128],
        [230, 180, 160],
        [20, 30, 40],
    ];

    #[test]
    fn yuv_colours_come_back_within_rounding() {
        for matrix in [YuvMatrix::Bt601, YuvMatrix::Bt709] {
            for range in [YuvRange::Limited, YuvRange::Full] {
                let to_rgb = YuvToRgb::new(matrix, range);
                for colour in COLOURS {
                    let [y, u, v] = encode(colour, matrix, range);
                    let back = to_rgb.pixel(y, u, v);
                    for (a, b) in colour.iter().zip(back) {
                        assert!(
                            a.abs_diff(b) <= 3,
                            "{matrix:?} {range:?}: {colour:?} came back as {back:?}"
                        );
                    }
                }
            }
        }
    }

    /// A 3×3 frame (odd sizes: chroma planes of 2×2) with a different colour in each 2×2
    /// chroma block, in both YUV layouts.
    #[test]
    fn planar_and_semi_planar_frames_put_each_chroma_sample_on_its_pixels() {
        let (w, h) = (3, 3);
        let colours = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]];
        let block = |x: usize, y: usize| (y / 2) * 2 + x / 2;
        let (matrix, range) = (YuvMatrix::Bt601, YuvRange::Limited);
        let yuv: Vec<[u8; 3]> = colours.iter().map(|&c| encode(c, matrix, range)).collect();
        let luma: Vec<u8> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| yuv[block(x, y)][0])
            .collect();
        let mut i420 = luma.clone();
        i420.extend(yuv.iter().map(|c| c[1]));
        i420.extend(yuv.iter().map(|c| c[2]));
        let mut nv12 = luma;
        nv12.extend(yuv.iter().flat_map(|c| [c[1], c[2]]));
        for layout in [
            PixelLayout::I420(matrix, range),
            PixelLayout::Nv12(matrix, range),
        ] {
            let bytes = if matches!(layout, PixelLayout::I420(..)) {
                &i420
            } else {
                &nv12
            };
            let image = raw_to_image(layout, w, h, bytes).unwrap();
            for y in 0..h {
                for x in 0..w {
                    let got = &image.rgb[(y * w + x) * 3..][..3];
                    let want = colours[block(x, y)];
                    assert!(
                        got.iter().zip(want).all(|(a, b)| a.abs_diff(b) <= 3),
                        "{layout:?} pixel ({x}, {y}): {got:?}, want {want:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn packed_layouts_drop_the_fourth_byte_and_order_channels() {
        let bytes = [1, 2, 3, 255, 4, 5, 6, 0];
        assert_eq!(
            raw_to_image(PixelLayout::Rgbx, 2, 1, &bytes).unwrap().rgb,
            [1, 2, 3, 4, 5, 6]
        );
        assert_eq!(
            raw_to_image(PixelLayout::Bgrx, 2, 1, &bytes).unwrap().rgb,
            [3, 2, 1, 6, 5, 4]
        );
    }

    #[test]
    fn a_wrong_byte_count_or_format_is_refused_with_the_sizes() {
        let layout = PixelLayout::I420(YuvMatrix::Bt601, YuvRange::Limited);
        assert_eq!(layout.frame_bytes(640, 480), 640 * 480 * 3 / 2);
        let error = raw_to_image(layout, 640, 480, &[0; 1000]).unwrap_err();
        assert!(
            error.contains("1000 bytes") && error.contains("460800"),
            "{error}"
        );
        let error =
            PixelLayout::from_names("P010", YuvMatrix::Bt601, YuvRange::Limited).unwrap_err();
        assert!(error.contains("P010"), "{error}");
    }
}
