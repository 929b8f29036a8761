//! The 15 visemes put on a character's own shapes.
//!
//! - A rig with viseme shapes (Ready Player Me's `viseme_*`, VRM's `aa ih ou ee oh`, VRoid's
//!   `Fcl_MTH_A…O`, at least five of them) gets them by name ([`Route::Visemes`]); a viseme it
//!   lacks borrows from those it has ([`VOWEL_FALLBACK`]: a rig of five vowels shows an S as a
//!   little "ih").
//! - Otherwise a rig whose names carry ARKit's mouth channels (ARKit itself, ICT, Character
//!   Creator, Daz…) gets each viseme as a mix of those channels ([`MouthTable`], which the user
//!   may replace: `faceanim lipsync --viseme-table FILE`), through the one name table
//!   ([`NameMap`](faceanim_rig::name_map::NameMap)) capture uses ([`Route::Arkit`]).
//! - A rig with neither has no mouth to drive by name ([`MouthError::NoMouth`]).
//! - A body with no blendshapes at all opens its jaw bone ([`Route::JawBone`]), or has nothing
//!   to lip-sync ([`MouthError::NoShapes`]).

use std::collections::BTreeMap;

use faceanim_rig::Character;
use faceanim_rig::names::{Drive, Expression, Viseme, drive};
use serde::{Deserialize, Serialize};

use crate::visemes::index;

/// How visemes reach the character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// Its own viseme shapes, by name.
    Visemes,
    /// Its ARKit mouth channels, through the viseme table.
    Arkit,
    /// Its own shapes, as its adapter reads renders of the built-in head making each viseme
    /// ([`Mouth::from_readings`]): for a rig whose names say nothing of a mouth.
    Adapter,
    /// Its own shapes, as its retarget map puts each viseme's ARKit channels on them
    /// ([`Mouth::through_map`]): for a rig whose names say nothing of a mouth, by geometry.
    Retarget,
    /// None of its shapes (it has none): its jaw bone, turned by each viseme's `jawOpen`
    /// ([`Mouth::jaw_bone`], with the take's ARKit values from [`Mouth::arkit`]).
    JawBone,
}

/// Why a character's mouth cannot be driven.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MouthError {
    /// Neither viseme shapes nor ARKit mouth channels.
    #[error(
        "{0} has neither viseme shapes (viseme_aa, aa/ih/ou/ee/oh, Fcl_MTH_A…) nor ARKit mouth shapes (jawOpen, mouthFunnel…) to lip-sync; make its retarget map (faceanim retarget, or Make map in the studio) and lip sync reaches its shapes by geometry"
    )]
    NoMouth(String),
    /// No blendshapes at all, and no jaw bone.
    #[error(
        "{0} has no blendshapes and no jaw bone to lip-sync: make ARKit's 52 shapes on it with `faceanim generate-shapes` (Generate blendshapes in the studio), then lip-sync that"
    )]
    NoShapes(String),
    /// A viseme table is malformed.
    #[error("viseme table: {0}")]
    Table(String),
}

