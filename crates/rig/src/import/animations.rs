//! The file's morph-weight animations (with the bones they turn), read as they are stored (see
//! [`crate::file_animation`]). A channel that cannot be read is left out with a warning: the
//! character still opens.

use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation as GltfInterpolation, Property};

use super::accessor::{Buffers, read_floats};
use crate::file_animation::{FileAnimation, Interpolation, RotationTrack, WeightsTrack};

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
        let unread = |c: usize, why: String, what: &str| {
            format!(
                "animations[{a}].channels[{c}] ('{}'): {why}; its {what} are not read",
                crate::excerpt(&name)
            )
        };
        // Rotation channels are read only for an animation that moves morph targets (a body's
        // own animations are no take).
        let mut rotations = Vec::new();
        for (c, channel) in animation.channels().enumerate() {
            let target = channel.target();
            if target.property() == Property::Rotation {
                rotations.push((c, channel));
                continue;
            }
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
            let read = keys(buffers, &sampler, Dimensions::Scalar).and_then(|(times, values)| {
                WeightsTrack::new(mesh_index, times, values, targets, interpolation(&sampler))
            });
            match read {
                Ok(track) => tracks.push(track),
                Err(why) => warnings.push(unread(c, why, "weights")),
            }
        }
        let ours = animation
            .extras()
            .as_ref()
            .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
            .and_then(|mut extras| {
                extras
                    .get_mut(crate::file_animation::EXTRAS_KEY)
                    .map(serde_json::Value::take)
            });
        // An animation of bones alone is read where faceanim wrote it (a body with no
        // blendshapes, turned by its head, eyes and jaw); another tool's (a walk, an idle) is
        // no take of the face.
        if tracks.is_empty() && ours.is_none() {
            continue;
        }
        let mut turns: Vec<RotationTrack> = Vec::new();
        for (c, channel) in rotations {
            let sampler = channel.sampler();
            let node = channel.target().node().index() as u32;
            let read = keys(buffers, &sampler, Dimensions::Vec4).and_then(|(times, values)| {
                let quats = values
                    .chunks_exact(4)
                    .map(|q| [q[0], q[1], q[2], q[3]])
                    .collect();
                RotationTrack::new(node, times, quats, interpolation(&sampler))
            });
            match read {
                Ok(track) => turns.push(track),
                Err(why) => warnings.push(unread(c, why, "rotations")),
            }
        }
        if tracks.is_empty() && turns.is_empty() {
            continue;
        }
        let strokes = ours
            .as_ref()
            .and_then(|o| o.get(crate::file_animation::STROKES_KEY))
            .filter(|s| s.is_object())
            .cloned();
        out.push(FileAnimation {
            name,
            tracks,
            ours: ours.is_some(),
            turns,
            strokes,
        });
    }
    out
}

/// A sampler's key times and its values (`dimensions` each).
pub(super) fn keys(
    buffers: &Buffers<'_>,
    sampler: &gltf::animation::Sampler<'_>,
    dimensions: Dimensions,
) -> Result<(Vec<f32>, Vec<f32>), String> {
    let times = read_floats(buffers, &sampler.input(), Some(Dimensions::Scalar))
        .map_err(|e| e.to_string())?;
    let values =
        read_floats(buffers, &sampler.output(), Some(dimensions)).map_err(|e| e.to_string())?;
    Ok((times, values))
}

/// How `sampler` goes from key to key.
pub(super) fn interpolation(sampler: &gltf::animation::Sampler<'_>) -> Interpolation {
    match sampler.interpolation() {
        GltfInterpolation::Step => Interpolation::Step,
        GltfInterpolation::Linear => Interpolation::Linear,
        GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
    }
}
