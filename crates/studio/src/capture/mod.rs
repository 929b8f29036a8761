//! Capture mode: a face video, photos or the webcam drive the character (seed 003's toolkit).
//!
//! Owns the *take* (the input's frames read by the capture pipeline, as an
//! [`faceanim_adapt::Session`]: estimates, keyframes, corrections, preference, smoothing, plus
//! a small preview of every input frame), the character's adapter (loaded from beside the
//! character, trained or fine-tuned from the page), the long jobs (reading a video, rendering
//! and training) with their progress and cancel flag, and live webcam tracking with recording.
//!
//! Without an adapter the take is estimated by name (ARKit-named shapes get MediaPipe's
//! scores), so any ARKit rig works at once; with one, every shape of any rig is estimated.
//! Either way the take is a session, so corrections, keyframes and preference work the same.
//! Strokes of the sketch layer on top of the take ([`layered_weights`]).

mod jobs;
mod live;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use faceanim_adapt::session::{Session, SessionFrame, estimate_frames};
use faceanim_adapt::{Adapter, Expression, Fingerprint, Fit};
use faceanim_anim::Clip;
use faceanim_anim::filter::OneEuro;
use faceanim_capture::FrameRecord;
use faceanim_rig::Character;
use faceanim_track::FaceModels;
use serde_json::{Value, json};

use crate::lock;

pub use jobs::{start_capture, start_finetune, start_training};
use live::Live;
pub use live::{LiveHandle, LiveResult};

/// Input previews are at most this tall: enough to judge an expression beside the character.
const PREVIEW_HEIGHT: usize = 360;
/// Live takes keep smaller previews, made between camera frames.
const LIVE_PREVIEW_HEIGHT: usize = 240;
/// The seed's keyframe spacing.
pub const DEFAULT_KEYFRAME_EVERY: usize = 5;
/// Frames a photo's 0 → peak → 0 animation lasts.
const STILL_FRAMES: usize = 30;
/// Training-set size when the page does not say (the seed's).
pub const DEFAULT_SAMPLES: usize = 10_000;
/// Fine-tuning needs the training set as an anchor; without a cached one it renders this many.
const FINETUNE_ANCHOR_SAMPLES: usize = 2_000;

/// The face models, loaded once on first use and kept for the process (live tracking holds a
/// tracker that borrows them between requests).
fn face_models() -> Result<&'static FaceModels, String> {
    static MODELS: OnceLock<Result<FaceModels, String>> = OnceLock::new();
    MODELS
        .get_or_init(|| FaceModels::load_with_threads(1).map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| format!("loading the face models: {e}"))
}

/// A captured input being edited.
#[derive(Debug)]
pub struct Take {
    /// Estimates, keyframes, corrections and preference.
    pub session: Session,
    /// A PNG preview of each input frame.
    pub previews: Previews,
    /// Whether the estimates came from the adapter (else by name); unknown for a take opened
    /// from a session file, which does not say.
    pub by_adapter: Option<bool>,
    undo: Vec<Edits>,
    redo: Vec<Edits>,
    /// Different for every take this process opened: the page tells takes apart by it (two
    /// uploads of `clip.mp4` are different takes).
    id: u64,
}

/// A take's frame previews: PNG files in a private temporary folder (a long video's previews
/// would not fit in memory), removed with the take.
#[derive(Debug, Default)]
pub struct Previews {
    dir: Option<tempfile::TempDir>,
    count: usize,
}

impl Previews {
    /// An empty set, its folder made on the first frame.
    #[must_use]
    pub fn new() -> Previews {
        Previews::default()
    }

    /// Adds the next frame's preview.
    ///
    /// # Errors
    /// The file error.
    pub fn push(&mut self, png: &[u8]) -> Result<(), String> {
        let dir = private_dir(&mut self.dir, "faceanim-previews-", "previews")?;
        let path = dir.join(format!("{}.png", self.count));
        std::fs::write(&path, png).map_err(|e| format!("{}: {e}", path.display()))?;
        self.count += 1;
        Ok(())
    }

