//! One still image to one face: detection, the face's rotated region, landmarks in image
//! pixels, and the 52 expression scores — MediaPipe's Face Landmarker graph, step by step.
//!
//! - The image is letterboxed to a square and scaled to 128×128 for the detector.
//! - The detector's 896 anchors (strides 8 and 16, two and six anchors per cell) decode to boxes
//!   and six keypoints; scores pass a sigmoid; overlapping boxes (IoU > 0.3) are merged by a
//!   score-weighted mean, as MediaPipe's weighted non-maximum suppression does.
//! - The face region is the box, turned so the eyes (keypoints 0 and 1) are level and enlarged
//!   1.5× (MediaPipe enlarges width and height apart; BlazeFace's boxes are square to 1 part in
//!   10⁵, so the region is kept square); it is resampled into the 256×256 landmark crop, and the
//!   landmarks are mapped back into image pixels.
//! - Both resamplings follow MediaPipe's CPU preprocessing to the pixel (OpenCV's warp: its
//!   pixel-centre convention, positions rounded to 1/32 px, bilinear, the result rounded to 8
//!   bits; black outside the frame for the detector, the edge repeated for the crop). Half a
//!   pixel's difference here moved scores by up to 0.22; now landmarks agree with MediaPipe's
//!   own runtime within 0.01 px and scores within 0.001 on the same pixels
//!   (`tests/mediapipe_stills.rs`).

use crate::{FaceModels, HeadPose, ModelError};

/// An RGB image, 8 bits per channel, rows top to bottom.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width × height × 3` bytes.
    pub rgb: &'a [u8],
}

impl<'a> Frame<'a> {
    /// A frame of `width × height` pixels over `rgb` (`width × height × 3` bytes; a size that
    /// does not match is refused where the frame is read).
    #[must_use]
    pub fn new(width: usize, height: usize, rgb: &'a [u8]) -> Frame<'a> {
        Frame { width, height, rgb }
    }
}

/// A face found in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// Detector confidence, 0..1.
    pub detection_score: f32,
    /// Landmark network's face presence, 0..1.
    pub presence: f32,
    /// The 478 landmarks: x, y in image pixels, z in the same scale.
    pub landmarks: Vec<[f32; 3]>,
    /// The 52 scores with their names (`_neutral` first).
    pub scores: Vec<(&'static str, f32)>,
    /// Centre, size (side, pixels) and rotation (radians) of the region the landmarks came from.
    pub region: Region,
    /// Head pose from the landmarks (`None` only for degenerate landmarks).
    pub pose: Option<HeadPose>,
}

/// A square region of the image, turned by `rotation` about its centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// Centre x, in pixels.
    pub cx: f32,
    /// Centre y, in pixels.
    pub cy: f32,
    /// Side length, in pixels.
    pub size: f32,
    /// Rotation, radians (positive turns the region clockwise on screen).
    pub rotation: f32,
}

const MIN_SCORE: f32 = 0.5;
const MIN_SUPPRESSION_IOU: f32 = 0.3;
/// How much larger than the face's box its landmark crop is.
pub(crate) const REGION_SCALE: f32 = 1.5;

struct Detection {
    score: f32,
    /// xmin, ymin, xmax, ymax and six keypoints (x, y), all in [0, 1] of the letterboxed square.
    values: [f32; 16],
}

/// Anchor centres of the short-range BlazeFace model, in [0, 1].
fn anchors() -> Vec<(f32, f32)> {
    let mut out = Vec::with_capacity(896);
    for (grid, per_cell) in [(16usize, 2usize), (8, 6)] {
        for y in 0..grid {
            for x in 0..grid {
                for _ in 0..per_cell {
                    out.push((
                        (x as f32 + 0.5) / grid as f32,
                        (y as f32 + 0.5) / grid as f32,
                    ));
                }
            }
        }
    }
    out
}

fn iou(a: &[f32; 16], b: &[f32; 16]) -> f32 {
    let w = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let h = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = w * h;
    let union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
    if union > 0.0 { inter / union } else { 0.0 }
}

/// The rotation (radians, the [`Region`] convention) that makes the line from `a` to `b` (two
/// image points, the subject's right then left eye) level in the crop.
pub(crate) fn level_rotation(a: [f32; 2], b: [f32; 2]) -> f32 {
    -(-(b[1] - a[1])).atan2(b[0] - a[0])
}

