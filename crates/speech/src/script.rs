//! What a transcript says aloud: the words of a line as people have them, without what is not
//! spoken.
//!
//! Transcripts come from scripts, subtitles and TTS prompts, and carry more than their words:
//! - subtitles (SubRip `.srt`, WebVTT `.vtt`): a `WEBVTT` header, cue numbers, timecodes
//!   (`00:00:01,000 --> 00:00:02,500`); Advanced SubStation Alpha (`.ass`, `.ssa`, as
//!   Aegisub, fansubs and ffmpeg write them): a script's header and styles, and each
//!   `Dialogue:` event's fields around its text, override tags (`{\i1}`, `{\k20}`, `{\fad(…)}`)
//!   and vector drawings (`{\p1}m 0 0 l …`), its line breaks (`\N`) read as breaks, and
//!   signs (on-screen text placed with `\pos` or `\move`), which nobody says;
//! - markup: SSML (`<break time="500ms"/>`, `<prosody …>`), subtitle styling (`<i>`,
//!   `<v Roger>`, `{\an8}`);
//! - directions in square brackets (`[laughs]`, `[music]`), as subtitles for the deaf and game
//!   scripts write them;
//! - a speaker's name in capitals before a colon at the start of a line (`NARRATOR: …`);
//! - emoji and pictographs (`😀`, `👍🏽`, `❤️`, `🇫🇷`, `✨`, `▶`, `→`), as chat messages read
//!   by a TTS voice and social posts carry them, and the `♪` that subtitles put around
//!   singing.
//!
//! Spoken, each would become words nobody said ("zero zero colon zero one…", "break time
//! five hundred ms"; eSpeak NG says an emoji's name, `👍` "thumbs up", `⭐` "estrella blanca
//! mediana"), aligned onto the speech of others. They are left out, and said so. A
//! subtitle's timecodes still say when each cue's words are shown ([`Spoken::cues`]), so that
//! each can be aligned within its own time.
//! Parentheses are kept: prose puts spoken asides in them as often as scripts put directions.
//!
//! The words left are read as they were meant, whatever program typed them ([`plain`]): a
//! word processor's curly apostrophe (`It’s`), macOS's decomposed accents (`e` + `◌́`, Korean
//! as separate jamo), full-width digits and letters, ligatures a PDF copies (`ﬁ`).

use unicode_normalization::UnicodeNormalization;

/// A transcript's spoken words and what was left out of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Spoken {
    /// The text, without what is not spoken (lines kept as lines).
    pub text: String,
    /// What was left out: each bracketed direction and tag as written (the first few), and
    /// how many timecodes.
    pub left_out: Vec<String>,
    /// A subtitle's cues, in order of their start, each with what it says aloud (empty for
    /// a transcript without timecodes). Cues that overlap (two speakers at once) are one.
    pub cues: Vec<Cue>,
}

/// One cue of a subtitle.
#[derive(Debug, Clone, PartialEq)]
pub struct Cue {
    /// When it is shown, seconds: from its start to its end.
    pub shown: std::ops::Range<f32>,
    /// What it says aloud ([`spoken`]).
    pub text: String,
}

/// The times of a SubRip or WebVTT timecode line (`00:01:02,500 --> 00:01:04,000`, `01:02.500
/// --> 01:04.000 align:start`), seconds; `None` for another line or an end before the start.
fn timecode(line: &str) -> Option<(f32, f32)> {
    let (from, to) = line.split_once("-->")?;
    let (start, end) = (
        subtitle_time(from.split_whitespace().next()?)?,
        subtitle_time(to.split_whitespace().next()?)?,
    );
    (end > start).then_some((start, end))
}

/// A subtitle's clock time (`00:01:02,500`, `01:02.500`, SubStation's `0:01:02.50`), seconds;
/// `None` for anything else.
fn subtitle_time(t: &str) -> Option<f32> {
    let t = t.trim().replace(',', ".");
    let mut seconds = 0.0f64;
    for part in t.split(':') {
        let value: f64 = part
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v >= 0.0)?;
        seconds = seconds * 60.0 + value;
    }
    (t.contains(':')).then_some(seconds as f32)
}

impl Spoken {
    /// The note that says what was left out, when anything was.
    #[must_use]
    pub fn note(&self) -> Option<String> {
        (!self.left_out.is_empty()).then(|| {
            format!(
                "left out of the transcript as not spoken: {}",
                self.left_out.join(", ")
            )
        })
    }
}

/// The directions, tags and names a note lists by name; more are counted.
const LISTED: usize = 6;

/// The longest speaker's name taken as one before a colon, characters.
const LONGEST_NAME: usize = 30;

/// Extensions of the files a transcript comes in: plain text, a subtitle (SubRip, WebVTT,
/// SubStation Alpha), a label file, Markdown. The studio's page offers the same
/// (`web/capture.js`, `TRANSCRIPT`).
pub const TRANSCRIPT_FILES: [&str; 8] = ["txt", "text", "lab", "srt", "vtt", "ass", "ssa", "md"];

/// What `text` says aloud (see the module's docs).
#[must_use]
pub fn spoken(text: &str) -> Spoken {
    let text = plain(text);
    let lines: Vec<&str> = text.lines().collect();
    if let Some(events) = substation(&lines) {
        let mut left_out = events.left_out;
        if events.styled {
            left_out.insert(0, "the subtitle's override tags".to_owned());
        }
        return said_from(events.kept, events.times, left_out);
    }
    let webvtt = lines
        .first()
        .is_some_and(|l| l.trim().starts_with("WEBVTT"));
    let (mut kept, mut timecodes) = (Vec::with_capacity(lines.len()), 0usize);
    // Inside a WebVTT comment, style or region block: up to the next blank line.
    let mut block = false;
    // The cues' times, and the cue (an index into them) the line being read belongs to.
    let (mut times, mut cue): (Vec<(f32, f32)>, Option<usize>) = (Vec::new(), None);
    for (k, line) in lines.iter().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() {
            block = false;
            cue = None;
        } else if webvtt
            && ["NOTE", "STYLE", "REGION"]
                .iter()
                .any(|b| trimmed.starts_with(b))
        {
            block = true;
        }
        // A cue's number (SubRip) or identifier (WebVTT: any text) stands on the line before
        // its timecode.
        let cue_number = !trimmed.is_empty()
            && (trimmed.chars().all(|c| c.is_ascii_digit()) || webvtt)
            && lines.get(k + 1).is_some_and(|next| next.contains("-->"));
        if trimmed.contains("-->") {
            timecodes += 1;
            cue = timecode(trimmed).map(|t| {
                times.push(t);
                times.len() - 1
            });
        } else if !(block || cue_number || (k == 0 && webvtt)) {
            kept.push(((*line).to_owned(), cue));
        }
    }
    let all_read = timecodes == times.len();
    let mut spoken = said_from(kept, times, Vec::new());
    match timecodes {
        0 => {}
        1 => spoken.left_out.push("a subtitle timecode".to_owned()),
        n => spoken.left_out.push(format!("{n} subtitle timecodes")),
    }
    if !all_read {
        spoken.cues.clear();
    }
    spoken
}

/// What the `kept` lines of a transcript (each with the cue, an index into `times`, it belongs
/// to) say aloud, with what was left out of them added to `left_out`; cue by cue only where
/// every line with words is in a cue.
fn said_from(
    kept: Vec<(String, Option<usize>)>,
    times: Vec<(f32, f32)>,
    mut left_out: Vec<String>,
) -> Spoken {
    let mut out = String::with_capacity(kept.iter().map(|(line, _)| line.len() + 1).sum());
    let mut said: Vec<String> = vec![String::new(); times.len()];
    for (k, (line, cue)) in kept.iter().enumerate() {
        if k > 0 {
            out.push('\n');
        }
        let line = unbracketed(line, &mut left_out);
        let line = unpictured(&line, &mut left_out);
        let line = unnamed(&line, &mut left_out);
        out.push_str(line);
        if let Some(text) = cue.and_then(|c| said.get_mut(c)) {
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(line);
        }
    }
    let mut listed: Vec<String> = Vec::new();
    for item in &left_out {
        if !listed.contains(item) {
            listed.push(item.clone());
        }
    }
    if listed.len() > LISTED {
        let more = listed.len() - LISTED;
        listed.truncate(LISTED);
        listed.push(format!("{more} more"));
    }
    Spoken {
        text: out,
        left_out: listed,
        // Cue by cue only where every word is in a cue whose time was read.
        cues: if kept
            .iter()
            .all(|(line, cue)| cue.is_some() || line.trim().is_empty())
        {
            merged(times, said)
        } else {
            Vec::new()
        },
    }
}

/// An Advanced SubStation Alpha script's events, read for their words.
struct Events {
    /// Each line of each event's text, with its event (an index into `times`).
    kept: Vec<(String, Option<usize>)>,
    /// Each event's start and end, seconds.
    times: Vec<(f32, f32)>,
    /// Whether any text had override tags (left out, and said so once).
    styled: bool,
    /// Events that could not be read, described.
    left_out: Vec<String>,
}

/// The SubStation Alpha fields of an event before its text, when the script has no `Format:`
/// line of its own (v4.00+; v4.00 names the first `Marked`).
const SUBSTATION_FIELDS: [&str; 10] = [
    "Layer", "Start", "End", "Style", "Name", "MarginL", "MarginR", "MarginV", "Effect", "Text",
];