    /// How many frames have a preview (the first ones).
    #[must_use]
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether no frame has a preview.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Frame `index`'s preview, if there is one.
    #[must_use]
    pub fn get(&self, index: usize) -> Option<Vec<u8>> {
        let dir = self.dir.as_ref()?;
        (index < self.count)
            .then(|| std::fs::read(dir.path().join(format!("{index}.png"))).ok())
            .flatten()
    }
}

/// The private temporary folder kept in `slot`, made on first use (named `prefix…`; `what` it
/// holds names it in the error).
pub(super) fn private_dir<'a>(
    slot: &'a mut Option<tempfile::TempDir>,
    prefix: &str,
    what: &str,
) -> Result<&'a std::path::Path, String> {
    let dir = match slot.take() {
        Some(dir) => dir,
        None => tempfile::Builder::new()
            .prefix(prefix)
            .tempdir()
            .map_err(|e| format!("making a folder for {what}: {e}"))?,
    };
    Ok(slot.insert(dir).path())
}

/// What the user changes in a take (the frames and estimates stay): small enough to keep
/// hundreds of steps of undo.
#[derive(Debug, Clone, PartialEq)]
struct Edits {
    keyframe_every: usize,
    smoothing: Option<OneEuro>,
    added_keyframes: Vec<usize>,
    removed_keyframes: Vec<usize>,
    corrections: std::collections::BTreeMap<usize, std::collections::BTreeMap<String, f32>>,
    preference: Option<Vec<f32>>,
}

impl Edits {
    fn of(session: &Session) -> Edits {
        Edits {
            keyframe_every: session.keyframe_every,
            smoothing: session.smoothing,
            added_keyframes: session.added_keyframes.clone(),
            removed_keyframes: session.removed_keyframes.clone(),
            corrections: session.corrections.clone(),
            preference: session.preference.clone(),
        }
    }

    fn restore(self, session: &mut Session) {
        session.keyframe_every = self.keyframe_every;
        session.smoothing = self.smoothing;
        session.added_keyframes = self.added_keyframes;
        session.removed_keyframes = self.removed_keyframes;
        session.corrections = self.corrections;
        session.preference = self.preference;
    }
}

/// How many edits of a take undo remembers.
const TAKE_UNDO_DEPTH: usize = 500;

impl Take {
    fn new(session: Session, previews: Previews, by_adapter: Option<bool>) -> Take {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        Take {
            id: NEXT.fetch_add(1, Ordering::Relaxed),
            session,
            previews,
            by_adapter,
            undo: Vec::new(),
            redo: Vec::new(),
        }
    }

    /// Applies `change` to the session; a change that changed something can be undone.
    ///
    /// # Errors
    /// `change`'s message (the session is then as it was).
    pub fn edit(
        &mut self,
        change: impl FnOnce(&mut Session) -> Result<(), String>,
    ) -> Result<(), String> {
        let before = Edits::of(&self.session);
        if let Err(e) = change(&mut self.session) {
            before.restore(&mut self.session);
            return Err(e);
        }
        if Edits::of(&self.session) != before {
            self.undo.push(before);
            if self.undo.len() > TAKE_UNDO_DEPTH {
                self.undo.remove(0);
            }
            self.redo.clear();
        }
        Ok(())
    }

    /// Steps back one edit; false when there is none.
    pub fn undo(&mut self) -> bool {
        let Some(previous) = self.undo.pop() else {
            return false;
        };
        self.redo.push(Edits::of(&self.session));
        previous.restore(&mut self.session);
        true
    }

    /// Steps forward one undone edit; false when there is none.
    pub fn redo(&mut self) -> bool {
        let Some(next) = self.redo.pop() else {
            return false;
        };
        self.undo.push(Edits::of(&self.session));
        next.restore(&mut self.session);
        true
    }
}