/// What a sample outside the frame reads, as MediaPipe's preprocessing has it: black for the
/// detector's letterbox (`BORDER_ZERO`), the nearest edge pixel for the landmark crop
/// (`BORDER_REPLICATE`, its default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Border {
    Zero,
    Replicate,
}

/// Positions are rounded to 1/2^this of a pixel, as OpenCV's warps do (`INTER_BITS`).
const SUBPIXEL_BITS: i32 = 5;

/// The nearest integer, ties to even (OpenCV's `cvRound`), for |t| < 2^22, without the libm
/// call `f32::round` is on x86-64's baseline (this runs a few hundred thousand times a frame).
#[inline]
fn round_even(t: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 × 2^23
    (t + MAGIC) - MAGIC
}

/// A position rounded to 1/32 pixel: the pixel at or before it and the fraction past it.
#[inline]
fn subpixel(x: f32) -> (isize, f32) {
    let q = round_even(x * (1 << SUBPIXEL_BITS) as f32) as i32;
    (
        (q >> SUBPIXEL_BITS) as isize,
        (q & ((1 << SUBPIXEL_BITS) - 1)) as f32 / (1 << SUBPIXEL_BITS) as f32,
    )
}

/// The pixel at (x, y) of `frame` read as MediaPipe's `ImageToTensorCalculator` reads it on
/// the CPU (`cv::warpPerspective`, `INTER_LINEAR`): (x, y) in OpenCV's convention (pixel i's
/// centre at i), rounded to 1/32 pixel; bilinear between the four pixels around it; rounded
/// to 8 bits ([`round_half_up`]), as the warp's output image is before it becomes a tensor.
fn sample(frame: &Frame<'_>, x: f32, y: f32, border: Border) -> [f32; 3] {
    let ((x0, fx), (y0, fy)) = (subpixel(x), subpixel(y));
    let (w, h) = (frame.width as isize, frame.height as isize);
    let mut out = [0.0; 3];
    for (dx, dy, weight) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let (mut px, mut py) = (x0 + dx, y0 + dy);
        if px < 0 || py < 0 || px >= w || py >= h {
            match border {
                Border::Zero => continue,
                Border::Replicate => (px, py) = (px.clamp(0, w - 1), py.clamp(0, h - 1)),
            }
        }
        let i = (py as usize * frame.width + px as usize) * 3;
        for (o, &v) in out.iter_mut().zip(&frame.rgb[i..i + 3]) {
            *o += weight * f32::from(v);
        }
    }
    out.map(round_half_up)
}

/// A bilinear value (0..=255) to 8 bits as OpenCV's fixed-point interpolation rounds it: halves
/// up (`(sum + 2^14) >> 15`), not to even; a warp that halves an image meets halves on every
/// other pixel.
#[inline]
fn round_half_up(v: f32) -> f32 {
    (v + 0.5) as u32 as f32
}

/// The 256×256 landmark crop of `region`, values 0..1, appended to `out`. As MediaPipe's
/// preprocessing maps it: crop pixel (i, j) reads the image at the region's centre plus the
/// turned offset ((i/256 − ½)·size, (j/256 − ½)·size), in OpenCV's pixel convention, by
/// [`sample`]. Where all four pixels around a position are inside the frame (nearly
/// everywhere; this is most of a tracked frame's work outside the networks) they are read
/// directly, without the border checks.
fn crop_into(frame: &Frame<'_>, region: &Region, out: &mut Vec<f32>) {
    let (sin, cos) = region.rotation.sin_cos();
    let step = region.size / 256.0;
    let half = region.size / 2.0;
    let (w, h) = (frame.width as isize, frame.height as isize);
    let row_bytes = frame.width * 3;
    let p = &frame.rgb;
    out.reserve(256 * 256 * 3);
    for j in 0..256 {
        let dy = j as f32 * step - half;
        for i in 0..256 {
            let dx = i as f32 * step - half;
            let x = region.cx + dx * cos - dy * sin;
            let y = region.cy + dx * sin + dy * cos;
            let (qx, qy) = (subpixel_fixed(x), subpixel_fixed(y));
            let (xi, yi) = (
                (qx >> SUBPIXEL_BITS) as isize,
                (qy >> SUBPIXEL_BITS) as isize,
            );
            if xi < 0 || yi < 0 || xi + 1 >= w || yi + 1 >= h {
                out.extend(sample(frame, x, y, Border::Replicate).map(|v| v / 255.0));
                continue;
            }
            // OpenCV's fixed-point weights: with positions in 1/32 pixel, each of the four is
            // a whole number of 1/1024ths, so the sum is exact and rounds half up at the end.
            let (fx, fy) = (qx & SUBPIXEL_MASK, qy & SUBPIXEL_MASK);
            let one = 1 << SUBPIXEL_BITS;
            let weights = [
                (one - fx) * (one - fy),
                fx * (one - fy),
                (one - fx) * fy,
                fx * fy,
            ];
            let top = yi as usize * row_bytes + xi as usize * 3;
            let bottom = top + row_bytes;
            for c in 0..3 {
                let sum = i32::from(p[top + c]) * weights[0]
                    + i32::from(p[top + 3 + c]) * weights[1]
                    + i32::from(p[bottom + c]) * weights[2]
                    + i32::from(p[bottom + 3 + c]) * weights[3];
                let byte = (sum + (1 << (2 * SUBPIXEL_BITS - 1))) >> (2 * SUBPIXEL_BITS);
                out.push(UNIT[byte as usize & 0xff]);
            }
        }
    }
}

