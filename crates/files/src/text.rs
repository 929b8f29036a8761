//! Text files as people save them.
//!
//! A transcript, a subtitle or a batch manifest is UTF-8 when a current editor saves it, but
//! not always: Windows' Notepad saves "Unicode" as UTF-16 with a byte-order mark (and older
//! Notepad puts one before UTF-8), Excel saves "Unicode text" as UTF-16 and "CSV" in the
//! system's code page, and subtitles fetched from subtitle sites or written by older tools
//! are in the code page of their language — Shift_JIS for Japanese, GBK or Big5 for Chinese,
//! EUC-KR for Korean, windows-1251 for Russian, windows-1252 for French or German. Such a file
//! was refused as "not UTF-8".
//!
//! [`decode`] reads, in this order:
//! 1. a byte-order mark: UTF-8, UTF-16LE or UTF-16BE, the mark dropped;
//! 2. UTF-16 without a mark, when the bytes show it (a NUL beside each ASCII letter, which no
//!    text in UTF-8 or a code page has);
//! 3. UTF-8 — every other file that is valid UTF-8 is read as UTF-8, so no text that read
//!    before reads otherwise;
//! 4. where the format allows ([`Accept::Legacy`]), a legacy code page, guessed from the bytes
//!    by `chardetng` (Firefox's detector for legacy web pages) and told the language the text is
//!    in, which is what tells a short line of Japanese kana in Shift_JIS from Russian in
//!    windows-1251 ([`region_of`]). The file must decode without a malformed byte in the
//!    encoding guessed, and to no control character (a picture or a program is no text);
//!    [`Text::guessed`] says that it was guessed, for a note to the user.
//!
//! ```
//! use faceanim_files::text::{Accept, decode};
//! // "こんにちは" as a Japanese Windows program saves it (Shift_JIS).
//! let bytes = b"\x82\xb1\x82\xf1\x82\xc9\x82\xbf\x82\xcd";
//! let text = decode(bytes, Accept::Legacy { language: Some("ja") }).unwrap();
//! assert_eq!(text.text, "こんにちは");
//! assert_eq!(text.encoding, "Shift_JIS");
//! assert!(text.guessed);
//! // JSON is Unicode by its specification: the same bytes are refused.
//! assert!(decode(bytes, Accept::Unicode).is_err());
//! ```

use encoding_rs::{Encoding, UTF_8, UTF_16BE, UTF_16LE};

/// The encodings a file may be read in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Accept<'a> {
    /// Unicode only (UTF-8, UTF-16): formats whose specification says so, as JSON's does.
    Unicode,
    /// Unicode, or a legacy code page guessed from the bytes: plain text, subtitles, CSV.
    Legacy {
        /// The language the text is in, when known: a BCP 47 tag (`ja-JP`, `zh-Hant`), a
        /// POSIX locale (`ru_RU.CP1251`) or eSpeak NG's name (`cmn-latn-pinyin`, `en-us+f3`).
        language: Option<&'a str>,
    },
}

/// A file's text and the encoding it was read in.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Text {
    /// The text, without a byte-order mark.
    pub text: String,
    /// The encoding's name as the WHATWG Encoding Standard writes it (`UTF-8`, `UTF-16LE`,
    /// `Shift_JIS`, `windows-1252`).
    pub encoding: &'static str,
    /// The encoding was guessed from the bytes (a legacy code page), not stated by a
    /// byte-order mark or implied by valid UTF-8: worth a note, since a guess can be wrong.
    pub guessed: bool,
}

impl Text {
    /// What to tell the user of `what` (the file as they know it) when its encoding was
    /// guessed ([`guessed_note`]; `also` names what besides its bytes chose it, such as the
    /// language given), `None` when it was Unicode.
    #[must_use]
    pub fn note(&self, what: &str, also: Option<&str>) -> Option<String> {
        self.guessed
            .then(|| guessed_note(what, self.encoding, also, "UTF-8"))
    }
}

/// The one wording of a file read in a guessed code page: `what` (the file as the user knows
/// it) is not Unicode, it was read as `encoding`, which its bytes (and `also`: the language
/// given) suggest — and what to do when the guess is wrong: save it as `unicode` (UTF-8, or
/// the name a program gives it, such as Excel's "CSV UTF-8").
///
/// ```
/// let note = faceanim_files::text::guessed_note("a.srt", "Shift_JIS", Some("--language ja"), "UTF-8");
/// assert_eq!(
///     note,
///     "a.srt is not Unicode: it was read as Shift_JIS, the encoding its bytes and --language ja \
///      suggest (save it as UTF-8 if its text comes out wrong)"
/// );
/// ```
#[must_use]
pub fn guessed_note(what: &str, encoding: &str, also: Option<&str>, unicode: &str) -> String {
    let also = also.map_or_else(String::new, |a| format!(" and {a}"));
    format!(
        "{what} is not Unicode: it was read as {encoding}, the encoding its bytes{also} suggest \
         (save it as {unicode} if its text comes out wrong)"
    )
}

