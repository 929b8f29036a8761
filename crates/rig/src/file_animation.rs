//! The morph-weight animations a glTF file already holds (a take or sketch faceanim exported,
//! or one made in Blender, Maya or a capture tool), read so that they open again as takes.
//!
//! Each animation keeps, per animated mesh, its `weights` channel as the file stores it (key
//! times, one weight per morph target per key, the sampler's interpolation). [`FileAnimation::
//! sample`] plays them at a steady rate and reads each blendshape back through its bindings: a
//! raw target's weight as it is, a VRM expression's as its bound target's weight over the
//! binding's weight.
//!
//! ```
//! use faceanim_rig::file_animation::{FileAnimation, Interpolation, WeightsTrack};
//! use faceanim_rig::source::Binding;
//!
//! // One mesh with two targets, keyed at 0 and 1 s.
//! let track = WeightsTrack::new(0, vec![0.0, 1.0], vec![0.0, 0.0, 1.0, 0.5], 2, Interpolation::Linear)?;
//! let animation = FileAnimation { name: "smile".into(), tracks: vec![track], ours: false, turns: vec![], strokes: None };
//! // Blendshape 0 is target 1 of mesh 0.
//! let played = animation.sample(&[vec![Binding { mesh: 0, target: 1, weight: 1.0 }]]);
//! assert_eq!(played.times.len(), 31); // 30 frames a second, from 0 to 1 s
//! assert!((played.weights[15][0] - 0.25).abs() < 1e-6);
//! # Ok::<(), String>(())
//! ```

use crate::animation::MorphAnimation;
use crate::binding::Binding;

/// The key in an animation's `extras` that marks it as faceanim's (`{"faceanim": {"take":
/// true}}`), written by the GLB exporter.
pub const EXTRAS_KEY: &str = "faceanim";

/// The key under [`EXTRAS_KEY`] that keeps the strokes a sketched animation was made from.
pub const STROKES_KEY: &str = "strokes";

/// The rate an animation plays at when its keys keep no steady one.
pub const DEFAULT_FPS: f32 = 30.0;
/// The longest animation played back: one hour.
pub(crate) const MAX_SECONDS: f32 = 3600.0;

/// How a sampler goes from key to key (glTF's `interpolation`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// Held until the next key.
    Step,
    /// Straight lines between keys.
    Linear,
    /// Hermite curves: each key stores an in-tangent, the value and an out-tangent.
    CubicSpline,
}

/// One mesh's `weights` channel as the file stores it.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightsTrack {
    mesh: u32,
    times: Vec<f32>,
    values: Vec<f32>,
    targets: usize,
    interpolation: Interpolation,
}

impl WeightsTrack {
    /// A track of `mesh`: `values` holds `targets` weights per key (three times that for a
    /// cubic spline: in-tangents, values, out-tangents).
    ///
    /// # Errors
    /// A sentence when the times are not finite and increasing or the values do not fit them.
    pub fn new(
        mesh: u32,
        times: Vec<f32>,
        values: Vec<f32>,
        targets: usize,
        interpolation: Interpolation,
    ) -> Result<WeightsTrack, String> {
        check_times(&times)?;
        let per_key = match interpolation {
            Interpolation::CubicSpline => 3 * targets,
            _ => targets,
        };
        if targets == 0 || values.len() != times.len() * per_key {
            return Err(format!(
                "{} weights for {} keys of {targets} morph targets",
                values.len(),
                times.len()
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err("a weight is not a number".into());
        }
        Ok(WeightsTrack {
            mesh,
            times,
            values,
            targets,
            interpolation,
        })
    }

    /// The mesh it animates.
    #[must_use]
    pub fn mesh(&self) -> u32 {
        self.mesh
    }

    /// Its last key's time, seconds.
    #[must_use]
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    fn value(&self, key: usize, target: usize) -> f32 {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[(3 * key + 1) * self.targets + target],
            _ => self.values[key * self.targets + target],
        }
    }

    /// Target `target`'s weight at `t` seconds (held before the first key and after the last).
    #[must_use]
    pub fn at(&self, t: f32, target: usize) -> f32 {
        if target >= self.targets {
            return 0.0;
        }
        let (k, s) = match segment(&self.times, t) {
            Segment::At(k) => return self.value(k, target),
            Segment::Between(k, s) => (k, s),
        };
        let next = k + 1;
        let span = self.times[next] - self.times[k];
        match self.interpolation {
            Interpolation::Step => self.value(k, target),
            Interpolation::Linear => {
                let (a, b) = (self.value(k, target), self.value(next, target));
                a + (b - a) * s
            }
            Interpolation::CubicSpline => {
                let out_tangent = self.values[(3 * k + 2) * self.targets + target];
                let in_tangent = self.values[(3 * next) * self.targets + target];
                hermite(
                    s,
                    span,
                    [self.value(k, target), out_tangent],
                    [self.value(next, target), in_tangent],
                )
            }
        }
    }
}

/// The middle step between keys `times`, `None` for fewer than two.
pub(crate) fn median_step(times: &[f32]) -> Option<f32> {
    let mut steps: Vec<f32> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return None;
    }
    steps.sort_unstable_by(f32::total_cmp);
    Some(steps[steps.len() / 2])
}

