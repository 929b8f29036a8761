//! The take a file's animation opens as ([`GltfSource::take`]), with what it turns read back as
//! the take's head pose and gaze: the inverse of the rules faceanim's export turns bones by
//! (`faceanim_export::bones`). A head pose is the turns of the upper spine, the neck and the
//! head (or of the scene's root, for a character without a head bone) in character space, one
//! after the other; each eye's gaze is its bone's turn, read through a VRM's lookAt range maps
//! where it has them; the jaw's opening is the angle of its bone's turn. Files keyed in other
//! tools read the same way: whatever turns those bones is the head pose, the gaze and the jaw.

use glam::{EulerRot, Quat};

use crate::bones::{Bone, Gaze, Joint};
use crate::file_animation::{FileAnimation, RotationTrack};
use crate::source::GltfSource;

/// A file's animation played as a take (see [`GltfSource::take`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Take {
    /// Its weights per frame, and the head's turn in character space where it turns the head.
    pub animation: crate::animation::MorphAnimation,
    /// Its rate, frames a second.
    pub fps: f32,
    /// Each eye's gaze `[yaw, pitch]` in degrees per frame (left eye, right eye), where it
    /// turns the eye bones.
    pub gaze: Option<Vec<[[f32; 2]; 2]>>,
    /// How far the jaw bone is open per frame, in degrees (its turn beyond the head's), where
    /// it turns the jaw bone.
    pub jaw: Option<Vec<f32>>,
}

impl GltfSource {
    /// The animation that opens as a take: the last one faceanim wrote (exports add theirs
    /// after the file's own), else the file's first; played on the character's blendshapes
    /// (see [`crate::file_animation::FileAnimation::sample`]) with the head's turn it makes
    /// (`rotations`) and the eyes' gaze (see [`crate::turns`]), at its rate.
    #[must_use]
    pub fn take(&self) -> Option<Take> {
        let animation = self.opened_animation()?;
        let mut played = animation.sample(&self.shapes);
        let start = animation.start();
        played.rotations = head(self, animation, start, &played.times);
        Some(Take {
            gaze: gaze(self, animation, start, &played.times),
            jaw: jaw(self, animation, start, &played.times),
            animation: played,
            fps: animation.fps(),
        })
    }
}

impl GltfSource {
    /// The animation that opens (as a take, or as strokes): the last one faceanim wrote, else
    /// the file's first.
    #[must_use]
    pub fn opened_animation(&self) -> Option<&FileAnimation> {
        self.animations
            .iter()
            .rev()
            .find(|a| a.ours)
            .or_else(|| self.animations.first())
    }

    /// The strokes the animation that opens was sketched from, where faceanim kept them in the
    /// file (a sketch project's JSON): it opens as those strokes, to edit, rather than as a take.
    #[must_use]
    pub fn strokes(&self) -> Option<&serde_json::Value> {
        self.opened_animation()?.strokes.as_ref()
    }
}

/// The node a captured head pose turns in `source`: its head bone, else the scene's first
/// root node (the whole character).
#[must_use]
pub fn turned_head(source: &GltfSource) -> Option<usize> {
    source.bones().get(Bone::Head).or_else(|| {
        let doc = source.document();
        let scene = doc
            .get("scene")
            .and_then(serde_json::Value::as_u64)
            .unwrap_or(0);
        doc.pointer(&format!("/scenes/{scene}/nodes/0"))
            .and_then(serde_json::Value::as_u64)
            .and_then(|n| usize::try_from(n).ok())
    })
}

/// A bone with the track that turns it in an animation.
struct Turned<'a> {
    joint: Joint,
    track: &'a RotationTrack,
}

impl Turned<'_> {
    fn find<'a>(
        source: &GltfSource,
        animation: &'a FileAnimation,
        node: Option<usize>,
    ) -> Option<Turned<'a>> {
        let node = node?;
        let track = animation.turns.iter().find(|t| t.node() as usize == node)?;
        Some(Turned {
            joint: source.joint(node)?,
            track,
        })
    }

    fn at(&self, t: f32) -> Quat {
        self.joint.turn(self.track.at(t))
    }
}

/// The head's turn in character space (`[x, y, z, w]`) at each of `times` (seconds from the
/// animation's `start`), where `animation` turns the head, the neck or the upper spine.
#[must_use]
pub fn head(
    source: &GltfSource,
    animation: &FileAnimation,
    start: f32,
    times: &[f32],
) -> Option<Vec<[f32; 4]>> {
    let bones = source.bones();
    let head_bone = bones.get(Bone::Head);
    let chain: Vec<Turned<'_>> = [
        head_bone.and(bones.get(Bone::UpperSpine)),
        head_bone.and(bones.get(Bone::Neck)),
        turned_head(source),
    ]
    .into_iter()
    .filter_map(|node| Turned::find(source, animation, node))
    .collect();
    if chain.is_empty() {
        return None;
    }
    Some(
        times
            .iter()
            .map(|&t| {
                chain
                    .iter()
                    .fold(Quat::IDENTITY, |q, bone| q * bone.at(start + t))
                    .normalize()
                    .to_array()
            })
            .collect(),
    )
}

/// Each eye's gaze `[yaw, pitch]` in degrees (left eye, right eye; yaw towards the character's
/// left, pitch up) at each of `times`, where `animation` turns both eye bones of a file whose
/// eyes turn by bone.
#[must_use]
pub fn gaze(
    source: &GltfSource,
    animation: &FileAnimation,
    start: f32,
    times: &[f32],
) -> Option<Vec<[[f32; 2]; 2]>> {
    let look = source.gaze();
    if look == Gaze::Expressions {
        return None;
    }
    let bones = source.bones();
    let left = Turned::find(source, animation, bones.get(Bone::LeftEye))?;
    let right = Turned::find(source, animation, bones.get(Bone::RightEye))?;
    let eye = |bone: &Turned<'_>, t: f32, is_left: bool| {
        // The export turns an eye by Ry(yaw)·Rx(−pitch).
        let (yaw, x, _) = bone.at(t).to_euler(EulerRot::YXZ);
        let turn = [yaw.to_degrees(), -x.to_degrees()];
        match look {
            Gaze::Bones(look) => look.gaze(turn, is_left),
            _ => turn,
        }
    };
    Some(
        times
            .iter()
            .map(|&t| [eye(&left, start + t, true), eye(&right, start + t, false)])
            .collect(),
    )
}

/// How far the jaw bone is open, in degrees (the angle of its turn beyond the head's), at each
/// of `times`, where `animation` turns it.
#[must_use]
pub fn jaw(
    source: &GltfSource,
    animation: &FileAnimation,
    start: f32,
    times: &[f32],
) -> Option<Vec<f32>> {
    let jaw = Turned::find(source, animation, source.bones().get(Bone::Jaw))?;
    Some(
        times
            .iter()
            .map(|&t| jaw.at(start + t).angle_between(Quat::IDENTITY).to_degrees())
            .collect(),
    )
}
