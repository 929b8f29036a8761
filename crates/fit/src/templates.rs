//! The templates faceanim ships: a realistic head with artist-made shapes, and the built-in
//! stylised head whose shapes are made in code.

use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};

use crate::FitError;

/// ICT-FaceKit's neutral head and its expression shapes (MIT; see `templates/README.md`).
const REALISTIC: &[u8] = include_bytes!("../templates/ict-facekit.glb");

/// A template to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Template {
    /// ICT-FaceKit's realistic head (artist-made shapes), then the built-in head for the
    /// channels it lacks (`tongueOut`).
    Realistic,
    /// The built-in stylised head alone (52 shapes made in code).
    Stylised,
}

impl Template {
    /// The template's heads, in the order they are asked for shapes.
    ///
    /// # Errors
    /// [`FitError::Template`] if the embedded file does not import (a broken build).
    pub fn characters(self) -> Result<Vec<Character>, FitError> {
        let stylised = faceanim_head::default_character();
        Ok(match self {
            Template::Realistic => vec![realistic()?, stylised],
            Template::Stylised => vec![stylised],
        })
    }
}

/// The realistic template.
///
/// # Errors
/// [`FitError::Template`] if the embedded file does not import.
pub fn realistic() -> Result<Character, FitError> {
    import_gltf(REALISTIC, "ict-facekit", &NoExternalResources)
        .map(|imported| imported.character)
        .map_err(|e| FitError::Template(e.to_string()))
}
