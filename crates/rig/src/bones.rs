//! The bones a face animation moves besides morph targets: head, neck and upper spine (a
//! captured head pose), the eyes (gaze) and the jaw, found in a glTF or VRM file; and VRM's
//! lookAt, which says how far gaze turns the eyes.
//!
//! A VRM names its bones (`humanoid.humanBones`, 0.x and 1.0); other files are read by their
//! joints' names along the skeleton: the head is the joint named like one (`Head`,
//! `mixamorig:Head`, `J_Bip_C_Head`, `CC_Base_Head`, or Blender Rigify's `spine.006`), the neck
//! the nearest of its ancestors named with "neck" (`CC_Base_NeckTwist02`, or Rigify's
//! `spine.004`), the upper spine the nearest above the neck named with "chest" or "spine"
//! (`Spine2`, `J_Bip_C_UpperChest`, `CC_Base_Spine02`, `spine.003`); the eyes and the jaw are
//! nodes below the head named with "eye" and a side (`LeftEye`, `CC_Base_L_Eye`,
//! `J_Adj_L_FaceEye`, `eye.L`) and with "jaw" and no side (`CC_Base_JawRoot`, `FACIAL_C_Jaw`,
//! Rigify's `jaw`, not its jawline's `jaw.L`).

use glam::Quat;
use serde_json::Value;

/// A bone a face animation turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Bone {
    /// The head: a captured head pose turns it.
    Head,
    /// The neck: half the turn where it exists.
    Neck,
    /// The upper spine (upper chest, else chest): a share of the yaw.
    UpperSpine,
    /// The left eye (the character's left).
    LeftEye,
    /// The right eye.
    RightEye,
    /// The jaw: `jawOpen` opens it.
    Jaw,
}

impl Bone {
    /// Every bone, head first.
    pub const ALL: [Bone; 6] = [
        Bone::Head,
        Bone::Neck,
        Bone::UpperSpine,
        Bone::LeftEye,
        Bone::RightEye,
        Bone::Jaw,
    ];

    /// Its name in reports (`upper_spine`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Bone::Head => "head",
            Bone::Neck => "neck",
            Bone::UpperSpine => "upper_spine",
            Bone::LeftEye => "left_eye",
            Bone::RightEye => "right_eye",
            Bone::Jaw => "jaw",
        }
    }

    /// The bone the ARKit channel called `arkit` turns, where one does: each eye its four
    /// eyeLook channels ([`gaze_from_arkit`]), the jaw `jawOpen`.
    ///
    /// ```
    /// use faceanim_rig::bones::Bone;
    /// assert_eq!(Bone::turned_by("eyeLookInLeft"), Some(Bone::LeftEye));
    /// assert_eq!(Bone::turned_by("eyeLookUpRight"), Some(Bone::RightEye));
    /// assert_eq!(Bone::turned_by("jawOpen"), Some(Bone::Jaw));
    /// assert_eq!(Bone::turned_by("eyeBlinkLeft"), None);
    /// ```
    #[must_use]
    pub fn turned_by(arkit: &str) -> Option<Bone> {
        if arkit == "jawOpen" {
            return Some(Bone::Jaw);
        }
        if !crate::names::is_gaze(arkit) {
            return None;
        }
        if arkit.ends_with("Left") {
            Some(Bone::LeftEye)
        } else if arkit.ends_with("Right") {
            Some(Bone::RightEye)
        } else {
            None
        }
    }
}

/// The face's bones in a file, by node index.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaceBones([Option<usize>; 6]);

impl FaceBones {
    /// The node of `bone`, when the file has it.
    #[must_use]
    pub fn get(&self, bone: Bone) -> Option<usize> {
        self.0[bone as usize]
    }

    /// The bones found, with their nodes, in [`Bone::ALL`]'s order.
    pub fn found(&self) -> impl Iterator<Item = (Bone, usize)> + '_ {
        Bone::ALL
            .into_iter()
            .filter_map(|b| Some((b, self.get(b)?)))
    }
}

