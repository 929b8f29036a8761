//! Which of a character's blendshapes ARKit's channels drive by name, and how: the one rule that
//! capture by name, live streaming's `--names arkit|vrm`, the Live Link export and
//! `faceanim info` share.
//!
//! Each name is read through [`crate::names::drive`]. A rig may name one motion twice — a VRoid
//! avatar has `Fcl_EYE_Close_L` and the VRM expression `blinkLeft` bound to it, a Ready Player
//! Me avatar has `jawOpen` and `viseme_aa` — and a face must never move twice for one channel,
//! so, in the blendshapes' order:
//!
//! 1. a shape that is one channel is driven unless another shape already is that channel,
//!    ARKit's own spelling first (`eyeBlinkLeft` before VRoid's `Fcl_EYE_Close_L`, whatever the
//!    order); one side of a channel ARKit does not split (`browInnerUp_L`) is driven unless the
//!    rig also has the whole channel under ARKit's name (`browInnerUp`), and a synonym
//!    (VRoid's `Fcl_BRW_Sorrow`) gives way to those halves;
//! 2. a shape merging a left/right pair is driven unless both channels already drive shapes of
//!    their own (VRoid's `Fcl_EYE_Close` beside `Fcl_EYE_Close_L` and `_R`);
//! 3. an expression (a viseme, `surprised`) is driven only when none of the channels it reads
//!    drives a shape directly (Ready Player Me's `viseme_aa` beside `jawOpen` is left to lip
//!    sync);
//! 4. a VRM expression that binds morph targets which are blendshapes driven by name is not
//!    driven itself (its targets already move).
//!
//! ```
//! use faceanim_rig::name_map::{NameMap, Use};
//!
//! let names: Vec<String> = ["browInnerUp_L", "browInnerUp_R", "jawOpen", "viseme_aa", "Fcl_ALL_Joy"]
//!     .map(String::from)
//!     .to_vec();
//! let map = NameMap::from_names(&names, &[]);
//! // ARKit's single browInnerUp drives both of ICT's halves; viseme_aa is left to lip sync.
//! let weights = map.weights_from_channels(|c| if c == "browInnerUp" { 0.8 } else { 0.0 });
//! assert_eq!(weights, vec![0.8, 0.8, 0.0, 0.0, 0.0]);
//! assert_eq!(map.entries()[3].as_ref().map(|e| e.used), Some(Use::Covered));
//! assert!(map.entries()[4].is_none());
//! ```

use crate::names::{Channel, Drive, drive};

/// Whether a shape with a meaning is driven by name, and if not, why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Use {
    /// Driven by its channels.
    Driven,
    /// An earlier blendshape (its index) is the same channel and is driven instead.
    Duplicate(usize),
    /// The channels it reads already drive other blendshapes directly.
    Covered,
    /// A VRM expression whose bound targets are driven by name themselves.
    TargetsDriven,
    /// Its name has a meaning the face's channels give no reading of (most visemes: lip sync
    /// drives those).
    NoReading,
}

/// One blendshape's meaning and use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// What its name means in ARKit's channels.
    pub drive: Drive,
    /// Whether capture by name drives it.
    pub used: Use,
}

/// A character's blendshapes against ARKit's channels. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct NameMap {
    entries: Vec<Option<Entry>>,
}

