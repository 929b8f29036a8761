//! A take: a session being edited, with its undo history, and how captured frames become one.

use faceanim_capture::FrameRecord;
use faceanim_rig::Character;

use crate::estimator::{Estimator, EstimatorSource};
use crate::expression::Expression;
use crate::session::{Edits, Filtering, Session, SessionFrame, estimate_frames};
use crate::steady::Steady;
use crate::{Fingerprint, TakeError};

/// How many edits of a take undo remembers.
const UNDO_DEPTH: usize = 500;

/// What was captured from one input, before any character.
#[derive(Debug, Clone)]
pub struct Footage {
    /// The input's name as the user knows it.
    pub source: String,
    /// Frames per second.
    pub fps: f32,
    /// One record per frame.
    pub records: Vec<FrameRecord>,
    /// One per record: the image file, or `{stem}_{n}.png` for video frames (the first column
    /// of the seed's CSV).
    pub frame_names: Vec<String>,
    /// For a single photo: the length in frames of the 0 → peak → 0 animation it becomes.
    pub still_frames: Option<usize>,
}

impl Footage {
    /// Footage of frames recorded as they arrived (a webcam tracked live, `records` with their
    /// times in seconds), on a steady rate ([`Steady`]): each frame is the record nearest its
    /// time, renumbered and retimed, and named by `name` from its number. Also, per frame,
    /// which record it is (for what was kept beside the records, such as previews).
    #[must_use]
    pub fn from_arrivals(
        source: String,
        records: &[FrameRecord],
        name: impl Fn(usize) -> String,
    ) -> (Footage, Vec<usize>) {
        let times: Vec<f64> = records.iter().map(|r| f64::from(r.time)).collect();
        let steady = Steady::of(&times);
        let chosen = steady.nearest();
        let step = 1.0 / f64::from(steady.fps);
        let records: Vec<FrameRecord> = chosen
            .iter()
            .enumerate()
            .map(|(k, &r)| FrameRecord {
                index: k,
                time: (k as f64 * step) as f32,
                ..records[r].clone()
            })
            .collect();
        let footage = Footage {
            source,
            fps: steady.fps,
            frame_names: (0..records.len()).map(name).collect(),
            records,
            still_frames: None,
        };
        (footage, chosen)
    }
}

/// One frame that arrived as the character's own weights (a VMC stream, a phone tracker), as
/// the live link records it: when, the weights in the character's order, the head pose, and
/// the ARKit values a sender sent them from — kept as what the take was made of
/// ([`SessionFrame::arkit`]), so that the eyes' and jaw's bones and Live Link Face follow the
/// sender where the character has no shape for a channel (or no shapes at all).
pub use faceanim_live::ReceivedFrame;

/// A captured input being edited: its session, where the estimates came from, and the undo and
/// redo stacks of the user's [`Edits`].
#[derive(Debug, Clone)]
pub struct Take {
    /// Estimates, keyframes, corrections and preference.
    pub session: Session,
    estimated_by: EstimatorSource,
    undo: Vec<Edits>,
    redo: Vec<Edits>,
}

impl Take {
    /// A take of `session`, whose estimates came from `estimated_by`, with no history.
    #[must_use]
    pub fn new(session: Session, estimated_by: EstimatorSource) -> Take {
        Take {
            session,
            estimated_by,
            undo: Vec::new(),
            redo: Vec::new(),
        }
    }

    /// A take opened from a session file (which does not say what estimated it).
    #[must_use]
    pub fn from_session(session: Session) -> Take {
        Take::new(session, EstimatorSource::SessionFile)
    }

    /// Whether a capture estimated by `estimator` moves anything of `character`: some of its
    /// shapes, or — on a body with no blendshapes at all (a Mixamo or Ready Player Me body
    /// exported without its morph targets) — its head, eye or jaw bones, which the take's head
    /// pose, gaze and jawOpen turn. Checked by [`Take::from_capture`]; callers check it before
    /// minutes of video.
    ///
    /// # Errors
    /// [`TakeError::NoArkitNames`] when the estimator moves none of the character's shapes (a
    /// by-name mapping onto a rig without ARKit names); [`TakeError::NothingToMove`] when the
    /// character has neither shapes nor face bones.
    pub fn check_moves(character: &Character, estimator: &dyn Estimator) -> Result<(), TakeError> {
        if estimator.driven() > 0 {
            return Ok(());
        }
        let character_name = || character.name().to_owned();
        if !character.blendshapes().is_empty() {
            return Err(TakeError::NoArkitNames {
                character: character_name(),
            });
        }
        let bones = character
            .source()
            .map(faceanim_rig::source::GltfSource::bones);
        if bones.is_some_and(|b| b.found().next().is_some()) {
            Ok(())
        } else {
            Err(TakeError::NothingToMove {
                character: character_name(),
            })
        }
    }

