//! `faceanim batch`: a manifest of jobs, each row run once, on this machine or as one worker of
//! an array job (the contract is `faceanim_batch`'s; this file runs the rows).
//!
//! A row runs in a worker process — this binary with `--index N` — whether the rows are spread
//! over machines by an engine (Ray, Kubernetes, AWS Batch, Slurm) or over this machine's cores
//! by `--jobs`: one way to run a row, a crash or a full memory costs one row, and the command's
//! own messages stay with the row they belong to.

use std::collections::VecDeque;
use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};
use std::process::{ExitCode, Stdio};
use std::sync::{Mutex, mpsc};
use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use faceanim_batch::manifest::{Entry, Kind, Manifest, Row};
use faceanim_batch::record::{self, Planner, Policy, Reason, State};
use faceanim_batch::report::{Event, Report, RowResult, Status};
use faceanim_batch::select::Selection;

/// `faceanim batch`'s arguments.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// The manifest: JSON Lines, or a sheet (.csv, .tsv, a spreadsheet's "Unicode text" .txt;
    /// cells separated by commas, semicolons or tabs); one row per job (docs/batch.md). Paths in it are relative to its folder.
    pub manifest: PathBuf,
    /// Run only the row at this index (0-based, among the rows): the worker contract. Without
    /// it, JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX or SLURM_ARRAY_TASK_ID name the row
    /// when set. Exits 0 when the row is done or skipped, 42 when its input is bad (do not
    /// retry), anything else for a failure worth retrying.
    #[arg(long, conflicts_with = "shard")]
    pub index: Option<usize>,
    /// Run the Ith of N shares of the rows (I/N, counting from 0): rows whose index is I
    /// modulo N.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Run every row, even where an index variable is set.
    #[arg(long, conflicts_with_all = ["index", "shard"])]
    pub all: bool,
    /// Rows run at once on this machine (default: its cores).
    #[arg(short, long)]
    pub jobs: Option<usize>,
    /// Redo rows whose record says they are up to date.
    #[arg(long)]
    pub force: bool,
    /// Overwrite outputs edited since the batch wrote them (kept and reported otherwise).
    #[arg(long)]
    pub overwrite_edits: bool,
    /// How many more times a row that failed for the machine's reasons (not its input's) is
    /// started.
    #[arg(long, default_value_t = 1)]
    pub retries: u32,
    /// Progress on standard error: a bar, JSON lines (an event per row), or nothing.
    #[arg(long, value_enum, default_value_t = Progress::Bar)]
    pub progress: Progress,
    /// The report (JSON, every row's result). Default: MANIFEST.report.json beside the
    /// manifest; a worker running one row writes none unless asked.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Print where each selected row stands (JSON lines: to run and why, skipped, edited, bad)
    /// and run nothing.
    #[arg(long)]
    pub plan: bool,
}

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Progress {
    /// A bar for a person.
    Bar,
    /// A JSON object per line (`start`, one `row` per row, `end`).
    Json,
    /// Nothing.
    None,
}

/// The commands a row runs, parsed from the row as from a command line.
#[derive(Debug, Parser)]
#[command(name = "faceanim", no_binary_name = true)]
struct RowLine {
    #[command(subcommand)]
    job: RowJob,
}

#[derive(Debug, Subcommand)]
enum RowJob {
    Lipsync(crate::lipsync::LipsyncArgs),
    Track(crate::track::TrackArgs),
    GenerateShapes(crate::generate::GenerateArgs),
}

