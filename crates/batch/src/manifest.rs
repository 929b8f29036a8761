//! The manifest: one row per job, as JSON Lines or a sheet (CSV), checked row by row before
//! any work starts.
//!
//! A JSON Lines row is an object:
//!
//! ```json
//! {"id": "hero_0001", "kind": "lipsync", "speech": "audio/hero_0001.wav",
//!  "text": "Over here!", "language": "en-us", "character": "hero.vrm",
//!  "outputs": ["out/hero_0001.glb", "out/hero_0001.json"], "options": {"face": true}}
//! ```
//!
//! A sheet (CSV, or cells separated by `;` or tabs as spreadsheets save them where a comma is
//! the decimal point, and as their "Unicode text") has a header naming the same fields;
//! `outputs` holds the outputs separated by `;`, and every column that is not a field is an
//! option of the row's command (an empty cell gives none; TRUE or FALSE, in any case or the
//! spreadsheet's language, a switch). Paths are relative to the manifest's folder. A row's
//! problem is the row's: it is named with its line and field, and the other rows still run;
//! only a manifest that cannot be read at all stops the batch.

use std::collections::{BTreeMap, HashMap};
use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};

use faceanim_files::text::{Accept, decode};
use serde_json::Value;

use crate::BatchError;

/// The largest manifest read, in bytes (a million rows of a few hundred bytes).
pub const MAX_MANIFEST_BYTES: u64 = 512 << 20;

/// What a row asks faceanim to do: one of its commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// `faceanim lipsync`: speech drives the mouth.
    Lipsync,
    /// `faceanim track`: a video, photos or a folder of images drive the face.
    Track,
    /// `faceanim generate-shapes`: ARKit's shapes made on a head without them.
    GenerateShapes,
}

impl Kind {
    /// Every kind, in the order the documentation lists them.
    pub const ALL: [Kind; 3] = [Kind::Lipsync, Kind::Track, Kind::GenerateShapes];

    /// The kind's name in a manifest, which is also its command's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kind::Lipsync => "lipsync",
            Kind::Track => "track",
            Kind::GenerateShapes => "generate-shapes",
        }
    }

    fn from_name(name: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The fields a row of this kind may have (besides `id`, `kind`, `outputs` and `options`);
    /// the first is required and is the command's positional input.
    #[must_use]
    pub fn fields(self) -> &'static [Field] {
        match self {
            Kind::Lipsync => &[
                Field::Speech,
                Field::Character,
                Field::Text,
                Field::Transcript,
                Field::Language,
                Field::Adapter,
                Field::VisemeTable,
            ],
            Kind::Track => &[
                Field::Video,
                Field::Character,
                Field::Adapter,
                Field::Retarget,
            ],
            Kind::GenerateShapes => &[Field::Character, Field::Template],
        }
    }

    /// Options a row may not give because they name files the batch must know of: inputs are
    /// fields and outputs are `outputs`, so that both are hashed and written once.
    fn reserved_options(self) -> &'static [&'static str] {
        match self {
            Kind::Lipsync => &["output", "clip", "o"],
            Kind::Track => &["output", "session", "raw", "o"],
            Kind::GenerateShapes => &["output", "o"],
        }
    }

    /// How many outputs a row of this kind writes at most.
    fn max_outputs(self) -> usize {
        match self {
            Kind::GenerateShapes => 1,
            Kind::Lipsync | Kind::Track => 16,
        }
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A field of a row besides its id, kind, outputs and options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Field {
    /// The speech to lip-sync (a file).
    Speech,
    /// The video, photo or folder of images to track.
    Video,
    /// The character (a file or an OBJ folder; the built-in head when left out).
    Character,
    /// What was said, as words.
    Text,
    /// What was said, as a text file.
    Transcript,
    /// The language spoken (eSpeak NG's name, a voice of it, a BCP 47 tag or a locale:
    /// `en-us`, `en-us+f3`, `ja-JP`, `pt_BR`).
    Language,
    /// The character's adapter.
    Adapter,
    /// The character's retarget map.
    Retarget,
    /// A viseme table (JSON).
    VisemeTable,
    /// generate-shapes' template: `default`, `stylised` or a file.
    Template,
}

/// Every field with its name in a manifest.
const FIELD_NAMES: [(Field, &str); 10] = [
    (Field::Speech, "speech"),
    (Field::Video, "video"),
    (Field::Character, "character"),
    (Field::Text, "text"),
    (Field::Transcript, "transcript"),
    (Field::Language, "language"),
    (Field::Adapter, "adapter"),
    (Field::Retarget, "retarget"),
    (Field::VisemeTable, "viseme_table"),
    (Field::Template, "template"),
];

impl Field {
    /// The field's name in a manifest.
    #[must_use]
    pub fn name(self) -> &'static str {
        FIELD_NAMES
            .iter()
            .find(|(field, _)| *field == self)
            .map_or("", |(_, name)| name)
    }

    fn from_name(name: &str) -> Option<Field> {
        FIELD_NAMES
            .iter()
            .find(|(_, n)| *n == name)
            .map(|(field, _)| *field)
    }

    /// Whether the field names a file (or folder) whose contents the output depends on.
    #[must_use]
    pub fn is_path(self, value: &str) -> bool {
        match self {
            Field::Text | Field::Language => false,
            Field::Template => !matches!(value, "default" | "stylised"),
            _ => true,
        }
    }

    /// The command's flag for the field; `None` for the positional input.
    fn flag(self, kind: Kind) -> Option<&'static str> {
        match (self, kind) {
            (Field::Speech | Field::Video, _) | (Field::Character, Kind::GenerateShapes) => None,
            (Field::Character, _) => Some("--character"),
            // The command reads a file given to --text (a value without spaces that names one).
            (Field::Text | Field::Transcript, _) => Some("--text"),
            (Field::Language, _) => Some("--language"),
            (Field::Adapter, _) => Some("--adapter"),
            (Field::Retarget, _) => Some("--retarget"),
            (Field::VisemeTable, _) => Some("--viseme-table"),
            (Field::Template, _) => Some("--template"),
        }
    }
}