/// Each viseme as ARKit channel values: the default lip-sync look on ARKit rigs.
pub const ARKIT_TABLE: [(Viseme, &[(&str, f32)]); 14] = [
    (
        Viseme::PP,
        &[
            ("mouthPressLeft", 0.6),
            ("mouthPressRight", 0.6),
            ("mouthRollLower", 0.3),
            ("mouthRollUpper", 0.2),
        ],
    ),
    (
        Viseme::FF,
        &[
            ("mouthRollLower", 0.6),
            ("mouthUpperUpLeft", 0.25),
            ("mouthUpperUpRight", 0.25),
            ("jawOpen", 0.05),
        ],
    ),
    (
        Viseme::TH,
        &[
            ("jawOpen", 0.15),
            ("tongueOut", 0.4),
            ("mouthStretchLeft", 0.1),
            ("mouthStretchRight", 0.1),
        ],
    ),
    (
        Viseme::DD,
        &[
            ("jawOpen", 0.2),
            ("mouthStretchLeft", 0.15),
            ("mouthStretchRight", 0.15),
        ],
    ),
    (
        Viseme::Kk,
        &[
            ("jawOpen", 0.25),
            ("mouthStretchLeft", 0.1),
            ("mouthStretchRight", 0.1),
        ],
    ),
    (
        Viseme::CH,
        &[
            ("jawOpen", 0.1),
            ("mouthFunnel", 0.5),
            ("mouthPucker", 0.2),
            ("mouthUpperUpLeft", 0.2),
            ("mouthUpperUpRight", 0.2),
        ],
    ),
    (
        Viseme::SS,
        &[
            ("jawOpen", 0.05),
            ("mouthStretchLeft", 0.35),
            ("mouthStretchRight", 0.35),
            ("mouthSmileLeft", 0.1),
            ("mouthSmileRight", 0.1),
        ],
    ),
    (
        Viseme::Nn,
        &[
            ("jawOpen", 0.15),
            ("mouthStretchLeft", 0.1),
            ("mouthStretchRight", 0.1),
        ],
    ),
    (
        Viseme::RR,
        &[
            ("jawOpen", 0.15),
            ("mouthFunnel", 0.35),
            ("mouthPucker", 0.25),
        ],
    ),
    (
        Viseme::Aa,
        &[
            ("jawOpen", 0.65),
            ("mouthLowerDownLeft", 0.3),
            ("mouthLowerDownRight", 0.3),
        ],
    ),
    (
        Viseme::E,
        &[
            ("jawOpen", 0.35),
            ("mouthStretchLeft", 0.35),
            ("mouthStretchRight", 0.35),
            ("mouthLowerDownLeft", 0.2),
            ("mouthLowerDownRight", 0.2),
        ],
    ),
    (
        Viseme::Ih,
        &[
            ("jawOpen", 0.2),
            ("mouthStretchLeft", 0.4),
            ("mouthStretchRight", 0.4),
            ("mouthSmileLeft", 0.15),
            ("mouthSmileRight", 0.15),
        ],
    ),
    (Viseme::Oh, &[("jawOpen", 0.45), ("mouthFunnel", 0.6)]),
    (
        Viseme::Ou,
        &[
            ("jawOpen", 0.15),
            ("mouthPucker", 0.8),
            ("mouthFunnel", 0.3),
        ],
    ),
];

/// What a viseme the rig lacks borrows from the vowels it has.
pub const VOWEL_FALLBACK: [(Viseme, &[(Viseme, f32)]); 9] = [
    (Viseme::PP, &[]),
    (Viseme::FF, &[(Viseme::Ih, 0.2)]),
    (Viseme::TH, &[(Viseme::Ih, 0.2), (Viseme::Aa, 0.1)]),
    (Viseme::DD, &[(Viseme::Ih, 0.3)]),
    (Viseme::Kk, &[(Viseme::Aa, 0.3)]),
    (Viseme::CH, &[(Viseme::Ou, 0.3), (Viseme::Ih, 0.2)]),
    (Viseme::SS, &[(Viseme::Ih, 0.4)]),
    (Viseme::Nn, &[(Viseme::Ih, 0.2), (Viseme::Aa, 0.1)]),
    (Viseme::RR, &[(Viseme::Ou, 0.4)]),
];

/// Visemes as ARKit channel values: [`ARKIT_TABLE`] or the user's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MouthTable {
    /// Per viseme name (`PP`, `aa`…), channel name → value in 0..1.
    pub visemes: BTreeMap<String, BTreeMap<String, f32>>,
}

impl Default for MouthTable {
    fn default() -> MouthTable {
        MouthTable {
            visemes: ARKIT_TABLE
                .iter()
                .map(|(v, channels)| {
                    (
                        v.name().to_owned(),
                        channels
                            .iter()
                            .map(|(c, w)| ((*c).to_owned(), *w))
                            .collect(),
                    )
                })
                .collect(),
        }
    }
}

