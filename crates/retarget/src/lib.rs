//! # faceanim-retarget: ARKit's channels onto any character's own shapes
//!
//! MediaPipe, phone trackers, VMC senders and lip sync all speak ARKit's 52 channels. A
//! character speaks its own blendshapes, whatever they are called. A [`RetargetMap`] is the
//! bridge, one per character, kept beside it as `NAME.retarget.json` (readable rows a user may
//! edit):
//!
//! - **by name** where the names say it ([`faceanim_rig::name_map`]: `eyeBlinkLeft`,
//!   `browInnerUp_L`, VRoid's `Fcl_EYE_Close_L`, a merged `mouthSmile`): each such shape takes
//!   its channel's value, as capture by name always did;
//! - **by geometry** for the channels the names leave out: a template head's shape for the
//!   channel, moved onto the character's vertices (`faceanim-fit` makes the map), is matched by
//!   the character's own shapes in a bounded, sparse least-squares sense. Per frame
//!   ([`Solve`]), the channels' combined displacement is matched at once, so a shape that is
//!   several channels together (VRoid's `Fcl_MTH_A`: jaw and lips) answers to the combination;
//!   the [`Row`]s keep each channel's own fit, to show and to edit;
//! - **by the user** where a row was overridden: that channel moves the shapes the row lists,
//!   and nothing else.
//!
//! MediaPipe's scores move with a face but do not reach an artist's weights: a blink the
//! character makes fully may read 0.6. A [`Calibration`] measured on the character's own
//! renders turns each score into the channel value that makes the character look so.
//!
//! ```
//! use faceanim_retarget::{RetargetMap, RowSource, channel_index};
//! let names: Vec<String> = ["jawOpen", "smile_both"].map(String::from).to_vec();
//! let mut map = RetargetMap::by_name("head", &names, &[]);
//! // The by-name row drives jawOpen; no name says what smile_both is: a user says so.
//! map.set_row("mouthSmileLeft", [("smile_both".to_owned(), 0.5)].into())?;
//! map.set_row("mouthSmileRight", [("smile_both".to_owned(), 0.5)].into())?;
//! let mut channels = [0.0; 52];
//! channels[channel_index("jawOpen").unwrap()] = 0.7;
//! channels[channel_index("mouthSmileLeft").unwrap()] = 0.8;
//! channels[channel_index("mouthSmileRight").unwrap()] = 0.6;
//! let weights = map.weights(&channels);
//! assert!((weights[0] - 0.7).abs() < 1e-6 && (weights[1] - 0.7).abs() < 1e-6);
//! assert_eq!(map.rows[channel_index("mouthSmileLeft").unwrap()].from, RowSource::User);
//! let back = RetargetMap::from_json(map.to_json().as_bytes(), &names)?;
//! assert_eq!(back.weights(&channels), weights);
//! # Ok::<(), faceanim_retarget::RetargetError>(())
//! ```
#![deny(missing_docs)]

mod calibration;
mod solve;

use std::collections::BTreeMap;

use faceanim_rig::name_map::{Entry, Use};
use faceanim_rig::names::{ARKIT_52, Channel, Drive};
use serde::{Deserialize, Serialize};

pub use calibration::{Calibration, Curve, MAX_GAIN, MIN_RESPONSE};
pub use solve::Solve;

/// ARKit's channels, in Apple's order ([`ARKIT_52`]).
pub const CHANNELS: usize = ARKIT_52.len();

/// The file format's version.
pub const VERSION: u32 = 1;

/// The index of ARKit channel `name` (canonical spelling) in [`ARKIT_52`].
#[must_use]
pub fn channel_index(name: &str) -> Option<usize> {
    ARKIT_52.iter().position(|n| *n == name)
}

