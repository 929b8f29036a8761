//! Blendshape names: the one table of every rig convention faceanim understands.
//!
//! Rigs name the same motion in many ways. This module owns how a name is read, and every
//! part of faceanim that goes by names (capture by name, live streaming's `--names arkit|vrm`,
//! the Live Link export, lip sync, `faceanim info`) asks it:
//!
//! - [`sided`] reduces a name to a side-free *stem* plus a [`Side`] (`browDown_L`, `browDown.L`,
//!   `L_browDown`, `jawLeft`, `eyeBlink_l`), so that partners pair by name;
//! - [`drive`] says which of ARKit's 52 channels ([`Channel`]) a blendshape's name means, and
//!   how ([`Drive`]): one channel as it is; one side of a channel ARKit does not split (ICT's and
//!   Character Creator's `browInnerUp_L`, `cheekPuff_R`); the mean of a left/right pair for a
//!   shape that merges them (a single `mouthSmile`, VRM's `blink`, VRoid's `Fcl_EYE_Close`); or
//!   an [`Expression`] made of several channels (the visemes, VRM's `surprised`).
//!
//! Conventions read (case-insensitively, with any separator, camelCase or PascalCase):
//!
//! | convention | examples |
//! | --- | --- |
//! | ARKit, Live Link, Ready Player Me, MPFB, Avaturn | `eyeBlinkLeft`, `EyeBlinkLeft`, `eye_blink_left`, `JawOpen` |
//! | ARKit split per side (ICT-FaceKit, Character Creator) | `eyeBlink_L`, `browInnerUp_R`, `cheekPuff_L` |
//! | Character Creator 4 (CC_Base) | `Eye_Blink_L`, `Brow_Raise_Inner_L`, `Brow_Drop_R`, `Cheek_Raise_L`, `Mouth_Smile_L`, `Mouth_Up_Upper_L`, `Mouth_Down_Lower_R`, `Mouth_Roll_In_Upper_L`, `Eye_L_Look_R`, `Jaw_L`, `Mouth_L` |
//! | VRM 1.0 presets | `blink`, `blinkLeft`, `aa`, `ih`, `ou`, `ee`, `oh`, `happy`, `angry`, `sad`, `surprised`, `lookUp`, `lookLeft` |
//! | VRM 0.x presets | `Blink`, `Blink_L`, `A`, `I`, `U`, `E`, `O`, `Joy`, `Angry`, `Sorrow`, `LookUp` |
//! | VRoid Studio | `Fcl_EYE_Close`, `Fcl_EYE_Close_L`, `Fcl_EYE_Surprised`, `Fcl_EYE_Angry`, `Fcl_BRW_Angry`, `Fcl_BRW_Sorrow`, `Fcl_BRW_Surprised`, `Fcl_MTH_A` … `Fcl_MTH_O`, `Fcl_MTH_Joy`, `Fcl_MTH_Sorrow`, `Fcl_MTH_Up`, `Fcl_MTH_Down` |
//! | Ready Player Me / Oculus visemes | `viseme_aa`, `viseme_E`, `viseme_I`, `viseme_O`, `viseme_U`, `viseme_PP` … |
//! | Daz Genesis 8 controls | `eCTRLEyesClosedL`, `eCTRLMouthSmileL`, `facs_bs_EyeBlinkLeft` |
//! | namespaces and numbered prefixes | `blendShape1.jawOpen`, `A25_Jaw_Open`, `CC_Base_Body.Mouth_Smile_L` |
//!
//! Whole-face emotions (`Fcl_ALL_Joy`, VRM `relaxed`), VRoid's teeth and highlight keys, and
//! anything else without an ARKit meaning drive nothing by name: capture reaches them through
//! the character's adapter.

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

/// One of ARKit's 52 blendshape channels (an index into [`ARKIT_52`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Channel(u8);

impl Channel {
    /// Every channel, in [`ARKIT_52`]'s order.
    pub fn all() -> impl ExactSizeIterator<Item = Channel> {
        (0..ARKIT_52.len() as u8).map(Channel)
    }

    /// The channel with this exact ARKit name (`eyeBlinkLeft`).
    #[must_use]
    pub fn named(name: &str) -> Option<Channel> {
        ARKIT_52
            .iter()
            .position(|n| *n == name)
            .map(|i| Channel(i as u8))
    }

    /// Its ARKit name.
    #[must_use]
    pub fn name(self) -> &'static str {
        ARKIT_52[usize::from(self.0)]
    }

    /// Its position in [`ARKIT_52`].
    #[must_use]
    pub fn index(self) -> usize {
        usize::from(self.0)
    }

    /// The same movement on the other side of the face (`eyeBlinkLeft` ↔ `eyeBlinkRight`);
    /// `None` for a channel of the middle (`jawOpen`) and for the directions `jawLeft`,
    /// `jawRight`, `mouthLeft` and `mouthRight`, which move the whole jaw or mouth one way
    /// rather than one side of the face.
    ///
    /// ```
    /// use faceanim_rig::names::Channel;
    /// let blink = Channel::named("eyeBlinkLeft").unwrap();
    /// assert_eq!(blink.twin().map(Channel::name), Some("eyeBlinkRight"));
    /// assert_eq!(Channel::named("mouthLeft").unwrap().twin(), None);
    /// assert_eq!(Channel::named("jawOpen").unwrap().twin(), None);
    /// ```
    #[must_use]
    pub fn twin(self) -> Option<Channel> {
        let name = self.name();
        let (stem, other) = if let Some(stem) = name.strip_suffix("Left") {
            (stem, "Right")
        } else {
            (name.strip_suffix("Right")?, "Left")
        };
        if matches!(stem, "jaw" | "mouth") {
            return None;
        }
        Channel::named(&format!("{stem}{other}"))
    }
}