    /// Estimates every frame of `footage` for `character` with `estimator` (frames without a
    /// face are bridged from their neighbours) and starts a take with `filtering`.
    ///
    /// # Errors
    /// As [`Take::check_moves`], or [`TakeError::Mismatch`] when the estimator is for another
    /// character's blendshapes.
    pub fn from_capture(
        character: &Character,
        estimator: &dyn Estimator,
        footage: Footage,
        filtering: Filtering,
    ) -> Result<Take, TakeError> {
        Take::check_moves(character, estimator)?;
        let names: Vec<String> = character.blendshape_names();
        if estimator.blendshapes() != names.as_slice() {
            return Err(TakeError::Mismatch {
                character: character.name().to_owned(),
                reason: format!(
                    "the {}'s blendshapes are not the character's",
                    estimator.source().noun()
                ),
            });
        }
        let Footage {
            source,
            fps,
            records,
            frame_names,
            still_frames,
        } = footage;
        let expressions: Vec<Option<Expression>> =
            records.iter().map(Expression::from_record).collect();
        let faces: Vec<Option<&Expression>> = expressions.iter().map(Option::as_ref).collect();
        // A new take is read relative to its parts' calmest frames until the user picks one.
        let neutral = crate::expression::calmest_parts(&faces)
            .and_then(|parts| crate::expression::rest_face(&faces, parts));
        let estimates = estimate_frames(&faces, estimator, neutral.as_ref());
        let frames = records
            .iter()
            .zip(expressions)
            .zip(estimates)
            .zip(frame_names)
            .map(|(((record, expression), estimate), name)| {
                SessionFrame::from_record(record, name, expression, estimate)
            })
            .collect();
        let mut session = session_of(character, source, names, fps, frames, filtering);
        session.edits.still_frames = still_frames;
        Ok(Take::new(session, estimator.source()))
    }

    /// A take of frames that arrived as `character`'s weights (named `source`), on a steady
    /// rate by their times, each frame the blend of the two arrivals around its time, weights
    /// and head pose alike ([`Steady`]), named `{source}_{n}`.
    ///
    /// # Errors
    /// [`TakeError::Mismatch`] when a frame has another number of weights than the character
    /// has blendshapes.
    pub fn from_received(
        character: &Character,
        source: &str,
        frames: Vec<ReceivedFrame>,
        filtering: Filtering,
    ) -> Result<Take, TakeError> {
        let names: Vec<String> = character.blendshape_names();
        mismatch(character, &names, &frames)?;
        let wanted = faceanim_rig::names::ARKIT_52.len();
        if let Some((k, row)) = frames.iter().enumerate().find_map(|(k, f)| {
            f.arkit
                .as_ref()
                .map(|a| (k, a))
                .filter(|(_, a)| a.len() != wanted)
        }) {
            return Err(TakeError::Invalid(vec![format!(
                "frames[{k}].arkit: {} values, not {wanted}",
                row.len()
            )]));
        }
        let times: Vec<f64> = frames.iter().map(|f| f.time).collect();
        let steady = Steady::of(&times);
        let weights: Vec<&[f32]> = frames.iter().map(|f| f.weights.as_slice()).collect();
        let step = 1.0 / f64::from(steady.fps);
        let frames = steady
            .blend(&weights)
            .into_iter()
            .zip(&steady.slots)
            .enumerate()
            .map(|(k, (weights, slot))| {
                let head = match (frames[slot.before].head, frames[slot.after].head) {
                    (Some(a), Some(b)) => {
                        let t = slot.toward_after;
                        Some(std::array::from_fn(|i| a[i] + (b[i] - a[i]) * t))
                    }
                    _ => frames[slot.nearest()].head,
                };
                let arkit = match (&frames[slot.before].arkit, &frames[slot.after].arkit) {
                    (Some(a), Some(b)) => Some(
                        a.iter()
                            .zip(b)
                            .map(|(a, b)| a + (b - a) * slot.toward_after)
                            .collect(),
                    ),
                    _ => frames[slot.nearest()].arkit.clone(),
                }
                .map(|row: Vec<f32>| row.into_iter().map(|w| w.clamp(0.0, 1.0)).collect());
                ReceivedFrame {
                    time: k as f64 * step,
                    weights,
                    head,
                    arkit,
                }
            })
            .collect();
        Ok(Take::of_frames(
            character, source, steady.fps, names, frames, filtering,
        ))
    }

