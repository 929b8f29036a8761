//! Phones and when they are said, from PocketSphinx (English): a transcript's words become
//! phones by the CMU dictionary and each phone is timed by forced alignment; without a
//! transcript, the words recognised with the language model are aligned again the same way,
//! or any phone after any other is recognised (a phone loop). Where phones cannot be aligned
//! one by one, a word's time is shared between its phones by their typical lengths. Which
//! route a line takes is [`crate::recognition`]'s choice.

use std::collections::HashMap;
use std::path::Path;

use faceanim_sphinx_sys::{EN_US, FRAME_RATE, SphinxError};

use crate::audio::Sound;
use crate::warp::Heard;

/// A phone (ARPAbet, as the CMU dictionary spells them, stress removed; `SIL` for silence
/// and noise) from `start` to `end` seconds.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Phone {
    /// The phone.
    pub label: String,
    /// Start, seconds.
    pub start: f32,
    /// End, seconds.
    pub end: f32,
}

impl Phone {
    /// The first 10 ms frame of this phone in a list of `frames` (cut at its end): where
    /// [`Phone::frames`] starts.
    #[must_use]
    pub fn first_frame(&self, frames: usize) -> usize {
        ((self.start.max(0.0) * 100.0) as usize).min(frames)
    }

    /// This phone's part of `per_frame`, one value per 10 ms of the sound (a voice-activity
    /// flag, a loudness): the frames from its start to its end, cut at the list's end.
    #[must_use]
    pub fn frames<'a, T>(&self, per_frame: &'a [T]) -> &'a [T] {
        let a = self.first_frame(per_frame.len());
        let b = ((self.end.max(0.0) * 100.0).ceil() as usize).clamp(a, per_frame.len());
        &per_frame[a..b]
    }
}

/// How the phones were found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Recognition {
    /// Words recognised with the English language model, spoken as the dictionary says (the
    /// default without a transcript: a quarter to a half of real time on a line of a few
    /// seconds, a fifth on a longer reading; Rhubarb Lip Sync works so).
    Words,
    /// Any phone after any other (no words assumed: other languages, gibberish, singing), at
    /// about a tenth of real time.
    PhoneLoop,
    /// The transcript's words aligned to the sound by the recogniser (English).
    Transcript,
    /// The transcript spoken by eSpeak NG in its language and that version's phones carried
    /// onto the sound by warping one onto the other (any language).
    Synthesis,
}

/// Why recognition failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PhoneError {
    /// The recogniser failed.
    #[error(transparent)]
    Sphinx(#[from] SphinxError),
    /// The dictionary could not be read.
    #[error("{path}: {message}")]
    Dictionary {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// The transcript could not be spoken to align it by synthesis.
    #[error(transparent)]
    Synthesis(#[from] faceanim_espeak_sys::EspeakError),
    /// A Japanese transcript's kanji could not be read.
    #[error(transparent)]
    Reading(#[from] crate::japanese::ReadingError),
    /// The language is not one eSpeak NG speaks (nor a voice of one).
    #[error(
        "eSpeak NG has no language or voice '{0}' (`espeak-ng --voices` lists those it speaks: en-us, es, ja, de, fr, …)"
    )]
    UnknownLanguage(String),
    /// The transcript has no word to align.
    #[error("the transcript has no words")]
    EmptyTranscript,
    /// The transcript has more words than the sound could say.
    #[error(
        "the transcript has {words} words for {seconds:.1} s of sound; a voice says at most {most} in that time (give the line's own words)"
    )]
    TranscriptTooLong {
        /// Its words.
        words: usize,
        /// The sound's length.
        seconds: f32,
        /// The most words accepted for that length.
        most: usize,
    },
}

/// The fastest speech a transcript may describe, in words a second (auctioneers reach about
/// 6; conversational English is 2 to 3).
pub const MAX_WORDS_PER_SECOND: f32 = 10.0;