/// The rate keys a `step` apart were written at: a whole number of frames a second from 24 to
/// 240 (one key per frame), else [`DEFAULT_FPS`] (keys set by hand, further apart, are played
/// between).
pub(crate) fn rate_of(step: Option<f32>) -> f32 {
    let Some(step) = step else {
        return DEFAULT_FPS;
    };
    let rate = 1.0 / step;
    let whole = rate.round();
    if (24.0..=240.0).contains(&whole) && (rate - whole).abs() < 0.01 * whole {
        whole
    } else {
        DEFAULT_FPS
    }
}

/// Key times that are finite, from 0 and strictly increasing, or why not.
fn check_times(times: &[f32]) -> Result<(), String> {
    if times.is_empty() {
        return Err("it has no keys".into());
    }
    if let Some(k) = times
        .iter()
        .position(|t| !t.is_finite() || *t < 0.0)
        .or_else(|| times.windows(2).position(|w| w[1] <= w[0]).map(|k| k + 1))
    {
        return Err(format!(
            "key {k}'s time {} is not after the one before it",
            times[k]
        ));
    }
    Ok(())
}

/// glTF's cubic spline `s` (0..1) of the way between a key `[value, out-tangent]` and the
/// next `[value, in-tangent]`, `span` seconds apart.
fn hermite<T>(s: f32, span: f32, [p0, m0]: [T; 2], [p1, m1]: [T; 2]) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>,
{
    let (s2, s3) = (s * s, s * s * s);
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + m0 * ((s3 - 2.0 * s2 + s) * span)
        + p1 * (-2.0 * s3 + 3.0 * s2)
        + m1 * ((s3 - s2) * span)
}

/// Where a time falls among a track's keys.
enum Segment {
    /// On key `k` (or held before the first key or after the last).
    At(usize),
    /// Between key `k` and the next, `s` (0..1) of the way.
    Between(usize, f32),
}

fn segment(times: &[f32], t: f32) -> Segment {
    let last = times.len() - 1;
    let next = times.partition_point(|&k| k <= t);
    if next == 0 {
        return Segment::At(0);
    }
    if next > last {
        return Segment::At(last);
    }
    let k = next - 1;
    Segment::Between(k, (t - times[k]) / (times[next] - times[k]))
}

/// One node's `rotation` channel as the file stores it (a head, neck or eye bone turned).
#[derive(Debug, Clone, PartialEq)]
pub struct RotationTrack {
    node: u32,
    times: Vec<f32>,
    /// `[x, y, z, w]` per key (in-tangent, value and out-tangent for a cubic spline).
    values: Vec<[f32; 4]>,
    interpolation: Interpolation,
}

impl RotationTrack {
    /// A track of `node`: `values` holds one quaternion `[x, y, z, w]` per key (three for a
    /// cubic spline: in-tangent, value, out-tangent).
    ///
    /// # Errors
    /// A sentence when the times are not finite and increasing, the values do not fit them or
    /// a rotation is not one.
    pub fn new(
        node: u32,
        times: Vec<f32>,
        values: Vec<[f32; 4]>,
        interpolation: Interpolation,
    ) -> Result<RotationTrack, String> {
        check_times(&times)?;
        let per_key = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if values.len() != times.len() * per_key {
            return Err(format!(
                "{} rotations for {} keys",
                values.len(),
                times.len()
            ));
        }
        if values.iter().flatten().any(|v| !v.is_finite()) {
            return Err("a rotation is not a number".into());
        }
        Ok(RotationTrack {
            node,
            times,
            values,
            interpolation,
        })
    }

    /// The node it turns.
    #[must_use]
    pub fn node(&self) -> u32 {
        self.node
    }

    fn value(&self, key: usize) -> glam::Quat {
        let at = match self.interpolation {
            Interpolation::CubicSpline => 3 * key + 1,
            _ => key,
        };
        glam::Quat::from_array(self.values[at])
    }