/// One long piece of work: progress, a cancel flag, and how it ended.
#[derive(Debug, Default)]
pub struct Job {
    kind: &'static str,
    stage: Mutex<String>,
    done: AtomicUsize,
    total: AtomicUsize,
    cancel: AtomicBool,
    finished: AtomicBool,
    outcome: Mutex<Option<Result<String, String>>>,
    started: Option<Instant>,
}

impl Job {
    fn new(kind: &'static str) -> Arc<Job> {
        Arc::new(Job {
            kind,
            started: Some(Instant::now()),
            ..Job::default()
        })
    }

    fn stage(&self, stage: &str, total: usize) {
        *lock(&self.stage) = stage.to_owned();
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    fn progress(&self, done: usize) {
        self.done.store(done, Ordering::Relaxed);
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    fn finish(&self, outcome: Result<String, String>) {
        *lock(&self.outcome) = Some(outcome);
        self.finished.store(true, Ordering::Release);
    }

    fn view(&self) -> Value {
        let outcome = lock(&self.outcome).clone();
        json!({
            "kind": self.kind,
            "stage": lock(&self.stage).clone(),
            "done": self.done.load(Ordering::Relaxed),
            "total": self.total.load(Ordering::Relaxed),
            "running": !self.finished.load(Ordering::Acquire),
            "cancelling": self.cancelled(),
            "seconds": self.started.map_or(0.0, |s| s.elapsed().as_secs_f64()),
            "result": outcome.as_ref().and_then(|o| o.as_ref().ok()),
            "error": outcome.as_ref().and_then(|o| o.as_ref().err()),
        })
    }
}

/// Capture mode's state (see the module docs).
#[derive(Debug)]
pub struct CaptureDesk {
    /// Where the character's adapter is read from and saved to.
    pub adapter_path: PathBuf,
    adapter: Option<Adapter>,
    /// Why the adapter beside the character is not used, or that it fits another shape.
    adapter_note: Option<String>,
    take: Option<Take>,
    job: Option<Arc<Job>>,
    live: Arc<Mutex<Option<Live>>>,
    /// The smoothing and keyframe spacing new takes get (the page's controls).
    keyframe_every: usize,
    smoothing: Option<OneEuro>,
    /// Uploaded inputs are written here (ffmpeg reads files).
    uploads: Option<tempfile::TempDir>,
    /// The take's session is written here after every change and read back at start, so
    /// closing the studio loses no correction.
    take_path: PathBuf,
}

/// A shared capture desk.
pub type SharedDesk = Arc<Mutex<CaptureDesk>>;

/// The smoothing the page starts with: light enough to keep fast expressions.
fn default_smoothing() -> OneEuro {
    OneEuro {
        min_cutoff: 1.5,
        beta: 0.5,
        derivative_cutoff: 1.0,
    }
}

impl CaptureDesk {
    /// A desk for `character`, loading its adapter from `adapter_path` when there is one and
    /// the take autosaved at `take_path` when it belongs to this character.
    #[must_use]
    pub fn new(character: &Character, adapter_path: PathBuf, take_path: PathBuf) -> CaptureDesk {
        let mut desk = CaptureDesk {
            take_path,
            adapter_path,
            adapter: None,
            adapter_note: None,
            take: None,
            job: None,
            live: Arc::new(Mutex::new(None)),
            keyframe_every: DEFAULT_KEYFRAME_EVERY,
            smoothing: None,
            uploads: None,
        };
        desk.load_adapter(character);
        desk.restore_take(character);
        desk
    }

    /// Reopens the autosaved take (without its previews: the input is not kept).
    fn restore_take(&mut self, character: &Character) {
        let Ok(bytes) = std::fs::read(&self.take_path) else {
            return;
        };
        let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
        match Session::from_json(&bytes) {
            Ok(session) if session.blendshapes == names => {
                tracing::info!(
                    "reopened the take of {} from {}",
                    session.source,
                    self.take_path.display()
                );
                self.take = Some(Take::new(session, Previews::new(), None));
            }
            Ok(_) => tracing::warn!(
                "{} is a take of another character; not opened",
                self.take_path.display()
            ),
            Err(e) => tracing::warn!("{}: {e}; not opened", self.take_path.display()),
        }
    }

    /// Opens a session file as the take: one written by `faceanim track --adapter A --session
    /// FILE`, edited by `faceanim session`, or exported from this tab. It has no previews (a
    /// session does not keep its input). Returns its frame count.
    ///
    /// # Errors
    /// A message naming `shown` when the bytes are not a session, the session is of a
    /// character with other blendshapes, or a job is running.
    pub fn open_session(
        &mut self,
        character: &Character,
        bytes: &[u8],
        shown: &str,
    ) -> Result<usize, String> {
        self.busy()?;
        let session = Session::from_json(bytes).map_err(|e| format!("{shown}: {e}"))?;
        let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
        if session.blendshapes != names {
            let lacking: Vec<&str> = names
                .iter()
                .filter(|n| !session.blendshapes.iter().any(|s| s == *n))
                .copied()
                .collect();
            let how = match lacking.len() {
                0 => "the same names in another order or with others".to_owned(),
                n @ 1..=5 => format!("it lacks {n}: {}", lacking.join(", ")),
                n => format!("it lacks {n}: {}, …", lacking[..5].join(", ")),
            };
            return Err(format!(
                "{shown}: a session of {} with {} blendshapes, not of {} with {} ({how})",
                session.character,
                session.blendshapes.len(),
                character.name(),
                names.len()
            ));
        }
        let frames = session.frames.len();
        tracing::info!("opened the session {shown}: {frames} frames");
        self.set_take(Take::new(session, Previews::new(), None));
        Ok(frames)
    }

    /// Writes the take (or, with none, removes the autosave).
    fn save_take(&self) {
        let result = match &self.take {
            Some(take) => {
                faceanim_files::write_atomic(&self.take_path, take.session.to_json().as_bytes())
                    .map_err(|e| e.to_string())
            }
            None => match std::fs::remove_file(&self.take_path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e.to_string()),
                _ => Ok(()),
            },
        };
        if let Err(e) = result {
            tracing::warn!("autosaving the take failed: {e}");
        }
    }

    /// Makes `take` the one being edited (and autosaves it).
    fn set_take(&mut self, take: Take) {
        self.take = Some(take);
        self.save_take();
    }

    /// Applies `change` to the take's session (undoably) and autosaves it.
    ///
    /// # Errors
    /// A message when no take is open, or `change`'s.
    pub fn edit_take(
        &mut self,
        change: impl FnOnce(&mut Session) -> Result<(), String>,
    ) -> Result<(), String> {
        self.take_mut()?.edit(change)?;
        self.save_take();
        Ok(())
    }

    /// Undoes (`back`) or redoes one edit of the take; false when there was none.
    ///
    /// # Errors
    /// A message when no take is open.
    pub fn step_history(&mut self, back: bool) -> Result<bool, String> {
        let take = self.take_mut()?;
        let stepped = if back { take.undo() } else { take.redo() };
        if stepped {
            self.save_take();
        }
        Ok(stepped)
    }

    /// Reads the adapter beside the character, keeping it only when it fits.
    fn load_adapter(&mut self, character: &Character) {
        self.adapter = None;
        self.adapter_note = None;
        if !self.adapter_path.exists() {
            return;
        }
        let loaded = faceanim_files::read_bytes(&self.adapter_path)
            .map_err(|e| e.to_string())
            .and_then(|bytes| Adapter::from_bytes(&bytes).map_err(|e| e.to_string()))
            .and_then(|adapter| match adapter.check(character) {
                Ok(fit) => Ok((adapter, fit)),
                Err(e) => Err(e.to_string()),
            });
        match loaded {
            Ok((adapter, fit)) => {
                if fit == Fit::OtherShape {
                    self.adapter_note = Some(format!(
                        "{} was trained on another shape of this rig; retrain for best accuracy",
                        self.adapter_path.display()
                    ));
                }
                self.adapter = Some(adapter);
            }
            Err(e) => {
                tracing::warn!("{}: {e}", self.adapter_path.display());
                self.adapter_note = Some(format!(
                    "{}: not used ({e}); estimating by name",
                    self.adapter_path.display()
                ));
            }
        }
    }

    /// The character changed: the take and live tracking belong to the old one.
    pub fn character_changed(&mut self, character: &Character, adapter_path: PathBuf) {
        if let Some(job) = &self.job {
            job.cancel.store(true, Ordering::Relaxed);
        }
        self.take = None;
        *lock(&self.live) = None;
        self.adapter_path = adapter_path;
        self.load_adapter(character);
    }

    /// The take, if one is open.
    #[must_use]
    pub fn take(&self) -> Option<&Take> {
        self.take.as_ref()
    }

    /// The take for editing.
    ///
    /// # Errors
    /// A message when no input is open.
    pub fn take_mut(&mut self) -> Result<&mut Take, String> {
        self.take
            .as_mut()
            .ok_or_else(|| "no capture is open: open a video, photos or the webcam first".into())
    }

    /// Closes the take.
    pub fn close(&mut self) {
        self.take = None;
        self.save_take();
    }

    fn busy(&self) -> Result<(), String> {
        match &self.job {
            Some(job) if !job.finished.load(Ordering::Acquire) => Err(format!(
                "the studio is busy ({}); wait for it or cancel it",
                job.kind
            )),
            _ => Ok(()),
        }
    }

    /// Asks the running job to stop; false when none runs.
    pub fn cancel(&self) -> bool {
        match &self.job {
            Some(job) if !job.finished.load(Ordering::Acquire) => {
                job.cancel.store(true, Ordering::Relaxed);
                true
            }
            _ => false,
        }
    }

    /// Sets the keyframe spacing and smoothing (the take's and the next ones').
    ///
    /// # Errors
    /// A message naming the bad field.
    pub fn set_filtering(
        &mut self,
        keyframe_every: usize,
        smoothing: Option<OneEuro>,
    ) -> Result<(), String> {
        if !(1..=1000).contains(&keyframe_every) {
            return Err(format!(
                "keyframe_every: must be between 1 and 1000, got {keyframe_every}"
            ));
        }
        if let Some(s) = smoothing {
            s.validate().map_err(|e| format!("smoothing: {e}"))?;
        }
        self.keyframe_every = keyframe_every;
        self.smoothing = smoothing;
        if self.take.is_some() {
            self.edit_take(|session| {
                session.keyframe_every = keyframe_every;
                session.smoothing = smoothing;
                Ok(())
            })?;
        }
        if let Some(live) = lock(&self.live).as_mut() {
            live.set_smoothing(smoothing);
        }
        Ok(())
    }

    /// Everything the page shows of capture mode.
    #[must_use]
    pub fn view(&self, character: &Character) -> Value {
        let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
        let live = lock(&self.live);
        json!({
            "blendshapes": names,
            "groups": names.iter().map(|n| group_of(n)).collect::<Vec<_>>(),
            "adapter": {
                "path": self.adapter_path.display().to_string(),
                "loaded": self.adapter.is_some(),
                "note": self.adapter_note,
                "report": self.adapter.as_ref().map(|a| &a.report),
            },
            "job": self.job.as_ref().map(|j| j.view()),
            "filtering": {
                "keyframe_every": self.keyframe_every,
                "smoothing": self.smoothing.map(|s| json!({
                    "min_cutoff": s.min_cutoff, "beta": s.beta, "derivative_cutoff": s.derivative_cutoff,
                })),
                "default_smoothing": { "min_cutoff": default_smoothing().min_cutoff, "beta": default_smoothing().beta, "derivative_cutoff": default_smoothing().derivative_cutoff },
            },
            "live": live.as_ref().map(Live::view),
            "take": self.take.as_ref().map(take_view),
        })
    }
}

/// The ARKit family a blendshape belongs to (`eye`, `brow`, `jaw`, `mouth`, `cheek`, `nose`,
/// `tongue`), or `other` when its name is not an ARKit name.
#[must_use]
pub fn group_of(name: &str) -> &'static str {
    let Some(arkit) = faceanim_rig::names::arkit_name(name) else {
        return "other";
    };
    for group in ["eye", "brow", "jaw", "mouth", "cheek", "nose", "tongue"] {
        if arkit.starts_with(group) {
            return group;
        }
    }
    "other"
}

