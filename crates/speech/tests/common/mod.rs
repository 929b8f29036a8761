//! What the speech tests share: a voice that says which phone it speaks when, and the lip
//! shapes an animator checks.
#![allow(dead_code, reason = "each test binary uses its part")]

use std::path::Path;
use std::process::Command;

use faceanim_rig::names::Viseme;
use faceanim_speech::Sound;
use faceanim_speech::visemes::{index, viseme_of, viseme_of_ipa};

/// Speaks `text` in `voice` into `wav`; the visemes spoken with their end times.
pub fn flite(voice: &str, text: &str, wav: &Path) -> Vec<(Viseme, f32)> {
    let made = Command::new("flite")
        .args(["-voice", voice, "-t", text, "-o"])
        .arg(wav)
        .arg("-psdur")
        .output()
        .expect("flite is needed: run scripts/setup.sh");
    assert!(made.status.success(), "{made:?}");
    String::from_utf8_lossy(&made.stdout)
        .split_whitespace()
        .filter_map(|p| {
            let (phone, end) = p.split_once(':')?;
            Some((viseme_of(&phone.to_ascii_uppercase()), end.parse().ok()?))
        })
        .collect()
}

/// Flite's `voice` saying `text`, as a sound read from the WAV flite writes (named by `name`
/// and this process, removed once read), and the visemes spoken with their end times.
pub fn flite_sound(voice: &str, text: &str, name: &str) -> (Vec<(Viseme, f32)>, Sound) {
    let wav = std::env::temp_dir().join(format!("faceanim-{name}-{}.wav", std::process::id()));
    let said = flite(voice, text, &wav);
    let sound = Sound::read(&wav).unwrap();
    let _ = std::fs::remove_file(&wav);
    (said, sound)
}

/// What the lips do for a viseme: the classes an animator checks (the tongue's shapes are one).
pub fn class(v: Viseme) -> &'static str {
    let lips = "closed:PP lip-teeth:FF open:aa spread:E spread:ih round:oh round:ou rest:sil";
    lips.split(' ')
        .filter_map(|pair| pair.split_once(':'))
        .find(|(_, name)| *name == v.name())
        .map_or("tongue", |(class, _)| class)
}

/// The lip class a track's frame `k` (10 ms each, from `frames`) shows: its strongest
/// viseme's, or rest where none reaches 0.2 or the frame is outside the track.
pub fn shown(frames: &[[f32; 15]], k: i64) -> &'static str {
    let Some(row) = usize::try_from(k).ok().and_then(|k| frames.get(k)) else {
        return "rest";
    };
    let (best, weight) = row
        .iter()
        .enumerate()
        .fold((0, 0.0f32), |b, (i, &w)| if w > b.1 { (i, w) } else { b });
    if weight < 0.2 {
        "rest"
    } else {
        class(Viseme::ALL[best])
    }
}

/// Of the 10 ms frames of a phone spoken from `start` to `stop` seconds as `viseme`, how many
/// the track (`shown`: frame → lip class) shows in the phone's class within 40 ms, and how
/// many there are.
pub fn agreeing(
    shown: impl Fn(i64) -> &'static str,
    viseme: Viseme,
    start: f32,
    stop: f32,
) -> (usize, usize) {
    let (mut hits, mut total) = (0, 0);
    let mut t = start + 0.005;
    while t < stop {
        let k = (t * 100.0).round() as i64;
        total += 1;
        if (-4..=4).any(|d| shown(k + d) == class(viseme)) {
            hits += 1;
        }
        t += 0.01;
    }
    (hits, total)
}

/// What an eSpeak NG voice said: each phone's viseme, start and end (seconds, on the sound).
pub type Said = Vec<(Viseme, f32, f32)>;

