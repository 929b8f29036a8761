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
//! std locks files on, with no process numbers to be reused).

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;

/// How the studio's folders are named.
const PREFIX: &str = "faceanim-studio-";

/// The lock file in each studio's folder.
const LOCK: &str = "running.lock";

/// A folder without its lock file is taken to be one a studio is making just now, for this
/// long since it last changed.
const MAKING: Duration = Duration::from_secs(60);

/// The running studio's folder, while there is one.
static ROOT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// The running studio's scratch folder: made by [`Scratch::open`], removed with everything
/// in it when dropped.
#[derive(Debug)]
pub struct Scratch {
    // The lock is let go of before the folder is removed (fields drop in this order): a
    // system that cannot remove an open file would otherwise keep the folder.
    _lock: File,
    dir: tempfile::TempDir,
}

impl Scratch {
    /// Removes the folders of studios that are gone, then makes this studio's, the one every
    /// upload's, recording's and preview's folder is made in from now on.
    ///
    /// # Errors
    /// The file error, naming what could not be made.
    pub fn open() -> Result<Scratch, std::io::Error> {
        for removed in sweep(&std::env::temp_dir()) {
            tracing::info!(
                "removed {}, left by a studio that was stopped before it could",
                removed.display()
            );
        }
        let dir = tempfile::Builder::new().prefix(PREFIX).tempdir()?;
        let path = dir.path().join(LOCK);
        let lock = File::create(&path)
            .and_then(|file| file.lock().map(|()| file))
            .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
        *root() = Some(dir.path().to_owned());
        Ok(Scratch { _lock: lock, dir })
    }

    /// The folder.
    #[must_use]
    pub fn path(&self) -> &Path {
        self.dir.path()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let mut root = root();
        if root.as_deref() == Some(self.dir.path()) {
            *root = None;
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
/// One whose lock cannot be read is left alone, and so is one without a lock file that
/// changed within [`MAKING`].
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

/// Whether the studio folder `dir` belongs to no running studio.
fn abandoned(dir: &Path) -> bool {
    match File::open(dir.join(LOCK)) {
        // Taken, and let go of at once (the file is closed before the folder is removed).
        Ok(file) => file.try_lock().is_ok(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => std::fs::metadata(dir)
            .and_then(|m| m.modified())
            .is_ok_and(|changed| changed.elapsed().is_ok_and(|age| age > MAKING)),
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_swept_only_when_its_studio_is_gone() {
        let temp = tempfile::tempdir().unwrap();
        let running = temp.path().join(format!("{PREFIX}running"));
        let gone = temp.path().join(format!("{PREFIX}gone"));
        let making = temp.path().join(format!("{PREFIX}making"));
        let other = temp.path().join("someone-elses");
        for dir in [&running, &gone, &making, &other] {
            std::fs::create_dir(dir).unwrap();
            std::fs::write(dir.join("recording.wav"), b"RIFF").unwrap();
        }
        let held = File::create(running.join(LOCK)).unwrap();
        held.lock().unwrap();
        File::create(gone.join(LOCK)).unwrap();
        File::create(other.join(LOCK)).unwrap();
        assert_eq!(sweep(temp.path()), vec![gone.clone()]);
        assert!(running.exists() && making.exists() && other.exists() && !gone.exists());
        drop(held);
        assert_eq!(sweep(temp.path()), vec![running]);
    }
}