fn take_view(take: &Take) -> Value {
    let session = &take.session;
    let weights = session.weights();
    let mean: Vec<f32> = weights
        .iter()
        .map(|row| row.iter().sum::<f32>() / row.len().max(1) as f32)
        .collect();
    let corrected: Vec<usize> = session.corrections.keys().copied().collect();
    json!({
        "id": take.id,
        "source": session.source,
        "fps": session.fps,
        "frames": session.frames.len(),
        "previews": take.previews.len(),
        "still": session.still_frames.is_some(),
        "by_adapter": take.by_adapter,
        "names": session.frames.iter().map(|f| &f.name).collect::<Vec<_>>(),
        "presence": session.frames.iter().map(|f| f.presence).collect::<Vec<_>>(),
        "head": session.frames.iter().map(|f| f.head).collect::<Vec<_>>(),
        "estimates": session.frames.iter().map(|f| &f.estimate).collect::<Vec<_>>(),
        "weights": weights,
        "mean": mean,
        "keyframes": session.keyframes(),
        "added_keyframes": session.added_keyframes,
        "removed_keyframes": session.removed_keyframes,
        "corrected": corrected,
        "corrections": session.corrections,
        "preference": session.preference,
        "preference_pending": session.preference_offsets(),
        "keyframe_every": session.keyframe_every,
        "can_undo": !take.undo.is_empty(),
        "can_redo": !take.redo.is_empty(),
    })
}

