//! What capture can drive on the character: each shape shown alone, at half and at full
//! weight, from the front in the studio's light, read back through the capture pipeline and
//! the adapter.
//!
//! Capture sees a face through MediaPipe's landmarks and scores. A shape that barely moves
//! them (a cheek puff, a dimple, a jaw pushed forward, on most heads) cannot be captured,
//! whatever the adapter: the animator sketches it or corrects frames instead, and should know
//! which shapes those are before recording a take. The test MAE cannot tell: it is an average
//! over every shape of random faces, where a shape that is always read as 0 costs little.
//!
//! The front render in the studio's light is the easiest picture there is; a shape not read
//! there is not read from a webcam either.

use faceanim_rig::{Character, Pose};
use faceanim_track::FaceModels;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{AdaptError, Adapter, FaceCamera};

/// At full weight, the adapter gives a shape shown alone at least this: [`Reading::Read`].
pub const READ: f32 = 0.5;
/// At full weight, at least this (and under [`READ`]): [`Reading::Weak`].
pub const WEAK: f32 = 0.15;

/// How capture drives one shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reading {
    /// Shown alone at full weight, read at [`READ`] or more.
    Read,
    /// Read, but at less than [`READ`] of its weight: capture under-plays it.
    Weak,
    /// Not read (under [`WEAK`]): capture cannot drive it.
    Unseen,
}

impl Reading {
    /// The class of a shape the adapter reads at `at_full` when it is alone at weight 1.
    #[must_use]
    pub fn of(at_full: f32) -> Reading {
        if at_full >= READ {
            Reading::Read
        } else if at_full >= WEAK {
            Reading::Weak
        } else {
            Reading::Unseen
        }
    }
}

/// Another shape the adapter moves when one is shown alone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OtherShape {
    /// Its name.
    pub name: String,
    /// The weight the adapter gives it.
    pub weight: f32,
}

/// How the adapter reads one shape shown alone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeReading {
    /// The shape's name.
    pub name: String,
    /// The adapter's weight for it when it is alone at 0.5.
    pub at_half: f32,
    /// The adapter's weight for it when it is alone at 1.
    pub at_full: f32,
    /// At full weight, the other shape the adapter gives most (none when it gives the others
    /// nothing).
    pub largest_other: Option<OtherShape>,
    /// The class of `at_full`.
    pub reading: Reading,
}

impl FaceCamera {
    /// Every shape of `character` shown alone at 0.5 and 1 and read by `adapter` relative to
    /// the neutral face of the same render, in the character's order. Shapes render in
    /// parallel.
    ///
    /// # Errors
    /// [`AdaptError::Mismatch`] when `adapter` is not for `character`, [`AdaptError::Model`]
    /// if a network fails, [`AdaptError::NoNeutralFace`] when the neutral render has no face
    /// to read.
    pub fn readings(
        &self,
        character: &Character,
        models: &FaceModels,
        adapter: &Adapter,
    ) -> Result<Vec<ShapeReading>, AdaptError> {
        adapter.check(character)?;
        let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
        let count = names.len();
        let Some(neutral) = self
            .expression(character, models, &[], &mut Pose::default())?
            .0
        else {
            return Err(AdaptError::NoNeutralFace);
        };
        (0..count)
            .into_par_iter()
            .map_init(Pose::default, |pose, shape| {
                let mut read_at = |weight: f32| -> Result<Vec<f32>, AdaptError> {
                    let mut weights = vec![0.0; count];
                    weights[shape] = weight;
                    Ok(
                        match self.expression(character, models, &weights, pose)?.0 {
                            Some(expression) => adapter.predict(&expression, Some(&neutral)),
                            // Landmarks too degenerate to use: capture gives nothing either.
                            None => vec![0.0; count],
                        },
                    )
                };
                let half = read_at(0.5)?;
                let full = read_at(1.0)?;
                let largest_other = full
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != shape)
                    .max_by(|a, b| a.1.total_cmp(b.1))
                    .filter(|(_, w)| **w > 0.0)
                    .map(|(k, w)| OtherShape {
                        name: names[k].to_owned(),
                        weight: *w,
                    });
                Ok(ShapeReading {
                    name: names[shape].to_owned(),
                    at_half: half[shape],
                    at_full: full[shape],
                    largest_other,
                    reading: Reading::of(full[shape]),
                })
            })
            .collect()
    }
}

impl FaceCamera {
    /// Each row of `performer`'s weights shown from the front (this camera must frame the
    /// performer) and read by `adapter`, another character's, relative to the performer's
    /// neutral face: what the adapter's character does when the performer does that. Lip
    /// sync reads visemes this way for a rig whose names say nothing of a mouth.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails, [`AdaptError::NoNeutralFace`] when the
    /// performer's neutral render has no face to read.
    pub fn read_performer(
        &self,
        performer: &Character,
        models: &FaceModels,
        adapter: &Adapter,
        rows: &[Vec<f32>],
    ) -> Result<Vec<Vec<f32>>, AdaptError> {
        let mut pose = Pose::default();
        let Some(neutral) = self.expression(performer, models, &[], &mut pose)?.0 else {
            return Err(AdaptError::NoNeutralFace);
        };
        rows.iter()
            .map(|row| {
                Ok(
                    match self.expression(performer, models, row, &mut pose)?.0 {
                        Some(expression) => adapter.predict(&expression, Some(&neutral)),
                        None => vec![0.0; adapter.blendshapes.len()],
                    },
                )
            })
            .collect()
    }
}

/// The names of the shapes in `readings` that capture cannot drive.
#[must_use]
pub fn unseen(readings: &[ShapeReading]) -> Vec<&str> {
    readings
        .iter()
        .filter(|r| r.reading == Reading::Unseen)
        .map(|r| r.name.as_str())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readings_are_classed_by_the_full_weight() {
        assert_eq!(Reading::of(1.0), Reading::Read);
        assert_eq!(Reading::of(READ), Reading::Read);
        assert_eq!(Reading::of(0.49), Reading::Weak);
        assert_eq!(Reading::of(WEAK), Reading::Weak);
        assert_eq!(Reading::of(0.1), Reading::Unseen);
        assert_eq!(Reading::of(0.0), Reading::Unseen);
    }
}