/// Why a map could not be read or changed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RetargetError {
    /// Not JSON, or not a retarget map (its message names the field).
    #[error("not a retarget map: {0}")]
    Format(String),
    /// Values that cannot be used, each with its JSON path.
    #[error("invalid retarget map: {}", .0.join("; "))]
    Invalid(Vec<String>),
    /// A map made for another character (other shapes).
    #[error("the retarget map is for {map} ({shapes} shapes), not this character: make it again")]
    OtherCharacter {
        /// The character the map was made for.
        map: String,
        /// How many shapes it had.
        shapes: usize,
    },
    /// A row edit names a channel or a shape that does not exist, or a weight out of range.
    #[error("{0}")]
    Edit(String),
}

/// Where a channel's row comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RowSource {
    /// The character's shapes named for the channel.
    ByName,
    /// The character's shapes that move its face as the template's shape for the channel does.
    Geometry,
    /// The user's choice, kept when the map is made again.
    User,
    /// Nothing of the character answers to it.
    None,
}

/// One ARKit channel's own shapes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Row {
    /// The channel (ARKit's spelling).
    pub channel: String,
    /// Where the row comes from.
    pub from: RowSource,
    /// The character's shapes answering to the channel at 1, with their weights.
    pub shapes: BTreeMap<String, f32>,
    /// For a geometric row: the share of the channel's displacement the shapes reproduce (the
    /// rest has no shape of the character's to go to).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explained: Option<f32>,
    /// For a geometric row: made together with its twin on the other side of the face, of the
    /// shapes that move both sides at once, each side at half (see [`Fitted::with_twin`]);
    /// [`Row::explained`] is then the pair's.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub with_twin: bool,
}

/// One channel's fit by geometry, as the map's maker gives it ([`RetargetMap::set_geometry`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// The channel's index in [`ARKIT_52`].
    pub channel: usize,
    /// The shapes that make it, with their weights (none: nothing of the character does).
    pub shapes: BTreeMap<String, f32>,
    /// The share of the channel's displacement they reproduce.
    pub explained: f32,
    /// Whether it was made with its twin ([`Channel::twin`]): a channel of one side that no
    /// shape of one side makes, matched with its twin's displacement among the shapes that
    /// move both sides (`Fcl_BRW_Angry` for `browDownLeft` and `browDownRight`), each side's
    /// row half of that match and `explained` the pair's.
    pub with_twin: bool,
}

/// How the geometric channels reach the shapes: the per-frame solve, or each channel's row
/// added up (chosen when the map is made; see [`RetargetMap::mode`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Every frame's channels matched at once by a bounded least-squares solve.
    #[default]
    Frame,
    /// Each channel's row, weighted by its value, added.
    Matrix,
}

/// How the map was made, for `faceanim info` and the studio.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Made {
    /// The template registered onto the character (none for a map by name alone).
    pub template: Option<String>,
    /// Face landmarks that landed on both the character and the template.
    pub landmarks: Option<usize>,
    /// Mean distance of the registered template from the character's surface, as a share of
    /// the character's size.
    pub residual: Option<f32>,
    /// Seconds it took, calibration included.
    pub seconds: Option<f32>,
    /// faceanim's version.
    pub by: String,
}

/// ARKit's channels onto one character's shapes. See the crate docs.
#[derive(Debug, Clone, PartialEq)]
pub struct RetargetMap {
    /// The character's name.
    pub character: String,
    /// The character's shapes, in its order (what [`RetargetMap::weights`] returns).
    pub blendshapes: Vec<String>,
    /// One row per channel, in [`ARKIT_52`]'s order.
    pub rows: Vec<Row>,
    /// The per-frame solve over the shapes no name claims, when some channel needs geometry.
    pub solve: Option<Solve>,
    /// How geometric channels reach the shapes.
    pub mode: Mode,
    /// MediaPipe's response to each channel on the character, when measured.
    pub calibration: Option<Calibration>,
    /// How it was made.
    pub made: Made,
    /// Each row's shapes as indices, resolved once.
    resolved: Vec<Vec<(usize, f32)>>,
    /// The solve's shapes and channels as indices.
    solve_shapes: Vec<usize>,
    solve_channels: Vec<usize>,
}

