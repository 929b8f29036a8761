//! The fuzz suite: every input a user or another program hands faceanim, mutated the way a
//! careless tool or an attacker would, must give a clean answer — a result or an error naming
//! the file and field — and never a panic, an abort, a signal, memory without bound (each
//! test process runs under a data limit of [`MEMORY_LIMIT`]) or a 5xx from the studio.
//!
//! - in the library, seeded mutation corpora (`fuzz/mutate.rs`) of session files (a real
//!   capture of a photo), WAV files (flite's voices), OBJ heads, viseme tables and transcripts;
//! - through the command, the cases the issue found (a photo's animation of 10¹² frames, a
//!   10 MB transcript, a 1 Hz WAV, a closed pipe, `-o /dev/null`, values of 10³⁹);
//! - through the studio, its uploads and JSON routes, odd headers and same-name uploads at
//!   once, then the crash loop: a bad take autosaved and the studio started again.
//!
//! A failing case is written to `test-output/fuzz/` to be replayed; the case being tried is
//! always in `last-*` there, so that even an abort names it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

#[path = "fuzz/mutate.rs"]
mod mutate;
mod support;

use faceanim_speech::audio::wav_bytes as wav;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use mutate::Mutator;
use serde_json::{Value, json};
use support::{faceanim_ok, output_dir, request, start_on};

/// The most memory (data: heap and anonymous maps) a test process and what it starts may use.
const MEMORY_LIMIT: u64 = 1 << 30;

/// Puts this test's process (and the programs it starts) under [`MEMORY_LIMIT`]: an input
/// that makes faceanim allocate without bound aborts the test instead of the machine.
fn limit_memory() {
    let limit = rustix::process::Rlimit {
        current: Some(MEMORY_LIMIT),
        maximum: Some(MEMORY_LIMIT),
    };
    rustix::process::setrlimit(rustix::process::Resource::Data, limit).unwrap();
}

/// Runs mutated cases of one kind, collecting the ones that panic.
struct Cases {
    kind: &'static str,
    dir: PathBuf,
    tried: usize,
    failed: Vec<String>,
}

impl Cases {
    fn new(kind: &'static str) -> Cases {
        limit_memory();
        let dir = output_dir("fuzz");
        Cases {
            kind,
            dir,
            tried: 0,
            failed: Vec::new(),
        }
    }

    /// `check` on `input`, which must not panic.
    fn run(&mut self, input: &[u8], check: impl FnOnce(&[u8])) {
        let last = self.dir.join(format!("last-{}", self.kind));
        std::fs::write(&last, input).unwrap();
        self.tried += 1;
        if catch_unwind(AssertUnwindSafe(|| check(input))).is_err() {
            let kept = self.dir.join(format!("{}-{}.bin", self.kind, self.tried));
            std::fs::write(&kept, input).unwrap();
            self.failed.push(kept.display().to_string());
        }
    }

    fn finish(self) {
        eprintln!("{}: {} cases", self.kind, self.tried);
        assert!(
            self.failed.is_empty(),
            "{}: {} of {} cases panicked: {:?}",
            self.kind,
            self.failed.len(),
            self.tried,
            self.failed
        );
    }
}

/// A session of the built-in head from a real capture: `faceanim track` of the astronaut
/// photograph, with the session kept (made once per test run).
fn photo_session() -> Value {
    let dir = output_dir("fuzz");
    let session = dir.join("astronaut.session.json");
    if !session.exists() {
        let photo = faceanim_testdata::shared("images/astronaut.png");
        faceanim_ok(&[
            "track",
            photo.to_str().unwrap(),
            "-o",
            session.to_str().unwrap(),
        ]);
    }
    serde_json::from_slice(&std::fs::read(&session).unwrap()).unwrap()
}

/// The photo's session made a 12-frame video take (the still's length removed).
fn video_session(photo: &Value) -> Value {
    let mut video = photo.clone();
    let frame = video["frames"][0].clone();
    video["frames"] = Value::Array(
        (0..12)
            .map(|k| {
                let mut f = frame.clone();
                f["time"] = json!(k as f64 / 30.0);
                f
            })
            .collect(),
    );
    video.as_object_mut().unwrap().remove("still_frames");
    video
}

