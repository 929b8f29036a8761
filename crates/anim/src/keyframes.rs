//! The keyframe sampling of "Bring Your Own Character": keep the estimate on every `every`-th
//! frame (5 by default), on the last frame and on frames the user picks, and interpolate
//! linearly between them. It removes frame-to-frame jitter the way an animator's keys would,
//! and leaves the user a handful of keys to correct instead of every frame.

use crate::Clip;

/// The seed's default spacing of keyframes.
pub const DEFAULT_EVERY: usize = 5;

/// Sorted, distinct keyframe indices for `frame_count` frames: 0, `every`, `2·every`, …, the
/// last frame, and `extra` (indices past the end are ignored). `every` of 0 is taken as 1.
#[must_use]
pub fn keyframe_indices(frame_count: usize, every: usize, extra: &[usize]) -> Vec<usize> {
    if frame_count == 0 {
        return Vec::new();
    }
    let mut keys: Vec<usize> = (0..frame_count).step_by(every.max(1)).collect();
    keys.push(frame_count - 1);
    keys.extend(extra.iter().copied().filter(|&k| k < frame_count));
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// `clip` with every frame between keyframes replaced by linear interpolation of the keys
/// (weights, head rotation and position; presence is kept per frame).
#[must_use]
pub fn interpolate_between(clip: &Clip, keys: &[usize]) -> Clip {
    let mut out = clip.clone();
    let mut known = vec![false; clip.frames.len()];
    for &k in keys {
        if let Some(slot) = known.get_mut(k) {
            *slot = true;
        }
    }
    crate::filter::fill_gaps_rows(&mut out.frames, &known);
    if let Some(head) = out.head.as_mut() {
        crate::filter::fill_gaps(head, &known);
    }
    if let Some(position) = out.head_position.as_mut() {
        crate::filter::fill_gaps(position, &known);
    }
    out
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "keys are copied, so they compare exactly")]
mod tests {
    use super::*;

    #[test]
    fn keys_every_five_plus_the_last_and_extras() {
        assert_eq!(keyframe_indices(12, 5, &[7, 40]), vec![0, 5, 7, 10, 11]);
        assert_eq!(keyframe_indices(11, 5, &[]), vec![0, 5, 10]);
        assert_eq!(keyframe_indices(1, 5, &[]), vec![0]);
        assert!(keyframe_indices(0, 5, &[]).is_empty());
        assert_eq!(keyframe_indices(3, 0, &[]), vec![0, 1, 2]);
    }

    #[test]
    fn frames_between_keys_are_interpolated() {
        let clip = Clip {
            fps: 30.0,
            blendshapes: vec!["a".into()],
            frames: (0..11)
                .map(|i| vec![if i % 2 == 0 { 1.0 } else { 0.0 }])
                .collect(),
            head: Some((0..11).map(|i| [i as f32, 0.0, 0.0]).collect()),
            head_position: None,
            presence: None,
            arkit: None,
        };
        let keyed = interpolate_between(&clip, &keyframe_indices(11, 5, &[]));
        // Keys 0, 5 (value 0) and 10 (value 1).
        let got: Vec<f32> = keyed.frames.iter().map(|r| r[0]).collect();
        assert_eq!(got[0], 1.0);
        assert!((got[2] - 0.6).abs() < 1e-6);
        assert_eq!(got[5], 0.0);
        assert!((got[8] - 0.6).abs() < 1e-6);
        assert_eq!(keyed.head.unwrap()[3], [3.0, 0.0, 0.0]);
    }
}
