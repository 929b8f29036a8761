//! A trained adapter: the generic expression in, the character's own weights out, and the
//! small file it is kept in.
//!
//! Inference is plain Rust over the stored weights (two small matrix products, well under a
//! tenth of a millisecond), so playing an adapter needs no training library. The file is
//! safetensors: `input_mean`, `input_scale`, `hidden.weight`, `hidden.bias`, `output.weight`,
//! `output.bias`, and metadata naming the blendshapes, the character's fingerprint, the
//! architecture and how training went.

use std::collections::HashMap;

use faceanim_rig::Character;
use serde::{Deserialize, Serialize};

use crate::features::{Calibration, Expression, FeatureSet, LandmarkFrame};
use crate::locality::Locality;
use crate::readings::ShapeReading;
use crate::{AdaptError, Fingerprint};

/// The nonlinearity between the two layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// max(x, 0).
    Relu,
    /// max(x, 0.01·x) (the seed's best).
    #[default]
    LeakyRelu,
}

impl Activation {
    /// The slope for negative inputs.
    #[must_use]
    pub fn negative_slope(self) -> f32 {
        match self {
            Activation::Relu => 0.0,
            Activation::LeakyRelu => 0.01,
        }
    }
}

/// The shape of the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Architecture {
    /// Which features it reads.
    pub features: FeatureSet,
    /// Width of the hidden layer.
    pub hidden: usize,
    /// Nonlinearity between the layers.
    pub activation: Activation,
    /// Whether outputs are clamped to [0, 1] (in training too).
    pub clamp: bool,
    /// Whether it reads faces relative to a neutral one (adapters from before calibration
    /// existed read them as they are).
    #[serde(default)]
    pub calibration: Calibration,
    /// How it places the landmarks (adapters from before read them in the whole face's frame).
    #[serde(default)]
    pub frame: LandmarkFrame,
    /// Which inputs each shape reads (adapters from before read all of them). With
    /// [`Locality::PerShape`], training sets `hidden` to the width per shape times the shapes.
    #[serde(default)]
    pub locality: Locality,
}

/// Hidden units per shape in the default network.
pub const WIDTH_PER_SHAPE: usize = 16;

impl Default for Architecture {
    /// The seed's best, Linear → LeakyReLU → Linear → Clamp over both feature sets, relative to
    /// a neutral face; its landmarks in the rigid frame, and each shape with
    /// [`WIDTH_PER_SHAPE`] hidden units that read only what the shape moves
    /// ([`crate::locality`]).
    fn default() -> Architecture {
        Architecture {
            features: FeatureSet::Both,
            hidden: 256,
            activation: Activation::LeakyRelu,
            clamp: true,
            calibration: Calibration::Neutral,
            frame: LandmarkFrame::Rigid,
            locality: Locality::PerShape {
                width: WIDTH_PER_SHAPE,
            },
        }
    }
}

impl Architecture {
    /// The seed's network: one hidden layer of 256 over every input, landmarks in the whole
    /// face's frame (the adapters before rigid frames and per-shape parts).
    #[must_use]
    pub fn global() -> Architecture {
        Architecture {
            frame: LandmarkFrame::Whole,
            locality: Locality::Global,
            ..Architecture::default()
        }
    }
}

