//! What a stroke became: an action — one chain's timed transition between two layers — with
//! its sides (the stroke's own and its mirror image).

use faceanim_rig::{BlendshapeId, Character};
use glam::Vec3;

use crate::arc::{Arc, Path};
use crate::layer::Layer;
use crate::timing::Timing;

/// Index of an action in its [`Sketch`](crate::Sketch), in creation order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ActionId(pub usize);

/// Where a stroke sends the reference vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A blendshape at a weight (single-blendshape strokes).
    Blendshape(BlendshapeId),
    /// Back to where this chain started (no blendshape of the chain active).
    Neutral,
    /// Every weight solved at once (multi-blendshape strokes).
    Multi,
}

/// One side of an action: the stroke's own, or its mirror image.
#[derive(Debug, Clone, PartialEq)]
pub struct Side {
    /// The reference vertex.
    pub reference: u32,
    /// What it goes to.
    pub target: Target,
    /// The weight of the target blendshape (1 for neutral/multi).
    pub weight: f32,
    /// Where the reference vertex would go at weight 1 (the selected sphere).
    pub target_position: Vec3,
    /// Offset beyond the blendshape at the reference vertex (the exaggeration).
    pub exaggeration: Vec3,
    /// Start A, middle B and end C of the beautified stroke.
    pub a: Vec3,
    /// See `a`.
    pub b: Vec3,
    /// See `a`.
    pub c: Vec3,
    /// Arc or straight.
    pub path: Path,
    /// Where the reference vertex starts (its position in the start pose).
    pub start_position: Vec3,
}

/// What a stroke became: a timed transition of one chain between two layers.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    /// The chain (layer) it belongs to: the id of the chain's first action.
    pub chain: ActionId,
    /// The previous action of the chain.
    pub previous: Option<ActionId>,
    /// First frame.
    pub start_frame: f32,
    /// Length in frames.
    pub duration: f32,
    /// The stroke's side and, with symmetry, its mirror.
    pub sides: Vec<Side>,
    /// The chain's contribution when the action starts.
    pub from: Layer,
    /// The chain's contribution when it ends.
    pub to: Layer,
    /// Progress over time.
    pub timing: Timing,
    /// Vertices that swing along an arc: (vertex, share κ of the reference's motion, side).
    pub swing: Vec<(u32, f32, u8)>,
    /// The easing handle's α.
    pub ease: f32,
    /// Why an action that asked to be mirrored is not (no symmetry plane, no partner for its
    /// blendshape, no mirror of its vertex); `None` when it is, or did not ask.
    pub unmirrored: Option<String>,
}

impl Action {
    /// The frame at which it ends.
    #[must_use]
    pub fn end_frame(&self) -> f32 {
        self.start_frame + self.duration
    }

    /// Progress at `frame`: 0 before, 1 after, the timing curve in between.
    #[must_use]
    pub fn progress(&self, frame: f32) -> f32 {
        if frame <= self.start_frame {
            0.0
        } else if frame >= self.end_frame() {
            1.0
        } else {
            self.timing
                .progress((frame - self.start_frame) / self.duration)
        }
    }

    /// Its display name, such as `mouthSmile_L 0.80` or `jawOpen 1.00 + exaggeration`.
    #[must_use]
    pub fn name(&self, character: &Character) -> String {
        let mut names: Vec<String> = Vec::new();
        for side in &self.sides {
            let label = match side.target {
                Target::Blendshape(id) => {
                    format!(
                        "{} {:.2}",
                        character.blendshape(id).map_or("?", |b| b.name()),
                        side.weight
                    )
                }
                Target::Neutral => "neutral".to_owned(),
                Target::Multi => "multi".to_owned(),
            };
            if side.exaggeration.length() > 1e-6 {
                names.push(format!("{label} + exaggeration"));
            } else {
                names.push(label);
            }
        }
        names.join(" | ")
    }

    /// The arc of side `side`, if it is not straight.
    #[must_use]
    pub fn arc(&self, side: u8) -> Option<Arc> {
        match self.sides.get(side as usize)?.path {
            Path::Arc(arc) => Some(arc),
            Path::Straight => None,
        }
    }
}
