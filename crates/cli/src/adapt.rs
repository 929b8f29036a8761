//! `faceanim adapt`: train a character's adapter (renders → capture pipeline → candle), its
//! ablation table, and fine-tuning from the corrections in session files.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::Context as _;
use faceanim_adapt::heldout::{Evaluation, HeldOut};
use faceanim_adapt::sampling::{ExclusionReason, exclusive_pairs};
use faceanim_adapt::{
    Activation, Adapter, Architecture, Augmentation, Base, Calibration, Control, Dataset,
    DatasetOptions, FaceCamera, FeatureSet, LandmarkFrame, Locality, Loss, ShapeReading,
    TrainOptions, WIDTH_PER_SHAPE,
};
use faceanim_rig::Character;
use faceanim_take::Session;
use faceanim_track::FaceModels;

/// `faceanim adapt`'s arguments.
#[derive(Debug, clap::Args)]
pub struct AdaptArgs {
    /// The character (default: the built-in head).
    pub character: Option<PathBuf>,
    /// The adapter file to write.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Random expressions to render (split 80/10/10 into training, validation and test; the
    /// training part shared out among the --members networks).
    #[arg(long, default_value_t = faceanim_adapt::DEFAULT_SAMPLES)]
    pub samples: usize,
    /// Networks trained side by side, each on its own share of the training renders, whose
    /// mean the adapter reads out (bagging: people are read better than by one network on all
    /// of them, which follows the renders too closely); 1 for one network.
    #[arg(long, default_value_t = faceanim_adapt::DEFAULT_MEMBERS)]
    pub members: usize,
    /// Random seed (expressions, initial weights, batch order).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print {"mae_test", "mae_val", "samples", "members", "seconds", "shapes": [...],
    /// "heldout": [...]} as JSON at the end.
    #[arg(long)]
    pub json: bool,
    /// Whether the training renders vary camera, light, skin, background and picture quality
    /// (randomised) or all come from one front camera in one light (none).
    #[arg(long, value_enum, default_value_t = AugmentationChoice::Randomised)]
    pub augmentation: AugmentationChoice,
    /// Whether the adapter reads faces relative to a neutral face of the same source
    /// (neutral) or as they are (none).
    #[arg(long, value_enum, default_value_t = CalibrationChoice::Neutral)]
    pub calibration: CalibrationChoice,
    /// Also measure the adapter on stills from another renderer: a folder with pictures and
    /// `truth.json` (`{"neutral": "n.png", "frames": [{"image": "a.png", "weights": {"name":
    /// 0.5}}]}`); repeatable.
    #[arg(long = "eval-dir", value_name = "DIR")]
    pub eval_dirs: Vec<PathBuf>,
    /// What the adapter reads.
    #[arg(long, value_enum, default_value_t = FeatureChoice::Both)]
    pub features: FeatureChoice,
    /// Which inputs each shape reads: only those it moves in the training set, through hidden
    /// units of its own (per-shape), or all of them through one shared layer, as the seed's
    /// network (global).
    #[arg(long, value_enum, default_value_t = LocalityChoice::PerShape)]
    pub locality: LocalityChoice,
    /// Where the landmarks' origin and unit come from: the landmarks expressions hardly move
    /// (rigid), or all of them, as adapters before (whole).
    #[arg(long, value_enum, default_value_t = FrameChoice::Rigid)]
    pub landmark_frame: FrameChoice,
    /// Width of the hidden layer: per shape with --locality per-shape (default 16), in all
    /// with --locality global (default 256).
    #[arg(long)]
    pub hidden: Option<usize>,
    /// ReLU instead of LeakyReLU between the layers.
    #[arg(long)]
    pub relu: bool,
    /// Do not clamp the outputs to [0, 1].
    #[arg(long)]
    pub no_clamp: bool,
    /// What training minimises.
    #[arg(long, value_enum, default_value_t = LossChoice::CensoredAbsolute)]
    pub loss: LossChoice,
    /// Two blendshapes never active together in the training set, `A,B`; repeatable
    /// (opposites such as jawLeft/jawRight are found on their own).
    #[arg(long)]
    pub exclusive: Vec<String>,
    /// Where the rendered training set is cached (default: beside the adapter).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Render the training set again even when a cached one fits.
    #[arg(long)]
    pub fresh: bool,
    /// Train every row of the ablation table and print it, instead of writing an adapter.
    #[arg(long)]
    pub ablation: bool,
    /// Fine-tune on the corrections in these session files.
    #[arg(long, num_args = 1..)]
    pub finetune: Vec<PathBuf>,
    /// With --finetune: the adapter to start from (default: -o's file).
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// Instead of training, measure this adapter's MAE on renders of CHARACTER (for
    /// example another identity of the rig it was trained on); prints {"mae", "samples"}.
    #[arg(long, conflicts_with_all = ["finetune", "ablation"])]
    pub evaluate: Option<PathBuf>,
    /// Train the network alone. By default a character whose names leave channels to
    /// geometry gets its adapter on top of its retarget map (the map beside it, as `faceanim
    /// retarget` makes it, or --retarget): the network learns what the map misses, and the
    /// adapter keeps the map.
    #[arg(long)]
    pub alone: bool,
    /// The retarget map to train on (default: NAME.retarget.json beside the character, made
    /// when there is none).
    #[arg(long, conflicts_with = "alone")]
    pub retarget: Option<PathBuf>,
    /// On the map: how strongly the network is held to the map (the weight of its own
    /// outputs' mean absolute value in the loss): 0 reads the renders best and people worst,
    /// 1 or more is the map itself.
    #[arg(long, default_value_t = faceanim_adapt::DEFAULT_STAY, conflicts_with = "alone")]
    pub stay: f64,
}

