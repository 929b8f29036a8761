//! The capture desk's long jobs, each on its own thread with progress and a cancel flag:
//! reading an input (video, photo, folder, upload), training the adapter, fine-tuning it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use faceanim_adapt::{
    Adapter, Dataset, DatasetOptions, FaceCamera, Fingerprint, Fit, TrainOptions,
};
use faceanim_media::FrameSource;
use faceanim_rig::Character;
use faceanim_take::Footage;
use faceanim_track::{Tracker, TrackingMode};

use super::SharedDesk;
use crate::capture::job::{Job, spawn_job, with_control};
use crate::capture::models::{face_models, face_workers};
use crate::capture::open_take::{PREVIEW_HEIGHT, Previews};
use crate::error::ApiError;
use crate::lock;
use crate::views::{CaptureView, JobKind};

/// Frames a photo's 0 → peak → 0 animation lasts.
const STILL_FRAMES: usize = 30;
/// Fine-tuning needs the training set as an anchor; without a cached one it renders this many.
const FINETUNE_ANCHOR_SAMPLES: usize = 2_000;

/// Starts reading `path` (a video, an image or a folder of images) in the background.
///
/// # Errors
/// [`ApiError::Busy`] when another job runs.
pub fn start_capture(
    desk: &SharedDesk,
    character: Arc<Character>,
    path: PathBuf,
    shown_name: String,
) -> Result<(), ApiError> {
    let job = Job::new(JobKind::ReadingInput);
    {
        let mut guard = lock(desk);
        guard.busy()?;
        guard.job = Some(job.clone());
    }
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let (footage, previews) = read_input(job, &path, &shown_name)?;
        super::retarget::ensure_map(job, &desk, &character)?;
        let mut guard = lock(&desk);
        let take = guard.take_of(&character, footage)?;
        let message = format!(
            "{}: {} frames at {} fps",
            shown_name,
            take.session.frames.len(),
            take.session.fps
        );
        guard.set_take(take, previews);
        Ok(message)
    });
    Ok(())
}

/// Opens `clip` (of the file `shown`) as the take (the desk's `open_clip`), `opened` before
/// its notice. When the character needs its retarget map for it (a Live Link Face recording
/// on a VRoid avatar: the desk's `clip_needs_map`), the map is made first in the background,
/// as `faceanim export --clip` makes it; if it cannot be made, that is said and the clip goes
/// on by name. Answers with the state read under the lock that opened the take or started the
/// job.
///
/// # Errors
/// [`ApiError::Busy`] when another job runs, or (opened at once) the clip's error.
pub fn open_clip(
    desk: &SharedDesk,
    character: Arc<Character>,
    clip: faceanim_anim::Clip,
    shown: String,
    opened: Option<String>,
) -> Result<CaptureView, ApiError> {
    // A take kept with the ARKit values it was made of, opened on another character: those
    // values take the shapes its columns leave out.
    let clip = clip.for_character(&character).into_owned();
    let job = Job::new(JobKind::MakingMap);
    let (path, view) = {
        let mut guard = lock(desk);
        guard.busy()?;
        if !guard.clip_needs_map(&character, &clip) {
            guard.open_clip(&character, &clip, &shown)?;
            if let Some(opened) = opened {
                guard.notice_first(opened);
            }
            return Ok(guard.view(&character));
        }
        guard.job = Some(job.clone());
        (guard.map_path.clone(), guard.view(&character))
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let made = super::retarget::make(job, &desk, &character, None);
        if job.cancelled() {
            return Err(faceanim_adapt::AdaptError::Cancelled.into());
        }
        let mut guard = lock(&desk);
        guard.still_open(&path, &shown)?;
        let frames = guard.open_clip(&character, &clip, &shown)?;
        let mut first = opened.unwrap_or_default();
        let message = match made {
            Ok(map) => format!(
                "{}: {frames} frames, through the retarget map made for it ({} of ARKit's 52 channels reach its shapes)",
                faceanim_rig::excerpt(&shown),
                map.answered()
            ),
            Err(e) => {
                let said = format!(
                    "The retarget map could not be made ({e}): the clip's ARKit channels reach only the shapes named for them."
                );
                tracing::warn!("{shown}: {said}");
                first = format!("{first} {said}").trim().to_owned();
                format!(
                    "{}: {frames} frames, by name",
                    faceanim_rig::excerpt(&shown)
                )
            }
        };
        if !first.is_empty() {
            guard.notice_first(first);
        }
        Ok(message)
    });
    Ok(view)
}

