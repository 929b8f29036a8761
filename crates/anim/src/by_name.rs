//! How a clip's columns reach a character's blendshapes by name ([`crate::Clip::retarget`]),
//! by the name table's rules ([`faceanim_rig::name_map`]), so that a clip goes onto any rig as
//! capture by name goes:
//!
//! 1. a column of a blendshape's exact name sets it, as written (a VRM preset's name in either
//!    version's spelling is its exact name: `Fun` sets a VRM avatar's `relaxed`);
//! 2. a vowel (VRM's `aa` or `A`, VRoid's `Fcl_MTH_A`, `viseme_aa`) sets the character's shapes
//!    that are that viseme; a character with none takes the channels the vowel is made of
//!    ([`faceanim_rig::names::VRM_PRESETS`]: `A` is `jawOpen`), where no column carries them,
//!    as it takes those of VRM's `surprised` (brows up, eyes wide) and `relaxed` (VRM 0.x's
//!    `Fun`: the cheeks) ([`faceanim_rig::names::stands_for`]);
//! 3. every other column is read as ARKit channels — one channel in any spelling, both of a
//!    merged pair (VRM's `happy` and `blink`, VRoid's `Fcl_EYE_Close`), the mean of split
//!    halves (ICT's `browInnerUp_L` and `_R`), ARKit's own spelling first where two columns
//!    are one channel — and the channels drive the character's shapes as capture by name
//!    drives them (0..1): both of ICT's halves, VRoid's `Fcl_MTH_Joy` from the two smiles; or,
//!    given the character's retarget map, as the map drives them (by name where the names
//!    say it, by geometry where they do not: a Live Link Face recording on a rig whose names
//!    say nothing).
//!
//! A shape a column sets by its exact name takes nothing else; a column that reaches no shape
//! (no meaning, or its shapes all set by exact names) is unmatched.

use faceanim_retarget::RetargetMap;
use faceanim_rig::Character;
use faceanim_rig::name_map::{Entry, NameMap, Use};
use faceanim_rig::names::{Channel, Drive, Expression, stands_for};

/// The routes of one clip's columns onto one character. See the module docs.
#[derive(Debug)]
pub(crate) struct Routes<'a> {
    /// Each column's shape of its exact name.
    exact: Vec<Option<usize>>,
    /// Vowel columns and the character's shapes that are the vowel.
    vowels: Vec<(usize, Vec<usize>)>,
    /// Columns that are no channel but stand for some (a vowel the character has no shape
    /// for, `surprised`, `relaxed`), and those channels.
    recipes: Vec<(usize, Vec<Channel>)>,
    /// The clip's names read as channels, exact and vowel columns left out.
    columns: NameMap,
    /// The character's shapes by the channels that drive them.
    character: NameMap,
    /// The character's retarget map, which drives them instead where given.
    map: Option<&'a RetargetMap>,
    /// Shapes a column sets itself (exact or vowel): no channel drives them.
    set: Vec<bool>,
    /// Whether each column reaches a shape.
    reaches: Vec<bool>,
}