/// The gaze, in degrees, of an ARKit eyeLook value of 1 (sideways, and up or down): the phones'
/// own. Live Link Face sends each eye's angles beside its eyeLook values, and in a real
/// recording they are those values times 35°, sideways and up or down alike (r 0.9997;
/// `crates/live/tests/phones.rs` holds the two together).
pub const EYE_RANGE: [f32; 2] = [35.0, 35.0];

/// Each eye's gaze `[yaw, pitch]` in degrees (left eye, right eye; yaw towards the
/// character's left, pitch up) from ARKit's eyeLook values, `value(channel)` (0 for a channel
/// not there): the left eye looks to the character's left by looking out, the right eye in.
#[must_use]
pub fn gaze_from_arkit(value: impl Fn(&str) -> f32) -> [[f32; 2]; 2] {
    let eye = |side: &str, left: bool| {
        let v = |way: &str| value(&format!("eyeLook{way}{side}"));
        let towards_left = if left {
            v("Out") - v("In")
        } else {
            v("In") - v("Out")
        };
        [
            towards_left * EYE_RANGE[0],
            (v("Up") - v("Down")) * EYE_RANGE[1],
        ]
    };
    [eye("Left", true), eye("Right", false)]
}

/// The inverse of [`gaze_from_arkit`]: the eyeLook values (each 0..1, by ARKit name) of each
/// eye's gaze `[yaw, pitch]` in degrees; of each pair of opposite ways one is 0.
#[must_use]
pub fn arkit_from_gaze(gaze: [[f32; 2]; 2]) -> [(&'static str, f32); 8] {
    let share = |degrees: f32, range: f32| (degrees / range).clamp(0.0, 1.0);
    let [[left_yaw, left_pitch], [right_yaw, right_pitch]] = gaze;
    [
        ("eyeLookOutLeft", share(left_yaw, EYE_RANGE[0])),
        ("eyeLookInLeft", share(-left_yaw, EYE_RANGE[0])),
        ("eyeLookUpLeft", share(left_pitch, EYE_RANGE[1])),
        ("eyeLookDownLeft", share(-left_pitch, EYE_RANGE[1])),
        ("eyeLookInRight", share(right_yaw, EYE_RANGE[0])),
        ("eyeLookOutRight", share(-right_yaw, EYE_RANGE[0])),
        ("eyeLookUpRight", share(right_pitch, EYE_RANGE[1])),
        ("eyeLookDownRight", share(-right_pitch, EYE_RANGE[1])),
    ]
}

/// The share of the head's yaw the upper spine follows.
pub const SPINE_SHARE: f32 = 0.2;
/// How slowly the spine follows (seconds, the time constant of its smoothing).
pub const SPINE_LAG: f32 = 0.2;
/// The share of the head's turn the neck takes where the rig has one (half, as VMagicMirror
/// shares it).
pub const NECK_SHARE: f32 = 0.5;

/// A captured head pose shared between upper spine, neck and head, frame after frame: the
/// spine follows [`SPINE_SHARE`] of the yaw, smoothed over [`SPINE_LAG`]; the neck takes
/// [`NECK_SHARE`] of the rest; the head what remains. The one rule the export, the studio's
/// view and VMC turn bones by.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HeadSplit {
    /// The spine's yaw so far (radians), once a frame was shared.
    spine_yaw: Option<f32>,
}