/// A viseme of the Oculus / OpenXR set of 15 (Ready Player Me's `viseme_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Viseme {
    /// Silence: the mouth at rest.
    Sil,
    /// P, B, M: lips pressed together.
    PP,
    /// F, V: lower lip under the upper teeth.
    FF,
    /// TH: tongue between the teeth.
    TH,
    /// D, T: tongue behind the upper teeth.
    DD,
    /// K, G: back of the tongue raised.
    Kk,
    /// CH, J, SH: lips forward, teeth close.
    CH,
    /// S, Z: teeth close, lips spread.
    SS,
    /// N, L: tongue up, mouth slightly open.
    Nn,
    /// R: lips slightly rounded.
    RR,
    /// A as in "father": jaw open.
    Aa,
    /// E as in "bed": half open, spread.
    E,
    /// I as in "tip": nearly closed, spread.
    Ih,
    /// O as in "thought": rounded, open.
    Oh,
    /// U as in "book": rounded, pursed.
    Ou,
}

impl Viseme {
    /// All 15, in the Oculus order.
    pub const ALL: [Viseme; 15] = [
        Viseme::Sil,
        Viseme::PP,
        Viseme::FF,
        Viseme::TH,
        Viseme::DD,
        Viseme::Kk,
        Viseme::CH,
        Viseme::SS,
        Viseme::Nn,
        Viseme::RR,
        Viseme::Aa,
        Viseme::E,
        Viseme::Ih,
        Viseme::Oh,
        Viseme::Ou,
    ];

    /// Its Oculus name (`sil`, `PP`, `aa`, `E`, `ih`, …).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Viseme::Sil => "sil",
            Viseme::PP => "PP",
            Viseme::FF => "FF",
            Viseme::TH => "TH",
            Viseme::DD => "DD",
            Viseme::Kk => "kk",
            Viseme::CH => "CH",
            Viseme::SS => "SS",
            Viseme::Nn => "nn",
            Viseme::RR => "RR",
            Viseme::Aa => "aa",
            Viseme::E => "E",
            Viseme::Ih => "ih",
            Viseme::Oh => "oh",
            Viseme::Ou => "ou",
        }
    }
}

/// A shape made of several ARKit channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Expression {
    /// A mouth shape of speech.
    Viseme(Viseme),
    /// VRM's `surprised`: brows up and eyes wide.
    Surprised,
}

impl Expression {
    /// The ARKit channels this expression is read from by [`Expression::from_channels`]
    /// (empty for a viseme capture cannot read: lip sync drives those).
    #[must_use]
    pub fn inputs(self) -> &'static [&'static str] {
        match self {
            Expression::Viseme(Viseme::Aa) => &["jawOpen", "mouthFunnel", "mouthPucker"],
            Expression::Viseme(Viseme::Ih | Viseme::E) => {
                &["mouthStretchLeft", "mouthStretchRight", "jawOpen"]
            }
            Expression::Viseme(Viseme::Ou) => &["mouthPucker"],
            Expression::Viseme(Viseme::Oh) => &["mouthFunnel"],
            Expression::Viseme(_) => &[],
            Expression::Surprised => &["browInnerUp", "eyeWideLeft", "eyeWideRight"],
        }
    }

    /// Its weight in [0, 1] from ARKit channel values (`value(channel)` in [0, 1]); `None` for
    /// a viseme that has no reading from the face's channels.
    #[must_use]
    pub fn from_channels(self, value: impl Fn(&str) -> f32) -> Option<f32> {
        let mean = |a: &str, b: &str| 0.5 * (value(a) + value(b));
        let spread = mean("mouthStretchLeft", "mouthStretchRight");
        let rounded = value("mouthFunnel").max(value("mouthPucker"));
        let v = match self {
            Expression::Viseme(Viseme::Aa) => value("jawOpen") * (1.0 - rounded),
            Expression::Viseme(Viseme::Ih) => spread * (1.0 - value("jawOpen")),
            Expression::Viseme(Viseme::Ou) => value("mouthPucker"),
            Expression::Viseme(Viseme::E) => spread * value("jawOpen"),
            Expression::Viseme(Viseme::Oh) => value("mouthFunnel"),
            Expression::Viseme(_) => return None,
            Expression::Surprised => {
                0.5 * value("browInnerUp") + 0.25 * (value("eyeWideLeft") + value("eyeWideRight"))
            }
        };
        Some(v.clamp(0.0, 1.0))
    }
}