/// Starts lip-syncing `speech` after making the character's retarget map, when the mouth
/// needs the map and it has none (a rig whose names say nothing of a mouth, with no adapter:
/// the desk's `speech_needs_map`), as `faceanim lipsync` makes it; answers with the state
/// that shows the job. `None` when the map is not needed: the caller lip-syncs at once.
///
/// # Errors
/// [`ApiError::Busy`] when another job runs.
pub fn speech_after_map(
    desk: &SharedDesk,
    character: Arc<Character>,
    speech: &crate::capture::speech::Speech,
) -> Result<Option<CaptureView>, ApiError> {
    let job = Job::new(JobKind::MakingMap);
    let (path, view) = {
        let mut guard = lock(desk);
        if !guard.speech_needs_map(&character) {
            return Ok(None);
        }
        guard.busy()?;
        guard.job = Some(job.clone());
        (guard.map_path.clone(), guard.view(&character))
    };
    let (desk, speech) = (desk.clone(), speech.clone());
    spawn_job(job, move |job| {
        let map = super::retarget::make(job, &desk, &character, None).map_err(|e| {
            if job.cancelled() {
                return e;
            }
            ApiError::Invalid(format!(
                "{}: {} has no mouth shapes by name, and its retarget map, which lip sync would go through, could not be made: {e}",
                faceanim_rig::excerpt(&speech.shown),
                faceanim_rig::excerpt(character.name())
            ))
        })?;
        job.stage("lip sync", 0);
        let mouth = {
            let mut guard = lock(&desk);
            guard.still_open(&path, &speech.shown)?;
            guard.mouth(&character)?
        };
        let lip_sync = speech.lip_sync(&mouth).map_err(|e| speech.named(e))?;
        let frames =
            lock(&desk).put_speech(&character, &lip_sync, speech.sound(), &speech.shown)?;
        Ok(format!(
            "{}: {frames} frames of lip sync, through the retarget map made for it ({} of ARKit's 52 channels reach its shapes)",
            faceanim_rig::excerpt(&speech.shown),
            map.answered()
        ))
    });
    Ok(Some(view))
}

/// Reads every frame of `path` through the capture pipeline, with a preview of each.
fn read_input(job: &Job, path: &Path, shown_name: &str) -> Result<(Footage, Previews), ApiError> {
    job.stage("loading the face models", 1);
    let models = face_models()?;
    let renamed =
        |e: faceanim_media::MediaError| ApiError::Invalid(rename(&e.to_string(), path, shown_name));
    let mut source = FrameSource::open(path, 30.0).map_err(renamed)?;
    let info = source.info();
    job.stage("reading frames", info.frames.unwrap_or(0));
    let workers = lock(face_workers()?);
    let mut tracker = Tracker::new(models, TrackingMode::Track);
    let mut records = Vec::new();
    let mut previews = Previews::new();
    let mut names = Vec::new();
    // A frame for each thread at a time, each shown as it is read; the bytes of frames done
    // with are read into again.
    let mut frames = Vec::with_capacity(workers.count() + 1);
    let mut spares = Vec::with_capacity(workers.count() + 1);
    loop {
        spares.extend(frames.drain(..).filter_map(faceanim_capture::reusable));
        while frames.len() <= workers.count() {
            let Some(image) = source.next_frame_reusing(spares.pop()).map_err(renamed)? else {
                break;
            };
            previews.push_image(&image, PREVIEW_HEIGHT)?;
            names.push(source.frame_name(records.len() + frames.len()));
            frames.push(faceanim_capture::shared(image));
        }
        if frames.is_empty() {
            break;
        }
        if job.cancelled() {
            return Err(faceanim_adapt::AdaptError::Cancelled.into());
        }
        let first = records.len();
        records.extend(faceanim_capture::capture_frames(
            &mut tracker,
            &workers,
            first,
            info.fps,
            &frames,
        )?);
        job.progress(records.len());
    }
    if records.is_empty() {
        return Err(ApiError::Invalid(format!("{shown_name}: no frames")));
    }
    if records.iter().all(|r| r.found.is_none()) {
        return Err(ApiError::Invalid(format!(
            "{shown_name}: no face was found in any of its {} frames",
            records.len()
        )));
    }
    let footage = Footage {
        source: shown_name.to_owned(),
        fps: info.fps,
        records,
        frame_names: names,
        still_frames: source.is_still().then_some(STILL_FRAMES),
    };
    Ok((footage, previews))
}

/// Messages about an uploaded file name the file the user picked, not its temporary copy.
fn rename(message: &str, path: &Path, shown: &str) -> String {
    message.replace(&path.display().to_string(), shown)
}

