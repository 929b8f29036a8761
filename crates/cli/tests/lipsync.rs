//! `faceanim lipsync` on speech no line of faceanim made:
//! - real people reading a novel (LibriVox recordings in Debian's `pocketsphinx-testdata`,
//!   with their transcripts): the mouth moves while speech is heard and rests in silences,
//!   judged on the recording's own loudness away from its boundaries; the clip lasts as long
//!   as the sound; the GLB validates and three.js plays it;
//! - synthetic voices that say which phone they speak when (`flite -psdur`): the visemes'
//!   accuracy within ±40 ms, with the transcript and without;
//! - silence and noise give a closed mouth; empty, cut, non-audio and over-long files give
//!   errors that name them;
//! - a Spanish line spoken by the `espeak-ng` program, lip-synced from its transcript by
//!   synthesis, with the face around the mouth (blinks, brows) on the built-in head;
//! - a subtitle as SubRip and as an Advanced SubStation Alpha script (converted by ffmpeg)
//!   lip-syncs as its words do;
//! - transcripts saved in a legacy code page (Shift_JIS, windows-1251) or UTF-16 lip-sync as
//!   in UTF-8;
//! - a 44.1 kHz stereo 24-bit WAV (as ffmpeg writes one) lip-syncs where no ffmpeg is
//!   installed, as it does through ffmpeg.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use support::{
    assert_valid_gltf, faceanim, faceanim_ok, flite, output_dir, request, request_bytes, start_on,
    strings, stroke_along, threejs_render, vmc_receiver,
};

const LIBRIVOX: &str = "/usr/share/pocketsphinx/test/data/librivox";

/// The LibriVox recordings and their transcripts.
fn librivox() -> Vec<(PathBuf, String)> {
    let transcription = std::fs::read_to_string(Path::new(LIBRIVOX).join("transcription"))
        .expect("pocketsphinx-testdata is needed: run scripts/setup.sh");
    transcription
        .lines()
        .filter_map(|line| {
            let (text, id) = line.rsplit_once(" (")?;
            let id = id.trim_end_matches(')');
            let text = text.replace("<s>", "").replace("</s>", "");
            Some((
                Path::new(LIBRIVOX).join(format!("{id}.wav")),
                text.trim().to_owned(),
            ))
        })
        .collect()
}

/// 16-bit mono samples of a canonical WAV.
fn samples(path: &Path) -> (Vec<i16>, u32) {
    let bytes = std::fs::read(path).unwrap();
    let rate = u32::from_le_bytes(bytes[24..28].try_into().unwrap());
    let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
    (
        bytes[data..]
            .chunks_exact(2)
            .map(|b| i16::from_le_bytes([b[0], b[1]]))
            .collect(),
        rate,
    )
}

/// Per 10 ms: whether the recording is loud there (its own judgement, not faceanim's: louder
/// than its quiet parts by a third of its loudness range).
fn loud(path: &Path) -> Vec<bool> {
    let (samples, rate) = samples(path);
    let hop = (rate / 100) as usize;
    let levels: Vec<f64> = samples
        .chunks(hop)
        .map(|c| {
            let p = c
                .iter()
                .map(|&s| (f64::from(s) / 32768.0).powi(2))
                .sum::<f64>()
                / c.len() as f64;
            10.0 * p.max(1e-12).log10()
        })
        .collect();
    let mut sorted = levels.clone();
    sorted.sort_by(f64::total_cmp);
    let (quiet, peak) = (sorted[sorted.len() / 20], sorted[sorted.len() * 99 / 100]);
    let threshold = quiet + (peak - quiet) / 3.0;
    levels.iter().map(|l| *l > threshold).collect()
}

/// The clip's mouth activity per 10 ms: the largest weight of any shape.
fn mouth(clip: &Value, frames: usize) -> Vec<f64> {
    let fps = clip["fps"].as_f64().unwrap();
    let rows = clip["frames"].as_array().unwrap();
    (0..frames)
        .map(|k| {
            let f = ((k as f64 + 0.5) / 100.0 * fps).round() as usize;
            rows.get(f.min(rows.len() - 1))
                .unwrap()
                .as_array()
                .unwrap()
                .iter()
                .map(|w| w.as_f64().unwrap())
                .fold(0.0, f64::max)
        })
        .collect()
}

/// The largest weight in rows of weights.
fn peak(rows: &Value) -> f64 {
    rows.as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(|w| w.as_f64().unwrap()))
        .fold(0.0, f64::max)
}

fn run_lipsync(speech: &Path, more: &[&str], out: &Path) -> (Value, Value) {
    let clip = out.with_extension("json");
    let paths = [speech, &clip, out].map(|p| p.to_str().unwrap());
    let args: Vec<&str> = [
        "lipsync", paths[0], "--clip", paths[1], "-o", paths[2], "--json",
    ]
    .into_iter()
    .chain(more.iter().copied())
    .collect();
    let summary: Value = serde_json::from_str(faceanim_ok(&args).trim()).unwrap();
    let clip: Value = serde_json::from_slice(&std::fs::read(&clip).unwrap()).unwrap();
    (summary, clip)
}

#[test]
fn real_speech_opens_the_mouth_while_heard_and_rests_in_silence() {
    let out = output_dir("lipsync");
    let mut report = Vec::new();
    for (k, (wav, text)) in librivox().iter().enumerate() {
        // With the transcript on some, without on the others; at video's rates, NTSC's and a
        // fast one among them (a clip lasts as long as its sound at any of them).
        let with_text = k % 2 == 0;
        let mut more: Vec<&str> = if with_text {
            vec!["--text", text.as_str()]
        } else {
            vec![]
        };
        more.extend(["--fps", ["30", "240", "29.97", "23.976", "60"][k % 5]]);
        let glb = out.join(format!("librivox-{k}.glb"));
        let (summary, clip) = run_lipsync(wav, &more, &glb);
        let seconds = summary["audio_seconds"].as_f64().unwrap();
        let frames = clip["frames"].as_array().unwrap().len();
        let fps = clip["fps"].as_f64().unwrap();
        // As long as the sound, to a frame.
        assert!(
            ((frames as f64 - 1.0) / fps - seconds).abs() <= 1.0 / fps,
            "{frames} frames at {fps} for {seconds} s"
        );
        let heard = loud(wav);
        let open = mouth(&clip, heard.len());
        // Judged away from boundaries: frames whose neighbours within 100 ms agree.
        let (mut agree, mut judged) = (0, 0);
        for i in 10..heard.len().saturating_sub(10) {
            if heard[i - 10..=i + 10].iter().all(|h| *h == heard[i]) {
                judged += 1;
                if (open[i] > 0.05) == heard[i] {
                    agree += 1;
                }
            }
        }
        let share = f64::from(agree) / f64::from(judged.max(1));
        report.push(format!(
            "{}: {share:.3} of {judged} frames agree; {:.2}× real time; {}",
            wav.file_name().unwrap().to_string_lossy(),
            summary["real_time_factor"].as_f64().unwrap(),
            summary["recognition"]
        ));
        assert!(judged > 50, "{report:?}");
        assert!(share >= 0.85, "{report:?}");
        assert_eq!(
            summary["recognition"],
            if with_text { "transcript" } else { "words" },
            "{summary}"
        );
        if k == 0 {
            assert_valid_gltf(&glb);
            let played = threejs_render(&glb, &format!("{:.2}", seconds / 2.0));
            assert_eq!(played["animations"], 1, "{played}");
            assert!(played["maxInfluence"].as_f64().unwrap() > 0.0, "{played}");
        }
    }
    eprintln!("{}", report.join("\n"));
}

