//! The studio's state: the character, the project (strokes with their edits, settings), the
//! undo and redo stacks, and what the page is shown of it.

use std::path::PathBuf;
use std::sync::Arc;

use faceanim_rig::Character;
use faceanim_sketch::project::{ProjectFile, StrokeFile};
use faceanim_sketch::settings::{Selection, Settings};
use faceanim_sketch::{Project, Sketch};
use glam::Vec3;

use crate::error::ApiError;
use crate::views::{ActionView, AnchorView, CandidatesView, RejectedView, StateView};

/// How many edits undo remembers.
const UNDO_DEPTH: usize = 500;

/// A character and the animation being sketched on it.
#[derive(Debug)]
pub struct Studio {
    /// The character (shared with capture jobs that outlive a request).
    pub character: Arc<Character>,
    project: ProjectFile,
    undo: Vec<ProjectFile>,
    redo: Vec<ProjectFile>,
    /// The gesture the last change belonged to.
    gesture: Option<String>,
    /// Where Save writes.
    pub project_path: PathBuf,
    /// Where every edit is written at once, so a crash loses nothing.
    pub autosave_path: PathBuf,
    /// The name of the animation whose kept sketch the project is, when it came from the
    /// character's own file.
    sketch_from_file: Option<String>,
}

/// A new studio project. It selects targets by segment rather than by the paper's Eq. 1: a
/// stroke drawn on a screen, or an arrow dragged part-way back, should keep its blendshape at a
/// partial weight, not jump to whichever smaller blendshape's full target is nearer. Files
/// replayed on the command line keep the paper's default unless they say otherwise.
fn empty_project() -> ProjectFile {
    ProjectFile {
        version: 1,
        fps: 30.0,
        settings: Settings {
            selection: Selection::Segment,
            ..Settings::default()
        },
        strokes: Vec::new(),
    }
}

/// The sketch `character`'s own file keeps with its animation (a sketched GLB faceanim
/// wrote), when it is a project faceanim can replay; it opens as strokes, not as a take.
#[must_use]
pub fn file_sketch(character: &Character) -> Option<ProjectFile> {
    let strokes = character.source()?.strokes()?;
    let bytes = serde_json::to_vec(strokes).ok()?;
    match parse_project(&bytes, "the file's sketch") {
        Ok(file) => Some(file),
        Err(e) => {
            tracing::warn!("{}: {e}; its animation opens as a take", character.name());
            None
        }
    }
}

fn parse_project(bytes: &[u8], what: &str) -> Result<ProjectFile, ApiError> {
    let invalid = |source| ApiError::Project {
        what: what.to_owned(),
        source,
    };
    let file: ProjectFile = faceanim_rig::json::from_slice(bytes).map_err(|e| {
        invalid(faceanim_sketch::project::ProjectError::Syntax(
            e.to_string(),
        ))
    })?;
    Project::from_file(file.clone()).map_err(invalid)?;
    Ok(file)
}

impl Studio {
    /// Opens `project_path` if it exists (or its autosave, when that is newer: the last
    /// session ended without saving), else starts an empty project.
    ///
    /// # Errors
    /// [`ApiError::Disk`] or [`ApiError::Project`] naming the file when a project exists but
    /// cannot be used.
    pub fn open(character: Character, project_path: PathBuf) -> Result<Studio, ApiError> {
        let autosave_path = autosave_path(&project_path);
        let modified = |p: &PathBuf| std::fs::metadata(p).and_then(|m| m.modified()).ok();
        let newest = match (modified(&project_path), modified(&autosave_path)) {
            (Some(saved), Some(auto)) if auto > saved => Some(&autosave_path),
            (None, Some(_)) => Some(&autosave_path),
            (Some(_), _) => Some(&project_path),
            (None, None) => None,
        };
        let project = match newest {
            Some(path) => {
                let bytes = faceanim_files::read_bytes(path)?;
                if path == &autosave_path {
                    tracing::warn!("recovered unsaved work from {}", path.display());
                }
                Some(parse_project(&bytes, &path.display().to_string())?)
            }
            None => None,
        };
        // A sketched GLB faceanim wrote opens as its strokes, ready to edit, where no project
        // of the user's is kept.
        let from_file = if project.is_none() {
            file_sketch(&character)
        } else {
            None
        };
        let sketch_from_file = from_file.as_ref().and_then(|_| {
            let source = character.source()?;
            Some(source.opened_animation()?.name.clone())
        });
        let project = project.or(from_file).unwrap_or_else(empty_project);
        Ok(Studio {
            character: Arc::new(character),
            project,
            undo: Vec::new(),
            redo: Vec::new(),
            gesture: None,
            project_path,
            autosave_path,
            sketch_from_file,
        })
    }

