//! The neutral face of a live performance: the face a calibrated estimator reads every frame
//! relative to. The performer presses Calibrate with a relaxed face (the next frame with a face
//! becomes the neutral, whole), or holds still: after [`STILL_SECONDS`] of a face that barely
//! moves, its mean becomes the neutral when there is none yet; a later still face replaces
//! each part of it ([`FacePart`]: lids, gaze, brows, mouth) that it holds calmer, as a take's
//! automatic neutral takes each part from its own calmest frame ([`rest_face`]) — a performer
//! seldom holds still with every part at rest at once. A neutral the performer chose is never
//! replaced automatically.

use std::collections::VecDeque;

use crate::expression::{Expression, FacePart, PartFrames, rest_face};
use crate::session::NeutralChoice;

/// How long a face must stay still to be taken as the neutral one, seconds.
pub const STILL_SECONDS: f32 = 1.5;
/// The most a still face's pose-normalised landmarks may move: the root mean square distance
/// of each frame's from their mean, in units of the face's own spread (landmark noise of a
/// webcam is about a third of it; speaking or smiling moves them several times as much).
pub const STILL_SPREAD: f32 = 0.015;
/// How much less expression energy a part of a new still face needs to replace that part of an
/// automatic neutral.
const BETTER_BY: f32 = 0.05;

/// The live neutral face. See the module docs.
#[derive(Debug, Clone, Default)]
pub struct LiveNeutral {
    neutral: Option<(Expression, NeutralChoice)>,
    /// An automatic neutral's still faces, one per part in [`FacePart::ALL`]'s order: each
    /// part's calmest so far.
    still_parts: Vec<Expression>,
    pending: bool,
    window: VecDeque<(f32, Expression)>,
}

impl LiveNeutral {
    /// The next frame with a face becomes the neutral (the performer's Calibrate).
    pub fn calibrate(&mut self) {
        self.pending = true;
    }

    /// Whether Calibrate was pressed and no face has come since.
    #[must_use]
    pub fn pending(&self) -> bool {
        self.pending
    }

    /// The neutral face, once there is one.
    #[must_use]
    pub fn neutral(&self) -> Option<&Expression> {
        self.neutral.as_ref().map(|(e, _)| e)
    }

    /// Who chose the neutral, once there is one.
    #[must_use]
    pub fn chosen(&self) -> Option<NeutralChoice> {
        self.neutral.as_ref().map(|(_, c)| *c)
    }

    /// Takes in the frame at `time` seconds: its expression, or `None` without a face.
    pub fn observe(&mut self, time: f32, expression: Option<&Expression>) {
        let Some(expression) = expression else {
            self.window.clear();
            return;
        };
        if self.pending {
            self.pending = false;
            self.window.clear();
            self.still_parts.clear();
            self.neutral = Some((expression.clone(), NeutralChoice::User));
            return;
        }
        self.window.push_back((time, expression.clone()));
        while self
            .window
            .front()
            .is_some_and(|(t, _)| *t < time - STILL_SECONDS)
        {
            self.window.pop_front();
        }
        if self.chosen() == Some(NeutralChoice::User) {
            return;
        }
        let Some(&(first, _)) = self.window.front() else {
            return;
        };
        if time - first < 0.9 * STILL_SECONDS || self.window.len() < 8 {
            return;
        }
        let Some(still) = self.still_face() else {
            return;
        };
        if self.still_parts.len() != FacePart::ALL.len() {
            self.still_parts = vec![still.clone(); FacePart::ALL.len()];
            self.neutral = Some((still, NeutralChoice::Automatic));
            self.window.clear();
            return;
        }
        let mut changed = false;
        for (part, calmest) in FacePart::ALL.iter().zip(&mut self.still_parts) {
            if part.energy(&still) < part.energy(calmest) - BETTER_BY {
                *calmest = still.clone();
                changed = true;
            }
        }
        if changed {
            self.window.clear();
            let faces: Vec<Option<&Expression>> = self.still_parts.iter().map(Some).collect();
            let at = |part: FacePart| FacePart::ALL.iter().position(|p| *p == part).unwrap_or(0);
            let parts = PartFrames {
                lids: at(FacePart::Lids),
                gaze: at(FacePart::Gaze),
                brows: at(FacePart::Brows),
                mouth: at(FacePart::Mouth),
            };
            if let Some(rest) = rest_face(&faces, parts) {
                self.neutral = Some((rest, NeutralChoice::Automatic));
            }
        }
    }

