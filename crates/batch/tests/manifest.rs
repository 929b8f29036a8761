//! The manifest's checks: every bad row named by its line and field, the others kept; CSV as
//! spreadsheets write it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

use std::path::Path;

use faceanim_batch::manifest::{Kind, Manifest, OptionValue};
use proptest::prelude::*;

/// A folder with a speech file and a transcript, and a manifest named `name` holding `text`.
fn manifest(name: &str, text: &str) -> (tempfile::TempDir, Manifest) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.wav"), b"RIFF").unwrap();
    std::fs::write(dir.path().join("words.txt"), b"Hello there").unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    let manifest = Manifest::read(&path).unwrap();
    (dir, manifest)
}

/// The problem of row `index`: (line, field, problem).
fn problem(manifest: &Manifest, index: usize) -> (usize, Option<String>, String) {
    let error = manifest.entries[index]
        .row
        .as_ref()
        .expect_err("the row should be refused");
    (error.line, error.field.clone(), error.problem.clone())
}

#[test]
fn every_bad_row_is_named_by_its_line_and_field_and_the_good_ones_kept() {
    let rows = [
        r#"{"id": "ok", "kind": "lipsync", "speech": "a.wav", "text": "Hi there", "outputs": ["o/ok.json"]}"#,
        r#"{"kind": "lipsync", "speech": "a.wav", "outputs": "o/1.json"}"#,
        r#"{"id": "k", "kind": "dance", "speech": "a.wav", "outputs": "o/2.json"}"#,
        r#"{"id": "s", "kind": "lipsync", "speach": "a.wav", "outputs": "o/3.json"}"#,
        r#"{"id": "v", "kind": "lipsync", "speech": "a.wav", "video": "a.wav", "outputs": "o/4.json"}"#,
        "",
        r#"{"id": "t", "kind": "lipsync", "speech": "a.wav", "text": "x y", "transcript": "words.txt", "outputs": "o/5.json"}"#,
        r#"{"id": "m", "kind": "lipsync", "speech": "gone.wav", "outputs": "o/6.json"}"#,
        r#"{"id": "o", "kind": "lipsync", "speech": "a.wav", "outputs": []}"#,
        r#"{"id": "d", "kind": "lipsync", "speech": "a.wav", "outputs": "./o/ok.json"}"#,
        r#"{"id": "ok", "kind": "lipsync", "speech": "a.wav", "outputs": "o/7.json"}"#,
        r#"{"id": "c", "kind": "lipsync", "speech": "a.wav", "outputs": "o/8.json", "options": {"clip": "x.json"}}"#,
        r#"{"id": "f", "kind": "lipsync", "speech": "a.wav", "outputs": "o/9.json", "options": {"character": "x.glb"}}"#,
        "not json",
        "[1, 2]",
        r#"{"id": "w", "kind": "lipsync", "speech": "a.wav", "text": "words.txt", "outputs": "o/10.json"}"#,
        r#"{"id": "sp ace", "kind": "lipsync", "speech": "a.wav", "outputs": "o/11.json"}"#,
        r#"{"id": "g", "kind": "generate-shapes", "character": "a.wav", "outputs": ["x.glb", "y.glb"]}"#,
        r#"{"id": "in", "kind": "generate-shapes", "character": "./a.wav", "outputs": "a.wav"}"#,
        r#"{"id": "ok2", "kind": "lipsync", "speech": "a.wav", "transcript": "words.txt", "language": "es", "outputs": "o/12.json", "options": {"fps": 60, "face": true, "recognise": "phones"}}"#,
    ];
    let (_dir, manifest) = manifest("lines.jsonl", &rows.join("\n"));
    // The blank line is no row: 19 rows, and each keeps the line it is on.
    assert_eq!(manifest.entries.len(), 19);
    let expected: [(usize, Option<&str>, &str); 17] = [
        (2, Some("id"), "missing"),
        (3, Some("kind"), "`dance` is not a kind"),
        (4, Some("speach"), "not a field of a lipsync row"),
        (5, Some("video"), "a lipsync row has no `video`"),
        (7, Some("transcript"), "not both"),
        (8, Some("speech"), "gone.wav: no such file"),
        (9, Some("outputs"), "empty"),
        (10, Some("outputs"), "already written by line 1"),
        (11, Some("id"), "already the id of line 1"),
        (12, Some("clip"), "name it in `outputs`"),
        (13, Some("character"), "is a field"),
        (14, None, "not JSON"),
        (15, None, "a JSON object"),
        (16, Some("text"), "give it as `transcript`"),
        (17, Some("id"), "not an id"),
        (18, Some("outputs"), "at most 1"),
        (
            19,
            Some("outputs"),
            "a.wav is the row's character: it would be written over",
        ),
    ];
    for (k, (line, field, words)) in expected.into_iter().enumerate() {
        let (got_line, got_field, got) = problem(&manifest, k + 1);
        assert_eq!(got_line, line, "{got}");
        assert_eq!(got_field.as_deref(), field, "line {line}: {got}");
        assert!(got.contains(words), "line {line}: {got}");
    }
    let good: Vec<_> = manifest.rows().map(|r| r.id.as_str()).collect();
    assert_eq!(good, ["ok", "ok2"]);
    let row = manifest.rows().nth(1).unwrap();
    assert_eq!((row.index, row.line, row.kind), (18, 20, Kind::Lipsync));
    assert_eq!(row.options["face"], OptionValue::Flag(true));
    // The command line: the speech, a flag per field, -o per output, the options.
    let command: Vec<String> = row
        .command(&[Path::new("staged.json").to_owned()])
        .into_iter()
        .map(|a| a.into_string().unwrap())
        .collect();
    let base = row.base.display().to_string();
    assert_eq!(
        command,
        [
            "lipsync".to_owned(),
            format!("{base}/a.wav"),
            "--text".to_owned(),
            format!("{base}/words.txt"),
            "--language".to_owned(),
            "es".to_owned(),
            "-o".to_owned(),
            "staged.json".to_owned(),
            "--face".to_owned(),
            "--fps".to_owned(),
            "60".to_owned(),
            "--recognise".to_owned(),
            "phones".to_owned(),
        ]
    );
}

