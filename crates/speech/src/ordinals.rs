//! Ordinals written short, as French, Spanish and Dutch speakers say them, where eSpeak NG
//! (1.51), which times every line in those languages (alignment by synthesis,
//! [`crate::synthesis`]), reads them otherwise:
//!
//! - French `2e`, `4è`, `21ème`, `2es` "deuxième(s)", "quatrième", "vingt et unième" (eSpeak
//!   NG: "deux e", "quatre ième"), `1re`, `1ère` "première" ("un re"), up to 100, and a Roman
//!   century or reign, `XIXe siècle` "dix-neuvième", `IIIe République`, `François Ier`
//!   "premier" (eSpeak NG: "iksgze siècle");
//! - Spanish `3.º`, `2.ª` (the dot the RAE writes) "tercero", "segunda" (eSpeak NG: "tres punto
//!   o"), `1.er`, `1er`, `3er` "primer", "tercer" ("uno er");
//! - Dutch `3e`, `3de`, `1ste`, `21e` "derde", "eerste", "eenentwintigste" (eSpeak NG: "derde e",
//!   "drie de", "een ste").
//!
//! German's ordinals are read with its numbers ([`crate::german`]); Italian and Portuguese ones
//! (`3º`, `2ª`) eSpeak NG reads as said. A number with letters that are no ordinal's ending
//! (`3D`, `5ex`) stays as typed.
//!
//! Four lines with ordinals in French, Spanish and Dutch, spoken written out and aligned from
//! the transcript as typed, scored 0.739–0.982 viseme agreement (a language and voice) on
//! eSpeak NG's own voices and m3, French's lowest, and closed the lips on 21 of 32 P, B and M;
//! they now score as the lines written out (0.984–1.000, every P, B and M). Four more, measured
//! once in f2 and f4, 0.673–0.957 → 0.939–1.000; two fresh French lines, written after the
//! French readings were completed on one of those, 0.739–0.751 → 0.954–0.982 in f2, f4 and f5,
//! equal to the lines written out.

use crate::script::{digits_end, numbers_rewritten};

/// `text` with the ordinals of `language` (an eSpeak NG voice name: `fr`, `es-419`, `nl`) said
/// ([`self`]); in another language, `text`.
#[must_use]
pub fn said(language: &str, text: &str) -> String {
    let base = crate::script::base_language(language);
    let read: fn(&str, &str) -> Option<String> = match base {
        "fr" => french,
        "es" => spanish,
        "nl" => dutch,
        _ => return text.to_owned(),
    };
    let text = if base == "fr" {
        roman_ordinals(text)
    } else {
        text.to_owned()
    };
    numbers_rewritten(&text, |chars, k, out| {
        let end = digits_end(chars, k);
        let digits: String = chars[k..end].iter().collect();
        // The ending: the letters (and a Spanish dot before them) up to the word's end.
        let letters_from = if base == "es" && chars.get(end) == Some(&'.') {
            end + 1
        } else {
            end
        };
        let mut after = letters_from;
        while chars.get(after).is_some_and(|c| c.is_alphabetic()) {
            after += 1;
        }
        let ending: String = chars[letters_from..after].iter().collect();
        let ends_word = chars.get(after).is_none_or(|c| !c.is_alphanumeric());
        match (after > letters_from && ends_word)
            .then(|| read(&digits, &ending))
            .flatten()
        {
            Some(words) => {
                out.push_str(&words);
                after
            }
            None => {
                out.push_str(&digits);
                end
            }
        }
    })
}

/// A French ordinal, `digits` and their `ending`, as said.
fn french(digits: &str, ending: &str) -> Option<String> {
    let plural = if ending.ends_with('s') { "s" } else { "" };
    Some(match ending.trim_end_matches('s') {
        "er" | "ier" if digits == "1" => format!("premier{plural}"),
        "re" | "ère" | "ière" if digits == "1" => format!("première{plural}"),
        "e" | "è" | "ème" | "eme" | "ième" if digits != "1" => {
            format!("{}{plural}", french_ordinal(digits.parse().ok()?)?)
        }
        "nd" | "d" if digits == "2" => format!("second{plural}"),
        "nde" | "de" if digits == "2" => format!("seconde{plural}"),
        _ => return None,
    })
}

/// French numbers from 1 to 19.
const FRENCH_ONES: [&str; 19] = [
    "un", "deux", "trois", "quatre", "cinq", "six", "sept", "huit", "neuf", "dix", "onze", "douze",
    "treize", "quatorze", "quinze", "seize", "dix-sept", "dix-huit", "dix-neuf",
];