/// Why bytes are not text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TextError {
    /// Not UTF-8 nor UTF-16, where only Unicode is accepted.
    #[error("not UTF-8 text (byte {byte} is not)")]
    NotUnicode {
        /// The offset of the first byte that is not UTF-8.
        byte: usize,
    },
    /// Not UTF-8, and not the legacy encoding the bytes looked most like either.
    #[error(
        "not UTF-8 text (byte {byte} is not), nor {guess} (the encoding it looks most like): \
         save it as UTF-8"
    )]
    Undecodable {
        /// The offset of the first byte that is not UTF-8.
        byte: usize,
        /// The legacy encoding tried.
        guess: &'static str,
    },
    /// A UTF-16 file with a character cut in two (its last byte missing, or half of a pair
    /// of surrogates).
    #[error("malformed {encoding} text (a character cut in two)")]
    Malformed {
        /// The encoding named by the byte-order mark or seen in the bytes.
        encoding: &'static str,
    },
}

/// `bytes` as text, in the encodings `accept` allows (see the module's documentation).
///
/// # Errors
/// [`TextError`] when the bytes are none of them.
pub fn decode(bytes: &[u8], accept: Accept<'_>) -> Result<Text, TextError> {
    if let Some((encoding, mark)) = Encoding::for_bom(bytes) {
        if encoding == UTF_8 {
            return utf8(&bytes[mark..])
                .map_err(|byte| TextError::NotUnicode { byte: byte + mark });
        }
        return strict(&bytes[mark..], encoding, false).ok_or(TextError::Malformed {
            encoding: encoding.name(),
        });
    }
    // UTF-16's NULs are valid UTF-8, but no text means them.
    if let Some(encoding) = utf16_unmarked(bytes) {
        return strict(bytes, encoding, false).ok_or(TextError::Malformed {
            encoding: encoding.name(),
        });
    }
    let not_utf8 = match utf8(bytes) {
        Ok(text) => return Ok(text),
        Err(byte) => byte,
    };
    let Accept::Legacy { language } = accept else {
        return Err(TextError::NotUnicode { byte: not_utf8 });
    };
    let mut detector = chardetng::EncodingDetector::new(chardetng::Iso2022JpDetection::Deny);
    detector.feed(bytes, true);
    let region = language.and_then(region_of);
    let guess = detector.guess(region.map(str::as_bytes), chardetng::Utf8Detection::Deny);
    // A code page decodes almost any bytes: what holds control characters is no text (a
    // picture, an archive, a program given by mistake).
    strict(bytes, guess, true)
        .filter(|text| !text.text.chars().any(is_binary))
        .ok_or(TextError::Undecodable {
            byte: not_utf8,
            guess: guess.name(),
        })
}

/// A control character no text file holds: C0 but tab, line feed, form feed and carriage
/// return; delete; C1 (which windows-1252 gives its five unassigned bytes).
fn is_binary(c: char) -> bool {
    c.is_control() && !matches!(c, '\t' | '\n' | '\x0c' | '\r')
}

/// `bytes` as UTF-8, or the offset of the first byte that is not.
fn utf8(bytes: &[u8]) -> Result<Text, usize> {
    let text = std::str::from_utf8(bytes).map_err(|e| e.valid_up_to())?;
    Ok(Text {
        text: text.to_owned(),
        encoding: UTF_8.name(),
        guessed: false,
    })
}

/// `bytes` decoded by `encoding`, `None` where a sequence is malformed in it (none replaced).
fn strict(bytes: &[u8], encoding: &'static Encoding, guessed: bool) -> Option<Text> {
    let text = encoding.decode_without_bom_handling_and_without_replacement(bytes)?;
    Some(Text {
        text: text.into_owned(),
        encoding: encoding.name(),
        guessed,
    })
}

