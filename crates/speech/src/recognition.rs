//! Which route finds a line's phones: the transcript aligned by the recogniser (English) or by
//! synthesis (any language), else the sound recognised without it — and the notes that say
//! what was done instead of what was asked.

use faceanim_sphinx_sys::{Decoded, Recogniser, SphinxError, Turn};

use crate::adapt::FirstPass;
use crate::audio::{SAMPLE_RATE, Sound};
use crate::phones::{self, Phone, PhoneError, Recognition};
use crate::warp::{Heard, Hearing, Loaded, Voice};

/// The language of lines without one: US English.
pub const ENGLISH: &str = "en-us";

/// Whether `language` (an eSpeak NG voice name) is English, which the recogniser's models
/// are.
#[must_use]
pub fn is_english(language: &str) -> bool {
    is_language(language, "en")
}

/// Whether `language` (an eSpeak NG voice name: `de`, `de-at`, `de+m3`) is `base`.
fn is_language(language: &str, base: &str) -> bool {
    language
        .strip_prefix(base)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(['-', '+']))
}

/// The phones of `sound` in `language` (an eSpeak NG voice name: `en-us`, `es`, `ja`, …;
/// [`ENGLISH`] when `None`).
///
/// With `transcript` (what it says aloud: [`crate::script`]), its words are never thrown
/// away: an English line is aligned by the recogniser (its words in the pronouncing
/// dictionary, in order; one it lacks as eSpeak NG says it, [`crate::pronounce`]) unless its voice follows the
/// synthesiser's own rendition sharply (a synthesiser's voice of eSpeak NG's kind); that line,
/// a line the recogniser cannot align, or one in another language, is aligned by synthesis
/// ([`crate::synthesis`]); only when neither works is the sound recognised without it, with a
/// note saying why — or when eSpeak NG cannot read it: a Japanese transcript in kanji is read
/// into kana by MeCab ([`crate::japanese`]) and aligned; where MeCab is missing or cannot read
/// it, the sound is heard without it (eSpeak NG says "Chinese letter" for each kanji). Speech the transcript does not say (a second or more of voice in one of
/// its alignment's silences) is recognised without it, and a note says so; so does one when
/// the recording holds twice the speech of its transcript spoken or more, or half. Without a
/// transcript the sound is recognised by `blind`
/// ([`Recognition::Words`] or [`Recognition::PhoneLoop`]; words only in English, phones in any
/// other language). Every route of the recogniser hears a woman's or child's voice through a
/// longer vocal tract, as its pitch says ([`Voice::Auto`]). The notes say what was done
/// instead of what was asked.
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

/// Checks that eSpeak NG speaks `language` and gives the name faceanim speaks it by. The
/// language may be named as eSpeak NG names it (`es`, `en-gb`, `cmn`), as a voice of one
/// (`en-us+f3`), or as other software tags it: BCP 47 (`ja-JP`, `pt-BR`, `zh-Hant-TW`,
/// `es-MX`: game engines' and localisation tools' tags) or a POSIX locale (`en_US.UTF-8`).
/// A tag is taken to the language of eSpeak NG's nearest it (`spellings`): its region's where
/// eSpeak NG has one (`pt-br`, `en-us`, `fr-be`), Latin American Spanish for Spanish of the
/// Americas (`es-419`), Cantonese for Chinese of Hong Kong and Macau (`yue`), else the
/// language's own (`ja`; `zh`, Mandarin; `en`, British English). A name it does not know would
/// otherwise choose the route as if it were another language's (a misspelt English recognised
/// by its phones) and leave its transcript unspoken. Where this build has no eSpeak NG, any
/// name passes, written as eSpeak NG would name it: only the route depends on it.
///
/// # Errors
/// [`PhoneError::UnknownLanguage`] naming it as given.
pub fn check_language(language: &str) -> Result<String, PhoneError> {
    let spellings = spellings(language);
    for spelling in &spellings {
        match faceanim_espeak_sys::check_voice(spelling) {
            Ok(()) => return Ok(spelling.clone()),
            Err(
                faceanim_espeak_sys::EspeakError::NoVoice(_)
                | faceanim_espeak_sys::EspeakError::Nul,
            ) => {}
            Err(_) => break,
        }
    }
    match faceanim_espeak_sys::check_voice(ENGLISH) {
        Err(
            faceanim_espeak_sys::EspeakError::NoVoice(_) | faceanim_espeak_sys::EspeakError::Nul,
        )
        | Ok(()) => Err(PhoneError::UnknownLanguage(language.to_owned())),
        // No eSpeak NG here to ask.
        Err(_) => Ok(spellings.into_iter().next().unwrap_or_default()),
    }
}

/// `language` as the name faceanim speaks it by where eSpeak NG knows it ([`check_language`]),
/// else as given (which the checks that need eSpeak NG then refuse by name).
fn language_named(language: &str) -> String {
    check_language(language).unwrap_or_else(|_| language.to_owned())
}

/// The countries whose Spanish is Latin America's (eSpeak NG's `es-419`): BCP 47's regions
/// for the Americas, and `419` itself.
const SPANISH_OF_THE_AMERICAS: [&str; 21] = [
    "419", "ar", "bo", "cl", "co", "cr", "cu", "do", "ec", "gt", "hn", "mx", "ni", "pa", "pe",
    "pr", "py", "sv", "us", "uy", "ve",
];

