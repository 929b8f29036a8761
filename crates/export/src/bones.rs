//! The face's bones in an export: a captured head pose shared between upper spine, neck and
//! head (half each to neck and head, as VMagicMirror does, the spine following a smoothed share
//! of the yaw), gaze on the eye bones (through a VRM's lookAt range maps) and `jawOpen` on the
//! jaw bone, as much as the character's own jaw-open shape opens it.
//!
//! Rotations are made in character space and written as each bone's local rotation: a bone
//! whose parent's rest rotation is `P` and whose own rest rotation is `R`, turned by `q` in
//! character space beyond what its turned ancestors already turn (`A`), gets `P⁻¹·(A⁻¹·q)·P·R`.

use faceanim_anim::Clip;
use faceanim_rig::Character;
use faceanim_rig::bones::{Bone, FaceBones, Gaze, Joint};
use faceanim_rig::source::GltfSource as Source;
use glam::{EulerRot, Quat, Vec3};
use serde_json::Value;

/// The share of the head's yaw the upper spine follows.
pub const SPINE_SHARE: f32 = 0.2;
/// How slowly the spine follows (seconds, the time constant of its smoothing).
pub const SPINE_LAG: f32 = 0.2;
/// The share of the head's turn the neck takes where the rig has one.
pub const NECK_SHARE: f32 = 0.5;
/// How far a jaw opens at `jawOpen` 1 when the character has no jaw-open shape to measure.
pub const DEFAULT_JAW_DEGREES: f32 = 20.0;

/// Per key of an animation, what the eyes and the jaw do: from ARKit's eyeLook channels and
/// `jawOpen`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BoneKeys {
    /// Each eye's gaze `[yaw, pitch]` in degrees (left eye, right eye; yaw towards the
    /// character's left, pitch up), when the clip has eyeLook channels.
    pub gaze: Option<Vec<[[f32; 2]; 2]>>,
    /// `jawOpen`, 0..1, when the clip has it.
    pub jaw: Option<Vec<f32>>,
}

impl BoneKeys {
    /// The keys of `clip`, whose columns are read by their ARKit meaning in any spelling.
    #[must_use]
    pub fn from_clip(clip: &Clip) -> BoneKeys {
        // Each column's ARKit meaning, read once (a take has thousands of frames).
        let meaning: Vec<Option<&str>> = clip
            .blendshapes
            .iter()
            .map(|n| faceanim_rig::names::arkit_name(n))
            .collect();
        let column = |channel: &str| meaning.iter().position(|m| *m == Some(channel));
        let value =
            |row: &[f32], c: Option<usize>| c.and_then(|c| row.get(c)).copied().unwrap_or(0.0);
        let looks = meaning
            .iter()
            .any(|m| m.is_some_and(faceanim_rig::names::is_gaze));
        let gaze = looks.then(|| {
            clip.frames
                .iter()
                .map(|row| faceanim_rig::bones::gaze_from_arkit(|c| value(row, column(c))))
                .collect()
        });
        let jaw = column("jawOpen").map(|c| {
            clip.frames
                .iter()
                .map(|row| value(row, Some(c)).clamp(0.0, 1.0))
                .collect()
        });
        BoneKeys { gaze, jaw }
    }
}

/// A bone made ready to turn: its node written as TRS (an animated node may not have a
/// matrix), with the rotations that place it.
fn prepare_joint(source: &Source, nodes: &mut [Value], node: usize) -> Option<Joint> {
    let joint = source.joint(node)?;
    let value = nodes.get_mut(node)?;
    let (scale, _, translation) =
        faceanim_rig::source::local_matrix(value).to_scale_rotation_translation();
    if let Some(object) = value.as_object_mut() {
        object.remove("matrix");
    }
    // As f64 of the same f32 values, as the rest of the file writes numbers.
    let exact = |v: &[f32]| Value::from(v.iter().map(|&x| f64::from(x)).collect::<Vec<f64>>());
    value["translation"] = exact(&translation.to_array());
    value["rotation"] = exact(&joint.rest.to_array());
    value["scale"] = exact(&scale.to_array());
    Some(joint)
}

/// `joint`'s local rotation for a turn `q` in character space, as written.
fn local(joint: Joint, q: Quat) -> [f32; 4] {
    joint.local(q).to_array()
}

/// The rotation channels (node, one rotation per key) of one animation.
pub(crate) type Channels = Vec<(usize, Vec<[f32; 4]>)>;

