//! The `faceanim` command line: one binary, one subcommand per job.
//!
//! Errors are mapped once, here: every failure prints `error: ` followed by its cause chain
//! (which names the file and the problem) and exits with status 1; usage errors exit with 2.
//! Each subcommand's arguments are a clap `Args` struct, passed as they are to its code.

/// `println!` that returns the error (a reader that went away: `faceanim … | head`) instead of
/// panicking; `main` ends quietly on a broken pipe, as ripgrep does.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

/// `print!` that returns the error; see [`outln`].
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)?
    }};
}

mod adapt;
mod generate;
mod info;
mod lipsync;
mod outputs;
mod retarget;
mod session;
mod stream;
mod track;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};

/// faceanim animates the face of any blendshape character.
///
/// A character is a glTF 2.0 file (.glb or .gltf) with morph targets, or a folder of OBJ files
/// (neutral.obj plus one OBJ per blendshape, in the same vertex order). Where a command's
/// CHARACTER is left out, it uses the built-in default head (52 ARKit blendshapes).
#[derive(Debug, Parser)]
#[command(name = "faceanim", version, about, long_about = None, propagate_version = true)]
struct Cli {
    /// More log output (-v: debug, -vv: trace). `RUST_LOG` works too.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The studio: a local web app to sketch facial animation on a character, or drive it from
    /// a face video, photos or the webcam (the main job).
    ///
    /// Serves the page on http://127.0.0.1:PORT (local connections only) and prints the URL.
    /// The project is saved to --project (default: CHARACTER-NAME.faceanim.json in the current
    /// folder); every edit is also autosaved beside it. Capture mode uses the character's
    /// adapter (--adapter, default NAME.adapter.safetensors beside the character) when there is
    /// one, and trains it there from the page.
    ///
    /// Example: faceanim studio head.glb --open
    Studio(StudioArgs),
    /// Describe a character: vertices, triangles, blendshapes, symmetry pairs, ARKit coverage.
    ///
    /// Example: faceanim info head.glb --json
    Info(InfoArgs),
    /// Write a character as a binary glTF (.glb), optionally with an animation from a clip.
    ///
    /// Converts OBJ folders and .gltf files to a single .glb that Blender, Unity, Unreal and
    /// three.js open directly. Example: faceanim export ict-obj/ -o ict.glb --clip take.json
    Export(ExportArgs),
    /// Replay a strokes file (DESIGN.md format: samples, handle edits, settings) on a character
    /// and write the animation: a GLB whose extra morph targets carry arcs and exaggerations,
    /// and optionally the baked clip of blendshape weights.
    ///
    /// Example: faceanim sketch head.glb take.strokes.json -o take.glb --clip take.json
    Sketch(SketchArgs),
    /// Write the built-in default head (52 ARKit blendshapes) as a .glb.
    ///
    /// Example: faceanim export-default -o default.glb
    ExportDefault(ExportDefaultArgs),
    /// Render a character to PNG: one pose, or a contact sheet of every blendshape at weight 1.
    ///
    /// Examples: faceanim render --sheet -o sheet.png;
    /// faceanim render head.glb --weights jawOpen=0.6,mouthSmileLeft=1 -o smile.png
    Render(RenderArgs),
    /// Animate a character from a face photo, an image folder or a video: landmarks, ARKit
    /// scores and head pose per frame (MediaPipe's face models, run on the CPU), mapped by name
    /// onto the character's blendshapes, or through its adapter.
    ///
    /// Outputs by extension (repeat -o for several): .json the clip (DESIGN.md), .glb the
    /// character with the animation (head pose on its root), .csv Live Link Face, .byoc.csv
    /// the seed's CSV, .session.json the session. Prints a JSON summary with the jitter of
    /// each filter so you can choose.
    ///
    /// Example: faceanim track take.mp4 --character ict.glb -o take.glb -o take.csv
    Track(track::TrackArgs),
    /// Train a character's adapter: render it with random expressions, read them back through
    /// the capture pipeline, and fit a small network from those readings to its own weights.
    ///
    /// Any blendshape set works, whatever its names. The adapter is written next to the
    /// character (NAME.adapter.safetensors) unless -o says otherwise, and the rendered
    /// training set is cached beside it. --ablation prints the seed's Table 1 for this
    /// character instead; --finetune SESSION… retrains the adapter on the corrections made in
    /// sessions (the seed's offline mode).
    ///
    /// Examples: faceanim adapt head.glb --json;
    /// faceanim adapt head.glb --finetune take.session.json
    Adapt(adapt::AdaptArgs),
    /// Correct a capture session (from `faceanim track … --session FILE`) and export it: the
    /// seed's human in the loop.
    ///
    /// Example: faceanim session take.session.json correct 40 jawOpen=0.9
    Session(session::SessionArgs),
    /// Stream a clip or a take live to a VMC marionette (VSeeFace, Warudo, VNyan, Unity or
    /// Unreal's VMC receiver) over OSC/UDP, at a steady rate.
    ///
    /// Example: faceanim stream take.json --to 127.0.0.1:39539 --fps 60 --loop --names arkit
    Stream(stream::StreamArgs),
    /// Lip sync: speech (a WAV, MP3 or Ogg file, or a video's sound) drives the character's
    /// mouth. Phones are recognised offline (CMU PocketSphinx), aligned to --text when given,
    /// and become the 15 Oculus visemes with animators' timing; they reach the character
    /// through its viseme shapes by name, or its ARKit mouth shapes.
    ///
    /// Outputs by extension, as `track` writes them. Example: faceanim lipsync line.wav
    /// --character avatar.vrm --text "Hello there" -o line.vrm -o line.session.json
    Lipsync(lipsync::LipsyncArgs),
    /// Make ARKit's 52 blendshapes on a head that has none (a scan, a sculpt, an avatar
    /// exported without shape keys): the face found on a render, a template head registered
    /// onto it, and the template's shapes moved onto the head's own vertices (deformation
    /// transfer). Writes the head's own file with the shapes added; everything else in it is
    /// kept. Shapes the head already has are left as they are.
    ///
    /// Example: faceanim generate-shapes scan.glb -o scan-rigged.glb
    GenerateShapes(generate::GenerateArgs),
    /// Make, show or edit the character's retarget map: which of its own shapes answer to each
    /// of ARKit's 52 channels — by name, by geometry (a template head registered on its face,
    /// each channel's shape moved onto it and matched by its own shapes), or as you set them —
    /// with each channel calibrated on the character's renders. Seconds, no training; kept
    /// beside the character (NAME.retarget.json) and used by track, the studio, VMC in and lip
    /// sync.
    ///
    /// Examples: faceanim retarget avatar.vrm; faceanim retarget avatar.vrm --set
    /// jawOpen=Fcl_MTH_A:0.8
    Retarget(retarget::RetargetArgs),
    /// Compare a clip with a reference clip: DTW distance, jitter and MAE (the seeds' metrics).
    ///
    /// Example: faceanim eval take.json reference.json --json
    Eval(EvalArgs),
}