impl<'a> Routes<'a> {
    /// The routes of columns `names` onto `character`, through `map` when given (and made for
    /// its shapes: one of another character is not used).
    pub(crate) fn new(
        names: &[String],
        character: &Character,
        map: Option<&'a RetargetMap>,
    ) -> Routes<'a> {
        let count = character.blendshapes().len();
        let map = map.filter(|m| m.blendshapes.len() == count);
        let own: std::collections::HashMap<&str, usize> = character
            .blendshapes()
            .iter()
            .enumerate()
            .map(|(i, b)| (b.name(), i))
            .collect();
        // A VRM preset by the other version's name (`Fun` for a VRM avatar's `relaxed`) is
        // its exact name, where no column is called that.
        let exact: Vec<Option<usize>> = names
            .iter()
            .map(|n| {
                own.get(n.as_str()).copied().or_else(|| {
                    faceanim_rig::names::vrm_preset(n)
                        .filter(|preset| !names.iter().any(|m| m == preset))
                        .and_then(|preset| own.get(preset).copied())
                })
            })
            .collect();
        let character_map = character.name_map();
        let viseme_of = |drive: Option<Drive>| match drive {
            Some(Drive::Expression(Expression::Viseme(v))) => Some(v),
            _ => None,
        };
        let mut set = vec![false; count];
        for &c in exact.iter().flatten() {
            set[c] = true;
        }
        let (mut vowels, mut recipes) = (Vec::new(), Vec::new());
        let mut blanked: Vec<String> = names.to_vec();
        for (k, name) in names.iter().enumerate() {
            if exact[k].is_some() {
                blanked[k].clear();
                continue;
            }
            let drive = faceanim_rig::names::drive(name);
            if let Some(viseme) = viseme_of(drive) {
                blanked[k].clear();
                let shapes: Vec<usize> = (character_map.entries().iter().enumerate())
                    .filter(|(i, e)| {
                        !set[*i] && viseme_of(e.map(|e: Entry| e.drive)) == Some(viseme)
                    })
                    .map(|(i, _)| i)
                    .collect();
                if shapes.is_empty() {
                    recipes.push((k, stands_for(name)));
                } else {
                    vowels.push((k, shapes));
                }
            } else if matches!(drive, None | Some(Drive::Expression(_))) {
                // A name of no channel that stands for some (`surprised`, `relaxed`) sets them.
                let channels = stands_for(name);
                if !channels.is_empty() {
                    blanked[k].clear();
                    recipes.push((k, channels));
                }
            }
        }
        for (_, shapes) in &vowels {
            for &i in shapes {
                set[i] = true;
            }
        }
        let columns = NameMap::from_names(&blanked, &[]);
        // The channels that drive a shape no column sets itself.
        let mut reachable = vec![false; Channel::all().len()];
        match map {
            Some(map) => {
                for (c, reached) in reachable.iter_mut().enumerate() {
                    *reached = (map.answers(c).iter())
                        .any(|(shape, _)| own.get(shape).is_some_and(|&i| !set[i]));
                }
            }
            None => {
                for (i, drive) in character_map.driven_drives() {
                    if !set[i] {
                        for c in drive.channels() {
                            reachable[c.index()] = true;
                        }
                    }
                }
            }
        }
        let reaches_any = |channels: &[Channel]| channels.iter().any(|c| reachable[c.index()]);
        let reaches = (0..names.len())
            .map(|k| {
                exact[k].is_some()
                    || vowels.iter().any(|(v, _)| *v == k)
                    || recipes
                        .iter()
                        .any(|(r, channels)| *r == k && reaches_any(channels))
                    // An expression of several channels gives no channel values itself.
                    || matches!(
                        columns.entries()[k],
                        Some(Entry { drive, used: Use::Driven })
                            if !matches!(drive, Drive::Expression(_)) && reaches_any(&drive.channels())
                    )
            })
            .collect();
        Routes {
            exact,
            vowels,
            recipes,
            columns,
            character: character_map,
            map,
            set,
            reaches,
        }
    }

    /// Whether column `k` reaches a shape.
    pub(crate) fn reaches(&self, k: usize) -> bool {
        self.reaches.get(k).copied().unwrap_or(false)
    }

    /// The character's weights for one clip row.
    pub(crate) fn weights(&self, row: &[f32]) -> Vec<f32> {
        let value = |k: usize| row.get(k).copied().unwrap_or(0.0);
        let mut channels = self.columns.channel_values(row);
        for (k, stood_for) in &self.recipes {
            for c in stood_for {
                channels[c.index()].get_or_insert(value(*k));
            }
        }
        let mut weights = match self.map {
            Some(map) => {
                let values: Vec<f32> = channels.iter().map(|v| v.unwrap_or(0.0)).collect();
                map.weights(&values)
            }
            None => self.character.weights_from_channels(|name| {
                Channel::named(name)
                    .and_then(|c| channels[c.index()])
                    .unwrap_or(0.0)
            }),
        };
        for (w, set) in weights.iter_mut().zip(&self.set) {
            if *set {
                *w = 0.0;
            }
        }
        for (k, shapes) in &self.vowels {
            for &i in shapes {
                weights[i] = value(*k);
            }
        }
        for (k, shape) in self.exact.iter().enumerate() {
            if let Some(i) = shape {
                weights[*i] = value(k);
            }
        }
        weights
    }
}
