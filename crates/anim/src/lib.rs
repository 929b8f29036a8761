//! # faceanim-anim: clips of blendshape weights
//!
//! A [`Clip`] is the common currency of faceanim: one row of weights per frame for a list of
//! named blendshapes, at a frame rate, with an optional head rotation per frame. Sketches bake
//! into clips, capture produces them, metrics compare them and exporters write them.
//!
//! The JSON form (docs/formats.md, "Clip") is
//! `{"fps": 30, "blendshapes": [names], "frames": [[w, ...], ...], "head": [[yaw, pitch, roll], ...]}`,
//! and for clips from capture two more optional per-frame fields: `"head_position"` (metres
//! from the camera) and `"presence"` (0..1; 0 marks a frame where no face was found), and
//! `"arkit"`: the ARKit values a take was made of, where its own names leave channels without
//! a column ([`Clip::arkit`]).
//! [`Clip::from_json`] reports *every* problem with its path (`frames[3][7]`), not just the first.
//!
//! ```
//! let clip = faceanim_anim::Clip::from_json(br#"{"fps": 30, "blendshapes": ["jawOpen"], "frames": [[0.0], [0.5], [1.0]]}"#)?;
//! assert_eq!(clip.duration_seconds(), 2.0 / 30.0);
//! # Ok::<(), faceanim_anim::ClipError>(())
//! ```
#![deny(missing_docs)]

mod by_name;
pub mod filter;
pub mod keyframes;
pub mod metrics;

use faceanim_rig::Character;
use faceanim_rig::animation::MorphAnimation;
use serde::{Deserialize, Serialize};

/// Baked blendshape weights over time. See the crate docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Clip {
    /// Frames per second (positive).
    pub fps: f32,
    /// Blendshape names, one per column of `frames`.
    pub blendshapes: Vec<String>,
    /// One row of weights per frame.
    pub frames: Vec<Vec<f32>>,
    /// Head rotation per frame in degrees: yaw, pitch, roll (see [`head_rotation`] for the
    /// convention).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head: Option<Vec<[f32; 3]>>,
    /// Head position per frame in metres, relative to the camera (x right, y up, z towards the
    /// viewer), for clips from capture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head_position: Option<Vec<[f32; 3]>>,
    /// Per frame, how sure capture was that a face was there (0..1; 0 where no face was found
    /// and the weights were filled in from the neighbouring frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub presence: Option<Vec<f32>>,
    /// The ARKit values the clip was made of (a capture's scores, lip sync's visemes), per
    /// frame ARKit's 52 in [`ARKIT_52`](faceanim_rig::names::ARKIT_52) order, kept where the
    /// clip's own names leave some of those channels without a column: a VRoid avatar's gaze,
    /// which its eye bones show; every channel of a rig whose names say nothing. Eye and jaw
    /// bones and ARKit outputs (Live Link Face) read them ([`Clip::arkit_rows`]); they set
    /// shapes only on another character ([`Clip::for_character`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arkit: Option<Vec<Vec<f32>>>,
}

/// The head rotation `[yaw, pitch, roll]` (degrees) as a unit quaternion `[x, y, z, w]` in a
/// y-up, z-towards-the-viewer frame (glTF's, for a character facing the viewer):
/// `R = Ry(yaw) · Rx(−pitch) · Rz(roll)`, so positive yaw turns the face towards the subject's
/// own left, positive pitch lifts the chin, positive roll turns anticlockwise as the viewer sees it.
#[must_use]
pub fn head_rotation([yaw, pitch, roll]: [f32; 3]) -> [f32; 4] {
    let q = glam::Quat::from_rotation_y(yaw.to_radians())
        * glam::Quat::from_rotation_x(-pitch.to_radians())
        * glam::Quat::from_rotation_z(roll.to_radians());
    q.normalize().to_array()
}