#[test]
fn a_csv_manifest_reads_as_spreadsheets_write_it() {
    // As Excel writes "CSV UTF-8": a byte-order mark first, CRLF line ends.
    let text = "\u{feff}id,kind,speech,text,outputs,fps,face\r\n\
        a,lipsync,a.wav,\"Well, \"\"hello\"\" there\",o/a.json; o/a.csv,60,true\r\n\
        b,lipsync,a.wav,\"Two\nlines\",o/b.json,,\r\n\
        c,lipsync,a.wav,too,few\r\n\
        d,lipsync,,,o/d.json,,\r\n";
    let (_dir, manifest) = manifest("lines.csv", text);
    assert_eq!(manifest.entries.len(), 4);
    let a = manifest.entries[0].row.as_ref().unwrap();
    assert_eq!(
        a.field(faceanim_batch::manifest::Field::Text),
        Some("Well, \"hello\" there")
    );
    assert_eq!(a.outputs, ["o/a.json", "o/a.csv"]);
    assert_eq!(a.options["fps"], OptionValue::Value("60".to_owned()));
    assert_eq!(a.options["face"], OptionValue::Flag(true));
    let b = manifest.entries[1].row.as_ref().unwrap();
    assert!(b.options.is_empty(), "empty cells give no option");
    assert_eq!(b.line, 3);
    // A quoted cell over two lines: the next row starts on line 5.
    assert_eq!(
        problem(&manifest, 2),
        (5, None, "5 cells for 7 columns".to_owned())
    );
    assert_eq!(problem(&manifest, 3).1.as_deref(), Some("speech"));

    let dir = tempfile::tempdir().unwrap();
    for (text, words) in [
        ("id,kind\na,lipsync\n", "no `outputs` column"),
        ("id,kind,outputs,id\n", "named twice"),
        ("id,kind,outputs\n\"a,lipsync,o.json\n", "never closed"),
        ("", "has no rows"),
    ] {
        let path = dir.path().join("bad.csv");
        std::fs::write(&path, text).unwrap();
        let error = Manifest::read(&path).unwrap_err().to_string();
        assert!(
            error.contains("bad.csv") && error.contains(words),
            "{error}"
        );
    }
}