/// How a blendshape's name ties it to ARKit's channels. See the module docs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Drive {
    /// It is this channel (`eyeBlink_L`, `Eye_Blink_L`, `Fcl_EYE_Close_L`, `blinkLeft`).
    Channel(Channel),
    /// It is one side of a channel ARKit does not split (`browInnerUp_L`, `Cheek_Puff_R`).
    Split(Channel, Side),
    /// It merges a left/right pair of channels (`mouthSmile`, `blink`, `Fcl_EYE_Close`):
    /// driven by their mean.
    Merge(Channel, Channel),
    /// It is an expression of several channels (a viseme, VRM's `surprised`).
    Expression(Expression),
}

impl Drive {
    /// Its weight from ARKit channel values (`value(channel)` in [0, 1]); `None` where the name
    /// has no reading from the face's channels (most visemes).
    #[must_use]
    pub fn from_channels(self, value: impl Fn(&str) -> f32) -> Option<f32> {
        match self {
            Drive::Channel(c) | Drive::Split(c, _) => Some(value(c.name()).clamp(0.0, 1.0)),
            Drive::Merge(a, b) => Some((0.5 * (value(a.name()) + value(b.name()))).clamp(0.0, 1.0)),
            Drive::Expression(e) => e.from_channels(value),
        }
    }

    /// The channels it reads.
    #[must_use]
    pub fn channels(self) -> Vec<Channel> {
        match self {
            Drive::Channel(c) | Drive::Split(c, _) => vec![c],
            Drive::Merge(a, b) => vec![a, b],
            Drive::Expression(e) => e
                .inputs()
                .iter()
                .filter_map(|n| Channel::named(n))
                .collect(),
        }
    }

    /// A short description for people: `eyeBlinkLeft`, `browInnerUp (left side)`,
    /// `mean of mouthSmileLeft and mouthSmileRight`, `viseme aa (from jawOpen, …)`.
    #[must_use]
    pub fn describe(self) -> String {
        match self {
            Drive::Channel(c) => c.name().to_owned(),
            Drive::Split(c, Side::Left) => format!("{} (left side)", c.name()),
            Drive::Split(c, Side::Right) => format!("{} (right side)", c.name()),
            Drive::Merge(a, b) => format!("mean of {} and {}", a.name(), b.name()),
            Drive::Expression(Expression::Viseme(v)) => match Expression::Viseme(v).inputs() {
                [] => format!("viseme {} (lip sync only)", v.name()),
                inputs => format!("viseme {} (from {})", v.name(), inputs.join(", ")),
            },
            Drive::Expression(e @ Expression::Surprised) => {
                format!("surprised (from {})", e.inputs().join(", "))
            }
        }
    }
}

/// The canonical ARKit name that `name` spells, if any: case-insensitive, in any convention of
/// the module's table that names one channel as it is (`EyeBlink_L`, `eyeblink.l`,
/// `L_eyeBlink`, `Eye_Blink_L`, `Fcl_EYE_Close_L` → `eyeBlinkLeft`). Split and merged shapes
/// (`browInnerUp_L`, `mouthSmile`) are not ARKit names: see [`drive`].
#[must_use]
pub fn arkit_name(name: &str) -> Option<&'static str> {
    match drive(name)? {
        Drive::Channel(c) => Some(c.name()),
        _ => None,
    }
}

/// VRM's preset expressions: each one's VRM 0.x name (`presetName`, lower case) and its VRM 1.0
/// name. faceanim reads a VRM 0.x avatar's presets under their VRM 1.0 names.
pub const VRM_PRESET_NAMES: [(&str, &str); 18] = [
    ("a", "aa"),
    ("i", "ih"),
    ("u", "ou"),
    ("e", "ee"),
    ("o", "oh"),
    ("blink", "blink"),
    ("blink_l", "blinkLeft"),
    ("blink_r", "blinkRight"),
    ("joy", "happy"),
    ("angry", "angry"),
    ("sorrow", "sad"),
    ("fun", "relaxed"),
    ("surprised", "surprised"),
    ("lookup", "lookUp"),
    ("lookdown", "lookDown"),
    ("lookleft", "lookLeft"),
    ("lookright", "lookRight"),
    ("neutral", "neutral"),
];

/// The VRM 1.0 name of the preset expression called `name` in VRM 0.x's or VRM 1.0's
/// spelling, in any case (what VSeeFace and VMagicMirror send is VRM 0.x's: `Fun`, `Joy`,
/// `A`); `None` for any other name.
///
/// ```
/// use faceanim_rig::names::vrm_preset;
/// assert_eq!(vrm_preset("Fun"), Some("relaxed"));
/// assert_eq!(vrm_preset("Blink_L"), Some("blinkLeft"));
/// assert_eq!(vrm_preset("happy"), Some("happy"));
/// assert_eq!(vrm_preset("Fcl_ALL_Fun"), None);
/// ```
#[must_use]
pub fn vrm_preset(name: &str) -> Option<&'static str> {
    VRM_PRESET_NAMES
        .iter()
        .find(|(v0, v1)| v0.eq_ignore_ascii_case(name) || v1.eq_ignore_ascii_case(name))
        .map(|(_, v1)| *v1)
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

