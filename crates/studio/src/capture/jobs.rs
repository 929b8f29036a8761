//! The capture desk's long jobs, each on its own thread with progress and a cancel flag:
//! reading an input (video, photo, folder, upload), training the adapter, fine-tuning it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use faceanim_adapt::{
    Adapter, Control, Dataset, DatasetOptions, FaceCamera, Fingerprint, Fit, TrainOptions,
};
use faceanim_anim::filter::OneEuro;
use faceanim_media::FrameSource;
use faceanim_rig::Character;
use faceanim_track::{Frame, Tracker, TrackingMode};

use super::{
    CaptureDesk, FINETUNE_ANCHOR_SAMPLES, Footage, Job, PREVIEW_HEIGHT, Previews, SharedDesk, Take,
    face_models, lock, make_take, private_dir,
};

/// Starts reading `path` (a video, an image or a folder of images) in the background.
///
/// # Errors
/// A message when another job runs.
pub fn start_capture(
    desk: &SharedDesk,
    character: Arc<Character>,
    path: PathBuf,
    shown_name: String,
) -> Result<(), String> {
    let job = Job::new("reading the input");
    let (adapter, filtering) = {
        let mut guard = lock(desk);
        guard.busy()?;
        guard.job = Some(job.clone());
        (
            guard.adapter.clone(),
            (guard.keyframe_every, guard.smoothing),
        )
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let outcome = read_input(
            job,
            &character,
            adapter.as_ref(),
            &path,
            &shown_name,
            filtering,
        );
        let take = outcome?;
        let message = format!(
            "{}: {} frames at {} fps",
            shown_name,
            take.session.frames.len(),
            take.session.fps
        );
        lock(&desk).set_take(take);
        Ok(message)
    });
    Ok(())
}

fn read_input(
    job: &Job,
    character: &Character,
    adapter: Option<&Adapter>,
    path: &Path,
    shown_name: &str,
    filtering: (usize, Option<OneEuro>),
) -> Result<Take, String> {
    job.stage("loading the face models", 1);
    let models = face_models()?;
    let mut source =
        FrameSource::open(path, 30.0).map_err(|e| rename(&e.to_string(), path, shown_name))?;
    let info = source.info();
    job.stage("reading frames", info.frames.unwrap_or(0));
    let mut tracker = Tracker::new(models, TrackingMode::Track);
    let mut records = Vec::new();
    let mut previews = Previews::new();
    let mut names = Vec::new();
    while let Some(image) = source
        .next_frame()
        .map_err(|e| rename(&e.to_string(), path, shown_name))?
    {
        if job.cancelled() {
            return Err("cancelled".into());
        }
        let index = records.len();
        let frame = Frame {
            width: image.width,
            height: image.height,
            rgb: &image.rgb,
        };
        records.push(
            faceanim_capture::capture_frame(&mut tracker, index, index as f32 / info.fps, &frame)
                .map_err(|e| e.to_string())?,
        );
        previews.push(&image.preview(PREVIEW_HEIGHT).to_png()?)?;
        names.push(source.frame_name(index));
        job.progress(index + 1);
    }
    if records.is_empty() {
        return Err(format!("{shown_name}: no frames"));
    }
    if records.iter().all(|r| r.found.is_none()) {
        return Err(format!(
            "{shown_name}: no face was found in any of its {} frames",
            records.len()
        ));
    }
    make_take(
        character,
        adapter,
        Footage {
            source: shown_name.to_owned(),
            fps: info.fps,
            records,
            frame_names: names,
            previews,
            still: source.is_still(),
        },
        filtering,
    )
}

/// Messages about an uploaded file name the file the user picked, not its temporary copy.
fn rename(message: &str, path: &Path, shown: &str) -> String {
    message.replace(&path.display().to_string(), shown)
}

