//! How each row went, the events a worker prints, and the batch's report and exit status.

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::EXIT_BAD_INPUT;

/// How a row ended.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Run, and its outputs written.
    Done,
    /// Its record matched: nothing to do.
    Skipped,
    /// Its outputs were edited since they were written: left alone.
    Edited,
    /// Its input can never work as it is: not retried.
    BadInput,
    /// It failed for a reason worth retrying (the machine's, not the input's).
    Failed,
}

impl Status {
    /// The worker's exit status for a row that ended so.
    #[must_use]
    pub fn exit_code(self) -> u8 {
        match self {
            Status::Done | Status::Skipped | Status::Edited => 0,
            Status::BadInput => EXIT_BAD_INPUT,
            Status::Failed => 1,
        }
    }

    /// As the summary names it.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Status::Done => "done",
            Status::Skipped => "skipped (unchanged)",
            Status::Edited => "edited since (left alone)",
            Status::BadInput => "bad input",
            Status::Failed => "failed",
        }
    }
}

/// How one row went.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RowResult {
    /// The row's index (0-based).
    pub index: usize,
    /// The manifest line it starts on.
    pub line: usize,
    /// Its id, when it has a usable one.
    pub id: Option<String>,
    /// How it ended.
    pub status: Status,
    /// Why it ran (new, an input changed, …), or which outputs were edited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// What went wrong, for a bad input or a failure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Seconds it took.
    pub seconds: f64,
    /// How many times it was started (1 unless a failure was retried).
    pub attempts: u32,
    /// What its command said to heed while it ran, as it said it: its `warning:` and `note:`
    /// lines (a take in which no face was found, a line in which no voice was heard). Kept
    /// for a row a pool's worker ran; a `--index` worker says them on its standard error.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A line of `--progress json` on standard error.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum Event {
    /// The batch starts: its rows, and how many are selected and to be run.
    Start {
        /// Rows in the manifest.
        rows: usize,
        /// Rows selected.
        selected: usize,
        /// Selected rows that will run.
        to_run: usize,
    },
    /// A row ended.
    Row(RowResult),
    /// The batch ended.
    End {
        /// Rows per status.
        counts: BTreeMap<Status, usize>,
        /// Seconds it took.
        seconds: f64,
    },
}

/// The batch's report: every selected row's result.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// The manifest.
    pub manifest: PathBuf,
    /// The faceanim version.
    pub faceanim: String,
    /// Seconds the batch took.
    pub seconds: f64,
    /// Rows per status.
    pub counts: BTreeMap<Status, usize>,
    /// Every selected row, in the manifest's order.
    pub rows: Vec<RowResult>,
}

impl Report {
    /// The report of `rows` (sorted into the manifest's order).
    #[must_use]
    pub fn new(
        manifest: PathBuf,
        faceanim: &str,
        seconds: f64,
        mut rows: Vec<RowResult>,
    ) -> Report {
        rows.sort_by_key(|r| r.index);
        Report {
            manifest,
            faceanim: faceanim.to_owned(),
            seconds,
            counts: counts(&rows),
            rows,
        }
    }

    /// The batch's exit status: 0 when every row is done, skipped or kept; 1 when any failed
    /// (worth running again); else [`EXIT_BAD_INPUT`] when any row's input is bad.
    #[must_use]
    pub fn exit_code(&self) -> u8 {
        self.rows
            .iter()
            .map(|r| r.status.exit_code())
            .max_by_key(|&code| match code {
                0 => 0,
                EXIT_BAD_INPUT => 1,
                _ => 2,
            })
            .unwrap_or(0)
    }

    /// A few lines for a person: the counts, the rate, and each row that needs a look.
    #[must_use]
    pub fn summary(&self) -> String {
        use std::fmt::Write as _;
        let mut text = String::new();
        let counts = self
            .counts
            .iter()
            .map(|(status, n)| format!("{n} {}", status.describe()))
            .collect::<Vec<_>>()
            .join(", ");
        let _ = write!(
            text,
            "{}: {} rows in {:.1} s: {counts}",
            self.manifest.display(),
            self.rows.len(),
            self.seconds
        );
        let done = self.counts.get(&Status::Done).copied().unwrap_or(0);
        if done > 0 && self.seconds > 0.0 {
            let _ = write!(
                text,
                " ({:.0} rows a minute)",
                done as f64 * 60.0 / self.seconds
            );
        }
        text.push('\n');
        for row in &self.rows {
            // A row done with a warning needs a look too (a take in which no face was found).
            let warnings: Vec<&str> = row
                .notes
                .iter()
                .filter_map(|n| n.strip_prefix("warning: "))
                .collect();
            let note = match (row.status, warnings.as_slice()) {
                (Status::BadInput | Status::Failed, _) => row.error.clone(),
                (Status::Edited, _) => row.reason.clone(),
                (Status::Done, [first, more @ ..]) => Some(if more.is_empty() {
                    format!("warning: {first}")
                } else {
                    format!("warning: {first} (and {} more in the report)", more.len())
                }),
                (Status::Done | Status::Skipped, _) => None,
            };
            if let Some(note) = note {
                let _ = writeln!(
                    text,
                    "  line {} ({}): {}: {note}",
                    row.line,
                    row.id.as_deref().unwrap_or("no id"),
                    row.status.describe()
                );
            }
        }
        text
    }
}

/// Rows per status.
#[must_use]
pub fn counts(rows: &[RowResult]) -> BTreeMap<Status, usize> {
    let mut counts = BTreeMap::new();
    for row in rows {
        *counts.entry(row.status).or_insert(0) += 1;
    }
    counts
}