    /// Whether the sketch came from the character's own file (a sketched GLB's strokes): its
    /// animation is then not also opened as a take.
    #[must_use]
    pub fn sketch_from_file(&self) -> bool {
        self.sketch_from_file.is_some()
    }

    /// The name of the file's animation the sketch came from (exports write it back under it).
    #[must_use]
    pub fn file_sketch_name(&self) -> Option<&str> {
        self.sketch_from_file.as_deref()
    }

    /// The project as it would be saved.
    #[must_use]
    pub fn project(&self) -> &ProjectFile {
        &self.project
    }

    /// Replaces the project after checking it, remembering the old one for undo.
    ///
    /// # Errors
    /// [`ApiError::Project`] with every problem (the change is not made).
    pub fn change(&mut self, next: ProjectFile) -> Result<(), ApiError> {
        self.change_in_gesture(next, None)
    }

    /// Like [`Studio::change`], but the changes of one gesture (every step of dragging a
    /// handle, named by the page) undo as one.
    ///
    /// # Errors
    /// [`ApiError::Project`] with every problem (the change is not made).
    pub fn change_in_gesture(
        &mut self,
        next: ProjectFile,
        gesture: Option<String>,
    ) -> Result<(), ApiError> {
        Project::from_file(next.clone()).map_err(|source| ApiError::Project {
            what: "project".into(),
            source,
        })?;
        let same_gesture = gesture.is_some() && gesture == self.gesture;
        self.gesture = gesture;
        let previous = std::mem::replace(&mut self.project, next);
        if same_gesture {
            // The undo stack already holds the state from before the gesture began.
            self.autosave();
            return Ok(());
        }
        self.undo.push(previous);
        if self.undo.len() > UNDO_DEPTH {
            self.undo.remove(0);
        }
        self.redo.clear();
        self.autosave();
        Ok(())
    }

    /// Applies `apply` to a copy of the project and makes the copy current (see
    /// [`Studio::change_in_gesture`]); nothing changes when `apply` or the validation fails.
    ///
    /// # Errors
    /// `apply`'s error or [`ApiError::Project`].
    pub fn edit(
        &mut self,
        gesture: Option<String>,
        apply: impl FnOnce(&mut ProjectFile) -> Result<(), ApiError>,
    ) -> Result<(), ApiError> {
        let mut next = self.project.clone();
        apply(&mut next)?;
        self.change_in_gesture(next, gesture)
    }

    /// Steps back one edit; false when there is none.
    pub fn undo(&mut self) -> bool {
        self.gesture = None;
        let Some(previous) = self.undo.pop() else {
            return false;
        };
        self.redo
            .push(std::mem::replace(&mut self.project, previous));
        self.autosave();
        true
    }

    /// Steps forward one undone edit; false when there is none.
    pub fn redo(&mut self) -> bool {
        self.gesture = None;
        let Some(next) = self.redo.pop() else {
            return false;
        };
        self.undo.push(std::mem::replace(&mut self.project, next));
        self.autosave();
        true
    }

    /// A new, empty project (undoable).
    pub fn new_project(&mut self) {
        // Keeping the settings and rate of a valid project cannot fail validation.
        let _ = self.edit(None, |next| {
            next.strokes.clear();
            Ok(())
        });
    }

    /// Switches to another character; the project starts empty, with nothing to undo.
    pub fn replace_character(&mut self, character: Character) {
        self.character = Arc::new(character);
        self.project = ProjectFile {
            fps: self.project.fps,
            settings: self.project.settings.clone(),
            ..empty_project()
        };
        self.undo.clear();
        self.redo.clear();
        self.sketch_from_file = None;
        self.autosave();
    }

    /// Writes the project where it was opened from (atomically), and drops the autosave.
    ///
    /// # Errors
    /// [`ApiError::Disk`] naming the path.
    pub fn save(&self) -> Result<(), ApiError> {
        faceanim_files::write_atomic(&self.project_path, &self.project_json())?;
        let _ = std::fs::remove_file(&self.autosave_path);
        Ok(())
    }

    /// Reads the saved project back from disk (undoable).
    ///
    /// # Errors
    /// [`ApiError::Disk`] or [`ApiError::Project`] naming the file.
    pub fn reopen(&mut self) -> Result<(), ApiError> {
        let bytes = faceanim_files::read_bytes(&self.project_path)?;
        let file = parse_project(&bytes, &self.project_path.display().to_string())?;
        self.change(file)
    }

    /// Parses a project sent by the page (from a file the user picked).
    ///
    /// # Errors
    /// [`ApiError::Project`] naming `what`.
    pub fn parse(bytes: &[u8], what: &str) -> Result<ProjectFile, ApiError> {
        parse_project(bytes, what)
    }

