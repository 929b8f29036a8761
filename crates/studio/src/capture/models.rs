//! The face models and tracking threads, loaded once and kept for the process.

use std::sync::{Mutex, OnceLock};

use faceanim_track::{FaceModels, Workers};

use crate::error::ApiError;

/// The face models, loaded once on first use and kept for the process (live tracking holds a
/// tracker that borrows them between requests).
pub(super) fn face_models() -> Result<&'static FaceModels, ApiError> {
    static MODELS: OnceLock<Result<FaceModels, String>> = OnceLock::new();
    MODELS
        .get_or_init(|| FaceModels::load_with_threads(1).map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| ApiError::Models(e.clone()))
}

/// Threads that track beside a job's own thread (one per core beyond the first), started with
/// the face models on first use and kept for the process, warm, as `faceanim track` keeps its
/// own for a clip. One job reads an input at a time; the lock says so.
pub(super) fn face_workers() -> Result<&'static Mutex<Workers>, ApiError> {
    static WORKERS: OnceLock<Result<Mutex<Workers>, String>> = OnceLock::new();
    let models = face_models()?;
    WORKERS
        .get_or_init(|| {
            let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
            Workers::start(models, cores.clamp(1, 8) - 1)
                .map(Mutex::new)
                .map_err(|e| e.to_string())
        })
        .as_ref()
        .map_err(|e| ApiError::Models(e.clone()))
}