/// How training went, kept in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct TrainingReport {
    /// Mean absolute error on the test split.
    pub mae_test: f32,
    /// Mean absolute error on the validation split (at the kept epoch).
    pub mae_val: f32,
    /// Samples in the dataset.
    pub samples: usize,
    /// Networks averaged, each trained on its own share of the training split
    /// ([`crate::train::DEFAULT_MEMBERS`]); 1 in adapters from before.
    #[serde(default = "one")]
    pub members: usize,
    /// Epochs run (the most of any member).
    pub epochs: usize,
    /// The epoch whose weights were kept (the latest of any member's).
    pub best_epoch: usize,
    /// Seconds spent training.
    pub seconds: f64,
    /// Corrected frames it was fine-tuned on (0 for plain training).
    #[serde(default)]
    pub corrections: usize,
    /// Mean absolute error on the test split's front renders (the studio's light, full
    /// quality): the project's plain renders, also when training varied them
    /// ([`Adapter::front_test_error`]).
    #[serde(default)]
    pub mae_test_front: Option<f32>,
    /// The test split's error per sampling group (one, two or three shapes active, or all of
    /// them): the dense group's floor apart from the sparse groups'. Empty in adapters from
    /// before.
    #[serde(default)]
    pub mae_test_groups: Vec<crate::sampling::GroupError>,
    /// For an adapter on a [`Base`]: how strongly it was held to the map
    /// ([`crate::TrainOptions::stay`]); `None` for one trained alone.
    #[serde(default)]
    pub stay: Option<f64>,
    /// How it reads each shape shown alone ([`FaceCamera::readings`](crate::FaceCamera::readings)),
    /// filled where the character is at hand; empty in adapters from before.
    #[serde(default)]
    pub shapes: Vec<ShapeReading>,
}

fn one() -> usize {
    1
}

/// How a character relates to an adapter that passed [`Adapter::check`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fit {
    /// Trained on this very character.
    Exact,
    /// Same mesh and names, other shape (another identity of the rig, or edited shapes).
    OtherShape,
}

/// A trained adapter.
#[derive(Debug, Clone, PartialEq)]
pub struct Adapter {
    /// The character's blendshape names, one per output.
    pub blendshapes: Vec<String>,
    /// The character it was trained on.
    pub fingerprint: Fingerprint,
    /// Its shape.
    pub architecture: Architecture,
    /// How training went.
    pub report: TrainingReport,
    /// The neutral face's input, used when a face comes without its own neutral (the mean of
    /// the training set's neutral faces; unused without calibration).
    pub(crate) reference_neutral: Vec<f32>,
    /// Per input: subtracted before the first layer (the training set's mean).
    pub(crate) input_mean: Vec<f32>,
    /// Per input: multiplied after subtracting (1 / the training set's deviation).
    pub(crate) input_scale: Vec<f32>,
    /// hidden × inputs, row-major.
    pub(crate) hidden_weight: Vec<f32>,
    pub(crate) hidden_bias: Vec<f32>,
    /// outputs × hidden, row-major.
    pub(crate) output_weight: Vec<f32>,
    pub(crate) output_bias: Vec<f32>,
    /// What the network refines, when it was trained on top of the character's retarget map:
    /// its outputs are added to the map's estimate before the clamp.
    pub(crate) base: Option<Base>,
}

/// The estimate an adapter refines: the character's retarget map (geometry and calibration,
/// no training). Trained on top of it, the network learns only what the map misses — on the
/// seed's dense draws, antagonist shapes that cancel on the face — and starts from a bridge
/// that already follows people.
#[derive(Debug, Clone)]
pub struct Base(faceanim_take::Retargeted);

impl Base {
    /// A base of `map`.
    #[must_use]
    pub fn new(map: faceanim_retarget::RetargetMap) -> Base {
        Base(faceanim_take::Retargeted::new(std::sync::Arc::new(map)))
    }

    /// The map.
    #[must_use]
    pub fn map(&self) -> &faceanim_retarget::RetargetMap {
        self.0.map()
    }

    /// The map's weights for `expression` read against `neutral`.
    #[must_use]
    pub fn estimate(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        faceanim_take::Estimator::estimate(&self.0, expression, neutral)
    }

    /// The map's weights for each of `dataset`'s renders, read against its own neutral.
    pub(crate) fn estimates(&self, dataset: &crate::Dataset) -> Vec<Vec<f32>> {
        dataset
            .expressions
            .iter()
            .enumerate()
            .map(|(k, e)| self.estimate(e, Some(dataset.neutral(k))))
            .collect()
    }
}

impl PartialEq for Base {
    fn eq(&self, other: &Base) -> bool {
        self.map() == other.map()
    }
}

