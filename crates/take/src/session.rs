//! The human in the loop: one input's frames with the adapter's estimates, the keyframes, the
//! user's corrections and preference, kept in a JSON file between commands (and between the
//! studio's requests).
//!
//! The animation is derived, never stored: estimates → optional One Euro smoothing →
//! preference (per blendshape, the mean of the user's corrections added to every other frame,
//! clamped to [0, 1]) → corrections → keyframes (every N frames, plus the user's, plus every
//! corrected frame, minus keys the user removed) with linear interpolation between them. So
//! clearing the preference or a correction restores exactly what was there before.

use std::collections::BTreeMap;

use faceanim_anim::Clip;
use faceanim_anim::filter::OneEuro;
use serde::{Deserialize, Serialize};

use crate::estimator::Estimator;
use crate::expression::{Expression, PartFrames};
use crate::{Fingerprint, TakeError};

/// One frame of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionFrame {
    /// A name for the frame: the image's file name, or the video's name and frame number
    /// (the first column of the seed's CSV).
    pub name: String,
    /// Seconds from the first frame.
    pub time: f32,
    /// Face presence (0 where none was found).
    pub presence: f32,
    /// Head yaw, pitch, roll in degrees, where a face was found.
    pub head: Option<[f32; 3]>,
    /// Head position in metres, where a face was found.
    pub head_position: Option<[f32; 3]>,
    /// What capture read (kept for re-estimating and fine-tuning); `None` without a face.
    pub expression: Option<Expression>,
    /// The estimate, one weight per blendshape (bridged from neighbours without a face).
    pub estimate: Vec<f32>,
    /// ARKit's 52 channels ([`faceanim_rig::names::ARKIT_52`] order) as the frame was made of
    /// them where no camera read the face: a lip sync's visemes by its viseme table. What Live
    /// Link Face and a jaw bone get where the character's own shapes do not carry a channel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arkit: Option<Vec<f32>>,
}

impl SessionFrame {
    /// The session's frame for what capture recorded of it, named `name`, with its
    /// `expression` (from [`Expression::from_record`]) and `estimate`.
    #[must_use]
    pub fn from_record(
        record: &faceanim_capture::FrameRecord,
        name: String,
        expression: Option<Expression>,
        estimate: Vec<f32>,
    ) -> SessionFrame {
        SessionFrame {
            name,
            time: record.time,
            presence: record.presence,
            head: record.head,
            head_position: record.head_position,
            expression,
            estimate,
            arkit: None,
        }
    }
}

/// What the user changes in a session (the frames and their estimates stay): keyframes,
/// corrections, preference and smoothing, as one value — small enough for hundreds of steps of
/// undo, and compared to tell an edit that changed something from one that did not.
#[derive(Debug, Clone, PartialEq)]
pub struct Edits {
    /// Automatic keyframes every this many frames (1 keeps every frame).
    pub keyframe_every: usize,
    /// One Euro smoothing of the estimates, when chosen.
    pub smoothing: Option<OneEuro>,
    /// Keyframes the user added.
    pub added_keyframes: Vec<usize>,
    /// Automatic keyframes the user removed.
    pub removed_keyframes: Vec<usize>,
    /// Frame → blendshape name → the weight the user set.
    pub corrections: BTreeMap<usize, BTreeMap<String, f32>>,
    /// Per blendshape offsets, while the preference is applied.
    pub preference: Option<Vec<f32>>,
    /// For a still image: the length in frames of the 0 → peak → 0 animation it becomes.
    pub still_frames: Option<usize>,
}

impl Edits {
    /// No edits yet: a keyframe every `keyframe_every` frames (at least 1), no smoothing.
    #[must_use]
    pub fn new(keyframe_every: usize) -> Edits {
        Edits {
            keyframe_every: keyframe_every.max(1),
            smoothing: None,
            added_keyframes: Vec::new(),
            removed_keyframes: Vec::new(),
            corrections: BTreeMap::new(),
            preference: None,
            still_frames: None,
        }
    }
}

/// How a session's estimates are cleaned up: One Euro smoothing (optional), then a keyframe
/// every `keyframe_every` frames (1 to 1000) with the frames between interpolated. New takes
/// get the filtering chosen last; changing a take's is an edit like any other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filtering {
    /// Automatic keyframes every this many frames.
    pub keyframe_every: usize,
    /// One Euro smoothing of the estimates, when chosen.
    pub smoothing: Option<OneEuro>,
}

impl Filtering {
    /// The seed's default: a keyframe every 5 frames, no smoothing.
    pub const SEED: Filtering = Filtering {
        keyframe_every: 5,
        smoothing: None,
    };

    /// Checked filtering.
    ///
    /// # Errors
    /// [`TakeError::KeyframeSpacing`] or [`TakeError::Smoothing`] naming the bad value.
    pub fn new(keyframe_every: usize, smoothing: Option<OneEuro>) -> Result<Filtering, TakeError> {
        if !(1..=1000).contains(&keyframe_every) {
            return Err(TakeError::KeyframeSpacing(keyframe_every));
        }
        if let Some(s) = smoothing {
            s.validate().map_err(TakeError::Smoothing)?;
        }
        Ok(Filtering {
            keyframe_every,
            smoothing,
        })
    }
}

/// A session: one input's frames with their estimates, and the user's [`Edits`]. See the module
/// docs. Its file is the JSON of `SessionFile` (version 1, with the edits inline).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SessionFile", into = "SessionFile")]
pub struct Session {
    /// File format version (1).
    pub version: u32,
    /// The input it came from.
    pub source: String,
    /// The character's name.
    pub character: String,
    /// The character's blendshapes, one per estimate column.
    pub blendshapes: Vec<String>,
    /// The character's fingerprint.
    pub fingerprint: Fingerprint,
    /// Frames per second.
    pub fps: f32,
    /// The frames.
    pub frames: Vec<SessionFrame>,
    /// The frame the user said is neutral (`None`: each part at its calmest frame, see
    /// [`Session::neutral`]).
    pub neutral: Option<usize>,
    /// What the user changed.
    pub edits: Edits,
}

/// Who chose a take's neutral frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NeutralChoice {
    /// The frame with the least expression energy.
    Automatic,
    /// The user.
    User,
}

/// The neutral face a take's faces are read relative to: the frame the user named, or each
/// part of the face at its own calmest frame ([`crate::expression::calmest_parts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Neutral {
    /// The user's frame; automatically, the calmest frame of the mouth (and the rest of the
    /// face that is neither lids, gaze nor brows).
    pub frame: usize,
    /// Who chose it.
    pub chosen: NeutralChoice,
    /// The frame each part of the face comes from (all `frame` when the user chose it).
    pub parts: PartFrames,
}

