//! The microphone drives the mouth live: the page sends the microphone's samples as they come
//! (16 kHz, 20 ms at a time); each 10 ms frame is classed into visemes
//! ([`faceanim_speech::listen`]), put on the character's mouth, sent out over VMC like the
//! webcam's face, and recorded into a take with its sound when asked.
//!
//! The classifier learns the user's voice: Calibrate listens to 20 s of the passage read
//! aloud and aligns it in the background; while the microphone is on, every stretch of
//! [`REFINE_SECONDS`] is recognised in the background and refines it. Until a model exists the
//! mouth follows loudness alone.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use faceanim_speech::audio::{FRAME_RATE, SAMPLE_RATE};
use faceanim_speech::listen::{self, CALIBRATION_SECONDS, Listener, VoiceModel};
use faceanim_speech::{Mouth, MouthTable};
use serde::Serialize;

use crate::error::ApiError;
use crate::lock;
use crate::views::{Calibration, VoiceView};

/// Samples per second the page sends.
pub const RATE: usize = SAMPLE_RATE as usize;
/// Seconds of speech between background refinements, and the stretch each one recognises.
pub const REFINE_SECONDS: usize = 10;
/// The longest audio delay the page may set, milliseconds.
pub const MAX_DELAY_MS: u32 = 2000;
/// Frames per second of a recorded microphone take.
pub(super) const RECORDED_FPS: f32 = 30.0;
/// The longest recording, seconds (an hour, as for speech files).
const MAX_RECORDING_SECONDS: usize = 3600;

/// One chunk's answer.
#[derive(Debug, Serialize)]
pub struct VoiceResult {
    /// False when the microphone was stopped while the chunk was on its way.
    pub live: bool,
    /// The character's weights now (after the delay), when a frame is due.
    pub weights: Option<Vec<f32>>,
    /// How open the mouth is, 0..1, in that frame.
    pub open: f32,
    /// The view's skeleton turned by the line's jawOpen in that frame (a character whose file
    /// has a head bone: a body with no blendshapes opens its mouth by its jaw bone).
    pub bones: Option<Vec<[f32; 4]>>,
    /// The loudness of the newest frame heard, dB relative to full scale (a chunk too short
    /// to complete a frame answers the one before it: never a made-up silence).
    pub level_db: f32,
    /// Milliseconds the server spent.
    pub server_ms: f64,
    /// The microphone's state.
    pub voice: Option<VoiceView>,
}

/// A frame waiting for its time (the delay).
struct Due {
    at: f32,
    weights: Vec<f32>,
    open: f32,
    /// The line's ARKit values, for receivers of ARKit names (and jawOpen for jaw bones).
    arkit: Vec<f32>,
}

impl Due {
    /// The line's jawOpen, which turns jaw bones.
    fn jaw(&self) -> f32 {
        faceanim_rig::names::Channel::named("jawOpen").map_or(0.0, |c| self.arkit[c.index()])
    }
}

/// A recording under way: the sound, and per 10 ms frame the character's weights and the
/// line's ARKit values, as heard.
#[derive(Default)]
struct Recording {
    sound: Vec<i16>,
    weights: Vec<Vec<f32>>,
    arkit: Vec<Vec<f32>>,
}

/// A recording ended: its sound, and the character's weights and the line's ARKit values at
/// [`RECORDED_FPS`].
pub(super) struct Recorded {
    pub sound: Vec<i16>,
    pub weights: Vec<Vec<f32>>,
    pub arkit: Vec<Vec<f32>>,
}

/// The live microphone.
pub(super) struct Voice {
    /// Tells this microphone session's background work from a later one's.
    session: u64,
    listener: Listener,
    mouth: Mouth,
    /// Whether `mouth` waits for the character's retarget map, being made.
    awaits_map: bool,
    /// The visemes as ARKit's 52 values by the table (what a take keeps beside the weights:
    /// jaw bones and Live Link Face read them).
    arkit: Mouth,
    model: Option<VoiceModel>,
    /// Counts calibrations: a refinement begun before one is not applied after it.
    generation: u64,
    /// The language heard (eSpeak NG's name), checked.
    language: String,
    delay: f32,
    due: VecDeque<Due>,
    received: usize,
    calibration: Calibration,
    calibration_samples: Vec<i16>,
    /// The last [`REFINE_SECONDS`] of sound, and how much came since the last refinement.
    recent: VecDeque<i16>,
    since_refine: usize,
    refining: bool,
    refine_error: Option<String>,
    recording: Option<Recording>,
    /// The frame shown last.
    last: Option<Due>,
    /// The newest heard frame's loudness, dB.
    level_db: f32,
    performer: Option<Arc<Mutex<faceanim_live::Performer>>>,
}