const ADAPTER_FORMAT: &str = "faceanim-adapter-1";

/// Takes, live tracking and re-estimation use an adapter through the take layer's estimator.
impl faceanim_take::Estimator for Adapter {
    fn blendshapes(&self) -> &[String] {
        &self.blendshapes
    }

    fn estimate(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        self.predict(expression, neutral)
    }

    fn calibrated(&self) -> bool {
        self.architecture.calibration == Calibration::Neutral
    }

    fn source(&self) -> faceanim_take::EstimatorSource {
        faceanim_take::EstimatorSource::Adapter
    }
}

impl Adapter {
    /// Number of inputs.
    #[must_use]
    pub fn inputs(&self) -> usize {
        self.input_mean.len()
    }

    /// The map this adapter refines, when it was trained on top of one.
    #[must_use]
    pub fn base(&self) -> Option<&Base> {
        self.base.as_ref()
    }

    /// The character's weights for one input vector (`self.inputs()` long), written to `out`
    /// (one per blendshape). Allocation-free apart from the hidden layer's buffer. For an
    /// adapter on a [`Base`], `base` is the base's estimate for the same face: the network's
    /// outputs are added to it before the clamp.
    pub fn predict_into(&self, input: &[f32], base: Option<&[f32]>, out: &mut [f32]) {
        let hidden = self.architecture.hidden;
        let slope = self.architecture.activation.negative_slope();
        let x: Vec<f32> = input
            .iter()
            .zip(&self.input_mean)
            .zip(&self.input_scale)
            .map(|((v, m), s)| (v - m) * s)
            .collect();
        let mut h = vec![0.0f32; hidden];
        for (k, slot) in h.iter_mut().enumerate() {
            let row = &self.hidden_weight[k * x.len()..(k + 1) * x.len()];
            let z = dot(row, &x) + self.hidden_bias[k];
            *slot = if z >= 0.0 { z } else { slope * z };
        }
        for (o, slot) in out.iter_mut().enumerate().take(self.blendshapes.len()) {
            let row = &self.output_weight[o * hidden..(o + 1) * hidden];
            let under = base.and_then(|b| b.get(o)).copied().unwrap_or(0.0);
            let y = under + dot(row, &h) + self.output_bias[o];
            *slot = if self.architecture.clamp {
                y.clamp(0.0, 1.0)
            } else {
                y
            };
        }
    }

    /// The input vector for `expression`, relative to `neutral` when the adapter is
    /// calibrated (to the training set's typical neutral face when `neutral` is `None`).
    #[must_use]
    pub fn input(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        let Architecture {
            features,
            frame,
            calibration,
            ..
        } = self.architecture;
        let own = neutral.map(|n| features.input(frame, n));
        let neutral = own.as_deref().unwrap_or(&self.reference_neutral);
        calibration.input(features, frame, expression, neutral)
    }

    /// The character's weights for `expression` (see [`Adapter::input`] for `neutral`).
    #[must_use]
    pub fn predict(&self, expression: &Expression, neutral: Option<&Expression>) -> Vec<f32> {
        let base = self.base.as_ref().map(|b| b.estimate(expression, neutral));
        let mut out = vec![0.0; self.blendshapes.len()];
        self.predict_into(&self.input(expression, neutral), base.as_deref(), &mut out);
        out
    }

    /// Mean absolute error over every sample of `dataset` (outputs against rendered weights),
    /// each read relative to its own neutral.
    #[must_use]
    pub fn mean_absolute_error(&self, dataset: &crate::Dataset) -> f32 {
        self.mean_absolute_error_of(dataset, 0..dataset.len())
    }

