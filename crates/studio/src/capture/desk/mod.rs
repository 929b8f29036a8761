//! The capture desk: the open take, the character's adapter and retarget map, the running
//! job, and the parts that feed takes (the webcam, VMC, the microphone). The desk's methods for
//! each part are in the child module of its name; the parts' own state types are beside this
//! module and never reach back into the desk.

pub(super) mod jobs;
mod live;
pub(super) mod retarget;
mod uploads;
mod vmc;
mod voice;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use faceanim_adapt::{Adapter, Fit};
use faceanim_anim::filter::OneEuro;
use faceanim_rig::Character;
use faceanim_take::{ByName, Estimator, Filtering, Footage, Session, Take, TakeError};

use crate::capture::job::Job;
use crate::capture::live::Live;
use crate::capture::models::face_models;
use crate::capture::open_take::{OpenTake, Previews, Sound, audio_mime};
use crate::capture::vmc::Vmc;
use crate::capture::voice::SharedVoice;
use crate::error::ApiError;
use crate::lock;
use crate::views::{AdapterView, CaptureView, FilteringView, Group, TakeView, names};

/// Capture mode's state (see the module docs).
#[derive(Debug)]
pub struct CaptureDesk {
    /// Where the character's adapter is read from and saved to.
    pub adapter_path: PathBuf,
    adapter: Option<Adapter>,
    /// Why the adapter beside the character is not used, or that it fits another shape.
    adapter_note: Option<String>,
    /// Where the character's retarget map is read from and saved to (beside the adapter).
    map_path: PathBuf,
    /// The character's retarget map: what reads capture when there is no adapter.
    map: Option<Arc<faceanim_retarget::RetargetMap>>,
    /// Why the map beside the character is not used.
    map_note: Option<String>,
    /// Where the user marked the character's face (kept beside the map), when they did.
    face_points: Option<faceanim_fit::FacePoints>,
    /// The last map was not made because the face model found no face on the character.
    no_face: bool,
    take: Option<OpenTake>,
    job: Option<Arc<Job>>,
    live: Arc<Mutex<Option<Live>>>,
    /// The smoothing and keyframe spacing new takes get (the page's controls).
    filtering: Filtering,
    /// Uploaded inputs are written here (ffmpeg reads files).
    uploads: Option<tempfile::TempDir>,
    /// Uploads stored so far: each gets a folder of its own.
    uploads_stored: u64,
    /// What the page should tell the user once: an autosave that was set aside.
    notice: Option<String>,
    /// The take's session is written here after every change and read back at start, so
    /// closing the studio loses no correction.
    take_path: PathBuf,
    /// VMC in and out.
    vmc: Vmc,
    /// Whether the studio's sketch is the one the character's file kept (its animation is then
    /// not opened as a take too).
    sketch_from_file: bool,
    /// The face's bones as the page's view of the character turns them (for a character whose
    /// file has a head bone).
    skeleton: Option<Arc<faceanim_export::bones::ViewRig>>,
    /// The live microphone.
    voice: SharedVoice,
    /// The voice learned by a microphone session that was stopped, for the next one.
    voice_model: Option<faceanim_speech::listen::VoiceModel>,
    /// The mouth read through the adapter (for a rig without mouth names), with the adapter
    /// it was read by.
    adapter_mouth: Option<(Adapter, faceanim_speech::Mouth)>,
    /// Visemes as ARKit channel values (the user's, or the built-in table), and the file the
    /// user's is kept in.
    visemes: faceanim_speech::MouthTable,
    visemes_path: Option<PathBuf>,
}

/// A take of `session` once its animation has been worked out (what every view and export
/// asks for first), or why it cannot be: the session's own checks should leave nothing that
/// fails here, and this keeps one that slipped through from being stored.
fn playable(session: Session) -> Result<Take, String> {
    let take = Take::from_session(session);
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| take.session.clip())) {
        Ok(_) => Ok(take),
        Err(_) => Err("its animation could not be worked out".to_owned()),
    }
}

/// Renames the file at `path` to `NAME.broken-SECONDS.EXT` beside it; returns the new path.
/// The sounds a take keeps beside its autosave, by ending (those [`audio_mime`] knows).
const KEPT_SOUND_EXTENSIONS: [&str; 8] = ["wav", "mp3", "ogg", "oga", "opus", "flac", "m4a", "aac"];