/// The file as written.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    version: u32,
    character: String,
    blendshapes: Vec<String>,
    rows: Vec<Row>,
    #[serde(default)]
    mode: Mode,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    solve: Option<Solve>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    calibration: Option<Calibration>,
    #[serde(default)]
    made: Made,
}

impl RetargetMap {
    /// The map by name alone of a character called `character` with these `blendshapes` (and
    /// `parts`: each VRM expression's bound shapes, see
    /// [`faceanim_rig::Character::expression_parts`]): each channel's row holds the shapes its
    /// name drives; the others have none yet.
    #[must_use]
    pub fn by_name(character: &str, blendshapes: &[String], parts: &[Vec<usize>]) -> RetargetMap {
        let name_map = faceanim_rig::name_map::NameMap::from_names(blendshapes, parts);
        let mut rows: Vec<Row> = ARKIT_52
            .iter()
            .map(|c| Row {
                channel: (*c).to_owned(),
                from: RowSource::None,
                shapes: BTreeMap::new(),
                explained: None,
                with_twin: false,
            })
            .collect();
        for (i, drive) in name_map.driven_drives() {
            let parts: Vec<(Channel, f32)> = match drive {
                Drive::Channel(c) | Drive::Split(c, _) => vec![(c, 1.0)],
                Drive::Merge(a, b) => vec![(a, 0.5), (b, 0.5)],
                // Expressions (visemes, `surprised`) are several channels at once: geometry
                // places them.
                Drive::Expression(_) => continue,
            };
            for (c, w) in parts {
                let row = &mut rows[c.index()];
                row.from = RowSource::ByName;
                row.shapes.insert(blendshapes[i].clone(), w);
            }
        }
        RetargetMap::assemble(MapFile {
            version: VERSION,
            character: character.to_owned(),
            blendshapes: blendshapes.to_vec(),
            rows,
            mode: Mode::Frame,
            solve: None,
            calibration: None,
            made: Made {
                by: concat!("faceanim ", env!("CARGO_PKG_VERSION")).to_owned(),
                ..Made::default()
            },
        })
    }

    /// The shapes no name claims: the ones geometry may use. Shapes driven by name, their
    /// duplicates, and VRM expressions (whose bound shapes are in the list themselves) are
    /// left out, so that nothing moves twice.
    #[must_use]
    pub fn free_shapes(blendshapes: &[String], parts: &[Vec<usize>]) -> Vec<usize> {
        let name_map = faceanim_rig::name_map::NameMap::from_names(blendshapes, parts);
        (0..blendshapes.len())
            .filter(|&i| parts.get(i).is_none_or(Vec::is_empty))
            .filter(|&i| match name_map.entries()[i] {
                None => true,
                Some(Entry {
                    drive: Drive::Expression(_),
                    used: Use::Driven | Use::NoReading,
                }) => true,
                Some(_) => false,
            })
            .collect()
    }

    /// Channels with no row yet (neither by name nor by the user): the ones geometry is asked
    /// for.
    #[must_use]
    pub fn unanswered(&self) -> Vec<usize> {
        (0..CHANNELS)
            .filter(|&c| {
                self.rows[c].from == RowSource::None || self.rows[c].from == RowSource::Geometry
            })
            .collect()
    }

    /// Puts the geometric part in: each channel's own fit, the per-frame `solve`, and the
    /// `mode` chosen. Rows by name or set by the user stay.
    pub fn set_geometry(&mut self, rows: Vec<Fitted>, solve: Option<Solve>, mode: Mode) {
        for Fitted {
            channel: c,
            shapes,
            explained,
            with_twin,
        } in rows
        {
            let row = &mut self.rows[c];
            if matches!(row.from, RowSource::ByName | RowSource::User) {
                continue;
            }
            row.from = if shapes.is_empty() {
                RowSource::None
            } else {
                RowSource::Geometry
            };
            row.with_twin = with_twin && !shapes.is_empty();
            row.shapes = shapes;
            row.explained = Some(explained);
        }
        self.solve = solve;
        self.mode = mode;
        self.resolve();
    }