/// `faceanim studio`'s arguments.
#[derive(Debug, Args)]
struct StudioArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files (default: the built-in head).
    character: Option<PathBuf>,
    /// Port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 7878)]
    port: u16,
    /// Open the page in the default browser.
    #[arg(long)]
    open: bool,
    /// The project file (strokes JSON) to open and save.
    #[arg(long)]
    project: Option<PathBuf>,
    /// The character's adapter for capture mode: read if it exists, written when trained
    /// from the page.
    #[arg(long)]
    adapter: Option<PathBuf>,
    /// Listen for VMC (a phone tracker such as iFacialMocap or Waidayo, or another performer)
    /// on this UDP port, all interfaces, or on ADDR:PORT; the Capture tab's VMC button shows
    /// it live and records takes from it. Without a value: 39539, VMC's default.
    #[arg(long, num_args = 0..=1, default_missing_value = "39539", value_name = "[ADDR:]PORT")]
    vmc_listen: Option<String>,
    /// Send the live webcam face over VMC to a marionette (VSeeFace, Warudo, VNyan, Unity,
    /// Unreal) at HOST:PORT.
    #[arg(long, value_name = "HOST:PORT")]
    vmc_send: Option<String>,
    /// The names --vmc-send uses.
    #[arg(long, value_enum, default_value_t = stream::NameChoice::Own)]
    vmc_names: stream::NameChoice,
}

/// `faceanim info`'s arguments.
#[derive(Debug, Args)]
struct InfoArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files (default: the built-in head).
    character: Option<PathBuf>,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// `faceanim export`'s arguments.
#[derive(Debug, Args)]
struct ExportArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files.
    character: PathBuf,
    /// Where to write the .glb.
    #[arg(short, long)]
    output: PathBuf,
    /// A clip JSON (DESIGN.md "Baked clip") to add as a morph-weight animation; its
    /// blendshape names are matched to the character's (ARKit spellings understood).
    #[arg(long)]
    clip: Option<PathBuf>,
}