/// Phone → viseme, as the crate maps them (the test's own table: the Oculus set's usual
/// grouping).
fn viseme(phone: &str) -> &'static str {
    match phone {
        "p" | "b" | "m" => "PP",
        "f" | "v" => "FF",
        "th" | "dh" => "TH",
        "t" | "d" => "DD",
        "k" | "g" | "ng" => "kk",
        "ch" | "jh" | "sh" | "zh" => "CH",
        "s" | "z" => "SS",
        "n" | "l" => "nn",
        "r" | "er" => "RR",
        "aa" | "ae" | "ah" | "ay" | "aw" | "ax" => "aa",
        "eh" | "ey" => "E",
        "ih" | "iy" | "y" => "ih",
        "ao" | "ow" | "oy" => "oh",
        "uh" | "uw" | "w" => "ou",
        _ => "sil",
    }
}

/// flite's phones with their end times: "pau:0.164 hh:0.255 …".
fn flite_phones(text: &str) -> Vec<(String, f64)> {
    text.split_whitespace()
        .filter_map(|p| {
            let (phone, end) = p.split_once(':')?;
            Some((phone.to_owned(), end.parse().ok()?))
        })
        .collect()
}

#[test]
fn visemes_of_synthetic_voices_match_their_phones_within_40_ms() {
    let out = output_dir("lipsync-tts");
    let lines = [
        "The quick brown fox jumps over the lazy dog.",
        "Please bring me my blue map before the bus leaves.",
        "She sells sea shells by the sea shore on Thursday.",
    ];
    let mut report = Vec::new();
    let (mut total_hits, mut total_frames) = (0usize, 0usize);
    for voice in ["slt", "rms", "awb"] {
        for (k, line) in lines.iter().enumerate() {
            let wav = out.join(format!("{voice}-{k}.wav"));
            let truth = flite_phones(&flite(voice, line, &wav));
            assert!(truth.len() > 10, "{truth:?}");
            for with_text in [true, false] {
                let more: Vec<&str> = if with_text {
                    vec!["--text", line]
                } else {
                    vec![]
                };
                let (summary, _) = run_lipsync(
                    &wav,
                    &more,
                    &out.join(format!("{voice}-{k}-{with_text}.json")),
                );
                // Our viseme per 10 ms, from the phones recognised.
                let phones = summary["phones"].as_array().unwrap();
                let ours_at = |t: f64| {
                    phones
                        .iter()
                        .find(|p| {
                            p["start"].as_f64().unwrap() <= t && t < p["end"].as_f64().unwrap()
                        })
                        .map_or("sil", |p| {
                            viseme(&p["label"].as_str().unwrap().to_lowercase())
                        })
                };
                let (mut hits, mut frames) = (0, 0);
                let mut start = 0.0;
                for (phone, end) in &truth {
                    let expected = viseme(phone);
                    if expected != "sil" {
                        let mut t = start + 0.005;
                        while t < *end {
                            frames += 1;
                            let near =
                                (-4..=4).any(|d| ours_at(t + f64::from(d) * 0.01) == expected);
                            if near {
                                hits += 1;
                            }
                            t += 0.01;
                        }
                    }
                    start = *end;
                }
                let accuracy = f64::from(hits) / f64::from(frames.max(1));
                if with_text {
                    total_hits += hits as usize;
                    total_frames += frames as usize;
                }
                report.push(format!(
                    "{voice} line {k} {}: {accuracy:.3} of {frames} speech frames",
                    if with_text { "with text" } else { "recognised" }
                ));
            }
        }
    }
    let overall = total_hits as f64 / total_frames.max(1) as f64;
    eprintln!(
        "{}\nwith the transcript, overall: {overall:.3}",
        report.join("\n")
    );
    std::fs::write(
        out.join("accuracy.txt"),
        format!("{}\n{overall:.3}\n", report.join("\n")),
    )
    .unwrap();
    assert!(
        overall >= 0.8,
        "viseme accuracy within ±40 ms: {overall:.3}\n{report:?}"
    );
    // The same line's subtitle file, as a player has it (a cue number, a timecode, a
    // direction for the deaf, styling), is aligned as its words are: nothing of it is spoken
    // but the words, and the note says what was left out.
    let subtitle = out.join("slt-0.srt");
    std::fs::write(
        &subtitle,
        format!(
            "1\n00:00:00,000 --> 00:00:03,000\n[calmly] <i>{}</i>\n",
            lines[0]
        ),
    )
    .unwrap();
    let phones = |summary: &Value| summary["phones"].to_string();
    let wav = out.join("slt-0.wav");
    let (plain, _) = run_lipsync(&wav, &["--text", lines[0]], &out.join("slt-0-plain.json"));
    let (read, _) = run_lipsync(
        &wav,
        &["--text", subtitle.to_str().unwrap()],
        &out.join("slt-0-srt.json"),
    );
    assert_eq!(read["recognition"], "transcript", "{read}");
    assert_eq!(phones(&read), phones(&plain));
    let notes = read["notes"].to_string();
    assert!(
        notes.contains("[calmly]") && notes.contains("a subtitle timecode"),
        "{notes}"
    );
    // The same subtitle as an Advanced SubStation Alpha script, converted by ffmpeg (its
    // header, styles, `Dialogue:` fields and `{\i1}` tags), is aligned the same.
    let script = out.join("slt-0.ass");
    ffmpeg(&["-i", subtitle.to_str().unwrap(), script.to_str().unwrap()]);
    let (read, _) = run_lipsync(
        &wav,
        &["--text", script.to_str().unwrap()],
        &out.join("slt-0-ass.json"),
    );
    assert_eq!(phones(&read), phones(&plain), "{read}");
    let notes = read["notes"].to_string();
    assert!(notes.contains("override tags"), "{notes}");
}

