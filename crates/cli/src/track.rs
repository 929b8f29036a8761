//! `faceanim track`: a face image, image folder or video drives a character — by name, or
//! through the character's adapter (with a session file for corrections).

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
    pub adapter: Option<PathBuf>,
    pub session: Option<PathBuf>,
    pub keyframes: Vec<usize>,
    pub image_frames: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Format {
    ClipJson,
    Glb,
    LiveLinkCsv,
    SeedCsv,
}

fn format_of(path: &Path) -> anyhow::Result<Format> {
    let lower = path.to_string_lossy().to_ascii_lowercase();
    if lower.ends_with(".byoc.csv") {
        return Ok(Format::SeedCsv);
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("json") => Ok(Format::ClipJson),
        Some("glb") => Ok(Format::Glb),
        Some("csv") => Ok(Format::LiveLinkCsv),
        _ => anyhow::bail!(
            "-o {}: the name must end in .json (clip), .glb (character with the animation), .csv (Live Link Face) or .byoc.csv (the seed's CSV)",
            path.display()
        ),
    }
}

pub fn run(args: TrackArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        !args.outputs.is_empty() || args.raw.is_some(),
        "give at least one -o OUTPUT (.json, .glb or .csv) or --raw"
    );
    let formats = formats_of(&args.outputs)?;
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
    // Load the character and adapter first: a bad one should fail before minutes of video.
    let character = crate::load_or_default(args.character.as_deref())?.character;
    let adapter = match &args.adapter {
        Some(path) => {
            let adapter = faceanim_adapt::Adapter::from_bytes(&faceanim_files::read_bytes(path)?)
                .with_context(|| format!("reading the adapter {}", path.display()))?;
            if adapter.check(&character)? == faceanim_adapt::Fit::OtherShape {
                eprintln!(
                    "warning: {} was trained on another shape of this rig; it works, but an adapter trained on {} (faceanim adapt) will be more accurate",
                    path.display(),
                    character.name()
                );
            }
            Some(adapter)
        }
        None => {
            anyhow::ensure!(
                args.session.is_none(),
                "--session needs --adapter (a session records the adapter's estimates)"
            );
            anyhow::ensure!(
                !formats.contains(&Format::SeedCsv),
                ".byoc.csv output needs --adapter"
            );
            None
        }
    };

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

    if let Some(adapter) = adapter {
        return with_adapter(
            &args, &formats, &character, &adapter, &result, &source, seconds,
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
            Format::SeedCsv => unreachable_format(path)?,
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

fn unreachable_format(path: &Path) -> anyhow::Result<()> {
    anyhow::bail!("{}: this output needs --adapter", path.display())
}

/// The adapter's path: every frame estimated in the character's own blendshapes, a session
/// (keyframes, corrections later), and the outputs from it.
fn with_adapter(
    args: &TrackArgs,
    formats: &[Format],
    character: &faceanim_rig::Character,
    adapter: &faceanim_adapt::Adapter,
    result: &faceanim_capture::Capture,
    source: &FrameSource,
    capture_seconds: f64,
) -> anyhow::Result<()> {
    use faceanim_adapt::session::{Session, SessionFrame, estimate_frames};
    let started = Instant::now();
    let expressions: Vec<Option<faceanim_adapt::Expression>> = result
        .frames
        .iter()
        .map(faceanim_adapt::Expression::from_record)
        .collect();
    let estimates = estimate_frames(&expressions, adapter.blendshapes.len(), |e| {
        adapter.predict(e)
    });
    let adapter_seconds = started.elapsed().as_secs_f64();
    let frames: Vec<SessionFrame> = result
        .frames
        .iter()
        .zip(expressions)
        .zip(estimates)
        .map(|((f, expression), estimate)| {
            SessionFrame::from_record(f, source.frame_name(f.index), expression, estimate)
        })
        .collect();
    let (every, smoothing) = match args.filter {
        FilterChoice::Keyframes => (args.keyframe_every, None),
        FilterChoice::OneEuro => (1, Some(args.one_euro)),
        FilterChoice::Both => (args.keyframe_every, Some(args.one_euro)),
        FilterChoice::None => (1, None),
    };
    let mut session = Session::new(
        args.input.display().to_string(),
        character.name().to_owned(),
        adapter.blendshapes.clone(),
        adapter.fingerprint.clone(),
        result.fps,
        every,
        frames,
    );
    session.smoothing = smoothing;
    for &k in &args.keyframes {
        session
            .add_keyframe(k)
            .map_err(|e| anyhow::anyhow!("--keyframe: {e}"))?;
    }
    if source.is_still() {
        session.still_frames = Some(args.image_frames.max(1));
    }
    if let Some(path) = &args.session {
        faceanim_files::write_atomic(path, session.to_json().as_bytes())?;
        eprintln!(
            "wrote {} (the session: correct it with faceanim session)",
            path.display()
        );
    }
    let clip = session.clip();
    let arkit = result
        .clip(Filtering {
            one_euro: smoothing,
            keyframe_every: Some(every),
        })
        .map_err(anyhow::Error::msg)?;
    write_outputs(
        &args.outputs,
        formats,
        character,
        &clip,
        Some(&arkit),
        &session,
        &stem(&args.input),
    )?;
    let found = result.faces_found();
    let summary = serde_json::json!({
        "frames": result.frames.len(),
        "fps": result.fps,
        "faces_found": found,
        "detector_runs": result.detector_runs,
        "seconds": capture_seconds + adapter_seconds,
        "frames_per_second": result.frames.len() as f64 / capture_seconds.max(1e-9),
        "adapter_ms_per_frame": 1000.0 * adapter_seconds / result.frames.len().max(1) as f64,
        "character": character.name(),
        "blendshapes_driven": adapter.blendshapes.len(),
        "blendshapes": character.blendshapes().len(),
        "keyframes": session.keyframes().len(),
        "animation_frames": clip.frames.len(),
        "jitter": faceanim_anim::metrics::jitter(&clip.frames),
    });
    println!("{summary}");
    if found == 0 {
        eprintln!(
            "warning: {}: no face was found in any frame; the animation is all zeros",
            args.input.display()
        );
    }
    Ok(())
}

/// Writes a character clip (and, for the seed's CSV, the session's frames) in each format.
/// Live Link Face speaks ARKit: a character without ARKit names writes `arkit` (the capture's
/// own ARKit weights) there instead, when given.
pub(crate) fn write_outputs(
    outputs: &[PathBuf],
    formats: &[Format],
    character: &faceanim_rig::Character,
    clip: &Clip,
    arkit: Option<&Clip>,
    session: &faceanim_adapt::Session,
    name: &str,
) -> anyhow::Result<()> {
    for (path, format) in outputs.iter().zip(formats) {
        match format {
            Format::ClipJson => faceanim_files::write_atomic(path, clip.to_json().as_bytes())?,
            Format::Glb => {
                let retarget = clip
                    .retarget(character, name)
                    .with_context(|| format!("mapping the animation onto {}", character.name()))?;
                let glb = faceanim_rig::export::export_glb(
                    character,
                    std::slice::from_ref(&retarget.animation),
                )?;
                faceanim_files::write_atomic(path, &glb)?;
            }
            Format::LiveLinkCsv => {
                let arkit_count = clip
                    .blendshapes
                    .iter()
                    .filter(|n| faceanim_rig::names::arkit_name(n).is_some())
                    .count();
                let written = match (arkit_count, arkit) {
                    (0, Some(capture)) => {
                        eprintln!(
                            "note: {} has no ARKit-named blendshapes; {} gets the capture's ARKit weights",
                            character.name(),
                            path.display()
                        );
                        capture
                    }
                    (0, None) => {
                        eprintln!(
                            "warning: {}: Live Link Face speaks ARKit and {} has no ARKit-named blendshapes; the curves are zero",
                            path.display(),
                            character.name()
                        );
                        clip
                    }
                    _ => clip,
                };
                faceanim_files::write_atomic(
                    path,
                    faceanim_anim::livelink::to_csv(written).as_bytes(),
                )?;
            }
            Format::SeedCsv => {
                faceanim_files::write_atomic(path, session.to_seed_csv().as_bytes())?
            }
        }
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The output formats of `paths`, by extension.
pub(crate) fn formats_of(paths: &[PathBuf]) -> anyhow::Result<Vec<Format>> {
    paths.iter().map(|p| format_of(p)).collect()
}

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(
        || "capture".to_owned(),
        |s| s.to_string_lossy().into_owned(),
    )
}
