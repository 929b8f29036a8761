//! Which names a performer sends: the character's own, ARKit's 52, or VRM 0.x's presets.

/// The names blendshapes are sent under.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Names {
    /// The character's own blendshape names (for a marionette showing the same character).
    #[default]
    Own,
    /// ARKit's 52 names, capitalised as perfect-sync avatars and Live Link name them
    /// (`EyeBlinkLeft`), for the character's ARKit-named shapes.
    Arkit,
    /// VRM 0.x's preset expressions ([`VRM_PRESETS`]), each made from the character's
    /// ARKit-named shapes — the vowels from its shapes named for them where it has those
    /// ([`VRM_VOWELS`]) — for apps that only know those.
    VrmPresets,
}

pub use faceanim_rig::names::{VRM_PRESETS, VRM_VOWELS};

/// How one sent value is made from the character's weights: a weighted sum of blendshapes
/// (one shape; the halves of a split channel; the mean of a preset's channels), or the
/// smallest of several such sums (`Blink`, so that a wink is not a blink).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Source {
    /// Σ weight × the blendshape's weight.
    Sum(Vec<(usize, f32)>),
    /// The smallest of these sums.
    Min(Vec<Vec<(usize, f32)>>),
}

impl Source {
    pub(crate) fn value(&self, weights: &[f32]) -> f32 {
        let sum = |terms: &[(usize, f32)]| {
            terms
                .iter()
                .map(|&(i, w)| w * weights.get(i).copied().unwrap_or(0.0))
                .sum::<f32>()
        };
        match self {
            Source::Sum(terms) => sum(terms),
            Source::Min(list) => list.iter().map(|t| sum(t)).fold(f32::INFINITY, f32::min),
        }
    }
}

impl Names {
    /// What it is called in messages.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Names::Own => "blendshapes",
            Names::Arkit => "blendshapes named for ARKit channels",
            Names::VrmPresets => {
                "blendshapes named for ARKit channels or VRM's vowels to make VRM presets from"
            }
        }
    }

    /// The sent names for a character with blendshapes `names` and how each value is made
    /// (empty when none applies). ARKit channels are read back from the character's shapes by
    /// [`faceanim_rig::name_map`]'s rule (a split channel from the mean of its halves, a merged
    /// shape for both of its channels).
    pub(crate) fn table(self, names: &[String]) -> Vec<(String, Source)> {
        let channels = channel_terms(names);
        let terms = |arkit: &str| {
            faceanim_rig::names::Channel::named(arkit).and_then(|c| channels[c.index()].clone())
        };
        match self {
            Names::Own => names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), Source::Sum(vec![(i, 1.0)])))
                .collect(),
            Names::Arkit => faceanim_rig::names::ARKIT_52
                .iter()
                .filter_map(|&arkit| Some((capitalised(arkit), Source::Sum(terms(arkit)?))))
                .collect(),
            Names::VrmPresets => VRM_PRESETS
                .iter()
                .filter_map(|&(preset, shapes)| {
                    // A vowel from the shapes that are its viseme, where there are any.
                    let vowel = VRM_VOWELS.iter().find(|(v, _)| *v == preset);
                    if let Some(terms) = vowel.and_then(|&(_, viseme)| viseme_terms(names, viseme))
                    {
                        return Some((preset.to_owned(), Source::Sum(terms)));
                    }
                    let found: Vec<Vec<(usize, f32)>> =
                        shapes.iter().filter_map(|s| terms(s)).collect();
                    if found.len() != shapes.len() {
                        return None;
                    }
                    let source = if preset == "Blink" {
                        Source::Min(found)
                    } else {
                        let share = 1.0 / found.len() as f32;
                        Source::Sum(
                            found
                                .into_iter()
                                .flatten()
                                .map(|(i, w)| (i, w * share))
                                .collect(),
                        )
                    };
                    Some((preset.to_owned(), source))
                })
                .collect(),
        }
    }
}

/// For each ARKit channel, the blendshapes that carry it, weighted: its own shape; else the
/// halves of a split channel, half each; else a shape that merges it with its partner.
fn channel_terms(names: &[String]) -> Vec<Option<Vec<(usize, f32)>>> {
    use faceanim_rig::name_map::Use;
    use faceanim_rig::names::Drive;
    let map = faceanim_rig::name_map::NameMap::from_names(names, &[]);
    let count = faceanim_rig::names::Channel::all().len();
    let mut own: Vec<Option<usize>> = vec![None; count];
    let mut halves: Vec<Vec<usize>> = vec![Vec::new(); count];
    let mut merged: Vec<Option<usize>> = vec![None; count];
    for (i, entry) in map.entries().iter().enumerate() {
        let Some(entry) = entry.filter(|e| e.used == Use::Driven) else {
            continue;
        };
        match entry.drive {
            Drive::Channel(c) => own[c.index()] = Some(i),
            Drive::Split(c, _) => halves[c.index()].push(i),
            Drive::Merge(a, b) => {
                merged[a.index()] = Some(i);
                merged[b.index()] = Some(i);
            }
            _ => {}
        }
    }
    (0..count)
        .map(|c| {
            if let Some(i) = own[c] {
                Some(vec![(i, 1.0)])
            } else if !halves[c].is_empty() {
                let share = 1.0 / halves[c].len() as f32;
                Some(halves[c].iter().map(|&i| (i, share)).collect())
            } else {
                merged[c].map(|i| vec![(i, 1.0)])
            }
        })
        .collect()
}

