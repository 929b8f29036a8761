//! # faceanim-espeak-sys: eSpeak NG, as Debian ships it
//!
//! Thin bindings to `libespeak-ng` (`apt-get install libespeak-ng-dev`), the open synthesiser
//! with pronunciation rules for more than a hundred languages. faceanim uses it for two
//! things a lip sync in any language needs, both from one call, [`speak`]:
//!
//! - the **phones** of a line of text, in IPA, in the language's own pronunciation (Japanese
//!   kana, Spanish, German, Korean, Mandarin: whatever its voice reads);
//! - **when each is said** in a spoken version of the line (its synthesis events, to the
//!   millisecond), with the sound itself — what an alignment by synthesis matches a recording
//!   against.
//!
//! The library keeps global state and is not re-entrant: every call here holds one lock.
//!
//! Licence: eSpeak NG is GPL-3.0-or-later and is linked dynamically, found at build time;
//! built where it is missing, the crate still compiles and [`speak`] returns
//! [`EspeakError::NotInstalled`], so the rest of faceanim builds and runs on any machine.
//!
//! ```no_run
//! let line = faceanim_espeak_sys::speak("hola, ¿qué tal?", "es", None)?;
//! for phone in &line.phones {
//!     println!("{} at {} ms", phone.ipa, phone.start_ms);
//! }
//! # Ok::<(), faceanim_espeak_sys::EspeakError>(())
//! ```
#![deny(missing_docs)]

/// One phone of a spoken line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PhoneEvent {
    /// Its IPA name (`p`, `aɪ`, `tʃ`, `ə`; length and stress marks kept as eSpeak NG gives
    /// them), or [`PAUSE`] for a pause.
    pub ipa: String,
    /// When it starts in [`Spoken::samples`], milliseconds.
    pub start_ms: u32,
    /// Which word of the line it belongs to (0-based; phones before the first word: 0).
    pub word: usize,
}

/// The name [`PhoneEvent::ipa`] gives a pause (eSpeak NG's pause phonemes have no IPA).
pub const PAUSE: &str = "_";

/// A line spoken by eSpeak NG.
#[derive(Debug, Clone, PartialEq)]
pub struct Spoken {
    /// Mono samples.
    pub samples: Vec<i16>,
    /// Samples per second (22 050 for eSpeak NG's voices).
    pub sample_rate: u32,
    /// The phones in order; each ends where the next starts, the last at the end of the sound.
    pub phones: Vec<PhoneEvent>,
    /// When each word starts, milliseconds.
    pub words_ms: Vec<u32>,
}

/// Why a line could not be spoken.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum EspeakError {
    /// This build of faceanim was made without the library.
    #[error(
        "speaking a transcript needs eSpeak NG: apt-get install libespeak-ng-dev (or your system's espeak-ng package), then build faceanim again"
    )]
    NotInstalled,
    /// The library could not start (its data folder is missing).
    #[error("eSpeak NG could not start: its data (espeak-ng-data) was not found")]
    NoData,
    /// The voice or language is not one eSpeak NG has.
    #[error("eSpeak NG has no voice '{0}' (see `espeak-ng --voices` for the languages it speaks)")]
    NoVoice(String),
    /// The text holds a NUL character.
    #[error("the text holds a NUL character")]
    Nul,
    /// Synthesis failed.
    #[error("eSpeak NG failed to speak the line (error {0})")]
    Failed(i32),
}

/// A voice eSpeak NG has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Voice {
    /// What [`speak`] takes: its identifier (`es`, `en-us`, `cmn`).
    pub name: String,
    /// The languages it speaks, most preferred first (`es`, `en-us`).
    pub languages: Vec<String>,
}

