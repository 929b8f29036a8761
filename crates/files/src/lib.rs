//! # faceanim-files: the file-system edge
//!
//! The pure crates parse bytes; this crate turns paths into bytes and back. It loads characters
//! (`.glb`, `.gltf` with its external buffers and images, or a folder of OBJ files), loads
//! clips and text files in the encodings people save them in ([`text`]), and writes every
//! output atomically (a temporary file in the target folder, synced, then renamed), so a crash
//! or a full disk never leaves a half-written file behind. Every error carries the path it
//! concerns.
#![deny(missing_docs)]

pub mod text;

use std::io::Write as _;
use std::path::{Path, PathBuf};

use faceanim_anim::{Clip, ClipError};
use faceanim_rig::import::{
    ImportError, Imported, ObjSource, Resources, import_gltf, import_obj_set,
};

/// Files larger than this are refused before reading (a face rig is tens of MB).
pub const MAX_FILE_BYTES: u64 = 2 << 30;

/// Why a file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileError {
    /// The operating system refused.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is larger than its kind may be ([`MAX_FILE_BYTES`] for a character).
    #[error("{}: {} larger than the {limit}-byte limit", path.display(), size.map_or_else(|| "what it gives is".to_owned(), |s| format!("{s} bytes is")))]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size; `None` for what has none (a device, a pipe) and gave more than the limit.
        size: Option<u64>,
        /// The most it may be.
        limit: u64,
    },
    /// The path does not name something faceanim can read as a character.
    #[error("{}: {reason}", path.display())]
    NotACharacter {
        /// The path.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The importer rejected the contents (its message names the file).
    #[error(transparent)]
    Import(#[from] ImportError),
    /// A text file is in no encoding it may be in.
    #[error("{}: {source}", path.display())]
    Text {
        /// The file.
        path: PathBuf,
        /// Why it is not text.
        source: text::TextError,
    },
    /// A clip file is malformed.
    #[error("{}: {source}", path.display())]
    Clip {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: ClipError,
    },
}

/// Reads a whole file, refusing ones over [`MAX_FILE_BYTES`].
///
/// # Errors
/// [`FileError::Io`] or [`FileError::TooLarge`], with the path.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FileError> {
    read_at_most(path, MAX_FILE_BYTES)
}

/// The bytes of `path`, refused when it is larger than `limit`: a file by its size before it
/// is read, and what has no size (a device such as `/dev/zero`, a pipe) once it gives more.
///
/// # Errors
/// [`FileError::Io`] or [`FileError::TooLarge`], with the path.
pub fn read_at_most(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let io = |source| FileError::Io {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let too_large = |size| FileError::TooLarge {
        path: path.to_owned(),
        size,
        limit,
    };
    if size > limit {
        return Err(too_large(Some(size)));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    std::io::Read::read_to_end(
        &mut std::io::Read::take(file, limit.saturating_add(1)),
        &mut bytes,
    )
    .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(None));
    }
    Ok(bytes)
}

/// Loads a character from a `.glb`/`.gltf` file or a folder of OBJ files.
///
/// A folder must hold `neutral.obj` (or exactly one OBJ whose name contains `neutral`) and one
/// OBJ per blendshape, named after it. Files are recognised by content, not only extension.
///
/// # Errors
/// A [`FileError`] naming the path and the problem.
pub fn load_character(path: &Path) -> Result<Imported, FileError> {
    if path.is_dir() {
        return load_obj_folder(path);
    }
    let bytes = read_bytes(path)?;
    let name = path.display().to_string();
    let is_obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        // A single OBJ (a scan, a sculpt): a head without blendshapes.
        let text = String::from_utf8_lossy(&bytes);
        let stem = path
            .file_stem()
            .map_or_else(|| name.clone(), |s| s.to_string_lossy().into_owned());
        return Ok(import_obj_set(
            &stem,
            ObjSource {
                name: &name,
                text: &text,
            },
            &[],
        )?);
    }
    let dir = path
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_owned);
    Ok(import_gltf(&bytes, &name, &FolderResources { dir })?)
}