/// An option of the row's command, as the manifest gives it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(untagged)]
pub enum OptionValue {
    /// A switch, given when true.
    Flag(bool),
    /// One value.
    Value(String),
    /// The option given once per value.
    List(Vec<String>),
}

/// One job of the manifest, checked.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Row {
    /// The row's place among the rows (0-based): what `--index` and `JOB_COMPLETION_INDEX`
    /// name.
    pub index: usize,
    /// The manifest line it starts on (1-based).
    pub line: usize,
    /// The row's id, unique in the manifest.
    pub id: String,
    /// What it asks for.
    pub kind: Kind,
    /// Its fields, as written.
    pub fields: BTreeMap<&'static str, String>,
    /// Its outputs, as written (relative to the manifest's folder).
    pub outputs: Vec<String>,
    /// Options passed to the command, by their flag's name.
    pub options: BTreeMap<String, OptionValue>,
    /// The manifest's folder, which relative paths start from.
    #[serde(skip)]
    pub base: PathBuf,
}

impl Row {
    /// The value of `field`, when the row gives it.
    #[must_use]
    pub fn field(&self, field: Field) -> Option<&str> {
        self.fields.get(field.name()).map(String::as_str)
    }

    /// `path` (as written in the manifest) from the manifest's folder. A manifest written on
    /// Windows separates folders with `\` (`audio\line_0001.wav`); where `\` is no separator,
    /// such a path is read with `/` unless a file is named with the `\` itself, so that a sheet
    /// made on Windows runs on Linux workers, inputs found and outputs written in their folders
    /// (not beside the manifest under names holding `\`).
    #[must_use]
    pub fn resolve(&self, path: &str) -> PathBuf {
        resolve(&self.base, path)
    }

    /// The files the row reads, each with the field that names it, from the manifest's folder.
    #[must_use]
    pub fn input_files(&self) -> Vec<(Field, PathBuf)> {
        self.kind
            .fields()
            .iter()
            .filter_map(|&field| {
                let value = self.field(field)?;
                field.is_path(value).then(|| (field, self.resolve(value)))
            })
            .collect()
    }

    /// The outputs, from the manifest's folder.
    #[must_use]
    pub fn output_paths(&self) -> Vec<PathBuf> {
        self.outputs.iter().map(|o| self.resolve(o)).collect()
    }

    /// The command line that runs the row (without the program's name), writing to `outputs`
    /// (the row's outputs, or where they are staged): the kind's subcommand, its positional
    /// input, a flag per field, `-o` per output, then the options.
    #[must_use]
    pub fn command(&self, outputs: &[PathBuf]) -> Vec<OsString> {
        let mut args: Vec<OsString> = vec![self.kind.name().into()];
        for &field in self.kind.fields() {
            let Some(value) = self.field(field) else {
                continue;
            };
            let value: OsString = if field.is_path(value) {
                self.resolve(value).into()
            } else {
                value.into()
            };
            match field.flag(self.kind) {
                None => args.push(value),
                Some(flag) => {
                    args.push(flag.into());
                    args.push(value);
                }
            }
        }
        for output in outputs {
            args.push("-o".into());
            args.push(output.into());
        }
        for (name, value) in &self.options {
            let flag = format!("--{name}");
            match value {
                OptionValue::Flag(true) => args.push(flag.into()),
                OptionValue::Flag(false) => {}
                OptionValue::Value(v) => {
                    args.push(flag.into());
                    args.push(v.into());
                }
                OptionValue::List(values) => {
                    for v in values {
                        args.push(flag.clone().into());
                        args.push(v.into());
                    }
                }
            }
        }
        args
    }
}