/// The inverse of [`head_rotation`]: a rotation `[x, y, z, w]` as `[yaw, pitch, roll]` in
/// degrees; `None` for one that is not a finite, non-zero quaternion.
#[must_use]
pub fn head_angles(q: [f32; 4]) -> Option<[f32; 3]> {
    let q = glam::Quat::from_array(q);
    let length = q.length();
    if !length.is_finite() || length < 1e-6 {
        return None;
    }
    let (yaw, x_angle, roll) = (q / length).to_euler(glam::EulerRot::YXZ);
    Some([yaw.to_degrees(), -x_angle.to_degrees(), roll.to_degrees()])
}

/// Problems with a clip, each with the JSON path it concerns.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ClipError {
    /// The text is not a clip at all (JSON syntax, missing or unknown fields, wrong types).
    #[error("not a clip: {0}")]
    Syntax(String),
    /// The clip parses but its values are inconsistent.
    #[error("invalid clip: {}", .0.join("; "))]
    Invalid(Vec<String>),
    /// The clip names no blendshape of the character it is applied to.
    #[error("none of the clip's blendshapes exist on character '{character}' (clip has: {clip})")]
    NothingInCommon {
        /// The character's name.
        character: String,
        /// The first few clip names.
        clip: String,
    },
}

/// How a clip's columns landed on a character.
#[derive(Debug, Clone, PartialEq)]
pub struct Retarget {
    /// The animation, one weight per character blendshape per frame.
    pub animation: MorphAnimation,
    /// Clip columns that reach no blendshape of the character (no meaning it has a shape for,
    /// or only shapes other columns set by their exact names): their weights are dropped.
    pub unmatched: Vec<String>,
}