    /// A take of `rows` of `character`'s weights made at a steady `fps` (a lip sync, a clip
    /// opened), row `k` at `k / fps` seconds with the head's yaw, pitch and roll `heads[k]`
    /// where given, named `source`, unfiltered. The rate is kept as given — 29.97 stays 29.97
    /// and 240 stays 240, where [`Take::from_received`] puts frames that arrived on a rate
    /// it estimates and rounds — so that the take lasts as long as what it was made from.
    ///
    /// # Errors
    /// [`TakeError::Mismatch`] when a row has another number of weights than the character
    /// has blendshapes; [`TakeError::Invalid`] when `fps` is not above 0 and at most
    /// [`crate::session::MAX_FPS`].
    pub fn from_weights(
        character: &Character,
        source: &str,
        fps: f32,
        rows: &[Vec<f32>],
        heads: Option<&[[f32; 3]]>,
    ) -> Result<Take, TakeError> {
        if let Some(problem) = crate::session::fps_problem(fps) {
            return Err(TakeError::Invalid(vec![problem]));
        }
        let names: Vec<String> = character.blendshape_names();
        let step = 1.0 / f64::from(fps);
        let frames: Vec<ReceivedFrame> = rows
            .iter()
            .enumerate()
            .map(|(k, weights)| ReceivedFrame {
                time: k as f64 * step,
                weights: weights.clone(),
                head: heads.and_then(|h| h.get(k).copied()),
                arkit: None,
            })
            .collect();
        mismatch(character, &names, &frames)?;
        Ok(Take::of_frames(
            character,
            source,
            fps,
            names,
            frames,
            Filtering::new(1, None)?,
        ))
    }

    /// The take of `frames` at `fps`, each named `{source}_{n}`.
    fn of_frames(
        character: &Character,
        source: &str,
        fps: f32,
        names: Vec<String>,
        frames: Vec<ReceivedFrame>,
        filtering: Filtering,
    ) -> Take {
        let first = frames.first().map_or(0.0, |f| f.time);
        let frames = frames
            .into_iter()
            .enumerate()
            .map(|(k, f)| SessionFrame {
                name: format!("{source}_{:06}", k + 1),
                time: (f.time - first) as f32,
                presence: 1.0,
                head: f.head,
                head_position: None,
                expression: None,
                estimate: f.weights,
                arkit: f.arkit,
            })
            .collect();
        let session = session_of(character, source.to_owned(), names, fps, frames, filtering);
        Take::new(session, EstimatorSource::Received)
    }

    /// The take with what each frame was made of as ARKit's 52 channels
    /// ([`SessionFrame::arkit`]: a lip sync's visemes by its viseme table), one row per frame.
    ///
    /// # Errors
    /// [`TakeError::Invalid`] when there is another number of rows than frames, or a row is
    /// not 52 values in 0..1.
    pub fn made_of_arkit(mut self, rows: Vec<Vec<f32>>) -> Result<Take, TakeError> {
        let frames = &mut self.session.frames;
        if rows.len() != frames.len() {
            return Err(TakeError::Invalid(vec![format!(
                "{} rows of ARKit values for {} frames",
                rows.len(),
                frames.len()
            )]));
        }
        if let Some(problem) = rows
            .iter()
            .enumerate()
            .find_map(|(k, row)| crate::session::arkit_problem(&format!("frames[{k}]"), row))
        {
            return Err(TakeError::Invalid(vec![problem]));
        }
        for (frame, row) in frames.iter_mut().zip(rows) {
            frame.arkit = Some(row);
        }
        Ok(self)
    }

    /// Where the estimates came from.
    #[must_use]
    pub fn estimated_by(&self) -> EstimatorSource {
        self.estimated_by
    }