/// `lines` read as an Advanced SubStation Alpha (`.ass`) or SubStation Alpha (`.ssa`) script,
/// `None` when they are not one (no `[Events]` section with a `Dialogue:` in it). Each
/// `Dialogue:` event's text is split at its hard and soft line breaks (`\N`, `\n`), its hard
/// spaces (`\h`) made spaces, its override blocks (`{…}`) taken out, and the vector drawing
/// that `{\p1}` starts and `{\p0}` ends left out with them; an event whose times and text
/// are those of another before it (drawn twice, its border and its fill) is said once. Signs —
/// events placed on the picture (`\pos`, `\move`, `\org`, `\clip`), as typesetters translate a
/// shop's name or a letter; dialogue keeps to its style's place, at most moved to the top with
/// `\an8` — are shown, not said: they are left out, and counted, since their words would
/// otherwise be aligned onto whoever speaks meanwhile. `Comment:` events are not shown, and not
/// said.
fn substation(lines: &[&str]) -> Option<Events> {
    let events = lines
        .iter()
        .position(|l| l.trim().eq_ignore_ascii_case("[events]"))?;
    let section = lines[events + 1..]
        .iter()
        .take_while(|l| !l.trim_start().starts_with('['));
    let mut fields: Vec<String> = SUBSTATION_FIELDS.iter().map(|f| (*f).to_owned()).collect();
    let mut out = Events {
        kept: Vec::new(),
        times: Vec::new(),
        styled: false,
        left_out: Vec::new(),
    };
    let mut seen: Vec<((f32, f32), String)> = Vec::new();
    let (mut dialogue, mut signs) = (false, 0usize);
    for line in section {
        let Some((kind, rest)) = line.split_once(':') else {
            continue;
        };
        match kind.trim() {
            "Format" => {
                fields = rest.split(',').map(|f| f.trim().to_owned()).collect();
            }
            "Dialogue" => {
                dialogue = true;
                let values: Vec<&str> = rest.trim_start().splitn(fields.len(), ',').collect();
                let field = |name: &str| {
                    fields
                        .iter()
                        .position(|f| f.eq_ignore_ascii_case(name))
                        .and_then(|k| values.get(k))
                };
                let (Some(start), Some(end), Some(text)) =
                    (field("Start"), field("End"), field("Text"))
                else {
                    out.left_out
                        .push(format!("an event of {} fields", values.len()));
                    continue;
                };
                let Some(shown) = subtitle_time(start)
                    .zip(subtitle_time(end))
                    .filter(|(start, end)| end > start)
                else {
                    out.left_out
                        .push(format!("an event timed {start} to {end}"));
                    continue;
                };
                let Shown {
                    text,
                    styled,
                    placed,
                } = substation_text(text);
                out.styled |= styled;
                if placed {
                    signs += 1;
                    continue;
                }
                if text.trim().is_empty() || seen.contains(&(shown, text.clone())) {
                    continue;
                }
                seen.push((shown, text.clone()));
                out.times.push(shown);
                let cue = Some(out.times.len() - 1);
                out.kept
                    .extend(text.split('\n').map(|line| (line.to_owned(), cue)));
            }
            _ => {}
        }
    }
    match signs {
        0 => {}
        1 => out
            .left_out
            .push("a sign (on-screen text placed with \\pos or \\move)".to_owned()),
        n => out.left_out.push(format!(
            "{n} signs (on-screen text placed with \\pos or \\move)"
        )),
    }
    dialogue.then_some(out)
}

/// A SubStation event's text as shown, and what its override tags said of it.
struct Shown {
    /// Its text: line breaks (`\N`, `\n`) as breaks, hard spaces (`\h`) as spaces, without
    /// its override blocks or what it draws.
    text: String,
    /// It had override tags.
    styled: bool,
    /// It is placed on the picture (`\pos`, `\move`, `\org`, `\clip`): a sign, translated
    /// on-screen text that nobody says.
    placed: bool,
}

/// What a SubStation event's `text` shows ([`Shown`]).
fn substation_text(text: &str) -> Shown {
    let mut out = Shown {
        text: String::with_capacity(text.len()),
        styled: false,
        placed: false,
    };
    let mut drawing = false;
    let mut rest = text;
    while !rest.is_empty() {
        if let Some(block) = rest.strip_prefix('{')
            && let Some(close) = block.find('}')
        {
            out.styled = true;
            for tag in block[..close].split('\\').skip(1) {
                // `\p1` (or any scale) draws until `\p0`; `\pos(…)` is a position.
                if let Some(scale) = tag.strip_prefix('p')
                    && let Ok(scale) = scale.trim().parse::<u32>()
                {
                    drawing = scale > 0;
                }
                out.placed |= ["pos(", "move(", "org(", "clip(", "iclip("]
                    .iter()
                    .any(|placing| tag.trim_start().starts_with(placing));
            }
            rest = &block[close + 1..];
            continue;
        }
        let mut chars = rest.chars();
        let Some(c) = chars.next() else { break };
        let after = chars.as_str();
        if c == '\\'
            && let Some(next) = after.chars().next()
        {
            let replaced = match next {
                'N' | 'n' => Some('\n'),
                'h' => Some(' '),
                _ => None,
            };
            if let Some(r) = replaced {
                if !drawing {
                    out.text.push(r);
                }
                rest = &after[next.len_utf8()..];
                continue;
            }
        }
        if !drawing {
            out.text.push(c);
        }
        rest = after;
    }
    out
}

/// Cues from their `times` and what each `said`, in order of their start: those that overlap
/// one cue (both texts, the first's first), those that say nothing left out.
fn merged(times: Vec<(f32, f32)>, said: Vec<String>) -> Vec<Cue> {
    let mut cues: Vec<Cue> = times
        .into_iter()
        .zip(said)
        .filter(|(_, text)| !text.trim().is_empty())
        .map(|((start, end), text)| Cue {
            shown: start..end,
            text,
        })
        .collect();
    cues.sort_by(|a, b| a.shown.start.total_cmp(&b.shown.start));
    let mut out: Vec<Cue> = Vec::with_capacity(cues.len());
    for cue in cues {
        match out.last_mut() {
            Some(last) if cue.shown.start < last.shown.end => {
                last.shown.end = last.shown.end.max(cue.shown.end);
                last.text.push('\n');
                last.text.push_str(&cue.text);
            }
            _ => out.push(cue),
        }
    }
    out
}

/// Titles written short before a name, and what is said for them (`Dr. Jones`, `Sgt Hale`).
/// The pronouncing dictionary reads `dr` as "drive" and `st` as "street", and lacks the rest,
/// which eSpeak NG then says letter by letter or as another word (`Lt.` "L T", `Gen.` "Jen").
const TITLES: [(&str, &str); 24] = [
    ("Adm", "admiral"),
    ("Capt", "captain"),
    ("Cmdr", "commander"),
    ("Col", "colonel"),
    ("Cpl", "corporal"),
    ("Det", "detective"),
    ("Dr", "doctor"),
    ("Fr", "father"),
    ("Ft", "fort"),
    ("Gen", "general"),
    ("Gov", "governor"),
    ("Insp", "inspector"),
    ("Lt", "lieutenant"),
    ("Maj", "major"),
    ("Mt", "mount"),
    ("Pres", "president"),
    ("Prof", "professor"),
    ("Pvt", "private"),
    ("Rep", "representative"),
    ("Rev", "reverend"),
    ("Sen", "senator"),
    ("Sgt", "sergeant"),
    ("Sr", "senior"),
    ("St", "saint"),
];

/// Months written short before a day or a year (`Jan. 5`, `Oct 1990`), and their names: the
/// dictionary says `jan` "jan", `oct` "ocked" and `sept` "sept".
const MONTHS: [(&str, &str); 12] = [
    ("Jan", "January"),
    ("Feb", "February"),
    ("Mar", "March"),
    ("Apr", "April"),
    ("Jun", "June"),
    ("Jul", "July"),
    ("Aug", "August"),
    ("Sep", "September"),
    ("Sept", "September"),
    ("Oct", "October"),
    ("Nov", "November"),
    ("Dec", "December"),
];

/// Abbreviations written with their full stops, and what is said for them: the dictionary
/// reads each letter (`e.g.` "E G") and lacks the rest (`approx.`, which eSpeak NG says
/// "approks"). `etc.` keeps its full stop, which may end a sentence.
const DOTTED: [(&str, &str); 8] = [
    ("approx.", "approximately"),
    ("dept.", "department"),
    ("e.g.", "for example"),
    ("esp.", "especially"),
    ("etc.", "et cetera."),
    ("govt.", "government"),
    ("i.e.", "that is"),
    ("incl.", "including"),
];

/// `text` with its [`DOTTED`] abbreviations said (in any case: `E.g.`), where each stands
/// alone: not after a letter, a digit or a full stop.
fn latin_abbreviations(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    let mut k = 0;
    'text: while k < text.len() {
        let alone = !out
            .chars()
            .next_back()
            .is_some_and(|c: char| c.is_alphanumeric() || c == '.');
        if alone {
            for (short, said) in DOTTED {
                if text
                    .get(k..k + short.len())
                    .is_some_and(|t| t.eq_ignore_ascii_case(short))
                {
                    out.push_str(said);
                    k += short.len();
                    continue 'text;
                }
            }
        }
        let c = text[k..].chars().next().unwrap_or(' ');
        out.push(c);
        k += c.len_utf8();
    }
    out
}

/// Words of an address written short after a name (`Main St.`, `Oak Dr.`, `5th Ave.`), and
/// what is said for them.
const STREETS: [(&str, &str); 5] = [
    ("Ave", "avenue"),
    ("Blvd", "boulevard"),
    ("Dr", "drive"),
    ("Rd", "road"),
    ("St", "street"),
];