    /// [`Adapter::mean_absolute_error`] over the samples `indices` (a split's test part, say).
    #[must_use]
    pub fn mean_absolute_error_of(
        &self,
        dataset: &crate::Dataset,
        indices: impl IntoIterator<Item = usize>,
    ) -> f32 {
        let (mut sum, mut count) = (0.0f64, 0usize);
        for k in indices {
            let (Some(expression), Some(target)) =
                (dataset.expressions.get(k), dataset.targets.get(k))
            else {
                continue;
            };
            for (p, t) in self
                .predict(expression, Some(dataset.neutral(k)))
                .iter()
                .zip(target)
            {
                sum += f64::from((p - t).abs());
                count += 1;
            }
        }
        (sum / count.max(1) as f64) as f32
    }

    /// The error per sampling group over `dataset`'s test split.
    #[must_use]
    pub fn test_errors_by_group(
        &self,
        dataset: &crate::Dataset,
    ) -> Vec<crate::sampling::GroupError> {
        let predicted: Vec<(usize, Vec<f32>)> = dataset
            .split()
            .test
            .map(|k| {
                (
                    k,
                    self.predict(&dataset.expressions[k], Some(dataset.neutral(k))),
                )
            })
            .collect();
        crate::sampling::errors_by_group(
            predicted
                .iter()
                .map(|(k, p)| (dataset.targets[*k].as_slice(), p.as_slice())),
        )
    }

    /// [`Adapter::mean_absolute_error`] over the front renders of `dataset`'s test split;
    /// `None` when it has none.
    #[must_use]
    pub fn front_test_error(&self, dataset: &crate::Dataset) -> Option<f32> {
        let front: Vec<usize> = dataset
            .split()
            .test
            .filter(|&k| dataset.is_front(k))
            .collect();
        (!front.is_empty()).then(|| self.mean_absolute_error_of(dataset, front))
    }

    /// Whether this adapter can drive `character`: the same blendshape names in the same
    /// order and the same mesh.
    ///
    /// # Errors
    /// [`AdaptError::Mismatch`] saying what differs.
    pub fn check(&self, character: &Character) -> Result<Fit, AdaptError> {
        let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
        let mismatch = |reason: String| AdaptError::Mismatch {
            character: character.name().to_owned(),
            reason,
        };
        if names != self.blendshapes {
            let missing: Vec<&str> = self
                .blendshapes
                .iter()
                .filter(|n| !names.contains(&n.as_str()))
                .map(String::as_str)
                .take(5)
                .collect();
            let extra: Vec<&str> = names
                .iter()
                .filter(|n| !self.blendshapes.iter().any(|m| m == *n))
                .copied()
                .take(5)
                .collect();
            return Err(mismatch(if missing.is_empty() && extra.is_empty() {
                format!(
                    "the adapter's {} blendshapes are the character's, in another order",
                    names.len()
                )
            } else {
                format!(
                    "the adapter was trained for {} blendshapes, the character has {}; the character lacks {:?} and has {:?} the adapter does not know",
                    self.blendshapes.len(),
                    names.len(),
                    missing,
                    extra
                )
            }));
        }
        let fingerprint = Fingerprint::of(character);
        if fingerprint.topology != self.fingerprint.topology {
            return Err(mismatch(format!(
                "the adapter was trained on another mesh (topology {} here, {} in the adapter)",
                fingerprint.topology, self.fingerprint.topology
            )));
        }
        Ok(if fingerprint.geometry == self.fingerprint.geometry {
            Fit::Exact
        } else {
            Fit::OtherShape
        })
    }

