//! Following one face through the frames of a video or a webcam, as MediaPipe's Face
//! Landmarker does in its video mode: the landmarks of one frame give the region of the next,
//! and the detector runs only on the first frame and whenever the landmark network says the
//! face is gone (presence below [`MIN_PRESENCE`]).
//!
//! [`Tracker::next_frames`] follows several frames at once, one per thread: they share the
//! region of the last frame done (a frame or two older than MediaPipe's, well inside the
//! region's margin at video rates), and a frame where the face is lost is done again alone.

use crate::face::{REGION_SCALE, level_rotation};
use crate::{Face, FaceModels, Frame, ModelError, Region};

/// Landmark presence below which a face counts as lost (MediaPipe's default
/// `min_tracking_confidence` and `min_face_presence_confidence`).
pub const MIN_PRESENCE: f32 = 0.5;

/// Whether the detector runs on every frame or only when tracking is lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrackingMode {
    /// Each frame's region comes from the previous frame's landmarks (fast; the default).
    #[default]
    Track,
    /// The detector runs on every frame (each frame independent, as for still images).
    DetectEveryFrame,
}

/// How a frame's face was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Found {
    /// From the previous frame's landmarks.
    Tracked,
    /// By the detector.
    Detected,
}

/// Counts of what the tracker did, for reports and benchmarks.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TrackerStats {
    /// Frames seen.
    pub frames: usize,
    /// Frames on which the detector ran.
    pub detector_runs: usize,
    /// Frames with no face.
    pub no_face: usize,
}

/// Follows one face from frame to frame. See the module docs.
#[derive(Debug)]
pub struct Tracker<'m> {
    models: &'m FaceModels,
    mode: TrackingMode,
    previous: Option<(Region, f32)>,
    stats: TrackerStats,
}

impl<'m> Tracker<'m> {
    /// A tracker with no face yet.
    #[must_use]
    pub fn new(models: &'m FaceModels, mode: TrackingMode) -> Tracker<'m> {
        Tracker {
            models,
            mode,
            previous: None,
            stats: TrackerStats::default(),
        }
    }

    /// What the tracker has done so far.
    #[must_use]
    pub fn stats(&self) -> TrackerStats {
        self.stats
    }

    /// Forgets the face (the next frame runs the detector), for a cut in the footage.
    pub fn reset(&mut self) {
        self.previous = None;
    }

    /// The face in the next frame, or `None` when there is none.
    ///
    /// # Errors
    /// [`ModelError`] if the frame is malformed or a model fails.
    pub fn next_frame(&mut self, frame: &Frame<'_>) -> Result<Option<(Face, Found)>, ModelError> {
        self.stats.frames += 1;
        if let (TrackingMode::Track, Some((region, score))) = (self.mode, self.previous) {
            let face = self.models.face_in_region(frame, region, score)?;
            if face.presence >= MIN_PRESENCE {
                self.previous = Some((region_from_landmarks(&face.landmarks), score));
                return Ok(Some((face, Found::Tracked)));
            }
        }
        self.stats.detector_runs += 1;
        match self.models.find_face(frame)? {
            Some(face) if face.presence >= MIN_PRESENCE => {
                self.previous =
                    Some((region_from_landmarks(&face.landmarks), face.detection_score));
                Ok(Some((face, Found::Detected)))
            }
            _ => {
                self.previous = None;
                self.stats.no_face += 1;
                Ok(None)
            }
        }
    }
}

impl Tracker<'_> {
    /// The faces in `frames` (consecutive frames of one video), tracked in parallel, one
    /// thread per frame, from the region of the last frame done; the same as calling
    /// [`Tracker::next_frame`] on each when there is no face to follow yet or it is lost.
    ///
    /// # Errors
    /// [`ModelError`] if a frame is malformed or a model fails.
    pub fn next_frames(
        &mut self,
        frames: &[Frame<'_>],
    ) -> Result<Vec<Option<(Face, Found)>>, ModelError> {
        let shared = match (self.mode, self.previous) {
            (TrackingMode::Track, Some(previous)) if frames.len() > 1 => previous,
            _ => return frames.iter().map(|f| self.next_frame(f)).collect(),
        };
        let (region, score) = shared;
        let models = self.models;
        let faces: Vec<Result<Face, ModelError>> = std::thread::scope(|scope| {
            let others: Vec<_> = frames[1..]
                .iter()
                .map(|frame| scope.spawn(move || models.face_in_region(frame, region, score)))
                .collect();
            let mut faces = vec![models.face_in_region(&frames[0], region, score)];
            faces.extend(others.into_iter().map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(ModelError::Runtime {
                        model: "face landmarks",
                        message: "a tracking thread panicked".into(),
                    })
                })
            }));
            faces
        });
        let mut out = Vec::with_capacity(frames.len());
        let mut shared_valid = true;
        for (frame, face) in frames.iter().zip(faces) {
            if shared_valid {
                let face = face?;
                if face.presence >= MIN_PRESENCE {
                    self.stats.frames += 1;
                    self.previous = Some((region_from_landmarks(&face.landmarks), score));
                    out.push(Some((face, Found::Tracked)));
                    continue;
                }
                // Lost: the frames from here are done one by one. When the shared region
                // itself failed, this frame goes straight to the detector; otherwise an
                // earlier frame of this batch gave a newer region, tried first.
                shared_valid = false;
                if self.previous == Some(shared) {
                    self.previous = None;
                }
            }
            out.push(self.next_frame(frame)?);
        }
        Ok(out)
    }
}

/// The region for the next frame, as MediaPipe's video mode makes it from the landmarks:
/// centred on their box in the image (upright, not turned with the face), its longer side
/// enlarged as the detector's region is, and turned so the outer eye corners (landmarks 33 and
/// 263) are level in the crop.
#[must_use]
pub fn region_from_landmarks(landmarks: &[[f32; 3]]) -> Region {
    let (a, b) = (landmarks[33], landmarks[263]);
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for p in landmarks {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    Region {
        cx: (lo[0] + hi[0]) / 2.0,
        cy: (lo[1] + hi[1]) / 2.0,
        size: (hi[0] - lo[0]).max(hi[1] - lo[1]) * REGION_SCALE,
        rotation: level_rotation([a[0], a[1]], [b[0], b[1]]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_follows_a_turned_face() {
        // A 478-point "face": a square grid, with the eye corners on a line at 30°.
        let angle = 30f32.to_radians();
        let (sin, cos) = angle.sin_cos();
        let mut points = vec![[0.0f32; 3]; 478];
        for (i, p) in points.iter_mut().enumerate() {
            let (u, v) = ((i % 22) as f32 * 5.0 - 52.5, (i / 22) as f32 * 5.0 - 52.5);
            *p = [200.0 + u * cos - v * sin, 150.0 + u * sin + v * cos, 0.0];
        }
        let eye = |u: f32| [200.0 + u * cos, 150.0 + u * sin, 0.0];
        points[33] = eye(-30.0);
        points[263] = eye(30.0);
        let region = region_from_landmarks(&points);
        assert!(
            (region.rotation - angle).abs() < 1e-4,
            "{}",
            region.rotation
        );
        assert!(
            (region.cx - 200.0).abs() < 0.5 && (region.cy - 150.0).abs() < 3.0,
            "{region:?}"
        );
        // The grid spans 105 × 105 (22 columns, 22 rows), turned 30°: its upright box in the
        // image is 105 (cos 30° + sin 30°) across, enlarged 1.5×.
        let across = 105.0 * (angle.cos() + angle.sin());
        assert!((region.size - across * 1.5).abs() < 1.0, "{}", region.size);
    }
}
