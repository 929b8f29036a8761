//! What made each output: a record beside a row's first output (`NAME.made.json`) holding the
//! faceanim version, the row's job (fields, options, outputs as written) and the SHA-256 of
//! every input and output.
//!
//! A row whose record matches what it would do now is skipped. An output whose bytes are not
//! the ones its record says were written has been edited (or was never written by a batch)
//! and is left alone. Outputs are replaced in three steps — staged beside themselves, a record
//! marked `writing` that accepts both the old and the new bytes, the renames, then the final
//! record — so a worker killed at any point leaves every output either old or new, never
//! half-written, and a later run neither mistakes its own files for edits nor skips the row.

use std::collections::HashMap;
use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use sha2::{Digest as _, Sha256};

use crate::BatchError;
use crate::manifest::Row;

/// The ending added to a row's first output to name its record.
pub const RECORD_SUFFIX: &str = ".made.json";

/// The start of the name an output is staged under, beside itself, until the row is done.
pub const STAGED_PREFIX: &str = ".faceanim-partial.";

/// A file and the SHA-256 of its bytes (hex).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Hashed {
    /// The path as the manifest writes it.
    pub path: String,
    /// The hash.
    pub sha256: String,
}

/// What made a row's outputs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// The faceanim version that wrote them.
    pub faceanim: String,
    /// The row's id.
    pub id: String,
    /// The row's job: kind, fields, outputs and options as written.
    pub job: serde_json::Value,
    /// Every input file, by field.
    pub inputs: Vec<Hashed>,
    /// Every output, as written.
    pub outputs: Vec<Hashed>,
    /// Set while the outputs are being replaced: the bytes they had before, which are not
    /// edits either.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub replacing: Vec<Hashed>,
    /// Whether the outputs were being replaced (a worker stopped before it finished).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub writing: bool,
    /// Why the row's input was found bad, when it was: the row is not run again until its
    /// inputs or options change (its outputs are then the ones a run before it wrote, if any).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bad: Option<String>,
}

/// What to redo.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Policy {
    /// Redo rows whose record matches (`--force`).
    pub force: bool,
    /// Overwrite outputs edited since they were written (`--overwrite-edits`).
    pub overwrite_edits: bool,
}

/// Why a row runs.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "why", content = "what")]
pub enum Reason {
    /// It has no record: never done.
    New,
    /// Asked to (`--force`).
    Forced,
    /// An input, an option or faceanim changed since: which.
    Changed(String),
    /// An output is gone.
    Missing(String),
    /// A worker stopped while writing it.
    Interrupted,
    /// Its edited outputs are overwritten, as asked.
    OverwritingEdits,
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reason::New => f.write_str("new"),
            Reason::Forced => f.write_str("forced"),
            Reason::Changed(what) => write!(f, "{what} changed"),
            Reason::Missing(path) => write!(f, "{path} is missing"),
            Reason::Interrupted => f.write_str("interrupted while writing"),
            Reason::OverwritingEdits => f.write_str("overwriting edits, as asked"),
        }
    }
}

/// Where a row stands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum State {
    /// It must run, and why.
    ToDo(Reason),
    /// Its record matches: nothing to do.
    Done,
    /// These outputs were edited since they were written (or were not written by a batch):
    /// the row is left alone.
    Edited(Vec<String>),
    /// The last run found its input bad, and nothing it depends on has changed since: why.
    Bad(String),
}

/// Works out rows' states, hashing each input file once however many rows read it.
pub struct Planner {
    version: String,
    hashes: Mutex<HashMap<PathBuf, String>>,
}

impl Planner {
    /// A planner for faceanim `version` (part of every record: a new version redoes rows).
    #[must_use]
    pub fn new(version: &str) -> Planner {
        Planner {
            version: version.to_owned(),
            hashes: Mutex::new(HashMap::new()),
        }
    }