/// What an adapter reads (the command line's names for [`FeatureSet`]; clap stays out of the
/// library).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FeatureChoice {
    /// The 52 expression scores.
    Scores,
    /// Pose-normalised landmarks.
    Landmarks,
    /// Both.
    Both,
}

/// The command line's names for [`Augmentation`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AugmentationChoice {
    /// One front camera, one light.
    None,
    /// Camera, light, skin, background and picture quality drawn per group of samples.
    Randomised,
}

impl From<AugmentationChoice> for Augmentation {
    fn from(choice: AugmentationChoice) -> Augmentation {
        match choice {
            AugmentationChoice::None => Augmentation::None,
            AugmentationChoice::Randomised => Augmentation::Randomised,
        }
    }
}

/// The command line's names for [`Loss`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LossChoice {
    /// Absolute error before the clamp, a target at 0 or 1 counting only outputs beyond it.
    CensoredAbsolute,
    /// The seed's: squared error of the clamped outputs.
    SquaredClamped,
}

impl From<LossChoice> for Loss {
    fn from(choice: LossChoice) -> Loss {
        match choice {
            LossChoice::CensoredAbsolute => Loss::CensoredAbsolute,
            LossChoice::SquaredClamped => Loss::SquaredClamped,
        }
    }
}

/// The command line's names for [`Locality`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LocalityChoice {
    /// Each shape reads only what it moves, through hidden units of its own.
    PerShape,
    /// Every shape reads every input through one shared hidden layer (the seed's).
    Global,
}

/// The command line's names for [`LandmarkFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FrameChoice {
    /// Placed by the landmarks expressions hardly move.
    Rigid,
    /// Placed by all landmarks (adapters before).
    Whole,
}

/// The command line's names for [`Calibration`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CalibrationChoice {
    /// Faces as captured.
    None,
    /// Faces relative to a neutral face of the same source.
    Neutral,
}

impl From<CalibrationChoice> for Calibration {
    fn from(choice: CalibrationChoice) -> Calibration {
        match choice {
            CalibrationChoice::None => Calibration::None,
            CalibrationChoice::Neutral => Calibration::Neutral,
        }
    }
}

impl From<FeatureChoice> for FeatureSet {
    fn from(choice: FeatureChoice) -> FeatureSet {
        match choice {
            FeatureChoice::Scores => FeatureSet::Scores,
            FeatureChoice::Landmarks => FeatureSet::Landmarks,
            FeatureChoice::Both => FeatureSet::Both,
        }
    }
}