impl MouthTable {
    /// Viseme `v` as ARKit's 52 channels ([`faceanim_rig::names::ARKIT_52`] order); `None`
    /// for silence and a viseme the table leaves out.
    fn arkit_of(&self, v: Viseme) -> Option<Vec<f32>> {
        let channels = self.visemes.get(v.name()).filter(|_| v != Viseme::Sil)?;
        Some(
            faceanim_rig::names::ARKIT_52
                .iter()
                .map(|c| channels.get(*c).copied().unwrap_or(0.0))
                .collect(),
        )
    }

    /// A table from JSON: `{"aa": {"jawOpen": 0.7}, "PP": {"mouthClose": 0.5}}`; visemes left
    /// out keep the default's.
    ///
    /// # Errors
    /// [`MouthError::Table`] naming the field that is wrong.
    pub fn from_json(text: &str) -> Result<MouthTable, MouthError> {
        let given: BTreeMap<String, BTreeMap<String, f32>> =
            faceanim_rig::json::from_slice(text.as_bytes()).map_err(|e| {
                MouthError::Table(format!("not a table of viseme → channel → value: {e}"))
            })?;
        let mut table = MouthTable::default();
        for (viseme, channels) in given {
            if !Viseme::ALL.iter().any(|v| v.name() == viseme) || viseme == Viseme::Sil.name() {
                return Err(MouthError::Table(format!(
                    "{}: not one of the visemes {}",
                    faceanim_rig::excerpt(&viseme),
                    Viseme::ALL[1..]
                        .iter()
                        .map(|v| v.name())
                        .collect::<Vec<_>>()
                        .join(" ")
                )));
            }
            for (channel, value) in &channels {
                if faceanim_rig::names::Channel::named(channel).is_none() {
                    return Err(MouthError::Table(format!(
                        "{viseme}.{}: not an ARKit channel",
                        faceanim_rig::excerpt(channel)
                    )));
                }
                if !(0.0..=1.0).contains(value) {
                    return Err(MouthError::Table(format!(
                        "{viseme}.{}: {value} is not in 0..1",
                        faceanim_rig::excerpt(channel)
                    )));
                }
            }
            table.visemes.insert(viseme, channels);
        }
        Ok(table)
    }
}

/// An adapter's reading under this is left out of a viseme read through it.
pub const MIN_READING: f32 = 0.08;

/// Viseme weights to a character's blendshape weights.
#[derive(Debug, Clone)]
pub struct Mouth {
    /// How.
    pub route: Route,
    shapes: usize,
    /// Per viseme (Oculus order): (blendshape, weight) pairs it moves.
    per_viseme: Vec<Vec<(usize, f32)>>,
}

impl Mouth {
    /// The mouth of `character`, with `table` for ARKit rigs.
    ///
    /// # Errors
    /// [`MouthError::NoMouth`] when it has neither visemes nor ARKit mouth shapes;
    /// [`MouthError::NoShapes`] when it has no shapes at all and no jaw bone.
    pub fn of(character: &Character, table: &MouthTable) -> Result<Mouth, MouthError> {
        let shapes = character.blendshapes().len();
        if shapes == 0 {
            let jaw = character
                .source()
                .and_then(|s| s.bones().get(faceanim_rig::bones::Bone::Jaw));
            return match jaw {
                Some(_) => Ok(Mouth::jaw_bone()),
                None => Err(MouthError::NoShapes(character.name().to_owned())),
            };
        }
        let parts = character.expression_parts();
        // Per viseme, the shape that is it: one with its own targets before a VRM expression
        // bound to others (VRM's aa bound to Fcl_MTH_A moves the same vertices).
        let mut own: Vec<Option<usize>> = vec![None; Viseme::ALL.len()];
        for (i, b) in character.blendshapes().iter().enumerate() {
            if let Some(Drive::Expression(Expression::Viseme(v))) = drive(b.name()) {
                let slot = &mut own[index(v)];
                let better = match *slot {
                    None => true,
                    Some(j) => !parts[j].is_empty() && parts[i].is_empty(),
                };
                if better {
                    *slot = Some(i);
                }
            }
        }
        let present = own[1..].iter().flatten().count();
        if present >= 5 {
            let per_viseme = Viseme::ALL
                .iter()
                .map(|&v| match own[index(v)] {
                    Some(i) if v != Viseme::Sil => vec![(i, 1.0)],
                    _ => VOWEL_FALLBACK
                        .iter()
                        .find(|(w, _)| *w == v)
                        .map(|(_, mix)| {
                            mix.iter()
                                .filter_map(|(vowel, w)| own[index(*vowel)].map(|i| (i, *w)))
                                .collect()
                        })
                        .unwrap_or_default(),
                })
                .collect();
            return Ok(Mouth {
                route: Route::Visemes,
                shapes,
                per_viseme,
            });
        }
        let map = character.name_map();
        let undriven = map.undriven_channels();
        if undriven.iter().any(|c| c.name() == "jawOpen") {
            return Err(MouthError::NoMouth(character.name().to_owned()));
        }
        let per_viseme = Viseme::ALL
            .iter()
            .map(|v| {
                let Some(channels) = table.visemes.get(v.name()) else {
                    return Vec::new();
                };
                let weights =
                    map.weights_from_channels(|c| channels.get(c).copied().unwrap_or(0.0));
                weights
                    .into_iter()
                    .enumerate()
                    .filter(|(_, w)| *w > 0.0)
                    .collect()
            })
            .collect();
        Ok(Mouth {
            route: Route::Arkit,
            shapes,
            per_viseme,
        })
    }

