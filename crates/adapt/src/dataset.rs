//! The character's own training set: random weight vectors, each rendered from a fixed front
//! camera and run through the capture pipeline, giving (expression, weights) pairs.
//!
//! The crop comes from the known camera, not from the detector: the neutral face is found once
//! (detector, then the tracker's rule for the region, so training sees the crops tracking will
//! give at run time), and every sample is rendered straight into that square at the landmark
//! network's 256×256. Samples render and run in parallel, one per core.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use faceanim_render::{Appearance, Camera};
use faceanim_rig::{Character, Pose};
use faceanim_track::{FaceModels, Frame, Region};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::features::{Expression, LANDMARK_COORDINATES, SCORES};
use crate::sampling::{ExclusivePair, WeightSampler};
use crate::{AdaptError, Fingerprint};

/// Side of the landmark network's input, in pixels.
const CROP: u32 = 256;
/// Side of the calibration render the neutral face is detected in.
const CALIBRATION: u32 = 512;

/// How the face crop was placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Framing {
    /// From the neutral face's landmarks.
    Detected,
    /// No face was detected in the neutral render; the crop is the middle of the camera's view.
    Assumed,
}

/// The fixed camera every sample is rendered with.
#[derive(Debug, Clone)]
pub struct FaceCamera {
    camera: Camera,
    appearance: Appearance,
    /// How the crop was found.
    pub framing: Framing,
}

impl FaceCamera {
    /// Frames the character's face: renders it neutral, finds the face, and narrows the camera
    /// to the tracker's crop around it.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails.
    pub fn frame(character: &Character, models: &FaceModels) -> Result<FaceCamera, AdaptError> {
        let appearance = Appearance::of(character);
        let camera = Camera::front(&character.head_bounds(), 0.75);
        let neutral = character.pose(&[]);
        let image = faceanim_render::render(character, &neutral, &camera, &appearance, CALIBRATION);
        let frame = Frame {
            width: CALIBRATION as usize,
            height: CALIBRATION as usize,
            rgb: &image.rgb,
        };
        let size = CALIBRATION as f32;
        let (region, framing) = match models.find_face(&frame)? {
            Some(face) => (
                faceanim_track::region_from_landmarks(&face.landmarks),
                Framing::Detected,
            ),
            None => (
                Region {
                    cx: size / 2.0,
                    cy: size / 2.0,
                    size: 0.8 * size,
                    rotation: 0.0,
                },
                Framing::Assumed,
            ),
        };
        Ok(FaceCamera {
            camera: camera.cropped(size, region.cx, region.cy, region.size, region.rotation),
            appearance,
            framing,
        })
    }

    /// The 256×256 face crop of `pose`, as the landmark network gets it.
    #[must_use]
    pub fn crop(&self, character: &Character, pose: &Pose) -> faceanim_render::Image {
        faceanim_render::render(character, pose, &self.camera, &self.appearance, CROP)
    }

    /// Textures the renderer could not use.
    #[must_use]
    pub fn warnings(&self) -> &[String] {
        self.appearance.warnings()
    }

    /// The expression the capture pipeline reads from `character` at `weights`, and the face
    /// presence; `None` when the landmarks are degenerate.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails.
    pub fn expression(
        &self,
        character: &Character,
        models: &FaceModels,
        weights: &[f32],
        pose: &mut Pose,
    ) -> Result<(Option<Expression>, f32), AdaptError> {
        character.pose_into(weights, pose);
        let image = self.crop(character, pose);
        let frame = Frame {
            width: CROP as usize,
            height: CROP as usize,
            rgb: &image.rgb,
        };
        let whole = Region {
            cx: CROP as f32 / 2.0,
            cy: CROP as f32 / 2.0,
            size: CROP as f32,
            rotation: 0.0,
        };
        let face = models.face_in_region(&frame, whole, 1.0)?;
        let scores: Vec<f32> = face.scores.iter().map(|s| s.1).collect();
        let head = face.pose.map(|p| [p.yaw, p.pitch, p.roll]);
        Ok((
            Expression::from_face(&scores, &face.landmarks, head),
            face.presence,
        ))
    }
}

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetOptions {
    /// Number of weight vectors (the seed's 10,000 by default).
    pub samples: usize,
    /// Random seed.
    pub seed: u64,
    /// Shapes never active together.
    pub exclusive: Vec<ExclusivePair>,
}