/// A neutral face that reads as an expression: what an estimate makes of the neutral frame
/// itself, read against the character's own neutral (an adapter's typical neutral face from its
/// training; MediaPipe's zeros by name). A take read relative to such a frame has that
/// expression taken out of every other frame, so it is worth a warning.
pub const EXPRESSIVE_NEUTRAL: f32 = 0.35;

/// How neutral a take's neutral face looks: its frame, who chose it, and the blendshapes it
/// reads above [`EXPRESSIVE_NEUTRAL`] on its own, strongest first (none: it looks neutral).
///
/// A take with one face (a photo) has no neutral face to read it against: it is read on its
/// own, against the estimator's own neutral, so whatever that face holds at rest (a person
/// whose lids MediaPipe reads as squinting when relaxed) shows on the character. The check then
/// reads that face, with `chosen` `None`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NeutralCheck {
    /// The neutral frame (the one face's frame when there is no neutral).
    pub frame: usize,
    /// Who chose it; `None` when the take's one face is read on its own.
    pub chosen: Option<NeutralChoice>,
    /// The frame each part of the neutral face comes from.
    pub parts: PartFrames,
    /// The shapes the neutral face reads on its own, with their weights, strongest first.
    pub expressive: Vec<(String, f32)>,
}

impl NeutralCheck {
    /// Whether the neutral frame looks neutral.
    #[must_use]
    pub fn is_clear(&self) -> bool {
        self.expressive.is_empty()
    }

    /// What to tell the user when it does not (`None` when it does): no frame of the take looks
    /// neutral (an automatic choice), or the chosen one reads as an expression.
    #[must_use]
    pub fn warning(&self) -> Option<String> {
        if self.is_clear() {
            return None;
        }
        let reads: Vec<String> = self
            .expressive
            .iter()
            .take(4)
            .map(|(name, w)| format!("{name} {w:.2}"))
            .collect();
        Some(match self.chosen {
            Some(NeutralChoice::Automatic) => format!(
                "no frame of this take looks clearly neutral: its calmest face ({}) reads {}; \
                 mark a relaxed frame as the neutral one, or record a second of a relaxed face",
                self.parts,
                reads.join(", ")
            ),
            Some(NeutralChoice::User) => format!(
                "the neutral frame {} reads {}: every frame is read relative to that expression",
                self.frame,
                reads.join(", ")
            ),
            None => format!(
                "this take has one face (frame {}), read on its own for want of a relaxed \
                 face of the person: it reads {}, some of which may be how they look at rest; \
                 capture it with a relaxed picture of them (one folder, pictures of one size) \
                 to read it against that",
                self.frame,
                reads.join(", ")
            ),
        })
    }
}

/// The session file as written (version 1): the session's fields with its edits inline.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SessionFile {
    version: u32,
    source: String,
    character: String,
    blendshapes: Vec<String>,
    fingerprint: Fingerprint,
    fps: f32,
    keyframe_every: usize,
    #[serde(default)]
    smoothing: Option<OneEuro>,
    frames: Vec<SessionFrame>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    neutral: Option<usize>,
    #[serde(default)]
    added_keyframes: Vec<usize>,
    #[serde(default)]
    removed_keyframes: Vec<usize>,
    #[serde(default)]
    corrections: BTreeMap<usize, BTreeMap<String, f32>>,
    #[serde(default)]
    preference: Option<Vec<f32>>,
    #[serde(default)]
    still_frames: Option<usize>,
}

impl From<SessionFile> for Session {
    fn from(f: SessionFile) -> Session {
        Session {
            version: f.version,
            source: f.source,
            character: f.character,
            blendshapes: f.blendshapes,
            fingerprint: f.fingerprint,
            fps: f.fps,
            frames: f.frames,
            neutral: f.neutral,
            edits: Edits {
                keyframe_every: f.keyframe_every,
                smoothing: f.smoothing,
                added_keyframes: f.added_keyframes,
                removed_keyframes: f.removed_keyframes,
                corrections: f.corrections,
                preference: f.preference,
                still_frames: f.still_frames,
            },
        }
    }
}

impl From<Session> for SessionFile {
    fn from(s: Session) -> SessionFile {
        SessionFile {
            version: s.version,
            source: s.source,
            character: s.character,
            blendshapes: s.blendshapes,
            fingerprint: s.fingerprint,
            fps: s.fps,
            keyframe_every: s.edits.keyframe_every,
            smoothing: s.edits.smoothing,
            frames: s.frames,
            neutral: s.neutral,
            added_keyframes: s.edits.added_keyframes,
            removed_keyframes: s.edits.removed_keyframes,
            corrections: s.edits.corrections,
            preference: s.edits.preference,
            still_frames: s.edits.still_frames,
        }
    }
}

/// A frame the user corrected: what capture read, and the weights the user wants (the
/// examples fine-tuning learns from).
#[derive(Debug, Clone, PartialEq)]
pub struct Correction {
    /// The frame's expression.
    pub expression: Expression,
    /// The take's neutral face, when it has one.
    pub neutral: Option<Expression>,
    /// The wanted weights, one per blendshape (the estimate, with the user's changes).
    pub target: Vec<f32>,
}

impl Session {
    /// A session over `frames` for a character with these blendshapes.
    #[must_use]
    pub fn new(
        source: String,
        character: String,
        blendshapes: Vec<String>,
        fingerprint: Fingerprint,
        fps: f32,
        keyframe_every: usize,
        frames: Vec<SessionFrame>,
    ) -> Session {
        Session {
            version: 1,
            source,
            character,
            blendshapes,
            fingerprint,
            fps,
            frames,
            neutral: None,
            edits: Edits::new(keyframe_every),
        }
    }

    /// The same footage read for another character by `estimator` (its blendshapes, its
    /// fingerprint `fingerprint`): frames, expressions, head pose, neutral frame and filtering
    /// are kept; estimates are made anew; corrections and the preference, which name the old
    /// character's shapes, are left behind.
    #[must_use]
    pub fn for_character(
        &self,
        character: String,
        fingerprint: Fingerprint,
        estimator: &dyn Estimator,
    ) -> Session {
        let mut session = Session::new(
            self.source.clone(),
            character,
            estimator.blendshapes().to_vec(),
            fingerprint,
            self.fps,
            self.edits.keyframe_every,
            self.frames.clone(),
        );
        session.neutral = self.neutral;
        session.edits.smoothing = self.edits.smoothing;
        session.edits.still_frames = self.edits.still_frames;
        let neutral = session.neutral_expression();
        let estimates = estimate_frames(&session.expressions(), estimator, neutral.as_ref());
        for (frame, estimate) in session.frames.iter_mut().zip(estimates) {
            frame.estimate = estimate;
        }
        session
    }