impl std::fmt::Debug for Voice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Voice")
            .field("received", &self.received)
            .field("calibration", &self.calibration)
            .finish_non_exhaustive()
    }
}

impl Voice {
    /// A microphone session driving `mouth` (made by `table`), held back by `delay_ms`
    /// (checked), reading with `model` (a voice learned earlier) when there is one.
    pub(super) fn start(
        mouth: Mouth,
        table: &MouthTable,
        model: Option<VoiceModel>,
        delay_ms: u32,
        language: Option<&str>,
        performer: Option<Arc<Mutex<faceanim_live::Performer>>>,
    ) -> Result<Voice, ApiError> {
        static SESSIONS: AtomicU64 = AtomicU64::new(1);
        check_delay(delay_ms)?;
        let language = checked_language(language)?;
        Ok(Voice {
            session: SESSIONS.fetch_add(1, Ordering::Relaxed),
            listener: Listener::new(model.as_ref()),
            mouth,
            awaits_map: false,
            arkit: Mouth::arkit(table),
            model,
            generation: 0,
            language,
            delay: delay_ms as f32 / 1000.0,
            due: VecDeque::new(),
            received: 0,
            calibration: Calibration::None,
            calibration_samples: Vec::new(),
            recent: VecDeque::with_capacity(REFINE_SECONDS * RATE),
            since_refine: 0,
            refining: false,
            refine_error: None,
            recording: None,
            last: None,
            level_db: -100.0,
            performer,
        })
    }

    /// The voice learned so far, if any.
    pub(super) fn model(&self) -> Option<&VoiceModel> {
        self.model.as_ref()
    }

    /// The voice learned, kept when the microphone stops.
    pub(super) fn into_model(self) -> Option<VoiceModel> {
        self.model
    }

    /// Holds the mouth back by `delay_ms` from now on.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] out of range.
    pub(super) fn set_delay(&mut self, delay_ms: u32) -> Result<(), ApiError> {
        check_delay(delay_ms)?;
        self.delay = delay_ms as f32 / 1000.0;
        Ok(())
    }

    /// Hears `language` from now on (its passage for the next calibration, its speech for the
    /// next refinements).
    ///
    /// # Errors
    /// [`ApiError::Invalid`] naming a language eSpeak NG does not speak.
    pub(super) fn set_language(&mut self, language: &str) -> Result<(), ApiError> {
        self.language = checked_language(Some(language))?;
        Ok(())
    }

    /// Listens to the next [`CALIBRATION_SECONDS`] as the passage read aloud.
    ///
    /// # Errors
    /// [`ApiError::Live`] when calibration is already under way.
    pub(super) fn calibrate(&mut self) -> Result<(), ApiError> {
        if matches!(
            self.calibration,
            Calibration::Listening { .. } | Calibration::Fitting
        ) {
            return Err(ApiError::Live("calibration is already under way"));
        }
        self.calibration = Calibration::Listening { seconds: 0.0 };
        self.calibration_samples.clear();
        Ok(())
    }

    /// Starts recording what is heard.
    pub(super) fn start_recording(&mut self) {
        self.recording = Some(Recording::default());
    }

    /// Ends the recording: what was heard at the take's rate.
    ///
    /// # Errors
    /// [`ApiError::Live`] when not recording, or nothing was heard.
    pub(super) fn stop_recording(&mut self) -> Result<Recorded, ApiError> {
        let Some(recording) = self.recording.take() else {
            return Err(ApiError::Live("not recording"));
        };
        if recording.weights.is_empty() {
            return Err(ApiError::Live("nothing was recorded (no sound arrived)"));
        }
        // Frames came every 10 ms: the take samples them at its own rate.
        let per_frame = FRAME_RATE as f32 / RECORDED_FPS;
        let count = ((recording.weights.len() as f32 / per_frame).ceil() as usize).max(1);
        let sampled = |frames: &[Vec<f32>]| -> Vec<Vec<f32>> {
            (0..count)
                .map(|i| {
                    frames[((i as f32 * per_frame).round() as usize).min(frames.len() - 1)].clone()
                })
                .collect()
        };
        Ok(Recorded {
            weights: sampled(&recording.weights),
            arkit: sampled(&recording.arkit),
            sound: recording.sound,
        })
    }