    /// Where `row` stands under `policy`.
    ///
    /// # Errors
    /// [`BatchError::Io`] when an input or an output cannot be read.
    pub fn state(&self, row: &Row, policy: Policy) -> Result<State, BatchError> {
        let record = read_record(row);
        let mut edited = Vec::new();
        let mut missing = None;
        for (written, path) in row.outputs.iter().zip(row.output_paths()) {
            if !path.exists() {
                missing.get_or_insert_with(|| written.clone());
                continue;
            }
            let hash = hash_file(&path)?;
            let ours = record.as_ref().is_some_and(|r| {
                r.outputs
                    .iter()
                    .chain(&r.replacing)
                    .any(|h| h.path == *written && h.sha256 == hash)
            });
            if !ours {
                edited.push(written.clone());
            }
        }
        if !edited.is_empty() {
            return Ok(if policy.overwrite_edits {
                State::ToDo(Reason::OverwritingEdits)
            } else {
                State::Edited(edited)
            });
        }
        if policy.force {
            return Ok(State::ToDo(Reason::Forced));
        }
        let Some(record) = record else {
            return Ok(State::ToDo(Reason::New));
        };
        if record.writing {
            return Ok(State::ToDo(Reason::Interrupted));
        }
        if record.faceanim != self.version {
            return Ok(State::ToDo(Reason::Changed(format!(
                "faceanim ({} → {})",
                record.faceanim, self.version
            ))));
        }
        if record.job != job(row) {
            return Ok(State::ToDo(Reason::Changed("the row".to_owned())));
        }
        let inputs = self.inputs(row)?;
        if record.inputs != inputs {
            let what = inputs
                .iter()
                .find(|h| !record.inputs.contains(h))
                .map_or_else(|| "an input".to_owned(), |h| h.path.clone());
            return Ok(State::ToDo(Reason::Changed(what)));
        }
        if let Some(bad) = record.bad {
            return Ok(State::Bad(bad));
        }
        if let Some(path) = missing {
            return Ok(State::ToDo(Reason::Missing(path)));
        }
        Ok(State::Done)
    }

    /// The hash of every input of `row`.
    fn inputs(&self, row: &Row) -> Result<Vec<Hashed>, BatchError> {
        row.input_files()
            .into_iter()
            .map(|(field, path)| {
                let cached = self.hashes.lock().ok().and_then(|h| h.get(&path).cloned());
                let sha256 = match cached {
                    Some(hash) => hash,
                    None => {
                        let hash = hash_path(&path)?;
                        if let Ok(mut hashes) = self.hashes.lock() {
                            hashes.insert(path, hash.clone());
                        }
                        hash
                    }
                };
                Ok(Hashed {
                    path: row.field(field).unwrap_or_default().to_owned(),
                    sha256,
                })
            })
            .collect()
    }

    /// Makes `staged` (from [`staged_paths`], written by the row's command) the row's outputs
    /// and records what made them: the record marked `writing` first, then the renames, then
    /// the final record.
    ///
    /// # Errors
    /// [`BatchError`] when a file cannot be read, renamed or written.
    pub fn commit(&self, row: &Row, staged: &[PathBuf]) -> Result<(), BatchError> {
        let outputs = row
            .outputs
            .iter()
            .zip(staged)
            .map(|(written, path)| {
                Ok(Hashed {
                    path: written.clone(),
                    sha256: hash_file(path)?,
                })
            })
            .collect::<Result<Vec<_>, BatchError>>()?;
        let mut replacing = Vec::new();
        for (written, path) in row.outputs.iter().zip(row.output_paths()) {
            if path.exists() {
                replacing.push(Hashed {
                    path: written.clone(),
                    sha256: hash_file(&path)?,
                });
            }
        }
        let mut record = Record {
            faceanim: self.version.clone(),
            id: row.id.clone(),
            job: job(row),
            inputs: self.inputs(row)?,
            outputs,
            replacing,
            writing: true,
            bad: None,
        };
        write_record(row, &record)?;
        for (from, to) in staged.iter().zip(row.output_paths()) {
            std::fs::rename(from, &to).map_err(|source| BatchError::io(&to, source))?;
        }
        record.writing = false;
        record.replacing.clear();
        write_record(row, &record)
    }
}

impl Planner {
    /// Records that `row`'s input was found bad (`why`), so that it is reported again without
    /// running until its inputs, its options or faceanim change. Outputs an earlier run wrote
    /// stay the batch's.
    ///
    /// # Errors
    /// [`BatchError`] when an input cannot be read or the record cannot be written.
    pub fn remember_bad(&self, row: &Row, why: &str) -> Result<(), BatchError> {
        let record = Record {
            faceanim: self.version.clone(),
            id: row.id.clone(),
            job: job(row),
            inputs: self.inputs(row)?,
            outputs: read_record(row).map(|r| r.outputs).unwrap_or_default(),
            replacing: Vec::new(),
            writing: false,
            bad: Some(why.to_owned()),
        };
        write_record(row, &record)
    }
}

