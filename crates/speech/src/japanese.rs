//! Japanese written in kanji, read into kana as it is said, by MeCab with the IPADIC dictionary
//! (Debian `apt-get install mecab mecab-ipadic-utf8`, Homebrew `brew install mecab
//! mecab-ipadic`), so that eSpeak NG, which times every Japanese line (alignment by synthesis,
//! [`crate::synthesis`]) but reads no kanji (it says "Chinese letter", in English, for each),
//! can say it.
//!
//! MeCab cuts a line into words by its dictionary's costs, with the context of each; a word is
//! written as the dictionary pronounces it (発音: `今日は` "キョーワ", the particle `は` "ワ", `へ`
//! "エ", long vowels with `ー`), one it does not know (Latin letters, digits, markup) as
//! typed. Lines without kanji are left as they are; the spaces between words are kept.
//!
//! Two lines in kanji, spoken in kana by eSpeak NG's ja and m3, scored 0.68–0.80 viseme
//! agreement aligned to eSpeak NG's rendition of the kanji, and 0.80–0.93 recognised without
//! their transcript; read by MeCab they are aligned as the same lines typed in kana are.
//!
//! MeCab runs as its own program (GPL, LGPL or BSD at the user's choice; IPADIC's licence is
//! its own, permissive): nothing of either is linked or shipped.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Where IPADIC is installed: Debian's and Ubuntu's UTF-8 build, Homebrew's (Apple silicon,
/// Intel), and other Linux distributions'.
const IPADIC: [&str; 6] = [
    "/var/lib/mecab/dic/ipadic-utf8",
    "/opt/homebrew/lib/mecab/dic/ipadic",
    "/usr/local/lib/mecab/dic/ipadic",
    "/usr/lib/mecab/dic/ipadic",
    "/usr/lib64/mecab/dic/ipadic",
    "/usr/share/mecab/dic/ipadic",
];

/// How to install what reads kanji, for the notes.
pub const INSTALL: &str =
    "apt-get install mecab mecab-ipadic-utf8; brew install mecab mecab-ipadic";

/// Why a text's kanji could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ReadingError {
    /// The `mecab` program is not installed.
    #[error("MeCab, which reads kanji, is not installed ({INSTALL})")]
    NoMecab,
    /// MeCab ran and failed, or wrote what is not its output.
    #[error("MeCab could not read the kanji: {0}")]
    Failed(String),
    /// Words MeCab's dictionary does not know, still in kanji.
    #[error("MeCab's dictionary does not know {0:?} (IPADIC: {INSTALL})")]
    Unknown(String),
}

/// Whether `c` is a Han character (a kanji) or the iteration mark `々`.
#[must_use]
pub fn is_kanji(c: char) -> bool {
    matches!(c,
        '\u{3005}' | '\u{3400}'..='\u{4DBF}' | '\u{4E00}'..='\u{9FFF}' | '\u{F900}'..='\u{FAFF}'
            | '\u{20000}'..='\u{2FA1F}')
}

/// Whether `text` holds a kanji ([`is_kanji`]).
#[must_use]
pub fn has_kanji(text: &str) -> bool {
    text.chars().any(is_kanji)
}

/// `text` with each line that holds kanji read into kana as it is said ([`self`]), by the
/// `mecab` program on the path with IPADIC where it is installed (else MeCab's own dictionary).
///
/// # Errors
/// [`ReadingError`] when MeCab is missing or fails, or a word stays in kanji (its dictionary
/// is not IPADIC, or does not know the word).
pub fn kana(text: &str) -> Result<String, ReadingError> {
    read_with(Path::new("mecab"), ipadic().as_deref(), text)
}

/// The IPADIC folder installed, if one is.
fn ipadic() -> Option<PathBuf> {
    IPADIC
        .iter()
        .map(PathBuf::from)
        .find(|dir| dir.join("sys.dic").is_file())
}