#[test]
fn a_spanish_line_lip_syncs_from_its_transcript_with_blinks_and_brows() {
    let out = output_dir("lipsync-languages");
    let wav = out.join("mama.wav");
    let line = "Mi mamá me mima mucho. Y el perro de Pablo bebe agua en la playa.";
    espeak_ng("es+f3", "140", line, &wav);
    let (summary, clip) = run_lipsync(
        &wav,
        &["--text", line, "--language", "es", "--face"],
        &out.join("mama.glb"),
    );
    assert_eq!(summary["recognition"], "synthesis", "{summary}");
    assert!(summary["notes"].as_array().unwrap().is_empty(), "{summary}");
    // Every m, p and b of the line closes the lips.
    let phones = summary["phones"].as_array().unwrap();
    let bilabials: Vec<(f64, f64)> = phones
        .iter()
        .filter(|p| matches!(p["label"].as_str().unwrap(), "m" | "p" | "b" | "β"))
        .map(|p| (p["start"].as_f64().unwrap(), p["end"].as_f64().unwrap()))
        .collect();
    assert!(bilabials.len() >= 8, "{summary}");
    let keys = summary["visemes"].as_array().unwrap();
    for (start, end) in &bilabials {
        assert!(
            keys.iter().any(|k| {
                let t = k["start"].as_f64().unwrap();
                k["viseme"] == "PP" && t >= start - 0.1 && t <= *end
            }),
            "the lips stay open at {start:.2}..{end:.2} s: {keys:?}"
        );
    }
    // A line too short and even for a blink or a raise says so, not that the head lacks the
    // shapes (it has them: the line above blinks).
    let short = out.join("paper.wav");
    let line = "Bring me the blue paper, please.";
    flite("slt", line, &short);
    let (said, _) = run_lipsync(&short, &["--text", line, "--face"], &out.join("paper.glb"));
    assert!(
        said["gestures"]["blinks"].as_array().unwrap().is_empty()
            && said["gestures"]["accents"].as_array().unwrap().is_empty(),
        "{said}"
    );
    let notes = said["notes"].to_string();
    assert!(
        notes.contains("no blink or brow raise falls in this line") && !notes.contains("shapes"),
        "{notes}"
    );
    // The pause between the sentences blinks; the built-in head's lids move.
    let gestures = &summary["gestures"];
    assert!(
        !gestures["blinks"].as_array().unwrap().is_empty(),
        "{summary}"
    );
    let names = clip["blendshapes"].as_array().unwrap();
    let lid = names.iter().position(|n| n == "eyeBlinkLeft").unwrap();
    let rows = clip["frames"].as_array().unwrap();
    assert!(
        rows.iter().any(|r| r[lid].as_f64().unwrap() > 0.9),
        "no blink drawn"
    );
    // The head turns a little with each of the two sentences (one way, then the other), is
    // still before the voice starts, and nods on the accents.
    let head: Vec<[f64; 3]> = clip["head"]
        .as_array()
        .unwrap_or_else(|| panic!("no head motion with --face: {}", clip["head"]))
        .iter()
        .map(|h| [0, 1, 2].map(|i| h[i].as_f64().unwrap()))
        .collect();
    assert_eq!(head.len(), rows.len());
    let phrases = gestures["phrases"].as_array().unwrap();
    assert_eq!(phrases.len(), 2, "{gestures}");
    let yaw_at = |t: f64| head[((t * 30.0) as usize).min(head.len() - 1)][0];
    let middle = |p: &Value| (p[0].as_f64().unwrap() + p[1].as_f64().unwrap()) / 2.0;
    let (first, second) = (yaw_at(middle(&phrases[0])), yaw_at(middle(&phrases[1])));
    assert!(
        first > 1.0 && second < -1.0,
        "the head's yaw in the two sentences: {first:.2}°, {second:.2}°"
    );
    assert!(head[0].iter().all(|a| a.abs() < 0.5), "{:?}", head[0]);
    let deepest = head.iter().map(|h| h[1]).fold(0.0, f64::min);
    let accents = gestures["accents"].as_array().unwrap().len();
    assert!(
        accents == 0 || deepest < -2.0,
        "{accents} accents, the chin dips {deepest:.2}°"
    );
    assert!(
        head.iter().all(|h| h.iter().all(|a| a.abs() <= 3.5)),
        "too much head motion"
    );
    assert_valid_gltf(&out.join("mama.glb"));
    // A language eSpeak NG does not speak (a misspelt one) is refused by name, with or
    // without a transcript, before anything is written: it would choose the route as if it
    // were another language's.
    for more in [&["--text", line][..], &[]] {
        let nowhere = out.join("nowhere.json");
        let _ = std::fs::remove_file(&nowhere);
        let args: Vec<&str> = ["lipsync", wav.to_str().unwrap(), "--clip"]
            .into_iter()
            .chain([nowhere.to_str().unwrap(), "--language", "englsh"])
            .chain(more.iter().copied())
            .collect();
        let run = faceanim(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{stderr}");
        assert!(
            stderr.contains("--language englsh: eSpeak NG has no language or voice 'englsh'"),
            "{stderr}"
        );
        assert!(!nowhere.exists());
    }
}

#[test]
fn the_studio_aligns_dropped_speech_to_its_transcript_in_its_language_and_voice() {
    let out = output_dir("lipsync-studio-languages");
    let wav = out.join("pablo.wav");
    espeak_ng("es+m3", "150", "El perro de Pablo bebe mucho.", &wav);
    let bytes = std::fs::read(&wav).unwrap();
    let studio = start_on(None, &out.join("project.json"), &[]);
    let upload = |query: &str| {
        request(
            studio.port,
            "POST",
            &format!("/api/capture/upload?{query}"),
            &[("x-filename", "pablo.wav")],
            &bytes,
        )
    };
    let (status, state) = upload("text=El%20perro%20de%20Pablo%20bebe%20mucho.&language=es");
    assert_eq!(status, 200, "{state}");
    let state: Value = serde_json::from_str(&state).unwrap();
    assert!(
        state["notice"].is_null(),
        "the transcript was used: {state}"
    );
    assert!(peak(&state["take"]["weights"]) > 0.3, "{state}");
    // As a POSIX locale names it (the field once refused the `.`), the same language.
    let (status, state) =
        upload("text=El%20perro%20de%20Pablo%20bebe%20mucho.&language=es_ES.UTF-8");
    assert_eq!(status, 200, "{state}");
    let state: Value = serde_json::from_str(&state).unwrap();
    assert!(state["notice"].is_null(), "Spanish by its locale: {state}");
    // Without the language the Spanish words are not English: the note says what was done.
    let (status, state) = upload("text=El%20perro%20de%20Pablo%20bebe%20mucho.");
    assert_eq!(status, 200, "{state}");
    let state: Value = serde_json::from_str(&state).unwrap();
    let notice = state["notice"].as_str().unwrap_or_default();
    assert!(notice.starts_with("pablo.wav: "), "{state}");
    // A language that is not a name is refused, naming the field.
    let (status, body) = upload("language=es%3Brm");
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("language"), "{body}");
    // So is a name eSpeak NG does not speak (the page's field is free text).
    let (status, body) = upload("language=sp");
    assert_eq!(status, 400, "{body}");
    assert!(
        body.contains("language: eSpeak NG has no language or voice 'sp'"),
        "{body}"
    );
    // Whose voice it is: every choice the page offers is one the studio takes, and reaches the
    // recogniser (heard through another vocal tract, the phones recognised differ).
    let page = std::fs::read_to_string(support::repo().join("web/index.html")).unwrap();
    let select = page
        .split_once("id=\"speech-voice\"")
        .and_then(|(_, rest)| rest.split_once("</select>"))
        .expect("the page's voice choice")
        .0;
    let choices: Vec<&str> = select
        .split("value=\"")
        .skip(1)
        .filter_map(|v| v.split_once('"').map(|(value, _)| value))
        .collect();
    assert!(choices.len() >= 4, "{choices:?}");
    let mut takes = Vec::new();
    for voice in &choices {
        let (status, state) = upload(&format!("language=es&voice={voice}"));
        assert_eq!(status, 200, "voice {voice}: {state}");
        let state: Value = serde_json::from_str(&state).unwrap();
        takes.push(state["take"]["weights"].clone());
    }
    let deeper = choices
        .iter()
        .position(|v| *v == "0.8")
        .expect("deeper than a man's");
    assert_ne!(
        takes[0], takes[deeper],
        "heard as {} and as 0.8",
        choices[0]
    );
    let (status, body) = upload("voice=robot");
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("voice"), "{body}");

    // A transcript file picked with the speech is read as the command line reads --text, in
    // the code page it was saved in (a Japanese subtitle in Shift_JIS, which the page cannot
    // tell apart), cues and all; a picture is refused by name.
    let cue = "1\r\n00:00:00,000 --> 00:00:02,000\r\n今日は天気がいいですね。\r\n";
    let utf8 = out.join("cue.utf8.srt");
    std::fs::write(&utf8, cue).unwrap();
    let shift_jis = Command::new("iconv")
        .args(["-f", "UTF-8", "-t", "SHIFT_JIS"])
        .arg(&utf8)
        .output()
        .expect("iconv (glibc's, in every Debian)");
    assert!(shift_jis.status.success(), "{shift_jis:?}");
    let read = |name: &str, query: &str, bytes: &[u8]| {
        let (status, body) = request(
            studio.port,
            "POST",
            &format!("/api/capture/transcript{query}"),
            &[("x-filename", name)],
            bytes,
        );
        (
            status,
            serde_json::from_str::<Value>(&body).unwrap_or(Value::String(body)),
        )
    };
    let (status, sjis) = read("cue.srt", "?language=ja", &shift_jis.stdout);
    assert_eq!(status, 200, "{sjis}");
    assert_eq!(sjis["text"], cue, "{sjis}");
    assert_eq!(sjis["encoding"], "Shift_JIS");
    let note = sjis["note"].as_str().unwrap_or_default();
    assert!(
        note.contains("cue.srt") && note.contains("Shift_JIS"),
        "{sjis}"
    );
    let (status, plain) = read("cue.srt", "", cue.as_bytes());
    assert_eq!((status, &plain["text"]), (200, &Value::from(cue)));
    assert!(plain["note"].is_null(), "{plain}");
    // A PNG's first bytes: its signature and header chunk.
    let png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01\0\0\0\x01\x08\x06\0\0\0\x1f\x15\xc4\x89";
    let (status, body) = read("photo.srt", "?language=ja", png);
    assert_eq!(status, 400, "{body}");
    assert!(body.to_string().contains("photo.srt"), "{body}");
    // The page offers exactly the files lip sync reads as transcripts.
    let page = std::fs::read_to_string(support::repo().join("web/capture.js")).unwrap();
    let line = page
        .lines()
        .find(|l| l.starts_with("export const TRANSCRIPT = "))
        .expect("the page's TRANSCRIPT pattern");
    let list = line
        .trim_start_matches("export const TRANSCRIPT = /\\.(")
        .trim_end_matches(")$/i;");
    let mut offered: Vec<&str> = list.split('|').collect();
    offered.sort_unstable();
    let mut read_by_lip_sync = faceanim_speech::script::TRANSCRIPT_FILES.to_vec();
    read_by_lip_sync.sort_unstable();
    assert_eq!(offered, read_by_lip_sync);
    // The page says how lip sync reaches the character for every route it can take.
    let page = std::fs::read_to_string(support::repo().join("web/visemes.js")).unwrap();
    use faceanim_speech::Route;
    for route in [
        Route::Visemes,
        Route::Arkit,
        Route::Adapter,
        Route::Retarget,
        Route::JawBone,
    ] {
        // A route added to the enum must be added above (and to the page).
        match route {
            Route::Visemes | Route::Arkit | Route::Adapter | Route::Retarget | Route::JawBone => {}
        }
        let name = serde_json::to_value(route).unwrap();
        let name = name.as_str().unwrap();
        assert!(
            page.contains(&format!("\n  {name}: '")),
            "web/visemes.js says nothing of the route {name}"
        );
    }
}

