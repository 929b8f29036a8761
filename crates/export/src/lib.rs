//! # faceanim-export: one exporter for every command and the studio
//!
//! Whatever made the animation (strokes, a capture, a take with strokes over it), it leaves as
//! one [`Animation`]: the character, the weights of each of its targets per frame with the head
//! turn, and the same frames as a clip by name. [`export`] writes it in any [`Format`], chosen
//! by name or by a file's extension; the command line writes the bytes to files, the studio
//! sends them as downloads. The rules that belong to a format live here once:
//!
//! - **GLB** — the user's own file with one morph-weight animation added (every node, skin,
//!   material and texture kept; the sketch's baked corrective targets for arcs and
//!   exaggerations appended to the meshes they move; the head turn shared between the upper
//!   spine, neck and head bones, gaze on the eye bones and `jawOpen` on the jaw bone where the
//!   file has them, see [`bones`]): what
//!   Blender, Unity, Unreal and three.js play. A character made in code or from OBJ files is
//!   written as one mesh, as is the studio's own view ([`view_glb`]).
//! - **Live Link Face CSV** speaks ARKit: it gets the character's own weights when the
//!   character has ARKit-named shapes, else the capture's own ARKit weights when a capture made
//!   the animation (with a note saying so), else zero curves (with a warning).
//! - The **seed toolkit's CSV** and the **session file** need the take's session.
//!
//! ```
//! use faceanim_export::{Animation, Format, export};
//!
//! let character = faceanim_head::default_character();
//! let clip = faceanim_anim::Clip {
//!     fps: 30.0,
//!     blendshapes: vec!["jawOpen".into()],
//!     frames: vec![vec![0.0], vec![1.0]],
//!     head: None,
//!     head_position: None,
//!     presence: None,
//!     arkit: None,
//! };
//! let animation = Animation::from_clip(&character, &clip, "open")?;
//! let format = Format::from_path(std::path::Path::new("open.csv"))?;
//! let csv = export(format, &animation)?;
//! assert!(String::from_utf8(csv.bytes)?.starts_with("Timecode,BlendShapeCount"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod bones;
pub mod glb;
pub mod livelink;
mod meshopt;
pub mod reopen;
mod vrma;

use std::path::Path;

use faceanim_anim::Clip;
use faceanim_rig::Character;
use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::source::GltfSource;
use faceanim_take::Session;

/// The formats an animation leaves in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Format {
    /// The clip JSON (docs/formats.md): every blendshape's weight per frame, by name.
    ClipJson,
    /// The character with the animation, as a binary glTF.
    Glb,
    /// Live Link Face CSV (ARKit's 52 curves and the head and eye angles).
    LiveLinkCsv,
    /// The seed toolkit's CSV: `name.png,w1,…,wN` per frame (needs a session).
    SeedCsv,
    /// The session file, which `faceanim session` and the studio edit (needs a session).
    Session,
    /// VRM Animation (`.vrma`): the animation alone, on a VRM avatar's expressions, humanoid
    /// head and gaze, for any VRM app to play on any VRM (needs a VRM character).
    Vrma,
}

impl Format {
    /// Every format, in the order the studio offers them.
    pub const ALL: [Format; 6] = [
        Format::Glb,
        Format::ClipJson,
        Format::LiveLinkCsv,
        Format::SeedCsv,
        Format::Session,
        Format::Vrma,
    ];

    /// The format a file name asks for, by its ending: `.byoc.csv` the seed's CSV,
    /// `.session.json` a session, `.json` a clip, `.glb` the character (`.vrm` too: a VRM
    /// avatar's file is a GLB), `.csv` Live Link Face,
    /// `.vrma` a VRM Animation;
    /// `-` (standard output) the clip.
    ///
    /// # Errors
    /// [`ExportError::UnknownExtension`] naming the file and the endings understood.
    pub fn from_path(path: &Path) -> Result<Format, ExportError> {
        // Standard output: the clip, the common currency of pipes.
        if path.as_os_str() == "-" {
            return Ok(Format::ClipJson);
        }
        let lower = path.to_string_lossy().to_ascii_lowercase();
        // The longest endings first: `.byoc.csv` is also `.csv`.
        let mut endings: Vec<(Format, &str)> = Format::ALL
            .iter()
            .map(|&f| (f, f.extension()))
            .chain([(Format::ClipJson, "json"), (Format::Glb, "vrm")])
            .collect();
        endings.sort_by_key(|(_, e)| std::cmp::Reverse(e.len()));
        endings
            .into_iter()
            .find(|(_, e)| lower.ends_with(&format!(".{e}")))
            .map(|(f, _)| f)
            .ok_or_else(|| ExportError::UnknownExtension(path.display().to_string()))
    }