    /// Whether there is an edit to undo.
    #[must_use]
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is an undone edit to redo.
    #[must_use]
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Applies `change` to the session; a change that changed something can be undone.
    ///
    /// # Errors
    /// `change`'s error (the session is then as it was).
    pub fn edit(
        &mut self,
        change: impl FnOnce(&mut Session) -> Result<(), TakeError>,
    ) -> Result<(), TakeError> {
        let before = self.session.edits.clone();
        if let Err(e) = change(&mut self.session) {
            self.session.edits = before;
            return Err(e);
        }
        if self.session.edits != before {
            self.undo.push(before);
            if self.undo.len() > UNDO_DEPTH {
                self.undo.remove(0);
            }
            self.redo.clear();
        }
        Ok(())
    }

    /// Steps back one edit; false when there is none.
    pub fn undo(&mut self) -> bool {
        step(&mut self.undo, &mut self.redo, &mut self.session.edits)
    }

    /// Steps forward one undone edit; false when there is none.
    pub fn redo(&mut self) -> bool {
        step(&mut self.redo, &mut self.undo, &mut self.session.edits)
    }

    /// Estimates every frame again with `estimator` (a new or fine-tuned adapter); the edits
    /// and their history stay.
    ///
    /// # Errors
    /// [`TakeError::Mismatch`] when the estimator is for other blendshapes.
    pub fn reestimate(&mut self, estimator: &dyn Estimator) -> Result<(), TakeError> {
        self.session.reestimate(estimator)?;
        self.estimated_by = estimator.source();
        Ok(())
    }
}

/// A new session of `character` (its blendshapes `names`) over `frames`, filtered by
/// `filtering`.
/// A frame with another number of weights than `names`, as the error.
fn mismatch(
    character: &Character,
    names: &[String],
    frames: &[ReceivedFrame],
) -> Result<(), TakeError> {
    match frames.iter().find(|f| f.weights.len() != names.len()) {
        Some(bad) => Err(TakeError::Mismatch {
            character: character.name().to_owned(),
            reason: format!(
                "a frame has {} weights for {} blendshapes",
                bad.weights.len(),
                names.len()
            ),
        }),
        None => Ok(()),
    }
}

fn session_of(
    character: &Character,
    source: String,
    names: Vec<String>,
    fps: f32,
    frames: Vec<SessionFrame>,
    filtering: Filtering,
) -> Session {
    let mut session = Session::new(
        source,
        character.name().to_owned(),
        names,
        Fingerprint::of(character),
        fps,
        filtering.keyframe_every,
        frames,
    );
    session.set_filtering(filtering);
    session
}

/// Moves the current edits onto `to` and makes the top of `from` current; false when `from` is
/// empty.
fn step(from: &mut Vec<Edits>, to: &mut Vec<Edits>, current: &mut Edits) -> bool {
    let Some(edits) = from.pop() else {
        return false;
    };
    to.push(std::mem::replace(current, edits));
    true
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "sums of exact binary fractions")]
mod tests {
    use super::*;

    fn two_frame_take() -> Take {
        Take::new(
            crate::session::test_session(2, |_| vec![0.25, 0.5]),
            EstimatorSource::ByName,
        )
    }

    /// The built-in head, its blendshape count, and where jawOpen is among ARKit's 52.
    fn head_and_jaw() -> (Character, usize, usize) {
        let character = faceanim_head::default_character();
        let n = character.blendshape_names().len();
        let jaw = faceanim_rig::names::ARKIT_52
            .iter()
            .position(|c| *c == "jawOpen")
            .unwrap();
        (character, n, jaw)
    }

    #[test]
    fn a_phones_arkit_values_go_into_the_take_as_what_it_was_made_of() {
        let (character, n, jaw) = head_and_jaw();
        let phone = |k: usize| {
            let mut arkit = vec![0.0; faceanim_rig::names::ARKIT_52.len()];
            arkit[jaw] = k as f32 / 100.0;
            ReceivedFrame {
                time: k as f64 / 30.0,
                weights: vec![0.0; n],
                head: None,
                arkit: Some(arkit),
            }
        };
        let take = Take::from_received(
            &character,
            "phone",
            (0..=100).map(phone).collect(),
            Filtering::new(1, None).unwrap(),
        )
        .unwrap();
        let made_of = take.session.arkit_clip().unwrap();
        let column = made_of.column("jawOpen").unwrap();
        assert!(
            (made_of.frames[50][column] - 0.5).abs() < 1e-3,
            "{made_of:?}"
        );
        // What it was made of survives the session file.
        let back = Session::from_json(take.session.to_json().as_bytes()).unwrap();
        assert_eq!(back.frames[50].arkit, take.session.frames[50].arkit);
        // A row that is not ARKit's 52 is refused by its frame.
        let mut bad: Vec<ReceivedFrame> = (0..3).map(phone).collect();
        bad[1].arkit = Some(vec![0.5; 3]);
        let refused =
            Take::from_received(&character, "phone", bad, Filtering::new(1, None).unwrap())
                .unwrap_err();
        assert!(refused.to_string().contains("frames[1].arkit"), "{refused}");
    }