/// By-name estimates: each of the character's ARKit-named shapes gets MediaPipe's score.
struct ByName {
    /// For each of MediaPipe's scores (in its order), the character's blendshape it drives.
    columns: Vec<Option<usize>>,
    count: usize,
}

impl ByName {
    fn new(character: &Character) -> ByName {
        ByName {
            columns: faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .map(|n| {
                    if n.starts_with('_') {
                        None
                    } else {
                        character.find_blendshape(n).map(|id| id.index())
                    }
                })
                .collect(),
            count: character.blendshapes().len(),
        }
    }

    fn estimate(&self, scores: &[f32]) -> Vec<f32> {
        let mut row = vec![0.0; self.count];
        for (score, column) in scores.iter().zip(&self.columns) {
            if let Some(c) = column {
                row[*c] = score.clamp(0.0, 1.0);
            }
        }
        row
    }

    fn drives_any(&self) -> bool {
        self.columns.iter().any(Option::is_some)
    }
}

/// What was captured from one input.
struct Footage {
    /// The input's name as the user knows it.
    source: String,
    fps: f32,
    records: Vec<FrameRecord>,
    /// One per record: the image file, or `{stem}_{n}.png` for video frames.
    frame_names: Vec<String>,
    previews: Previews,
    /// A single photo (animated 0 → peak → 0).
    still: bool,
}