    /// The ending of a file in this format (after the dot): `clip.json`, `glb`, `csv`,
    /// `byoc.csv`, `session.json`.
    #[must_use]
    pub fn extension(self) -> &'static str {
        match self {
            Format::ClipJson => "clip.json",
            Format::Glb => "glb",
            Format::LiveLinkCsv => "csv",
            Format::SeedCsv => "byoc.csv",
            Format::Session => "session.json",
            Format::Vrma => "vrma",
        }
    }

    /// The ending for `character`'s file in this format: a GLB written into a VRM avatar's own
    /// file is a VRM, and VRM apps look for `.vrm`; otherwise [`Format::extension`].
    #[must_use]
    pub fn extension_for(self, character: Option<&Character>) -> &'static str {
        match (self, character.and_then(Character::source)) {
            (Format::Glb, Some(source)) if source.is_vrm() => "vrm",
            _ => self.extension(),
        }
    }

    /// The media type of a file in this format.
    #[must_use]
    pub fn mime(self) -> &'static str {
        match self {
            Format::ClipJson | Format::Session => "application/json",
            Format::Glb | Format::Vrma => "model/gltf-binary",
            Format::LiveLinkCsv | Format::SeedCsv => "text/csv",
        }
    }

    /// Whether the format needs the take's session ([`Animation::session`]).
    #[must_use]
    pub fn needs_session(self) -> bool {
        matches!(self, Format::SeedCsv | Format::Session)
    }

    /// Whether the format needs the character (the GLB and the VRM Animation).
    #[must_use]
    pub fn needs_character(self) -> bool {
        matches!(self, Format::Glb | Format::Vrma)
    }

    /// Whether `character` can take the format, known before any work is done for it: the
    /// GLB and the VRM Animation need a character, and the VRM Animation a VRM avatar (it
    /// moves a VRM's expressions and humanoid bones). Commands ask this once the character is
    /// read, so that a take is not made only to be refused.
    ///
    /// # Errors
    /// As [`Format::character_of`], for a format that needs a character.
    pub fn check_character(self, character: Option<&Character>) -> Result<(), ExportError> {
        if self.needs_character() {
            self.character_of(character)?;
        }
        Ok(())
    }

    /// The character the format is written for (one that [needs it](Format::needs_character)):
    /// `character`, when it can take the format.
    ///
    /// # Errors
    /// [`ExportError::NeedsCharacter`] without one, [`ExportError::NotVrm`] for a VRM
    /// Animation of a character that is no VRM.
    pub fn character_of(self, character: Option<&Character>) -> Result<&Character, ExportError> {
        let character = character.ok_or(ExportError::NeedsCharacter(self))?;
        if self == Format::Vrma && !character.source().is_some_and(GltfSource::is_vrm) {
            return Err(ExportError::NotVrm(character.name().to_owned()));
        }
        Ok(character)
    }

    /// What the format is called in messages.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Format::ClipJson => "the clip JSON",
            Format::Glb => "the GLB",
            Format::LiveLinkCsv => "the Live Link Face CSV",
            Format::SeedCsv => "the seed's CSV",
            Format::Session => "the session file",
            Format::Vrma => "the VRM Animation",
        }
    }
}

