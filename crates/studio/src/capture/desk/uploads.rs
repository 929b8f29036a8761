//! Inputs uploaded from the page, kept in private folders for the jobs that read them.

use std::path::PathBuf;

use super::CaptureDesk;
use crate::capture::open_take::private_dir;
use crate::error::ApiError;

impl CaptureDesk {
    /// Saves an uploaded input (or one photo of a sequence sent as `batch`) to a private
    /// folder and returns its path. Each upload gets a folder of its own (a sequence's photos
    /// share their batch's), so that two uploads of the same name at once never share a file.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] for a bad batch name, or the file error.
    pub fn store_upload(
        &mut self,
        name: &str,
        bytes: &[u8],
        batch: Option<&str>,
    ) -> Result<PathBuf, ApiError> {
        let root = private_dir(&mut self.uploads, "faceanim-capture-", "uploads")?.to_owned();
        // Photos sent together are one sequence: a folder of their own, read in name order.
        let dir = match batch {
            Some(batch) => {
                if batch.is_empty()
                    || batch.len() > 64
                    || !batch.chars().all(|c| c.is_ascii_alphanumeric())
                {
                    return Err(ApiError::Invalid(format!(
                        "batch: '{}' must be 1 to 64 letters and digits",
                        faceanim_rig::excerpt(batch)
                    )));
                }
                root.join(format!("batch-{batch}"))
            }
            None => {
                self.uploads_stored += 1;
                root.join(format!("upload-{}", self.uploads_stored))
            }
        };
        std::fs::create_dir_all(&dir).map_err(|source| ApiError::Scratch {
            what: dir.display().to_string(),
            source,
        })?;
        // Keep only a safe file name (its extension tells images from videos).
        let clean: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let clean = clean.trim_start_matches('.');
        let path = dir.join(if clean.is_empty() { "input" } else { clean });
        faceanim_files::write_atomic(&path, bytes)?;
        Ok(path)
    }
}
