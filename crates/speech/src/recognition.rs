//! Which route finds a line's phones: the transcript aligned by the recogniser (English) or by
//! synthesis (any language), else the sound recognised without it — and the notes that say
//! what was done instead of what was asked.

use faceanim_sphinx_sys::{Recogniser, SphinxError};

use crate::audio::Sound;
use crate::phones::{self, Phone, PhoneError, Recognition};
use crate::warp::{Heard, Hearing, Loaded, Voice};

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
/// only in English, phones in any other language). Every route of the recogniser hears a
/// woman's or child's voice through a longer vocal tract, as its pitch says ([`Voice::Auto`]).
/// The notes say what was done instead of what was asked.
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
    recognise_loaded(sound, transcript, language, blind, None, Voice::Auto)
}

/// The route [`recognise`] takes without a transcript in `language`: `blind`, except that
/// words are recognised in English only (other languages by their phones).
fn blind_route(language: &str, blind: Recognition) -> Recognition {
    if is_english(language) || blind != Recognition::Words {
        blind
    } else {
        Recognition::PhoneLoop
    }
}

/// The recogniser a line without a transcript needs, loading on a thread of its own from
/// the moment it is made: its models need no more of the sound than how it is heard, so they
/// load while the character loads (most of a short line's time otherwise). Give it to
/// [`recognise_loaded`].
#[derive(Debug)]
pub struct Loading {
    route: Recognition,
    /// The sound's length and a hash of its samples: the decision is for that sound only.
    sound: (usize, u64),
    voice: Voice,
    /// How the sound is heard, decided before the recogniser started loading: its frame
    /// rate is the one the recogniser reads at.
    hearing: Hearing,
    thread: std::thread::JoinHandle<Result<Recogniser, SphinxError>>,
}

impl Loading {
    /// Starts loading the recogniser for `sound` in `language` (English when `None`)
    /// recognised by `blind`, heard through the vocal tract `voice` says: decides how it is
    /// heard first (its pitch: a few milliseconds), so that a woman's or child's voice,
    /// warped, and a whisper, recognised by its phones, find theirs loaded too.
    #[must_use]
    pub fn start(
        sound: &Sound,
        language: Option<&str>,
        blind: Recognition,
        voice: Voice,
    ) -> Loading {
        let hearing = Hearing::of(sound, voice);
        let route = heard_route(blind_route(language.unwrap_or(ENGLISH), blind), hearing);
        let search = phones::blind_search(route).warped(hearing.frame_rate);
        Loading {
            route,
            sound: identity(sound),
            voice,
            hearing,
            thread: std::thread::spawn(move || Recogniser::load(&search)),
        }
    }

    /// How `sound` is heard through `voice`, when this recogniser was loaded for them.
    fn hearing_of(&self, sound: &Sound, voice: Voice) -> Option<Hearing> {
        (self.voice == voice && self.sound == identity(sound)).then_some(self.hearing)
    }

    /// The loaded recogniser, when it is the one `route` needs at `frame_rate`.
    fn finish(self, route: Recognition, frame_rate: u32) -> Result<Option<Loaded>, PhoneError> {
        if self.route != route || self.hearing.frame_rate != frame_rate {
            return Ok(None);
        }
        match self.thread.join() {
            Ok(loaded) => Ok(Some(Loaded {
                recogniser: loaded?,
                frame_rate,
            })),
            Err(_) => Err(PhoneError::Sphinx(SphinxError::Decoder(
                "loading the recogniser stopped".into(),
            ))),
        }
    }
}

/// A sound's length and a hash of its samples.
fn identity(sound: &Sound) -> (usize, u64) {
    use std::hash::{Hash, Hasher};
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    sound.samples.hash(&mut hasher);
    (sound.samples.len(), hasher.finish())
}

/// The route a line recognised by `blind` takes when heard as `hearing` says: a whisper's
/// words are seldom made out, and slowly (the acoustic scores are flat): its phones say more,
/// at a quarter of the time (eSpeak NG's whisperf: 0.65 agreement against 0.58).
fn heard_route(blind: Recognition, hearing: Hearing) -> Recognition {
    if blind == Recognition::Words && hearing.whispered {
        Recognition::PhoneLoop
    } else {
        blind
    }
}

