//! Blendshape names: left/right side conventions and the ARKit-52 vocabulary.
//!
//! Rigs name sides in many ways (`browDown_L`, `browDown.L`, `L_browDown`, `jawLeft`,
//! `eyeBlink_l`). This module reduces a name to a side-free *stem* plus a [`Side`], so that
//! partners can be paired by name, and maps any of those spellings onto the canonical ARKit name
//! (`eyeBlink_L` → `eyeBlinkLeft`), case-insensitively.

/// The 52 ARKit blendshape names, in Apple's documented order.
pub const ARKIT_52: [&str; 52] = [
    "eyeBlinkLeft",
    "eyeLookDownLeft",
    "eyeLookInLeft",
    "eyeLookOutLeft",
    "eyeLookUpLeft",
    "eyeSquintLeft",
    "eyeWideLeft",
    "eyeBlinkRight",
    "eyeLookDownRight",
    "eyeLookInRight",
    "eyeLookOutRight",
    "eyeLookUpRight",
    "eyeSquintRight",
    "eyeWideRight",
    "jawForward",
    "jawLeft",
    "jawRight",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthLeft",
    "mouthRight",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "noseSneerLeft",
    "noseSneerRight",
    "tongueOut",
];

/// Which side of the face a name says a blendshape belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// The character's left.
    Left,
    /// The character's right.
    Right,
}

impl Side {
    /// The other side.
    #[must_use]
    pub fn opposite(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// A name split into its side and a side-free stem; two names with equal stems and opposite
/// sides are partners.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct SidedName {
    /// The name with its side marker replaced by `*` and lower-cased, e.g. `eyeblink_*`.
    pub stem: String,
    /// The side the marker names.
    pub side: Side,
}

/// Splits a blendshape name into stem and side, recognising (in this order) the suffixes
/// `.L`/`.R`, `_L`/`_R`, `_l`/`_r`, `-L`/`-R`, ` L`/` R`, the prefixes `L_`/`R_` (and `l_`, `L.`),
/// and the words `Left`/`Right` at the end or followed by a separator or capital letter
/// (`jawLeft`, `eyeLeft_blink`). Returns `None` for names without a side (`jawOpen`).
#[must_use]
pub fn sided(name: &str) -> Option<SidedName> {
    let make = |stem: String, side| {
        Some(SidedName {
            stem: stem.to_lowercase(),
            side,
        })
    };
    // Single-letter suffixes after a separator: `.L`, `_L`, `_l`, `-L`, ` L`.
    let bytes = name.as_bytes();
    if bytes.len() >= 3 {
        let sep = bytes[bytes.len() - 2];
        let letter = bytes[bytes.len() - 1];
        if matches!(sep, b'.' | b'_' | b'-' | b' ') {
            let side = match letter {
                b'L' | b'l' => Some(Side::Left),
                b'R' | b'r' => Some(Side::Right),
                _ => None,
            };
            if let Some(side) = side {
                return make(format!("{}*", &name[..name.len() - 1]), side);
            }
        }
        // Prefixes `L_`, `R_`, `L.`, `l_` ...
        let letter = bytes[0];
        let sep = bytes[1];
        if matches!(sep, b'.' | b'_' | b'-') {
            let side = match letter {
                b'L' | b'l' => Some(Side::Left),
                b'R' | b'r' => Some(Side::Right),
                _ => None,
            };
            if let Some(side) = side {
                return make(format!("*{}", &name[1..]), side);
            }
        }
    }
    // Whole words `Left`/`Right` (any case) that end the name or are followed by a separator or
    // an upper-case letter, and are preceded by the start, a separator or a lower-case letter.
    let lower = name.to_lowercase();
    for (word, side) in [("left", Side::Left), ("right", Side::Right)] {
        let mut search_from = 0;
        while let Some(found) = lower[search_from..].find(word) {
            let start = search_from + found;
            let end = start + word.len();
            let before_ok = start == 0 || {
                let b = bytes[start - 1];
                matches!(b, b'.' | b'_' | b'-' | b' ')
                    || b.is_ascii_lowercase()
                    || b.is_ascii_digit()
            };
            let after_ok = end == bytes.len() || {
                let a = bytes[end];
                matches!(a, b'.' | b'_' | b'-' | b' ')
                    || a.is_ascii_uppercase()
                    || a.is_ascii_digit()
            };
            // `Left` inside a camel-case name must itself be capitalised (`jawLeft`, not `cleft`).
            let capital_ok = start == 0
                || bytes[start].is_ascii_uppercase()
                || matches!(bytes[start - 1], b'.' | b'_' | b'-' | b' ');
            if before_ok && after_ok && capital_ok {
                return make(format!("{}*{}", &name[..start], &name[end..]), side);
            }
            search_from = start + 1;
        }
    }
    None
}

/// The canonical ARKit name that `name` spells, if any: case-insensitive, with any side
/// convention understood (`EyeBlink_L`, `eyeblink.l`, `L_eyeBlink` → `eyeBlinkLeft`).
#[must_use]
pub fn arkit_name(name: &str) -> Option<&'static str> {
    let key = arkit_key(name);
    ARKIT_52
        .iter()
        .copied()
        .find(|candidate| arkit_key(candidate) == key)
}