    /// Each viseme (Oculus order) as `performer`'s weights, by [`Mouth::of`]: what the
    /// performer (the built-in head) does to make it; silence is its rest.
    ///
    /// # Errors
    /// [`MouthError::NoMouth`] when the performer has no mouth either.
    pub fn performer_rows(
        performer: &Character,
        table: &MouthTable,
    ) -> Result<Vec<Vec<f32>>, MouthError> {
        let mouth = Mouth::of(performer, table)?;
        Ok((0..Viseme::ALL.len())
            .map(|v| {
                let mut one = [0.0f32; 15];
                if v > 0 {
                    one[v] = 1.0;
                }
                mouth.weights(&one)
            })
            .collect())
    }

    /// A mouth through `map` (the character's retarget map, see `faceanim-retarget`): each
    /// viseme's ARKit channel values in `table` put on the character's own shapes by the
    /// map's rows (by name where its names say, by geometry where they do not).
    #[must_use]
    pub fn through_map(map: &faceanim_retarget::RetargetMap, table: &MouthTable) -> Mouth {
        let per_viseme = Viseme::ALL
            .iter()
            .map(|v| {
                let Some(values) = table.arkit_of(*v) else {
                    return Vec::new();
                };
                map.weights(&values)
                    .into_iter()
                    .enumerate()
                    .filter(|(_, w)| *w >= MIN_READING)
                    .collect()
            })
            .collect();
        Mouth {
            route: Route::Retarget,
            shapes: map.blendshapes.len(),
            per_viseme,
        }
    }

    /// Each viseme (Oculus order) as ARKit's 52 channels ([`faceanim_rig::names::ARKIT_52`]
    /// order) by `table`: what a take's ARKit values are, whatever the character's shapes — Live
    /// Link Face's curves, and the jaw bone's `jawOpen`.
    #[must_use]
    pub fn arkit(table: &MouthTable) -> Mouth {
        let per_viseme = Viseme::ALL
            .iter()
            .map(|v| {
                table.arkit_of(*v).map_or_else(Vec::new, |values| {
                    values
                        .into_iter()
                        .enumerate()
                        .filter(|(_, w)| *w > 0.0)
                        .collect()
                })
            })
            .collect();
        Mouth {
            route: Route::Arkit,
            shapes: faceanim_rig::names::ARKIT_52.len(),
            per_viseme,
        }
    }