/// VRM's five vowel presets and the viseme each is: a character whose shapes are named for the
/// viseme (VRoid's `Fcl_MTH_A`, a VRM's own `aa` expression, Ready Player Me's `viseme_aa`)
/// sends the preset from them rather than from [`VRM_PRESETS`]' ARKit channels (faceanim's live
/// performer), and a received vowel sets them (its marionette, a clip put on a character).
pub const VRM_VOWELS: [(&str, Viseme); 5] = [
    ("A", Viseme::Aa),
    ("I", Viseme::Ih),
    ("U", Viseme::Ou),
    ("E", Viseme::E),
    ("O", Viseme::Oh),
];

/// The ARKit channels a received name stands for when it is not one channel itself, each to be
/// set to the name's value: both of a merged pair (VRM's `Blink`, `Joy`, `Angry`, `Sorrow`,
/// VRoid's `Fcl_EYE_Close`); for VRM's `surprised` the channels it is read from
/// ([`Expression::inputs`], which read back as the value); for one of VRM's vowels (`A`, `aa`)
/// and for VRM 0.x's `Fun` (VRM 1.0 renamed it `relaxed`) the channels a performer sends the
/// preset from ([`VRM_PRESETS`]); none otherwise. What VSeeFace, VMagicMirror and trackers
/// without perfect sync send, and what a VRM Animation moves.
///
/// ```
/// use faceanim_rig::names::stands_for;
/// let names = |name: &str| stands_for(name).iter().map(|c| c.name()).collect::<Vec<_>>();
/// assert_eq!(names("Joy"), ["mouthSmileLeft", "mouthSmileRight"]);
/// assert_eq!(names("aa"), ["jawOpen"]);
/// assert_eq!(names("surprised"), ["browInnerUp", "eyeWideLeft", "eyeWideRight"]);
/// assert_eq!(names("relaxed"), names("Fun"));
/// assert_eq!(names("Fun"), ["cheekSquintLeft", "cheekSquintRight"]);
/// assert!(names("jawOpen").is_empty());
/// ```
#[must_use]
pub fn stands_for(name: &str) -> Vec<Channel> {
    let preset = |name: &str| {
        VRM_PRESETS
            .iter()
            .find(|(preset, _)| *preset == name)
            .map(|(_, channels)| channels.iter().filter_map(|c| Channel::named(c)).collect())
            .unwrap_or_default()
    };
    match drive(name) {
        Some(Drive::Merge(a, b)) => vec![a, b],
        Some(Drive::Expression(Expression::Viseme(viseme))) => VRM_VOWELS
            .iter()
            .find(|(_, v)| *v == viseme)
            .map(|(vowel, _)| preset(vowel))
            .unwrap_or_default(),
        Some(Drive::Expression(e @ Expression::Surprised)) => e
            .inputs()
            .iter()
            .filter_map(|c| Channel::named(c))
            .collect(),
        // Capture by name drives no `relaxed` (a whole-face emotion, not a motion of the
        // face); a received or recorded one stands for the channels `Fun` is sent from.
        None if vrm_preset(name) == Some("relaxed") => preset("Fun"),
        _ => Vec::new(),
    }
}

/// The part of the face an ARKit channel moves, by its family in ARKit's names: the one rule
/// that the retarget map's fit (its regions), the take's face parts and the studio's groups
/// share.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Region {
    /// The eight `eyeLook*`: where the eyes look.
    Gaze,
    /// The other `eye*`: blinks, squints, wide eyes.
    Lids,
    /// `brow*`.
    Brows,
    /// `cheek*`.
    Cheeks,
    /// `nose*`.
    Nose,
    /// `jaw*`.
    Jaw,
    /// `mouth*`.
    Mouth,
    /// `tongueOut`.
    Tongue,
}

/// The [`Region`] of the ARKit channel called `arkit` (its canonical name, or MediaPipe's
/// score of the same name; anything else is the mouth's).
///
/// ```
/// use faceanim_rig::names::{Region, region};
/// assert_eq!(region("eyeLookUpLeft"), Region::Gaze);
/// assert_eq!(region("eyeBlinkLeft"), Region::Lids);
/// assert_eq!(region("jawOpen"), Region::Jaw);
/// assert_eq!(region("tongueOut"), Region::Tongue);
/// assert_eq!(region("mouthSmileLeft"), Region::Mouth);
/// ```
#[must_use]
pub fn region(arkit: &str) -> Region {
    if is_gaze(arkit) {
        return Region::Gaze;
    }
    [
        ("eye", Region::Lids),
        ("brow", Region::Brows),
        ("cheek", Region::Cheeks),
        ("nose", Region::Nose),
        ("jaw", Region::Jaw),
        ("tongue", Region::Tongue),
    ]
    .into_iter()
    .find(|(prefix, _)| arkit.starts_with(prefix))
    .map_or(Region::Mouth, |(_, r)| r)
}