fn set_aside(path: &std::path::Path) -> std::io::Result<PathBuf> {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let name = path
        .file_name()
        .map_or_else(|| "take".into(), |n| n.to_string_lossy().into_owned());
    let aside = path.with_file_name(match name.rsplit_once('.') {
        Some((stem, extension)) => format!("{stem}.broken-{seconds}.{extension}"),
        None => format!("{name}.broken-{seconds}"),
    });
    std::fs::rename(path, &aside)?;
    Ok(aside)
}

/// Where the map of `character` lives: beside its adapter.
fn map_path(adapter_path: &std::path::Path, character: &Character) -> PathBuf {
    faceanim_adapt::bridge::default_map_path(adapter_path.parent(), character.name())
}

/// Per frame of `session`, the view's bones as its export turns them: the head pose shared
/// between spine, neck and head, gaze and jaw from the capture's own ARKit values (else from the
/// frames by their names' ARKit meaning).
fn take_bones(skeleton: &faceanim_export::bones::ViewRig, session: &Session) -> Vec<Vec<[f32; 4]>> {
    let clip = session.clip();
    let keys = faceanim_export::bones::BoneKeys::of_take(&clip, session.arkit_clip().as_ref());
    let head: Vec<Option<[f32; 3]>> = match &clip.head {
        Some(head) => head.iter().copied().map(Some).collect(),
        None => vec![None; clip.frames.len()],
    };
    skeleton.poses(clip.fps, &head, &keys)
}

/// A shared capture desk.
pub type SharedDesk = Arc<Mutex<CaptureDesk>>;

