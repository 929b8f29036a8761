//! The generic expression of one face: what capture measured, before any character — the 52
//! expression scores and the landmarks with the head pose taken out.
//!
//! Landmarks are made independent of where the head is and how it is turned: centred, rotated
//! back by the fitted head pose and scaled to unit spread, so a frontal render and a turned
//! webcam face give comparable numbers. Estimators (by name, by a character's adapter) read
//! expressions; sessions keep them for re-estimating and fine-tuning.

use faceanim_track::BLENDSHAPE_LANDMARKS;
use serde::{Deserialize, Serialize};

/// Number of expression scores (MediaPipe's 52, `_neutral` first).
pub const SCORES: usize = 52;
/// Number of landmark coordinates: x, y, z of the blendshape model's 146 landmarks.
pub const LANDMARK_COORDINATES: usize = BLENDSHAPE_LANDMARKS.len() * 3;

/// The generic expression of one face: what capture measured, before any character.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Expression {
    /// The 52 scores in MediaPipe's order.
    pub scores: Vec<f32>,
    /// [`LANDMARK_COORDINATES`] pose-normalised coordinates.
    pub landmarks: Vec<f32>,
}

impl Expression {
    /// From one captured face: its 52 scores, 478 landmarks (image pixels) and head pose
    /// (yaw, pitch, roll in degrees; `None` leaves the rotation in). `None` when the face is
    /// incomplete or degenerate.
    #[must_use]
    pub fn from_face(
        scores: &[f32],
        landmarks: &[[f32; 3]],
        head: Option<[f32; 3]>,
    ) -> Option<Expression> {
        if scores.len() != SCORES || landmarks.len() < 468 {
            return None;
        }
        Some(Expression {
            scores: scores.to_vec(),
            landmarks: normalised_landmarks(landmarks, head)?,
        })
    }

    /// How far the face is from rest: the sum of its 51 ARKit scores (MediaPipe's `_neutral`
    /// left out). A relaxed face scores near 0.
    #[must_use]
    pub fn energy(&self) -> f32 {
        self.scores.iter().skip(1).map(|s| s.clamp(0.0, 1.0)).sum()
    }

    /// From one frame capture recorded (see [`Expression::from_face`]).
    #[must_use]
    pub fn from_record(record: &faceanim_capture::FrameRecord) -> Option<Expression> {
        let scores: Vec<f32> = record.scores.iter().map(|s| s.1).collect();
        Expression::from_face(&scores, &record.landmarks, record.head)
    }
}

/// The frame whose face is nearest to rest (least [`Expression::energy`]), the automatic
/// neutral of a take; `None` when fewer than two frames have a face (a single picture is not
/// read against itself: an adapter then uses the neutral face typical of its training).
#[must_use]
pub fn least_expressive(expressions: &[Option<&Expression>]) -> Option<usize> {
    let faces: Vec<(usize, f32)> = expressions
        .iter()
        .enumerate()
        .filter_map(|(k, e)| e.map(|e| (k, e.energy())))
        .collect();
    if faces.len() < 2 {
        return None;
    }
    faces
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// The blendshape model's landmarks with the pose removed: into a y-up frame, centred on the
/// mean of all landmarks, turned back by the head rotation, divided by their RMS distance from
/// the centre. `None` for non-finite or collapsed landmarks.
#[must_use]
pub fn normalised_landmarks(landmarks: &[[f32; 3]], head: Option<[f32; 3]>) -> Option<Vec<f32>> {
    // Image pixels (y down, z away) to the pose fit's frame (y up, z towards the viewer).
    let points: Vec<glam::Vec3> = landmarks
        .iter()
        .map(|p| glam::Vec3::new(p[0], -p[1], -p[2]))
        .collect();
    if points.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let centre = points.iter().copied().sum::<glam::Vec3>() / points.len() as f32;
    let spread = (points
        .iter()
        .map(|p| (*p - centre).length_squared())
        .sum::<f32>()
        / points.len() as f32)
        .sqrt();
    if spread <= f32::EPSILON {
        return None;
    }
    let unturn = match head {
        Some(angles) => glam::Quat::from_array(faceanim_anim::head_rotation(angles)).inverse(),
        None => glam::Quat::IDENTITY,
    };
    let mut out = Vec::with_capacity(LANDMARK_COORDINATES);
    for &index in &BLENDSHAPE_LANDMARKS {
        let p = unturn * (*points.get(index)? - centre) / spread;
        out.extend_from_slice(&p.to_array());
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_moving_and_scaling_a_face_leaves_its_features() {
        // A made-up face: landmarks on a squashed sphere, deterministic.
        let face: Vec<[f32; 3]> = (0..478)
            .map(|i| {
                let t = i as f32 * 0.37;
                [
                    40.0 * t.sin() * (0.5 * t).cos(),
                    55.0 * (0.5 * t).sin(),
                    30.0 * t.cos(),
                ]
            })
            .collect();
        let head = [25.0, -10.0, 8.0];
        let turn = glam::Quat::from_array(faceanim_anim::head_rotation(head));
        // The same face turned by `head`, scaled 1.7× and moved, in image coordinates.
        let moved: Vec<[f32; 3]> = face
            .iter()
            .map(|p| {
                let fit = glam::Vec3::new(p[0], -p[1], -p[2]);
                let q = turn * fit * 1.7 + glam::Vec3::new(300.0, -200.0, 5.0);
                [q.x, -q.y, -q.z]
            })
            .collect();
        let a = normalised_landmarks(&face, None).unwrap();
        let b = normalised_landmarks(&moved, Some(head)).unwrap();
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-4, "features moved by {worst}");
        assert_eq!(a.len(), LANDMARK_COORDINATES);
    }

    #[test]
    fn degenerate_faces_have_no_features() {
        assert!(normalised_landmarks(&[[1.0, 2.0, 3.0]; 478], None).is_none());
        let mut nan = vec![[0.0, 0.0, 0.0]; 478];
        nan[3] = [f32::NAN, 0.0, 0.0];
        assert!(normalised_landmarks(&nan, None).is_none());
    }
}
