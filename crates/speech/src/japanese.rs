//! Japanese as it is said, for eSpeak NG, which times every Japanese line (alignment by
//! synthesis, [`crate::synthesis`]) but reads no kanji (it says "Chinese letter", in English,
//! for each) and says numbers without their counters' sound changes.
//!
//! - **Numbers** ([`numbers_said`]) with their counters, as speakers say them: `3本` "san-bon"
//!   (eSpeak NG: "san hon"), `1分` "ip-pun", `1人` "hitori", `5日` "itsuka", `12月1日` "jū-ni-gatsu
//!   tsuitachi", `10:30`, `2024` "ni-sen ni-jū yon" (eSpeak NG: "… shi"). Three lines with
//!   numbers in eSpeak NG's ja and m3 scored 0.79–0.97 viseme agreement and closed the lips on
//!   6 of 12 P, B and M with MeCab alone; said so, 0.97–1.00 and 12 of 12, as the lines typed
//!   in kana. Four fresh lines in f2 and f4, measured once: 0.62–0.97, 11 of 22, → 0.96–1.00,
//!   22 of 22, as typed in kana.
//! - **Kanji** ([`Mecab`]), read into kana by MeCab with the IPADIC dictionary (Debian
//!   `apt-get install mecab mecab-ipadic-utf8`, Homebrew `brew install mecab mecab-ipadic`).
//!   MeCab cuts a line into words by its dictionary's costs, with the context of each; a word
//!   is written as the dictionary pronounces it (発音: `今日は` "キョーワ", the particle `は`
//!   "ワ", `へ` "エ", long vowels with `ー`), one it does not know (Latin letters, markup) as
//!   typed. Lines without kanji are left as they are; the spaces between words are kept. Two
//!   lines in kanji in ja and m3 scored 0.61–0.80 aligned to eSpeak NG's rendition of the
//!   kanji, 0.80–0.93 recognised without their transcript (which is still done, with a note,
//!   where MeCab is missing); read by MeCab, 0.99–1.00. Six fresh lines in f2 and f4, measured
//!   once: 0.944–0.994, where typed in kana they score 0.955–1.000.
//! - **What is not said** ([`unsaid_parentheses`]): short spans in parentheses, a direction or a
//!   speaker (`（笑）`, `（拍手）`) or a word's reading after it (`東京（とうきょう）`).
//!
//! ```
//! use faceanim_speech::japanese;
//! assert_eq!(japanese::numbers_said("ペンを3本と猫を1匹"), "ペンをサンボンと猫をイッピキ");
//! assert_eq!(japanese::unsaid_parentheses("そうですね（笑）").0, "そうですね");
//! ```
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
    c == '\u{3005}' || crate::script::is_han(c)
}

/// Whether `text` holds a kanji ([`is_kanji`]).
#[must_use]
pub fn has_kanji(text: &str) -> bool {
    text.chars().any(is_kanji)
}

/// MeCab, found on the path, with IPADIC where it is installed (else MeCab's own dictionary).
#[derive(Clone, Debug)]
pub struct Mecab {
    program: PathBuf,
    dictionary: Option<PathBuf>,
}

impl Mecab {
    /// The `mecab` program on the path (`mecab.exe` on Windows), with IPADIC where it is
    /// installed.
    ///
    /// # Errors
    /// [`ReadingError::NoMecab`] when there is none.
    pub fn find() -> Result<Self, ReadingError> {
        let names: &[&str] = if cfg!(windows) {
            &["mecab.exe"]
        } else {
            &["mecab"]
        };
        let program = std::env::var_os("PATH")
            .iter()
            .flat_map(std::env::split_paths)
            .flat_map(|dir| names.iter().map(move |name| dir.join(name)))
            .find(|path| path.is_file())
            .ok_or(ReadingError::NoMecab)?;
        Ok(Self {
            program,
            dictionary: IPADIC
                .iter()
                .map(PathBuf::from)
                .find(|dir| dir.join("sys.dic").is_file()),
        })
    }

    /// `text` with each line that holds kanji read into kana as it is said ([`self`]); lines
    /// without kanji as they are.
    ///
    /// # Errors
    /// [`ReadingError`] when MeCab fails, or a word stays in kanji (its dictionary is not
    /// IPADIC, or does not know the word).
    pub fn kana(&self, text: &str) -> Result<String, ReadingError> {
        Ok(self.kana_each(vec![text.to_owned()])?.concat())
    }

    /// [`Mecab::kana`] of each of `texts`, in one run of MeCab.
    ///
    /// # Errors
    /// As [`Mecab::kana`].
    pub fn kana_each(&self, texts: Vec<String>) -> Result<Vec<String>, ReadingError> {
        read_with(&self.program, self.dictionary.as_deref(), texts)
    }
}

