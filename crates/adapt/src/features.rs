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

pub use faceanim_take::expression::{Expression, LANDMARK_COORDINATES, SCORES};
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

/// MediaPipe's landmarks (indices into the 478) that place [`LandmarkFrame::Rigid`]: the nose
/// from bridge to tip, the eyes' inner and outer corners, the forehead and the temples. All are
/// among the blendshape model's landmarks.
pub const RIGID: [usize; 26] = [
    1, 4, 5, 6, 168, 195, 197, 133, 362, 33, 263, 10, 21, 54, 103, 67, 109, 251, 284, 332, 297,
    338, 127, 234, 356, 454,
];

/// `landmarks` (an [`Expression`]'s, three coordinates each) moved and scaled so that the
/// [`RIGID`] ones are centred at the origin with unit spread. A similarity of the whole-face
/// frame, so it can be applied to features recorded in it.
#[must_use]
pub fn rigid_frame(landmarks: &[f32]) -> Vec<f32> {
    let point = |k: usize| {
        landmarks
            .get(3 * k..3 * k + 3)
            .map_or(glam::Vec3::ZERO, glam::Vec3::from_slice)
    };
    let rigid: Vec<glam::Vec3> = faceanim_track::BLENDSHAPE_LANDMARKS
        .iter()
        .enumerate()
        .filter(|(_, l)| RIGID.contains(l))
        .map(|(k, _)| point(k))
        .collect();
    let centre = rigid.iter().copied().sum::<glam::Vec3>() / rigid.len().max(1) as f32;
    let spread = (rigid
        .iter()
        .map(|p| (*p - centre).length_squared())
        .sum::<f32>()
        / rigid.len().max(1) as f32)
        .sqrt();
    let scale = if spread > f32::EPSILON {
        1.0 / spread
    } else {
        1.0
    };
    landmarks
        .chunks_exact(3)
        .flat_map(|p| ((glam::Vec3::from_slice(p) - centre) * scale).to_array())
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rigid_frame_ignores_where_the_face_was_placed_and_how_big_it_was() {
        let landmarks: Vec<f32> = (0..LANDMARK_COORDINATES)
            .map(|k| ((k * 37) % 101) as f32 / 50.0 - 1.0)
            .collect();
        let moved: Vec<f32> = landmarks
            .iter()
            .enumerate()
            .map(|(k, v)| 2.5 * v + [0.3, -1.0, 0.7][k % 3])
            .collect();
        for (a, b) in rigid_frame(&landmarks).iter().zip(rigid_frame(&moved)) {
            assert!((a - b).abs() < 1e-4, "{a} {b}");
        }
    }

    #[test]
    fn an_open_jaw_moves_no_eye_landmark_in_the_rigid_frame() {
        let landmarks: Vec<f32> = (0..LANDMARK_COORDINATES)
            .map(|k| ((k * 53) % 97) as f32 / 40.0 - 1.0)
            .collect();
        // The chin and lower lip drop; nothing else moves.
        let jaw = [17, 14, 152, 148, 176, 377, 400, 84, 314];
        let mut open = landmarks.clone();
        for (k, l) in faceanim_track::BLENDSHAPE_LANDMARKS.iter().enumerate() {
            if jaw.contains(l) {
                open[3 * k + 1] -= 0.8;
            }
        }
        let (before, after) = (rigid_frame(&landmarks), rigid_frame(&open));
        let eye = faceanim_track::BLENDSHAPE_LANDMARKS
            .iter()
            .position(|l| *l == 145)
            .unwrap_or(0);
        assert!((before[3 * eye + 1] - after[3 * eye + 1]).abs() < 1e-6);
    }
}