/// Why a row cannot run: its line, the field at fault when there is one, and the problem.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error, serde::Serialize)]
#[error("line {line}{}: {problem}", field.as_ref().map(|f| format!(", field `{f}`")).unwrap_or_default())]
pub struct RowError {
    /// The manifest line the row starts on.
    pub line: usize,
    /// The field at fault.
    pub field: Option<String>,
    /// What is wrong.
    pub problem: String,
}

/// A row of the manifest: checked, or why not.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The row's place among the rows (0-based).
    pub index: usize,
    /// The line it starts on.
    pub line: usize,
    /// Its id, when it has a usable one.
    pub id: Option<String>,
    /// The row, or its first problem.
    pub row: Result<Row, RowError>,
}

/// A manifest read and checked.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// The manifest file.
    pub path: PathBuf,
    /// Its rows, in order.
    pub entries: Vec<Entry>,
    /// The legacy code page a sheet that is not Unicode was read in, guessed from its
    /// bytes ([`faceanim_files::text`]): worth telling the user.
    pub guessed_encoding: Option<&'static str>,
}

impl Manifest {
    /// Reads and checks the manifest at `path`: a sheet when its name ends in `.csv`, `.tsv` or
    /// `.tab` (cells separated by commas, `;` or tabs, as spreadsheets save them in every
    /// language), JSON Lines when it ends in `.jsonl`, `.ndjson` or `.json`, and otherwise (a
    /// spreadsheet's "Unicode text" `.txt`) JSON Lines when its first line is an object, a
    /// sheet when not. Every row is checked (fields, values, input files present, ids and
    /// outputs unique); a bad row stays in [`Manifest::entries`] with its problem.
    ///
    /// # Errors
    /// [`BatchError`] when the file cannot be read, is not text (JSON Lines: not UTF-8 or
    /// UTF-16; a sheet: nor a legacy code page), has no rows, or (a sheet) has no usable
    /// header.
    pub fn read(path: &Path) -> Result<Manifest, BatchError> {
        let bytes =
            faceanim_files::read_at_most(path, MAX_MANIFEST_BYTES).map_err(|e| match e {
                faceanim_files::FileError::Io { source, .. } => BatchError::io(path, source),
                faceanim_files::FileError::TooLarge {
                    size: Some(size), ..
                } => BatchError::manifest(
                    path,
                    format!("{size} bytes; a manifest is at most {MAX_MANIFEST_BYTES} bytes"),
                ),
                _ => BatchError::manifest(
                    path,
                    format!("more than a manifest's {MAX_MANIFEST_BYTES} bytes"),
                ),
            })?;
        // A manifest named without a folder: paths in it are the working folder's, as given.
        let base = path.parent().unwrap_or(Path::new("")).to_owned();
        let named = Layout::named(path);
        // Spreadsheets write sheets with a byte-order mark (Excel's "CSV UTF-8"), in UTF-16
        // (its "Unicode text"), or in the system's code page (its "CSV": Shift_JIS on a
        // Japanese Windows); JSON is Unicode.
        let accept = if named == Some(Layout::JsonLines) {
            Accept::Unicode
        } else {
            Accept::Legacy { language: None }
        };
        let unreadable =
            |e: faceanim_files::text::TextError| BatchError::manifest(path, e.to_string());
        let text = decode(&bytes, accept).map_err(unreadable)?;
        let layout = named.unwrap_or(if text.text.trim_start().starts_with('{') {
            Layout::JsonLines
        } else {
            Layout::Sheet
        });
        if layout == Layout::JsonLines && text.guessed {
            decode(&bytes, Accept::Unicode).map_err(unreadable)?;
        }
        let raw = match layout {
            Layout::Sheet => {
                sheet_rows(&text.text).map_err(|problem| BatchError::manifest(path, problem))?
            }
            Layout::JsonLines => jsonl_rows(&text.text),
        };
        if raw.is_empty() {
            return Err(BatchError::manifest(path, "has no rows".to_owned()));
        }
        Ok(Manifest {
            path: path.to_owned(),
            entries: check_rows(raw, &base),
            guessed_encoding: text.guessed.then_some(text.encoding),
        })
    }