    /// The neutral face faces are read relative to: the user's frame, else each part of the
    /// face at its calmest frame with a face; `None` when fewer than two frames have one.
    #[must_use]
    pub fn neutral(&self) -> Option<Neutral> {
        if let Some(frame) = self.neutral {
            return Some(Neutral {
                frame,
                chosen: NeutralChoice::User,
                parts: PartFrames::all(frame),
            });
        }
        crate::expression::calmest_parts(&self.expressions()).map(|parts| Neutral {
            frame: parts.mouth,
            chosen: NeutralChoice::Automatic,
            parts,
        })
    }

    /// Every frame's expression (`None` without a face).
    fn expressions(&self) -> Vec<Option<&Expression>> {
        self.frames.iter().map(|f| f.expression.as_ref()).collect()
    }

    /// How neutral the neutral frame looks to `estimator`, which reads it on its own (see
    /// [`NeutralCheck`]); with one face and so no neutral, how that face reads on its own.
    /// `None` when no frame has a face or the estimator does not read faces relative to a
    /// neutral one (then the neutral frame does not matter).
    #[must_use]
    pub fn neutral_check(&self, estimator: &dyn Estimator) -> Option<NeutralCheck> {
        if !estimator.calibrated() {
            return None;
        }
        let expressions = self.expressions();
        let (frame, chosen, parts, expression) = match self.neutral() {
            Some(neutral) => (
                neutral.frame,
                Some(neutral.chosen),
                neutral.parts,
                crate::expression::rest_face(&expressions, neutral.parts)?,
            ),
            // Fewer than two faces: the one there is, read on its own.
            None => {
                let (frame, face) = expressions
                    .iter()
                    .enumerate()
                    .find_map(|(k, e)| e.map(|e| (k, e.clone())))?;
                (frame, None, PartFrames::all(frame), face)
            }
        };
        let reading = estimator.estimate(&expression, None);
        let mut expressive: Vec<(String, f32)> = self
            .blendshapes
            .iter()
            .zip(reading)
            .filter(|(_, w)| *w > EXPRESSIVE_NEUTRAL)
            .map(|(name, w)| (name.clone(), w))
            .collect();
        expressive.sort_by(|a, b| b.1.total_cmp(&a.1));
        Some(NeutralCheck {
            frame,
            chosen,
            parts,
            expressive,
        })
    }

    /// The neutral face's expression ([`crate::expression::rest_face`] of its parts).
    #[must_use]
    pub fn neutral_expression(&self) -> Option<Expression> {
        crate::expression::rest_face(&self.expressions(), self.neutral()?.parts)
    }

    /// Makes `frame` the neutral one (`None`: back to the automatic choice) and estimates
    /// every frame again with `estimator` relative to it.
    ///
    /// # Errors
    /// [`TakeError::PastTheEnd`] for a frame past the end, [`TakeError::NoFace`] for a frame
    /// without a face, [`TakeError::Mismatch`] for another character's estimator.
    pub fn set_neutral(
        &mut self,
        frame: Option<usize>,
        estimator: &dyn Estimator,
    ) -> Result<(), TakeError> {
        if let Some(frame) = frame {
            let frame = self.frame_index(frame)?;
            if self.frames[frame].expression.is_none() {
                return Err(TakeError::NoFace { frame });
            }
        }
        let before = self.neutral;
        self.neutral = frame;
        self.reestimate(estimator)
            .inspect_err(|_| self.neutral = before)
    }

    fn frame_index(&self, frame: usize) -> Result<usize, TakeError> {
        if frame < self.frames.len() {
            Ok(frame)
        } else {
            Err(TakeError::PastTheEnd {
                frame,
                frames: self.frames.len(),
            })
        }
    }

