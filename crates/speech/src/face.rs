//! The face around the mouth (`faceanim lipsync --face`): what a speaker's eyes and brows do
//! while the mouth speaks, so that a lip-synced line does not stare.
//!
//! - **Blinks** at phrase boundaries (a pause of at least [`PHRASE_PAUSE`], just after the
//!   voice stops), and wherever [`LONGEST_WITHOUT`] passes without one, at the next end of a
//!   vowel; each closes in 80 ms, holds 40 ms and opens in 160 ms.
//! - **Brows** rise on accents: a syllable clearly louder than the speech around it (its
//!   loudness [`ACCENT_DB`] over the line's speaking level), at most one every
//!   [`ACCENT_SPACING`]; they rise over 120 ms, hold for the syllable and settle over 300 ms.
//!
//! - **The head** nods on the same accents (the chin dips [`NOD_DEGREES`] as the syllable
//!   starts and comes back over 0.45 s, a speaker's beat) and turns slightly while a phrase is
//!   spoken ([`SWAY_DEGREES`] of yaw and half that of roll, to one side and then the other from
//!   phrase to phrase, easing back in the pauses) ([`Gestures::head_at`]).
//!
//! Blinks and brows are ARKit channels (`eyeBlinkLeft`/`Right`, `browInnerUp`,
//! `browOuterUpLeft`/`Right`), so any rig gets them through its name table
//! ([`faceanim_rig::names`]); the head goes where a captured head pose goes (the head and neck
//! bones, or the character's root).

use crate::audio::Sound;
use crate::phones::Phone;
use crate::visemes::{self, viseme_of};

/// A pause at least this long ends a phrase (and is a moment to blink).
pub const PHRASE_PAUSE: f32 = 0.25;
/// The longest a speaker goes without blinking, seconds (people blink about every 3 to 4 s
/// while talking).
pub const LONGEST_WITHOUT: f32 = 3.5;
/// How much louder than the line's speaking level an accented syllable is, dB.
pub const ACCENT_DB: f32 = 4.0;
/// The least time between two brow raises, seconds.
pub const ACCENT_SPACING: f32 = 1.2;
/// How far the chin dips on an accent, degrees.
pub const NOD_DEGREES: f32 = 3.0;
/// How far the head turns while a phrase is spoken, degrees of yaw.
pub const SWAY_DEGREES: f32 = 2.0;

/// The ARKit channels the face moves, in the order of [`Gestures::at`].
pub const CHANNELS: [&str; 5] = [
    "eyeBlinkLeft",
    "eyeBlinkRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
];

/// Blinks and brow raises over a line.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Gestures {
    /// When each blink starts closing, seconds.
    pub blinks: Vec<f32>,
    /// Each brow raise: (when the accented syllable starts, when it ends), seconds.
    pub accents: Vec<(f32, f32)>,
    /// Each phrase: (when its first sound starts, when its last ends), seconds.
    pub phrases: Vec<(f32, f32)>,
}

