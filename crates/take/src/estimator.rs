//! Estimators: what turns a frame's generic [`Expression`] into the character's own weights.
//!
//! Two kinds exist, behind one trait: [`ByName`] gives each of the character's ARKit-named
//! shapes MediaPipe's score for it (any ARKit rig works at once), and a character's trained
//! adapter (`faceanim_adapt::Adapter` implements [`Estimator`]) estimates every shape of any
//! rig. Takes, live tracking and re-estimation only ever see the trait.

use faceanim_rig::Character;
use serde::Serialize;

use crate::expression::Expression;

/// Where a take's estimates came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum EstimatorSource {
    /// MediaPipe's scores put on the character's ARKit-named shapes.
    ByName,
    /// The character's adapter.
    Adapter,
    /// Unknown: the take was opened from a session file, which does not say.
    SessionFile,
    /// None: the weights arrived as they are (a VMC stream from a phone or another app).
    Received,
}

impl EstimatorSource {
    /// What it is called in messages.
    #[must_use]
    pub fn noun(self) -> &'static str {
        match self {
            EstimatorSource::ByName => "by-name mapping",
            EstimatorSource::Adapter => "adapter",
            EstimatorSource::SessionFile => "session file",
            EstimatorSource::Received => "received stream",
        }
    }
}

/// Turns expressions into one character's weights.
pub trait Estimator: Send + Sync {
    /// The character's blendshapes, in the order of the weights it returns.
    fn blendshapes(&self) -> &[String];
    /// The weights for `expression`, one per blendshape; `neutral` is a neutral face of the
    /// same source (the same person, camera and light), when one is known.
    fn estimate(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32>;
    /// Whether estimates are read relative to the neutral face (so choosing another neutral
    /// frame changes them).
    fn calibrated(&self) -> bool {
        false
    }
    /// Which kind of estimator it is.
    fn source(&self) -> EstimatorSource;
    /// How many of the character's shapes it can move (none for a by-name mapping onto a rig
    /// without ARKit names).
    fn driven(&self) -> usize {
        self.blendshapes().len()
    }
}

/// By-name estimates: each of the character's ARKit-named shapes gets MediaPipe's score. A
/// character without ARKit names whose blendshapes are VRM expressions (a VRoid or other VRM
/// avatar) gets those derived from the scores where the mapping is clear: `blink`,
/// `blinkLeft`, `blinkRight`; the visemes `aa`, `ih`, `ou`, `ee`, `oh` from the jaw and the
/// mouth's shapes; `happy`, `sad`, `angry`, `surprised`; `lookUp`, `lookDown`, `lookLeft`,
/// `lookRight` (see [`VrmPreset::from_scores`]).
#[derive(Debug, Clone)]
pub struct ByName {
    /// For each of MediaPipe's scores (in its order), the character's blendshape it drives.
    columns: Vec<Option<usize>>,
    /// VRM expressions derived from the scores, with their columns.
    derived: Vec<(usize, VrmPreset)>,
    names: Vec<String>,
}

/// A VRM 1.0 expression preset that by-name capture can drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum VrmPreset {
    /// Both eyes closed.
    Blink,
    /// The character's left eye closed.
    BlinkLeft,
    /// The character's right eye closed.
    BlinkRight,
    /// Viseme "a": an open jaw.
    Aa,
    /// Viseme "i": spread lips, nearly closed.
    Ih,
    /// Viseme "u": pursed lips.
    Ou,
    /// Viseme "e": spread lips, half open.
    Ee,
    /// Viseme "o": rounded lips.
    Oh,
    /// A smile.
    Happy,
    /// Mouth corners down.
    Sad,
    /// Brows down.
    Angry,
    /// Brows up, eyes wide.
    Surprised,
    /// Eyes up.
    LookUp,
    /// Eyes down.
    LookDown,
    /// Eyes to the character's left.
    LookLeft,
    /// Eyes to the character's right.
    LookRight,
}

impl VrmPreset {
    /// The preset a blendshape name spells (VRM 1.0 names, as faceanim imports both versions).
    #[must_use]
    pub fn from_name(name: &str) -> Option<VrmPreset> {
        Some(match name {
            "blink" => VrmPreset::Blink,
            "blinkLeft" => VrmPreset::BlinkLeft,
            "blinkRight" => VrmPreset::BlinkRight,
            "aa" => VrmPreset::Aa,
            "ih" => VrmPreset::Ih,
            "ou" => VrmPreset::Ou,
            "ee" => VrmPreset::Ee,
            "oh" => VrmPreset::Oh,
            "happy" => VrmPreset::Happy,
            "sad" => VrmPreset::Sad,
            "angry" => VrmPreset::Angry,
            "surprised" => VrmPreset::Surprised,
            "lookUp" => VrmPreset::LookUp,
            "lookDown" => VrmPreset::LookDown,
            "lookLeft" => VrmPreset::LookLeft,
            "lookRight" => VrmPreset::LookRight,
            _ => return None,
        })
    }