    fn blendshape_index(&self, name: &str) -> Result<usize, TakeError> {
        self.blendshapes
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| TakeError::NoBlendshape {
                character: self.character.clone(),
                name: name.to_owned(),
            })
    }

    /// Sets blendshape `name` to `value` on `frame`; the frame becomes a keyframe.
    ///
    /// # Errors
    /// [`TakeError`] for a frame past the end, an unknown name or a value outside
    /// [0, 1].
    pub fn correct(&mut self, frame: usize, name: &str, value: f32) -> Result<(), TakeError> {
        let frame = self.frame_index(frame)?;
        self.blendshape_index(name)?;
        if !(0.0..=1.0).contains(&value) {
            return Err(TakeError::OutOfRange {
                name: name.to_owned(),
                value,
            });
        }
        self.edits
            .corrections
            .entry(frame)
            .or_default()
            .insert(name.to_owned(), value);
        Ok(())
    }

    /// Removes the correction of `name` on `frame` (all of the frame's with `None`).
    ///
    /// # Errors
    /// [`TakeError`] for a frame past the end or an unknown name.
    pub fn uncorrect(&mut self, frame: usize, name: Option<&str>) -> Result<(), TakeError> {
        let frame = self.frame_index(frame)?;
        match name {
            None => {
                self.edits.corrections.remove(&frame);
            }
            Some(name) => {
                self.blendshape_index(name)?;
                if let Some(c) = self.edits.corrections.get_mut(&frame) {
                    c.remove(name);
                    if c.is_empty() {
                        self.edits.corrections.remove(&frame);
                    }
                }
            }
        }
        Ok(())
    }

    /// Makes `frame` a keyframe.
    ///
    /// # Errors
    /// [`TakeError`] for a frame past the end.
    pub fn add_keyframe(&mut self, frame: usize) -> Result<(), TakeError> {
        let frame = self.frame_index(frame)?;
        self.edits.removed_keyframes.retain(|&k| k != frame);
        if !self.edits.added_keyframes.contains(&frame) {
            self.edits.added_keyframes.push(frame);
            self.edits.added_keyframes.sort_unstable();
        }
        Ok(())
    }

    /// Stops `frame` being a keyframe (it is then interpolated).
    ///
    /// # Errors
    /// [`TakeError`] for a frame past the end, or a corrected frame (a correction
    /// is kept as a key; remove the correction first).
    pub fn remove_keyframe(&mut self, frame: usize) -> Result<(), TakeError> {
        let frame = self.frame_index(frame)?;
        if self.edits.corrections.contains_key(&frame) {
            return Err(TakeError::CorrectedKeyframe { frame });
        }
        self.edits.added_keyframes.retain(|&k| k != frame);
        if !self.edits.removed_keyframes.contains(&frame) {
            self.edits.removed_keyframes.push(frame);
            self.edits.removed_keyframes.sort_unstable();
        }
        Ok(())
    }

    /// The keyframes: every `keyframe_every`-th frame and the last, minus removed ones, plus
    /// added and corrected frames, sorted. Never empty for a non-empty session: with every key
    /// removed, the first frame stays.
    #[must_use]
    pub fn keyframes(&self) -> Vec<usize> {
        let n = self.frames.len();
        let mut keys: Vec<usize> =
            faceanim_anim::keyframes::keyframe_indices(n, self.edits.keyframe_every, &[])
                .into_iter()
                .filter(|k| !self.edits.removed_keyframes.contains(k))
                .collect();
        keys.extend(
            self.edits
                .added_keyframes
                .iter()
                .copied()
                .filter(|&k| k < n),
        );
        keys.extend(self.edits.corrections.keys().copied().filter(|&k| k < n));
        keys.sort_unstable();
        keys.dedup();
        if keys.is_empty() && n > 0 {
            keys.push(0);
        }
        keys
    }

    /// The estimates after smoothing, before any user change.
    fn smoothed_estimates(&self) -> Vec<Vec<f32>> {
        self.smoothed(self.frames.iter().map(|f| f.estimate.clone()).collect())
    }

    /// `rows` (one per frame) under the session's One Euro smoothing, clamped to [0, 1].
    fn smoothed(&self, mut rows: Vec<Vec<f32>>) -> Vec<Vec<f32>> {
        if let Some(settings) = self.edits.smoothing {
            let mut state = faceanim_anim::filter::OneEuroState::new(settings);
            for (row, frame) in rows.iter_mut().zip(&self.frames) {
                state.filter(frame.time, row);
                row.iter_mut().for_each(|w| *w = w.clamp(0.0, 1.0));
            }
        }
        rows
    }

    /// Per blendshape, the mean of (correction − estimate) over the frames where it was
    /// corrected; 0 for blendshapes never corrected.
    #[must_use]
    pub fn preference_offsets(&self) -> Vec<f32> {
        let estimates = self.smoothed_estimates();
        let mut sum = vec![0.0f32; self.blendshapes.len()];
        let mut count = vec![0usize; self.blendshapes.len()];
        for (&frame, values) in &self.edits.corrections {
            for (name, &value) in values {
                if let (Ok(b), Some(row)) = (self.blendshape_index(name), estimates.get(frame)) {
                    sum[b] += value - row[b];
                    count[b] += 1;
                }
            }
        }
        sum.iter()
            .zip(&count)
            .map(|(s, &c)| if c > 0 { s / c as f32 } else { 0.0 })
            .collect()
    }

    /// Applies the preference: the current mean corrections are added to every other frame.
    /// Applying again after more corrections updates it.
    pub fn apply_preference(&mut self) {
        self.edits.preference = Some(self.preference_offsets());
    }

    /// Removes the preference.
    pub fn clear_preference(&mut self) {
        self.edits.preference = None;
    }

    /// Sets the smoothing and keyframe spacing.
    pub fn set_filtering(&mut self, filtering: Filtering) {
        self.edits.keyframe_every = filtering.keyframe_every;
        self.edits.smoothing = filtering.smoothing;
    }

    /// Makes a still image's 0 → peak → 0 animation `frames` frames long.
    ///
    /// # Errors
    /// [`TakeError::NotStill`] for a take of a video or sequence, [`TakeError::StillFrames`]
    /// for a length outside 1 to 10,000.
    pub fn set_still_frames(&mut self, frames: usize) -> Result<(), TakeError> {
        if self.edits.still_frames.is_none() {
            return Err(TakeError::NotStill);
        }
        if !(1..=10_000).contains(&frames) {
            return Err(TakeError::StillFrames(frames));
        }
        self.edits.still_frames = Some(frames);
        Ok(())
    }

    /// The smoothing and keyframe spacing in use.
    #[must_use]
    pub fn filtering(&self) -> Filtering {
        Filtering {
            keyframe_every: self.edits.keyframe_every,
            smoothing: self.edits.smoothing,
        }
    }

    /// The weights of every frame, one row per frame (see the module docs for the order).
    #[must_use]
    pub fn weights(&self) -> Vec<Vec<f32>> {
        let mut rows = self.smoothed_estimates();
        if let Some(offsets) = &self.edits.preference {
            for row in &mut rows {
                for (w, o) in row.iter_mut().zip(offsets) {
                    *w = (*w + o).clamp(0.0, 1.0);
                }
            }
        }
        for (&frame, values) in &self.edits.corrections {
            for (name, &value) in values {
                if let (Ok(b), Some(row)) = (self.blendshape_index(name), rows.get_mut(frame)) {
                    row[b] = value;
                }
            }
        }
        faceanim_anim::filter::fill_gaps_rows(&mut rows, &self.keyframe_mask());
        rows
    }

    /// Per frame, whether it is a keyframe.
    fn keyframe_mask(&self) -> Vec<bool> {
        let mut known = vec![false; self.frames.len()];
        for k in self.keyframes() {
            known[k] = true;
        }
        known
    }

    /// The animation as a clip (weights as [`Session::weights`], head pose interpolated
    /// between the same keyframes); for a still image, the 0 → peak → 0 animation.
    #[must_use]
    pub fn clip(&self) -> Clip {
        self.clip_of(self.blendshapes.clone(), self.weights())
    }

    /// What capture read as ARKit weights (MediaPipe's scores but `_neutral`, bridged over
    /// frames without a face) under the session's smoothing and keyframes, as a clip with the
    /// session's head pose: what Live Link Face gets for a character without ARKit names. Where
    /// no frame kept its expression, what the frames were made of ([`SessionFrame::arkit`]: a
    /// lip sync's); `None` when neither.
    #[must_use]
    pub fn arkit_clip(&self) -> Option<Clip> {
        let names = &faceanim_track::BLENDSHAPE_NAMES[1..];
        let known: Vec<bool> = self.frames.iter().map(|f| f.expression.is_some()).collect();
        if !known.contains(&true) {
            return self.made_of_clip();
        }
        let mut rows: Vec<Vec<f32>> = self
            .frames
            .iter()
            .map(|f| {
                f.expression.as_ref().map_or_else(
                    || vec![0.0; names.len()],
                    |e| e.scores.iter().skip(1).copied().collect(),
                )
            })
            .collect();
        faceanim_anim::filter::fill_gaps_rows(&mut rows, &known);
        let mut rows = self.smoothed(rows);
        faceanim_anim::filter::fill_gaps_rows(&mut rows, &self.keyframe_mask());
        Some(self.clip_of(names.iter().map(|&n| n.to_owned()).collect(), rows))
    }

    /// The frames' [`SessionFrame::arkit`] as a clip of the channels they move (eyes at rest
    /// are not keyed), under the session's smoothing; `None` when no frame has them.
    fn made_of_clip(&self) -> Option<Clip> {
        if self.frames.iter().all(|f| f.arkit.is_none()) {
            return None;
        }
        let names = &faceanim_rig::names::ARKIT_52;
        let moving: Vec<usize> = (0..names.len())
            .filter(|&c| {
                self.frames.iter().any(|f| {
                    f.arkit
                        .as_ref()
                        .is_some_and(|a| a.get(c).is_some_and(|w| *w > 0.0))
                })
            })
            .collect();
        let rows = self
            .frames
            .iter()
            .map(|f| {
                moving
                    .iter()
                    .map(|&c| {
                        f.arkit
                            .as_ref()
                            .and_then(|a| a.get(c))
                            .copied()
                            .unwrap_or(0.0)
                    })
                    .collect()
            })
            .collect();
        let rows = self.smoothed(rows);
        Some(self.clip_of(moving.iter().map(|&c| names[c].to_owned()).collect(), rows))
    }

    /// A clip of `rows` (one per frame, in `names`' order) with the session's rate, head pose
    /// and presence; for a still image, the 0 → peak → 0 animation of the first row.
    fn clip_of(&self, names: Vec<String>, rows: Vec<Vec<f32>>) -> Clip {
        if let Some(length) = self.edits.still_frames {
            let peak = rows.into_iter().next().unwrap_or_default();
            return peak_animation(&peak, names, self.fps, length);
        }
        let head: Option<Vec<[f32; 3]>> = self
            .frames
            .iter()
            .any(|f| f.head.is_some())
            .then(|| bridged(self.frames.iter().map(|f| f.head).collect()));
        let head_position: Option<Vec<[f32; 3]>> = self
            .frames
            .iter()
            .any(|f| f.head_position.is_some())
            .then(|| bridged(self.frames.iter().map(|f| f.head_position).collect()));
        let mut clip = Clip {
            fps: self.fps,
            blendshapes: names,
            frames: rows,
            head,
            head_position,
            presence: Some(self.frames.iter().map(|f| f.presence).collect()),
            arkit: None,
        };
        let known = self.keyframe_mask();
        if let Some(head) = clip.head.as_mut() {
            faceanim_anim::filter::fill_gaps(head, &known);
        }
        if let Some(position) = clip.head_position.as_mut() {
            faceanim_anim::filter::fill_gaps(position, &known);
        }
        clip
    }

    /// The corrected frames as fine-tuning examples: each frame's expression and its estimate
    /// with the user's values (frames without a face are skipped).
    #[must_use]
    pub fn corrections_for_training(&self) -> Vec<Correction> {
        let neutral = self.neutral_expression();
        self.edits
            .corrections
            .iter()
            .filter_map(|(&frame, values)| {
                let f = self.frames.get(frame)?;
                let expression = f.expression.clone()?;
                let mut target = f.estimate.clone();
                for (name, &value) in values {
                    let b = self.blendshape_index(name).ok()?;
                    target[b] = value;
                }
                Some(Correction {
                    expression,
                    neutral: neutral.clone(),
                    target,
                })
            })
            .collect()
    }

    /// Estimates every frame again with `estimator` (an adapter after fine-tuning, say);
    /// corrections, keyframes and preference stay.
    ///
    /// # Errors
    /// [`TakeError::Mismatch`] when the estimator is for other blendshapes.
    pub fn reestimate(&mut self, estimator: &dyn Estimator) -> Result<(), TakeError> {
        if estimator.blendshapes() != self.blendshapes.as_slice() {
            return Err(TakeError::Mismatch {
                character: self.character.clone(),
                reason: format!(
                    "the {}'s blendshapes are not the session's",
                    estimator.source().noun()
                ),
            });
        }
        let neutral = self.neutral_expression();
        let estimates = estimate_frames(&self.expressions(), estimator, neutral.as_ref());
        for (frame, estimate) in self.frames.iter_mut().zip(estimates) {
            frame.estimate = estimate;
        }
        Ok(())
    }

    /// The session as JSON.
    #[must_use]
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Parses and checks a session file: every value that cannot be finite or in range is
    /// refused with its JSON path, before anything is computed from it (a photo's animation
    /// length, keyframes, indices), so that no session can make a later step allocate without
    /// bound or produce NaN.
    ///
    /// # Errors
    /// [`TakeError::Format`] for JSON that is not a session (with the path of the value that is
    /// wrong), [`TakeError::Invalid`] with every problem found and its path.
    pub fn from_json(bytes: &[u8]) -> Result<Session, TakeError> {
        let session: Session = faceanim_rig::json::from_slice(bytes)
            .map_err(|e| TakeError::Format(format!("not a session file: {e}")))?;
        let problems = session.problems();
        if problems.is_empty() {
            Ok(session)
        } else {
            Err(TakeError::Invalid(problems))
        }
    }

    /// Every value of the session that is out of range, with its JSON path.
    fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        let mut bad = |p: String| problems.push(p);
        if self.version != 1 {
            bad(format!("version: {} is not supported (1 is)", self.version));
        }
        if let Some(problem) = fps_problem(self.fps) {
            bad(problem);
        }
        if self.frames.len() > MAX_FRAMES {
            bad(format!(
                "frames: {} frames; a session holds at most {MAX_FRAMES}",
                self.frames.len()
            ));
        }
        if !(1..=1000).contains(&self.edits.keyframe_every) {
            bad(format!(
                "keyframe_every: {} must be between 1 and 1000",
                self.edits.keyframe_every
            ));
        }
        if let Some(Err(why)) = self.edits.smoothing.map(|s| s.validate()) {
            bad(format!("smoothing: {why}"));
        }
        if let Some(length) = self.edits.still_frames {
            if !(1..=MAX_STILL_FRAMES).contains(&length) {
                bad(format!(
                    "still_frames: {length} must be between 1 and {MAX_STILL_FRAMES}"
                ));
            }
            if self.frames.len() != 1 {
                bad(format!(
                    "still_frames: only a take of one photo has it, this one has {} frames",
                    self.frames.len()
                ));
            }
        }
        let width = self.blendshapes.len();
        for (k, frame) in self.frames.iter().enumerate() {
            frame_problems(frame, &format!("frames[{k}]"), width, &mut bad);
        }
        let count = self.frames.len();
        if let Some(frame) = self.neutral
            && self
                .frames
                .get(frame)
                .is_none_or(|f| f.expression.is_none())
        {
            bad(format!(
                "neutral: frame {frame} is past the end or has no face"
            ));
        }
        for (field, list) in [
            ("added_keyframes", &self.edits.added_keyframes),
            ("removed_keyframes", &self.edits.removed_keyframes),
        ] {
            if let Some((k, frame)) = list.iter().enumerate().find(|(_, f)| **f >= count) {
                bad(format!(
                    "{field}[{k}]: frame {frame} is past the end ({count} frames)"
                ));
            }
        }
        for (&frame, values) in &self.edits.corrections {
            if frame >= count {
                bad(format!(
                    "corrections.{frame}: frame {frame} is past the end ({count} frames)"
                ));
            }
            for (name, value) in values {
                let shown = faceanim_rig::excerpt(name);
                if !self.blendshapes.contains(name) {
                    bad(format!("corrections.{frame}: no blendshape '{shown}'"));
                } else if !(0.0..=1.0).contains(value) {
                    bad(format!(
                        "corrections.{frame}.{shown}: {value} is outside 0..1"
                    ));
                }
            }
        }
        if let Some(offsets) = &self.edits.preference {
            if offsets.len() != width {
                bad(format!(
                    "preference: {} offsets for {width} blendshapes",
                    offsets.len()
                ));
            }
            if let Some((k, v)) = offsets
                .iter()
                .enumerate()
                .find(|(_, v)| !(-1.0..=1.0).contains(*v))
            {
                bad(format!("preference[{k}]: {v} is outside -1..1"));
            }
        }
        // A file full of bad values says what is wrong in a few lines, not a megabyte.
        if problems.len() > MAX_PROBLEMS {
            let more = problems.len() - MAX_PROBLEMS;
            problems.truncate(MAX_PROBLEMS);
            problems.push(format!("and {more} more"));
        }
        problems
    }

    /// The seed toolkit's CSV: one line per frame, `name.png,w1,…,wN`, in the session's
    /// blendshape order, without a header.
    #[must_use]
    pub fn to_seed_csv(&self) -> String {
        let mut out = String::new();
        for (frame, row) in self.frames.iter().zip(self.weights()) {
            out.push_str(&frame.name);
            for w in row {
                out.push(',');
                out.push_str(&format!("{w:.6}"));
            }
            out.push('\n');
        }
        out
    }
}