pub fn run(args: &BatchArgs) -> anyhow::Result<ExitCode> {
    let started = Instant::now();
    // A manifest that cannot be used, or a row that is not in it, is the input's fault: 42,
    // which an engine does not retry (a manifest it cannot read at all may be a volume not yet
    // mounted: retried).
    let refuse = |error: &dyn std::fmt::Display| {
        eprintln!("error: {error}");
        Ok(ExitCode::from(faceanim_batch::EXIT_BAD_INPUT))
    };
    let mut manifest = match Manifest::read(&args.manifest) {
        Ok(manifest) => manifest,
        Err(error) if error.is_bad_input() => return refuse(&error),
        Err(error) => return Err(error.into()),
    };
    if let Some(encoding) = manifest.guessed_encoding {
        let manifest = args.manifest.display().to_string();
        let note = faceanim_files::text::guessed_note(&manifest, encoding, None, "\"CSV UTF-8\"");
        eprintln!("{note}");
    }
    check_outputs(&mut manifest);
    let selection = if args.all {
        Selection::All
    } else {
        match Selection::choose(args.index, args.shard.as_deref(), |name| {
            std::env::var(name).ok()
        }) {
            Ok(selection) => selection,
            Err(error) => return refuse(&error),
        }
    };
    if let Selection::Index(index) = selection
        && index >= manifest.entries.len()
    {
        return refuse(&format!(
            "{}: row {index} asked for; the rows are 0 to {}",
            args.manifest.display(),
            manifest.entries.len() - 1
        ));
    }
    let policy = Policy {
        force: args.force,
        overwrite_edits: args.overwrite_edits,
    };
    let planner = Planner::new(env!("CARGO_PKG_VERSION"));
    let selected: Vec<&Entry> = manifest
        .entries
        .iter()
        .filter(|e| selection.contains(e.index))
        .collect();
    if args.plan {
        for entry in selected {
            outln!(
                "{}",
                serde_json::to_string(&plan_line(entry, &planner, policy))?
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    if let Selection::Index(_) = selection {
        // The worker: this process runs the row.
        let result = run_here(selected[0], &planner, policy);
        report_row(args.progress, &result)?;
        if let Some(path) = &args.report {
            write_report(
                path,
                &Report::new(
                    args.manifest.clone(),
                    env!("CARGO_PKG_VERSION"),
                    started.elapsed().as_secs_f64(),
                    vec![result.clone()],
                ),
            )?;
        }
        return Ok(ExitCode::from(result.status.exit_code()));
    }
    let report = run_pool(
        args,
        manifest.entries.len(),
        &selected,
        &planner,
        policy,
        started,
    )?;
    let path = args
        .report
        .clone()
        .unwrap_or_else(|| default_report_path(&args.manifest));
    write_report(&path, &report)?;
    out!("{}", report.summary());
    outln!("report: {}", path.display());
    Ok(ExitCode::from(report.exit_code()))
}

/// The outputs' formats, checked with the rows: the exporter knows them.
fn check_outputs(manifest: &mut Manifest) {
    let mut bad = Vec::new();
    for row in manifest.rows() {
        for output in &row.outputs {
            let problem = match row.kind {
                Kind::Lipsync | Kind::Track => {
                    faceanim_export::Format::from_path(Path::new(output))
                        .err()
                        .map(|e| e.to_string())
                }
                Kind::GenerateShapes => {
                    let lower = output.to_ascii_lowercase();
                    (!(lower.ends_with(".glb") || lower.ends_with(".vrm")))
                        .then(|| format!("{output}: generate-shapes writes .glb or .vrm"))
                }
            };
            if let Some(problem) = problem {
                bad.push((row.index, problem));
                break;
            }
        }
    }
    for (index, problem) in bad {
        manifest.reject(index, "outputs", problem);
    }
}

/// How a row ended, or stands without running.
struct Outcome {
    status: Status,
    reason: Option<String>,
    error: Option<String>,
}

impl Outcome {
    fn new(status: Status, reason: Option<String>, error: Option<String>) -> Outcome {
        Outcome {
            status,
            reason,
            error,
        }
    }

    fn bad(error: &dyn std::fmt::Display) -> Outcome {
        Outcome::new(Status::BadInput, None, Some(error.to_string()))
    }

    fn failed(error: String) -> Outcome {
        Outcome::new(Status::Failed, None, Some(error))
    }

    /// The result of `entry`'s row.
    fn of(self, entry: &Entry, seconds: f64, attempts: u32) -> RowResult {
        RowResult {
            index: entry.index,
            line: entry.line,
            id: entry.id.clone(),
            status: self.status,
            reason: self.reason,
            error: self.error,
            seconds,
            attempts,
            notes: Vec::new(),
        }
    }
}

/// Where `entry`'s row stands: settled without running it (bad, up to date, edited), or to
/// run, and why.
fn standing(entry: &Entry, planner: &Planner, policy: Policy) -> Result<Outcome, Reason> {
    let row = match &entry.row {
        Err(problem) => return Ok(Outcome::bad(problem)),
        Ok(row) => row,
    };
    match planner.state(row, policy) {
        Ok(State::ToDo(reason)) => Err(reason),
        Ok(State::Done) => Ok(Outcome::new(Status::Skipped, None, None)),
        Ok(State::Edited(paths)) => Ok(Outcome::new(Status::Edited, Some(paths.join(", ")), None)),
        Ok(State::Bad(why)) => Ok(Outcome::bad(&why)),
        Err(error) => Ok(Outcome::bad(&error)),
    }
}

/// One line of `--plan`.
fn plan_line(entry: &Entry, planner: &Planner, policy: Policy) -> serde_json::Value {
    let (state, detail) = match standing(entry, planner, policy) {
        Err(reason) => ("to_run", Some(reason.to_string())),
        Ok(outcome) => (
            match outcome.status {
                Status::Skipped => "skipped",
                Status::Edited => "edited",
                _ => "bad_input",
            },
            outcome.error.or(outcome.reason),
        ),
    };
    serde_json::json!({
        "index": entry.index,
        "line": entry.line,
        "id": entry.id,
        "state": state,
        "detail": detail,
    })
}

/// Runs the row of `entry` in this process, under its lock, and says how it went.
fn run_here(entry: &Entry, planner: &Planner, policy: Policy) -> RowResult {
    let started = Instant::now();
    let outcome = match &entry.row {
        Err(problem) => Outcome::bad(problem),
        Ok(row) => run_row(entry, row, planner, policy),
    };
    outcome.of(entry, started.elapsed().as_secs_f64(), 1)
}

fn run_row(entry: &Entry, row: &Row, planner: &Planner, policy: Policy) -> Outcome {
    let _lock = match record::lock(row) {
        Ok(lock) => lock,
        Err(error) => return Outcome::failed(error.to_string()),
    };
    // Input found bad by running is recorded, so that it is not run again until it changes.
    let bad = |why: String| {
        if let Err(error) = planner.remember_bad(row, &why) {
            tracing::warn!("{}: the row's bad input is not recorded: {error}", row.id);
        }
        Outcome::bad(&why)
    };
    // Under the lock: another worker may have done the row meanwhile.
    let reason = match standing(entry, planner, policy) {
        Ok(settled) => return settled,
        Err(reason) => reason,
    };
    let staged = record::staged_paths(row);
    let line = match RowLine::try_parse_from(row.command(&staged)) {
        Ok(line) => line,
        Err(e) => {
            let text = e.render().to_string();
            let first = text.lines().next().unwrap_or_default();
            let problem = first.trim_start_matches("error: ");
            return bad(format!("the row's options: {problem}"));
        }
    };
    tracing::debug!(id = %row.id, %reason, "running the row");
    let ran = match line.job {
        RowJob::Lipsync(args) => crate::lipsync::run(args),
        RowJob::Track(args) => crate::track::run(args),
        RowJob::GenerateShapes(args) => crate::generate::run(&args),
    };
    if let Err(error) = ran {
        for path in &staged {
            let _ = std::fs::remove_file(path);
        }
        let told = in_users_names(row, chain(&error));
        return match status_of(&error) {
            Status::BadInput => bad(told),
            status => Outcome::new(status, None, Some(told)),
        };
    }
    match planner.commit(row, &staged) {
        Ok(()) => Outcome::new(Status::Done, Some(reason.to_string()), None),
        Err(error) => Outcome::failed(error.to_string()),
    }
}

/// `text` a row's command said, with its outputs named as the user named them: the command
/// wrote to staged names.
fn in_users_names(row: &Row, text: String) -> String {
    record::staged_paths(row)
        .iter()
        .zip(row.output_paths())
        .fold(text, |told, (staged, output)| {
            told.replace(&staged.display().to_string(), &output.display().to_string())
        })
}

/// A command's failure: the machine's (an operating-system error while reading or writing,
/// worth retrying) or the input's (anything the command found wrong with what it read).
fn status_of(error: &anyhow::Error) -> Status {
    let machine = error.chain().any(|cause| {
        cause.downcast_ref::<std::io::Error>().is_some_and(|e| {
            !matches!(
                e.kind(),
                std::io::ErrorKind::NotFound
                    | std::io::ErrorKind::InvalidData
                    | std::io::ErrorKind::InvalidInput
                    | std::io::ErrorKind::UnexpectedEof
            )
        })
    });
    if machine {
        Status::Failed
    } else {
        Status::BadInput
    }
}

/// An error with its causes, on one line.
fn chain(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    for cause in error.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

fn report_row(progress: Progress, result: &RowResult) -> anyhow::Result<()> {
    match progress {
        Progress::Json => eprintln!("{}", serde_json::to_string(&Event::Row(result.clone()))?),
        Progress::Bar => eprintln!("{}", row_line(result)),
        Progress::None => {}
    }
    Ok(())
}

/// A row's result for a person.
fn row_line(result: &RowResult) -> String {
    let mut text = format!(
        "line {} ({}): {}",
        result.line,
        result.id.as_deref().unwrap_or("no id"),
        result.status.describe()
    );
    for note in [&result.reason, &result.error].into_iter().flatten() {
        text.push_str(": ");
        text.push_str(note);
    }
    text
}

/// Runs the selected rows on this machine, `--jobs` at a time, each in a worker process.
fn run_pool(
    args: &BatchArgs,
    rows: usize,
    selected: &[&Entry],
    planner: &Planner,
    policy: Policy,
    started: Instant,
) -> anyhow::Result<Report> {
    let mut results = Vec::new();
    let mut queue = VecDeque::new();
    for entry in selected {
        match standing(entry, planner, policy) {
            Ok(settled) => results.push(settled.of(entry, 0.0, 0)),
            Err(_) => queue.push_back(entry.index),
        }
    }
    let to_run = queue.len();
    let progress = Shown::new(args.progress, rows, selected.len(), to_run)?;
    for result in &results {
        progress.row(result)?;
    }
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from))
        .clamp(1, to_run.max(1));
    let queue = Mutex::new(queue);
    let exe = std::env::current_exe()?;
    let (sender, receiver) = mpsc::channel();
    std::thread::scope(|scope| -> anyhow::Result<()> {
        for _ in 0..jobs {
            let sender = sender.clone();
            let (queue, exe) = (&queue, &exe);
            scope.spawn(move || {
                loop {
                    let next = queue.lock().ok().and_then(|mut q| q.pop_front());
                    let Some(index) = next else { break };
                    let entry = selected.iter().find(|e| e.index == index).copied();
                    let Some(entry) = entry else { break };
                    let result = run_worker(exe, args, entry);
                    if sender.send(result).is_err() {
                        break;
                    }
                }
            });
        }
        drop(sender);
        for result in receiver {
            progress.row(&result)?;
            results.push(result);
        }
        Ok(())
    })?;
    let report = Report::new(
        args.manifest.clone(),
        env!("CARGO_PKG_VERSION"),
        started.elapsed().as_secs_f64(),
        results,
    );
    progress.end(&report)?;
    Ok(report)
}

/// Runs `entry`'s row in a worker process (this binary with `--index`), starting it again
/// while it fails for the machine's reasons and `--retries` allows.
fn run_worker(exe: &Path, args: &BatchArgs, entry: &Entry) -> RowResult {
    let started = Instant::now();
    let mut attempts = 0;
    loop {
        attempts += 1;
        let mut result = run_process(exe, args, entry);
        result.attempts = attempts;
        result.seconds = started.elapsed().as_secs_f64();
        if result.status != Status::Failed || attempts > args.retries {
            return result;
        }
        tracing::warn!(
            line = entry.line,
            "row failed, starting it again: {:?}",
            result.error
        );
    }
}

/// The longest tail of a worker's messages kept for its report.
const LOG_TAIL: usize = 20;
/// The most warnings and notes kept for a row.
const MOST_NOTES: usize = 20;

/// Whether a line a command said is one to heed: a warning or a note (as `lipsync` says how a
/// line was heard), not what it wrote or how long it took.
fn is_note(line: &str) -> bool {
    line.starts_with("warning: ") || line.starts_with("note: ")
}

fn run_process(exe: &Path, args: &BatchArgs, entry: &Entry) -> RowResult {
    let mut command = std::process::Command::new(exe);
    command
        .arg("batch")
        .arg(&args.manifest)
        .args(["--index", &entry.index.to_string(), "--progress", "json"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    if args.force {
        command.arg("--force");
    }
    if args.overwrite_edits {
        command.arg("--overwrite-edits");
    }
    let mut child = match command.spawn() {
        Ok(child) => child,
        Err(e) => {
            return Outcome::failed(format!("starting {}: {e}", exe.display())).of(entry, 0.0, 1);
        }
    };
    let mut result = None;
    let mut tail = VecDeque::new();
    let mut notes = Vec::new();
    if let Some(stderr) = child.stderr.take() {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            match serde_json::from_str::<Event>(&line) {
                Ok(Event::Row(row)) => result = Some(row),
                _ => {
                    if is_note(&line) && notes.len() < MOST_NOTES {
                        notes.push(match &entry.row {
                            Ok(row) => in_users_names(row, line.clone()),
                            Err(_) => line.clone(),
                        });
                    }
                    tail.push_back(line);
                    if tail.len() > LOG_TAIL {
                        tail.pop_front();
                    }
                }
            }
        }
    }
    let status = child.wait();
    match (result, status) {
        (Some(result), Ok(status))
            if status.code() == Some(i32::from(result.status.exit_code())) =>
        {
            RowResult { notes, ..result }
        }
        (_, status) => {
            let how = match status {
                Ok(status) => status.to_string(),
                Err(e) => e.to_string(),
            };
            let log = Vec::from(tail).join("\n");
            Outcome::failed(format!(
                "the worker ended ({how}) without a result; its last words: {log}"
            ))
            .of(entry, 0.0, 1)
        }
    }
}

/// Progress as asked: a bar, JSON lines, or nothing.
struct Shown {
    how: Progress,
    bar: Option<indicatif::ProgressBar>,
}

impl Shown {
    fn new(how: Progress, rows: usize, selected: usize, to_run: usize) -> anyhow::Result<Shown> {
        let bar = (how == Progress::Bar).then(|| {
            let bar = indicatif::ProgressBar::new(selected as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} rows  {elapsed_precise} (eta {eta}) {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        if how == Progress::Json {
            let start = Event::Start {
                rows,
                selected,
                to_run,
            };
            eprintln!("{}", serde_json::to_string(&start)?);
        }
        Ok(Shown { how, bar })
    }

    fn row(&self, result: &RowResult) -> anyhow::Result<()> {
        match (&self.bar, self.how) {
            (Some(bar), _) => {
                if matches!(result.status, Status::BadInput | Status::Failed) {
                    bar.println(row_line(result));
                }
                bar.inc(1);
            }
            (None, Progress::Json) => {
                eprintln!("{}", serde_json::to_string(&Event::Row(result.clone()))?);
            }
            (None, _) => {}
        }
        Ok(())
    }

    fn end(&self, report: &Report) -> anyhow::Result<()> {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
        if self.how == Progress::Json {
            let end = Event::End {
                counts: report.counts.clone(),
                seconds: report.seconds,
            };
            eprintln!("{}", serde_json::to_string(&end)?);
        }
        Ok(())
    }
}

/// `MANIFEST.report.json` beside the manifest.
fn default_report_path(manifest: &Path) -> PathBuf {
    let name = manifest.file_name().unwrap_or_default().to_string_lossy();
    manifest.with_file_name(format!("{name}.report.json"))
}

fn write_report(path: &Path, report: &Report) -> anyhow::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(report)?;
    bytes.push(b'\n');
    faceanim_files::write_output(path, &bytes)?;
    Ok(())
}