/// The character's shapes that are `viseme` by name (and drive it: a VRM expression that
/// gives way to the targets it binds does not), each at weight 1; `None` when it has none.
fn viseme_terms(
    names: &[String],
    viseme: faceanim_rig::names::Viseme,
) -> Option<Vec<(usize, f32)>> {
    use faceanim_rig::name_map::Use;
    use faceanim_rig::names::{Drive, Expression};
    let map = faceanim_rig::name_map::NameMap::from_names(names, &[]);
    let terms: Vec<(usize, f32)> = map
        .entries()
        .iter()
        .enumerate()
        .filter(|(_, entry)| {
            entry.is_some_and(|e| {
                e.used == Use::Driven && e.drive == Drive::Expression(Expression::Viseme(viseme))
            })
        })
        .map(|(i, _)| (i, 1.0))
        .collect();
    (!terms.is_empty()).then_some(terms)
}

/// `eyeBlinkLeft` → `EyeBlinkLeft`.
fn capitalised(name: &str) -> String {
    let mut chars = name.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_uppercase().chain(chars).collect()
    })
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "means of exact binary fractions")]
mod tests {
    use super::*;

    #[test]
    fn split_channels_are_sent_as_their_halves_mean() {
        let names: Vec<String> = ["browInnerUp_L", "browInnerUp_R", "mouthSmile", "jawOpen"]
            .map(String::from)
            .to_vec();
        let table = Names::Arkit.table(&names);
        let value = |name: &str| {
            table
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, s)| s.value(&[0.2, 0.6, 0.5, 0.9]))
        };
        assert!((value("BrowInnerUp").unwrap_or(0.0) - 0.4).abs() < 1e-6);
        assert_eq!(value("MouthSmileLeft"), Some(0.5));
        assert_eq!(value("JawOpen"), Some(0.9));
        assert_eq!(value("CheekPuff"), None);
    }

    /// VRoid's vowels are VRM's vowel presets, sent from the shapes themselves (not from
    /// ARKit channels VRoid does not have); its blinks from its merged and one-sided lids.
    #[test]
    fn vowels_come_from_the_shapes_named_for_them() {
        let names: Vec<String> = [
            "Fcl_MTH_A",
            "Fcl_MTH_I",
            "Fcl_MTH_U",
            "Fcl_MTH_E",
            "Fcl_MTH_O",
            "Fcl_EYE_Close_L",
            "Fcl_EYE_Close_R",
            "viseme_aa",
        ]
        .map(String::from)
        .to_vec();
        let table = Names::VrmPresets.table(&names);
        let weights = [0.25, 0.5, 0.125, 0.75, 1.0, 1.0, 0.5, 0.5];
        let value = |name: &str| {
            table
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, s)| s.value(&weights))
        };
        // Two shapes named for aa: the first drives it, as capture and lip sync drive it (the
        // name table's rule: nothing moves twice).
        assert_eq!(value("A"), Some(0.25));
        assert_eq!(value("I"), Some(0.5));
        assert_eq!(value("U"), Some(0.125));
        assert_eq!(value("E"), Some(0.75));
        assert_eq!(value("O"), Some(1.0));
        assert_eq!(value("Blink"), Some(0.5));
        assert_eq!(value("Blink_L"), Some(1.0));
        assert_eq!(value("Joy"), None);
    }

    #[test]
    fn each_naming_covers_the_default_head() {
        let character = faceanim_head::default_character();
        let names: Vec<String> = character.blendshape_names();
        assert_eq!(Names::Own.table(&names).len(), 52);
        let arkit = Names::Arkit.table(&names);
        assert_eq!(arkit.len(), 52);
        assert!(arkit.iter().any(|(n, _)| n == "EyeBlinkLeft"));
        let presets = Names::VrmPresets.table(&names);
        assert_eq!(presets.len(), 12);
        let mut weights = vec![0.0; 52];
        let left = character
            .find_blendshape("eyeBlinkLeft")
            .map_or(0, |id| id.index());
        weights[left] = 1.0;
        let value = |name: &str| {
            presets
                .iter()
                .find(|(n, _)| n == name)
                .map_or(f32::NAN, |(_, s)| s.value(&weights))
        };
        assert_eq!(value("Blink_L"), 1.0);
        assert_eq!(value("Blink"), 0.0, "a wink is not a blink");
    }
}