    /// The node's local rotation at `t` seconds (held before the first key and after the
    /// last; spherical between linear keys, as glTF plays them).
    #[must_use]
    pub fn at(&self, t: f32) -> glam::Quat {
        let q = match segment(&self.times, t) {
            Segment::At(k) => self.value(k),
            Segment::Between(k, s) => match self.interpolation {
                Interpolation::Step => self.value(k),
                Interpolation::Linear => self
                    .value(k)
                    .normalize()
                    .slerp(self.value(k + 1).normalize(), s),
                Interpolation::CubicSpline => {
                    let span = self.times[k + 1] - self.times[k];
                    let v = |i: usize| glam::Vec4::from_array(self.values[i]);
                    glam::Quat::from_vec4(hermite(
                        s,
                        span,
                        [v(3 * k + 1), v(3 * k + 2)],
                        [v(3 * k + 4), v(3 * k + 3)],
                    ))
                }
            },
        };
        let length = q.length();
        if length > 1e-6 && length.is_finite() {
            q / length
        } else {
            glam::Quat::IDENTITY
        }
    }
}

/// One of the file's animations that moves morph targets, or that faceanim wrote turning bones
/// alone (a body with no blendshapes).
#[derive(Debug, Clone, PartialEq)]
pub struct FileAnimation {
    /// Its name in the file (or `animation N`).
    pub name: String,
    /// Its `weights` channels, one per animated mesh.
    pub tracks: Vec<WeightsTrack>,
    /// Whether faceanim wrote it (its `extras` say so): a take or sketch exported before.
    pub ours: bool,
    /// Its `rotation` channels (the bones it turns beside the morph targets).
    pub turns: Vec<RotationTrack>,
    /// The strokes it was sketched from, where faceanim kept them (`extras.faceanim.strokes`:
    /// a sketch project, see the sketch crate's `ProjectFile`), so the sketch opens again as
    /// strokes to edit.
    pub strokes: Option<serde_json::Value>,
}

impl FileAnimation {
    /// The rate its keys were written at: the most common step between keys when it is a
    /// whole number of frames a second from 24 to 240 (faceanim and capture tools write one key
    /// per frame), else [`DEFAULT_FPS`] (keys set by hand, further apart, are played between).
    #[must_use]
    pub fn fps(&self) -> f32 {
        let longest = self.key_times().into_iter().max_by_key(|t| t.len());
        rate_of(longest.and_then(median_step))
    }

    /// The key times it is played by: its weights', or its turns' where it has no weights.
    fn key_times(&self) -> Vec<&[f32]> {
        if self.tracks.is_empty() {
            self.turns.iter().map(|t| t.times.as_slice()).collect()
        } else {
            self.tracks.iter().map(|t| t.times.as_slice()).collect()
        }
    }

    /// Its first key's time, seconds (Blender writes frame 1 at 1/fps).
    #[must_use]
    pub fn start(&self) -> f32 {
        self.key_times()
            .iter()
            .filter_map(|t| t.first().copied())
            .fold(f32::INFINITY, f32::min)
            .min(self.seconds())
    }

    /// Its last key's time, seconds.
    #[must_use]
    pub fn seconds(&self) -> f32 {
        self.key_times()
            .iter()
            .filter_map(|t| t.last().copied())
            .fold(0.0, f32::max)
    }

    /// Plays it at [`FileAnimation::fps`] from its first key to its last (as a take from 0),
    /// each blendshape read through the first of its `bindings` whose mesh the animation moves
    /// (0 where none is, or where an earlier blendshape already reads one of its targets: a
    /// VRM expression whose target is also the file's own raw shape).
    #[must_use]
    pub fn sample(&self, bindings: &[Vec<Binding>]) -> MorphAnimation {
        let fps = self.fps();
        let start = self.start();
        let frames = ((self.seconds() - start).min(MAX_SECONDS) * fps).round() as usize + 1;
        // Each morph target is read into one blendshape: the first that binds it (a raw
        // target's own, before the VRM expressions that bind it too), so that exporting the
        // take again gives each target the weight it had, not that weight twice.
        let mut claimed: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
        let reads: Vec<Option<(&WeightsTrack, usize, f32)>> = bindings
            .iter()
            .map(|binds| {
                if binds.iter().any(|b| claimed.contains(&(b.mesh, b.target))) {
                    return None;
                }
                let read = binds.iter().find_map(|b| {
                    let track = self.tracks.iter().find(|t| t.mesh == b.mesh)?;
                    (b.weight.abs() > 1e-6).then_some((track, b.target as usize, b.weight))
                });
                if read.is_some() {
                    claimed.extend(binds.iter().map(|b| (b.mesh, b.target)));
                }
                read
            })
            .collect();
        let times: Vec<f32> = (0..frames).map(|k| k as f32 / fps).collect();
        let weights = times
            .iter()
            .map(|&t| {
                reads
                    .iter()
                    .map(|read| {
                        read.map_or(0.0, |(track, target, weight)| {
                            (track.at(start + t, target) / weight).clamp(0.0, 1.0)
                        })
                    })
                    .collect()
            })
            .collect();
        MorphAnimation {
            name: self.name.clone(),
            times,
            weights,
            rotations: None,
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "keys and whole rates are exact")]
mod tests {
    use super::*;