/// Everything a session file is used for once read: its animation, Live Link's curves, the
/// seed's CSV and each export format.
fn use_session(bytes: &[u8], character: &faceanim_rig::Character, glb: bool) {
    let Ok(session) = faceanim_take::Session::from_json(bytes) else {
        return;
    };
    let clip = session.clip();
    let _ = session.arkit_clip();
    let _ = session.to_seed_csv();
    let _ = session.keyframes();
    for row in &clip.frames {
        assert!(row.iter().all(|w| w.is_finite()), "a weight is not finite");
    }
    let layered = faceanim_take::layer(&clip, None, session.blendshapes.len(), "fuzz");
    let animation = faceanim_export::Animation {
        character: Some(character),
        animation: layered.animation,
        clip: layered.clip,
        arkit: session.arkit_clip(),
        session: Some(&session),
        bones: None,
        strokes: None,
        bones_only: false,
    };
    for format in faceanim_export::Format::ALL {
        if format != faceanim_export::Format::Glb || glb {
            let _ = faceanim_export::export(format, &animation);
        }
    }
}

#[test]
fn session_files() {
    let mut cases = Cases::new("session");
    let head = faceanim_head::default_character();
    let photo = photo_session();
    let video = video_session(&photo);
    let mut mutator = Mutator::new(43);
    for k in 0..1500 {
        let seed = if k % 2 == 0 { &photo } else { &video };
        let input = mutator.json(seed);
        cases.run(&input, |bytes| use_session(bytes, &head, k % 25 == 0));
    }
    // The cases, each refused with the field named.
    for (field, value) in [
        ("still_frames", json!(1e12)),
        ("still_frames", json!(1_000_000_000_000_u64)),
        ("still_frames", json!(9_223_372_036_854_775_808_u64)),
        (
            "smoothing",
            json!({"min_cutoff": 1e39, "beta": 1e39, "derivative_cutoff": 1}),
        ),
    ] {
        let mut bad = photo.clone();
        bad[field] = value;
        let error = faceanim_take::Session::from_json(&serde_json::to_vec(&bad).unwrap())
            .unwrap_err()
            .to_string();
        assert!(error.contains(field), "{field}: {error}");
    }
    let mut bad = video.clone();
    bad["frames"][3]["head"] = json!([1e39, 0, 0]);
    let error = faceanim_take::Session::from_json(&serde_json::to_vec(&bad).unwrap())
        .unwrap_err()
        .to_string();
    assert!(error.contains("frames[3].head[0]"), "{error}");
    bad = video.clone();
    bad["frames"][2]["presence"] = json!("high");
    let error = faceanim_take::Session::from_json(&serde_json::to_vec(&bad).unwrap())
        .unwrap_err()
        .to_string();
    assert!(error.contains("frames[2].presence"), "{error}");
    cases.finish();
}

/// flite's `slt` voice saying a line, as the WAV flite writes (16 kHz mono).
fn speech_wav(dir: &Path) -> Vec<u8> {
    let path = dir.join("mama.wav");
    support::flite("slt", "Mama made my bed.", &path);
    std::fs::read(path).unwrap()
}

