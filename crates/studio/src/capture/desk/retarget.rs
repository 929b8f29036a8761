//! The character's retarget map on the capture desk: read from beside the character, made in
//! the background (by the page's button; for a rig whose names leave channels without a shape,
//! before its first capture, clip or line of speech that needs it, and when its live inputs
//! start), shown row by row, and edited a row at a time.

use std::collections::BTreeMap;
use std::sync::Arc;

use faceanim_retarget::RetargetMap;
use faceanim_rig::Character;

use super::{CaptureDesk, SharedDesk};
use crate::capture::job::{Job, spawn_job};
use crate::capture::models::face_models;
use crate::error::ApiError;
use crate::lock;
use crate::views::JobKind;
use crate::views::{FaceMarkView, RetargetRowView, RetargetView};

impl CaptureDesk {
    /// Reads the map beside the character, when there is one that fits it.
    pub(super) fn load_map(&mut self, character: &Character) {
        self.map = None;
        self.map_note = None;
        self.no_face = false;
        self.face_points = None;
        let points_path = self.points_path(character);
        if points_path.exists() {
            let read = faceanim_files::read_bytes(&points_path)
                .map_err(|e| e.to_string())
                .and_then(|b| faceanim_fit::FacePoints::from_json(&b).map_err(|e| e.to_string()));
            match read {
                Ok(points) => self.face_points = Some(points),
                Err(e) => {
                    tracing::warn!("{}: {e}", points_path.display());
                    self.map_note = Some(format!("{} is not used: {e}", points_path.display()));
                }
            }
        }
        if !self.map_path.exists() {
            return;
        }
        let names = crate::views::names(character);
        let loaded = faceanim_files::read_bytes(&self.map_path)
            .map_err(|e| e.to_string())
            .and_then(|bytes| RetargetMap::from_json(&bytes, &names).map_err(|e| e.to_string()));
        match loaded {
            Ok(map) => self.map = Some(Arc::new(map)),
            Err(e) => {
                tracing::warn!("{}: {e}", self.map_path.display());
                self.map_note = Some(format!(
                    "{} is not used: {e}. Make map writes a new one in its place (nothing else \
                     writes over it).",
                    self.map_path.display()
                ));
            }
        }
    }

    /// Where the marks on `character`'s face are kept: beside its map.
    fn points_path(&self, character: &Character) -> std::path::PathBuf {
        faceanim_fit::points::default_path(self.map_path.parent(), character.name())
    }

    /// Where the user marked the character's face, when they did.
    #[must_use]
    pub fn face_points(&self) -> Option<&faceanim_fit::FacePoints> {
        self.face_points.as_ref()
    }

    /// Keeps the user's marks on `character`'s face (saved beside the map): the next map, and
    /// shapes generated in the studio, place the template by them.
    ///
    /// # Errors
    /// [`ApiError::Busy`] while a job runs; [`ApiError::Invalid`] naming the point that is
    /// missing or wrong; the save's error.
    pub fn set_face_points(
        &mut self,
        character: &Character,
        points: BTreeMap<faceanim_fit::FacePoint, [f32; 3]>,
    ) -> Result<(), ApiError> {
        self.busy()?;
        let points =
            faceanim_fit::FacePoints::new(points).map_err(|e| ApiError::Invalid(e.to_string()))?;
        faceanim_files::write_atomic(&self.points_path(character), points.to_json().as_bytes())?;
        self.face_points = Some(points);
        self.no_face = false;
        Ok(())
    }

    /// The character's retarget map, when it has one.
    #[must_use]
    pub fn map(&self) -> Option<&RetargetMap> {
        self.map.as_deref()
    }

    /// The map's rows for the page.
    #[must_use]
    pub fn map_view(&self, character: &Character) -> RetargetView {
        let rows = self.map.as_ref().map_or_else(Vec::new, |map| {
            map.rows
                .iter()
                .enumerate()
                .map(|(c, row)| RetargetRowView {
                    channel: row.channel.clone(),
                    from: row.from,
                    shapes: map
                        .answers(c)
                        .into_iter()
                        .map(|(s, w)| (s.to_owned(), w))
                        .collect(),
                    explained: row.explained,
                    with_twin: map
                        .shares_with_twin(c)
                        .map(|t| faceanim_rig::names::ARKIT_52[t]),
                    calibrated: map
                        .calibration
                        .as_ref()
                        .is_some_and(|k| k.channels.contains_key(&row.channel)),
                })
                .collect()
        });
        RetargetView {
            path: self.map_path.display().to_string(),
            loaded: self.map.is_some(),
            needed: faceanim_adapt::bridge::needs_map(character),
            in_use: self.adapter.is_none() && self.map.is_some(),
            note: self.map_note.clone(),
            seconds: self.map.as_ref().and_then(|m| m.made.seconds),
            rows,
            marks: faceanim_fit::FacePoint::ALL
                .iter()
                .map(|&point| FaceMarkView {
                    point,
                    describe: point.describe(),
                })
                .collect(),
            face_points: self.face_points.as_ref().map(|p| p.points.clone()),
            no_face: self.no_face,
        }
    }

    /// Sets `channel`'s row to `shapes` (the user's choice, kept when the map is made again),
    /// saves the map and re-reads the take through it.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] when there is no map, or naming the channel, shape or weight that
    /// is wrong; the save's error.
    pub fn set_map_row(
        &mut self,
        character: &Character,
        channel: &str,
        shapes: BTreeMap<String, f32>,
    ) -> Result<(), ApiError> {
        self.busy()?;
        let mut map =
            self.map.as_deref().cloned().ok_or_else(|| {
                ApiError::Invalid("there is no retarget map: make one first".into())
            })?;
        map.set_row(channel, shapes)
            .map_err(|e| ApiError::Invalid(e.to_string()))?;
        faceanim_files::write_atomic(&self.map_path, map.to_json().as_bytes())?;
        self.install_map(character, map)
    }