/// Speaks `text` (UTF-8) with the voice `voice` (a language such as `en-us`, `es`, `ja`, `de`,
/// `fr`, `ko`, `cmn`, or a voice with a variant, `en-us+f3`), at `words_per_minute` (eSpeak NG's
/// default, 175, when `None`).
///
/// # Errors
/// [`EspeakError`] when the library is missing, the voice is unknown or synthesis fails.
pub fn speak(
    text: &str,
    voice: &str,
    words_per_minute: Option<u32>,
) -> Result<Spoken, EspeakError> {
    if text.contains('\0') || voice.contains('\0') {
        return Err(EspeakError::Nul);
    }
    imp::speak(text, voice, words_per_minute)
}

/// The voices eSpeak NG has.
///
/// # Errors
/// [`EspeakError::NotInstalled`] or [`EspeakError::NoData`].
pub fn voices() -> Result<Vec<Voice>, EspeakError> {
    imp::voices()
}

/// Checks that eSpeak NG has `voice` (a language such as `es`, or a voice with a variant,
/// `en-us+f3`), as [`speak`] would choose it.
///
/// # Errors
/// [`EspeakError::NoVoice`] when it has not; [`EspeakError::NotInstalled`],
/// [`EspeakError::NoData`] or [`EspeakError::Nul`] as [`speak`] gives them.
pub fn check_voice(voice: &str) -> Result<(), EspeakError> {
    if voice.contains('\0') {
        return Err(EspeakError::Nul);
    }
    imp::check_voice(voice)
}

/// Whether this build can speak (the library was found when it was built).
#[must_use]
pub fn available() -> bool {
    cfg!(espeak)
}

/// The phones of a line from its events: each phone event's IPA and time, tagged with the word
/// it falls in; empty names (eSpeak NG's pauses) are [`PAUSE`], one for a run of them.
fn phones_of(events: &[(i32, i32, [u8; 8])]) -> (Vec<PhoneEvent>, Vec<u32>) {
    let mut phones = Vec::new();
    let mut words = Vec::new();
    for &(kind, at, name) in events {
        let at = u32::try_from(at.max(0)).unwrap_or(0);
        match kind {
            ffi::EVENT_WORD => words.push(at),
            ffi::EVENT_PHONEME => {
                let end = name.iter().position(|&b| b == 0).unwrap_or(name.len());
                let mut ipa = String::from_utf8_lossy(&name[..end]).trim().to_owned();
                if ipa.is_empty() {
                    if phones.last().is_some_and(|p: &PhoneEvent| p.ipa == PAUSE) {
                        continue;
                    }
                    PAUSE.clone_into(&mut ipa);
                }
                phones.push(PhoneEvent {
                    ipa,
                    start_ms: at,
                    word: words.len().saturating_sub(1),
                });
            }
            _ => {}
        }
    }
    (phones, words)
}

/// The C interface (`speak_lib.h`), as much of it as faceanim calls.
#[allow(
    unsafe_code,
    non_camel_case_types,
    missing_docs,
    reason = "C declarations, named as the header names them"
)]
pub mod ffi {
    use std::ffi::{c_char, c_int, c_short, c_uint, c_void};

    /// `AUDIO_OUTPUT_SYNCHRONOUS`: audio and events through the callback, returning when done.
    pub const AUDIO_OUTPUT_SYNCHRONOUS: c_int = 2;
    pub const INITIALIZE_PHONEME_EVENTS: c_int = 0x0001;
    pub const INITIALIZE_PHONEME_IPA: c_int = 0x0002;
    pub const CHARS_UTF8: c_uint = 1;
    pub const POS_CHARACTER: c_int = 1;
    pub const EVENT_LIST_TERMINATED: c_int = 0;
    pub const EVENT_WORD: c_int = 1;
    pub const EVENT_PHONEME: c_int = 7;
    pub const RATE: c_int = 1;

    /// `espeak_EVENT`'s `id`.
    #[repr(C)]
    #[derive(Clone, Copy)]
    pub union EventId {
        pub number: c_int,
        pub name: *const c_char,
        pub string: [c_char; 8],
    }