/// UTF-16 without a byte-order mark, little- or big-endian, when the bytes show it: an even
/// length, and a NUL in at least a third of the characters' high bytes while none of their low
/// bytes is one (text in a Latin script has a NUL beside every letter; no text in a
/// single-byte or multi-byte code page has NULs).
fn utf16_unmarked(bytes: &[u8]) -> Option<&'static Encoding> {
    if bytes.len() < 4 || !bytes.len().is_multiple_of(2) {
        return None;
    }
    let pairs = bytes.len() / 2;
    let nul_at = |offset: usize| {
        bytes
            .iter()
            .skip(offset)
            .step_by(2)
            .filter(|b| **b == 0)
            .count()
    };
    let (even, odd) = (nul_at(0), nul_at(1));
    if even == 0 && odd * 3 >= pairs {
        Some(UTF_16LE)
    } else if odd == 0 && even * 3 >= pairs {
        Some(UTF_16BE)
    } else {
        None
    }
}

/// The country code top-level domain whose legacy code page text in `language` was most
/// likely saved in, as `chardetng` takes it for a hint (`ja` → `jp`: Shift_JIS or EUC-JP;
/// `zh-Hant` → `tw`: Big5; `sr-Latn` → `hr`: windows-1250); `None` for a language it gives no
/// hint on (English, whose legacy text is windows-1252 anyway) or one this does not know.
///
/// ```
/// use faceanim_files::text::region_of;
/// assert_eq!(region_of("ja-JP"), Some("jp"));
/// assert_eq!(region_of("zh_TW.Big5"), Some("tw"));
/// assert_eq!(region_of("cmn-latn-pinyin"), Some("cn"));
/// assert_eq!(region_of("ru+f3"), Some("ru"));
/// assert_eq!(region_of("en-us"), None);
/// ```
#[must_use]
pub fn region_of(language: &str) -> Option<&'static str> {
    let tag = language
        .split(['+', '.', '@'])
        .next()
        .unwrap_or_default()
        .to_ascii_lowercase();
    let mut subtags = tag.split(['-', '_']);
    let base = subtags.next().unwrap_or_default();
    let rest: Vec<&str> = subtags.collect();
    let has = |s: &str| rest.contains(&s);
    match base {
        "zh" | "cmn" if has("hant") || has("tw") || has("hk") || has("mo") => Some("tw"),
        "zh" | "cmn" => Some("cn"),
        // Cantonese is written in traditional characters (Hong Kong's Big5).
        "yue" => Some("tw"),
        "sr" | "bs" if has("latn") => Some("hr"),
        _ => REGIONS
            .iter()
            .find(|(language, _)| *language == base)
            .map(|(_, region)| *region),
    }
}