/// [`recognise`], with the recogniser for a line without a transcript already `loading`
/// (used only when that route is taken; otherwise it is left to finish and be dropped), and
/// the voice heard through the vocal tract `voice` says.
///
/// # Errors
/// As [`recognise`].
pub fn recognise_loaded(
    sound: &Sound,
    transcript: Option<&str>,
    language: Option<&str>,
    blind: Recognition,
    loading: Option<Loading>,
    voice: Voice,
) -> Result<(Vec<Phone>, Recognition, Vec<String>), PhoneError> {
    let language = language.unwrap_or(ENGLISH);
    let mut notes = Vec::new();
    let asked = blind;
    let blind = blind_route(language, blind);
    if blind != asked && transcript.is_none() {
        notes.push(format!(
            "words are recognised in English only: the phones of this {language} line were recognised instead"
        ));
    }
    // The voice as the acoustic model hears it best (a woman's, a child's slowed), as decided
    // when its recogniser started loading if it was.
    let hearing = loading
        .as_ref()
        .and_then(|l| l.hearing_of(sound, voice))
        .unwrap_or_else(|| Hearing::of(sound, voice));
    let heard = Heard::as_decided(sound, hearing);
    if let Some(text) = transcript {
        let words = phones::transcript_words(text, sound.seconds())?;
        // Why the recogniser could not align it, when it tried.
        let mut why = None;
        if is_english(language) {
            match phones::align_english(&heard, &words) {
                Ok(phones) => {
                    let phones = phones::voiced_pauses(phones, &sound.voice_activity());
                    return Ok((phones, Recognition::Transcript, notes));
                }
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
    let route = heard_route(blind, hearing);
    if route != blind {
        notes.push("the voice has no pitch (a whisper): its phones were recognised".to_owned());
    }
    let blind = route;
    let loaded = loading
        .map(|l| l.finish(blind, hearing.frame_rate))
        .transpose()?
        .flatten();
    if blind != Recognition::Words {
        return Ok((
            crate::holds::lips_held(sound, phones::phone_loop(&heard, loaded)?, heard.warp()),
            blind,
            notes,
        ));
    }
    let words = phones::recognise_words(&heard, loaded)?;
    // Words the recogniser could not make out leave the voice unsaid (a formant synthesiser,
    // a whisper): the phones heard there, where they say more.
    let voiced = sound.voice_activity();
    let said = said_share(&words, &voiced);
    tracing::debug!(said, "the words recognised cover this share of the voice");
    if said < WORDS_SAY_ENOUGH {
        let phones = phones::phone_loop(&heard, None)?;
        if said_share(&phones, &voiced) > said {
            notes.push(format!(
                "the words recognised cover {:.0} % of the voice: its phones were recognised instead",
                said * 100.0
            ));
            return Ok((
                crate::holds::lips_held(sound, phones, heard.warp()),
                Recognition::PhoneLoop,
                notes,
            ));
        }
    }
    Ok((
        crate::holds::lips_held(sound, words, heard.warp()),
        blind,
        notes,
    ))
}

/// The share of a line's voice its words recognised must cover (`said_share`), below which its
/// phones are recognised too. Every line of the flite voices and of LibriVox readings is
/// covered at 0.97 or more; the lines of a formant voice (eSpeak NG) the recogniser fails on,
/// at 0.35 to 0.6.
const WORDS_SAY_ENOUGH: f32 = 0.8;

/// The share of `voiced` frames (10 ms each) inside a phone that is not silence: 1 when none
/// is voiced.
fn said_share(phones: &[Phone], voiced: &[bool]) -> f32 {
    let total = voiced.iter().filter(|&&v| v).count();
    if total == 0 {
        return 1.0;
    }
    let mut said = vec![false; voiced.len()];
    for phone in phones.iter().filter(|p| p.label != "SIL") {
        let start = phone.first_frame(voiced.len());
        let frames = phone.frames(voiced).len();
        said[start..start + frames].fill(true);
    }
    let covered = voiced.iter().zip(&said).filter(|(v, s)| **v && **s).count();
    covered as f32 / total as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warp::tests::buzz;

    /// A recogniser loaded once the sound is at hand is the one its voice is heard with, and
    /// its decision is used for that sound and voice only.
    #[test]
    fn a_recogniser_loaded_for_a_sound_is_the_one_its_voice_needs() {
        let woman = buzz(230.0, 1.0);
        let loading = Loading::start(&woman, None, Recognition::Words, Voice::Auto);
        assert_eq!(loading.route, Recognition::Words);
        assert_eq!(
            loading.hearing.frame_rate, 83,
            "a woman's voice is warped by 1.2"
        );
        assert_eq!(
            loading.hearing_of(&woman, Voice::Auto),
            Some(Hearing::of(&woman, Voice::Auto))
        );
        assert_eq!(loading.hearing_of(&woman, Voice::Warp(1.0)), None);
        assert_eq!(loading.hearing_of(&buzz(110.0, 1.0), Voice::Auto), None);
        // Another voice's frame rate, or another route, is not served by it.
        let by_hand = Loading::start(&woman, None, Recognition::Words, Voice::Warp(1.0));
        assert_eq!(by_hand.hearing.frame_rate, faceanim_sphinx_sys::FRAME_RATE);
        assert!(matches!(
            loading.finish(Recognition::PhoneLoop, 83),
            Ok(None)
        ));
        assert!(matches!(by_hand.finish(Recognition::Words, 83), Ok(None)));
    }
}