/// `text` (Japanese, as said aloud: [`crate::script::spoken`]) as eSpeak NG is to say it:
/// without the short spans in parentheses it does not say ([`unsaid_parentheses`]), its
/// numbers said with their counters ([`numbers_said`]), then, by `mecab` where it is given,
/// its kanji read into kana.
///
/// # Errors
/// [`ReadingError`] when MeCab fails or leaves a word in kanji.
pub fn said(text: &str, mecab: Option<&Mecab>) -> Result<String, ReadingError> {
    Ok(said_each(vec![text.to_owned()], mecab)?.concat())
}

/// [`said`] of each of `texts` (a subtitle's cues), with one run of MeCab for all.
///
/// # Errors
/// As [`said`].
pub fn said_each(texts: Vec<String>, mecab: Option<&Mecab>) -> Result<Vec<String>, ReadingError> {
    let texts = texts
        .iter()
        .map(|text| numbers_said(&unsaid_parentheses(text).0))
        .collect::<Vec<_>>();
    match mecab {
        Some(mecab) if texts.iter().any(|t| has_kanji(t)) => mecab.kana_each(texts),
        _ => Ok(texts),
    }
}

/// The longest span in parentheses a Japanese transcript leaves unsaid, in characters.
const UNSAID: usize = 10;

/// `text` (Japanese) without the short spans in parentheses that are not said, with those
/// spans: a direction or a speaker, as Japanese subtitles and interviews write them (`（笑）`,
/// `（拍手）`, `（田中）`), or a word's reading after it (`東京（とうきょう）`, said once).
/// Full-width parentheses are read as `(` and `)` ([`crate::script::spoken`] folds them); a
/// span of more than ten characters, or one with a sentence's punctuation, is an aside, and
/// said.
#[must_use]
pub fn unsaid_parentheses(text: &str) -> (String, Vec<String>) {
    let width = |at: &str| at.chars().next().map_or(1, char::len_utf8);
    let (mut out, mut left) = (String::with_capacity(text.len()), Vec::new());
    let mut rest = text;
    while let Some(open) = rest.find(['(', '（']) {
        let after = open + width(&rest[open..]);
        let Some(close) = rest[after..].find([')', '）']).map(|c| after + c) else {
            break;
        };
        let end = close + width(&rest[close..]);
        let span = &rest[after..close];
        if span.trim().is_empty()
            || span.chars().count() > UNSAID
            || span.contains(['。', '、', '.', ',', '!', '?', '！', '？', '(', '（'])
        {
            out.push_str(&rest[..after]);
            rest = &rest[after..];
            continue;
        }
        out.push_str(&rest[..open]);
        left.push(rest[open..end].to_owned());
        rest = &rest[end..];
    }
    out.push_str(rest);
    (out, left)
}

