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
    /// The weights for `expression`, one per blendshape.
    fn estimate(&self, expression: &Expression) -> Vec<f32>;
    /// Which kind of estimator it is.
    fn source(&self) -> EstimatorSource;
    /// How many of the character's shapes it can move (none for a by-name mapping onto a rig
    /// without ARKit names).
    fn driven(&self) -> usize {
        self.blendshapes().len()
    }
}

/// By-name estimates: each of the character's ARKit-named shapes gets MediaPipe's score.
#[derive(Debug, Clone)]
pub struct ByName {
    /// For each of MediaPipe's scores (in its order), the character's blendshape it drives.
    columns: Vec<Option<usize>>,
    names: Vec<String>,
}

impl ByName {
    /// The mapping onto `character`'s shapes (ARKit spellings such as `eyeBlink_L` match).
    #[must_use]
    pub fn new(character: &Character) -> ByName {
        ByName {
            columns: faceanim_track::BLENDSHAPE_NAMES
                .iter()
                .map(|n| {
                    if n.starts_with('_') {
                        None
                    } else {
                        character.find_blendshape(n).map(|id| id.index())
                    }
                })
                .collect(),
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

    fn estimate(&self, expression: &Expression) -> Vec<f32> {
        let mut row = vec![0.0; self.names.len()];
        for (score, column) in expression.scores.iter().zip(&self.columns) {
            if let Some(c) = column {
                row[*c] = score.clamp(0.0, 1.0);
            }
        }
        row
    }

    fn source(&self) -> EstimatorSource {
        EstimatorSource::ByName
    }

    fn driven(&self) -> usize {
        self.columns.iter().flatten().count()
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "a score copied exactly")]
mod tests {
    use super::*;
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
        let row = by_name.estimate(&Expression {
            scores,
            landmarks: vec![0.0; LANDMARK_COORDINATES],
        });
        let column = character
            .find_blendshape("jawOpen")
            .map(|id| id.index())
            .unwrap_or_default();
        assert_eq!(row[column], 0.625);
        assert_eq!(row.iter().sum::<f32>(), 0.625);
        assert_eq!(by_name.source(), EstimatorSource::ByName);
    }
}