/// `text` in `encoding`, as GNU iconv writes it (not the library that reads it back).
fn iconv(text: &str, encoding: &str) -> Vec<u8> {
    use std::io::Write as _;
    let mut child = std::process::Command::new("iconv")
        .args(["-f", "UTF-8", "-t", encoding])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("iconv (glibc's, in every Debian)");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{out:?}");
    out.stdout
}

#[test]
fn a_manifest_saved_in_a_code_page_or_utf16_reads_as_its_utf8_does() {
    // A localisation sheet saved as "CSV" by Excel on a Japanese Windows (Shift_JIS), and the
    // same as "Unicode" (UTF-16 with its byte-order mark).
    let sheet = "id,kind,speech,text,language,outputs\r\n\
        l1,lipsync,a.wav,今日は天気がいいですね。,ja,o/l1.json\r\n\
        l2,lipsync,a.wav,ありがとうございました。,ja,o/l2.json\r\n";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.wav"), b"RIFF").unwrap();
    let texts = |manifest: &Manifest| -> Vec<String> {
        manifest
            .rows()
            .map(|r| {
                r.field(faceanim_batch::manifest::Field::Text)
                    .unwrap()
                    .to_owned()
            })
            .collect()
    };
    let utf8 = dir.path().join("utf8.csv");
    std::fs::write(&utf8, sheet).unwrap();
    let want = texts(&Manifest::read(&utf8).unwrap());
    assert_eq!(want.len(), 2);
    for (encoding, guessed) in [("SHIFT_JIS", Some("Shift_JIS")), ("UTF-16", None)] {
        let path = dir.path().join(format!("{encoding}.csv"));
        std::fs::write(&path, iconv(sheet, encoding)).unwrap();
        let manifest = Manifest::read(&path).unwrap_or_else(|e| panic!("{encoding}: {e}"));
        assert_eq!(texts(&manifest), want, "{encoding}");
        assert_eq!(manifest.guessed_encoding, guessed, "{encoding}");
    }
    // JSON Lines are Unicode by JSON's rule: UTF-16 reads, a code page is refused by name.
    let line = r#"{"id": "l1", "kind": "lipsync", "speech": "a.wav", "text": "今日は", "outputs": "o/l1.json"}"#;
    let jsonl = dir.path().join("lines.jsonl");
    std::fs::write(&jsonl, iconv(line, "UTF-16")).unwrap();
    let manifest = Manifest::read(&jsonl).unwrap();
    assert_eq!(texts(&manifest), ["今日は"]);
    std::fs::write(&jsonl, iconv(line, "SHIFT_JIS")).unwrap();
    let error = Manifest::read(&jsonl).unwrap_err().to_string();
    assert!(
        error.contains("lines.jsonl") && error.contains("not UTF-8"),
        "{error}"
    );
}

proptest! {
    /// Whatever a cell holds (commas, quotes, line breaks, spaces inside), quoted as a
    /// spreadsheet quotes it, it reads back the same.
    #[test]
    fn csv_cells_read_back_as_written(words in "[a-zA-Z ,\"\n']{1,40}") {
        let quoted = format!("\"{}\"", words.replace('"', "\"\""));
        let text = format!("id,kind,speech,text,outputs\na,lipsync,a.wav,{quoted},o.json\n");
        let (_dir, manifest) = manifest("lines.csv", &text);
        let row = manifest.entries[0].row.as_ref();
        if words.trim().is_empty() {
            prop_assert!(row.is_ok_and(|r| r.field(faceanim_batch::manifest::Field::Text).is_none()));
        } else {
            // A cell is read trimmed, as its value.
            let text = row.unwrap().field(faceanim_batch::manifest::Field::Text).unwrap().to_owned();
            prop_assert_eq!(text, words.trim());
        }
    }
}

