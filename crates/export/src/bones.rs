//! The face's bones in an export: a captured head pose shared between upper spine, neck and
//! head (half each to neck and head, as VMagicMirror does, the spine following a smoothed share
//! of the yaw), gaze on the eye bones (through a VRM's lookAt range maps) and `jawOpen` on the
//! jaw bone, so that the mouth opens once, by the shape or by the bone (`jaw_turn`).
//!
//! Rotations are made in character space and written as each bone's local rotation: a bone
//! whose parent's rest rotation is `P` and whose own rest rotation is `R`, turned by `q` in
//! character space beyond what its turned ancestors already turn (`A`), gets `P⁻¹·(A⁻¹·q)·P·R`.

use faceanim_anim::Clip;
use faceanim_retarget::RetargetMap;
use faceanim_rig::Character;
use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::bones::{Bone, FaceBones, Gaze, Joint};
use faceanim_rig::source::GltfSource as Source;
use glam::{Quat, Vec3};
use serde_json::Value;

pub use faceanim_rig::bones::{NECK_SHARE, SPINE_LAG, SPINE_SHARE};
/// How far a jaw opens at `jawOpen` 1 when the character has no jaw-open shape to measure, or
/// one that only shapes the lips beside a chin the bone carries.
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
    /// The character's own weights at `jawOpen` 1 through its retarget map
    /// ([`jaw_opening`]): which of its shapes open its mouth when no name says so (a rig whose
    /// names say nothing), so that the jaw bone's turn is measured on them. `None`: by names.
    pub opening: Option<Vec<f32>>,
}

impl BoneKeys {
    /// The keys of a take: from the capture's own ARKit values (`arkit`) when there are any,
    /// else from its frames (`clip`) by their names' ARKit meaning.
    #[must_use]
    pub fn of_take(clip: &Clip, arkit: Option<&Clip>) -> BoneKeys {
        BoneKeys::from_clip(arkit.unwrap_or(clip))
    }

    /// The gaze and the jaw of one row of weights named `names` (a frame the studio's page
    /// plays), read as [`BoneKeys::from_clip`] reads a clip's rows.
    #[must_use]
    pub fn of_row(names: &[String], row: &[f32]) -> (Option<[[f32; 2]; 2]>, Option<f32>) {
        let keys = BoneKeys::of_rows(names, &[row]);
        (
            keys.gaze.and_then(|g| g.first().copied()),
            keys.jaw.and_then(|j| j.first().copied()),
        )
    }

    /// The keys of `clip`, whose columns are read by their ARKit meaning in any spelling.
    #[must_use]
    pub fn from_clip(clip: &Clip) -> BoneKeys {
        BoneKeys::of_rows(&clip.blendshapes, &clip.frames)
    }

    /// The keys of `rows` of weights named `names`, read by their ARKit meaning in any
    /// spelling.
    fn of_rows<R: AsRef<[f32]>>(names: &[String], rows: &[R]) -> BoneKeys {
        // Each column's ARKit meaning, read once (a take has thousands of frames).
        let meaning: Vec<Option<&str>> = names
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
            rows.iter()
                .map(|row| faceanim_rig::bones::gaze_from_arkit(|c| value(row.as_ref(), column(c))))
                .collect()
        });
        let jaw = column("jawOpen").map(|c| {
            rows.iter()
                .map(|row| value(row.as_ref(), Some(c)).clamp(0.0, 1.0))
                .collect()
        });
        BoneKeys {
            gaze,
            jaw,
            opening: None,
        }
    }
}

/// The character's own weights at `jawOpen` 1 through its retarget `map` (`None` where the
/// map moves none of its shapes for it): what opens its mouth when a take's jawOpen does, for
/// a rig whose names do not say.
#[must_use]
pub fn jaw_opening(map: &RetargetMap) -> Option<Vec<f32>> {
    let channel = faceanim_rig::names::ARKIT_52
        .iter()
        .position(|&c| c == "jawOpen")?;
    let mut values = [0.0; faceanim_rig::names::ARKIT_52.len()];
    values[channel] = 1.0;
    let weights = map.weights(&values);
    weights.iter().any(|&w| w > 0.01).then_some(weights)
}