/// An animated character, ready to export in any [`Format`].
#[derive(Debug, Clone)]
pub struct Animation<'a> {
    /// The character the animation is for: the user's, with the sketch's baked corrective
    /// targets appended when there are any (its first targets are the user's own, in order).
    /// Only the GLB needs it: a session exported on its own still gives the clip and the CSVs.
    pub character: Option<&'a Character>,
    /// Every target's weight per frame (the character's own, then any baked ones) and the head
    /// turn.
    pub animation: MorphAnimation,
    /// The same frames as the character's own weights by name (with the head pose).
    pub clip: Clip,
    /// The take's own ARKit weights, when a capture or lip sync made the animation: Live Link
    /// Face's curves for a character without ARKit names, and the eyes' and jaw's bones.
    pub arkit: Option<Clip>,
    /// The take's session, when the animation is a take's.
    pub session: Option<&'a Session>,
    /// What the eyes and the jaw do, for their bones; `None`: read from `arkit`, else from
    /// `clip` by its names' ARKit meaning.
    pub bones: Option<bones::BoneKeys>,
    /// The sketch the animation was made from (its project's JSON), kept in the GLB so that it
    /// opens again as strokes to edit.
    pub strokes: Option<serde_json::Value>,
    /// None of the character's shapes takes the clip, and its bones do: only they move
    /// ([`Animation::from_clip_through`]).
    pub bones_only: bool,
}

impl<'a> Animation<'a> {
    /// `clip` put on `character` by name (ARKit spellings match), as an animation named `name`.
    /// A body with no blendshapes at all, or one none of whose shapes takes any of the clip's
    /// channels, takes the clip on its bones (head pose, gaze, `jawOpen`; see [`bones`]), and
    /// Live Link Face the clip's own ARKit values. Where the clip keeps the ARKit values its
    /// take was made of ([`Clip::arkit`]), the bones and Live Link Face read those, as the
    /// take's own export did, and another character's shapes take those its columns leave out
    /// ([`Clip::for_character`]).
    ///
    /// # Errors
    /// [`ExportError::Clip`] when no name of the clip is one of the character's;
    /// [`ExportError::NothingForBones`] when the character has no blendshapes and nothing of the
    /// clip turns its bones.
    pub fn from_clip(
        character: &'a Character,
        clip: &Clip,
        name: &str,
    ) -> Result<Animation<'a>, ExportError> {
        Animation::from_clip_through(character, clip, name, None)
    }

    /// [`Animation::from_clip`], the clip's ARKit channels reaching the character through its
    /// retarget `map` where given ([`Clip::retarget_through`]).
    ///
    /// # Errors
    /// As [`Animation::from_clip`].
    pub fn from_clip_through(
        character: &'a Character,
        clip: &Clip,
        name: &str,
        map: Option<&faceanim_retarget::RetargetMap>,
    ) -> Result<Animation<'a>, ExportError> {
        // A take kept with the ARKit values it was made of, put on another character: those
        // values take the shapes its columns leave out.
        let widened = clip.for_character(character);
        let clip = &*widened;
        let mut on_bones = false;
        let retarget = match clip.retarget_through(character, name, map) {
            // None of its shapes takes the clip, but its bones do: the shapes hold still.
            Err(faceanim_anim::ClipError::NothingInCommon { .. })
                if bones::bones_take(character, clip) =>
            {
                on_bones = true;
                faceanim_anim::Retarget {
                    animation: MorphAnimation {
                        name: name.to_owned(),
                        times: (0..clip.frames.len())
                            .map(|f| f as f32 / clip.fps)
                            .collect(),
                        weights: vec![vec![0.0; character.blendshapes().len()]; clip.frames.len()],
                        rotations: clip.head.as_ref().map(|head| {
                            head.iter()
                                .map(|&h| faceanim_anim::head_rotation(h))
                                .collect()
                        }),
                    },
                    unmatched: clip.blendshapes.clone(),
                }
            }
            Err(faceanim_anim::ClipError::NothingInCommon { .. })
                if character.blendshapes().is_empty() =>
            {
                return Err(ExportError::NothingForBones(character.name().to_owned()));
            }
            other => other?,
        };
        let names: Vec<String> = character.blendshape_names();
        // The ARKit values the clip was made of, where it keeps them (its own names leave
        // channels without a column): they turn the bones and fill Live Link Face's curves, as
        // the take's own export did. Else the clip's columns by their ARKit meaning.
        let made_of = clip.arkit_clip();
        Ok(Animation {
            // The clip's own gaze and jaw: a character without eyeLook shapes still has eyes.
            bones: Some(bones::BoneKeys {
                opening: map.and_then(bones::jaw_opening),
                ..bones::BoneKeys::of_take(clip, made_of.as_ref())
            }),
            character: Some(character),
            arkit: made_of.or_else(|| on_bones.then(|| clip.clone())),
            clip: Clip {
                blendshapes: names,
                frames: retarget.animation.weights.clone(),
                arkit: None,
                ..clip.clone()
            },
            animation: retarget.animation,
            session: None,
            strokes: None,
            bones_only: on_bones,
        })
    }

    /// A take as an animation named `name`: its frames (`take`, the session's clip), the
    /// capture's own ARKit weights (`arkit`, for Live Link Face), the session for the formats
    /// that are its own, and a sketch's weights layered on top (`faceanim_take::layer`; its
    /// corrective targets follow the character's own). `character` is needed for a GLB only;
    /// its first targets must be the take's blendshapes, in order.
    ///
    /// # Errors
    /// [`ExportError::OtherCharacter`] when `character`'s targets are not the take's.
    pub fn from_take(
        character: Option<&'a Character>,
        take: &Clip,
        arkit: Option<Clip>,
        session: Option<&'a Session>,
        sketch: Option<&MorphAnimation>,
        name: &str,
    ) -> Result<Animation<'a>, ExportError> {
        let own = take.blendshapes.len();
        if let Some(character) = character {
            let shapes = character.blendshapes();
            // Only a sketch's corrective targets may follow the take's own.
            let fits = if sketch.is_some() {
                shapes.len() >= own
            } else {
                shapes.len() == own
            };
            if !fits
                || shapes
                    .iter()
                    .zip(&take.blendshapes)
                    .any(|(b, n)| b.name() != n)
            {
                return Err(ExportError::OtherCharacter {
                    take: session.map_or_else(
                        || "the take".to_owned(),
                        |s| format!("the take of {}", s.character),
                    ),
                    character: character.name().to_owned(),
                    blendshapes: own,
                });
            }
        }
        let layered = faceanim_take::layer(take, sketch, own, name);
        Ok(Animation {
            character,
            animation: layered.animation,
            clip: layered.clip,
            arkit,
            session,
            bones: None,
            strokes: None,
            bones_only: false,
        })
    }
}