    /// Overrides `channel`'s row with `shapes` (name → weight in 0..=1): the user's choice,
    /// which the channel then moves alone. An empty `shapes` makes the channel move nothing.
    ///
    /// # Errors
    /// [`RetargetError::Edit`] for an unknown channel or shape, or a weight out of range.
    pub fn set_row(
        &mut self,
        channel: &str,
        shapes: BTreeMap<String, f32>,
    ) -> Result<(), RetargetError> {
        let c = channel_index(channel)
            .or_else(|| faceanim_rig::names::arkit_name(channel).and_then(channel_index))
            .ok_or_else(|| {
                RetargetError::Edit(format!(
                    "'{}' is not one of ARKit's 52 channels",
                    faceanim_rig::excerpt(channel)
                ))
            })?;
        for (name, w) in &shapes {
            if !self.blendshapes.contains(name) {
                return Err(RetargetError::Edit(format!(
                    "{}: {} has no shape '{}'",
                    ARKIT_52[c],
                    self.character,
                    faceanim_rig::excerpt(name)
                )));
            }
            if !(0.0..=1.0).contains(w) {
                return Err(RetargetError::Edit(format!(
                    "{}.{}: {w} is outside 0..1",
                    ARKIT_52[c],
                    faceanim_rig::excerpt(name)
                )));
            }
        }
        let row = &mut self.rows[c];
        row.from = RowSource::User;
        row.shapes = shapes;
        row.explained = None;
        row.with_twin = false;
        self.resolve();
        Ok(())
    }

    /// The character's weights for ARKit channel `values` (in [`ARKIT_52`]'s order, each in
    /// 0..=1, or up to its [`RetargetMap::reach`] where calibration took it past 1), each in
    /// 0..=1.
    #[must_use]
    pub fn weights(&self, values: &[f32]) -> Vec<f32> {
        let mut out = vec![0.0; self.blendshapes.len()];
        let value = |c: usize| {
            let v = values.get(c).copied().unwrap_or(0.0).max(0.0);
            if v > 1.0 { v.min(self.reach(c)) } else { v }
        };
        for (c, row) in self.rows.iter().enumerate() {
            let linear = match row.from {
                RowSource::ByName | RowSource::User => true,
                // A geometric row the solve does not take (a channel with a shape of its own)
                // is driven as a named one is.
                RowSource::Geometry => {
                    self.mode == Mode::Matrix || !self.solve_channels.contains(&c)
                }
                RowSource::None => false,
            };
            if linear {
                let v = value(c);
                for &(i, w) in &self.resolved[c] {
                    out[i] += v * w;
                }
            }
        }
        if let (Mode::Frame, Some(solve)) = (self.mode, &self.solve) {
            // Channels a user took over are theirs alone.
            let channel_values: Vec<f32> = self
                .solve_channels
                .iter()
                .map(|&c| {
                    if self.rows[c].from == RowSource::Geometry {
                        value(c)
                    } else {
                        0.0
                    }
                })
                .collect();
            for (k, x) in solve.weights(&channel_values).into_iter().enumerate() {
                out[self.solve_shapes[k]] += x;
            }
        }
        for w in &mut out {
            *w = w.clamp(0.0, 1.0);
        }
        out
    }

