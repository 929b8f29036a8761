//! Live lip sync ([`faceanim_speech::listen`]) on speech no line of faceanim made: each flite
//! voice (a synthetic voice that says which phone it speaks when, `flite -psdur`) reads the
//! first 20 seconds of the calibration passage, then lines it never read are streamed through
//! the listener 20 ms at a time, as the studio's microphone sends them. The viseme shown at
//! each 10 ms is compared with the phone spoken then (±40 ms), the mouth's openness with
//! whether anything is spoken, and the mouth's delay at the voice's onsets is measured.
//! Silence, steady noise and hum keep the mouth shut; calibrating on silence is refused.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

mod common;

use std::path::Path;

use common::{espeak, flite};
use faceanim_rig::names::Viseme;
use faceanim_speech::Sound;
use faceanim_speech::listen::{self, CALIBRATION_SECONDS, Heard, Listener, PASSAGE};

fn spoken_at(phones: &[(Viseme, f32)], t: f32) -> Viseme {
    phones
        .iter()
        .find(|(_, end)| t < *end)
        .map_or(Viseme::Sil, |p| p.0)
}

/// The viseme a frame shows: its strongest, or silence when the mouth is nearly shut.
fn shown(h: &Heard) -> Viseme {
    if h.open < 0.15 {
        return Viseme::Sil;
    }
    let (best, _) = h.visemes[1..]
        .iter()
        .enumerate()
        .fold((0, 0.0), |b, (i, w)| if *w > b.1 { (i, *w) } else { b });
    Viseme::ALL[1 + best]
}

fn stream(listener: &mut Listener, samples: &[i16]) -> Vec<Heard> {
    samples.chunks(320).flat_map(|c| listener.push(c)).collect()
}

#[test]
fn a_voice_calibrated_on_the_passage_shows_the_visemes_of_lines_it_never_read() {
    let dir = tempfile::tempdir().unwrap();
    let lines = [
        "Please bring me my blue map before the bus leaves.",
        "She sells sea shells by the sea shore on Thursday.",
        "We often go fishing with our father in the early morning.",
    ];
    let (mut hits, mut frames, mut open_agree, mut loud_agree, mut all) = (0, 0, 0, 0, 0);
    let mut onset_lags = Vec::new();
    for voice in ["slt", "rms", "awb"] {
        let passage = dir.path().join(format!("{voice}-passage.wav"));
        flite(voice, PASSAGE, &passage);
        let sound = Sound::read(&passage).unwrap();
        let heard = (CALIBRATION_SECONDS * 16_000.0) as usize;
        let (model, recognition, notes) =
            listen::calibrate(&sound.samples[..heard.min(sound.samples.len())], "en-us").unwrap();
        assert_eq!(
            recognition,
            faceanim_speech::Recognition::Transcript,
            "{notes:?}"
        );
        assert!(model.visemes_known() >= 12, "{}", model.visemes_known());
        for (k, line) in lines.iter().enumerate() {
            let wav = dir.path().join(format!("{voice}-{k}.wav"));
            let truth = flite(voice, line, &wav);
            let sound = Sound::read(&wav).unwrap();
            let heard = stream(&mut Listener::new(Some(&model)), &sound.samples);
            let loudness_only = stream(&mut Listener::new(None), &sound.samples);
            let mut h = 0;
            let mut n = 0;
            for (f, g) in heard.iter().zip(&loudness_only) {
                let spoken = spoken_at(&truth, f.time);
                let silent = spoken == Viseme::Sil;
                all += 1;
                open_agree += usize::from(silent == (shown(f) == Viseme::Sil));
                loud_agree += usize::from(silent == (shown(g) == Viseme::Sil));
                if silent {
                    continue;
                }
                n += 1;
                let near = [-0.04f32, -0.02, 0.0, 0.02, 0.04]
                    .iter()
                    .any(|d| spoken_at(&truth, f.time + d) == shown(f));
                h += usize::from(near);
            }
            println!("{voice} line {k}: {h}/{n} = {:.2}", h as f32 / n as f32);
            hits += h;
            frames += n;
            // The mouth at the voice's onsets: from the first 10 ms of a voice after a pause
            // (20 dB over the pause, and held: not a breath or a click) to the first frame
            // (known half a window after its centre) with the mouth open.
            let levels = sound.frame_levels();
            for k in 10..levels.len().saturating_sub(5) {
                let pause = levels[k - 10..k].iter().all(|l| *l < levels[k] - 20.0);
                if pause && levels[k..k + 5].iter().all(|l| *l > -50.0) {
                    let start = k as f32 * 0.01;
                    let open = heard
                        .iter()
                        .find(|h| h.time + 0.0125 > start && h.open > 0.2)
                        .unwrap();
                    onset_lags.push(((open.time + 0.0125 - start) * 1000.0).max(0.0));
                }
            }
        }
    }
    let accuracy = hits as f32 / frames as f32;
    let (open_agree, loud_agree) = (
        open_agree as f32 / all as f32,
        loud_agree as f32 / all as f32,
    );
    println!(
        "viseme within ±40 ms: {accuracy:.3} over {frames} speech frames; mouth open exactly while speaking: \
         {open_agree:.3} (loudness alone: {loud_agree:.3}); onset delays {onset_lags:?} ms"
    );
    assert!(accuracy >= 0.5, "{accuracy}");
    assert!(
        open_agree >= 0.85 && loud_agree >= 0.85,
        "{open_agree} {loud_agree}"
    );
    assert!(!onset_lags.is_empty());
    assert!(onset_lags.iter().all(|l| *l <= 50.0), "{onset_lags:?}");
}