    /// The checked rows.
    pub fn rows(&self) -> impl Iterator<Item = &Row> {
        self.entries.iter().filter_map(|e| e.row.as_ref().ok())
    }

    /// Marks the row at `index` bad (a check only the caller can make, such as an output's
    /// format).
    pub fn reject(&mut self, index: usize, field: &str, problem: String) {
        if let Some(entry) = self.entries.get_mut(index)
            && entry.row.is_ok()
        {
            entry.row = Err(RowError {
                line: entry.line,
                field: Some(field.to_owned()),
                problem,
            });
        }
    }
}

/// How a manifest's rows are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Layout {
    /// One JSON object a line.
    JsonLines,
    /// A header and rows of cells: CSV, or cells separated by `;` or tabs.
    Sheet,
}

impl Layout {
    /// The layout the file's name says, if it says one.
    fn named(path: &Path) -> Option<Layout> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "csv" | "tsv" | "tab" => Some(Layout::Sheet),
            "jsonl" | "ndjson" | "json" => Some(Layout::JsonLines),
            _ => None,
        }
    }
}

/// A row before its check: its line and its values by name.
struct RawRow {
    line: usize,
    values: Result<Vec<(String, Value)>, RowError>,
    /// From a sheet, whose columns that are not fields are options (a JSON row gives
    /// them in `options`, so a stray key of it is a mistake).
    csv: bool,
}

fn jsonl_rows(text: &str) -> Vec<RawRow> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            let line = k + 1;
            let values = match serde_json::from_str::<Value>(l) {
                Ok(Value::Object(map)) => Ok(map
                    .into_iter()
                    .map(|(k, v)| match (k.as_str(), whole_number(&v)) {
                        ("id", Some(id)) => (k, Value::String(id)),
                        _ => (k, v),
                    })
                    .collect()),
                Ok(_) => Err(RowError {
                    line,
                    field: None,
                    problem: "a row is a JSON object".to_owned(),
                }),
                Err(e) => Err(RowError {
                    line,
                    field: None,
                    problem: format!("not JSON: {e}"),
                }),
            };
            RawRow {
                line,
                values,
                csv: false,
            }
        })
        .collect()
}

/// A JSON number that is a whole number, as its digits: dataframe libraries write an id column
/// of numbers so (pandas' `to_json`, `1`; `1.0` when the column has an empty cell, which makes
/// it a column of floats). `None` for anything else.
fn whole_number(value: &Value) -> Option<String> {
    let Value::Number(n) = value else {
        return None;
    };
    if let Some(k) = n.as_i64() {
        return Some(k.to_string());
    }
    if let Some(k) = n.as_u64() {
        return Some(k.to_string());
    }
    // A float stands for a whole number exactly up to 2^53.
    let f = n.as_f64()?;
    (f.fract() == 0.0 && f.abs() <= 9_007_199_254_740_992.0).then(|| format!("{f:.0}"))
}

/// The words spreadsheets write for a TRUE and a FALSE cell, in the languages of their menus
/// (Excel writes a sheet's switches in them: `WAHR` on a German Windows, `VRAI` on a French
/// one), read without regard to case.
const SWITCH_WORDS: [(&str, &str); 15] = [
    ("true", "false"),
    ("wahr", "falsch"),
    ("vrai", "faux"),
    ("verdadero", "falso"),
    ("vero", "falso"),
    ("verdadeiro", "falso"),
    ("waar", "onwaar"),
    ("sant", "falskt"),
    ("sand", "falsk"),
    ("sann", "usann"),
    ("tosi", "epätosi"),
    ("prawda", "fałsz"),
    ("pravda", "nepravda"),
    ("истина", "ложь"),
    ("doğru", "yanlış"),
];

/// How a sheet's cells are separated, and the line its header is on.
struct Separator {
    cell: char,
    header_line: usize,
}