/// The names eSpeak NG may know `language` by, nearest first: as eSpeak NG writes names (lower
/// case, `-` between parts; a POSIX locale's codeset and modifier left out: `en_US.UTF-8@euro`
/// is `en-us`), then without a BCP 47 script (`zh-hant-tw`: `zh-tw`), then the regional
/// languages eSpeak NG names otherwise (`es-mx`: `es-419`; `zh-hk`: `yue`), then shorter and
/// shorter (`zh-tw`: `zh`), then as given; each with its `+variant`.
fn spellings(language: &str) -> Vec<String> {
    let given = language.trim();
    let (tag, variant) = given
        .split_once('+')
        .map_or((given, None), |(t, v)| (t, Some(v)));
    let tag = tag.split(['.', '@']).next().unwrap_or(tag);
    let tag = tag.replace('_', "-").to_ascii_lowercase();
    let parts: Vec<&str> = tag.split('-').filter(|p| !p.is_empty()).collect();
    let script = |k: usize, part: &str| {
        k > 0 && part.len() == 4 && part.chars().all(|c| c.is_ascii_alphabetic())
    };
    let unscripted: Vec<&str> = parts
        .iter()
        .enumerate()
        .filter(|&(k, part)| !script(k, part))
        .map(|(_, part)| *part)
        .collect();
    let mut names = vec![tag.clone(), unscripted.join("-")];
    match unscripted.as_slice() {
        ["zh", "hk" | "mo", ..] => names.push("yue".to_owned()),
        ["es", region, ..] if SPANISH_OF_THE_AMERICAS.contains(region) => {
            names.push("es-419".to_owned());
        }
        _ => {}
    }
    for n in (1..unscripted.len()).rev() {
        names.push(unscripted[..n].join("-"));
    }
    names.push(given.split_once('+').map_or(given, |(t, _)| t).to_owned());
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for name in names {
        if name.is_empty() {
            continue;
        }
        let name = match variant {
            Some(variant) => format!("{name}+{variant}"),
            None => name,
        };
        if !out.contains(&name) {
            out.push(name);
        }
    }
    out
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
/// load while the character loads (most of a short line's time otherwise); a line recognised
/// by its words has its phones decoded meanwhile. Give it to
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
    thread: std::thread::JoinHandle<Ready>,
}

/// A line's recogniser, loaded; for a line recognised by its words, with its first
/// [`SCORED_VOICE`] decoded beside it ([`prepare`]).
#[derive(Debug)]
struct Ready {
    recogniser: Result<Recogniser, SphinxError>,
    phones: Option<Result<Scored, SphinxError>>,
}

/// A line's phones from its start, and whether they are the whole line's; what adapts the
/// model to the voice they were decoded from, when it is heard poorly ([`crate::adapt`]);
/// and the phone loop's recogniser, for the line's phones when its words are not searched
/// for.
#[derive(Debug)]
struct Scored {
    decoded: Decoded,
    whole: bool,
    first: Option<FirstPass>,
    recogniser: Recogniser,
}

/// Frames of voice (10 ms each) a line's phones are scored on before its words are searched
/// for: 3 s, as long as a Harvard sentence (the lines [`HEARD_POORLY`] was chosen on). A
/// longer line is scored on its start, so that its words wait no longer than a short line's
/// (a phone loop over a 25 s reading took 2.5 s, the word search 0.25 s to load).
const SCORED_VOICE: usize = 300;

/// Loads the recogniser `route` needs for `heard` (`sound` read at its frame rate). A line
/// recognised by its words has its first [`SCORED_VOICE`] decoded by a phone loop meanwhile,
/// on another thread and the same [`Turn`] (a phone loop is small, and over a short line as
/// long to decode as the word search is to load): how well the acoustic model hears them
/// says whether its words are worth searching for ([`HEARD_POORLY`]), and a short line whose
/// words say too little falls back on them.
fn prepare(route: Recognition, sound: &Sound, heard: &Heard<'_>) -> Ready {
    let turn = Turn::wait();
    let search = phones::blind_search(route).warped(heard.frame_rate());
    if route != Recognition::Words {
        return Ready {
            recogniser: Recogniser::load_on(&search, Some(&turn)),
            phones: None,
        };
    }
    let loop_search = phones::blind_search(Recognition::PhoneLoop).warped(heard.frame_rate());
    let samples = heard.samples();
    let cut = scored_cut(&sound.voice_activity(), heard);
    std::thread::scope(|scope| {
        let phones = scope.spawn(|| {
            let mut recogniser = Recogniser::load_on(&loop_search, Some(&turn))?;
            let decoded = recogniser.decode_scored(&samples[..cut])?;
            let first = crate::adapt::first_pass(
                &mut recogniser,
                &samples[..cut],
                &decoded,
                sound,
                heard.warp(),
            );
            Ok(Scored {
                decoded,
                whole: cut == samples.len(),
                first,
                recogniser,
            })
        });
        let recogniser = Recogniser::load_on(&search, Some(&turn));
        let phones = phones.join().unwrap_or_else(|_| {
            Err(SphinxError::Decoder(
                "decoding the phone loop stopped".into(),
            ))
        });
        Ready {
            recogniser,
            phones: Some(phones),
        }
    })
}

/// The end of a sound's first [`SCORED_VOICE`] frames of voice (`voiced`: its voice
/// activity), in `heard`'s samples (its frames are the sound's, each `SAMPLE_RATE /
/// frame_rate` samples long): what a phone loop scores a voice on.
fn scored_cut(voiced: &[bool], heard: &Heard<'_>) -> usize {
    let samples = heard.samples().len();
    voiced
        .iter()
        .enumerate()
        .filter(|(_, v)| **v)
        .nth(SCORED_VOICE)
        .map_or(samples, |(frame, _)| {
            (frame * SAMPLE_RATE as usize / heard.frame_rate() as usize).min(samples)
        })
}

/// How `sound` is heard through `voice` ([`Hearing::of`]), a [`Voice::Search`] found by
/// listening ([`searched`]).
fn hearing(sound: &Sound, voice: Voice) -> Hearing {
    let by_pitch = Hearing::of(sound, voice);
    if voice != Voice::Search || by_pitch.whispered {
        return by_pitch;
    }
    match searched(sound, by_pitch.frame_rate) {
        Some(warp) => {
            tracing::debug!(
                warp,
                "the warp the acoustic model hears the voice best through"
            );
            // The sound's own findings (its pitch, whether it is whispered) stand; only the
            // tract it is heard through is the one found.
            Hearing {
                frame_rate: crate::warp::frame_rate_of(warp),
                ..by_pitch
            }
        }
        None => by_pitch,
    }
}

/// The warps a [`Voice::Search`] tries: from a voice lowered below a man's to a child's.
const SEARCHED_WARPS: [f32; 8] = [0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.45, 1.6];

