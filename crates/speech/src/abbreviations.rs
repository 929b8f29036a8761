//! A transcript's abbreviations as its language's speakers say them, where eSpeak NG (1.51),
//! which times every line in a language other than English (alignment by synthesis,
//! [`crate::synthesis`]), reads them otherwise: it spells many (Spanish `p. ej.` "pe ex",
//! Portuguese `Sr.` "esse erre", Dutch `dhr.` "de ha er", German `z. B.` "zet be"), cuts others
//! short (`etc.` "etk", Italian `Dott.` "dott", French `env.` "env") and ends a sentence at
//! every abbreviation's dot, even where it says the word (`Dra.` "doctora", then a pause). The
//! rendition the recording is warped onto then has sounds and pauses the speaker never made.
//!
//! Units after a number are read the same way (`5 km` "5 kilómetros", `1 h` "eine Stunde",
//! `14h30` "14 heures 30", `20 °C`, `30 m²`, Dutch `15 €` "15 euro"), where eSpeak NG spells
//! most ("ka em", Italian `kg` "kappa gi", German `h` "ha", Dutch `€` "euroteken"): "1" and its
//! unit are said together as the language agrees them ("un kilómetro", "una hora", "één uur").
//! So are amounts of money, a currency sign written before the amount moved after it, where
//! it is said (`€ 25` "25 euro", `R$ 30` "30 reais", `$40` "40 Dollar"; eSpeak NG: "euroteken
//! 25", "real 30", "Dollar 40").
//!
//! Each language's table holds the abbreviations of everyday writing — titles, "for example",
//! "and so on", "about", "number", "page" — that eSpeak NG misreads or ends a sentence at; an
//! abbreviation that could be something else (a single letter with a dot, Spanish `D.`, Italian
//! `n.`) is left alone. English has readings of its own ([`crate::script::english_said`]).
//!
//! Two lines a language with abbreviations in Spanish, French, Italian, Portuguese and Dutch,
//! spoken as written out and aligned from the transcript as typed, scored 0.825–0.910 viseme
//! agreement (a language and voice) on eSpeak NG's own voices and m3, and two more a language
//! in voices no choice was made on (f2, f4) 0.681–0.837; with these tables each scores as the
//! lines aligned from their written-out transcripts (0.958–0.994). A line a language with units
//! (German's too) scored 0.724–0.910 on those voices and 0.751–0.897 on f2 and f4; as written
//! out now, 0.961–1.000 and 0.984–0.998 (the German line in f2 and f4 showed that `m²` reaches
//! the tables as `m2`; after that, two fresh lines there, German and Portuguese, 0.738–0.781 →
//! 0.966–0.977). A line a language with amounts scored 0.734–0.972 on those voices and
//! 0.615–0.941 on f2 and f4 (fresh lines, measured once); now as written out, 0.962–1.000 and
//! 0.951–1.000.

/// The tables, one a language ([`self`]): a language's lines after its `[xx]`, each
/// `where: written | another form = said`.
const TABLES: &str = include_str!("abbreviations.txt");

/// An abbreviation: its language (eSpeak NG's name), how it is written (each form, with and
/// without inner spaces), how it is said, and where it is read; a unit, also how "1" and it
/// are said together (`1 h` "eine Stunde", `1 km` "un kilómetro").
#[derive(Debug, PartialEq, Eq)]
struct Abbreviation {
    language: &'static str,
    written: Vec<&'static str>,
    said: &'static str,
    one: Option<&'static str>,
    at: Place,
}

/// Where an abbreviation is read as its words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    /// Anywhere; its dot never ends a sentence (`Dr.`, `z. B.`).
    Within,
    /// Anywhere; at a sentence's end its dot is the sentence's too (`… usw. Dann`, `etc.`).
    MayEnd,
    /// Only before a name (a capital after a space): French `M.` is "monsieur" in `M.
    /// Dupont` and a letter elsewhere.
    BeforeName,
    /// A unit, only after a number (`5 km`, `5km`, `14h30`): `m` is a letter elsewhere.
    AfterNumber,
}

