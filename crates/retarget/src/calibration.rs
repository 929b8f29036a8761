//! MediaPipe's response to each channel on one character, and its inverse.
//!
//! The character is rendered showing each channel through the map at a few intensities and
//! read back by the capture pipeline, relative to its neutral render: `response(x)` is how much
//! MediaPipe's score for the channel rises when the character shows it at `x`. A [`Curve`] is
//! the monotone inverse: a rise in the score to the channel value that makes the character look
//! so. A channel MediaPipe hardly sees on the character (its score rises less than
//! [`MIN_RESPONSE`] at full strength) keeps the score as it is.
//!
//! What is applied to a frame is the curve's straight part: one gain per channel (the least
//! squares line through the origin of the measured response's inverse), at most [`MAX_GAIN`].
//! Measured on tuning material, the bent curve itself reads stills of the character by another
//! renderer no better, and people worse: a person's scores do not bend as a render's do, and a
//! curve steep near zero turns a person's small movements into large ones.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A channel whose score rises less than this at full strength is not calibrated.
pub const MIN_RESPONSE: f32 = 0.05;
/// The largest gain a calibration applies: a channel MediaPipe barely sees on the character
/// is not blown up from noise.
pub const MAX_GAIN: f32 = 3.0;

/// A monotone map from a score's rise to a channel value, piecewise linear through its knots
/// (`rises` increasing from 0, `values` from 0 up to at most 1). Beyond the last knot the last
/// piece goes on, up to 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curve {
    /// The score's rise at each knot.
    pub rises: Vec<f32>,
    /// The channel value there.
    pub values: Vec<f32>,
}

impl Curve {
    /// The inverse of the measured response: `samples` are (channel value shown, score rise
    /// read) pairs, in any order. The rises are made non-decreasing in the value (pooled where
    /// they fall: pool-adjacent-violators); `None` when the score rises less than
    /// [`MIN_RESPONSE`] at the strongest value shown.
    #[must_use]
    pub fn fit(samples: &[(f32, f32)]) -> Option<Curve> {
        let mut sorted: Vec<(f32, f32)> = samples
            .iter()
            .copied()
            .filter(|(x, r)| x.is_finite() && r.is_finite())
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Pool adjacent violators: blocks of (sum of rises, count, value of the last member).
        let mut blocks: Vec<(f32, f32, f32)> = Vec::new();
        for (x, r) in sorted {
            blocks.push((r, 1.0, x));
            while blocks.len() > 1 {
                let n = blocks.len();
                let (last, before) = (blocks[n - 1], blocks[n - 2]);
                if before.0 / before.1 <= last.0 / last.1 {
                    break;
                }
                blocks.truncate(n - 2);
                blocks.push((before.0 + last.0, before.1 + last.1, last.2));
            }
        }
        let strongest = blocks.last().map_or(0.0, |b| b.0 / b.1);
        if strongest < MIN_RESPONSE {
            return None;
        }
        let mut rises = vec![0.0];
        let mut values = vec![0.0];
        for (sum, count, x) in blocks {
            let rise = sum / count;
            if rise > rises[rises.len() - 1] + 1e-4 && x > values[values.len() - 1] {
                rises.push(rise);
                values.push(x.min(1.0));
            }
        }
        (rises.len() >= 2).then_some(Curve { rises, values })
    }

    /// The gain applied to a score's rise: the least-squares line through the origin of the
    /// curve's knots (values against rises), at most [`MAX_GAIN`].
    #[must_use]
    pub fn gain(&self) -> f32 {
        let (rr, rv) = self
            .rises
            .iter()
            .zip(&self.values)
            .fold((0.0f32, 0.0f32), |(rr, rv), (r, v)| {
                (rr + r * r, rv + r * v)
            });
        if rr <= 0.0 {
            1.0
        } else {
            (rv / rr).clamp(0.0, MAX_GAIN)
        }
    }