    /// The window's mean face when no frame in it strays more than [`STILL_SPREAD`] from it.
    fn still_face(&self) -> Option<Expression> {
        let n = self.window.len() as f32;
        let (_, first) = self.window.front()?;
        let mut mean = Expression {
            scores: vec![0.0; first.scores.len()],
            landmarks: vec![0.0; first.landmarks.len()],
        };
        for (_, e) in &self.window {
            mean.scores
                .iter_mut()
                .zip(&e.scores)
                .for_each(|(m, v)| *m += v / n);
            mean.landmarks
                .iter_mut()
                .zip(&e.landmarks)
                .for_each(|(m, v)| *m += v / n);
        }
        let points = (mean.landmarks.len() / 3).max(1) as f32;
        let still = self.window.iter().all(|(_, e)| {
            let squared: f32 = e
                .landmarks
                .iter()
                .zip(&mean.landmarks)
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            (squared / points).sqrt() <= STILL_SPREAD
        });
        still.then_some(mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expression::{LANDMARK_COORDINATES, SCORES};

    fn face(smile: f32, wobble: f32) -> Expression {
        let mut scores = vec![0.0; SCORES];
        scores[44] = smile;
        Expression {
            scores,
            landmarks: (0..LANDMARK_COORDINATES)
                .map(|k| (k as f32 * 0.1).sin() * 0.1 + wobble * (k as f32).cos())
                .collect(),
        }
    }

    /// A face with these scores set, by MediaPipe's names.
    fn scored(set: &[(&str, f32)]) -> Expression {
        let mut e = face(0.0, 0.0);
        for (name, value) in set {
            let k = faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .position(|n| n == name)
                .unwrap();
            e.scores[k] = *value;
        }
        e
    }

    fn score(e: &Expression, name: &str) -> f32 {
        let k = faceanim_track::BLENDSHAPE_NAMES
            .iter()
            .position(|n| *n == name)
            .unwrap();
        e.scores[k]
    }

    #[test]
    fn each_part_of_the_neutral_comes_from_the_stillness_where_it_was_calmest() {
        let mut live = LiveNeutral::default();
        // Held still with the lids half shut and the mouth at rest...
        let sleepy = scored(&[("eyeBlinkLeft", 0.3), ("eyeBlinkRight", 0.3)]);
        for f in 0..60 {
            live.observe(f as f32 / 30.0, Some(&sleepy));
        }
        assert_eq!(live.chosen(), Some(NeutralChoice::Automatic));
        // ...a moment of talking...
        for f in 60..90 {
            let t = f as f32 / 30.0;
            live.observe(t, Some(&face(0.3, 0.2 * (t * 9.0).sin())));
        }
        // ...then still again, the eyes wide open but smiling: as expressive as a whole, so
        // neither face is the calmer, but each has one part at rest.
        let smiling = scored(&[("mouthSmileLeft", 0.3), ("mouthSmileRight", 0.3)]);
        for f in 90..150 {
            live.observe(f as f32 / 30.0, Some(&smiling));
        }
        let neutral = live.neutral().unwrap();
        for name in [
            "eyeBlinkLeft",
            "eyeBlinkRight",
            "mouthSmileLeft",
            "mouthSmileRight",
        ] {
            assert!(
                score(neutral, name) < 1e-6,
                "{name}: {}",
                score(neutral, name)
            );
        }
        assert_eq!(live.chosen(), Some(NeutralChoice::Automatic));
    }

    #[test]
    fn a_still_face_becomes_the_neutral_and_a_moving_one_does_not() {
        let mut live = LiveNeutral::default();
        // Talking for three seconds at 30 fps: never still.
        for f in 0..90 {
            let t = f as f32 / 30.0;
            live.observe(t, Some(&face(0.3, 0.2 * (t * 9.0).sin())));
        }
        assert_eq!(live.chosen(), None);
        // Held still (a little noise) with a slight smile: taken.
        for f in 90..150 {
            let t = f as f32 / 30.0;
            live.observe(t, Some(&face(0.3, 0.005 * (f as f32).sin())));
        }
        assert_eq!(live.chosen(), Some(NeutralChoice::Automatic));
        let smiling = live.neutral().unwrap().energy();
        // Later, still and relaxed: a better neutral replaces it.
        for f in 150..210 {
            live.observe(f as f32 / 30.0, Some(&face(0.0, 0.0)));
        }
        assert!(live.neutral().unwrap().energy() < smiling - 0.2);
        // Calibrate takes the next face, whatever it is, and nothing replaces it.
        live.calibrate();
        live.observe(7.0, None);
        assert!(live.pending());
        live.observe(7.1, Some(&face(0.5, 0.0)));
        assert_eq!(live.chosen(), Some(NeutralChoice::User));
        for f in 0..90 {
            live.observe(7.2 + f as f32 / 30.0, Some(&face(0.0, 0.0)));
        }
        assert_eq!(live.chosen(), Some(NeutralChoice::User));
        assert!((live.neutral().unwrap().energy() - 0.5).abs() < 1e-6);
    }
}
