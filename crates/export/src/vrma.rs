//! VRM Animation (`.vrma`, the `VRMC_vrm_animation` 1.0 extension): the animation alone, as
//! any VRM app plays it on any VRM avatar (three-vrm's `@pixiv/three-vrm-animation`, UniVRM,
//! VRoid Hub). VRM apps drive a face through its VRM expressions, not its raw morph targets
//! (three-vrm sets every morph target an expression binds from the expressions, each frame), so
//! a morph-weight animation inside a `.vrm` is overwritten there; this is how one reaches them.
//!
//! - **Expressions**: each frame's morph targets (what every blendshape of the character moves,
//!   a VRM expression's through its bindings) are expressed in the avatar's own expressions, a
//!   bounded least-squares fit (weights in 0..1, as the specification clamps them), so that an
//!   animation on `Fcl_MTH_A` becomes `aa` and one on `aa` stays `aa`. Each expression is a
//!   node whose translation's X is its weight. The lookAt expressions (`lookUp`…) may not be
//!   animated: the gaze goes through `lookAt`. What no expression binds cannot be carried; a
//!   note names it.
//! - **Humanoid**: the avatar's humanoid bones (but its eyes) as nodes at their places,
//!   unrotated (VRM's T-pose, facing +Z: VRM 0.x avatars are read turned so; players take the
//!   hips' height from them), and with a head pose the head's turn shared between the upper
//!   spine, neck and head as the GLB export shares it ([`faceanim_rig::bones::HeadSplit`]).
//! - **LookAt**: with a gaze, a node whose rotation is the two eyes' mean gaze as yaw (towards
//!   the avatar's left) and pitch (up), in degrees through Euler YXZ, as three-vrm reads it.

use faceanim_rig::Character;
use faceanim_rig::bones::HeadSplit;
use faceanim_rig::source::{GltfSource, VrmExpression};
use glam::{EulerRot, Quat, Vec3};
use serde_json::{Map, Value, json};

use crate::glb::Bin;
use crate::{Animation, ExportError};

/// The lookAt presets, which an animation may not move (the gaze does).
const LOOK_PRESETS: [&str; 4] = ["lookUp", "lookDown", "lookLeft", "lookRight"];

/// The least weight an expression must reach somewhere for its track to be written.
const MOVES: f32 = 1e-3;

/// The most sweeps of the fit per frame, and the change at which it stops.
const SWEEPS: usize = 200;
const SETTLED: f32 = 1e-6;

/// `animation` as a VRM Animation, with notes on what it carries and what it cannot.
///
/// # Errors
/// [`ExportError::NeedsCharacter`] without a character, [`ExportError::NotVrm`] for one that is
/// no VRM, [`ExportError::Glb`] for keys that do not fit one another (none, weights or turns
/// of another count), [`ExportError::NothingToCarry`] when nothing the format carries moves.
pub(crate) fn vrma(
    animation: &Animation<'_>,
    notes: &mut Vec<String>,
) -> Result<Vec<u8>, ExportError> {
    let character = crate::Format::Vrma.character_of(animation.character)?;
    // A VRM avatar, as `character_of` says: read from its file.
    let source = character
        .source()
        .ok_or_else(|| ExportError::NotVrm(character.name().to_owned()))?;
    let morph = &animation.animation;
    // Keys, weights and turns that fit one another (the GLB's rule), whatever made them.
    crate::glb::check_animation(morph, morph.weights.first().map_or(0, Vec::len))?;
    let times = &morph.times;
    let mut file = File::default();

    let expressions = expression_tracks(character, source, &morph.weights, notes);
    for (expression, weights) in &expressions {
        let node = file.node(json!({ "name": expression.name }));
        let values: Vec<f32> = weights.iter().flat_map(|&w| [w, 0.0, 0.0]).collect();
        file.channel(node, "translation", times, &values, "VEC3");
        let kind = if expression.preset {
            "preset"
        } else {
            "custom"
        };
        file.extension["expressions"][kind][&expression.name] = json!({ "node": node });
    }

    let turned = humanoid(&mut file, source, times, morph.rotations.as_deref());

    let keys = animation.bone_keys();
    // A gaze that never turns is left to the app (its own look at the camera).
    let gaze = keys
        .gaze
        .as_ref()
        .filter(|g| g.iter().flatten().flatten().any(|a| a.abs() > 0.01));
    if let Some(gaze) = gaze {
        let node = file.node(json!({ "name": "lookAt" }));
        let values: Vec<f32> = (0..times.len())
            .flat_map(|k| {
                let [[ly, lp], [ry, rp]] = gaze[k.min(gaze.len() - 1)];
                let (yaw, pitch) = (
                    (0.5 * (ly + ry)).to_radians(),
                    (0.5 * (lp + rp)).to_radians(),
                );
                Quat::from_euler(EulerRot::YXZ, yaw, pitch, 0.0).to_array()
            })
            .collect();
        file.channel(node, "rotation", times, &values, "VEC4");
        file.extension["lookAt"] = json!({ "node": node });
    }

    if file.channels.is_empty() {
        return Err(ExportError::NothingToCarry(character.name().to_owned()));
    }
    let mut carried = Vec::new();
    if !expressions.is_empty() {
        let names: Vec<&str> = expressions.iter().map(|(e, _)| e.name.as_str()).collect();
        carried.push(format!(
            "{} VRM expression{} ({})",
            names.len(),
            if names.len() == 1 { "" } else { "s" },
            names.join(", ")
        ));
    }
    if !turned.is_empty() {
        carried.push(format!("the head's turn ({})", turned.join(", ")));
    }
    if gaze.is_some() {
        carried.push("the gaze (lookAt)".to_owned());
    }
    notes.push(format!("carries {}", carried.join(", ")));
    file.finish(&morph.name)
}