    /// `espeak_EVENT`.
    #[repr(C)]
    #[derive(Clone, Copy)]
    pub struct espeak_EVENT {
        pub kind: c_int,
        pub unique_identifier: c_uint,
        pub text_position: c_int,
        pub length: c_int,
        pub audio_position: c_int,
        pub sample: c_int,
        pub user_data: *mut c_void,
        pub id: EventId,
    }

    /// `espeak_VOICE`.
    #[repr(C)]
    pub struct espeak_VOICE {
        pub name: *const c_char,
        pub languages: *const c_char,
        pub identifier: *const c_char,
        pub gender: u8,
        pub age: u8,
        pub variant: u8,
        pub xx1: u8,
        pub score: c_int,
        pub spare: *mut c_void,
    }

    pub type SynthCallback =
        unsafe extern "C" fn(wav: *mut c_short, samples: c_int, events: *mut espeak_EVENT) -> c_int;

    #[cfg(espeak)]
    unsafe extern "C" {
        pub fn espeak_Initialize(
            output: c_int,
            buflength: c_int,
            path: *const c_char,
            options: c_int,
        ) -> c_int;
        pub fn espeak_SetSynthCallback(callback: SynthCallback);
        pub fn espeak_SetVoiceByName(name: *const c_char) -> c_int;
        pub fn espeak_SetParameter(parameter: c_int, value: c_int, relative: c_int) -> c_int;
        pub fn espeak_Synth(
            text: *const c_void,
            size: usize,
            position: c_uint,
            position_type: c_int,
            end_position: c_uint,
            flags: c_uint,
            unique_identifier: *mut c_uint,
            user_data: *mut c_void,
        ) -> c_int;
        pub fn espeak_Synchronize() -> c_int;
        pub fn espeak_ListVoices(spec: *mut espeak_VOICE) -> *const *const espeak_VOICE;
    }
}

#[cfg(espeak)]
#[allow(unsafe_code, reason = "calls into libespeak-ng")]
mod imp {
    use std::ffi::{CStr, CString, c_int, c_short, c_void};
    use std::sync::Mutex;

    use super::{EspeakError, Spoken, Voice, ffi, phones_of};

    /// The library's one instance: its sample rate once started.
    static ENGINE: Mutex<Option<u32>> = Mutex::new(None);

    /// What the callback gathers for one call.
    #[derive(Default)]
    struct Gathered {
        samples: Vec<i16>,
        events: Vec<(i32, i32, [u8; 8])>,
    }

    unsafe extern "C" fn gather(
        wav: *mut c_short,
        count: c_int,
        events: *mut ffi::espeak_EVENT,
    ) -> c_int {
        if events.is_null() {
            return 0;
        }
        // SAFETY: eSpeak NG passes an event list terminated by EVENT_LIST_TERMINATED whose
        // user_data is the `Gathered` given to espeak_Synth below, alive for the whole call.
        unsafe {
            let gathered = (*events).user_data.cast::<Gathered>();
            if gathered.is_null() {
                return 0;
            }
            let gathered = &mut *gathered;
            if !wav.is_null() && count > 0 {
                let count = usize::try_from(count).unwrap_or(0);
                gathered
                    .samples
                    .extend_from_slice(std::slice::from_raw_parts(wav, count));
            }
            let mut event = events;
            while (*event).kind != ffi::EVENT_LIST_TERMINATED {
                let e = *event;
                let mut name = [0u8; 8];
                if e.kind == ffi::EVENT_PHONEME {
                    for (n, c) in name.iter_mut().zip(e.id.string) {
                        *n = c as u8;
                    }
                }
                gathered.events.push((e.kind, e.audio_position, name));
                event = event.add(1);
            }
        }
        0
    }