/// A line of [`TABLES`] that is not an abbreviation: its number (from 1) and what is wrong.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("abbreviations.txt, line {line}: {problem}")]
struct TableError {
    line: usize,
    problem: &'static str,
}

/// Every abbreviation of `tables` (written as [`TABLES`]), in order.
fn parsed(tables: &'static str) -> Result<Vec<Abbreviation>, TableError> {
    let mut language = None;
    let mut table = Vec::new();
    for (k, line) in tables.lines().enumerate() {
        let error = |problem| TableError {
            line: k + 1,
            problem,
        };
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(header) = line.strip_prefix('[') {
            let (name, _) = header
                .split_once(']')
                .ok_or(error("a `[` without its `]`"))?;
            language = Some(name);
            continue;
        }
        let language = language.ok_or(error("an abbreviation before its language's `[xx]`"))?;
        let (at, rest) = line
            .split_once(": ")
            .ok_or(error("no `where: ` at its start"))?;
        let at = match at {
            "within" => Place::Within,
            "may-end" => Place::MayEnd,
            "before-name" => Place::BeforeName,
            "after-number" => Place::AfterNumber,
            _ => {
                return Err(error(
                    "where is not `within`, `may-end`, `before-name` or `after-number`",
                ));
            }
        };
        let (written, said) = rest.split_once(" = ").ok_or(error("no ` = said`"))?;
        let written: Vec<&str> = written.split(" | ").map(str::trim).collect();
        let (one, said) = match (at, said.split_once(" / ")) {
            (Place::AfterNumber, Some((one, many))) => (Some(one.trim()), many.trim()),
            (Place::AfterNumber, None) => return Err(error("a unit without `one / many`")),
            (_, Some(_)) => return Err(error("` / ` in the reading of what is not a unit")),
            (_, None) => (None, said.trim()),
        };
        if said.is_empty() || one == Some("") || written.iter().any(|w| w.is_empty()) {
            return Err(error("an empty written form or reading"));
        }
        table.push(Abbreviation {
            language,
            written,
            said,
            one,
            at,
        });
    }
    Ok(table)
}

/// [`TABLES`] read once. Its lines are checked by this module's tests; were one wrong, no
/// abbreviation would be said (and the error logged) rather than a transcript refused.
fn tables() -> &'static [Abbreviation] {
    static TABLE: std::sync::LazyLock<Vec<Abbreviation>> = std::sync::LazyLock::new(|| {
        parsed(TABLES).unwrap_or_else(|e| {
            tracing::error!("{e}");
            Vec::new()
        })
    });
    &TABLE
}

/// The abbreviations of `language` (an eSpeak NG voice name: `es`, `pt-br`, `fr-be`, `de+m3`),
/// none for a language without a table.
fn table(language: &str) -> impl Iterator<Item = &'static Abbreviation> {
    let base = crate::script::base_language(language);
    tables().iter().filter(move |a| a.language == base)
}