/// [`Mecab::kana_each`] by `program`, with the dictionary in `dictionary` (MeCab's own when
/// `None`).
fn read_with(
    program: &Path,
    dictionary: Option<&Path>,
    texts: Vec<String>,
) -> Result<Vec<String>, ReadingError> {
    let kanji: Vec<&str> = texts
        .iter()
        .flat_map(|text| text.split('\n'))
        .filter(|l| has_kanji(l))
        .collect();
    if kanji.is_empty() {
        return Ok(texts);
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
    let mut read = |line: &str| -> Result<String, ReadingError> {
        if !has_kanji(line) {
            return Ok(line.to_owned());
        }
        let words = sentences.next().ok_or_else(|| {
            ReadingError::Failed("it answered fewer lines than it was given".into())
        })?;
        let said = line_said(line.trim_end_matches('\r'), words)?;
        match said.split_whitespace().find(|w| has_kanji(w)) {
            Some(unknown) => Err(ReadingError::Unknown(unknown.to_owned())),
            None => Ok(said),
        }
    };
    texts
        .iter()
        .map(|text| {
            let lines = text
                .split('\n')
                .map(&mut read)
                .collect::<Result<Vec<_>, _>>()?;
            Ok(lines.join("\n"))
        })
        .collect()
}

/// `line` said as MeCab's `words` (a word a line: form, tab, features) say, with the spaces
/// between them kept.
fn line_said(line: &str, words: &str) -> Result<String, ReadingError> {
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

/// The kana of the digits 1–9 (index 0 unused: a zero inside a number is not said).
const DIGITS: [&str; 10] = [
    "ゼロ",
    "イチ",
    "ニ",
    "サン",
    "ヨン",
    "ゴ",
    "ロク",
    "ナナ",
    "ハチ",
    "キュウ",
];

/// A number's spoken parts, in order: a digit (1–9) or a power of ten's name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Digit(u8),
    Ten,
    Hundred,
    Thousand,
    Man,
    Oku,
}

/// The parts `n` (under a trillion) is said in: 2024 "ni-sen ni-jū yon", 10,000 "ichi-man",
/// 1,000 "sen" (not "ichi-sen").
fn parts(n: u64) -> Vec<Part> {
    fn group(n: u64, out: &mut Vec<Part>) {
        for (unit, part) in [
            (1000, Part::Thousand),
            (100, Part::Hundred),
            (10, Part::Ten),
        ] {
            let d = (n / unit % 10) as u8;
            if d > 1 {
                out.push(Part::Digit(d));
            }
            if d > 0 {
                out.push(part);
            }
        }
        if !n.is_multiple_of(10) {
            out.push(Part::Digit((n % 10) as u8));
        }
    }
    let mut out = Vec::new();
    for (unit, part) in [
        (100_000_000, Some(Part::Oku)),
        (10_000, Some(Part::Man)),
        (1, None),
    ] {
        let g = n / unit % 10_000;
        if g == 0 {
            continue;
        }
        group(g, &mut out);
        out.extend(part);
    }
    out
}

/// How a counter's sound follows the number's last part ("ip-pon", "san-bon", "rop-pun").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sound {
    /// No change (枚 "mai", 台 "dai", 年 "nen").
    Plain,
    /// A counter in h (本 "hon", 匹 "hiki", 杯 "hai"): "p" after a doubled 1, 6, 8, 10, 100;
    /// "b" after 3 and a thousand.
    H,
    /// 分 "fun": "p" after a doubled 1, 6, 8, 10, 100 and after 3 and 4.
    Fun,
    /// A counter in k: the number's 1, 6, 8, 10, 100 doubled ("ik-ko", "rok-kai").
    K,
    /// A counter in k voiced after 3 (階 "san-gai", 軒 "san-gen").
    KVoiced,
    /// A counter in s, t, or p: 1, 8, 10 doubled ("is-satsu", "hat-tō", "jup-pāsento").
    S,
}

/// Japanese counters after a number, one a line: the ways it is written (`/` between), how it
/// is said, how its sound follows the number ([`Sound`]: plain, h, fun, k, k-voiced, s), then
/// a last digit said otherwise before it (`4=ヨ`: 4時 "yo-ji", 14時 "jū-yo-ji"), and whole
/// numbers said otherwise (`1:ヒトリ`; `days`: the days of the month said in native numbers,
/// 2日 "futsuka" … 24日). A counter in Latin letters is a unit after digits (100m).
const COUNTERS: &str = "\
時間 ジカン plain 4=ヨ 7=シチ 9=ク
時 ジ plain 4=ヨ 7=シチ 9=ク
分間 フンカン fun
分 フン fun
秒 ビョウ plain
日間 ニチカン plain days
日 ニチ plain days
週間 シュウカン s
ヶ月/ヵ月/か月/カ月/ケ月/箇月 カゲツ k
月 ガツ plain 4=シ 7=シチ 9=ク
年間 ネンカン plain 4=ヨ
年 ネン plain 4=ヨ
歳/才 サイ s
人 ニン plain 4=ヨ 1:ヒトリ 2:フタリ
本 ホン h
匹 ヒキ h
杯 ハイ h
個 コ k
回 カイ k
階 カイ k-voiced
軒 ケン k-voiced
件 ケン k
曲 キョク k
冊 サツ s
頭 トウ s
点 テン s
章 ショウ s
% パーセント s
円 エン plain 4=ヨ
枚 マイ plain
台 ダイ plain
度 ド plain
番目 バンメ plain
番 バン plain
話 ワ plain
行 ギョウ plain
号 ゴウ plain
倍 バイ plain
つ ツ plain 1:ヒトツ 2:フタツ 3:ミッツ 4:ヨッツ 5:イツツ 6:ムッツ 7:ナナツ 8:ヤッツ 9:ココノツ
km キロメートル k
kg キログラム k
cm センチメートル s
mm ミリメートル plain
ml/mL ミリリットル plain
m メートル plain
g グラム plain
L リットル plain
";

/// The days of the month, and counted, said in native numbers (2日 "futsuka"): the table's
/// `days`.
const DAYS: &str = "2:フツカ 3:ミッカ 4:ヨッカ 5:イツカ 6:ムイカ 7:ナノカ 8:ヨウカ 9:ココノカ 10:トオカ 14:ジュウヨッカ 20:ハツカ 24:ニジュウヨッカ";