    /// Makes `map` the desk's, and re-reads the take, the webcam and the microphone's mouth
    /// (one that goes through a map, or waits for it) through it unless an adapter reads them.
    fn install_map(&mut self, character: &Character, map: RetargetMap) -> Result<(), ApiError> {
        let map = Arc::new(map);
        self.map = Some(map.clone());
        self.map_note = None;
        self.vmc.set_map(Some(map.clone()));
        // The jaw bone's turn, where the map says what opens the mouth.
        self.remake_skeleton(character);
        if self.adapter.is_some() {
            return Ok(());
        }
        let still = match lock(&self.voice).as_mut() {
            Some(voice) if voice.through_map() => !voice.use_map(&map, &self.visemes),
            _ => false,
        };
        if still {
            self.notice_first(
                "The retarget map gives the mouth none of the character's shapes: the microphone \
                 moves nothing."
                    .into(),
            );
        }
        let estimator = faceanim_take::Retargeted::new(map);
        if let Some(open) = self.take.as_mut() {
            open.take.reestimate(&estimator)?;
            self.save_take();
        }
        if let Some(live) = lock(&self.live).as_mut() {
            live.estimator = Box::new(estimator);
        }
        Ok(())
    }
}

/// Starts making `character`'s map in the background (again, keeping the rows the user set,
/// when `remake`); saves it beside the character and re-reads the take through it. With
/// `marks`, the user's marks on the face are kept first ([`CaptureDesk::set_face_points`])
/// and the map is made from them.
///
/// # Errors
/// [`ApiError::Busy`] when another job runs; [`ApiError::Invalid`] when there is a map and
/// `remake` is false, or naming the mark that is wrong.
pub fn start_map(
    desk: &SharedDesk,
    character: Arc<Character>,
    remake: bool,
    marks: Option<BTreeMap<faceanim_fit::FacePoint, [f32; 3]>>,
) -> Result<(), ApiError> {
    let job = Job::new(JobKind::MakingMap);
    let previous = {
        let mut guard = lock(desk);
        guard.busy()?;
        if guard.map.is_some() && !remake {
            return Err(ApiError::Invalid(
                "the character has a retarget map: ask to remake it".into(),
            ));
        }
        if let Some(marks) = marks {
            guard.set_face_points(&character, marks)?;
        }
        guard.job = Some(job.clone());
        guard.map.clone()
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let map = make(job, &desk, &character, previous.as_deref())?;
        let message = format!(
            "{} of ARKit's 52 channels reach its shapes, in {:.1} s",
            map.answered(),
            map.made.seconds.unwrap_or(0.0)
        );
        Ok(message)
    });
    Ok(())
}

/// Starts making the map in the background for live input (the webcam, a phone or a VMC
/// tracker), when the rig lacks one (the desk's `lacks_map`), no adapter reads capture
/// and no job runs. The input goes on by name meanwhile, and through the map once it is
/// installed. Returns whether it started.
pub fn map_for_live(desk: &SharedDesk, character: Arc<Character>) -> bool {
    let wanted = {
        let guard = lock(desk);
        guard.adapter.is_none() && guard.busy().is_ok() && guard.lacks_map(&character)
    };
    wanted && start_map(desk, character, false, None).is_ok()
}

/// [`map_for_live`] for a phone or a VMC tracker, when the studio listens to one: started
/// with the studio and for each character opened, so the phone's ARKit channels reach a rig
/// whose names say nothing once the map is there.
pub fn map_for_listeners(desk: &SharedDesk, character: Arc<Character>) -> bool {
    let listening = lock(desk).vmc.marionette().is_ok();
    listening && map_for_live(desk, character)
}

/// Makes the map before a capture when the rig needs one, has none and no adapter reads it
/// (a file there that could not be read as its map is not written over unasked).
pub(super) fn ensure_map(
    job: &Job,
    desk: &SharedDesk,
    character: &Character,
) -> Result<(), ApiError> {
    {
        let guard = lock(desk);
        if guard.adapter.is_some() || !guard.map_missing(character) {
            return Ok(());
        }
    }
    make(job, desk, character, None).map(|_| ())
}

/// Makes the map, saves it and installs it on the desk (unless another character was opened
/// meanwhile).
pub(super) fn make(
    job: &Job,
    desk: &SharedDesk,
    character: &Character,
    previous: Option<&RetargetMap>,
) -> Result<RetargetMap, ApiError> {
    job.stage("making the retarget map", 0);
    let models = face_models()?;
    let (path, points) = {
        let guard = lock(desk);
        (guard.map_path.clone(), guard.face_points.clone())
    };
    let progress = |done: usize, total: usize| job.progress_of(done, total);
    let made = faceanim_adapt::bridge::make_map(
        character,
        models,
        previous,
        points.as_ref(),
        true,
        faceanim_adapt::Control {
            progress: &progress,
            cancel: job.cancel_flag(),
        },
    );
    let no_face = matches!(
        made,
        Err(faceanim_adapt::bridge::BridgeError::Fit(
            faceanim_fit::FitError::NoFace(_)
        ))
    );
    {
        let mut guard = lock(desk);
        if guard.map_path == path {
            guard.no_face = no_face;
        }
    }
    let map = made?;
    faceanim_files::write_atomic(&path, map.to_json().as_bytes())?;
    let mut guard = lock(desk);
    if guard.map_path != path {
        return Err(ApiError::Invalid(format!(
            "another character was opened meanwhile; the map was saved to {} but is not used",
            path.display()
        )));
    }
    guard.install_map(character, map.clone())?;
    Ok(map)
}
