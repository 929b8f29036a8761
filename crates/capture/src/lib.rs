//! # faceanim-capture: footage to a clip
//!
//! Runs capture's per-frame pipeline ([`faceanim_track`]: detection or tracking, landmarks,
//! 52 scores, head pose) over every frame of a [`FrameSource`] and gathers the result as a
//! [`Capture`]: one row per frame, in order, with frames where no face was found *marked*
//! (presence 0, weights bridged from their neighbours) rather than dropped, so the clip keeps
//! the footage's timeline exactly.
//!
//! The clip's columns are the 51 ARKit names MediaPipe estimates (its `_neutral` score is
//! kept only in the raw record). Mapping onto a character by name, smoothing and keyframing
//! are steps the caller chooses ([`Capture::clip`], [`Filtering`]).
#![deny(missing_docs)]

use faceanim_anim::Clip;
use faceanim_anim::filter::{OneEuro, fill_gaps, fill_gaps_rows};
use faceanim_anim::keyframes::{interpolate_between, keyframe_indices};
use faceanim_media::{FrameSource, MediaError};
use faceanim_track::{
    Face, FaceModels, Found, Frame, ModelError, SharedFrame, Tracker, TrackingMode, Workers,
};
use serde::Serialize;

/// Why capture stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CaptureError {
    /// Reading the input failed.
    #[error(transparent)]
    Media(#[from] MediaError),
    /// A face model failed.
    #[error("frame {frame}: {source}")]
    Model {
        /// The frame.
        frame: usize,
        /// What failed.
        source: ModelError,
    },
    /// The input had no frames.
    #[error("the input has no frames")]
    Empty,
}

/// What capture kept of one frame: enough to redo any later step without the models.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameRecord {
    /// Frame index.
    pub index: usize,
    /// Seconds from the first frame.
    pub time: f32,
    /// How the face was found: `"tracked"`, `"detected"`, or `null` for no face.
    pub found: Option<&'static str>,
    /// The landmark network's face presence (0 when no face).
    pub presence: f32,
    /// The detector's score for the face being followed (0 when no face).
    pub detection_score: f32,
    /// 52 scores in MediaPipe's order with names (`_neutral` first); empty when no face.
    pub scores: Vec<(&'static str, f32)>,
    /// Head yaw, pitch and roll in degrees, when a face was found.
    pub head: Option<[f32; 3]>,
    /// Head position in metres from the camera, when a face was found.
    pub head_position: Option<[f32; 3]>,
    /// The 478 landmarks in image pixels (x, y, z); empty when no face.
    pub landmarks: Vec<[f32; 3]>,
}

/// The result of capture over a whole input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Capture {
    /// Frames per second of the input.
    pub fps: f32,
    /// Frame size in pixels.
    pub width: usize,
    /// Frame size in pixels.
    pub height: usize,
    /// One record per frame.
    pub frames: Vec<FrameRecord>,
    /// Frames on which the detector ran.
    pub detector_runs: usize,
}

/// Post-processing of a captured clip; each is optional so users can choose and compare.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Filtering {
    /// One Euro smoothing, applied first.
    pub one_euro: Option<OneEuro>,
    /// Keyframes every this many frames (the seed's default is 5), linearly interpolated.
    pub keyframe_every: Option<usize>,
}

impl FrameRecord {
    fn from_face(index: usize, time: f32, face: Option<(Face, Found)>) -> FrameRecord {
        match face {
            Some((face, found)) => FrameRecord {
                index,
                time,
                found: Some(match found {
                    Found::Tracked => "tracked",
                    Found::Detected => "detected",
                }),
                presence: face.presence,
                detection_score: face.detection_score,
                head: face.pose.map(|p| [p.yaw, p.pitch, p.roll]),
                head_position: face.pose.map(|p| p.translation),
                scores: face.scores,
                landmarks: face.landmarks,
            },
            None => FrameRecord::missing(index, time),
        }
    }

    /// The record of frame `index` at `time` seconds in which no face was found.
    #[must_use]
    pub fn missing(index: usize, time: f32) -> FrameRecord {
        FrameRecord {
            index,
            time,
            found: None,
            presence: 0.0,
            detection_score: 0.0,
            scores: Vec::new(),
            head: None,
            head_position: None,
            landmarks: Vec::new(),
        }
    }
}

/// Captures one frame given as raw RGB bytes (a webcam frame from the studio, say), with a
/// tracker that persists between calls.
///
/// # Errors
/// [`CaptureError::Model`] if the frame is malformed or a model fails.
pub fn capture_frame(
    tracker: &mut Tracker<'_>,
    index: usize,
    time: f32,
    frame: &Frame<'_>,
) -> Result<FrameRecord, CaptureError> {
    let face = tracker
        .next_frame(frame)
        .map_err(|source| CaptureError::Model {
            frame: index,
            source,
        })?;
    Ok(FrameRecord::from_face(index, time, face))
}

/// A decoded frame as tracking threads share it (its bytes moved, not copied).
#[must_use]
pub fn shared(image: faceanim_media::Image) -> SharedFrame {
    SharedFrame {
        width: image.width,
        height: image.height,
        rgb: std::sync::Arc::new(image.rgb),
    }
}

/// The bytes of a frame tracking is done with, to read the next frame into
/// ([`FrameSource::next_frame_reusing`]); `None` while another thread still holds the frame
/// (a worker that has not let go of it yet).
#[must_use]
pub fn reusable(frame: SharedFrame) -> Option<Vec<u8>> {
    std::sync::Arc::try_unwrap(frame.rgb).ok()
}