    #[test]
    fn a_capture_needs_a_shape_it_drives_or_a_body_with_face_bones() {
        // A mesh with no shapes, made in code: no file, so no bones either.
        let bare = Character::new(faceanim_rig::CharacterParts {
            name: "bare".into(),
            positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
            triangles: vec![[0, 1, 2]],
            ..faceanim_rig::CharacterParts::default()
        })
        .unwrap();
        let refused = Take::check_moves(&bare, &crate::ByName::new(&bare)).unwrap_err();
        assert!(matches!(refused, TakeError::NothingToMove { .. }));
        assert!(refused.to_string().contains("generate-shapes"), "{refused}");
        // The built-in head is driven by its ARKit names.
        let head = faceanim_head::default_character();
        assert!(Take::check_moves(&head, &crate::ByName::new(&head)).is_ok());
    }

    #[test]
    fn a_takes_edits_undo_and_redo_and_a_failed_edit_changes_nothing() {
        let mut take = two_frame_take();
        take.edit(|s| s.correct(1, "a", 0.75)).unwrap_or_default();
        take.edit(|s| {
            s.apply_preference();
            Ok(())
        })
        .unwrap_or_default();
        assert_eq!(take.session.weights()[0], vec![0.75, 0.5]);
        // A refused edit leaves no trace, not even on the undo stack.
        let refused = take.edit(|s| {
            s.edits.keyframe_every = 7;
            s.correct(9, "a", 0.5)
        });
        assert!(refused.is_err());
        assert_eq!(take.session.edits.keyframe_every, 1);
        assert!(take.undo());
        assert_eq!(take.session.weights()[0], vec![0.25, 0.5]);
        assert!(take.undo());
        assert!(take.session.edits.corrections.is_empty());
        assert!(!take.undo());
        assert!(take.redo() && take.redo());
        assert_eq!(take.session.weights()[0], vec![0.75, 0.5]);
        assert!(!take.redo());
    }

    #[test]
    fn webcam_frames_tracked_as_fast_as_the_machine_allowed_keep_their_time() {
        // Tracked at 20 fps for a second, then at 10 (the machine busy), then 20 again: the
        // slow second's frames are each shown twice, at their own time.
        let mut times: Vec<f32> = (0..20).map(|k| k as f32 / 20.0).collect();
        times.extend((0..10).map(|k| 1.0 + k as f32 / 10.0));
        times.extend((0..20).map(|k| 2.0 + k as f32 / 20.0));
        let records: Vec<FrameRecord> = times
            .iter()
            .enumerate()
            .map(|(index, &time)| FrameRecord::missing(index, time))
            .collect();
        let (footage, chosen) =
            Footage::from_arrivals("webcam".into(), &records, |k| format!("w{k}.png"));
        assert_eq!(footage.fps, 20.0);
        assert_eq!(footage.records.len(), 60);
        assert_eq!(chosen.len(), 60);
        for (k, record) in footage.records.iter().enumerate() {
            assert_eq!(record.index, k);
            assert!((record.time - k as f32 / 20.0).abs() < 1e-5);
            // The frame recorded nearest its time, never more than half a slow frame away.
            let recorded = times[chosen[k]];
            assert!(
                (recorded - record.time).abs() <= 0.05 + 1e-5,
                "{k}: {recorded}"
            );
        }
        assert_eq!([chosen[20], chosen[22], chosen[24]], [20, 21, 22]);
        assert_eq!(footage.frame_names[59], "w59.png");
    }