#[test]
fn wav_files() {
    let mut cases = Cases::new("wav");
    let dir = tempfile::tempdir().unwrap();
    let speech = speech_wav(dir.path());
    // The same speech as a 44.1 kHz stereo file: ffmpeg converts it.
    let samples: Vec<i16> = speech[44..]
        .chunks_exact(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .take(16_000)
        .flat_map(|s| [s, s])
        .collect();
    let stereo = wav(&samples, 44_100, 2);
    let mut mutator = Mutator::new(46);
    let path = dir.path().join("case.wav");
    for k in 0..400 {
        let seed = if k % 4 == 0 { &stereo } else { &speech };
        let input = mutator.bytes(seed);
        cases.run(&input, |bytes| {
            std::fs::write(&path, bytes).unwrap();
            if let Ok(sound) = faceanim_speech::Sound::read(&path) {
                assert!(sound.seconds() <= faceanim_speech::audio::MAX_SECONDS);
                let _ = sound.voice_activity();
            }
        });
    }
    // A header claiming 1 Hz (or no channels) is refused from the header, before ffmpeg.
    for (rate, channels) in [(1, 1), (2, 1), (16_000, 0)] {
        std::fs::write(&path, wav(&[0; 16_000], rate, channels)).unwrap();
        let started = std::time::Instant::now();
        let error = faceanim_speech::Sound::read(&path).unwrap_err().to_string();
        assert!(error.contains("case.wav"), "{error}");
        assert!(started.elapsed().as_secs_f32() < 1.0, "{error}");
    }
    cases.finish();
}

/// A small OBJ face: a 12×12 grid with texture coordinates and normals, and one shape.
fn obj_grid(lift: f32) -> String {
    let n = 12;
    let mut text = String::from("# grid\nmtllib face.mtl\no face\n");
    for y in 0..n {
        for x in 0..n {
            let bump = if (4..8).contains(&x) && (4..8).contains(&y) {
                lift
            } else {
                0.0
            };
            text.push_str(&format!(
                "v {:.4} {:.4} {:.4}\n",
                x as f32 / n as f32 - 0.5,
                y as f32 / n as f32 - 0.5,
                bump
            ));
            text.push_str(&format!(
                "vt {:.4} {:.4}\nvn 0 0 1\n",
                x as f32 / n as f32,
                y as f32 / n as f32
            ));
        }
    }
    text.push_str("usemtl skin\ns 1\n");
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let i = y * n + x + 1;
            text.push_str(&format!(
                "f {i}/{i}/{i} {}/{}/{} {}/{}/{} {}/{}/{}\n",
                i + 1,
                i + 1,
                i + 1,
                i + n + 1,
                i + n + 1,
                i + n + 1,
                i + n,
                i + n,
                i + n
            ));
        }
    }
    text
}

#[test]
fn obj_heads() {
    let mut cases = Cases::new("obj");
    let neutral = obj_grid(0.0);
    let shape = obj_grid(0.05);
    let mut mutator = Mutator::new(44);
    let dir = tempfile::tempdir().unwrap();
    for k in 0..1000 {
        let input = mutator.bytes(if k % 3 == 0 {
            shape.as_bytes()
        } else {
            neutral.as_bytes()
        });
        cases.run(&input, |bytes| {
            let text = String::from_utf8_lossy(bytes);
            let (n, s) = if k % 3 == 0 {
                (neutral.as_str(), text.as_ref())
            } else {
                (text.as_ref(), shape.as_str())
            };
            let imported = faceanim_rig::import::import_obj_set(
                "fuzz",
                faceanim_rig::import::ObjSource {
                    name: "neutral.obj",
                    text: n,
                },
                &[faceanim_rig::import::ObjSource {
                    name: "smile.obj",
                    text: s,
                }],
            );
            if let Ok(imported) = imported {
                let c = imported.character;
                let _ = c.pose(&[0.5]);
                let _ = c.head_bounds();
                let _ = faceanim_export::glb(&c, None);
            }
            if k % 10 == 0 {
                // By path too, as the commands load a head.
                let file = dir.path().join("head.obj");
                std::fs::write(&file, bytes).unwrap();
                let _ = faceanim_files::load_character(&file);
            }
        });
    }
    // An OBJ with no vertices is named an OBJ, not a glTF.
    let empty = dir.path().join("empty.obj");
    std::fs::write(&empty, "# nothing\no empty\n").unwrap();
    let error = faceanim_files::load_character(&empty)
        .unwrap_err()
        .to_string();
    assert!(!error.contains("glTF"), "{error}");
    assert!(error.contains("empty.obj"), "{error}");
    cases.finish();
}