/// The humanoid's bones (but its eyes) as unrotated nodes at their places (also without a head
/// pose: players take the hips' height from them), with the head's turn, where `rotations`
/// gives one, on its upper spine, neck and head; the bones turned.
fn humanoid(
    file: &mut File,
    source: &GltfSource,
    times: &[f32],
    rotations: Option<&[[f32; 4]]>,
) -> Vec<String> {
    let bones: Vec<(String, usize)> = faceanim_rig::bones::vrm_humanoid(source.document())
        .into_iter()
        .filter(|(name, _)| name != "leftEye" && name != "rightEye")
        .collect();
    if bones.is_empty() {
        return Vec::new();
    }
    let nodes = source
        .document()
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(&[][..], Vec::as_slice);
    let parents = faceanim_rig::bones::parents(nodes);
    let place = |node: usize| source.world_matrix(node).transform_point3(Vec3::ZERO);
    // Each bone's nearest ancestor among the bones.
    let above = |node: usize| {
        let mut at = parents.get(node).copied().flatten();
        while let Some(n) = at {
            if let Some(k) = bones.iter().position(|(_, b)| *b == n) {
                return Some(k);
            }
            at = parents.get(n).copied().flatten();
        }
        None
    };
    let first = file.nodes.len();
    let mut extension = Map::new();
    for (k, (name, node)) in bones.iter().enumerate() {
        let parent = above(*node);
        let offset = place(*node) - parent.map_or(Vec3::ZERO, |p| place(bones[p].1));
        file.push(json!({ "name": name, "translation": crate::glb::exact(&offset.to_array()) }));
        extension.insert(name.clone(), json!({ "node": first + k }));
    }
    for (k, (_, node)) in bones.iter().enumerate() {
        if let Some(p) = above(*node) {
            push_child(&mut file.nodes[first + p], first + k);
        } else {
            file.roots.push(first + k);
        }
    }
    file.extension["humanoid"] = json!({ "humanBones": extension });

    let face = source.bones();
    let name_of = |node: Option<usize>| {
        node.and_then(|n| bones.iter().find(|(_, b)| *b == n))
            .map(|(name, _)| name.clone())
    };
    let (Some(rotations), Some(head_name)) = (
        rotations,
        name_of(face.get(faceanim_rig::bones::Bone::Head)),
    ) else {
        return Vec::new();
    };

    let spine = name_of(face.get(faceanim_rig::bones::Bone::UpperSpine));
    let neck = name_of(face.get(faceanim_rig::bones::Bone::Neck));
    let mut split = HeadSplit::default();
    let mut keys = [Vec::new(), Vec::new(), Vec::new()];
    for (k, q) in rotations.iter().enumerate() {
        let dt = k
            .checked_sub(1)
            .and_then(|p| Some(times.get(k)? - times.get(p)?))
            .unwrap_or(0.0);
        let turns = split.share(Quat::from_array(*q), dt, spine.is_some(), neck.is_some());
        for (list, turn) in keys.iter_mut().zip(turns) {
            list.extend(turn.to_array());
        }
    }
    let mut turned = Vec::new();
    for (name, values) in [spine, neck, Some(head_name)].into_iter().zip(keys) {
        if let Some(name) = name
            && let Some(k) = bones.iter().position(|(b, _)| *b == name)
        {
            file.channel(first + k, "rotation", times, &values, "VEC4");
            turned.push(name);
        }
    }
    turned
}