/// `faceanim sketch`'s arguments.
#[derive(Debug, Args)]
struct SketchArgs {
    /// `[CHARACTER] STROKES`: the character (default: the built-in head) and the strokes file.
    #[arg(num_args = 1..=2, required = true, value_names = ["CHARACTER", "STROKES"])]
    inputs: Vec<PathBuf>,
    /// Where to write the animated .glb.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the baked clip (one row of weights per frame) here.
    #[arg(long)]
    clip: Option<PathBuf>,
}

/// `faceanim export-default`'s arguments.
#[derive(Debug, Args)]
struct ExportDefaultArgs {
    /// Where to write the .glb.
    #[arg(short, long)]
    output: PathBuf,
}

/// `faceanim render`'s arguments.
#[derive(Debug, Args)]
struct RenderArgs {
    /// The character (default: the built-in head).
    character: Option<PathBuf>,
    /// Where to write the PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Blendshape weights as NAME=VALUE pairs separated by commas (ARKit spellings match).
    #[arg(long, value_delimiter = ',')]
    weights: Vec<String>,
    /// A labelled grid of the neutral face and each blendshape at weight 1 instead.
    #[arg(long, conflicts_with = "weights")]
    sheet: bool,
    /// Image size in pixels (for a sheet, each cell's size, at most 512).
    #[arg(long, default_value_t = 512)]
    size: u32,
}

/// `faceanim eval`'s arguments.
#[derive(Debug, Args)]
struct EvalArgs {
    /// The clip to judge.
    a: PathBuf,
    /// The reference clip.
    b: PathBuf,
    /// Print machine-readable JSON.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let spare_heap = faceanim_malloc::keep_spare_heap();
    let cli = Cli::parse();
    let filter = match cli.verbose {
        0 => "warn",
        1 => "debug",
        _ => "trace",
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| filter.into()),
        )
        .with_writer(std::io::stderr)
        .without_time()
        .init();
    tracing::debug!(spare_heap, "allocator keeps spare heap");
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of standard output went away (`faceanim … | head`): nothing more to say.
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            // Library errors already spell out their source (with its path); print a cause
            // only when it adds something.
            let mut printed = error.to_string();
            eprintln!("error: {printed}");
            for cause in error.chain().skip(1) {
                let text = cause.to_string();
                if !printed.contains(&text) {
                    eprintln!("  caused by: {text}");
                    printed.push_str(&text);
                }
            }
            ExitCode::FAILURE
        }
    }
}

/// Whether `error` comes from writing to a pipe whose reader has gone.
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
            || cause
                .downcast_ref::<faceanim_files::FileError>()
                .is_some_and(|e| {
                    matches!(e, faceanim_files::FileError::Io { source, .. }
                        if source.kind() == std::io::ErrorKind::BrokenPipe)
                })
    })
}

fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Studio(args) => studio(args),
        Command::Info(args) => info(&args),
        Command::Export(args) => export(&args),
        Command::Sketch(args) => sketch(&args),
        Command::ExportDefault(args) => {
            let character = faceanim_head::default_character();
            faceanim_files::write_output(&args.output, &faceanim_export::glb(&character, None)?)?;
            eprintln!(
                "wrote {} ({} vertices, {} blendshapes)",
                args.output.display(),
                character.vertex_count(),
                character.blendshapes().len()
            );
            Ok(())
        }
        Command::Render(args) => render(&args),
        Command::Track(args) => track::run(args),
        Command::Lipsync(args) => lipsync::run(args),
        Command::Adapt(args) => adapt::run(args),
        Command::Session(args) => session::run(args),
        Command::Stream(args) => stream::run(args),
        Command::GenerateShapes(args) => generate::run(&args),
        Command::Retarget(args) => retarget::run(args),
        Command::Eval(args) => eval(&args),
    }
}

fn info(args: &InfoArgs) -> anyhow::Result<()> {
    let imported = load_or_default(args.character.as_deref())?;
    let character = &imported.character;
    let report = info::Report::of(character);
    // Which of its shapes answer to each ARKit channel: its retarget map, when it has one.
    let map_path = retarget::default_path(args.character.as_deref(), character);
    let map = retarget::read_beside(&map_path, character)?;
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        value["retarget"] = serde_json::json!({
            "path": map_path,
            "needed": faceanim_adapt::bridge::needs_map(character),
            "rows": map.as_ref().map(|m| &m.rows),
        });
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        out!("{}", report.text(character));
        match &map {
            Some(map) => out!(
                "retarget map ({}):\n{}",
                map_path.display(),
                retarget::table(map)
            ),
            None if faceanim_adapt::bridge::needs_map(character) => outln!(
                "no retarget map yet: `faceanim retarget` makes one (capture makes it too) at {}",
                map_path.display()
            ),
            None => {}
        }
    }
    Ok(())
}