    #[test]
    fn a_cubic_spline_passes_through_its_keys_and_follows_its_tangents() {
        // Value 0 then 1 with zero tangents: a smoothstep.
        let track = WeightsTrack::new(
            0,
            vec![0.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            1,
            Interpolation::CubicSpline,
        )
        .unwrap();
        assert_eq!(track.at(0.0, 0), 0.0);
        assert_eq!(track.at(1.0, 0), 1.0);
        assert!((track.at(0.5, 0) - 0.5).abs() < 1e-6);
        assert!((track.at(0.25, 0) - 0.15625).abs() < 1e-6);
    }

    #[test]
    fn steps_hold_and_the_rate_comes_from_the_keys() {
        let times: Vec<f32> = (0..25).map(|k| k as f32 / 24.0).collect();
        let values: Vec<f32> = (0..25).map(|k| (k % 2) as f32).collect();
        let track = WeightsTrack::new(3, times, values, 1, Interpolation::Step).unwrap();
        assert_eq!(track.at(0.5 / 24.0, 0), 0.0);
        assert_eq!(track.at(1.5 / 24.0, 0), 1.0);
        let animation = FileAnimation {
            name: "blink".into(),
            tracks: vec![track],
            ours: false,
            turns: vec![],
            strokes: None,
        };
        assert_eq!(animation.fps(), 24.0);
        // A VRM expression bound at 0.5: the target at 0.5 reads as the expression at 1.
        let played = animation.sample(&[
            vec![Binding {
                mesh: 3,
                target: 0,
                weight: 0.5,
            }],
            vec![],
        ]);
        assert_eq!(played.times.len(), 25);
        assert_eq!(played.weights[1], vec![1.0, 0.0]);
        assert_eq!(played.weights[2], vec![0.0, 0.0]);
        // A raw target and an expression binding it: the raw shape reads it, the expression
        // stays 0 (exported again, the target is not counted twice).
        let raw = Binding {
            mesh: 3,
            target: 0,
            weight: 1.0,
        };
        let played = animation.sample(&[vec![raw], vec![raw]]);
        assert_eq!(played.weights[1], vec![1.0, 0.0]);
    }

    #[test]
    fn rotations_turn_the_short_way_between_keys() {
        let half = std::f32::consts::FRAC_PI_2;
        let keys = [glam::Quat::IDENTITY, glam::Quat::from_rotation_y(half)];
        let linear = RotationTrack::new(
            4,
            vec![0.0, 1.0],
            keys.iter().map(|q| q.to_array()).collect(),
            Interpolation::Linear,
        )
        .unwrap();
        let mid = glam::Quat::from_rotation_y(half / 2.0);
        assert!(linear.at(0.5).angle_between(mid) < 1e-5);
        assert!(linear.at(2.0).angle_between(keys[1]) < 1e-6);
        // A cubic spline with zero tangents passes through its keys.
        let zero = [0.0; 4];
        let cubic = RotationTrack::new(
            4,
            vec![0.0, 1.0],
            vec![
                zero,
                keys[0].to_array(),
                zero,
                zero,
                keys[1].to_array(),
                zero,
            ],
            Interpolation::CubicSpline,
        )
        .unwrap();
        assert!(cubic.at(1.0).angle_between(keys[1]) < 1e-6);
        assert!(cubic.at(0.5).angle_between(mid) < 1e-3);
        assert!(RotationTrack::new(4, vec![0.0, 1.0], vec![zero], Interpolation::Step).is_err());
    }

    #[test]
    fn bad_tracks_are_refused_with_a_reason() {
        assert!(WeightsTrack::new(0, vec![], vec![], 1, Interpolation::Linear).is_err());
        let back = WeightsTrack::new(0, vec![0.0, 0.0], vec![0.0, 1.0], 1, Interpolation::Linear);
        assert!(back.unwrap_err().contains("key 1"));
        let short = WeightsTrack::new(0, vec![0.0, 1.0], vec![0.0], 1, Interpolation::Linear);
        assert!(short.unwrap_err().contains("1 weights for 2 keys"));
        let nan = WeightsTrack::new(0, vec![0.0], vec![f32::NAN], 1, Interpolation::Linear);
        assert!(nan.is_err());
    }
}
