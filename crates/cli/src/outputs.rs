//! Every command's files leave through one exporter (`faceanim-export`): the format from the
//! file's name, the bytes written atomically, the exporter's notes printed.

use std::path::{Path, PathBuf};

use faceanim_export::glb::Compression;
use faceanim_export::{Animation, Format};
use faceanim_take::Session;

/// Where a command that writes one character (`export`, `sketch`) writes it, and how.
#[derive(Debug, Clone, clap::Args)]
pub struct GlbOutput {
    /// Where to write: .glb (or .vrm) the character with the animation; any other ending the
    /// animation alone in that format — .vrma a VRM avatar's VRM Animation, .json the clip,
    /// .csv Live Link Face.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub glb: GlbArgs,
}

/// How GLB outputs are written (every command that writes one flattens these).
#[derive(Debug, Clone, Copy, Default, clap::Args)]
pub struct GlbArgs {
    /// Write the GLB plain. A character read meshopt-compressed (gltfpack, VRoid's optimiser) is
    /// otherwise written compressed again, as it came, so it keeps its size; plain is for tools
    /// without a meshopt decoder (Blender's importer).
    #[arg(long)]
    pub uncompressed: bool,
}

impl GlbArgs {
    /// The compression asked for.
    pub fn compression(self) -> Compression {
        if self.uncompressed {
            Compression::None
        } else {
            Compression::AsRead
        }
    }
}

/// The formats `paths` ask for, by their endings, checked before any work is done for them:
/// the first name that asks for none, or that cannot be written (a folder that is not there:
/// [`faceanim_files::check_output`]), is an error.
pub fn formats_of(paths: &[PathBuf]) -> anyhow::Result<Vec<Format>> {
    paths
        .iter()
        .map(|p| {
            let format = Format::from_path(p)?;
            faceanim_files::check_output(p)?;
            Ok(format)
        })
        .collect()
}

/// What a command that writes a character (`export`, `sketch`) writes to `path`, by its ending:
/// the character's own file as a binary glTF for `.glb` and `.vrm` (a VRM avatar keeps its
/// ending) and a name with no ending, or the animation alone in any other format
/// [`Format::from_path`] knows. Checked before any work is done: a `.gltf` (faceanim writes
/// binary glTF only), an ending no format has, or a folder that is not there is an error naming
/// the file.
pub fn character_format(path: &Path) -> anyhow::Result<Format> {
    anyhow::ensure!(
        !path
            .to_string_lossy()
            .to_ascii_lowercase()
            .ends_with(".gltf"),
        "{}: faceanim writes the character as binary glTF: name it .glb (or .vrm for a VRM avatar)",
        path.display()
    );
    // A name with no ending at all (`/dev/null`) is the character's file, as it always was;
    // `-` is the clip on standard output.
    let format = if path.extension().is_none() && !faceanim_files::is_stdout(path) {
        Format::Glb
    } else {
        Format::from_path(path)?
    };
    faceanim_files::check_output(path)?;
    Ok(format)
}

/// Where a command that writes an animation (`track`, `lipsync`) writes it: any number of
/// files, each in the format its name asks for.
#[derive(Debug, Clone, clap::Args)]
pub struct Outputs {
    /// Where to write, by ending (repeat -o for several): .json the clip, .glb (.vrm for a VRM
    /// avatar) the character with the animation, .vrma a VRM avatar's VRM Animation, .csv Live
    /// Link Face, .byoc.csv the seed's CSV, .session.json the take; - the clip on standard
    /// output.
    #[arg(short, long = "output", value_name = "OUT")]
    pub outputs: Vec<PathBuf>,
    #[command(flatten)]
    pub glb: GlbArgs,
}

/// Checks, once the character is read and before any work is done, that it can take every
/// output's format ([`Format::check_character`]: a VRM Animation needs a VRM avatar), so that
/// a long video is not tracked only to be refused: an error naming the first file that cannot.
pub fn check_for(
    paths: &[PathBuf],
    formats: &[Format],
    character: Option<&faceanim_rig::Character>,
) -> anyhow::Result<()> {
    for (path, format) in paths.iter().zip(formats) {
        format
            .check_character(character)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// Writes `animation` to each of `paths` in its format (GLBs as `glb` says). Every file is made
/// before any is written, so that one that cannot be made (a VRM Animation in which nothing
/// moves) leaves none of them behind.
pub fn write_all(
    paths: &[PathBuf],
    formats: &[Format],
    animation: &Animation<'_>,
    glb: GlbArgs,
) -> anyhow::Result<()> {
    let made = paths
        .iter()
        .zip(formats)
        .map(|(path, &format)| make(path, format, animation, glb))
        .collect::<anyhow::Result<Vec<_>>>()?;
    for (path, bytes) in paths.iter().zip(made) {
        save(path, &bytes)?;
    }
    Ok(())
}

/// Writes `animation` to `path` in `format` (a GLB as `glb` says).
pub fn write(
    path: &Path,
    format: Format,
    animation: &Animation<'_>,
    glb: GlbArgs,
) -> anyhow::Result<()> {
    save(path, &make(path, format, animation, glb)?)
}

/// `animation` in `format` for `path`, with the exporter's notes (and a warning for a plain
/// glTF named `.vrm`) printed.
fn make(
    path: &Path,
    format: Format,
    animation: &Animation<'_>,
    glb: GlbArgs,
) -> anyhow::Result<Vec<u8>> {
    let not_vrm = animation.character.filter(|c| {
        !c.source()
            .is_some_and(faceanim_rig::source::GltfSource::is_vrm)
    });
    if let Some(character) = not_vrm
        && format == Format::Glb
        && path
            .to_string_lossy()
            .to_ascii_lowercase()
            .ends_with(".vrm")
    {
        eprintln!(
            "warning: {}: {} is no VRM avatar, so this is a plain glTF named .vrm, which VRM apps refuse; name it .glb",
            path.display(),
            character.name()
        );
    }
    let exported = faceanim_export::export_with(format, animation, glb.compression())
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    for note in &exported.notes {
        eprintln!("note: {}: {note}", path.display());
    }
    Ok(exported.bytes)
}

fn save(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    faceanim_files::write_output(path, bytes)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// A take's session as an export of `character` (needed for a GLB only): its clip, the head
/// turn on the root, the capture's ARKit weights for Live Link Face and the bones, and the
/// session itself.
pub fn take_animation<'a>(
    character: Option<&'a faceanim_rig::Character>,
    session: &'a Session,
    name: &str,
) -> anyhow::Result<Animation<'a>> {
    Ok(Animation::from_take(
        character,
        &session.clip(),
        session.arkit_clip(),
        Some(session),
        None,
        name,
    )?)
}
