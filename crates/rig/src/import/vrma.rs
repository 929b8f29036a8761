//! VRM Animation files (`.vrma`, the `VRMC_vrm_animation` 1.0 extension) read back as a take:
//! each VRM expression's weight (its node's translation X, clamped to 0..1), the head's turn
//! (the humanoid's spine, chest, upper chest, neck and head, each turned as VRM players turn
//! its normalized bone: its parent's rest rotation, its track, its own rest rotation undone),
//! and the gaze (the lookAt node's rotation as yaw and pitch, Euler YXZ), played at their keys'
//! rate from the first key to the last.

use std::collections::HashMap;

use glam::{EulerRot, Quat};
use gltf::accessor::Dimensions;
use gltf::animation::Property;
use serde_json::Value;

use super::types::{ImportError, ImportErrorKind, NoExternalResources};
use crate::file_animation::{RotationTrack, WeightsTrack, median_step, rate_of};

/// The humanoid bones whose turns make the head's, from the hips up.
const HEAD_CHAIN: [&str; 5] = ["spine", "chest", "upperChest", "neck", "head"];

/// A VRM Animation, played: frames of expression weights, the head's turn and the gaze.
#[derive(Debug, Clone, PartialEq)]
pub struct VrmaTake {
    /// The animation's name (`animation 0` where it has none).
    pub name: String,
    /// Frames a second: its keys' rate, where they are a whole 24–240 a second apart, else 30.
    pub fps: f32,
    /// The VRM expressions it moves, by name (presets in VRM 1.0's spelling).
    pub expressions: Vec<String>,
    /// Each frame's weight of every expression, 0..1.
    pub frames: Vec<Vec<f32>>,
    /// Each frame's head turn `[x, y, z, w]` (facing +Z), where it turns the head.
    pub head: Option<Vec<[f32; 4]>>,
    /// Each frame's gaze `[yaw, pitch]` in degrees (yaw towards the avatar's left, pitch up),
    /// where it has a lookAt track.
    pub gaze: Option<Vec<[f32; 2]>>,
}

/// Reads `bytes` (a `.vrma` named `source_name`) and plays its first animation.
///
/// # Errors
/// An [`ImportError`] naming `source_name`: not a glTF, no `VRMC_vrm_animation` extension, no
/// animation, a track that cannot be read.
pub fn import_vrma(bytes: &[u8], source_name: &str) -> Result<VrmaTake, ImportError> {
    read(bytes).map_err(|kind| ImportError {
        source_name: source_name.to_owned(),
        kind,
    })
}

/// One humanoid bone's turns, with the rest rotations that make them a normalized bone's.
struct Turn {
    bone: String,
    track: RotationTrack,
    parent_rest: Quat,
    rest: Quat,
}

