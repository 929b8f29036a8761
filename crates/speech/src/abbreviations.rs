//! A transcript's abbreviations as its language's speakers say them, where eSpeak NG (1.51),
//! which times every line in a language other than English (alignment by synthesis,
//! [`crate::synthesis`]), reads them otherwise: it spells many (Spanish `p. ej.` "pe ex",
//! Portuguese `Sr.` "esse erre", Dutch `dhr.` "de ha er", German `z. B.` "zet be"), cuts others
//! short (`etc.` "etk", Italian `Dott.` "dott", French `env.` "env") and ends a sentence at
//! every abbreviation's dot, even where it says the word (`Dra.` "doctora", then a pause). The
//! rendition the recording is warped onto then has sounds and pauses the speaker never made.
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
//! lines aligned from their written-out transcripts (0.958–0.994).

/// The tables, one a language ([`self`]): a language's lines after its `[xx]`, each
/// `where: written | another form = said`.
const TABLES: &str = include_str!("abbreviations.txt");

/// An abbreviation: its language (eSpeak NG's name), how it is written (each form, with and
/// without inner spaces), how it is said, and where it is read.
#[derive(Debug, PartialEq, Eq)]
struct Abbreviation {
    language: &'static str,
    written: Vec<&'static str>,
    said: &'static str,
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
            _ => return Err(error("where is not `within`, `may-end` or `before-name`")),
        };
        let (written, said) = rest.split_once(" = ").ok_or(error("no ` = said`"))?;
        let written: Vec<&str> = written.split(" | ").map(str::trim).collect();
        if said.trim().is_empty() || written.iter().any(|w| w.is_empty()) {
            return Err(error("an empty written form or reading"));
        }
        table.push(Abbreviation {
            language,
            written,
            said: said.trim(),
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
    let base = language.split(['-', '+', '_']).next().unwrap_or_default();
    tables().iter().filter(move |a| a.language == base)
}

/// `text` with the abbreviations of `language` ([`self`]) said. A written form in lower case
/// is found capitalised too (`Z. B.` at a sentence's start), and said so; one with a capital
/// (a title: `Dr.`, `M.`) only as written. A form inside a word (`Nrn`, `Sig.ra` for `Sig.`)
/// is not one.
#[must_use]
pub fn said(language: &str, text: &str) -> String {
    let forms: Vec<(Vec<char>, &Abbreviation)> = table(language)
        .flat_map(|a| {
            a.written
                .iter()
                .map(move |form| (form.chars().collect(), a))
        })
        .collect();
    if forms.is_empty() {
        return text.to_owned();
    }
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 16);
    let mut k = 0;
    'scan: while k < chars.len() {
        if k == 0 || !chars[k - 1].is_alphanumeric() {
            for (form, abbreviation) in &forms {
                let Some(here) = chars.get(k..k + form.len()) else {
                    continue;
                };
                let capitalised = form[0].is_lowercase()
                    && here[0].to_lowercase().eq(form[0].to_lowercase())
                    && here[0].is_uppercase();
                if (here[0] != form[0] && !capitalised) || here[1..] != form[1..] {
                    continue;
                }
                let after = k + form.len();
                if chars.get(after).is_some_and(|c| c.is_alphanumeric()) {
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
                if capitalised {
                    let mut letters = abbreviation.said.chars();
                    out.extend(letters.next().into_iter().flat_map(char::to_uppercase));
                    out.extend(letters);
                } else {
                    out.push_str(abbreviation.said);
                }
                if abbreviation.at == Place::MayEnd && capital_next {
                    out.push('.');
                }
                k = after;
                continue 'scan;
            }
        }
        out.push(chars[k]);
        k += 1;
    }
    out
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
                at: Place::Within
            }
        );
        for (wrong, line) in [
            ("within: a. = b", 1),
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
            typed in "[a-zA-ZäöüéíñçàÀ .,;()\\-°º]{0,60}",
            language in "(de|es|fr|it|pt|nl|en)",
        ) {
            let _ = said(&language, &typed);
        }
    }
}
