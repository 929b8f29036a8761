//! `faceanim track`: a face image, image folder or video drives a character — by name, or
//! through the character's adapter — as open → capture → take → write.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use faceanim_anim::filter::OneEuro;
use faceanim_media::FrameSource;
use faceanim_take::{ByName, Estimator, Filtering, Footage, Retargeted, Session, Take};
use faceanim_track::{FaceModels, TrackingMode, Workers};

/// Which of the clean-ups to apply; the jitter of each is reported so users can choose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FilterChoice {
    /// The seed's keyframe sampling: a key every N frames, interpolated (default).
    Keyframes,
    /// One Euro smoothing (tunable with --min-cutoff and --beta).
    OneEuro,
    /// One Euro smoothing, then keyframes.
    Both,
    /// The raw per-frame estimates.
    None,
}

/// `faceanim track`'s arguments.
#[derive(Debug, clap::Args)]
pub struct TrackArgs {
    /// A photo (PNG, JPEG, WebP, or HEIC/AVIF through libheif's heif-dec), a folder of them (an
    /// image sequence, in name order), or a video
    /// (read with the ffmpeg program).
    pub input: PathBuf,
    /// The character (default: the built-in head).
    #[arg(long)]
    pub character: Option<PathBuf>,
    #[command(flatten)]
    pub out: crate::outputs::Outputs,
    /// Also keep every frame's landmarks, scores and pose here (JSON).
    #[arg(long)]
    pub raw: Option<PathBuf>,
    /// Clean-up of the per-frame estimates.
    #[arg(long, value_enum, default_value_t = FilterChoice::Keyframes)]
    pub filter: FilterChoice,
    /// Keyframe spacing in frames (the seed's default is 5).
    #[arg(long, default_value_t = faceanim_anim::keyframes::DEFAULT_EVERY)]
    pub keyframe_every: usize,
    /// One Euro cutoff at rest, Hz: lower is smoother.
    #[arg(long, default_value_t = OneEuro::default().min_cutoff)]
    pub min_cutoff: f32,
    /// One Euro speed coefficient: higher follows fast motion more closely.
    #[arg(long, default_value_t = OneEuro::default().beta)]
    pub beta: f32,
    /// Run the face detector on every frame instead of tracking from the previous one.
    #[arg(long)]
    pub detect_every_frame: bool,
    /// Frame rate given to a still image or an image folder (videos carry their own).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f32,
    /// Video frames tracked at once, one per thread, while another thread decodes ahead
    /// (default: the number of cores; 1 tracks frame by frame).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Drive the character through its adapter (from `faceanim adapt`) instead of its
    /// retarget map.
    #[arg(long)]
    pub adapter: Option<PathBuf>,
    /// The character's retarget map (default: NAME.retarget.json beside the character, made
    /// there in seconds when its shapes' names do not cover what MediaPipe reads).
    #[arg(long, value_name = "MAP")]
    pub retarget: Option<PathBuf>,
    /// Only the shapes whose names say an ARKit channel move, with MediaPipe's scores as they
    /// are (no retarget map).
    #[arg(long, conflicts_with_all = ["adapter", "retarget"])]
    pub by_name: bool,
    /// Also write the session (frames, estimates, keyframes) to correct with `faceanim
    /// session`.
    #[arg(long)]
    pub session: Option<PathBuf>,
    /// The frame of a neutral face (relaxed, mouth closed, looking ahead) that the adapter
    /// reads every other frame relative to; without it, the frame with the least expression.
    #[arg(long)]
    pub neutral_frame: Option<usize>,
    /// A frame to keep as a keyframe besides every --keyframe-every-th; repeatable.
    #[arg(long = "keyframe")]
    pub keyframes: Vec<usize>,
    /// For a still image: make it a 0 → peak → 0 animation of this many frames (without it, the
    /// photo's one pose).
    #[arg(long)]
    pub image_frames: Option<usize>,
}