/// An English transcript's abbreviations as the words said for them: a title before a name
/// (`Dr. Jones`: "doctor Jones", `St. Louis`: "saint Louis", `Sgt Hale`: "sergeant Hale"), a
/// street after one (`Main St.`: "Main street", `Oak Dr.`: "Oak drive"), a month before a day
/// or a year (`Jan. 5`: "January 5"), `No. 5` "number 5", `vs.` "versus", and the
/// abbreviations written with full stops (`e.g.`, `i.e.`, `etc.`, `approx.`). Only where the
/// capitals and numbers say which (a title is followed by a capitalised word, a street follows
/// one, a month and `No.` are followed by a number); any other use is left to the dictionary.
#[must_use]
pub fn english_abbreviations(text: &str) -> String {
    let text = latin_abbreviations(text);
    let mut out = String::with_capacity(text.len() + 16);
    let mut rest = text.as_str();
    // Whether the word before was a name or a number (a street follows one): capitalised
    // where a sentence does not start.
    let mut after_name = false;
    let mut sentence_starts = true;
    while let Some(start) = rest.find(char::is_alphanumeric) {
        let gap = &rest[..start];
        if gap.contains(['.', '!', '?', '\n']) {
            sentence_starts = true;
        }
        if gap.contains(|c: char| !c.is_whitespace()) {
            // `Paris, Dr. Jones`: the name before is not the street's.
            after_name &= !gap.contains([',', ';', ':', '(', ')', '"']);
        }
        out.push_str(gap);
        let word_and_after = &rest[start..];
        let end = word_and_after
            .find(|c: char| !c.is_alphanumeric() && c != '\'')
            .unwrap_or(word_and_after.len());
        let word = &word_and_after[..end];
        let after = &word_and_after[end..];
        // A word inside another (`e2e`, `x86`) or right after one is not an abbreviation.
        let alone = !out.chars().next_back().is_some_and(char::is_alphanumeric);
        let dotted = after.starts_with('.');
        let following = after[usize::from(dotted)..].trim_start();
        let spaced = after[usize::from(dotted)..].starts_with(char::is_whitespace);
        let named_next = spaced && following.starts_with(|c: char| c.is_uppercase());
        let numbered_next = spaced && following.starts_with(|c: char| c.is_ascii_digit());
        // A street after a name before a title before one: `Main St. Then …` ends a sentence,
        // while `Ask Dr. Banks` starts one.
        // What is said, and whether its full stop only marked it short (a title's is not a
        // sentence's end; a street's may be).
        let said = if !alone {
            None
        } else if word.eq_ignore_ascii_case("vs") || (word == "v" && dotted && named_next) {
            Some(("versus", dotted))
        } else if after_name
            && (dotted || !following.starts_with(|c: char| c.is_alphanumeric()))
            && let Some((_, street)) = STREETS.iter().find(|(t, _)| *t == word)
        {
            Some((*street, false))
        } else if named_next && let Some((_, title)) = TITLES.iter().find(|(t, _)| *t == word) {
            Some((*title, dotted))
        } else if numbered_next && dotted && word == "No" {
            Some(("number", true))
        } else if numbered_next && let Some((_, month)) = MONTHS.iter().find(|(m, _)| *m == word) {
            Some((*month, dotted))
        } else {
            None
        };
        match said {
            Some((said, short)) => {
                out.push_str(said);
                rest = if short { &after[1..] } else { after };
            }
            None => {
                out.push_str(word);
                rest = after;
            }
        }
        after_name = word.starts_with(|c: char| c.is_ascii_digit())
            || (!sentence_starts && word.starts_with(|c: char| c.is_uppercase()));
        sentence_starts = false;
    }
    out.push_str(rest);
    out
}

/// Marks typed for an apostrophe: the word processor's (’, and ‘ where it turned the wrong
/// way), Unicode's modifier letter (ʼ, Ukrainian's), a prime (′), and the accents keyboards
/// without an apostrophe key offer (´, `).
const APOSTROPHES: [char; 6] = [
    '\u{2019}', '\u{2018}', '\u{02BC}', '\u{2032}', '\u{00B4}', '`',
];

/// Characters kept as typed, although Unicode has a plainer form for them: eSpeak NG says
/// them as words that the plain form loses (`1º` "primero" in Spanish, `1o` "uno o"; `µm`
/// "micrometre", `μm` "mu m"; `™` "trademark", `TM` "T M"; `½` "a half", `1⁄2` "one two").
fn kept_as_typed(c: char) -> bool {
    matches!(
        c,
        '\u{00AA}'
            | '\u{00BA}'
            | '\u{00B5}'
            | '\u{2122}'
            | '\u{00BC}'..='\u{00BE}'
            | '\u{2150}'..='\u{215F}'
            | '\u{2189}'
    )
        // Korean's letters written alone (`ㅋㅋ`): their compatibility form is the one eSpeak
        // NG reads.
        || ('\u{3130}'..='\u{318F}').contains(&c)
}

/// `text` as the dictionaries and eSpeak NG read it, the same words however they were typed:
/// - every apostrophe-like mark as `'` (`It’s` is one word, "it's", not "it" and the letter
///   "s"; `I’m` has no "M" to close the lips on);
/// - Unicode's compatibility forms as their plain letters (NFKC): full-width `１２３`, `ＯＫ`,
///   ligatures `ﬁ`, `ﬃ`, Arabic presentation forms, `ᵉʳ`, `Ⅻ`, `㎞` — but for punctuation
///   and spaces (a full-width `？`) and the few letters that eSpeak NG says better as typed
///   (`kept_as_typed`);
/// - letters and their accents composed (NFC): macOS and some editors write `é` as `e` and a
///   combining accent, and Korean syllables as their separate letters, which eSpeak NG reads
///   as other words (`mère` as "mer", `엄마` letter by letter).
#[must_use]
pub fn plain(text: &str) -> std::borrow::Cow<'_, str> {
    if text.is_ascii() && !text.contains('`') {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut decomposed = String::with_capacity(text.len());
    for c in text.chars() {
        let c = if APOSTROPHES.contains(&c) { '\'' } else { c };
        let folded = std::iter::once(c).nfkd();
        // Punctuation and spaces stay as typed: eSpeak NG pauses at a full-width `？` or `，`
        // in Chinese, Japanese and Korean, and reads on through (or says) an ASCII one there.
        if kept_as_typed(c)
            || folded
                .clone()
                .all(|f| f.is_ascii_punctuation() || f.is_whitespace())
        {
            decomposed.push(c);
        } else {
            decomposed.extend(folded);
        }
    }
    let plain: String = decomposed.nfc().collect();
    if plain == text {
        std::borrow::Cow::Borrowed(text)
    } else {
        std::borrow::Cow::Owned(plain)
    }
}

/// `text` with the full-width marks of a number written as ASCII ones, which [`plain`] keeps
/// as typed (they are punctuation): `：` `．` `，` between two digits (`10：30`, `3．14`,
/// `1，000`) and `％` after one (`50％`), as Chinese, Japanese and Korean input methods type
/// them.
#[must_use]
pub fn number_marks_folded(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains(['：', '．', '，', '％']) {
        return std::borrow::Cow::Borrowed(text);
    }
    let chars: Vec<char> = text.chars().collect();
    let digit = |k: Option<usize>| {
        k.and_then(|k| chars.get(k))
            .is_some_and(char::is_ascii_digit)
    };
    let folded = chars
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let (before, after) = (digit(k.checked_sub(1)), digit(Some(k + 1)));
            match c {
                '：' if before && after => ':',
                '．' if before && after => '.',
                '，' if before && after => ',',
                '％' if before => '%',
                c => c,
            }
        })
        .collect();
    std::borrow::Cow::Owned(folded)
}

/// An English transcript's symbols as their words, the way a speaker says them: `$5.50` is
/// "5 dollars 50", `$0.99` "99 cents", `1,000` "1000", `3.14` "3 point 1 4", `50%` "50
/// percent", `20°C` "20 degrees Celsius", `&` "and", `@` "at", `+` "plus", `=` "equals", `#3`
/// "number 3", the dots of `example.com` and `notes.pdf` "dot". The words left (numbers among
/// them) are said as the dictionary or eSpeak NG says them. Without it a symbol is no word:
/// "$5" loses its "dollars", and the speech of it is spread over its neighbours'.
#[must_use]
pub fn english_symbols(text: &str) -> String {
    rewritten(text, |chars, mut k, out| {
        let c = chars[k];
        if c.is_ascii_digit() {
            let start = k;
            k = amount_end(chars, k);
            let number: String = chars[start..k].iter().collect();
            let currency = start
                .checked_sub(1)
                .map(|p| chars[p])
                .filter(|&c| currency_word(c, false).is_some());
            say_number(&number, currency, out);
            let unit = matches!(chars.get(k), Some('%' | '°'));
            match chars.get(k) {
                Some('%') => {
                    out.push_str(" percent");
                    k += 1;
                }
                Some('°') => {
                    out.push_str(" degrees");
                    k += 1;
                    let scale = chars.get(k).and_then(|c| match c {
                        'C' => Some(" Celsius"),
                        'F' => Some(" Fahrenheit"),
                        _ => None,
                    });
                    if let Some(scale) = scale
                        && !chars.get(k + 1).is_some_and(|c| c.is_alphanumeric())
                    {
                        out.push_str(scale);
                        k += 1;
                    }
                }
                _ => {}
            }
            // `100%sure`: the unit's word apart from the next.
            if unit && chars.get(k).is_some_and(|c| c.is_alphanumeric()) {
                out.push(' ');
            }
            return k;
        }
        let next_is_digit = chars.get(k + 1).is_some_and(char::is_ascii_digit);
        let word = match c {
            // Said after its number.
            _ if currency_word(c, false).is_some() && next_is_digit => "",
            '&' => "and",
            '@' => "at",
            '+' => "plus",
            '=' => "equals",
            '#' if next_is_digit => "number",
            // A web address's or a file's dots (`example.com`, `notes.pdf`): between two
            // letters each side, lower case after it, so that `U.S.`, `e.g.` and a sentence
            // typed on without its space (`end.Then`) are not read so.
            '.' if k >= 2
                && chars[k - 2..k].iter().all(|c| c.is_alphabetic())
                && chars
                    .get(k + 1..k + 3)
                    .is_some_and(|n| n.iter().all(|c| c.is_lowercase())) =>
            {
                "dot"
            }
            _ => {
                out.push(c);
                return k + 1;
            }
        };
        // Apart from the words either side (`US$5`, `me@home`), without doubling a space.
        if out.chars().next_back().is_some_and(char::is_alphanumeric) {
            out.push(' ');
        }
        out.push_str(word);
        if !word.is_empty() && chars.get(k + 1).is_some_and(|n| n.is_alphanumeric()) {
            out.push(' ');
        }
        k + 1
    })
}

