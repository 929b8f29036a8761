//! # faceanim-batch: thousands of jobs, each done once
//!
//! A batch is a manifest (JSON Lines or CSV, [`manifest`]) with one row per job — a line of
//! dialogue to lip-sync, a take to track, a head to give shapes — and the outputs each row
//! writes. This crate holds the contract that makes a batch safe to run again and again, by
//! hand or spread over machines:
//!
//! - **checked first**: every row is checked before any work starts; a bad row is named with
//!   its line and field, and the others still run ([`manifest::Manifest::read`]);
//! - **idempotent**: each row's outputs are written atomically beside a small record of what
//!   made them — the hash of every input, the row's options and the faceanim version
//!   ([`record`]); a row whose record still matches is skipped;
//! - **edits are kept**: an output that differs from what its record says was written (a take
//!   edited in the studio, a file made by hand) is never overwritten unless asked;
//! - **one row per worker**: a worker runs the row its index names (`--index`, or an array
//!   job's `JOB_COMPLETION_INDEX`, `AWS_BATCH_JOB_ARRAY_INDEX`, `SLURM_ARRAY_TASK_ID`) or a
//!   shard of them ([`select`]), and says how it went by its exit status: 0 done or skipped,
//!   [`EXIT_BAD_INPUT`] for input that will never work (do not retry), anything else for a
//!   failure worth retrying ([`report`]).
//!
//! Running a row is the command line's job (it is `faceanim lipsync`, `track` or
//! `generate-shapes` with the row's arguments, [`manifest::Row::command`]); this crate knows no
//! command.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let dir = tempfile::tempdir()?;
//! std::fs::write(dir.path().join("line.wav"), b"RIFF")?;
//! let manifest = dir.path().join("lines.jsonl");
//! std::fs::write(
//!     &manifest,
//!     concat!(
//!         r#"{"id": "a", "kind": "lipsync", "speech": "line.wav", "outputs": "a.json"}"#, "\n",
//!         r#"{"id": "b", "kind": "lipsync", "speech": "gone.wav", "outputs": "b.json"}"#, "\n",
//!     ),
//! )?;
//! let manifest = faceanim_batch::manifest::Manifest::read(&manifest)?;
//! assert_eq!(manifest.rows().count(), 1);
//! let bad = manifest.entries[1].row.as_ref().unwrap_err();
//! assert_eq!(bad.line, 2);
//! assert_eq!(bad.field.as_deref(), Some("speech"));
//!
//! let planner = faceanim_batch::record::Planner::new("0.1.0");
//! let row = manifest.rows().next().unwrap();
//! let state = planner.state(row, faceanim_batch::record::Policy::default())?;
//! assert!(matches!(state, faceanim_batch::record::State::ToDo(_)));
//! # Ok(())
//! # }
//! ```
#![deny(missing_docs)]

pub mod manifest;
pub mod record;
pub mod report;
pub mod select;

use std::path::{Path, PathBuf};

/// The exit status of a worker whose row can never succeed as it is (a missing or broken
/// input, a bad row): an engine must not retry it. Kubernetes' `podFailurePolicy` maps it to
/// `FailIndex`.
pub const EXIT_BAD_INPUT: u8 = 42;

/// Why a batch could not start or a row's bookkeeping failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BatchError {
    /// The operating system refused.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The manifest as a whole cannot be used.
    #[error("{}: {problem}", path.display())]
    Manifest {
        /// The manifest.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// An atomic write failed.
    #[error(transparent)]
    Write(#[from] faceanim_files::FileError),
    /// The rows to run cannot be chosen (`--index`, `--shard`, an index variable).
    #[error("{0}")]
    Selection(String),
}

impl BatchError {
    fn io(path: &Path, source: std::io::Error) -> BatchError {
        BatchError::Io {
            path: path.to_owned(),
            source,
        }
    }

    fn manifest(path: &Path, problem: String) -> BatchError {
        BatchError::Manifest {
            path: path.to_owned(),
            problem,
        }
    }

    /// Whether the error is the input's (retrying cannot help) rather than the machine's.
    #[must_use]
    pub fn is_bad_input(&self) -> bool {
        matches!(self, BatchError::Manifest { .. } | BatchError::Selection(_))
    }
}