impl NameMap {
    /// The map of blendshapes called `names`; `parts[i]` lists the blendshapes whose morph
    /// targets blendshape `i` binds when it is a VRM expression (empty or missing otherwise).
    #[must_use]
    pub fn from_names(names: &[String], parts: &[Vec<usize>]) -> NameMap {
        let drives: Vec<Option<Drive>> = names.iter().map(|n| drive(n)).collect();
        let is_expression = |i: usize| parts.get(i).is_some_and(|p| !p.is_empty());
        let mut entries: Vec<Option<Entry>> = vec![None; names.len()];
        // Channels that drive a shape directly, with the shape.
        let mut direct: Vec<Option<usize>> = vec![None; Channel::all().len()];
        let mut merged: Vec<(Channel, Channel, usize)> = Vec::new();
        let mut expressions: Vec<(crate::names::Expression, usize)> = Vec::new();
        // Raw shapes first, then the VRM expressions (which bind raw shapes).
        let order: Vec<usize> = (0..names.len())
            .filter(|&i| !is_expression(i))
            .chain((0..names.len()).filter(|&i| is_expression(i)))
            .collect();
        // Pass 1: shapes that are one channel, or one half of one, in three rounds: ARKit's own
        // names for a channel first, then the halves of split channels (which give way to
        // ARKit's whole channel: a rig with browInnerUp and browInnerUp_L/_R moves it once),
        // then every other spelling (ICT's eyeBlink_L, VRoid's Fcl_EYE_Close_L, its
        // Fcl_BRW_Sorrow), each giving way to a shape that already has its channel.
        let spelled = |i: usize, c: Channel| crate::names::spells(&names[i], c);
        for &i in &order {
            if let Some(d @ Drive::Channel(c)) = drives[i]
                && spelled(i, c)
            {
                let used = claim(&mut direct, c, i);
                entries[i] = Some(Entry { drive: d, used });
            }
        }
        let whole = direct.clone();
        for &i in &order {
            if let Some(d @ Drive::Split(c, _)) = drives[i] {
                let used = match whole[c.index()] {
                    Some(first) => Use::Duplicate(first),
                    None => {
                        direct[c.index()].get_or_insert(i);
                        Use::Driven
                    }
                };
                entries[i] = Some(Entry { drive: d, used });
            }
        }
        for &i in &order {
            if let Some(d @ Drive::Channel(c)) = drives[i]
                && !spelled(i, c)
            {
                let used = claim(&mut direct, c, i);
                entries[i] = Some(Entry { drive: d, used });
            }
        }
        // Pass 2: merges and expressions, which give way to the direct channels.
        for &i in &order {
            let Some(d) = drives[i] else { continue };
            let used = match d {
                Drive::Merge(a, b) => {
                    if direct[a.index()].is_some() && direct[b.index()].is_some() {
                        Use::Covered
                    } else if let Some(&(_, _, first)) =
                        merged.iter().find(|(x, y, _)| (*x, *y) == (a, b))
                    {
                        Use::Duplicate(first)
                    } else {
                        merged.push((a, b, i));
                        Use::Driven
                    }
                }
                Drive::Expression(e) => {
                    let channels = d.channels();
                    if channels.is_empty() {
                        Use::NoReading
                    } else if channels.iter().any(|c| {
                        direct[c.index()].is_some()
                            || merged.iter().any(|(x, y, _)| x == c || y == c)
                    }) {
                        Use::Covered
                    } else if let Some(&(_, first)) = expressions.iter().find(|(x, _)| *x == e) {
                        Use::Duplicate(first)
                    } else {
                        expressions.push((e, i));
                        Use::Driven
                    }
                }
                _ => continue,
            };
            entries[i] = Some(Entry { drive: d, used });
        }
        // Pass 3: a VRM expression whose targets already move by name.
        for i in (0..names.len()).filter(|&i| is_expression(i)) {
            let targets_driven = parts[i].iter().any(|&p| {
                p != i
                    && entries
                        .get(p)
                        .copied()
                        .flatten()
                        .is_some_and(|e| e.used == Use::Driven)
            });
            if let Some(entry) = entries[i].as_mut()
                && entry.used == Use::Driven
                && targets_driven
            {
                entry.used = Use::TargetsDriven;
            }
        }
        NameMap { entries }
    }

    /// Each blendshape's meaning and use (`None`: its name means nothing to ARKit).
    #[must_use]
    pub fn entries(&self) -> &[Option<Entry>] {
        &self.entries
    }

    /// How many blendshapes are driven.
    #[must_use]
    pub fn driven(&self) -> usize {
        self.entries
            .iter()
            .flatten()
            .filter(|e| e.used == Use::Driven)
            .count()
    }