fn export(args: &ExportArgs) -> anyhow::Result<()> {
    let character = load(&args.character)?.character;
    let glb = match &args.clip {
        Some(clip_path) => {
            let clip = faceanim_files::load_clip(clip_path)?;
            let name = clip_path
                .file_stem()
                .map_or_else(|| "clip".to_owned(), |s| s.to_string_lossy().into_owned());
            let unmatched: Vec<&str> = clip
                .blendshapes
                .iter()
                .filter(|n| character.find_blendshape(n).is_none())
                .map(String::as_str)
                .collect();
            if !unmatched.is_empty() {
                tracing::warn!(
                    "{}: no blendshape for {}",
                    clip_path.display(),
                    unmatched.join(", ")
                );
            }
            let animation = faceanim_export::Animation::from_clip(&character, &clip, &name)
                .with_context(|| format!("applying {}", clip_path.display()))?;
            faceanim_export::export(faceanim_export::Format::Glb, &animation)?.bytes
        }
        None => faceanim_export::glb(&character, None)?,
    };
    faceanim_files::write_output(&args.output, &glb)?;
    eprintln!(
        "wrote {} ({} vertices, {} blendshapes{})",
        args.output.display(),
        character.vertex_count(),
        character.blendshapes().len(),
        if args.clip.is_some() {
            ", 1 animation"
        } else {
            ""
        }
    );
    Ok(())
}

fn render(args: &RenderArgs) -> anyhow::Result<()> {
    let character = load_or_default(args.character.as_deref())?.character;
    let size = args.size;
    anyhow::ensure!(
        (16..=4096).contains(&size),
        "--size must be between 16 and 4096 pixels, got {size}"
    );
    let image = if args.sheet {
        faceanim_render::contact_sheet(&character, size.min(512))
    } else {
        let mut w = vec![0.0; character.blendshapes().len()];
        for pair in &args.weights {
            let (name, value) = pair
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--weights: '{pair}' is not NAME=VALUE"))?;
            let id = character.find_blendshape(name.trim()).ok_or_else(|| {
                anyhow::anyhow!(
                    "--weights: '{name}' is not a blendshape of {}",
                    character.name()
                )
            })?;
            let value: f32 = value
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--weights: '{value}' is not a number"))?;
            anyhow::ensure!(
                value.is_finite(),
                "--weights: '{value}' is not a finite number"
            );
            w[id.index()] = value;
        }
        let pose = character.pose(&w);
        let camera = faceanim_render::Camera::front(&character.head_bounds(), 0.75);
        let appearance = faceanim_render::Appearance::of(&character);
        for warning in appearance.warnings() {
            eprintln!("warning: {warning}");
        }
        faceanim_render::render(&character, &pose, &camera, &appearance, size)
    };
    faceanim_files::write_output(&args.output, &image.to_png()?)?;
    eprintln!(
        "wrote {} ({}×{})",
        args.output.display(),
        image.width,
        image.height
    );
    Ok(())
}

fn eval(args: &EvalArgs) -> anyhow::Result<()> {
    let (clip_a, clip_b) = (
        faceanim_files::load_clip(&args.a)?,
        faceanim_files::load_clip(&args.b)?,
    );
    let result = faceanim_anim::metrics::compare(&clip_a, &clip_b);
    if args.json {
        outln!("{}", serde_json::to_string(&result)?);
    } else {
        outln!(
            "DTW distance        {:.4} ({:.4} per frame)",
            result.dtw,
            result.dtw_per_frame
        );
        outln!(
            "jitter (RMS change) {:.4} vs {:.4} (difference {:+.4})",
            result.jitter_a,
            result.jitter_b,
            result.jitter_diff
        );
        match result.mae {
            Some(mae) => outln!("MAE                 {mae:.4}"),
            None => {
                outln!("MAE                 n/a (the clips differ in frames or names)")
            }
        }
    }
    Ok(())
}