    /// The expression's weight from MediaPipe's ARKit scores (`score(name)` in [0, 1]).
    /// `split_blinks`: the character also has `blinkLeft` and `blinkRight`, which then carry
    /// the eyes (so `blink` stays 0 and an eye never closes twice).
    #[must_use]
    pub fn from_scores(self, score: impl Fn(&str) -> f32, split_blinks: bool) -> f32 {
        let mean = |a: &str, b: &str| 0.5 * (score(a) + score(b));
        let spread = mean("mouthStretchLeft", "mouthStretchRight");
        let rounded = score("mouthFunnel").max(score("mouthPucker"));
        let value = match self {
            VrmPreset::Blink if split_blinks => 0.0,
            VrmPreset::Blink => mean("eyeBlinkLeft", "eyeBlinkRight"),
            VrmPreset::BlinkLeft => score("eyeBlinkLeft"),
            VrmPreset::BlinkRight => score("eyeBlinkRight"),
            VrmPreset::Aa => score("jawOpen") * (1.0 - rounded),
            VrmPreset::Ih => spread * (1.0 - score("jawOpen")),
            VrmPreset::Ou => score("mouthPucker"),
            VrmPreset::Ee => spread * score("jawOpen"),
            VrmPreset::Oh => score("mouthFunnel"),
            VrmPreset::Happy => mean("mouthSmileLeft", "mouthSmileRight"),
            VrmPreset::Sad => mean("mouthFrownLeft", "mouthFrownRight"),
            VrmPreset::Angry => mean("browDownLeft", "browDownRight"),
            VrmPreset::Surprised => {
                0.5 * score("browInnerUp") + 0.25 * (score("eyeWideLeft") + score("eyeWideRight"))
            }
            VrmPreset::LookUp => mean("eyeLookUpLeft", "eyeLookUpRight"),
            VrmPreset::LookDown => mean("eyeLookDownLeft", "eyeLookDownRight"),
            VrmPreset::LookLeft => mean("eyeLookOutLeft", "eyeLookInRight"),
            VrmPreset::LookRight => mean("eyeLookInLeft", "eyeLookOutRight"),
        };
        value.clamp(0.0, 1.0)
    }
}

impl ByName {
    /// The mapping onto `character`'s shapes (ARKit spellings such as `eyeBlink_L` match).
    #[must_use]
    pub fn new(character: &Character) -> ByName {
        let columns: Vec<Option<usize>> = faceanim_track::BLENDSHAPE_NAMES
            .iter()
            .map(|n| {
                if n.starts_with('_') {
                    None
                } else {
                    character.find_blendshape(n).map(|id| id.index())
                }
            })
            .collect();
        // VRM expressions bind the same targets an ARKit rig's shapes would: derive them only
        // where no ARKit shape is driven, so nothing moves twice.
        let derived = if columns.iter().all(Option::is_none) {
            character
                .blendshapes()
                .iter()
                .enumerate()
                .filter_map(|(c, b)| VrmPreset::from_name(b.name()).map(|p| (c, p)))
                .collect()
        } else {
            Vec::new()
        };
        ByName {
            columns,
            derived,
            names: character
                .blendshapes()
                .iter()
                .map(|b| b.name().to_owned())
                .collect(),
        }
    }
}

impl Estimator for ByName {
    fn blendshapes(&self) -> &[String] {
        &self.names
    }

    /// MediaPipe's scores are trained to read a neutral face as zeros: the neutral frame is
    /// not used.
    fn estimate(&self, expression: &Expression, _neutral: Option<&Expression>) -> Vec<f32> {
        let mut row = vec![0.0; self.names.len()];
        for (score, column) in expression.scores.iter().zip(&self.columns) {
            if let Some(c) = column {
                row[*c] = score.clamp(0.0, 1.0);
            }
        }
        if !self.derived.is_empty() {
            let score = |name: &str| {
                faceanim_track::BLENDSHAPE_NAMES
                    .iter()
                    .position(|n| *n == name)
                    .and_then(|i| expression.scores.get(i))
                    .copied()
                    .unwrap_or(0.0)
                    .clamp(0.0, 1.0)
            };
            let split = [VrmPreset::BlinkLeft, VrmPreset::BlinkRight]
                .iter()
                .all(|p| self.derived.iter().any(|(_, q)| q == p));
            for &(column, preset) in &self.derived {
                row[column] = preset.from_scores(score, split);
            }
        }
        row
    }