/// The highest frame rate a session may have.
pub const MAX_FPS: f32 = 1000.0;

/// What is wrong with a session's rate `fps`, if anything: it is above 0 and at most
/// [`MAX_FPS`].
pub(crate) fn fps_problem(fps: f32) -> Option<String> {
    (!(fps.is_finite() && fps > 0.0 && fps <= MAX_FPS))
        .then(|| format!("fps: {fps} must be above 0 and at most {MAX_FPS}"))
}
/// The most frames a session may have: ten hours at 60 frames a second.
pub const MAX_FRAMES: usize = 10 * 3600 * 60;
/// The longest 0 → peak → 0 animation a photo becomes, in frames.
pub const MAX_STILL_FRAMES: usize = 10_000;
/// Problems listed in one message at most.
const MAX_PROBLEMS: usize = 12;
/// The largest head angle a session may hold, in degrees (a turn and a half either way: a
/// tracker that unwraps angles may pass ±180).
const MAX_DEGREES: f32 = 540.0;
/// The farthest head position a session may hold, in metres.
const MAX_METRES: f32 = 1000.0;

/// The problems of one session frame at JSON path `path`, for a character of `width` shapes.
fn frame_problems(frame: &SessionFrame, path: &str, width: usize, bad: &mut impl FnMut(String)) {
    if !(frame.time.is_finite() && frame.time >= 0.0) {
        bad(format!(
            "{path}.time: {} must be a time in seconds from 0",
            frame.time
        ));
    }
    if !(0.0..=1.0).contains(&frame.presence) {
        bad(format!(
            "{path}.presence: {} is outside 0..1",
            frame.presence
        ));
    }
    let out_of =
        |values: &[f32], limit: f32| values.iter().position(|v| !(-limit..=limit).contains(v));
    if let Some(k) = frame.head.and_then(|h| out_of(&h, MAX_DEGREES)) {
        bad(format!(
            "{path}.head[{k}]: {} degrees is not a head angle (at most {MAX_DEGREES})",
            frame.head.map_or(f32::NAN, |h| h[k])
        ));
    }
    if let Some(k) = frame.head_position.and_then(|p| out_of(&p, MAX_METRES)) {
        bad(format!(
            "{path}.head_position[{k}]: {} m is not a head position (at most {MAX_METRES} m)",
            frame.head_position.map_or(f32::NAN, |p| p[k])
        ));
    }
    if let Some(expression) = &frame.expression {
        for (field, values, wanted) in [
            ("scores", &expression.scores, crate::expression::SCORES),
            (
                "landmarks",
                &expression.landmarks,
                crate::expression::LANDMARK_COORDINATES,
            ),
        ] {
            if values.len() != wanted {
                bad(format!(
                    "{path}.expression.{field}: {} values, not {wanted}",
                    values.len()
                ));
            } else if let Some(k) = out_of(values, 1e3) {
                bad(format!(
                    "{path}.expression.{field}[{k}]: {} is not a measurement",
                    values[k]
                ));
            }
        }
    }
    if let Some(problem) = frame.arkit.as_deref().and_then(|a| arkit_problem(path, a)) {
        bad(problem);
    }
    if frame.estimate.len() != width {
        bad(format!(
            "{path}.estimate: {} weights for {width} blendshapes",
            frame.estimate.len()
        ));
    } else if let Some(k) = frame
        .estimate
        .iter()
        .position(|w| !(-1.0..=2.0).contains(w))
    {
        bad(format!(
            "{path}.estimate[{k}]: {} is not a weight",
            frame.estimate[k]
        ));
    }
}