fn push_child(node: &mut Value, child: usize) {
    match node.get_mut("children").and_then(Value::as_array_mut) {
        Some(children) => children.push(json!(child)),
        None => node["children"] = json!([child]),
    }
}

/// Each VRM expression that moves, with its weight per key: every key's morph targets (what the
/// character's blendshapes move in the file) fitted by the expressions' bindings, bounded to
/// 0..1. Notes name the blendshapes that move and that no expression binds.
fn expression_tracks(
    character: &Character,
    source: &GltfSource,
    weights: &[Vec<f32>],
    notes: &mut Vec<String>,
) -> Vec<(VrmExpression, Vec<f32>)> {
    let all = source.vrm_expressions();
    let expressions: Vec<&VrmExpression> = all
        .iter()
        .filter(|e| {
            !e.binds.is_empty() && e.name != "neutral" && !LOOK_PRESETS.contains(&e.name.as_str())
        })
        .collect();
    // The morph targets, numbered as met.
    let mut targets: Vec<(u32, u32)> = Vec::new();
    let mut slot = |mesh: u32, target: u32| {
        targets
            .iter()
            .position(|&t| t == (mesh, target))
            .unwrap_or_else(|| {
                targets.push((mesh, target));
                targets.len() - 1
            })
    };
    let binds: Vec<Vec<(usize, f32)>> = expressions
        .iter()
        .map(|e| {
            e.binds
                .iter()
                .map(|b| (slot(b.mesh, b.target), b.weight))
                .collect()
        })
        .collect();
    let shapes: Vec<Vec<(usize, f32)>> = source
        .shapes()
        .iter()
        .map(|s| {
            s.iter()
                .map(|b| (slot(b.mesh, b.target), b.weight))
                .collect()
        })
        .collect();
    let count = targets.len();
    let dense = |list: &[(usize, f32)]| {
        let mut v = vec![0.0f32; count];
        for &(t, w) in list {
            v[t] += w;
        }
        v
    };
    let columns: Vec<Vec<f32>> = binds.iter().map(|b| dense(b)).collect();
    let gram: Vec<Vec<f32>> = columns
        .iter()
        .map(|a| {
            columns
                .iter()
                .map(|b| a.iter().zip(b).map(|(x, y)| x * y).sum())
                .collect()
        })
        .collect();

    let mut fitted = vec![Vec::with_capacity(weights.len()); expressions.len()];
    let mut e = vec![0.0f32; expressions.len()];
    let mut moved = vec![false; count];
    for row in weights {
        let mut m = vec![0.0f32; count];
        for (shape, &w) in shapes.iter().zip(row) {
            for &(t, b) in shape {
                m[t] += w * b;
            }
        }
        for (t, &v) in m.iter().enumerate() {
            moved[t] |= v.abs() > 0.05;
        }
        let c: Vec<f32> = columns
            .iter()
            .map(|col| col.iter().zip(&m).map(|(x, y)| x * y).sum())
            .collect();
        // Coordinate descent on ½eᵀGe − cᵀe within 0..1, from the last key's weights.
        for _ in 0..SWEEPS {
            let mut change = 0.0f32;
            for i in 0..e.len() {
                if gram[i][i] <= 0.0 {
                    continue;
                }
                let rest: f32 = (0..e.len())
                    .filter(|&j| j != i)
                    .map(|j| gram[i][j] * e[j])
                    .sum();
                let next = ((c[i] - rest) / gram[i][i]).clamp(0.0, 1.0);
                change = change.max((next - e[i]).abs());
                e[i] = next;
            }
            if change < SETTLED {
                break;
            }
        }
        for (track, &w) in fitted.iter_mut().zip(&e) {
            track.push(w);
        }
    }

    // The character's own blendshapes that move targets no expression binds.
    let bound: Vec<bool> = (0..count)
        .map(|t| columns.iter().any(|c| c[t] != 0.0))
        .collect();
    let names = character.blendshape_names();
    let unbound: Vec<usize> = shapes
        .iter()
        .enumerate()
        .filter(|(_, s)| s.iter().any(|&(t, _)| moved[t] && !bound[t]))
        .map(|(i, _)| i)
        // The gaze goes through lookAt.
        .filter(|&i| {
            names.get(i).is_some_and(|n| {
                !LOOK_PRESETS.iter().any(|l| n.starts_with(l))
                    && !faceanim_rig::names::arkit_name(n).is_some_and(faceanim_rig::names::is_gaze)
            })
        })
        .collect();
    // A blink shape outside the expressions (an ARKit eyeBlink beside VRoid's own lids) closes
    // the lids through the avatar's blinkLeft or blinkRight, where it has them.
    let mut lost: Vec<&str> = Vec::new();
    for i in unbound {
        let name = names.get(i).map_or("", String::as_str);
        let preset = match faceanim_rig::names::arkit_name(name) {
            Some("eyeBlinkLeft") => Some("blinkLeft"),
            Some("eyeBlinkRight") => Some("blinkRight"),
            _ => None,
        };
        match preset.and_then(|p| expressions.iter().position(|e| e.name == p)) {
            Some(e) => {
                for (track, row) in fitted[e].iter_mut().zip(weights) {
                    *track = track.max(row.get(i).copied().unwrap_or(0.0).clamp(0.0, 1.0));
                }
                notes.push(format!(
                    "{name}, in no VRM expression, closes the lids through {}",
                    expressions[e].name
                ));
            }
            None => lost.push(name),
        }
    }
    if !lost.is_empty() {
        let shown: Vec<&str> = lost.iter().take(8).copied().collect();
        notes.push(format!(
            "{} shape{} the animation moves {} in no VRM expression, which is all a VRM Animation moves: {}{}",
            lost.len(),
            if lost.len() == 1 { "" } else { "s" },
            if lost.len() == 1 { "is" } else { "are" },
            shown.join(", "),
            if lost.len() > shown.len() { ", …" } else { "" }
        ));
    }
    expressions
        .into_iter()
        .zip(fitted)
        .filter(|(_, w)| w.iter().any(|&w| w > MOVES))
        .map(|(e, w)| (e.clone(), w))
        .collect()
}

