//! What the adapter sees of a face: the 52 expression scores, the landmarks with the head pose
//! taken out, or both; absolute, or relative to a neutral face of the same source
//! ([`Calibration`]); the landmarks placed by the whole face or by its rigid part
//! ([`LandmarkFrame`]).
//!
//! The scores alone are blind to what MediaPipe's blendshape model was not trained to name
//! (a character's own shapes, asymmetries, tongue or cheek shapes); the landmarks carry the
//! geometry itself. Landmarks are made independent of where the head is and how it is turned:
//! centred, rotated back by the fitted head pose and scaled to unit spread, so a frontal render
//! and a turned webcam face give comparable numbers.

//!
//! The expression itself ([`Expression`]) belongs to `faceanim-take`, which estimators and
//! sessions share; this module only chooses what of it the adapter reads.

pub use faceanim_take::expression::{Expression, LANDMARK_COORDINATES, RIGID, SCORES, rigid_frame};
use serde::{Deserialize, Serialize};

/// Which features feed the adapter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FeatureSet {
    /// The 52 expression scores.
    Scores,
    /// The pose-normalised landmark coordinates.
    Landmarks,
    /// Both (the default: the best in our ablation).
    #[default]
    Both,
}

impl FeatureSet {
    /// Length of the input vector.
    #[must_use]
    pub fn len(self) -> usize {
        match self {
            FeatureSet::Scores => SCORES,
            FeatureSet::Landmarks => LANDMARK_COORDINATES,
            FeatureSet::Both => SCORES + LANDMARK_COORDINATES,
        }
    }

    /// Never empty; here for clippy's `len` convention.
    #[must_use]
    pub fn is_empty(self) -> bool {
        false
    }

    /// The input vector from the two parts.
    #[must_use]
    pub fn assemble(self, scores: &[f32], landmarks: &[f32]) -> Vec<f32> {
        match self {
            FeatureSet::Scores => scores.to_vec(),
            FeatureSet::Landmarks => landmarks.to_vec(),
            FeatureSet::Both => [scores, landmarks].concat(),
        }
    }

    /// The name used on the command line and in files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            FeatureSet::Scores => "scores",
            FeatureSet::Landmarks => "landmarks",
            FeatureSet::Both => "both",
        }
    }

    /// The adapter's input for `expression`, its landmarks placed by `frame`.
    #[must_use]
    pub fn input(self, frame: LandmarkFrame, expression: &Expression) -> Vec<f32> {
        match frame {
            LandmarkFrame::Whole => self.assemble(&expression.scores, &expression.landmarks),
            LandmarkFrame::Rigid => {
                self.assemble(&expression.scores, &rigid_frame(&expression.landmarks))
            }
        }
    }

    /// How many of the inputs are scores (they come first; the landmarks' coordinates follow,
    /// three per landmark).
    #[must_use]
    pub fn scores(self) -> usize {
        match self {
            FeatureSet::Scores | FeatureSet::Both => SCORES,
            FeatureSet::Landmarks => 0,
        }
    }
}

/// Where the landmarks' origin and unit come from.
///
/// [`Expression`] centres the landmarks on their mean and scales them to unit spread. Both move
/// with the expression: an open jaw lowers the centre and widens the spread, so every eye and
/// brow landmark moves with it, and an adapter reads the mouth into the eyes. Placed by the
/// landmarks that expressions hardly move ([`RIGID`]: the nose's bridge, the eyes' corners, the
/// forehead and temples), an eye landmark moves only when the eye does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum LandmarkFrame {
    /// Centred on all landmarks and scaled by their spread (adapters trained before the rigid
    /// frame existed).
    #[default]
    Whole,
    /// Centred on the [`RIGID`] landmarks and scaled by their spread.
    Rigid,
}

impl LandmarkFrame {
    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            LandmarkFrame::Whole => "whole",
            LandmarkFrame::Rigid => "rigid",
        }
    }
}

/// Whether the adapter reads a face as it is or relative to a neutral face of the same source.
///
/// The seed's expression space is relative to a neutral face; MediaPipe's features are not:
/// a camera, a lens, a light or a face's own build shift them all by a constant. Subtracting
/// the features of a neutral frame taken under the same conditions (a calibration frame of a
/// take, or the neutral render of each training sample's camera and light) removes the shift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Calibration {
    /// Features as captured (adapters trained before calibration existed).
    #[default]
    None,
    /// Features minus the neutral face's.
    Neutral,
}

impl Calibration {
    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Calibration::None => "none",
            Calibration::Neutral => "neutral",
        }
    }

    /// The adapter's input for `expression` read relative to `neutral` (as is without
    /// calibration).
    #[must_use]
    pub fn input(
        self,
        features: FeatureSet,
        frame: LandmarkFrame,
        expression: &Expression,
        neutral: &[f32],
    ) -> Vec<f32> {
        let mut input = features.input(frame, expression);
        if self == Calibration::Neutral {
            input.iter_mut().zip(neutral).for_each(|(v, n)| *v -= n);
        }
        input
    }
}