/// The transcript's words — those it says aloud ([`crate::script::spoken`]: a subtitle's
/// timecodes, markup and bracketed directions left out) — checked against the sound's length
/// before any work is done with them: not empty, and no more than [`MAX_WORDS_PER_SECOND`] allow (plus a few, for very
/// short sounds), so that a wrong file given as a transcript is refused at once instead of
/// growing the recogniser's grammar without bound.
///
/// # Errors
/// [`PhoneError::EmptyTranscript`] or [`PhoneError::TranscriptTooLong`].
pub fn transcript_words(text: &str, seconds: f32) -> Result<Vec<String>, PhoneError> {
    let spoken = crate::script::spoken(text);
    let text = spoken.text.as_str();
    let most = (seconds.max(0.0) * MAX_WORDS_PER_SECOND) as usize + 8;
    // Counted before the words are made: a huge text costs one copy, not a word list, to
    // refuse.
    let words = text
        .split(|c: char| !(c.is_alphanumeric() || c == '\''))
        .filter(|w| !w.trim_matches('\'').is_empty())
        .count();
    if words == 0 {
        return Err(PhoneError::EmptyTranscript);
    }
    if words > most {
        return Err(PhoneError::TranscriptTooLong {
            words,
            seconds,
            most,
        });
    }
    Ok(words_of(text))
}

/// The words recognised with the English language model, each aligned again phone by phone
/// (the recogniser's first pass times words, not the closures and releases inside them).
///
/// # Errors
/// [`PhoneError`] when the recogniser or its models are missing or fail.
pub(crate) fn recognise_words(
    heard: &Heard<'_>,
    recogniser: Option<crate::warp::Loaded>,
) -> Result<Vec<Phone>, PhoneError> {
    // The recogniser is dropped once it has decoded, before the alignment below waits for a
    // turn of the cores.
    let segments = heard.decode(blind_search(Recognition::Words), recogniser)?;
    // Only the words heard are looked up: reading the whole dictionary would cost more than
    // recognising a line.
    let recognised: Vec<String> = segments
        .iter()
        .map(|s| s.label.split('(').next().unwrap_or("").to_lowercase())
        .collect();
    tracing::debug!(words = ?recognised, "recognised");
    let dictionary = Dictionary::english_words(&recognised)?;
    let words: Vec<String> = recognised
        .into_iter()
        .filter(|w| dictionary.phones(w).is_some_and(|p| !p.is_empty()))
        .collect();
    let phones = match words.is_empty() {
        false => align_phones(heard, &words, &dictionary)?,
        true => None,
    };
    Ok(phones.unwrap_or_else(|| phones_of_words(segments, &dictionary).0))
}

/// What the recogniser searches for on a line recognised by `route` without a transcript:
/// English words, or any phone after any other. One place, for the recogniser loaded ahead
/// ([`crate::recognition::Loading`]) and the one loaded when the sound is at hand.
pub(crate) fn blind_search(route: Recognition) -> faceanim_sphinx_sys::Search {
    match route {
        Recognition::Words => EN_US.words(),
        _ => EN_US.phone_loop(),
    }
}

/// Any phone after any other (no words assumed: other languages, gibberish, singing), by
/// the model as `heard` is decoded (adapted to its voice or not).
///
/// # Errors
/// [`PhoneError`] when the recogniser or its models are missing or fail.
pub(crate) fn phone_loop(
    heard: &Heard<'_>,
    recogniser: Option<crate::warp::Loaded>,
) -> Result<Vec<Phone>, PhoneError> {
    Ok(phones_of(heard.decode(
        blind_search(Recognition::PhoneLoop),
        recogniser,
    )?))
}

/// A phone loop's segments as phones.
pub(crate) fn phones_of(segments: Vec<faceanim_sphinx_sys::Segment>) -> Vec<Phone> {
    segments
        .into_iter()
        .map(|s| Phone {
            label: phone_label(&s.label),
            start: frame_time(s.start),
            end: frame_time(s.end + 1),
        })
        .collect()
}