impl TrackArgs {
    fn one_euro(&self) -> OneEuro {
        OneEuro {
            min_cutoff: self.min_cutoff,
            beta: self.beta,
            ..OneEuro::default()
        }
    }

    /// The filtering `choice` stands for, with these arguments' settings.
    fn filtering(&self, choice: FilterChoice) -> anyhow::Result<Filtering> {
        let (every, smoothing) = match choice {
            FilterChoice::Keyframes => (self.keyframe_every, None),
            FilterChoice::OneEuro => (1, Some(self.one_euro())),
            FilterChoice::Both => (self.keyframe_every, Some(self.one_euro())),
            FilterChoice::None => (1, None),
        };
        Filtering::new(every, smoothing)
            .map_err(|e| anyhow::anyhow!("--keyframe-every/--min-cutoff/--beta: {e}"))
    }
}

pub fn run(args: TrackArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        !args.out.outputs.is_empty() || args.raw.is_some() || args.session.is_some(),
        "give at least one -o OUTPUT (.json, .glb, .vrm, .vrma, .csv, .byoc.csv, .session.json), --session or --raw"
    );
    let formats = crate::outputs::formats_of(&args.out.outputs)?;
    for path in args.raw.iter().chain(&args.session) {
        faceanim_files::check_output(path)?;
    }
    anyhow::ensure!(
        args.fps.is_finite() && args.fps > 0.0,
        "--fps must be a positive number, got {}",
        args.fps
    );
    let threads = args.threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    anyhow::ensure!(
        (1..=64).contains(&threads),
        "--threads must be between 1 and 64, got {threads}"
    );
    let filtering = args.filtering(args.filter)?;
    // Load the character and its estimator first: a bad one should fail before minutes of
    // video.
    let character = crate::input::load_or_default(args.character.as_deref())?.character;
    crate::outputs::check_for(&args.out.outputs, &formats, Some(&character))?;
    // Start-up (once per process): the face models, and the threads that run them beside
    // this one (as MediaPipe's graph starts its own with the models; each warms itself on a
    // blank picture, which overlaps the clip's start below). What follows is per clip, and
    // is what the summary's whole-command rate counts.
    let models = FaceModels::load().context("loading the face models")?;
    let estimator = estimator(&args, &character, &models)?;
    if !formats.is_empty() || args.session.is_some() {
        match Take::check_moves(&character, estimator.as_ref()) {
            Err(faceanim_take::TakeError::NoArkitNames { .. }) => anyhow::bail!(
                "no shape of {} answers to MediaPipe's channels, by name or by geometry: set the map's rows (faceanim retarget --set) or train an adapter (faceanim adapt)",
                character.name()
            ),
            other => other?,
        }
    }

    let workers = Workers::start(&models, threads - 1).context("starting the face models")?;
    let clip_started = Instant::now();
    let (source, result, capture_seconds) = capture(&args, &models, &workers)?;
    if let Some(raw) = &args.raw {
        faceanim_files::write_output(raw, &serde_json::to_vec(&result)?)?;
        eprintln!(
            "wrote {} (landmarks and scores of {} frames)",
            raw.display(),
            result.frames.len()
        );
    }
    if formats.is_empty() && args.session.is_none() {
        return Ok(());
    }

    // The take: the records move into it (a long video's landmarks are not copied).
    let started = Instant::now();
    let (frames, fps, found, detector_runs) = (
        result.frames.len(),
        result.fps,
        result.faces_found(),
        result.detector_runs,
    );
    let footage = Footage {
        source: args.input.display().to_string(),
        fps,
        frame_names: result
            .frames
            .iter()
            .map(|f| source.frame_name(f.index))
            .collect(),
        records: result.frames,
        still_frames: args
            .image_frames
            .filter(|_| source.is_still())
            .map(|n| n.max(1)),
    };
    let mut take = Take::from_capture(&character, estimator.as_ref(), footage, filtering)?;
    if args.neutral_frame.is_some() {
        take.session
            .set_neutral(args.neutral_frame, estimator.as_ref())
            .map_err(|e| anyhow::anyhow!("--neutral-frame: {e}"))?;
    }
    if estimator.calibrated() {
        report_neutral(&take, estimator.as_ref());
    }
    let estimate_seconds = started.elapsed().as_secs_f64();
    for &k in &args.keyframes {
        take.session
            .add_keyframe(k)
            .map_err(|e| anyhow::anyhow!("--keyframe: {e}"))?;
    }
    let session = &take.session;
    if let Some(path) = &args.session {
        faceanim_files::write_output(path, session.to_json().as_bytes())?;
        eprintln!(
            "wrote {} (the session: correct it with faceanim session)",
            path.display()
        );
    }

    // Write.
    let animation = crate::outputs::take_animation(
        Some(&character),
        session,
        &crate::input::stem(&args.input, "capture"),
    )?
    // A jaw bone opens beside the shapes the map opens the mouth with, not twice.
    .with_opening(
        estimator
            .retarget_map()
            .and_then(faceanim_export::bones::jaw_opening),
    );
    crate::outputs::write_all(&args.out.outputs, &formats, &animation, args.out.glb)?;

    let timing = Timing {
        frames,
        fps,
        found,
        detector_runs,
        capture_seconds,
        estimate_seconds,
        clip_started,
    };
    let summary = summary(
        &args,
        &character,
        &take,
        estimator.as_ref(),
        &animation,
        timing,
    )?;
    outln!("{summary}");
    if found == 0 {
        eprintln!(
            "warning: {}: no face was found in any frame; the animation is all zeros",
            args.input.display()
        );
    }
    Ok(())
}

