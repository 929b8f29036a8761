//! The character's own training set: random weight vectors, each rendered and run through the
//! capture pipeline, giving (expression, weights) pairs, with the neutral face of the same
//! camera and light for each.
//!
//! The crop comes from the known camera, not from the detector: the neutral face is found once
//! in a front render (detector, then the tracker's rule for the region, so training sees the
//! crops tracking will give at run time) and kept as a [`FaceFrame`] in the world. Samples come
//! in groups of [`augment::GROUP`] sharing a [`Condition`] (camera, light, skin, background,
//! picture quality — see [`augment`]); each group's neutral is rendered under its condition,
//! and each sample straight into its jittered crop at the landmark network's 256×256. Groups
//! render and run in parallel, one per core.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use faceanim_render::{Appearance, Camera};
use faceanim_rig::{Character, Pose};
use faceanim_track::{FaceModels, Frame, Region};
use rand::SeedableRng as _;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::augment::{self, Augmentation, Condition, FaceFrame, Jitter};
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

/// Where the character's face is, and how the character looks to the renderer.
#[derive(Debug, Clone)]
pub struct FaceCamera {
    face: FaceFrame,
    appearance: Appearance,
    /// How the crop was found.
    pub framing: Framing,
}

impl FaceCamera {
    /// Frames the character's face: renders it neutral from the front, finds the face, and
    /// keeps the tracker's crop around it as a square in the world.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails.
    pub fn frame(character: &Character, models: &FaceModels) -> Result<FaceCamera, AdaptError> {
        let appearance = Appearance::of(character);
        let bounds = character.head_bounds();
        let camera = Camera::front(&bounds, 0.75);
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
        // The crop's square on the plane of the face (a little behind the tip of the nose).
        let extent = bounds.max - bounds.min;
        let plane = glam::Vec3::new(
            bounds.center().x,
            bounds.center().y,
            bounds.max.z - 0.15 * extent.z,
        );
        let on_face = |x: f32, y: f32| camera.unproject(size, x, y, plane);
        let half = region.size / 2.0;
        let face = match (
            on_face(region.cx, region.cy),
            on_face(region.cx - half, region.cy),
            on_face(region.cx + half, region.cy),
        ) {
            (Some(centre), Some(left), Some(right)) => FaceFrame {
                centre,
                side: left.distance(right),
                distance: camera.eye.distance(centre),
                depth: centre.z - bounds.min.z,
            },
            _ => {
                return Err(AdaptError::Training(
                    "the front camera cannot be inverted".into(),
                ));
            }
        };
        Ok(FaceCamera {
            face,
            appearance,
            framing,
        })
    }

    /// Where the face is in the world.
    #[must_use]
    pub fn face(&self) -> FaceFrame {
        self.face
    }

    /// The 256×256 face crop of `pose` from the front in the studio's light, as the landmark
    /// network gets it.
    #[must_use]
    pub fn crop(&self, character: &Character, pose: &Pose) -> faceanim_render::Image {
        let camera = Condition::canonical().camera(&self.face, Jitter::NONE);
        faceanim_render::render(character, pose, &camera, &self.appearance, CROP)
    }

    /// The 256×256 crop of `pose` under `condition`, its crop placed by `jitter`, degraded as
    /// the condition says (`rng` draws the noise).
    #[must_use]
    pub fn picture(
        &self,
        character: &Character,
        pose: &Pose,
        condition: &Condition,
        jitter: Jitter,
        rng: &mut impl rand::Rng,
    ) -> faceanim_render::Image {
        let camera = condition.camera(&self.face, jitter);
        let image = faceanim_render::render_shaded(
            character,
            pose,
            &camera,
            &self.appearance,
            &condition.shading,
            condition.resolution.min(CROP),
        );
        condition.degrade(image, CROP, rng)
    }

    /// Textures the renderer could not use.
    #[must_use]
    pub fn warnings(&self) -> &[String] {
        self.appearance.warnings()
    }

    /// The expression the capture pipeline reads from `character` at `weights`, from the front
    /// in the studio's light, and the face presence; `None` when the landmarks are degenerate.
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
        read(models, &image)
    }
}