    fn source(&self) -> EstimatorSource {
        EstimatorSource::ByName
    }

    fn driven(&self) -> usize {
        self.columns.iter().flatten().count() + self.derived.len()
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "a score copied exactly")]
mod tests {
    use super::*;

    /// A VRM avatar without ARKit names: its expressions follow the face by name.
    #[test]
    fn vrm_expressions_follow_the_face_where_the_mapping_is_clear() {
        use faceanim_rig::glam::Vec3;
        let names = [
            "Fcl_EYE_Close",
            "blink",
            "blinkLeft",
            "blinkRight",
            "aa",
            "oh",
            "happy",
            "lookLeft",
            "relaxed",
        ];
        let shapes = names
            .iter()
            .enumerate()
            .map(|(k, n)| {
                faceanim_rig::Blendshape::from_sparse(*n, vec![k as u32 % 3], vec![Vec3::Y])
            })
            .collect();
        let character = Character::new(faceanim_rig::CharacterParts {
            name: "vrm".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            blendshapes: shapes,
            ..faceanim_rig::CharacterParts::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let by_name = ByName::new(&character);
        assert_eq!(
            by_name.driven(),
            7,
            "every preset with a clear mapping, not relaxed or raw targets"
        );
        let mut scores = vec![0.0; SCORES];
        let set = |scores: &mut Vec<f32>, name: &str, v: f32| {
            let i = faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .position(|n| *n == name)
                .unwrap_or_default();
            scores[i] = v;
        };
        set(&mut scores, "eyeBlinkLeft", 0.9);
        set(&mut scores, "eyeBlinkRight", 0.1);
        set(&mut scores, "jawOpen", 0.8);
        set(&mut scores, "mouthFunnel", 0.25);
        set(&mut scores, "mouthSmileLeft", 0.6);
        set(&mut scores, "mouthSmileRight", 0.4);
        set(&mut scores, "eyeLookOutLeft", 0.7);
        set(&mut scores, "eyeLookInRight", 0.5);
        let row = by_name.estimate(
            &Expression {
                scores,
                landmarks: vec![0.0; LANDMARK_COORDINATES],
            },
            None,
        );
        let at = |n: &str| row[names.iter().position(|m| *m == n).unwrap_or_default()];
        assert_eq!(at("Fcl_EYE_Close"), 0.0);
        assert_eq!(
            at("blink"),
            0.0,
            "the eyes go through blinkLeft and blinkRight"
        );
        assert_eq!((at("blinkLeft"), at("blinkRight")), (0.9, 0.1));
        assert!(
            (at("aa") - 0.6).abs() < 1e-6,
            "jaw open less the rounding: {}",
            at("aa")
        );
        assert_eq!(at("oh"), 0.25);
        assert!((at("happy") - 0.5).abs() < 1e-6);
        assert!((at("lookLeft") - 0.6).abs() < 1e-6);
        assert_eq!(at("relaxed"), 0.0);
    }
    use crate::expression::{LANDMARK_COORDINATES, SCORES};

    #[test]
    fn by_name_puts_each_score_on_its_shape() {
        let character = faceanim_head::default_character();
        let by_name = ByName::new(&character);
        assert_eq!(by_name.driven(), 51, "MediaPipe names 51 ARKit shapes");
        let mut scores = vec![0.0; SCORES];
        let jaw = faceanim_track::BLENDSHAPE_NAMES
            .iter()
            .position(|n| *n == "jawOpen")
            .unwrap_or_default();
        scores[jaw] = 0.625;
        scores[0] = 0.9; // `_neutral` drives nothing
        let row = by_name.estimate(
            &Expression {
                scores,
                landmarks: vec![0.0; LANDMARK_COORDINATES],
            },
            None,
        );
        let column = character
            .find_blendshape("jawOpen")
            .map(|id| id.index())
            .unwrap_or_default();
        assert_eq!(row[column], 0.625);
        assert_eq!(row.iter().sum::<f32>(), 0.625);
        assert_eq!(by_name.source(), EstimatorSource::ByName);
    }
}
