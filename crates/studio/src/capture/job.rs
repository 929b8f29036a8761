//! One long piece of work (reading a video, making a map, rendering and training) with its
//! progress, cancel flag and outcome, run on its own thread.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::error::ApiError;
use crate::lock;
use crate::views::{JobKind, JobView};
use faceanim_adapt::Control;

/// One long piece of work: progress, a cancel flag, and how it ended (its message, or its
/// error's).
#[derive(Debug)]
pub struct Job {
    kind: JobKind,
    stage: Mutex<String>,
    done: AtomicUsize,
    total: AtomicUsize,
    cancel: AtomicBool,
    finished: AtomicBool,
    outcome: Mutex<Option<Result<String, String>>>,
    started: Instant,
}

impl Job {
    pub(super) fn new(kind: JobKind) -> Arc<Job> {
        Arc::new(Job {
            kind,
            stage: Mutex::new(String::new()),
            done: AtomicUsize::new(0),
            total: AtomicUsize::new(0),
            cancel: AtomicBool::new(false),
            finished: AtomicBool::new(false),
            outcome: Mutex::new(None),
            started: Instant::now(),
        })
    }

    pub(super) fn stage(&self, stage: &str, total: usize) {
        *lock(&self.stage) = stage.to_owned();
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    pub(super) fn progress(&self, done: usize) {
        self.done.store(done, Ordering::Relaxed);
    }

    /// Progress where the work itself says how long it is.
    pub(super) fn progress_of(&self, done: usize, total: usize) {
        self.total.store(total, Ordering::Relaxed);
        self.progress(done);
    }

    /// What the work is.
    pub(super) fn kind(&self) -> JobKind {
        self.kind
    }

    /// Asks the work to stop at its next check.
    pub(super) fn ask_to_cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// The flag the work checks.
    pub(super) fn cancel_flag(&self) -> &AtomicBool {
        &self.cancel
    }

    pub(super) fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    pub(super) fn running(&self) -> bool {
        !self.finished.load(Ordering::Acquire)
    }

    pub(super) fn finish(&self, outcome: Result<String, ApiError>) {
        *lock(&self.outcome) = Some(outcome.map_err(|e| e.to_string()));
        self.finished.store(true, Ordering::Release);
    }

    pub(super) fn view(&self) -> JobView {
        let outcome = lock(&self.outcome).clone();
        JobView {
            kind: self.kind,
            title: self.kind.to_string(),
            stage: lock(&self.stage).clone(),
            done: self.done.load(Ordering::Relaxed),
            total: self.total.load(Ordering::Relaxed),
            running: self.running(),
            cancelling: self.cancelled(),
            seconds: self.started.elapsed().as_secs_f64(),
            result: outcome.clone().and_then(Result::ok),
            error: outcome.and_then(Result::err),
        }
    }
}

/// Runs `work` on its own thread and ends `job` with its outcome. A panic (a bug) ends the job
/// with an error instead of leaving the studio busy for ever.
pub(super) fn spawn_job(
    job: Arc<Job>,
    work: impl FnOnce(&Job) -> Result<String, ApiError> + Send + 'static,
) {
    std::thread::spawn(move || {
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&job)))
            .unwrap_or_else(|_| {
                Err(ApiError::Internal(
                    "stopped by an internal error (a bug; the studio's log says where)".into(),
                ))
            });
        job.finish(outcome);
    });
}

/// Runs `work` with the job's progress and cancel flag.
pub(super) fn with_control<T>(
    job: &Job,
    work: impl FnOnce(Control<'_>) -> Result<T, faceanim_adapt::AdaptError>,
) -> Result<T, ApiError> {
    // The work knows its length best (training: every network's epochs at most).
    let progress = |done: usize, total: usize| job.progress_of(done, total);
    Ok(work(Control {
        progress: &progress,
        cancel: job.cancel_flag(),
    })?)
}
