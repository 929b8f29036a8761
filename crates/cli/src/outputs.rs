//! Every command's files leave through one exporter (`faceanim-export`): the format from the
//! file's name, the bytes written atomically, the exporter's notes printed.

use std::path::{Path, PathBuf};

use faceanim_export::{Animation, Format};

/// The formats `paths` ask for, by their endings; the first name that asks for none is an
/// error.
pub fn formats_of(paths: &[PathBuf]) -> anyhow::Result<Vec<Format>> {
    Ok(paths
        .iter()
        .map(|p| Format::from_path(p))
        .collect::<Result<_, _>>()?)
}

/// Writes `animation` to `path` in `format`.
pub fn write(path: &Path, format: Format, animation: &Animation<'_>) -> anyhow::Result<()> {
    let exported = faceanim_export::export(format, animation)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    for note in &exported.notes {
        eprintln!("{}: {note}", path.display());
    }
    faceanim_files::write_atomic(path, &exported.bytes)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
