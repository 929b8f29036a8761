//! `faceanim track`: a face image, image folder or video drives a character, by name.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use faceanim_anim::Clip;
use faceanim_anim::filter::OneEuro;
use faceanim_capture::{Filtering, capture};
use faceanim_media::FrameSource;
use faceanim_track::{FaceModels, TrackingMode};

/// Which of the two clean-ups to apply; both are reported so users can choose.
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

/// What `faceanim track` was asked to do.
#[derive(Debug)]
pub struct TrackArgs {
    pub input: PathBuf,
    pub character: Option<PathBuf>,
    pub outputs: Vec<PathBuf>,
    pub raw: Option<PathBuf>,
    pub filter: FilterChoice,
    pub keyframe_every: usize,
    pub one_euro: OneEuro,
    pub detect_every_frame: bool,
    pub fps: f32,
    pub threads: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    ClipJson,
    Glb,
    LiveLinkCsv,
}

fn format_of(path: &Path) -> anyhow::Result<Format> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("json") => Ok(Format::ClipJson),
        Some("glb") => Ok(Format::Glb),
        Some("csv") => Ok(Format::LiveLinkCsv),
        _ => anyhow::bail!(
            "-o {}: the name must end in .json (clip), .glb (character with the animation) or .csv (Live Link Face)",
            path.display()
        ),
    }
}

pub fn run(args: TrackArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        !args.outputs.is_empty() || args.raw.is_some(),
        "give at least one -o OUTPUT (.json, .glb or .csv) or --raw"
    );
    let formats: Vec<Format> = args
        .outputs
        .iter()
        .map(|p| format_of(p))
        .collect::<anyhow::Result<_>>()?;
    anyhow::ensure!(
        args.fps.is_finite() && args.fps > 0.0,
        "--fps must be a positive number, got {}",
        args.fps
    );
    anyhow::ensure!(
        (1..=64).contains(&args.threads),
        "--threads must be between 1 and 64, got {}",
        args.threads
    );
    args.one_euro
        .validate()
        .map_err(|e| anyhow::anyhow!("--min-cutoff/--beta: {e}"))?;
    // Load the character first: a bad character should fail before minutes of video work.
    let character = crate::load_or_default(args.character.as_deref())?.character;

    let mut source = FrameSource::open(&args.input, args.fps)?;
    let info = source.info();
    let models = FaceModels::load_with_threads(args.threads).context("loading the face models")?;
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
    let result = capture(&models, &mut source, mode, |n| bar.set_position(n as u64))
        .with_context(|| format!("capturing {}", args.input.display()))?;
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();

    if let Some(raw) = &args.raw {
        let json = serde_json::to_vec(&result)?;
        faceanim_files::write_atomic(raw, &json)?;
        eprintln!(
            "wrote {} (landmarks and scores of {} frames)",
            raw.display(),
            result.frames.len()
        );
    }

    let raw_clip = result
        .clip(Filtering::default())
        .map_err(anyhow::Error::msg)?;
    let one_euro = result
        .clip(Filtering {
            one_euro: Some(args.one_euro),
            keyframe_every: None,
        })
        .map_err(anyhow::Error::msg)?;
    let keyed = result
        .clip(Filtering {
            one_euro: None,
            keyframe_every: Some(args.keyframe_every),
        })
        .map_err(anyhow::Error::msg)?;
    let chosen = match args.filter {
        FilterChoice::None => raw_clip.clone(),
        FilterChoice::OneEuro => one_euro.clone(),
        FilterChoice::Keyframes => keyed.clone(),
        FilterChoice::Both => result
            .clip(Filtering {
                one_euro: Some(args.one_euro),
                keyframe_every: Some(args.keyframe_every),
            })
            .map_err(anyhow::Error::msg)?,
    };

    // By name onto the character (zero-shot): ARKit-named rigs work at once.
    let retarget = chosen
        .retarget(&character, &stem(&args.input))
        .with_context(|| format!("mapping the capture onto {}", character.name()))?;
    let names: Vec<String> = character
        .blendshapes()
        .iter()
        .map(|b| b.name().to_owned())
        .collect();
    let matched = chosen.blendshapes.len() - retarget.unmatched.len();
    let character_clip = Clip {
        fps: chosen.fps,
        blendshapes: names,
        frames: retarget.animation.weights.clone(),
        head: chosen.head.clone(),
        head_position: chosen.head_position.clone(),
        presence: chosen.presence.clone(),
    };
    for (path, format) in args.outputs.iter().zip(formats) {
        match format {
            Format::ClipJson => {
                faceanim_files::write_atomic(path, character_clip.to_json().as_bytes())?
            }
            Format::Glb => {
                let glb = faceanim_rig::export::export_glb(
                    &character,
                    std::slice::from_ref(&retarget.animation),
                )?;
                faceanim_files::write_atomic(path, &glb)?;
            }
            // Live Link Face speaks ARKit: write the capture's own ARKit weights, whatever the
            // character.
            Format::LiveLinkCsv => faceanim_files::write_atomic(
                path,
                faceanim_anim::livelink::to_csv(&chosen).as_bytes(),
            )?,
        }
        eprintln!("wrote {}", path.display());
    }

    let jitter = |c: &Clip| faceanim_anim::metrics::jitter(&c.frames);
    let summary = serde_json::json!({
        "frames": result.frames.len(),
        "fps": result.fps,
        "faces_found": result.faces_found(),
        "detector_runs": result.detector_runs,
        "seconds": seconds,
        "frames_per_second": result.frames.len() as f64 / seconds.max(1e-9),
        "character": character.name(),
        "blendshapes_driven": matched,
        "blendshapes": character.blendshapes().len(),
        "filter": format!("{:?}", args.filter),
        "jitter": { "raw": jitter(&raw_clip), "one_euro": jitter(&one_euro), "keyframes": jitter(&keyed) },
    });
    println!("{summary}");
    if result.faces_found() == 0 {
        eprintln!(
            "warning: {}: no face was found in any frame; the animation is all zeros",
            args.input.display()
        );
    } else if matched == 0 {
        eprintln!(
            "warning: {} has no ARKit-named blendshapes; train an adapter for it (faceanim adapt)",
            character.name()
        );
    }
    Ok(())
}

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(
        || "capture".to_owned(),
        |s| s.to_string_lossy().into_owned(),
    )
}