/// The bones a set of animations turns, made ready once for all of them.
#[derive(Debug, Clone)]
pub(crate) struct Rig {
    head: Option<Joint>,
    neck: Option<Joint>,
    spine: Option<Joint>,
    eyes: Option<[Joint; 2]>,
    look: Gaze,
    jaw: Option<(Joint, f32)>,
}

impl Rig {
    /// The bones of `character`'s file that `wants_turn` (head poses), `wants_gaze` and
    /// `wants_jaw` need, written as TRS in `nodes`. Without a head bone the scene's first root
    /// turns instead.
    pub(crate) fn prepare(
        character: &Character,
        source: &Source,
        nodes: &mut [Value],
        wants: [bool; 3],
    ) -> Rig {
        let [wants_turn, wants_gaze, wants_jaw] = wants;
        let bones: FaceBones = source.bones();
        let mut joint = |n: Option<usize>| n.and_then(|n| prepare_joint(source, nodes, n));
        let head = if wants_turn {
            joint(faceanim_rig::turns::turned_head(source))
        } else {
            None
        };
        let split = wants_turn && bones.get(Bone::Head).is_some();
        let neck = if split {
            joint(bones.get(Bone::Neck))
        } else {
            None
        };
        let spine = if split {
            joint(bones.get(Bone::UpperSpine))
        } else {
            None
        };
        let look = source.gaze();
        let eyes = if wants_gaze && look != Gaze::Expressions {
            match (
                joint(bones.get(Bone::LeftEye)),
                joint(bones.get(Bone::RightEye)),
            ) {
                (Some(l), Some(r)) => Some([l, r]),
                _ => None,
            }
        } else {
            None
        };
        let jaw = if wants_jaw {
            joint(bones.get(Bone::Jaw)).map(|j| (j, jaw_degrees(character, source, j.node)))
        } else {
            None
        };
        Rig {
            head,
            neck,
            spine,
            eyes,
            look,
            jaw,
        }
    }

    /// Whether it turns eye bones with the gaze.
    pub(crate) fn turns_eyes(&self) -> bool {
        self.eyes.is_some()
    }

    /// The rotation channels of an animation with key `times`, head `rotations` and `keys`.
    pub(crate) fn channels(
        &self,
        times: &[f32],
        rotations: Option<&[[f32; 4]]>,
        keys: Option<&BoneKeys>,
    ) -> Channels {
        let mut out: Channels = Vec::new();
        if let (Some(head), Some(rotations)) = (self.head, rotations) {
            let mut spine_keys = Vec::with_capacity(rotations.len());
            let mut neck_keys = Vec::with_capacity(rotations.len());
            let mut head_keys = Vec::with_capacity(rotations.len());
            let mut spine_yaw: Option<f32> = None;
            for (k, q) in rotations.iter().enumerate() {
                let q = Quat::from_array(*q).normalize();
                let (yaw, _, _) = q.to_euler(EulerRot::YXZ);
                let dt = k
                    .checked_sub(1)
                    .and_then(|p| Some(times.get(k)? - times.get(p)?))
                    .unwrap_or(0.0)
                    .max(0.0);
                let target = SPINE_SHARE * yaw;
                let follow = 1.0 - (-dt / SPINE_LAG).exp();
                let now = spine_yaw.map_or(target, |s| s + (target - s) * follow);
                spine_yaw = Some(now);
                let spine = if self.spine.is_some() {
                    Quat::from_rotation_y(now)
                } else {
                    Quat::IDENTITY
                };
                let above = spine.inverse() * q;
                let neck = if self.neck.is_some() {
                    spine * Quat::IDENTITY.slerp(above, NECK_SHARE)
                } else {
                    spine
                };
                if let Some(j) = self.spine {
                    spine_keys.push(local(j, spine));
                }
                if let Some(j) = self.neck {
                    neck_keys.push(local(j, spine.inverse() * neck));
                }
                head_keys.push(local(head, neck.inverse() * q));
            }
            for (joint, keys) in [
                (self.spine, spine_keys),
                (self.neck, neck_keys),
                (Some(head), head_keys),
            ] {
                if let Some(j) = joint {
                    out.push((j.node, keys));
                }
            }
        }
        let held = |list: &[[[f32; 2]; 2]], k: usize| {
            list.get(k.min(list.len().saturating_sub(1))).copied()
        };
        if let (Some(eyes), Some(gaze)) = (self.eyes, keys.and_then(|k| k.gaze.as_ref())) {
            for (side, joint) in eyes.iter().enumerate() {
                let turns = (0..times.len())
                    .map(|k| {
                        let [yaw, pitch] = held(gaze, k).map_or([0.0; 2], |g| g[side]);
                        let [yaw, pitch] = match self.look {
                            Gaze::Bones(look) => look.eye([yaw, pitch], side == 0),
                            _ => [yaw, pitch],
                        };
                        local(
                            *joint,
                            Quat::from_array(faceanim_anim::head_rotation([yaw, pitch, 0.0])),
                        )
                    })
                    .collect();
                out.push((joint.node, turns));
            }
        }
        if let (Some((joint, degrees)), Some(open)) = (self.jaw, keys.and_then(|k| k.jaw.as_ref()))
        {
            let turns = (0..times.len())
                .map(|k| {
                    let open = open
                        .get(k.min(open.len().saturating_sub(1)))
                        .copied()
                        .unwrap_or(0.0);
                    local(joint, Quat::from_rotation_x((degrees * open).to_radians()))
                })
                .collect();
            out.push((joint.node, turns));
        }
        out
    }
}