impl Separator {
    /// Excel's `sep=;` line when the sheet starts with one (it is not a row); else, of `,`, `;`
    /// and tab, the one that cuts the header into the most names a manifest knows — `;` is
    /// what spreadsheets write where a comma is the decimal point (Excel's "CSV" in Germany,
    /// France, Spain, Russia, Brazil…), tab their "Unicode text" — and `,` when none does.
    fn of(text: &str) -> (Separator, &str) {
        // The first line without its end (`lines` takes a CR before the LF too).
        let first = text.lines().next().unwrap_or("");
        let mut given = first.chars();
        if given
            .by_ref()
            .take(4)
            .collect::<String>()
            .eq_ignore_ascii_case("sep=")
            && let (Some(cell), None) = (given.next(), given.next())
        {
            let rest = text.get(first.len()..).unwrap_or("");
            let rest = rest.strip_prefix('\r').unwrap_or(rest);
            let rest = rest.strip_prefix('\n').unwrap_or(rest);
            return (
                Separator {
                    cell,
                    header_line: 2,
                },
                rest,
            );
        }
        let known =
            |name: &str| names_a_field(&name.trim().trim_matches('"').trim().to_ascii_lowercase());
        let names = |cell: char| first.split(cell).filter(|n| known(n)).count();
        let cell = [',', ';', '\t']
            .into_iter()
            .fold((',', 0), |best, cell| {
                let n = names(cell);
                if n > best.1 { (cell, n) } else { best }
            })
            .0;
        (
            Separator {
                cell,
                header_line: 1,
            },
            text,
        )
    }
}

/// The rows of a sheet (CSV, RFC 4180, or cells separated by `;` or tabs: fields quoted with
/// `"`, quotes doubled inside), each cell under its header's name; empty cells are left out,
/// and so are rows with no cell filled and columns with no name and no cell filled (what
/// spreadsheets write for the blank rows and columns of a sheet's used range).
fn sheet_rows(text: &str) -> Result<Vec<RawRow>, String> {
    let (separator, text) = Separator::of(text);
    let records = sheet_records(text, &separator)?;
    let mut records = records.into_iter();
    let Some((header_line, header)) = records.next() else {
        return Ok(Vec::new());
    };
    // Names as the fields' and options' are written, whatever case a spreadsheet's header
    // gave them (`Speech`, `FPS`).
    let header: Vec<String> = header
        .into_iter()
        .map(|h| h.trim().to_ascii_lowercase())
        .collect();
    let mut seen = HashMap::new();
    for (k, name) in header.iter().enumerate() {
        if name.is_empty() {
            continue;
        }
        if let Some(first) = seen.insert(name.as_str(), k) {
            return Err(format!(
                "line {header_line}: column `{name}` is named twice (columns {} and {})",
                first + 1,
                k + 1
            ));
        }
    }
    for needed in ["id", "kind", "outputs"] {
        if !seen.contains_key(needed) {
            return Err(format!(
                "line {header_line}: the header has no `{needed}` column"
            ));
        }
    }
    // A row may end before columns that have no name (a header written with a separator
    // after its last name).
    let named = header
        .iter()
        .rposition(|h| !h.is_empty())
        .map_or(0, |k| k + 1);
    let records: Vec<(usize, Vec<String>)> = records.collect();
    let decimal_comma = decimal_comma(separator.cell, &header, &records);
    Ok(records
        .into_iter()
        .filter(|(_, cells)| cells.iter().any(|c| !c.trim().is_empty()))
        .map(|(line, cells)| {
            let values = if (named..=header.len()).contains(&cells.len()) {
                sheet_values(&header, cells, decimal_comma).map_err(|problem| RowError {
                    line,
                    field: None,
                    problem,
                })
            } else {
                Err(RowError {
                    line,
                    field: None,
                    problem: format!("{} cells for {} columns", cells.len(), header.len()),
                })
            };
            RawRow {
                line,
                values,
                csv: true,
            }
        })
        .collect())
}

/// A sheet row's values by name, as a JSON row would give them.
fn sheet_values(
    header: &[String],
    cells: Vec<String>,
    decimal_comma: bool,
) -> Result<Vec<(String, Value)>, String> {
    let mut values = Vec::new();
    for (k, (name, cell)) in header.iter().zip(cells).enumerate() {
        let cell = cell.trim();
        if cell.is_empty() {
            continue;
        }
        if name.is_empty() {
            return Err(format!(
                "column {} has no name in the header, but this row has `{cell}` in it",
                k + 1
            ));
        }
        values.push((name.clone(), sheet_value(name, cell, decimal_comma)));
    }
    Ok(values)
}