/// An exported file's bytes, and what the user should know about them.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The file.
    pub bytes: Vec<u8>,
    /// Notes and warnings (a fallback taken, curves left at zero).
    pub notes: Vec<String>,
}

/// Why an export could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// A file name whose ending names no format.
    #[error(
        "{0}: the name must end in .json (clip), .glb or .vrm (character with the animation), .csv (Live Link Face), .byoc.csv (the seed's CSV), .session.json (the session) or .vrma (VRM Animation)"
    )]
    UnknownExtension(String),
    /// The format needs a take's session and the animation has none.
    #[error("{} needs a capture's session (track with --adapter, or the studio's Capture tab)", .0.describe())]
    NeedsSession(Format),
    /// The take was made for another character than the one given.
    #[error(
        "{take} ({blendshapes} blendshapes) is not for {character}: give the take's own character (with --character)"
    )]
    OtherCharacter {
        /// The take: whose it is, when its session says.
        take: String,
        /// The character given.
        character: String,
        /// How many blendshapes the take has.
        blendshapes: usize,
    },
    /// The format needs the character and the animation has none.
    #[error("{} needs the character: give it with --character", .0.describe())]
    NeedsCharacter(Format),
    /// A VRM Animation was asked for a character that is no VRM.
    #[error(
        "{0} is no VRM avatar: a VRM Animation (.vrma) moves a VRM's expressions and humanoid bones; give a .vrm character, or write .glb"
    )]
    NotVrm(String),
    /// Nothing a VRM Animation carries moves.
    #[error(
        "nothing in the animation moves {0}'s VRM expressions, head or gaze: there is no VRM Animation to write"
    )]
    NothingToCarry(String),
    /// A clip for a body with no blendshapes that turns none of its bones.
    #[error(
        "{0} has no blendshapes, and nothing of the clip turns its bones (a head pose on its head, eyeLook on its eyes, jawOpen on its jaw): make ARKit's 52 shapes on it with `faceanim generate-shapes`"
    )]
    NothingForBones(String),
    /// The clip cannot be put on the character.
    #[error(transparent)]
    Clip(#[from] faceanim_anim::ClipError),
    /// The GLB writer refused the animation.
    #[error(transparent)]
    Glb(#[from] glb::GlbError),
}

/// Writes `animation` in `format` (a GLB compressed as its input was).
///
/// # Errors
/// [`ExportError::NeedsSession`] for the seed's CSV or the session without a session;
/// [`ExportError::Glb`] when the animation does not fit the character.
pub fn export(format: Format, animation: &Animation<'_>) -> Result<Exported, ExportError> {
    export_with(format, animation, glb::Compression::AsRead)
}

/// [`export`], with a GLB written into the user's file compressed as `compression` says; a
/// note says when it is meshopt-compressed, and how to write it plain.
///
/// # Errors
/// As [`export`].
pub fn export_with(
    format: Format,
    animation: &Animation<'_>,
    compression: glb::Compression,
) -> Result<Exported, ExportError> {
    let mut notes = Vec::new();
    let bytes = match format {
        Format::ClipJson => clip_json(animation, &mut notes),
        Format::Glb => {
            // Gaze and jaw for the bones, from the capture's own ARKit values when there are
            // any, else from the frames by their names' ARKit meaning.
            let keys = animation.bone_keys();
            let character = format.character_of(animation.character)?;
            let bytes = match character.source() {
                Some(source) => {
                    if source.meshopt() && compression == glb::Compression::AsRead {
                        notes.push(
                            "meshopt-compressed as the file was read (EXT_meshopt_compression); \
                             --uncompressed writes it plain for tools without a meshopt decoder \
                             (Blender's importer)"
                                .to_owned(),
                        );
                    }
                    glb::export_into_source_with(
                        character,
                        std::slice::from_ref(&animation.animation),
                        &[Some(&keys)],
                        compression,
                    )?
                }
                None => view_glb(character, Some(&animation.animation))?,
            };
            match &animation.strokes {
                Some(strokes) => glb::with_strokes(bytes, &animation.animation.name, strokes)?,
                None => bytes,
            }
        }
        Format::LiveLinkCsv => {
            livelink::to_csv(&live_link_curves(animation, &mut notes)).into_bytes()
        }
        Format::SeedCsv => session(format, animation)?.to_seed_csv().into_bytes(),
        Format::Session => session(format, animation)?.to_json().into_bytes(),
        Format::Vrma => vrma::vrma(animation, &mut notes)?,
    };
    Ok(Exported { bytes, notes })
}

/// The GLB writer: `character` with `animation` (when given), as a binary glTF: the user's
/// own file with the animation added when the character came from a glTF file, else the
/// character as one mesh.
///
/// # Errors
/// [`ExportError::Glb`] when the animation does not fit the character.
pub fn glb(
    character: &Character,
    animation: Option<&MorphAnimation>,
) -> Result<Vec<u8>, ExportError> {
    match character.source() {
        Some(_) => Ok(glb::export_into_source(
            character,
            animation.map(std::slice::from_ref).unwrap_or_default(),
        )?),
        None => view_glb(character, animation),
    }
}

/// The character as faceanim sees it, as one mesh whose targets are the character's own in
/// order, with `animation`: what the studio's page plays and picks on (its vertex and target
/// indices are the character's), whatever file the character came from. Where the file has a
/// head bone the mesh is skinned to the face's bones ([`bones::ViewRig`]), so the page turns
/// spine, neck, head, eyes and jaw as the export does.
///
/// # Errors
/// [`ExportError::Glb`] when the animation does not fit the character.
pub fn view_glb(
    character: &Character,
    animation: Option<&MorphAnimation>,
) -> Result<Vec<u8>, ExportError> {
    Ok(glb::export_glb_skinned(
        character,
        animation.map(std::slice::from_ref).unwrap_or_default(),
        // No map: the animation's jaw keys come from the character's own names, which then
        // name what opens its mouth too.
        bones::ViewRig::of(character, None).as_ref(),
    )?)
}

impl Animation<'_> {
    /// This animation with what opens the character's mouth through its retarget map
    /// (`opening`: its own weights at `jawOpen` 1, [`bones::jaw_opening`]), which the jaw
    /// bone's turn is measured on where the character's names do not say
    /// ([`bones::BoneKeys::opening`]).
    #[must_use]
    pub fn with_opening(self, opening: Option<Vec<f32>>) -> Self {
        let bones = bones::BoneKeys {
            opening,
            ..self.bone_keys()
        };
        Animation {
            bones: Some(bones),
            ..self
        }
    }

    /// What the eyes and the jaw do ([`Animation::bones`]; where not given, from the capture's
    /// own ARKit values, else from the frames by their names' ARKit meaning).
    pub(crate) fn bone_keys(&self) -> bones::BoneKeys {
        self.bones
            .clone()
            .unwrap_or_else(|| bones::BoneKeys::of_take(&self.clip, self.arkit.as_ref()))
    }
}