/// Resolves a glTF file's relative URIs inside its own folder (or below it).
struct FolderResources {
    dir: PathBuf,
}

impl Resources for FolderResources {
    fn load(&self, uri: &str) -> Result<Vec<u8>, String> {
        let relative = Path::new(uri);
        if relative.is_absolute() {
            return Err("absolute paths are not allowed in glTF URIs".into());
        }
        let path = self.dir.join(relative);
        read_bytes(&path).map_err(|e| match e {
            FileError::Io { source, .. } => format!("{}: {source}", path.display()),
            other => other.to_string(),
        })
    }
}

fn load_obj_folder(dir: &Path) -> Result<Imported, FileError> {
    let io = |source| FileError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut objs: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .collect();
    objs.sort();
    let stem = |p: &Path| {
        p.file_stem()
            .map(|s| s.to_string_lossy().to_lowercase())
            .unwrap_or_default()
    };
    let neutral_candidates: Vec<&PathBuf> = match objs.iter().find(|p| stem(p) == "neutral") {
        Some(exact) => vec![exact],
        None => objs
            .iter()
            .filter(|p| stem(p).contains("neutral"))
            .collect(),
    };
    let neutral = match neutral_candidates.as_slice() {
        [one] => (*one).clone(),
        [] => {
            return Err(FileError::NotACharacter {
                path: dir.to_owned(),
                reason: format!(
                    "no neutral OBJ: name it neutral.obj ({} OBJ files found)",
                    objs.len()
                ),
            });
        }
        several => {
            return Err(FileError::NotACharacter {
                path: dir.to_owned(),
                reason: format!(
                    "{} OBJ files could be the neutral ({}); rename one to neutral.obj",
                    several.len(),
                    several
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
    };
    let read_text = |p: &Path| read_bytes(p).map(|b| String::from_utf8_lossy(&b).into_owned());
    let neutral_text = read_text(&neutral)?;
    let shape_paths: Vec<&PathBuf> = objs.iter().filter(|p| **p != neutral).collect();
    let shape_texts: Vec<(String, String)> = shape_paths
        .iter()
        .map(|p| {
            Ok((
                p.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                read_text(p)?,
            ))
        })
        .collect::<Result<_, FileError>>()?;
    let shapes: Vec<ObjSource<'_>> = shape_texts
        .iter()
        .map(|(name, text)| ObjSource { name, text })
        .collect();
    let neutral_name = neutral.display().to_string();
    let character_name = dir.file_name().map_or_else(
        || "character".to_owned(),
        |n| n.to_string_lossy().into_owned(),
    );
    Ok(import_obj_set(
        &character_name,
        ObjSource {
            name: &neutral_name,
            text: &neutral_text,
        },
        &shapes,
    )?)
}

/// Reads a text file of at most `max_bytes` (its size checked before it is read), decoded in
/// the encodings `accept` allows ([`text::decode`]).
///
/// # Errors
/// [`FileError::Io`], [`FileError::TooLarge`] or [`FileError::Text`], with the path.
pub fn read_text(
    path: &Path,
    max_bytes: u64,
    accept: text::Accept<'_>,
) -> Result<text::Text, FileError> {
    let bytes = read_at_most(path, max_bytes.min(MAX_FILE_BYTES))?;
    text::decode(&bytes, accept).map_err(|source| FileError::Text {
        path: path.to_owned(),
        source,
    })
}

/// Loads and validates a clip JSON file.
///
/// # Errors
/// [`FileError::Io`] or [`FileError::Clip`], with the path.
pub fn load_clip(path: &Path) -> Result<Clip, FileError> {
    let bytes = read_bytes(path)?;
    Clip::from_json(&bytes).map_err(|source| FileError::Clip {
        path: path.to_owned(),
        source,
    })
}

/// What a write in progress is called until it replaces its file: `.NAME.XXXXXX` followed by
/// this.
pub const PARTIAL_SUFFIX: &str = ".faceanim-partial";

/// Removes the partial writes ([`write_atomic`]'s temporary files) in `dir` that a killed
/// process left behind: those older than `age` (younger ones may be another process's writes in
/// progress). Returns the files removed; a folder that cannot be read removes nothing.
#[must_use = "say what was cleaned up"]
pub fn remove_stale_partials(dir: &Path, age: std::time::Duration) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let now = std::time::SystemTime::now();
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with('.') && name.ends_with(PARTIAL_SUFFIX)
        })
        .filter(|e| {
            e.metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| now.duration_since(t).ok())
                .is_some_and(|elapsed| elapsed >= age)
        })
        .filter_map(|e| std::fs::remove_file(e.path()).ok().map(|()| e.path()))
        .collect()
}