/// A counter of [`COUNTERS`].
#[derive(Debug)]
struct Counter {
    written: Vec<&'static str>,
    said: &'static str,
    sound: Sound,
    tails: Vec<(u8, &'static str)>,
    whole: Vec<(u64, &'static str)>,
}

/// [`COUNTERS`]' line `line`, or what is wrong with it.
fn counter(line: &'static str) -> Result<Counter, String> {
    let mut fields = line.split_whitespace();
    let (Some(written), Some(said), Some(sound)) = (fields.next(), fields.next(), fields.next())
    else {
        return Err(format!(
            "{line:?}: ways written, how said and how it sounds"
        ));
    };
    let sound = match sound {
        "plain" => Sound::Plain,
        "h" => Sound::H,
        "fun" => Sound::Fun,
        "k" => Sound::K,
        "k-voiced" => Sound::KVoiced,
        "s" => Sound::S,
        other => return Err(format!("{line:?}: no sound {other:?}")),
    };
    let mut counter = Counter {
        written: written.split('/').collect(),
        said,
        sound,
        tails: Vec::new(),
        whole: Vec::new(),
    };
    for field in fields.flat_map(|f| {
        if f == "days" {
            DAYS.split(' ').collect()
        } else {
            vec![f]
        }
    }) {
        let bad = || format!("{line:?}: {field:?} is neither 4=ヨ nor 1:ヒトリ");
        if let Some((digit, kana)) = field.split_once('=') {
            counter
                .tails
                .push((digit.parse().map_err(|_| bad())?, kana));
        } else if let Some((number, kana)) = field.split_once(':') {
            counter
                .whole
                .push((number.parse().map_err(|_| bad())?, kana));
        } else {
            return Err(bad());
        }
    }
    Ok(counter)
}

/// [`COUNTERS`], read once (a line that does not parse is logged and left out).
fn counters() -> &'static [Counter] {
    static READ: std::sync::OnceLock<Vec<Counter>> = std::sync::OnceLock::new();
    READ.get_or_init(|| {
        COUNTERS
            .lines()
            .filter_map(|line| {
                counter(line)
                    .map_err(|e| tracing::warn!("Japanese counters: {e}"))
                    .ok()
            })
            .collect()
    })
}

/// `n` said, in katakana, before `counter` ([`COUNTERS`]) or alone.
fn number_said(n: u64, counter: Option<&Counter>, after_month: bool) -> String {
    if n == 0 {
        return format!("ゼロ{}", counter.map_or("", |c| c.said));
    }
    if let Some(Counter { said, whole, .. }) = counter {
        if let Some((_, whole)) = whole.iter().find(|(m, _)| *m == n) {
            // The day counter's days: "futsuka-kan"; a count of people or things has none.
            return format!("{whole}{}", said.strip_prefix("ニチ").unwrap_or(""));
        }
        // The first of the month: "tsuitachi"; one day counted: "ichi-nichi".
        if *said == "ニチ" && n == 1 && after_month {
            return "ツイタチ".to_owned();
        }
    }
    let parts = parts(n);
    let mut out = String::new();
    for (k, part) in parts.iter().enumerate() {
        let (before, after) = (
            k.checked_sub(1).map(|b| parts[b]),
            parts.get(k + 1).copied(),
        );
        let last = after.is_none();
        out.push_str(match part {
            Part::Digit(d) => {
                let tail = counter
                    .filter(|_| last)
                    .and_then(|c| c.tails.iter().find(|(t, _)| t == d).map(|(_, said)| *said));
                match (d, after) {
                    _ if tail.is_some() => tail.unwrap_or_default(),
                    (3, Some(Part::Hundred)) => "サン",
                    (6, Some(Part::Hundred)) => "ロッ",
                    (8, Some(Part::Hundred | Part::Thousand)) => "ハッ",
                    _ => DIGITS[usize::from(*d)],
                }
            }
            Part::Ten => "ジュウ",
            Part::Hundred => match before {
                Some(Part::Digit(3)) => "ビャク",
                Some(Part::Digit(6 | 8)) => "ピャク",
                _ => "ヒャク",
            },
            Part::Thousand => match (before, after) {
                (Some(Part::Digit(3)), _) => "ゼン",
                (Some(Part::Digit(_)), _) => "セン",
                (_, Some(Part::Man | Part::Oku)) => "イッセン",
                _ => "セン",
            },
            Part::Man => "マン",
            Part::Oku => "オク",
        });
    }
    let Some(&Counter {
        said,
        sound,
        ref tails,
        ..
    }) = counter
    else {
        return out;
    };
    let last = *parts.last().unwrap_or(&Part::Man);
    if matches!(last, Part::Digit(d) if tails.iter().any(|(t, _)| *t == d)) {
        return out + said;
    }
    // The number's last sound doubled before the counter: "ichi" "it-", "jū" "jut-".
    let doubled = |out: String, also_six: bool| -> Option<String> {
        let stem = match last {
            Part::Digit(1) => out.strip_suffix("イチ")?.to_owned() + "イッ",
            Part::Digit(6) if also_six => out.strip_suffix("ロク")?.to_owned() + "ロッ",
            Part::Digit(8) => out.strip_suffix("ハチ")?.to_owned() + "ハッ",
            Part::Ten => out.strip_suffix("ジュウ")?.to_owned() + "ジュッ",
            Part::Hundred if also_six => out.strip_suffix("ャク")?.to_owned() + "ャッ",
            _ => return None,
        };
        Some(stem)
    };
    // The counter's first sound made "p" or "b" (ホン "pon", "bon"; ハイ "pai"; フン "pun"), or
    // voiced (カイ "gai").
    let voiced = |said: &str, semi: bool| -> String {
        const CHANGED: [(char, char, char); 7] = [
            ('ハ', 'パ', 'バ'),
            ('ヒ', 'ピ', 'ビ'),
            ('フ', 'プ', 'ブ'),
            ('ヘ', 'ペ', 'ベ'),
            ('ホ', 'ポ', 'ボ'),
            ('カ', 'ガ', 'ガ'),
            ('ケ', 'ゲ', 'ゲ'),
        ];
        let mut chars = said.chars();
        let first = chars.next().unwrap_or_default();
        let changed = CHANGED
            .iter()
            .find(|(from, _, _)| *from == first)
            .map_or(first, |&(_, p, b)| if semi { p } else { b });
        std::iter::once(changed).chain(chars).collect()
    };
    match sound {
        Sound::Plain => out + said,
        Sound::H | Sound::Fun => match doubled(out.clone(), true) {
            Some(stem) => stem + &voiced(said, true),
            None => match last {
                Part::Digit(3) if sound == Sound::H => out + &voiced(said, false),
                Part::Thousand if sound == Sound::H => out + &voiced(said, false),
                Part::Digit(3 | 4) if sound == Sound::Fun => out + &voiced(said, true),
                _ => out + said,
            },
        },
        Sound::K | Sound::KVoiced => match doubled(out.clone(), true) {
            Some(stem) => stem + said,
            None if sound == Sound::KVoiced && last == Part::Digit(3) => out + &voiced(said, false),
            None => out + said,
        },
        Sound::S => match doubled(out.clone(), false) {
            Some(stem) => stem + said,
            None => out + said,
        },
    }
}

/// The value of kanji numerals (`二千二十四`, `三`, `十五`, `二〇二四`), if `written` is one.
fn kanji_value(written: &[char]) -> Option<u64> {
    let digit = |c: char| {
        "〇一二三四五六七八九"
            .chars()
            .position(|d| d == c)
            .map(|d| d as u64)
    };
    // Written digit by digit, as years are: 二〇二四.
    if written.len() > 1 && written.iter().all(|&c| digit(c).is_some()) {
        return written
            .iter()
            .try_fold(0u64, |n, &c| n.checked_mul(10)?.checked_add(digit(c)?));
    }
    let (mut total, mut section, mut pending) = (0u64, 0u64, None::<u64>);
    for &c in written {
        if let Some(d) = digit(c) {
            if pending.is_some() {
                return None;
            }
            pending = Some(d);
            continue;
        }
        let unit = match c {
            '十' => 10,
            '百' => 100,
            '千' => 1000,
            '万' | '億' => {
                let big = if c == '万' { 10_000 } else { 100_000_000 };
                let group = section + pending.take().unwrap_or(0);
                total += group.max(1) * big;
                section = 0;
                continue;
            }
            _ => return None,
        };
        section += pending.take().unwrap_or(1) * unit;
    }
    Some(total + section + pending.unwrap_or(0)).filter(|&n| n < 1_000_000_000_000)
}

/// `text` (Japanese) with its numbers said as Japanese speakers say them, in katakana: with
/// their counters (`3本` "san-bon", `1人` "hitori", `5日` "itsuka", `6分` "rop-pun", `10%`
/// "jup-pāsento"), the months (`4月` "shi-gatsu") and the first of the month (`12月1日`
/// "…tsuitachi"), and alone (`2024` "ni-sen ni-jū yon", where eSpeak NG says "… shi"). A number in
/// kanji numerals is read only before a counter and not within a word (`三本`, not `統一`,
/// `三日月`, `十分` "enough").
#[must_use]
pub fn numbers_said(text: &str) -> String {
    let chars: Vec<char> = crate::script::number_marks_folded(text).chars().collect();
    let mut out = String::with_capacity(text.len() * 2);
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        let after_month = out.ends_with("ガツ") || out.ends_with('月');
        if c.is_ascii_digit() && (k == 0 || !chars[k - 1].is_ascii_alphanumeric()) {
            let Some((n, end)) = arabic(&chars, k) else {
                let end = crate::script::digits_end(&chars, k);
                out.extend(&chars[k..end]);
                k = end;
                continue;
            };
            // A unit in Latin letters is a counter (100m, 5kg); other letters make a name or a
            // code (3D, A4).
            let unit = counter_at(&chars, end).filter(|_| chars[end].is_ascii());
            let unit_ends = unit.is_none_or(|(_, len)| {
                chars
                    .get(end + len)
                    .is_none_or(|n| !n.is_ascii_alphanumeric())
            });
            if chars.get(end).is_some_and(|c| c.is_ascii_alphabetic())
                && (unit.is_none() || !unit_ends)
            {
                out.extend(&chars[k..end]);
                k = end;
                continue;
            }
            // Digits with a leading zero, a telephone number's (090-1234-5678, 007): digit by
            // digit, through its hyphens.
            let hyphened = |at: usize| {
                chars.get(at) == Some(&'-') && chars.get(at + 1).is_some_and(char::is_ascii_digit)
            };
            if chars[k] == '0' && end > k + 1 {
                let mut at = k;
                while at < chars.len() && (chars[at].is_ascii_digit() || hyphened(at)) {
                    match chars[at].to_digit(10) {
                        Some(d) => out.push_str(DIGITS[d as usize]),
                        None => out.push('、'),
                    }
                    at += 1;
                }
                k = at;
                continue;
            }
            // A sign before the number: ¥500 "go-hyaku en", -5 "mainasu go".
            if out.ends_with(['¥', '￥']) && counter_at(&chars, end).is_none() {
                out.pop();
                out.push_str(&number_said(n, counter_named("円"), false));
                k = end;
                continue;
            }
            // (As written: a hyphen after a number or a letter joins, 1939-1945, B-1.)
            let minus = k
                .checked_sub(1)
                .is_some_and(|b| chars[b] == '-' || chars[b] == '−')
                && !k
                    .checked_sub(2)
                    .is_some_and(|b| chars[b].is_ascii_alphanumeric());
            if minus && out.ends_with(['-', '−']) {
                out.pop();
                out.push_str("マイナス");
            }
            // A time of day, 10:30: "jū-ji san-jup-pun".
            let minutes = chars
                .get(end + 1..end + 3)
                .filter(|m| chars[end] == ':' && m.iter().all(char::is_ascii_digit))
                .filter(|_| n < 48 && !chars.get(end + 3).is_some_and(char::is_ascii_digit))
                .map(|m| {
                    m.iter()
                        .fold(0, |v, c| v * 10 + u64::from(c.to_digit(10).unwrap_or(0)))
                });
            if let Some(minutes) = minutes.filter(|&m| m < 60) {
                out.push_str(&number_said(n, counter_named("時"), false));
                if minutes > 0 {
                    out.push_str(&number_said(minutes, counter_named("分"), false));
                }
                k = end + 3;
                continue;
            }
            if chars.get(end) == Some(&'.') && chars.get(end + 1).is_some_and(char::is_ascii_digit)
            {
                let fraction_end = crate::script::digits_end(&chars, end + 1);
                out.push_str(&number_said(n, None, false));
                out.push_str("テン");
                for d in &chars[end + 1..fraction_end] {
                    out.push_str(DIGITS[d.to_digit(10).unwrap_or(0) as usize]);
                }
                k = fraction_end;
                continue;
            }
            let counter = counter_at(&chars, end);
            out.push_str(&number_said(n, counter.map(|c| c.0), after_month));
            k = end + counter.map_or(0, |c| c.1);
            continue;
        }
        if "〇一二三四五六七八九十百千万億".contains(c) && (k == 0 || !is_kanji(chars[k - 1]))
        {
            let mut end = k;
            while chars
                .get(end)
                .is_some_and(|&c| "〇一二三四五六七八九十百千万億".contains(c))
            {
                end += 1;
            }
            let counter = counter_at(&chars, end).filter(|&(counter, len)| {
                // A counter a word goes on from (三日月, 一本化) is not one here; 十分 is
                // "enough" as often as ten minutes; units in Latin letters follow digits.
                let next = end + len;
                let word_goes_on = chars.get(next).is_some_and(|&n| is_kanji(n));
                let enough = chars[k..end] == ['十'] && counter.said == "フン";
                !word_goes_on && !enough && !chars[end].is_ascii()
            });
            if let (Some((counter, len)), Some(n)) = (counter, kanji_value(&chars[k..end])) {
                out.push_str(&number_said(n, Some(counter), after_month));
                k = end + len;
                continue;
            }
            out.extend(&chars[k..end]);
            k = end;
            continue;
        }
        out.push(c);
        k += 1;
    }
    out
}