/// What is wrong with `arkit`, the ARKit values frame `path` was made of
/// ([`SessionFrame::arkit`]): not ARKit's 52, or a value outside 0..1.
pub(crate) fn arkit_problem(path: &str, arkit: &[f32]) -> Option<String> {
    let wanted = faceanim_rig::names::ARKIT_52.len();
    if arkit.len() != wanted {
        return Some(format!(
            "{path}.arkit: {} values, not {wanted}",
            arkit.len()
        ));
    }
    let k = arkit.iter().position(|w| !(0.0..=1.0).contains(w))?;
    Some(format!("{path}.arkit[{k}]: {} is not in 0..1", arkit[k]))
}

/// Per frame, the estimator's weights for its expression relative to `neutral`; frames without
/// an expression take values interpolated from their neighbours (all zeros when no frame has a
/// face).
#[must_use]
pub fn estimate_frames(
    expressions: &[Option<&Expression>],
    estimator: &dyn Estimator,
    neutral: Option<&Expression>,
) -> Vec<Vec<f32>> {
    let width = estimator.blendshapes().len();
    let mut rows: Vec<Vec<f32>> = expressions
        .iter()
        .map(|e| e.map_or_else(|| vec![0.0; width], |e| estimator.estimate(e, neutral)))
        .collect();
    let known: Vec<bool> = expressions.iter().map(Option::is_some).collect();
    faceanim_anim::filter::fill_gaps_rows(&mut rows, &known);
    rows
}