/// An English transcript's `words` aligned by the recogniser, or why they could not be (a
/// word neither the dictionary nor eSpeak NG can pronounce, an alignment that failed). Words
/// the dictionary lacks are said as eSpeak NG says them ([`crate::pronounce`]), and pushed
/// onto `pronounced` once each.
pub(crate) fn align_english(
    heard: &Heard<'_>,
    words: &[String],
    pronounced: &mut Vec<String>,
) -> Result<Vec<Phone>, String> {
    let mut dictionary = Dictionary::english_words(words).map_err(|e| e.to_string())?;
    // Words it lacks, as eSpeak NG says them (see `crate::pronounce`).
    for word in words {
        if !dictionary.has(word)
            && let Some(phones) = crate::pronounce::english(word)
        {
            dictionary.words.insert(word.clone(), phones);
            let shown = faceanim_rig::excerpt(word).into_owned();
            if !pronounced.contains(&shown) {
                pronounced.push(shown);
            }
        }
    }
    let unknown: Vec<&str> = words
        .iter()
        .filter(|w| !dictionary.has(w))
        .map(String::as_str)
        .collect();
    if !unknown.is_empty() {
        let shown: Vec<String> = unknown
            .iter()
            .take(8)
            .map(|w| faceanim_rig::excerpt(w).into_owned())
            .collect();
        let more = match unknown.len() {
            n if n > 8 => format!(" and {} more", n - 8),
            _ => String::new(),
        };
        return Err(format!(
            "the pronouncing dictionary lacks {}{more}",
            shown.join(", ")
        ));
    }
    match align(heard, words, &dictionary) {
        Ok(phones) if !phones.is_empty() => Ok(phones),
        Ok(_) => Err("the recogniser could not align the transcript to the sound".into()),
        Err(e) => Err(format!(
            "the recogniser could not align the transcript ({e})"
        )),
    }
}

fn frame_time(frame: u32) -> f32 {
    frame as f32 / FRAME_RATE as f32
}

/// A recogniser label as a phone: stress and case removed; silence, breath and noise `SIL`.
fn phone_label(label: &str) -> String {
    let upper: String = label
        .chars()
        .filter(char::is_ascii_alphabetic)
        .collect::<String>()
        .to_ascii_uppercase();
    if label.starts_with('+')
        || label.starts_with('<')
        || label.starts_with('[')
        || upper.is_empty()
    {
        "SIL".into()
    } else {
        upper
    }
}

/// The transcript's words, lower case, as the dictionary spells them (letters, digits and
/// apostrophes; everything else separates words).
fn words_of(text: &str) -> Vec<String> {
    text.split(|c: char| !(c.is_alphanumeric() || c == '\''))
        .map(|w| w.trim_matches('\'').to_lowercase())
        .filter(|w| !w.is_empty())
        .collect()
}

/// The CMU pronouncing dictionary: each word's first pronunciation.
pub struct Dictionary {
    words: HashMap<String, Vec<String>>,
}

impl Dictionary {
    /// Only `words` of Debian's `cmudict-en-us.dict` (pocketsphinx-en-us): a line's words,
    /// found without keeping the other hundred thousand.
    ///
    /// # Errors
    /// [`PhoneError::Dictionary`] naming the file.
    pub fn english_words(words: &[String]) -> Result<Dictionary, PhoneError> {
        let wanted: std::collections::HashSet<&str> = words.iter().map(String::as_str).collect();
        Dictionary::read(Path::new(EN_US.dictionary), &wanted)
    }

    fn read(path: &Path, only: &std::collections::HashSet<&str>) -> Result<Dictionary, PhoneError> {
        let text = std::fs::read_to_string(path).map_err(|e| PhoneError::Dictionary {
            path: path.display().to_string(),
            message: format!("{e} (scripts/setup.sh libraries installs the US English models)"),
        })?;
        let mut words = HashMap::new();
        for line in text.lines() {
            let mut parts = line.split_whitespace();
            let Some(word) = parts.next() else { continue };
            // Alternative pronunciations are written word(2): the first is kept.
            if word.contains('(') || !only.contains(word) {
                continue;
            }
            words
                .entry(word.to_owned())
                .or_insert_with(|| parts.map(phone_label).collect());
        }
        Ok(Dictionary { words })
    }

    /// Whether `word` is in it.
    #[must_use]
    pub fn has(&self, word: &str) -> bool {
        self.words.contains_key(word)
    }

    /// The phones of `word`.
    #[must_use]
    pub fn phones(&self, word: &str) -> Option<&[String]> {
        self.words.get(word).map(Vec::as_slice)
    }
}

/// How long a phone typically lasts, relative to others (vowels and diphthongs longest,
/// stops shortest): a word's time is shared between its phones by these.
fn typical_length(phone: &str) -> f32 {
    match phone {
        "AA" | "AE" | "AO" | "AW" | "AY" | "EY" | "OW" | "OY" => 1.6,
        "AH" | "EH" | "ER" | "IH" | "IY" | "UH" | "UW" => 1.2,
        "P" | "B" | "T" | "D" | "K" | "G" => 0.8,
        "S" | "Z" | "SH" | "CH" | "JH" | "F" => 1.1,
        _ => 1.0,
    }
}