/// Where `row`'s outputs are staged while its command writes them: beside each output, under a
/// hidden name that keeps its ending (so its format is still known). One per output, the same
/// on every run: a row runs under its lock only, and a stale one is simply written over.
#[must_use]
pub fn staged_paths(row: &Row) -> Vec<PathBuf> {
    row.output_paths()
        .iter()
        .map(|path| {
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            path.with_file_name(format!("{STAGED_PREFIX}{name}"))
        })
        .collect()
}

/// Takes `row`'s lock (waiting while another worker holds it), creating its outputs' folders:
/// two workers given the same row — an engine's retry while the first attempt still runs —
/// run it one after the other, and the second finds it done. Held until the file is dropped.
///
/// # Errors
/// [`BatchError::Io`] when a folder or the lock cannot be made.
pub fn lock(row: &Row) -> Result<std::fs::File, BatchError> {
    for path in row.output_paths() {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| BatchError::io(dir, source))?;
        }
    }
    let path = beside_first_output(row, ".", ".lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|source| BatchError::io(&path, source))?;
    file.lock()
        .map_err(|source| BatchError::io(&path, source))?;
    Ok(file)
}

/// The record of `row`: beside its first output.
#[must_use]
pub fn record_path(row: &Row) -> PathBuf {
    beside_first_output(row, "", RECORD_SUFFIX)
}

/// A file beside `row`'s first output, named after it with `prefix` and `suffix`.
fn beside_first_output(row: &Row, prefix: &str, suffix: &str) -> PathBuf {
    let first = row.resolve(&row.outputs[0]);
    let name = first.file_name().unwrap_or_default().to_string_lossy();
    first.with_file_name(format!("{prefix}{name}{suffix}"))
}

/// `row`'s record, when it has a readable one (an unreadable record is none: its outputs are
/// then not known to be the batch's, and are kept).
fn read_record(row: &Row) -> Option<Record> {
    let bytes = std::fs::read(record_path(row)).ok()?;
    serde_json::from_slice(&bytes).ok()
}

fn write_record(row: &Row, record: &Record) -> Result<(), BatchError> {
    let mut bytes = serde_json::to_vec_pretty(record).map_err(|e| BatchError::Io {
        path: record_path(row),
        source: std::io::Error::other(e),
    })?;
    bytes.push(b'\n');
    faceanim_files::write_atomic(&record_path(row), &bytes)?;
    Ok(())
}

/// What identifies a row's job: everything it does, but not where it stands in the manifest.
fn job(row: &Row) -> serde_json::Value {
    serde_json::json!({
        "kind": row.kind,
        "fields": row.fields,
        "outputs": row.outputs,
        "options": row.options,
    })
}

/// The SHA-256 of a file's bytes, or of a folder's files (each name with its hash, sorted).
fn hash_path(path: &Path) -> Result<String, BatchError> {
    if !path.is_dir() {
        return hash_file(path);
    }
    let mut entries = std::fs::read_dir(path)
        .map_err(|source| BatchError::io(path, source))?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|source| BatchError::io(path, source))?;
    entries.sort();
    let mut hasher = Sha256::new();
    for entry in entries {
        let name = entry.file_name().unwrap_or_default().to_string_lossy();
        if name.starts_with('.') {
            continue;
        }
        hasher.update(name.as_bytes());
        hasher.update([0]);
        hasher.update(hash_path(&entry)?.as_bytes());
        hasher.update([b'\n']);
    }
    Ok(hex(&hasher.finalize()))
}

/// The SHA-256 of a file's bytes, read in pieces.
fn hash_file(path: &Path) -> Result<String, BatchError> {
    let io = |source| BatchError::io(path, source);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0; 1 << 16];
    loop {
        let read = file.read(&mut buffer).map_err(io)?;
        if read == 0 {
            break;
        }
        hasher.update(&buffer[..read]);
    }
    Ok(hex(&hasher.finalize()))
}

fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write as _;
    bytes.iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}