/// Words before a number that say it is a count, not a year (`about 1500 people`).
const COUNT_CUES: [&str; 10] = [
    "about",
    "almost",
    "approximately",
    "exactly",
    "nearly",
    "over",
    "roughly",
    "some",
    "than",
    "under",
];

/// The tens said in the plural, for decades (`the 60s`: "sixties"), from ten.
const DECADES: [&str; 9] = [
    "tens",
    "twenties",
    "thirties",
    "forties",
    "fifties",
    "sixties",
    "seventies",
    "eighties",
    "nineties",
];

/// `text` cut into pieces of at most about `most` words, each whole sentences where the
/// sentences allow (a sentence ends at `.`, `!`, `?` or `;` before a space, or with its line),
/// a longer sentence into equal runs of words: the pieces a long recording is aligned in, one
/// after the other. Every word is in one piece, in order; a text of `most` words or fewer is
/// one piece.
#[must_use]
pub fn pieces(text: &str, most: usize) -> Vec<String> {
    let most = most.max(1);
    let mut sentences: Vec<Vec<&str>> = Vec::new();
    for line in text.lines() {
        let mut sentence = Vec::new();
        for word in line.split_whitespace() {
            sentence.push(word);
            if word.ends_with(['.', '!', '?', ';']) {
                sentences.push(std::mem::take(&mut sentence));
            }
        }
        if !sentence.is_empty() {
            sentences.push(sentence);
        }
    }
    let mut pieces: Vec<Vec<&str>> = Vec::new();
    let mut piece: Vec<&str> = Vec::new();
    for sentence in sentences {
        if !piece.is_empty() && piece.len() + sentence.len() > most {
            pieces.push(std::mem::take(&mut piece));
        }
        if sentence.len() <= most {
            piece.extend(sentence);
            continue;
        }
        // A sentence longer than a piece: equal runs of its words.
        let (n, runs) = (sentence.len(), sentence.len().div_ceil(most));
        pieces.extend((0..runs).map(|r| sentence[r * n / runs..(r + 1) * n / runs].to_vec()));
    }
    if !piece.is_empty() {
        pieces.push(piece);
    }
    pieces.into_iter().map(|words| words.join(" ")).collect()
}

/// An English transcript's words as they are said: its numbers ([`english_numbers`]), symbols
/// ([`english_symbols`]), units ([`english_units`]) and abbreviations
/// ([`english_abbreviations`]), read in that order (a count's comma is read before the symbols
/// drop it; a unit follows the number the symbols made of an amount).
#[must_use]
pub fn english_said(text: &str) -> String {
    english_abbreviations(&english_units(&english_symbols(&english_numbers(text))))
}

/// An English transcript's years, decades, ranges and telephone numbers as speakers say them:
/// - a year in two pairs (`1985` "19 85", `1905` "19 oh 5", `1900` "19 hundred", `2024` "20
///   24") and a decade by its tens (`the 1960s` "19 sixties", `'80s` and `80s` "eighties",
///   `the 1800s` "18 hundreds", `the 2000s` "2 thousands");
/// - a range with "to" (`9-5` "9 to 5", `1939–1945` "19 39 to 19 45");
/// - a telephone number digit by digit, `0` as "oh" (`555-0199` "5 5 5 oh 1 9 9",
///   `1-800-555-0199` "1 8 hundred 5 5 5 …", `(555) 123-4567`, `555.123.4567`);
/// - a time on the hour as "o'clock" (`7:00` "7 o'clock", `7:00 pm` "7 pm") and minutes under
///   ten with "oh" (`7:05` "7 oh 5"), where eSpeak NG says "zero".
///
/// The dictionary lacks numbers, and eSpeak NG counts them ("one thousand nine hundred and
/// eighty five", "five hundred fifty five"), says `1960s` as "… sixty" and the letter "s",
/// and leaves the `-` of a range unsaid: six lines with years and decades in digits lost
/// 0.07–0.18 agreement on flite's slt, awb and rms against the same lines spelled out, six
/// with ranges and telephone numbers 0.07–0.1, most of them aligned whole by synthesis.
///
/// A year is a number of four digits from 1100 to 1999 or from 2010 to 2099, standing alone:
/// a count written with its comma (`1,985`), an amount (`$1985`), a part of another number
/// (`1985.5`, `10:1985`) or a number after a word that says it counts (`about 1985 people`)
/// is left as it is. Runs before [`english_symbols`], which drops the comma of a count: see
/// [`english_said`].
#[must_use]
pub fn english_numbers(text: &str) -> String {
    numbers_rewritten(text, |chars, k, out| {
        if let Some((end, words)) = telephone(chars, k)
            .or_else(|| range(chars, k))
            .or_else(|| clock(chars, k))
        {
            out.push_str(&words);
            return end;
        }
        let end = digits_end(chars, k);
        let digits: String = chars[k..end].iter().collect();
        // A decade's plural: `60s`, `1960s`, `1960's`.
        let plural = match (chars.get(end), chars.get(end + 1)) {
            (Some('s'), _) => 1,
            (Some('\''), Some('s')) => 2,
            _ => 0,
        };
        let words = if plural > 0 && ends_number(chars, end + plural) {
            decade(&digits)
        } else if ends_number(chars, end) && !after_count_cue(&chars[..k]) {
            year(&digits)
        } else {
            None
        };
        match words {
            Some(words) => {
                // `'80s`: the apostrophe stood for the century.
                if plural > 0 && out.ends_with('\'') {
                    out.pop();
                }
                out.push_str(&words);
                end + plural
            }
            None => {
                out.push_str(&digits);
                end
            }
        }
    })
}

/// Whether a number of its own starts at `k`: a digit after no letter, digit or sign that
/// would make it part of another word, number or amount (`A4`, `1.5`, `$5`, `#3`). Chinese,
/// Japanese and Korean write a number against the word before it (`我有2本`, `친구5명`): their
/// letters do not make it part of a word.
fn starts_number(chars: &[char], k: usize) -> bool {
    chars[k].is_ascii_digit()
        && k.checked_sub(1).is_none_or(|p| {
            let before = chars[p];
            let joined = matches!(before,
                '\u{3040}'..='\u{30FF}' | '\u{3400}'..='\u{4DBF}' | '\u{4E00}'..='\u{9FFF}'
                    | '\u{AC00}'..='\u{D7AF}' | '\u{F900}'..='\u{FAFF}');
            !((before.is_alphanumeric() && !joined) || "$€£¥.,:/#+-_–".contains(before))
        })
}

/// `text` with each number of its own ([`starts_number`]) rewritten by `number`, given the
/// characters, where the number starts and the text written so far: it writes what it reads
/// there and says where to read on. Everything else is kept as it is.
pub(crate) fn numbers_rewritten(
    text: &str,
    mut number: impl FnMut(&[char], usize, &mut String) -> usize,
) -> String {
    rewritten(text, |chars, k, out| {
        if starts_number(chars, k) {
            number(chars, k, out)
        } else {
            out.push(chars[k]);
            k + 1
        }
    })
}

/// `text` rewritten as it is read, character by character: `step` is given the characters,
/// where it stands and the text written so far; it writes what it reads there and says where
/// to read on (past where it stands).
fn rewritten(text: &str, mut step: impl FnMut(&[char], usize, &mut String) -> usize) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 16);
    let mut k = 0;
    while k < chars.len() {
        k = step(&chars, k, &mut out).max(k + 1);
    }
    out
}

/// Where the amount that starts at `k` ends: its digits, with a `,` or `.` between two of them
/// (`1,000`, `15.50`, `1.250,00`); `k` when no digit starts there.
pub(crate) fn amount_end(chars: &[char], k: usize) -> usize {
    let mut end = digits_end(chars, k);
    while end > k
        && chars.get(end).is_some_and(|c| matches!(c, ',' | '.'))
        && chars.get(end + 1).is_some_and(char::is_ascii_digit)
    {
        end = digits_end(chars, end + 1);
    }
    end
}

/// Whether `c` is a Han character (Chinese hanzi, Japanese kanji): the CJK unified ideographs
/// and their extensions, and the compatibility ideographs.
pub(crate) fn is_han(c: char) -> bool {
    matches!(c,
        '\u{3400}'..='\u{4DBF}' | '\u{4E00}'..='\u{9FFF}' | '\u{F900}'..='\u{FAFF}'
            | '\u{20000}'..='\u{2FA1F}')
}

/// The base of an eSpeak NG voice name, the language its readings follow: `pt` of `pt-br`,
/// `de` of `de+m3`, `es` of `es_419`.
pub(crate) fn base_language(language: &str) -> &str {
    language.split(['-', '+', '_']).next().unwrap_or_default()
}

/// How many characters `word` takes where it is written at `at` in `chars` (a counter after
/// a number, a word after another); `None` where it is not written there.
pub(crate) fn written_at(chars: &[char], at: usize, word: &str) -> Option<usize> {
    let mut end = at;
    for c in word.chars() {
        if chars.get(end) != Some(&c) {
            return None;
        }
        end += 1;
    }
    Some(end - at)
}