    pub(super) fn view(&self) -> VoiceView {
        VoiceView {
            seconds: self.received as f32 / RATE as f32,
            delay_ms: (self.delay * 1000.0).round() as u32,
            max_delay_ms: MAX_DELAY_MS,
            awaits_map: self.awaits_map,
            calibration: self.calibration.clone(),
            language: self.language.clone(),
            passage: listen::passage(&self.language),
            learned: self.model.as_ref().map_or(0, |m| m.stretches),
            classifying: self.listener.classifies(),
            refine_error: self.refine_error.clone(),
            recording: self
                .recording
                .as_ref()
                .map(|r| r.sound.len() as f32 / RATE as f32),
        }
    }

    /// Drives `mouth`, made by `table`, from now on.
    pub(super) fn set_mouth(&mut self, mouth: Mouth, table: &MouthTable) {
        self.mouth = mouth;
        self.awaits_map = false;
        self.arkit = Mouth::arkit(table);
    }

    /// Drives the mouth through `map` by `table` from now on; a recording under way while the
    /// mouth waited for the map gets its frames' weights from their ARKit values through it.
    /// Returns whether the mouth moves any shape.
    pub(super) fn use_map(
        &mut self,
        map: &faceanim_retarget::RetargetMap,
        table: &MouthTable,
    ) -> bool {
        let mouth = Mouth::through_map(map, table);
        let moves = mouth.moves();
        if self.awaits_map
            && let Some(recording) = self.recording.as_mut()
        {
            for (weights, arkit) in recording.weights.iter_mut().zip(&recording.arkit) {
                *weights = map.weights(arkit);
            }
        }
        self.set_mouth(mouth, table);
        moves
    }

    /// Marks the mouth ([`Mouth::before_map`]) as waiting for the retarget map being made: the
    /// voice is heard (and recorded) meanwhile, and the mouth rests.
    pub(super) fn wait_for_map(&mut self) {
        self.awaits_map = true;
    }

    /// Whether the mouth waits for the character's retarget map ([`Voice::wait_for_map`]).
    pub(super) fn awaits_map(&self) -> bool {
        self.awaits_map
    }

    /// Whether the mouth goes through the character's retarget map (or waits for it): a new
    /// map replaces it.
    pub(super) fn through_map(&self) -> bool {
        self.mouth.route == faceanim_speech::Route::Retarget
    }

    fn set_model(&mut self, model: VoiceModel) {
        self.listener.set_model(&model);
        self.model = Some(model);
    }
}

/// The live microphone, shared with its background work.
pub(super) type SharedVoice = Arc<Mutex<Option<Voice>>>;

/// Checks a delay the page asks for.
fn check_delay(delay_ms: u32) -> Result<(), ApiError> {
    if delay_ms > MAX_DELAY_MS {
        return Err(ApiError::Invalid(format!(
            "delay_ms: {delay_ms} ms; the audio delay is 0 to {MAX_DELAY_MS} ms"
        )));
    }
    Ok(())
}

/// What a chunk needs, taken from the desk so hearing it does not block the desk.
pub struct VoiceHandle {
    voice: SharedVoice,
    skeleton: Option<Arc<faceanim_export::bones::ViewRig>>,
}

impl VoiceHandle {
    /// A handle on `voice`, turning the view's `skeleton` where the character has one.
    pub(super) fn new(
        voice: SharedVoice,
        skeleton: Option<Arc<faceanim_export::bones::ViewRig>>,
    ) -> VoiceHandle {
        VoiceHandle { voice, skeleton }
    }

    /// Hears one chunk of the microphone (16 kHz mono samples) and returns the mouth now.
    #[must_use]
    pub fn hear(&self, samples: &[i16]) -> VoiceResult {
        let started = Instant::now();
        let mut slot = lock(&self.voice);
        let Some(voice) = slot.as_mut() else {
            return VoiceResult {
                live: false,
                weights: None,
                open: 0.0,
                bones: None,
                level_db: -100.0,
                server_ms: 0.0,
                voice: None,
            };
        };
        voice.received += samples.len();
        let now = voice.received as f32 / RATE as f32;
        // A recording keeps the sound and each frame's mouth as heard (not delayed: the take
        // plays them together), up to an hour.
        let mut recording = voice
            .recording
            .as_mut()
            .filter(|r| r.sound.len() < MAX_RECORDING_SECONDS * RATE);
        if let Some(r) = recording.as_mut() {
            r.sound.extend_from_slice(samples);
        }
        for heard in voice.listener.push(samples) {
            voice.level_db = heard.level_db;
            let weights = voice.mouth.weights(&heard.visemes);
            let arkit = voice.arkit.weights(&heard.visemes);
            if let Some(r) = recording.as_mut() {
                r.weights.push(weights.clone());
                r.arkit.push(arkit.clone());
            }
            voice.due.push_back(Due {
                at: heard.time + voice.delay,
                weights,
                open: heard.open,
                arkit,
            });
        }
        // The newest frame whose time has come (the delay holds frames back).
        let mut shown = None;
        while voice.due.front().is_some_and(|d| d.at <= now) {
            shown = voice.due.pop_front();
        }
        if let Some(d) = shown {
            if let Some(performer) = &voice.performer {
                let pose = faceanim_live::Pose {
                    jaw: Some(d.jaw()),
                    ..faceanim_live::Pose::default()
                };
                lock(performer).send_with_arkit(&d.weights, &d.arkit, pose, now);
            }
            voice.last = Some(d);
        }
        self.listen(voice, samples);
        let last = voice.last.as_ref();
        VoiceResult {
            live: true,
            weights: last.map(|d| d.weights.clone()),
            open: last.map_or(0.0, |d| d.open),
            bones: self
                .skeleton
                .as_ref()
                .zip(last)
                .map(|(s, d)| s.pose(None, None, Some(d.jaw()))),
            level_db: voice.level_db,
            server_ms: started.elapsed().as_secs_f64() * 1000.0,
            voice: Some(voice.view()),
        }
    }

