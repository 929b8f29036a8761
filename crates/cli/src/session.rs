//! `faceanim session`: the human in the loop on the command line — show a session, correct a
//! blendshape on a frame, add or remove keyframes, apply or clear the preference, estimate
//! again with a fine-tuned adapter, and export the result. Every edit saves the file
//! atomically.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use faceanim_take::{Session, TakeError};

/// `faceanim session`'s arguments.
#[derive(Debug, clap::Args)]
pub struct SessionArgs {
    /// The session file.
    pub session: PathBuf,
    #[command(subcommand)]
    pub action: SessionAction,
}

/// What to do with a session.
#[derive(Debug, clap::Subcommand)]
pub enum SessionAction {
    /// Frames, keyframes, corrections and preference (JSON with --json).
    Show {
        /// Machine-readable JSON.
        #[arg(long)]
        json: bool,
    },
    /// Set blendshapes on a frame: `correct 12 jawOpen=0.8 mouthSmileLeft=0.3`.
    Correct {
        /// The frame (from 0).
        frame: usize,
        /// NAME=VALUE pairs, values in 0..1.
        #[arg(required = true)]
        values: Vec<String>,
    },
    /// Remove a frame's corrections (one blendshape's with NAME).
    Uncorrect {
        /// The frame (from 0).
        frame: usize,
        /// Only this blendshape.
        name: Option<String>,
    },
    /// Make a frame a keyframe.
    AddKeyframe {
        /// The frame (from 0).
        frame: usize,
    },
    /// Stop a frame being a keyframe.
    RemoveKeyframe {
        /// The frame (from 0).
        frame: usize,
    },
    /// Add each blendshape's mean correction to every other frame (clamped to 0..1).
    ApplyPreference,
    /// Take the preference off again.
    ClearPreference,
    /// Say which frame shows the neutral face (relaxed, mouth closed), or `auto` for the least
    /// expressive one, and estimate every frame again relative to it.
    Neutral {
        /// The frame (from 0), or `auto`.
        frame: NeutralFrame,
        /// The adapter that estimated the session.
        #[arg(long)]
        adapter: PathBuf,
    },
    /// Estimate every frame again with an adapter (after `faceanim adapt --finetune`).
    Reestimate {
        /// The adapter.
        #[arg(long)]
        adapter: PathBuf,
    },
    /// Write the animation: .json clip, .glb (needs --character), .csv Live Link Face,
    /// .byoc.csv the seed's CSV, .session.json the session; repeatable.
    Export {
        /// Output files.
        #[arg(short, long, required = true)]
        output: Vec<PathBuf>,
        /// The character, for .glb.
        #[arg(long)]
        character: Option<PathBuf>,
        #[command(flatten)]
        glb: crate::outputs::GlbArgs,
    },
}

/// A frame number or `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NeutralFrame {
    /// Each part of the face at its calmest frame.
    Auto,
    /// This frame.
    Frame(usize),
}

impl std::str::FromStr for NeutralFrame {
    type Err = String;

    fn from_str(text: &str) -> Result<NeutralFrame, String> {
        if text.eq_ignore_ascii_case("auto") {
            return Ok(NeutralFrame::Auto);
        }
        text.parse()
            .map(NeutralFrame::Frame)
            .map_err(|_| format!("'{text}' is neither a frame number nor 'auto'"))
    }
}

fn load(path: &Path) -> anyhow::Result<Session> {
    Session::from_json(&faceanim_files::read_bytes(path)?)
        .with_context(|| format!("reading the session {}", path.display()))
}

fn save(path: &Path, session: &Session) -> anyhow::Result<()> {
    faceanim_files::write_output(path, session.to_json().as_bytes())?;
    Ok(())
}