    /// The channel whose row `channel`'s was made with: its twin on the other side of the
    /// face ([`Channel::twin`]) where the geometric fit matched the two together among the
    /// shapes that move both sides ([`Row::with_twin`]: `Fcl_BRW_Angry` for both
    /// `browDownLeft` and `browDownRight` on a rig whose names say nothing, each at half).
    /// Such a channel is calibrated with its twin raised too (alone it moves its shape half
    /// way, and the score of that half would be taken for the whole), and its row's share
    /// explained is the pair's.
    ///
    /// Rows by name are not: a name that merges the two sides (`Fcl_MTH_Joy` read as both
    /// smiles) is calibrated side by side, as by-name channels always were (shown with their
    /// twins, the tests' VRoid-style avatar by its own names followed people's mouth corners
    /// less: 0.72 → 0.53 and 0.40 → 0.22 on two videos); nor is a row the user set, nor one
    /// fitted alone that happens to take a shape of both sides.
    ///
    /// ```
    /// use faceanim_retarget::{Fitted, Mode, RetargetMap, RowSource, channel_index};
    /// let names: Vec<String> = ["shape_0", "shape_1", "shape_2", "Fcl_MTH_Joy"]
    ///     .map(String::from)
    ///     .to_vec();
    /// let mut map = RetargetMap::by_name("head", &names, &[]);
    /// let index = |name: &str| channel_index(name).unwrap();
    /// let row = |channel: &str, shape: &str, weight: f32, with_twin: bool| Fitted {
    ///     channel: index(channel),
    ///     shapes: [(shape.to_owned(), weight)].into(),
    ///     explained: 0.9,
    ///     with_twin,
    /// };
    /// map.set_geometry(
    ///     vec![
    ///         row("browDownLeft", "shape_0", 0.5, true),
    ///         row("browDownRight", "shape_0", 0.5, true),
    ///         row("eyeBlinkLeft", "shape_1", 1.0, false),
    ///         row("eyeBlinkRight", "shape_2", 1.0, false),
    ///     ],
    ///     None,
    ///     Mode::Matrix,
    /// );
    /// assert_eq!(map.shares_with_twin(index("browDownLeft")), Some(index("browDownRight")));
    /// assert_eq!(map.shares_with_twin(index("browDownRight")), Some(index("browDownLeft")));
    /// assert_eq!(map.shares_with_twin(index("eyeBlinkLeft")), None);
    /// assert_eq!(map.shares_with_twin(index("jawOpen")), None);
    /// // VRoid's smile, read by name as both smiles.
    /// assert_eq!(map.rows[index("mouthSmileLeft")].from, RowSource::ByName);
    /// assert_eq!(map.shares_with_twin(index("mouthSmileLeft")), None);
    /// // The user's row is theirs.
    /// map.set_row("browDownLeft", [("shape_0".to_owned(), 0.8)].into())?;
    /// assert_eq!(map.shares_with_twin(index("browDownLeft")), None);
    /// # Ok::<(), faceanim_retarget::RetargetError>(())
    /// ```
    #[must_use]
    pub fn shares_with_twin(&self, channel: usize) -> Option<usize> {
        let row = self.rows.get(channel)?;
        if row.from != RowSource::Geometry || !row.with_twin {
            return None;
        }
        Some(Channel::named(&row.channel)?.twin()?.index())
    }

