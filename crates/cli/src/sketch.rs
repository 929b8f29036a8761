//! `faceanim sketch`: a strokes file replayed on a character, written as an animated GLB (or
//! the animation alone in another format, by the output's ending) and optionally its baked clip.

use std::path::PathBuf;

use clap::Args;

/// `faceanim sketch`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct SketchArgs {
    /// `[CHARACTER] STROKES`: the character (default: the built-in head) and the strokes file.
    #[arg(num_args = 1..=2, required = true, value_names = ["CHARACTER", "STROKES"])]
    pub(crate) inputs: Vec<PathBuf>,
    #[command(flatten)]
    pub(crate) out: crate::outputs::GlbOutput,
    /// Also write the baked clip (one row of weights per frame) here.
    #[arg(long)]
    pub(crate) clip: Option<PathBuf>,
}

/// `faceanim sketch`.
pub(crate) fn run(args: &SketchArgs) -> anyhow::Result<()> {
    let (character, strokes) = match args.inputs.as_slice() {
        [strokes] => (None, strokes),
        [character, strokes] => (Some(character.as_path()), strokes),
        _ => anyhow::bail!("give [CHARACTER] STROKES"),
    };
    let format = crate::outputs::character_format(&args.out.output)?;
    if let Some(clip) = &args.clip {
        faceanim_files::check_output(clip)?;
    }
    let character = crate::input::load_or_default(character)?.character;
    crate::outputs::check_for(
        std::slice::from_ref(&args.out.output),
        &[format],
        Some(&character),
    )?;
    let bytes = faceanim_files::read_bytes(strokes)?;
    let project = faceanim_sketch::Project::from_json(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: {e}", strokes.display()))?;
    let (sketch, warnings) = faceanim_sketch::Sketch::from_project(&character, &project);
    for warning in &warnings {
        eprintln!("warning: {}: {warning}", strokes.display());
    }
    let name = crate::input::stem(strokes, "sketch");
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
        bones: None,
        // The strokes go with the sketch, so the file opens again as them.
        strokes: serde_json::from_slice(&bytes).ok(),
        bones_only: false,
    };
    if format == faceanim_export::Format::Glb {
        crate::outputs::write(&args.out.output, format, &animation, args.out.glb)?;
    } else {
        // The animation alone, as the studio's downloads write it: the sketch's weights on the
        // character's own shapes.
        let alone = faceanim_export::Animation::from_clip(&character, &animation.clip, &name)?;
        crate::outputs::write(&args.out.output, format, &alone, args.out.glb)?;
    }
    if let Some(path) = &args.clip {
        crate::outputs::write(
            path,
            faceanim_export::Format::ClipJson,
            &animation,
            args.out.glb,
        )?;
    }
    // Arcs and exaggerations are extra targets, which only the GLB carries.
    let extra = if format == faceanim_export::Format::Glb {
        format!(", {extra} extra targets for arcs and exaggerations")
    } else {
        if extra > 0 {
            eprintln!(
                "warning: {}: {} carries the blendshapes' weights alone: the arcs and exaggerations ({extra} extra targets) are only in a .glb",
                args.out.output.display(),
                format.describe()
            );
        }
        String::new()
    };
    eprintln!(
        "{}: {} actions, {} frames at {} fps{extra}",
        args.out.output.display(),
        sketch.actions().count(),
        animation.clip.frames.len(),
        sketch.fps(),
    );
    Ok(())
}