/// The gestures that go with `phones` heard in `sound`.
#[must_use]
pub fn gestures(sound: &Sound, phones: &[Phone]) -> Gestures {
    let levels = sound.frame_levels();
    let heard = sound.voice_activity();
    let level_of = |p: &Phone| p.frames(&levels).iter().copied().fold(f32::MIN, f32::max);
    let is_vowel = |p: &Phone| visemes::is_vowel(viseme_of(&p.label));
    let heard_at = |t: f32| heard.get((t * 100.0) as usize).copied().unwrap_or(false);
    // The line's speaking level: the median loudness of its vowels.
    let mut vowel_levels: Vec<f32> = phones
        .iter()
        .filter(|p| is_vowel(p) && heard_at((p.start + p.end) / 2.0))
        .map(level_of)
        .collect();
    vowel_levels.sort_by(f32::total_cmp);
    let speaking = vowel_levels.get(vowel_levels.len() / 2).copied();
    let mut blinks: Vec<f32> = Vec::new();
    let mut accents: Vec<(f32, f32)> = Vec::new();
    let mut last_blink = -1.0f32;
    let mut phrases: Vec<(f32, f32)> = Vec::new();
    for (k, p) in phones.iter().enumerate() {
        let silent = viseme_of(&p.label) == faceanim_rig::names::Viseme::Sil;
        if !silent {
            match phrases.last_mut() {
                Some(phrase) if p.start - phrase.1 < PHRASE_PAUSE => phrase.1 = p.end,
                _ => phrases.push((p.start, p.end)),
            }
        }
        if silent && p.end - p.start >= PHRASE_PAUSE && k > 0 && p.start - last_blink > 1.0 {
            last_blink = p.start + 0.05;
            blinks.push(last_blink);
        } else if is_vowel(p) && p.end - last_blink > LONGEST_WITHOUT {
            last_blink = p.end;
            blinks.push(last_blink);
        }
        if let Some(speaking) = speaking
            && is_vowel(p)
            && heard_at((p.start + p.end) / 2.0)
            && level_of(p) >= speaking + ACCENT_DB
            && accents
                .last()
                .is_none_or(|a| p.start - a.0 >= ACCENT_SPACING)
        {
            accents.push((p.start, p.end));
        }
    }
    blinks.retain(|&t| t < sound.seconds());
    Gestures {
        blinks,
        accents,
        phrases,
    }
}

impl Gestures {
    /// The [`CHANNELS`]' values at `t` seconds.
    #[must_use]
    pub fn at(&self, t: f32) -> [f32; 5] {
        let blink = self
            .blinks
            .iter()
            .map(|&b| {
                let d = t - b;
                if !(0.0..0.28).contains(&d) {
                    0.0
                } else if d < 0.08 {
                    d / 0.08
                } else if d < 0.12 {
                    1.0
                } else {
                    1.0 - (d - 0.12) / 0.16
                }
            })
            .fold(0.0, f32::max);
        let brows = self
            .accents
            .iter()
            .map(|&(start, end)| {
                let rise = start - 0.12;
                if t < rise || t > end + 0.3 {
                    0.0
                } else if t < start {
                    smooth((t - rise) / 0.12)
                } else if t <= end {
                    1.0
                } else {
                    1.0 - smooth((t - end) / 0.3)
                }
            })
            .fold(0.0, f32::max);
        [blink, blink, 0.5 * brows, 0.35 * brows, 0.35 * brows]
    }

    /// The head's `[yaw, pitch, roll]` at `t` seconds, degrees (faceanim's convention: pitch
    /// up is positive, so a nod is negative).
    #[must_use]
    pub fn head_at(&self, t: f32) -> [f32; 3] {
        let nod = self
            .accents
            .iter()
            .map(|&(start, _)| {
                let d = t - start;
                if !(-0.15..=0.45).contains(&d) {
                    0.0
                } else if d < 0.0 {
                    smooth((d + 0.15) / 0.15)
                } else {
                    1.0 - smooth(d / 0.45)
                }
            })
            .fold(0.0, f32::max);
        let mut turn = 0.0;
        for (k, &(start, end)) in self.phrases.iter().enumerate() {
            let side = if k % 2 == 0 { 1.0 } else { -1.0 };
            let on = if t < start || t > end + 0.5 {
                0.0
            } else if t < start + 0.6 {
                smooth((t - start) / 0.6)
            } else if t <= end {
                1.0
            } else {
                1.0 - smooth((t - end) / 0.5)
            };
            turn += side * on;
        }
        let turn = turn.clamp(-1.0, 1.0);
        [
            SWAY_DEGREES * turn,
            -NOD_DEGREES * nod,
            0.5 * SWAY_DEGREES * turn,
        ]
    }
}

