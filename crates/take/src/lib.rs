//! # faceanim-take: the take layer
//!
//! Between the animation core (`faceanim-anim`) and the front ends (the studio, the command
//! line): what a captured input becomes once it meets a character, and what the user does to
//! it. It knows no HTTP and no neural network: a character's adapter reaches it through the
//! [`Estimator`] trait, which `faceanim_adapt::Adapter` implements beside [`ByName`].
//!
//! - [`expression`]: the generic expression of one face (scores, pose-normalised landmarks).
//! - [`estimator`]: expressions to the character's own weights, by name or by an adapter.
//! - [`session`]: one input's frames and estimates with the user's [`Edits`] (keyframes,
//!   corrections, preference, smoothing), kept in a JSON file; the animation is derived.
//! - [`take`]: a session being edited with undo and redo, and [`Take::from_capture`].
//! - [`steady`]: frames recorded as they arrived (a phone, a webcam tracked live) put on a
//!   steady rate by their times.
//! - [`calibration`]: a live performer's neutral face (Calibrate, or a face held still); a
//!   take's is made of each part of the face at its calmest frame, or is the frame the user
//!   names ([`Session::set_neutral`]).
//! - [`layer`](mod@layer): the one rule that puts a sketch over a take.
//!
//! ```
//! use faceanim_take::{ByName, Estimator, Filtering, Footage, Take};
//!
//! let character = faceanim_head::default_character();
//! let by_name = ByName::new(&character);
//! // Two frames without a face: the take exists, its weights are zero.
//! let footage = Footage {
//!     source: "empty.mp4".into(),
//!     fps: 30.0,
//!     records: Vec::new(),
//!     frame_names: Vec::new(),
//!     still_frames: None,
//! };
//! let mut take = Take::from_capture(&character, &by_name, footage, Filtering::SEED)?;
//! assert_eq!(take.session.frames.len(), 0);
//! take.edit(|session| {
//!     session.set_filtering(Filtering::new(2, None)?);
//!     Ok(())
//! })?;
//! assert!(take.undo());
//! assert_eq!(take.session.edits.keyframe_every, 5);
//! # Ok::<(), faceanim_take::TakeError>(())
//! ```
#![deny(missing_docs)]

pub mod calibration;
pub mod estimator;
pub mod expression;
mod fingerprint;
pub mod layer;
pub mod session;
pub mod steady;
pub mod take;

pub use estimator::{ByName, Estimator, EstimatorSource, Retargeted};
pub use expression::Expression;
pub use fingerprint::Fingerprint;
pub use layer::{Layered, layer};
pub use session::{
    Correction, EXPRESSIVE_NEUTRAL, Edits, Filtering, Neutral, NeutralCheck, NeutralChoice,
    Session, SessionFrame, peak_animation,
};
pub use steady::Steady;
pub use take::{Footage, ReceivedFrame, Take};

/// Why a take or session refused a change, or a file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TakeError {
    /// A frame number past the last frame.
    #[error("frame {frame} is past the end (the session has {frames} frames, 0 to {})", frames.saturating_sub(1))]
    PastTheEnd {
        /// The frame asked for.
        frame: usize,
        /// How many frames there are.
        frames: usize,
    },
    /// A blendshape name the character does not have.
    #[error("{character} has no blendshape named '{name}'")]
    NoBlendshape {
        /// The character's name.
        character: String,
        /// The name asked for.
        name: String,
    },
    /// A weight outside [0, 1].
    #[error("{name} = {value}: weights are between 0 and 1")]
    OutOfRange {
        /// The blendshape.
        name: String,
        /// The value given.
        value: f32,
    },
    /// A corrected frame cannot stop being a keyframe.
    #[error("frame {frame} is corrected, so it stays a keyframe; remove its corrections first")]
    CorrectedKeyframe {
        /// The frame.
        frame: usize,
    },
    /// The preference is the mean of the corrections: there must be one.
    #[error("preference: correct at least one frame first")]
    NothingCorrected,
    /// A keyframe spacing outside 1 to 1000.
    #[error("keyframe_every: must be between 1 and 1000, got {0}")]
    KeyframeSpacing(usize),
    /// Only a still image becomes a 0 → peak → 0 animation.
    #[error("still_frames: the take is not of a single photo")]
    NotStill,
    /// A photo's animation length outside 1 to 10,000 frames.
    #[error("still_frames: must be between 1 and 10000, got {0}")]
    StillFrames(usize),
    /// One Euro settings that are not usable.
    #[error("smoothing: {0}")]
    Smoothing(String),
    /// A by-name mapping onto a character without ARKit names moves nothing.
    #[error(
        "{character} has no ARKit-named blendshapes: train an adapter for it first (Train adapter)"
    )]
    NoArkitNames {
        /// The character's name.
        character: String,
    },
    /// A capture onto a character with no blendshapes and no head, eye or jaw bone moves
    /// nothing of it.
    #[error(
        "{character} has no blendshapes, and no head, eye or jaw bone, for a capture to move: make ARKit's 52 shapes on it with `faceanim generate-shapes` (Generate blendshapes in the studio), then capture onto that"
    )]
    NothingToMove {
        /// The character's name.
        character: String,
    },
    /// An estimator or session of another character's blendshapes.
    #[error(
        "this estimate cannot drive {character}: {reason}; train an adapter for it with `faceanim adapt`"
    )]
    Mismatch {
        /// The character's name.
        character: String,
        /// What differs.
        reason: String,
    },
    /// A session file that is malformed (not JSON, or not a session: its message names the
    /// field).
    #[error("{0}")]
    Format(String),
    /// A session file whose values cannot be used, each problem with its JSON path.
    #[error("invalid session file: {}", .0.join("; "))]
    Invalid(Vec<String>),
    /// A frame without a face cannot be the neutral one.
    #[error("frame {frame} has no face, so it cannot be the neutral frame")]
    NoFace {
        /// The frame.
        frame: usize,
    },
}
