//! Live webcam puppeteering: frames tracked as they arrive, the character's weights sent
//! back, and a take recorded from them.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use faceanim_anim::filter::{OneEuro, OneEuroState};
use faceanim_capture::FrameRecord;
use faceanim_media::Image;
use faceanim_rig::Character;
use faceanim_take::calibration::LiveNeutral;
use faceanim_take::{Estimator, Expression, Footage, NeutralChoice};
use faceanim_track::{Frame, Tracker, TrackingMode};

use super::models::face_models;
use super::open_take::{LIVE_PREVIEW_HEIGHT, Previews};
use crate::error::ApiError;
use crate::lock;
use crate::views::LiveView;

/// Live webcam tracking: the tracker follows the face from frame to frame.
pub(super) struct Live {
    tracker: Tracker<'static>,
    /// The desk's estimator (the adapter copied once, not per frame, or the by-name mapping;
    /// replaced when an adapter is trained).
    pub(super) estimator: Box<dyn Estimator>,
    started: Instant,
    filter: Option<OneEuroState>,
    /// The performer's neutral face (Calibrate, or held still).
    neutral: LiveNeutral,
    recording: Option<Recording>,
    frames: usize,
    /// Where each frame's face goes out over VMC, when the studio sends it.
    performer: Option<Arc<Mutex<faceanim_live::Performer>>>,
}

impl Live {
    /// Live tracking reading faces with `estimator`, smoothed with `smoothing`, each frame's
    /// face sent to `performer` when there is one.
    ///
    /// # Errors
    /// [`ApiError::Models`] when the face models cannot be loaded.
    pub(super) fn start(
        estimator: Box<dyn Estimator>,
        smoothing: Option<OneEuro>,
        performer: Option<Arc<Mutex<faceanim_live::Performer>>>,
    ) -> Result<Live, ApiError> {
        Ok(Live {
            tracker: Tracker::new(face_models()?, TrackingMode::Track),
            estimator,
            started: Instant::now(),
            filter: smoothing.map(OneEuroState::new),
            neutral: LiveNeutral::default(),
            recording: None,
            frames: 0,
            performer,
        })
    }

    /// Takes the next frame with a face as the neutral one (the performer's Calibrate).
    pub(super) fn calibrate(&mut self) {
        self.neutral.calibrate();
    }

    /// Starts recording the frames.
    pub(super) fn start_recording(&mut self) {
        self.recording = Some(Recording::default());
    }

    /// Ends the recording: its frames as footage, and their previews.
    ///
    /// # Errors
    /// [`ApiError::Live`] when not recording, nothing was recorded or no face was seen.
    pub(super) fn stop_recording(&mut self) -> Result<(Footage, Previews), ApiError> {
        let recording = self
            .recording
            .take()
            .ok_or(ApiError::Live("not recording"))?;
        if recording.records.is_empty() {
            return Err(ApiError::Live("nothing was recorded (no frames arrived)"));
        }
        if recording.records.iter().all(|r| r.found.is_none()) {
            return Err(ApiError::Live("no face was seen while recording"));
        }
        // Frames were recorded as they arrived, as fast as they were tracked: each frame of
        // the take is the one recorded nearest its time, so that the take keeps the
        // performance's timing whatever the machine's load.
        let (footage, chosen) = Footage::from_arrivals("webcam".into(), &recording.records, |k| {
            format!("webcam_{:06}.png", k + 1)
        });
        let previews = recording.previews.chosen(&chosen)?;
        Ok((footage, previews))
    }

    /// Smooths the frames from now on with `smoothing` (or not at all).
    pub(super) fn set_smoothing(&mut self, smoothing: Option<OneEuro>) {
        self.filter = smoothing.map(OneEuroState::new);
    }

    /// Frames tracked, and frames recorded while recording.
    pub(super) fn view(&self) -> LiveView {
        LiveView {
            frames: self.frames,
            recording: self.recording.as_ref().map(|r| r.records.len()),
            neutral: self.neutral.chosen(),
            calibrating: self.neutral.pending(),
        }
    }
}