impl HeadSplit {
    /// Shares the head's turn `q` (character space) `dt` seconds after the last frame, on a rig
    /// with (`spine`) an upper spine and (`neck`) a neck bone: each bone's turn in character
    /// space beyond what its ancestors turn, `[spine, neck, head]` (identity for a bone the rig
    /// lacks); their product is `q`.
    pub fn share(&mut self, q: Quat, dt: f32, spine: bool, neck: bool) -> [Quat; 3] {
        let q = q.normalize();
        let (yaw, _, _) = q.to_euler(glam::EulerRot::YXZ);
        let target = SPINE_SHARE * yaw;
        let follow = 1.0 - (-dt.max(0.0) / SPINE_LAG).exp();
        let now = self.spine_yaw.map_or(target, |s| s + (target - s) * follow);
        self.spine_yaw = Some(now);
        let spine_turn = if spine {
            Quat::from_rotation_y(now)
        } else {
            Quat::IDENTITY
        };
        let above = spine_turn.inverse() * q;
        let neck_turn = if neck {
            Quat::IDENTITY.slerp(above, NECK_SHARE).normalize()
        } else {
            Quat::IDENTITY
        };
        let head_turn = (neck_turn.inverse() * above).normalize();
        [spine_turn, neck_turn, head_turn]
    }
}

/// A bone as the face's rules turn it. A turn `q` in character space, beyond what its turned
/// ancestors already turn, is the local rotation `P⁻¹·q·P·R`, where `P` is its parent's
/// rotation in character space at rest and `R` its own local rotation at rest; [`Joint::turn`]
/// reads a local rotation back as that turn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// Its node.
    pub node: usize,
    /// Its parent's rotation in character space, at rest.
    pub parent: Quat,
    /// Its own local rotation at rest.
    pub rest: Quat,
}

impl Joint {
    /// Its local rotation for a turn `q` in character space.
    #[must_use]
    pub fn local(self, q: Quat) -> Quat {
        (self.parent.inverse() * q * self.parent * self.rest).normalize()
    }

    /// The turn in character space that its local rotation `local` makes (the inverse of
    /// [`Joint::local`]).
    #[must_use]
    pub fn turn(self, local: Quat) -> Quat {
        (self.parent * local * self.rest.inverse() * self.parent.inverse()).normalize()
    }
}

/// How far a gaze in degrees turns the eyes: VRM's `lookAt` range maps (bone type), each an
/// input's largest value and the output it gives, in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LookAt {
    /// Towards the nose.
    pub horizontal_inner: RangeMap,
    /// Away from the nose.
    pub horizontal_outer: RangeMap,
    /// Down.
    pub vertical_down: RangeMap,
    /// Up.
    pub vertical_up: RangeMap,
}

/// One of VRM's lookAt range maps: an input up to `input_max` degrees gives up to `output`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeMap {
    /// The input at which the output is full (degrees).
    pub input_max: f32,
    /// The full output (degrees of the eye bone).
    pub output: f32,
}

impl RangeMap {
    /// `degrees` (signed) mapped, its sign kept.
    #[must_use]
    pub fn map(self, degrees: f32) -> f32 {
        if self.input_max <= 0.0 {
            return 0.0;
        }
        degrees.signum() * (degrees.abs().min(self.input_max) / self.input_max) * self.output
    }

    /// The input that [`RangeMap::map`]s to `degrees` of the bone (signed; at most
    /// `input_max`).
    #[must_use]
    pub fn unmap(self, degrees: f32) -> f32 {
        if self.input_max <= 0.0 || self.output.abs() < 1e-6 {
            return 0.0;
        }
        degrees.signum() * (degrees.abs() / self.output.abs()).min(1.0) * self.input_max
    }
}

impl LookAt {
    /// The range maps that serve a turn `[yaw, pitch]` of the eye `left` says (whose outer
    /// side is the character's left): outer or inner, up or down by its signs.
    fn maps(&self, [yaw, pitch]: [f32; 2], left: bool) -> [RangeMap; 2] {
        let outward = if left { yaw >= 0.0 } else { yaw < 0.0 };
        [
            if outward {
                self.horizontal_outer
            } else {
                self.horizontal_inner
            },
            if pitch >= 0.0 {
                self.vertical_up
            } else {
                self.vertical_down
            },
        ]
    }

    /// An eye's turn for a gaze `[yaw, pitch]` (degrees; yaw towards the character's left,
    /// pitch up): `left` says which eye, whose outer side is the character's left.
    #[must_use]
    pub fn eye(&self, gaze: [f32; 2], left: bool) -> [f32; 2] {
        let [horizontal, vertical] = self.maps(gaze, left);
        [horizontal.map(gaze[0]), vertical.map(gaze[1])]
    }

