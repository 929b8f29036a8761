//! faceanim-rig's integration tests, as one test binary: broken files and the importers'
//! fuzzing, the glTF layouts other tools write, and the ICT-FaceKit heads.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests panic to fail, and compare exact zeros (a zero delta means: does not move)"
)]

#[path = "../support/mod.rs"]
mod support;

mod asymmetric;
mod avatars;
mod bad_input;
mod compressed;
mod fuzz_import;
mod gltf_layouts;
mod ict;
mod real_symmetry;
mod source_export;
mod vrma;