#[test]
fn silence_noise_and_hum_keep_the_mouth_shut_and_calibrating_on_them_is_refused() {
    let seconds = 4 * 16_000;
    let mut noise_state = 12_345u32;
    let mut noise = || {
        noise_state = noise_state
            .wrapping_mul(1_664_525)
            .wrapping_add(1_013_904_223);
        ((noise_state >> 16) as i32 - 32_768) as f32 / 32_768.0
    };
    let inputs: [(&str, Vec<i16>); 3] = [
        ("silence", vec![0; seconds]),
        (
            "noise",
            (0..seconds).map(|_| (noise() * 3000.0) as i16).collect(),
        ),
        (
            "hum",
            (0..seconds)
                .map(|i| {
                    ((i as f32 * 2.0 * std::f32::consts::PI * 50.0 / 16_000.0).sin() * 8000.0)
                        as i16
                })
                .collect(),
        ),
    ];
    for (name, samples) in &inputs {
        let heard = stream(&mut Listener::new(None), samples);
        let most = heard.iter().map(|h| h.open).fold(0.0, f32::max);
        assert!(most < 0.05, "{name}: the mouth opened to {most}");
        assert!(
            listen::calibrate(samples, "en-us").is_err(),
            "{name}: calibrated on no voice"
        );
    }
}

/// A real person (the five LibriVox readings in Debian's pocketsphinx-testdata, one reader,
/// one after the other) on a microphone that
/// was never calibrated: the first ten seconds are recognised and teach the classifier (as the
/// studio does in the background), and the mouth is open while the reader is heard and shut in
/// the pauses, judged on the recording's own loudness away from its boundaries.
#[test]
fn an_uncalibrated_microphone_learns_a_real_voice_from_its_first_stretch() {
    let folder = Path::new("/usr/share/pocketsphinx/test/data/librivox");
    assert!(
        folder.exists(),
        "pocketsphinx-testdata is needed: run scripts/setup.sh"
    );
    let mut samples = Vec::new();
    for part in ["0870", "0880", "0890", "0920", "0930"] {
        let path = folder.join(format!("sense_and_sensibility_01_austen_64kb-{part}.wav"));
        samples.extend(Sound::read(&path).unwrap().samples);
    }
    let sound = Sound { samples };
    let first = 10 * 16_000;
    let mut listener = Listener::new(None);
    stream(&mut listener, &sound.samples[..first]);
    let model = listen::refine(
        None,
        &sound.samples[..first],
        listener.speaker_mean(),
        "en-us",
    )
    .unwrap();
    assert_eq!(model.stretches, 1);
    listener.set_model(&model);
    let heard = stream(&mut listener, &sound.samples[first..]);
    let voiced = Sound {
        samples: sound.samples[first..].to_vec(),
    }
    .voice_activity();
    let (mut agree, mut judged) = (0, 0);
    for h in &heard {
        // The frame whose 10 ms the window centres on (the stream began ten seconds before),
        // judged where the loudness is steady.
        let at = ((h.time - 10.0) * 100.0) as usize;
        if at < 5
            || at + 5 >= voiced.len()
            || voiced[at - 5..=at + 5].iter().any(|v| *v != voiced[at])
        {
            continue;
        }
        judged += 1;
        agree += usize::from(voiced[at] == (h.open > 0.15));
    }
    let share = agree as f32 / judged as f32;
    println!(
        "LibriVox, uncalibrated then learned: {share:.3} of {judged} frames agree with the loudness"
    );
    assert!(share >= 0.85, "{share}");
}