/// What capture found in one clip, and how long its parts took.
#[derive(Clone, Copy)]
struct Timing {
    frames: usize,
    fps: f32,
    /// Frames with a face.
    found: usize,
    detector_runs: usize,
    /// Opening, decoding and the face models.
    capture_seconds: f64,
    /// The take's estimates.
    estimate_seconds: f64,
    /// When this clip began: its whole time counts opening it, decoding, the face models,
    /// the estimates, the files written and the summary's measures; not the models' loading.
    clip_started: Instant,
}

/// The JSON summary `track` prints: counts, rates, the estimator and the jitter of each filter.
fn summary(
    args: &TrackArgs,
    character: &faceanim_rig::Character,
    take: &Take,
    estimator: &dyn Estimator,
    animation: &faceanim_export::Animation<'_>,
    timing: Timing,
) -> anyhow::Result<serde_json::Value> {
    let session = &take.session;
    let Timing {
        frames,
        fps,
        found,
        detector_runs,
        ..
    } = timing;
    let neutral = session.neutral();
    let jitter = |choice: FilterChoice| -> anyhow::Result<f32> {
        let mut variant: Session = session.clone();
        variant.set_filtering(args.filtering(choice)?);
        Ok(faceanim_anim::metrics::jitter(&variant.clip().frames))
    };
    let jitters = [
        jitter(FilterChoice::None)?,
        jitter(FilterChoice::OneEuro)?,
        jitter(FilterChoice::Keyframes)?,
    ];
    let whole_seconds = timing.clip_started.elapsed().as_secs_f64();
    Ok(serde_json::json!({
        "frames": frames,
        "fps": fps,
        "faces_found": found,
        "detector_runs": detector_runs,
        "seconds": timing.capture_seconds + timing.estimate_seconds,
        "frames_per_second": frames as f64 / timing.capture_seconds.max(1e-9),
        "whole_seconds": whole_seconds,
        "whole_frames_per_second": frames as f64 / whole_seconds.max(1e-9),
        "estimator": take.estimated_by(),
        "neutral": neutral,
        "adapter_ms_per_frame": 1000.0 * timing.estimate_seconds / frames.max(1) as f64,
        "character": character.name(),
        "blendshapes_driven": estimator.driven(),
        "bones": character
            .source()
            .map(|s| s.bones().found().map(|(b, _)| b.name()).collect::<Vec<_>>())
            .unwrap_or_default(),
        "blendshapes": character.blendshapes().len(),
        "filter": format!("{:?}", args.filter),
        "keyframes": session.keyframes().len(),
        "animation_frames": animation.clip.frames.len(),
        "jitter": {
            "raw": jitters[0],
            "one_euro": jitters[1],
            "keyframes": jitters[2],
            "chosen": faceanim_anim::metrics::jitter(&animation.clip.frames),
        },
    }))
}