/// Turns captured frames into a take for `character` (adapter when given, else by name).
fn make_take(
    character: &Character,
    adapter: Option<&Adapter>,
    footage: Footage,
    filtering: (usize, Option<OneEuro>),
) -> Result<Take, String> {
    let Footage {
        source,
        fps,
        records,
        frame_names,
        previews,
        still,
    } = footage;
    let expressions: Vec<Option<Expression>> =
        records.iter().map(Expression::from_record).collect();
    let count = character.blendshapes().len();
    let estimates = match adapter {
        Some(adapter) => estimate_frames(&expressions, count, |e| adapter.predict(e)),
        None => {
            let by_name = ByName::new(character);
            if !by_name.drives_any() {
                return Err(format!(
                    "{} has no ARKit-named blendshapes: train an adapter for it first (Train adapter)",
                    character.name()
                ));
            }
            let rows: Vec<Option<Vec<f32>>> = records
                .iter()
                .map(|f| {
                    (f.scores.len() == faceanim_track::BLENDSHAPE_NAMES.len()).then(|| {
                        by_name.estimate(&f.scores.iter().map(|s| s.1).collect::<Vec<_>>())
                    })
                })
                .collect();
            let known: Vec<bool> = rows.iter().map(Option::is_some).collect();
            let mut rows: Vec<Vec<f32>> = rows
                .into_iter()
                .map(|r| r.unwrap_or_else(|| vec![0.0; count]))
                .collect();
            faceanim_anim::filter::fill_gaps_rows(&mut rows, &known);
            rows
        }
    };
    let frames: Vec<SessionFrame> = records
        .iter()
        .zip(expressions)
        .zip(estimates)
        .zip(frame_names)
        .map(|(((f, expression), estimate), name)| {
            SessionFrame::from_record(f, name, expression, estimate)
        })
        .collect();
    let names = character
        .blendshapes()
        .iter()
        .map(|b| b.name().to_owned())
        .collect();
    let mut session = Session::new(
        source,
        character.name().to_owned(),
        names,
        Fingerprint::of(character),
        fps,
        filtering.0,
        frames,
    );
    session.smoothing = filtering.1;
    if still {
        session.still_frames = Some(STILL_FRAMES);
    }
    Ok(Take::new(session, previews, Some(adapter.is_some())))
}

