//! # faceanim-head: the built-in default character
//!
//! faceanim does its main job with no file from the user: the studio opens on this head,
//! capture drives it, sketches animate it. It is built in code, deterministically (same bytes
//! every time), from nothing but geometry: a stylised human head and neck with hair, brows and
//! lips coloured, eyeballs with iris and pupil that look around, lids that close over them,
//! teeth, a tongue and a dark mouth behind lips that part — and the 52 ARKit blendshapes under
//! their ARKit names, left and right exact mirror images. Units are metres, +Y up, facing +Z.
//!
//! ```
//! let head = faceanim_head::default_character();
//! assert_eq!(head.blendshapes().len(), 52);
//! assert_eq!(head.arkit_coverage().len(), 52);
//! assert_eq!(head.symmetry().pairs().len(), 20);
//! ```
#![deny(missing_docs)]

pub mod field;
pub mod mesh;
pub mod shapes;

use faceanim_rig::{Blendshape, Character, CharacterParts, Material};

/// The character's name in files and the studio.
pub const NAME: &str = "faceanim-default";

/// Builds the default head (about 16,000 vertices, 52 blendshapes).
///
/// # Panics
/// Never for the shipped geometry; a broken edit to this crate panics here and in its tests.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "the input is this crate's own geometry, checked by its tests"
)]
pub fn default_character() -> Character {
    let mesh = mesh::build();
    let blendshapes = shapes::blendshapes(&mesh)
        .into_iter()
        .map(|(name, deltas)| Blendshape::from_dense(name, &deltas, 1e-7))
        .collect();
    Character::new(CharacterParts {
        name: NAME.to_owned(),
        positions: mesh.vertices.iter().map(|v| v.p).collect(),
        normals: None,
        uvs: None,
        colors: Some(mesh.colours),
        triangles: mesh.triangles,
        materials: vec![Material {
            name: "head".to_owned(),
            roughness: 0.6,
            ..Material::default()
        }],
        parts: Vec::new(),
        blendshapes,
        normal_deltas: None,
    })
    .expect("the default head is a valid character")
}