impl AdaptArgs {
    /// The network the arguments describe.
    fn architecture(&self) -> Architecture {
        let (locality, hidden) = match self.locality {
            LocalityChoice::PerShape => (
                Locality::PerShape {
                    width: self.hidden.unwrap_or(WIDTH_PER_SHAPE),
                },
                Architecture::default().hidden,
            ),
            LocalityChoice::Global => (
                Locality::Global,
                self.hidden.unwrap_or(Architecture::global().hidden),
            ),
        };
        Architecture {
            features: self.features.into(),
            hidden,
            locality,
            frame: match self.landmark_frame {
                FrameChoice::Rigid => LandmarkFrame::Rigid,
                FrameChoice::Whole => LandmarkFrame::Whole,
            },
            activation: if self.relu {
                Activation::Relu
            } else {
                Activation::LeakyRelu
            },
            clamp: !self.no_clamp,
            calibration: self.calibration.into(),
        }
    }
}

/// Reads every `--eval-dir` for `character`'s blendshapes.
fn held_out(dirs: &[PathBuf], character: &Character) -> anyhow::Result<Vec<HeldOut>> {
    let names: Vec<String> = character.blendshape_names();
    dirs.iter()
        .map(|dir| Ok(HeldOut::read(dir, &names)?))
        .collect()
}

/// The face models, loaded on first use and kept: the ablation renders two training sets and
/// measures every row on the held-out folders.
fn face_models() -> anyhow::Result<&'static FaceModels> {
    static MODELS: std::sync::OnceLock<FaceModels> = std::sync::OnceLock::new();
    if let Some(models) = MODELS.get() {
        return Ok(models);
    }
    let loaded = FaceModels::load_with_threads(1).context("loading the face models")?;
    Ok(MODELS.get_or_init(|| loaded))
}