/// Of the 10 ms frames of speech in `said` (an eSpeak NG line's phones), the share whose lip
/// class the listener shows within ±40 ms.
fn agreement(heard: &[Heard], said: &common::Said) -> (usize, usize) {
    let at = |t: f32| {
        said.iter()
            .find(|(_, start, end)| *start <= t && t < *end)
            .map_or(Viseme::Sil, |p| p.0)
    };
    let (mut hits, mut frames) = (0, 0);
    for f in heard {
        if at(f.time) == Viseme::Sil {
            continue;
        }
        frames += 1;
        hits += usize::from(
            [-0.04f32, -0.02, 0.0, 0.02, 0.04]
                .iter()
                .any(|d| common::class(at(f.time + d)) == common::class(shown(f))),
        );
    }
    (hits, frames)
}

/// A speaker of another language reads the passage in it: eSpeak NG's Spanish and German
/// voices, calibrated on their language's passage (aligned by synthesis), show the lip shapes
/// of lines they never read far better than calibrated on the English passage (all the
/// microphone offered before), and the voice is kept from blind refinement; a language with no
/// passage learns from the phones of free speech.
#[test]
fn a_voice_calibrated_on_its_own_languages_passage_shows_its_visemes() {
    let heard = (CALIBRATION_SECONDS * 16_000.0) as usize;
    let first = |sound: &Sound| sound.samples[..heard.min(sound.samples.len())].to_vec();
    for (voice, language, lines) in [
        (
            "es+f3",
            "es",
            [
                "Mi mamá me mima mucho.",
                "El perro de Pablo bebe agua en la playa.",
            ],
        ),
        (
            "de+m3",
            "de",
            [
                "Guten Morgen, wie geht es dir?",
                "Meine Mutter mag warme Milch am Abend.",
            ],
        ),
    ] {
        let (_, own) = espeak(listen::passage(language).unwrap(), voice, None);
        let (model, recognition, notes) = listen::calibrate(&first(&own), language).unwrap();
        assert_eq!(
            recognition,
            faceanim_speech::Recognition::Synthesis,
            "{notes:?}"
        );
        assert!(
            model.passage_language.as_deref() == Some(language) && notes.is_empty(),
            "{notes:?}"
        );
        let (_, english) = espeak(PASSAGE, voice, None);
        let (before, _, _) = listen::calibrate(&first(&english), "en-us").unwrap();
        assert!(before.passage_language.is_none());
        let (mut now, mut then, mut frames) = (0, 0, 0);
        for line in lines {
            let (said, sound) = espeak(line, voice, None);
            let (hits, n) = agreement(
                &stream(&mut Listener::new(Some(&model)), &sound.samples),
                &said,
            );
            let (old, _) = agreement(
                &stream(&mut Listener::new(Some(&before)), &sound.samples),
                &said,
            );
            now += hits;
            then += old;
            frames += n;
        }
        let (now, then) = (now as f32 / frames as f32, then as f32 / frames as f32);
        println!("{voice}: its own passage {now:.3}, the English passage {then:.3}");
        assert!(now >= 0.85 && now >= then + 0.1, "{voice}: {now} {then}");
        // Refining by the phones of live speech keeps what the passage taught.
        let (_, line) = espeak(lines[0], voice, None);
        let refined =
            listen::refine(Some(&model), &line.samples, model.speaker_mean(), language).unwrap();
        assert_eq!(refined.stretches, model.stretches);
        // Heard as another language, it learns from the stretch.
        let relearned =
            listen::refine(Some(&model), &line.samples, model.speaker_mean(), "it").unwrap();
        assert_eq!(relearned.stretches, model.stretches + 1);
    }
    // A reading cut off by the end of calibration is not squeezed into the passage whole: the
    // phones heard teach the voice.
    let (_, spanish) = espeak(listen::passage("es").unwrap(), "es+f3", None);
    let voiced = spanish.voice_activity();
    let middle = (voiced.len() * 6 / 10..voiced.len())
        .find(|&k| voiced[k - 15..k].iter().all(|v| *v))
        .unwrap();
    let (_, recognition, notes) =
        listen::calibrate(&spanish.samples[..middle * 160], "es").unwrap();
    assert_eq!(recognition, faceanim_speech::Recognition::PhoneLoop);
    assert!(
        notes.iter().any(|n| n.contains("still being read")),
        "{notes:?}"
    );
    // Swahili has no passage: the phones of what was said teach the voice, and a note says so.
    let (_, free) = espeak(
        "Habari za asubuhi. Mama anapika mboga na mkate. Watoto wanacheza mpira uwanjani.",
        "sw",
        None,
    );
    let (model, recognition, notes) = listen::calibrate(&first(&free), "sw").unwrap();
    assert_eq!(recognition, faceanim_speech::Recognition::PhoneLoop);
    assert!(
        model.passage_language.is_none() && notes.iter().any(|n| n.contains("no passage")),
        "{notes:?}"
    );
}