/// The take's clip with the sketch's weights added on top (clamped to [0, 1]); the longer of
/// the two sets the length, and each holds its last frame beyond its end.
#[must_use]
pub fn layered_weights(base: &Clip, sketch: &[Vec<f32>]) -> Clip {
    let frames = base.frames.len().max(sketch.len());
    let hold = |rows: &[Vec<f32>], f: usize| -> Option<Vec<f32>> {
        rows.get(f.min(rows.len().saturating_sub(1))).cloned()
    };
    let mut clip = base.clone();
    clip.frames = (0..frames)
        .map(|f| {
            let mut row =
                hold(&base.frames, f).unwrap_or_else(|| vec![0.0; base.blendshapes.len()]);
            if let Some(extra) = hold(sketch, f) {
                for (w, e) in row.iter_mut().zip(extra) {
                    *w = (*w + e).clamp(0.0, 1.0);
                }
            }
            row
        })
        .collect();
    let extend = |v: &mut Vec<[f32; 3]>| {
        if let Some(&last) = v.last() {
            v.resize(frames, last);
        }
    };
    if let Some(h) = clip.head.as_mut() {
        extend(h);
    }
    if let Some(p) = clip.head_position.as_mut() {
        extend(p);
    }
    if let Some(p) = clip.presence.as_mut() {
        let last = p.last().copied().unwrap_or(1.0);
        p.resize(frames, last);
    }
    clip
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "sums of exact binary fractions")]
mod tests {
    use super::*;

    fn clip(rows: Vec<Vec<f32>>) -> Clip {
        Clip {
            fps: 30.0,
            blendshapes: vec!["a".into(), "b".into()],
            frames: rows,
            head: None,
            head_position: None,
            presence: None,
        }
    }