    /// Feeds calibration and refinement, starting their background work when a stretch is
    /// complete.
    fn listen(&self, voice: &mut Voice, samples: &[i16]) {
        if let Calibration::Listening { .. } = voice.calibration {
            voice.calibration_samples.extend_from_slice(samples);
            let seconds = voice.calibration_samples.len() as f32 / RATE as f32;
            voice.calibration = Calibration::Listening { seconds };
            if seconds >= CALIBRATION_SECONDS {
                voice.calibration = Calibration::Fitting;
                let heard = std::mem::take(&mut voice.calibration_samples);
                let (shared, session) = (self.voice.clone(), voice.session);
                let language = voice.language.clone();
                std::thread::spawn(move || {
                    let result = listen::calibrate(&heard, &language);
                    let mut slot = lock(&shared);
                    let Some(voice) = slot.as_mut().filter(|v| v.session == session) else {
                        return;
                    };
                    match result {
                        Ok((model, _, notes)) => {
                            voice.generation += 1;
                            voice.calibration = Calibration::Calibrated {
                                visemes: model.visemes_known(),
                                notes,
                            };
                            voice.set_model(model);
                        }
                        Err(e) => {
                            voice.calibration = Calibration::Failed {
                                message: e.to_string(),
                            };
                        }
                    }
                });
            }
            return;
        }
        if voice.calibration == Calibration::Fitting {
            return;
        }
        let keep = REFINE_SECONDS * RATE;
        voice.recent.extend(samples.iter().copied());
        while voice.recent.len() > keep {
            voice.recent.pop_front();
        }
        voice.since_refine += samples.len();
        if voice.since_refine < keep || voice.refining {
            return;
        }
        voice.since_refine = 0;
        let stretch: Vec<i16> = voice.recent.iter().copied().collect();
        // Only a stretch with speech in it is worth recognising.
        let sound = faceanim_speech::Sound { samples: stretch };
        if sound.voice_activity().iter().filter(|v| **v).count() < 200 {
            return;
        }
        voice.refining = true;
        let (shared, session) = (self.voice.clone(), voice.session);
        let (model, mean, generation, language) = (
            voice.model.clone(),
            voice.listener.speaker_mean(),
            voice.generation,
            voice.language.clone(),
        );
        std::thread::spawn(move || {
            let result = listen::refine(model.as_ref(), &sound.samples, mean, &language);
            let mut slot = lock(&shared);
            let Some(voice) = slot.as_mut().filter(|v| v.session == session) else {
                return;
            };
            voice.refining = false;
            // A calibration under way or finished meanwhile wins over a refinement of the voice
            // as it was before.
            if voice.generation != generation
                || voice.calibration == Calibration::Fitting
                || matches!(voice.calibration, Calibration::Listening { .. })
            {
                return;
            }
            match result {
                Ok(model) => {
                    voice.refine_error = None;
                    voice.set_model(model);
                }
                Err(e) => voice.refine_error = Some(e.to_string()),
            }
        });
    }
}

/// `language` as eSpeak NG names it (English, `en-us`, when not given): the microphone's
/// passage and recognition follow it.
///
/// # Errors
/// [`ApiError::Invalid`] naming a language eSpeak NG does not speak.
fn checked_language(language: Option<&str>) -> Result<String, ApiError> {
    let given = language.map(str::trim).filter(|l| !l.is_empty());
    faceanim_speech::recognition::check_language(given.unwrap_or("en-us"))
        .map_err(|e| ApiError::Invalid(format!("language: {e}")))
}