/// Starts rendering a training set of `samples` expressions (or reusing the cached one) and
/// training the character's adapter on it in the background, on top of the character's
/// retarget map when it has one (as `faceanim adapt` does); saves it and re-estimates the
/// take.
///
/// # Errors
/// [`ApiError::Invalid`] for too few samples, or [`ApiError::Busy`] with another job running.
pub fn start_training(
    desk: &SharedDesk,
    character: Arc<Character>,
    samples: usize,
    seed: u64,
) -> Result<(), ApiError> {
    if samples < faceanim_adapt::MIN_SAMPLES {
        return Err(ApiError::Invalid(format!(
            "samples: at least {}, got {samples}",
            faceanim_adapt::MIN_SAMPLES
        )));
    }
    let exclusive = faceanim_adapt::sampling::exclusive_pairs(&character, &[])
        .map_err(|e| ApiError::Invalid(e.to_string()))?;
    let options = DatasetOptions {
        samples,
        seed,
        exclusive,
        augmentation: faceanim_adapt::Augmentation::default(),
    };
    let job = Job::new(JobKind::TrainingAdapter);
    let (adapter_path, map) = {
        let mut guard = lock(desk);
        guard.busy()?;
        guard.job = Some(job.clone());
        (guard.adapter_path.clone(), guard.map.clone())
    };
    let desk = desk.clone();
    spawn_job(job, move |job| {
        let cache = faceanim_adapt::dataset_cache_path(&adapter_path);
        let dataset = dataset_for(job, &character, &options, &cache, true)?;
        let train_options = TrainOptions {
            seed,
            ..TrainOptions::default()
        };
        job.stage("training", train_options.epochs_at_most());
        let base = map.map(|m| faceanim_adapt::Base::new((*m).clone()));
        let mut adapter = with_control(job, |control| {
            faceanim_adapt::train_on(&dataset, &train_options, base, control)
        })?;
        adapter.report.shapes = readings(job, &character, &adapter)?;
        faceanim_files::write_atomic(&adapter_path, &adapter.to_bytes()?)?;
        // Short: the adapter's path and report show beside it.
        let message = format!(
            "trained on {} renders, test MAE {:.3}",
            adapter.report.samples, adapter.report.mae_test
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
/// [`ApiError::Invalid`] when there is no adapter or no correction, [`ApiError::NoTake`], or
/// [`ApiError::Busy`] when another job runs.
pub fn start_finetune(desk: &SharedDesk, character: Arc<Character>) -> Result<(), ApiError> {
    let job = Job::new(JobKind::FineTuning);
    let (adapter, corrections, adapter_path) = {
        let mut guard = lock(desk);
        guard.busy()?;
        let adapter = guard.adapter.clone().ok_or(ApiError::Invalid(
            "there is no adapter to fine-tune: train one first".into(),
        ))?;
        let corrections = guard.open_take()?.take.session.corrections_for_training();
        if corrections.is_empty() {
            return Err(ApiError::Invalid(
                "correct at least one frame with a face first".into(),
            ));
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
                .map_err(|e| ApiError::Invalid(e.to_string()))?,
            augmentation: faceanim_adapt::Augmentation::default(),
        };
        let dataset = dataset_for(job, &character, &options, &cache, false)?;
        let options = TrainOptions {
            architecture: adapter.architecture,
            ..TrainOptions::default()
        };
        job.stage("fine-tuning", options.max_epochs);
        let (mut tuned, report) = with_control(job, |control| {
            faceanim_adapt::finetune(&adapter, &dataset, &corrections, &options, control)
        })?;
        tuned.report.shapes = readings(job, &character, &tuned)?;
        faceanim_files::write_atomic(&adapter_path, &tuned.to_bytes()?)?;
        install_adapter(&desk, &character, &adapter_path, tuned)?;
        Ok(format!(
            "fine-tuned on {} corrected frames: their error {:.3} → {:.3}, test {:.3} → {:.3}",
            corrections.len(),
            report.corrected_before,
            report.corrected_after,
            report.test_before,
            report.test_after,
        ))
    });
    Ok(())
}

/// The training set: the cached one when it fits (exactly `options` when `exact`, else any
/// set rendered from this character), else rendered now and cached.
fn dataset_for(
    job: &Job,
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    exact: bool,
) -> Result<Dataset, ApiError> {
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
    let camera = FaceCamera::frame(character, models)?;
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

/// Each of `character`'s shapes shown alone and read by `adapter`, for the page to say which
/// ones capture cannot drive; none when the character's neutral face is not read (the
/// adapter is still saved).
fn readings(
    job: &Job,
    character: &Character,
    adapter: &Adapter,
) -> Result<Vec<faceanim_adapt::ShapeReading>, ApiError> {
    job.stage("reading each shape alone", 1);
    let models = face_models()?;
    let camera = FaceCamera::frame(character, models)?;
    match camera.readings(character, models, adapter) {
        Err(e @ faceanim_adapt::AdaptError::NoNeutralFace) => {
            tracing::warn!("the shapes were not read one by one: {e}");
            Ok(Vec::new())
        }
        other => Ok(other?),
    }
}

/// Makes `adapter` the desk's and re-estimates the open take with it.
fn install_adapter(
    desk: &SharedDesk,
    character: &Character,
    adapter_path: &Path,
    adapter: Adapter,
) -> Result<(), ApiError> {
    let mut guard = lock(desk);
    if guard.adapter_path != adapter_path {
        return Err(ApiError::Invalid(format!(
            "another character was opened meanwhile; the adapter was saved to {} but is not used",
            adapter_path.display()
        )));
    }
    if let Some(open) = guard.take.as_mut() {
        open.take.reestimate(&adapter)?;
        guard.save_take();
    }
    guard.adapter_note = match adapter.check(character) {
        Ok(Fit::OtherShape) => Some("trained on another shape of this rig".into()),
        _ => None,
    };
    if let Some(live) = lock(&guard.live).as_mut() {
        live.estimator = Box::new(adapter.clone());
    }
    guard.adapter = Some(adapter);
    Ok(())
}