impl CaptureDesk {
    /// Saves an uploaded input (or one photo of a sequence sent as `batch`) to a private
    /// folder and returns its path.
    ///
    /// # Errors
    /// The file error.
    pub fn store_upload(
        &mut self,
        name: &str,
        bytes: &[u8],
        batch: Option<&str>,
    ) -> Result<PathBuf, String> {
        let mut dir = private_dir(&mut self.uploads, "faceanim-capture-", "uploads")?.to_owned();
        // Photos sent together are one sequence: a folder of their own, read in name order.
        if let Some(batch) = batch {
            if batch.is_empty() || !batch.chars().all(|c| c.is_ascii_alphanumeric()) {
                return Err(format!("batch: '{batch}' must be letters and digits"));
            }
            dir = dir.join(format!("batch-{batch}"));
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        // Keep only a safe file name (its extension tells images from videos).
        let clean: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let clean = clean.trim_start_matches('.');
        let path = dir.join(if clean.is_empty() { "input" } else { clean });
        faceanim_files::write_atomic(&path, bytes).map_err(|e| e.to_string())?;
        Ok(path)
    }
}

/// Starts rendering a training set of `samples` expressions (or reusing the cached one) and
/// training the character's adapter on it in the background; saves it and re-estimates the
/// take.
///
/// # Errors
/// A message for too few samples, an unknown exclusive shape, or another job running.
pub fn start_training(
    desk: &SharedDesk,
    character: Arc<Character>,
    samples: usize,
    seed: u64,
) -> Result<(), String> {
    if samples < 100 {
        return Err(format!("samples: at least 100, got {samples}"));
    }
    let exclusive =
        faceanim_adapt::sampling::exclusive_pairs(&character, &[]).map_err(|e| e.to_string())?;
    let options = DatasetOptions {
        samples,
        seed,
        exclusive,
    };
    let job = Job::new("training the adapter");
    let adapter_path = {
        let mut guard = lock(desk);
        guard.busy()?;
        guard.job = Some(job.clone());
        guard.adapter_path.clone()
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let cache = faceanim_adapt::dataset_cache_path(&adapter_path);
        let dataset = dataset_for(job, &character, &options, &cache, true)?;
        let train_options = TrainOptions {
            seed,
            ..TrainOptions::default()
        };
        job.stage("training", train_options.max_epochs);
        let adapter = with_control(job, |control| {
            faceanim_adapt::train(&dataset, &train_options, control)
        })?;
        faceanim_files::write_atomic(
            &adapter_path,
            &adapter.to_bytes().map_err(|e| e.to_string())?,
        )
        .map_err(|e| e.to_string())?;
        let message = format!(
            "trained on {} renders: test MAE {:.4}; saved {}",
            adapter.report.samples,
            adapter.report.mae_test,
            adapter_path.display()
        );
        install_adapter(&desk, &character, &adapter_path, adapter)?;
        Ok(message)
    });
    Ok(())
}

/// Starts fine-tuning the adapter on the take's corrected frames (the seed's offline mode) in
/// the background; saves it and re-estimates the take.
///
/// # Errors
/// A message when there is no adapter, no take or no correction, or another job runs.
pub fn start_finetune(desk: &SharedDesk, character: Arc<Character>) -> Result<(), String> {
    let job = Job::new("fine-tuning the adapter");
    let (adapter, corrections, adapter_path) = {
        let mut guard = lock(desk);
        guard.busy()?;
        let adapter = guard
            .adapter
            .clone()
            .ok_or("there is no adapter to fine-tune: train one first")?;
        let take = guard.take.as_ref().ok_or("no capture is open")?;
        let corrections = take.session.corrections_for_training();
        if corrections.is_empty() {
            return Err("correct at least one frame with a face first".into());
        }
        guard.job = Some(job.clone());
        (adapter, corrections, guard.adapter_path.clone())
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let cache = faceanim_adapt::dataset_cache_path(&adapter_path);
        let options = DatasetOptions {
            samples: FINETUNE_ANCHOR_SAMPLES,
            seed: 1,
            exclusive: faceanim_adapt::sampling::exclusive_pairs(&character, &[])
                .map_err(|e| e.to_string())?,
        };
        let dataset = dataset_for(job, &character, &options, &cache, false)?;
        let options = TrainOptions {
            architecture: adapter.architecture,
            ..TrainOptions::default()
        };
        job.stage("fine-tuning", options.max_epochs);
        let (tuned, report) = with_control(job, |control| {
            faceanim_adapt::finetune(&adapter, &dataset, &corrections, &options, control)
        })?;
        faceanim_files::write_atomic(&adapter_path, &tuned.to_bytes().map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())?;
        install_adapter(&desk, &character, &adapter_path, tuned)?;
        Ok(format!(
            "fine-tuned on {} corrected frames: their error {:.4} → {:.4}, test {:.4} → {:.4}; saved {}",
            corrections.len(),
            report.corrected_before,
            report.corrected_after,
            report.test_before,
            report.test_after,
            adapter_path.display()
        ))
    });
    Ok(())
}