/// The number in digits at `k` (`2024`, `1,000`, `3万5000`: thousands' commas, and the ten
/// thousands and hundred millions written in kanji), with where it ends; `None` past a
/// trillion.
fn arabic(chars: &[char], k: usize) -> Option<(u64, usize)> {
    let (mut total, mut at) = (0u64, k);
    loop {
        let mut end = at;
        let mut digits = String::new();
        while let Some(&c) = chars.get(end) {
            let grouped = c == ','
                && !digits.is_empty()
                && chars
                    .get(end + 1..end + 4)
                    .is_some_and(|g| g.iter().all(char::is_ascii_digit))
                && chars.get(end + 4).is_none_or(|c| !c.is_ascii_digit());
            if c.is_ascii_digit() {
                digits.push(c);
            } else if !grouped {
                break;
            }
            end += 1;
        }
        if digits.is_empty() {
            return (at > k).then_some((total, at));
        }
        let n: u64 = digits.parse().ok()?;
        let unit = match chars.get(end) {
            Some('億') => 100_000_000,
            Some('万') => 10_000,
            _ => {
                let total = total.checked_add(n)?;
                return (total < 1_000_000_000_000).then_some((total, end));
            }
        };
        total = total.checked_add(n.checked_mul(unit)?)?;
        at = end + 1;
        if !chars.get(at).is_some_and(char::is_ascii_digit) {
            return (total < 1_000_000_000_000).then_some((total, at));
        }
    }
}