/// Callbacks for long work: progress (done, total) and a flag that stops it.
#[derive(Clone, Copy)]
pub struct Control<'a> {
    /// Called with (done, total) as work completes, from any thread.
    pub progress: &'a (dyn Fn(usize, usize) + Sync),
    /// Set to stop early; the work then returns [`AdaptError::Cancelled`].
    pub cancel: &'a AtomicBool,
}

impl std::fmt::Debug for Control<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field("cancel", &self.cancel)
            .finish_non_exhaustive()
    }
}

impl Control<'_> {
    /// A control that reports nothing and is never cancelled.
    #[must_use]
    pub fn silent() -> Control<'static> {
        static NEVER: AtomicBool = AtomicBool::new(false);
        Control {
            progress: &|_, _| {},
            cancel: &NEVER,
        }
    }

    pub(crate) fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// Pairs of (the pipeline's expression, the weights that were rendered), in the order drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The character's blendshape names, one per target column.
    pub blendshapes: Vec<String>,
    /// The character it was rendered from.
    pub fingerprint: Fingerprint,
    /// The seed it was drawn with.
    pub seed: u64,
    /// How many vectors were drawn (samples with degenerate landmarks are left out).
    pub drawn: usize,
    /// Rendered weights, one row per sample.
    pub targets: Vec<Vec<f32>>,
    /// What the pipeline read from each render.
    pub expressions: Vec<Expression>,
    /// Face presence of each render.
    pub presence: Vec<f32>,
    /// The exclusive pairs used.
    pub exclusive: Vec<ExclusivePair>,
}

/// Indices of the training, validation and test samples: the seed's 80/10/10 split, in draw
/// order (the draws are random, so the parts are too).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Split {
    /// Training samples.
    pub train: std::ops::Range<usize>,
    /// Validation samples (early stopping).
    pub validation: std::ops::Range<usize>,
    /// Test samples (the reported MAE).
    pub test: std::ops::Range<usize>,
}

impl Split {
    /// 80/10/10 of `n` samples.
    #[must_use]
    pub fn of(n: usize) -> Split {
        let train = n * 8 / 10;
        let validation = n / 10;
        Split {
            train: 0..train,
            validation: train..train + validation,
            test: train + validation..n,
        }
    }
}

impl Dataset {
    /// Renders `options.samples` random expressions of `character` and reads them back
    /// through the capture pipeline.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails, [`AdaptError::Cancelled`] when cancelled.
    pub fn generate(
        character: &Character,
        models: &FaceModels,
        camera: &FaceCamera,
        options: &DatasetOptions,
        control: Control<'_>,
    ) -> Result<Dataset, AdaptError> {
        let count = character.blendshapes().len();
        let sampler = WeightSampler::new(count, &options.exclusive);
        let draws = sampler.draw(options.samples, options.seed);
        let done = AtomicUsize::new(0);
        let total = draws.len();
        let read: Vec<(Option<Expression>, f32)> = draws
            .par_iter()
            .map_init(Pose::default, |pose, weights| {
                if control.cancelled() {
                    return Err(AdaptError::Cancelled);
                }
                let out = camera.expression(character, models, weights, pose)?;
                (control.progress)(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                Ok(out)
            })
            .collect::<Result<_, AdaptError>>()?;
        let mut dataset = Dataset {
            blendshapes: character
                .blendshapes()
                .iter()
                .map(|b| b.name().to_owned())
                .collect(),
            fingerprint: Fingerprint::of(character),
            seed: options.seed,
            drawn: options.samples,
            targets: Vec::with_capacity(total),
            expressions: Vec::with_capacity(total),
            presence: Vec::with_capacity(total),
            exclusive: options.exclusive.clone(),
        };
        for (weights, (expression, presence)) in draws.into_iter().zip(read) {
            if let Some(expression) = expression {
                dataset.targets.push(weights);
                dataset.expressions.push(expression);
                dataset.presence.push(presence);
            }
        }
        Ok(dataset)
    }

    /// Whether this set was rendered from `character` with `options`, so a cached copy can
    /// stand in for rendering it again.
    #[must_use]
    pub fn made_with(&self, character: &Character, options: &DatasetOptions) -> bool {
        self.fingerprint == Fingerprint::of(character)
            && self.blendshapes.len() == character.blendshapes().len()
            && self.seed == options.seed
            && self.drawn == options.samples
            && self.exclusive == options.exclusive
    }

    /// Number of samples kept.
    #[must_use]
    pub fn len(&self) -> usize {
        self.targets.len()
    }

    /// True when no sample was kept.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty()
    }

