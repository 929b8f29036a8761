//! # faceanim-testdata: the shared test data, for tests and benchmarks only
//!
//! The realistic test heads and images live in `../shared` beside the repository (or wherever
//! `FACEANIM_SHARED` points), never inside the product. This crate finds them, says clearly
//! when they are missing, and caches the parsed ICT head so a test binary imports it once.
#![deny(missing_docs)]

use std::path::PathBuf;
use std::sync::OnceLock;

use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};

/// `../shared/<rel>` beside the repository, or under `FACEANIM_SHARED`.
///
/// # Panics
/// When the file is missing, with a message saying where it was expected.
#[must_use]
#[expect(
    clippy::panic,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn shared(rel: &str) -> PathBuf {
    let base = std::env::var_os("FACEANIM_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let path = base.join(rel);
    if !path.exists() {
        panic!(
            "test data {} is missing: the shared/ folder must sit beside the repository",
            path.display()
        );
    }
    path
}

/// The bytes of `../shared/characters/ict-face.glb`, read once.
///
/// # Panics
/// When the file is missing or unreadable.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn ict_bytes() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        std::fs::read(shared("characters/ict-face.glb")).expect("ict-face.glb is readable")
    })
}

/// The ICT head (24,591 vertices, 53 blendshapes), imported once.
///
/// # Panics
/// When the file is missing or does not import.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn ict() -> &'static Character {
    static ICT: OnceLock<Character> = OnceLock::new();
    ICT.get_or_init(|| {
        import_gltf(ict_bytes(), "ict-face.glb", &NoExternalResources)
            .expect("ict-face.glb imports")
            .character
    })
}