/// A sheet as spreadsheets save it in other languages, written by Python's `csv` module (not
/// the reader's code) in Excel's dialects, reads as the plain CSV does: Excel's "CSV" on a
/// German Windows (cells separated by `;`, windows-1252, `WAHR`/`FALSCH`, a decimal comma, a
/// blank column and a blank row of the used range), its "Unicode text" (tabs, UTF-16, `.txt`),
/// a sheet that names its separator on a `sep=;` line first, and a `.tsv`.
#[test]
fn a_sheet_saved_in_any_language_reads_as_the_plain_csv_does() {
    let plain = "id,kind,speech,text,outputs,fps,face\n\
        a,lipsync,a.wav,\"Guten Tag; schön, dass du da bist\",o/a.json;o/a.csv,29.97,true\n\
        b,lipsync,a.wav,true,o/b.json,25,false\n";
    let write = r#"
import csv, sys
header = ["id", "kind", "speech", "text", "outputs", "fps", "face"]
rows = [["a", "lipsync", "a.wav", "Guten Tag; schön, dass du da bist", "o/a.json;o/a.csv", 29.97, True],
        ["b", "lipsync", "a.wav", "true", "o/b.json", 25, False]]
def sheet(name, encoding, words, decimal, blank=False, **dialect):
    with open(name, "w", newline="", encoding=encoding) as f:
        if dialect.pop("sep", False):
            f.write("sep=" + dialect["delimiter"] + "\r\n")
        out = csv.writer(f, **dialect)
        cell = lambda v: words[v] if isinstance(v, bool) else str(v).replace(".", decimal) if isinstance(v, float) else v
        out.writerow(header + [""] * blank)
        for k, row in enumerate(rows):
            out.writerow([cell(v) for v in row] + [""] * blank)
            if blank and k == 0:
                out.writerow([""] * (len(header) + 1))
sheet("de.csv", "cp1252", {True: "WAHR", False: "FALSCH"}, ",", blank=True, delimiter=";")
sheet("unicode.txt", "utf-16", {True: "TRUE", False: "FALSE"}, ".", dialect="excel-tab")
sheet("de-unicode.txt", "utf-16", {True: "WAHR", False: "FALSCH"}, ",", dialect="excel-tab")
sheet("fr.csv", "utf-8-sig", {True: "VRAI", False: "FAUX"}, ",", sep=True, delimiter=";")
sheet("libre.tsv", "utf-8", {True: "true", False: "false"}, ".", delimiter="\t")
"#;
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.wav"), b"RIFF").unwrap();
    let out = std::process::Command::new("python3")
        .args(["-c", write])
        .current_dir(dir.path())
        .output()
        .expect("python3");
    assert!(out.status.success(), "{out:?}");
    // Each row as it would run: its id, kind, fields, outputs and options, not its line.
    let rows = |name: &str| {
        let manifest = Manifest::read(&dir.path().join(name)).unwrap_or_else(|e| panic!("{e}"));
        manifest
            .entries
            .into_iter()
            .map(|e| {
                let row = e.row.unwrap_or_else(|e| panic!("{name}: {e}"));
                (row.id, row.kind, row.fields, row.outputs, row.options)
            })
            .collect::<Vec<_>>()
    };
    std::fs::write(dir.path().join("plain.csv"), plain).unwrap();
    let want = rows("plain.csv");
    assert_eq!(want.len(), 2);
    assert_eq!(want[0].4["fps"], OptionValue::Value("29.97".to_owned()));
    assert_eq!(want[1].4["face"], OptionValue::Flag(false));
    assert_eq!(
        want[1].2.get("text").map(String::as_str),
        Some("true"),
        "a field's cell is its text, even when it reads as a switch"
    );
    // A header in a spreadsheet's capitals names the same columns.
    std::fs::write(
        dir.path().join("capitals.csv"),
        "ID;Kind;Speech;Text;Outputs;FPS;Face\n\
         a;lipsync;a.wav;\"Guten Tag; schön, dass du da bist\";\"o/a.json;o/a.csv\";29,97;TRUE\n\
         b;lipsync;a.wav;true;o/b.json;25;FALSE\n",
    )
    .unwrap();
    for name in [
        "de.csv",
        "unicode.txt",
        "de-unicode.txt",
        "fr.csv",
        "libre.tsv",
        "capitals.csv",
    ] {
        assert_eq!(rows(name), want, "{name}");
    }
    // A tab-separated sheet's decimal mark is the one its numbers show: `1,500` alone could be
    // a thousand and a half (and is left for the command to refuse), beside `29,97` it is 1.5,
    // beside `29.97` it stays as written.
    let tabs = |name: &str, fps: &str, other: &str| {
        let text = format!(
            "id\tkind\tspeech\toutputs\tfps\tsmoothing\na\tlipsync\ta.wav\to/{name}.json\t{fps}\t{other}\n"
        );
        std::fs::write(dir.path().join(format!("{name}.tsv")), text).unwrap();
        match &rows(&format!("{name}.tsv"))[0].4["fps"] {
            OptionValue::Value(v) => v.clone(),
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(tabs("alone", "1,500", "2"), "1,500");
    assert_eq!(tabs("comma", "1,500", "29,97"), "1.500");
    assert_eq!(tabs("point", "1,500", "29.97"), "1,500");
    assert_eq!(tabs("short", "29,97", "2"), "29.97");
    // Lines are the file's: the German sheet's second row is on line 4, after the blank one;
    // a named separator's header is on line 2.
    let de = Manifest::read(&dir.path().join("de.csv")).unwrap();
    assert_eq!(de.entries[1].line, 4);
    let fr = Manifest::read(&dir.path().join("fr.csv")).unwrap();
    assert_eq!(fr.entries[0].line, 3);
    // A cell under a column with no name is the row's problem, not lost.
    let path = dir.path().join("stray.csv");
    std::fs::write(
        &path,
        "id;kind;speech;outputs;\na;lipsync;a.wav;o/a.json;\nb;lipsync;a.wav;o/b.json;note\n",
    )
    .unwrap();
    let stray = Manifest::read(&path).unwrap();
    assert!(stray.entries[0].row.is_ok());
    assert_eq!(
        problem(&stray, 1),
        (
            3,
            None,
            "column 5 has no name in the header, but this row has `note` in it".to_owned()
        )
    );
}

/// A sheet made on Windows names its folders with `\`: on Linux workers its inputs are found and
/// its outputs written in their folders, and a Windows machine's own path is named as such.
#[cfg(unix)]
#[test]
fn a_manifest_written_on_windows_finds_its_folders_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("audio")).unwrap();
    std::fs::write(dir.path().join("audio").join("a.wav"), b"RIFF").unwrap();
    std::fs::create_dir(dir.path().join("lines")).unwrap();
    std::fs::write(dir.path().join("lines").join("a.txt"), b"Hello").unwrap();
    let path = dir.path().join("lines.csv");
    std::fs::write(
        &path,
        "id,kind,speech,text,outputs\r\n\
         a,lipsync,audio\\a.wav,,out\\clips\\a.json\r\n\
         b,lipsync,C:\\Users\\me\\audio\\b.wav,,out\\b.json\r\n\
         c,lipsync,audio\\a.wav,lines\\a.txt,out\\c.json\r\n",
    )
    .unwrap();
    let manifest = Manifest::read(&path).unwrap();
    let a = manifest.entries[0].row.as_ref().unwrap();
    assert_eq!(a.input_files()[0].1, dir.path().join("audio").join("a.wav"));
    assert_eq!(
        a.output_paths(),
        [dir.path().join("out").join("clips").join("a.json")]
    );
    let (line, field, why) = problem(&manifest, 1);
    assert_eq!((line, field.as_deref()), (3, Some("speech")));
    assert!(
        why.contains("no such file") && why.contains("a path on a Windows machine"),
        "{why}"
    );
    // A transcript's file named as the words is caught before any work, as it is written
    // with `/`: not spoken as "lines a dot t x t", nor left for the row's command to refuse.
    assert_eq!(
        problem(&manifest, 2),
        (
            4,
            Some("text".to_owned()),
            "`lines\\a.txt` names a file: give it as `transcript`".to_owned()
        )
    );
}