    /// The mouth of a character with `shapes` shapes whose retarget map is still being made
    /// ([`Route::Retarget`]): it moves none of them until [`Mouth::through_map`] of the map
    /// takes its place; the take's ARKit values ([`Mouth::arkit`]) are read as they come.
    #[must_use]
    pub fn before_map(shapes: usize) -> Mouth {
        Mouth {
            route: Route::Retarget,
            shapes,
            per_viseme: vec![Vec::new(); Viseme::ALL.len()],
        }
    }

    /// The mouth of a character with no shapes but a jaw bone ([`Route::JawBone`]): it moves
    /// none of its (no) shapes; the take's ARKit values ([`Mouth::arkit`]) turn the bone.
    #[must_use]
    pub fn jaw_bone() -> Mouth {
        Mouth {
            route: Route::JawBone,
            shapes: 0,
            per_viseme: vec![Vec::new(); Viseme::ALL.len()],
        }
    }

    /// Whether any viseme moves a shape.
    #[must_use]
    pub fn moves(&self) -> bool {
        self.per_viseme.iter().any(|pairs| !pairs.is_empty())
    }

    /// A mouth from `readings`: per viseme (Oculus order), the character's weights as its
    /// adapter read the performer making it ([`Mouth::performer_rows`]). Readings under
    /// [`MIN_READING`] are left out (the adapter's noise, not the mouth).
    #[must_use]
    pub fn from_readings(shapes: usize, readings: &[Vec<f32>]) -> Mouth {
        Mouth {
            route: Route::Adapter,
            shapes,
            per_viseme: readings
                .iter()
                .enumerate()
                .map(|(v, row)| {
                    row.iter()
                        .enumerate()
                        .filter(|(i, w)| v > 0 && *i < shapes && **w >= MIN_READING)
                        .map(|(i, w)| (i, w.min(1.0)))
                        .collect()
                })
                .collect(),
        }
    }

    /// The character's weights for viseme weights `visemes` (Oculus order), each clamped to
    /// 0..1.
    #[must_use]
    pub fn weights(&self, visemes: &[f32; 15]) -> Vec<f32> {
        let mut out = vec![0.0f32; self.shapes];
        for (w, pairs) in visemes.iter().zip(&self.per_viseme) {
            if *w > 0.0 {
                for &(i, k) in pairs {
                    out[i] += w * k;
                }
            }
        }
        out.iter_mut().for_each(|w| *w = w.clamp(0.0, 1.0));
        out
    }

    /// How many of the character's shapes lip sync moves.
    #[must_use]
    pub fn moved(&self) -> usize {
        let mut seen = vec![false; self.shapes];
        for pairs in &self.per_viseme {
            for &(i, _) in pairs {
                seen[i] = true;
            }
        }
        seen.iter().filter(|s| **s).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_head_takes_visemes_through_its_arkit_shapes() {
        let head = faceanim_head::default_character();
        let mouth = Mouth::of(&head, &MouthTable::default()).unwrap();
        assert_eq!(mouth.route, Route::Arkit);
        let mut aa = [0.0; 15];
        aa[index(Viseme::Aa)] = 1.0;
        let weights = mouth.weights(&aa);
        let jaw = head.find_blendshape("jawOpen").unwrap().index();
        assert!((weights[jaw] - 0.65).abs() < 1e-6);
        assert!(mouth.moved() >= 10);
    }

    #[test]
    fn a_table_is_checked_field_by_field() {
        let t = MouthTable::from_json(r#"{"aa": {"jawOpen": 0.9}}"#).unwrap();
        assert!((t.visemes["aa"]["jawOpen"] - 0.9).abs() < 1e-6);
        assert_eq!(t.visemes["PP"].len(), 4);
        for (json, says) in [
            (r#"{"zz": {}}"#, "zz: not one of the visemes"),
            (
                r#"{"aa": {"jawOpened": 1}}"#,
                "aa.jawOpened: not an ARKit channel",
            ),
            (r#"{"aa": {"jawOpen": 2}}"#, "aa.jawOpen: 2 is not in 0..1"),
            ("[", "not a table"),
        ] {
            let e = MouthTable::from_json(json).unwrap_err().to_string();
            assert!(e.contains(says), "{json}: {e}");
        }
    }
}
