//! The file's morph-weight animations, read as they are stored (see
//! [`crate::file_animation`]). A channel that cannot be read is left out with a warning: the
//! character still opens.

use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation as GltfInterpolation, Property};

use super::accessor::{Buffers, read_floats};
use crate::file_animation::{FileAnimation, Interpolation, WeightsTrack};

/// Every animation of `doc` that moves morph targets, with its `weights` channels.
pub(super) fn read(
    doc: &gltf::Document,
    buffers: &Buffers<'_>,
    warnings: &mut Vec<String>,
) -> Vec<FileAnimation> {
    let mut out = Vec::new();
    for animation in doc.animations() {
        let a = animation.index();
        let name = animation
            .name()
            .map_or_else(|| format!("animation {a}"), str::to_owned);
        let mut tracks: Vec<WeightsTrack> = Vec::new();
        for (c, channel) in animation.channels().enumerate() {
            let target = channel.target();
            if target.property() != Property::MorphTargetWeights {
                continue;
            }
            let Some(mesh) = target.node().mesh() else {
                continue;
            };
            let mesh_index = mesh.index() as u32;
            if tracks.iter().any(|t| t.mesh() == mesh_index) {
                // Another node showing the same mesh: one track per mesh.
                continue;
            }
            let targets = mesh
                .primitives()
                .map(|p| p.morph_targets().len())
                .max()
                .unwrap_or(0);
            let sampler = channel.sampler();
            let interpolation = match sampler.interpolation() {
                GltfInterpolation::Step => Interpolation::Step,
                GltfInterpolation::Linear => Interpolation::Linear,
                GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let read = read_floats(buffers, &sampler.input(), Some(Dimensions::Scalar))
                .map_err(|e| e.to_string())
                .and_then(|times| {
                    let values = read_floats(buffers, &sampler.output(), Some(Dimensions::Scalar))
                        .map_err(|e| e.to_string())?;
                    WeightsTrack::new(mesh_index, times, values, targets, interpolation)
                });
            match read {
                Ok(track) => tracks.push(track),
                Err(why) => warnings.push(format!(
                    "animations[{a}].channels[{c}] ('{}'): {why}; its weights are not read",
                    crate::excerpt(&name)
                )),
            }
        }
        let ours = animation
            .extras()
            .as_ref()
            .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
            .is_some_and(|extras| extras.get(crate::file_animation::EXTRAS_KEY).is_some());
        if !tracks.is_empty() {
            out.push(FileAnimation { name, tracks, ours });
        }
    }
    out
}
