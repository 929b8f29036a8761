//! The file's morph-weight animations (with the bones they turn), and those of the face's
//! bones alone, read as they are stored (see [`crate::file_animation`]). A channel that cannot
//! be read is left out with a warning: the character still opens.

use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation as GltfInterpolation, Property};

use super::accessor::{Buffers, read_floats};
use crate::bones::FaceBones;
use crate::file_animation::{FileAnimation, Interpolation, RotationTrack, WeightsTrack};

/// How far a key may stray from the first (a quaternion's or a position's component) and the
/// channel still hold still: exporters write every bone's rest as keys.
const STILL: f32 = 1e-4;

/// Every animation of `doc` that moves morph targets, with its `weights` channels and its
/// rotations; and every one that moves nothing but the turns of the face's `bones` (a head,
/// eyes or jaw keyed in another tool), with those.
pub(super) fn read(
    doc: &gltf::Document,
    buffers: &Buffers<'_>,
    bones: &FaceBones,
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
        // Rotation channels are read for an animation that moves morph targets, or that turns
        // the face's bones alone (a body's own animations are no take).
        let mut rotations = Vec::new();
        let mut placements = Vec::new();
        for (c, channel) in animation.channels().enumerate() {
            let target = channel.target();
            match target.property() {
                Property::Rotation => {
                    rotations.push((c, channel));
                    continue;
                }
                Property::Translation | Property::Scale => {
                    placements.push(channel);
                    continue;
                }
                Property::MorphTargetWeights => {}
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
        // blendshapes, turned by its head, eyes and jaw), or where all it moves is the turns of
        // the face's bones (a jaw and eyes keyed in Blender, whose exporter also writes every
        // other bone's rest); one that moves more (a walk, an idle) is no take of the face.
        let face_only = tracks.is_empty() && ours.is_none();
        if face_only && placements.iter().any(|channel| moves(buffers, channel, 3)) {
            continue;
        }
        let face: Vec<usize> = bones.found().map(|(_, node)| node).collect();
        if face_only
            && rotations.iter().any(|(_, channel)| {
                !face.contains(&channel.target().node().index()) && moves(buffers, channel, 4)
            })
        {
            continue;
        }
        let mut turns: Vec<RotationTrack> = Vec::new();
        for (c, channel) in rotations {
            let sampler = channel.sampler();
            let node = channel.target().node().index();
            // Of the face alone, the face's bones that move (the rest of the body holds still).
            if face_only && !(face.contains(&node) && moves(buffers, &channel, 4)) {
                continue;
            }
            let read = keys(buffers, &sampler, Dimensions::Vec4).and_then(|(times, values)| {
                let quats = values
                    .chunks_exact(4)
                    .map(|q| [q[0], q[1], q[2], q[3]])
                    .collect();
                RotationTrack::new(node as u32, times, quats, interpolation(&sampler))
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

/// Whether `channel`'s values (`width` numbers each: 3 for a position or scale, 4 for a
/// rotation) stray from its first key's by more than [`STILL`]; a channel that cannot be read
/// counts as moving (its animation is then no take of the face alone).
fn moves(buffers: &Buffers<'_>, channel: &gltf::animation::Channel<'_>, width: usize) -> bool {
    let dimensions = if width == 3 {
        Dimensions::Vec3
    } else {
        Dimensions::Vec4
    };
    let Ok((_, values)) = keys(buffers, &channel.sampler(), dimensions) else {
        return true;
    };
    // A cubic spline's keys are in-tangent, value, out-tangent: its values are the middles.
    let step = if interpolation(&channel.sampler()) == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    let mut keys = values.chunks_exact(width).skip(step / 3).step_by(step);
    let Some(first) = keys.next() else {
        return false;
    };
    keys.any(|key| key.iter().zip(first).any(|(a, b)| (a - b).abs() > STILL))
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