/// `text` with the abbreviations of `language` ([`self`]) said. A written form in lower case
/// is found capitalised too (`Z. B.` at a sentence's start), and said so; one with a capital
/// (a title: `Dr.`, `M.`) only as written. A form inside a word (`Nrn`, `Sig.ra` for `Sig.`)
/// is not one.
#[must_use]
pub fn said(language: &str, text: &str) -> String {
    let mut forms: Vec<(Vec<char>, &Abbreviation)> = table(language)
        .flat_map(|a| {
            a.written
                .iter()
                .map(move |form| (form.chars().collect(), a))
        })
        .collect();
    // The longest form first: `km/h` before `km`.
    forms.sort_by_key(|(form, _)| std::cmp::Reverse(form.len()));
    if forms.is_empty() {
        return text.to_owned();
    }
    // The currencies the language's table says (Spanish `$` is a dollar or a peso: left).
    let currencies: Vec<&str> = CURRENCIES
        .into_iter()
        .filter(|sign| {
            forms.iter().any(|(form, a)| {
                a.at == Place::AfterNumber && form.iter().copied().eq(sign.chars())
            })
        })
        .collect();
    let chars: Vec<char> = currency_after_amount(text, &currencies).chars().collect();
    let mut out = String::with_capacity(text.len() + 16);
    let mut k = 0;
    'scan: while k < chars.len() {
        // The number a unit here would follow (`5 km`, `5km`), asked once a place.
        let mut number_here = None;
        for (form, abbreviation) in &forms {
            let unit = abbreviation.at == Place::AfterNumber;
            // A word's start; a unit's, after a number.
            let number = if unit {
                *number_here.get_or_insert_with(|| number_before(&chars[..k]))
            } else {
                None
            };
            let starts = k == 0
                || !chars[k - 1].is_alphanumeric()
                || (number.is_some() && chars[k - 1].is_ascii_digit());
            if !starts || (unit && number.is_none()) {
                continue;
            }
            let Some(here) = chars.get(k..k + form.len()) else {
                continue;
            };
            let capitalised = form[0].is_lowercase()
                && !unit
                && here[0].to_lowercase().eq(form[0].to_lowercase())
                && here[0].is_uppercase();
            if (here[0] != form[0] && !capitalised) || here[1..] != form[1..] {
                continue;
            }
            let after = k + form.len();
            // Not inside a word; only the hour has digits after it, a time's minutes
            // (`14h30`; `5m2` is a name).
            let clock = unit && form[..] == ['h'];
            if chars
                .get(after)
                .is_some_and(|c| c.is_alphanumeric() && !(clock && c.is_ascii_digit()))
            {
                continue;
            }
            // A letter elided before an apostrophe is a word's (`En 2020 l'entreprise`, `nel
            // 2020 l'azienda`, `3 m'ont vu`), not a unit.
            if unit
                && chars
                    .get(after)
                    .is_some_and(|&c| c == '\'' || c == '\u{2019}')
            {
                continue;
            }
            // What comes next: the text ends, or a capital (a sentence or a name).
            let next = chars[after..].iter().find(|c| !c.is_whitespace());
            let capital_next = next.is_none_or(|c| c.is_uppercase());
            if abbreviation.at == Place::BeforeName
                && !(next.is_some_and(|c| c.is_uppercase())
                    && chars.get(after).is_some_and(|c| c.is_whitespace()))
            {
                continue;
            }
            // The number as written before the unit, with its spaces.
            let written: Option<String> = number.map(|start| chars[start..k].iter().collect());
            match (&written, abbreviation.one) {
                // "1" and its unit said together, in place of both.
                (Some(written), Some(one))
                    if written.trim_end() == "1" && out.ends_with(written) =>
                {
                    out.truncate(out.len() - written.len());
                    out.push_str(one);
                }
                _ if capitalised => {
                    let mut letters = abbreviation.said.chars();
                    out.extend(letters.next().into_iter().flat_map(char::to_uppercase));
                    out.extend(letters);
                }
                _ => {
                    if unit && chars[k - 1].is_ascii_digit() {
                        out.push(' ');
                    }
                    out.push_str(abbreviation.said);
                }
            }
            if clock && chars.get(after).is_some_and(char::is_ascii_digit) {
                out.push(' ');
            }
            if abbreviation.at == Place::MayEnd && capital_next {
                out.push('.');
            }
            k = after;
            continue 'scan;
        }
        out.push(chars[k]);
        k += 1;
    }
    out
}

/// Currency signs written before an amount, longest first (`US$`, `R$` before `$`).
const CURRENCIES: [&str; 5] = ["US$", "R$", "€", "$", "£"];