/// Whether the ARKit channel called `arkit` (its canonical name: one of [`ARKIT_52`], or
/// MediaPipe's score of the same name) says where the eyes look — the eight `eyeLook*` — rather
/// than an expression of the face.
///
/// ```
/// assert!(faceanim_rig::names::is_gaze("eyeLookUpLeft"));
/// assert!(!faceanim_rig::names::is_gaze("eyeBlinkLeft"));
/// ```
#[must_use]
pub fn is_gaze(arkit: &str) -> bool {
    arkit.starts_with("eyeLook")
}

/// Whether `name` is ARKit's own name for `channel`, in any case or separator
/// (`browInnerUp`, `BrowInnerUp`, `brow_inner_up`), not a synonym from another convention
/// (VRoid's `Fcl_BRW_Sorrow` also means browInnerUp, but is an expression of its own).
#[must_use]
pub fn spells(name: &str, channel: Channel) -> bool {
    tokens(name).concat() == channel.name().to_ascii_lowercase()
}

/// What a blendshape called `name` means in ARKit's channels, if anything. See the module docs.
#[must_use]
pub fn drive(name: &str) -> Option<Drive> {
    let tokens = tokens(name);
    let (rest, sides) = take_sides(&tokens);
    // Character Creator's eye looks: Eye_L_Look_R, Eye_L_Look_Up (which eye, then which way).
    let words: Vec<&str> = rest.iter().map(String::as_str).collect();
    let look = match (words.as_slice(), sides.as_slice()) {
        (["eye", "look"], [eye, Side::Left]) => eye_look(*eye, "l"),
        (["eye", "look"], [eye, Side::Right]) => eye_look(*eye, "r"),
        (["eye", "look", way], [eye]) => eye_look(*eye, way),
        _ => None,
    };
    if look.is_some() {
        return look;
    }
    let side = match sides.as_slice() {
        [] => None,
        [side] => Some(*side),
        _ => return None,
    };
    let stem: String = rest.concat();
    let family = family(&stem)?;
    match (family, side) {
        (Family::Sided(l, _), Some(Side::Left)) | (Family::Directional(l, _), Some(Side::Left)) => {
            Some(Drive::Channel(channel(l)?))
        }
        (Family::Sided(_, r), Some(Side::Right))
        | (Family::Directional(_, r), Some(Side::Right)) => Some(Drive::Channel(channel(r)?)),
        (Family::Sided(l, r), None) => Some(Drive::Merge(channel(l)?, channel(r)?)),
        (Family::Directional(..), None) => None,
        (Family::Single(c), None) => Some(Drive::Channel(channel(c)?)),
        (Family::Single(c), Some(side)) => Some(Drive::Split(channel(c)?, side)),
        (Family::Merged(a, b), None) => Some(Drive::Merge(channel(a)?, channel(b)?)),
        // VRM's lookLeft and lookRight move both eyes, one inwards and one outwards.
        (Family::Look, Some(Side::Left)) => Some(Drive::Merge(
            channel("eyeLookOutLeft")?,
            channel("eyeLookInRight")?,
        )),
        (Family::Look, Some(Side::Right)) => Some(Drive::Merge(
            channel("eyeLookInLeft")?,
            channel("eyeLookOutRight")?,
        )),
        (Family::Look, None) => None,
        (Family::Expression(e), None) => Some(Drive::Expression(e)),
        (Family::Merged(..) | Family::Expression(_), Some(_)) => None,
    }
}

fn channel(name: &str) -> Option<Channel> {
    Channel::named(name)
}

/// Character Creator's `Eye_{L,R}_Look_{L,R,Up,Down}`: one eye looking to the character's
/// left, right, up or down.
fn eye_look(eye: Side, way: &str) -> Option<Drive> {
    let name = match (eye, way) {
        (Side::Left, "l") => "eyeLookOutLeft",
        (Side::Left, "r") => "eyeLookInLeft",
        (Side::Right, "l") => "eyeLookInRight",
        (Side::Right, "r") => "eyeLookOutRight",
        (Side::Left, "up") => "eyeLookUpLeft",
        (Side::Right, "up") => "eyeLookUpRight",
        (Side::Left, "down") => "eyeLookDownLeft",
        (Side::Right, "down") => "eyeLookDownRight",
        _ => return None,
    };
    Some(Drive::Channel(channel(name)?))
}