/// Whether a body with no blendshapes takes something of `clip` on its bones ([`bones_take`];
/// `false` for a character with blendshapes, which takes a clip by their names).
#[must_use]
pub fn takes_clip(character: &Character, clip: &Clip) -> bool {
    character.blendshapes().is_empty() && bones_take(character, clip)
}

/// Whether `character`'s bones take something of `clip`, whatever its shapes: a head pose on
/// its head bone, gaze on its eye bones or `jawOpen` on its jaw bone. A clip none of whose
/// channels reaches its shapes still turns them (a jaw bone opened by `jawOpen` beside shapes
/// that only shape the lips).
#[must_use]
pub fn bones_take(character: &Character, clip: &Clip) -> bool {
    let Some(source) = character.source() else {
        return false;
    };
    let found = source.bones();
    let has = |bone: Bone| found.get(bone).is_some();
    let keys = BoneKeys::from_clip(clip);
    (clip.head.is_some() && has(Bone::Head))
        || (keys.gaze.is_some() && (has(Bone::LeftEye) || has(Bone::RightEye)))
        || (keys.jaw.is_some() && has(Bone::Jaw))
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
    /// turns instead. `opening`: what opens its mouth through its retarget map
    /// ([`BoneKeys::opening`]).
    pub(crate) fn prepare(
        character: &Character,
        source: &Source,
        nodes: &mut [Value],
        wants: [bool; 3],
        opening: Option<&[f32]>,
    ) -> Rig {
        Rig::build(character, source, wants, opening, |n| {
            prepare_joint(source, nodes, n)
        })
    }

    /// The bones `wants` needs (as [`Rig::prepare`]), each made by `make` from its node.
    fn build(
        character: &Character,
        source: &Source,
        wants: [bool; 3],
        opening: Option<&[f32]>,
        mut make: impl FnMut(usize) -> Option<Joint>,
    ) -> Rig {
        let [wants_turn, wants_gaze, wants_jaw] = wants;
        let bones: FaceBones = source.bones();
        let mut joint = |n: Option<usize>| n.and_then(&mut make);
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
        // Eye bones that carry no vertex (the eyeballs skinned to the head, a bone left
        // unweighted) would turn nothing: the gaze stays on the eyeLook shapes then.
        let eye_bones = [Bone::LeftEye, Bone::RightEye].map(|b| bones.get(b));
        let carried = || {
            let parents = node_parents(source);
            eye_bones
                .iter()
                .all(|b| b.is_some_and(|node| carries(source, &parents, node)))
        };
        let eyes = if wants_gaze && look != Gaze::Expressions && carried() {
            match eye_bones.map(&mut joint) {
                [Some(l), Some(r)] => Some([l, r]),
                _ => None,
            }
        } else {
            None
        };
        let jaw = if wants_jaw {
            bones.get(Bone::Jaw).and_then(|node| {
                joint(Some(node)).map(|j| (j, jaw_degrees(character, source, node, opening)))
            })
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
            let mut split = faceanim_rig::bones::HeadSplit::default();
            for (k, q) in rotations.iter().enumerate() {
                let dt = k
                    .checked_sub(1)
                    .and_then(|p| Some(times.get(k)? - times.get(p)?))
                    .unwrap_or(0.0);
                let [spine, neck, head_turn] = split.share(
                    Quat::from_array(*q),
                    dt,
                    self.spine.is_some(),
                    self.neck.is_some(),
                );
                if let Some(j) = self.spine {
                    spine_keys.push(local(j, spine));
                }
                if let Some(j) = self.neck {
                    neck_keys.push(local(j, neck));
                }
                head_keys.push(local(head, head_turn));
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

/// The face's bones as the studio's view carries them: a small skeleton of the bones a head
/// pose, the gaze and the jaw turn (the rest of the character on one bone at the origin), each
/// with no rotation at rest and at its bone's place in character space, and each vertex's share
/// of them summed from the file's own skinning (a vertex on a hair bone under the head follows
/// the head). Its poses are the export's turns (`Rig::channels`) of the same bones, so the
/// view turns what the exported file turns.
#[derive(Debug, Clone)]
pub struct ViewRig {
    /// The view's joints: the rest first, then the face's bones in [`Bone::ALL`]'s order where
    /// the rig turns them.
    pub joints: Vec<ViewJoint>,
    rig: Rig,
}

/// One joint of a [`ViewRig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewJoint {
    /// The face's bone it is, `None` for the rest of the character.
    pub bone: Option<Bone>,
    /// Its node in the character's file (`None` for the rest).
    pub node: Option<usize>,
    /// Its parent joint (`None` for the rest).
    pub parent: Option<usize>,
    /// Where it is in character space.
    pub pivot: Vec3,
}

impl ViewRig {
    /// The view's skeleton of `character`, when its file has a head bone (without one, a head
    /// pose turns the whole character and the view turns it so). Its jaw turns as the export's
    /// does, with what opens the mouth read through the character's retarget `map` where its
    /// names do not say ([`BoneKeys::opening`]).
    #[must_use]
    pub fn of(character: &Character, map: Option<&RetargetMap>) -> Option<ViewRig> {
        let opening = map.and_then(jaw_opening);
        let source = character.source()?;
        let bones = source.bones();
        bones.get(Bone::Head)?;
        let mut joints = vec![ViewJoint {
            bone: None,
            node: None,
            parent: None,
            pivot: Vec3::ZERO,
        }];
        let rig = Rig::build(character, source, [true; 3], opening.as_deref(), |node| {
            joints.push(ViewJoint {
                bone: bones.found().find(|(_, n)| *n == node).map(|(b, _)| b),
                node: Some(node),
                parent: None,
                pivot: source.world_matrix(node).transform_point3(Vec3::ZERO),
            });
            Some(Joint {
                node: joints.len() - 1,
                parent: Quat::IDENTITY,
                rest: Quat::IDENTITY,
            })
        });
        let parents = node_parents(source);
        let joint_of = nearest_joints(&joints, &parents);
        for joint in joints.iter_mut().skip(1) {
            let above = joint.node.and_then(|n| parents.get(n).copied().flatten());
            joint.parent = Some(above.and_then(|n| joint_of.get(n).copied()).unwrap_or(0));
        }
        Some(ViewRig { joints, rig })
    }

    /// How far the jaw bone turns at `jawOpen` 1, in degrees (0: the character's shapes open
    /// its mouth on their own), when it has one the view turns.
    #[must_use]
    pub fn jaw_degrees(&self) -> Option<f32> {
        self.rig.jaw.map(|(_, degrees)| degrees)
    }

    /// Whether the view's bones show what a value named `name` means: every ARKit channel the
    /// name is or stands for ([`faceanim_rig::names::stands_for`]) turns a bone the view has
    /// ([`Bone::turned_by`]: a sender's `eyeLookInLeft` or VRM's `lookLeft` the eyes, its
    /// `jawOpen` the jaw), so a body without shapes for them still follows them.
    #[must_use]
    pub fn shows(&self, name: &str) -> bool {
        let channels = match faceanim_rig::names::arkit_name(name) {
            Some(channel) => vec![channel],
            None => faceanim_rig::names::stands_for(name)
                .iter()
                .map(|c| c.name())
                .collect(),
        };
        let has = |bone| self.joints.iter().any(|j| j.bone == Some(bone));
        !channels.is_empty() && channels.iter().all(|c| Bone::turned_by(c).is_some_and(has))
    }

    /// Each vertex's four joints and shares (summing to 1): the file's skinning, each node it
    /// is placed by counted on the nearest of the view's joints at or above it.
    #[must_use]
    pub fn skin(&self, character: &Character) -> (Vec<[u8; 4]>, Vec<[f32; 4]>) {
        let Some(source) = character.source() else {
            let n = character.vertex_count();
            return (vec![[0; 4]; n], vec![[1.0, 0.0, 0.0, 0.0]; n]);
        };
        // Each node's joint, found once (a file has far fewer nodes than vertices).
        let joint_of = nearest_joints(&self.joints, &node_parents(source));
        let origins = source.origins();
        (0..character.vertex_count())
            .map(|v| {
                let mut share = vec![0.0f32; self.joints.len()];
                if let Some(Some(origin)) = origins.get(v) {
                    for &(node, w) in &origin.placed_by {
                        if w > 0.0 {
                            let j = joint_of.get(node as usize).copied().unwrap_or(0);
                            share[j] += w;
                        }
                    }
                }
                let mut order: Vec<usize> = (0..share.len()).collect();
                order.sort_by(|&a, &b| share[b].total_cmp(&share[a]));
                let mut joints = [0u8; 4];
                let mut weights = [0.0f32; 4];
                // A joint with no share is written as joint 0 (glTF asks unused ones to be).
                for (k, &j) in order.iter().take(4).enumerate() {
                    if share[j] > 0.0 {
                        joints[k] = u8::try_from(j).unwrap_or(0);
                        weights[k] = share[j];
                    }
                }
                let total: f32 = weights.iter().sum();
                if total > 0.0 {
                    weights.iter_mut().for_each(|w| *w /= total);
                } else {
                    (joints, weights) = ([0; 4], [1.0, 0.0, 0.0, 0.0]);
                }
                (joints, weights)
            })
            .unzip()
    }

    /// Per frame (one per `head`, at `fps`), each joint's rotation `[x, y, z, w]` as the
    /// export turns the bones: `head` shared between spine, neck and head, the gaze on the eyes
    /// and `jawOpen` on the jaw from `keys`. A frame without a head pose holds the head at rest.
    #[must_use]
    pub fn poses(
        &self,
        fps: f32,
        head: &[Option<[f32; 3]>],
        keys: &BoneKeys,
    ) -> Vec<Vec<[f32; 4]>> {
        let step = if fps > 0.0 { 1.0 / fps } else { 0.0 };
        let times: Vec<f32> = (0..head.len()).map(|k| k as f32 * step).collect();
        let rotations: Vec<[f32; 4]> = head
            .iter()
            .map(|h| h.map_or([0.0, 0.0, 0.0, 1.0], faceanim_anim::head_rotation))
            .collect();
        let channels = self.rig.channels(&times, Some(&rotations), Some(keys));
        let mut frames = vec![vec![[0.0, 0.0, 0.0, 1.0]; self.joints.len()]; head.len()];
        for (joint, keys) in channels {
            for (frame, q) in frames.iter_mut().zip(keys) {
                if let Some(slot) = frame.get_mut(joint) {
                    *slot = q;
                }
            }
        }
        frames
    }

    /// The joints `animation` of `character` turns (its weights by their names' ARKit meaning:
    /// the gaze on the eyes, `jawOpen` on the jaw, as a GLB export of the same weights turns the
    /// file's bones; its head rotations on spine, neck and head), with one rotation per key.
    #[must_use]
    pub fn turns(
        &self,
        character: &Character,
        animation: &MorphAnimation,
    ) -> Vec<(usize, Vec<[f32; 4]>)> {
        let keys = BoneKeys::from_clip(&Clip {
            fps: 30.0,
            blendshapes: character.blendshape_names(),
            frames: animation.weights.clone(),
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        });
        self.rig.channels(
            &animation.times,
            animation.rotations.as_deref(),
            Some(&keys),
        )
    }

    /// One live frame's rotations (as [`ViewRig::poses`]: the spine takes its share at once).
    #[must_use]
    pub fn pose(
        &self,
        head: Option<[f32; 3]>,
        gaze: Option<[[f32; 2]; 2]>,
        jaw: Option<f32>,
    ) -> Vec<[f32; 4]> {
        let keys = BoneKeys {
            gaze: gaze.map(|g| vec![g]),
            jaw: jaw.map(|j| vec![j.clamp(0.0, 1.0)]),
            opening: None,
        };
        self.poses(0.0, &[head], &keys).pop().unwrap_or_default()
    }
}

/// Each node's parent in `source`'s file.
fn node_parents(source: &Source) -> Vec<Option<usize>> {
    let nodes = source.document().get("nodes").and_then(Value::as_array);
    nodes.map_or_else(Vec::new, |n| faceanim_rig::bones::parents(n))
}

/// For each node, the nearest of `joints` at or above it (0, the rest, for none).
fn nearest_joints(joints: &[ViewJoint], parents: &[Option<usize>]) -> Vec<usize> {
    (0..parents.len())
        .map(|node| {
            let mut at = Some(node);
            // A file whose parents loop is cut after as many steps as it has nodes.
            for _ in 0..=parents.len() {
                let Some(n) = at else { break };
                if let Some(j) = joints.iter().position(|j| j.node == Some(n)) {
                    return j;
                }
                at = parents.get(n).copied().flatten();
            }
            0
        })
        .collect()
}

/// How far the jaw bone turns at `jawOpen` 1 (degrees, about the character's left-right axis),
/// from what opens the character's mouth ([`jaw_turn`]): its own jaw-open shape, else its open
/// vowel, else the shapes its retarget map opens it with (`opening`, the character's weights at
/// `jawOpen` 1); [`DEFAULT_JAW_DEGREES`] without any.
fn jaw_degrees(character: &Character, source: &Source, jaw: usize, opening: Option<&[f32]>) -> f32 {
    use faceanim_rig::names::{Drive, Expression, Viseme};
    let map = character.name_map();
    // Its jawOpen shape, else its open vowel (VRoid's `Fcl_MTH_A`, Ready Player Me's
    // `viseme_aa`): the shape that opens its mouth when a take's jawOpen does.
    let find = |wanted: fn(Drive) -> bool| {
        map.driven_drives()
            .find_map(|(i, drive)| wanted(drive).then_some(i))
    };
    let shape = find(|d| matches!(d, Drive::Channel(c) if c.name() == "jawOpen"))
        .or_else(|| find(|d| d == Drive::Expression(Expression::Viseme(Viseme::Aa))));
    let moves = match (shape.and_then(|i| character.blendshapes().get(i)), opening) {
        (Some(shape), _) => shape.moves().collect(),
        (None, Some(weights)) => mixed_moves(character, weights),
        (None, None) => Vec::new(),
    };
    let pivot = source.world_matrix(jaw).transform_point3(Vec3::ZERO);
    let largest = moves.iter().map(|(_, d)| d.length()).fold(0.0, f32::max);
    if largest <= 0.0 || !pivot.is_finite() {
        return DEFAULT_JAW_DEGREES;
    }
    let positions = character.positions();
    let under_jaw = below(&node_parents(source), jaw);
    let origins = source.origins();
    let (mut angles, mut on_bone) = (Vec::new(), 0usize);
    for &(v, d) in moves.iter().filter(|(_, d)| d.length() > 0.5 * largest) {
        let Some(&p) = positions.get(v as usize) else {
            continue;
        };
        let (a, b) = (p - pivot, p + d - pivot);
        // The signed angle from a to b in the (y, z) plane: a turn about +X.
        let angle = (a.y * b.z - a.z * b.y).atan2(a.y * b.y + a.z * b.z);
        if !angle.is_finite() {
            continue;
        }
        angles.push(angle.to_degrees());
        let share = match origins.get(v as usize) {
            Some(Some(origin)) => share_under(origin, &under_jaw),
            _ => 0.0,
        };
        on_bone += usize::from(share >= 0.5);
    }
    if angles.is_empty() {
        return DEFAULT_JAW_DEGREES;
    }
    angles.sort_by(f32::total_cmp);
    jaw_turn(angles[angles.len() / 2], 2 * on_bone > angles.len())
}

/// Each vertex's displacement when the character's shapes take `weights` together (its pose
/// there, less its rest), for the vertices that move, in vertex order.
fn mixed_moves(character: &Character, weights: &[f32]) -> Vec<(u32, Vec3)> {
    let posed = character.pose(weights).positions;
    posed
        .iter()
        .zip(character.positions())
        .map(|(&p, &rest)| p - rest)
        .enumerate()
        .filter(|(_, d)| d.length_squared() > 0.0)
        .filter_map(|(v, d)| Some((u32::try_from(v).ok()?, d)))
        .collect()
}

/// Below this turn of the chin, a jaw-open shape on a chin the jaw bone carries is a corrective
/// beside the bone's turn (Character Creator's `Jaw_Open` morph), not the opening itself.
const CORRECTIVE_DEGREES: f32 = 5.0;

/// How far the jaw bone turns at `jawOpen` 1, for a jaw-open shape that turns the chin by
/// `shape_degrees`, on a chin the bone carries (`chin_on_bone`) or not. The mouth opens once:
/// - the chin is not on the bone (it opens by the shape; the teeth and tongue may hang on the
///   bone): the bone turns as far as the shape turns the chin, so they go with it;
/// - the chin is on the bone and the shape is a corrective (under [`CORRECTIVE_DEGREES`]): the
///   bone opens the jaw by [`DEFAULT_JAW_DEGREES`], the shape shaping the lips around it;
/// - the chin is on the bone and the shape opens it on its own: the bone stays, as turning it
///   too would open the chin twice.
fn jaw_turn(shape_degrees: f32, chin_on_bone: bool) -> f32 {
    match (chin_on_bone, shape_degrees.abs() < CORRECTIVE_DEGREES) {
        (false, _) => shape_degrees.clamp(1.0, 40.0),
        (true, true) => DEFAULT_JAW_DEGREES,
        (true, false) => 0.0,
    }
}

/// Whether `node` or a node below it places some vertex of the character (its skinning, or a
/// mesh hung below it).
fn carries(source: &Source, parents: &[Option<usize>], node: usize) -> bool {
    let under = below(parents, node);
    source
        .origins()
        .iter()
        .flatten()
        .any(|origin| share_under(origin, &under) > 0.0)
}

/// How much of a vertex placed by `origin` the nodes marked in `under` ([`below`]) place.
fn share_under(origin: &faceanim_rig::source::Origin, under: &[bool]) -> f32 {
    origin
        .placed_by
        .iter()
        .filter(|(node, w)| *w > 0.0 && under.get(*node as usize) == Some(&true))
        .map(|(_, w)| w)
        .sum()
}

/// For each node, whether it is `node` or below it.
fn below(parents: &[Option<usize>], node: usize) -> Vec<bool> {
    (0..parents.len())
        .map(|start| {
            let mut at = Some(start);
            // A file whose parents loop is cut after as many steps as it has nodes.
            for _ in 0..=parents.len() {
                match at {
                    Some(n) if n == node => return true,
                    Some(n) => at = parents.get(n).copied().flatten(),
                    None => break,
                }
            }
            false
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mouth_opens_once_by_the_shape_or_by_the_bone() {
        let turns = |shape: f32, on_bone: bool, want: f32| {
            let got = jaw_turn(shape, on_bone);
            assert!(
                (got - want).abs() < 1e-6,
                "{shape}° on bone {on_bone}: {got}°"
            );
        };
        // A chin the shape opens: the bone (the teeth on it) goes as far.
        turns(12.0, false, 12.0);
        turns(0.2, false, 1.0);
        // A chin on the bone: a corrective beside it, or an opening of its own.
        turns(2.0, true, DEFAULT_JAW_DEGREES);
        turns(-3.0, true, DEFAULT_JAW_DEGREES);
        turns(12.0, true, 0.0);
    }

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
            arkit: None,
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