/// Reduces a name to lower-case letters and digits with its side spelled `left`/`right` at the end.
fn arkit_key(name: &str) -> String {
    let (base, side) = match sided(name) {
        Some(s) => (s.stem.replace('*', ""), Some(s.side)),
        None => (name.to_lowercase(), None),
    };
    let mut key: String = base.chars().filter(char::is_ascii_alphanumeric).collect();
    match side {
        Some(Side::Left) => key.push_str("left"),
        Some(Side::Right) => key.push_str("right"),
        None => {}
    }
    key
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_in_every_convention() {
        for (name, stem, side) in [
            ("browDown_L", "browdown_*", Side::Left),
            ("browDown_R", "browdown_*", Side::Right),
            ("browDown.L", "browdown.*", Side::Left),
            ("brow_down_l", "brow_down_*", Side::Left),
            ("L_brow", "*_brow", Side::Left),
            ("R_brow", "*_brow", Side::Right),
            ("jawLeft", "jaw*", Side::Left),
            ("mouthRight", "mouth*", Side::Right),
            ("eyeBlinkLeft", "eyeblink*", Side::Left),
            ("Left_eye_close", "*_eye_close", Side::Left),
            ("eyeLeftClose", "eye*close", Side::Left),
        ] {
            let got = sided(name).unwrap_or_else(|| panic!("{name} has no side"));
            assert_eq!((got.stem.as_str(), got.side), (stem, side), "{name}");
        }
    }

    #[test]
    fn names_without_sides() {
        for name in [
            "jawOpen",
            "mouthClose",
            "cleft",
            "Lips",
            "R",
            "browInnerUp",
            "bereft_chin",
            "shape_12",
        ] {
            assert_eq!(sided(name), None, "{name}");
        }
    }

    #[test]
    fn arkit_names_in_any_spelling() {
        assert_eq!(arkit_name("eyeBlink_L"), Some("eyeBlinkLeft"));
        assert_eq!(arkit_name("EYEBLINKLEFT"), Some("eyeBlinkLeft"));
        assert_eq!(arkit_name("mouthSmile.R"), Some("mouthSmileRight"));
        assert_eq!(arkit_name("L_noseSneer"), Some("noseSneerLeft"));
        assert_eq!(arkit_name("jaw_open"), Some("jawOpen"));
        assert_eq!(arkit_name("jawLeft"), Some("jawLeft"));
        assert_eq!(arkit_name("browInnerUp"), Some("browInnerUp"));
        // ICT-FaceKit splits some ARKit shapes per side; those are not ARKit names.
        assert_eq!(arkit_name("browInnerUp_L"), None);
        assert_eq!(arkit_name("cheekPuff_R"), None);
        assert_eq!(arkit_name("smile"), None);
    }

    #[test]
    fn every_arkit_name_maps_to_itself() {
        for name in ARKIT_52 {
            assert_eq!(arkit_name(name), Some(name));
        }
    }
}