/// Where the digits that start at `k` end.
pub(crate) fn digits_end(chars: &[char], k: usize) -> usize {
    let mut end = k;
    while chars.get(end).is_some_and(char::is_ascii_digit) {
        end += 1;
    }
    end
}

/// Whether a number ends at `at`: no letter or digit follows, nor a sign that makes it part of
/// another number or a measure (`%`, `°`; `.5`, `,000`, `:30`, `/2`, `-3`).
pub(crate) fn ends_number(chars: &[char], at: usize) -> bool {
    chars.get(at).is_none_or(|&after| {
        !(after.is_alphanumeric()
            || "%‰°".contains(after)
            || (".,:/-–".contains(after) && chars.get(at + 1).is_some_and(char::is_ascii_digit)))
    })
}

/// The groups of digits from `k` joined by one separator among `separators` (the same each
/// time), with where they end.
fn digit_groups(chars: &[char], k: usize, separators: &str) -> (Vec<String>, usize) {
    let mut groups = Vec::new();
    let (mut at, mut separator) = (k, None);
    loop {
        let end = digits_end(chars, at);
        groups.push(chars[at..end].iter().collect());
        let next = chars.get(end).copied();
        let joins = next
            .is_some_and(|c| separators.contains(c) && separator.is_none_or(|s| s == c))
            && chars.get(end + 1).is_some_and(char::is_ascii_digit);
        if !joins {
            return (groups, end);
        }
        separator = next;
        at = end + 1;
    }
}

/// A telephone number at `k` (`555-0199`, `555-123-4567`, `1-800-555-0199`, `555.123.4567`,
/// `(555) 123-4567`) as it is said, with where it ends.
fn telephone(chars: &[char], k: usize) -> Option<(usize, String)> {
    let (mut groups, mut end) = digit_groups(chars, k, "-.");
    // An area code in parentheses, then a space.
    if groups.len() == 1
        && groups[0].len() == 3
        && k.checked_sub(1).is_some_and(|p| chars[p] == '(')
        && chars.get(end) == Some(&')')
        && chars.get(end + 1) == Some(&' ')
        && chars.get(end + 2).is_some_and(char::is_ascii_digit)
    {
        let (rest, rest_end) = digit_groups(chars, end + 2, "-");
        groups.extend(rest);
        end = rest_end;
    }
    let lengths: Vec<usize> = groups.iter().map(String::len).collect();
    let telephone = matches!(lengths.as_slice(), [3, 4] | [3, 3, 4])
        || (lengths == [1, 3, 3, 4] && groups[0] == "1");
    if !telephone || !ends_number(chars, end) {
        return None;
    }
    let mut said = Vec::new();
    for (n, group) in groups.iter().enumerate() {
        // A toll-free or area code of hundreds: "8 hundred".
        if n + 1 < groups.len() && group.len() == 3 && group.ends_with("00") {
            said.push(format!("{} hundred", &group[..1]));
            continue;
        }
        said.extend(group.chars().map(|d| match d {
            '0' => "oh".to_owned(),
            d => d.to_string(),
        }));
    }
    Some((end, said.join(" ")))
}

/// A time at `k` (`7:00`, `7:05`, `19:00`) where eSpeak NG would say its minutes' zeros, as it
/// is said, with where it ends.
fn clock(chars: &[char], k: usize) -> Option<(usize, String)> {
    let (groups, end) = digit_groups(chars, k, ":");
    let [hours, minutes] = groups.as_slice() else {
        return None;
    };
    let hour: u32 = hours.parse().ok()?;
    if hours.len() > 2 || hour > 24 || minutes.len() != 2 || !ends_number(chars, end) {
        return None;
    }
    let said = match minutes.as_bytes() {
        b"00" => {
            // "7 pm", not "7 o'clock pm".
            let rest: String = chars[end..]
                .iter()
                .skip_while(|c| c.is_whitespace())
                .take(4)
                .filter(|c| c.is_alphabetic())
                .collect::<String>()
                .to_lowercase();
            if ["am", "pm"].iter().any(|m| rest.starts_with(m)) {
                hours.clone()
            } else {
                format!("{hours} o'clock")
            }
        }
        [b'0', minute] => format!("{hours} oh {}", char::from(*minute)),
        _ => return None,
    };
    Some((end, said))
}

/// A range of two numbers at `k` (`9-5`, `5–12`, `1939-1945`), said with "to" (a year as a
/// year), with where it ends.
fn range(chars: &[char], k: usize) -> Option<(usize, String)> {
    let (groups, end) = digit_groups(chars, k, "-–");
    let [from, to] = groups.as_slice() else {
        return None;
    };
    // `1-800-FLOWERS` is no range.
    let joined_on = chars.get(end).is_some_and(|c| "-–".contains(*c));
    if from.len() > 4 || to.len() > 4 || joined_on || !ends_number(chars, end) {
        return None;
    }
    let said = |number: &String| year(number).unwrap_or_else(|| number.clone());
    Some((end, format!("{} to {}", said(from), said(to))))
}

/// Whether the word before a number (`before`, the text up to it) says that it counts.
fn after_count_cue(before: &[char]) -> bool {
    COUNT_CUES.contains(&word_before(before).as_str())
}

/// The word at the end of `before` (the text up to a number), past any space, in lower case.
pub(crate) fn word_before(before: &[char]) -> String {
    let word: String = before
        .iter()
        .rev()
        .skip_while(|c| c.is_whitespace())
        .take_while(|c| c.is_alphabetic())
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    word.to_lowercase()
}

/// A year's digits as said in two pairs (`english_numbers`), when `digits` is one.
fn year(digits: &str) -> Option<String> {
    let value: u32 = digits.parse().ok()?;
    if digits.len() != 4 || !((1100..=1999).contains(&value) || (2010..=2099).contains(&value)) {
        return None;
    }
    let (century, rest) = (value / 100, value % 100);
    Some(match rest {
        0 => format!("{century} hundred"),
        1..=9 => format!("{century} oh {rest}"),
        _ => format!("{century} {rest}"),
    })
}

/// A decade's digits (the `60` of `60s`, the `1960` of `1960s`) as said, when they are one.
fn decade(digits: &str) -> Option<String> {
    let value: u32 = digits.parse().ok()?;
    let tens = |t: u32| {
        DECADES
            .get(usize::try_from(t).ok()?.checked_sub(1)?)
            .copied()
    };
    match digits.len() {
        2 if value.is_multiple_of(10) => tens(value / 10).map(str::to_owned),
        4 if value.is_multiple_of(10) && (1100..=2090).contains(&value) => {
            let (century, rest) = (value / 100, value % 100);
            Some(match (rest, century) {
                (0, 20) => "2 thousands".to_owned(),
                (0, _) => format!("{century} hundreds"),
                _ => format!("{century} {}", tens(rest / 10)?),
            })
        }
        _ => None,
    }
}

/// Units written short after a number, and the word said for one of them (more than one:
/// `plural`).
const UNITS: [(&str, &str); 33] = [
    ("GB", "gigabyte"),
    ("GHz", "gigahertz"),
    ("Hz", "hertz"),
    ("KB", "kilobyte"),
    ("MB", "megabyte"),
    ("MHz", "megahertz"),
    ("TB", "terabyte"),
    ("cm", "centimeter"),
    ("ft", "foot"),
    ("g", "gram"),
    ("hr", "hour"),
    ("hrs", "hour"),
    ("kHz", "kilohertz"),
    ("kW", "kilowatt"),
    ("kWh", "kilowatt hour"),
    ("kg", "kilogram"),
    ("km", "kilometer"),
    ("km/h", "kilometer per hour"),
    ("kph", "kilometer per hour"),
    ("lb", "pound"),
    ("lbs", "pound"),
    ("mL", "milliliter"),
    ("mg", "milligram"),
    ("mi", "mile"),
    ("min", "minute"),
    ("mins", "minute"),
    ("ml", "milliliter"),
    ("mm", "millimeter"),
    ("mph", "mile per hour"),
    ("ms", "millisecond"),
    ("oz", "ounce"),
    ("sec", "second"),
    ("yd", "yard"),
];

/// `unit` (a word, or words with "per") said of more than one: `kilograms`, `feet`, `hertz`,
/// `miles per hour`.
fn plural(unit: &str) -> String {
    match unit.split_once(" per ") {
        Some((each, per)) => format!("{} per {per}", plural(each)),
        None if unit.ends_with("hertz") => unit.to_owned(),
        None if unit.ends_with("foot") => format!("{}feet", &unit[..unit.len() - 4]),
        None => format!("{unit}s"),
    }
}

/// An English transcript's units written short after a number as their words: `5 kg` "5
/// kilograms", `1 km` "1 kilometer", `100mph` "100 miles per hour", `2 point 5 GB` "… gigabytes".
/// Only after a number, and only units no word is written as (`in`, `m`, `s` are left to the
/// dictionary); the dictionary lacks the rest, and eSpeak NG spells them out ("K G").
#[must_use]
pub fn english_units(text: &str) -> String {
    let unit = |core: &str| UNITS.iter().find(|(short, ..)| *short == core);
    let mut out = String::with_capacity(text.len() + 16);
    // The number just said (its last word: `5`, or the `5` of `2 point 5`), and whether it was
    // one.
    let mut number: Option<bool> = None;
    let mut before_number = "";
    for piece in text.split_inclusive(char::is_whitespace) {
        let word = piece.trim_end();
        let core = word.trim_end_matches(|c: char| ".,;:!?)\"'".contains(c));
        let ending = &word[core.len()..];
        let digits = core.len() - core.trim_start_matches(|c: char| c.is_ascii_digit()).len();
        let one = |digits: &str, before: &str| digits == "1" && before != "point";
        let said = |word: &str, one: bool| if one { word.to_owned() } else { plural(word) };
        if digits > 0
            && digits < core.len()
            && let Some((_, word)) = unit(&core[digits..])
        {
            // Written together: `5kg`.
            out.push_str(&core[..digits]);
            out.push(' ');
            out.push_str(&said(word, one(&core[..digits], before_number)));
            out.push_str(&piece[core.len()..]);
            number = None;
        } else if let (Some(one), Some((_, word))) = (number, unit(core)) {
            out.push_str(&said(word, one));
            out.push_str(&piece[core.len()..]);
            number = None;
        } else {
            out.push_str(piece);
            number = (digits == core.len() && digits > 0 && ending.is_empty())
                .then(|| one(core, before_number));
        }
        before_number = core;
    }
    out
}