    /// How far `channel`'s value may go ([`RetargetMap::weights`] takes values up to it): 1,
    /// or, for a calibrated channel made by geometry that drives a shape of its own by its row
    /// (its strongest: no other row moves it), past 1 until that shape reaches 1; for one made
    /// with its twin ([`RetargetMap::shares_with_twin`]: one shape for both sides), until the
    /// two together move it fully, each side alone half.
    ///
    /// Such a row says how much of the character's shape makes the template's channel: an ICT
    /// head's blink is 0.67–0.82 of its own `eyeBlink_R` (its eye is larger than the
    /// template's), so at 1 the channel left the eye a third open, and a person's full blink,
    /// however far the calibration's gain took it, stopped there. A calibrated channel's value
    /// is measured on the character's own renders, not in the template's units: it may close
    /// the eye the character's artist made. A channel sharing its strongest shape otherwise (a
    /// merged name's, another channel's, the per-frame solve's) stays within 1.
    ///
    /// ```
    /// use faceanim_retarget::{Calibration, Curve, Fitted, Mode, RetargetMap, channel_index};
    /// let names: Vec<String> = ["shape_0", "shape_1", "shape_2"].map(String::from).to_vec();
    /// let mut map = RetargetMap::by_name("head", &names, &[]);
    /// let index = |name: &str| channel_index(name).unwrap();
    /// let row = |channel: &str, shape: &str, weight: f32| Fitted {
    ///     channel: index(channel),
    ///     shapes: [(shape.to_owned(), weight)].into(),
    ///     explained: 0.9,
    ///     with_twin: false,
    /// };
    /// let mut rows = vec![
    ///     row("eyeBlinkRight", "shape_0", 0.67),
    ///     row("eyeBlinkLeft", "shape_1", 0.8),
    ///     // One shape lowers both brows, each side's row half of it and a little less.
    ///     row("browDownLeft", "shape_2", 0.4),
    ///     row("browDownRight", "shape_2", 0.4),
    /// ];
    /// rows[2].with_twin = true;
    /// rows[3].with_twin = true;
    /// map.set_geometry(rows, None, Mode::Matrix);
    /// let curve = Curve { rises: vec![0.0, 0.4], values: vec![0.0, 1.0] };
    /// let mut calibration = Calibration::default();
    /// for channel in ["eyeBlinkRight", "browDownLeft", "browDownRight"] {
    ///     calibration.channels.insert(channel.to_owned(), curve.clone());
    /// }
    /// map.calibration = Some(calibration);
    /// assert!((map.reach(index("eyeBlinkRight")) - 1.0 / 0.67).abs() < 1e-5);
    /// // Not calibrated: its value's scale is the template's.
    /// assert_eq!(map.reach(index("eyeBlinkLeft")), 1.0);
    /// assert!((map.reach(index("browDownLeft")) - 1.0 / 0.8).abs() < 1e-5);
    /// let mut values = [0.0; 52];
    /// values[index("eyeBlinkRight")] = 2.0;
    /// values[index("eyeBlinkLeft")] = 2.0;
    /// values[index("browDownLeft")] = 2.0;
    /// assert_eq!(map.weights(&values), [1.0, 0.8, 0.5]);
    /// values[index("browDownRight")] = 2.0;
    /// assert_eq!(map.weights(&values), [1.0, 0.8, 1.0]);
    /// ```
    #[must_use]
    pub fn reach(&self, channel: usize) -> f32 {
        let Some(row) = self.rows.get(channel) else {
            return 1.0;
        };
        let calibrated = self
            .calibration
            .as_ref()
            .is_some_and(|k| k.channels.contains_key(&row.channel));
        let in_solve = self.mode == Mode::Frame && self.solve_channels.contains(&channel);
        if row.from != RowSource::Geometry || !calibrated || in_solve {
            return 1.0;
        }
        // Its strongest shape, which no other row (nor the solve) moves but its twin's, where
        // the two were made together: then both together reach 1.
        let Some(&(strongest, weight)) = self.resolved[channel]
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            return 1.0;
        };
        let twin = self.shares_with_twin(channel);
        let on = |d: usize| {
            self.resolved[d]
                .iter()
                .find(|&&(i, _)| i == strongest)
                .map(|&(_, w)| w)
        };
        let shared = (0..self.rows.len())
            .any(|d| d != channel && Some(d) != twin && on(d).is_some())
            || self.solve_shapes.contains(&strongest);
        let together = weight + twin.and_then(on).unwrap_or(0.0);
        if shared || together <= 0.0 {
            1.0
        } else {
            (1.0 / together).max(1.0)
        }
    }

    /// Which shapes answer to `channel` (its row), strongest first.
    #[must_use]
    pub fn answers(&self, channel: usize) -> Vec<(&str, f32)> {
        let mut shapes: Vec<(&str, f32)> = self.rows[channel]
            .shapes
            .iter()
            .map(|(n, w)| (n.as_str(), *w))
            .collect();
        shapes.sort_by(|a, b| b.1.total_cmp(&a.1));
        shapes
    }

    /// How many channels reach at least one shape.
    #[must_use]
    pub fn answered(&self) -> usize {
        self.rows.iter().filter(|r| !r.shapes.is_empty()).count()
    }

    /// The map as its file's JSON (pretty, so rows can be read and edited).
    #[must_use]
    pub fn to_json(&self) -> String {
        let file = MapFile {
            version: VERSION,
            character: self.character.clone(),
            blendshapes: self.blendshapes.clone(),
            rows: self.rows.clone(),
            mode: self.mode,
            solve: self.solve.clone(),
            calibration: self.calibration.clone(),
            made: self.made.clone(),
        };
        serde_json::to_string_pretty(&file).unwrap_or_default()
    }

    /// Reads a map file made for a character with these `blendshapes`.
    ///
    /// # Errors
    /// [`RetargetError::Format`] naming the field of a malformed file,
    /// [`RetargetError::Invalid`] with every bad value's path, or
    /// [`RetargetError::OtherCharacter`] when the map's shapes are not the character's.
    pub fn from_json(bytes: &[u8], blendshapes: &[String]) -> Result<RetargetMap, RetargetError> {
        let file: MapFile = faceanim_rig::json::from_slice(bytes)
            .map_err(|e| RetargetError::Format(e.to_string()))?;
        let problems = problems(&file);
        if !problems.is_empty() {
            return Err(RetargetError::Invalid(problems));
        }
        if file.blendshapes != blendshapes {
            return Err(RetargetError::OtherCharacter {
                map: faceanim_rig::excerpt(&file.character).into_owned(),
                shapes: file.blendshapes.len(),
            });
        }
        Ok(RetargetMap::assemble(file))
    }

    fn assemble(file: MapFile) -> RetargetMap {
        let mut map = RetargetMap {
            character: file.character,
            blendshapes: file.blendshapes,
            rows: file.rows,
            solve: file.solve,
            mode: file.mode,
            calibration: file.calibration,
            made: file.made,
            resolved: Vec::new(),
            solve_shapes: Vec::new(),
            solve_channels: Vec::new(),
        };
        map.resolve();
        map
    }

    /// Names to indices (the file's names were checked).
    fn resolve(&mut self) {
        let index = |name: &str| self.blendshapes.iter().position(|b| b == name);
        self.resolved = self
            .rows
            .iter()
            .map(|row| {
                row.shapes
                    .iter()
                    .filter_map(|(n, w)| index(n).map(|i| (i, *w)))
                    .collect()
            })
            .collect();
        if let Some(solve) = &self.solve {
            self.solve_shapes = solve.shapes.iter().filter_map(|n| index(n)).collect();
            self.solve_channels = solve
                .channels
                .iter()
                .filter_map(|c| channel_index(c))
                .collect();
        }
    }
}

