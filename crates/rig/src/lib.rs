//! # faceanim-rig: the blendshape character
//!
//! Everything in faceanim — sketching, capture, the studio, the exporters — works on one
//! [`Character`]: a triangle mesh with a neutral pose and named blendshapes stored as sparse
//! per-vertex deltas, plus what is derived from them once: normals and normal deltas, the
//! bounding box (whose diagonal is the size `D` that default distances scale with), the edge
//! graph, the symmetry plane with each vertex's mirror partner, and left/right blendshape pairs.
//!
//! This crate is pure: it parses bytes and never opens a file, so it can run in a
//! server, a test or a browser alike. External glTF resources come through [`import::Resources`].
//! Writing characters back (GLB, the user's own file with an animation) is `faceanim-export`'s.
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
//! assert_eq!(character.find_blendshape("raise").map(|id| id.index()), Some(0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod animation;
mod binding;
mod blendshape;
pub mod bones;
mod bounds;
mod character;
mod excerpt;
pub mod file_animation;
mod graph;
pub mod import;
pub mod json;
pub mod name_map;
pub mod names;
pub mod normals;
mod pose;
mod runs;
pub mod source;
pub mod symmetry;
pub mod turns;

pub use blendshape::{Blendshape, BlendshapeId, SPARSE_DELTA_THRESHOLD};
pub use bounds::Aabb;
pub use character::{
    AlphaMode, Character, CharacterParts, Material, MaterialId, ModelError, Part, Texture,
};
pub use excerpt::{QUOTED_CHARS, excerpt};
/// The vector types of the public API, re-exported so users need not match versions.
pub use glam;
pub use graph::EdgeGraph;
pub use pose::Pose;