    fn project_json(&self) -> Vec<u8> {
        serde_json::to_vec_pretty(&self.project).unwrap_or_default()
    }

    fn autosave(&self) {
        if let Err(e) = faceanim_files::write_atomic(&self.autosave_path, &self.project_json()) {
            tracing::warn!("autosave failed: {e}");
        }
    }

    /// The sketch the project describes, with the warnings of skipped strokes.
    #[must_use]
    pub fn sketch(&self) -> (Sketch<'_>, Vec<String>) {
        match Project::from_file(self.project.clone()) {
            Ok(project) => Sketch::from_project(&self.character, &project),
            // `change` only admits valid projects; an invalid one shows as empty.
            Err(e) => (
                Sketch::new(&self.character, Default::default(), 30.0),
                vec![e.to_string()],
            ),
        }
    }

    /// Adds a stroke.
    ///
    /// # Errors
    /// [`ApiError::Project`] naming what is wrong with the stroke.
    pub fn add_stroke(&mut self, stroke: StrokeFile) -> Result<usize, ApiError> {
        let index = self.project.strokes.len();
        self.edit(None, |next| {
            next.strokes.push(stroke);
            Ok(())
        })?;
        Ok(index)
    }

    /// Everything the page draws: actions with their handles and paths, timeline, settings.
    #[must_use]
    pub fn view(&self) -> StateView {
        let (sketch, warnings) = self.sketch();
        let mut actions = Vec::new();
        let mut rejected = Vec::new();
        for (stroke, result) in sketch.results().iter().enumerate() {
            match result {
                Ok(action) => actions.push(ActionView::of(&self.character, stroke, action)),
                Err(reason) => rejected.push(RejectedView {
                    stroke,
                    reason: reason.to_string(),
                }),
            }
        }
        StateView {
            character: self.character.name().to_owned(),
            fps: sketch.fps(),
            last_frame: sketch.last_frame(),
            settings: self.project.settings.clone(),
            resolved: sketch.resolved().clone(),
            actions,
            rejected,
            warnings,
            can_undo: !self.undo.is_empty(),
            can_redo: !self.redo.is_empty(),
            project_path: self.project_path.display().to_string(),
            added: None,
        }
    }

    /// Candidate targets for a stroke starting at `point` on the pose at `frame`; `None` when
    /// the point is too far from the face.
    #[must_use]
    pub fn candidates(&self, point: Vec3, frame: f32) -> Option<CandidatesView> {
        let (sketch, _) = self.sketch();
        let found = sketch.candidates(point, frame)?;
        Some(CandidatesView::of(&self.character, &found))
    }

    /// Where each blendshape moves the most: the vertex (rest position) and where weight 1
    /// takes it. Scripts and tests use it to aim strokes; the page to label targets.
    #[must_use]
    pub fn blendshape_anchors(&self) -> Vec<AnchorView> {
        let positions = self.character.positions();
        self.character
            .blendshapes()
            .iter()
            .map(|shape| {
                let name = shape.name().to_owned();
                match shape.peak() {
                    Some((vertex, delta)) => {
                        let rest = positions[vertex as usize];
                        AnchorView {
                            name,
                            vertex: Some(vertex),
                            rest: Some(rest.to_array()),
                            target: Some((rest + delta).to_array()),
                        }
                    }
                    None => AnchorView {
                        name,
                        vertex: None,
                        rest: None,
                        target: None,
                    },
                }
            })
            .collect()
    }
}

fn autosave_path(project: &std::path::Path) -> PathBuf {
    let name = project
        .file_name()
        .map_or_else(|| "project".into(), |n| n.to_string_lossy().into_owned());
    project.with_file_name(format!(".{name}.autosave"))
}

/// Where capture mode keeps the take being edited: `.NAME.take.json` beside the project.
/// Where the studio keeps the user's viseme table for `project` (beside it, visible: the same
/// file works with `faceanim lipsync --viseme-table`).
pub(crate) fn visemes_path(project: &std::path::Path) -> PathBuf {
    let name = project
        .file_name()
        .map_or_else(|| "project".into(), |n| n.to_string_lossy().into_owned());
    let stem = name.strip_suffix(".json").unwrap_or(&name);
    project.with_file_name(format!("{stem}.visemes.json"))
}

pub(crate) fn take_autosave_path(project: &std::path::Path) -> PathBuf {
    let name = project
        .file_name()
        .map_or_else(|| "project".into(), |n| n.to_string_lossy().into_owned());
    project.with_file_name(format!(".{name}.take.json"))
}
