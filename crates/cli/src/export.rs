//! `faceanim export` and `faceanim export-default`: a character as a binary glTF, with a clip's
//! animation when one is given.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

/// `faceanim export`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct ExportArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files.
    pub(crate) character: PathBuf,
    #[command(flatten)]
    pub(crate) out: crate::outputs::GlbOutput,
    /// The animation to add, as a morph-weight animation: a clip JSON (docs/formats.md), a
    /// Live Link Face CSV (the app's recordings), a VRM Animation (.vrma), or a GLB or VRM
    /// whose animation it is. Its names are matched to the character's (ARKit spellings,
    /// VRM's presets understood), and its ARKit channels reach a rig whose names say nothing
    /// through its retarget map.
    #[arg(long)]
    pub(crate) clip: Option<PathBuf>,
    /// The character's retarget map for the clip's ARKit channels (default:
    /// NAME.retarget.json beside the character; made and saved there when the clip has ARKit
    /// channels the rig's names leave without a shape, as `faceanim retarget` makes it).
    #[arg(long, value_name = "MAP", requires = "clip")]
    pub(crate) retarget: Option<PathBuf>,
}

/// `faceanim export-default`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct ExportDefaultArgs {
    /// Where to write the .glb.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
}

/// `faceanim export`.
pub(crate) fn run(args: &ExportArgs) -> anyhow::Result<()> {
    // A `.glb` (`.vrm`) is the character's own file; any other ending the clip alone.
    let format = crate::outputs::character_format(&args.out.output)?;
    anyhow::ensure!(
        format == faceanim_export::Format::Glb || args.clip.is_some(),
        "{}: {} is an animation: give the clip with --clip",
        args.out.output.display(),
        format.describe()
    );
    let character = crate::input::load(&args.character)?.character;
    crate::outputs::check_for(
        std::slice::from_ref(&args.out.output),
        &[format],
        Some(&character),
    )?;
    let glb = match &args.clip {
        Some(clip_path) => {
            let read = crate::input::clip(clip_path)?;
            let clip = read.for_character(&character);
            let name = crate::input::stem(clip_path, "clip");
            let map = crate::retarget::for_clip(
                &character,
                Some(&args.character),
                args.retarget.as_deref(),
                &clip,
            )?;
            let mut unmatched = clip.unmatched(&character, map.as_ref());
            // The eye and jaw bones take what they show (gaze on eye bones without eyeLook
            // shapes): not lost. (Which bones there are; how far the jaw turns is not asked.)
            if let Some(skeleton) = faceanim_export::bones::ViewRig::of(&character, None) {
                unmatched.retain(|name| !skeleton.shows(name));
            }
            let animation = faceanim_export::Animation::from_clip_through(
                &character,
                &clip,
                &name,
                map.as_ref(),
            )
            .with_context(|| {
                let hint = if map.is_none() && faceanim_adapt::bridge::needs_map(&character) {
                    format!(
                        " (its ARKit channels reach a rig whose names say nothing through its retarget map: faceanim retarget {})",
                        args.character.display()
                    )
                } else {
                    String::new()
                };
                format!("applying {}{hint}", clip_path.display())
            })?;
            if character.blendshapes().is_empty() {
                tracing::warn!(
                    "{}: {} has no blendshapes: its bones take the clip's head pose, eyeLook and jawOpen; nothing takes its other channels",
                    clip_path.display(),
                    character.name()
                );
            } else if animation.bones_only {
                tracing::warn!(
                    "{}: none of {}'s shapes answers to the clip's channels: only its bones move (head pose, eyeLook, jawOpen)",
                    clip_path.display(),
                    character.name()
                );
            } else if !unmatched.is_empty() {
                tracing::warn!(
                    "{}: no blendshape for {}",
                    clip_path.display(),
                    unmatched.join(", ")
                );
            }
            let exported =
                faceanim_export::export_with(format, &animation, args.out.glb.compression())
                    .map_err(|e| anyhow::anyhow!("{}: {e}", args.out.output.display()))?;
            for note in &exported.notes {
                eprintln!("note: {}: {note}", args.out.output.display());
            }
            exported.bytes
        }
        None if character.source().is_some() => faceanim_export::glb::export_into_source_with(
            &character,
            &[],
            &[],
            args.out.glb.compression(),
        )?,
        None => faceanim_export::glb(&character, None)?,
    };
    faceanim_files::write_output(&args.out.output, &glb)?;
    if format != faceanim_export::Format::Glb {
        eprintln!("wrote {}", args.out.output.display());
        return Ok(());
    }
    eprintln!(
        "wrote {} ({} vertices, {} blendshapes{})",
        args.out.output.display(),
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

/// `faceanim export-default`.
pub(crate) fn run_default(args: &ExportDefaultArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        crate::outputs::character_format(&args.output)? == faceanim_export::Format::Glb,
        "{}: export-default writes the built-in head as a .glb",
        args.output.display()
    );
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
