//! # faceanim-speech: speech drives the mouth
//!
//! A recording of speech becomes the character's mouth animation:
//!
//! 1. [`audio`]: the sound at 16 kHz mono (WAV read directly; MP3, Ogg, FLAC and the sound of
//!    a video through `ffmpeg`), and where a voice is heard in it;
//! 2. [`phones`]: phones and their times from CMU PocketSphinx ([`faceanim_sphinx_sys`]):
//!    the transcript (what it says aloud: [`script`]) aligned to the sound when there is one;
//!    else the words recognised and spoken as the dictionary says, or a phone loop;
//! 3. [`visemes`]: phones to the 15 Oculus visemes, with animators' timing rules
//!    (anticipation, a minimum hold, closed lips on P/B/M, pauses that relax or close);
//! 4. [`mouth`]: visemes onto the character's own shapes — its visemes by name, or its ARKit
//!    mouth shapes through a table the user can replace.
//!
//! With [`face`], blinks and brows go with the speech too.
//!
//! Live, from a microphone, [`listen`] classes each 10 ms as it arrives with a small
//! classifier learned from the user's own voice (calibrated on a read passage, refined by the
//! recogniser as they speak).
//!
//! ```no_run
//! let character = faceanim_head::default_character();
//! let sound = faceanim_speech::audio::Sound::read(std::path::Path::new("line.wav"))?;
//! let lip_sync = faceanim_speech::lip_sync(
//!     &sound, None, &character, &Default::default(), 30.0, faceanim_speech::Recognition::Words)?;
//! assert_eq!(lip_sync.frames[0].len(), character.blendshapes().len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod abbreviations;
mod adapt;
pub mod audio;
pub mod chinese;
pub mod face;
pub mod features;
pub mod german;
mod holds;
pub mod japanese;
pub mod korean;
pub mod listen;
pub mod mouth;
pub mod ordinals;
pub mod phones;
pub mod pronounce;
pub mod recognition;
pub mod script;
pub mod synthesis;
pub mod visemes;
mod warp;

use faceanim_rig::Character;

pub use audio::{AudioError, Sound};
pub use mouth::{Mouth, MouthError, MouthTable, Route};
pub use phones::{Phone, PhoneError, Recognition};
pub use visemes::Track;
pub use warp::Voice;

