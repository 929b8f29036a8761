//! What faceanim writes opens again: a GLB or VRM with a morph-weight animation (an export, or
//! a file animated in another tool), a VRM Animation (`.vrma`) and a Live Link Face CSV read
//! back as a [`Clip`] by name, ready to be a take on any character whose blendshapes answer to
//! those names. (Clip JSON and session files are read by their own crates.)
//!
//! ```
//! use faceanim_export::{Animation, Format, export, reopen};
//!
//! let character = faceanim_head::default_character();
//! let clip = faceanim_anim::Clip {
//!     fps: 30.0,
//!     blendshapes: vec!["jawOpen".into()],
//!     frames: vec![vec![0.0], vec![0.5], vec![1.0]],
//!     head: None,
//!     head_position: None,
//!     presence: None,
//!     arkit: None,
//! };
//! let animation = Animation::from_clip(&character, &clip, "open")?;
//! let glb = export(Format::Glb, &animation)?;
//! let back = reopen::clip_of_file("open.glb", &glb.bytes)?;
//! let jaw = back.clip.blendshapes.iter().position(|n| n == "jawOpen").unwrap();
//! assert!((back.clip.frames[1][jaw] - 0.5).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use faceanim_anim::Clip;
use faceanim_rig::import::{ImportError, NoExternalResources, VrmaTake, import_gltf, import_vrma};

/// A file read back as a clip.
#[derive(Debug, Clone, PartialEq)]
pub struct Reopened {
    /// Its frames by blendshape name, at its rate.
    pub clip: Clip,
    /// What was read: `animation 'take' (2.4 s at 30 fps)`, `Live Link Face recording`.
    pub what: String,
    /// The animation's name in the file (the file's stem for a Live Link recording).
    pub name: String,
}

/// Why a file could not be read back as a take; each names the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReopenError {
    /// An ending that is no take's.
    #[error(
        "{0}: a take opens from .glb, .vrm or .gltf (its animation), .vrma (VRM Animation), .csv (Live Link Face) or .json (a clip or a session)"
    )]
    UnknownExtension(String),
    /// The glTF could not be read.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// The glTF holds no animation that moves morph targets, or the face's bones alone.
    #[error(
        "{0}: it has no animation of morph targets, or of the face's bones alone, to open as a take (its blendshapes are the character's: open it with `faceanim studio` to animate it)"
    )]
    NoAnimation(String),
    /// The CSV is not a Live Link Face recording.
    #[error("{name}: {source}")]
    Csv {
        /// The file.
        name: String,
        /// The line and the problem.
        source: crate::livelink::CsvError,
    },
}

/// Whether a file named `name` is one [`clip_of_file`] reads.
#[must_use]
pub fn reads(name: &str) -> bool {
    extension(name).is_some_and(|e| ["glb", "vrm", "gltf", "csv", "vrma"].contains(&e.as_str()))
}

fn extension(name: &str) -> Option<String> {
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".byoc.csv") {
        // The seed's CSV is weights without names: only a session of the same character
        // gives it meaning.
        return None;
    }
    std::path::Path::new(&lower)
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
}

/// The morph-weight animation `character`'s own file holds (the last one faceanim wrote, else
/// its first) as a clip of the character's blendshapes by name, with the head pose and the
/// gaze its bones turn; `None` for a file without one (or a character made in code). A body
/// with no blendshapes, whose animation faceanim wrote on its bones, opens as the ARKit values
/// its eyes and jaw were turned by (eyeLook, and jawOpen at [`DEFAULT_JAW_DEGREES`]), with
/// the head pose: the clip its export takes.
///
/// [`DEFAULT_JAW_DEGREES`]: crate::bones::DEFAULT_JAW_DEGREES
#[must_use]
pub fn animation_of(character: &faceanim_rig::Character) -> Option<Reopened> {
    let faceanim_rig::turns::Take {
        animation,
        fps,
        gaze,
        jaw,
    } = character.source()?.take()?;
    let seconds = animation.times.last().copied().unwrap_or(0.0);
    let head = animation.rotations.map(|turns| {
        turns
            .into_iter()
            .map(|q| faceanim_anim::head_angles(q).unwrap_or([0.0; 3]))
            .collect()
    });
    let what = format!(
        "animation '{}' ({seconds:.2} s at {fps} fps)",
        faceanim_rig::excerpt(&animation.name)
    );
    let (blendshapes, frames) = if character.blendshapes().is_empty() {
        turned_channels(animation.times.len(), gaze, jaw)
    } else {
        let blendshapes = character.blendshape_names();
        let frames = with_gaze(&blendshapes, animation.weights, gaze);
        (blendshapes, frames)
    };
    Some(Reopened {
        what,
        name: animation.name,
        clip: Clip {
            fps,
            blendshapes,
            frames,
            head,
            head_position: None,
            presence: None,
            arkit: None,
        },
    })
}

