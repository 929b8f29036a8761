//! The bridge a character's capture goes through by default: its retarget map
//! ([`faceanim_retarget::RetargetMap`]), made by geometry ([`faceanim_fit::retarget_map`]) and
//! calibrated on the character ([`FaceCamera::calibrate`]) in seconds, kept beside the
//! character as `NAME.retarget.json`. No training: the adapter is an optional refinement.

use std::path::{Path, PathBuf};
use std::time::Instant;

use faceanim_retarget::RetargetMap;
use faceanim_rig::Character;
use faceanim_track::FaceModels;

use crate::{AdaptError, Control, FaceCamera};

/// Where a character's retarget map lives by default: `NAME.retarget.json` in `folder` (the
/// character file's folder), or in the current folder.
#[must_use]
pub fn default_map_path(folder: Option<&Path>, character_name: &str) -> PathBuf {
    let file = format!("{character_name}.retarget.json");
    match folder {
        Some(dir) => dir.join(file),
        None => PathBuf::from(file),
    }
}

/// Whether `character` needs a map at all: some channel MediaPipe reads has no shape of the
/// character's by name while some shape is free to take it. A rig with ARKit's names (or
/// nothing free) is driven by name as it is.
#[must_use]
pub fn needs_map(character: &Character) -> bool {
    let names: Vec<String> = character.blendshape_names();
    let parts = character.expression_parts();
    let by_name = RetargetMap::by_name(character.name(), &names, &parts);
    let unread = by_name.rows.iter().any(|row| {
        row.from == faceanim_retarget::RowSource::None
            && faceanim_track::BLENDSHAPE_NAMES.contains(&row.channel.as_str())
    });
    unread && !RetargetMap::free_shapes(&names, &parts).is_empty()
}

/// Why a map could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BridgeError {
    /// The template could not be placed on the character (no face found, too few landmarks).
    #[error(transparent)]
    Fit(#[from] faceanim_fit::FitError),
    /// Calibrating failed.
    #[error(transparent)]
    Calibration(#[from] AdaptError),
}

/// `character`'s retarget map: by name, by geometry from the shipped template for what its
/// names leave out, and calibrated on the character unless `calibrate` is false. A user's
/// rows in `previous` are kept. The face is found by the face model, or taken from `points`
/// where the user marked it ([`faceanim_fit::points`]); a face the face model cannot read on
/// the character's renders leaves the map uncalibrated (MediaPipe's scores as they are).
///
/// # Errors
/// [`BridgeError`] naming what failed.
pub fn make_map(
    character: &Character,
    models: &FaceModels,
    previous: Option<&RetargetMap>,
    points: Option<&faceanim_fit::FacePoints>,
    calibrate: bool,
    control: Control<'_>,
) -> Result<RetargetMap, BridgeError> {
    let started = Instant::now();
    let templates = faceanim_fit::Template::Realistic.characters()?;
    let templates: Vec<&Character> = templates.iter().collect();
    let mut map = faceanim_fit::retarget_map(character, &templates, models, previous, points)?;
    if calibrate {
        let camera = FaceCamera::frame(character, models)?;
        match camera.calibrate(character, models, &map, control) {
            Ok(calibration) => map.calibration = Some(calibration),
            Err(AdaptError::NoNeutralFace) => tracing::warn!(
                "{}: the face model does not read its renders, so the map is not calibrated",
                character.name()
            ),
            Err(e) => return Err(e.into()),
        }
    }
    map.made.seconds = Some((started.elapsed().as_secs_f32() * 10.0).round() / 10.0);
    Ok(map)
}