    /// The blendshapes' weights from ARKit channel values (`value(name)`, in [0, 1]); 0 for the
    /// ones not driven.
    #[must_use]
    pub fn weights_from_channels(&self, value: impl Fn(&str) -> f32) -> Vec<f32> {
        self.entries
            .iter()
            .map(|e| match e {
                Some(Entry {
                    drive,
                    used: Use::Driven,
                }) => drive.from_channels(&value).unwrap_or(0.0),
                _ => 0.0,
            })
            .collect()
    }

    /// Each blendshape capture by name drives, with what its name means: (index, drive).
    pub fn driven_drives(&self) -> impl Iterator<Item = (usize, Drive)> + '_ {
        self.entries
            .iter()
            .enumerate()
            .filter_map(|(i, e)| match e {
                Some(Entry {
                    drive,
                    used: Use::Driven,
                }) => Some((i, *drive)),
                _ => None,
            })
    }

    /// ARKit's 52 channel values read back from the blendshapes' `weights` (`None` where no
    /// driven shape carries the channel): a channel's own shape gives its weight; the halves
    /// of a split channel give their mean; a merged shape gives its weight to both channels it
    /// merges, where neither has a shape of its own.
    #[must_use]
    pub fn channel_values(&self, weights: &[f32]) -> Vec<Option<f32>> {
        let mut direct: Vec<Option<f32>> = vec![None; Channel::all().len()];
        let mut split: Vec<(f32, u32)> = vec![(0.0, 0); Channel::all().len()];
        let mut merged: Vec<Option<f32>> = vec![None; Channel::all().len()];
        for (i, drive) in self.driven_drives() {
            let w = weights.get(i).copied().unwrap_or(0.0);
            match drive {
                Drive::Channel(c) => direct[c.index()] = Some(w),
                Drive::Split(c, _) => {
                    let s = &mut split[c.index()];
                    s.0 += w;
                    s.1 += 1;
                }
                Drive::Merge(a, b) => {
                    merged[a.index()] = Some(w);
                    merged[b.index()] = Some(w);
                }
                Drive::Expression(_) => {}
            }
        }
        (0..direct.len())
            .map(|c| {
                direct[c]
                    .or_else(|| (split[c].1 > 0).then(|| split[c].0 / split[c].1 as f32))
                    .or(merged[c])
            })
            .collect()
    }

    /// [`NameMap::channel_values`] as a row of ARKit's 52 values in their order, a channel no
    /// driven shape carries at 0 (a clip's row as a phone would have sent it).
    #[must_use]
    pub fn arkit_row(&self, weights: &[f32]) -> Vec<f32> {
        self.channel_values(weights)
            .into_iter()
            .map(|v| v.unwrap_or(0.0))
            .collect()
    }

    /// ARKit channels that drive none of the blendshapes.
    #[must_use]
    pub fn undriven_channels(&self) -> Vec<Channel> {
        let mut reached = vec![false; Channel::all().len()];
        for entry in self.entries.iter().flatten() {
            if entry.used == Use::Driven {
                for c in entry.drive.channels() {
                    reached[c.index()] = true;
                }
            }
        }
        Channel::all().filter(|c| !reached[c.index()]).collect()
    }
}