/// Opens `args.input` and reads every frame's landmarks and scores, with a progress bar; with
/// the seconds the reading took (not the opening).
fn capture(
    args: &TrackArgs,
    models: &FaceModels,
    workers: &Workers,
) -> anyhow::Result<(FrameSource, faceanim_capture::Capture, f64)> {
    let mut source = FrameSource::open(&args.input, args.fps)?;
    let info = source.info();
    let mode = if args.detect_every_frame {
        TrackingMode::DetectEveryFrame
    } else {
        TrackingMode::Track
    };
    let bar = match info.frames {
        Some(n) => indicatif::ProgressBar::new(n as u64),
        None => indicatif::ProgressBar::no_length(),
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {pos}/{len} frames [{bar:40}] {per_sec} {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let started = Instant::now();
    let result = faceanim_capture::capture(models, workers, &mut source, mode, |n| {
        bar.set_position(n as u64)
    })
    .with_context(|| format!("capturing {}", args.input.display()))?;
    bar.finish_and_clear();
    Ok((source, result, started.elapsed().as_secs_f64()))
}

/// Says which neutral face the take is read against, and warns when it does not look neutral
/// (or, for one face read on its own, when that face reads as an expression).
fn report_neutral(take: &Take, estimator: &dyn Estimator) {
    if let Some(n) = take.session.neutral() {
        eprintln!(
            "neutral face: {} ({}){}",
            n.parts,
            match n.chosen {
                faceanim_take::NeutralChoice::User => "--neutral-frame",
                faceanim_take::NeutralChoice::Automatic => "each part of the face at its calmest",
            },
            if n.chosen == faceanim_take::NeutralChoice::Automatic {
                "; give --neutral-frame N if another frame is more neutral"
            } else {
                ""
            }
        );
    }
    if let Some(check) = take.session.neutral_check(estimator)
        && let Some(warning) = check.warning()
    {
        // With one face there is no other frame to name.
        let hint = if check.chosen.is_some() {
            " (--neutral-frame N)"
        } else {
            ""
        };
        eprintln!("warning: {warning}{hint}");
    }
}

/// The character's adapter (`--adapter`), else its retarget map (`--retarget`, or the one
/// beside it, made when needed), else its names.
fn estimator(
    args: &TrackArgs,
    character: &faceanim_rig::Character,
    models: &FaceModels,
) -> anyhow::Result<Box<dyn Estimator>> {
    let Some(path) = &args.adapter else {
        if args.by_name {
            return Ok(Box::new(ByName::new(character)));
        }
        return Ok(
            match crate::retarget::for_capture(
                character,
                args.character.as_deref(),
                args.retarget.as_deref(),
                models,
            )? {
                Some(map) => Box::new(Retargeted::new(std::sync::Arc::new(map))),
                None => Box::new(ByName::new(character)),
            },
        );
    };
    let adapter = crate::input::adapter(path)?;
    if adapter.check(character)? == faceanim_adapt::Fit::OtherShape {
        eprintln!(
            "warning: {} was trained on another shape of this rig; it works, but an adapter trained on {} (faceanim adapt) will be more accurate",
            path.display(),
            character.name()
        );
    }
    Ok(Box::new(adapter))
}