/// Writes `bytes` to `path` atomically: readers see the old file or the new one, never a part.
///
/// Only a regular file is replaced that way. A symbolic link is followed and its target
/// written (the link stays a link); something that is not a regular file — a device such as
/// `/dev/null`, a named pipe, a socket — is written in place, never replaced by a file.
///
/// # Errors
/// [`FileError::Io`] with the path.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    let io = |source| FileError::Io {
        path: path.to_owned(),
        source,
    };
    let target = writable_target(path).map_err(io)?;
    match std::fs::metadata(&target) {
        Ok(existing) if !existing.is_file() => {
            // A device, a pipe or a socket: written as it is, never replaced.
            let mut file = std::fs::OpenOptions::new()
                .write(true)
                .open(&target)
                .map_err(io)?;
            file.write_all(bytes).map_err(io)?;
            return file.flush().map_err(io);
        }
        _ => {}
    }
    replace_file(&target, bytes).map_err(io)
}

/// Checks that `path` can be written as a command's output, before any work is done for it:
/// standard output (`-`), or a file (new, or one to replace) in a folder that exists — so that
/// a mistyped folder fails at once, not after minutes of tracking or training.
///
/// # Errors
/// [`FileError::Io`] with the path: its folder does not exist (or is a file), or the path is a
/// folder.
pub fn check_output(path: &Path) -> Result<(), FileError> {
    if is_stdout(path) {
        return Ok(());
    }
    writable_target(path)
        .map(drop)
        .map_err(|source| FileError::Io {
            path: path.to_owned(),
            source,
        })
}

/// The file `path` finally names ([`link_target`]), when a file can be written there: its
/// folder exists and it is not itself a folder. The one check [`check_output`] makes before a
/// command's work and [`write_atomic`] at the write (where a folder removed meanwhile is said
/// plainly, not as the temporary file's path).
fn writable_target(path: &Path) -> std::io::Result<PathBuf> {
    let target = link_target(path)?;
    folder_exists(&target)?;
    if target.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a folder, not a file",
        ));
    }
    Ok(target)
}

/// The folder a file `path` is written in: its parent, or the working folder.
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// Whether the folder `path` is written in exists; an error that names it when not.
fn folder_exists(path: &Path) -> std::io::Result<()> {
    let folder = folder_of(path);
    if folder.is_dir() {
        return Ok(());
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::NotFound,
        if folder.exists() {
            format!("{} is not a folder", folder.display())
        } else {
            format!("its folder {} does not exist", folder.display())
        },
    ))
}

/// Writes a command's output: `-` is standard output, anything else [`write_atomic`].
///
/// # Errors
/// [`FileError::Io`] with the path (`-` for standard output: a reader that went away gives
/// [`std::io::ErrorKind::BrokenPipe`], which a command ends on quietly).
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    if is_stdout(path) {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(bytes)
            .and_then(|()| out.flush())
            .map_err(|source| FileError::Io {
                path: path.to_owned(),
                source,
            });
    }
    write_atomic(path, bytes)
}

