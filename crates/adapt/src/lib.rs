//! # faceanim-adapt: bring your own character
//!
//! Seed 003 ("Bring Your Own Character", Bai et al.) in Rust: any blendshape character — any
//! number, order and naming of shapes — is animated from a face image or video through a small
//! adapter that learns, from renders of that very character, to turn the capture pipeline's
//! generic expression into the character's own weights.
//!
//! - [`sampling`]: random weight vectors in the seed's groups, exclusive pairs zeroed.
//! - [`dataset`]: each vector rendered and read back by the capture pipeline, with the neutral
//!   face of the same camera and light ([`FaceCamera`], [`Dataset`]).
//! - [`augment`]: domain randomisation of those renders (camera, light, skin, background,
//!   picture quality), so the adapter transfers to pictures it never saw.
//! - [`features`]: what the adapter sees (scores, pose-normalised landmarks, or both), as
//!   captured or relative to a neutral face ([`Calibration`]), the landmarks placed by the
//!   face's rigid part ([`LandmarkFrame`]).
//! - [`locality`]: which inputs each shape reads — only what it moves, so that a person's
//!   mouth does not drive the character's eyes ([`Locality`]).
//! - [`heldout`]: the adapter measured on stills of the character from another renderer.
//! - [`readings`]: which shapes capture can drive, each shown alone and read back.
//! - [`mod@train`] (candle): Adam on a censored absolute error ([`Loss`]; the seed's squared
//!   error on request) with early stopping; fine-tuning from corrections.
//! - [`adapter`]: inference in plain Rust and the safetensors file, bound to its character;
//!   an [`Adapter`] is a [`faceanim_take::Estimator`], so takes and live tracking use it like
//!   the by-name mapping.
//!
//! The human in the loop (sessions, corrections, preference, undo) is `faceanim-take`'s, which
//! needs no training library; fine-tuning reads its corrections.
#![deny(missing_docs)]

pub mod ablation;
pub mod adapter;
pub mod augment;
pub mod bridge;
pub mod calibrate;
pub mod dataset;
pub mod features;
pub mod heldout;
pub mod locality;
pub mod readings;
pub mod sampling;
mod tensors;
pub mod train;

pub use adapter::{Activation, Adapter, Architecture, Base, Fit, TrainingReport, WIDTH_PER_SHAPE};
pub use augment::Augmentation;
pub use dataset::{Control, Dataset, DatasetOptions, FaceCamera, Framing, Split};
pub use faceanim_take::{Correction, Fingerprint};
pub use features::{Calibration, Expression, FeatureSet, LandmarkFrame};
pub use locality::Locality;
pub use readings::{Reading, ShapeReading};
pub use train::{
    DEFAULT_MEMBERS, DEFAULT_SAMPLES, DEFAULT_STAY, FinetuneReport, Loss, TrainOptions, finetune,
    train, train_on,
};

use std::path::{Path, PathBuf};

/// The fewest samples a training set may have: fewer cannot be split into training,
/// validation and test. The command line and the studio refuse fewer before rendering any.
pub const MIN_SAMPLES: usize = 10;

/// Where a character's adapter lives by default: `NAME.adapter.safetensors` in `folder` (the
/// character file's folder), or in the current folder.
#[must_use]
pub fn default_adapter_path(folder: Option<&Path>, character_name: &str) -> PathBuf {
    let file = format!("{character_name}.adapter.safetensors");
    match folder {
        Some(dir) => dir.join(file),
        None => PathBuf::from(file),
    }
}

/// Where the training set behind `adapter` is cached: `NAME.dataset.safetensors` beside it.
#[must_use]
pub fn dataset_cache_path(adapter: &Path) -> PathBuf {
    let name = adapter
        .file_name()
        .map_or_else(|| "adapter".into(), |n| n.to_string_lossy().into_owned());
    let stem = name.strip_suffix(".safetensors").unwrap_or(&name);
    let stem = stem.strip_suffix(".adapter").unwrap_or(stem);
    adapter.with_file_name(format!("{stem}.dataset.safetensors"))
}

/// Why adaptation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AdaptError {
    /// A face network failed.
    #[error(transparent)]
    Model(#[from] faceanim_track::ModelError),
    /// An adapter or dataset file is malformed.
    #[error("{0}")]
    Format(String),
    /// The adapter does not belong to this character.
    #[error(
        "this adapter cannot drive {character}: {reason}; train one for it with `faceanim adapt`"
    )]
    Mismatch {
        /// The character's name.
        character: String,
        /// What differs.
        reason: String,
    },
    /// The training library failed.
    #[error("training failed: {0}")]
    Training(String),
    /// Too few samples to split into training, validation and test.
    #[error("{0} samples are too few to train on")]
    NotEnoughData(usize),
    /// More networks than training samples to share out among them.
    #[error("{members} networks cannot share {training} training samples")]
    TooManyMembers {
        /// Networks asked for.
        members: usize,
        /// Samples in the training split.
        training: usize,
    },
    /// The face model found no face in the character's neutral front render, so its shapes
    /// cannot be read one by one.
    #[error("the face model reads no face in the character's neutral front render")]
    NoNeutralFace,
    /// The user stopped the work.
    #[error("cancelled")]
    Cancelled,
}
