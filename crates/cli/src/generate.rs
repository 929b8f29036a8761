//! `faceanim generate-shapes`: ARKit's 52 blendshapes made on a head that has none.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use clap::Args;
use faceanim_fit::{Options, Template};
use faceanim_rig::Character;

/// `faceanim generate-shapes`'s arguments.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The head: a glTF/GLB/VRM file (a full-body avatar is fine) or an OBJ folder. It is
    /// read, never changed.
    pub character: PathBuf,
    /// Where to write the head with its new shapes: .glb, or .vrm for a VRM avatar.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The template whose shapes are moved onto the head: `default` (a realistic head,
    /// ICT-FaceKit's, with artist-made shapes; the built-in head for the one it lacks),
    /// `stylised` (the built-in head's shapes, made in code), or a character file with
    /// ARKit-named shapes (the built-in head for any it lacks).
    #[arg(long, default_value = "default", value_name = "default|stylised|FILE")]
    pub template: String,
    /// Only these ARKit shapes (comma-separated ARKit names).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub only: Vec<String>,
    /// Where the head's face is, when the face model cannot find it: a file of ten points
    /// marked on it (default: NAME.face-points.json beside the head, when there is one; the
    /// studio writes it).
    #[arg(long, value_name = "FILE")]
    pub face_points: Option<PathBuf>,
    /// Print a JSON report on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &GenerateArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    check_output(&args.character, &args.output)?;
    for name in &args.only {
        anyhow::ensure!(
            faceanim_rig::names::ARKIT_52.contains(&name.as_str()),
            "--only: {name} is not one of ARKit's 52 names (e.g. eyeBlinkLeft, jawOpen)"
        );
    }
    // A head without shapes is what this command is for: no warning telling to run it.
    let user =
        crate::input::load_saying(&args.character, |w| !w.contains("faceanim generate-shapes"))?
            .character;
    if args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vrm"))
    {
        anyhow::ensure!(
            user.source().is_some_and(|s| s.is_vrm()),
            "{}: a .vrm output needs a VRM avatar as input; write .glb",
            args.output.display()
        );
    }
    let templates = templates(&args.template)?;
    let templates: Vec<&Character> = templates.iter().collect();
    let models = faceanim_track::FaceModels::load().context("loading the face models")?;
    let options = Options {
        only: (!args.only.is_empty()).then(|| args.only.clone()),
        points: crate::retarget::face_points(
            Some(&args.character),
            &user,
            args.face_points.as_deref(),
        )?,
    };
    let (with, generated) =
        faceanim_fit::with_generated_shapes(&user, &templates, &models, &options)
            .with_context(|| format!("generating shapes on {}", args.character.display()))?;
    let names: Vec<&str> = generated.shapes.iter().map(|s| s.name()).collect();
    let bytes = faceanim_export::glb(&with, None)?;
    faceanim_files::write_output(&args.output, &bytes)?;
    let seconds = started.elapsed().as_secs_f64();
    if args.json {
        let report = serde_json::json!({
            "character": user.name(),
            "vertices": user.vertex_count(),
            "output": args.output.display().to_string(),
            "shapes": names,
            "kept": generated.kept,
            "landmarks": generated.landmarks,
            "templates": generated.templates.iter().map(|t| serde_json::json!({
                "name": t.name,
                "landmarks": t.landmarks[0],
                "landmarks_on_both": t.landmarks[1],
                "scale": t.scale,
                "fit_residual": t.residual,
                "corresponding_vertices": t.corresponding,
                "shapes": t.shapes,
            })).collect::<Vec<_>>(),
            "seconds": seconds,
        });
        outln!("{report}");
    }
    eprintln!(
        "wrote {} ({} shapes made on {} vertices in {seconds:.1} s{})",
        args.output.display(),
        names.len(),
        user.vertex_count(),
        if generated.kept.is_empty() {
            String::new()
        } else {
            format!("; {} it had already kept", generated.kept.len())
        }
    );
    Ok(())
}

/// The user's file is never written over.
fn check_output(input: &Path, output: &Path) -> anyhow::Result<()> {
    let extension = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    anyhow::ensure!(
        matches!(extension.as_deref(), Some("glb" | "vrm")),
        "{}: the output must be a .glb or .vrm file",
        output.display()
    );
    faceanim_files::check_output(output)?;
    let same = match (input.canonicalize(), output.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    anyhow::ensure!(
        !same,
        "{}: the output would replace the input; write the result to another file",
        output.display()
    );
    Ok(())
}

/// The template heads `--template` names, in the order they are asked for shapes.
fn templates(choice: &str) -> anyhow::Result<Vec<Character>> {
    Ok(match choice {
        "default" | "realistic" => Template::Realistic.characters()?,
        "stylised" | "stylized" | "builtin" => Template::Stylised.characters()?,
        path => {
            let template = crate::input::load(Path::new(path))
                .with_context(|| format!("--template {path}"))?
                .character;
            anyhow::ensure!(
                !template.arkit_coverage().is_empty(),
                "--template {path}: it has no ARKit-named shapes to transfer"
            );
            let mut all = vec![template];
            all.extend(Template::Stylised.characters()?);
            all
        }
    })
}
