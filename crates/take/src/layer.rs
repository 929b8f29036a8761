//! The one rule that puts a sketch over a take: the take's weights plus the sketch's on the
//! character's own targets, clamped to [0, 1]; the sketch's extra baked targets (arcs and
//! exaggerations) from the sketch alone; the longer of the two sets the length, and each holds
//! its last frame beyond its end (the head pose too).
//!
//! Every export of a take with strokes goes through [`layer`], which gives the clip (weights
//! by name) and the morph animation (own and extra targets, the head turn as rotations) from
//! the same rows. The studio's page plays the same rule while editing, and a browser test ties
//! the two.

use faceanim_anim::Clip;
use faceanim_rig::animation::MorphAnimation;

/// A take with a sketch over it.
#[derive(Debug, Clone, PartialEq)]
pub struct Layered {
    /// The character's own weights per frame, with the take's head pose and presence.
    pub clip: Clip,
    /// The same frames for every target (own, then the sketch's extras) with the head turn.
    pub animation: MorphAnimation,
}

/// Layers `sketch` (its baked animation: one row per frame, the character's `own` targets
/// first, then its extra targets; `None` when there are no strokes) over `base` (the take's
/// clip, in the character's own blendshapes), into an animation named `name`.
#[must_use]
pub fn layer(base: &Clip, sketch: Option<&MorphAnimation>, own: usize, name: &str) -> Layered {
    let sketch_rows: &[Vec<f32>] = sketch.map_or(&[], |s| &s.weights);
    let frames = base.frames.len().max(sketch_rows.len());
    let extras = sketch_rows
        .first()
        .map_or(0, |row| row.len().saturating_sub(own));
    let mut own_rows = Vec::with_capacity(frames);
    let mut all_rows = Vec::with_capacity(frames);
    for f in 0..frames {
        let mut row = held(&base.frames, f).map_or_else(|| vec![0.0; own], |r| r.to_vec());
        row.resize(own, 0.0);
        let extra = held(sketch_rows, f);
        if let Some(s) = extra {
            for (w, v) in row.iter_mut().zip(s) {
                *w = (*w + v).clamp(0.0, 1.0);
            }
        }
        let mut all = row.clone();
        all.extend((0..extras).map(|k| extra.and_then(|s| s.get(own + k)).copied().unwrap_or(0.0)));
        own_rows.push(row);
        all_rows.push(all);
    }
    let mut clip = Clip {
        frames: own_rows,
        ..base.clone()
    };
    let extend = |v: &mut Vec<[f32; 3]>| {
        if let Some(&last) = v.last() {
            v.resize(frames, last);
        }
    };
    if let Some(h) = clip.head.as_mut() {
        extend(h);
    }
    if let Some(p) = clip.head_position.as_mut() {
        extend(p);
    }
    if let Some(p) = clip.presence.as_mut() {
        let last = p.last().copied().unwrap_or(1.0);
        p.resize(frames, last);
    }
    let fps = clip.fps.max(1e-3);
    let animation = MorphAnimation {
        name: name.to_owned(),
        times: (0..frames.max(1)).map(|f| f as f32 / fps).collect(),
        weights: if all_rows.is_empty() {
            vec![vec![0.0; own + extras]]
        } else {
            all_rows
        },
        rotations: clip.head.as_ref().map(|head| {
            head.iter()
                .map(|&h| faceanim_anim::head_rotation(h))
                .collect()
        }),
    };
    Layered { clip, animation }
}

/// Row `f` of `rows`, or its last row beyond its end; `None` when it has none.
fn held(rows: &[Vec<f32>], f: usize) -> Option<&[f32]> {
    rows.get(f.min(rows.len().checked_sub(1)?))
        .map(Vec::as_slice)
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "sums of exact binary fractions")]
mod tests {
    use super::*;

    fn clip(rows: Vec<Vec<f32>>, head: Option<Vec<[f32; 3]>>) -> Clip {
        Clip {
            fps: 2.0,
            blendshapes: vec!["a".into(), "b".into()],
            frames: rows,
            head,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }

    #[test]
    fn strokes_add_onto_the_take_clamped_and_the_longer_sets_the_length() {
        let base = clip(vec![vec![0.25, 0.5], vec![0.75, 0.5]], None);
        let sketch = MorphAnimation {
            name: "sketch".into(),
            times: vec![0.0, 0.5, 1.0],
            weights: vec![vec![0.5, 0.0], vec![0.5, 0.25], vec![0.0, 0.75]],
            rotations: None,
        };
        let layered = layer(&base, Some(&sketch), 2, "take");
        assert_eq!(
            layered.clip.frames,
            vec![vec![0.75, 0.5], vec![1.0, 0.75], vec![0.75, 1.0]],
            "the third frame holds the take's last frame under the sketch's"
        );
        // No strokes: the take as it is.
        assert_eq!(layer(&base, None, 2, "take").clip.frames, base.frames);
    }

    #[test]
    fn the_animation_layers_the_sketch_over_the_take_and_keeps_the_head_turn() {
        let base = clip(
            vec![vec![0.5, 0.25], vec![0.75, 0.25]],
            Some(vec![[0.0, 0.0, 0.0], [90.0, 0.0, 0.0]]),
        );
        // Two own targets and one baked exaggeration target; three frames.
        let sketch = MorphAnimation {
            name: "sketch".into(),
            times: vec![0.0, 0.5, 1.0],
            weights: vec![
                vec![0.0, 0.0, 0.0],
                vec![0.5, 0.5, 0.5],
                vec![0.25, 0.0, 1.0],
            ],
            rotations: None,
        };
        let layered = layer(&base, Some(&sketch), 2, "take");
        let animation = layered.animation;
        assert_eq!(animation.times, vec![0.0, 0.5, 1.0]);
        assert_eq!(
            animation.weights,
            vec![
                vec![0.5, 0.25, 0.0],
                vec![1.0, 0.75, 0.5],
                vec![1.0, 0.25, 1.0],
            ]
        );
        let turn = faceanim_anim::head_rotation([90.0, 0.0, 0.0]);
        assert_eq!(
            animation.rotations,
            Some(vec![faceanim_anim::head_rotation([0.0; 3]), turn, turn])
        );
        assert_eq!(layered.clip.head.map(|h| h.len()), Some(3));
    }
}
