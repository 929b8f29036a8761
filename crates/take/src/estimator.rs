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
    /// MediaPipe's scores through the character's retarget map (by name and by geometry,
    /// calibrated on the character).
    Retarget,
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
            EstimatorSource::Retarget => "retarget map",
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
    /// The retarget map it reads ARKit's channels through, when it does (what else reads the
    /// same take, a jaw bone's turn, measures on it).
    fn retarget_map(&self) -> Option<&faceanim_retarget::RetargetMap> {
        None
    }
}

/// By-name estimates: each of the character's blendshapes whose name means ARKit channels
/// (in any convention of [`faceanim_rig::names`]: ARKit, ICT's and Character Creator's splits,
/// VRoid's `Fcl_*`, VRM presets, visemes) gets them from MediaPipe's scores, under the rule of
/// [`faceanim_rig::name_map`] that nothing moves twice: a split shape (`browInnerUp_L`) gets its
/// channel, a merged one (`mouthSmile`, `blink`) the mean of its pair, an expression (`aa`,
/// `surprised`) its formula.
#[derive(Debug, Clone)]
pub struct ByName {
    map: faceanim_rig::name_map::NameMap,
    names: Vec<String>,
    /// How many shapes MediaPipe's scores reach (it has no tongueOut).
    driven: usize,
}

impl ByName {
    /// The mapping onto `character`'s shapes.
    #[must_use]
    pub fn new(character: &Character) -> ByName {
        let map = character.name_map();
        let scored =
            |c: faceanim_rig::names::Channel| faceanim_track::BLENDSHAPE_NAMES.contains(&c.name());
        let driven = map
            .entries()
            .iter()
            .flatten()
            .filter(|e| {
                e.used == faceanim_rig::name_map::Use::Driven
                    && e.drive.channels().into_iter().any(scored)
            })
            .count();
        ByName {
            map,
            names: character.blendshape_names(),
            driven,
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
        let score = |name: &str| {
            faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .position(|n| *n == name)
                .and_then(|i| expression.scores.get(i))
                .copied()
                .unwrap_or(0.0)
                .clamp(0.0, 1.0)
        };
        self.map.weights_from_channels(score)
    }

    fn source(&self) -> EstimatorSource {
        EstimatorSource::ByName
    }

    fn driven(&self) -> usize {
        self.driven
    }
}

/// Estimates through a character's retarget map ([`faceanim_retarget::RetargetMap`]): each
/// MediaPipe score, as it rises above the face's neutral one, becomes a channel value (times
/// the gain the map's calibration measured on the character); the map puts the channels on
/// the character's own shapes — by name where the names say it, by geometry where they do
/// not.
#[derive(Debug, Clone)]
pub struct Retargeted {
    map: std::sync::Arc<faceanim_retarget::RetargetMap>,
    /// For each ARKit channel, its index in MediaPipe's scores (none for `tongueOut`).
    score_of: Vec<Option<usize>>,
}

impl Retargeted {
    /// Estimates through `map`.
    #[must_use]
    pub fn new(map: std::sync::Arc<faceanim_retarget::RetargetMap>) -> Retargeted {
        let score_of = faceanim_rig::names::ARKIT_52
            .iter()
            .map(|c| faceanim_track::BLENDSHAPE_NAMES.iter().position(|n| n == c))
            .collect();
        Retargeted { map, score_of }
    }

    /// The map.
    #[must_use]
    pub fn map(&self) -> &faceanim_retarget::RetargetMap {
        &self.map
    }

    /// ARKit's 52 channel values for `expression` read against `neutral` (each score's rise
    /// above the neutral face's; the score itself without one), times the map's calibrated gain
    /// where it has one; the gaze's scores are read as they are.
    #[must_use]
    pub fn channels(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        let score = |e: &Expression, c: usize| {
            self.score_of[c]
                .and_then(|i| e.scores.get(i))
                .copied()
                .unwrap_or(0.0)
        };
        let rise = |name: &str| {
            let Some(c) = faceanim_retarget::channel_index(name) else {
                return 0.0;
            };
            // Where the eyes look is no expression over a resting face: looking at the
            // camera is rest, whatever the neutral frame's eyes did.
            let base = match neutral {
                Some(n) if !faceanim_rig::names::is_gaze(name) => score(n, c),
                _ => 0.0,
            };
            score(expression, c) - base
        };
        let values = match &self.map.calibration {
            Some(calibration) => calibration.values(rise),
            None => faceanim_rig::names::ARKIT_52
                .iter()
                .map(|name| rise(name).clamp(0.0, 1.0))
                .collect(),
        };
        // Nor is it calibrated: MediaPipe reads a person's gaze as it reads a render's.
        values
            .into_iter()
            .zip(faceanim_rig::names::ARKIT_52)
            .map(|(v, name)| {
                if faceanim_rig::names::is_gaze(name) {
                    rise(name).clamp(0.0, 1.0)
                } else {
                    v
                }
            })
            .collect()
    }
}

impl Estimator for Retargeted {
    fn blendshapes(&self) -> &[String] {
        &self.map.blendshapes
    }

    fn estimate(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        self.map.weights(&self.channels(expression, neutral))
    }

    /// A map reads each score's rise above the take's neutral face.
    fn calibrated(&self) -> bool {
        true
    }

    fn source(&self) -> EstimatorSource {
        EstimatorSource::Retarget
    }

    fn retarget_map(&self) -> Option<&faceanim_retarget::RetargetMap> {
        Some(&self.map)
    }

    fn driven(&self) -> usize {
        let mut moved = vec![false; self.map.blendshapes.len()];
        for row in &self.map.rows {
            for name in row.shapes.keys() {
                if let Some(i) = self.map.blendshapes.iter().position(|b| b == name) {
                    moved[i] = true;
                }
            }
        }
        if let Some(solve) = &self.map.solve {
            for name in &solve.shapes {
                if let Some(i) = self.map.blendshapes.iter().position(|b| b == name) {
                    moved[i] = true;
                }
            }
        }
        moved.iter().filter(|m| **m).count()
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
            6,
            "every preset with a clear mapping, not relaxed, nor a blink or Fcl_EYE_Close whose eyes blinkLeft and blinkRight carry"
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