fn sketch(args: &SketchArgs) -> anyhow::Result<()> {
    let (character, strokes) = match args.inputs.as_slice() {
        [strokes] => (None, strokes),
        [character, strokes] => (Some(character.as_path()), strokes),
        _ => anyhow::bail!("give [CHARACTER] STROKES"),
    };
    let character = load_or_default(character)?.character;
    let bytes = faceanim_files::read_bytes(strokes)?;
    let project = faceanim_sketch::Project::from_json(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: {e}", strokes.display()))?;
    let (sketch, warnings) = faceanim_sketch::Sketch::from_project(&character, &project);
    for warning in &warnings {
        eprintln!("warning: {}: {warning}", strokes.display());
    }
    let name = strokes
        .file_stem()
        .map_or_else(|| "sketch".to_owned(), |s| s.to_string_lossy().into_owned());
    for (index, result) in sketch.results().iter().enumerate() {
        if let Ok(faceanim_sketch::Action {
            unmirrored: Some(why),
            ..
        }) = result
        {
            eprintln!("warning: {}: strokes[{index}]: {why}", strokes.display());
        }
    }
    let baked = sketch.bake(&name)?;
    let extra = baked.character.blendshapes().len() - character.blendshapes().len();
    let animation = faceanim_export::Animation {
        character: Some(&baked.character),
        animation: baked.animation,
        clip: sketch.bake_clip(),
        arkit: None,
        session: None,
    };
    outputs::write(&args.output, faceanim_export::Format::Glb, &animation)?;
    if let Some(path) = &args.clip {
        outputs::write(path, faceanim_export::Format::ClipJson, &animation)?;
    }
    eprintln!(
        "{}: {} actions, {} frames at {} fps, {} extra targets for arcs and exaggerations",
        args.output.display(),
        sketch.actions().count(),
        animation.clip.frames.len(),
        sketch.fps(),
        extra
    );
    Ok(())
}

fn studio(args: StudioArgs) -> anyhow::Result<()> {
    let StudioArgs {
        character: character_file,
        port,
        open,
        project,
        adapter,
        vmc_listen,
        vmc_send,
        vmc_names,
    } = args;
    let vmc = faceanim_studio::capture::VmcConfig {
        listen: vmc_listen.map(|a| stream::listen_address(&a)).transpose()?,
        send: vmc_send
            .map(|a| stream::destination(&a).map(|d| (d, vmc_names.into())))
            .transpose()?,
    };
    let character = load_or_default(character_file.as_deref())?.character;
    let project_path = match project {
        Some(path) => path,
        None => std::env::current_dir()
            .context("finding the current folder for the project file")?
            .join(format!(
                "{}.faceanim.json",
                safe_file_name(character.name())
            )),
    };
    // The adapter lives beside the character file; the built-in head's beside the project.
    let adapter_path = adapter.unwrap_or_else(|| {
        faceanim_adapt::default_adapter_path(
            character_file
                .as_deref()
                .and_then(std::path::Path::parent)
                .or_else(|| project_path.parent()),
            character.name(),
        )
    });
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the server runtime")?;
    runtime.block_on(async move {
        let (listener, address) = faceanim_studio::bind(port).await?;
        let url = format!("http://{address}/");
        outln!(
            "faceanim studio: {url}  (character: {}, project: {})",
            character.name(),
            project_path.display()
        );
        if open {
            let opener = if cfg!(target_os = "macos") {
                "open"
            } else {
                "xdg-open"
            };
            if let Err(e) = std::process::Command::new(opener).arg(&url).spawn() {
                eprintln!("warning: could not open a browser ({opener}: {e}); open {url} yourself");
            }
        }
        faceanim_studio::serve(
            faceanim_studio::Config {
                adapter_path,
                character,
                project_path,
                vmc,
            },
            listener,
        )
        .await?;
        anyhow::Ok(())
    })
}

/// A character name made safe to use as a file name.
fn safe_file_name(name: &str) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if cleaned.is_empty() {
        "character".to_owned()
    } else {
        cleaned
    }
}

/// The character at `path`, or the built-in default head.
pub(crate) fn load_or_default(
    path: Option<&std::path::Path>,
) -> anyhow::Result<faceanim_rig::import::Imported> {
    match path {
        Some(path) => load(path),
        None => Ok(faceanim_rig::import::Imported {
            character: faceanim_head::default_character(),
            warnings: Vec::new(),
        }),
    }
}

pub(crate) fn load(path: &std::path::Path) -> anyhow::Result<faceanim_rig::import::Imported> {
    let imported = faceanim_files::load_character(path)?;
    for warning in &imported.warnings {
        tracing::warn!("{}: {warning}", path.display());
    }
    Ok(imported)
}
