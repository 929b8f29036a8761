//! The `faceanim` command line: one binary, one subcommand per job.
//!
//! Errors are mapped once, here: every failure prints `error: ` followed by its cause chain
//! (which names the file and the problem) and exits with status 1; usage errors exit with 2.
//! Each subcommand's arguments are a clap `Args` struct, passed as they are to its code.

#[macro_use]
mod print;

mod adapt;
mod batch;
mod eval;
mod export;
mod generate;
mod info;
mod input;
mod lipsync;
mod outputs;
mod phone;
mod render;
mod retarget;
mod session;
mod sketch;
mod stream;
mod studio;
mod track;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
    Studio(studio::StudioArgs),
    /// Describe a character: vertices, triangles, blendshapes, symmetry pairs, ARKit coverage.
    ///
    /// Example: faceanim info head.glb --json
    Info(info::InfoArgs),
    /// Write a character as a binary glTF (.glb), optionally with an animation from a clip.
    ///
    /// Converts OBJ folders and .gltf files to a single .glb that Blender, Unity, Unreal and
    /// three.js open directly. Example: faceanim export ict-obj/ -o ict.glb --clip take.json.
    /// An output named .vrma is the clip alone as a VRM Animation, for a VRM avatar (VRM apps
    /// play it on any VRM): faceanim export avatar.vrm --clip take.json -o take.vrma
    Export(export::ExportArgs),
    /// Replay a strokes file (docs/formats.md: samples, handle edits, settings) on a character
    /// and write the animation: a GLB whose extra morph targets carry arcs and exaggerations,
    /// and optionally the baked clip of blendshape weights.
    ///
    /// Example: faceanim sketch head.glb take.strokes.json -o take.glb --clip take.json
    Sketch(sketch::SketchArgs),
    /// Write the built-in default head (52 ARKit blendshapes) as a .glb.
    ///
    /// Example: faceanim export-default -o default.glb
    ExportDefault(export::ExportDefaultArgs),
    /// Render a character to PNG: one pose, or a contact sheet of every blendshape at weight 1.
    ///
    /// Examples: faceanim render --sheet -o sheet.png;
    /// faceanim render head.glb --weights jawOpen=0.6,mouthSmileLeft=1 -o smile.png
    Render(render::RenderArgs),
    /// Animate a character from a face photo, an image folder or a video: landmarks, ARKit
    /// scores and head pose per frame (MediaPipe's face models, run on the CPU), mapped by name
    /// onto the character's blendshapes, or through its adapter.
    ///
    /// Outputs by extension (repeat -o for several): .json the clip (docs/formats.md), .glb the
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
    /// Run a manifest of jobs (JSON Lines or CSV: lipsync, track, generate-shapes rows), each
    /// row once: unchanged rows are skipped, edited outputs kept, bad rows reported (exit 42).
    ///
    /// On this machine (--jobs), or as one worker of an array job (--index, or the engine's
    /// JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX, SLURM_ARRAY_TASK_ID); docs/batch.md
    /// has the Ray driver and the Kubernetes Job. Example: faceanim batch lines.jsonl --jobs 4
    Batch(batch::BatchArgs),
    /// Compare a clip with a reference clip: DTW distance, jitter and MAE (the seeds' metrics).
    ///
    /// Example: faceanim eval take.json reference.json --json
    Eval(eval::EvalArgs),
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
        // Colours only for a person at a terminal, never into a pipe or a log file.
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .without_time()
        .init();
    tracing::debug!(spare_heap, "allocator keeps spare heap");
    match run(cli.command) {
        Ok(code) => code,
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

fn run(command: Command) -> anyhow::Result<ExitCode> {
    let done = match command {
        // The one command whose exit status says more than success or failure: a worker's row.
        Command::Batch(args) => return batch::run(&args),
        Command::Studio(args) => studio::run(args),
        Command::Info(args) => info::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Sketch(args) => sketch::run(&args),
        Command::ExportDefault(args) => export::run_default(&args),
        Command::Render(args) => render::run(&args),
        Command::Track(args) => track::run(args),
        Command::Lipsync(args) => lipsync::run(args),
        Command::Adapt(args) => adapt::run(args),
        Command::Session(args) => session::run(args),
        Command::Stream(args) => stream::run(args),
        Command::GenerateShapes(args) => generate::run(&args),
        Command::Retarget(args) => retarget::run(args),
        Command::Eval(args) => eval::run(&args),
    };
    done.map(|()| ExitCode::SUCCESS)
}