/// JSON Lines as dataframe libraries write them (pandas' `to_json(orient="records",
/// lines=True)`, Polars' `write_ndjson`): every column on every row, `null` where a cell is
/// empty. A null field is one not given, as an empty CSV cell is.
#[test]
fn rows_with_null_fields_read_as_rows_without_them() {
    let text = [
        r#"{"id":"p1","kind":"lipsync","speech":"a.wav","text":"Hi there","transcript":null,"language":null,"outputs":"o/p1.json","options":{"fps":29.97,"face":true}}"#,
        r#"{"id":"p2","kind":"lipsync","speech":"a.wav","text":null,"transcript":"words.txt","language":"en-us","outputs":"o/p2.json","options":{"fps":null,"face":false}}"#,
        r#"{"id":"p3","kind":"lipsync","speech":null,"text":null,"transcript":null,"language":null,"outputs":"o/p3.json","options":null}"#,
    ]
    .join("\n");
    let (_dir, manifest) = manifest("frame.jsonl", &text);
    let p1 = manifest.entries[0].row.as_ref().unwrap();
    assert_eq!(
        p1.fields.keys().copied().collect::<Vec<_>>(),
        ["speech", "text"]
    );
    assert_eq!(p1.options["fps"], OptionValue::Value("29.97".to_owned()));
    let p2 = manifest.entries[1].row.as_ref().unwrap();
    assert_eq!(
        p2.fields.keys().copied().collect::<Vec<_>>(),
        ["language", "speech", "transcript"]
    );
    // The required field, null, is missing.
    let (line, field, problem) = problem(&manifest, 2);
    assert_eq!((line, field.as_deref()), (3, Some("speech")));
    assert!(problem.starts_with("missing"), "{problem}");
}