/// Runs `work` on its own thread and ends `job` with its outcome. A panic (a bug) ends the job
/// with an error instead of leaving the studio busy for ever.
fn spawn_job(job: Arc<Job>, work: impl FnOnce(&Job) -> Result<String, String> + Send + 'static) {
    std::thread::spawn(move || {
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&job)))
            .unwrap_or_else(|_| {
                Err("stopped by an internal error (a bug; the studio's log says where)".into())
            });
        job.finish(outcome);
    });
}

/// Runs `work` with the job's progress and cancel flag.
fn with_control<T>(
    job: &Job,
    work: impl FnOnce(Control<'_>) -> Result<T, faceanim_adapt::AdaptError>,
) -> Result<T, String> {
    let progress = |done: usize, _total: usize| job.progress(done);
    work(Control {
        progress: &progress,
        cancel: &job.cancel,
    })
    .map_err(|e| e.to_string())
}

/// The training set: the cached one when it fits (exactly `options` when `exact`, else any
/// set rendered from this character), else rendered now and cached.
fn dataset_for(
    job: &Job,
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    exact: bool,
) -> Result<Dataset, String> {
    if let Ok(bytes) = std::fs::read(cache)
        && let Ok(cached) = Dataset::from_bytes(&bytes)
    {
        let fits = if exact {
            cached.made_with(character, options)
        } else {
            cached.fingerprint == Fingerprint::of(character)
                && cached.blendshapes.len() == character.blendshapes().len()
        };
        if fits {
            return Ok(cached);
        }
    }
    job.stage("loading the face models", 1);
    let models = face_models()?;
    let camera = FaceCamera::frame(character, models).map_err(|e| e.to_string())?;
    job.stage("rendering", options.samples);
    let dataset = with_control(job, |control| {
        Dataset::generate(character, models, &camera, options, control)
    })?;
    if let Ok(bytes) = dataset.to_bytes()
        && let Err(e) = faceanim_files::write_atomic(cache, &bytes)
    {
        tracing::warn!("could not cache the training set: {e}");
    }
    Ok(dataset)
}

/// Makes `adapter` the desk's and re-estimates the open take with it.
fn install_adapter(
    desk: &SharedDesk,
    character: &Character,
    adapter_path: &Path,
    adapter: Adapter,
) -> Result<(), String> {
    let mut guard = lock(desk);
    if guard.adapter_path != adapter_path {
        return Err(format!(
            "another character was opened meanwhile; the adapter was saved to {} but is not used",
            adapter_path.display()
        ));
    }
    if let Some(take) = guard.take.as_mut() {
        take.session
            .reestimate(&adapter)
            .map_err(|e| e.to_string())?;
        take.by_adapter = Some(true);
        guard.save_take();
    }
    guard.adapter_note = match adapter.check(character) {
        Ok(Fit::OtherShape) => Some("trained on another shape of this rig".into()),
        _ => None,
    };
    if let Some(live) = lock(&guard.live).as_mut() {
        live.adapter = Some(adapter.clone());
    }
    guard.adapter = Some(adapter);
    Ok(())
}