fn read(bytes: &[u8]) -> Result<VrmaTake, ImportErrorKind> {
    let (json, bin) = super::gltf::split_container(bytes)?;
    let raw: Value =
        serde_json::from_slice(json).map_err(|e| ImportErrorKind::InvalidJson(e.to_string()))?;
    let extension = raw
        .pointer("/extensions/VRMC_vrm_animation")
        .cloned()
        .ok_or_else(|| {
            ImportErrorKind::Unsupported(
                "no VRMC_vrm_animation extension: not a VRM Animation".into(),
            )
        })?;
    let node_of = |v: &Value| v.get("node").and_then(Value::as_u64).map(|n| n as usize);
    let mut expression_nodes: Vec<(usize, String)> = Vec::new();
    for kind in ["preset", "custom"] {
        if let Some(map) = extension
            .pointer(&format!("/expressions/{kind}"))
            .and_then(Value::as_object)
        {
            for (name, e) in map {
                if let Some(n) = node_of(e) {
                    expression_nodes.push((n, name.clone()));
                }
            }
        }
    }
    let bones: HashMap<usize, String> = extension
        .pointer("/humanoid/humanBones")
        .and_then(Value::as_object)
        .map(|m| {
            m.iter()
                .filter_map(|(name, b)| Some((node_of(b)?, name.clone())))
                .collect()
        })
        .unwrap_or_default();
    let look_at = extension.get("lookAt").and_then(node_of);

    let prepared = super::extensions::prepare(json, bin, &NoExternalResources)?;
    let document = gltf::Document::from_json(prepared.root)
        .map_err(|e| ImportErrorKind::InvalidJson(e.to_string()))?;
    let buffers = prepared.buffers;
    let animation = document.animations().next().ok_or_else(|| {
        ImportErrorKind::Unsupported("a VRM Animation without an animation".into())
    })?;
    let name = animation
        .name()
        .map_or_else(|| "animation 0".to_owned(), str::to_owned);

    // Each node's rotation at rest, in the file's space (a node its own ancestor is refused
    // there), and its parent.
    let parent = super::gltf::node_parents(&document);
    let rests: Vec<Quat> = super::gltf::world_matrices(&document)?
        .iter()
        .map(|m| m.to_scale_rotation_translation().1.normalize())
        .collect();
    let world = |node: usize| rests.get(node).copied().unwrap_or(Quat::IDENTITY);
    let bone_parent = |node: usize| -> Quat {
        let mut at = parent.get(node).copied().flatten();
        while let Some(n) = at {
            if bones.contains_key(&n) {
                return world(n);
            }
            at = parent.get(n).copied().flatten();
        }
        Quat::IDENTITY
    };

    let mut expressions: Vec<(String, WeightsTrack)> = Vec::new();
    let mut turns: Vec<Turn> = Vec::new();
    let mut look: Option<RotationTrack> = None;
    let mut longest: Vec<f32> = Vec::new();
    let (mut start, mut end) = (f32::INFINITY, 0.0f32);
    for (c, channel) in animation.channels().enumerate() {
        let target = channel.target();
        let node = target.node().index();
        let sampler = channel.sampler();
        let interpolation = super::animations::interpolation(&sampler);
        let unread = |why: String| {
            ImportErrorKind::InvalidJson(format!("animations[0].channels[{c}]: {why}"))
        };
        let expression = expression_nodes.iter().find(|(n, _)| *n == node);
        let (times, track) = match (target.property(), expression) {
            (Property::Translation, Some((_, expression))) => {
                let (times, values) = super::animations::keys(&buffers, &sampler, Dimensions::Vec3)
                    .map_err(unread)?;
                let weights: Vec<f32> = values.chunks_exact(3).map(|v| v[0]).collect();
                let track = WeightsTrack::new(0, times.clone(), weights, 1, interpolation)
                    .map_err(unread)?;
                expressions.push((expression.clone(), track));
                (times, None)
            }
            (Property::Rotation, _) if bones.contains_key(&node) || look_at == Some(node) => {
                let (times, values) = super::animations::keys(&buffers, &sampler, Dimensions::Vec4)
                    .map_err(unread)?;
                let quats = values
                    .chunks_exact(4)
                    .map(|q| [q[0], q[1], q[2], q[3]])
                    .collect();
                let track = RotationTrack::new(node as u32, times.clone(), quats, interpolation)
                    .map_err(unread)?;
                (times, Some(track))
            }
            // Hips' translation, other bones' scale: nothing a face takes.
            _ => continue,
        };
        if let Some(track) = track {
            if look_at == Some(node) {
                look = Some(track);
            } else if let Some(bone) = bones
                .get(&node)
                .filter(|b| HEAD_CHAIN.contains(&b.as_str()))
            {
                turns.push(Turn {
                    bone: bone.clone(),
                    track,
                    parent_rest: bone_parent(node),
                    rest: world(node),
                });
            }
        }
        start = start.min(times.first().copied().unwrap_or(0.0));
        end = end.max(times.last().copied().unwrap_or(0.0));
        if times.len() > longest.len() {
            longest = times;
        }
    }
    if expressions.is_empty() && turns.is_empty() && look.is_none() {
        return Err(ImportErrorKind::Unsupported(
            "its animation moves no expression, head bone or lookAt".into(),
        ));
    }
    turns.sort_by_key(|t| HEAD_CHAIN.iter().position(|b| *b == t.bone));

    let fps = rate_of(median_step(&longest));
    let start = if start.is_finite() { start } else { 0.0 };
    let count =
        ((end - start).clamp(0.0, crate::file_animation::MAX_SECONDS) * fps).round() as usize + 1;
    let time = |k: usize| start + k as f32 / fps;
    let frames = (0..count)
        .map(|k| {
            expressions
                .iter()
                .map(|(_, track)| track.at(time(k), 0).clamp(0.0, 1.0))
                .collect()
        })
        .collect();
    let head = (!turns.is_empty()).then(|| {
        (0..count)
            .map(|k| {
                turns
                    .iter()
                    .fold(Quat::IDENTITY, |q, turn| {
                        q * (turn.parent_rest * turn.track.at(time(k)) * turn.rest.inverse())
                    })
                    .normalize()
                    .to_array()
            })
            .collect()
    });
    let gaze = look.map(|track| {
        (0..count)
            .map(|k| {
                let (yaw, pitch, _) = track.at(time(k)).to_euler(EulerRot::YXZ);
                [yaw.to_degrees(), pitch.to_degrees()]
            })
            .collect()
    });
    Ok(VrmaTake {
        name,
        fps,
        expressions: expressions.into_iter().map(|(n, _)| n).collect(),
        frames,
        head,
        gaze,
    })
}
