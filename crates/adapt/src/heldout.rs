//! Measuring an adapter (or any estimator: a retarget map) on pictures it never saw: stills of the character made by another
//! renderer (Blender, three.js, a game engine) with the weights each was posed at.
//!
//! A folder holds the pictures and `truth.json`:
//!
//! ```json
//! {
//!   "neutral": "neutral.png",
//!   "frames": [
//!     { "image": "0000.png", "weights": { "jawOpen": 0.7, "shape_12": 0.3 } },
//!     { "image": "0001.png", "weights": [0.0, 0.2, 0.9] }
//!   ]
//! }
//! ```
//!
//! Weights are given by blendshape name (names left out are 0) or as an array in the
//! character's blendshape order. `neutral` (optional) is a picture of the neutral face under
//! the same camera and light; without it each part of the face (lids, gaze, brows, mouth) is
//! taken from the still where it is calmest, as for a take. Every picture goes through capture
//! as a photo does (the detector on each, no temporal filter).

use std::path::{Path, PathBuf};

use faceanim_track::{FaceModels, Frame, Tracker, TrackingMode};
use rayon::prelude::*;
use serde::Serialize;

use crate::AdaptError;
use crate::features::Expression;
use faceanim_take::Estimator;

/// The truth file's name in a held-out folder.
pub const TRUTH: &str = "truth.json";

/// One still and the weights it was posed at.
#[derive(Debug, Clone, PartialEq)]
pub struct Still {
    /// The picture.
    pub image: PathBuf,
    /// One weight per blendshape, in the character's order.
    pub weights: Vec<f32>,
}

/// A held-out folder, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// The folder.
    pub dir: PathBuf,
    /// The stills.
    pub stills: Vec<Still>,
    /// The neutral picture, when the folder has one.
    pub neutral: Option<PathBuf>,
}

/// Where the neutral face of an evaluation came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NeutralSource {
    /// The folder's neutral picture.
    Given,
    /// Each part of the face from the still where it is calmest
    /// ([`faceanim_take::expression::rest_face`]).
    Calmest,
    /// Fewer than two stills had a face: the adapter's typical neutral was used.
    Typical,
}

/// How an adapter did on a held-out folder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// The folder.
    pub dir: PathBuf,
    /// Stills in it.
    pub stills: usize,
    /// Stills where a face was found (the MAE is over these).
    pub faces: usize,
    /// Mean absolute error of the adapter's weights.
    pub mae: f32,
    /// The MAE of always answering the stills' mean weights.
    pub mae_mean_baseline: f32,
    /// The MAE of always answering zeros.
    pub mae_zero_baseline: f32,
    /// Where the neutral face came from.
    pub neutral: NeutralSource,
    /// Per blendshape: name, MAE and mean signed error (bias), worst first.
    pub worst: Vec<(String, f32, f32)>,
    /// The MAE per sampling group of the stills' truths (one, two, three or many shapes).
    pub groups: Vec<crate::sampling::GroupError>,
}

fn bad(path: &Path, message: impl std::fmt::Display) -> AdaptError {
    AdaptError::Format(format!("{}: {message}", path.display()))
}

