//! # faceanim-sketch: strokes become facial animation
//!
//! The algorithms of Cannavò et al., *A Sketch-based Interface for Facial Animation in
//! Immersive Virtual Reality* (sections 3.2–3.8), as a pure library that the studio and the
//! command line share:
//!
//! - a stroke's start picks the **reference vertex** (nearest vertex of the displayed pose);
//!   its end picks the **target** among the **candidates** (blendshapes that move that vertex,
//!   and "back to neutral"), Eq. 1 — [`Sketch::candidates`] gives the spheres to show;
//! - the **weight** is the end's projection on the blendshape's motion; what remains is the
//!   **exaggeration**, spread over the neighbours by distance along the mesh with a falloff
//!   ([`settings::Falloff`]), so the reference vertex lands exactly on the stroke end;
//! - the **arc** through the first, middle and last samples shapes the trajectory of every
//!   moving vertex ([`arc`]); the **timing** comes from the drawing speed, with an easing
//!   handle that composes with it ([`timing`]);
//! - **handles** (end, middle, easing) and timeline edits are inputs too ([`engine::Input`]);
//!   strokes **chain**, chains **layer**, **symmetry** mirrors, and a **multi-blendshape** mode
//!   solves all weights at once ([`solve`]);
//! - the result evaluates at any frame ([`evaluate`]), bakes into a clip, and bakes for glTF
//!   with arcs and exaggerations as extra morph targets ([`bake`]).
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use faceanim_rig::{Blendshape, Character, CharacterParts};
//! use faceanim_sketch::{Project, Sketch};
//! use glam::Vec3;
//!
//! // A small grid whose lower edge can drop ("open").
//! let mut positions = Vec::new();
//! for j in 0..5 { for i in 0..5 { positions.push(Vec3::new(i as f32 * 0.01, j as f32 * 0.01, 0.0)); } }
//! let mut triangles = Vec::new();
//! for j in 0..4u32 { for i in 0..4u32 { let a = j * 5 + i; triangles.push([a, a + 1, a + 6]); triangles.push([a, a + 6, a + 5]); } }
//! let open: Vec<Vec3> = positions.iter().map(|p| if p.y < 0.015 { Vec3::new(0.0, -0.01, 0.0) } else { Vec3::ZERO }).collect();
//! let character = Character::new(CharacterParts {
//!     name: "grid".into(), positions, triangles,
//!     blendshapes: vec![Blendshape::from_dense("open", &open, 1e-9)],
//!     ..CharacterParts::default()
//! })?;
//!
//! // One stroke from the lower edge halfway down, drawn in half a second.
//! let project = Project::from_json(br#"{"version": 1, "fps": 30, "strokes": [{"samples": [
//!     {"t": 0.0, "p": [0.02, 0.0, 0.0]}, {"t": 0.25, "p": [0.02, -0.0025, 0.0]}, {"t": 0.5, "p": [0.02, -0.005, 0.0]}]}]}"#)?;
//! let (sketch, warnings) = Sketch::from_project(&character, &project);
//! assert!(warnings.is_empty());
//! let clip = sketch.bake_clip();
//! assert_eq!(clip.frames.len(), 16); // 0.5 s at 30 fps: frames 0..=15
//! assert!((clip.frames[15][0] - 0.5).abs() < 1e-4); // halfway down = weight 0.5
//! # Ok(()) }
//! ```
#![deny(missing_docs)]

mod action;
pub mod arc;
pub mod bake;
pub mod engine;
pub mod evaluate;
pub mod layer;
pub mod project;
pub mod settings;
pub mod solve;
pub mod surface;
pub mod timing;

pub use engine::{Action, ActionId, Candidate, Candidates, Rejected, Side, Sketch, Target};
pub use project::{Input, Project, ProjectError, ProjectFile, Stroke, StrokeFile, StrokeSpec};
pub use settings::{Falloff, Settings};
