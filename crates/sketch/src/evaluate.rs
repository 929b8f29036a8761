//! The face at any frame: each chain contributes its active action's interpolation (weights,
//! exaggeration offsets and arc swing), and chains add up.

use std::collections::HashMap;

use faceanim_rig::{Character, Pose};
use glam::Vec3;

use crate::action::{Action, ActionId};

/// Weights and extra per-vertex offsets at one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePose {
    /// One weight per blendshape of the character.
    pub weights: Vec<f32>,
    /// Offsets beyond the blendshapes (exaggerations and arcs), one per vertex.
    pub offsets: Vec<Vec3>,
}

impl FramePose {
    /// A neutral frame for `character`.
    #[must_use]
    pub fn new(character: &Character) -> FramePose {
        FramePose {
            weights: vec![0.0; character.blendshapes().len()],
            offsets: vec![Vec3::ZERO; character.vertex_count()],
        }
    }

    /// The vertex positions: the blendshape pose plus the offsets.
    #[must_use]
    pub fn positions(&self, character: &Character) -> Vec<Vec3> {
        let mut pose = Pose::default();
        self.positions_into(character, &mut pose);
        pose.positions
    }

    /// Like [`FramePose::positions`] (and normals of the blendshape pose) into reused buffers.
    pub fn positions_into(&self, character: &Character, pose: &mut Pose) {
        character.pose_into(&self.weights, pose);
        for (p, o) in pose.positions.iter_mut().zip(&self.offsets) {
            *p += *o;
        }
    }
}

/// The action of each chain that is in effect at `frame`: the latest-starting one that has
/// started (later actions of the same chain win ties).
pub(crate) fn active<'a>(
    actions: impl Iterator<Item = (ActionId, &'a Action)>,
    frame: f32,
) -> Vec<(ActionId, &'a Action)> {
    let mut by_chain: HashMap<ActionId, (ActionId, &Action)> = HashMap::new();
    for (id, action) in actions {
        if action.start_frame > frame && action.previous.is_some() {
            continue;
        }
        let replace = match by_chain.get(&action.chain) {
            None => true,
            Some((_, current)) => {
                action.start_frame <= frame && action.start_frame >= current.start_frame
            }
        };
        if replace {
            by_chain.insert(action.chain, (id, action));
        }
    }
    let mut out: Vec<(ActionId, &Action)> = by_chain.into_values().collect();
    out.sort_by_key(|(id, _)| *id);
    out
}

/// Evaluates `actions` at `frame` into `out` (which is reset first).
pub fn evaluate<'a>(
    character: &Character,
    actions: impl Iterator<Item = (ActionId, &'a Action)>,
    frame: f32,
    out: &mut FramePose,
) {
    out.weights.iter_mut().for_each(|w| *w = 0.0);
    out.offsets.iter_mut().for_each(|o| *o = Vec3::ZERO);
    out.weights.resize(character.blendshapes().len(), 0.0);
    out.offsets.resize(character.vertex_count(), Vec3::ZERO);
    for (_, action) in active(actions, frame) {
        let s = action.progress(frame);
        action.from.add_weights_to(1.0 - s, &mut out.weights);
        action.to.add_weights_to(s, &mut out.weights);
        action.from.offsets.add_scaled_to(1.0 - s, &mut out.offsets);
        action.to.offsets.add_scaled_to(s, &mut out.offsets);
        if s > 0.0 && s < 1.0 {
            let arcs: Vec<_> = (0..action.sides.len() as u8)
                .map(|k| action.arc(k))
                .collect();
            for &(v, kappa, side) in &action.swing {
                if let (Some(Some(arc)), Some(slot)) =
                    (arcs.get(side as usize), out.offsets.get_mut(v as usize))
                {
                    *slot += arc.deviation(kappa, s);
                }
            }
        }
    }
}