/// Exactly the whole of a 256×256 frame, the landmark network's own input size: a frame read
/// in this region is the crop itself, without resampling (not nearly this region: then it is
/// resampled).
pub(crate) const WHOLE_CROP: Region = Region {
    cx: 128.0,
    cy: 128.0,
    size: 256.0,
    rotation: 0.0,
};

/// `v / 255` for every byte value, as the crop's inputs are.
static UNIT: [f32; 256] = {
    let mut table = [0.0; 256];
    let mut v = 0;
    while v < 256 {
        table[v] = v as f32 / 255.0;
        v += 1;
    }
    table
};

/// A position in 1/32 pixels, rounded as [`subpixel`] rounds it.
#[inline]
fn subpixel_fixed(x: f32) -> i32 {
    round_even(x * (1 << SUBPIXEL_BITS) as f32) as i32
}

/// The fraction bits of a [`subpixel_fixed`] position.
const SUBPIXEL_MASK: i32 = (1 << SUBPIXEL_BITS) - 1;

impl FaceModels {
    /// The most confident face in `frame`, or `None` when there is none.
    ///
    /// # Errors
    /// [`ModelError`] if the frame's size and bytes disagree or a model fails.
    pub fn find_face(&self, frame: &Frame<'_>) -> Result<Option<Face>, ModelError> {
        match self.detect_face(frame)? {
            Some((region, score)) => self.face_in_region(frame, region, score).map(Some),
            None => Ok(None),
        }
    }

