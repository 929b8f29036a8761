//! What the speech tests share: a voice that says which phone it speaks when, and the lip
//! shapes an animator checks.
#![allow(dead_code, reason = "each test binary uses its part")]

use std::path::Path;
use std::process::Command;

use faceanim_rig::names::Viseme;
use faceanim_speech::visemes::viseme_of;

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