/// A sheet's cell as the value a JSON row would give: `outputs` split on `;`; in an option's
/// column a spreadsheet's TRUE or FALSE (in its language) is a switch, and in a sheet that
/// writes decimal commas ([`decimal_comma`]) a number with one (`29,97`) is that number
/// (`29.97`). A field's cell is its text as written.
fn sheet_value(column: &str, cell: &str, decimal_comma: bool) -> Value {
    if column == "outputs" {
        return Value::Array(
            cell.split(';')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| Value::String(s.to_owned()))
                .collect(),
        );
    }
    if names_a_field(column) {
        return Value::String(cell.to_owned());
    }
    let lower = cell.to_lowercase();
    if let Some(on) = SWITCH_WORDS.iter().find_map(|(yes, no)| {
        if lower == *yes {
            Some(true)
        } else if lower == *no {
            Some(false)
        } else {
            None
        }
    }) {
        return Value::Bool(on);
    }
    if decimal_comma && let Some(number) = with_decimal_point(cell) {
        return Value::String(number);
    }
    Value::String(cell.to_owned())
}

/// Whether a column's name is a row's field (`id`, `kind`, `outputs`, `options` or a
/// [`Field`]), not an option of its command.
fn names_a_field(name: &str) -> bool {
    matches!(name, "id" | "kind" | "outputs" | "options") || Field::from_name(name).is_some()
}

/// Whether a sheet writes numbers with a decimal comma. A sheet separated by `;` does (it is
/// what spreadsheets write where the comma is the decimal point). One separated by tabs (Excel's
/// "Unicode text", in whatever language the spreadsheet runs) does when its option cells show
/// it: a number with a comma and other than three digits after it (`29,97`; `1,500` could be a
/// thousand and a half), and no number with a decimal point. A CSV's commas are its separators.
fn decimal_comma(separator: char, header: &[String], records: &[(usize, Vec<String>)]) -> bool {
    match separator {
        ';' => true,
        '\t' => {
            let options = || {
                records.iter().flat_map(|(_, cells)| {
                    header
                        .iter()
                        .zip(cells)
                        .filter(|(name, _)| !name.is_empty() && !names_a_field(name))
                        .map(|(_, cell)| cell.trim())
                })
            };
            let point = options().any(|cell| decimal_number(cell, '.').is_some());
            let comma = options()
                .any(|cell| decimal_number(cell, ',').is_some_and(|fraction| fraction.len() != 3));
            comma && !point
        }
        _ => false,
    }
}

/// The digits after the decimal mark of a number written with `mark` (digits, the mark,
/// digits, and a sign before them).
fn decimal_number(cell: &str, mark: char) -> Option<&str> {
    let digits = cell.strip_prefix(['-', '+']).unwrap_or(cell);
    let (whole, fraction) = digits.split_once(mark)?;
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (all_digits(whole) && all_digits(fraction)).then_some(fraction)
}

/// `29,97` as `29.97`: digits, one comma, digits, and a sign before them.
fn with_decimal_point(cell: &str) -> Option<String> {
    decimal_number(cell, ',').map(|_| cell.replacen(',', ".", 1))
}

/// The records of a sheet's text, each with the line it starts on.
fn sheet_records(text: &str, separator: &Separator) -> Result<Vec<(usize, Vec<String>)>, String> {
    let mut records = Vec::new();
    let mut cells = Vec::new();
    let mut cell = String::new();
    let mut quoted = false;
    let mut line = separator.header_line;
    let mut start = line;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                cell.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => {
                if c == '\n' {
                    line += 1;
                }
                cell.push(c);
            }
            (false, '"') if cell.trim().is_empty() => {
                cell.clear();
                quoted = true;
            }
            (false, c) if c == separator.cell => cells.push(std::mem::take(&mut cell)),
            (false, '\r') if chars.peek() == Some(&'\n') => {}
            (false, '\n') => {
                cells.push(std::mem::take(&mut cell));
                records.push((start, std::mem::take(&mut cells)));
                line += 1;
                start = line;
            }
            (false, c) => cell.push(c),
        }
    }
    if quoted {
        return Err(format!("line {start}: a quoted cell is never closed"));
    }
    if !cell.is_empty() || !cells.is_empty() {
        cells.push(cell);
        records.push((start, cells));
    }
    Ok(records)
}