/// `frames` of `blendshapes` with the eyes' `gaze` (turned by bone) given back to the eyeLook
/// shapes (the export holds those shapes still where the bones turn the eyes, not to turn them
/// twice).
fn with_gaze(
    blendshapes: &[String],
    mut frames: Vec<Vec<f32>>,
    gaze: Option<Vec<[[f32; 2]; 2]>>,
) -> Vec<Vec<f32>> {
    let Some(gaze) = gaze else {
        return frames;
    };
    let columns: Vec<(usize, &str)> = blendshapes
        .iter()
        .enumerate()
        .filter_map(|(c, n)| Some((c, faceanim_rig::names::arkit_name(n)?)))
        .filter(|(_, a)| faceanim_rig::names::is_gaze(a))
        .collect();
    for (row, eyes) in frames.iter_mut().zip(gaze) {
        let looks = faceanim_rig::bones::arkit_from_gaze(eyes);
        for &(c, channel) in &columns {
            if let (Some(slot), Some((_, v))) =
                (row.get_mut(c), looks.iter().find(|(n, _)| *n == channel))
            {
                *slot = slot.max(*v);
            }
        }
    }
    frames
}

/// The ARKit channels turned bones were turned by, over `frames` frames: each eye's gaze as
/// its eyeLook values, the jaw's opening as jawOpen (at [`crate::bones::DEFAULT_JAW_DEGREES`]
/// for 1, as the export opens a jaw with no jaw-open shape beside it).
fn turned_channels(
    frames: usize,
    gaze: Option<Vec<[[f32; 2]; 2]>>,
    jaw: Option<Vec<f32>>,
) -> (Vec<String>, Vec<Vec<f32>>) {
    let mut names: Vec<String> = Vec::new();
    let mut rows: Vec<Vec<f32>> = vec![Vec::new(); frames];
    if let Some(gaze) = gaze {
        let looks = |k: usize| {
            let eyes = gaze.get(k).or(gaze.last()).copied().unwrap_or_default();
            faceanim_rig::bones::arkit_from_gaze(eyes)
        };
        names.extend(looks(0).iter().map(|(n, _)| (*n).to_owned()));
        for (k, row) in rows.iter_mut().enumerate() {
            row.extend(looks(k).iter().map(|(_, v)| *v));
        }
    }
    if let Some(jaw) = jaw {
        names.push("jawOpen".to_owned());
        for (k, row) in rows.iter_mut().enumerate() {
            let degrees = jaw.get(k).or(jaw.last()).copied().unwrap_or(0.0);
            row.push((degrees / crate::bones::DEFAULT_JAW_DEGREES).clamp(0.0, 1.0));
        }
    }
    (names, rows)
}

/// Reads `bytes` (the file `name`) as a clip: a glTF's morph-weight animation (the last one
/// faceanim wrote, else its first) played at its keys' rate on its own blendshapes' names, a
/// VRM Animation on its expressions' names, or a Live Link Face CSV.
///
/// # Errors
/// A [`ReopenError`] naming the file.
pub fn clip_of_file(name: &str, bytes: &[u8]) -> Result<Reopened, ReopenError> {
    match extension(name).as_deref() {
        Some("glb" | "vrm" | "gltf") => {
            let imported = import_gltf(bytes, name, &NoExternalResources)?;
            animation_of(&imported.character)
                .ok_or_else(|| ReopenError::NoAnimation(name.to_owned()))
        }
        Some("vrma") => Ok(vrma_clip(import_vrma(bytes, name)?)),
        Some("csv") => {
            let text = String::from_utf8_lossy(bytes);
            let clip = crate::livelink::from_csv(&text).map_err(|source| ReopenError::Csv {
                name: name.to_owned(),
                source,
            })?;
            Ok(Reopened {
                name: std::path::Path::new(name)
                    .file_stem()
                    .map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
                what: format!(
                    "Live Link Face recording ({} frames at {} fps)",
                    clip.frames.len(),
                    clip.fps
                ),
                clip,
            })
        }
        _ => Err(ReopenError::UnknownExtension(name.to_owned())),
    }
}

/// A VRM Animation as a clip: its expressions by name (a VRM avatar's expressions are
/// blendshapes of the character by those names), the gaze as ARKit's eyeLook values, the head
/// pose.
fn vrma_clip(take: VrmaTake) -> Reopened {
    let VrmaTake {
        name,
        fps,
        mut expressions,
        mut frames,
        head,
        gaze,
    } = take;
    if let Some(gaze) = &gaze {
        let looks = |k: usize| {
            let [yaw, pitch] = gaze[k.min(gaze.len().saturating_sub(1))];
            faceanim_rig::bones::arkit_from_gaze([[yaw, pitch]; 2])
        };
        expressions.extend(looks(0).iter().map(|(n, _)| (*n).to_owned()));
        for (k, row) in frames.iter_mut().enumerate() {
            row.extend(looks(k).iter().map(|(_, v)| *v));
        }
    }
    let seconds = frames.len().saturating_sub(1) as f32 / fps;
    Reopened {
        what: format!(
            "VRM Animation '{}' ({seconds:.2} s at {fps} fps)",
            faceanim_rig::excerpt(&name)
        ),
        name,
        clip: Clip {
            fps,
            blendshapes: expressions,
            frames,
            head: head.map(|turns| {
                turns
                    .into_iter()
                    .map(|q| faceanim_anim::head_angles(q).unwrap_or([0.0; 3]))
                    .collect()
            }),
            head_position: None,
            presence: None,
            arkit: None,
        },
    }
}