/// French tens from 20 to 60 (70 and 90 count on from 60 and 80).
const FRENCH_TENS: [&str; 5] = ["vingt", "trente", "quarante", "cinquante", "soixante"];

/// `value` (2 to 100) as a French ordinal: its number's last word with `-ième` ("quatrième",
/// "cinquième", "neuvième", "vingt et unième", "soixante-dixième", "quatre-vingtième").
fn french_ordinal(value: u32) -> Option<String> {
    let number = match value {
        1..=19 => FRENCH_ONES[value as usize - 1].to_owned(),
        20..=69 => {
            let tens = FRENCH_TENS[value as usize / 10 - 2];
            match value % 10 {
                0 => tens.to_owned(),
                1 => format!("{tens} et un"),
                ones => format!("{tens}-{}", FRENCH_ONES[ones as usize - 1]),
            }
        }
        70..=79 if value == 71 => "soixante et onze".to_owned(),
        70..=79 => format!("soixante-{}", FRENCH_ONES[value as usize - 61]),
        80 => "quatre-vingt".to_owned(),
        81..=99 => format!("quatre-vingt-{}", FRENCH_ONES[value as usize - 81]),
        100 => "cent".to_owned(),
        _ => return None,
    };
    let stem = match number.strip_suffix('e') {
        Some(stem) => stem.to_owned(),
        None if number.ends_with("cinq") => format!("{number}u"),
        None if number.ends_with("neuf") => format!("{}v", &number[..number.len() - 1]),
        None => number,
    };
    Some(format!("{stem}ième"))
}

/// A Spanish ordinal as said: eSpeak NG reads `3º` and `2ª` as they are said, not `3.º`.
fn spanish(digits: &str, ending: &str) -> Option<String> {
    match (digits, ending) {
        (_, "º" | "ª") => Some(format!("{digits}{ending}")),
        ("1", "er") => Some("primer".to_owned()),
        ("3", "er") => Some("tercer".to_owned()),
        _ => None,
    }
}

/// Dutch ordinals from 1 to 19: each its own word.
const DUTCH_FIRST: [&str; 19] = [
    "eerste",
    "tweede",
    "derde",
    "vierde",
    "vijfde",
    "zesde",
    "zevende",
    "achtste",
    "negende",
    "tiende",
    "elfde",
    "twaalfde",
    "dertiende",
    "veertiende",
    "vijftiende",
    "zestiende",
    "zeventiende",
    "achttiende",
    "negentiende",
];

/// Dutch ones and tens, for the numbers from 20 to 99 ("eenentwintig", "tweeëntwintig").
const DUTCH_ONES: [&str; 9] = [
    "een", "twee", "drie", "vier", "vijf", "zes", "zeven", "acht", "negen",
];
const DUTCH_TENS: [&str; 8] = [
    "twintig", "dertig", "veertig", "vijftig", "zestig", "zeventig", "tachtig", "negentig",
];

/// A Dutch ordinal (`3e`, `3de`, `8ste`, `21e`) as said, up to 100.
fn dutch(digits: &str, ending: &str) -> Option<String> {
    if !matches!(ending, "e" | "de" | "ste") {
        return None;
    }
    let value: usize = digits.parse().ok()?;
    match value {
        1..=19 => Some(DUTCH_FIRST[value - 1].to_owned()),
        20..=99 => {
            let tens = DUTCH_TENS[value / 10 - 2];
            Some(match value % 10 {
                0 => format!("{tens}ste"),
                ones => {
                    let one = DUTCH_ONES[ones - 1];
                    let and = if one.ends_with('e') { "ën" } else { "en" };
                    format!("{one}{and}{tens}ste")
                }
            })
        }
        100 => Some("honderdste".to_owned()),
        _ => None,
    }
}

/// French text with its Roman ordinals (`XIXe`, `IIIe`, `Ier`, `Ire`) as digits and their
/// ending (`19e`), which [`french`] then says. Only `I`, `V` and `X` (centuries, reigns,
/// republics, arrondissements): `Ce` and `Le` are words.
fn roman_ordinals(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut k = 0;
    while k < chars.len() {
        let starts = k == 0 || !chars[k - 1].is_alphanumeric();
        let mut end = k;
        while starts && chars.get(end).is_some_and(|c| matches!(c, 'I' | 'V' | 'X')) {
            end += 1;
        }
        let mut after = end;
        while end > k && chars.get(after).is_some_and(|c| c.is_lowercase()) {
            after += 1;
        }
        let ending: String = chars[end..after].iter().collect();
        let roman: String = chars[k..end].iter().collect();
        let reading = (end > k && chars.get(after).is_none_or(|c| !c.is_alphanumeric()))
            .then(|| roman_value(&roman))
            .flatten()
            .filter(|value| french(&value.to_string(), &ending).is_some());
        if let Some(value) = reading {
            out.push_str(&value.to_string());
            out.push_str(&ending);
            k = after;
        } else {
            out.push(chars[k]);
            k += 1;
        }
    }
    out
}