/// Checks every row, then what rows share: ids and outputs are each one row's.
fn check_rows(raw: Vec<RawRow>, base: &Path) -> Vec<Entry> {
    let mut ids: HashMap<String, usize> = HashMap::new();
    let mut outputs: HashMap<PathBuf, usize> = HashMap::new();
    raw.into_iter()
        .enumerate()
        .map(|(index, raw)| {
            let line = raw.line;
            let id = raw.values.as_ref().ok().and_then(|values| {
                values.iter().find_map(|(k, v)| match (k.as_str(), v) {
                    ("id", Value::String(id)) if valid_id(id) => Some(id.clone()),
                    _ => None,
                })
            });
            let row = raw
                .values
                .and_then(|values| check_row(index, line, values, raw.csv, base))
                .and_then(|row| {
                    let fail = |field: &str, problem: String| RowError {
                        line,
                        field: Some(field.to_owned()),
                        problem,
                    };
                    if let Some(first) = ids.get(&row.id) {
                        return Err(fail(
                            "id",
                            format!("`{}` is already the id of line {first}", row.id),
                        ));
                    }
                    for (path, written) in row.output_paths().into_iter().zip(&row.outputs) {
                        if let Some(first) = outputs.get(&normal(&path)) {
                            return Err(fail(
                                "outputs",
                                format!("{written} is already written by line {first}"),
                            ));
                        }
                    }
                    ids.insert(row.id.clone(), line);
                    for path in row.output_paths() {
                        outputs.insert(normal(&path), line);
                    }
                    Ok(row)
                });
            Entry {
                index,
                line,
                id,
                row,
            }
        })
        .collect()
}

/// `path` with `.` steps removed, so that `out/a.json` and `./out/a.json` are one output.
fn normal(path: &Path) -> PathBuf {
    path.components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect()
}

fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 128
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