pub fn run(args: SessionArgs) -> anyhow::Result<()> {
    let path = args.session.as_path();
    let mut session = load(path)?;
    let edit = |e: TakeError| anyhow::anyhow!("{}: {e}", path.display());
    match args.action {
        SessionAction::Show { json } => {
            let corrections: usize = session.edits.corrections.values().map(|c| c.len()).sum();
            let summary = serde_json::json!({
                "source": session.source,
                "character": session.character,
                "frames": session.frames.len(),
                "fps": session.fps,
                "blendshapes": session.blendshapes,
                "keyframes": session.keyframes(),
                "corrections": session.edits.corrections,
                "corrected_values": corrections,
                "preference": session.edits.preference,
                "neutral": session.neutral(),
            });
            if json {
                outln!("{summary}");
            } else {
                outln!(
                    "{}: {} frames at {} fps of {}, for {} ({} blendshapes)",
                    path.display(),
                    session.frames.len(),
                    session.fps,
                    session.source,
                    session.character,
                    session.blendshapes.len()
                );
                outln!("keyframes: {:?}", session.keyframes());
                if let Some(n) = session.neutral() {
                    outln!("neutral: {} ({:?})", n.parts, n.chosen);
                }
                for (frame, values) in &session.edits.corrections {
                    let list: Vec<String> =
                        values.iter().map(|(n, v)| format!("{n}={v:.3}")).collect();
                    outln!("frame {frame}: {}", list.join(" "));
                }
                outln!(
                    "preference: {}",
                    if session.edits.preference.is_some() {
                        "applied"
                    } else {
                        "off"
                    }
                );
            }
            return Ok(());
        }
        SessionAction::Correct { frame, values } => {
            for pair in values {
                let (name, value) = pair.split_once('=').with_context(|| {
                    format!("'{pair}': write NAME=VALUE, for example jawOpen=0.8")
                })?;
                let value: f32 = value
                    .trim()
                    .parse()
                    .map_err(|_| anyhow::anyhow!("'{pair}': '{value}' is not a number"))?;
                session.correct(frame, name.trim(), value).map_err(edit)?;
            }
        }
        SessionAction::Uncorrect { frame, name } => {
            session.uncorrect(frame, name.as_deref()).map_err(edit)?;
        }
        SessionAction::AddKeyframe { frame } => session.add_keyframe(frame).map_err(edit)?,
        SessionAction::RemoveKeyframe { frame } => session.remove_keyframe(frame).map_err(edit)?,
        SessionAction::ApplyPreference => session.apply_preference(),
        SessionAction::ClearPreference => session.clear_preference(),
        SessionAction::Neutral { frame, adapter } => {
            let adapter = crate::input::adapter(&adapter)?;
            let frame = match frame {
                NeutralFrame::Auto => None,
                NeutralFrame::Frame(k) => Some(k),
            };
            session.set_neutral(frame, &adapter).map_err(edit)?;
        }
        SessionAction::Reestimate { adapter } => {
            let adapter = crate::input::adapter(&adapter)?;
            session.reestimate(&adapter).map_err(edit)?;
        }
        SessionAction::Export {
            output,
            character,
            glb,
        } => {
            let formats = crate::outputs::formats_of(&output)?;
            // The GLB and the VRM Animation need the character; the clip and the CSVs come
            // from the session alone.
            let character_path = character;
            let character =
                if character_path.is_some() || formats.iter().any(|f| f.needs_character()) {
                    Some(crate::input::load_or_default(character_path.as_deref())?.character)
                } else {
                    None
                };
            // What opens the mouth through the map beside the character, for its jaw bone.
            let opening = match &character {
                Some(character) => crate::retarget::read_beside(
                    &crate::retarget::default_path(character_path.as_deref(), character),
                    character,
                )?
                .as_ref()
                .and_then(faceanim_export::bones::jaw_opening),
                None => None,
            };
            let stem = crate::input::stem(path, "session");
            let animation = crate::outputs::take_animation(character.as_ref(), &session, &stem)?
                .with_opening(opening);
            crate::outputs::write_all(&output, &formats, &animation, glb)?;
            return Ok(());
        }
    }
    save(path, &session)?;
    eprintln!("saved {}", path.display());
    Ok(())
}
