//! # faceanim-rig: the blendshape character
//!
//! Everything in faceanim — sketching, capture, the studio, the exporters — works on one
//! [`Character`]: a triangle mesh with a neutral pose and named blendshapes stored as sparse
//! per-vertex deltas, plus what is derived from them once: normals and normal deltas, the
//! bounding box (whose diagonal is the size `D` that default distances scale with), the edge
//! graph, the symmetry plane with each vertex's mirror partner, and left/right blendshape pairs.
//!
//! This crate is pure: it parses and writes bytes but never opens a file, so it can run in a
//! server, a test or a browser alike. External glTF resources come through [`import::Resources`].
//!
//! ```
//! use faceanim_rig::{Blendshape, Character, CharacterParts};
//! use glam::Vec3;
//!
//! // A one-triangle "face" whose top corner can rise.
//! let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
//! let raise = Blendshape::from_dense("raise", &[Vec3::ZERO, Vec3::ZERO, Vec3::new(0.0, 0.5, 0.0)], 1e-6);
//! let character = Character::new(CharacterParts {
//!     name: "tri".into(),
//!     positions,
//!     triangles: vec![[0, 1, 2]],
//!     blendshapes: vec![raise],
//!     ..CharacterParts::default()
//! })?;
//! let pose = character.pose(&[0.5]);
//! assert_eq!(pose.positions[2], Vec3::new(0.0, 1.25, 0.0));
//!
//! // Round trip through glTF.
//! let glb = faceanim_rig::export::export_glb(&character, &[])?;
//! let back = faceanim_rig::import::import_gltf(&glb, "tri.glb", &faceanim_rig::import::NoExternalResources)?;
//! assert_eq!(back.character.blendshapes()[0].name(), "raise");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod character;
mod excerpt;
pub mod export;
mod graph;
pub mod import;
pub mod json;
pub mod name_map;
pub mod names;
pub mod normals;
mod pose;
pub mod source;
pub mod symmetry;

pub use character::{
    Aabb, Blendshape, BlendshapeId, Character, CharacterParts, Material, MaterialId, ModelError,
    Part, SPARSE_DELTA_THRESHOLD, Texture,
};
pub use excerpt::{QUOTED_CHARS, excerpt};
/// The vector types of the public API, re-exported so users need not match versions.
pub use glam;
pub use graph::EdgeGraph;
pub use pose::Pose;