    #[test]
    fn a_take_keeps_what_it_was_made_of_through_its_file() {
        let (character, n, jaw) = head_and_jaw();
        let mut made_of = vec![vec![0.0; 52]; 4];
        made_of[2][jaw] = 0.6;
        let take = Take::from_weights(&character, "line", 30.0, &vec![vec![0.0; n]; 4], None)
            .unwrap()
            .made_of_arkit(made_of.clone())
            .unwrap();
        // Only the channels that move; saved and read again, the same.
        for session in [
            take.session.clone(),
            Session::from_json(take.session.to_json().as_bytes()).unwrap(),
        ] {
            let clip = session.arkit_clip().unwrap();
            assert_eq!(clip.blendshapes, ["jawOpen"]);
            let column: Vec<f32> = clip.frames.iter().map(|r| r[0]).collect();
            assert_eq!(column, [0.0, 0.0, 0.6, 0.0]);
        }
        // Rows that do not fit the frames, or values that are no weights, are refused.
        let fresh = || Take::from_weights(&character, "line", 30.0, &vec![vec![0.0; n]; 4], None);
        let e = fresh()
            .unwrap()
            .made_of_arkit(made_of[..3].to_vec())
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("3 rows of ARKit values for 4 frames"),
            "{e}"
        );
        made_of[1][0] = 1.5;
        let e = fresh().unwrap().made_of_arkit(made_of).unwrap_err();
        assert!(e.to_string().contains("frames[1].arkit"), "{e}");
        // A session file's values are checked as its estimates are.
        let mut file: serde_json::Value = serde_json::from_str(&take.session.to_json()).unwrap();
        file["frames"][0]["arkit"] = serde_json::json!([0.5]);
        let e = Session::from_json(file.to_string().as_bytes()).unwrap_err();
        assert!(
            e.to_string().contains("frames[0].arkit: 1 values, not 52"),
            "{e}"
        );
    }

    #[test]
    fn a_take_at_a_steady_rate_keeps_the_rate_and_a_recording_rounds_its_own() {
        let character = faceanim_head::default_character();
        let n = character.blendshape_names().len();
        let rows = vec![vec![0.0; n]; 300];
        // NTSC's rate and a high one: as made, so that 300 frames last as long as they did.
        for fps in [30_000.0 / 1001.0, 240.0] {
            let take = Take::from_weights(&character, "line", fps, &rows, None).unwrap();
            assert_eq!(take.session.fps, fps);
            assert_eq!(take.session.clip().fps, fps);
            let last = take.session.frames.last().unwrap().time;
            assert!(
                (f64::from(last) - 299.0 / f64::from(fps)).abs() < 1e-4,
                "{last}"
            );
        }
        let heads = [[1.0, 2.0, 3.0]];
        let take = Take::from_weights(&character, "line", 30.0, &rows[..2], Some(&heads)).unwrap();
        assert_eq!(take.session.frames[0].head, Some([1.0, 2.0, 3.0]));
        assert_eq!(take.session.frames[1].head, None);
        for fps in [0.0, -1.0, f32::NAN, 5000.0] {
            let error = Take::from_weights(&character, "line", fps, &rows, None).unwrap_err();
            assert!(error.to_string().contains("fps"), "{error}");
        }
        // Frames that arrived about 1/60 s apart, a tenth of a second of them lost: their
        // rate, rounded, and each where it arrived.
        let arrived: Vec<ReceivedFrame> = (0..300)
            .filter(|k| !(100..106).contains(k))
            .map(|k| ReceivedFrame {
                time: 10.0 + f64::from(k) / 59.7,
                weights: vec![k as f32 / 300.0; n],
                head: (k % 2 == 0).then_some([k as f32, 0.0, 0.0]),
                arkit: None,
            })
            .collect();
        let take =
            Take::from_received(&character, "vmc", arrived, Filtering::new(1, None).unwrap())
                .unwrap();
        assert_eq!(take.session.fps, 60.0);
        assert_eq!(take.session.frames.len(), 302);
        let frames = &take.session.frames;
        assert_eq!(frames[0].time, 0.0);
        assert!((frames[301].time - 301.0 / 60.0).abs() < 1e-5);
        // 200 frames at 59.7 fps arrived at 3.35 s: the steady take's frame 200 is at 3.33 s.
        let frame = &frames[200];
        assert!((frame.estimate[0] * 300.0 - 200.0 * 59.7 / 60.0).abs() < 1.0);
        // The head, where one of the two arrivals around a frame had none, is the nearer's.
        assert_eq!(frames[0].head, Some([0.0, 0.0, 0.0]));
        assert_eq!(frames[1].head, None);
        assert_eq!(frames[2].head, Some([2.0, 0.0, 0.0]));
    }
}