    /// The detector alone: the region of the most confident face in `frame` (for the landmark
    /// network) and its score, or `None` when there is none.
    ///
    /// # Errors
    /// [`ModelError`] if the frame's size and bytes disagree or the detector fails.
    pub fn detect_face(&self, frame: &Frame<'_>) -> Result<Option<(Region, f32)>, ModelError> {
        let bad = |message: String| ModelError::Runtime {
            model: "frame",
            message,
        };
        if frame.width == 0
            || frame.height == 0
            || frame.rgb.len() != frame.width * frame.height * 3
        {
            return Err(bad(format!(
                "{}×{} frame with {} bytes",
                frame.width,
                frame.height,
                frame.rgb.len()
            )));
        }
        // Letterbox to a square, scale to 128×128, values in [−1, 1].
        let side = frame.width.max(frame.height) as f32;
        let (pad_x, pad_y) = (
            (side - frame.width as f32) / 2.0,
            (side - frame.height as f32) / 2.0,
        );
        let mut input = Vec::with_capacity(128 * 128 * 3);
        // MediaPipe's mapping of the letterboxed square onto the 128×128 input: input pixel
        // (i, j) reads the square at (i, j)·side/128 in OpenCV's pixel convention.
        for j in 0..128 {
            for i in 0..128 {
                let x = i as f32 * side / 128.0 - pad_x;
                let y = j as f32 * side / 128.0 - pad_y;
                input.extend(sample(frame, x, y, Border::Zero).map(|v| v / 127.5 - 1.0));
            }
        }
        let (regressors, logits) = self.detect(&input)?;
        let mut detections: Vec<Detection> = anchors()
            .iter()
            .enumerate()
            .filter_map(|(k, &(ax, ay))| {
                let score = 1.0 / (1.0 + (-logits[k].clamp(-100.0, 100.0)).exp());
                if score < MIN_SCORE {
                    return None;
                }
                let r = &regressors[k * 16..k * 16 + 16];
                let (cx, cy, w, h) = (
                    r[0] / 128.0 + ax,
                    r[1] / 128.0 + ay,
                    r[2] / 128.0,
                    r[3] / 128.0,
                );
                let mut values = [0.0; 16];
                values[..4].copy_from_slice(&[
                    cx - w / 2.0,
                    cy - h / 2.0,
                    cx + w / 2.0,
                    cy + h / 2.0,
                ]);
                for p in 0..6 {
                    values[4 + 2 * p] = r[4 + 2 * p] / 128.0 + ax;
                    values[5 + 2 * p] = r[5 + 2 * p] / 128.0 + ay;
                }
                Some(Detection { score, values })
            })
            .collect();
        detections.sort_by(|a, b| b.score.total_cmp(&a.score));
        // Weighted non-maximum suppression: the best detection, averaged with those overlapping it.
        let Some(best) = detections.first() else {
            return Ok(None);
        };
        let cluster: Vec<&Detection> = detections
            .iter()
            .filter(|d| iou(&d.values, &best.values) > MIN_SUPPRESSION_IOU)
            .collect();
        let total: f32 = cluster.iter().map(|d| d.score).sum();
        let mut merged = [0.0f32; 16];
        for d in &cluster {
            for (m, v) in merged.iter_mut().zip(d.values) {
                *m += v * d.score / total;
            }
        }
        let to_image = |u: f32, v: f32| (u * side - pad_x, v * side - pad_y);
        let (x0, y0) = to_image(merged[0], merged[1]);
        let (x1, y1) = to_image(merged[2], merged[3]);
        let (ex0, ey0) = to_image(merged[4], merged[5]);
        let (ex1, ey1) = to_image(merged[6], merged[7]);
        let rotation = level_rotation([ex0, ey0], [ex1, ey1]);
        let region = Region {
            cx: (x0 + x1) / 2.0,
            cy: (y0 + y1) / 2.0,
            size: (x1 - x0).max(y1 - y0) * REGION_SCALE,
            rotation,
        };
        Ok(Some((region, best.score)))
    }

    /// Landmarks and scores of the face in `region` of `frame` (tracking reuses the previous
    /// frame's region instead of detecting again).
    ///
    /// # Errors
    /// [`ModelError`] if a model fails.
    pub fn face_in_region(
        &self,
        frame: &Frame<'_>,
        region: Region,
        detection_score: f32,
    ) -> Result<Face, ModelError> {
        let (sin, cos) = region.rotation.sin_cos();
        let to_image = |u: f32, v: f32| {
            // (u, v) in crop pixels → image pixels.
            let (dx, dy) = (
                (u / 256.0 - 0.5) * region.size,
                (v / 256.0 - 0.5) * region.size,
            );
            (
                region.cx + dx * cos - dy * sin,
                region.cy + dx * sin + dy * cos,
            )
        };
        let mut crop = Vec::with_capacity(256 * 256 * 3);
        let identity = frame.width == 256 && frame.height == 256 && region == WHOLE_CROP;
        if identity {
            // The frame is the crop (a render made for the network): no resampling.
            crop.extend(frame.rgb.iter().map(|&v| f32::from(v) / 255.0));
        } else {
            crop_into(frame, &region, &mut crop);
        }
        let out = self.landmarks_of(crop)?;
        let scale = region.size / 256.0;
        let landmarks: Vec<[f32; 3]> = out
            .points
            .iter()
            .map(|p| {
                let (x, y) = to_image(p[0], p[1]);
                [x, y, p[2] * scale]
            })
            .collect();
        let scores = self.expression(&landmarks)?;
        let pose = self.canonical.fit(&landmarks, frame.width, frame.height);
        Ok(Face {
            pose,
            detection_score,
            presence: out.presence,
            landmarks,
            scores,
            region,
        })
    }
}