/// Adds `gestures` to `frames` (one row of `character`'s weights per frame at `fps`): each
/// shape takes the larger of its lip-sync weight and what the gestures' channels give it
/// through the character's name table. Returns how many of its shapes the gestures moved.
pub fn add(
    frames: &mut [Vec<f32>],
    fps: f32,
    gestures: &Gestures,
    character: &faceanim_rig::Character,
) -> usize {
    let map = character.name_map();
    let mut moved = vec![false; character.blendshapes().len()];
    for (k, row) in frames.iter_mut().enumerate() {
        let values = gestures.at(k as f32 / fps);
        let weights = map.weights_from_channels(|c| {
            CHANNELS
                .iter()
                .position(|n| *n == c)
                .map_or(0.0, |i| values[i])
        });
        for ((w, g), m) in row.iter_mut().zip(weights).zip(&mut moved) {
            if g > *w {
                *w = g;
            }
            *m |= g > 0.0;
        }
    }
    moved.into_iter().filter(|m| *m).count()
}

/// How many of `character`'s shapes the face's [`CHANNELS`] reach through its name table: 0
/// for a rig with no blink or brow shapes it knows, whatever a line's gestures are.
#[must_use]
pub fn shapes_reached(character: &faceanim_rig::Character) -> usize {
    character
        .name_map()
        .weights_from_channels(|c| if CHANNELS.contains(&c) { 1.0 } else { 0.0 })
        .into_iter()
        .filter(|w| *w > 0.0)
        .count()
}

fn smooth(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_channels_reach_the_lids_and_brows_a_rig_has() {
        let head = faceanim_head::default_character();
        assert_eq!(shapes_reached(&head), 5);
    }

    #[test]
    fn a_blink_closes_fast_and_opens_slowly() {
        let g = Gestures {
            blinks: vec![1.0],
            accents: vec![(3.0, 3.2)],
            phrases: vec![(0.5, 2.0), (2.6, 4.0)],
        };
        let near = |a: f32, b: f32| (a - b).abs() < 1e-4;
        assert!(g.at(0.9).iter().all(|v| near(*v, 0.0)));
        assert!(near(g.at(1.04)[0], 0.5));
        assert!(near(g.at(1.1)[0], 1.0));
        assert!(g.at(1.2)[0] > 0.4 && g.at(1.2)[0] < 0.6);
        assert!(near(g.at(1.3)[0], 0.0));
        assert!(near(g.at(3.1)[2], 0.5));
        assert!(near(g.at(3.6)[2], 0.0));
        // The head: still before speech, turned one way in the first phrase and the other in
        // the second, nodding on the accent.
        assert!(g.head_at(0.2).iter().all(|a| near(*a, 0.0)));
        assert!(near(g.head_at(1.5)[0], SWAY_DEGREES));
        assert!(near(g.head_at(3.0)[1], -NOD_DEGREES));
        assert!(near(g.head_at(3.5)[0], -SWAY_DEGREES));
        assert!(near(g.head_at(3.5)[1], 0.0));
        assert!(near(g.head_at(4.6)[0], 0.0));
    }

    #[test]
    fn pauses_and_long_stretches_blink() {
        // 8 s of "speech": vowels every 0.2 s, a pause from 4.0 to 4.6 s.
        let mut phones = Vec::new();
        let mut t = 0.0;
        while t < 8.0 {
            let label = if (4.0..4.6).contains(&t) { "SIL" } else { "AA" };
            phones.push(Phone {
                label: label.into(),
                start: t,
                end: t + 0.2,
            });
            t += 0.2;
        }
        let sound = Sound {
            samples: (0..128_000)
                .map(|k| ((k as f32 * 0.05).sin() * 8000.0) as i16)
                .collect(),
        };
        let g = gestures(&sound, &phones);
        // Two phrases, either side of the pause.
        assert_eq!(g.phrases.len(), 2, "{g:?}");
        assert!(
            (g.phrases[0].1 - 4.0).abs() < 1e-3 && (g.phrases[1].0 - 4.6).abs() < 1e-3,
            "{g:?}"
        );
        assert!(g.blinks.len() >= 2, "{g:?}");
        for pair in g.blinks.windows(2) {
            assert!(pair[1] - pair[0] <= LONGEST_WITHOUT + 0.3, "{g:?}");
        }
    }
}