/// An id column of numbers, as pandas writes one (`1`; `1.0` in a column with an empty cell,
/// which makes it a column of floats), is the ids' digits; a fraction is no id.
#[test]
fn an_id_column_of_numbers_reads_as_its_digits() {
    let (_dir, numbers) = manifest(
        "numbers.jsonl",
        "{\"id\":7,\"kind\":\"lipsync\",\"speech\":\"a.wav\",\"outputs\":\"o/7.json\"}\n\
         {\"id\":8.0,\"kind\":\"lipsync\",\"speech\":\"a.wav\",\"outputs\":\"o/8.json\"}\n\
         {\"id\":8,\"kind\":\"lipsync\",\"speech\":\"a.wav\",\"outputs\":\"o/8b.json\"}\n\
         {\"id\":8.5,\"kind\":\"lipsync\",\"speech\":\"a.wav\",\"outputs\":\"o/9.json\"}\n",
    );
    assert_eq!(numbers.entries[0].row.as_ref().unwrap().id, "7");
    assert_eq!(numbers.entries[1].id.as_deref(), Some("8"));
    assert_eq!(
        problem(&numbers, 2),
        (
            3,
            Some("id".to_owned()),
            "`8` is already the id of line 2".to_owned()
        )
    );
    assert_eq!(
        problem(&numbers, 3),
        (
            4,
            Some("id".to_owned()),
            "a string or a whole number, not 8.5".to_owned()
        )
    );
}