/// Forced alignment: the words' phones in order, each timed by the acoustic model, with
/// optional silences and fillers between them; the words alone (their time shared between
/// their phones by typical lengths) when the phones cannot be aligned.
fn align(
    heard: &Heard<'_>,
    words: &[String],
    dictionary: &Dictionary,
) -> Result<Vec<Phone>, PhoneError> {
    match align_phones(heard, words, dictionary)? {
        Some(phones) => Ok(phones),
        None => align_words(heard, words, dictionary),
    }
}

/// The words' phones in order, each timed by the acoustic model; `None` when the recogniser
/// could not fit them all to the sound.
fn align_phones(
    heard: &Heard<'_>,
    words: &[String],
    dictionary: &Dictionary,
) -> Result<Option<Vec<Phone>>, PhoneError> {
    let sequence: Vec<String> = words
        .iter()
        .filter_map(|w| dictionary.phones(w))
        .flatten()
        .cloned()
        .collect();
    let segments = heard.decode(EN_US.phones(sequence.clone()), None)?;
    let phones: Vec<Phone> = segments
        .iter()
        .map(|s| Phone {
            label: s
                .label
                .strip_prefix("ph_")
                .map_or_else(|| "SIL".to_owned(), str::to_ascii_uppercase),
            start: frame_time(s.start),
            end: frame_time(s.end + 1),
        })
        .collect();
    let said: Vec<&str> = phones
        .iter()
        .map(|p| p.label.as_str())
        .filter(|l| *l != "SIL")
        .collect();
    Ok((said == sequence).then(|| closures(phones)))
}

/// Silences the aligner put inside a transcript's speech where the voice goes on: a whisper's
/// or a breathy voice's quiet vowels, which the acoustic model's silence fits better than any
/// phone. A pause between two phones whose frames are mostly `voiced` (one flag per 10 ms) is
/// no pause: the phones on either side meet in its middle.
pub(crate) fn voiced_pauses(mut phones: Vec<Phone>, voiced: &[bool]) -> Vec<Phone> {
    let mut k = 1;
    while k + 1 < phones.len() {
        let (before, pause, after) = (&phones[k - 1], &phones[k], &phones[k + 1]);
        let frames = pause.frames(voiced);
        let heard = frames.iter().filter(|&&v| v).count() as f32;
        if pause.label == "SIL"
            && before.label != "SIL"
            && after.label != "SIL"
            && !frames.is_empty()
            && 2.0 * heard >= frames.len() as f32
        {
            let middle = (pause.start + pause.end) / 2.0;
            phones[k - 1].end = middle;
            phones[k + 1].start = middle;
            phones.remove(k);
        } else {
            k += 1;
        }
    }
    phones
}

/// Short silences the recogniser put inside speech: the hold before a stop's release is the
/// stop's (the lips of a P are closed in it), any other goes to the phone before it.
fn closures(phones: Vec<Phone>) -> Vec<Phone> {
    const SHORTEST_PAUSE: f32 = 0.12;
    let stop = |label: &str| matches!(label, "P" | "B" | "M" | "T" | "D" | "K" | "G" | "CH" | "JH");
    let mut out: Vec<Phone> = Vec::with_capacity(phones.len());
    let mut k = 0;
    while k < phones.len() {
        let phone = &phones[k];
        let inside = k > 0 && k + 1 < phones.len();
        if phone.label == "SIL" && inside && phone.end - phone.start < SHORTEST_PAUSE {
            let next = &phones[k + 1];
            if stop(&next.label) {
                out.push(Phone {
                    start: phone.start,
                    ..next.clone()
                });
                k += 2;
                continue;
            }
            if let Some(last) = out.last_mut() {
                last.end = phone.end;
                k += 1;
                continue;
            }
        }
        out.push(phone.clone());
        k += 1;
    }
    out
}

/// Forced alignment of the words in order, with optional silences and fillers between them.
fn align_words(
    heard: &Heard<'_>,
    words: &[String],
    dictionary: &Dictionary,
) -> Result<Vec<Phone>, PhoneError> {
    let grammar = format!(
        "#JSGF V1.0;\ngrammar transcript;\npublic <s> = {};\n",
        words.join(" ")
    );
    let segments = heard.decode(EN_US.grammar(grammar), None)?;
    let (phones, said) = phones_of_words(segments, dictionary);
    Ok(if said == words.len() {
        phones
    } else {
        Vec::new()
    })
}

