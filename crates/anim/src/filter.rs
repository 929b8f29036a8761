//! Smoothing for captured clips: the One Euro filter (Casiez, Roussel and Vogel, CHI 2012), a
//! low-pass filter whose cutoff rises with speed, so a still face stops jittering while a
//! fast jaw drop keeps its timing; and gap filling for frames where capture found no face.
//!
//! Weights (0..1) and head angles (degrees) share one set of settings: angles are filtered as
//! fractions of 90° so that `beta` means the same for both.

use serde::{Deserialize, Serialize};

use crate::Clip;

/// One Euro filter settings. Larger `min_cutoff` keeps more detail (and jitter) at rest; larger
/// `beta` lets fast motion through with less lag.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OneEuro {
    /// Cutoff frequency at rest, Hz (positive).
    pub min_cutoff: f32,
    /// How much the cutoff rises per unit of speed (units per second).
    pub beta: f32,
    /// Cutoff of the speed estimate, Hz (positive).
    pub derivative_cutoff: f32,
}

impl Default for OneEuro {
    /// Tuned on captured ARKit weights at 30 fps: at rest jitter of ±0.02 is cut by about
    /// three quarters; a 0 → 1 change in 0.2 s lags by about one frame.
    fn default() -> OneEuro {
        OneEuro {
            min_cutoff: 1.5,
            beta: 1.5,
            derivative_cutoff: 1.0,
        }
    }
}

impl OneEuro {
    /// Checks that the cutoffs are positive and beta is not negative.
    ///
    /// # Errors
    /// A message naming the bad field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.min_cutoff.is_finite() && self.min_cutoff > 0.0) {
            return Err(format!(
                "min_cutoff must be positive, got {}",
                self.min_cutoff
            ));
        }
        if !(self.beta.is_finite() && self.beta >= 0.0) {
            return Err(format!("beta must be zero or more, got {}", self.beta));
        }
        if !(self.derivative_cutoff.is_finite() && self.derivative_cutoff > 0.0) {
            return Err(format!(
                "derivative_cutoff must be positive, got {}",
                self.derivative_cutoff
            ));
        }
        Ok(())
    }
}

fn smoothing_factor(cutoff: f32, dt: f32) -> f32 {
    let tau = 1.0 / (2.0 * std::f32::consts::PI * cutoff);
    1.0 / (1.0 + tau / dt)
}

/// A One Euro filter over a vector of values, fed one frame at a time (live capture uses it
/// as frames arrive; [`smooth`] runs it over a whole clip).
#[derive(Debug, Clone)]
pub struct OneEuroState {
    settings: OneEuro,
    previous: Option<(f32, Vec<f32>, Vec<f32>)>,
}

impl OneEuroState {
    /// A filter that has seen nothing yet.
    #[must_use]
    pub fn new(settings: OneEuro) -> OneEuroState {
        OneEuroState {
            settings,
            previous: None,
        }
    }

    /// Filters `values` (in place) taken at `time` seconds. The first call, a change of
    /// length, or a time that does not advance passes the values through and restarts.
    pub fn filter(&mut self, time: f32, values: &mut [f32]) {
        let OneEuro {
            min_cutoff,
            beta,
            derivative_cutoff,
        } = self.settings;
        match &mut self.previous {
            Some((last_time, last, speed)) if last.len() == values.len() && time > *last_time => {
                let dt = time - *last_time;
                let a_speed = smoothing_factor(derivative_cutoff, dt);
                for ((value, last), speed) in
                    values.iter_mut().zip(last.iter_mut()).zip(speed.iter_mut())
                {
                    let raw_speed = (*value - *last) / dt;
                    *speed += a_speed * (raw_speed - *speed);
                    let cutoff = min_cutoff + beta * speed.abs();
                    let a = smoothing_factor(cutoff, dt);
                    *last += a * (*value - *last);
                    *value = *last;
                }
                *last_time = time;
            }
            _ => self.previous = Some((time, values.to_vec(), vec![0.0; values.len()])),
        }
    }
}