/// The clip JSON: the character's own weights by name, with the ARKit values the take was made
/// of where its names leave channels that move without a column ([`kept_arkit`]); for a body
/// with no blendshapes, whose bones follow the take's ARKit values, those values (with the head
/// pose). So the clip put on it again (`export --clip`) turns the same bones.
fn clip_json(animation: &Animation<'_>, notes: &mut Vec<String>) -> Vec<u8> {
    match &animation.arkit {
        Some(arkit)
            if animation.clip.blendshapes.is_empty()
                && arkit.frames.len() == animation.clip.frames.len() =>
        {
            notes.push(
                "the character has no blendshapes: the clip holds the ARKit values its eye and \
                 jaw bones follow, with the head pose"
                    .to_owned(),
            );
            Clip {
                head: animation.clip.head.clone(),
                head_position: animation.clip.head_position.clone(),
                presence: animation.clip.presence.clone(),
                ..arkit.clone()
            }
            .to_json()
            .into_bytes()
        }
        _ => Clip {
            arkit: kept_arkit(animation, notes),
            ..animation.clip.clone()
        }
        .to_json()
        .into_bytes(),
    }
}

/// The take's own ARKit values ([`Animation::arkit`]) as the clip JSON keeps them
/// ([`Clip::arkit`]): ARKit's 52 per frame, where a channel that moves in them has no column
/// among the character's names (a VRoid avatar's gaze, which its eye bones show; the jaw of a
/// rig whose names say nothing); `None` where the columns carry all that moves.
fn kept_arkit(animation: &Animation<'_>, notes: &mut Vec<String>) -> Option<Vec<Vec<f32>>> {
    let arkit = animation.arkit.as_ref()?;
    if arkit.frames.len() != animation.clip.frames.len() {
        return None;
    }
    let rows = arkit.arkit_rows();
    let left: Vec<&str> = faceanim_anim::left_out(&animation.clip.blendshapes, &rows)
        .into_iter()
        .map(|c| c.name())
        .collect();
    if left.is_empty() {
        return None;
    }
    let more = match left.len() {
        0..=3 => String::new(),
        n => format!(" and {} more", n - 3),
    };
    notes.push(format!(
        "the clip keeps the ARKit values the take was made of (\"arkit\") for what its blendshapes have no column for ({}{more}): the eye and jaw bones and Live Link Face read them there",
        left[..left.len().min(3)].join(", ")
    ));
    Some(rows)
}