#[test]
fn viseme_tables() {
    let mut cases = Cases::new("visemes");
    let head = faceanim_head::default_character();
    let table: serde_json::Map<String, Value> = faceanim_speech::mouth::ARKIT_TABLE
        .iter()
        .map(|(v, channels)| {
            (
                v.name().to_owned(),
                channels
                    .iter()
                    .map(|(c, w)| ((*c).to_owned(), json!(w)))
                    .collect(),
            )
        })
        .collect();
    let seed = Value::Object(table);
    let mut mutator = Mutator::new(45);
    for _ in 0..1000 {
        let input = mutator.json(&seed);
        cases.run(&input, |bytes| {
            let Ok(table) = faceanim_speech::MouthTable::from_json(&String::from_utf8_lossy(bytes))
            else {
                return;
            };
            let mouth = faceanim_speech::Mouth::of(&head, &table).unwrap();
            for v in 0..15 {
                let mut visemes = [0.0; 15];
                visemes[v] = 1.0;
                assert!(mouth.weights(&visemes).iter().all(|w| w.is_finite()));
            }
        });
    }
    // A 10 MB key is named in a line, not printed whole.
    let huge = format!("{{\"{}\": {{\"jawOpen\": 0.5}}}}", "k".repeat(10_000_000));
    let error = faceanim_speech::MouthTable::from_json(&huge)
        .unwrap_err()
        .to_string();
    assert!(error.len() < 400, "{} characters", error.len());
    cases.finish();
}

#[test]
fn transcripts() {
    let mut cases = Cases::new("transcript");
    let mut mutator = Mutator::new(47);
    for k in 0..1000 {
        let words = [0, 1, 5, 40, 400, 4000][k % 6];
        let text = mutator.text(words);
        let input = mutator.bytes(text.as_bytes());
        let seconds = (k % 13) as f32 * 0.7;
        cases.run(&input, |bytes| {
            let text = String::from_utf8_lossy(bytes);
            if let Ok(words) = faceanim_speech::phones::transcript_words(&text, seconds) {
                assert!(words.len() as f32 <= seconds * 10.0 + 8.0);
            }
        });
    }
    cases.finish();
}

/// `faceanim ARGS` with its exit status and stderr; a status from a signal or a panic fails.
fn command(args: &[&std::ffi::OsStr]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("faceanim {args:?} was killed: {}\n{stderr}", out.status));
    assert!(
        code <= 2 && !stderr.contains("panicked"),
        "faceanim {args:?} exited {code}:\n{stderr}"
    );
    (code, stderr)
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