/// `adapter` on each held-out folder, each result printed as it comes.
fn evaluate_held_out(adapter: &Adapter, folders: &[HeldOut]) -> anyhow::Result<Vec<Evaluation>> {
    if folders.is_empty() {
        return Ok(Vec::new());
    }
    let models = face_models()?;
    folders
        .iter()
        .map(|folder| {
            let e = folder.evaluate(adapter, models)?;
            eprintln!(
                "held out {}: MAE {:.4} on {} of {} stills (predicting the mean: {:.4}, zeros: {:.4}; neutral: {:?}); by group: {}; worst: {}",
                e.dir.display(),
                e.mae,
                e.faces,
                e.stills,
                e.mae_mean_baseline,
                e.mae_zero_baseline,
                e.neutral,
                by_group(&e.groups),
                e.worst
                    .iter()
                    .take(4)
                    .map(|(n, mae, bias)| format!("{n} {mae:.2} (bias {bias:+.2})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            Ok(e)
        })
        .collect()
}

/// Errors per sampling group, for the terminal: `one 0.021 (12), …`.
fn by_group(groups: &[faceanim_adapt::sampling::GroupError]) -> String {
    groups
        .iter()
        .map(|g| format!("{} {:.3} ({})", g.group.name(), g.mae, g.samples))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The adapter file next to a character: `NAME.adapter.safetensors`.
pub fn default_adapter_path(character: Option<&Path>, name: &str) -> PathBuf {
    faceanim_adapt::default_adapter_path(character.and_then(Path::parent), name)
}

fn bar(total: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{spinner}} {what} {{pos}}/{{len}} [{{bar:40}}] {{per_sec}} {{eta}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar
}

/// Runs `work` with a progress bar of `total` steps; the command line never cancels.
fn with_bar<T>(
    total: usize,
    what: &str,
    work: impl FnOnce(Control<'_>) -> Result<T, faceanim_adapt::AdaptError>,
) -> anyhow::Result<T> {
    let progress = bar(total as u64, what);
    let never = AtomicBool::new(false);
    let report = |done: usize, total: usize| {
        progress.set_length(total as u64);
        progress.set_position(done as u64);
    };
    let result = work(Control {
        progress: &report,
        cancel: &never,
    })?;
    progress.finish_and_clear();
    Ok(result)
}

fn parse_exclusive(rules: &[String]) -> anyhow::Result<Vec<(String, String)>> {
    rules
        .iter()
        .map(|rule| {
            let (a, b) = rule.split_once(',').with_context(|| {
                format!("--exclusive '{rule}': give two blendshape names separated by a comma")
            })?;
            Ok((a.trim().to_owned(), b.trim().to_owned()))
        })
        .collect()
}

/// Loads the cached training set when it was made from this character with these settings,
/// else renders a new one and caches it.
fn dataset(
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    fresh: bool,
) -> anyhow::Result<(Dataset, bool)> {
    if !fresh && cache.exists() {
        let bytes = faceanim_files::read_bytes(cache)?;
        match Dataset::from_bytes(&bytes) {
            Ok(cached) if cached.made_with(character, options) => {
                eprintln!(
                    "using the training set cached in {} ({} samples)",
                    cache.display(),
                    cached.len()
                );
                return Ok((cached, true));
            }
            Ok(_) => eprintln!(
                "{} was made with other settings or another character; rendering a new one",
                cache.display()
            ),
            Err(e) => eprintln!("{}: {e}; rendering a new one", cache.display()),
        }
    }
    let models = face_models()?;
    let camera = FaceCamera::frame(character, models)?;
    for warning in camera.warnings() {
        eprintln!("warning: {warning}");
    }
    if camera.framing == faceanim_adapt::Framing::Assumed {
        eprintln!(
            "warning: no face was detected in a front render of {}; using the middle of the picture",
            character.name()
        );
    }
    let dataset = with_bar(options.samples, "rendering", |control| {
        Dataset::generate(character, models, &camera, options, control)
    })?;
    let dropped = options.samples - dataset.len();
    if dropped > 0 {
        eprintln!("{dropped} renders gave degenerate landmarks and were left out");
    }
    faceanim_files::write_atomic(cache, &dataset.to_bytes()?)?;
    Ok((dataset, false))
}

fn train_with_bar(
    dataset: &Dataset,
    options: &TrainOptions,
    base: Option<&Base>,
) -> anyhow::Result<Adapter> {
    with_bar(options.epochs_at_most(), "training epoch", |control| {
        faceanim_adapt::train_on(dataset, options, base.cloned(), control)
    })
}

/// The map the adapter is trained on top of: none with --alone, else --retarget's, else the
/// one a capture of `character` would use (`None` for a rig its names drive whole).
fn base(args: &AdaptArgs, character: &Character) -> anyhow::Result<Option<Base>> {
    if args.alone {
        return Ok(None);
    }
    let map = crate::retarget::for_capture(
        character,
        args.character.as_deref(),
        args.retarget.as_deref(),
        face_models()?,
    )?;
    if let Some(map) = &map {
        eprintln!(
            "training on top of the retarget map of {} ({} of 52 channels): --alone trains the network alone",
            map.character,
            map.answered()
        );
    }
    Ok(map.map(Base::new))
}

pub fn run(args: AdaptArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    anyhow::ensure!(
        args.samples >= faceanim_adapt::MIN_SAMPLES,
        "--samples must be at least {}, got {}",
        faceanim_adapt::MIN_SAMPLES,
        args.samples
    );
    let training = faceanim_adapt::Split::of(args.samples).train.len();
    anyhow::ensure!(
        (1..=training).contains(&args.members),
        "--members must be between 1 and the {training} training samples of --samples {}, got {}",
        args.samples,
        args.members
    );
    anyhow::ensure!(
        args.stay.is_finite() && args.stay >= 0.0,
        "--stay must be 0 or more, got {}",
        args.stay
    );
    if let Some(hidden) = args.hidden {
        anyhow::ensure!(
            (1..=4096).contains(&hidden),
            "--hidden must be between 1 and 4096, got {hidden}"
        );
    }
    let character = crate::input::load_or_default(args.character.as_deref())?.character;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_adapter_path(args.character.as_deref(), character.name()));
    // Before minutes of rendering and training, not after.
    faceanim_files::check_output(&output)?;
    let cache = args
        .dataset
        .clone()
        .unwrap_or_else(|| faceanim_adapt::dataset_cache_path(&output));
    faceanim_files::check_output(&cache)?;
    let user_rules = parse_exclusive(&args.exclusive)?;
    let exclusive = exclusive_pairs(&character, &user_rules)?;
    let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
    let describe = |reason: ExclusionReason| {
        exclusive
            .iter()
            .filter(|p| p.reason == reason)
            .map(|p| format!("{}/{}", names[p.a], names[p.b]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    eprintln!(
        "{} exclusive pairs — opposite motion: {}; ARKit names: {}; yours: {}",
        exclusive.len(),
        describe(ExclusionReason::Opposite),
        describe(ExclusionReason::ArkitNames),
        describe(ExclusionReason::User)
    );
    let options = DatasetOptions {
        samples: args.samples,
        seed: args.seed,
        exclusive,
        augmentation: args.augmentation.into(),
    };
    let folders = held_out(&args.eval_dirs, &character)?;

    if !args.finetune.is_empty() {
        return finetune(
            &args, &character, &options, &cache, &output, started, &folders,
        );
    }
    if let Some(path) = &args.evaluate {
        return evaluate(path, &character, &options, &cache, args.fresh, &folders);
    }

    let (dataset, _) = dataset(&character, &options, &cache, args.fresh)?;
    let dataset_seconds = started.elapsed().as_secs_f64();
    let train_options = TrainOptions {
        architecture: args.architecture(),
        loss: args.loss.into(),
        seed: args.seed,
        members: args.members,
        stay: args.stay,
        ..TrainOptions::default()
    };
    if args.ablation {
        return ablation(
            &character,
            &options,
            &cache,
            &dataset,
            &train_options,
            &folders,
            args.json,
        );
    }
    let base = base(&args, &character)?;
    let mut adapter = train_with_bar(&dataset, &train_options, base.as_ref())?;
    adapter.report.shapes = readings(&character, &adapter)?;
    faceanim_files::write_output(&output, &adapter.to_bytes()?)?;
    let seconds = started.elapsed().as_secs_f64();
    let heldout = evaluate_held_out(&adapter, &folders)?;
    let report = &adapter.report;
    eprintln!(
        "wrote {} — test MAE {:.4} ({} on the front renders; by group: {}), validation MAE {:.4}, {} samples, {} networks, best epoch {} of {}; {:.1} s ({:.1} s for the training set, {:.1} s training)",
        output.display(),
        report.mae_test,
        report
            .mae_test_front
            .map_or_else(|| "–".to_owned(), |m| format!("{m:.4}")),
        by_group(&report.mae_test_groups),
        report.mae_val,
        report.samples,
        report.members,
        report.best_epoch,
        report.epochs,
        seconds,
        dataset_seconds,
        report.seconds
    );
    if args.json {
        let summary = TrainingSummary {
            mae_test: report.mae_test,
            mae_test_front: report.mae_test_front,
            mae_test_groups: &report.mae_test_groups,
            mae_val: report.mae_val,
            samples: report.samples,
            members: report.members,
            best_epoch: report.best_epoch,
            epochs: report.epochs,
            seconds,
            seconds_dataset: dataset_seconds,
            seconds_training: report.seconds,
            augmentation: args.augmentation.into(),
            calibration: adapter.architecture.calibration,
            loss: train_options.loss,
            readings: Readings {
                shapes: &report.shapes,
                heldout: &heldout,
            },
        };
        outln!("{}", serde_json::to_string(&summary)?);
    }
    Ok(())
}

/// What `faceanim adapt --json` prints after training.
#[derive(serde::Serialize)]
struct TrainingSummary<'a> {
    mae_test: f32,
    /// On the test split's front renders.
    mae_test_front: Option<f32>,
    /// On the test split, per sampling group.
    mae_test_groups: &'a [faceanim_adapt::sampling::GroupError],
    mae_val: f32,
    samples: usize,
    /// Networks averaged.
    members: usize,
    best_epoch: usize,
    epochs: usize,
    /// Wall-clock seconds from the start to the written adapter (training set, training and
    /// the shape readings).
    seconds: f64,
    /// Of which rendering and reading the training set (or loading it when cached).
    seconds_dataset: f64,
    /// Of which training.
    seconds_training: f64,
    augmentation: Augmentation,
    calibration: Calibration,
    loss: Loss,
    #[serde(flatten)]
    readings: Readings<'a>,
}

/// What both summaries end with: each shape shown alone and read back, and the adapter on the
/// held-out renders.
#[derive(serde::Serialize)]
struct Readings<'a> {
    shapes: &'a [ShapeReading],
    heldout: &'a [Evaluation],
}

/// Each of `character`'s shapes shown alone and read by `adapter`; the ones capture cannot
/// drive are printed. A character whose neutral face is not read gets none (said on the
/// terminal): the adapter is still written.
fn readings(character: &Character, adapter: &Adapter) -> anyhow::Result<Vec<ShapeReading>> {
    let models = face_models()?;
    let camera = FaceCamera::frame(character, models)?;
    let readings = match camera.readings(character, models, adapter) {
        Ok(readings) => readings,
        Err(e @ faceanim_adapt::AdaptError::NoNeutralFace) => {
            eprintln!("the shapes were not read one by one: {e}");
            return Ok(Vec::new());
        }
        Err(e) => return Err(e.into()),
    };
    let count = |r: faceanim_adapt::Reading| readings.iter().filter(|s| s.reading == r).count();
    let unseen = faceanim_adapt::readings::unseen(&readings);
    eprintln!(
        "shown alone from the front, {} of {} shapes are read ({} more weakly){}",
        count(faceanim_adapt::Reading::Read),
        readings.len(),
        count(faceanim_adapt::Reading::Weak),
        if unseen.is_empty() {
            String::new()
        } else {
            format!(
                "; capture cannot drive {}: sketch them or correct frames",
                unseen.join(", ")
            )
        }
    );
    Ok(readings)
}

/// The seed's Table 1 on this character, extended: features × calibration × augmentation,
/// then the seed's architecture rows and its loss on the default setting. Each row: its own
/// test MAE, and the MAE on every held-out folder.
fn ablation(
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    dataset_given: &Dataset,
    base: &TrainOptions,
    folders: &[HeldOut],
    json: bool,
) -> anyhow::Result<()> {
    // The other augmentation's training set is cached beside the given one.
    let other = |augmentation: Augmentation| -> anyhow::Result<Dataset> {
        let options = DatasetOptions {
            augmentation,
            ..options.clone()
        };
        let name = cache
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let path = cache.with_file_name(format!("{}.{name}", augmentation.name()));
        Ok(dataset(character, &options, &path, false)?.0)
    };
    let mut datasets: Vec<(Augmentation, Dataset)> =
        vec![(options.augmentation, dataset_given.clone())];
    let mut results = Vec::new();
    for experiment in faceanim_adapt::ablation::experiments(base) {
        let (augmentation, loss, members) = (
            experiment.augmentation,
            experiment.options.loss,
            experiment.options.members,
        );
        if !datasets.iter().any(|(a, _)| *a == augmentation) {
            datasets.push((augmentation, other(augmentation)?));
        }
        let Some((_, data)) = datasets.iter().find(|(a, _)| *a == augmentation) else {
            continue;
        };
        let adapter = train_with_bar(data, &experiment.options, None)?;
        let heldout = evaluate_held_out(&adapter, folders)?;
        // As trained: a per-shape network's width is known once the shapes are.
        let architecture = adapter.architecture;
        // Every row on the front renders' test split too (the project's renders without
        // augmentation), once they exist.
        let front = datasets
            .iter()
            .find(|(a, _)| *a == Augmentation::None)
            .map(|(_, d)| adapter.mean_absolute_error_of(d, d.split().test));
        eprintln!(
            "{} {} {} {} {} {} {:?} clamp={} {}: test MAE {:.4}",
            augmentation.name(),
            architecture.features.name(),
            architecture.calibration.name(),
            architecture.frame.name(),
            architecture.locality.name(),
            architecture.hidden,
            architecture.activation,
            architecture.clamp,
            loss.name(),
            adapter.report.mae_test
        );
        results.push(AblationRow {
            augmentation,
            features: architecture.features,
            calibration: architecture.calibration,
            frame: architecture.frame,
            locality: architecture.locality,
            hidden: architecture.hidden,
            members,
            activation: architecture.activation,
            clamp: architecture.clamp,
            loss,
            mae_test: adapter.report.mae_test,
            mae_val: adapter.report.mae_val,
            mae_front_renders_test: front,
            epochs: adapter.report.best_epoch,
            seconds: adapter.report.seconds,
            heldout,
        });
    }
    if json {
        outln!("{}", serde_json::to_string(&results)?);
    } else {
        let heldout_columns: String = folders
            .iter()
            .map(|f| format!(" held-out MAE ({}) |", f.dir.display()))
            .collect();
        outln!(
            "| augmentation | features | calibration | landmarks | inputs per shape | layers | hidden | networks | loss | test MAE (own renders) | test MAE (front renders) |{heldout_columns} best epoch | seconds |"
        );
        outln!("|{}", " --- |".repeat(13 + folders.len()));
        for r in &results {
            let activation = match r.activation {
                Activation::Relu => "ReLU",
                Activation::LeakyRelu => "LeakyReLU",
            };
            let clamp = if r.clamp { " → Clamp" } else { "" };
            let heldout: String = r
                .heldout
                .iter()
                .map(|e| format!(" {:.4} |", e.mae))
                .collect();
            let front = r
                .mae_front_renders_test
                .map_or_else(|| "–".to_owned(), |m| format!("{m:.4}"));
            outln!(
                "| {} | {} | {} | {} | {} | Linear → {activation} → Linear{clamp} | {} | {} | {} | {:.4} | {front} |{heldout} {} | {:.1} |",
                r.augmentation.name(),
                r.features.name(),
                r.calibration.name(),
                r.frame.name(),
                match r.locality {
                    Locality::Global => "all",
                    Locality::PerShape { .. } => "what it moves",
                },
                r.hidden,
                r.members,
                r.loss.name(),
                r.mae_test,
                r.epochs,
                r.seconds
            );
        }
    }
    Ok(())
}

/// One row of the ablation table, as `--ablation --json` prints it.
#[derive(serde::Serialize)]
struct AblationRow {
    augmentation: Augmentation,
    features: FeatureSet,
    calibration: Calibration,
    frame: LandmarkFrame,
    locality: Locality,
    /// Hidden units in all (of every member).
    hidden: usize,
    /// Networks averaged.
    members: usize,
    activation: Activation,
    clamp: bool,
    loss: Loss,
    mae_test: f32,
    mae_val: f32,
    /// The row's adapter on the test split of the front renders (once that set exists).
    mae_front_renders_test: Option<f32>,
    /// The epoch whose weights were kept.
    epochs: usize,
    seconds: f64,
    heldout: Vec<Evaluation>,
}

/// The seed's offline mode: the corrections recorded in sessions fine-tune the adapter.
fn finetune(
    args: &AdaptArgs,
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    output: &Path,
    started: Instant,
    folders: &[HeldOut],
) -> anyhow::Result<()> {
    let from = args.from.clone().unwrap_or_else(|| output.to_owned());
    let adapter = crate::input::adapter(&from)?;
    adapter.check(character)?;
    let mut corrections = Vec::new();
    for path in &args.finetune {
        let session = Session::from_json(&faceanim_files::read_bytes(path)?)
            .with_context(|| format!("reading the session {}", path.display()))?;
        anyhow::ensure!(
            session.blendshapes == adapter.blendshapes,
            "{}: the session is for other blendshapes than the adapter {}",
            path.display(),
            from.display()
        );
        let found = session.corrections_for_training();
        eprintln!("{}: {} corrected frames", path.display(), found.len());
        corrections.extend(found);
    }
    anyhow::ensure!(
        !corrections.is_empty(),
        "the sessions hold no corrected frames with a face; correct some first (faceanim session SESSION correct …)"
    );
    // Fine-tuning mixes in the training set, so that the adapter does not forget the
    // character: the cached one the adapter was trained on, whatever settings made it.
    let cached = cache
        .exists()
        .then(|| faceanim_files::read_bytes(cache).ok())
        .flatten()
        .and_then(|bytes| Dataset::from_bytes(&bytes).ok())
        .filter(|d| d.fingerprint == faceanim_adapt::Fingerprint::of(character));
    let dataset = match cached {
        Some(d) => d,
        None => dataset(character, options, cache, false)?.0,
    };
    let train_options = TrainOptions {
        architecture: adapter.architecture,
        loss: args.loss.into(),
        seed: args.seed,
        ..TrainOptions::default()
    };
    let (mut tuned, outcome) = with_bar(40, "fine-tuning epoch", |control| {
        faceanim_adapt::finetune(&adapter, &dataset, &corrections, &train_options, control)
    })?;
    tuned.report.shapes = readings(character, &tuned)?;
    faceanim_files::write_output(output, &tuned.to_bytes()?)?;
    let seconds = started.elapsed().as_secs_f64();
    let heldout = evaluate_held_out(&tuned, folders)?;
    eprintln!(
        "wrote {}: MAE on the {} corrected frames {:.4} → {:.4}; test MAE {:.4} → {:.4}",
        output.display(),
        corrections.len(),
        outcome.corrected_before,
        outcome.corrected_after,
        outcome.test_before,
        outcome.test_after
    );
    if args.json {
        let summary = FinetuneSummary {
            mae_test: tuned.report.mae_test,
            mae_val: tuned.report.mae_val,
            samples: tuned.report.samples,
            seconds,
            corrected_frames: corrections.len(),
            mae_corrected_before: outcome.corrected_before,
            mae_corrected_after: outcome.corrected_after,
            mae_test_before: outcome.test_before,
            readings: Readings {
                shapes: &tuned.report.shapes,
                heldout: &heldout,
            },
        };
        outln!("{}", serde_json::to_string(&summary)?);
    }
    Ok(())
}

/// What `faceanim adapt --finetune … --json` prints.
#[derive(serde::Serialize)]
struct FinetuneSummary<'a> {
    /// Test MAE after fine-tuning.
    mae_test: f32,
    mae_val: f32,
    samples: usize,
    seconds: f64,
    corrected_frames: usize,
    mae_corrected_before: f32,
    mae_corrected_after: f32,
    mae_test_before: f32,
    #[serde(flatten)]
    readings: Readings<'a>,
}

/// MAE of an existing adapter on renders of `character` (another identity of its rig, say).
fn evaluate(
    path: &Path,
    character: &Character,
    options: &DatasetOptions,
    cache: &Path,
    fresh: bool,
    folders: &[HeldOut],
) -> anyhow::Result<()> {
    let adapter = crate::input::adapter(path)?;
    if adapter.check(character)? == faceanim_adapt::Fit::OtherShape {
        eprintln!(
            "{} was trained on another shape of this rig: measuring how well it transfers",
            path.display()
        );
    }
    // Held-out folders alone need no renders.
    if !folders.is_empty() {
        let heldout = evaluate_held_out(&adapter, folders)?;
        outln!("{}", serde_json::to_string(&Measured::HeldOut { heldout })?);
        return Ok(());
    }
    let (dataset, _) = dataset(character, options, cache, fresh)?;
    let mae = adapter.mean_absolute_error(&dataset);
    eprintln!(
        "{} on {} renders of {}: MAE {mae:.4}",
        path.display(),
        dataset.len(),
        character.name()
    );
    outln!(
        "{}",
        serde_json::to_string(&Measured::Renders {
            mae,
            samples: dataset.len(),
        })?
    );
    Ok(())
}

/// What `faceanim adapt --evaluate` prints.
#[derive(serde::Serialize)]
#[serde(untagged)]
enum Measured {
    /// On the held-out folders.
    HeldOut { heldout: Vec<Evaluation> },
    /// On renders of the character.
    Renders { mae: f32, samples: usize },
}
