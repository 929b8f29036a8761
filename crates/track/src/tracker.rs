//! Following one face through the frames of a video or a webcam, as MediaPipe's Face
//! Landmarker does in its video mode: the landmarks of one frame give the region of the next,
//! and the detector runs only on the first frame and whenever the landmark network says the
//! face is gone (presence below [`MIN_PRESENCE`]).
//!
//! [`Tracker::next_frames`] follows several frames at once, one per thread ([`Workers`],
//! started with the models): they share the region of the last frame done (a frame or two older
//! than MediaPipe's, well inside the region's margin at video rates), and a frame where the
//! face is lost is done again alone. With the detector on every frame, the frames are
//! independent and each thread finds its own frame's face.

use std::sync::{Arc, mpsc};

use crate::face::{REGION_SCALE, WHOLE_CROP, level_rotation};
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
        let face = self.models.find_face(frame)?;
        Ok(self.detected(face))
    }
}

impl Tracker<'_> {
    /// The faces in `frames` (consecutive frames of one video), tracked in parallel from one
    /// region — the last frame done's, or when there is no face to follow yet the detector's
    /// on the first of them — the first frame on this thread, the next ones on `workers`'
    /// threads (any beyond them on this thread too). A frame where the face is lost, and every
    /// one after it, is done as [`Tracker::next_frame`] does it. With
    /// [`TrackingMode::DetectEveryFrame`] each frame is found by the detector on its own
    /// thread, as [`Tracker::next_frame`] finds it.
    ///
    /// # Errors
    /// [`ModelError`] if a frame is malformed or a model fails.
    pub fn next_frames(
        &mut self,
        frames: &[SharedFrame],
        workers: &Workers,
    ) -> Result<Vec<Option<(Face, Found)>>, ModelError> {
        let (shared, detected) = match (self.mode, self.previous) {
            (TrackingMode::DetectEveryFrame, _) if frames.len() > 1 => {
                return self.detect_frames(frames, workers);
            }
            (TrackingMode::Track, Some(previous)) if frames.len() > 1 => (previous, false),
            (TrackingMode::Track, None) if frames.len() > 1 => {
                self.stats.detector_runs += 1;
                match self.models.detect_face(&frames[0].frame())? {
                    Some(found) => (found, true),
                    None => {
                        self.stats.frames += 1;
                        self.stats.no_face += 1;
                        let mut out = vec![None];
                        out.extend(self.next_frames(&frames[1..], workers)?);
                        return Ok(out);
                    }
                }
            }
            _ => return frames.iter().map(|f| self.next_frame(&f.frame())).collect(),
        };
        let (region, score) = shared;
        let faces = workers.run(self.models, frames, Job::InRegion(region, score));
        let mut out = Vec::with_capacity(frames.len());
        let mut shared_valid = true;
        for (k, (frame, face)) in frames.iter().zip(faces).enumerate() {
            let first_detected = detected && k == 0;
            if shared_valid {
                if let Some(face) = face?.filter(|f| f.presence >= MIN_PRESENCE) {
                    self.stats.frames += 1;
                    self.previous = Some((region_from_landmarks(&face.landmarks), score));
                    let found = if first_detected {
                        Found::Detected
                    } else {
                        Found::Tracked
                    };
                    out.push(Some((face, found)));
                    continue;
                }
                // Lost: the frames from here are done one by one. When the shared region
                // itself failed, this frame goes straight to the detector (or, when the
                // detector gave it, has no face); otherwise an earlier frame of this batch
                // gave a newer region, tried first.
                shared_valid = false;
                if self.previous == Some(shared) {
                    self.previous = None;
                }
                if first_detected {
                    self.stats.frames += 1;
                    self.stats.no_face += 1;
                    out.push(None);
                    continue;
                }
            }
            out.push(self.next_frame(&frame.frame())?);
        }
        Ok(out)
    }

    /// [`TrackingMode::DetectEveryFrame`]'s [`Tracker::next_frames`]: the detector on every
    /// frame at once, each as [`Tracker::next_frame`] would count and keep it.
    fn detect_frames(
        &mut self,
        frames: &[SharedFrame],
        workers: &Workers,
    ) -> Result<Vec<Option<(Face, Found)>>, ModelError> {
        workers
            .run(self.models, frames, Job::Detect)
            .into_iter()
            .map(|face| {
                let face = face?;
                self.stats.frames += 1;
                self.stats.detector_runs += 1;
                Ok(self.detected(face))
            })
            .collect()
    }

    /// What the detector's `face` means for the tracker: a face to follow, or none.
    fn detected(&mut self, face: Option<Face>) -> Option<(Face, Found)> {
        match face {
            Some(face) if face.presence >= MIN_PRESENCE => {
                self.previous =
                    Some((region_from_landmarks(&face.landmarks), face.detection_score));
                Some((face, Found::Detected))
            }
            _ => {
                self.previous = None;
                self.stats.no_face += 1;
                None
            }
        }
    }
}