    /// The split of this dataset.
    #[must_use]
    pub fn split(&self) -> Split {
        Split::of(self.len())
    }

    /// The dataset as a safetensors file (so the features are cached between runs and
    /// readable from Python): tensors `targets`, `scores`, `landmarks`, `presence`; the rest in
    /// the metadata.
    ///
    /// # Errors
    /// [`AdaptError::Format`] if serialisation fails.
    pub fn to_bytes(&self) -> Result<Vec<u8>, AdaptError> {
        let n = self.len();
        let targets: Vec<f32> = self.targets.concat();
        let scores: Vec<f32> = self
            .expressions
            .iter()
            .flat_map(|e| e.scores.iter().copied())
            .collect();
        let landmarks: Vec<f32> = self
            .expressions
            .iter()
            .flat_map(|e| e.landmarks.iter().copied())
            .collect();
        use crate::tensors::json;
        let mut metadata = HashMap::new();
        metadata.insert("format".to_owned(), DATASET_FORMAT.to_owned());
        metadata.insert("blendshapes".to_owned(), json(&self.blendshapes)?);
        metadata.insert("fingerprint".to_owned(), json(&self.fingerprint)?);
        metadata.insert("seed".to_owned(), self.seed.to_string());
        metadata.insert("drawn".to_owned(), self.drawn.to_string());
        metadata.insert("exclusive".to_owned(), json(&self.exclusive)?);
        crate::tensors::write(
            &[
                ("targets", &targets, &[n, self.blendshapes.len()]),
                ("scores", &scores, &[n, SCORES]),
                ("landmarks", &landmarks, &[n, LANDMARK_COORDINATES]),
                ("presence", &self.presence, &[n]),
            ],
            metadata,
        )
    }

    /// Reads [`Dataset::to_bytes`]'s output.
    ///
    /// # Errors
    /// [`AdaptError::Format`] naming what is missing or malformed.
    pub fn from_bytes(bytes: &[u8]) -> Result<Dataset, AdaptError> {
        let file = crate::tensors::Read::new(bytes)?;
        file.expect_format(DATASET_FORMAT)?;
        let blendshapes: Vec<String> = file.metadata_json("blendshapes")?;
        let (targets, [n, b]) = file.matrix("targets")?;
        if b != blendshapes.len() {
            return Err(AdaptError::Format(format!(
                "targets have {b} columns for {} blendshapes",
                blendshapes.len()
            )));
        }
        let (scores, [ns, s]) = file.matrix("scores")?;
        let (landmarks, [nl, l]) = file.matrix("landmarks")?;
        let presence = file.vector("presence")?;
        if ns != n || nl != n || presence.len() != n || s != SCORES || l != LANDMARK_COORDINATES {
            return Err(AdaptError::Format(
                "the tensors disagree on the number of samples or features".into(),
            ));
        }
        Ok(Dataset {
            blendshapes,
            fingerprint: file.metadata_json("fingerprint")?,
            seed: file.metadata_json("seed")?,
            drawn: file.metadata_json("drawn")?,
            targets: targets.chunks(b.max(1)).map(<[f32]>::to_vec).collect(),
            expressions: scores
                .chunks(SCORES)
                .zip(landmarks.chunks(LANDMARK_COORDINATES))
                .map(|(s, l)| Expression {
                    scores: s.to_vec(),
                    landmarks: l.to_vec(),
                })
                .collect(),
            presence,
            exclusive: file.metadata_json("exclusive")?,
        })
    }
}

const DATASET_FORMAT: &str = "faceanim-dataset-1";
