//! # faceanim-studio: the local web app
//!
//! One axum server on 127.0.0.1 serves the page (embedded from `web/`, so the binary runs from
//! anywhere with no Node.js or build step) and a small HTTP/JSON API that the page and scripts
//! use alike (see `API.md` beside this crate). The engines stay in Rust: the server keeps the
//! project (the strokes file of docs/formats.md) as the single source of truth and rebuilds the
//! sketch from it on each change, which takes milliseconds and makes undo/redo exact.
//!
//! Capture mode ([`capture`]) adds a face video, photos or the webcam as the animation's
//! source, with seed 003's human-in-the-loop editing; its long jobs run on their own threads
//! and report progress through the API.
//!
//! Safety: it listens on loopback only; requests whose `Host` or `Origin` is not the studio's
//! own are refused (a web page elsewhere cannot drive it through DNS rebinding); request bodies
//! are size-limited; it writes only the project file it was started with (and its autosave
//! beside it), the take being captured (`.NAME.take.json` beside it), the character's adapter and
//! its cached training set (uploads, recordings and previews go to a private temporary folder,
//! [`scratch`], removed when the studio stops — Ctrl-C and SIGTERM stop it) — exports are
//! downloads the browser saves.
#![deny(missing_docs)]

mod api;
pub mod capture;
mod capture_api;
pub mod error;
mod http;
pub mod scratch;
mod state;
pub mod views;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use faceanim_rig::Character;
use std::sync::MutexGuard;

pub use error::ApiError;
pub use state::Studio;

/// Locks `mutex`. Every change made under the studio's locks replaces a whole value (a
/// project, a take, a job's outcome), so a lock poisoned by a panic still guards a consistent
/// state and is used as it is.
pub(crate) fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// What the studio opens with.
#[derive(Debug)]
pub struct Config {
    /// The character to animate.
    pub character: Character,
    /// Where the project is saved (and read from, if it exists).
    pub project_path: PathBuf,
    /// Where the character's adapter is read from and trained into (capture mode);
    /// characters uploaded later keep theirs beside the project file.
    pub adapter_path: PathBuf,
    /// VMC in (a phone tracker drives the character) and out (the live face to VTuber apps).
    pub vmc: capture::VmcConfig,
}

/// Why the studio could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudioError {
    /// The port is taken or not allowed.
    #[error("cannot listen on {address}: {source}")]
    Listen {
        /// The address.
        address: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// The saved project or its autosave exists but cannot be used.
    #[error(transparent)]
    Project(ApiError),
    /// A VMC port could not be opened.
    #[error("VMC: {0}")]
    Vmc(ApiError),
    /// The server stopped with an error.
    #[error("server: {0}")]
    Serve(std::io::Error),
    /// The studio's private temporary folder could not be made.
    #[error("making the studio's temporary folder: {0}")]
    Scratch(std::io::Error),
}

/// Binds 127.0.0.1:`port` (0 picks a free port) and returns the listener with its address.
///
/// # Errors
/// [`StudioError::Listen`].
pub async fn bind(port: u16) -> Result<(tokio::net::TcpListener, SocketAddr), StudioError> {
    let address = SocketAddr::from(([127, 0, 0, 1], port));
    let listener = tokio::net::TcpListener::bind(address)
        .await
        .map_err(|source| StudioError::Listen { address, source })?;
    let bound = listener
        .local_addr()
        .map_err(|source| StudioError::Listen { address, source })?;
    Ok((listener, bound))
}

/// Serves the studio on `listener` until the process is stopped.
///
/// # Errors
/// [`StudioError`] if the project cannot be opened or the server fails.
pub async fn serve(config: Config, listener: tokio::net::TcpListener) -> Result<(), StudioError> {
    let address = listener.local_addr().map_err(StudioError::Serve)?;
    // Saves interrupted by a crash or a kill leave partial writes beside the project: gone now.
    if let Some(folder) = config.project_path.parent() {
        let folder = if folder.as_os_str().is_empty() {
            std::path::Path::new(".")
        } else {
            folder
        };
        for stale in
            faceanim_files::remove_stale_partials(folder, std::time::Duration::from_secs(60))
        {
            tracing::info!("removed {}, a save that was interrupted", stale.display());
        }
    }
    let scratch = scratch::Scratch::open().map_err(StudioError::Scratch)?;
    let take_path = state::take_autosave_path(&config.project_path);
    let visemes_path = state::visemes_path(&config.project_path);
    let studio =
        Studio::open(config.character, config.project_path).map_err(StudioError::Project)?;
    let character = studio.character.clone();
    let mut desk = capture::CaptureDesk::new(
        &character,
        config.adapter_path,
        take_path,
        studio.sketch_from_file(),
    );
    desk.open_visemes(visemes_path);
    desk.open_vmc(config.vmc, &character)
        .map_err(StudioError::Vmc)?;
    let both = capture_api::Both {
        studio: Arc::new(Mutex::new(studio)),
        desk: Arc::new(Mutex::new(desk)),
    };
    // A phone or VMC tracker listened to reaches a rig whose names say nothing through its
    // retarget map: made now when it has none yet.
    if capture::map_for_listeners(&both.desk, character) {
        tracing::info!("making the retarget map for the phone or tracker listened to");
    }
    let app = api::router(both, address.port());
    // Live answers are small and wanted at once: without TCP_NODELAY, one waiting for the
    // acknowledgement of the last could sit 40 ms (Nagle's algorithm and delayed ACKs).
    let listener = axum::serve::ListenerExt::tap_io(listener, |stream| {
        if let Err(e) = stream.set_nodelay(true) {
            tracing::debug!("TCP_NODELAY could not be set: {e}");
        }
    });
    let stopping = Arc::new(tokio::sync::Notify::new());
    let stop = {
        let stopping = stopping.clone();
        async move {
            stop_asked().await;
            stopping.notify_one();
        }
    };
    let server = axum::serve(listener, app).with_graceful_shutdown(stop);
    tokio::select! {
        served = server => served.map_err(StudioError::Serve)?,
        () = async {
            stopping.notified().await;
            tokio::time::sleep(GRACE).await;
        } => tracing::warn!("requests still running {} s after the stop were cut short", GRACE.as_secs()),
    }
    drop(scratch);
    tracing::info!("the studio stopped; its scratch folder is removed");
    Ok(())
}

/// How long requests under way when the studio is asked to stop may take to finish.
const GRACE: std::time::Duration = std::time::Duration::from_secs(3);

/// Waits until the studio is asked to stop: Ctrl-C, or (on Unix) SIGTERM, as a service
/// manager or `kill` sends. Either lets the studio remove its scratch folder on the way out.
async fn stop_asked() {
    let interrupt = async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut signal) => {
                signal.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        () = interrupt => {},
        () = terminate => {},
    }
    tracing::info!("stopping the studio");
}