impl std::fmt::Debug for Live {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Live")
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

#[derive(Default)]
pub(super) struct Recording {
    records: Vec<FrameRecord>,
    previews: Previews,
    started: Option<f32>,
}

/// One webcam frame's result.
#[derive(Debug, serde::Serialize)]
pub struct LiveResult {
    /// False when live mode was stopped while the frame was on its way: it is dropped (a
    /// normal race between the camera and the stop button, not an error).
    pub live: bool,
    /// The character's weights (empty when dropped).
    pub weights: Vec<f32>,
    /// Whether a face was found.
    pub found: bool,
    /// Head yaw, pitch, roll in degrees.
    pub head: Option<[f32; 3]>,
    /// The view's bones in this frame, for a character whose file has a head bone (see
    /// `faceanim_export::bones::ViewRig`): the head pose on spine, neck and head, the gaze on
    /// the eyes, `jawOpen` on the jaw.
    pub bones: Option<Vec<[f32; 4]>>,
    /// Milliseconds the server spent on the frame.
    pub server_ms: f64,
    /// Frames recorded so far, while recording.
    pub recorded: Option<usize>,
    /// Who chose the neutral face the frame was read against (`null`: none yet).
    pub neutral: Option<NeutralChoice>,
}

/// What a live frame needs, taken from the desk so tracking does not block it.
pub struct LiveHandle {
    live: Arc<Mutex<Option<Live>>>,
    skeleton: Option<Arc<faceanim_export::bones::ViewRig>>,
}

impl LiveHandle {
    /// A handle on `live`.
    pub(super) fn new(
        live: Arc<Mutex<Option<Live>>>,
        skeleton: Option<Arc<faceanim_export::bones::ViewRig>>,
    ) -> LiveHandle {
        LiveHandle { live, skeleton }
    }

    /// Tracks one webcam frame and returns the character's weights.
    ///
    /// # Errors
    /// [`ApiError::Capture`] for a failing model.
    pub fn track(&self, character: &Character, image: Image) -> Result<LiveResult, ApiError> {
        let started = Instant::now();
        let mut guard = lock(&self.live);
        let Some(live) = guard.as_mut() else {
            return Ok(LiveResult {
                live: false,
                weights: Vec::new(),
                found: false,
                head: None,
                bones: None,
                server_ms: started.elapsed().as_secs_f64() * 1000.0,
                recorded: None,
                neutral: None,
            });
        };
        let time = live.started.elapsed().as_secs_f32();
        let index = live.frames;
        let record = faceanim_capture::capture_frame(
            &mut live.tracker,
            index,
            time,
            &Frame {
                width: image.width,
                height: image.height,
                rgb: &image.rgb,
            },
        )?;
        live.frames += 1;
        let found = record.found.is_some();
        let expression = found.then(|| Expression::from_record(&record)).flatten();
        live.neutral.observe(time, expression.as_ref());
        let mut weights = match &expression {
            Some(e) => live.estimator.estimate(e, live.neutral.neutral()),
            None => vec![0.0; character.blendshapes().len()],
        };
        if found && let Some(filter) = live.filter.as_mut() {
            filter.filter(time, &mut weights);
        }
        let head = record.head;
        // The gaze from MediaPipe's own eyeLook scores, as the eye bones take it, and the jaw
        // from its jawOpen.
        let score = |c: &str| {
            record
                .scores
                .iter()
                .find(|(n, _)| *n == c)
                .map_or(0.0, |(_, v)| *v)
        };
        let eyes = found.then(|| faceanim_rig::bones::gaze_from_arkit(score));
        let jaw = found.then(|| score("jawOpen"));
        // Out at once: the frame's weights, and MediaPipe's ARKit scores for what the
        // character's shapes cannot make, go to the marionette before anything else is done.
        if let Some(performer) = &live.performer {
            let pose = faceanim_live::Pose { head, eyes, jaw };
            let mut performer = lock(performer);
            if found {
                let arkit = faceanim_rig::names::ARKIT_52.map(score);
                performer.send_with_arkit(&weights, &arkit, pose, time);
            } else {
                performer.send_pose(&weights, pose, time);
            }
        }
        let bones = self.skeleton.as_ref().map(|s| s.pose(head, eyes, jaw));
        let recorded = match live.recording.as_mut() {
            Some(recording) => {
                let start = *recording.started.get_or_insert(time);
                let mut record = record;
                record.index = recording.records.len();
                record.time = time - start;
                recording.records.push(record);
                recording.previews.push_image(&image, LIVE_PREVIEW_HEIGHT)?;
                Some(recording.records.len())
            }
            None => None,
        };
        Ok(LiveResult {
            live: true,
            weights,
            found,
            head,
            bones,
            server_ms: started.elapsed().as_secs_f64() * 1000.0,
            recorded,
            neutral: live.neutral.chosen(),
        })
    }
}