fn session<'a>(format: Format, animation: &Animation<'a>) -> Result<&'a Session, ExportError> {
    animation.session.ok_or(ExportError::NeedsSession(format))
}

/// Live Link Face speaks ARKit (see the crate docs): each curve from the character's own
/// shape for that channel where it has one (the take as it is, corrections and all), else
/// from the ARKit weights the take was made of (a capture's scores, lip sync's visemes).
fn live_link_curves<'a>(
    animation: &'a Animation<'_>,
    notes: &mut Vec<String>,
) -> std::borrow::Cow<'a, Clip> {
    let name = match (animation.character, animation.session) {
        (Some(character), _) => character.name().to_owned(),
        (None, Some(session)) => session.character.clone(),
        (None, None) => "the character".to_owned(),
    };
    // The channels the character's own shapes carry: an ARKit-named shape the take moves (one
    // it leaves at rest while the take moves the face through others — a VRoid avatar's ARKit
    // shapes beside the vowels lip sync moves — says nothing of the face).
    let own: Vec<&str> = animation
        .clip
        .blendshapes
        .iter()
        .enumerate()
        .filter(|(_, n)| {
            faceanim_rig::names::drive(n)
                .is_some_and(|d| !matches!(d, faceanim_rig::names::Drive::Expression(_)))
        })
        .filter(|(k, _)| {
            animation.arkit.is_none()
                || animation
                    .clip
                    .frames
                    .iter()
                    .any(|row| row.get(*k).is_some_and(|w| *w != 0.0))
        })
        .filter_map(|(_, n)| faceanim_rig::names::arkit_name(n))
        .collect();
    let Some(made_of) = animation
        .arkit
        .as_ref()
        .filter(|a| a.frames.len() == animation.clip.frames.len())
    else {
        if own.is_empty() {
            notes.push(format!(
                "warning: Live Link Face speaks ARKit and {name} has no ARKit-named blendshapes; the curves are zero"
            ));
        }
        return std::borrow::Cow::Borrowed(&animation.clip);
    };
    if own.is_empty() {
        let named = animation
            .clip
            .blendshapes
            .iter()
            .any(|n| faceanim_rig::names::arkit_name(n).is_some());
        notes.push(if named {
            format!(
                "note: {name}'s ARKit-named blendshapes stay at rest in this take; Live Link Face gets the ARKit weights the take was made of"
            )
        } else {
            format!(
                "note: {name} has no ARKit-named blendshapes; Live Link Face gets the ARKit weights the take was made of"
            )
        });
        return std::borrow::Cow::Borrowed(made_of);
    }
    // The take's ARKit columns for the channels the character has no shape for.
    let filled: Vec<usize> = made_of
        .blendshapes
        .iter()
        .enumerate()
        .filter(|(_, n)| faceanim_rig::names::arkit_name(n).is_some_and(|c| !own.contains(&c)))
        .map(|(k, _)| k)
        .collect();
    if filled.is_empty() {
        return std::borrow::Cow::Borrowed(&animation.clip);
    }
    notes.push(format!(
        "note: {} Live Link Face curve(s) {name} has no ARKit-named shape for come from the ARKit weights the take was made of",
        filled.len()
    ));
    // The character's columns but those (at rest) of the channels filled, then the filled.
    let replaced: Vec<&str> = filled
        .iter()
        .filter_map(|&k| faceanim_rig::names::arkit_name(&made_of.blendshapes[k]))
        .collect();
    let kept: Vec<usize> = (0..animation.clip.blendshapes.len())
        .filter(|&k| {
            faceanim_rig::names::arkit_name(&animation.clip.blendshapes[k])
                .is_none_or(|c| !replaced.contains(&c))
        })
        .collect();
    let mut merged = animation.clip.clone();
    merged.blendshapes = kept
        .iter()
        .map(|&k| animation.clip.blendshapes[k].clone())
        .chain(filled.iter().map(|&k| made_of.blendshapes[k].clone()))
        .collect();
    for (row, from) in merged.frames.iter_mut().zip(&made_of.frames) {
        *row = kept
            .iter()
            .map(|&k| row.get(k).copied().unwrap_or(0.0))
            .chain(filled.iter().map(|&k| from.get(k).copied().unwrap_or(0.0)))
            .collect();
    }
    std::borrow::Cow::Owned(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_ending_longest_first() {
        let of = |name: &str| Format::from_path(Path::new(name));
        assert_eq!(of("a/take.json"), Ok(Format::ClipJson));
        assert_eq!(of("take.clip.json"), Ok(Format::ClipJson));
        assert_eq!(of("take.session.json"), Ok(Format::Session));
        assert_eq!(of("TAKE.GLB"), Ok(Format::Glb));
        // A VRM avatar's file is a GLB; its animation alone is a VRM Animation.
        assert_eq!(of("avatar.vrm"), Ok(Format::Glb));
        assert_eq!(of("take.vrma"), Ok(Format::Vrma));
        assert_eq!(of("take.csv"), Ok(Format::LiveLinkCsv));
        assert_eq!(of("take.byoc.csv"), Ok(Format::SeedCsv));
        let error = of("take.fbx").map(|_| ()).unwrap_err().to_string();
        assert!(
            error.starts_with("take.fbx: the name must end in .json"),
            "{error}"
        );
    }

    #[test]
    fn live_link_face_takes_each_curve_from_the_shape_that_carries_it() {
        let clip = |names: &[&str], frames: Vec<Vec<f32>>| Clip::of_weights(30.0, names, frames);
        // The character's own blink moves (a correction made it 0.9); its smile shape stays
        // at rest while its vowel opens the mouth; the take was made of a blink, a smile and
        // an open jaw.
        let own = clip(
            &["eyeBlink_L", "mouthSmile_L", "Fcl_MTH_A"],
            vec![vec![0.9, 0.0, 0.5]; 3],
        );
        let made_of = clip(
            &["eyeBlinkLeft", "mouthSmileLeft", "jawOpen"],
            vec![vec![0.6, 0.3, 0.7]; 3],
        );
        let curves = |arkit: Option<Clip>| {
            let animation = Animation {
                character: None,
                animation: MorphAnimation {
                    name: "take".into(),
                    times: vec![0.0, 1.0 / 30.0, 2.0 / 30.0],
                    weights: own.frames.clone(),
                    rotations: None,
                },
                clip: own.clone(),
                arkit,
                session: None,
                bones: None,
                strokes: None,
                bones_only: false,
            };
            let exported =
                export(Format::LiveLinkCsv, &animation).unwrap_or_else(|e| panic!("{e}"));
            let text = String::from_utf8(exported.bytes).unwrap_or_default();
            let back = livelink::from_csv(&text).unwrap_or_else(|e| panic!("{e}"));
            let value = |name: &str| {
                back.blendshapes
                    .iter()
                    .position(|n| n == name)
                    .map_or(0.0, |c| back.frames[1][c])
            };
            (
                [
                    value("eyeBlinkLeft"),
                    value("mouthSmileLeft"),
                    value("jawOpen"),
                ],
                exported.notes,
            )
        };
        let near = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
        let (values, notes) = curves(Some(made_of));
        assert!(near(values, [0.9, 0.3, 0.7]), "{values:?} {notes:?}");
        assert!(
            notes
                .iter()
                .any(|n| n.contains("2 Live Link Face curve(s)")),
            "{notes:?}"
        );
        // Without what the take was made of, the character's own shapes are all there is.
        let (values, _) = curves(None);
        assert!(near(values, [0.9, 0.0, 0.0]), "{values:?}");
    }

    #[test]
    fn a_take_is_put_only_on_its_own_character() {
        let character = faceanim_head::default_character();
        let names = character.blendshape_names();
        let take = Clip {
            fps: 30.0,
            blendshapes: names.clone(),
            frames: vec![vec![0.25; names.len()]; 3],
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        };
        let animation =
            Animation::from_take(Some(&character), &take, None, None, None, "take").unwrap();
        assert_eq!(animation.clip.frames, take.frames);
        assert_eq!(animation.animation.weights.len(), 3);
        // Another character's take (one shape fewer) is refused by name, not written.
        let other = Clip {
            blendshapes: names[1..].to_vec(),
            frames: vec![vec![0.25; names.len() - 1]; 3],
            ..take.clone()
        };
        let refused =
            Animation::from_take(Some(&character), &other, None, None, None, "take").unwrap_err();
        assert!(
            matches!(refused, ExportError::OtherCharacter { blendshapes, .. } if blendshapes == names.len() - 1),
            "{refused}"
        );
        // Without a character (the clip and the CSVs need none) any take is exported.
        assert!(Animation::from_take(None, &other, None, None, None, "take").is_ok());
    }

    #[test]
    fn a_clip_leaves_in_every_format_that_needs_no_session_or_a_vrm() {
        let character = faceanim_head::default_character();
        let clip = Clip {
            fps: 24.0,
            blendshapes: vec!["jawOpen".into(), "eyeBlinkLeft".into()],
            frames: vec![vec![0.0, 1.0], vec![1.0, 0.0]],
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        };
        let animation = Animation::from_clip(&character, &clip, "test").unwrap_or_else(|e| {
            panic!("{e}");
        });
        for format in Format::ALL {
            let result = export(format, &animation);
            if format.needs_session() {
                assert_eq!(result, Err(ExportError::NeedsSession(format)));
            } else if format == Format::Vrma {
                // The built-in head is no VRM: a VRM Animation moves a VRM's expressions.
                assert!(
                    matches!(&result, Err(ExportError::NotVrm(name)) if name == character.name()),
                    "{result:?}"
                );
            } else {
                let exported = result.unwrap_or_else(|e| panic!("{format:?}: {e}"));
                assert!(!exported.bytes.is_empty() && exported.notes.is_empty());
            }
        }
    }
}