    #[test]
    fn strokes_add_onto_the_take_clamped_and_the_longer_sets_the_length() {
        let base = clip(vec![vec![0.25, 0.5], vec![0.75, 0.5]]);
        let sketch = vec![vec![0.5, 0.0], vec![0.5, 0.25], vec![0.0, 0.75]];
        let layered = layered_weights(&base, &sketch);
        assert_eq!(
            layered.frames,
            vec![vec![0.75, 0.5], vec![1.0, 0.75], vec![0.75, 1.0]],
            "the third frame holds the take's last frame under the sketch's"
        );
        // No strokes: the take as it is.
        assert_eq!(layered_weights(&base, &[]).frames, base.frames);
    }

    fn two_frame_take() -> Take {
        let frames = (0..2)
            .map(|i| SessionFrame {
                name: format!("f{i}.png"),
                time: i as f32 / 30.0,
                presence: 1.0,
                head: None,
                head_position: None,
                expression: None,
                estimate: vec![0.25, 0.5],
            })
            .collect();
        let character = faceanim_testdata::ict();
        let session = Session::new(
            "test".into(),
            "test".into(),
            vec!["a".into(), "b".into()],
            Fingerprint::of(character),
            30.0,
            1,
            frames,
        );
        Take::new(session, Previews::new(), Some(false))
    }

    #[test]
    fn a_takes_edits_undo_and_redo_and_a_failed_edit_changes_nothing() {
        let mut take = two_frame_take();
        take.edit(|s| s.correct(1, "a", 0.75).map_err(|e| e.to_string()))
            .unwrap_or_default();
        take.edit(|s| {
            s.apply_preference();
            Ok(())
        })
        .unwrap_or_default();
        assert_eq!(take.session.weights()[0], vec![0.75, 0.5]);
        // A refused edit leaves no trace, not even on the undo stack.
        let refused = take.edit(|s| {
            s.keyframe_every = 7;
            s.correct(9, "a", 0.5).map_err(|e| e.to_string())
        });
        assert!(refused.is_err());
        assert_eq!(take.session.keyframe_every, 1);
        assert!(take.undo());
        assert_eq!(take.session.weights()[0], vec![0.25, 0.5]);
        assert!(take.undo());
        assert!(take.session.corrections.is_empty());
        assert!(!take.undo());
        assert!(take.redo() && take.redo());
        assert_eq!(take.session.weights()[0], vec![0.75, 0.5]);
        assert!(!take.redo());
    }

    #[test]
    fn arkit_families_group_the_sliders() {
        assert_eq!(group_of("jawOpen"), "jaw");
        assert_eq!(group_of("EyeBlink_L"), "eye");
        assert_eq!(group_of("mouthSmile_R"), "mouth");
        assert_eq!(group_of("browInnerUp"), "brow");
        assert_eq!(group_of("cheekPuff"), "cheek");
        assert_eq!(group_of("noseSneerLeft"), "nose");
        assert_eq!(group_of("shape_017"), "other");
    }

    #[test]
    fn by_name_puts_each_score_on_its_shape() {
        let character = faceanim_testdata::ict();
        let by_name = ByName::new(character);
        assert!(by_name.drives_any());
        let mut scores = vec![0.0; faceanim_track::BLENDSHAPE_NAMES.len()];
        let jaw = faceanim_track::BLENDSHAPE_NAMES
            .iter()
            .position(|n| *n == "jawOpen")
            .unwrap_or_default();
        scores[jaw] = 0.625;
        scores[0] = 0.9; // `_neutral` drives nothing
        let row = by_name.estimate(&scores);
        let column = character
            .find_blendshape("jawOpen")
            .map(|id| id.index())
            .unwrap_or_default();
        assert_eq!(row[column], 0.625);
        assert_eq!(row.iter().sum::<f32>(), 0.625);
    }
}