/// The file being written: its nodes, animation channels and extension.
struct File {
    bin: Bin,
    nodes: Vec<Value>,
    roots: Vec<usize>,
    channels: Vec<Value>,
    samplers: Vec<Value>,
    extension: Value,
    /// The key times' accessor, written once.
    times: Option<usize>,
}

impl Default for File {
    fn default() -> Self {
        File {
            bin: Bin::default(),
            nodes: Vec::new(),
            roots: Vec::new(),
            channels: Vec::new(),
            samplers: Vec::new(),
            extension: json!({ "specVersion": "1.0" }),
            times: None,
        }
    }
}

impl File {
    /// A node at the scene's root.
    fn node(&mut self, node: Value) -> usize {
        let n = self.push(node);
        self.roots.push(n);
        n
    }

    /// A node, placed by the caller.
    fn push(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// A linear channel moving `path` of `node` through `values` (`kind`: VEC3 or VEC4).
    fn channel(&mut self, node: usize, path: &str, times: &[f32], values: &[f32], kind: &str) {
        let input = match self.times {
            Some(input) => input,
            None => {
                let input = self.bin.key_times(times);
                self.times = Some(input);
                input
            }
        };
        let output = self.bin.floats(values, kind, None, None);
        self.samplers
            .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
        self.channels.push(json!({
            "sampler": self.samplers.len() - 1,
            "target": { "node": node, "path": path }
        }));
    }

    fn finish(self, name: &str) -> Result<Vec<u8>, ExportError> {
        let Bin {
            bytes,
            views,
            accessors,
        } = self.bin;
        let root = json!({
            "asset": { "version": "2.0", "generator": concat!("faceanim ", env!("CARGO_PKG_VERSION")) },
            "extensionsUsed": ["VRMC_vrm_animation"],
            "extensions": { "VRMC_vrm_animation": self.extension },
            "scene": 0,
            "scenes": [{ "nodes": self.roots }],
            "nodes": self.nodes,
            "animations": [{ "name": name, "channels": self.channels, "samplers": self.samplers }],
            "buffers": [{ "byteLength": bytes.len() }],
            "bufferViews": views,
            "accessors": accessors,
        });
        Ok(crate::glb::glb(&root, bytes)?)
    }
}