impl Clip {
    /// A clip of weights alone, at `fps`: columns named `names`, one row of `frames` per
    /// frame; no head pose, head position or presence.
    ///
    /// ```
    /// let clip = faceanim_anim::Clip::of_weights(30.0, &["jawOpen"], vec![vec![0.0], vec![0.5]]);
    /// assert_eq!(clip.column("jawOpen"), Some(0));
    /// assert!(clip.head.is_none());
    /// ```
    #[must_use]
    pub fn of_weights(fps: f32, names: &[&str], frames: Vec<Vec<f32>>) -> Clip {
        Clip {
            fps,
            blendshapes: names.iter().map(|&n| n.to_owned()).collect(),
            frames,
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }

    /// The column of the blendshape named exactly `name`, if the clip has one.
    #[must_use]
    pub fn column(&self, name: &str) -> Option<usize> {
        self.blendshapes.iter().position(|n| n == name)
    }

    /// The rows as ARKit's 52 channels in
    /// [`ARKIT_52`](faceanim_rig::names::ARKIT_52) order, read through the name table as the
    /// Live Link Face writer reads them (any spelling, split halves averaged), clamped to 0..1;
    /// a channel no column carries from the values the clip was made of ([`Clip::arkit`]),
    /// else at 0.
    ///
    /// ```
    /// let mut clip = faceanim_anim::Clip::of_weights(30.0, &["Fcl_EYE_Close_L"], vec![vec![0.5]]);
    /// let blink = faceanim_rig::names::Channel::named("eyeBlinkLeft").unwrap().index();
    /// let look = faceanim_rig::names::Channel::named("eyeLookInLeft").unwrap().index();
    /// let mut made_of = vec![0.0; 52];
    /// made_of[blink] = 0.9; // the capture's score, under the take's own weight
    /// made_of[look] = 0.3; // the gaze, which no column carries
    /// clip.arkit = Some(vec![made_of]);
    /// let row = &clip.arkit_rows()[0];
    /// assert_eq!((row[blink], row[look]), (0.5, 0.3));
    /// ```
    #[must_use]
    pub fn arkit_rows(&self) -> Vec<Vec<f32>> {
        let map = faceanim_rig::name_map::NameMap::from_names(&self.blendshapes, &[]);
        (0..self.frames.len())
            .map(|f| self.arkit_of(&map, f))
            .collect()
    }

    /// Frame `frame` as [`Clip::arkit_rows`] reads each; `None` past the last frame.
    #[must_use]
    pub fn arkit_row(&self, frame: usize) -> Option<Vec<f32>> {
        self.frames.get(frame)?;
        let map = faceanim_rig::name_map::NameMap::from_names(&self.blendshapes, &[]);
        Some(self.arkit_of(&map, frame))
    }

    /// Frame `frame` (which exists) through `map`, the channels it leaves from [`Clip::arkit`].
    fn arkit_of(&self, map: &faceanim_rig::name_map::NameMap, frame: usize) -> Vec<f32> {
        let made_of = self.arkit.as_ref().and_then(|rows| rows.get(frame));
        map.channel_values(&self.frames[frame])
            .into_iter()
            .enumerate()
            .map(|(c, v)| {
                v.or_else(|| made_of.and_then(|row| row.get(c)).copied())
                    .unwrap_or(0.0)
                    .clamp(0.0, 1.0)
            })
            .collect()
    }

    /// The values the clip was made of ([`Clip::arkit`]) as a clip of ARKit's 52 named
    /// columns, with the clip's head pose; `None` when it keeps none.
    #[must_use]
    pub fn arkit_clip(&self) -> Option<Clip> {
        Some(Clip {
            fps: self.fps,
            blendshapes: faceanim_rig::names::ARKIT_52
                .iter()
                .map(|&n| n.to_owned())
                .collect(),
            frames: self.arkit.clone()?,
            head: self.head.clone(),
            head_position: self.head_position.clone(),
            presence: self.presence.clone(),
            arkit: None,
        })
    }

    /// The clip as it reaches `character`. Where it keeps the ARKit values its take was made of
    /// ([`Clip::arkit`]) and its columns are not all `character`'s own names (a VRoid avatar's
    /// take put on another character), those values join it as ARKit-named columns for the
    /// channels that move there and that no column carries: the other character's eyeLook
    /// shapes take the gaze the VRoid's names left out. On the character the take was made on,
    /// its columns are that character's weights, which hold all its shapes could take: the kept
    /// values reach only its bones, and the clip is as it is.
    #[must_use]
    pub fn for_character(&self, character: &Character) -> std::borrow::Cow<'_, Clip> {
        use std::borrow::Cow;
        let Some(kept) = &self.arkit else {
            return Cow::Borrowed(self);
        };
        let own: std::collections::HashSet<&str> =
            character.blendshapes().iter().map(|b| b.name()).collect();
        if self.blendshapes.iter().all(|n| own.contains(n.as_str())) {
            return Cow::Borrowed(self);
        }
        let joining: Vec<usize> = left_out(&self.blendshapes, kept)
            .into_iter()
            .map(|c| c.index())
            .collect();
        if joining.is_empty() {
            return Cow::Borrowed(self);
        }
        let mut widened = self.clone();
        widened.blendshapes.extend(
            joining
                .iter()
                .map(|&c| faceanim_rig::names::ARKIT_52[c].to_owned()),
        );
        for (row, made_of) in widened.frames.iter_mut().zip(kept) {
            row.extend(
                joining
                    .iter()
                    .map(|&c| made_of.get(c).copied().unwrap_or(0.0)),
            );
        }
        Cow::Owned(widened)
    }

    /// Parses and validates clip JSON.
    ///
    /// # Errors
    /// [`ClipError::Syntax`] for malformed JSON, [`ClipError::Invalid`] listing every bad value.
    pub fn from_json(bytes: &[u8]) -> Result<Clip, ClipError> {
        let clip: Clip =
            faceanim_rig::json::from_slice(bytes).map_err(|e| ClipError::Syntax(e.to_string()))?;
        clip.validate()?;
        Ok(clip)
    }