/// What a side-free stem names.
#[derive(Debug, Clone, Copy)]
enum Family {
    /// A left/right pair of channels: a side picks one, no side merges them.
    Sided(&'static str, &'static str),
    /// A pair named by the direction of motion (`jawLeft`): only with a side.
    Directional(&'static str, &'static str),
    /// One channel: a side makes it a split.
    Single(&'static str),
    /// A pair that is only ever merged (VRM's `lookLeft` is both eyes).
    Merged(&'static str, &'static str),
    /// Several channels.
    Expression(Expression),
    /// Both eyes looking one way (VRM's `lookLeft`, `lookRight`).
    Look,
}

/// The stems of the table: lower-case tokens joined, side words removed.
fn family(stem: &str) -> Option<Family> {
    use Family::{Directional, Merged, Single};
    let sided = |base: &'static str| -> Family {
        match SIDED.iter().find(|(b, _, _)| *b == base) {
            Some(&(_, l, r)) => Family::Sided(l, r),
            None => Single(base),
        }
    };
    let viseme = |v| Some(Family::Expression(Expression::Viseme(v)));
    // ARKit's own names, side words removed.
    for &(base, l, r) in SIDED {
        if stem.eq_ignore_ascii_case(base) {
            return Some(Family::Sided(l, r));
        }
    }
    for name in ARKIT_52 {
        if stem.eq_ignore_ascii_case(name) {
            return Some(Single(name));
        }
    }
    Some(match stem {
        "jaw" => Directional("jawLeft", "jawRight"),
        "mouth" => Directional("mouthLeft", "mouthRight"),
        // Character Creator 4 and other splits of ARKit's names.
        "browraiseinner" | "browinnerraise" | "innerbrowraise" => Single("browInnerUp"),
        "browraiseouter" | "browouterraise" | "outerbrowraise" | "browup" => sided("browouterup"),
        "browdrop" | "browlower" | "browsdown" => sided("browdown"),
        "cheekraise" => sided("cheeksquint"),
        "mouthupupper" | "upperlipup" | "upperlipraise" => sided("mouthupperup"),
        "mouthdownlower" | "lowerlipdown" | "lowerlipdepress" => sided("mouthlowerdown"),
        "mouthrollinupper" | "mouthrollupperin" => Single("mouthRollUpper"),
        "mouthrollinlower" | "mouthrolllowerin" => Single("mouthRollLower"),
        "mouthpuckerup" | "mouthpuckerdown" | "pucker" => Single("mouthPucker"),
        "mouthfunnelup" | "mouthfunneldown" | "funnel" => Single("mouthFunnel"),
        "eyeclose" | "eyeclosed" | "eyesclosed" | "eyesclose" | "blink" | "wink" => {
            sided("eyeblink")
        }
        "eyeopen" | "eyeswide" | "eyewideopen" => sided("eyewide"),
        "smile" | "mouthsmileclosed" => sided("mouthsmile"),
        "frown" | "mouthcornerdown" => sided("mouthfrown"),
        "sneer" | "nosewrinkle" => sided("nosesneer"),
        "dimple" => sided("mouthdimple"),
        "jawdrop" | "mouthopen" => Single("jawOpen"),
        "tongue" | "tongueextend" => Single("tongueOut"),
        // VRM 1.0 and 0.x presets.
        "happy" | "joy" => sided("mouthsmile"),
        "angry" => sided("browdown"),
        "sad" | "sorrow" => sided("mouthfrown"),
        "surprised" => Family::Expression(Expression::Surprised),
        "lookup" => Merged("eyeLookUpLeft", "eyeLookUpRight"),
        "lookdown" => Merged("eyeLookDownLeft", "eyeLookDownRight"),
        "look" => Family::Look,
        "a" | "aa" => return viseme(Viseme::Aa),
        "i" | "ih" => return viseme(Viseme::Ih),
        "u" | "ou" => return viseme(Viseme::Ou),
        "e" | "ee" => return viseme(Viseme::E),
        "o" | "oh" => return viseme(Viseme::Oh),
        // VRoid Studio's face keys (region first, then what it does).
        "fcleyeclose" => sided("eyeblink"),
        "fcleyesurprised" => sided("eyewide"),
        "fcleyeangry" => sided("eyesquint"),
        "fclbrwangry" => sided("browdown"),
        "fclbrwsorrow" => Single("browInnerUp"),
        "fclbrwsurprised" => Merged("browOuterUpLeft", "browOuterUpRight"),
        "fclmthjoy" => sided("mouthsmile"),
        "fclmthsorrow" => sided("mouthfrown"),
        "fclmthup" => sided("mouthupperup"),
        "fclmthdown" => sided("mouthlowerdown"),
        "fclmtha" => return viseme(Viseme::Aa),
        "fclmthi" => return viseme(Viseme::Ih),
        "fclmthu" => return viseme(Viseme::Ou),
        "fclmthe" => return viseme(Viseme::E),
        "fclmtho" => return viseme(Viseme::Oh),
        // Oculus / Ready Player Me visemes.
        "visemesil" => return viseme(Viseme::Sil),
        "visemepp" => return viseme(Viseme::PP),
        "visemeff" => return viseme(Viseme::FF),
        "visemeth" => return viseme(Viseme::TH),
        "visemedd" => return viseme(Viseme::DD),
        "visemekk" => return viseme(Viseme::Kk),
        "visemech" => return viseme(Viseme::CH),
        "visemess" => return viseme(Viseme::SS),
        "visemenn" => return viseme(Viseme::Nn),
        "visemerr" => return viseme(Viseme::RR),
        "visemeaa" => return viseme(Viseme::Aa),
        "visemee" => return viseme(Viseme::E),
        "visemei" | "visemeih" => return viseme(Viseme::Ih),
        "visemeo" | "visemeoh" => return viseme(Viseme::Oh),
        "visemeu" | "visemeou" => return viseme(Viseme::Ou),
        _ => return None,
    })
}