/// Channel `c` for shape `i`: driven if no shape has it yet, else a duplicate of the one that has.
fn claim(direct: &mut [Option<usize>], c: Channel, i: usize) -> Use {
    match direct[c.index()] {
        Some(first) => Use::Duplicate(first),
        None => {
            direct[c.index()] = Some(i);
            Use::Driven
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "values copied exactly")]
mod tests {
    use super::*;
    use crate::names::{Expression, Viseme};

    fn map(names: &[&str]) -> NameMap {
        let names: Vec<String> = names.iter().map(|n| (*n).to_owned()).collect();
        NameMap::from_names(&names, &[])
    }

    #[test]
    fn a_vroid_face_moves_each_eye_once() {
        let m = map(&[
            "Fcl_EYE_Close",
            "Fcl_EYE_Close_R",
            "Fcl_EYE_Close_L",
            "Fcl_MTH_A",
            "Fcl_ALL_Joy",
        ]);
        let used: Vec<Option<Use>> = m.entries().iter().map(|e| e.map(|e| e.used)).collect();
        assert_eq!(
            used,
            [
                Some(Use::Covered),
                Some(Use::Driven),
                Some(Use::Driven),
                Some(Use::Driven),
                None
            ]
        );
        let w = m.weights_from_channels(|c| match c {
            "eyeBlinkLeft" => 1.0,
            "jawOpen" => 0.5,
            _ => 0.0,
        });
        assert_eq!(w, vec![0.0, 0.0, 1.0, 0.5, 0.0]);
    }

    #[test]
    fn a_ready_player_me_viseme_gives_way_to_the_jaw() {
        let m = map(&["jawOpen", "viseme_aa", "viseme_PP"]);
        assert_eq!(m.entries()[1].map(|e| e.used), Some(Use::Covered));
        assert_eq!(
            m.entries()[2],
            Some(Entry {
                drive: Drive::Expression(Expression::Viseme(Viseme::PP)),
                used: Use::NoReading
            })
        );
    }

    #[test]
    fn a_vrm_expression_bound_to_a_driven_target_is_not_driven_again() {
        let names: Vec<String> = [
            "Fcl_EYE_Close_L",
            "Fcl_EYE_Close_R",
            "blinkLeft",
            "aa",
            "Fcl_MTH_A",
        ]
        .map(String::from)
        .to_vec();
        let parts = vec![vec![], vec![], vec![0], vec![4], vec![]];
        let m = NameMap::from_names(&names, &parts);
        assert_eq!(m.entries()[2].map(|e| e.used), Some(Use::Duplicate(0)));
        assert_eq!(m.entries()[3].map(|e| e.used), Some(Use::Duplicate(4)));
        assert_eq!(m.entries()[4].map(|e| e.used), Some(Use::Driven));
    }

    #[test]
    fn a_whole_channel_beside_its_halves_moves_once() {
        let m = map(&["browInnerUp_L", "browInnerUp", "browInnerUp_R"]);
        let used: Vec<Option<Use>> = m.entries().iter().map(|e| e.map(|e| e.used)).collect();
        assert_eq!(
            used,
            [
                Some(Use::Duplicate(1)),
                Some(Use::Driven),
                Some(Use::Duplicate(1))
            ]
        );
    }

    #[test]
    fn channels_read_back_from_splits_and_merges() {
        let m = map(&["browInnerUp_L", "browInnerUp_R", "mouthSmile", "jawOpen"]);
        let values = m.channel_values(&[0.2, 0.6, 0.5, 0.9]);
        let get = |name: &str| values[Channel::named(name).unwrap().index()];
        assert!((get("browInnerUp").unwrap() - 0.4).abs() < 1e-6);
        assert_eq!(get("mouthSmileLeft"), Some(0.5));
        assert_eq!(get("jawOpen"), Some(0.9));
        assert_eq!(get("cheekPuff"), None);
        // As a row of ARKit's 52: the same values in ARKIT_52's order, 0 where none.
        let row = m.arkit_row(&[0.2, 0.6, 0.5, 0.9]);
        let at = |name: &str| {
            row[crate::names::ARKIT_52
                .iter()
                .position(|n| *n == name)
                .unwrap()]
        };
        assert_eq!((row.len(), at("jawOpen"), at("cheekPuff")), (52, 0.9, 0.0));
        assert!((at("browInnerUp") - 0.4).abs() < 1e-6);
        assert!(
            m.undriven_channels()
                .iter()
                .any(|c| c.name() == "cheekPuff")
        );
        assert!(
            !m.undriven_channels()
                .iter()
                .any(|c| c.name() == "browInnerUp")
        );
    }
}