/// A frame whose bytes are shared (reference-counted), so that handing it to a [`Workers`]
/// thread copies nothing.
#[derive(Debug, Clone)]
pub struct SharedFrame {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width × height × 3` bytes.
    pub rgb: Arc<Vec<u8>>,
}

impl SharedFrame {
    /// The frame, borrowed.
    #[must_use]
    pub fn frame(&self) -> Frame<'_> {
        Frame {
            width: self.width,
            height: self.height,
            rgb: &self.rgb,
        }
    }
}

/// Threads that find faces beside the caller's for [`Tracker::next_frames`], started with the
/// models and kept for every video after, as MediaPipe's graph keeps its threads: each runs
/// the networks once on a blank picture as it starts, so that what a thread's first frame
/// warms (the network runtime's scratch space, the allocator's memory for it) is ready before
/// any video. A thread started afresh for each frame paid that every time: its landmark pass
/// took half as long again as a warm thread's.
///
/// The threads end when this is dropped.
#[derive(Debug)]
pub struct Workers {
    threads: Vec<Worker>,
}

/// One worker thread: a frame and its job go in, its face comes out.
#[derive(Debug)]
struct Worker {
    jobs: Option<mpsc::Sender<(SharedFrame, Job)>>,
    faces: mpsc::Receiver<Result<Option<Face>, ModelError>>,
    handle: Option<std::thread::JoinHandle<()>>,
}

/// How a frame's face is to be found.
#[derive(Debug, Clone, Copy)]
enum Job {
    /// The landmarks in this region, with the detector's score that the region goes back to.
    InRegion(Region, f32),
    /// The detector first ([`FaceModels::find_face`]).
    Detect,
}

impl Job {
    /// The face `job` finds in `frame`, a panic in the models becoming the frame's error
    /// rather than the thread's end (so that every face handed to a worker comes back).
    fn run(self, models: &FaceModels, frame: &SharedFrame) -> Result<Option<Face>, ModelError> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match self {
            Job::InRegion(region, score) => models
                .face_in_region(&frame.frame(), region, score)
                .map(Some),
            Job::Detect => models.find_face(&frame.frame()),
        }))
        .unwrap_or_else(|_| Err(panicked()))
    }
}

impl Workers {
    /// Starts `count` threads (0: every frame on the caller's thread), each with its own
    /// handle on `models` (the networks are shared, not copied).
    ///
    /// # Errors
    /// [`ModelError::Runtime`] if the system refuses a thread.
    pub fn start(models: &FaceModels, count: usize) -> Result<Workers, ModelError> {
        let threads = (0..count)
            .map(|n| {
                let models = models.clone();
                let (jobs, incoming) = mpsc::channel::<(SharedFrame, Job)>();
                let (done, faces) = mpsc::channel();
                let handle = std::thread::Builder::new()
                    .name(format!("faceanim-track-{n}"))
                    .spawn(move || {
                        warm_up(&models);
                        for (frame, job) in incoming {
                            if done.send(job.run(&models, &frame)).is_err() {
                                break;
                            }
                        }
                    })
                    .map_err(|e| ModelError::Runtime {
                        model: "face landmarks",
                        message: format!("starting a tracking thread: {e}"),
                    })?;
                Ok(Worker {
                    jobs: Some(jobs),
                    faces,
                    handle: Some(handle),
                })
            })
            .collect::<Result<_, ModelError>>()?;
        Ok(Workers { threads })
    }

    /// How many threads there are.
    #[must_use]
    pub fn count(&self) -> usize {
        self.threads.len()
    }

    /// `job` on every frame: the first on the caller's thread, the next ones on the threads,
    /// any beyond them on the caller's thread after; the faces in the frames' order. Every
    /// face handed out is taken before this returns, errors included.
    fn run(
        &self,
        models: &FaceModels,
        frames: &[SharedFrame],
        job: Job,
    ) -> Vec<Result<Option<Face>, ModelError>> {
        let Some((first, rest)) = frames.split_first() else {
            return Vec::new();
        };
        let handed = self.threads.len().min(rest.len());
        for (thread, frame) in self.threads.iter().zip(&rest[..handed]) {
            thread.give(frame.clone(), job);
        }
        let mut faces = Vec::with_capacity(frames.len());
        faces.push(job.run(models, first));
        faces.extend(self.threads[..handed].iter().map(Worker::take));
        faces.extend(rest[handed..].iter().map(|f| job.run(models, f)));
        faces
    }
}

/// One pass of each network a job may run (the detector, then the landmark and blendshape
/// networks) on a blank 256×256 picture, whose result is not wanted.
fn warm_up(models: &FaceModels) {
    let blank = SharedFrame {
        width: 256,
        height: 256,
        rgb: Arc::new(vec![0u8; 256 * 256 * 3]),
    };
    let _ = Job::Detect.run(models, &blank);
    let _ = Job::InRegion(WHOLE_CROP, 0.0).run(models, &blank);
}

impl Worker {
    fn give(&self, frame: SharedFrame, job: Job) {
        // A thread that has ended says so when its face is taken.
        if let Some(jobs) = &self.jobs {
            let _ = jobs.send((frame, job));
        }
    }

    fn take(&self) -> Result<Option<Face>, ModelError> {
        self.faces.recv().unwrap_or_else(|_| Err(panicked()))
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing the queue ends the thread once its job in hand (if any) is done.
        self.jobs = None;
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }
}

fn panicked() -> ModelError {
    ModelError::Runtime {
        model: "face landmarks",
        message: "a tracking thread panicked".into(),
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
