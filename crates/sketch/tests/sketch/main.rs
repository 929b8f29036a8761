//! faceanim-sketch's integration tests, as one test binary: editing (handles, exaggeration,
//! layers, multi-blendshape strokes, the bake) and the paper's user-study tasks.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests"
)]

#[path = "../support/mod.rs"]
mod support;

mod any_face;
mod editing;
mod real_faces;
mod user_study;