/// The phones of as much of `text` as `sound` says from its start (a reader who stopped
/// early), with how many of its words were said; `Ok` with no phones when the dictionary lacks
/// a word or the recogniser found none.
///
/// # Errors
/// [`PhoneError`] when the recogniser or its models are missing or fail.
pub fn align_start(sound: &Sound, text: &str) -> Result<(Vec<Phone>, usize), PhoneError> {
    let words = words_of(text);
    let dictionary = Dictionary::english_words(&words)?;
    if words.is_empty() || words.iter().any(|w| !dictionary.has(w)) {
        return Ok((Vec::new(), 0));
    }
    // Every prefix of the text: w1 [w2 [w3 …]].
    let grammar = format!(
        "#JSGF V1.0;\ngrammar passage;\npublic <s> = {}{};\n",
        words.join(" ["),
        "]".repeat(words.len() - 1)
    );
    let segments = faceanim_sphinx_sys::decode(&EN_US.grammar(grammar), &sound.samples)?;
    Ok(phones_of_words(segments, &dictionary))
}

/// Word segments as phones (and how many were words, not silence or noise).
fn phones_of_words(
    segments: Vec<faceanim_sphinx_sys::Segment>,
    dictionary: &Dictionary,
) -> (Vec<Phone>, usize) {
    let mut phones = Vec::new();
    let mut said = 0;
    for segment in segments {
        let (start, end) = (frame_time(segment.start), frame_time(segment.end + 1));
        let word = segment.label.split('(').next().unwrap_or("").to_lowercase();
        match dictionary.phones(&word) {
            Some(pronunciation) if !segment.label.starts_with('<') && !pronunciation.is_empty() => {
                said += 1;
                let total: f32 = pronunciation.iter().map(|p| typical_length(p)).sum();
                let mut at = start;
                for p in pronunciation {
                    let length = (end - start) * typical_length(p) / total;
                    phones.push(Phone {
                        label: p.clone(),
                        start: at,
                        end: at + length,
                    });
                    at += length;
                }
            }
            _ => phones.push(Phone {
                label: "SIL".into(),
                start,
                end,
            }),
        }
    }
    (phones, said)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Phones from "LABEL START END, …".
    pub(crate) fn phones(text: &str) -> Vec<Phone> {
        text.split(',')
            .map(|p| {
                let parts: Vec<&str> = p.split_whitespace().collect();
                Phone {
                    label: parts[0].into(),
                    start: parts[1].parse().unwrap(),
                    end: parts[2].parse().unwrap(),
                }
            })
            .collect()
    }

    #[test]
    fn a_pause_where_the_voice_goes_on_is_no_pause() {
        // 10 ms frames: heard through 0.5 s, then silent to 0.8 s, heard again to 1.2 s.
        let voiced: Vec<bool> = (0..120).map(|k| !(50..80).contains(&k)).collect();
        let aligned = phones("IY 0 0.2, SIL 0.2 0.4, T 0.4 0.45, SIL 0.45 0.8, AA 0.8 1.2");
        let kept = voiced_pauses(aligned, &voiced);
        // The first pause is heard throughout: IY and T meet in its middle. The second is
        // silent: a pause.
        assert_eq!(
            kept,
            phones("IY 0 0.3, T 0.3 0.45, SIL 0.45 0.8, AA 0.8 1.2")
        );
        // A pause at either end stays, heard or not.
        let edges = phones("SIL 0 0.2, AA 0.2 0.6, SIL 0.6 1.2");
        assert_eq!(voiced_pauses(edges.clone(), &[true; 120]), edges);
    }

    #[test]
    fn labels_and_words_are_normalised() {
        assert_eq!(phone_label("AH0"), "AH");
        assert_eq!(phone_label("+NSN+"), "SIL");
        assert_eq!(phone_label("<sil>"), "SIL");
        assert_eq!(phone_label("SIL"), "SIL");
        assert_eq!(
            words_of("Hello, world! Don't—stop 'now'."),
            ["hello", "world", "don't", "stop", "now"]
        );
    }
}