/// The word for the currency symbol `c` (`one`: of an amount of one), when it is one.
fn currency_word(c: char, one: bool) -> Option<&'static str> {
    Some(match (c, one) {
        ('$', false) => "dollars",
        ('$', true) => "dollar",
        ('€', false) => "euros",
        ('€', true) => "euro",
        ('£', false) => "pounds",
        ('£', true) => "pound",
        ('¥', _) => "yen",
        _ => return None,
    })
}

/// `number` (digits with `,` and `.` between them) as it is said, pushed onto `out`, with the
/// words of the `currency` symbol before it (`$`, `€`, `£`, `¥`) after its whole part.
fn say_number(number: &str, currency: Option<char>, out: &mut String) {
    let (whole, fraction) = match number.split_once('.') {
        Some((whole, fraction)) if !fraction.contains(['.', ',']) => (whole, Some(fraction)),
        // Two points (a version, a date): said part by part.
        Some(_) => (number, None),
        None => (number, None),
    };
    let cents = fraction
        .map(|f| f.trim_start_matches('0'))
        .filter(|c| !c.is_empty());
    // `$0.99`: "99 cents".
    if let (Some(minor), Some(cents)) = (currency.and_then(minor_unit), cents)
        && whole.trim_start_matches('0').is_empty()
    {
        out.push_str(cents);
        out.push(' ');
        out.push_str(minor);
        return;
    }
    let groups: Vec<&str> = whole.split(',').collect();
    let thousands = groups.len() > 1
        && (1..=3).contains(&groups[0].len())
        && groups[1..].iter().all(|g| g.len() == 3);
    if thousands {
        out.extend(groups);
    } else {
        out.push_str(&whole.replace([',', '.'], " "));
    }
    let one = whole.trim_start_matches('0') == "1";
    match (currency.and_then(|c| currency_word(c, one)), fraction) {
        (Some(word), _) => {
            out.push(' ');
            out.push_str(word);
            // Cents as a number: "5 dollars 50".
            if let Some(cents) = cents {
                out.push(' ');
                out.push_str(cents);
            }
        }
        (None, Some(fraction)) => {
            out.push_str(" point");
            for digit in fraction.chars() {
                out.push(' ');
                out.push(digit);
            }
        }
        (None, None) => {}
    }
}

/// The hundredth of the currency of symbol `c`, when it has one said so.
fn minor_unit(c: char) -> Option<&'static str> {
    match c {
        '$' | '€' => Some("cents"),
        '£' => Some("pence"),
        _ => None,
    }
}

/// `line` without its `<…>`, `[…]` and `{…}` spans, each pushed onto `left_out`; a bracket
/// that is never closed is kept (it is punctuation, and no word).
fn unbracketed(line: &str, left_out: &mut Vec<String>) -> String {
    let mut out = String::with_capacity(line.len());
    let mut rest = line;
    while let Some(open) = rest.find(['<', '[', '{']) {
        let close = match rest.as_bytes()[open] {
            b'<' => '>',
            b'[' => ']',
            _ => '}',
        };
        let Some(length) = rest[open..].find(close) else {
            break;
        };
        out.push_str(&rest[..open]);
        // A space where the span was, so that the words either side stay two.
        out.push(' ');
        let span = &rest[open..=open + length];
        left_out.push(span.chars().take(40).collect());
        rest = &rest[open + length + 1..];
    }
    out.push_str(rest);
    out
}

/// A pictograph: an emoji or a symbol drawn rather than read (Unicode's emoji blocks,
/// miscellaneous symbols, dingbats, arrows, geometric shapes, and the emoji among the
/// technical symbols). The music signs that name a note's pitch (`♭`, `♮`, `♯`: "C sharp")
/// are read, and kept; so are `©`, `®`, `™` and `°`, which are said as words.
fn pictograph(c: char) -> bool {
    matches!(
        c,
        '\u{1F000}'..='\u{1FAFF}'
            | '\u{2600}'..='\u{266C}'
            | '\u{2670}'..='\u{27BF}'
            | '\u{2B00}'..='\u{2BFF}'
            | '\u{2190}'..='\u{21FF}'
            | '\u{25A0}'..='\u{25FF}'
            | '\u{231A}'..='\u{231B}'
            | '\u{2328}'
            | '\u{23CF}'
            | '\u{23E9}'..='\u{23F3}'
            | '\u{23F8}'..='\u{23FA}'
            | '\u{3030}'
            | '\u{303D}'
    )
}

/// What only shapes how an emoji is drawn and is never itself seen: the text and emoji
/// presentation selectors, the keycap's enclosing square (`1️⃣` is a `1`), and the tags of a
/// subdivision's flag.
fn emoji_mark(c: char) -> bool {
    matches!(
        c,
        '\u{FE0E}' | '\u{FE0F}' | '\u{20E3}' | '\u{E0020}'..='\u{E007F}'
    )
}

/// `line` without its pictographs (`pictograph`): each run of them (with the joiners and marks
/// that build one emoji of several, `👨‍👩‍👧`, `👍🏽`) becomes a space and is pushed onto
/// `left_out`; the marks alone go unsaid. A zero-width joiner between letters is kept: Indic
/// scripts write with it.
fn unpictured<'a>(line: &'a str, left_out: &mut Vec<String>) -> std::borrow::Cow<'a, str> {
    if line.is_ascii() {
        return std::borrow::Cow::Borrowed(line);
    }
    let chars: Vec<char> = line.chars().collect();
    let part_of_emoji = |k: usize| {
        let c = chars[k];
        pictograph(c)
            || emoji_mark(c)
            || (c == '\u{200D}'
                && (k
                    .checked_sub(1)
                    .is_some_and(|p| pictograph(chars[p]) || emoji_mark(chars[p]))
                    || chars.get(k + 1).copied().is_some_and(pictograph)))
    };
    if !(0..chars.len()).any(part_of_emoji) {
        return std::borrow::Cow::Borrowed(line);
    }
    let mut out = String::with_capacity(line.len());
    let mut k = 0;
    while k < chars.len() {
        if !part_of_emoji(k) {
            out.push(chars[k]);
            k += 1;
            continue;
        }
        let start = k;
        while k < chars.len() && part_of_emoji(k) {
            k += 1;
        }
        let run = &chars[start..k];
        if run.iter().copied().any(pictograph) {
            // A space where the run was, so that the words either side stay two.
            out.push(' ');
            left_out.push(run.iter().take(12).collect());
        }
    }
    std::borrow::Cow::Owned(out)
}