    /// The channel value for a score's `rise` along the bent curve itself.
    #[must_use]
    pub fn value(&self, rise: f32) -> f32 {
        if rise <= 0.0 || self.rises.len() < 2 {
            return 0.0;
        }
        let k = self
            .rises
            .iter()
            .position(|r| *r >= rise)
            .unwrap_or(self.rises.len() - 1)
            .max(1);
        let (r0, r1) = (self.rises[k - 1], self.rises[k]);
        let (v0, v1) = (self.values[k - 1], self.values[k]);
        let t = (rise - r0) / (r1 - r0).max(1e-6);
        (v0 + t * (v1 - v0)).clamp(0.0, 1.0)
    }

    fn problems(&self, path: &str) -> Vec<String> {
        let mut problems = Vec::new();
        if self.rises.len() != self.values.len() || self.rises.len() < 2 {
            problems.push(format!(
                "{path}: rises and values must be two lists of the same length, at least 2"
            ));
            return problems;
        }
        let increasing =
            |v: &[f32]| v.windows(2).all(|w| w[1] > w[0]) && v.iter().all(|x| x.is_finite());
        if !increasing(&self.rises) || self.rises[0] != 0.0 {
            problems.push(format!("{path}.rises: must increase from 0"));
        }
        if !increasing(&self.values)
            || self.values[0] != 0.0
            || self.values.iter().any(|v| *v > 1.0)
        {
            problems.push(format!("{path}.values: must increase from 0 to at most 1"));
        }
        problems
    }
}

/// Each channel's [`Curve`], by ARKit name (channels without one keep their score).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The curves.
    pub channels: BTreeMap<String, Curve>,
    /// Renders it was measured on.
    pub renders: usize,
}

impl Calibration {
    /// Channel values (in [`faceanim_rig::names::ARKIT_52`]'s order) from MediaPipe's scores:
    /// `rise(name)` is how far the score of channel `name` is above the face's neutral (or the
    /// score itself, without a neutral). A calibrated channel's rise is multiplied by its
    /// [`Curve::gain`], and may pass 1 (up to the gain: how far the character may go is the
    /// map's to say, [`crate::RetargetMap::reach`]); the others keep their rise, within 0..=1.
    #[must_use]
    pub fn values(&self, rise: impl Fn(&str) -> f32) -> Vec<f32> {
        faceanim_rig::names::ARKIT_52
            .iter()
            .map(|name| {
                let r = rise(name).clamp(0.0, 1.0);
                match self.channels.get(*name) {
                    Some(curve) => curve.gain() * r,
                    None => r,
                }
            })
            .collect()
    }

    pub(crate) fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        for (name, curve) in &self.channels {
            let path = format!("calibration.channels.{}", faceanim_rig::excerpt(name));
            if crate::channel_index(name).is_none() {
                problems.push(format!("{path}: not an ARKit channel"));
            }
            problems.extend(curve.problems(&path));
        }
        problems
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_response_is_inverted_and_made_monotone() {
        // MediaPipe reads half of what is shown, and one reading dips.
        let samples = [(0.25, 0.12), (0.5, 0.26), (0.75, 0.24), (1.0, 0.5)];
        let curve = Curve::fit(&samples).unwrap_or_else(|| panic!("a response"));
        assert!(curve.rises.windows(2).all(|w| w[1] > w[0]));
        assert!((curve.value(0.5) - 1.0).abs() < 1e-6);
        assert!((curve.value(0.12) - 0.25).abs() < 1e-4);
        assert!((curve.value(0.9) - 1.0).abs() < 1e-6);
        assert!(curve.value(-0.2).abs() < 1e-6);
        assert!(curve.problems("c").is_empty());
        // The straight line through the knots: close to the halving it inverts.
        assert!((curve.gain() - 2.0).abs() < 0.25, "{}", curve.gain());
        // Hardly seen: not calibrated.
        assert!(Curve::fit(&[(0.5, 0.01), (1.0, 0.02)]).is_none());
    }
}