    fn started(engine: &mut Option<u32>) -> Result<u32, EspeakError> {
        if let Some(rate) = *engine {
            return Ok(rate);
        }
        // SAFETY: plain calls with valid arguments; the callback matches the declared type.
        let rate = unsafe {
            let rate = ffi::espeak_Initialize(
                ffi::AUDIO_OUTPUT_SYNCHRONOUS,
                0,
                std::ptr::null(),
                ffi::INITIALIZE_PHONEME_EVENTS | ffi::INITIALIZE_PHONEME_IPA,
            );
            if rate > 0 {
                ffi::espeak_SetSynthCallback(gather);
            }
            rate
        };
        let rate = u32::try_from(rate).map_err(|_| EspeakError::NoData)?;
        if rate == 0 {
            return Err(EspeakError::NoData);
        }
        *engine = Some(rate);
        Ok(rate)
    }

    pub(super) fn speak(
        text: &str,
        voice: &str,
        words_per_minute: Option<u32>,
    ) -> Result<Spoken, EspeakError> {
        let mut engine = ENGINE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let sample_rate = started(&mut engine)?;
        set_voice(voice)?;
        let text = CString::new(text).map_err(|_| EspeakError::Nul)?;
        let mut gathered = Gathered::default();
        // SAFETY: the strings outlive the calls; `gathered` outlives espeak_Synth, which in
        // synchronous mode returns only when every callback has been made.
        let status = unsafe {
            let rate = words_per_minute.map_or(175, |w| w.clamp(80, 450));
            ffi::espeak_SetParameter(ffi::RATE, rate as c_int, 0);
            let bytes = text.as_bytes_with_nul();
            let status = ffi::espeak_Synth(
                bytes.as_ptr().cast::<c_void>(),
                bytes.len(),
                0,
                ffi::POS_CHARACTER,
                0,
                ffi::CHARS_UTF8,
                std::ptr::null_mut(),
                (&raw mut gathered).cast::<c_void>(),
            );
            ffi::espeak_Synchronize();
            status
        };
        if status != 0 {
            return Err(EspeakError::Failed(status));
        }
        let (phones, words_ms) = phones_of(&gathered.events);
        Ok(Spoken {
            samples: gathered.samples,
            sample_rate,
            phones,
            words_ms,
        })
    }

    pub(super) fn check_voice(voice: &str) -> Result<(), EspeakError> {
        let mut engine = ENGINE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        started(&mut engine)?;
        set_voice(voice)
    }

    /// Chooses `voice` as the `espeak-ng` program does: by its name (`en-us`, `cmn`,
    /// `en-us+f3`), else as a language one of the voices speaks (`zh`, which the Mandarin
    /// voice lists among its languages; `en-gb` and `fr-fr`, the languages `espeak-ng
    /// --voices` shows for the voices in the files `gmw/en` and `roa/fr`), keeping a
    /// `+variant`. The engine must be started and its lock held.
    fn set_voice(voice: &str) -> Result<(), EspeakError> {
        let by_name = |name: &str| -> Result<bool, EspeakError> {
            let name = CString::new(name).map_err(|_| EspeakError::Nul)?;
            // SAFETY: the string outlives the call.
            Ok(unsafe { ffi::espeak_SetVoiceByName(name.as_ptr()) } == 0)
        };
        if by_name(voice)? {
            return Ok(());
        }
        let (language, variant) = voice
            .split_once('+')
            .map_or((voice, None), |(l, v)| (l, Some(v)));
        // Chosen by its file (`gmw/en`): a voice's first language is not always a name it
        // answers to (`en-gb` is not, the voice's file being `en`).
        let speaker = listed()
            .into_iter()
            .find(|v| v.languages.iter().any(|l| l.eq_ignore_ascii_case(language)))
            .map(|v| v.name);
        if let Some(speaker) = speaker {
            let named = match variant {
                Some(variant) => format!("{speaker}+{variant}"),
                None => speaker,
            };
            if by_name(&named)? {
                return Ok(());
            }
        }
        Err(EspeakError::NoVoice(voice.to_owned()))
    }

    pub(super) fn voices() -> Result<Vec<Voice>, EspeakError> {
        let mut engine = ENGINE
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        started(&mut engine)?;
        Ok(listed())
    }

