//! The ICT head from `../shared`, and strokes drawn at 90 Hz the way a hand would draw them.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "test support"
)]

use faceanim_rig::BlendshapeId;
use faceanim_sketch::project::{SampleFile, StrokeFile};
use glam::Vec3;

pub use faceanim_testdata::ict;

pub fn id(name: &str) -> BlendshapeId {
    ict()
        .find_blendshape(name)
        .unwrap_or_else(|| panic!("no blendshape {name}"))
}

/// The vertex a blendshape moves most on the ICT head: the natural place to grab it (lip corner
/// for a smile).
pub fn handle_vertex(name: &str) -> u32 {
    most_moved(ict(), name)
}

/// The vertex blendshape `name` moves most on `character`.
pub fn most_moved(character: &faceanim_rig::Character, name: &str) -> u32 {
    let id = character
        .find_blendshape(name)
        .unwrap_or_else(|| panic!("no blendshape {name}"));
    let shape = character.blendshape(id).unwrap();
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

/// Where `v` goes with blendshape `name` at weight 1.
pub fn target_of(name: &str, v: u32) -> Vec3 {
    position(v) + ict().blendshape(id(name)).unwrap().delta_of(v)
}

/// Slightly off the surface, as a pen is when it touches the face.
pub fn near(v: u32) -> Vec3 {
    position(v) + ict().normals()[v as usize] * 0.001
}

/// A strokes project at 30 fps.
pub fn project(
    settings: faceanim_sketch::Settings,
    strokes: Vec<faceanim_sketch::StrokeFile>,
) -> faceanim_sketch::Project {
    faceanim_sketch::Project::from_file(faceanim_sketch::ProjectFile {
        version: 1,
        fps: 30.0,
        settings,
        strokes,
    })
    .unwrap()
}

pub fn uniform(x: f32) -> f32 {
    x
}