    /// The clip as pretty JSON.
    #[must_use]
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks frame rate, row lengths, finiteness and head rows; lists every problem.
    ///
    /// # Errors
    /// [`ClipError::Invalid`] with one entry per problem (at most 20, then a count).
    pub fn validate(&self) -> Result<(), ClipError> {
        let mut problems = Vec::new();
        if !(self.fps.is_finite() && self.fps > 0.0) {
            problems.push(format!(
                "fps: must be a positive number, found {}",
                self.fps
            ));
        }
        if self.frames.is_empty() {
            problems.push("frames: the clip has no frames".to_owned());
        }
        let width = self.blendshapes.len();
        let mut seen = std::collections::HashSet::new();
        for (i, name) in self.blendshapes.iter().enumerate() {
            if !seen.insert(name) {
                problems.push(format!("blendshapes[{i}]: '{name}' appears twice"));
            }
        }
        for (f, row) in self.frames.iter().enumerate() {
            if row.len() != width {
                problems.push(format!(
                    "frames[{f}]: {} weights for {width} blendshapes",
                    row.len()
                ));
            }
            for (k, w) in row.iter().enumerate() {
                if !w.is_finite() {
                    problems.push(format!("frames[{f}][{k}]: not a finite number"));
                }
            }
        }
        for (field, rows) in [("head", &self.head), ("head_position", &self.head_position)] {
            if let Some(rows) = rows {
                problems.extend(row_problems(field, rows, self.frames.len(), None));
            }
        }
        if let Some(rows) = &self.arkit {
            let channels = (faceanim_rig::names::ARKIT_52.len(), "ARKit's 52 channels");
            problems.extend(row_problems(
                "arkit",
                rows,
                self.frames.len(),
                Some(channels),
            ));
        }
        if let Some(presence) = &self.presence {
            problems.extend(count_problem(
                "presence",
                presence.len(),
                "values",
                self.frames.len(),
            ));
            for (f, p) in presence.iter().enumerate() {
                if !(0.0..=1.0).contains(p) {
                    problems.push(format!("presence[{f}]: {p} is not in [0, 1]"));
                }
            }
        }
        if problems.is_empty() {
            return Ok(());
        }
        let extra = problems.len().saturating_sub(20);
        problems.truncate(20);
        if extra > 0 {
            problems.push(format!("and {extra} more"));
        }
        Err(ClipError::Invalid(problems))
    }

    /// Length in seconds from the first frame to the last.
    #[must_use]
    pub fn duration_seconds(&self) -> f32 {
        self.frames.len().saturating_sub(1) as f32 / self.fps
    }

    /// The columns that move (are not 0 throughout) and reach no blendshape of `character` in
    /// [`Clip::retarget_through`] `map`: what would be lost, to warn of before exporting.
    #[must_use]
    pub fn unmatched(
        &self,
        character: &Character,
        map: Option<&faceanim_retarget::RetargetMap>,
    ) -> Vec<String> {
        let routes = by_name::Routes::new(&self.blendshapes, character, map);
        self.names_of(
            self.unreached(&routes)
                .into_iter()
                .filter(|&k| self.moves(k)),
        )
    }

    /// Whether some column that moves means ARKit channels (a spelling of one, a split or
    /// merged shape, VRM's presets) and reaches no blendshape of `character` by name: what its
    /// retarget map would carry, for a rig whose names say nothing.
    #[must_use]
    pub fn loses_arkit(&self, character: &Character) -> bool {
        self.unmatched(character, None)
            .iter()
            .any(|name| faceanim_rig::names::drive(name).is_some())
    }

    /// Whether column `k` is other than 0 in some frame.
    fn moves(&self, k: usize) -> bool {
        self.frames
            .iter()
            .any(|row| row.get(k).is_some_and(|&w| w != 0.0))
    }

    /// The columns `routes` takes to no blendshape.
    fn unreached(&self, routes: &by_name::Routes) -> Vec<usize> {
        (0..self.blendshapes.len())
            .filter(|&k| !routes.reaches(k))
            .collect()
    }

    /// The names of `columns`.
    fn names_of(&self, columns: impl Iterator<Item = usize>) -> Vec<String> {
        columns.map(|k| self.blendshapes[k].clone()).collect()
    }

    /// Maps the clip onto `character`'s blendshapes by name, one key per frame: a column of a
    /// blendshape's exact name sets it as written; the others reach the character by the name
    /// table, as capture by name does — an ARKit channel in any spelling, VRM's and VRoid's
    /// names for pairs (`happy`, `blink`, `Fcl_EYE_Close`) and vowels (`aa`, `A`), split halves
    /// (`browInnerUp_L`) — in 0..1 (see the `by_name` module). Character blendshapes the clip
    /// does not reach stay at 0. A head rotation, if the clip has one, turns the character's
    /// root.
    ///
    /// # Errors
    /// [`ClipError::NothingInCommon`] when no column reaches a blendshape.
    pub fn retarget(&self, character: &Character, name: &str) -> Result<Retarget, ClipError> {
        self.retarget_through(character, name, None)
    }