/// Smooths every weight column (clamped back to [0, 1]) and the head rotation of `clip`.
///
/// # Errors
/// The settings' validation message.
pub fn smooth(clip: &mut Clip, settings: OneEuro) -> Result<(), String> {
    settings.validate()?;
    let mut weights = OneEuroState::new(settings);
    let mut head = OneEuroState::new(settings);
    let mut position = OneEuroState::new(settings);
    for (f, row) in clip.frames.iter_mut().enumerate() {
        let time = f as f32 / clip.fps;
        weights.filter(time, row);
        for w in row.iter_mut() {
            *w = w.clamp(0.0, 1.0);
        }
        if let Some(angles) = clip.head.as_mut().and_then(|h| h.get_mut(f)) {
            let mut scaled = angles.map(|a| a / 90.0);
            head.filter(time, &mut scaled);
            *angles = scaled.map(|a| a * 90.0);
        }
        if let Some(p) = clip.head_position.as_mut().and_then(|h| h.get_mut(f)) {
            position.filter(time, p);
        }
    }
    Ok(())
}

/// Fills the rows of frames that are not `known` by linear interpolation between the nearest
/// known frames (holding the first and last known rows at the ends). With no known frame at
/// all, the rows are left as they are.
pub fn fill_gaps<const N: usize>(rows: &mut [[f32; N]], known: &[bool]) {
    let mut as_vecs: Vec<Vec<f32>> = rows.iter().map(|r| r.to_vec()).collect();
    fill_gaps_rows(&mut as_vecs, known);
    for (row, filled) in rows.iter_mut().zip(as_vecs) {
        row.copy_from_slice(&filled);
    }
}

/// [`fill_gaps`] for rows of any length (a clip's weight rows).
pub fn fill_gaps_rows(rows: &mut [Vec<f32>], known: &[bool]) {
    let indices: Vec<usize> = (0..rows.len())
        .filter(|&i| known.get(i) == Some(&true))
        .collect();
    let (Some(&first), Some(&last)) = (indices.first(), indices.last()) else {
        return;
    };
    for i in 0..first {
        rows[i] = rows[first].clone();
    }
    for i in last + 1..rows.len() {
        rows[i] = rows[last].clone();
    }
    for pair in indices.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        for i in a + 1..b {
            let t = (i - a) as f32 / (b - a) as f32;
            let row: Vec<f32> = rows[a]
                .iter()
                .zip(&rows[b])
                .map(|(x, y)| x + (y - x) * t)
                .collect();
            rows[i] = row;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(values: &[f32]) -> Clip {
        Clip {
            fps: 30.0,
            blendshapes: vec!["jawOpen".into()],
            frames: values.iter().map(|&v| vec![v]).collect(),
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }

    fn jitter(i: usize) -> f32 {
        // A deterministic ±0.02 zigzag.
        if i.is_multiple_of(2) { 0.02 } else { -0.02 }
    }

    #[test]
    fn jitter_at_rest_shrinks_and_a_fast_step_still_arrives() {
        let rest: Vec<f32> = (0..60).map(|i| 0.3 + jitter(i)).collect();
        let mut c = clip(&rest);
        smooth(&mut c, OneEuro::default()).unwrap();
        let spread = c.frames[30..]
            .iter()
            .map(|r| (r[0] - 0.3).abs())
            .fold(0.0f32, f32::max);
        assert!(spread < 0.006, "jitter left: {spread}");

        // 0 → 1 over 6 frames (0.2 s), then hold: within 0.05 of 1 three frames later.
        let step: Vec<f32> = (0..30)
            .map(|i| ((i as f32 - 10.0) / 6.0).clamp(0.0, 1.0))
            .collect();
        let mut c = clip(&step);
        smooth(&mut c, OneEuro::default()).unwrap();
        assert!(c.frames[19][0] > 0.95, "{:?}", &c.frames[14..22]);
        assert!(c.frames.iter().all(|r| (0.0..=1.0).contains(&r[0])));
    }

    #[test]
    fn bad_settings_are_named() {
        let mut c = clip(&[0.0, 1.0]);
        let bad = OneEuro {
            min_cutoff: 0.0,
            ..OneEuro::default()
        };
        assert!(smooth(&mut c, bad).unwrap_err().contains("min_cutoff"));
    }

    #[test]
    fn gaps_are_bridged_and_ends_held() {
        let mut rows = vec![
            vec![9.0],
            vec![0.0],
            vec![9.0],
            vec![9.0],
            vec![1.0],
            vec![9.0],
        ];
        fill_gaps_rows(&mut rows, &[false, true, false, false, true, false]);
        let got: Vec<f32> = rows.iter().map(|r| r[0]).collect();
        let want = [0.0, 0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0, 1.0];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{got:?}");
        }
        let mut none = vec![vec![5.0]; 3];
        fill_gaps_rows(&mut none, &[false; 3]);
        assert_eq!(none, vec![vec![5.0]; 3]);
    }
}