/// Captures consecutive frames together ([`Tracker::next_frames`]: the first on this thread,
/// the others on `workers`'), `first` being the first one's index in an input of `fps` frames
/// per second: what [`capture`] does with each group of frames, for callers that read the
/// frames themselves (to show them as they go, say).
///
/// # Errors
/// [`CaptureError::Model`] if a frame is malformed or a model fails.
pub fn capture_frames(
    tracker: &mut Tracker<'_>,
    workers: &Workers,
    first: usize,
    fps: f32,
    frames: &[SharedFrame],
) -> Result<Vec<FrameRecord>, CaptureError> {
    let faces = tracker
        .next_frames(frames, workers)
        .map_err(|source| CaptureError::Model {
            frame: first,
            source,
        })?;
    Ok(faces
        .into_iter()
        .enumerate()
        .map(|(k, face)| FrameRecord::from_face(first + k, (first + k) as f32 / fps, face))
        .collect())
}

/// Captures every frame of `source`; `progress` is called after each frame with the number
/// done.
///
/// The stages overlap: a thread reads (decodes) frames ahead while frames are tracked together,
/// one on this thread and one on each of `workers`' ([`Tracker::next_frames`]); with no
/// workers, one frame at a time.
///
/// # Errors
/// A [`CaptureError`] for unreadable input or a failing model.
pub fn capture(
    models: &FaceModels,
    workers: &Workers,
    source: &mut FrameSource,
    mode: TrackingMode,
    mut progress: impl FnMut(usize),
) -> Result<Capture, CaptureError> {
    let info = source.info();
    let mut tracker = Tracker::new(models, mode);
    let mut frames = Vec::with_capacity(info.frames.unwrap_or(0));
    let batch = workers.count() + 1;
    std::thread::scope(|scope| -> Result<(), CaptureError> {
        // Decoded frames wait here for the trackers: a few ahead, no more.
        let (send, receive) = std::sync::mpsc::sync_channel(2 * batch);
        // ... and their bytes come back to be read into again.
        let (give_back, spares) = std::sync::mpsc::channel::<Vec<u8>>();
        scope.spawn(move || {
            loop {
                let next = source.next_frame_reusing(spares.try_recv().ok());
                let end = !matches!(next, Ok(Some(_)));
                if send.send(next).is_err() || end {
                    break;
                }
            }
        });
        let mut images = Vec::with_capacity(batch);
        let mut done = false;
        while !done {
            images.clear();
            while images.len() < batch {
                match receive.recv() {
                    Ok(Ok(Some(image))) => images.push(shared(image)),
                    Ok(Ok(None)) | Err(_) => {
                        done = true;
                        break;
                    }
                    Ok(Err(e)) => return Err(e.into()),
                }
            }
            for record in capture_frames(&mut tracker, workers, frames.len(), info.fps, &images)? {
                frames.push(record);
                progress(frames.len());
            }
            for bytes in images.drain(..).filter_map(reusable) {
                let _ = give_back.send(bytes);
            }
        }
        Ok(())
    })?;
    if frames.is_empty() {
        return Err(CaptureError::Empty);
    }
    Ok(Capture {
        fps: info.fps,
        width: info.width,
        height: info.height,
        frames,
        detector_runs: tracker.stats().detector_runs,
    })
}

impl Capture {
    /// Frames where a face was found.
    #[must_use]
    pub fn faces_found(&self) -> usize {
        self.frames.iter().filter(|f| f.found.is_some()).count()
    }

    /// The clip of ARKit weights (51 columns, MediaPipe's order without `_neutral`), head
    /// rotation and position, and presence per frame; frames without a face are bridged
    /// from their neighbours and have presence 0. Then the chosen filtering.
    ///
    /// # Errors
    /// The One Euro settings' validation message.
    pub fn clip(&self, filtering: Filtering) -> Result<Clip, String> {
        let names: Vec<String> = faceanim_track::BLENDSHAPE_NAMES[1..]
            .iter()
            .map(|n| (*n).to_owned())
            .collect();
        let known: Vec<bool> = self.frames.iter().map(|f| f.found.is_some()).collect();
        let mut rows: Vec<Vec<f32>> = self
            .frames
            .iter()
            .map(|f| {
                if f.scores.len() == names.len() + 1 {
                    f.scores[1..].iter().map(|s| s.1.clamp(0.0, 1.0)).collect()
                } else {
                    vec![0.0; names.len()]
                }
            })
            .collect();
        fill_gaps_rows(&mut rows, &known);
        let posed: Vec<bool> = self.frames.iter().map(|f| f.head.is_some()).collect();
        let mut head: Vec<[f32; 3]> = self
            .frames
            .iter()
            .map(|f| f.head.unwrap_or([0.0; 3]))
            .collect();
        let mut position: Vec<[f32; 3]> = self
            .frames
            .iter()
            .map(|f| f.head_position.unwrap_or([0.0; 3]))
            .collect();
        fill_gaps(&mut head, &posed);
        fill_gaps(&mut position, &posed);
        let mut clip = Clip {
            fps: self.fps,
            blendshapes: names,
            frames: rows,
            head: Some(head),
            head_position: Some(position),
            presence: Some(
                self.frames
                    .iter()
                    .map(|f| f.presence.clamp(0.0, 1.0))
                    .collect(),
            ),
            arkit: None,
        };
        if let Some(settings) = filtering.one_euro {
            faceanim_anim::filter::smooth(&mut clip, settings)?;
        }
        if let Some(every) = filtering.keyframe_every {
            clip = interpolate_between(&clip, &keyframe_indices(clip.frames.len(), every, &[]));
        }
        Ok(clip)
    }
}