fn check_row(
    index: usize,
    line: usize,
    values: Vec<(String, Value)>,
    csv: bool,
    base: &Path,
) -> Result<Row, RowError> {
    let fail = |field: &str, problem: String| RowError {
        line,
        field: Some(field.to_owned()),
        problem,
    };
    // A field given as null is not given: dataframe libraries (pandas' and Polars' JSON Lines)
    // write an empty cell so.
    let mut values: BTreeMap<String, Value> =
        values.into_iter().filter(|(_, v)| !v.is_null()).collect();
    let id = match values.remove("id") {
        Some(Value::String(id)) if valid_id(&id) => id,
        Some(Value::String(id)) => {
            return Err(fail(
                "id",
                format!(
                    "`{id}` is not an id: 1 to 128 letters, digits, `_`, `-` or `.` (it names files and logs)"
                ),
            ));
        }
        Some(other) => {
            return Err(fail(
                "id",
                format!("a string or a whole number, not {other}"),
            ));
        }
        None => return Err(fail("id", "missing: every row has an id".to_owned())),
    };
    let kinds = || {
        Kind::ALL
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let kind = match values.remove("kind") {
        Some(Value::String(name)) => Kind::from_name(&name)
            .ok_or_else(|| fail("kind", format!("`{name}` is not a kind: {}", kinds())))?,
        Some(other) => return Err(fail("kind", format!("a string, not {other}"))),
        None => return Err(fail("kind", format!("missing: one of {}", kinds()))),
    };
    let outputs = match values.remove("outputs") {
        Some(Value::String(one)) => vec![one],
        Some(Value::Array(many)) => many
            .into_iter()
            .map(|v| match v {
                Value::String(s) => Ok(s),
                other => Err(fail("outputs", format!("a path is a string, not {other}"))),
            })
            .collect::<Result<_, _>>()?,
        Some(other) => {
            return Err(fail(
                "outputs",
                format!("a path or a list of paths, not {other}"),
            ));
        }
        None => return Err(fail("outputs", "missing: what the row writes".to_owned())),
    };
    if outputs.is_empty() {
        return Err(fail(
            "outputs",
            "empty: the row must write something".to_owned(),
        ));
    }
    if outputs.len() > kind.max_outputs() {
        return Err(fail(
            "outputs",
            format!(
                "{} outputs; a {kind} row writes at most {}",
                outputs.len(),
                kind.max_outputs()
            ),
        ));
    }
    for output in &outputs {
        if output.trim().is_empty() || output == "-" || output.ends_with('/') {
            return Err(fail("outputs", format!("`{output}` does not name a file")));
        }
    }
    let options = match values.remove("options") {
        Some(Value::Object(map)) => map.into_iter().collect(),
        Some(other) => return Err(fail("options", format!("an object, not {other}"))),
        None => Vec::new(),
    };
    let mut fields = BTreeMap::new();
    let mut extra = Vec::new();
    for (name, value) in values {
        let Some(field) = Field::from_name(&name) else {
            extra.push((name, value));
            continue;
        };
        if !kind.fields().contains(&field) {
            return Err(fail(
                &name,
                format!(
                    "a {kind} row has no `{name}`; its fields: {}",
                    field_names(kind)
                ),
            ));
        }
        let Value::String(text) = value else {
            return Err(fail(&name, format!("a string, not {value}")));
        };
        if text.trim().is_empty() {
            return Err(fail(&name, "empty".to_owned()));
        }
        fields.insert(field.name(), text);
    }
    // JSON rows put options under `options`; a sheet's extra columns are options, a JSON row's
    // extra keys are mistakes.
    let mut all_options = options;
    for (name, value) in extra {
        if !csv {
            return Err(fail(
                &name,
                format!(
                    "not a field of a {kind} row ({}, outputs, options)",
                    field_names(kind)
                ),
            ));
        }
        all_options.push((name, value));
    }
    let required = kind.fields()[0];
    if !fields.contains_key(required.name()) {
        return Err(fail(
            required.name(),
            format!("missing: a {kind} row names its {}", required.name()),
        ));
    }
    if fields.contains_key("text") && fields.contains_key("transcript") {
        return Err(fail(
            "transcript",
            "give the words (`text`) or a file of them (`transcript`), not both".to_owned(),
        ));
    }
    if let Some(language) = fields.get("language")
        && !language
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_+.@".contains(c))
    {
        return Err(fail(
            "language",
            format!("`{language}` is not a language name (en-us, es, ja, …)"),
        ));
    }
    if let Some(text) = fields.get("text")
        && !text.contains(char::is_whitespace)
        && resolve(base, text).exists()
    {
        // The command reads a file given to --text: one word that names a file would be read.
        return Err(fail(
            "text",
            format!("`{text}` names a file: give it as `transcript`"),
        ));
    }
    let options = all_options
        .into_iter()
        .map(|(name, value)| option(kind, &name, value).map_err(|p| fail(&name, p)))
        .collect::<Result<BTreeMap<_, _>, _>>()?;
    let row = Row {
        index,
        line,
        id,
        kind,
        fields,
        outputs,
        options,
        base: base.to_owned(),
    };
    for (field, path) in row.input_files() {
        if !path.exists() {
            return Err(fail(
                field.name(),
                format!(
                    "{}: no such file{}",
                    path.display(),
                    if windows_absolute(row.field(field).unwrap_or("")) {
                        " (a path on a Windows machine: give it relative to the manifest's folder)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        // A user's file is never written over: no output may be one of the row's inputs.
        let same = |output: &Path| {
            normal(output) == normal(&path)
                || matches!((output.canonicalize(), path.canonicalize()), (Ok(a), Ok(b)) if a == b)
        };
        if let Some(written) = row.outputs.iter().find(|o| same(&row.resolve(o))) {
            return Err(fail(
                "outputs",
                format!(
                    "{written} is the row's {}: it would be written over",
                    field.name()
                ),
            ));
        }
    }
    Ok(row)
}

/// `path` from `base` ([`Row::resolve`]).
fn resolve(base: &Path, path: &str) -> PathBuf {
    let given = base.join(path);
    if std::path::MAIN_SEPARATOR == '\\' || !path.contains('\\') || given.exists() {
        return given;
    }
    base.join(path.replace('\\', "/"))
}

/// Whether `path` is a Windows machine's own (`C:\…`, `C:/…`, `\\server\…`), which no other
/// machine can open.
fn windows_absolute(path: &str) -> bool {
    let bytes = path.as_bytes();
    let drive = bytes.len() > 2
        && bytes[0].is_ascii_alphabetic()
        && bytes[1] == b':'
        && matches!(bytes[2], b'\\' | b'/');
    drive || path.starts_with("\\\\")
}

fn field_names(kind: Kind) -> String {
    kind.fields()
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// An option by its flag's name (`viseme_table` and `viseme-table` are one), its value checked.
fn option(kind: Kind, name: &str, value: Value) -> Result<(String, OptionValue), String> {
    let flag = name.replace('_', "-");
    if flag.is_empty()
        || !flag.starts_with(|c: char| c.is_ascii_lowercase())
        || !flag
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
    {
        return Err(format!("`{name}` is not an option's name"));
    }
    if kind.reserved_options().contains(&flag.as_str()) {
        return Err(format!(
            "`{name}` writes a file: name it in `outputs`, so that it is written once and recorded"
        ));
    }
    if Field::from_name(&flag.replace('-', "_")).is_some() {
        return Err(format!("`{name}` is a field, not an option"));
    }
    let scalar = |v: Value| match v {
        Value::String(s) => Ok(s),
        Value::Number(n) => Ok(n.to_string()),
        other => Err(format!("a string or a number, not {other}")),
    };
    let value = match value {
        Value::Bool(b) => OptionValue::Flag(b),
        Value::Null => OptionValue::Flag(false),
        Value::Array(items) => {
            OptionValue::List(items.into_iter().map(scalar).collect::<Result<_, _>>()?)
        }
        other => OptionValue::Value(scalar(other)?),
    };
    Ok((flag, value))
}