/// Every problem of a map file, with its path.
fn problems(file: &MapFile) -> Vec<String> {
    let mut problems = Vec::new();
    if file.version != VERSION {
        problems.push(format!(
            "version: {} is not supported ({VERSION} is)",
            file.version
        ));
    }
    if file.rows.len() != CHANNELS {
        problems.push(format!(
            "rows: {} rows, one per ARKit channel ({CHANNELS}) is needed",
            file.rows.len()
        ));
    }
    for (k, row) in file.rows.iter().enumerate() {
        if ARKIT_52.get(k) != Some(&row.channel.as_str()) {
            problems.push(format!(
                "rows[{k}].channel: '{}' where {} belongs",
                faceanim_rig::excerpt(&row.channel),
                ARKIT_52.get(k).unwrap_or(&"nothing")
            ));
        }
        for (name, w) in &row.shapes {
            if !file.blendshapes.contains(name) {
                problems.push(format!(
                    "rows[{k}].shapes: no shape '{}'",
                    faceanim_rig::excerpt(name)
                ));
            } else if !(0.0..=1.0).contains(w) {
                problems.push(format!(
                    "rows[{k}].shapes.{}: {w} is outside 0..1",
                    faceanim_rig::excerpt(name)
                ));
            }
        }
    }
    if let Some(solve) = &file.solve {
        problems.extend(solve.problems(&file.blendshapes));
    }
    if let Some(calibration) = &file.calibration {
        problems.extend(calibration.problems());
    }
    problems.truncate(12);
    problems
}
