//! The API's errors: one enum, one mapping to an HTTP status, one JSON shape
//! (`{"error": "message naming the field or file"}`).

use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use faceanim_take::TakeError;

use crate::views::JobKind;

/// A handler's answer: a JSON view, or the error.
pub(crate) type Answer<T> = Result<axum::Json<T>, ApiError>;

/// Why a request was refused or failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ApiError {
    /// A request's body, header or path is wrong; the message names the field or file.
    #[error("{0}")]
    Invalid(String),
    /// A strokes project (sent, opened or edited) that is not valid.
    #[error("{what}: {source}")]
    Project {
        /// Which project: the file or what was sent.
        what: String,
        /// Every problem, with its path.
        source: faceanim_sketch::project::ProjectError,
    },
    /// A take or session refused an edit or a file.
    #[error("{0}")]
    Take(#[from] TakeError),
    /// A session file that was refused, named as the user knows it.
    #[error("{what}: {source}")]
    Session {
        /// The file as the user knows it.
        what: String,
        /// Why.
        source: TakeError,
    },
    /// A character the importer refused (the message names the file).
    #[error(transparent)]
    Import(#[from] faceanim_rig::import::ImportError),
    /// A capture edit with no take open.
    #[error("no capture is open: open a video, photos or the webcam first")]
    NoTake,
    /// A live-mode request at the wrong moment (not live, not recording).
    #[error("{0}")]
    Live(&'static str),
    /// No stroke with that index.
    #[error("no stroke {index} (there are {count})")]
    NoStroke {
        /// The index asked for.
        index: usize,
        /// How many strokes there are.
        count: usize,
    },
    /// No such input frame preview.
    #[error("{0}")]
    NoPreview(&'static str),
    /// Another long job is running.
    #[error("the studio is busy ({0}); wait for it or cancel it")]
    Busy(JobKind),
    /// A file the studio keeps (project, take, adapter, preview) could not be written or read.
    #[error(transparent)]
    Disk(#[from] faceanim_files::FileError),
    /// A private folder or file for previews or uploads could not be made.
    #[error("{what}: {source}")]
    Scratch {
        /// What was being written.
        what: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The sketch could not be baked for export (a bug, reported rather than hidden).
    #[error(transparent)]
    Bake(#[from] faceanim_rig::ModelError),
    /// An export could not be made.
    #[error(transparent)]
    Export(#[from] faceanim_export::ExportError),
    /// A GLB, VRM or Live Link CSV could not be read back as a take.
    #[error(transparent)]
    Reopen(#[from] faceanim_export::reopen::ReopenError),
    /// The face models could not be loaded.
    #[error("loading the face models: {0}")]
    Models(String),
    /// The adapter failed (training, fine-tuning, or a file that does not fit).
    #[error(transparent)]
    Adapt(#[from] faceanim_adapt::AdaptError),
    /// The capture pipeline failed on a frame.
    #[error(transparent)]
    Capture(#[from] faceanim_capture::CaptureError),
    /// A VMC socket could not be opened, or its names fit none of the character's.
    #[error(transparent)]
    Vmc(#[from] faceanim_live::LiveError),
    /// Blendshapes could not be generated (no face found on the character, too few
    /// landmarks, nothing to make, a failed solve).
    #[error(transparent)]
    Fit(#[from] faceanim_fit::FitError),
    /// A worker thread ended without an answer (a bug; the log says where).
    #[error("internal error: {0}")]
    Internal(String),
}

impl ApiError {
    /// The HTTP status of each kind of error: the one place it is chosen.
    #[must_use]
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::Invalid(_)
            | ApiError::Project { .. }
            | ApiError::Take(_)
            | ApiError::Session { .. }
            | ApiError::Import(_)
            | ApiError::Reopen(_)
            | ApiError::NoTake
            | ApiError::Live(_) => StatusCode::BAD_REQUEST,
            ApiError::NoStroke { .. } | ApiError::NoPreview(_) => StatusCode::NOT_FOUND,
            ApiError::Fit(
                faceanim_fit::FitError::NoFace(_)
                | faceanim_fit::FitError::TooFewLandmarks { .. }
                | faceanim_fit::FitError::NothingToMake { .. }
                | faceanim_fit::FitError::AlreadyHas { .. },
            ) => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::Busy(_) => StatusCode::CONFLICT,
            // A VRM Animation asked of a character that is no VRM, or of nothing it carries; a
            // clip that moves nothing of a body with no blendshapes.
            ApiError::Export(
                faceanim_export::ExportError::NotVrm(_)
                | faceanim_export::ExportError::NothingToCarry(_)
                | faceanim_export::ExportError::NothingForBones(_),
            ) => StatusCode::BAD_REQUEST,
            ApiError::Disk(_)
            | ApiError::Scratch { .. }
            | ApiError::Bake(_)
            | ApiError::Export(_)
            | ApiError::Models(_)
            | ApiError::Adapt(_)
            | ApiError::Capture(_)
            | ApiError::Vmc(_)
            | ApiError::Fit(_)
            | ApiError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }
}

impl From<faceanim_adapt::bridge::BridgeError> for ApiError {
    fn from(e: faceanim_adapt::bridge::BridgeError) -> ApiError {
        match e {
            faceanim_adapt::bridge::BridgeError::Fit(e) => ApiError::Fit(e),
            faceanim_adapt::bridge::BridgeError::Calibration(e) => ApiError::Adapt(e),
            other => ApiError::Internal(other.to_string()),
        }
    }
}

/// The error's JSON body.
#[derive(serde::Serialize)]
struct ErrorView {
    error: String,
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        if status.is_server_error() {
            tracing::error!("{self}");
        }
        (
            status,
            axum::Json(ErrorView {
                error: self.to_string(),
            }),
        )
            .into_response()
    }
}
