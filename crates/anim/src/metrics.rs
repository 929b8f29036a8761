//! Evaluation metrics of both seeds, comparing a clip with a reference clip.
//!
//! - Spatial accuracy (sketch paper, section 4.3): dynamic time warping over frames, with the
//!   distance between two frames the sum over blendshapes of |wₐ − w_b|; the total along the
//!   best path, and that total per step of the path.
//! - Temporal accuracy: the root mean square of frame-to-frame weight changes (jitter), and its
//!   difference to the reference's.
//! - Blendshape MAE (BYOC, Tables 1–2), when both clips have the same frames and names.
//!
//! Clips are aligned by blendshape name; a name missing from one clip counts as weight 0 there.

use serde::Serialize;

use crate::Clip;

/// The metrics of `faceanim eval` (field names are a stable JSON format).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// DTW distance: sum of frame distances along the optimal warping path.
    pub dtw: f32,
    /// `dtw` divided by the number of steps of the path.
    pub dtw_per_frame: f32,
    /// RMS frame-to-frame change of the first clip.
    pub jitter_a: f32,
    /// RMS frame-to-frame change of the second clip.
    pub jitter_b: f32,
    /// `jitter_a − jitter_b`.
    pub jitter_diff: f32,
    /// Mean absolute weight error, when the clips have the same frame count and names.
    pub mae: Option<f32>,
}

/// Compares clip `a` with reference `b`.
#[must_use]
pub fn compare(a: &Clip, b: &Clip) -> Comparison {
    let (a_rows, b_rows) = aligned(a, b);
    let (dtw, steps) = dtw(&a_rows, &b_rows);
    let jitter_a = jitter(&a_rows);
    let jitter_b = jitter(&b_rows);
    let same_names = {
        let mut x = a.blendshapes.clone();
        let mut y = b.blendshapes.clone();
        x.sort();
        y.sort();
        x == y
    };
    let mae = (same_names && a.frames.len() == b.frames.len()).then(|| mae(&a_rows, &b_rows));
    Comparison {
        dtw,
        dtw_per_frame: if steps > 0 { dtw / steps as f32 } else { 0.0 },
        jitter_a,
        jitter_b,
        jitter_diff: jitter_a - jitter_b,
        mae,
    }
}

/// Both clips' frames over the union of their names (a's order first).
fn aligned(a: &Clip, b: &Clip) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let mut names: Vec<&str> = a.blendshapes.iter().map(String::as_str).collect();
    for n in &b.blendshapes {
        if !names.contains(&n.as_str()) {
            names.push(n);
        }
    }
    let rows = |clip: &Clip| -> Vec<Vec<f32>> {
        let columns: Vec<Option<usize>> = names
            .iter()
            .map(|n| clip.blendshapes.iter().position(|m| m == n))
            .collect();
        clip.frames
            .iter()
            .map(|frame| {
                columns
                    .iter()
                    .map(|c| c.and_then(|c| frame.get(c).copied()).unwrap_or(0.0))
                    .collect()
            })
            .collect()
    };
    (rows(a), rows(b))
}

fn distance(x: &[f32], y: &[f32]) -> f32 {
    x.iter().zip(y).map(|(a, b)| (a - b).abs()).sum()
}

/// DTW total cost and the number of steps of the optimal path.
#[must_use]
pub fn dtw(a: &[Vec<f32>], b: &[Vec<f32>]) -> (f32, usize) {
    let (n, m) = (a.len(), b.len());
    if n == 0 || m == 0 {
        return (0.0, 0);
    }
    // cost and path length, row by row.
    let mut previous: Vec<(f32, usize)> = vec![(f32::INFINITY, 0); m + 1];
    previous[0] = (0.0, 0);
    let mut current = vec![(f32::INFINITY, 0); m + 1];
    for i in 1..=n {
        current[0] = (f32::INFINITY, 0);
        for j in 1..=m {
            let d = distance(&a[i - 1], &b[j - 1]);
            let best = [previous[j - 1], previous[j], current[j - 1]]
                .into_iter()
                .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                .unwrap_or((f32::INFINITY, 0));
            current[j] = (best.0 + d, best.1 + 1);
        }
        std::mem::swap(&mut previous, &mut current);
    }
    previous[m]
}

/// RMS of frame-to-frame weight changes over all blendshapes.
#[must_use]
pub fn jitter(frames: &[Vec<f32>]) -> f32 {
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for w in frames.windows(2) {
        for (x, y) in w[0].iter().zip(&w[1]) {
            sum += f64::from(y - x).powi(2);
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt() as f32
    }
}

/// Mean absolute difference of equally shaped frame lists.
#[must_use]
pub fn mae(a: &[Vec<f32>], b: &[Vec<f32>]) -> f32 {
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.iter().zip(y) {
            sum += f64::from((p - q).abs());
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f64) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(names: &[&str], frames: Vec<Vec<f32>>) -> Clip {
        Clip {
            fps: 30.0,
            blendshapes: names.iter().map(|s| (*s).to_owned()).collect(),
            frames,
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }

    #[test]
    fn identical_clips_are_at_distance_zero() {
        let a = clip(
            &["x", "y"],
            vec![vec![0.0, 0.1], vec![0.5, 0.2], vec![1.0, 0.3]],
        );
        let c = compare(&a, &a);
        assert_eq!((c.dtw, c.mae, c.jitter_diff), (0.0, Some(0.0), 0.0));
    }

    #[test]
    fn dtw_forgives_timing_but_not_shape() {
        // The same ramp played at half speed: DTW small, MAE not applicable (frame counts differ).
        let fast = clip(&["x"], (0..=10).map(|i| vec![i as f32 / 10.0]).collect());
        let slow = clip(&["x"], (0..=20).map(|i| vec![i as f32 / 20.0]).collect());
        let c = compare(&slow, &fast);
        assert!(c.dtw_per_frame < 0.03, "{c:?}");
        assert_eq!(c.mae, None);
        // A ramp to 0.5 instead of 1 is farther, however it is warped.
        let half = clip(&["x"], (0..=10).map(|i| vec![i as f32 / 20.0]).collect());
        assert!(compare(&half, &fast).dtw_per_frame > 3.0 * c.dtw_per_frame);
        // The slow ramp changes half as much per frame.
        assert!((c.jitter_a - 0.05).abs() < 1e-6 && (c.jitter_b - 0.1).abs() < 1e-6);
    }

    #[test]
    fn names_align_and_missing_ones_count_as_zero() {
        let a = clip(&["x", "y"], vec![vec![1.0, 0.0]]);
        let b = clip(&["y", "x"], vec![vec![0.0, 1.0]]);
        assert_eq!(compare(&a, &b).mae, Some(0.0));
        let c = clip(&["x"], vec![vec![1.0]]);
        let r = compare(&a, &c);
        assert_eq!((r.dtw, r.mae), (0.0, None));
    }
}