/// The smoothing the page offers when it is turned on: light enough to keep fast expressions.
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
    pub fn new(
        character: &Character,
        adapter_path: PathBuf,
        take_path: PathBuf,
        sketch_from_file: bool,
    ) -> CaptureDesk {
        let mut desk = CaptureDesk {
            take_path,
            map_path: map_path(&adapter_path, character),
            adapter_path,
            adapter: None,
            adapter_note: None,
            map: None,
            map_note: None,
            face_points: None,
            no_face: false,
            take: None,
            job: None,
            live: Arc::new(Mutex::new(None)),
            voice: Arc::new(Mutex::new(None)),
            voice_model: None,
            adapter_mouth: None,
            visemes: faceanim_speech::MouthTable::default(),
            visemes_path: None,
            filtering: Filtering::SEED,
            uploads: None,
            uploads_stored: 0,
            notice: None,
            vmc: Vmc::default(),
            skeleton: None,
            sketch_from_file,
        };
        desk.load_adapter(character);
        desk.load_map(character);
        desk.remake_skeleton(character);
        desk.restore_take(character);
        desk
    }

    /// What estimates new takes of `character`: its adapter when there is one (the user
    /// trained it), else its retarget map, else the by-name mapping.
    fn estimator(&self, character: &Character) -> Box<dyn Estimator> {
        match (&self.adapter, &self.map) {
            (Some(adapter), _) => Box::new(adapter.clone()),
            (None, Some(map)) => Box::new(faceanim_take::Retargeted::new(map.clone())),
            (None, None) => Box::new(ByName::new(character)),
        }
    }

    /// Makes a take of `footage` for `character` with the desk's estimator and filtering.
    fn take_of(&self, character: &Character, footage: Footage) -> Result<Take, ApiError> {
        let estimator = self.estimator(character);
        Ok(Take::from_capture(
            character,
            estimator.as_ref(),
            footage,
            self.filtering,
        )?)
    }

    /// Reopens the autosaved take (without its previews: the input is not kept). One that
    /// cannot be opened — refused, of another character, or failing to play — is set aside
    /// under another name and the page told so, so that it is neither lost nor met again at
    /// every start.
    fn restore_take(&mut self, character: &Character) {
        let bytes = match std::fs::read(&self.take_path) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                self.open_own_animation(character);
                return;
            }
            Err(e) => {
                tracing::warn!("{}: {e}; not opened", self.take_path.display());
                return;
            }
        };
        let opened = Session::from_json(&bytes)
            .map_err(|e| e.to_string())
            .and_then(|session| {
                if session.blendshapes == names(character) {
                    playable(session)
                } else {
                    Err(format!(
                        "it is a take of {}",
                        faceanim_rig::excerpt(&session.character)
                    ))
                }
            });
        match opened {
            Ok(take) => {
                tracing::info!(
                    "reopened the take of {} from {}",
                    take.session.source,
                    self.take_path.display()
                );
                // A lip-sync take plays with the sound kept beside it.
                let open = OpenTake::new(take, Previews::new());
                self.take = Some(match self.kept_sound() {
                    Some(sound) => open.with_sound(sound),
                    None => open,
                });
            }
            Err(why) => {
                let aside = set_aside(&self.take_path);
                let notice = match &aside {
                    Ok(path) => format!(
                        "The autosaved take could not be opened ({why}); it was set aside as {}.",
                        path.display()
                    ),
                    Err(e) => format!(
                        "The autosaved take {} could not be opened ({why}), nor set aside ({e}).",
                        self.take_path.display()
                    ),
                };
                tracing::warn!("{notice}");
                self.notice = Some(notice);
            }
        }
    }

    /// Opens a session file as the take: one written by `faceanim track --adapter A --session
    /// FILE`, edited by `faceanim session`, or exported from this tab (read by
    /// [`crate::capture::TakeJson::read`]). It has no previews (a session does not keep its
    /// input). Returns its frame count.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] when the session is of a character with other blendshapes, or
    /// [`ApiError::Busy`] when a job is running.
    pub fn open_session(
        &mut self,
        character: &Character,
        session: Session,
        shown: &str,
    ) -> Result<usize, ApiError> {
        self.busy()?;
        let names = names(character);
        if session.blendshapes != names {
            let lacking: Vec<&str> = names
                .iter()
                .filter(|n| !session.blendshapes.contains(n))
                .map(String::as_str)
                .collect();
            let how = match lacking.len() {
                0 => "the same names in another order or with others".to_owned(),
                n @ 1..=5 => format!("it lacks {n}: {}", lacking.join(", ")),
                n => format!("it lacks {n}: {}, …", lacking[..5].join(", ")),
            };
            return Err(ApiError::Invalid(format!(
                "{}: a session of {} with {} blendshapes, not of {} with {} ({how})",
                faceanim_rig::excerpt(shown),
                faceanim_rig::excerpt(&session.character),
                session.blendshapes.len(),
                character.name(),
                names.len()
            )));
        }
        // Played once before it is kept: a take that cannot be shown is never autosaved.
        let take = playable(session)
            .map_err(|why| ApiError::Invalid(format!("{}: {why}", faceanim_rig::excerpt(shown))))?;
        Ok(self.open_file_take(take, &format!("the session {shown}")))
    }

    /// With no take to restore, the character's own file's morph-weight animation (a take or
    /// sketch exported before) opens as the take, ready to correct and export again (under
    /// its name: the export replaces it).
    fn open_own_animation(&mut self, character: &Character) {
        let Some(reopened) = faceanim_export::reopen::animation_of(character) else {
            return;
        };
        // A sketch faceanim wrote opens as its strokes (the Sketch tab), not as a take too.
        if self.sketch_from_file {
            self.notice = Some(format!(
                "The file's {} is a sketch: its strokes are in the Sketch tab, ready to edit.",
                reopened.what
            ));
            return;
        }
        match self.open_clip(character, &reopened.clip, &reopened.name) {
            Ok(_) => {
                self.notice_first(format!("Opened the file's {} as the take.", reopened.what));
            }
            Err(e) => tracing::warn!("the file's animation was not opened: {e}"),
        }
    }

    /// Whether `character` lacks the retarget map it needs and one can be made now: its names
    /// leave channels MediaPipe reads without a shape while some shape is free to take them,
    /// it has no map and no file is where it would be saved (a map that could not be read is
    /// the user's to mend or make again: never written over unasked), and the face was found
    /// on it before (or the user has marked it since; a face not found is not looked for again
    /// on every clip).
    pub(super) fn lacks_map(&self, character: &Character) -> bool {
        self.map_missing(character) && !(self.no_face && self.face_points.is_none())
    }

    /// Whether `character` needs a retarget map and none is there: neither loaded nor a file
    /// where it would be saved (the part of [`CaptureDesk::lacks_map`] a capture goes by,
    /// which tries again where no face was found, to say so).
    pub(super) fn map_missing(&self, character: &Character) -> bool {
        self.map.is_none()
            && !self.map_path.exists()
            && faceanim_adapt::bridge::needs_map(character)
    }

    /// `Ok` while the character whose map would be saved at `path` is still the one open; a
    /// job that opens `shown` on it stops otherwise.
    pub(super) fn still_open(&self, path: &std::path::Path, shown: &str) -> Result<(), ApiError> {
        if self.map_path == path {
            return Ok(());
        }
        Err(ApiError::Invalid(format!(
            "{}: another character was opened meanwhile",
            faceanim_rig::excerpt(shown)
        )))
    }

    /// Whether opening `clip` on `character` waits for the character's retarget map: it
    /// [lacks](CaptureDesk::lacks_map) one, the clip moves ARKit channels its names leave
    /// without a shape ([`faceanim_anim::Clip::loses_arkit`]), and it is not a body with no
    /// blendshapes whose bones take the clip.
    pub(super) fn clip_needs_map(&self, character: &Character, clip: &faceanim_anim::Clip) -> bool {
        !faceanim_export::bones::takes_clip(character, clip)
            && clip.loses_arkit(character)
            && self.lacks_map(character)
    }

    /// Whether lip sync on `character` waits for its retarget map: its names say nothing of a
    /// mouth (no viseme or ARKit mouth shapes by the viseme table), no adapter reads it, and it
    /// [lacks](CaptureDesk::lacks_map) a map.
    pub(super) fn speech_needs_map(&self, character: &Character) -> bool {
        self.adapter.is_none()
            && faceanim_speech::Mouth::of(character, &self.visemes).is_err()
            && self.lacks_map(character)
    }

    /// Puts `text` before the notice there is (what opening a take found).
    fn notice_first(&mut self, text: String) {
        self.notice = Some(match self.notice.take() {
            Some(found) => format!("{text} {found}"),
            None => text,
        });
    }

    /// Makes `clip` the take: its columns put on `character` by name
    /// ([`faceanim_anim::Clip::retarget_through`]: ARKit's channels in any spelling, VRM's
    /// presets; through the character's retarget map where it has one), its head pose kept,
    /// one frame per row at its rate, unfiltered; the notice names the columns that move and
    /// reach none of the character's shapes. On a body with no blendshapes whose bones take
    /// the clip's head pose, gaze or jawOpen, the take is of no shapes, made of the clip's ARKit
    /// values (which turn the bones). Where the character's shapes miss columns its bones show
    /// (a clip's gaze on a body with eye bones and no eyeLook shapes), the take is made of the
    /// clip's ARKit values too, so the bones turn as the clip's export turns them, and the
    /// notice does not list those columns; where none of its shapes takes any column but its
    /// bones do, the shapes hold still. Returns its frame count.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] naming `shown` when no column reaches a shape of the character's
    /// (and none turns a bone of a body with no shapes), or the take's error.
    fn open_clip(
        &mut self,
        character: &Character,
        clip: &faceanim_anim::Clip,
        shown: &str,
    ) -> Result<usize, ApiError> {
        let count = clip.frames.len();
        // A body with no blendshapes takes the clip on its bones: the take is made of the
        // clip's ARKit values, which they follow.
        let on_bones = faceanim_export::bones::takes_clip(character, clip);
        // ARKit's channels reach a rig whose names say nothing through its map: where it has
        // none yet, what is lost says how to make it.
        let hint = if self.map.is_none()
            && !on_bones
            && clip.loses_arkit(character)
            && faceanim_adapt::bridge::needs_map(character)
        {
            " Make map (Retarget map, in this tab) carries ARKit's channels onto its shapes by geometry: then open the clip again."
        } else {
            ""
        };
        let (rows, mut unmatched) = if on_bones {
            (vec![Vec::new(); count], Vec::new())
        } else {
            let lost = clip.unmatched(character, self.map.as_deref());
            match clip.retarget_through(character, shown, self.map.as_deref()) {
                Ok(retarget) => (retarget.animation.weights, lost),
                // None of its shapes takes the clip, but its bones do (a jaw bone beside
                // shapes that only shape the lips): the shapes hold still, the bones turn.
                Err(faceanim_anim::ClipError::NothingInCommon { .. })
                    if faceanim_export::bones::bones_take(character, clip) =>
                {
                    (vec![vec![0.0; character.blendshapes().len()]; count], lost)
                }
                Err(e) => {
                    let shown = faceanim_rig::excerpt(shown);
                    return Err(ApiError::Invalid(if hint.is_empty() {
                        format!("{shown}: {e}")
                    } else {
                        format!("{shown}: {e}.{hint}")
                    }));
                }
            }
        };
        // What the character's eye and jaw bones show (a clip's gaze on a body with eye bones
        // and no eyeLook shapes) is not lost: the bones take it, as the clip's export turns
        // them from its own columns.
        let before = unmatched.len();
        if let Some(skeleton) = &self.skeleton {
            unmatched.retain(|name| !skeleton.shows(name));
        }
        let mut take = Take::from_weights(character, shown, clip.fps, &rows, clip.head.as_deref())?;
        // Through the map, the character's own names say nothing of the clip's ARKit channels:
        // the take is made of them too, so its bones (a jaw beside the shapes the map opens the
        // mouth with) turn as the clip's export turns them.
        let through_map = self.map.is_some() && clip.loses_arkit(character);
        // A clip JSON that keeps the ARKit values its take was made of (a VRoid take's gaze)
        // is made of them where its columns do not say.
        if on_bones || through_map || unmatched.len() < before || clip.arkit.is_some() {
            take = take.made_of_arkit(clip.arkit_rows())?;
        }
        let way = if on_bones { " on the bones" } else { "" };
        let frames = self.open_file_take(take, &format!("the clip {shown}{way}"));
        if !unmatched.is_empty() {
            let listed: Vec<_> = unmatched
                .iter()
                .take(8)
                .map(|n| faceanim_rig::excerpt(n))
                .collect();
            let more = unmatched.len().saturating_sub(listed.len());
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            let warning = format!(
                "None of {}'s shapes answers to {}{more}: left out.{}",
                faceanim_rig::excerpt(character.name()),
                listed.join(", "),
                hint
            );
            tracing::warn!("{shown}: {warning}");
            self.notice = Some(warning);
        }
        Ok(frames)
    }

    /// Makes `lip_sync` (of the uploaded `speech`) the take: its frames the character's
    /// weights at `lip_sync.fps`, played with the sound. Returns its frame count.
    ///
    /// # Errors
    /// [`ApiError::Busy`] when a job is running, or the take's error.
    pub fn open_speech(
        &mut self,
        character: &Character,
        lip_sync: &faceanim_speech::LipSync,
        speech: &crate::capture::speech::Speech,
    ) -> Result<usize, ApiError> {
        self.busy()?;
        self.put_speech(character, lip_sync, speech.sound(), &speech.shown)
    }

    /// [`CaptureDesk::open_speech`] from the job that made the map it needed.
    fn put_speech(
        &mut self,
        character: &Character,
        lip_sync: &faceanim_speech::LipSync,
        sound: Sound,
        shown: &str,
    ) -> Result<usize, ApiError> {
        let count = lip_sync.frames.len();
        // What it is made of goes with it (Live Link Face's curves, a jaw bone's opening).
        let take = Take::from_weights(character, shown, lip_sync.fps, &lip_sync.frames, None)?
            .made_of_arkit(lip_sync.arkit(&self.visemes))?;
        tracing::info!("lip sync of {shown}: {count} frames");
        if !lip_sync.notes.is_empty() {
            // What was done instead of what was asked (a transcript that could not be used).
            self.notice = Some(format!("{shown}: {}", lip_sync.notes.join("; ")));
        }
        let sound = self.keep_sound(sound);
        self.take = Some(OpenTake::new(take, Previews::new()).with_sound(sound));
        self.save_take();
        Ok(count)
    }

    /// Where the take's sound is kept beside its autosave, for a sound file ending in
    /// `extension` (`.project.take.sound.wav`): with the project, not in a temporary folder, so
    /// a lip-sync take plays with its sound after the studio is closed and opened again.
    fn kept_sound_path(&self, extension: &str) -> PathBuf {
        let stem = self
            .take_path
            .file_stem()
            .map_or_else(|| "take".into(), |s| s.to_string_lossy().into_owned());
        self.take_path
            .with_file_name(format!("{stem}.sound.{extension}"))
    }

    /// The take's sound kept beside the autosave, if there is one.
    fn kept_sound(&self) -> Option<Sound> {
        KEPT_SOUND_EXTENSIONS.iter().find_map(|extension| {
            let path = self.kept_sound_path(extension);
            let mime = audio_mime(&path.to_string_lossy())?;
            path.is_file().then_some(Sound { path, mime })
        })
    }

    /// Copies `sound` (an upload's private copy, a recording) beside the autosave and returns
    /// the kept copy; on failure the page is told, and the sound plays from where it is until
    /// the studio closes.
    pub(super) fn keep_sound(&mut self, sound: Sound) -> Sound {
        let extension = sound
            .path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .filter(|e| KEPT_SOUND_EXTENSIONS.contains(&e.as_str()));
        let Some(extension) = extension else {
            return sound;
        };
        self.remove_kept_sound();
        let kept = self.kept_sound_path(&extension);
        let copied = faceanim_files::read_bytes(&sound.path)
            .and_then(|bytes| faceanim_files::write_atomic(&kept, &bytes));
        match copied {
            Ok(()) => Sound {
                path: kept,
                mime: sound.mime,
            },
            Err(e) => {
                let why = format!(
                    "The take's sound could not be kept with the project ({e}): it plays until the studio closes."
                );
                tracing::warn!("{why}");
                self.notice = Some(why);
                sound
            }
        }
    }

    /// Removes a kept sound (the take it belonged to was replaced or closed).
    fn remove_kept_sound(&self) {
        for extension in KEPT_SOUND_EXTENSIONS {
            let path = self.kept_sound_path(extension);
            match std::fs::remove_file(&path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    tracing::warn!("{}: {e}; not removed", path.display());
                }
                _ => {}
            }
        }
    }

    /// Writes the take (or, with none, removes the autosave), and keeps its sound beside it
    /// only while it has one.
    fn save_take(&self) {
        if self.take.as_ref().is_none_or(|open| open.sound.is_none()) {
            self.remove_kept_sound();
        }
        let result = match &self.take {
            Some(open) => faceanim_files::write_atomic(
                &self.take_path,
                open.take.session.to_json().as_bytes(),
            )
            .map_err(|e| e.to_string()),
            None => match std::fs::remove_file(&self.take_path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e.to_string()),
                _ => Ok(()),
            },
        };
        if let Err(e) = result {
            tracing::warn!("autosaving the take failed: {e}");
        }
    }

    /// Makes `take`, opened from a file (`what`), the one being edited, with no previews (a
    /// file keeps no pictures); its frame count.
    fn open_file_take(&mut self, take: Take, what: &str) -> usize {
        let frames = take.session.frames.len();
        tracing::info!("opened {what}: {frames} frames");
        self.set_take(take, Previews::new());
        frames
    }

    /// Makes `take` the one being edited (and autosaves it).
    fn set_take(&mut self, take: Take, previews: Previews) {
        self.notice = None;
        self.take = Some(OpenTake::new(take, previews));
        self.save_take();
    }

    /// Applies `change` to the take's session (undoably) and autosaves it.
    ///
    /// # Errors
    /// [`ApiError::NoTake`] when no take is open, or `change`'s error.
    pub fn edit_take(
        &mut self,
        change: impl FnOnce(&mut Session) -> Result<(), TakeError>,
    ) -> Result<(), ApiError> {
        self.take_mut()?.take.edit(change)?;
        self.save_take();
        Ok(())
    }

    /// Makes `frame` the take's neutral one (`None`: each part of the face at its calmest
    /// frame) and estimates every frame again relative to it with the desk's estimator.
    ///
    /// # Errors
    /// [`ApiError::NoTake`] when no take is open, or the take's refusal (a frame past the end
    /// or without a face).
    pub fn set_neutral(
        &mut self,
        character: &Character,
        frame: Option<usize>,
    ) -> Result<(), ApiError> {
        let estimator = self.estimator(character);
        self.take_mut()?
            .take
            .session
            .set_neutral(frame, estimator.as_ref())?;
        self.save_take();
        Ok(())
    }

    /// Undoes (`back`) or redoes one edit of the take; false when there was none.
    ///
    /// # Errors
    /// [`ApiError::NoTake`] when no take is open.
    pub fn step_history(&mut self, back: bool) -> Result<bool, ApiError> {
        let take = &mut self.take_mut()?.take;
        let stepped = if back { take.undo() } else { take.redo() };
        if stepped {
            self.save_take();
        }
        Ok(stepped)
    }

    /// The character's mouth for lip sync: its visemes or ARKit mouth shapes by name, else
    /// read through its adapter (each viseme the built-in head makes, rendered and read; done
    /// once per adapter), else each viseme's channels through its retarget map.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] when it has no mouth by name, no adapter and no map that moves
    /// one; the face models' or the adapter's error.
    pub fn mouth(&mut self, character: &Character) -> Result<faceanim_speech::Mouth, ApiError> {
        let table = self.visemes.clone();
        let by_name = faceanim_speech::Mouth::of(character, &table);
        if by_name.is_err()
            && self.adapter.is_none()
            && let Some(map) = &self.map
        {
            let mouth = faceanim_speech::Mouth::through_map(map, &table);
            if mouth.moves() {
                return Ok(mouth);
            }
        }
        let (Err(no_mouth), Some(adapter)) = (&by_name, &self.adapter) else {
            return by_name.map_err(|e| ApiError::Invalid(e.to_string()));
        };
        tracing::debug!("{no_mouth}: reading the mouth through the adapter");
        if let Some((read_by, mouth)) = &self.adapter_mouth
            && read_by == adapter
        {
            return Ok(mouth.clone());
        }
        // The built-in head makes each viseme by the table: it is the adapter's route's too.
        let models = face_models()?;
        let performer = faceanim_head::default_character();
        let rows = faceanim_speech::Mouth::performer_rows(&performer, &table)
            .map_err(|e| ApiError::Internal(e.to_string()))?;
        let readings = faceanim_adapt::FaceCamera::frame(&performer, models)?
            .read_performer(&performer, models, adapter, &rows)?;
        let mouth = faceanim_speech::Mouth::from_readings(character.blendshapes().len(), &readings);
        self.adapter_mouth = Some((adapter.clone(), mouth.clone()));
        Ok(mouth)
    }

    /// Keeps the user's viseme table in `path`, reading it from there when it exists (a file
    /// that is not a table is reported and left alone).
    pub fn open_visemes(&mut self, path: PathBuf) {
        if let Ok(text) = std::fs::read_to_string(&path) {
            match faceanim_speech::MouthTable::from_json(&text) {
                Ok(table) => self.visemes = table,
                Err(e) => tracing::warn!("{}: not used ({e})", path.display()),
            }
        }
        self.visemes_path = Some(path);
    }

    /// Whether the character's adapter is loaded.
    #[must_use]
    pub fn has_adapter(&self) -> bool {
        self.adapter.is_some()
    }

    /// The viseme table lip sync uses on ARKit rigs, and whether it is the built-in one.
    #[must_use]
    pub fn visemes(&self) -> (&faceanim_speech::MouthTable, bool) {
        (
            &self.visemes,
            self.visemes == faceanim_speech::MouthTable::default(),
        )
    }

    /// Makes `text` (JSON, as `faceanim lipsync --viseme-table` reads it; visemes left out
    /// keep the built-in values, `{}` is the built-in table) the viseme table, saves it beside
    /// the project, and puts it on the live microphone's mouth.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] naming the field that is wrong; the save's error.
    pub fn set_visemes(&mut self, character: &Character, text: &str) -> Result<(), ApiError> {
        let table = faceanim_speech::MouthTable::from_json(text)
            .map_err(|e| ApiError::Invalid(e.to_string()))?;
        if let Some(path) = &self.visemes_path {
            let json = serde_json::to_string_pretty(&table.visemes)
                .map_err(|e| ApiError::Internal(e.to_string()))?;
            faceanim_files::write_atomic(path, json.as_bytes())?;
        }
        self.visemes = table;
        self.adapter_mouth = None;
        // A mouth that waits for the retarget map takes the table when the map comes.
        if lock(&self.voice).as_ref().is_some_and(|v| !v.awaits_map()) {
            let mouth = self.mouth(character)?;
            if let Some(voice) = lock(&self.voice).as_mut() {
                voice.set_mouth(mouth, &self.visemes);
            }
        }
        Ok(())
    }

    /// Reads the adapter beside the character, keeping it only when it fits.
    fn load_adapter(&mut self, character: &Character) {
        self.adapter = None;
        self.adapter_note = None;
        if !self.adapter_path.exists() {
            return;
        }
        let loaded = faceanim_files::read_bytes(&self.adapter_path)
            .map_err(ApiError::from)
            .and_then(|bytes| Ok(Adapter::from_bytes(&bytes)?))
            .and_then(|adapter| {
                let fit = adapter.check(character)?;
                Ok((adapter, fit))
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
            job.ask_to_cancel();
        }
        self.take = None;
        *lock(&self.live) = None;
        self.map_path = map_path(&adapter_path, character);
        self.adapter_path = adapter_path;
        self.load_adapter(character);
        self.load_map(character);
        self.remake_skeleton(character);
        // VMC names follow the character.
        if let Err(e) = self.open_vmc(self.vmc.config(), character) {
            tracing::warn!("VMC for {}: {e}", character.name());
        }
    }

    /// The view's skeleton of `character`, its jaw's turn measured through the retarget map
    /// where the character's names do not say what opens its mouth.
    fn remake_skeleton(&mut self, character: &Character) {
        self.skeleton =
            faceanim_export::bones::ViewRig::of(character, self.map.as_deref()).map(Arc::new);
    }

    /// The take, if one is open.
    #[must_use]
    pub fn take(&self) -> Option<&OpenTake> {
        self.take.as_ref()
    }

    /// The take, or [`ApiError::NoTake`].
    ///
    /// # Errors
    /// [`ApiError::NoTake`] when no input is open.
    pub fn open_take(&self) -> Result<&OpenTake, ApiError> {
        self.take.as_ref().ok_or(ApiError::NoTake)
    }

    fn take_mut(&mut self) -> Result<&mut OpenTake, ApiError> {
        self.take.as_mut().ok_or(ApiError::NoTake)
    }

    /// Closes the take.
    pub fn close(&mut self) {
        self.take = None;
        self.save_take();
    }

    fn busy(&self) -> Result<(), ApiError> {
        match &self.job {
            Some(job) if job.running() => Err(ApiError::Busy(job.kind())),
            _ => Ok(()),
        }
    }

    /// Whether the retarget map is being made now.
    fn making_map(&self) -> bool {
        matches!(&self.job, Some(job) if job.running() && job.kind() == crate::views::JobKind::MakingMap)
    }

    /// Asks the running job to stop; false when none runs.
    pub fn cancel(&self) -> bool {
        match &self.job {
            Some(job) if job.running() => {
                job.ask_to_cancel();
                true
            }
            _ => false,
        }
    }

    /// Sets the keyframe spacing and smoothing (the take's, as an edit, and the next ones').
    ///
    /// # Errors
    /// [`ApiError::Take`] when the take refuses it.
    pub fn set_filtering(&mut self, filtering: Filtering) -> Result<(), ApiError> {
        self.filtering = filtering;
        if self.take.is_some() {
            self.edit_take(|session| {
                session.set_filtering(filtering);
                Ok(())
            })?;
        }
        if let Some(live) = lock(&self.live).as_mut() {
            live.set_smoothing(filtering.smoothing);
        }
        Ok(())
    }

    /// Everything the page shows of capture mode.
    #[must_use]
    pub fn view(&self, character: &Character) -> CaptureView {
        let names = names(character);
        CaptureView {
            groups: names.iter().map(|n| Group::of(n)).collect(),
            partners: character
                .blendshapes()
                .iter()
                .enumerate()
                .map(|(i, _)| {
                    let id = faceanim_rig::BlendshapeId(i as u32);
                    character.symmetry().partner(id).map(|p| p.index())
                })
                .collect(),
            blendshapes: names,
            adapter: AdapterView {
                path: self.adapter_path.display().to_string(),
                loaded: self.adapter.is_some(),
                note: self.adapter_note.clone(),
                report: self.adapter.as_ref().map(|a| a.report.clone()),
                calibrated: self
                    .adapter
                    .as_ref()
                    .is_some_and(faceanim_take::Estimator::calibrated),
                on_map: self.adapter.as_ref().is_some_and(|a| a.base().is_some()),
                unseen: self.adapter.as_ref().map_or_else(Vec::new, |a| {
                    faceanim_adapt::readings::unseen(&a.report.shapes)
                        .into_iter()
                        .map(str::to_owned)
                        .collect()
                }),
                default_samples: faceanim_adapt::DEFAULT_SAMPLES,
            },
            job: self.job.as_ref().map(|j| j.view()),
            filtering: FilteringView {
                keyframe_every: self.filtering.keyframe_every,
                smoothing: self.filtering.smoothing.map(Into::into),
                default_smoothing: default_smoothing().into(),
            },
            live: lock(&self.live).as_ref().map(Live::view),
            voice: self.voice_view(),
            vmc: self.vmc_view(),
            notice: self.notice.clone(),
            retarget: self.map_view(character),
            take: self.take.as_ref().map(|open| {
                // The neutral check reads one frame: borrow the adapter, do not copy it.
                let estimator = self.estimator(character);
                let mut view = TakeView::of(
                    &open.take,
                    open.id(),
                    open.previews.len(),
                    estimator.as_ref(),
                );
                view.sound = open
                    .sound
                    .as_ref()
                    .map(|_| format!("api/capture/sound?take={}", open.id()));
                view.bones = self
                    .skeleton
                    .as_deref()
                    .map(|skeleton| take_bones(skeleton, &open.take.session));
                view
            }),
        }
    }
}