impl HeldOut {
    /// Reads `dir/truth.json` for a character with `blendshapes`.
    ///
    /// # Errors
    /// [`AdaptError::Format`] naming the file and the field that is wrong.
    pub fn read(dir: &Path, blendshapes: &[String]) -> Result<HeldOut, AdaptError> {
        let path = dir.join(TRUTH);
        let bytes = std::fs::read(&path).map_err(|e| bad(&path, e))?;
        let root: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| bad(&path, format!("not JSON: {e}")))?;
        let neutral = match root.get("neutral") {
            None | Some(serde_json::Value::Null) => None,
            Some(serde_json::Value::String(name)) => Some(dir.join(name)),
            Some(_) => return Err(bad(&path, "neutral: must be a picture's file name")),
        };
        let frames = root
            .get("frames")
            .and_then(serde_json::Value::as_array)
            .ok_or_else(|| bad(&path, "frames: an array of {image, weights} is needed"))?;
        let mut stills = Vec::with_capacity(frames.len());
        for (k, frame) in frames.iter().enumerate() {
            let at = |field: &str, message: String| {
                bad(&path, format!("frames[{k}].{field}: {message}"))
            };
            let image = frame
                .get("image")
                .and_then(serde_json::Value::as_str)
                .ok_or_else(|| at("image", "a picture's file name is needed".into()))?;
            let mut weights = vec![0.0f32; blendshapes.len()];
            match frame.get("weights") {
                Some(serde_json::Value::Object(named)) => {
                    for (name, value) in named {
                        let b = blendshapes.iter().position(|n| n == name).ok_or_else(|| {
                            at(
                                "weights",
                                format!("the character has no blendshape '{name}'"),
                            )
                        })?;
                        weights[b] = weight(value).ok_or_else(|| {
                            at(
                                "weights",
                                format!("{name}: {value} is not a weight in 0..1"),
                            )
                        })?;
                    }
                }
                Some(serde_json::Value::Array(values)) => {
                    if values.len() != blendshapes.len() {
                        return Err(at(
                            "weights",
                            format!(
                                "{} values for {} blendshapes",
                                values.len(),
                                blendshapes.len()
                            ),
                        ));
                    }
                    for (b, value) in values.iter().enumerate() {
                        weights[b] = weight(value).ok_or_else(|| {
                            at("weights", format!("[{b}]: {value} is not a weight in 0..1"))
                        })?;
                    }
                }
                _ => {
                    return Err(at(
                        "weights",
                        "an object of name → weight or an array is needed".into(),
                    ));
                }
            }
            stills.push(Still {
                image: dir.join(image),
                weights,
            });
        }
        if stills.is_empty() {
            return Err(bad(&path, "frames: there are none"));
        }
        Ok(HeldOut {
            dir: dir.to_owned(),
            stills,
            neutral,
        })
    }

    /// Runs every still through capture (the detector on each, the stills spread over the
    /// cores) and `estimator` (an adapter, a retarget map).
    ///
    /// # Errors
    /// [`AdaptError::Format`] for a picture that cannot be read, [`AdaptError::Model`] if a
    /// network fails.
    pub fn evaluate(
        &self,
        estimator: &dyn Estimator,
        models: &FaceModels,
    ) -> Result<Evaluation, AdaptError> {
        let read = |path: &Path| -> Result<Option<Expression>, AdaptError> {
            let image =
                faceanim_media::read_image(path).map_err(|e| AdaptError::Format(e.to_string()))?;
            let frame = Frame {
                width: image.width,
                height: image.height,
                rgb: &image.rgb,
            };
            let mut tracker = Tracker::new(models, TrackingMode::DetectEveryFrame);
            Ok(tracker.next_frame(&frame)?.and_then(|(face, _)| {
                let scores: Vec<f32> = face.scores.iter().map(|s| s.1).collect();
                Expression::from_face(
                    &scores,
                    &face.landmarks,
                    face.pose.map(|p| [p.yaw, p.pitch, p.roll]),
                )
            }))
        };
        // Each still on its own, so on every core.
        let expressions: Vec<Option<Expression>> = self
            .stills
            .par_iter()
            .map(|s| read(&s.image))
            .collect::<Result<_, _>>()?;
        let (neutral, source) = match &self.neutral {
            Some(path) => match read(path)? {
                Some(e) => (Some(e), NeutralSource::Given),
                None => {
                    return Err(bad(path, "no face was found in the neutral picture"));
                }
            },
            None => {
                let faces: Vec<Option<&Expression>> =
                    expressions.iter().map(Option::as_ref).collect();
                match faceanim_take::expression::calmest_parts(&faces) {
                    Some(parts) => (
                        faceanim_take::expression::rest_face(&faces, parts),
                        NeutralSource::Calmest,
                    ),
                    None => (None, NeutralSource::Typical),
                }
            }
        };
        let n = estimator.blendshapes().len();
        let found: Vec<(&Still, Vec<f32>)> = self
            .stills
            .iter()
            .zip(&expressions)
            .filter_map(|(s, e)| Some((s, estimator.estimate(e.as_ref()?, neutral.as_ref()))))
            .collect();
        let count = found.len().max(1) as f32;
        let mut mean = vec![0.0f32; n];
        for (s, _) in &found {
            mean.iter_mut()
                .zip(&s.weights)
                .for_each(|(m, w)| *m += w / count);
        }
        let (mut error, mut bias, mut mean_error, mut zero_error) =
            (vec![0.0f32; n], vec![0.0f32; n], 0.0f32, 0.0f32);
        for (s, predicted) in &found {
            for b in 0..n {
                let d = predicted[b] - s.weights[b];
                error[b] += d.abs() / count;
                bias[b] += d / count;
                mean_error += (mean[b] - s.weights[b]).abs();
                zero_error += s.weights[b].abs();
            }
        }
        let cells = (count * n.max(1) as f32).max(1.0);
        let mut worst: Vec<(String, f32, f32)> = estimator
            .blendshapes()
            .iter()
            .zip(error.iter().zip(&bias))
            .map(|(name, (&e, &b))| (name.clone(), e, b))
            .collect();
        worst.sort_by(|a, b| b.1.total_cmp(&a.1));
        worst.truncate(8);
        let groups = crate::sampling::errors_by_group(
            found
                .iter()
                .map(|(s, p)| (s.weights.as_slice(), p.as_slice())),
        );
        Ok(Evaluation {
            dir: self.dir.clone(),
            stills: self.stills.len(),
            faces: found.len(),
            mae: error.iter().sum::<f32>() / n.max(1) as f32,
            mae_mean_baseline: mean_error / cells,
            mae_zero_baseline: zero_error / cells,
            neutral: source,
            worst,
            groups,
        })
    }
}