    /// The gaze `[yaw, pitch]` that turns an eye by `turn` degrees (the inverse of
    /// [`LookAt::eye`] within its range maps' inputs).
    #[must_use]
    pub fn gaze(&self, turn: [f32; 2], left: bool) -> [f32; 2] {
        let [horizontal, vertical] = self.maps(turn, left);
        [horizontal.unmap(turn[0]), vertical.unmap(turn[1])]
    }
}

/// What a file says about gaze: whether a VRM turns its eyes by bone, and how far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Gaze {
    /// Not a VRM: eye bones, where found, turn by the gaze itself.
    Direct,
    /// A VRM whose lookAt turns eye bones, through its range maps.
    Bones(LookAt),
    /// A VRM whose lookAt moves expressions (lookLeft…): its eye bones are left alone.
    Expressions,
}

/// The face's bones of the glTF document `doc`.
#[must_use]
pub fn find(doc: &Value) -> FaceBones {
    let nodes = doc
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(&[][..], Vec::as_slice);
    let valid = |n: Option<usize>| n.filter(|&n| n < nodes.len());
    let vrm = |bone: &str| valid(vrm_bone(doc, bone));
    let parent = parents(nodes);
    let name = |n: usize| {
        nodes[n]
            .get("name")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_ascii_lowercase()
    };
    let head = vrm("head").or_else(|| head_joint(doc, nodes, &name));
    let ancestors = |from: Option<usize>| {
        let mut chain = Vec::new();
        let mut at = from.and_then(|n| parent[n]);
        while let Some(n) = at {
            if chain.contains(&n) {
                break;
            }
            chain.push(n);
            at = parent[n];
        }
        chain
    };
    let neck = vrm("neck").or_else(|| {
        ancestors(head)
            .into_iter()
            .take(3)
            .find(|&n| name(n).contains("neck") || name(n).ends_with(RIGIFY_NECK))
    });
    let upper_spine = vrm("upperChest").or_else(|| vrm("chest")).or_else(|| {
        ancestors(neck)
            .into_iter()
            .take(3)
            .find(|&n| ["chest", "spine"].iter().any(|w| name(n).contains(w)))
    });
    // Below the head, nearest first.
    let below = |what: &dyn Fn(&str) -> bool| {
        let mut queue: std::collections::VecDeque<usize> = head.into_iter().collect();
        let mut seen = 0;
        while let Some(n) = queue.pop_front() {
            seen += 1;
            if seen > nodes.len() {
                break;
            }
            if Some(n) != head && what(&name(n)) {
                return Some(n);
            }
            queue.extend(
                nodes[n]
                    .get("children")
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                    .filter_map(index)
                    .filter(|&c| c < nodes.len()),
            );
        }
        None
    };
    let eye = |side: Side| {
        below(&|n: &str| {
            n.contains("eye")
                && side_of(n) == Some(side)
                && !["lid", "lash", "brow", "end", "target", "socket"]
                    .iter()
                    .any(|w| n.contains(w))
        })
    };
    FaceBones([
        head,
        neck,
        upper_spine,
        vrm("leftEye").or_else(|| eye(Side::Left)),
        vrm("rightEye").or_else(|| eye(Side::Right)),
        // The jaw, not a side of the jawline (Rigify's `jaw.L` beside its `jaw`).
        vrm("jaw").or_else(|| {
            below(&|n: &str| n.contains("jaw") && !n.contains("end") && side_of(n).is_none())
        }),
    ])
}

