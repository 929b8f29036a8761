//! What the subcommands read from the user: characters (or the built-in head), adapters, and
//! the names of files they write from the ones they read.

use std::path::Path;

use anyhow::Context as _;

/// A character name made safe to use as a file name.
pub(crate) fn safe_file_name(name: &str) -> String {
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
    path: Option<&Path>,
) -> anyhow::Result<faceanim_rig::import::Imported> {
    match path {
        Some(path) => load(path),
        None => Ok(faceanim_rig::import::Imported {
            character: faceanim_head::default_character(),
            warnings: Vec::new(),
        }),
    }
}

pub(crate) fn load(path: &Path) -> anyhow::Result<faceanim_rig::import::Imported> {
    load_saying(path, |_| true)
}

/// [`load`], warning only of what `worth` lets through (`generate-shapes` does not tell its
/// user to run `generate-shapes`).
pub(crate) fn load_saying(
    path: &Path,
    worth: impl Fn(&str) -> bool,
) -> anyhow::Result<faceanim_rig::import::Imported> {
    let imported = faceanim_files::load_character(path)?;
    for warning in imported.warnings.iter().filter(|w| worth(w)) {
        tracing::warn!("{}: {warning}", path.display());
    }
    Ok(imported)
}

/// The animation at `path` as a clip: a clip JSON, or what the studio opens as a take — a Live
/// Link Face CSV (the app's recordings), a VRM Animation, a GLB's or VRM's morph-weight
/// animation — by its ending.
pub(crate) fn clip(path: &Path) -> anyhow::Result<faceanim_anim::Clip> {
    if !is_animation_file(path) {
        return Ok(faceanim_files::load_clip(path)?);
    }
    let bytes = faceanim_files::read_bytes(path)?;
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let reopened = faceanim_export::reopen::clip_of_file(&name, &bytes)?;
    tracing::info!("{}: {}", path.display(), reopened.what);
    Ok(reopened.clip)
}

/// Whether `path` is, by its ending, an animation of another kind than a clip JSON: a Live
/// Link Face CSV, a VRM Animation, a GLB's, glTF's or VRM's morph-weight animation.
pub(crate) fn is_animation_file(path: &Path) -> bool {
    let ending = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    matches!(
        ending.as_deref(),
        Some("csv" | "vrma" | "glb" | "vrm" | "gltf")
    )
}

/// The adapter at `path`, read whole; its errors name the file.
pub(crate) fn adapter(path: &Path) -> anyhow::Result<faceanim_adapt::Adapter> {
    faceanim_adapt::Adapter::from_bytes(&faceanim_files::read_bytes(path)?)
        .with_context(|| format!("reading the adapter {}", path.display()))
}

/// `path`'s file name without its extension (a take's or a clip's name), or `otherwise` when
/// it has none.
pub(crate) fn stem(path: &Path, otherwise: &str) -> String {
    path.file_stem().map_or_else(
        || otherwise.to_owned(),
        |s| s.to_string_lossy().into_owned(),
    )
}