fn weight(value: &serde_json::Value) -> Option<f32> {
    let w = value.as_f64()? as f32;
    (0.0..=1.0).contains(&w).then_some(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        ["jawOpen", "shape_2", "shape_3"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect()
    }

    fn read(truth: &str) -> Result<HeldOut, AdaptError> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(TRUTH), truth).unwrap();
        HeldOut::read(dir.path(), &names())
    }

    #[test]
    fn weights_by_name_or_in_order() {
        let folder = read(
            r#"{"neutral": "n.png", "frames": [
                {"image": "a.png", "weights": {"shape_3": 0.5}},
                {"image": "b.png", "weights": [0.25, 0, 1]}]}"#,
        )
        .unwrap();
        assert_eq!(folder.stills[0].weights, vec![0.0, 0.0, 0.5]);
        assert_eq!(folder.stills[1].weights, vec![0.25, 0.0, 1.0]);
        assert!(folder.neutral.unwrap().ends_with("n.png"));
        assert!(folder.stills[1].image.ends_with("b.png"));
    }

    #[test]
    fn a_bad_truth_file_is_refused_naming_the_field() {
        for (truth, expected) in [
            ("{", "truth.json: not JSON"),
            (r#"{"frames": 3}"#, "frames: an array"),
            (r#"{"frames": []}"#, "frames: there are none"),
            (r#"{"frames": [{"weights": {}}]}"#, "frames[0].image"),
            (
                r#"{"frames": [{"image": "a.png", "weights": {"smile": 1}}]}"#,
                "frames[0].weights: the character has no blendshape 'smile'",
            ),
            (
                r#"{"frames": [{"image": "a.png", "weights": {"jawOpen": 1.5}}]}"#,
                "jawOpen: 1.5 is not a weight in 0..1",
            ),
            (
                r#"{"frames": [{"image": "a.png", "weights": [0.5]}]}"#,
                "1 values for 3 blendshapes",
            ),
            (
                r#"{"neutral": 4, "frames": [{"image": "a.png", "weights": []}]}"#,
                "neutral: must be a picture's file name",
            ),
        ] {
            let error = read(truth).unwrap_err().to_string();
            assert!(error.contains(expected), "{truth}: {error}");
        }
        let missing = HeldOut::read(std::path::Path::new("/no/such/folder"), &names())
            .unwrap_err()
            .to_string();
        assert!(missing.contains("/no/such/folder/truth.json"), "{missing}");
    }
}