/// ARKit's left/right pairs by stem (lower case, side words removed).
const SIDED: &[(&str, &str, &str)] = &[
    ("eyeblink", "eyeBlinkLeft", "eyeBlinkRight"),
    ("eyelookdown", "eyeLookDownLeft", "eyeLookDownRight"),
    ("eyelookin", "eyeLookInLeft", "eyeLookInRight"),
    ("eyelookout", "eyeLookOutLeft", "eyeLookOutRight"),
    ("eyelookup", "eyeLookUpLeft", "eyeLookUpRight"),
    ("eyesquint", "eyeSquintLeft", "eyeSquintRight"),
    ("eyewide", "eyeWideLeft", "eyeWideRight"),
    ("mouthsmile", "mouthSmileLeft", "mouthSmileRight"),
    ("mouthfrown", "mouthFrownLeft", "mouthFrownRight"),
    ("mouthdimple", "mouthDimpleLeft", "mouthDimpleRight"),
    ("mouthstretch", "mouthStretchLeft", "mouthStretchRight"),
    ("mouthpress", "mouthPressLeft", "mouthPressRight"),
    (
        "mouthlowerdown",
        "mouthLowerDownLeft",
        "mouthLowerDownRight",
    ),
    ("mouthupperup", "mouthUpperUpLeft", "mouthUpperUpRight"),
    ("browdown", "browDownLeft", "browDownRight"),
    ("browouterup", "browOuterUpLeft", "browOuterUpRight"),
    ("cheeksquint", "cheekSquintLeft", "cheekSquintRight"),
    ("nosesneer", "noseSneerLeft", "noseSneerRight"),
];

/// Prefix tokens that carry no meaning: namespaces and exporters' decorations.
const NOISE: &[&str] = &[
    "blendshape",
    "blendshape1",
    "facs",
    "bs",
    "jnt",
    "ctrl",
    "e",
    "cc",
    "base",
    "morph",
    "shape",
    "key",
    "target",
];

/// A name's words, lower case: split at separators, camelCase and PascalCase boundaries (an
/// acronym stays whole: `eCTRLEyesClosedL` → e, ctrl, eyes, closed, l), after dropping a
/// namespace (`blendShape1.jawOpen`, `CC_Base_Body.Mouth_Smile_L`) and a numbered prefix
/// (`A25_Jaw_Open`), and leading decorations (`facs_bs_`, `eCTRL`).
fn tokens(name: &str) -> Vec<String> {
    // A namespace: text up to a dot that is followed by a word, not by a side letter (`.L`).
    let name = match name.rsplit_once('.') {
        Some((_, tail)) if tail.chars().filter(char::is_ascii_alphanumeric).count() > 1 => tail,
        _ => name,
    };
    let chars: Vec<char> = name.chars().collect();
    let mut words: Vec<String> = Vec::new();
    let mut current = String::new();
    for (i, &c) in chars.iter().enumerate() {
        if !c.is_ascii_alphanumeric() {
            if !current.is_empty() {
                words.push(std::mem::take(&mut current));
            }
            continue;
        }
        let prev = i.checked_sub(1).map(|j| chars[j]);
        let next = chars.get(i + 1).copied();
        let boundary = c.is_ascii_uppercase()
            && prev.is_some_and(|p| {
                p.is_ascii_lowercase()
                    || p.is_ascii_digit()
                    || (p.is_ascii_uppercase() && next.is_some_and(|n| n.is_ascii_lowercase()))
            });
        if boundary && !current.is_empty() {
            words.push(std::mem::take(&mut current));
        }
        current.push(c.to_ascii_lowercase());
    }
    if !current.is_empty() {
        words.push(current);
    }
    // A numbered prefix (`A25`, `01`), then decorations, only while a word is left after them.
    let mut start = 0;
    while start + 1 < words.len() {
        let w = words[start].as_str();
        let numbered = w.chars().any(|c| c.is_ascii_digit())
            && w.chars()
                .skip_while(char::is_ascii_alphabetic)
                .all(|c| c.is_ascii_digit())
            && w.chars().take_while(char::is_ascii_alphabetic).count() <= 1;
        if numbered || NOISE.contains(&w) {
            start += 1;
        } else {
            break;
        }
    }
    words.split_off(start)
}