/// VRM 1.0's and 0.x's lookAt: where it is, the field and value that say it moves expressions,
/// its four maps (inner, outer, down, up) and their input and output fields (0.x's curves, from
/// xRange degrees to yRange, are read as straight lines).
type LookAtSpec = (
    &'static str,
    &'static str,
    &'static str,
    [&'static str; 4],
    [&'static str; 2],
);
const LOOK_AT: [LookAtSpec; 2] = [
    (
        "/extensions/VRMC_vrm/lookAt",
        "type",
        "expression",
        [
            "rangeMapHorizontalInner",
            "rangeMapHorizontalOuter",
            "rangeMapVerticalDown",
            "rangeMapVerticalUp",
        ],
        ["inputMaxValue", "outputScale"],
    ),
    (
        "/extensions/VRM/firstPerson",
        "lookAtTypeName",
        "BlendShape",
        [
            "lookAtHorizontalInner",
            "lookAtHorizontalOuter",
            "lookAtVerticalDown",
            "lookAtVerticalUp",
        ],
        ["xRange", "yRange"],
    ),
];

/// What `doc`'s VRM says about gaze.
#[must_use]
pub fn gaze(doc: &Value) -> Gaze {
    let Some((look, &(_, type_field, expressions, keys, fields))) = LOOK_AT
        .iter()
        .find_map(|spec| Some((doc.pointer(spec.0)?, spec)))
    else {
        return Gaze::Direct;
    };
    let bone_type = look.get(type_field).and_then(Value::as_str) != Some(expressions);
    if !bone_type {
        return Gaze::Expressions;
    }
    let [inner, outer, down, up] = keys.map(|key| {
        let number = |field: &str, default: f32| {
            look.get(key)
                .and_then(|m| m.get(field))
                .and_then(Value::as_f64)
                .map_or(default, |v| v as f32)
        };
        RangeMap {
            input_max: number(fields[0], 90.0),
            output: number(fields[1], 10.0),
        }
    });
    Gaze::Bones(LookAt {
        horizontal_inner: inner,
        horizontal_outer: outer,
        vertical_down: down,
        vertical_up: up,
    })
}

/// Each node's parent, from the nodes' `children`.
#[must_use]
pub fn parents(nodes: &[Value]) -> Vec<Option<usize>> {
    let mut parent = vec![None; nodes.len()];
    for (p, node) in nodes.iter().enumerate() {
        for c in node
            .get("children")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(index)
        {
            if let Some(slot) = parent.get_mut(c) {
                *slot = Some(p);
            }
        }
    }
    parent
}

fn index(v: &Value) -> Option<usize> {
    v.as_u64().and_then(|n| usize::try_from(n).ok())
}

/// A VRM humanoid bone's node (1.0, then 0.x).
fn vrm_bone(doc: &Value, bone: &str) -> Option<usize> {
    vrm_humanoid(doc)
        .into_iter()
        .find(|(name, _)| name == bone)
        .map(|(_, node)| node)
}

/// A VRM's humanoid bones (`hips`, `head`, `leftEye`, …) and their nodes: VRM 1.0's
/// `humanoid.humanBones` map, else VRM 0.x's list; empty for a file that is no VRM.
#[must_use]
pub fn vrm_humanoid(doc: &Value) -> Vec<(String, usize)> {
    if let Some(bones) = doc
        .pointer("/extensions/VRMC_vrm/humanoid/humanBones")
        .and_then(Value::as_object)
    {
        return bones
            .iter()
            .filter_map(|(name, bone)| Some((name.clone(), index(bone.get("node")?)?)))
            .collect();
    }
    doc.pointer("/extensions/VRM/humanoid/humanBones")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(|bone| {
            let name = bone.get("bone").and_then(Value::as_str)?;
            Some((name.to_owned(), index(bone.get("node")?)?))
        })
        .collect()
}

/// A skin joint whose name ends in "head", lowest index first.
fn head_joint(doc: &Value, nodes: &[Value], name: &dyn Fn(usize) -> String) -> Option<usize> {
    let mut joints: Vec<usize> = doc
        .get("skins")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .flat_map(|s| {
            s.get("joints")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
        })
        .filter_map(index)
        .filter(|&j| j < nodes.len())
        .collect();
    joints.sort_unstable();
    joints.dedup();
    joints
        .iter()
        .copied()
        .find(|&j| name(j).ends_with("head"))
        // Blender's Rigify names its spine by number: the head is its seventh bone
        // (`spine.006`, `DEF-spine.006` in a generated rig).
        .or_else(|| {
            joints
                .iter()
                .copied()
                .find(|&j| name(j).ends_with(RIGIFY_HEAD))
        })
}

/// Blender's Rigify human: the head, and the neck's base, by their place in its spine.
const RIGIFY_HEAD: &str = "spine.006";
const RIGIFY_NECK: &str = "spine.004";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Left,
    Right,
}

/// The side a lower-case bone name says: `left…`/`…right`, or a lone `l`/`r` between
/// separators (`cc_base_l_eye`, `eye.r`, `j_adj_l_faceeye`).
fn side_of(name: &str) -> Option<Side> {
    if name.contains("left") {
        return Some(Side::Left);
    }
    if name.contains("right") {
        return Some(Side::Right);
    }
    let tokens: Vec<&str> = name
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|t| !t.is_empty())
        .collect();
    if tokens.contains(&"l") {
        Some(Side::Left)
    } else if tokens.contains(&"r") {
        Some(Side::Right)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A skeleton as Ready Player Me, Character Creator and VRoid name it.
    fn skeleton(names: &[&str]) -> Value {
        // A chain: each node the child of the one before, the last three children of the head.
        let mut nodes: Vec<Value> = names.iter().map(|n| json!({ "name": n })).collect();
        let head = names.len() - 4;
        for (i, node) in nodes.iter_mut().enumerate().take(head) {
            node["children"] = json!([i + 1]);
        }
        nodes[head]["children"] = json!([head + 1, head + 2, head + 3]);
        json!({ "nodes": nodes, "skins": [{ "joints": (0..names.len()).collect::<Vec<_>>() }] })
    }

    #[test]
    fn bones_are_found_by_name_along_the_skeleton() {
        let rpm = skeleton(&[
            "Hips",
            "Spine",
            "Spine1",
            "Spine2",
            "Neck",
            "Head",
            "LeftEye",
            "RightEye",
            "HeadTop_End",
        ]);
        assert_eq!(
            find(&rpm),
            FaceBones([Some(5), Some(4), Some(3), Some(6), Some(7), None])
        );
        let cc = skeleton(&[
            "CC_Base_Spine01",
            "CC_Base_Spine02",
            "CC_Base_NeckTwist01",
            "CC_Base_NeckTwist02",
            "CC_Base_Head",
            "CC_Base_R_Eye",
            "CC_Base_L_Eye",
            "CC_Base_JawRoot",
        ]);
        assert_eq!(
            find(&cc),
            FaceBones([Some(4), Some(3), Some(1), Some(6), Some(5), Some(7)])
        );
        // Blender's Rigify human (its metarig, or `DEF-` bones of a generated rig): the spine
        // by number, the jaw beside the jawline's sides.
        let rigify = skeleton(&[
            "spine",
            "spine.001",
            "spine.002",
            "spine.003",
            "DEF-spine.004",
            "DEF-spine.005",
            "DEF-spine.006",
            "eye.L",
            "jaw.L",
            "jaw",
        ]);
        assert_eq!(
            find(&rigify),
            FaceBones([Some(6), Some(4), Some(3), Some(7), None, Some(9)])
        );
        // No skeleton: nothing.
        assert_eq!(
            find(&json!({ "nodes": [{ "name": "Face" }] })),
            FaceBones::default()
        );
    }

    #[test]
    fn gaze_reads_back_as_the_eye_look_values_it_came_from() {
        let written = [
            ("eyeLookOutLeft", 0.4),
            ("eyeLookUpLeft", 0.7),
            ("eyeLookInRight", 0.4),
            ("eyeLookDownRight", 0.2),
        ];
        let value = |c: &str| written.iter().find(|(n, _)| *n == c).map_or(0.0, |w| w.1);
        for (channel, read) in arkit_from_gaze(gaze_from_arkit(value)) {
            assert!((read - value(channel)).abs() < 1e-6, "{channel}: {read}");
        }
    }

    #[test]
    fn a_joints_turn_reads_back_from_its_local_rotation() {
        let joint = Joint {
            node: 0,
            parent: Quat::from_rotation_x(1.2) * Quat::from_rotation_z(0.3),
            rest: Quat::from_rotation_y(-0.7),
        };
        let q = Quat::from_rotation_y(0.5) * Quat::from_rotation_x(-0.2);
        assert!(joint.turn(joint.local(q)).angle_between(q) < 1e-5);
    }

    #[test]
    fn vrm_bones_and_look_at_by_the_specification() {
        let doc = json!({
            "nodes": [{}, {}, {}, {}, {}],
            "extensions": { "VRMC_vrm": {
                "humanoid": { "humanBones": {
                    "head": { "node": 1 }, "neck": { "node": 0 },
                    "leftEye": { "node": 2 }, "rightEye": { "node": 3 }, "jaw": { "node": 9 }
                } },
                "lookAt": {
                    "type": "bone",
                    "rangeMapHorizontalInner": { "inputMaxValue": 90, "outputScale": 8 },
                    "rangeMapHorizontalOuter": { "inputMaxValue": 90, "outputScale": 12 },
                    "rangeMapVerticalDown": { "inputMaxValue": 90, "outputScale": 6 },
                    "rangeMapVerticalUp": { "inputMaxValue": 90, "outputScale": 4 }
                }
            } }
        });
        // A node index past the end is no bone.
        assert_eq!(
            find(&doc),
            FaceBones([Some(1), Some(0), None, Some(2), Some(3), None])
        );
        let Gaze::Bones(look) = gaze(&doc) else {
            panic!("bone lookAt");
        };
        // Up and down each by their own map (not swapped).
        assert!((look.eye([0.0, 45.0], true)[1] - 2.0).abs() < 1e-6);
        assert!((look.eye([0.0, -45.0], true)[1] + 3.0).abs() < 1e-6);
        // Towards the character's left: outer for the left eye, inner for the right.
        assert!((look.eye([45.0, 0.0], true)[0] - 6.0).abs() < 1e-6);
        assert!((look.eye([45.0, 0.0], false)[0] - 4.0).abs() < 1e-6);
        // Past the input's range, the full output.
        assert!((look.eye([0.0, 200.0], true)[1] - 4.0).abs() < 1e-6);
        // Read back, each way by its own map.
        for gaze in [[30.0, 20.0], [-30.0, -20.0], [10.0, -45.0]] {
            for left in [true, false] {
                let back = look.gaze(look.eye(gaze, left), left);
                assert!((back[0] - gaze[0]).abs() < 1e-4 && (back[1] - gaze[1]).abs() < 1e-4);
            }
        }
        let expression =
            json!({ "extensions": { "VRMC_vrm": { "lookAt": { "type": "expression" } } } });
        assert_eq!(gaze(&expression), Gaze::Expressions);
        // VRM 0.x: its curves' ranges, up by lookAtVerticalUp.
        let zero = json!({ "extensions": { "VRM": { "firstPerson": {
            "lookAtTypeName": "Bone",
            "lookAtVerticalUp": { "xRange": 90, "yRange": 10 },
            "lookAtVerticalDown": { "xRange": 90, "yRange": 12 }
        } } } });
        let Gaze::Bones(look) = gaze(&zero) else {
            panic!("0.x bone lookAt");
        };
        assert!((look.eye([0.0, 45.0], false)[1] - 5.0).abs() < 1e-6);
        assert!((look.eye([0.0, -45.0], false)[1] + 6.0).abs() < 1e-6);
        let blend = json!({ "extensions": { "VRM": { "firstPerson": { "lookAtTypeName": "BlendShape" } } } });
        assert_eq!(gaze(&blend), Gaze::Expressions);
        assert_eq!(gaze(&json!({})), Gaze::Direct);
    }
}