/// `line` spoken by the eSpeak NG `voice` at `rate` words a minute (its default when `None`),
/// with half a second of silence either side, written as a WAV and read as any is, and the
/// phones it said.
pub fn espeak(line: &str, voice: &str, rate: Option<u32>) -> (Said, Sound) {
    espeak_padded(line, voice, rate, 0.5)
}

/// As [`espeak`], with `pad` seconds of silence either side (0: the line as eSpeak NG writes
/// it, trimmed to its words).
pub fn espeak_padded(line: &str, voice: &str, rate: Option<u32>, pad: f32) -> (Said, Sound) {
    assert!(
        faceanim_espeak_sys::available(),
        "eSpeak NG is needed: run scripts/setup.sh (libespeak-ng-dev) and build again"
    );
    let spoken = faceanim_espeak_sys::speak(line, voice, rate).unwrap();
    // As a user has it: the synthesiser's WAV (22,050 Hz), read as any WAV is.
    let silence = vec![0i16; (spoken.sample_rate as f32 * pad).round() as usize];
    let samples: Vec<i16> = [&silence[..], &spoken.samples, &silence].concat();
    let wav = std::env::temp_dir().join(format!(
        "faceanim-espeak-{}-{:?}.wav",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::write(
        &wav,
        faceanim_speech::audio::wav_bytes(&samples, spoken.sample_rate, 1),
    )
    .unwrap();
    let sound = Sound::read(&wav).unwrap();
    let _ = std::fs::remove_file(&wav);
    let end = spoken.samples.len() as f32 / spoken.sample_rate as f32;
    let said = spoken
        .phones
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let next = spoken
                .phones
                .get(k + 1)
                .map_or(end, |n| n.start_ms as f32 / 1000.0);
            (
                viseme_of_ipa(&p.ipa),
                pad + p.start_ms as f32 / 1000.0,
                pad + next,
            )
        })
        .collect();
    (said, sound)
}

/// How a track (`frames`, 10 ms each) shows what was `said`: the spoken frames whose lip class
/// it shows within 40 ms and all spoken frames; the bilabials whose lips it closes (viseme PP
/// at 0.5 or more, within 40 ms) and all bilabials.
pub fn judged(frames: &[[f32; 15]], said: &Said) -> [usize; 4] {
    let [mut hits, mut total, mut closed, mut bilabials] = [0; 4];
    for &(viseme, start, stop) in said {
        if viseme == Viseme::Sil {
            continue;
        }
        let (agree, spoken) = agreeing(|k| shown(frames, k), viseme, start, stop);
        (hits, total) = (hits + agree, total + spoken);
        if viseme == Viseme::PP {
            bilabials += 1;
            let (a, b) = (
                ((start - 0.04) * 100.0) as usize,
                ((stop + 0.04) * 100.0) as usize,
            );
            if (a..=b.min(frames.len().saturating_sub(1)))
                .any(|k| frames.get(k).is_some_and(|f| f[index(Viseme::PP)] >= 0.5))
            {
                closed += 1;
            }
        }
    }
    [hits, total, closed, bilabials]
}

/// `sound` read without a transcript, asserting that its phones were recognised (not its
/// words) and that a note saying `why` told the user so.
pub fn read_by_its_phones(sound: &Sound, why: &str) -> faceanim_speech::Reading {
    read_by(sound, None, faceanim_speech::Recognition::PhoneLoop, why)
}

/// `sound` read with `transcript` (or without), asserting that `route` found its phones and
/// that a note saying `why` told the user so.
pub fn read_by(
    sound: &Sound,
    transcript: Option<&str>,
    route: faceanim_speech::Recognition,
    why: &str,
) -> faceanim_speech::Reading {
    let reading =
        faceanim_speech::read(sound, transcript, None, faceanim_speech::Recognition::Words)
            .unwrap();
    assert_eq!(reading.recognition, route, "{:?}", reading.notes);
    assert!(
        reading.notes.iter().any(|n| n.contains(why)),
        "{:?}",
        reading.notes
    );
    reading
}