/// Whether an output path means standard output (`-`).
#[must_use]
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The file a path finally names, following symbolic links (also ones whose target does not
/// exist yet, which the write creates); `path` itself when it is not a link.
fn link_target(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_owned();
    // As the kernel does: a chain of links longer than 40 is a loop.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let next = std::fs::read_link(&current)?;
                current = if next.is_absolute() {
                    next
                } else {
                    current.parent().unwrap_or(Path::new(".")).join(next)
                };
            }
            _ => return Ok(current),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// A regular file (or none yet) replaced by `bytes`: a temporary file beside it, synced, then
/// renamed over it.
fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = folder_of(path);
    // Named after the file and recognisably ours, so that one left by a killed process is
    // known for what it is and removed later ([`remove_stale_partials`]).
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let mut temp = tempfile::Builder::new()
        .prefix(&format!(".{}.", short_name(&name)))
        .suffix(PARTIAL_SUFFIX)
        .tempfile_in(&dir)?;
    // Temporary files are private (0600); the result should be as readable as the file it
    // replaces, or as an ordinary new file.
    let permissions = match std::fs::metadata(path) {
        Ok(existing) => Some(existing.permissions()),
        Err(_) => new_file_permissions(),
    };
    if let Some(permissions) = permissions {
        temp.as_file().set_permissions(permissions)?;
    }
    temp.write_all(bytes)?;
    temp.as_file().sync_all()?;
    temp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// A file name short enough to prefix a temporary name (file names are at most 255 bytes).
fn short_name(name: &str) -> &str {
    let cut = name
        .char_indices()
        .map(|(i, c)| i + c.len_utf8())
        .take_while(|&end| end <= 120)
        .last()
        .unwrap_or(0);
    &name[..cut]
}

/// Mode of a newly created output: rw-r--r--, like `touch` under the usual umask.
#[cfg(unix)]
fn new_file_permissions() -> Option<std::fs::Permissions> {
    use std::os::unix::fs::PermissionsExt as _;
    Some(std::fs::Permissions::from_mode(0o644))
}

/// Elsewhere temporary files are not private, so their permissions need no change.
#[cfg(not(unix))]
fn new_file_permissions() -> Option<std::fs::Permissions> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reading_stops_at_the_limit_also_where_there_is_no_size() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("big.json");
        std::fs::write(&path, [b' '; 100]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(read_at_most(&path, 100).map(|b| b.len()).ok(), Some(100));
        let e = read_at_most(&path, 99).err().map(|e| e.to_string());
        assert!(
            e.as_deref()
                .is_some_and(|e| e.contains("100 bytes is larger than the 99-byte limit")),
            "{e:?}"
        );
        // A device that never ends (what a mistyped path or a shell's `<(…)` can name).
        if cfg!(unix) {
            let e = read_at_most(Path::new("/dev/zero"), 1 << 20);
            assert!(
                matches!(e, Err(FileError::TooLarge { size: None, limit, .. }) if limit == 1 << 20),
                "{e:?}"
            );
        }
    }

    #[test]
    fn atomic_write_replaces_whole_files() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("out.json");
        write_atomic(&path, b"first").unwrap_or_else(|e| panic!("{e}"));
        write_atomic(&path, b"second").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read(&path).ok().as_deref(), Some(&b"second"[..]));
        // Nothing but the file itself is left in the folder.
        assert_eq!(
            std::fs::read_dir(dir.path()).map(|d| d.count()).ok(),
            Some(1)
        );
    }

    #[test]
    fn an_output_in_a_folder_that_is_not_there_is_refused_before_the_work_and_said_plainly() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let fine = dir.path().join("take.glb");
        assert!(
            check_output(&fine).is_ok(),
            "a new file in a folder that exists"
        );
        std::fs::write(&fine, b"old").unwrap_or_else(|e| panic!("{e}"));
        assert!(check_output(&fine).is_ok(), "a file to replace");
        assert!(check_output(Path::new("-")).is_ok(), "standard output");
        assert!(
            check_output(Path::new("take.glb")).is_ok(),
            "the working folder"
        );
        let missing = dir.path().join("typo").join("take.glb");
        let said = |e: FileError| e.to_string();
        let refused = check_output(&missing)
            .map_err(said)
            .err()
            .unwrap_or_default();
        assert!(
            refused.contains("does not exist") && refused.contains("typo"),
            "{refused}"
        );
        // The write says the same, not the name of its temporary file.
        let written = write_atomic(&missing, b"x")
            .map_err(said)
            .err()
            .unwrap_or_default();
        assert!(
            written.contains("its folder") && !written.contains(PARTIAL_SUFFIX),
            "{written}"
        );
        assert!(!missing.exists());
        // A file where the folder should be, and a folder where the file should be.
        let under_a_file = fine.join("take.json");
        let refused = check_output(&under_a_file)
            .map_err(said)
            .err()
            .unwrap_or_default();
        assert!(refused.contains("is not a folder"), "{refused}");
        let refused = check_output(dir.path())
            .map_err(said)
            .err()
            .unwrap_or_default();
        assert!(refused.contains("is a folder"), "{refused}");
    }

    #[test]
    fn partial_writes_a_killed_process_left_are_recognised_and_removed() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        // What a write in progress looks like (the process is killed before it ends).
        let temp = tempfile::Builder::new()
            .prefix(".take.json.")
            .suffix(PARTIAL_SUFFIX)
            .tempfile_in(dir.path())
            .unwrap_or_else(|e| panic!("{e}"));
        let (_, left) = temp.keep().unwrap_or_else(|e| panic!("{e}"));
        let mine = dir.path().join("notes.faceanim-partial.txt");
        std::fs::write(&mine, b"the user's").unwrap_or_else(|e| panic!("{e}"));
        // Young partial writes may be another process's: kept.
        assert!(remove_stale_partials(dir.path(), std::time::Duration::from_secs(60)).is_empty());
        assert_eq!(
            remove_stale_partials(dir.path(), std::time::Duration::ZERO),
            vec![left.clone()]
        );
        assert!(
            !left.exists() && mine.exists(),
            "only faceanim's partial write goes"
        );
    }

    #[test]
    #[cfg(unix)]
    fn special_files_are_written_in_place_and_links_stay_links() {
        use std::os::unix::fs::FileTypeExt as _;
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        // (Devices are tried through the command, in crates/cli/tests/fuzz.rs: a test that
        // failed here must not replace this machine's /dev/null.)
        // A link is followed, and stays a link; a dangling one creates its target.
        let target = dir.path().join("real.json");
        std::fs::write(&target, b"old").unwrap_or_else(|e| panic!("{e}"));
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink("real.json", &link).unwrap_or_else(|e| panic!("{e}"));
        write_atomic(&link, b"new").unwrap_or_else(|e| panic!("{e}"));
        assert!(std::fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink()));
        assert_eq!(std::fs::read(&target).ok().as_deref(), Some(&b"new"[..]));
        let dangling = dir.path().join("later.json");
        std::os::unix::fs::symlink("made.json", &dangling).unwrap_or_else(|e| panic!("{e}"));
        write_atomic(&dangling, b"made").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            std::fs::read(dir.path().join("made.json")).ok().as_deref(),
            Some(&b"made"[..])
        );
        // A loop of links is an error naming the path, not a hang.
        let a = dir.path().join("a");
        std::os::unix::fs::symlink("b", &a).unwrap_or_else(|e| panic!("{e}"));
        std::os::unix::fs::symlink("a", dir.path().join("b")).unwrap_or_else(|e| panic!("{e}"));
        assert!(write_atomic(&a, b"x").is_err());
        // A folder is refused by name.
        let e = write_atomic(dir.path(), b"x")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("is a folder"), "{e}");
        // A named pipe is written, not replaced.
        let fifo = dir.path().join("pipe");
        if std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || std::fs::read(fifo).unwrap_or_default())
            };
            write_atomic(&fifo, b"through the pipe").unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                reader.join().ok().as_deref(),
                Some(&b"through the pipe"[..])
            );
            assert!(std::fs::symlink_metadata(&fifo).is_ok_and(|m| m.file_type().is_fifo()));
        }
        // A very long name still gets its temporary file.
        let long = dir.path().join(format!("{}.json", "n".repeat(250)));
        write_atomic(&long, b"long").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read(&long).ok().as_deref(), Some(&b"long"[..]));
    }

    #[test]
    fn errors_name_the_path() {
        let e = load_character(Path::new("/nonexistent/face.glb"))
            .err()
            .map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("/nonexistent/face.glb: No such file or directory (os error 2)")
        );
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let e = load_character(dir.path())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("no neutral OBJ"), "{e}");
    }
}