/// How much better (log-likelihood a frame) the phone loop must hear a voice through another
/// warp than through its pitch's for [`Voice::Search`] to take it. Chosen with
/// [`HEARD_POORLY`] on the bench's Harvard lines (`scripts/bench-lipsync.py --voice`,
/// audio alone; the mean score of eight lines at each warp): flite's slt, rms, awb, festival's
/// ked, eSpeak NG's m3, f2 and f3 score best within 0.1–0.4 of their pitch's warp (slt at 1.1,
/// −9.6 against −10.0 at 1.2, where it agrees better, 0.933 against 0.919), while voices
/// raised or lowered whole score 0.7–2.6 better at the warp that lip-syncs them (slt raised
/// 40 %: 0.653 → 0.857 at 1.6; rms raised 40 %: 0.678 → 0.862 at 1.45; rms lowered 20 %:
/// 0.635 → 0.835 at 0.9; f2 lowered 20 %: 0.522 → 0.769 at 0.9). A formant synthesiser's
/// scores do not say its tract: eSpeak NG's m3 scores best at 1.6 (−16.7, against −18.1), where
/// it agrees at 0.304 against 0.728; a voice heard poorly through its pitch's warp (under
/// [`HEARD_POORLY`]) keeps it. Each line searched on its own, those voices give slt raised
/// 0.855, rms raised 0.884 and lowered 0.947, f2 lowered 0.565; as recorded, slt, rms and f2
/// lose 0.007–0.013 (a line here and there takes a neighbouring warp). Measured after the
/// choice, per line, on voices and effects it was not chosen on (the bench, audio alone):
/// flite's kal raised 40 % 0.615 → 0.684 and lowered 20 % 0.560 → 0.597, ked 0.648 → 0.767
/// and 0.630 → 0.719, awb lowered 0.692 → 0.911 (raised 0.820 → 0.796); as recorded, kal, awb
/// and ked within 0.006 of their pitch's warp.
/// eSpeak NG's f5 and m1 lose as they are (0.763 → 0.704, 0.773 → 0.707): a formant
/// synthesiser heard well enough on some lines still scores as no recorded voice does, which
/// is why the search is asked for, not the default.
const SEARCH_GAIN: f32 = 0.5;

