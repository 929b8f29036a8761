//! Which route finds a line's phones: the transcript aligned by the recogniser (English) or by
//! synthesis (any language), else the sound recognised without it — and the notes that say
//! what was done instead of what was asked.

use crate::audio::Sound;
use crate::phones::{self, Phone, PhoneError, Recognition};

/// The language of lines without one: US English.
pub const ENGLISH: &str = "en-us";

/// Whether `language` (an eSpeak NG voice name) is English, which the recogniser's models
/// are.
#[must_use]
pub fn is_english(language: &str) -> bool {
    language == "en" || language.starts_with("en-") || language.starts_with("en+")
}

/// The phones of `sound` in `language` (an eSpeak NG voice name: `en-us`, `es`, `ja`, …;
/// [`ENGLISH`] when `None`).
///
/// With `transcript`, its words are never thrown away: an English line is aligned by the
/// recogniser (its words in the pronouncing dictionary, in order); a line it cannot align, or
/// in another language, is aligned by synthesis ([`crate::synthesis`]); only when neither
/// works is the sound recognised without it, with a note saying why. Without a transcript the
/// sound is recognised by `blind` ([`Recognition::Words`] or [`Recognition::PhoneLoop`]; words
/// only in English, phones in any other language). The notes say what was done instead of
/// what was asked.
///
/// # Errors
/// [`PhoneError`] when the recogniser or its models are missing or fail, or the transcript is
/// empty or far too long for the sound.
pub fn recognise(
    sound: &Sound,
    transcript: Option<&str>,
    language: Option<&str>,
    blind: Recognition,
) -> Result<(Vec<Phone>, Recognition, Vec<String>), PhoneError> {
    let language = language.unwrap_or(ENGLISH);
    let mut notes = Vec::new();
    let blind = if is_english(language) || blind != Recognition::Words {
        blind
    } else {
        if transcript.is_none() {
            notes.push(format!(
                "words are recognised in English only: the phones of this {language} line were recognised instead"
            ));
        }
        Recognition::PhoneLoop
    };
    if let Some(text) = transcript {
        let words = phones::transcript_words(text, sound.seconds())?;
        // Why the recogniser could not align it, when it tried.
        let mut why = None;
        if is_english(language) {
            match phones::align_english(sound, &words) {
                Ok(phones) => return Ok((phones, Recognition::Transcript, notes)),
                Err(reason) => why = Some(reason),
            }
        }
        let failed = match crate::synthesis::align(sound, text, language) {
            Ok(phones) if !phones.is_empty() => {
                if let Some(why) = why {
                    notes.push(format!("{why}: the transcript was aligned by synthesis"));
                }
                return Ok((phones, Recognition::Synthesis, notes));
            }
            Ok(_) => "the transcript could not be aligned by synthesis".to_owned(),
            Err(e) => format!("the transcript could not be aligned by synthesis ({e})"),
        };
        notes.push(match why {
            Some(why) => format!("{why}, and {failed}: the speech was recognised without it"),
            None => format!("{failed}: the speech was recognised without it"),
        });
    }
    let phones = if blind == Recognition::Words {
        phones::recognise_words(sound)?
    } else {
        phones::phone_loop(sound)?
    };
    Ok((phones, blind, notes))
}