    /// The adapter as a safetensors file.
    ///
    /// # Errors
    /// [`AdaptError::Format`] if serialisation fails.
    pub fn to_bytes(&self) -> Result<Vec<u8>, AdaptError> {
        use crate::tensors::json;
        let mut metadata = HashMap::new();
        metadata.insert("format".to_owned(), ADAPTER_FORMAT.to_owned());
        metadata.insert("blendshapes".to_owned(), json(&self.blendshapes)?);
        metadata.insert("fingerprint".to_owned(), json(&self.fingerprint)?);
        metadata.insert("architecture".to_owned(), json(&self.architecture)?);
        metadata.insert("report".to_owned(), json(&self.report)?);
        if let Some(base) = &self.base {
            metadata.insert("base".to_owned(), base.map().to_json());
        }
        let (inputs, hidden, outputs) = (
            self.inputs(),
            self.architecture.hidden,
            self.blendshapes.len(),
        );
        crate::tensors::write(
            &[
                ("reference_neutral", &self.reference_neutral, &[inputs]),
                ("input_mean", &self.input_mean, &[inputs]),
                ("input_scale", &self.input_scale, &[inputs]),
                ("hidden.weight", &self.hidden_weight, &[hidden, inputs]),
                ("hidden.bias", &self.hidden_bias, &[hidden]),
                ("output.weight", &self.output_weight, &[outputs, hidden]),
                ("output.bias", &self.output_bias, &[outputs]),
            ],
            metadata,
        )
    }

    /// Reads [`Adapter::to_bytes`]'s output, checking every shape.
    ///
    /// # Errors
    /// [`AdaptError::Format`] naming what is missing or inconsistent.
    pub fn from_bytes(bytes: &[u8]) -> Result<Adapter, AdaptError> {
        let file = crate::tensors::Read::new(bytes)?;
        file.expect_format(ADAPTER_FORMAT)?;
        let blendshapes: Vec<String> = file.metadata_json("blendshapes")?;
        let architecture: Architecture = file.metadata_json("architecture")?;
        let input_mean = file.vector("input_mean")?;
        // Adapters from before calibration have none; they never read it.
        let reference_neutral = match architecture.calibration {
            Calibration::Neutral => file.vector("reference_neutral")?,
            Calibration::None => file
                .vector("reference_neutral")
                .unwrap_or_else(|_| vec![0.0; input_mean.len()]),
        };
        let input_scale = file.vector("input_scale")?;
        let (hidden_weight, [h, i]) = file.matrix("hidden.weight")?;
        let hidden_bias = file.vector("hidden.bias")?;
        let (output_weight, [o, h2]) = file.matrix("output.weight")?;
        let output_bias = file.vector("output.bias")?;
        let inputs = architecture.features.len();
        let consistent = input_mean.len() == inputs
            && reference_neutral.len() == inputs
            && input_scale.len() == inputs
            && i == inputs
            && h == architecture.hidden
            && hidden_bias.len() == h
            && h2 == h
            && o == blendshapes.len()
            && output_bias.len() == o;
        if !consistent {
            return Err(AdaptError::Format(format!(
                "tensor shapes do not fit {} inputs ({} features), {} hidden and {} blendshapes",
                inputs,
                architecture.features.name(),
                architecture.hidden,
                blendshapes.len()
            )));
        }
        // Adapters from before, or trained alone, have no base.
        let base = match file.metadata_text("base") {
            Some(text) => Some(Base::new(
                faceanim_retarget::RetargetMap::from_json(text.as_bytes(), &blendshapes)
                    .map_err(|e| AdaptError::Format(format!("metadata 'base': {e}")))?,
            )),
            None => None,
        };
        Ok(Adapter {
            blendshapes,
            fingerprint: file.metadata_json("fingerprint")?,
            architecture,
            report: file.metadata_json("report")?,
            reference_neutral,
            input_mean,
            input_scale,
            hidden_weight,
            hidden_bias,
            output_weight,
            output_bias,
            base,
        })
    }
}

fn dot(a: &[f32], b: &[f32]) -> f32 {
    // Eight independent sums let the compiler vectorise without reassociating floats itself.
    let mut sums = [0.0f32; 8];
    let (a8, a_rest) = a.split_at(a.len() / 8 * 8);
    let (b8, b_rest) = b.split_at(a8.len());
    for (x, y) in a8.chunks_exact(8).zip(b8.chunks_exact(8)) {
        for k in 0..8 {
            sums[k] += x[k] * y[k];
        }
    }
    let tail: f32 = a_rest.iter().zip(b_rest).map(|(x, y)| x * y).sum();
    sums.iter().sum::<f32>() + tail
}