/// The warp among [`SEARCHED_WARPS`] through which a phone loop hears `sound`'s first
/// [`SCORED_VOICE`] best, when that is at least [`SEARCH_GAIN`] a frame better than through
/// its pitch's warp (read at `by_pitch` frames a second); `None` to keep that one (also when
/// the recogniser fails: the line is then recognised as it would have been).
fn searched(sound: &Sound, by_pitch: u32) -> Option<f32> {
    let voiced = sound.voice_activity();
    let score = |frame_rate: u32| -> Option<f32> {
        let heard = Heard::warped(sound, frame_rate);
        let cut = scored_cut(&voiced, &heard);
        let search = phones::blind_search(Recognition::PhoneLoop).warped(frame_rate);
        let mut recogniser = Recogniser::load(&search).ok()?;
        recogniser
            .decode_scored(&heard.samples()[..cut])
            .ok()?
            .score_per_frame
    };
    let own = score(by_pitch)?;
    if own < HEARD_POORLY {
        return None;
    }
    let others: Vec<f32> = SEARCHED_WARPS
        .into_iter()
        .filter(|&w| crate::warp::frame_rate_of(w) != by_pitch)
        .collect();
    // Two at a time: each phone loop takes a turn of the cores of its own.
    let scored: Vec<(f32, f32)> = std::thread::scope(|scope| {
        let halves: Vec<_> = [0, 1]
            .map(|half| {
                let (others, score) = (&others, &score);
                scope.spawn(move || {
                    others
                        .iter()
                        .skip(half)
                        .step_by(2)
                        .filter_map(|&w| Some((w, score(crate::warp::frame_rate_of(w))?)))
                        .collect::<Vec<_>>()
                })
            })
            .into_iter()
            .collect();
        halves
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let (warp, best) = scored.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    tracing::debug!(own, warp, best, "the best warp found against the pitch's");
    (best >= own + SEARCH_GAIN).then_some(warp)
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
        let hearing = hearing(sound, voice);
        let language = language_named(language.unwrap_or(ENGLISH));
        let route = heard_route(blind_route(&language, blind), hearing);
        let owned = sound.clone();
        Loading {
            route,
            sound: identity(sound),
            voice,
            hearing,
            thread: std::thread::spawn(move || {
                prepare(route, &owned, &Heard::as_decided(&owned, hearing))
            }),
        }
    }

    /// How `sound` is heard through `voice`, when this recogniser was loaded for them.
    fn hearing_of(&self, sound: &Sound, voice: Voice) -> Option<Hearing> {
        (self.voice == voice && self.sound == identity(sound)).then_some(self.hearing)
    }

    /// The loaded recogniser, when it is the one `route` needs at `frame_rate`.
    fn finish(self, route: Recognition, frame_rate: u32) -> Result<Option<Ready>, PhoneError> {
        if self.route != route || self.hearing.frame_rate != frame_rate {
            return Ok(None);
        }
        match self.thread.join() {
            Ok(ready) => Ok(Some(ready)),
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
) -> Result<Recognised, PhoneError> {
    recognise_line(
        sound,
        transcript.map(Transcript::Typed),
        language,
        blind,
        loading,
        voice,
    )
}

/// A line's phones, how they were found, and what was done instead of what was asked.
pub type Recognised = (Vec<Phone>, Recognition, Vec<String>);

/// A transcript as it was typed, or as it is said already (a piece of a longer one whose
/// numbers, symbols and what is not spoken were read: [`in_pieces`]).
enum Transcript<'a> {
    Typed(&'a str),
    Said(String),
}

/// [`recognise_loaded`], with a transcript typed or said.
fn recognise_line(
    sound: &Sound,
    transcript: Option<Transcript<'_>>,
    language: Option<&str>,
    blind: Recognition,
    loading: Option<Loading>,
    voice: Voice,
) -> Result<Recognised, PhoneError> {
    let language = check_language(language.unwrap_or(ENGLISH))?;
    let language = language.as_str();
    let mut notes = Vec::new();
    // A Japanese transcript in kanji is read into kana by MeCab: eSpeak NG would say "Chinese
    // letter" for each kanji (two such lines: 0.68–0.80 viseme agreement, P/B/M 2/8, in eSpeak
    // NG's ja and m3). Without MeCab the speech is heard without it (0.80–0.93, 7/8).
    let japanese = is_language(language, "ja");
    // What a typed Japanese transcript says aloud.
    let spoken_japanese = match &transcript {
        Some(Transcript::Typed(text)) if japanese => Some(crate::script::spoken(text).text),
        _ => None,
    };
    let mut mecab = None;
    let transcript = match transcript {
        Some(Transcript::Typed(text))
            if spoken_japanese.as_deref().is_some_and(|spoken| {
                crate::japanese::said(spoken, None)
                    .is_ok_and(|plain| crate::japanese::has_kanji(&plain))
            }) =>
        {
            // Read once here, so that a MeCab that cannot read it (another dictionary, another
            // encoding) sets the transcript aside, as a missing one does.
            let found = crate::japanese::Mecab::find().and_then(|found| {
                let spoken = spoken_japanese.as_deref().unwrap_or_default();
                crate::japanese::said(spoken, Some(&found)).map(|_| found)
            });
            match found {
                Ok(found) => {
                    notes.push("the transcript's kanji were read into kana by MeCab".to_owned());
                    mecab = Some(found);
                    Some(Transcript::Typed(text))
                }
                Err(e) => {
                    notes.push(format!(
                        "eSpeak NG reads no kanji (it says \"Chinese letter\" for each) and {e}: the speech was recognised without its transcript; written in kana, the transcript is aligned"
                    ));
                    None
                }
            }
        }
        transcript => transcript,
    };
    if let (Some(_), Some(spoken)) = (&transcript, &spoken_japanese) {
        let (_, unsaid) = crate::japanese::unsaid_parentheses(spoken);
        if !unsaid.is_empty() {
            notes.push(format!(
                "left out of the transcript as not said (a direction, a speaker or a reading in parentheses): {}",
                unsaid.join(", ")
            ));
        }
    }
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
        .unwrap_or_else(|| hearing(sound, voice));
    if voice == Voice::Search && !hearing.whispered {
        notes.push(format!(
            "found by listening: the voice is heard through a vocal tract {:.2} times as long as the acoustic model's",
            faceanim_sphinx_sys::FRAME_RATE as f32 / hearing.frame_rate as f32
        ));
    }
    let heard = Heard::as_decided(sound, hearing);
    if let Some(transcript) = transcript {
        let english = is_english(language);
        // Numbers, symbols, units and abbreviations said as words ("1985": "19 85", "$5": "5
        // dollars", "Dr. Jones": "doctor Jones"; German "1985" "neunzehnhundert…", "am 3."
        // "am dritten"; Spanish "p. ej." "por ejemplo", French "XIXe" "dix-neuvième"; Japanese
        // "3本" "san-bon", its kanji read by MeCab; Korean "3시" "se si"; Mandarin "2个" "liǎng
        // gè", "2024年" digit by digit); eSpeak NG says the other languages' numbers as their
        // speakers do.
        let as_said = |text: String| -> Result<String, PhoneError> {
            Ok(if english {
                crate::script::english_said(&text)
            } else if is_language(language, "de") {
                crate::german::german_said(&text)
            } else if japanese {
                crate::japanese::said(&text, mecab.as_ref())?
            } else {
                let text = crate::abbreviations::said(language, &text);
                let text = crate::ordinals::said(language, &text);
                crate::chinese::said(language, &crate::korean::said(language, &text))
            })
        };
        let (said, cues) = match transcript {
            Transcript::Typed(text) => {
                // Only what is said aloud: a subtitle's timecodes, markup and bracketed
                // directions would be aligned as words nobody said.
                let spoken = crate::script::spoken(text);
                notes.extend(spoken.note());
                (as_said(spoken.text)?, spoken.cues)
            }
            Transcript::Said(text) => (text, Vec::new()),
        };
        let text = said.as_str();
        let words = phones::transcript_words(text, sound.seconds())?;
        // A subtitle is aligned cue by cue, each within its own time.
        if !cues.is_empty() {
            let cued = within_cues(&cues, sound.seconds());
            let cued = if japanese {
                // One run of MeCab reads every cue.
                let (times, texts): (Vec<_>, Vec<_>) =
                    cued.into_iter().map(|(s, e, text)| ((s, e), text)).unzip();
                let said = crate::japanese::said_each(texts, mecab.as_ref())?;
                times
                    .into_iter()
                    .zip(said)
                    .map(|((s, e), text)| (s, e, text))
                    .collect()
            } else {
                cued.into_iter()
                    .map(|(start, end, text)| Ok((start, end, as_said(text)?)))
                    .collect::<Result<Vec<_>, PhoneError>>()?
            };
            let cues = cued.len();
            let aligned = cues_fit(&cued).and_then(|()| {
                aligned_within(sound, cued, language, blind, voice).map_err(|e| e.to_string())
            });
            match aligned {
                Ok((phones, recognition, told)) => {
                    notes.extend(told);
                    notes.push(format!(
                        "aligned cue by cue within the subtitle's times ({cues} cues)"
                    ));
                    return Ok((phones, recognition, notes));
                }
                // The words are aligned together, as a transcript's.
                Err(e) => notes.push(format!(
                    "the subtitle's times do not fit the recording ({e}): its words were aligned together"
                )),
            }
        }
        let voiced = sound.voice_activity();
        // A long English recording is aligned a piece at a time.
        if english && sound.seconds() > WHOLE_LINE {
            let pieces = crate::script::pieces(text, PIECE_WORDS);
            if pieces.len() > 1 {
                match in_pieces(sound, &voiced, &pieces, language, blind, voice) {
                    Ok(Some((phones, recognition, told))) => {
                        notes.extend(told);
                        return Ok((phones, recognition, notes));
                    }
                    Ok(None) => {}
                    Err(e) => tracing::debug!(%e, "the recording could not be cut into pieces"),
                }
            }
        }
        // How sharply the voice follows a synthesiser's is asked of English lines only (the
        // others are timed by synthesis whatever it is).
        let synthesis = || match crate::synthesis::timed_by_synthesis(
            sound, &voiced, text, language, english,
        ) {
            Ok(timed) if !timed.phones.is_empty() => Ok(timed),
            Ok(_) => Err("the transcript could not be aligned by synthesis".to_owned()),
            Err(e) => Err(format!(
                "the transcript could not be aligned by synthesis ({e})"
            )),
        };
        // Timed by synthesis first (a few hundredths of the line's time): a voice the
        // synthesiser's own rendition follows sharply is timed by it; any other English line
        // by the recogniser, and by synthesis where the recogniser cannot align it.
        let by_synthesis = (!english || sound.seconds() <= SYNTHESIS_FIRST).then(synthesis);
        // Why the recogniser could not align it, when it tried.
        let mut why = None;
        if english {
            let sharp = match &by_synthesis {
                Some(Ok(timed)) => {
                    tracing::debug!(
                        sharpness = timed.sharpness,
                        voice_ratio = timed.voice_ratio,
                        "how sharply the synthesiser's rendition follows the voice"
                    );
                    timed.sharpness >= SAME_VOICE
                }
                _ => false,
            };
            if sharp {
                notes.push(
                    "the voice follows the synthesiser's own rendition of the transcript closely (a synthesiser's voice): the transcript was aligned by synthesis"
                        .to_owned(),
                );
            } else {
                let mut pronounced: Vec<String> = Vec::new();
                let aligned = phones::align_english(&heard, &words, &mut pronounced);
                match aligned {
                    Ok(phones) => {
                        if !pronounced.is_empty() {
                            notes.push(format!(
                                "the pronouncing dictionary lacks {}: said as eSpeak NG says {}",
                                pronounced.join(", "),
                                if pronounced.len() == 1 { "it" } else { "them" }
                            ));
                        }
                        let phones = phones::voiced_pauses(phones, &voiced);
                        let told = notes.len();
                        let phones = unsaid_recognised(
                            sound, phones, &voiced, language, blind, voice, &mut notes,
                        );
                        // Forced alignment spreads a transcript over speech it does not say
                        // too, where no silence is left over.
                        if notes.len() == told
                            && let Some(Ok(timed)) = &by_synthesis
                        {
                            notes.extend(mismatch(timed.voice_ratio));
                        }
                        return Ok((phones, Recognition::Transcript, notes));
                    }
                    Err(reason) => why = Some(reason),
                }
            }
        }
        let failed = match by_synthesis.unwrap_or_else(synthesis) {
            Ok(timed) => {
                if let Some(why) = why {
                    notes.push(format!("{why}: the transcript was aligned by synthesis"));
                }
                tracing::debug!(
                    voice_ratio = timed.voice_ratio,
                    "how many times the rendition's voice the recording holds"
                );
                notes.extend(mismatch(timed.voice_ratio));
                let phones = unsaid_recognised(
                    sound,
                    timed.phones,
                    &voiced,
                    language,
                    blind,
                    voice,
                    &mut notes,
                );
                return Ok((phones, Recognition::Synthesis, notes));
            }
            Err(failed) => failed,
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
    let ready = match loading
        .map(|l| l.finish(blind, hearing.frame_rate))
        .transpose()?
        .flatten()
    {
        Some(ready) => ready,
        None => prepare(blind, sound, &heard),
    };
    let loaded = Loaded {
        recogniser: ready.recogniser?,
        frame_rate: heard.frame_rate(),
    };
    let Some(phones) = ready.phones else {
        return Ok((
            crate::holds::lips_held(
                sound,
                phone_loop_adapting(sound, &heard, Some(loaded))?,
                heard.warp(),
            ),
            blind,
            notes,
        ));
    };
    let Scored {
        decoded,
        whole,
        first,
        recogniser: loop_recogniser,
    } = phones?;
    tracing::debug!(
        score_per_frame = decoded.score_per_frame,
        whole,
        adapted = first.is_some(),
        "the phone loop's acoustic score a frame of speech"
    );
    // Every later decode of the line by the model adapted to its voice: the words, their
    // alignment, the phones; with the closures of the lips the first pass heard.
    let (adaptation, closures) = first.map(|f| (f.adaptation, f.closures)).unzip();
    let adapted = adaptation.is_some();
    let closures = |phones: Vec<Phone>| match &closures {
        Some(closures) => crate::adapt::keep_closures(phones, closures),
        None => phones,
    };
    let keep = &closures;
    let heard = heard.adapted(adaptation);
    let heard_ref = &heard;
    let frame_rate = heard.frame_rate();
    // The line's phones: those decoded already when they are the whole line's and the model
    // was not adapted; else decoded (again) by the phone loop `loaded`, when its first pass
    // was the whole line's, or by one loaded now. A recogniser is loaded only when this line
    // holds no other: each holds a turn of the cores, and a line that waits for a second turn
    // while it holds one would wait forever once every core's turn is held so.
    let segments = decoded.segments;
    let phones_heard = move |loaded: Option<Recogniser>| {
        if whole && !adapted {
            return Ok(phones::phones_of(segments));
        }
        let loaded = loaded.filter(|_| whole).map(|recogniser| Loaded {
            recogniser,
            frame_rate,
        });
        phone_loop_adapting(sound, heard_ref, loaded).map(keep)
    };
    // A voice the acoustic model hears poorly (a formant synthesiser's buzz) is recognised
    // by its phones: its words are mostly wrong, and slow to search for.
    if decoded.score_per_frame.is_some_and(|s| s < HEARD_POORLY) {
        drop(loaded);
        let phones_heard = phones_heard(Some(loop_recogniser))?;
        notes.push(
            "the recogniser hears this voice poorly (as a formant synthesiser's): its phones were recognised, not its words"
                .to_owned(),
        );
        return Ok((
            crate::holds::lips_held(sound, phones_heard, heard.warp()),
            Recognition::PhoneLoop,
            notes,
        ));
    }
    // The words' alignment loads a recogniser of its own.
    drop(loop_recogniser);
    let words = closures(phones::recognise_words(&heard, Some(loaded))?);
    // Words the recogniser could not make out leave the voice unsaid (a formant synthesiser,
    // a whisper): the phones heard there, where they say more.
    let voiced = sound.voice_activity();
    let said = said_share(&words, &voiced);
    tracing::debug!(said, "the words recognised cover this share of the voice");
    if said < WORDS_SAY_ENOUGH {
        let phones = phones_heard(None)?;
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

/// The longest English line, seconds, the recogniser aligns to its transcript whole; a longer
/// one is aligned a piece at a time ([`in_pieces`]), as quickly whatever its length (flite's
/// slt reading a paragraph 70 times over, 20 minutes: 0.959 agreement at 0.03× real time;
/// whole, 0.958 at 0.21×, the search growing faster than the line), and where the recogniser
/// cannot align a piece, only that piece is aligned by synthesis.
const WHOLE_LINE: f32 = 30.0;

/// About how many words a piece of a long English line holds ([`crate::script::pieces`]):
/// 15–20 s of speech.
const PIECE_WORDS: usize = 45;

/// `sound`, an English recording of a long transcript cut into `pieces`, aligned a piece at a
/// time: where each piece starts and ends is found by synthesis ([`crate::synthesis::seams`]:
/// the pieces spoken one after the other, the recording warped onto them, each seam moved into
/// the pause nearest it), and each piece of the recording is then a line of its own
/// ([`aligned_within`]), with a note that says so. `None` where either sound holds no speech.
fn in_pieces(
    sound: &Sound,
    voiced: &[bool],
    pieces: &[String],
    language: &str,
    blind: Recognition,
    voice: Voice,
) -> Result<Option<Recognised>, PhoneError> {
    let Some(seams) = crate::synthesis::seams(sound, voiced, pieces, language)? else {
        return Ok(None);
    };
    let starts = std::iter::once(0.0).chain(seams.iter().copied());
    let ends = seams
        .iter()
        .copied()
        .chain(std::iter::once(sound.seconds()));
    let windows = starts
        .zip(ends)
        .zip(pieces.iter().cloned())
        .map(|((start, end), piece)| (start, end, piece))
        .collect();
    let (phones, recognition, mut notes) = aligned_within(sound, windows, language, blind, voice)?;
    notes.push(format!(
        "the recording is long: its transcript was aligned in {} pieces, each a few sentences",
        pieces.len()
    ));
    Ok(Some((phones, recognition, notes)))
}

/// How long before a subtitle's cue shows its words are looked for, seconds: cues are timed by
/// hand, often a little late. None are looked for after it hides: a cue is held on screen
/// until its words end or after, and what follows them (music, a sound effect) would be
/// taken for their end.
const CUE_MARGIN: f32 = 0.5;

/// The stretch of a recording of `seconds` each of `cues` is aligned within, with its words:
/// the cue's time from [`CUE_MARGIN`] before it, but never before the middle of the gap after
/// the cue before, nor outside the recording (a cue that starts after it ends is left out).
fn within_cues(cues: &[crate::script::Cue], seconds: f32) -> Vec<(f32, f32, String)> {
    let mut windows = Vec::with_capacity(cues.len());
    for (k, cue) in cues.iter().enumerate() {
        let after = k
            .checked_sub(1)
            .map_or(0.0, |p| (cues[p].shown.end + cue.shown.start) / 2.0);
        let start = (cue.shown.start - CUE_MARGIN).max(after).max(0.0);
        let end = cue.shown.end.min(seconds);
        if end > start {
            windows.push((start, end, cue.text.clone()));
        }
    }
    windows
}

/// Whether `cued`, the stretch each cue is aligned within and its words ([`within_cues`]),
/// can be this recording's; why not where it cannot: a cue whose time cannot hold its words
/// (a subtitle for another cut of the video, or another recording), or none within it.
fn cues_fit(cued: &[(f32, f32, String)]) -> Result<(), String> {
    if cued.is_empty() {
        return Err("every cue starts after it ends".to_owned());
    }
    for (start, end, text) in cued {
        let words = text.split_whitespace().count();
        if words as f32 > phones::MAX_WORDS_PER_SECOND * (end - start) + 1.0 {
            return Err(format!(
                "the cue at {start:.1} s holds {words} words for {:.1} s",
                end - start
            ));
        }
    }
    Ok(())
}

/// `sound` aligned a stretch at a time: each of `windows` (start, end, seconds, in order and
/// apart, and the words said in it) is a line of its own ([`recognise_line`]: aligned by the
/// recogniser, or by synthesis where that fails), its phones placed back at its start, and
/// what lies between them said by nobody ([`crate::visemes::NOTHING_SAID`]). The notes are the stretches' own, each once; the route is
/// the recogniser's where it aligned any stretch.
fn aligned_within(
    sound: &Sound,
    windows: Vec<(f32, f32, String)>,
    language: &str,
    blind: Recognition,
    voice: Voice,
) -> Result<Recognised, PhoneError> {
    let rate = crate::audio::SAMPLE_RATE as f32;
    let sample = |t: f32| ((t.max(0.0) * rate).round() as usize).min(sound.samples.len());
    let (mut phones, mut notes, mut routes) = (Vec::<Phone>::new(), Vec::new(), Vec::new());
    // Whether the last stretch ends before the sound does.
    let short = windows.last().map_or(0, |w| sample(w.1)) < sound.samples.len();
    let silence = |start: f32, end: f32| Phone {
        label: crate::visemes::NOTHING_SAID.to_owned(),
        start,
        end,
    };
    for (start, end, text) in windows {
        let (from, to) = (sample(start), sample(end));
        let offset = from as f32 / rate;
        let reached = phones.last().map_or(0.0, |p| p.end);
        if offset > reached {
            phones.push(silence(reached, offset));
        }
        let part = Sound {
            samples: sound.samples[from..to.max(from)].to_vec(),
        };
        let (said, route, told) = recognise_line(
            &part,
            Some(Transcript::Said(text)),
            Some(language),
            blind,
            None,
            voice,
        )?;
        phones.extend(said.into_iter().map(|p| Phone {
            start: p.start + offset,
            end: p.end + offset,
            ..p
        }));
        // A stretch that something said by nobody follows is its phones' to its end: the
        // alignment's last may end a frame short, or at the end of its speech.
        let end = to as f32 / rate;
        match phones.last_mut().filter(|_| to < sound.samples.len()) {
            Some(last) if end - last.end < 0.05 => last.end = last.end.max(end),
            Some(last) => {
                let start = last.end;
                phones.push(Phone {
                    label: "SIL".to_owned(),
                    start,
                    end,
                });
            }
            None => {}
        }
        for note in told {
            if !notes.contains(&note) {
                notes.push(note);
            }
        }
        routes.push(route);
    }
    if short {
        let reached = phones.last().map_or(0.0, |p| p.end);
        phones.push(silence(reached, sound.seconds()));
    }
    let route = if routes.contains(&Recognition::Transcript) {
        Recognition::Transcript
    } else {
        routes.first().copied().unwrap_or(Recognition::Synthesis)
    };
    Ok((phones, route, notes))
}

/// `heard`'s phones by a phone loop (`loaded`, or one loaded now): when `heard` is not adapted
/// yet and its first pass hears the voice poorly, decoded a second time by the model adapted
/// to that voice, with the lips' closures the first pass's silences held ([`crate::adapt`]).
fn phone_loop_adapting(
    sound: &Sound,
    heard: &Heard<'_>,
    loaded: Option<Loaded>,
) -> Result<Vec<Phone>, PhoneError> {
    if heard.is_adapted() {
        return phones::phone_loop(heard, loaded);
    }
    let search = phones::blind_search(Recognition::PhoneLoop);
    let mut recogniser = heard.recogniser(search, loaded)?;
    let first = recogniser.decode_scored(heard.samples())?;
    let Some(pass) = crate::adapt::first_pass(
        &mut recogniser,
        heard.samples(),
        &first,
        sound,
        heard.warp(),
    ) else {
        return Ok(phones::phones_of(first.segments));
    };
    recogniser.adapt(&pass.adaptation)?;
    let second = phones::phones_of(recogniser.decode(heard.samples())?);
    Ok(crate::adapt::keep_closures(second, &pass.closures))
}

/// The least voice, seconds, a silence of a transcript's alignment may hold before that
/// stretch is taken for speech the transcript does not say ([`unsaid_recognised`]). A
/// speaker's pauses, breaths and a room's noise leave a few hundredths of a second of frames
/// heard inside one pause (the five LibriVox readings with their transcripts: at most 0.05 s;
/// two flite lines with 3 s of pink room noise between them: 0.01 s).
const UNSAID: f32 = 1.0;

/// How many times the voice of its transcript's rendition a recording may hold before a note
/// says the transcript may not say all of it: [`crate::synthesis`]'s warping spreads a
/// transcript over the whole recording, however much more was said, and the recogniser's
/// forced alignment does so where no silence is left over.
/// Measured: 0.9–1.3 for whole transcripts at a speaker's own pace (the five LibriVox readings;
/// flite's slt, kal, awb and rms; eSpeak NG in Japanese, German, French, Chinese and Korean),
/// 1.6–2.0 for those eSpeak NG lines at its slow 100 words a minute, 2.2 for a Spanish line
/// of two sentences with the first as its transcript. Its inverse bounds the other way: a
/// transcript that says twice what the recording holds or more (flite's slt saying two
/// sentences of a transcript of three, 0.43) is squeezed into it, and noted too.
const UNSAID_RATIO: f32 = 2.0;

/// The note a transcript aligned to a recording that holds `voice_ratio` times the voice of
/// its rendition gets: one when it says half of what the recording holds or less (its phones
/// spread over the rest), or twice as much or more (squeezed) — see [`UNSAID_RATIO`].
fn mismatch(voice_ratio: f32) -> Option<String> {
    if voice_ratio >= UNSAID_RATIO {
        Some(format!(
            "the recording holds {voice_ratio:.1} times the speech of its transcript spoken: if the transcript does not say all of it, its phones are spread over more than was said"
        ))
    } else if voice_ratio > 0.0 && voice_ratio * UNSAID_RATIO <= 1.0 {
        Some(format!(
            "the transcript spoken holds {:.1} times the speech of the recording: if the recording does not say all of it, its phones are squeezed into what was said",
            1.0 / voice_ratio
        ))
    } else {
        None
    }
}

/// How far before its first frame of voice and after its last a stretch the transcript does
/// not say is recognised, seconds: its first and last sounds' onsets and releases.
const UNSAID_MARGIN: f32 = 0.1;

/// `phones` (a transcript aligned to `sound`, its frames `voiced` as
/// [`Sound::voice_activity`] says) with each of its silences (runs of them taken as one) that
/// holds at least [`UNSAID`] of voice recognised without the transcript (by `blind`, in
/// `language`): speech the transcript does not say (a line's transcript given for a longer
/// take, an ad-lib after it), which would otherwise move the mouth through no phones. A note
/// says how much was; a stretch the recogniser cannot recognise (it is not installed, or hears
/// nothing) stays silence, its voice moving the mouth as any silence heard does.
fn unsaid_recognised(
    sound: &Sound,
    phones: Vec<Phone>,
    voiced: &[bool],
    language: &str,
    blind: Recognition,
    voice: Voice,
    notes: &mut Vec<String>,
) -> Vec<Phone> {
    let silence = |start: f32, end: f32| Phone {
        label: "SIL".to_owned(),
        start,
        end,
    };
    // Runs of silences as one.
    let mut merged: Vec<Phone> = Vec::with_capacity(phones.len());
    for phone in phones {
        match merged.last_mut() {
            Some(last) if last.label == "SIL" && phone.label == "SIL" => last.end = phone.end,
            _ => merged.push(phone),
        }
    }
    let mut out = Vec::with_capacity(merged.len());
    let (mut unsaid, mut stretches, mut span) = (0.0f32, 0usize, (f32::MAX, 0.0f32));
    for phone in merged {
        let frames = phone.frames(voiced);
        let heard = frames.iter().filter(|&&v| v).count();
        let first = phone.first_frame(voiced.len());
        if phone.label == "SIL" {
            tracing::trace!(
                start = phone.start,
                end = phone.end,
                heard = heard as f32 / 100.0,
                "a silence of the transcript's alignment, and the voice heard in it"
            );
        }
        let ends = frames
            .iter()
            .position(|&v| v)
            .zip(frames.iter().rposition(|&v| v));
        let (true, Some((a, b))) = (phone.label == "SIL" && heard as f32 >= UNSAID * 100.0, ends)
        else {
            out.push(phone);
            continue;
        };
        let start = ((first + a) as f32 / 100.0 - UNSAID_MARGIN).max(phone.start);
        let end = ((first + b + 1) as f32 / 100.0 + UNSAID_MARGIN).min(phone.end);
        let sample = |t: f32| ((t * SAMPLE_RATE as f32) as usize).min(sound.samples.len());
        let stretch = Sound {
            samples: sound.samples[sample(start)..sample(end)].to_vec(),
        };
        let said = match recognise_loaded(&stretch, None, Some(language), blind, None, voice) {
            Ok((said, _, _)) if said.iter().any(|p| p.label != "SIL") => said,
            Ok(_) | Err(_) => {
                tracing::debug!(
                    start,
                    end,
                    "speech the transcript does not say, not recognised"
                );
                out.push(phone);
                continue;
            }
        };
        unsaid += heard as f32 / 100.0;
        stretches += 1;
        span = (span.0.min(start), span.1.max(end));
        if start > phone.start {
            out.push(silence(phone.start, start));
        }
        out.extend(said.into_iter().map(|p| Phone {
            start: p.start + start,
            end: (p.end + start).min(end),
            ..p
        }));
        if phone.end > end {
            out.push(silence(end, phone.end));
        }
    }
    if stretches > 0 {
        let stretches = match stretches {
            1 => String::new(),
            n => format!(" in {n} stretches"),
        };
        notes.push(format!(
            "the transcript does not cover {unsaid:.1} s of the voice{stretches} ({:.2}–{:.2} s): that speech was recognised without it",
            span.0, span.1
        ));
    }
    out
}

/// The phone loop's acoustic score per frame of speech ([`Decoded::score_per_frame`]) below
/// which a voice is heard too poorly for its words to be searched for. Chosen on the tuning
/// voices' Harvard lines (`scripts/bench-lipsync.py`, and the same lines from the
/// synthesisers' command lines): flite's slt, rms and awb score −7.8 to −13.1, to −13.8 with
/// pink room noise, to −14.2 raised as a child's, to −16.0 lowered by a fifth (a deep voice,
/// whose words still do better than its phones); eSpeak NG's m3 −15.6 to −20.4, its f2 −13.0
/// to −18.6. The lines of m3 below this (seven of eight) are lip-synced as well or better by
/// their phones (0.632 agreement and P/B/M 0.69 over all eight, against 0.608 and 0.66 by its
/// words), in half the time; f2's words mostly do better, and its lines below this
/// (three) did as well either way (0.718 and 0.59 over all eight, against 0.712 and 0.59).
/// Real readings score −8.5 to −14.0 (LibriVox, and the recordings of Debian's
/// pocketsphinx-testdata).
const HEARD_POORLY: f32 = -17.0;

/// The [`crate::synthesis`] warping's sharpness (how much closer a recording follows the
/// synthesiser's own rendition of its transcript on the warping path than a few frames beside
/// it) from which an English line is timed by synthesis, not by the recogniser: the voice is
/// a synthesiser's of eSpeak NG's kind, whose phones its rendition times closely. Chosen on the
/// tuning voices' Harvard lines (`scripts/bench-lipsync.py`, with their transcripts, clean and
/// with the bench's effects): eSpeak NG's m3 scores 3.2–3.6 (2.8–3.1 in a noisy room) and
/// its lines are timed better by synthesis (0.974 agreement against 0.892); flite's slt, rms
/// and awb score 1.1–1.6, clean, noisy, raised or lowered, and are timed better by the
/// recogniser (0.959–0.964 against 0.87–0.91); LibriVox readers 1.2–1.3. eSpeak NG's f2
/// (1.6–1.8) and whisperf (1.4–1.6) fall among the diphone voices and keep the recogniser's
/// alignment (0.87 and 0.89), as does m3 raised or lowered by the bench's effects (1.0–1.1).
const SAME_VOICE: f32 = 2.0;

/// The longest English line, seconds, timed by synthesis before the recogniser aligns it (to
/// see whether its voice is a synthesiser's, [`SAME_VOICE`]): a line of dialogue. Warping a
/// longer recording onto its rendition costs memory and time that grow with the square of its
/// length up to three minutes (a minute: about 20 MB and half a second; three minutes,
/// 200 MB), so a longer one (whose transcript is too short to cut into pieces: [`WHOLE_LINE`])
/// is aligned by the recogniser, and by synthesis only where the recogniser cannot.
const SYNTHESIS_FIRST: f32 = 60.0;

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

    /// Tags as game engines, localisation tools and locales write them are tried as eSpeak NG
    /// names them, nearest first.
    #[test]
    fn a_language_is_known_by_its_name_whatever_the_voice() {
        assert!(
            is_language("de", "de") && is_language("de-at", "de") && is_language("de+m3", "de")
        );
        assert!(!is_language("den", "de") && !is_language("d", "de") && !is_language("en", "de"));
    }

    #[test]
    fn a_language_tag_is_spelt_as_espeak_ng_names_languages() {
        let first = |tag: &str| spellings(tag).into_iter().next().unwrap();
        assert_eq!(first("ja-JP"), "ja-jp");
        assert_eq!(first("en_US.UTF-8"), "en-us");
        assert_eq!(first("de_DE@euro"), "de-de");
        assert_eq!(first(" EN "), "en");
        assert_eq!(spellings("ja-JP"), ["ja-jp", "ja", "ja-JP"]);
        assert_eq!(
            spellings("zh-Hant-TW"),
            ["zh-hant-tw", "zh-tw", "zh", "zh-Hant-TW"]
        );
        assert_eq!(spellings("zh_HK"), ["zh-hk", "yue", "zh", "zh_HK"]);
        assert_eq!(spellings("es-MX"), ["es-mx", "es-419", "es", "es-MX"]);
        assert_eq!(spellings("es-ES"), ["es-es", "es", "es-ES"]);
        assert_eq!(spellings("en-US+f3"), ["en-us+f3", "en+f3", "en-US+f3"]);
        assert_eq!(spellings("cmn"), ["cmn"]);
        assert_eq!(spellings("Japanese"), ["japanese", "Japanese"]);
    }

    /// Each tag reaches the language eSpeak NG speaks nearest it, and the routes see it as that
    /// language (an English locale is English, recognised by words).
    #[test]
    fn a_language_tag_is_spoken_as_the_nearest_language_espeak_ng_has() {
        if faceanim_espeak_sys::check_voice(ENGLISH).is_err() {
            return;
        }
        for (tag, named) in [
            ("en-us", "en-us"),
            ("en_US.UTF-8", "en-us"),
            ("EN", "en"),
            ("en-GB", "en-gb"),
            ("en-AU", "en"),
            ("en-US+f3", "en-us+f3"),
            ("ja-JP", "ja"),
            ("pt_BR", "pt-br"),
            ("pt-PT", "pt-pt"),
            ("es-MX", "es-mx"),
            ("es-AR", "es-419"),
            ("es-ES", "es"),
            ("fr-FR", "fr-fr"),
            ("fr-CA", "fr"),
            ("zh-CN", "zh"),
            ("zh-Hant-TW", "zh"),
            ("zh-HK", "yue"),
            ("sr-Latn-RS", "sr"),
            ("ko-KR", "ko"),
        ] {
            assert_eq!(check_language(tag).unwrap(), named, "{tag}");
        }
        assert!(is_english(&check_language("en_GB.UTF-8").unwrap()));
        assert_eq!(
            blind_route(&language_named("en_US"), Recognition::Words),
            Recognition::Words
        );
        for wrong in ["englsh", "xx-YY", "e\0s"] {
            let error = check_language(wrong).unwrap_err();
            assert!(
                matches!(&error, PhoneError::UnknownLanguage(l) if l == wrong),
                "{error}"
            );
        }
    }

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