/// [`kana`] by `program`, with the dictionary in `dictionary` (MeCab's own when `None`).
fn read_with(
    program: &Path,
    dictionary: Option<&Path>,
    text: &str,
) -> Result<String, ReadingError> {
    let lines: Vec<&str> = text.split('\n').collect();
    let kanji: Vec<&str> = lines.iter().copied().filter(|l| has_kanji(l)).collect();
    if kanji.is_empty() {
        return Ok(text.to_owned());
    }
    let mut command = Command::new(program);
    if let Some(dictionary) = dictionary {
        command.arg("-d").arg(dictionary);
    }
    // Each word: its form as written, a tab, the dictionary's features (the ninth is how it
    // is said); a line's end: EOS. A line as long as the whole transcript fits the buffer.
    command
        .args([
            "--input-buffer-size=1048576",
            "--node-format=%m\\t%H\\n",
            "--unk-format=%m\\t%H\\n",
            "--eos-format=EOS\\n",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = command.spawn().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => ReadingError::NoMecab,
        _ => ReadingError::Failed(format!("running {}: {e}", program.display())),
    })?;
    let mut input = kanji.join("\n").replace('\r', "");
    input.push('\n');
    // Written from another thread: MeCab answers as it reads, and a long transcript would
    // fill the pipe it answers through before it had read all.
    let mut stdin = child
        .stdin
        .take()
        .ok_or_else(|| ReadingError::Failed("no pipe to MeCab".into()))?;
    let writer = std::thread::spawn(move || stdin.write_all(input.as_bytes()));
    let output = child
        .wait_with_output()
        .map_err(|e| ReadingError::Failed(e.to_string()))?;
    let written = writer
        .join()
        .map_err(|_| ReadingError::Failed("writing to MeCab".into()))?;
    if !output.status.success() {
        return Err(ReadingError::Failed(
            String::from_utf8_lossy(&output.stderr).trim().to_owned(),
        ));
    }
    written.map_err(|e| ReadingError::Failed(format!("writing to MeCab: {e}")))?;
    let answer = String::from_utf8(output.stdout).map_err(|_| {
        ReadingError::Failed(
            "its dictionary is not UTF-8 (IPADIC's UTF-8 build: mecab-ipadic-utf8)".into(),
        )
    })?;
    let mut sentences = answer.split("EOS\n");
    let mut out = Vec::with_capacity(lines.len());
    for line in lines {
        if !has_kanji(line) {
            out.push(line.to_owned());
            continue;
        }
        let words = sentences.next().ok_or_else(|| {
            ReadingError::Failed("it answered fewer lines than it was given".into())
        })?;
        let said = said(line.trim_end_matches('\r'), words)?;
        if let Some(unknown) = said.split_whitespace().find(|w| has_kanji(w)) {
            return Err(ReadingError::Unknown(unknown.to_owned()));
        }
        out.push(said);
    }
    Ok(out.join("\n"))
}

/// `line` said as MeCab's `words` (a word a line: form, tab, features) say, with the spaces
/// between them kept.
fn said(line: &str, words: &str) -> Result<String, ReadingError> {
    let mut out = String::with_capacity(line.len() * 2);
    let mut rest = line;
    for word in words.lines().filter(|w| !w.is_empty()) {
        let (form, features) = word
            .split_once('\t')
            .ok_or_else(|| ReadingError::Failed(format!("unexpected answer {word:?}")))?;
        let trimmed = rest.trim_start();
        if trimmed.len() != rest.len() {
            out.push(' ');
        }
        rest = trimmed.strip_prefix(form).unwrap_or(trimmed);
        // IPADIC's features: part of speech (four), conjugation (two), base form, reading,
        // pronunciation; a word it does not know has the first seven.
        match features.split(',').nth(8) {
            Some(spoken) if spoken != "*" && !spoken.is_empty() => out.push_str(spoken),
            _ => out.push_str(form),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_are_said_as_the_dictionary_pronounces_them_with_their_spaces() {
        let words = "今日\t名詞,副詞可能,*,*,*,*,今日,キョウ,キョー\nは\t助詞,係助詞,*,*,*,*,は,ハ,ワ\nABC\t名詞,一般,*,*,*,*,*\n3\t名詞,数,*,*,*,*,*\n時\t名詞,接尾,助数詞,*,*,*,時,ジ,ジ\n";
        assert_eq!(said("今日は ABC 3時", words).unwrap(), "キョーワ ABC 3ジ");
        assert!(matches!(said("x", "no tab"), Err(ReadingError::Failed(_))));
    }

    #[test]
    fn kana_alone_needs_no_mecab_and_a_missing_one_is_named() {
        let missing = Path::new("/nonexistent/mecab");
        assert_eq!(
            read_with(missing, None, "きょうは\nいい天気").unwrap_err(),
            ReadingError::NoMecab
        );
        assert_eq!(
            read_with(missing, None, "きょうは、ABC").unwrap(),
            "きょうは、ABC"
        );
        assert!(has_kanji("毎朝、母と") && has_kanji("人々") && has_kanji("𠮷"));
        assert!(!has_kanji("まいあさ、パン、ｱｲ、한국어, 1985"));
    }
}