/// What the capture pipeline reads from a 256×256 crop: the expression (`None` when the
/// landmarks are degenerate) and the face presence.
fn read(
    models: &FaceModels,
    image: &faceanim_render::Image,
) -> Result<(Option<Expression>, f32), AdaptError> {
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

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetOptions {
    /// Number of weight vectors ([`crate::DEFAULT_SAMPLES`] where the user does not say; the
    /// seed renders 10,000).
    pub samples: usize,
    /// Random seed.
    pub seed: u64,
    /// Shapes never active together.
    pub exclusive: Vec<ExclusivePair>,
    /// Whether camera, light and picture vary.
    pub augmentation: Augmentation,
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
    /// The neutral face of each group's condition.
    pub neutrals: Vec<Expression>,
    /// Per sample, its neutral in [`Dataset::neutrals`].
    pub neutral_of: Vec<usize>,
    /// Per group (one per neutral): whether it was rendered from the front in the studio's
    /// light at full quality — every group without augmentation, one in
    /// [`augment::FRONT_EVERY`] with it, so a set always measures the project's plain renders.
    pub front: Vec<bool>,
    /// The exclusive pairs used.
    pub exclusive: Vec<ExclusivePair>,
    /// Whether camera, light and picture varied.
    pub augmentation: Augmentation,
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
        // The front render's neutral is the same for every front group: read it once.
        let front_neutral = read(models, &camera.crop(character, &character.pose(&[])))?.0;
        let varied = options.augmentation == Augmentation::Randomised;
        let groups: Vec<Group> = draws
            .par_chunks(augment::GROUP)
            .enumerate()
            .map_init(Pose::default, |pose, (index, weights)| {
                if control.cancelled() {
                    return Err(AdaptError::Cancelled);
                }
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                    options.seed ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                );
                let front = !varied || index % augment::FRONT_EVERY == 0;
                let condition = if front {
                    Condition::canonical()
                } else {
                    Condition::draw(&mut rng)
                };
                let face = camera.face();
                let mut at = |w: &[f32], jitter: Jitter, rng: &mut rand_chacha::ChaCha8Rng| {
                    character.pose_into(w, pose);
                    condition.identity.apply(&face, &mut pose.positions);
                    read(
                        models,
                        &camera.picture(character, pose, &condition, jitter, rng),
                    )
                };
                let neutral = if front {
                    front_neutral.clone()
                } else {
                    at(&[], Jitter::NONE, &mut rng)?.0
                };
                let mut samples = Vec::with_capacity(weights.len());
                for w in weights {
                    let jitter = if varied {
                        Jitter::draw(&mut rng, !front)
                    } else {
                        Jitter::NONE
                    };
                    samples.push(at(w, jitter, &mut rng)?);
                }
                let group = Group {
                    front,
                    neutral,
                    samples,
                };
                (control.progress)(
                    done.fetch_add(weights.len(), Ordering::Relaxed) + weights.len(),
                    total,
                );
                Ok(group)
            })
            .collect::<Result<_, AdaptError>>()?;
        let mut dataset = Dataset {
            blendshapes: character.blendshape_names(),
            fingerprint: Fingerprint::of(character),
            seed: options.seed,
            drawn: options.samples,
            targets: Vec::with_capacity(total),
            expressions: Vec::with_capacity(total),
            presence: Vec::with_capacity(total),
            neutrals: Vec::with_capacity(groups.len()),
            neutral_of: Vec::with_capacity(total),
            front: Vec::with_capacity(groups.len()),
            exclusive: options.exclusive.clone(),
            augmentation: options.augmentation,
        };
        for (weights, group) in draws.chunks(augment::GROUP).zip(groups) {
            // A group whose neutral face was not read cannot be calibrated: it is left out.
            let Some(neutral) = group.neutral else {
                continue;
            };
            let index = dataset.neutrals.len();
            dataset.neutrals.push(neutral);
            dataset.front.push(group.front);
            for (weights, (expression, presence)) in weights.iter().zip(group.samples) {
                if let Some(expression) = expression {
                    dataset.targets.push(weights.clone());
                    dataset.expressions.push(expression);
                    dataset.presence.push(presence);
                    dataset.neutral_of.push(index);
                }
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
            && self.augmentation == options.augmentation
    }

    /// Whether sample `index` was rendered from the front in the studio's light.
    #[must_use]
    pub fn is_front(&self, index: usize) -> bool {
        self.front[self.neutral_of[index]]
    }

    /// The neutral face of sample `index`'s camera and light.
    #[must_use]
    pub fn neutral(&self, index: usize) -> &Expression {
        &self.neutrals[self.neutral_of[index]]
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
        let (scores, landmarks) = columns(&self.expressions);
        let (neutral_scores, neutral_landmarks) = columns(&self.neutrals);
        // Indices are far below 2^24, where f32 holds every integer.
        let neutral_of: Vec<f32> = self.neutral_of.iter().map(|&i| i as f32).collect();
        let front: Vec<f32> = self.front.iter().map(|&f| f32::from(u8::from(f))).collect();
        let groups = self.neutrals.len();
        use crate::tensors::json;
        let mut metadata = HashMap::new();
        metadata.insert("format".to_owned(), DATASET_FORMAT.to_owned());
        metadata.insert("augmentation".to_owned(), json(&self.augmentation)?);
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
                ("neutral_scores", &neutral_scores, &[groups, SCORES]),
                (
                    "neutral_landmarks",
                    &neutral_landmarks,
                    &[groups, LANDMARK_COORDINATES],
                ),
                ("neutral_of", &neutral_of, &[n]),
                ("front", &front, &[groups]),
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
        let (neutral_scores, [g, gs]) = file.matrix("neutral_scores")?;
        let (neutral_landmarks, [gl, gll]) = file.matrix("neutral_landmarks")?;
        let neutral_of = file.vector("neutral_of")?;
        let front = file.vector("front")?;
        if ns != n
            || nl != n
            || presence.len() != n
            || neutral_of.len() != n
            || front.len() != g
            || s != SCORES
            || l != LANDMARK_COORDINATES
            || gs != SCORES
            || gl != g
            || gll != LANDMARK_COORDINATES
        {
            return Err(AdaptError::Format(
                "the tensors disagree on the number of samples or features".into(),
            ));
        }
        let neutral_of: Vec<usize> = neutral_of
            .iter()
            .map(|&i| {
                (i >= 0.0 && i.fract() == 0.0 && (i as usize) < g)
                    .then_some(i as usize)
                    .ok_or_else(|| {
                        AdaptError::Format(format!("neutral_of holds {i}, not one of {g} groups"))
                    })
            })
            .collect::<Result<_, _>>()?;
        let expressions = |scores: &[f32], landmarks: &[f32]| -> Vec<Expression> {
            scores
                .chunks(SCORES)
                .zip(landmarks.chunks(LANDMARK_COORDINATES))
                .map(|(s, l)| Expression {
                    scores: s.to_vec(),
                    landmarks: l.to_vec(),
                })
                .collect()
        };
        Ok(Dataset {
            blendshapes,
            fingerprint: file.metadata_json("fingerprint")?,
            seed: file.metadata_json("seed")?,
            drawn: file.metadata_json("drawn")?,
            targets: targets.chunks(b.max(1)).map(<[f32]>::to_vec).collect(),
            expressions: expressions(&scores, &landmarks),
            presence,
            neutrals: expressions(&neutral_scores, &neutral_landmarks),
            neutral_of,
            front: front.iter().map(|&f| f > 0.5).collect(),
            exclusive: file.metadata_json("exclusive")?,
            augmentation: file.metadata_json("augmentation")?,
        })
    }
}

/// The file format, and the recipe of the renders: bumped whenever either changes (a new
/// augmentation, other ranges), so a cached training set from before is rendered again.
const DATASET_FORMAT: &str = "faceanim-dataset-5";

/// The scores and the landmarks of `expressions`, each as one row-major matrix.
fn columns(expressions: &[Expression]) -> (Vec<f32>, Vec<f32>) {
    let scores = expressions.iter().flat_map(|e| e.scores.iter().copied());
    let landmarks = expressions.iter().flat_map(|e| e.landmarks.iter().copied());
    (scores.collect(), landmarks.collect())
}

/// One group's reads: its neutral and its samples.
struct Group {
    front: bool,
    neutral: Option<Expression>,
    samples: Vec<(Option<Expression>, f32)>,
}