/// Why lip sync failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SpeechError {
    /// The sound could not be read.
    #[error(transparent)]
    Audio(#[from] AudioError),
    /// Phones could not be recognised.
    #[error(transparent)]
    Phones(#[from] PhoneError),
    /// The character has no mouth to drive.
    #[error(transparent)]
    Mouth(#[from] MouthError),
}

/// A sound's lip sync on a character.
#[derive(Debug, Clone)]
pub struct LipSync {
    /// Frames per second.
    pub fps: f32,
    /// One row of the character's weights per frame, covering the whole sound.
    pub frames: Vec<Vec<f32>>,
    /// The visemes over time.
    pub track: Track,
    /// The phones recognised.
    pub phones: Vec<Phone>,
    /// How they were recognised.
    pub recognition: Recognition,
    /// How the visemes reached the character.
    pub route: Route,
    /// How many of the character's shapes move.
    pub shapes_moved: usize,
    /// What was done instead of what was asked (a transcript that could not be used).
    pub notes: Vec<String>,
}

impl LipSync {
    /// Each frame as ARKit's 52 channels ([`faceanim_rig::names::ARKIT_52`] order), its
    /// visemes by `table` ([`Mouth::arkit`]): what the take is made of, whatever the
    /// character's shapes (Live Link Face's curves, a jaw bone's opening).
    #[must_use]
    pub fn arkit(&self, table: &MouthTable) -> Vec<Vec<f32>> {
        let mouth = Mouth::arkit(table);
        let mut rows: Vec<Vec<f32>> = self
            .track
            .sample(self.fps)
            .iter()
            .map(|v| mouth.weights(v))
            .collect();
        rows.resize(
            self.frames.len(),
            vec![0.0; faceanim_rig::names::ARKIT_52.len()],
        );
        rows
    }
}

/// Lip sync of `sound` on `character` at `fps`, aligned to `transcript` when given, else
/// recognised by `blind` ([`Recognition::Words`] or [`Recognition::PhoneLoop`]).
///
/// # Errors
/// [`SpeechError`] when the character has no mouth or the recogniser fails.
pub fn lip_sync(
    sound: &Sound,
    transcript: Option<&str>,
    character: &Character,
    table: &MouthTable,
    fps: f32,
    blind: Recognition,
) -> Result<LipSync, SpeechError> {
    lip_sync_with(
        sound,
        transcript,
        None,
        &Mouth::of(character, table)?,
        fps,
        blind,
        Voice::Auto,
    )
}

/// Lip sync of `sound` in `language` (an eSpeak NG voice name; English when `None`: see
/// [`recognition::recognise`]) through `mouth` (one read through the character's adapter:
/// [`Mouth::from_readings`]), heard through the vocal tract `voice` says, as [`lip_sync`]
/// does.
///
/// # Errors
/// [`SpeechError`] when the recogniser fails.
pub fn lip_sync_with(
    sound: &Sound,
    transcript: Option<&str>,
    language: Option<&str>,
    mouth: &Mouth,
    fps: f32,
    blind: Recognition,
    voice: Voice,
) -> Result<LipSync, SpeechError> {
    Ok(read_loaded(sound, transcript, language, blind, None, voice)?.on(mouth, fps))
}

/// A sound's visemes, before they are put on a character: what [`read`] finds.
#[derive(Debug, Clone)]
pub struct Reading {
    /// The visemes over time.
    pub track: Track,
    /// The phones found.
    pub phones: Vec<Phone>,
    /// How they were found.
    pub recognition: Recognition,
    /// What was done instead of what was asked.
    pub notes: Vec<String>,
}

/// The visemes of `sound` in `language`, aligned to `transcript` or recognised by `blind` (see
/// [`recognition::recognise`]): the part of a lip sync that needs no character, so that a caller
/// can load the character meanwhile.
///
/// # Errors
/// [`SpeechError`] when the recogniser fails.
pub fn read(
    sound: &Sound,
    transcript: Option<&str>,
    language: Option<&str>,
    blind: Recognition,
) -> Result<Reading, SpeechError> {
    read_loaded(sound, transcript, language, blind, None, Voice::Auto)
}

/// [`read`], with the recogniser a line without a transcript needs already `loading` (started
/// before the sound was read: [`recognition::Loading`]), and the voice heard through the vocal
/// tract `voice` says ([`Voice::Auto`]: as its pitch says).
///
/// # Errors
/// As [`read`].
pub fn read_loaded(
    sound: &Sound,
    transcript: Option<&str>,
    language: Option<&str>,
    blind: Recognition,
    loading: Option<recognition::Loading>,
    voice: Voice,
) -> Result<Reading, SpeechError> {
    let (phones, recognition, notes) =
        recognition::recognise_loaded(sound, transcript, language, blind, loading, voice)?;
    tracing::debug!(
        ?recognition,
        phones = %phones
            .iter()
            .map(|p| format!("{} {:.2}-{:.2}", p.label, p.start, p.end))
            .collect::<Vec<_>>()
            .join(", "),
        "the line's phones"
    );
    let track = visemes::track(&phones, &sound.voice_activity(), sound.seconds());
    let mut notes = notes;
    if let Some(note) = unheard(&track, transcript.is_some()) {
        notes.push(note.to_owned());
    }
    Ok(Reading {
        track,
        phones,
        recognition,
        notes,
    })
}

/// What to tell the user of a sound whose `track` never moves the mouth (silence, a room's
/// noise, music without a voice: a wrong file or a video's empty sound track), when a
/// `transcript` was given or not; `None` when the mouth moves.
fn unheard(track: &Track, transcript: bool) -> Option<&'static str> {
    if track
        .keys
        .iter()
        .any(|k| k.viseme != faceanim_rig::names::Viseme::Sil)
    {
        return None;
    }
    Some(if transcript {
        "no voice was heard in it: the mouth rests throughout, and the transcript's words were placed nowhere"
    } else {
        "no voice was heard in it: the mouth rests throughout"
    })
}

impl Reading {
    /// The lip sync these visemes make through `mouth` at `fps`.
    #[must_use]
    pub fn on(self, mouth: &Mouth, fps: f32) -> LipSync {
        let frames = self
            .track
            .sample(fps)
            .iter()
            .map(|v| mouth.weights(v))
            .collect();
        LipSync {
            fps,
            frames,
            track: self.track,
            phones: self.phones,
            recognition: self.recognition,
            route: mouth.route,
            shapes_moved: mouth.moved(),
            notes: self.notes,
        }
    }
}
