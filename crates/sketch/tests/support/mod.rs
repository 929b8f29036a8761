//! The ICT head from `../shared`, and strokes drawn at 90 Hz the way a hand would draw them.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "test support"
)]

use std::path::PathBuf;
use std::sync::OnceLock;

use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_rig::{BlendshapeId, Character};
use faceanim_sketch::project::{SampleFile, StrokeFile};
use glam::Vec3;

pub fn ict() -> &'static Character {
    static ICT: OnceLock<Character> = OnceLock::new();
    ICT.get_or_init(|| {
        let base = std::env::var_os("FACEANIM_SHARED")
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
        let bytes = std::fs::read(base.join("characters/ict-face.glb"))
            .expect("../shared/characters/ict-face.glb is needed");
        import_gltf(&bytes, "ict-face.glb", &NoExternalResources)
            .unwrap()
            .character
    })
}

pub fn id(name: &str) -> BlendshapeId {
    ict()
        .find_blendshape(name)
        .unwrap_or_else(|| panic!("no blendshape {name}"))
}

/// The vertex a blendshape moves most: the natural place to grab it (lip corner for a smile).
pub fn handle_vertex(name: &str) -> u32 {
    let shape = ict().blendshape(id(name)).unwrap();
    let k = (0..shape.moved())
        .max_by(|&a, &b| {
            shape.deltas()[a]
                .length()
                .total_cmp(&shape.deltas()[b].length())
        })
        .unwrap();
    shape.indices()[k]
}

pub fn position(v: u32) -> Vec3 {
    ict().positions()[v as usize]
}

/// Samples at 90 Hz for `seconds`, at `path(progress(t / seconds))`.
pub fn draw(seconds: f32, path: impl Fn(f32) -> Vec3, progress: impl Fn(f32) -> f32) -> StrokeFile {
    let n = (seconds * 90.0).round() as usize;
    let samples = (0..=n)
        .map(|i| {
            let t = i as f32 / 90.0;
            SampleFile {
                t,
                p: path(progress(t / seconds)).to_array(),
            }
        })
        .collect();
    StrokeFile {
        samples,
        start_frame: None,
        duration: None,
        end: None,
        mid: None,
        ease: None,
        symmetry: None,
    }
}

/// A straight line from `a` to `b`.
pub fn line(a: Vec3, b: Vec3) -> impl Fn(f32) -> Vec3 {
    move |s| a.lerp(b, s)
}

/// A symmetric bow from `a` to `b`, bulging at the middle by the part of `bulge` perpendicular
/// to the chord.
pub fn bow(a: Vec3, b: Vec3, bulge: Vec3) -> impl Fn(f32) -> Vec3 {
    let chord = (b - a).normalize_or_zero();
    let bulge = bulge - chord * bulge.dot(chord);
    move |s| a.lerp(b, s) + bulge * (4.0 * s * (1.0 - s))
}

pub fn uniform(x: f32) -> f32 {
    x
}