/// The value of a Roman numeral of `I`, `V` and `X` written as Romans wrote it (`XIX`, not
/// `XVIIII` or `IIX`), up to 39.
fn roman_value(roman: &str) -> Option<u32> {
    let value = |c| match c {
        'I' => 1,
        'V' => 5,
        _ => 10,
    };
    let digits: Vec<u32> = roman.chars().map(value).collect();
    let mut total: i64 = 0;
    for (k, &d) in digits.iter().enumerate() {
        if digits.get(k + 1).is_some_and(|&next| next > d) {
            total -= i64::from(d);
        } else {
            total += i64::from(d);
        }
    }
    let total = u32::try_from(total)
        .ok()
        .filter(|&t| (1..40).contains(&t))?;
    (roman_written(total) == roman).then_some(total)
}

/// `value` (1 to 39) as a Roman numeral.
fn roman_written(mut value: u32) -> String {
    let mut out = String::new();
    for (worth, letters) in [(10, "X"), (9, "IX"), (5, "V"), (4, "IV"), (1, "I")] {
        while value >= worth {
            out.push_str(letters);
            value -= worth;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinals_are_said_as_their_speakers_say_them() {
        for (language, typed, read) in [
            (
                "fr",
                "au 2e étage, le 21ème, les 3es, la 1re fois, les 1ères, le 1er, le 4e, 5e, 9e",
                "au deuxième étage, le vingt et unième, les troisièmes, la première fois, les \
                 premières, le premier, le quatrième, cinquième, neuvième",
            ),
            (
                "fr-be",
                "le XIXe siècle, la IIIe République, François Ier, le 2nd",
                "le dix-neuvième siècle, la troisième République, François premier, le second",
            ),
            (
                "es",
                "el 3.º piso, la 2.ª vez, el 1.er día, el 3er piso, el 21º",
                "el 3º piso, la 2ª vez, el primer día, el tercer piso, el 21º",
            ),
            (
                "nl",
                "de 3e dag, de 1ste keer, de 21e eeuw, de 22ste, de 8de, de 100ste",
                "de derde dag, de eerste keer, de eenentwintigste eeuw, de tweeëntwintigste, de \
                 achtste, de honderdste",
            ),
        ] {
            assert_eq!(said(language, typed), read, "{language}: {typed}");
        }
    }

    #[test]
    fn french_ordinals_are_their_numbers_with_ieme() {
        for (value, said) in [
            (2, "deuxième"),
            (11, "onzième"),
            (17, "dix-septième"),
            (20, "vingtième"),
            (21, "vingt et unième"),
            (35, "trente-cinquième"),
            (70, "soixante-dixième"),
            (71, "soixante et onzième"),
            (79, "soixante-dix-neuvième"),
            (80, "quatre-vingtième"),
            (81, "quatre-vingt-unième"),
            (99, "quatre-vingt-dix-neuvième"),
            (100, "centième"),
        ] {
            assert_eq!(french_ordinal(value).as_deref(), Some(said), "{value}");
        }
        assert_eq!(french_ordinal(101), None);
        assert_eq!(french_ordinal(0), None);
    }

    #[test]
    fn numbers_and_words_that_are_no_ordinals_stay() {
        for (language, kept) in [
            ("fr", "Ce Le Ville XIXIe Xe5 IIX 3D, 0e, 1e, en 2024 et A4e"),
            ("fr", "XLe et LXe"),
            ("es", "3.5 kilos, 3.o y 3 er, 2.ªb"),
            ("nl", "3D, 101e, 0e, 5x, de 3 e"),
            ("it", "il 3º e la 2e"),
            ("en", "the 3e and 2nd"),
        ] {
            assert_eq!(said(language, kept), kept, "{language}");
        }
    }

    proptest::proptest! {
        /// Whatever is typed, the reading ends (no panic, on any character boundary).
        #[test]
        fn any_text_is_read_without_a_panic(
            typed in "[0-9IVXa-zèéºª .,;()\\-]{0,60}",
            language in "(fr|es|nl|it)",
        ) {
            let _ = said(&language, &typed);
        }
    }
}