fn bridged(values: Vec<Option<[f32; 3]>>) -> Vec<[f32; 3]> {
    let known: Vec<bool> = values.iter().map(Option::is_some).collect();
    let mut rows: Vec<[f32; 3]> = values.into_iter().map(Option::unwrap_or_default).collect();
    faceanim_anim::filter::fill_gaps(&mut rows, &known);
    rows
}

/// A still image's estimate as a short animation: 0 → `peak` → 0 over `frames` frames at
/// `fps`, eased in and out (smoothstep), the peak on the middle frame.
#[must_use]
pub fn peak_animation(peak: &[f32], blendshapes: Vec<String>, fps: f32, frames: usize) -> Clip {
    let frames = frames.max(1);
    let middle = (frames - 1) as f32 / 2.0;
    let rows = (0..frames)
        .map(|i| {
            let u = if middle > 0.0 {
                1.0 - ((i as f32 - middle) / middle).abs()
            } else {
                1.0
            };
            let s = u * u * (3.0 - 2.0 * u);
            peak.iter().map(|w| w * s).collect()
        })
        .collect();
    Clip {
        fps,
        blendshapes,
        frames: rows,
        head: None,
        head_position: None,
        presence: None,
        arkit: None,
    }
}

/// A session of `frames` frames at 30 fps for blendshapes `a` and `b`, with no face and the
/// estimate `estimate(frame)`: the fixture of this crate's tests.
#[cfg(test)]
pub(crate) fn test_session(frames: usize, estimate: impl Fn(usize) -> Vec<f32>) -> Session {
    let frames = (0..frames)
        .map(|i| SessionFrame {
            name: format!("f_{i:06}.png"),
            time: i as f32 / 30.0,
            presence: 1.0,
            head: None,
            head_position: None,
            expression: None,
            estimate: estimate(i),
            arkit: None,
        })
        .collect();
    Session::new(
        "test".into(),
        "char".into(),
        vec!["a".to_owned(), "b".to_owned()],
        Fingerprint {
            topology: "t".into(),
            geometry: "g".into(),
        },
        30.0,
        1,
        frames,
    )
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "values set and copied exactly")]
mod tests {
    use super::*;

    fn session(frames: usize) -> Session {
        test_session(frames, |i| vec![0.1 + 0.01 * i as f32, 0.5])
    }

    #[test]
    fn preference_shifts_every_other_frame_by_the_mean_correction() {
        let mut s = session(10);
        s.correct(3, "a", 0.43).unwrap(); // estimate 0.13: +0.30
        s.correct(6, "a", 0.56).unwrap(); // estimate 0.16: +0.40
        s.apply_preference();
        let w = s.weights();
        assert_eq!(w[3][0], 0.43);
        assert_eq!(w[6][0], 0.56);
        for (i, row) in w.iter().enumerate().filter(|(i, _)| *i != 3 && *i != 6) {
            assert!(
                (row[0] - (0.1 + 0.01 * i as f32 + 0.35)).abs() < 1e-6,
                "{i}: {row:?}"
            );
            assert_eq!(row[1], 0.5, "an uncorrected blendshape keeps its estimate");
        }
        s.clear_preference();
        assert!((s.weights()[0][0] - 0.1).abs() < 1e-6);
    }

    #[test]
    fn preference_is_clamped() {
        let mut s = session(4);
        s.correct(0, "b", 1.0).unwrap(); // +0.5 on b, whose estimate is 0.5 everywhere
        s.correct(1, "b", 1.0).unwrap();
        s.apply_preference();
        assert!(s.weights().iter().all(|r| r[1] == 1.0));
    }

    #[test]
    fn keyframes_interpolate_and_corrections_are_keys() {
        let mut s = session(11);
        s.edits.keyframe_every = 5;
        assert_eq!(s.keyframes(), vec![0, 5, 10]);
        s.correct(2, "b", 0.9).unwrap();
        s.add_keyframe(8).unwrap();
        s.remove_keyframe(5).unwrap();
        assert_eq!(s.keyframes(), vec![0, 2, 8, 10]);
        let w = s.weights();
        // Frame 1 is halfway between keys 0 (0.5) and 2 (0.9) for b.
        assert!((w[1][1] - 0.7).abs() < 1e-6);
        assert!(s.remove_keyframe(2).is_err());
        assert!(s.correct(11, "a", 0.5).is_err());
        assert!(s.correct(1, "nope", 0.5).is_err());
        assert!(s.correct(1, "a", 1.5).is_err());
    }