/// How far the character's own jaw-open shape turns the chin about the jaw bone (degrees,
/// about the character's left-right axis), or [`DEFAULT_JAW_DEGREES`] without one.
fn jaw_degrees(character: &Character, source: &Source, jaw: usize) -> f32 {
    let map = character.name_map();
    let shape = map.driven_drives().find_map(|(i, drive)| {
        matches!(drive, faceanim_rig::names::Drive::Channel(c) if c.name() == "jawOpen")
            .then_some(i)
    });
    let Some(shape) = shape.and_then(|i| character.blendshapes().get(i)) else {
        return DEFAULT_JAW_DEGREES;
    };
    let pivot = source.world_matrix(jaw).transform_point3(Vec3::ZERO);
    let largest = shape.max_displacement();
    if largest <= 0.0 || !pivot.is_finite() {
        return DEFAULT_JAW_DEGREES;
    }
    let positions = character.positions();
    let mut angles: Vec<f32> = shape
        .indices()
        .iter()
        .zip(shape.deltas())
        .filter(|(_, d)| d.length() > 0.5 * largest)
        .filter_map(|(&v, d)| {
            let p = *positions.get(v as usize)?;
            let (a, b) = (p - pivot, p + *d - pivot);
            // The signed angle from a to b in the (y, z) plane: a turn about +X.
            let angle = (a.y * b.z - a.z * b.y).atan2(a.y * b.y + a.z * b.z);
            angle.is_finite().then_some(angle.to_degrees())
        })
        .collect();
    if angles.is_empty() {
        return DEFAULT_JAW_DEGREES;
    }
    angles.sort_by(f32::total_cmp);
    angles[angles.len() / 2].clamp(1.0, 40.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaze_and_jaw_come_from_arkit_channels_in_any_spelling() {
        let clip = Clip {
            fps: 30.0,
            blendshapes: [
                "EyeLookOut_L",
                "eyeLookInRight",
                "eyeLookUpLeft",
                "jawOpen",
                "x",
            ]
            .map(String::from)
            .to_vec(),
            frames: vec![vec![1.0, 0.5, 0.2, 0.4, 1.0], vec![0.0; 5]],
            head: None,
            head_position: None,
            presence: None,
        };
        let keys = BoneKeys::from_clip(&clip);
        let gaze = keys.gaze.unwrap();
        // Both eyes towards the character's left: the left eye out, the right eye in.
        let [sideways, up] = faceanim_rig::bones::EYE_RANGE;
        assert!((gaze[0][0][0] - sideways).abs() < 1e-5);
        assert!((gaze[0][1][0] - 0.5 * sideways).abs() < 1e-5);
        assert!((gaze[0][0][1] - 0.2 * up).abs() < 1e-5);
        assert_eq!(gaze[1], [[0.0; 2]; 2]);
        assert_eq!(keys.jaw, Some(vec![0.4, 0.0]));
        let none = BoneKeys::from_clip(&Clip {
            blendshapes: vec!["smile".into()],
            frames: vec![vec![1.0]],
            ..clip
        });
        assert_eq!(none, BoneKeys::default());
    }
}
