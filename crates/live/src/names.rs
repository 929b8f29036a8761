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
    /// ARKit-named shapes, for apps that only know those.
    VrmPresets,
}

/// VRM 0.x's preset expressions and the ARKit shapes each is made of: the mean of the shapes
/// listed (the smaller of the two for `Blink`, so a wink is not a blink).
pub const VRM_PRESETS: [(&str, &[&str]); 12] = [
    ("A", &["jawOpen"]),
    ("I", &["mouthStretchLeft", "mouthStretchRight"]),
    ("U", &["mouthPucker"]),
    ("E", &["mouthLowerDownLeft", "mouthLowerDownRight"]),
    ("O", &["mouthFunnel"]),
    ("Blink", &["eyeBlinkLeft", "eyeBlinkRight"]),
    ("Blink_L", &["eyeBlinkLeft"]),
    ("Blink_R", &["eyeBlinkRight"]),
    ("Joy", &["mouthSmileLeft", "mouthSmileRight"]),
    ("Angry", &["browDownLeft", "browDownRight"]),
    ("Sorrow", &["mouthFrownLeft", "mouthFrownRight"]),
    ("Fun", &["cheekSquintLeft", "cheekSquintRight"]),
];

/// How one sent value is made from the character's weights.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Source {
    /// One blendshape's weight.
    One(usize),
    /// The mean of these blendshapes' weights.
    Mean(Vec<usize>),
    /// The smallest of these blendshapes' weights.
    Min(Vec<usize>),
}

impl Source {
    pub(crate) fn value(&self, weights: &[f32]) -> f32 {
        let get = |i: &usize| weights.get(*i).copied().unwrap_or(0.0);
        match self {
            Source::One(i) => get(i),
            Source::Mean(list) => list.iter().map(get).sum::<f32>() / list.len().max(1) as f32,
            Source::Min(list) => list.iter().map(get).fold(f32::INFINITY, f32::min),
        }
    }
}

impl Names {
    /// What it is called in messages.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Names::Own => "blendshapes",
            Names::Arkit => "ARKit-named blendshapes",
            Names::VrmPresets => "ARKit-named blendshapes to make VRM presets from",
        }
    }

    /// The sent names for a character with blendshapes `names` and how each value is made
    /// (empty when none applies).
    pub(crate) fn table(self, names: &[String]) -> Vec<(String, Source)> {
        let index = |wanted: &str| index_of(names, wanted);
        match self {
            Names::Own => names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), Source::One(i)))
                .collect(),
            Names::Arkit => faceanim_rig::names::ARKIT_52
                .iter()
                .filter_map(|&arkit| Some((capitalised(arkit), Source::One(index(arkit)?))))
                .collect(),
            Names::VrmPresets => VRM_PRESETS
                .iter()
                .filter_map(|&(preset, shapes)| {
                    let found: Vec<usize> = shapes.iter().filter_map(|s| index(s)).collect();
                    if found.len() != shapes.len() {
                        return None;
                    }
                    let source = if preset == "Blink" {
                        Source::Min(found)
                    } else {
                        Source::Mean(found)
                    };
                    Some((preset.to_owned(), source))
                })
                .collect(),
        }
    }
}

/// Where `wanted` is among `names`: the same name, or the same ARKit shape in another spelling
/// (`eyeBlink_L`, `EyeBlinkLeft`).
pub(crate) fn index_of(names: &[String], wanted: &str) -> Option<usize> {
    if let Some(i) = names.iter().position(|n| n == wanted) {
        return Some(i);
    }
    let arkit = faceanim_rig::names::arkit_name(wanted)?;
    names
        .iter()
        .position(|n| faceanim_rig::names::arkit_name(n) == Some(arkit))
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
    fn each_naming_covers_the_default_head() {
        let character = faceanim_head::default_character();
        let names: Vec<String> = character
            .blendshapes()
            .iter()
            .map(|b| b.name().to_owned())
            .collect();
        assert_eq!(Names::Own.table(&names).len(), 52);
        let arkit = Names::Arkit.table(&names);
        assert_eq!(arkit.len(), 52);
        assert!(arkit.iter().any(|(n, _)| n == "EyeBlinkLeft"));
        let presets = Names::VrmPresets.table(&names);
        assert_eq!(
            index_of(&names, "EyeBlinkLeft"),
            character
                .find_blendshape("eyeBlinkLeft")
                .map(|id| id.index())
        );
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