    #[test]
    fn a_session_survives_its_file() {
        let mut s = session(5);
        s.correct(1, "a", 0.9).unwrap();
        s.apply_preference();
        let back = Session::from_json(s.to_json().as_bytes()).unwrap();
        assert_eq!(back, s);
        let broken = s.to_json().replace("\"fps\":30.0", "\"fps\":-1.0");
        let error = Session::from_json(broken.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(error.contains("fps"), "{error}");
    }

    /// Reads "a" as the first score relative to the neutral's, "b" as the first score itself.
    /// The score the tests' faces move: jawOpen, one of the mouth's (the part whose calmest
    /// frame is the neutral's `frame`).
    const JAW: usize = 25;

    /// Reads [`JAW`] relative to the neutral face's, and as it is.
    struct Relative;

    impl Estimator for Relative {
        fn blendshapes(&self) -> &[String] {
            static NAMES: std::sync::LazyLock<Vec<String>> =
                std::sync::LazyLock::new(|| vec!["a".to_owned(), "b".to_owned()]);
            &NAMES
        }
        fn estimate(&self, e: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
            let rest = neutral.map_or(0.0, |n| n.scores[JAW]);
            vec![(e.scores[JAW] - rest).clamp(0.0, 1.0), e.scores[JAW]]
        }
        fn source(&self) -> crate::EstimatorSource {
            crate::EstimatorSource::Adapter
        }
        fn calibrated(&self) -> bool {
            true
        }
    }

    #[test]
    fn the_neutral_face_is_each_parts_calmest_frame_until_the_user_names_one() {
        // Frame i's face has its jawOpen at |i − 3| / 10 and its browDownLeft at |i − 6| / 10:
        // the mouth rests in frame 3, the brows in frame 6; frame 5 has no face.
        let mut s = session(8);
        for (i, frame) in s.frames.iter_mut().enumerate() {
            let mut scores = vec![0.0; crate::expression::SCORES];
            scores[JAW] = (i as f32 - 3.0).abs() / 10.0;
            scores[1] = (i as f32 - 6.0).abs() / 10.0;
            frame.expression = (i != 5).then(|| Expression {
                scores,
                landmarks: vec![0.0; crate::expression::LANDMARK_COORDINATES],
            });
        }
        let automatic = s.neutral().unwrap();
        assert_eq!(
            (automatic.frame, automatic.chosen),
            (3, NeutralChoice::Automatic)
        );
        // The lids and the gaze never move: their first frame is as calm as any.
        assert_eq!(
            automatic.parts,
            PartFrames {
                lids: 0,
                gaze: 0,
                brows: 6,
                mouth: 3
            }
        );
        let rest = s.neutral_expression().unwrap();
        assert_eq!((rest.scores[JAW], rest.scores[1]), (0.0, 0.0));
        s.set_neutral(Some(7), &Relative).unwrap();
        assert_eq!(s.neutral().unwrap().chosen, NeutralChoice::User);
        assert_eq!(s.neutral().unwrap().parts, PartFrames::all(7));
        // Frame 0 (0.3) against frame 7 (0.4): below rest, so 0; frame 7 against itself: 0.
        assert_eq!(s.frames[0].estimate, vec![0.0, 0.3]);
        s.set_neutral(None, &Relative).unwrap();
        assert!((s.frames[0].estimate[0] - 0.3).abs() < 1e-6);
        // A frame without a face or past the end is refused, and nothing changes.
        assert!(matches!(
            s.set_neutral(Some(5), &Relative),
            Err(TakeError::NoFace { frame: 5 })
        ));
        assert!(s.set_neutral(Some(8), &Relative).is_err());
        assert_eq!(s.neutral().unwrap().frame, 3);
        // Kept in the file, and checked when read.
        s.set_neutral(Some(6), &Relative).unwrap();
        let back = Session::from_json(s.to_json().as_bytes()).unwrap();
        assert_eq!(back.neutral().unwrap().frame, 6);
        let broken = s.to_json().replace("\"neutral\":6", "\"neutral\":5");
        let error = Session::from_json(broken.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(error.contains("neutral: frame 5"), "{error}");
    }

    /// A take whose every face is expressive says it has no clearly neutral frame; a relaxed
    /// frame clears it; choosing an expressive one warns; by name nothing is checked.
    #[test]
    fn a_neutral_frame_that_reads_as_an_expression_is_flagged() {
        let mut s = session(4);
        let face = |first: f32| {
            let mut scores = vec![0.0; crate::expression::SCORES];
            scores[JAW] = first;
            Some(Expression {
                scores,
                landmarks: vec![0.0; crate::expression::LANDMARK_COORDINATES],
            })
        };
        for (frame, first) in s.frames.iter_mut().zip([0.9, 0.6, 0.8, 0.7]) {
            frame.expression = face(first);
        }
        let check = s.neutral_check(&Relative).unwrap();
        assert_eq!(
            (check.frame, check.chosen),
            (1, Some(NeutralChoice::Automatic))
        );
        assert_eq!(check.parts.mouth, 1);
        assert_eq!(
            check.expressive,
            vec![("a".to_owned(), 0.6), ("b".to_owned(), 0.6)]
        );
        let warning = check.warning().unwrap();
        assert!(
            warning.contains("no frame of this take looks clearly neutral"),
            "{warning}"
        );
        assert!(
            warning.contains("mouth 1") && warning.contains("a 0.60, b 0.60"),
            "{warning}"
        );

        s.frames[3].expression = face(0.05);
        assert!(s.neutral_check(&Relative).unwrap().is_clear());
        s.set_neutral(Some(0), &Relative).unwrap();
        let chosen = s.neutral_check(&Relative).unwrap();
        assert!(
            chosen
                .warning()
                .unwrap()
                .starts_with("the neutral frame 0 reads a 0.90, b 0.90")
        );

        let by_name = crate::ByName::new(&faceanim_head::default_character());
        assert_eq!(
            s.neutral_check(&by_name),
            None,
            "by name, no neutral is used"
        );

        // One face (a photo): no neutral to read it against, so the face itself is read, and
        // what it shows may be the person at rest; a relaxed one says nothing.
        let mut photo = session(3);
        assert_eq!(
            photo.neutral_check(&Relative),
            None,
            "no face, nothing to read"
        );
        photo.frames[2].expression = face(0.7);
        assert_eq!(photo.neutral(), None);
        let alone = photo.neutral_check(&Relative).unwrap();
        assert_eq!((alone.frame, alone.chosen), (2, None));
        let warning = alone.warning().unwrap();
        assert!(
            warning.starts_with("this take has one face (frame 2)")
                && warning.contains("reads a 0.70, b 0.70")
                && warning.contains("relaxed picture"),
            "{warning}"
        );
        photo.frames[2].expression = face(0.1);
        assert!(photo.neutral_check(&Relative).unwrap().is_clear());
    }

    #[test]
    fn an_image_becomes_zero_peak_zero() {
        let clip = peak_animation(&[0.8, 0.4], vec!["a".into(), "b".into()], 30.0, 31);
        assert_eq!(clip.frames.len(), 31);
        assert_eq!(clip.frames[0], vec![0.0, 0.0]);
        assert_eq!(clip.frames[30], vec![0.0, 0.0]);
        assert_eq!(clip.frames[15], vec![0.8, 0.4]);
        assert!(clip.frames[7][0] > 0.0 && clip.frames[7][0] < 0.8);
    }
}