/// The counter written `written`.
fn counter_named(written: &str) -> Option<&'static Counter> {
    counters().iter().find(|c| c.written.contains(&written))
}

/// The counter written at `at`, if one is (the longest way written that is there: 時間 before
/// 時), with how many characters it takes.
fn counter_at(chars: &[char], at: usize) -> Option<(&'static Counter, usize)> {
    counters()
        .iter()
        .flat_map(|c| {
            c.written
                .iter()
                .filter_map(move |w| Some((c, crate::script::written_at(chars, at, w)?)))
        })
        .max_by_key(|(_, length)| *length)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_are_said_as_the_dictionary_pronounces_them_with_their_spaces() {
        let words = "今日\t名詞,副詞可能,*,*,*,*,今日,キョウ,キョー\nは\t助詞,係助詞,*,*,*,*,は,ハ,ワ\nABC\t名詞,一般,*,*,*,*,*\n3\t名詞,数,*,*,*,*,*\n時\t名詞,接尾,助数詞,*,*,*,時,ジ,ジ\n";
        assert_eq!(
            line_said("今日は ABC 3時", words).unwrap(),
            "キョーワ ABC 3ジ"
        );
        assert!(matches!(
            line_said("x", "no tab"),
            Err(ReadingError::Failed(_))
        ));
    }

    #[test]
    fn numbers_are_said_with_their_counters_as_speakers_say_them() {
        for (written, said) in [
            ("2024", "ニセンニジュウヨン"),
            ("1,000円", "センエン"),
            ("300円", "サンビャクエン"),
            ("600", "ロッピャク"),
            ("8000", "ハッセン"),
            ("3000", "サンゼン"),
            ("10000", "イチマン"),
            ("1億", "イチオク"),
            ("3万5000円", "サンマンゴセンエン"),
            ("10000000", "イッセンマン"),
            ("3本", "サンボン"),
            ("1本", "イッポン"),
            ("6本", "ロッポン"),
            ("10本", "ジュッポン"),
            ("100本", "ヒャッポン"),
            ("4本", "ヨンホン"),
            ("21本", "ニジュウイッポン"),
            ("3杯", "サンバイ"),
            ("1匹", "イッピキ"),
            ("1分", "イップン"),
            ("3分", "サンプン"),
            ("4分", "ヨンプン"),
            ("5分", "ゴフン"),
            ("30分間", "サンジュップンカン"),
            ("1人", "ヒトリ"),
            ("2人", "フタリ"),
            ("4人", "ヨニン"),
            ("11人", "ジュウイチニン"),
            ("4時", "ヨジ"),
            ("9時", "クジ"),
            ("14時", "ジュウヨジ"),
            ("2時間", "ニジカン"),
            ("10:30", "ジュウジサンジュップン"),
            ("7:00", "シチジ"),
            ("4月", "シガツ"),
            ("12月1日", "ジュウニガツツイタチ"),
            ("1日", "イチニチ"),
            ("5日", "イツカ"),
            ("20日", "ハツカ"),
            ("24日", "ニジュウヨッカ"),
            ("3日間", "ミッカカン"),
            ("3ヶ月", "サンカゲツ"),
            ("6ヶ月", "ロッカゲツ"),
            ("1回", "イッカイ"),
            ("3階", "サンガイ"),
            ("8個", "ハッコ"),
            ("1冊", "イッサツ"),
            ("10歳", "ジュッサイ"),
            ("8%", "ハッパーセント"),
            ("3.5", "サンテンゴ"),
            ("3つ", "ミッツ"),
            ("三本", "サンボン"),
            ("二人", "フタリ"),
            ("八百円", "ハッピャクエン"),
            ("二〇二四年", "ニセンニジュウヨネン"),
            ("¥1,980", "センキュウヒャクハチジュウエン"),
            ("-5度", "マイナスゴド"),
            ("−5", "マイナスゴ"),
            (
                "090-1234-5678",
                "ゼロキュウゼロ、イチニサンヨン、ゴロクナナハチ",
            ),
            ("100m", "ヒャクメートル"),
            ("5kg", "ゴキログラム"),
            ("1km", "イッキロメートル"),
            ("第3章", "第サンショウ"),
            (
                "1939-1945",
                "センキュウヒャクサンジュウキュウ-センキュウヒャクヨンジュウゴ",
            ),
        ] {
            assert_eq!(numbers_said(written), said, "{written}");
        }
        // Kanji numerals within a word, or whose counter a word goes on from, are words.
        for word in [
            "統一",
            "三日月",
            "一本化",
            "十分",
            "一緒",
            "第三回",
            "MP3",
            "A4",
        ] {
            assert_eq!(numbers_said(word), word);
        }
        assert_eq!(
            numbers_said("りんごを3つと、ペンを1本。"),
            "りんごをミッツと、ペンをイッポン。"
        );
    }

    proptest::proptest! {
        /// Whatever is typed, the numbers' reading ends (no panic, on any character boundary),
        /// and leaves text without digits or kanji numerals as it was.
        #[test]
        fn any_text_is_read_without_a_panic(
            typed in "[0-9,.:%万億〇一二三四五六七八九十百千本人日月時分つ年円ヶかa-zあ ()（）、]{0,60}",
        ) {
            let _ = numbers_said(&typed);
            let _ = unsaid_parentheses(&typed);
        }

        #[test]
        fn text_without_numbers_is_left_alone(typed in "[a-zあ-んア-ン本人日月時分 、。]{0,40}") {
            proptest::prop_assert_eq!(numbers_said(&typed), typed);
        }
    }

    #[test]
    fn every_counter_line_parses_and_a_malformed_one_is_named() {
        assert_eq!(counters().len(), COUNTERS.lines().count());
        for line in COUNTERS.lines() {
            counter(line).unwrap();
        }
        for bad in [
            "本 ホン",
            "本 ホン loud",
            "本 ホン h 4-ヨ",
            "本 ホン h x=ヨ",
        ] {
            let e = counter(bad).unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
    }

    #[test]
    fn short_spans_in_parentheses_are_unsaid_and_asides_said() {
        for (typed, said, left) in [
            ("そうですね（笑）", "そうですね", vec!["（笑）"]),
            ("(拍手) ありがとう", " ありがとう", vec!["(拍手)"]),
            (
                "東京（とうきょう）へ行く",
                "東京へ行く",
                vec!["（とうきょう）"],
            ),
            ("A(1)とB(2)", "AとB", vec!["(1)", "(2)"]),
            (
                "彼は（たぶん、疲れていたので）帰った",
                "彼は（たぶん、疲れていたので）帰った",
                vec![],
            ),
            (
                "（これはとても長い説明の文章です）",
                "（これはとても長い説明の文章です）",
                vec![],
            ),
            ("()と( )と(閉じない", "()と( )と(閉じない", vec![]),
            ("((笑))", "()", vec!["(笑)"]),
        ] {
            assert_eq!(
                unsaid_parentheses(typed),
                (
                    said.to_owned(),
                    left.iter().map(|s| s.to_string()).collect::<Vec<_>>()
                ),
                "{typed}"
            );
        }
    }

    #[test]
    fn kana_alone_needs_no_mecab_and_a_missing_one_is_named() {
        let missing = Path::new("/nonexistent/mecab");
        assert_eq!(
            read_with(missing, None, vec!["きょうは\nいい天気".into()]).unwrap_err(),
            ReadingError::NoMecab
        );
        assert_eq!(
            read_with(missing, None, vec!["きょうは、ABC".into()]).unwrap(),
            ["きょうは、ABC"]
        );
        assert!(has_kanji("毎朝、母と") && has_kanji("人々") && has_kanji("𠮷"));
        assert!(!has_kanji("まいあさ、パン、ｱｲ、한국어, 1985"));
    }
}