    /// [`Clip::retarget`], with the ARKit channels the columns carry reaching the character's
    /// shapes through its retarget `map` where given (by name where the names say it, by
    /// geometry where they do not: an ARKit clip on a rig whose names say nothing). A map made
    /// for other shapes is not used.
    ///
    /// # Errors
    /// [`ClipError::NothingInCommon`] when no column reaches a blendshape.
    pub fn retarget_through(
        &self,
        character: &Character,
        name: &str,
        map: Option<&faceanim_retarget::RetargetMap>,
    ) -> Result<Retarget, ClipError> {
        let routes = by_name::Routes::new(&self.blendshapes, character, map);
        let unreached = self.unreached(&routes);
        if unreached.len() == self.blendshapes.len() && !self.blendshapes.is_empty() {
            return Err(ClipError::NothingInCommon {
                character: character.name().to_owned(),
                clip: self
                    .blendshapes
                    .iter()
                    .take(5)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let weights = self.frames.iter().map(|row| routes.weights(row)).collect();
        let times = (0..self.frames.len())
            .map(|f| f as f32 / self.fps)
            .collect();
        Ok(Retarget {
            animation: MorphAnimation {
                name: name.to_owned(),
                times,
                weights,
                rotations: self
                    .head
                    .as_ref()
                    .map(|head| head.iter().map(|&h| head_rotation(h)).collect()),
            },
            unmatched: self.names_of(unreached.into_iter()),
        })
    }
}

/// The ARKit channels that move somewhere in `rows` (ARKit's 52 per frame, as
/// [`Clip::arkit`] keeps them) and that no column named `names` carries: what a clip of those
/// columns keeps the values of, and what those values give another character.
#[must_use]
pub fn left_out(names: &[String], rows: &[Vec<f32>]) -> Vec<faceanim_rig::names::Channel> {
    faceanim_rig::name_map::NameMap::from_names(names, &[])
        .undriven_channels()
        .into_iter()
        .filter(|c| {
            rows.iter()
                .any(|row| row.get(c.index()).is_some_and(|v| *v != 0.0))
        })
        .collect()
}

/// The problems of `rows`, the per-frame list `field`: its length against the `frames`, each
/// row's against `width` (how many values, and what they are for) where given, and its first
/// value that is not a finite number.
fn row_problems<R: AsRef<[f32]>>(
    field: &str,
    rows: &[R],
    frames: usize,
    width: Option<(usize, &str)>,
) -> Vec<String> {
    let mut problems: Vec<String> = count_problem(field, rows.len(), "rows", frames)
        .into_iter()
        .collect();
    for (f, row) in rows.iter().enumerate() {
        let row = row.as_ref();
        if let Some((width, of)) = width
            && row.len() != width
        {
            problems.push(format!("{field}[{f}]: {} values for {of}", row.len()));
        }
        if let Some(k) = row.iter().position(|x| !x.is_finite()) {
            problems.push(format!("{field}[{f}][{k}]: not a finite number"));
        }
    }
    problems
}

/// The problem of a per-frame list `field` holding `len` `what` for `frames` frames, if its
/// length is not the frames'.
fn count_problem(field: &str, len: usize, what: &str, frames: usize) -> Option<String> {
    (len != frames).then(|| format!("{field}: {len} {what} for {frames} frames"))
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "weights are copied exactly")]
mod tests {
    use super::*;

    #[test]
    fn every_problem_is_listed_with_its_path() {
        let json = br#"{"fps": 0, "blendshapes": ["a", "a"], "frames": [[0.1, 0.2], [0.3]], "head": [[0, 0, 0]]}"#;
        let Err(ClipError::Invalid(problems)) = Clip::from_json(json) else {
            panic!("accepted a bad clip")
        };
        assert_eq!(
            problems,
            vec![
                "fps: must be a positive number, found 0",
                "blendshapes[1]: 'a' appears twice",
                "frames[1]: 1 weights for 2 blendshapes",
                "head: 1 rows for 2 frames",
            ]
        );
    }

    /// The ARKit values a clip keeps: one row of 52 a frame, checked with their paths, and
    /// written and read back as they are.
    #[test]
    fn the_arkit_values_a_clip_keeps_are_checked_and_kept() {
        let mut clip = Clip::of_weights(30.0, &["Fcl_MTH_A"], vec![vec![0.2], vec![0.4]]);
        let mut row = vec![0.0; 52];
        row[3] = 0.5;
        clip.arkit = Some(vec![row.clone(), row.clone()]);
        let back = Clip::from_json(clip.to_json().as_bytes()).unwrap();
        assert_eq!(back, clip);
        assert_eq!(back.arkit_clip().unwrap().frames[1][3], 0.5);
        let mut short = row.clone();
        short.pop();
        let mut broken = row;
        broken[7] = f32::NAN;
        clip.arkit = Some(vec![short, broken.clone(), broken]);
        let Err(ClipError::Invalid(problems)) = clip.validate() else {
            panic!("accepted bad ARKit values")
        };
        assert_eq!(
            problems,
            vec![
                "arkit: 3 rows for 2 frames",
                "arkit[0]: 51 values for ARKit's 52 channels",
                "arkit[1][7]: not a finite number",
                "arkit[2][7]: not a finite number",
            ]
        );
    }

    #[test]
    fn unknown_fields_are_refused() {
        let json = br#"{"fps": 30, "blendshapes": [], "frames": [[]], "weights": []}"#;
        assert!(
            matches!(Clip::from_json(json), Err(ClipError::Syntax(m)) if m.contains("unknown field `weights`"))
        );
    }

    /// A character of one triangle with blendshapes called `names`.
    fn character_of(names: &[&str]) -> Character {
        use faceanim_rig::{Blendshape, CharacterParts};
        use glam::Vec3;
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let blendshapes = names
            .iter()
            .map(|&n| Blendshape::from_dense(n, &[Vec3::ZERO, Vec3::ZERO, Vec3::Y], 1e-6))
            .collect();
        Character::new(CharacterParts {
            name: "tri".into(),
            positions,
            triangles: vec![[0, 1, 2]],
            blendshapes,
            ..CharacterParts::default()
        })
        .unwrap()
    }

    /// A take's kept ARKit values reach another character's shapes for what its columns leave
    /// out, and nothing more of the character it was made on.
    #[test]
    fn kept_values_reach_another_characters_shapes_only() {
        let index = |name: &str| faceanim_rig::names::Channel::named(name).unwrap().index();
        let mut take = Clip::of_weights(30.0, &["Fcl_EYE_Close_L"], vec![vec![0.5]]);
        let mut made_of = vec![0.0; 52];
        made_of[index("eyeBlinkLeft")] = 0.9;
        made_of[index("eyeLookInLeft")] = 0.3;
        take.arkit = Some(vec![made_of]);
        let vroid = character_of(&["Fcl_EYE_Close_L", "Fcl_MTH_A"]);
        assert!(matches!(
            take.for_character(&vroid),
            std::borrow::Cow::Borrowed(_)
        ));
        let head = character_of(&["eyeBlink_L", "eyeLookIn_L", "eyeLookOut_L"]);
        let widened = take.for_character(&head);
        assert_eq!(widened.blendshapes, ["Fcl_EYE_Close_L", "eyeLookInLeft"]);
        let weights = &widened.retarget(&head, "take").unwrap().animation.weights[0];
        assert_eq!(weights, &[0.5, 0.3, 0.0]);
        // Widened once is widened: nothing joins twice.
        assert!(matches!(
            widened.for_character(&head),
            std::borrow::Cow::Borrowed(_)
        ));
    }

    /// A clip of one frame: `columns` (name, value).
    fn clip_of(columns: &[(&str, f32)]) -> Clip {
        Clip {
            fps: 30.0,
            blendshapes: columns.iter().map(|(n, _)| (*n).to_owned()).collect(),
            frames: vec![columns.iter().map(|(_, v)| *v).collect()],
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }

    #[test]
    fn columns_answering_to_one_blendshape_do_not_overwrite_it() {
        let character = character_of(&["eyeBlinkLeft"]);
        // The exact name fills it, wherever it stands.
        let exact = clip_of(&[("eyeBlink_L", 0.25), ("eyeBlinkLeft", 0.75)])
            .retarget(&character, "t")
            .unwrap();
        assert_eq!(exact.animation.weights[0], [0.75]);
        assert_eq!(exact.unmatched, ["eyeBlink_L"]);
        // Two spellings, neither exact: ARKit's own, as capture by name reads them.
        for columns in [
            [("eyeBlink_L", 0.25), ("EyeBlinkLeft", 0.75)],
            [("EyeBlinkLeft", 0.75), ("eyeBlink_L", 0.25)],
        ] {
            let first = clip_of(&columns).retarget(&character, "t").unwrap();
            assert_eq!(first.animation.weights[0], [0.75]);
        }
    }

    /// A clip in one rig's names goes onto another's as capture by name would: VRM's pairs and
    /// vowels, split halves, merged shapes; what reaches nothing is named.
    #[test]
    fn columns_reach_a_rig_by_the_name_tables_meaning() {
        let weights = |names: &[&str], columns: &[(&str, f32)]| {
            let retarget = clip_of(columns)
                .retarget(&character_of(names), "t")
                .unwrap();
            (retarget.animation.weights[0].clone(), retarget.unmatched)
        };
        // A VRM Animation's expressions on an ARKit head: happy both corners, aa the jaw (the
        // channel it is made of, where no column carries it); relaxed and surprised, whose
        // channels this head lacks, nothing.
        let arkit = ["mouthSmileLeft", "mouthSmileRight", "jawOpen"];
        assert_eq!(
            weights(
                &arkit,
                &[
                    ("happy", 0.5),
                    ("aa", 0.25),
                    ("relaxed", 1.0),
                    ("surprised", 1.0)
                ]
            ),
            (
                vec![0.5, 0.5, 0.25],
                vec!["relaxed".to_owned(), "surprised".to_owned()]
            )
        );
        assert_eq!(
            weights(&arkit, &[("aa", 0.25), ("JawOpen", 0.75)]).0,
            [0.0, 0.0, 0.75]
        );
        // The same on a VRoid face: the vowel its own shape, the smiles its merged one.
        let vroid = ["Fcl_MTH_A", "Fcl_MTH_Joy"];
        assert_eq!(
            weights(
                &vroid,
                &[
                    ("aa", 0.25),
                    ("mouthSmileLeft", 0.5),
                    ("mouthSmileRight", 1.0)
                ]
            )
            .0,
            [0.25, 0.75]
        );
        // VRM's whole-face presets on a face with the channels they stand for: `surprised`
        // the brows and the eyes it is read from, `relaxed` (VRM 0.x's `Fun`) the cheeks; a
        // column of the channel itself wins.
        let face = [
            "browInnerUp",
            "eyeWideLeft",
            "eyeWideRight",
            "cheekSquintLeft",
            "cheekSquintRight",
        ];
        assert_eq!(
            weights(&face, &[("surprised", 0.5), ("relaxed", 0.75)]),
            (vec![0.5, 0.5, 0.5, 0.75, 0.75], vec![])
        );
        assert_eq!(
            weights(
                &face,
                &[("Fun", 0.75), ("eyeWideLeft", 0.25), ("Surprised", 0.5)]
            )
            .0,
            [0.5, 0.25, 0.5, 0.75, 0.75]
        );
        // A VRM 0.x clip on a VRM avatar (its presets read under VRM 1.0's names): each preset
        // its own expression; a column of the expression's own name wins.
        let avatar = ["relaxed", "happy", "blink", "blinkLeft"];
        assert_eq!(
            weights(&avatar, &[("Fun", 0.25), ("Joy", 0.5), ("Blink", 1.0)]),
            (vec![0.25, 0.5, 1.0, 0.0], vec![])
        );
        assert_eq!(
            weights(&avatar, &[("Fun", 0.25), ("relaxed", 0.75)]).0,
            [0.75, 0.0, 0.0, 0.0]
        );
        // ICT's halves onto ARKit's one channel, and ARKit's one channel onto ICT's halves.
        assert_eq!(
            weights(
                &["browInnerUp"],
                &[("browInnerUp_L", 0.5), ("browInnerUp_R", 1.0)]
            )
            .0,
            [0.75]
        );
        assert_eq!(
            weights(&["browInnerUp_L", "browInnerUp_R"], &[("BrowInnerUp", 0.5)]).0,
            [0.5, 0.5]
        );
        // Nothing in common is an error.
        let none = clip_of(&[("relaxed", 1.0)]).retarget(&character_of(&arkit), "t");
        assert!(matches!(none, Err(ClipError::NothingInCommon { .. })));
    }

    /// An ARKit clip on a rig whose names say nothing reaches it through its retarget map.
    #[test]
    fn arkit_columns_reach_a_rig_whose_names_say_nothing_through_its_map() {
        let character = character_of(&["shape_1", "shape_2"]);
        let clip = clip_of(&[("JawOpen", 0.5), ("EyeBlinkLeft", 1.0)]);
        assert!(matches!(
            clip.retarget(&character, "t"),
            Err(ClipError::NothingInCommon { .. })
        ));
        // Its ARKit channels are lost by name (what a map carries); the rig's own names and
        // names of no meaning are not ARKit's.
        assert!(clip.loses_arkit(&character));
        assert!(!clip_of(&[("shape_1", 1.0), ("Extra", 1.0)]).loses_arkit(&character));
        let names = character.blendshape_names();
        let mut map = faceanim_retarget::RetargetMap::by_name("tri", &names, &[]);
        map.set_row("jawOpen", [("shape_2".to_owned(), 0.8)].into())
            .unwrap();
        let through = clip.retarget_through(&character, "t", Some(&map)).unwrap();
        assert_eq!(through.animation.weights[0], [0.0, 0.4]);
        assert_eq!(through.unmatched, ["EyeBlinkLeft"]);
        assert_eq!(clip.unmatched(&character, Some(&map)), ["EyeBlinkLeft"]);
        // A column at 0 throughout loses nothing: it is not warned of.
        let still = clip_of(&[("JawOpen", 0.5), ("EyeBlinkLeft", 0.0)]);
        assert!(still.unmatched(&character, Some(&map)).is_empty());
        // A map of other shapes is not used.
        let other = faceanim_retarget::RetargetMap::by_name("x", &names[..1], &[]);
        assert!(
            clip.retarget_through(&character, "t", Some(&other))
                .is_err()
        );
    }

    #[test]
    fn round_trips_through_json() {
        let clip = Clip {
            fps: 24.0,
            blendshapes: vec!["jawOpen".into()],
            frames: vec![vec![0.0], vec![1.0]],
            head: Some(vec![[1.0, 2.0, 3.0]; 2]),
            head_position: Some(vec![[0.0, 0.1, -0.5]; 2]),
            presence: Some(vec![1.0, 0.0]),
            arkit: None,
        };
        assert_eq!(Clip::from_json(clip.to_json().as_bytes()), Ok(clip));
    }

    proptest::proptest! {
        /// Every weight and head angle a clip holds (any finite f32) reads back bit for bit
        /// from its JSON: a saved take is the take.
        #[test]
        fn any_value_reads_back_exactly(
            values in proptest::collection::vec(
                proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO,
                1..64,
            ),
        ) {
            let clip = Clip {
                fps: 30.0,
                blendshapes: vec!["a".into()],
                frames: values.iter().map(|v| vec![*v]).collect(),
                head: Some(values.iter().map(|v| [*v, -*v, v * 0.5]).collect()),
                head_position: None,
                presence: None,
                arkit: None,
            };
            proptest::prop_assert_eq!(Clip::from_json(clip.to_json().as_bytes()), Ok(clip));
        }
    }
}
