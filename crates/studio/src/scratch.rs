//! The studio's scratch space: one private folder per running studio in the system's
//! temporary folder (`faceanim-studio-XXXXXX`), inside which every upload, microphone
//! recording and frame preview gets a folder of its own.
//!
//! One folder for all of them, so that stopping the studio removes them at once, whatever
//! still holds them (a job reading frames, a take's previews): a recording of the user's voice
//! must not outlive the studio that made it. A studio that was killed before it could remove
//! its folder (`kill -9`, a crash, a power cut) leaves it behind; the next studio to start
//! removes every such folder whose studio is gone. Each folder holds a lock file its studio
//! keeps locked while it runs: the system drops the lock when the process ends, however it
//! ends, so a folder whose lock can be taken is one no running studio uses (on every system
//! std locks files on, with no process numbers to be reused). A folder gets its studio's name
//! only once its lock is held (it is made under another name and renamed), so no sweep ever
//! sees a studio's folder before its lock.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// How the studio's folders are named.
const PREFIX: &str = "faceanim-studio-";

/// How a studio's folder is named while it is made, before its lock is held.
const MAKING: &str = ".faceanim-studio-making-";

/// The lock file in each studio's folder.
const LOCK: &str = "running.lock";

/// The running studio's folder, while there is one.
static ROOT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// The running studio's scratch folder: made by [`Scratch::open`], removed with everything
/// in it when dropped. One studio per process: a second one opened takes the first's place
/// for the folders made after it.
#[derive(Debug)]
pub struct Scratch {
    /// Let go of before the folder is removed: a system that cannot remove an open file
    /// would otherwise keep the folder.
    lock: Option<File>,
    path: PathBuf,
}

impl Scratch {
    /// Removes the folders of studios that are gone, then makes this studio's, the one every
    /// upload's, recording's and preview's folder is made in from now on.
    ///
    /// # Errors
    /// The file error, naming what could not be made.
    pub fn open() -> Result<Scratch, std::io::Error> {
        let temp = std::env::temp_dir();
        for removed in sweep(&temp) {
            tracing::info!(
                "removed {}, left by a studio that was stopped before it could",
                removed.display()
            );
        }
        let named = |e: std::io::Error, path: &Path| {
            std::io::Error::new(e.kind(), format!("{}: {e}", path.display()))
        };
        let making = tempfile::Builder::new()
            .prefix(MAKING)
            .tempdir()
            .map_err(|e| named(e, &temp))?;
        let lock_path = making.path().join(LOCK);
        let lock = File::create(&lock_path)
            .and_then(|file| file.lock().map(|()| file))
            .map_err(|e| named(e, &lock_path))?;
        let suffix = making
            .path()
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix(MAKING))
            .unwrap_or("0")
            .to_owned();
        let path = temp.join(format!("{PREFIX}{suffix}"));
        std::fs::rename(making.path(), &path).map_err(|e| named(e, &path))?;
        // Renamed: the folder is this Scratch's to remove now.
        let _ = making.keep();
        *root() = Some(path.clone());
        Ok(Scratch {
            lock: Some(lock),
            path,
        })
    }

    /// The folder.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        {
            let mut root = root();
            if root.as_deref() == Some(self.path.as_path()) {
                *root = None;
            }
        }
        drop(self.lock.take());
        if let Err(e) = std::fs::remove_dir_all(&self.path) {
            tracing::warn!("{}: could not be removed: {e}", self.path.display());
        }
    }
}

/// The running studio's folder slot.
fn root() -> std::sync::MutexGuard<'static, Option<PathBuf>> {
    ROOT.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A new private folder named `prefix…`: inside the running studio's scratch folder, or in
/// the system's temporary folder when none is open (a library caller's, a unit test's).
///
/// # Errors
/// The file error.
pub(crate) fn private_dir(prefix: &str) -> Result<tempfile::TempDir, std::io::Error> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(prefix);
    match root().clone() {
        Some(root) => builder.tempdir_in(root),
        None => builder.tempdir(),
    }
}

/// Removes the studio folders in `temp` that no running studio holds; the folders removed.
/// A folder without its lock file, or whose lock cannot be read, is left alone.
pub(crate) fn sweep(temp: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(temp) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let is_studios = entry
            .file_name()
            .to_str()
            .is_some_and(|name| name.starts_with(PREFIX))
            && entry.file_type().is_ok_and(|t| t.is_dir());
        if is_studios && abandoned(&entry.path()) && std::fs::remove_dir_all(entry.path()).is_ok() {
            removed.push(entry.path());
        }
    }
    removed
}

/// Whether the studio folder `dir` belongs to no running studio: its lock can be taken (and is
/// let go of at once: the file is closed before the folder is removed).
fn abandoned(dir: &Path) -> bool {
    File::open(dir.join(LOCK)).is_ok_and(|file| file.try_lock().is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_swept_only_when_its_studio_is_gone() {
        let temp = tempfile::tempdir().unwrap();
        let running = temp.path().join(format!("{PREFIX}running"));
        let gone = temp.path().join(format!("{PREFIX}gone"));
        let unlocked = temp.path().join(format!("{PREFIX}without-lock"));
        let other = temp.path().join("someone-elses");
        for dir in [&running, &gone, &unlocked, &other] {
            std::fs::create_dir(dir).unwrap();
            std::fs::write(dir.join("recording.wav"), b"RIFF").unwrap();
        }
        let held = File::create(running.join(LOCK)).unwrap();
        held.lock().unwrap();
        File::create(gone.join(LOCK)).unwrap();
        File::create(other.join(LOCK)).unwrap();
        assert_eq!(sweep(temp.path()), vec![gone.clone()]);
        assert!(running.exists() && unlocked.exists() && other.exists() && !gone.exists());
        drop(held);
        assert_eq!(sweep(temp.path()), vec![running]);
    }

    #[test]
    fn an_open_scratch_folder_holds_the_private_folders_and_goes_with_them() {
        let scratch = Scratch::open().unwrap();
        let folder = scratch.path().to_owned();
        assert!(
            folder
                .file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .starts_with(PREFIX)
        );
        // Held: no sweep removes it.
        assert!(!sweep(folder.parent().unwrap()).contains(&folder));
        let inside = private_dir("faceanim-uploads-").unwrap();
        assert_eq!(inside.path().parent(), Some(folder.as_path()));
        std::fs::write(inside.path().join("microphone.wav"), b"RIFF").unwrap();
        drop(scratch);
        assert!(!folder.exists());
    }
}
