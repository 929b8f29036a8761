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