/// `line` without a speaker's name in capitals and its colon at its start (`NARRATOR:`,
/// `DR. JONES:`), pushed onto `left_out`; three letters at least, so that a line that starts
/// `OK:` keeps it.
fn unnamed<'a>(line: &'a str, left_out: &mut Vec<String>) -> &'a str {
    let start = line.len() - line.trim_start().len();
    let Some(colon) = line[start..].find(':') else {
        return line;
    };
    let name = &line[start..start + colon];
    let letters = name.chars().filter(|c| c.is_alphabetic()).count();
    let named = letters >= 3
        && name.chars().count() <= LONGEST_NAME
        && name.chars().all(|c| {
            c.is_uppercase() || c.is_ascii_digit() || c.is_whitespace() || ".'-_".contains(c)
        });
    if !named {
        return line;
    }
    left_out.push(format!("{name}:"));
    &line[start + colon + 1..]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_read_the_same_however_it_was_typed() {
        let same = |typed: &str, meant: &str| assert_eq!(plain(typed), meant, "{typed:?}");
        // A word processor's apostrophes, Ukrainian's modifier letter, keyboards' accents.
        same("It\u{2019}s easy, I\u{2019}m sure", "It's easy, I'm sure");
        same("\u{2018}Hello,\u{2019} she said", "'Hello,' she said");
        same(
            "\u{043c}\u{02bc}\u{044f}\u{0441}\u{043e}",
            "\u{043c}'\u{044f}\u{0441}\u{043e}",
        );
        same("don\u{00b4}t won`t", "don't won't");
        // Decomposed accents and Korean letters, as macOS writes them.
        same("me\u{0300}re M\u{00fc}ller", "m\u{00e8}re M\u{00fc}ller");
        same("mu\u{0308}de", "m\u{00fc}de");
        same(
            "\u{110b}\u{1165}\u{11b7}\u{1106}\u{1161}",
            "\u{c5c4}\u{b9c8}",
        );
        // Compatibility forms: full width, ligatures, letters as units.
        same(
            "\u{ff11}\u{ff12}\u{ff13}\u{5186}\u{ff0c}\u{ff2f}\u{ff2b}",
            "123\u{5186}\u{ff0c}OK",
        );
        same(
            "\u{fb01}fty \u{fb03}ce \u{2162} 5\u{338f}",
            "fifty ffice III 5kg",
        );
        same("le 1\u{1d49}\u{02b3} mai", "le 1er mai");
        // What eSpeak NG says better as typed stays: ordinals, micro, trademark, fractions,
        // Korean letters alone.
        for typed in [
            "el 1\u{00ba} de mayo, la 2\u{00aa} vez",
            "5 \u{00b5}m",
            "the \u{2122} sign",
            "\u{00bd} cup, \u{2153} left",
            "\u{314b}\u{314b}",
            "\u{4f60}\u{597d}\u{ff0c}\u{8c22}\u{8c22}\u{ff01}\u{3000}\u{2026}",
            "plain ASCII, untouched",
        ] {
            same(typed, typed);
            assert!(matches!(plain(typed), std::borrow::Cow::Borrowed(_)));
        }
        // And the transcript's words are read from it.
        assert_eq!(spoken("I\u{2019}m here.").text, "I'm here.");
    }

    /// The words a transcript says aloud.
    fn words(said: &Spoken) -> Vec<&str> {
        said.text.split_whitespace().collect()
    }

    #[test]
    fn subtitles_are_read_for_their_words() {
        let srt = "1\n00:00:00,100 --> 00:00:01,000\nHello there,\n\n2\n00:00:01,000 --> 00:00:03,000\n<i>how are you today?</i> I am fine.\n";
        let said = spoken(srt);
        assert_eq!(
            words(&said),
            [
                "Hello", "there,", "how", "are", "you", "today?", "I", "am", "fine."
            ]
        );
        assert_eq!(said.left_out, ["<i>", "</i>", "2 subtitle timecodes"]);
        let vtt = "WEBVTT - a talk\n\nNOTE written by hand,\nover two lines\n\nSTYLE\n::cue { color: red }\n\n00:01.000 --> 00:04.000 align:start\n<v Roger>Never drink liquid nitrogen.\n";
        let said = spoken(vtt);
        assert_eq!(said.text.trim(), "Never drink liquid nitrogen.");
        assert_eq!(said.left_out, ["<v Roger>", "a subtitle timecode"]);
    }

    #[test]
    fn substation_alpha_scripts_are_read_for_their_dialogue() {
        // As ffmpeg writes one from a SubRip file (`ffmpeg -i in.srt out.ass`).
        let ass = "[Script Info]\n; Script generated by FFmpeg/Lavc\nScriptType: v4.00+\nPlayResX: 384\n\n[V4+ Styles]\nFormat: Name, Fontname, Fontsize, PrimaryColour, SecondaryColour, OutlineColour, BackColour, Bold, Italic, Underline, StrikeOut, ScaleX, ScaleY, Spacing, Angle, BorderStyle, Outline, Shadow, Alignment, MarginL, MarginR, MarginV, Encoding\nStyle: Default,Arial,16,&Hffffff,&Hffffff,&H0,&H0,0,0,0,0,100,100,0,0,1,1,0,2,10,10,10,0\n\n[Events]\nFormat: Layer, Start, End, Style, Name, MarginL, MarginR, MarginV, Effect, Text\nDialogue: 0,0:00:00.50,0:00:02.00,Default,,0,0,0,,{\\i1}Hello{\\i0} there,\\Nmy friend.\nDialogue: 0,0:00:02.50,0:00:04.00,Default,,0,0,0,,{\\an8}How are you?\n";
        let said = spoken(ass);
        let expected = ["Hello", "there,", "my", "friend.", "How", "are", "you?"];
        assert_eq!(words(&said), expected);
        assert_eq!(said.cues.len(), 2);
        assert_eq!(said.cues[0].shown, 0.5..2.0);
        assert_eq!(said.cues[0].text, "Hello there,\nmy friend.");
        assert_eq!(said.cues[1].shown, 2.5..4.0);
        assert_eq!(said.left_out, ["the subtitle's override tags"]);
        // As Aegisub and fansubs write them: a speaker's name field, karaoke timing, a hard
        // space, a line drawn twice (border and fill), a sign placed on the picture, a vector
        // drawing, a comment, commas in the text, CRLF line ends, and a section after the
        // events.
        let ass = "[Script Info]\r\nTitle: Episode 1\r\n\r\n[Events]\r\nFormat: Layer, Start, End, Style, Name, MarginL, MarginR, MarginV, Effect, Text\r\nComment: 0,0:00:00.00,0:00:01.00,Default,,0,0,0,,Not said, a translator's note\r\nDialogue: 0,0:00:01.00,0:00:03.00,Default,Kenji,0,0,0,,Well, well,\\hwell.\r\nDialogue: 0,0:00:03.00,0:00:05.00,OP,,0,0,0,Karaoke,{\\k20}Ma{\\k30}ma {\\k25}mi{\\k40}a\r\nDialogue: 1,0:00:05.00,0:00:06.00,Default,,0,0,0,,{\\an8}Hello!\r\nDialogue: 0,0:00:05.00,0:00:06.00,Default,,0,0,0,,{\\an8\\bord3}Hello!\r\nDialogue: 0,0:00:04.00,0:00:06.00,Sign,,0,0,0,,{\\fad(200,0)\\pos(120,40)\\frz5}Bakery\r\nDialogue: 0,0:00:06.00,0:00:07.00,Default,,0,0,0,,{\\p1}m 0 0 l 100 0 100 100{\\p0}Bye now.\r\n\r\n[Aegisub Project Garbage]\r\nDialogue: not an event\r\n";
        let said = spoken(ass);
        assert_eq!(
            words(&said),
            [
                "Well,", "well,", "well.", "Mama", "mia", "Hello!", "Bye", "now."
            ]
        );
        assert_eq!(
            said.left_out,
            [
                "the subtitle's override tags",
                "a sign (on-screen text placed with \\pos or \\move)"
            ]
        );
        assert_eq!(
            said.cues
                .iter()
                .map(|c| c.shown.clone())
                .collect::<Vec<_>>(),
            [1.0..3.0, 3.0..5.0, 5.0..6.0, 6.0..7.0]
        );
        // SubStation Alpha v4 (`.ssa`): its first field is `Marked`; an event with a time it
        // cannot read is named, and the rest kept.
        let ssa = "[Script Info]\nScriptType: v4.00\n\n[Events]\nFormat: Marked, Start, End, Style, Name, MarginL, MarginR, MarginV, Effect, Text\nDialogue: Marked=0,0:00:01.00,0:00:02.00,Default,,0000,0000,0000,,Good morning.\nDialogue: Marked=0,soon,0:00:03.00,Default,,0000,0000,0000,,Later.\n";
        let said = spoken(ssa);
        assert_eq!(said.text, "Good morning.");
        assert_eq!(said.left_out, ["an event timed soon to 0:00:03.00"]);
        // Text that only mentions a section is no script.
        assert_eq!(
            spoken("Open [Events] and read.").text.trim(),
            "Open   and read."
        );
    }

    /// Asserts that `typed` says `words` aloud, and that its note lists what was left out.
    fn says(typed: &str, words: &[&str], note: &str) {
        let said = spoken(typed);
        assert_eq!(self::words(&said), words);
        assert_eq!(
            said.note().unwrap(),
            format!("left out of the transcript as not spoken: {note}")
        );
    }

    #[test]
    fn markup_directions_and_speakers_are_left_out_and_said() {
        says(
            "NARRATOR: [laughs] Hello there,<break time=\"500ms\"/>how are you?\n{\\an8}DR. JONES: Fine.",
            &["Hello", "there,", "how", "are", "you?", "Fine."],
            "[laughs], <break time=\"500ms\"/>, NARRATOR:, {\\an8}, DR. JONES:",
        );
    }

    #[test]
    fn emoji_and_pictographs_are_left_out_and_said() {
        says(
            "\u{266A} Happy birthday \u{266A}\nGreat job\u{1F44D}\u{1F3FD} I love it \u{2764}\u{FE0F}\u{1F602}\u{1F602}\nOur family \u{1F468}\u{200D}\u{1F469}\u{200D}\u{1F467} in \u{1F1EB}\u{1F1F7}, \u{2B50} five stars \u{2192} done",
            &[
                "Happy", "birthday", "Great", "job", "I", "love", "it", "Our", "family", "in", ",",
                "five", "stars", "done",
            ],
            "\u{266A}, \u{1F44D}\u{1F3FD}, \u{2764}\u{FE0F}\u{1F602}\u{1F602}, \u{1F468}\u{200D}\u{1F469}\u{200D}\u{1F467}, \u{1F1EB}\u{1F1F7}, \u{2B50}, 1 more",
        );
        // What is read stays: a note's sharp and flat, the signs said as words, a keycap's
        // digit, and the joiner Indic scripts write with (Malayalam's chillu).
        let kept =
            "C\u{266F} minor, B\u{266D}, \u{00A9} 2024, 20\u{00B0}, \u{0D28}\u{0D4D}\u{200D}";
        assert_eq!(spoken(kept).text, kept);
        assert!(spoken(kept).left_out.is_empty());
        assert_eq!(spoken("Press 1\u{FE0F}\u{20E3} now").text, "Press 1 now");
        assert!(spoken("Press 1\u{FE0F}\u{20E3} now").left_out.is_empty());
    }

    #[test]
    fn english_symbols_are_said_as_words() {
        for (text, said) in [
            ("It costs $5.50 today.", "It costs 5 dollars 50 today."),
            (
                "$1 or €1,000,000 or £20.00",
                "1 dollar or 1000000 euros or 20 pounds",
            ),
            (
                "¥300 & 50% off, US$5",
                "300 yen and 50 percent off, US 5 dollars",
            ),
            (
                "pi is 3.14, it's 20°C, 68°F or 5°Cs",
                "pi is 3 point 1 4, it's 20 degrees Celsius, 68 degrees Fahrenheit or 5 degrees Cs",
            ),
            ("3rd and 100%sure", "3rd and 100 percent sure"),
            ("1,2,3 and 10.0.1", "1 2 3 and 10 0 1"),
            (
                "mail me@home: 2+2=4, #1",
                "mail me at home: 2 plus 2 equals 4, number 1",
            ),
            ("Mama made my bed.", "Mama made my bed."),
            ("$ alone, a # and 100 $", "$ alone, a # and 100 $"),
            (
                "see shop.example.com, notes.pdf, me@mail.org.",
                "see shop dot example dot com, notes dot pdf, me at mail dot org.",
            ),
            (
                "the U.S. e.g. Ph.D a.m. end.Then",
                "the U.S. e.g. Ph.D a.m. end.Then",
            ),
        ] {
            assert_eq!(english_symbols(text), said, "{text}");
        }
    }

    #[test]
    fn english_numbers_are_said_as_speakers_say_them() {
        let said =
            |typed: &str, meant: &str| assert_eq!(english_numbers(typed), meant, "{typed:?}");
        said(
            "Born in 1985, moved in 1999.",
            "Born in 19 85, moved in 19 99.",
        );
        said(
            "By 1905 the mill closed (1900).",
            "By 19 oh 5 the mill closed (19 hundred).",
        );
        said("In 2024 and 2010", "In 20 24 and 20 10");
        said("the 1960s, the 1960's", "the 19 sixties, the 19 sixties");
        said("the '80s and 90s", "the eighties and nineties");
        said(
            "the 1800s and the 2000s",
            "the 18 hundreds and the 2 thousands",
        );
        said("open 9-5, ages 5\u{2013}12", "open 9 to 5, ages 5 to 12");
        said("from 1939-1945.", "from 19 39 to 19 45.");
        said("Call 555-0199, or", "Call 5 5 5 oh 1 9 9, or");
        said("dial 1-800-555-2346!", "dial 1 8 hundred 5 5 5 2 3 4 6!");
        said("(555) 123-4567", "(5 5 5 1 2 3 4 5 6 7");
        said("555.123.4567", "5 5 5 1 2 3 4 5 6 7");
        said(
            "at 7:00, at 7:00 pm, 7:00 a.m.",
            "at 7 o'clock, at 7 pm, 7 a.m.",
        );
        said("at 19:05 or 3:45", "at 19 oh 5 or 3:45");
        // Left as they are: counts, amounts, parts of other numbers, other years and numbers.
        for kept in [
            "1,985 people",
            "$1985",
            "1985.5",
            "10:30",
            "2024-12-05",
            "3:1",
            "10:30:15",
            "1-800-FLOWERS",
            "-5",
            "COVID-19",
            "12345-6789",
            "about 1985 people",
            "over 1500",
            "in 2008",
            "in 1066",
            "12345",
            "the 1990th",
            "1985%",
            "R2D2 1985x",
            "the 85s",
            "00s",
        ] {
            said(kept, kept);
        }
    }

    #[test]
    fn english_units_are_said_as_words() {
        let said = |typed: &str, meant: &str| assert_eq!(english_units(typed), meant, "{typed:?}");
        said("Add 5 kg, then 1 km.", "Add 5 kilograms, then 1 kilometer.");
        said(
            "at 100mph for 2 point 5 GB",
            "at 100 miles per hour for 2 point 5 gigabytes",
        );
        said("1 point 5 lbs and 1 oz", "1 point 5 pounds and 1 ounce");
        said("10\nmin", "10\nminutes");
        for kept in [
            "5 in a row",
            "5 m",
            "kg alone",
            "5, mg",
            "5G phones",
            "ms Smith",
        ] {
            said(kept, kept);
        }
    }

    #[test]
    fn english_abbreviations_are_said_as_words() {
        for (text, said) in [
            (
                "Dr. Jones met St. Patrick on Main St.",
                "doctor Jones met saint Patrick on Main street.",
            ),
            (
                "Sgt Hale and Lt. Dan, vs. Capt. Price",
                "sergeant Hale and lieutenant Dan, versus captain Price",
            ),
            (
                "Lakers vs Bulls, 5th Ave. and Oak Dr",
                "Lakers versus Bulls, 5th avenue. and Oak drive",
            ),
            (
                "Meet at 10 Downing St, then leave.",
                "Meet at 10 Downing street, then leave.",
            ),
            // Where the capitals do not say which, the dictionary reads them.
            ("the dr. said st. is fine", "the dr. said st. is fine"),
            ("Dr. no capital", "Dr. no capital"),
            ("the St. of it", "the St. of it"),
            (
                "DrJones, Xdr. Smith, Gen3 Lee",
                "DrJones, Xdr. Smith, Gen3 Lee",
            ),
            ("", ""),
            // A street ends a sentence; a title may start one.
            (
                "We live on Main St. Then Dr. Banks came.",
                "We live on Main street. Then doctor Banks came.",
            ),
            (
                "Ask Dr. Banks to drive to Oak Dr.",
                "Ask doctor Banks to drive to Oak drive.",
            ),
            ("In Paris, Dr. Jones", "In Paris, doctor Jones"),
            (
                "On Jan. 5 and Oct 19 90, No. 1 fan",
                "On January 5 and October 19 90, number 1 fan",
            ),
            ("Say No. Then Jan said Dec.", "Say No. Then Jan said Dec."),
            (
                "Fruit, e.g. pears, etc. E.g. approx. 5, i.e. few.",
                "Fruit, for example pears, et cetera. for example approximately 5, that is few.",
            ),
            ("tree.g. bee.i.e. dept", "tree.g. bee.i.e. dept"),
        ] {
            assert_eq!(english_abbreviations(text), said, "{text}");
        }
    }

    #[test]
    fn plain_words_are_kept_as_they_are() {
        for text in [
            "Mama made my bed before breakfast.",
            "Note: the numbers 1 2 3 are said (all of them) — and 2 < 3.",
            "I: me, myself",
            "OK: let's go.",
            "妈妈骂马吗？",
            "42",
        ] {
            let said = spoken(text);
            assert_eq!(said.text, text);
            assert_eq!(said.note(), None, "{text}");
        }
        // More directions than a note lists are counted.
        let many = spoken("[a] [b] [c] [d] [e] [f] [g] [h] words");
        assert_eq!(many.left_out.last().unwrap(), "2 more");
        assert_eq!(many.text.trim(), "words");
    }

    proptest::proptest! {
        /// Whatever is typed, the English readings end (no panic, on any character boundary),
        /// and words without digits or signs pass through the number, symbol and unit readings
        /// as they are.
        #[test]
        fn any_text_is_read_without_a_panic(
            typed in "[0-9a-zA-Z .,:;'()\\-\u{2013}/$%°@&#+=!?\u{1F600}\u{2764}\u{FE0F}\u{200D}\u{266A}éü]{0,60}",
            words in "[a-zA-Z ]{0,40}",
        ) {
            let said = spoken(&typed);
            let _ = english_said(&said.text);
            proptest::prop_assert_eq!(english_units(&english_symbols(&english_numbers(&words))), words);
        }
    }

    #[test]
    fn a_long_text_is_cut_between_sentences() {
        let text = "One two three. Four five six seven!\nEight nine ten eleven twelve; thirteen";
        assert_eq!(
            pieces(text, 7),
            [
                "One two three. Four five six seven!",
                "Eight nine ten eleven twelve; thirteen"
            ]
        );
        assert_eq!(pieces(text, 100), [text.replace('\n', " ")]);
        // A sentence longer than a piece is cut into equal runs.
        let words: Vec<String> = (0..10).map(|k| format!("w{k}")).collect();
        let run_on = words.join(" ");
        assert_eq!(pieces(&run_on, 4), ["w0 w1 w2", "w3 w4 w5", "w6 w7 w8 w9"]);
        assert!(pieces("", 4).is_empty());
    }

    #[test]
    fn a_subtitles_cues_keep_their_times_and_spoken_words() {
        let srt = "1\n00:00:01,250 --> 00:00:03,000\n<i>Hello</i> there.\n\n\
                   2\n00:00:05,000 --> 00:00:06,000\n[music]\n\n\
                   3\n00:00:07,000 --> 00:00:09,500\nNARRATOR: Two lines\nof words.\n\n\
                   4\n00:00:09,000 --> 00:00:10,000\n- Over it!\n";
        let cues = spoken(srt).cues;
        let said: Vec<(f32, f32, String)> = cues
            .iter()
            .map(|c| {
                (
                    c.shown.start,
                    c.shown.end,
                    c.text.split_whitespace().collect::<Vec<_>>().join(" "),
                )
            })
            .collect();
        // The music's cue says nothing; the last two overlap and are one.
        assert_eq!(
            said,
            [
                (1.25, 3.0, "Hello there.".to_owned()),
                (7.0, 10.0, "Two lines of words. - Over it!".to_owned())
            ]
        );
        let vtt = "WEBVTT\n\nintro\n01:02.500 --> 01:04.000 align:start position:10%\nHola.\n";
        assert_eq!(spoken(vtt).text.trim(), "Hola.");
        let cues = spoken(vtt).cues;
        assert_eq!(cues.len(), 1);
        assert!((cues[0].shown.start - 62.5).abs() < 1e-4);
        assert!((cues[0].shown.end - 64.0).abs() < 1e-4);
        // A line with an arrow but no times, and a cue that ends before it starts, are no cues.
        assert!(spoken("a --> b").cues.is_empty());
        assert!(spoken("00:00:03,000 --> 00:00:01,000\nNo.").cues.is_empty());
        assert!(spoken("Just words.").cues.is_empty());
        // Where a word is in no cue, or a cue's time cannot be read, none is used: the words
        // are aligned together, none left out.
        assert!(
            spoken("Before.\n\n00:00:01,000 --> 00:00:02,000\nIn.")
                .cues
                .is_empty()
        );
        assert!(
            spoken("00:00:01,000 --> 00:00:02,000\nIn.\n\n00:0x:03,000 --> 00:00:04,000\nOut.")
                .cues
                .is_empty()
        );
    }
}