/// Languages (ISO 639-1, or 639-3 where eSpeak NG uses it) and the country whose legacy code
/// page their text is in.
const REGIONS: [(&str, &str); 44] = [
    ("ja", "jp"),
    ("ko", "kr"),
    ("th", "th"),
    ("vi", "vn"),
    ("ru", "ru"),
    ("uk", "ua"),
    ("be", "by"),
    ("bg", "bg"),
    ("mk", "mk"),
    ("sr", "rs"),
    ("kk", "kz"),
    ("ky", "kg"),
    ("tt", "ru"),
    ("ba", "ru"),
    ("el", "gr"),
    ("tr", "tr"),
    ("az", "az"),
    ("he", "il"),
    ("ar", "sa"),
    ("fa", "ir"),
    ("ur", "pk"),
    ("lt", "lt"),
    ("lv", "lv"),
    ("et", "ee"),
    ("pl", "pl"),
    ("cs", "cz"),
    ("sk", "sk"),
    ("hu", "hu"),
    ("hr", "hr"),
    ("sl", "si"),
    ("ro", "ro"),
    ("bs", "ba"),
    ("sq", "al"),
    ("is", "is"),
    ("fo", "fo"),
    ("de", "de"),
    ("fr", "fr"),
    ("es", "es"),
    ("it", "it"),
    ("pt", "pt"),
    ("nl", "nl"),
    ("sv", "se"),
    ("da", "dk"),
    ("fi", "fi"),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn legacy(bytes: &[u8], language: &str) -> Text {
        decode(
            bytes,
            Accept::Legacy {
                language: Some(language),
            },
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    // The bytes below were written by GNU iconv (`printf '%s' TEXT | iconv -t ENCODING`), not
    // by the library that reads them.

    #[test]
    fn legacy_code_pages_are_read_with_the_language_as_a_hint() {
        // まいにち、ももをたべます。 in Shift_JIS: kana alone, which without the hint read as
        // windows-1251.
        let kana = b"\x82\xdc\x82\xa2\x82\xc9\x82\xbf\x81\x41\x82\xe0\x82\xe0\x82\xf0\x82\xbd\x82\xd7\x82\xdc\x82\xb7\x81\x42";
        assert_eq!(legacy(kana, "ja").text, "まいにち、ももをたべます。");
        // 妈妈每天买面包。 in GBK, which without the hint read as EUC-JP.
        let gbk = b"\xc2\xe8\xc2\xe8\xc3\xbf\xcc\xec\xc2\xf2\xc3\xe6\xb0\xfc\xa1\xa3";
        let text = legacy(gbk, "zh");
        assert_eq!(text.text, "妈妈每天买面包。");
        assert_eq!(text.encoding, "GBK");
        // 엄마는 매일 밥을 먹어요. in CP949.
        let korean =
            b"\xbe\xf6\xb8\xb6\xb4\xc2 \xb8\xc5\xc0\xcf \xb9\xe4\xc0\xbb \xb8\xd4\xbe\xee\xbf\xe4.";
        assert_eq!(legacy(korean, "ko-KR").text, "엄마는 매일 밥을 먹어요.");
        // Мама мыла раму. in windows-1251.
        let russian = b"\xcc\xe0\xec\xe0 \xec\xfb\xeb\xe0 \xf0\xe0\xec\xf3.";
        assert_eq!(legacy(russian, "ru").text, "Мама мыла раму.");
        // Grüße aus München. in windows-1252.
        let german = b"Gr\xfc\xdfe aus M\xfcnchen.";
        let text = legacy(german, "de");
        assert_eq!(text.text, "Grüße aus München.");
        assert!(text.guessed);
    }

    #[test]
    fn byte_order_marks_say_the_encoding_and_are_dropped() {
        // Notepad's "Unicode": UTF-16LE with its mark.
        let utf16 = b"\xff\xfeH\x00i\x00 \x00\xe9\x00";
        for accept in [Accept::Unicode, Accept::Legacy { language: None }] {
            let text = decode(utf16, accept).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(text.text, "Hi é");
            assert_eq!(text.encoding, "UTF-16LE");
            assert!(!text.guessed);
        }
        let big = b"\xfe\xff\x00H\x00i";
        assert_eq!(
            decode(big, Accept::Unicode).map(|t| t.text),
            Ok("Hi".to_owned())
        );
        let utf8 = b"\xef\xbb\xbfHi";
        assert_eq!(
            decode(utf8, Accept::Unicode).map(|t| t.text),
            Ok("Hi".to_owned())
        );
        // Cut in the middle of a character.
        assert_eq!(
            decode(b"\xff\xfeH\x00i", Accept::Unicode),
            Err(TextError::Malformed {
                encoding: "UTF-16LE"
            })
        );
    }

    #[test]
    fn utf16_without_a_mark_is_seen_in_its_nuls() {
        let le = b"H\x00e\x00l\x00l\x00o\x00";
        assert_eq!(
            decode(le, Accept::Unicode).map(|t| t.encoding),
            Ok("UTF-16LE")
        );
        let be = b"\x00H\x00e\x00l\x00l\x00o";
        assert_eq!(
            decode(be, Accept::Unicode).map(|t| t.text),
            Ok("Hello".to_owned())
        );
    }

    #[test]
    fn valid_utf8_is_always_utf8_and_unicode_only_refuses_the_rest() {
        // Valid UTF-8 that a legacy detector might call something else.
        let text = legacy("Ma mère".as_bytes(), "fr");
        assert_eq!((text.encoding, text.guessed), ("UTF-8", false));
        assert_eq!(
            decode(b"caf\xe9", Accept::Unicode),
            Err(TextError::NotUnicode { byte: 3 })
        );
        // A picture given by mistake (a PNG's signature and header) is no text in any code page.
        let png = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR";
        assert!(matches!(
            decode(
                png,
                Accept::Legacy {
                    language: Some("de")
                }
            ),
            Err(TextError::Undecodable { byte: 0, .. })
        ));
    }

    #[test]
    fn regions_of_languages_as_users_name_them() {
        let named = [
            "zh-Hant-TW",
            "zh-HK",
            "yue",
            "sr-Latn",
            "sr",
            "pt_BR.UTF-8",
            "EN",
            "",
            "x-y",
        ];
        let (tw, hr, rs, pt) = (Some("tw"), Some("hr"), Some("rs"), Some("pt"));
        assert_eq!(
            named.map(region_of),
            [tw, tw, tw, hr, rs, pt, None, None, None]
        );
    }
}