/// `text` with each of the currency signs `currencies` written before an amount (`€ 15`,
/// `€15,50`, `R$ 20`) moved after it (`15 €`), where the speakers of every language with a
/// table say it (eSpeak NG says it first, "euro fünfzehn", and Dutch `€` "euroteken"); the
/// tables then say it.
fn currency_after_amount(text: &str, currencies: &[&str]) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 4);
    let mut k = 0;
    'scan: while k < chars.len() {
        if k == 0 || !chars[k - 1].is_alphanumeric() {
            for sign in currencies {
                let Some(length) = crate::script::written_at(&chars, k, sign) else {
                    continue;
                };
                let mut start = k + length;
                if chars.get(start).is_some_and(|c| c.is_whitespace()) {
                    start += 1;
                }
                let end = crate::script::amount_end(&chars, start);
                if end == start || chars.get(end).is_some_and(|c| c.is_alphanumeric()) {
                    continue;
                }
                out.extend(&chars[start..end]);
                out.push(' ');
                out.push_str(sign);
                k = end;
                continue 'scan;
            }
        }
        out.push(chars[k]);
        k += 1;
    }
    out
}

/// Where the number that `before` ends with starts (its digits, with `,` or `.` between them,
/// and the spaces after it), when it ends with one.
fn number_before(before: &[char]) -> Option<usize> {
    let digits_end = before.len()
        - before
            .iter()
            .rev()
            .take_while(|c| c.is_whitespace())
            .count();
    let mut start = digits_end;
    while start > 0
        && (before[start - 1].is_ascii_digit()
            || (matches!(before[start - 1], ',' | '.')
                && start < digits_end
                && start >= 2
                && before[start - 2].is_ascii_digit()))
    {
        start -= 1;
    }
    // A number, not the end of a word (`A4 m`).
    let whole = start < digits_end && (start == 0 || !before[start - 1].is_alphanumeric());
    whole.then_some(start)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn abbreviations_are_said_as_their_speakers_say_them() {
        for (language, typed, read) in [
            (
                "de",
                "Obst, z. B. Äpfel, d.h. nichts",
                "Obst, zum Beispiel Äpfel, das heißt nichts",
            ),
            (
                "de",
                "Z. B. ca. 20 Leute, Nr. 5",
                "Zum Beispiel circa 20 Leute, Nummer 5",
            ),
            (
                "de-AT",
                "Birnen usw. Dann Dr. Weber",
                "Birnen und so weiter. Dann Doktor Weber",
            ),
            (
                "de",
                "Birnen usw. und Kiwis",
                "Birnen und so weiter und Kiwis",
            ),
            (
                "es",
                "El Sr. García y la Dra. Pérez, p. ej. en EE. UU., etc.",
                "El señor García y la doctora Pérez, por ejemplo en Estados Unidos, etcétera.",
            ),
            (
                "es-419",
                "Vea la pág. 12, núm. 3, aprox. a las 5",
                "Vea la página 12, número 3, aproximadamente a las 5",
            ),
            (
                "fr",
                "M. Dupont, p. ex. le 3, c.-à-d. env. 20, etc. Puis Dr. Roux",
                "monsieur Dupont, par exemple le 3, c'est-à-dire environ 20, etcétéra. Puis \
                 docteur Roux",
            ),
            ("fr", "un M. et 5 M. ou M.", "un M. et 5 M. ou M."),
            (
                "fr",
                "M.\u{a0}Dupont et MM. Petit",
                "monsieur\u{a0}Dupont et messieurs Petit",
            ),
            (
                "it",
                "La Sig.ra Rossi e il Dott. Bianchi, ecc. Poi la Dott.ssa Neri",
                "La signora Rossi e il dottor Bianchi, eccetera. Poi la dottoressa Neri",
            ),
            (
                "pt-br",
                "O Sr. Silva e a Dra. Costa, p. ex. na Av. Paulista",
                "O senhor Silva e a doutora Costa, por exemplo na avenida Paulista",
            ),
            (
                "nl",
                "Dhr. Jansen en mevr. de Vries, bijv. op blz. 4, enz.",
                "De heer Jansen en mevrouw de Vries, bijvoorbeeld op bladzijde 4, enzovoort.",
            ),
            (
                "es",
                "A 1 km, 3,5 kg y 21 km/h, 1h o 2 h, 20 °C y 1,5 m.",
                "A un kilómetro, 3,5 kilogramos y 21 kilómetros por hora, una hora o 2 horas, \
                 20 grados Celsius y 1,5 metros.",
            ),
            (
                "fr",
                "À 14h30, 1 h et 5 min, 1 m² et 12 m, à 10 km.",
                "À 14 heures 30, une heure et 5 minutes, un mètre carré et 12 mètres, à 10 \
                 kilomètres.",
            ),
            (
                "de",
                "Nach 1 h und 5 km, 2,5 l und 1 kg. Z. B. 3 mg",
                "Nach eine Stunde und 5 Kilometer, 2,5 Liter und ein Kilogramm. Zum Beispiel 3 \
                 Milligramm",
            ),
            ("nl", "Het kost 15 € en 1 €", "Het kost 15 euro en één euro"),
            (
                "nl",
                "Het kost € 15, €2,50 of £1",
                "Het kost 15 euro, 2,50 euro of één pond",
            ),
            (
                "de",
                "Nur €15 oder $1, 20 £ und 3 €.",
                "Nur 15 Euro oder ein Dollar, 20 Pfund und 3 Euro.",
            ),
            (
                "pt-br",
                "Custa R$ 20 ou US$ 1,50",
                "Custa 20 reais ou 1,50 dólares",
            ),
            // `m²` as the transcript reaches it (its `²` a plain `2`: `script::plain`).
            (
                "de",
                "30 m2 und 1 m2",
                "30 Quadratmeter und ein Quadratmeter",
            ),
        ] {
            assert_eq!(said(language, typed), read, "{language}: {typed}");
        }
    }

    #[test]
    fn every_line_of_the_tables_is_an_abbreviation() {
        let table = parsed(TABLES).unwrap();
        for language in ["de", "es", "fr", "it", "pt", "nl"] {
            assert!(table.iter().filter(|a| a.language == language).count() >= 13);
        }
        assert_eq!(
            table[0],
            Abbreviation {
                language: "de",
                written: vec!["z. B.", "z.B."],
                said: "zum Beispiel",
                one: None,
                at: Place::Within
            }
        );
        for (wrong, line) in [
            ("within: a. = b", 1),
            ("[de]\nafter-number: a = b", 2),
            ("[de]\nwithin: a = b / c", 2),
            ("[de]\nafter-number: a =  / c", 2),
            ("[de]\nwithin a. = b", 2),
            ("[de]\nsometimes: a. = b", 2),
            ("[de]\n\nwithin: a.", 3),
            ("[de]\nwithin: a. |  = b", 2),
            ("[de\nwithin: a. = b", 1),
        ] {
            assert_eq!(parsed(wrong).map_err(|e| e.line), Err(line), "{wrong}");
        }
    }

    #[test]
    fn words_that_look_like_abbreviations_stay() {
        for (language, kept) in [
            ("de", "Anzug, Abbau, Nrn, dr. und DR."),
            ("de", "Das A4 m und der km, Typ 5m3, 5 Mm, g 5 kmh"),
            ("es", "La m y 5 mu, 5 kilos, $ y €, $5."),
            (
                "fr",
                "En 2020 l'entreprise, les 3 m'ont vu, 2 l\u{2019}ont dit",
            ),
            ("it", "Nel 2020 l'azienda e 5 l'anno"),
            ("de", "Preis in € oder €X, A$5"),
            ("es", "Los Srs. y la SRA. y sra. López"),
            ("fr", "Me voici, me Dupont, M.Dupont et m. Dupont"),
            ("it", "La Sig.rina e il Sig.ore"),
            ("en", "Dr. Jones, e.g. etc."),
            ("ja", "p. ex."),
        ] {
            assert_eq!(said(language, kept), kept, "{language}");
        }
    }

    proptest::proptest! {
        /// Whatever is typed, the reading ends (no panic, on any character boundary).
        #[test]
        fn any_text_is_read_without_a_panic(
            typed in "[0-9a-zA-ZäöüéíñçàÀ .,;()\\-°º²/€]{0,60}",
            language in "(de|es|fr|it|pt|nl|en)",
        ) {
            let _ = said(&language, &typed);
        }
    }
}