/// A line saved as people's editors save it.
struct Saved {
    language: &'static str,
    /// What is spoken, as eSpeak NG reads it best.
    said: &'static str,
    /// The transcript as typed.
    typed: &'static str,
    /// Its file's kind.
    kind: &'static str,
    /// The encoding it is saved in (GNU iconv's name).
    encoding: &'static str,
    /// The code page a note should name.
    guessed: Option<&'static str>,
}

const SAVED: [Saved; 3] = [
    Saved {
        language: "ja",
        said: "きょうわ、てんきがいいですね。",
        typed: "1\r\n00:00:00,000 --> 00:00:04,000\r\n今日は、天気がいいですね。\r\n",
        kind: "srt",
        encoding: "SHIFT_JIS",
        guessed: Some("Shift_JIS"),
    },
    Saved {
        language: "ru",
        said: "Папа купил большую белую машину.",
        typed: "Папа купил большую белую машину.",
        kind: "txt",
        encoding: "CP1251",
        guessed: Some("windows-1251"),
    },
    Saved {
        language: "en-us",
        said: "Bob brought a big purple map.",
        typed: "Bob brought a big purple map.",
        kind: "txt",
        encoding: "UTF-16",
        guessed: None,
    },
];

/// Transcripts as people's editors save them: a Japanese subtitle in Shift_JIS (as subtitle
/// sites and Japanese Windows programs keep them), a Russian line in windows-1251, an English
/// line as Notepad saves "Unicode" (UTF-16 with its byte-order mark), each written by GNU
/// iconv, lip-sync exactly as the same transcript in UTF-8 does; a transcript in a code page
/// says which one it was read in.
#[test]
fn transcripts_saved_in_a_code_page_or_utf16_lip_sync_as_in_utf8() {
    let out = output_dir("lipsync-encodings");
    for Saved {
        language,
        said,
        typed,
        kind,
        encoding,
        guessed,
    } in SAVED
    {
        let wav = out.join(format!("{language}.wav"));
        espeak_ng(language, "150", said, &wav);
        let run = |transcript: &Path| {
            run_lipsync(
                &wav,
                &[
                    "--text",
                    transcript.to_str().unwrap(),
                    "--language",
                    language,
                ],
                &out.join(format!("{language}.csv")),
            )
            .0
        };
        let utf8 = out.join(format!("{language}.utf8.{kind}"));
        std::fs::write(&utf8, typed).unwrap();
        let saved = out.join(format!("{language}.{encoding}.{kind}"));
        let iconv = Command::new("iconv")
            .args(["-f", "UTF-8", "-t", encoding])
            .arg(&utf8)
            .output()
            .expect("iconv (glibc's, in every Debian)");
        assert!(iconv.status.success(), "{iconv:?}");
        std::fs::write(&saved, &iconv.stdout).unwrap();
        let (want, got) = (run(&utf8), run(&saved));
        assert_eq!(got["phones"], want["phones"], "{language} in {encoding}");
        assert!(
            !want["phones"].as_array().unwrap().is_empty(),
            "{language}: {want}"
        );
        let notes: Vec<&str> = got["notes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        let said_how = notes.iter().find(|n| n.contains("not Unicode"));
        match guessed {
            Some(name) => assert!(
                said_how.is_some_and(|n| n.contains(name)),
                "{language} in {encoding}: {notes:?}"
            ),
            None => assert!(said_how.is_none(), "{language} in {encoding}: {notes:?}"),
        }
    }
}

/// `text` spoken into `wav` by the `espeak-ng` program with `voice` at `rate` words a minute.
fn espeak_ng(voice: &str, rate: &str, text: &str, wav: &Path) {
    let spoke = Command::new("espeak-ng")
        .args(["-v", voice, "-s", rate, "-w"])
        .arg(wav)
        .arg(text)
        .output()
        .expect("espeak-ng is needed: run scripts/setup.sh");
    assert!(spoke.status.success(), "{spoke:?}");
}

fn ffmpeg(args: &[&str]) {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(args)
        .output()
        .expect("ffmpeg");
    assert!(out.status.success(), "{out:?}");
}

#[test]
fn a_studio_wav_lip_syncs_without_ffmpeg_as_it_does_with_it() {
    let out = output_dir("lipsync-no-ffmpeg");
    let (line, text) = (
        out.join("line.wav"),
        "Bob brought a big purple map to the bumpy boat.",
    );
    flite("slt", text, &line);
    // A DAW's export: 44.1 kHz, stereo, 24-bit.
    let studio = out.join("studio.wav");
    let (from, to, pcm24) = (
        line.to_str().unwrap(),
        studio.to_str().unwrap(),
        "pcm_s24le",
    );
    ffmpeg(&["-i", from, "-ar", "44100", "-ac", "2", "-c:a", pcm24, to]);
    let with = out.join("with.json");
    faceanim_ok(&[
        "lipsync",
        studio.to_str().unwrap(),
        "--text",
        text,
        "-o",
        with.to_str().unwrap(),
    ]);
    // The same command where no program named ffmpeg can be found.
    let nowhere = tempfile::tempdir().unwrap();
    let without = out.join("without.json");
    let ran = Command::new(env!("CARGO_BIN_EXE_faceanim"))
        .args(["lipsync", studio.to_str().unwrap(), "--text", text, "-o"])
        .arg(&without)
        .env("PATH", nowhere.path())
        .output()
        .unwrap();
    assert!(ran.status.success(), "{ran:?}");
    let [with, without] = [&with, &without]
        .map(|p| serde_json::from_slice::<Value>(&std::fs::read(p).unwrap()).unwrap());
    let rows = |clip: &Value| -> Vec<f64> {
        clip["frames"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|r| r.as_array().unwrap().iter().map(|w| w.as_f64().unwrap()))
            .collect()
    };
    let (a, b) = (rows(&with), rows(&without));
    assert_eq!(a.len(), b.len(), "as many frames");
    // The mouth moves the same: each frame's weights within a few hundredths.
    let mean = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f64>() / a.len() as f64;
    let fps = with["fps"].as_f64().unwrap();
    let tens = (with["frames"].as_array().unwrap().len() as f64 / fps * 100.0) as usize;
    let r = support::correlation(&mouth(&with, tens), &mouth(&without, tens));
    assert!(
        mean < 0.01 && r > 0.95,
        "without ffmpeg: weights {mean} apart on average, mouth at r {r}"
    );
    eprintln!("without ffmpeg: weights {mean:.4} apart on average, mouth at r {r:.3}");
}

#[test]
fn silence_and_noise_keep_the_mouth_closed_and_bad_files_are_named() {
    let out = output_dir("lipsync-bad");
    // Three seconds each of digital silence, pink noise and mains hum, as ffmpeg makes them.
    let [silence, noise, hum] = [
        ("silence.wav", "anullsrc=r=16000:cl=mono:d=3"),
        ("noise.mp3", "anoisesrc=d=3:c=pink:a=0.2"),
        ("hum.ogg", "sine=f=50:d=3"),
    ]
    .map(|(name, source)| {
        let path = out.join(name);
        ffmpeg(&[
            "-f",
            "lavfi",
            "-i",
            source,
            "-t",
            "3",
            path.to_str().unwrap(),
        ]);
        path
    });
    for quiet in [&silence, &noise, &hum] {
        let (_, clip) = run_lipsync(quiet, &[], &out.join("quiet.json"));
        let most = peak(&clip["frames"]);
        assert!(
            most < 0.01,
            "{}: the mouth moved to {most}",
            quiet.display()
        );
    }
    let empty = out.join("empty.wav");
    std::fs::write(&empty, []).unwrap();
    let text = out.join("notes.wav");
    std::fs::write(&text, "these are not sounds").unwrap();
    let cut = out.join("cut.wav");
    let whole = std::fs::read(&silence).unwrap();
    std::fs::write(&cut, &whole[..30]).unwrap();
    let long = out.join("long.flac");
    ffmpeg(&[
        "-f",
        "lavfi",
        "-i",
        "anullsrc=r=8000:cl=mono",
        "-t",
        "3700",
        long.to_str().unwrap(),
    ]);
    let picture = support::repo().join("web/favicon.png");
    let mut cases = vec![
        (empty, "empty.wav: there is no sound"),
        (text, "notes.wav"),
        (cut, "cut.wav"),
        (long, "long.flac: more than 3600 s of sound; at most 3600 s"),
        (out.join("missing.wav"), "missing.wav"),
    ];
    if picture.exists() {
        cases.push((picture, "favicon.png"));
    }
    for (file, says) in cases {
        let run = faceanim(&[
            "lipsync",
            file.to_str().unwrap(),
            "--clip",
            out.join("x.json").to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{}: {stderr}", file.display());
        assert!(stderr.contains(says), "{}: {stderr}", file.display());
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // A character or an adapter that is not there is named before any speech is heard.
    for option in ["--character", "--adapter"] {
        let missing = out.join("missing.glb");
        let run = faceanim(&[
            "lipsync",
            noise.to_str().unwrap(),
            option,
            missing.to_str().unwrap(),
            "--clip",
            out.join("x.json").to_str().unwrap(),
            "-v",
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{option}: {stderr}");
        assert!(stderr.contains("missing.glb"), "{option}: {stderr}");
        assert!(
            !stderr.contains("as the recogniser hears it"),
            "{option}: the speech was heard first: {stderr}"
        );
    }
}

#[test]
fn the_studio_lip_syncs_dropped_speech_and_layers_a_stroke_on_it() {
    let out = output_dir("lipsync-studio");
    let (wav, _) = librivox().into_iter().nth(3).unwrap();
    let bytes = std::fs::read(&wav).unwrap();
    let studio = start_on(None, &out.join("project.json"), &[]);
    let (status, state) = request(
        studio.port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", "line.wav")],
        &bytes,
    );
    assert_eq!(status, 200, "{state}");
    let state: Value = serde_json::from_str(&state).unwrap();
    let take = &state["take"];
    assert_eq!(take["estimator"], "received", "{take}");
    let sound = take["sound"].as_str().unwrap();
    assert!(sound.starts_with("api/capture/sound"), "{take}");
    let seconds = (bytes.len() - 44) as f64 / 32_000.0;
    let frames = take["frames"].as_u64().unwrap() as f64;
    assert!(
        ((frames - 1.0) / 30.0 - seconds).abs() < 0.05,
        "{frames} frames for {seconds} s"
    );
    // The mouth moves in it.
    let most = peak(&take["weights"]);
    assert!(most > 0.3, "{most}");
    // The page gets the sound back to play.
    let (status, played) = request_bytes(studio.port, "GET", &format!("/{sound}"), &[], b"");
    assert_eq!(status, 200);
    assert_eq!(played, bytes);
    // A stroke on top: the built-in head's left brow raised.
    let stroke = stroke_along(
        &faceanim_head::default_character(),
        "browOuterUpLeft",
        30,
        1.0 / 60.0,
    );
    let (status, sketch) = request(studio.port, "POST", "/api/strokes", &[], stroke.as_bytes());
    assert_eq!(status, 200, "{sketch}");
    let sketch: Value = serde_json::from_str(&sketch).unwrap();
    assert_eq!(
        sketch["actions"][0]["sides"][0]["target"], "browOuterUpLeft",
        "{sketch}"
    );
    let (_, glb) = support::get_with_head(studio.port, "/api/capture/export.glb");
    let (_, clip) = support::get_with_head(studio.port, "/api/capture/export.json");
    drop(studio);
    // Closed and opened again, the take plays with its sound: kept beside the project, not in
    // a temporary folder.
    let kept = out.join(".project.json.take.sound.wav");
    assert_eq!(
        std::fs::read(&kept).unwrap(),
        bytes,
        "the sound is not kept beside the project"
    );
    let studio = start_on(None, &out.join("project.json"), &[]);
    let (_, state) = request(studio.port, "GET", "/api/capture/state", &[], b"");
    let state: Value = serde_json::from_str(&state).unwrap();
    assert_eq!(state["take"]["frames"], frames as u64, "{}", state["take"]);
    let sound = state["take"]["sound"]
        .as_str()
        .unwrap_or_else(|| panic!("the reopened take has no sound: {}", state["take"]));
    let (status, played) = request_bytes(studio.port, "GET", &format!("/{sound}"), &[], b"");
    assert_eq!(
        (status, played == bytes),
        (200, true),
        "the reopened take's sound"
    );
    drop(studio);
    let exported = out.join("layered.glb");
    std::fs::write(&exported, glb).unwrap();
    assert_valid_gltf(&exported);
    // The exported clip has the lip sync and the stroke's brow together.
    let clip: Value = serde_json::from_slice(&clip).unwrap();
    let names = strings(&clip["blendshapes"]);
    let (jaw, brow) = (
        names.iter().position(|n| *n == "jawOpen").unwrap(),
        names.iter().position(|n| *n == "browOuterUpLeft").unwrap(),
    );
    let rows = clip["frames"].as_array().unwrap();
    let peak = |i: usize| {
        rows.iter()
            .map(|r| r[i].as_f64().unwrap())
            .fold(0.0, f64::max)
    };
    assert!(peak(jaw) > 0.3, "the lip sync's jaw: {}", peak(jaw));
    assert!(peak(brow) > 0.5, "the stroke's brow: {}", peak(brow));
}

/// A chunk of 16-bit samples (as bytes) sent to the studio's microphone at `rate`.
fn chunk(port: u16, rate: &str, bytes: &[u8]) -> (u16, String) {
    request(
        port,
        "POST",
        "/api/capture/voice/chunk",
        &[("x-sample-rate", rate)],
        bytes,
    )
}

/// A JSON request to the studio; its status and answer.
fn send(port: u16, method: &str, path: &str, body: &str) -> (u16, Value) {
    let (status, answer) = request(
        port,
        method,
        path,
        &[("Content-Type", "application/json")],
        body.as_bytes(),
    );
    (
        status,
        serde_json::from_str(&answer).unwrap_or(Value::String(answer)),
    )
}

/// A studio on `character` (the built-in head for `None`), its project in `out`, sending VMC
/// to an independent peer (`vmc_receiver`) that keeps `frames` frames, for `seconds` at most:
/// the studio, the peer and its report.
fn studio_sending_vmc(
    character: Option<&Path>,
    out: &Path,
    frames: usize,
    seconds: f32,
    names: &str,
) -> (support::Studio, std::process::Child, PathBuf) {
    let report = out.join("vmc.json");
    let (peer, vmc_port) = vmc_receiver(frames, seconds, &report);
    let to = format!("127.0.0.1:{vmc_port}");
    let send = [
        "--vmc-send".as_ref(),
        to.as_ref(),
        "--vmc-names".as_ref(),
        names.as_ref(),
    ];
    let studio = start_on(character, &out.join("project.json"), &send);
    (studio, peer, report)
}

/// Starts (`on`) or ends the studio's microphone recording; the state after.
fn record_microphone(port: u16, on: bool) -> Value {
    let body = format!(r#"{{"on": {on}}}"#);
    let (status, state) = send(port, "POST", "/api/capture/voice/record", &body);
    assert_eq!(status, 200, "{state}");
    state
}

/// Sends `samples` to the studio's microphone, `size` samples a request; the last answer.
fn speak(port: u16, samples: &[i16], size: usize) -> Value {
    let mut last = Value::Null;
    for part in samples.chunks(size) {
        let bytes: Vec<u8> = part.iter().flat_map(|s| s.to_le_bytes()).collect();
        let (status, body) = chunk(port, "16000", &bytes);
        assert_eq!(status, 200, "{body}");
        last = serde_json::from_str(&body).unwrap();
    }
    last
}

/// The studio's live microphone through its API, as the page drives it (the page itself is
/// `tools/capture-e2e.mjs`): a synthetic voice reads the calibration passage and the voice is
/// learned; a real person (the LibriVox readings, one after the other) is recorded into a take
/// with its sound, which exports and validates; the mouth goes out over VMC to an independent
/// peer (PyPI's python-osc); bad chunks and delays are refused by name.
#[test]
fn the_studio_microphone_learns_a_voice_drives_vmc_and_records_a_take() {
    let out = output_dir("lipsync-microphone");
    let (studio, mut peer, report) = studio_sending_vmc(None, &out, 30, 120.0, "own");
    let port = studio.port;
    let start = |delay: u32| {
        let body = format!(r#"{{"on": true, "delay_ms": {delay}}}"#);
        send(port, "PUT", "/api/capture/voice", &body)
    };
    let (status, body) = start(5000);
    assert_eq!(status, 400, "{body}");
    assert!(body.to_string().contains("delay_ms"), "{body}");
    // A chunk still on its way when the microphone stops is dropped, not an error.
    let (status, body) = chunk(port, "16000", &[0; 64]);
    assert_eq!(status, 200, "{body}");
    assert!(body.contains(r#""live":false"#), "{body}");
    // Held back by 300 ms (a stream's audio delay): the first 200 ms give no mouth yet, the
    // next do; then the delay is taken off while the microphone runs.
    let (status, body) = start(300);
    assert_eq!(status, 200, "{body}");
    assert_eq!(body["voice"]["delay_ms"], 300, "{body}");
    let silence = vec![0i16; 3200];
    assert_eq!(speak(port, &silence, 3200)["weights"], Value::Null);
    assert!(speak(port, &silence, 3200)["weights"].is_array());
    let (status, body) = start(0);
    assert_eq!(body["voice"]["delay_ms"], 0, "{status} {body}");
    // The language spoken: English unless said; another's passage to read, or none (speak
    // freely) where the studio has none; a language eSpeak NG does not speak is named.
    assert_eq!(body["voice"]["language"], "en-us", "{body}");
    for (language, passage) in [
        (
            "es-MX",
            Some(faceanim_speech::listen::passage("es").unwrap()),
        ),
        ("sw", None),
        ("en-us", Some(faceanim_speech::listen::PASSAGE)),
    ] {
        let body = format!(r#"{{"on": true, "language": "{language}"}}"#);
        let (status, body) = send(port, "PUT", "/api/capture/voice", &body);
        assert_eq!(status, 200, "{body}");
        assert_eq!(body["voice"]["passage"].as_str(), passage, "{body}");
    }
    let (status, body) = send(
        port,
        "PUT",
        "/api/capture/voice",
        r#"{"on": true, "language": "zzz"}"#,
    );
    assert_eq!(status, 400, "{body}");
    assert!(body.to_string().contains("language"), "{body}");
    for (rate, bytes, named) in [("44100", 64, "x-sample-rate"), ("16000", 63, "chunk")] {
        let (status, body) = chunk(port, rate, &vec![0; bytes]);
        assert_eq!(status, 400, "{body}");
        assert!(body.contains(named), "{body}");
    }

    // Calibration: the passage read by a voice the studio never heard, sent faster than real
    // time; the voice is learned in the background.
    let passage = out.join("passage.wav");
    flite("rms", faceanim_speech::listen::PASSAGE, &passage);
    let (read, rate) = samples(&passage);
    assert_eq!(rate, 16_000);
    let (status, body) = send(port, "POST", "/api/capture/voice/calibrate", "{}");
    assert_eq!(status, 200, "{body}");
    let answer = speak(port, &read[..(21 * 16_000).min(read.len())], 3200);
    assert_eq!(answer["live"], true, "{answer}");
    let calibrated = (0..1200)
        .find_map(|_| {
            let (_, state) = send(port, "GET", "/api/capture/state", "");
            let calibration = state["voice"]["calibration"].clone();
            if calibration["state"] == "fitting" {
                std::thread::sleep(std::time::Duration::from_millis(50));
                None
            } else {
                Some(calibration)
            }
        })
        .expect("calibration never finished");
    assert_eq!(calibrated["state"], "calibrated", "{calibrated}");
    assert!(
        calibrated["visemes"].as_u64().unwrap() >= 12,
        "{calibrated}"
    );
    assert_eq!(calibrated["notes"], serde_json::json!([]), "{calibrated}");

    // A real person, recorded.
    record_microphone(port, true);
    let mut person = Vec::new();
    for (wav, _) in librivox() {
        person.extend(samples(&wav).0);
    }
    let answer = speak(port, &person, 320);
    assert!(
        answer["voice"]["recording"].as_f64().unwrap() > 20.0,
        "{answer}"
    );
    let state = record_microphone(port, false);
    let take = &state["take"];
    let seconds = person.len() as f64 / 16_000.0;
    let frames = take["frames"].as_u64().unwrap() as f64;
    assert!(
        (frames / 30.0 - seconds).abs() < 0.1,
        "{frames} frames for {seconds} s"
    );
    assert!(peak(&take["weights"]) > 0.3, "{}", peak(&take["weights"]));
    let sound = take["sound"].as_str().unwrap();
    let (status, played) = request_bytes(port, "GET", &format!("/{sound}"), &[], b"");
    assert_eq!(status, 200);
    assert_eq!(played.len(), 44 + 2 * person.len());
    let (status, glb) = request_bytes(port, "GET", "/api/capture/export.glb", &[], b"");
    assert_eq!(status, 200);
    let exported = out.join("microphone.glb");
    std::fs::write(&exported, glb).unwrap();
    assert_valid_gltf(&exported);
    drop(studio);

    // Out over VMC: the peer saw the mouth move.
    let jaw = support::vmc_values(&mut peer, &report, "jawOpen");
    assert!(
        jaw.iter().any(|w| *w > 0.1),
        "the mouth never went out: {jaw:?}"
    );
}

/// The studio's live microphone on a body with no blendshapes (the Blender avatar exported
/// without shape keys): a real person's reading opens the view's jaw bone as it is heard, the
/// jaw goes out over VMC as the `Jaw` bone (python-osc decodes it) and, in ARKit's names, as
/// the line's own JawOpen (the body has no shape to make it), and the recording is a take
/// whose jaw bone opens and whose Clip JSON holds the line's jawOpen. The microphone kept the
/// character's weights alone before: the body's jaw stayed shut live and in the take.
#[test]
fn the_microphone_opens_the_jaw_bone_of_a_body_with_no_shapes() {
    let out = output_dir("lipsync-microphone-bare");
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let (studio, mut peer, report) = studio_sending_vmc(Some(&bare), &out, 200, 60.0, "arkit");
    let port = studio.port;
    let (status, body) = send(port, "PUT", "/api/capture/voice", r#"{"on": true}"#);
    assert_eq!(status, 200, "{body}");
    record_microphone(port, true);
    // The jaw is the view's last joint: its turn from rest, in degrees, per answer.
    let opened = |bones: &Value| {
        let jaw = bones.as_array().unwrap().last().unwrap();
        let q = glam::Quat::from_slice(&support::f32s(jaw));
        f64::from(q.angle_between(glam::Quat::IDENTITY).to_degrees())
    };
    let (wav, _) = &librivox()[0];
    let person = samples(wav).0;
    let mut widest: f64 = 0.0;
    for part in person.chunks(320) {
        let bytes: Vec<u8> = part.iter().flat_map(|s| s.to_le_bytes()).collect();
        let (status, body) = chunk(port, "16000", &bytes);
        assert_eq!(status, 200, "{body}");
        let answer: Value = serde_json::from_str(&body).unwrap();
        if answer["weights"].is_array() {
            widest = widest.max(opened(&answer["bones"]));
        }
    }
    assert!(widest > 5.0, "the view's jaw opened at most {widest}°");
    // Out over VMC (the peer has its frames): the Jaw bone turned down (about Unity's X)
    // while the person spoke.
    let turns: Vec<f64> = support::vmc_numbers(&mut peer, &report, "/VMC/Ext/Bone/Pos", "Jaw")
        .iter()
        .map(|pose| 2.0 * pose[3].asin().to_degrees())
        .collect();
    assert!(
        turns.iter().any(|t| *t > 2.0),
        "the Jaw bone never went out open: {turns:?}"
    );
    // In ARKit's names (`--vmc-names arkit`) the body with no shapes sends the line's own
    // values: each frame's JawOpen is its Jaw bone's turn.
    let mut opened_by_name: Vec<f64> = Vec::new();
    for (value, turned) in support::vmc_jaw_pairs(&report) {
        assert!(
            (value * 20.0 - turned).abs() < 0.01,
            "JawOpen {value} went out with the Jaw bone turned {turned}°"
        );
        opened_by_name.push(value);
    }
    let widest_by_name = opened_by_name.iter().copied().fold(0.0, f64::max);
    assert!(
        widest_by_name > 0.1,
        "JawOpen went out in {} frames, at most {widest_by_name}",
        opened_by_name.len()
    );
    let state = record_microphone(port, false);
    let take = &state["take"];
    let frames = take["bones"].as_array().unwrap();
    let take_widest = frames.iter().map(opened).fold(0.0, f64::max);
    let rests = frames.iter().filter(|b| opened(b) < 0.5).count();
    assert!(
        take_widest > 5.0 && rests > 0,
        "the take's jaw opened at most {take_widest}°, rested in {rests} of {} frames",
        frames.len()
    );
    let (status, clip) = request_bytes(port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200);
    let clip: Value = serde_json::from_slice(&clip).unwrap();
    let names = strings(&clip["blendshapes"]);
    assert!(names.iter().any(|n| n == "jawOpen"), "{names:?}");
}

/// A rig whose shape names say nothing of a mouth (ICT's head with every shape renamed
/// `shape_N`, in reverse order): lip sync reaches its mouth through its retarget map (made
/// and kept beside it), and through its adapter when one is given (each viseme the built-in
/// head makes, read by the adapter); either way the shape that is ICT's jawOpen opens while
/// a synthetic voice speaks and rests before it does. The studio, given the line with no map
/// there, makes the map first and gives the command's take.
#[test]
fn a_rig_without_mouth_names_lip_syncs_through_its_map_or_its_adapter() {
    let out = output_dir("lipsync-adapter");
    let mut parts = faceanim_testdata::ict().to_parts();
    let count = parts.blendshapes.len();
    let jaw_was = parts
        .blendshapes
        .iter()
        .position(|b| b.name() == "jawOpen")
        .unwrap();
    parts.blendshapes.reverse();
    if let Some(normals) = parts.normal_deltas.as_mut() {
        normals.reverse();
    }
    parts.blendshapes = support::renamed_shapes(&parts.blendshapes, glam::Quat::IDENTITY);
    let jaw = format!("shape_{}", count - 1 - jaw_was);
    let character = faceanim_rig::Character::new(parts).unwrap();
    let glb = out.join("unnamed.glb");
    std::fs::write(&glb, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    let speech = out.join("line.wav");
    flite(
        "slt",
        "Bob and Mary moved the heavy boxes up the narrow path.",
        &speech,
    );
    let clip = out.join("clip.json");
    let args = |more: &[&str]| {
        let mut all = vec![
            "lipsync".to_owned(),
            speech.display().to_string(),
            "--character".into(),
            glb.display().to_string(),
            "-o".into(),
            clip.display().to_string(),
            "--json".into(),
        ];
        all.extend(more.iter().map(|s| (*s).to_owned()));
        all
    };
    // Geometry first: lip sync makes the rig's retarget map (saved beside it) and puts each
    // viseme's channels on the shapes that move the face as they do.
    let map = out.join("unnamed.retarget.json");
    let _ = std::fs::remove_file(&map);
    let jaw_of = |clip: &Value| -> Vec<f64> {
        let names = strings(&clip["blendshapes"]);
        let column = names.iter().position(|n| *n == jaw).unwrap();
        let rows = clip["frames"].as_array().unwrap();
        rows.iter().map(|r| r[column].as_f64().unwrap()).collect()
    };
    let summary = faceanim_ok(&args(&[]).iter().map(String::as_str).collect::<Vec<_>>());
    let summary: Value = serde_json::from_str(summary.trim()).unwrap();
    assert_eq!(summary["route"], "retarget", "{summary}");
    assert!(map.exists(), "the map is kept beside the character");
    let by_map = jaw_of(&serde_json::from_slice(&std::fs::read(&clip).unwrap()).unwrap());
    let most = by_map.iter().copied().fold(0.0, f64::max);
    println!("through the map, {jaw} (ICT's jawOpen) peaks at {most:.2}");
    assert!(most > 0.25, "{by_map:?}");
    assert!(by_map[0] < 0.05, "{by_map:?}");
    // The studio, asked to lip-sync the same line on the same rig with no map, makes the map
    // first (a job, as `faceanim lipsync` makes it), then the same take.
    std::fs::remove_file(&map).unwrap();
    // (An adapter beside it, from an earlier run, would read the mouth instead.)
    let _ = std::fs::remove_file(out.join("unnamed.adapter.safetensors"));
    let studio = start_on(Some(&glb), &out.join("unnamed.faceanim.json"), &[]);
    let (status, body) = support::upload(studio.port, "line.wav", &std::fs::read(&speech).unwrap());
    let state = support::map_made(studio.port, status, &body);
    assert!(
        map.exists(),
        "the studio keeps the map beside the character"
    );
    assert!(state["take"]["sound"].is_string(), "{}", state["take"]);
    let (status, body) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{body}");
    let in_studio = jaw_of(&serde_json::from_str(&body).unwrap());
    drop(studio);
    assert_eq!(in_studio.len(), by_map.len());
    let apart = in_studio
        .iter()
        .zip(&by_map)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        apart < 0.02,
        "the studio's take is apart by {apart}: {in_studio:?}"
    );
    // The live microphone on the same rig with no map: starting it makes the map, and the
    // mouth rests while it waits for it (a recording goes on). Once the map is there, the line
    // opens the shape that is ICT's jawOpen while it is heard, and the silence before it does
    // not; the recording's part heard while waiting gets its mouth through the map too.
    std::fs::remove_file(&map).unwrap();
    let studio = start_on(Some(&glb), &out.join("unnamed.faceanim.json"), &[]);
    let (status, started) = request(
        studio.port,
        "PUT",
        "/api/capture/voice",
        &[("Content-Type", "application/json")],
        br#"{"on": true}"#,
    );
    let answer: Value = serde_json::from_str(&started).unwrap();
    assert_eq!(answer["voice"]["awaits_map"], true, "{}", answer["voice"]);
    record_microphone(studio.port, true);
    let (line, rate) = samples(&speech);
    assert_eq!(rate, 16_000);
    let mut heard = vec![0i16; 12_000];
    heard.extend(&line);
    let column = count - 1 - jaw_was;
    let hear = || -> Vec<(bool, f64)> {
        heard
            .chunks(1600)
            .filter_map(|part| {
                let bytes: Vec<u8> = part.iter().flat_map(|s| s.to_le_bytes()).collect();
                let (status, body) = chunk(studio.port, "16000", &bytes);
                assert_eq!(status, 200, "{body}");
                let answer: Value = serde_json::from_str(&body).unwrap();
                let waits = answer["voice"]["awaits_map"].as_bool().unwrap();
                let weights = answer["weights"].as_array()?;
                Some((waits, weights[column].as_f64().unwrap()))
            })
            .collect()
    };
    let waiting = hear();
    assert!(waiting[0].0, "the map was there at once: {waiting:?}");
    assert!(
        waiting.iter().all(|(waits, w)| !waits || *w == 0.0),
        "the mouth moved before the map: {waiting:?}"
    );
    let state = support::map_made(studio.port, status, &started);
    assert_eq!(state["voice"]["awaits_map"], false, "{}", state["voice"]);
    assert!(map.exists(), "the map is kept beside the character");
    let jaw_live: Vec<f64> = hear().into_iter().map(|(_, w)| w).collect();
    let (silent, spoken) = jaw_live.split_at(4);
    let most = spoken.iter().copied().fold(0.0, f64::max);
    println!("the microphone opens {jaw} (ICT's jawOpen) to {most:.2}");
    assert!(most > 0.25, "{jaw_live:?}");
    assert!(silent.iter().all(|w| *w < 0.05), "{jaw_live:?}");
    record_microphone(studio.port, false);
    let (status, body) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{body}");
    drop(studio);
    let recorded = jaw_of(&serde_json::from_str(&body).unwrap());
    let first = &recorded[..recorded.len() / 2];
    let most = first.iter().copied().fold(0.0, f64::max);
    println!("the recording heard while waiting opens {jaw} to {most:.2}");
    assert!(most > 0.25, "{first:?}");
    // The adapter, when given, reads the mouth instead (few renders: this checks the route;
    // the adapter tests check its accuracy).
    let adapter = out.join("unnamed.adapter.safetensors");
    let (character_arg, adapter_arg) = (glb.to_str().unwrap(), adapter.to_str().unwrap());
    faceanim_ok(&[
        "adapt",
        character_arg,
        "-o",
        adapter_arg,
        "--samples",
        "400",
    ]);
    let summary = faceanim_ok(
        &args(&["--adapter", adapter_arg])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    let summary: Value = serde_json::from_str(summary.trim()).unwrap();
    assert_eq!(summary["route"], "adapter", "{summary}");
    let jaw_curve = jaw_of(&serde_json::from_slice(&std::fs::read(&clip).unwrap()).unwrap());
    let most = jaw_curve.iter().copied().fold(0.0, f64::max);
    println!(
        "{jaw} (ICT's jawOpen) peaks at {most:.2}; first frame {:.2}",
        jaw_curve[0]
    );
    assert!(most > 0.25, "{jaw_curve:?}");
    assert!(jaw_curve[0] < 0.05, "{jaw_curve:?}");
}

/// The studio's viseme table: refused by field when wrong; a table that moves nothing keeps
/// the mouth of uploaded speech still; it is kept beside the project, read again when the
/// studio starts, and `{}` brings the built-in table back.
#[test]
fn the_studio_viseme_table_is_checked_kept_and_used() {
    let out = output_dir("lipsync-visemes");
    let project = out.join("visemes.faceanim.json");
    let _ = std::fs::remove_file(out.join("visemes.faceanim.visemes.json"));
    let studio = start_on(None, &project, &[]);
    let port = studio.port;
    let (_, view) = send(port, "GET", "/api/capture/visemes", "");
    assert_eq!(view["route"], "arkit", "{view}");
    assert_eq!(view["default"], true, "{view}");
    for (bad, named) in [
        (r#"{"aa": {"jawOpen": 2}}"#, "aa.jawOpen"),
        (r#"{"zz": {"jawOpen": 0.5}}"#, "zz"),
        (r#"{"aa": {"jawWide": 0.5}}"#, "jawWide"),
        ("[1, 2]", "viseme"),
    ] {
        let (status, body) = send(port, "PUT", "/api/capture/visemes", bad);
        assert_eq!(status, 400, "{bad}: {body}");
        assert!(body.to_string().contains(named), "{bad}: {body}");
    }
    // Every viseme moves nothing.
    let still: serde_json::Map<String, Value> = view["visemes"]
        .as_object()
        .unwrap()
        .keys()
        .map(|v| (v.clone(), serde_json::json!({ "jawOpen": 0.0 })))
        .collect();
    let (status, view) = send(
        port,
        "PUT",
        "/api/capture/visemes",
        &Value::Object(still).to_string(),
    );
    assert_eq!(status, 200, "{view}");
    assert_eq!(view["default"], false, "{view}");
    let (wav, _) = librivox().into_iter().nth(1).unwrap();
    let (status, state) = request(
        port,
        "POST",
        "/api/capture/upload",
        &[("x-filename", "line.wav")],
        &std::fs::read(&wav).unwrap(),
    );
    assert_eq!(status, 200, "{state}");
    let state: Value = serde_json::from_str(&state).unwrap();
    let most = peak(&state["take"]["weights"]);
    assert!(
        most < 1e-6,
        "a table that moves nothing moved the mouth to {most}"
    );
    drop(studio);
    assert!(out.join("visemes.faceanim.visemes.json").exists());
    let studio = start_on(None, &project, &[]);
    let (_, view) = send(studio.port, "GET", "/api/capture/visemes", "");
    assert_eq!(
        view["default"], false,
        "the table was not read again: {view}"
    );
    let (_, view) = send(studio.port, "PUT", "/api/capture/visemes", "{}");
    assert_eq!(view["default"], true, "{view}");
}