/// Removes the side words (`l`, `r`, `left`, `right`) and returns them in order. A lone `l` or
/// `r` inside a name counts only beside a separator, which tokens already ensure.
fn take_sides(tokens: &[String]) -> (Vec<String>, Vec<Side>) {
    let mut rest = Vec::new();
    let mut sides = Vec::new();
    for t in tokens {
        match t.as_str() {
            "l" | "left" => sides.push(Side::Left),
            "r" | "right" => sides.push(Side::Right),
            _ => rest.push(t.clone()),
        }
    }
    (rest, sides)
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

    /// The conventions of the module's table, each with names as their tools write them.
    #[test]
    fn every_convention_of_the_table() {
        let channel = |n: &str| Drive::Channel(Channel::named(n).unwrap());
        let split = |n: &str, side| Drive::Split(Channel::named(n).unwrap(), side);
        let merge =
            |a: &str, b: &str| Drive::Merge(Channel::named(a).unwrap(), Channel::named(b).unwrap());
        let viseme = |v| Drive::Expression(Expression::Viseme(v));
        for (name, want) in [
            // ARKit in every case and separator, Live Link's PascalCase, MPFB's snake case.
            ("eyeBlinkLeft", channel("eyeBlinkLeft")),
            ("EyeBlinkLeft", channel("eyeBlinkLeft")),
            ("eye_blink_left", channel("eyeBlinkLeft")),
            ("JawOpen", channel("jawOpen")),
            ("mouthRollUpper", channel("mouthRollUpper")),
            // ICT-FaceKit and Character Creator's splits of ARKit's single channels.
            ("eyeBlink_L", channel("eyeBlinkLeft")),
            ("browInnerUp_L", split("browInnerUp", Side::Left)),
            ("cheekPuff_R", split("cheekPuff", Side::Right)),
            // Character Creator 4.
            ("Eye_Blink_L", channel("eyeBlinkLeft")),
            ("Brow_Raise_Inner_R", split("browInnerUp", Side::Right)),
            ("Brow_Raise_Outer_L", channel("browOuterUpLeft")),
            ("Brow_Drop_R", channel("browDownRight")),
            ("Cheek_Raise_L", channel("cheekSquintLeft")),
            ("Cheek_Puff_L", split("cheekPuff", Side::Left)),
            ("Mouth_Smile_L", channel("mouthSmileLeft")),
            ("Mouth_Up_Upper_L", channel("mouthUpperUpLeft")),
            ("Mouth_Down_Lower_R", channel("mouthLowerDownRight")),
            ("Mouth_Roll_In_Upper_L", split("mouthRollUpper", Side::Left)),
            ("Mouth_Pucker_Up_R", split("mouthPucker", Side::Right)),
            ("Eye_L_Look_L", channel("eyeLookOutLeft")),
            ("Eye_L_Look_R", channel("eyeLookInLeft")),
            ("Eye_R_Look_L", channel("eyeLookInRight")),
            ("Eye_R_Look_Up", channel("eyeLookUpRight")),
            ("Jaw_L", channel("jawLeft")),
            ("Mouth_R", channel("mouthRight")),
            ("Jaw_Open", channel("jawOpen")),
            ("Tongue_Out", channel("tongueOut")),
            // VRM 1.0 and 0.x presets.
            ("blink", merge("eyeBlinkLeft", "eyeBlinkRight")),
            ("blinkLeft", channel("eyeBlinkLeft")),
            ("Blink_R", channel("eyeBlinkRight")),
            ("happy", merge("mouthSmileLeft", "mouthSmileRight")),
            ("Joy", merge("mouthSmileLeft", "mouthSmileRight")),
            ("Sorrow", merge("mouthFrownLeft", "mouthFrownRight")),
            ("lookLeft", merge("eyeLookOutLeft", "eyeLookInRight")),
            ("LookUp", merge("eyeLookUpLeft", "eyeLookUpRight")),
            ("aa", viseme(Viseme::Aa)),
            ("A", viseme(Viseme::Aa)),
            ("O", viseme(Viseme::Oh)),
            ("surprised", Drive::Expression(Expression::Surprised)),
            // VRoid Studio.
            ("Fcl_EYE_Close", merge("eyeBlinkLeft", "eyeBlinkRight")),
            ("Fcl_EYE_Close_L", channel("eyeBlinkLeft")),
            ("Fcl_BRW_Angry", merge("browDownLeft", "browDownRight")),
            ("Fcl_MTH_A", viseme(Viseme::Aa)),
            ("Fcl_MTH_Joy", merge("mouthSmileLeft", "mouthSmileRight")),
            // Ready Player Me / Oculus visemes.
            ("viseme_PP", viseme(Viseme::PP)),
            ("viseme_I", viseme(Viseme::Ih)),
            ("viseme_kk", viseme(Viseme::Kk)),
            // Daz Genesis 8, namespaces and numbered prefixes.
            ("eCTRLEyesClosedL", channel("eyeBlinkLeft")),
            ("facs_bs_EyeBlinkLeft", channel("eyeBlinkLeft")),
            ("blendShape1.jawOpen", channel("jawOpen")),
            ("CC_Base_Body.Mouth_Smile_R", channel("mouthSmileRight")),
            ("A25_Jaw_Open", channel("jawOpen")),
            // Side suffixes with a dot stay sides, not namespaces.
            ("mouthSmile.R", channel("mouthSmileRight")),
        ] {
            assert_eq!(drive(name), Some(want), "{name}");
        }
        for nothing in [
            "Fcl_ALL_Joy",
            "Fcl_HA_Hide",
            "relaxed",
            "neutral",
            "shape_12",
            "target_0",
            "Key 1",
            "jaw",
            "cleft",
        ] {
            assert_eq!(drive(nothing), None, "{nothing}");
        }
    }

    #[test]
    fn every_arkit_name_maps_to_itself() {
        for name in ARKIT_52 {
            assert_eq!(arkit_name(name), Some(name));
        }
    }
}