#[test]
fn the_command_refuses_what_it_cannot_use_by_name() {
    limit_memory();
    let dir = tempfile::tempdir().unwrap();
    let photo = photo_session();
    let session = dir.path().join("take.session.json");
    let out = dir.path().join("x.json");
    // `faceanim session take.session.json export -o TO` of `bad`.
    let export = |bad: &Value, to: &Path| {
        std::fs::write(&session, serde_json::to_vec(bad).unwrap()).unwrap();
        command(&[
            os("session"),
            session.as_os_str(),
            os("export"),
            os("-o"),
            to.as_os_str(),
        ])
    };
    for (field, value) in [
        ("still_frames", json!(1e9)),
        ("still_frames", json!(1e12)),
        ("still_frames", json!(9_223_372_036_854_775_808_u64)),
        (
            "smoothing",
            json!({"min_cutoff": 1e39, "beta": 1e39, "derivative_cutoff": 1e39}),
        ),
    ] {
        let mut bad = photo.clone();
        bad[field] = value;
        let (code, stderr) = export(&bad, &out);
        assert_eq!(code, 1, "{stderr}");
        assert!(
            stderr.contains(field) && stderr.contains("take.session.json"),
            "{stderr}"
        );
    }
    let mut bad = photo.clone();
    bad["frames"][0]["head"] = json!([1e39, 0, 0]);
    let (code, stderr) = export(&bad, &dir.path().join("x.csv"));
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("frames[0].head[0]"), "{stderr}");

    // Lip sync: a 10 MB transcript, a transcript that is not text, a 1 Hz header.
    let speech = dir.path().join("line.wav");
    std::fs::write(&speech, speech_wav(dir.path())).unwrap();
    let words = dir.path().join("words.txt");
    let clip = dir.path().join("line.json");
    let with_text = |text: &[u8]| {
        std::fs::write(&words, text).unwrap();
        command(&[
            os("lipsync"),
            speech.as_os_str(),
            os("--text"),
            words.as_os_str(),
            os("-o"),
            clip.as_os_str(),
        ])
    };
    let started = std::time::Instant::now();
    let (code, stderr) = with_text("mama made my bed ".repeat(600_000).as_bytes());
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("--text") && stderr.contains("words.txt"),
        "{stderr}"
    );
    assert!(started.elapsed().as_secs() < 20, "{stderr}");
    for (text, said) in [
        ("mama made my bed ".repeat(200).into_bytes(), "800 words"),
        (vec![0xff, 0xfe, b'a'], "UTF-16LE"),
        (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR".to_vec(), "not UTF-8"),
        (b"...".to_vec(), "no words"),
    ] {
        let (code, stderr) = with_text(&text);
        assert_eq!(code, 1, "{stderr}");
        assert!(
            stderr.contains("--text") && stderr.contains(said),
            "{stderr}"
        );
    }
    // A transcript file's name that names none is refused, not spoken as its words.
    let missing = dir.path().join("wrods.txt");
    let (code, stderr) = command(&[
        os("lipsync"),
        speech.as_os_str(),
        os("--text"),
        missing.as_os_str(),
        os("-o"),
        clip.as_os_str(),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("--text") && stderr.contains("wrods.txt: no such file"),
        "{stderr}"
    );
    let slow = dir.path().join("slow.wav");
    std::fs::write(&slow, wav(&[0; 200_000], 1, 1)).unwrap();
    let started = std::time::Instant::now();
    let (code, stderr) = command(&[os("lipsync"), slow.as_os_str(), os("-o"), clip.as_os_str()]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("slow.wav") && stderr.contains("1 Hz"),
        "{stderr}"
    );
    assert!(started.elapsed().as_secs() < 5, "{stderr}");

    // An output in a folder that is not there (a typo) is refused before the work, by name:
    // not after minutes of tracking or training, and not as a temporary file's name.
    let typo = dir.path().join("typo");
    for args in [
        vec![os("lipsync"), speech.as_os_str(), os("-o")],
        vec![
            os("lipsync"),
            speech.as_os_str(),
            os("-o"),
            clip.as_os_str(),
            os("--clip"),
        ],
        vec![os("track"), speech.as_os_str(), os("--session")],
        vec![os("adapt"), os("--output")],
        vec![
            os("adapt"),
            os("--output"),
            clip.as_os_str(),
            os("--dataset"),
        ],
        vec![os("retarget"), os("-o")],
        vec![os("generate-shapes"), speech.as_os_str(), os("-o")],
    ] {
        let into = typo.join("out.glb");
        let mut args = args;
        args.push(into.as_os_str());
        let started = std::time::Instant::now();
        let (code, stderr) = command(&args);
        assert!(code != 0, "{args:?}: {stderr}");
        assert!(
            stderr.contains(&format!("its folder {} does not exist", typo.display())),
            "{args:?}: {stderr}"
        );
        assert!(started.elapsed().as_secs() < 5, "{args:?}: {stderr}");
    }
    assert!(!typo.exists());

    // A reader that goes away ends the command quietly.
    let mut child = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args(["info", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let finished = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&finished.stderr);
    assert!(
        finished.status.code().is_some(),
        "killed: {}",
        finished.status
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    // Special files stay what they are; `-` is standard output.
    faceanim_ok(&["export-default", "-o", "/dev/null"]);
    let null = std::fs::metadata("/dev/null").unwrap();
    assert!(std::os::unix::fs::FileTypeExt::is_char_device(
        &null.file_type()
    ));
    std::fs::write(&session, serde_json::to_vec(&photo).unwrap()).unwrap();
    let printed = faceanim_ok(&["session", session.to_str().unwrap(), "export", "-o", "-"]);
    let clip: Value = serde_json::from_str(&printed).unwrap();
    assert!(clip["frames"].as_array().is_some_and(|f| !f.is_empty()));
}

/// The most memory process `pid` has held resident so far (`VmHWM`), in bytes.
fn peak_memory(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kb: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap();
    kb * 1024
}

/// A studio answer: any status but 5xx, and an error's body `{"error": …}`.
fn answered(what: &str, (status, body): (u16, String)) -> (u16, String) {
    assert!(status < 500, "{what}: {status} {body}");
    if status >= 400 {
        let parsed: Value = serde_json::from_str(&body)
            .unwrap_or_else(|_| panic!("{what}: {status} is not JSON: {body}"));
        let error = parsed["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{what}: {body}"));
        assert!(error.len() < 2_000, "{what}: a {} byte error", error.len());
    }
    (status, body)
}

#[test]
fn the_studio_answers_every_upload_and_survives_a_bad_take() {
    // The studio's threads each reserve address space for their own heap, so its bound is
    // on what it holds (its peak resident memory, read at the end), not on its reservations.
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("fuzz.faceanim.json");
    let studio = start_on(None, &project, &[]);
    let port = studio.port;
    let upload = |name: &str, body: &[u8]| support::upload(port, name, body);
    let photo = photo_session();
    let mut mutator = Mutator::new(48);
    for k in 0..300 {
        let case = mutator.json(&photo);
        answered(
            &format!("session case {k}"),
            upload("take.session.json", &case),
        );
    }
    // Uploads of other kinds: noise named as video and images, cut PNGs. An accepted one is
    // read in the background; each is seen to its end (a short error naming the file, the
    // studio still answering) before the next, as a user who waits for it would.
    let png = std::fs::read(faceanim_testdata::shared("images/ict-face-neutral.png")).unwrap();
    let read_to_its_end = |what: &str, name: &str, answer: (u16, String)| {
        if answer.0 != 200 {
            return;
        }
        let state = support::settled(port, 120);
        let job = &state["job"];
        if let Some(error) = job["error"].as_str() {
            assert!(
                error.len() < 2_000 && error.contains(name) && !error.contains("/tmp"),
                "{what}: {error}"
            );
        } else {
            assert!(job["result"].is_string(), "{what}: {state}");
        }
    };
    for (k, name) in ["a.mp4", "b.png", "c.jpg", "d", "e.mov"].iter().enumerate() {
        let noise = mutator.bytes(&png[..png.len().min(4096)]);
        read_to_its_end(name, name, answered(name, upload(name, &noise)));
        let what = format!("cut png {k}");
        let cut = &png[..png.len() / (k + 2)];
        read_to_its_end(&what, "cut.png", answered(&what, upload("cut.png", cut)));
    }
    // Odd names: 10 KB, not ASCII, a path, none; every answer is JSON and short.
    let long = format!("{}.wav", "n".repeat(10_000));
    let (status, body) = answered("a long name", upload(&long, b"RIFF"));
    assert!(status == 400 && body.len() < 2_000, "{status} {body}");
    let speech = speech_wav(dir.path());
    let (status, body) = answered("a Japanese name", upload("%E5%8F%B0%E8%A9%9E.wav", &speech));
    assert_eq!(status, 200, "{body}");
    let view: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(view["take"]["source"], "台詞.wav", "{body}");
    answered("a path", upload("../../etc/passwd", b"x"));
    answered(
        "no name",
        request(port, "POST", "/api/capture/upload", &[], b"x"),
    );
    // Headers of the live routes, wrong.
    let (status, body) = answered(
        "a bad sample rate",
        request(
            port,
            "POST",
            "/api/capture/voice/chunk",
            &[("x-sample-rate", "fast")],
            &[0; 64],
        ),
    );
    assert!(
        status == 400 && body.contains("x-sample-rate") && !body.contains("pixels"),
        "{body}"
    );
    answered(
        "a huge frame",
        request(
            port,
            "POST",
            "/api/capture/live/frame",
            &[("x-width", "99999999"), ("x-height", "99999999")],
            &[0; 64],
        ),
    );
    for (what, method, path) in [
        ("a path that is not a number", "GET", "/api/capture/frame/x"),
        ("no such route", "DELETE", "/api/capture/state"),
    ] {
        answered(what, request(port, method, path, &[], b""));
    }
    // JSON routes with values of every wrong kind, a take open.
    answered(
        "the photo",
        upload(
            "astronaut.session.json",
            &serde_json::to_vec(&photo).unwrap(),
        ),
    );
    let routes: [(&str, &str, Value); 8] = [
        (
            "PUT",
            "/api/capture/filtering",
            json!({"keyframe_every": 5, "smoothing": {"min_cutoff": 1.0, "beta": 0.5}}),
        ),
        ("PUT", "/api/capture/still", json!({"frames": 30})),
        (
            "POST",
            "/api/capture/correct",
            json!({"frame": 0, "name": "jawOpen", "value": 0.5}),
        ),
        (
            "POST",
            "/api/capture/keyframe",
            json!({"frame": 0, "on": true}),
        ),
        ("POST", "/api/capture/neutral", json!({"frame": null})),
        (
            "PUT",
            "/api/settings",
            json!({"candidate_radius": null, "subsample": 3, "falloff": "smooth", "symmetry": false}),
        ),
        ("PUT", "/api/fps", json!({"fps": 30})),
        (
            "PUT",
            "/api/capture/visemes",
            json!({"aa": {"jawOpen": 0.7}}),
        ),
    ];
    for (method, path, seed) in &routes {
        for k in 0..12 {
            let body = mutator.json(seed);
            answered(
                &format!("{method} {path} case {k}"),
                request(port, method, path, &[], &body),
            );
        }
        answered(path, request(port, "GET", "/api/capture/state", &[], b""));
    }
    // Same-name uploads at once each get their own answer: four good lines of different
    // lengths and four that are not sound.
    let lines: Vec<(Vec<u8>, Option<usize>)> = (0..8)
        .map(|k| {
            if k % 2 == 0 {
                let path = dir.path().join(format!("line{k}.wav"));
                support::flite("slt", &"Mama made my bed. ".repeat(k / 2 + 1), &path);
                let bytes = std::fs::read(&path).unwrap();
                let seconds = (bytes.len() - 44) as f32 / 32_000.0;
                (bytes, Some((seconds * 30.0).ceil() as usize))
            } else {
                (vec![b'x'; 1000 + k], None)
            }
        })
        .collect();
    let answers: Vec<(u16, String)> = std::thread::scope(|scope| {
        let handles: Vec<_> = lines
            .iter()
            .map(|(bytes, _)| scope.spawn(move || upload("same.wav", bytes)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for ((status, body), (_, frames)) in answers.iter().zip(&lines) {
        match frames {
            Some(frames) => {
                assert_eq!(*status, 200, "{body}");
                let view: Value = serde_json::from_str(body).unwrap();
                let got = view["take"]["frames"].as_u64().unwrap() as usize;
                assert!(
                    got.abs_diff(*frames) <= 2,
                    "{got} frames for {frames}: another's sound"
                );
            }
            None => assert_eq!(*status, 400, "{body}"),
        }
    }

    let peak = peak_memory(studio.child.id());
    assert!(peak < MEMORY_LIMIT, "the studio held {} MB", peak >> 20);
    eprintln!("the studio's peak resident memory: {} MB", peak >> 20);

    // The crash loop: a photo whose animation would be 10¹² frames is refused, not stored.
    let mut bad = photo.clone();
    bad["still_frames"] = json!(1_000_000_000_000_u64);
    let (status, body) = answered(
        "10¹² frames",
        upload("bad.session.json", &serde_json::to_vec(&bad).unwrap()),
    );
    assert!(status == 400 && body.contains("still_frames"), "{body}");
    for (what, path) in [
        ("after it", "/api/capture/state"),
        ("an export after it", "/api/capture/export.json"),
    ] {
        answered(what, request(port, "GET", path, &[], b""));
    }
    drop(studio);
    // A bad take autosaved (by an older version, or by hand) is set aside at the next start.
    let autosave = dir.path().join(".fuzz.faceanim.json.take.json");
    std::fs::write(&autosave, serde_json::to_vec(&bad).unwrap()).unwrap();
    let studio = start_on(None, &project, &[]);
    let (status, body) = answered(
        "restart",
        request(studio.port, "GET", "/api/capture/state", &[], b""),
    );
    assert_eq!(status, 200);
    let view: Value = serde_json::from_str(&body).unwrap();
    let notice = view["notice"].as_str().unwrap_or_default();
    assert!(notice.contains("set aside"), "{body}");
    assert!(!autosave.exists(), "the bad autosave is set aside");
    let aside = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .any(|e| e.file_name().to_string_lossy().contains(".broken-"));
    assert!(aside, "the bad autosave is kept under another name");
    answered(
        "export",
        request(studio.port, "GET", "/api/capture/export.json", &[], b""),
    );
}