    /// The voices, with the engine started and its lock held.
    fn listed() -> Vec<Voice> {
        let mut out = Vec::new();
        // SAFETY: espeak_ListVoices(NULL) returns a NULL-terminated array of voices whose
        // strings live as long as the library; `languages` is a list of (priority byte,
        // NUL-terminated name) entries ending with a zero byte.
        unsafe {
            let mut list = ffi::espeak_ListVoices(std::ptr::null_mut());
            while !list.is_null() && !(*list).is_null() {
                let v = &**list;
                let name = if v.identifier.is_null() {
                    String::new()
                } else {
                    CStr::from_ptr(v.identifier).to_string_lossy().into_owned()
                };
                let mut languages = Vec::new();
                let mut at = v.languages;
                while !at.is_null() && *at != 0 {
                    let language = CStr::from_ptr(at.add(1));
                    languages.push(language.to_string_lossy().into_owned());
                    at = at.add(2 + language.to_bytes().len());
                }
                out.push(Voice { name, languages });
                list = list.add(1);
            }
        }
        out
    }
}

#[cfg(not(espeak))]
mod imp {
    use super::{EspeakError, Spoken, Voice};

    pub(super) fn speak(_: &str, _: &str, _: Option<u32>) -> Result<Spoken, EspeakError> {
        Err(EspeakError::NotInstalled)
    }

    pub(super) fn voices() -> Result<Vec<Voice>, EspeakError> {
        Err(EspeakError::NotInstalled)
    }

    pub(super) fn check_voice(_: &str) -> Result<(), EspeakError> {
        Err(EspeakError::NotInstalled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_become_phones_in_their_words() {
        let name = |s: &str| {
            let mut n = [0u8; 8];
            n[..s.len()].copy_from_slice(s.as_bytes());
            n
        };
        let events = [
            (ffi::EVENT_PHONEME, 0, name("")),
            (ffi::EVENT_WORD, 10, [0; 8]),
            (ffi::EVENT_PHONEME, 10, name("h")),
            (ffi::EVENT_PHONEME, 60, name("ˈoː")),
            (ffi::EVENT_WORD, 200, [0; 8]),
            (ffi::EVENT_PHONEME, 200, name("tʃ")),
        ];
        let (phones, words) = phones_of(&events);
        assert_eq!(words, [10, 200]);
        let got: Vec<(&str, u32, usize)> = phones
            .iter()
            .map(|p| (p.ipa.as_str(), p.start_ms, p.word))
            .collect();
        assert_eq!(
            got,
            [("_", 0, 0), ("h", 10, 0), ("ˈoː", 60, 0), ("tʃ", 200, 1)]
        );
    }

    #[test]
    fn a_voice_is_known_by_its_language_or_refused_by_its_name() {
        if !available() {
            assert!(matches!(check_voice("es"), Err(EspeakError::NotInstalled)));
            return;
        }
        // By name, with a variant, or as a language a voice lists (zh: the Mandarin voice's).
        // Every language `espeak-ng --voices` lists is one it takes (`en-gb`, `fr-fr` were not).
        for voice in [
            "es", "en-us", "en-us+f3", "ja", "cmn", "zh", "zh+f2", "en-gb", "en-gb+f3", "fr-fr",
            "EN-GB",
        ] {
            check_voice(voice).unwrap_or_else(|e| panic!("{voice}: {e}"));
        }
        for voice in voices().unwrap() {
            for language in &voice.languages {
                check_voice(language).unwrap_or_else(|e| panic!("{language} ({voice:?}): {e}"));
            }
        }
        let error = check_voice("xx").unwrap_err();
        assert!(
            matches!(&error, EspeakError::NoVoice(v) if v == "xx"),
            "{error}"
        );
        assert!(error.to_string().contains("'xx'"), "{error}");
        assert!(matches!(check_voice("e\0s"), Err(EspeakError::Nul)));
    }
}
