//! Live lip sync: the microphone's samples, as they come, drive the mouth.
//!
//! Live speech cannot wait for a recogniser, so each 10 ms frame is classed as it arrives by a
//! small classifier over its MFCCs — one diagonal Gaussian per viseme — learned from the
//! user's own voice:
//!
//! 1. **Calibration**: the user reads a passage in their language ([`passage`]) for
//!    [`CALIBRATION_SECONDS`], and every frame's viseme becomes a labelled example
//!    ([`VoiceModel::fit`]). English ([`PASSAGE`]) is aligned by the recogniser as far as it was
//!    read ([`phones::align_start`]); a passage in another language is aligned by synthesis
//!    (eSpeak NG says it, the recording is warped onto that), and in a language faceanim has no
//!    passage in, the user speaks freely and the phones heard label it.
//! 2. **Refinement**: while the microphone is on, stretches of speech are recognised in the
//!    background (English by its words, other languages by their phones) and their frames
//!    refine the classes ([`VoiceModel::refine`]); an uncalibrated microphone learns this way
//!    from its first stretch. A voice learned from a passage in a language other than English
//!    keeps its classes (phones heard without words would only blur what the passage taught)
//!    and follows only the speaker's mean.
//! 3. Until there is a model, the mouth opens with the voice's loudness alone.
//!
//! [`Listener`] is the streaming part: [`Frontend`] features (pre-emphasis, 25 ms Hamming
//! windows every 10 ms, 26 mel bands, 12 cepstra with the speaker's running mean removed, and
//! their change over the last two frames, which adds no delay), a loudness gate that follows
//! the room's own noise floor, the classifier, and smoothing: the mouth's openness follows the
//! voice with a short [`ATTACK`] and [`RELEASE`], its shape moves between visemes over
//! [`SHAPE_BLEND`]. The mouth of a frame is known 12.5 ms after its centre (half a window).
//!
//! ```no_run
//! use faceanim_speech::listen::Listener;
//! let mut listener = Listener::new(None);
//! # let samples: Vec<i16> = vec![0; 1600];
//! for heard in listener.push(&samples) {
//!     println!("{:.2} s: {:.0} dB, open {:.2}", heard.time, heard.level_db, heard.open);
//! }
//! ```

use faceanim_rig::names::Viseme;
use serde::{Deserialize, Serialize};

use crate::SpeechError;
use crate::audio::Sound;
pub use crate::features::{CEPSTRA, DIMS, Features, Frontend, HOP, WINDOW};
use crate::phones::{self, Phone, Recognition};
use crate::visemes::{index, viseme_of};

/// How long calibration listens, seconds.
pub const CALIBRATION_SECONDS: f32 = 20.0;
/// How fast the mouth follows a rise in a viseme's weight, seconds (time constant).
pub const ATTACK: f32 = 0.015;
/// How fast it lets go, seconds.
pub const RELEASE: f32 = 0.05;
/// How fast the mouth's shape moves from one viseme to the next, seconds (time constant).
pub const SHAPE_BLEND: f32 = 0.03;
/// How many frames of earlier examples (a minute) are kept at full weight when refining: older
/// ones fade so the model follows the voice and the room.
const REMEMBERED_FRAMES: f64 = 6000.0;
/// A class needs this many frames to be recognised at all.
const MIN_CLASS_FRAMES: f64 = 8.0;

/// Calibration aligns the passage when at least this many of its words were read.
pub const MIN_PASSAGE_WORDS: usize = 12;

/// What the user reads to calibrate: every viseme several times, in words any English reader
/// knows (written for faceanim; every word is in the CMU dictionary).
pub const PASSAGE: &str = "When the sunlight strikes raindrops in the air, they act as a prism \
and form a rainbow. Peter bought five fresh pears, a bag of cherries and a jar of jam. She \
thought the zoo would show us a huge brown owl, a few cheeky monkeys and one very lazy lion. \
Judge each shape with your own eyes, then measure how far the king's wagon rolled. Bob and \
Mary moved the heavy boxes up the narrow path.";

/// The passages read to calibrate in languages other than English, by the base of eSpeak NG's
/// name of the language (`pt` for `pt-br`): like [`PASSAGE`], every lip shape several times
/// (closed, lip to teeth, open, spread, round, tongue and teeth) in everyday words, 12–16 s
/// as eSpeak NG says them, so that a reader at an ordinary pace finishes within
/// [`CALIBRATION_SECONDS`]. Written for faceanim; Japanese in kana, which eSpeak NG reads.
/// Mandarin has none: eSpeak NG's rendition of a passage in characters taught the voice less
/// than free speech's phones did (on its own voice, 0.56–0.77 against 0.91 lip-class agreement).
pub const PASSAGES: [(&str, &str); 8] = [
    (
        "es",
        "Cuando el sol brilla sobre la lluvia, aparece un arco iris. Pablo compró fresas, peras y \
         un bote de mermelada. Mi abuela vive junto al mar, en una casa blanca con ventanas \
         verdes. En el zoológico vimos un búho y unos monos muy juguetones.",
    ),
    (
        "de",
        "Wenn die Sonne auf den Regen scheint, bildet sich ein Regenbogen. Peter kaufte fünf \
         frische Birnen und ein Glas Marmelade. Meine Oma wohnt am Meer in einem weißen Haus. Im \
         Zoo sahen wir eine braune Eule und ein paar freche Affen.",
    ),
    (
        "fr",
        "Quand le soleil brille sous la pluie, un arc-en-ciel apparaît. Pierre a acheté cinq \
         poires et un pot de confiture. Ma grand-mère habite au bord de la mer, dans une maison \
         blanche aux volets verts. Au zoo, nous avons vu un hibou brun et des singes malins.",
    ),
    (
        "it",
        "Quando il sole splende sulla pioggia, appare un arcobaleno. Paolo ha comprato fragole, \
         pere e un barattolo di marmellata. Mia nonna vive vicino al mare, in una casa bianca con \
         le finestre verdi. Allo zoo abbiamo visto un gufo e alcune scimmie molto vivaci.",
    ),
    (
        "pt",
        "Quando o sol brilha sobre a chuva, aparece um arco-íris. O Paulo comprou morangos, peras \
         e um pote de geleia. A minha avó mora perto do mar, numa casa branca com janelas verdes. \
         No zoológico vimos uma coruja e uns macacos muito brincalhões.",
    ),
    (
        "nl",
        "Als de zon op de regen schijnt, verschijnt er een regenboog. Peter kocht vijf verse peren \
         en een pot jam. Mijn oma woont aan zee in een wit huis met groene ramen. In de \
         dierentuin zagen we een bruine uil en een paar brutale apen.",
    ),
    (
        "ja",
        "あめのあとに、そらにおおきなにじがでました。まいにち、ははとふたりでうみべをさんぽします。\
         ぱんやさんで、ぶどうぱんとみるくをかいました。どうぶつえんで、ふくろうとさるをみました。",
    ),
    (
        "ko",
        "비가 그친 뒤에 하늘에 큰 무지개가 떴어요. 엄마와 바닷가를 천천히 걸었어요. 빵집에서 \
         포도빵과 우유를 샀어요. 동물원에서 부엉이와 원숭이를 봤어요.",
    ),
];

/// The passage to read in `language` (eSpeak NG's name of it, as
/// [`crate::recognition::check_language`] gives): [`PASSAGE`] in English, one of
/// [`PASSAGES`], or `None` where faceanim has none (the user then speaks freely).
#[must_use]
pub fn passage(language: &str) -> Option<&'static str> {
    if crate::recognition::is_english(language) {
        return Some(PASSAGE);
    }
    let base = crate::script::base_language(language);
    PASSAGES
        .iter()
        .find(|(name, _)| *name == base)
        .map(|(_, text)| *text)
}

/// Why calibration or refinement failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ListenError {
    /// Nothing was heard.
    #[error(
        "no voice was heard in {seconds:.1} s from the microphone (is it muted, or is the input level too low?)"
    )]
    NoVoice {
        /// How long was listened to.
        seconds: f32,
    },
    /// Too few visemes were heard to tell them apart.
    #[error(
        "only {0} kinds of mouth shape were heard: read the whole passage aloud, at your usual pace"
    )]
    TooFewVisemes(usize),
    /// The recogniser failed.
    #[error(transparent)]
    Speech(#[from] SpeechError),
}

/// One viseme's examples: their count, sum and sum of squares (so that refining adds to them).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
struct Class {
    count: f64,
    sum: Vec<f64>,
    squares: Vec<f64>,
}

impl Class {
    fn empty() -> Class {
        Class {
            count: 0.0,
            sum: vec![0.0; DIMS],
            squares: vec![0.0; DIMS],
        }
    }
}

/// The classifier: per viseme (Oculus order), a diagonal Gaussian of its frames' features.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct VoiceModel {
    classes: Vec<Class>,
    /// The speaker's cepstral mean.
    mean: [f32; CEPSTRA],
    /// Stretches it learned from (calibration and refinements).
    pub stretches: usize,
    /// The language (eSpeak NG's name) of the passage it was learned from, when that is not
    /// English: [`refine`] in that language keeps its classes (the phones of live speech, heard
    /// without its words, would only blur them) and follows the speaker's mean alone.
    #[serde(default)]
    pub passage_language: Option<String>,
}

/// A class ready to score frames.
#[derive(Debug, Clone)]
struct Scorer {
    viseme: usize,
    log_prior: f32,
    mean: [f32; DIMS],
    inverse_variance: [f32; DIMS],
    log_norm: f32,
}

impl VoiceModel {
    /// Learns from `features` labelled by `phones` (frames where no voice is heard are
    /// silence).
    ///
    /// # Errors
    /// [`ListenError`] when no voice was heard or too few visemes to tell apart.
    pub fn fit(
        features: &[Features],
        phones: &[Phone],
        mean: [f32; CEPSTRA],
    ) -> Result<VoiceModel, ListenError> {
        let mut model = VoiceModel {
            classes: vec![Class::empty(); Viseme::ALL.len()],
            mean,
            stretches: 0,
            passage_language: None,
        };
        model.learn(features, phones)?;
        Ok(model)
    }

    /// Adds a stretch of speech to what the model knows, earlier stretches fading.
    ///
    /// # Errors
    /// [`ListenError`] when no voice was heard in it or too few visemes (the model is kept).
    pub fn refine(
        &mut self,
        features: &[Features],
        phones: &[Phone],
        mean: [f32; CEPSTRA],
    ) -> Result<(), ListenError> {
        let mut next = self.clone();
        let known: f64 = next.classes.iter().map(|c| c.count).sum();
        let keep = (REMEMBERED_FRAMES / known.max(1.0)).min(1.0);
        for class in &mut next.classes {
            class.count *= keep;
            class.sum.iter_mut().for_each(|s| *s *= keep);
            class.squares.iter_mut().for_each(|s| *s *= keep);
        }
        next.mean = mean;
        next.learn(features, phones)?;
        *self = next;
        Ok(())
    }

    fn learn(&mut self, features: &[Features], phones: &[Phone]) -> Result<(), ListenError> {
        if !features.iter().any(|f| f.voiced) {
            return Err(ListenError::NoVoice {
                seconds: features.last().map_or(0.0, |f| f.time),
            });
        }
        let mut heard = vec![false; Viseme::ALL.len()];
        for (f, label) in features.iter().zip(labels(features, phones)) {
            let class = &mut self.classes[index(label)];
            heard[index(label)] = true;
            class.count += 1.0;
            for (k, x) in f.vector.iter().enumerate() {
                let x = f64::from(*x);
                class.sum[k] += x;
                class.squares[k] += x * x;
            }
        }
        let kinds = heard.iter().filter(|h| **h).count();
        if kinds < 5 {
            return Err(ListenError::TooFewVisemes(kinds.saturating_sub(1)));
        }
        self.stretches += 1;
        Ok(())
    }

    /// The speaker's cepstral mean the model was learned with.
    #[must_use]
    pub fn speaker_mean(&self) -> [f32; CEPSTRA] {
        self.mean
    }

    /// How many visemes the model can tell apart (silence included).
    #[must_use]
    pub fn visemes_known(&self) -> usize {
        self.classes
            .iter()
            .filter(|c| c.count >= MIN_CLASS_FRAMES)
            .count()
    }

    fn scorers(&self) -> Vec<Scorer> {
        let total: f64 = self.classes.iter().map(|c| c.count).sum();
        // The variance of all frames together, a floor under each class's own.
        let mut all = [0.0f64; DIMS];
        let mut all_mean = [0.0f64; DIMS];
        for class in &self.classes {
            for k in 0..DIMS {
                all_mean[k] += class.sum[k];
                all[k] += class.squares[k];
            }
        }
        for k in 0..DIMS {
            all_mean[k] /= total.max(1.0);
            all[k] = (all[k] / total.max(1.0) - all_mean[k] * all_mean[k]).max(1e-6);
        }
        self.classes
            .iter()
            .enumerate()
            .filter(|(_, c)| c.count >= MIN_CLASS_FRAMES)
            .map(|(viseme, c)| {
                let mut mean = [0.0f32; DIMS];
                let mut inverse_variance = [0.0f32; DIMS];
                let mut log_norm = 0.0f32;
                for k in 0..DIMS {
                    let m = c.sum[k] / c.count;
                    let v = (c.squares[k] / c.count - m * m).max(0.05 * all[k]);
                    mean[k] = m as f32;
                    inverse_variance[k] = (1.0 / v) as f32;
                    log_norm -= 0.5 * (v as f32).ln();
                }
                Scorer {
                    viseme,
                    log_prior: ((c.count / total) as f32).ln(),
                    mean,
                    inverse_variance,
                    log_norm,
                }
            })
            .collect()
    }
}

/// Each frame's viseme by `phones` (silence where no voice is heard or no phone covers it).
#[must_use]
pub fn labels(features: &[Features], phones: &[Phone]) -> Vec<Viseme> {
    let mut at = 0usize;
    features
        .iter()
        .map(|f| {
            while at < phones.len() && phones[at].end <= f.time {
                at += 1;
            }
            match phones.get(at) {
                Some(p) if f.voiced && p.start <= f.time => {
                    let v = viseme_of(&p.label);
                    if p.label == "HH" { Viseme::Aa } else { v }
                }
                _ => Viseme::Sil,
            }
        })
        .collect()
}

/// The mouth at one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Heard {
    /// The frame's centre, seconds from the start of the stream.
    pub time: f32,
    /// Loudness, dB relative to full scale.
    pub level_db: f32,
    /// Whether a voice is heard.
    pub voiced: bool,
    /// How open the mouth is, 0..1 (the largest viseme weight).
    pub open: f32,
    /// The 15 viseme weights (Oculus order), smoothed.
    pub visemes: [f32; 15],
}

/// Samples in, the mouth out: features, the classifier (when there is a model) and smoothing.
#[derive(Debug)]
pub struct Listener {
    front: Frontend,
    scorers: Vec<Scorer>,
    /// How open the mouth is, smoothed by [`ATTACK`] and [`RELEASE`].
    open: f32,
    /// The mouth's shape (viseme weights with the largest 1), smoothed by [`SHAPE_BLEND`]: kept
    /// through pauses, so the mouth closes from the shape it had.
    shape: [f32; 15],
}

impl Listener {
    /// A listener classing frames with `model`, or opening the mouth with loudness alone.
    #[must_use]
    pub fn new(model: Option<&VoiceModel>) -> Listener {
        Listener {
            front: Frontend::new(model.map(VoiceModel::speaker_mean)),
            scorers: model.map(VoiceModel::scorers).unwrap_or_default(),
            open: 0.0,
            shape: [0.0; 15],
        }
    }

    /// Classes frames with `model` from now on.
    pub fn set_model(&mut self, model: &VoiceModel) {
        self.scorers = model.scorers();
    }

    /// Whether frames are classed (else loudness alone opens the mouth).
    #[must_use]
    pub fn classifies(&self) -> bool {
        !self.scorers.is_empty()
    }

    /// The speaker's cepstral mean so far.
    #[must_use]
    pub fn speaker_mean(&self) -> [f32; CEPSTRA] {
        self.front.mean()
    }

    /// The mouth at every frame `samples` completes.
    pub fn push(&mut self, samples: &[i16]) -> Vec<Heard> {
        self.front
            .push(samples)
            .into_iter()
            .map(|f| self.hear(&f))
            .collect()
    }

    fn hear(&mut self, f: &Features) -> Heard {
        let step = HOP as f32 / faceanim_sphinx_sys::SAMPLE_RATE as f32;
        let rate = |seconds: f32| 1.0 - (-step / seconds).exp();
        let open = if f.voiced { f.open } else { 0.0 };
        self.open += (open - self.open) * rate(if open > self.open { ATTACK } else { RELEASE });
        if let Some(shape) = f.voiced.then(|| self.shape_of(f)) {
            // A mouth opening from rest takes its shape at once; a moving one blends.
            let k = if self.open < 0.05 {
                1.0
            } else {
                rate(SHAPE_BLEND)
            };
            for (s, t) in self.shape.iter_mut().zip(shape) {
                *s += (t - *s) * k;
            }
        }
        let mut visemes = [0.0f32; 15];
        for (v, s) in visemes.iter_mut().zip(&self.shape) {
            *v = s * self.open;
        }
        Heard {
            time: f.time,
            level_db: f.level_db,
            voiced: f.voiced,
            open: self.open,
            visemes,
        }
    }

    /// A voiced frame's mouth shape: the likeliest viseme at 1, close runners-up blended in
    /// (together at most [`BLEND_CAP`]); loudness alone gives an open "aa".
    fn shape_of(&self, f: &Features) -> [f32; 15] {
        let mut out = [0.0f32; 15];
        if self.scorers.is_empty() {
            out[index(Viseme::Aa)] = 0.8;
            return out;
        }
        let scores: Vec<f32> = self
            .scorers
            .iter()
            .map(|s| {
                let distance: f32 = f
                    .vector
                    .iter()
                    .zip(&s.mean)
                    .zip(&s.inverse_variance)
                    .map(|((x, m), iv)| (x - m) * (x - m) * iv)
                    .sum();
                // Tempered: diagonal Gaussians over correlated features are overconfident.
                (s.log_prior + s.log_norm - 0.5 * distance) / TEMPERATURE
            })
            .collect();
        let best = scores.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        for (s, score) in self.scorers.iter().zip(&scores) {
            out[s.viseme] = (score - best).exp();
        }
        // Silence's share says nothing of the shape: the loudness gate decides openness.
        out[0] = 0.0;
        let most = out.iter().copied().fold(0.0, f32::max);
        if most <= 0.0 {
            out[index(Viseme::Aa)] = 0.8;
            return out;
        }
        out.iter_mut()
            .for_each(|w| *w = if *w >= 0.25 * most { *w / most } else { 0.0 });
        let total: f32 = out.iter().sum();
        if total > BLEND_CAP {
            out.iter_mut().for_each(|w| *w *= BLEND_CAP / total);
        }
        out
    }
}

/// The viseme weights of a frame add up to at most this much (the largest is 1).
const BLEND_CAP: f32 = 1.35;

/// How much the classifier's log-likelihoods are flattened.
const TEMPERATURE: f32 = 4.0;

/// A model of the voice in `samples`, the user reading [`passage`] in `language` (any name
/// [`crate::recognition::check_language`] reads; the recording is [`CALIBRATION_SECONDS`] or
/// less), each frame labelled by its phone: in English the recording aligned to [`PASSAGE`] as
/// far as it was read (at least [`MIN_PASSAGE_WORDS`] words of it), else recognised; in
/// another language the passage aligned by synthesis, or, where the reading was cut off by the
/// end of the recording or faceanim has no passage in the language, the phones heard.
///
/// # Errors
/// [`ListenError`] when the language is not one eSpeak NG speaks, no voice was heard, too few
/// visemes, or the recogniser fails.
pub fn calibrate(
    samples: &[i16],
    language: &str,
) -> Result<(VoiceModel, Recognition, Vec<String>), ListenError> {
    let language = crate::recognition::check_language(language).map_err(SpeechError::from)?;
    let sound = Sound {
        samples: samples.to_vec(),
    };
    let heard = |transcript: Option<&str>| {
        crate::recognition::recognise(&sound, transcript, Some(&language), Recognition::Words)
            .map_err(SpeechError::from)
    };
    let (phones, recognition, notes) = if crate::recognition::is_english(&language) {
        // The passage as far as it was read; recognised instead when too little of it was.
        let (aligned, said) = phones::align_start(&sound, PASSAGE).map_err(SpeechError::from)?;
        if said >= MIN_PASSAGE_WORDS {
            (aligned, Recognition::Transcript, Vec::new())
        } else {
            let (phones, recognition, _) = heard(None)?;
            let note = format!(
                "only {said} words of the passage were heard in order: the voice was learned from the words recognised instead"
            );
            (phones, recognition, vec![note])
        }
    } else {
        match passage(&language) {
            // Aligned whole: a passage read only in part would be squeezed into what was said.
            Some(text) if !cut_off(&sound) => heard(Some(text))?,
            Some(_) => {
                let (phones, recognition, _) = heard(None)?;
                let note = "the passage was still being read when calibration ended: the voice was learned from the phones heard".to_owned();
                (phones, recognition, vec![note])
            }
            None => {
                let (phones, recognition, _) = heard(None)?;
                let note = format!(
                    "faceanim has no passage in {language}: the voice was learned from the phones heard"
                );
                (phones, recognition, vec![note])
            }
        }
    };
    // Only another language's passage is aligned by synthesis.
    let kept = (recognition == Recognition::Synthesis).then(|| language.clone());
    // Twice: the speaker's mean from the whole recording first, so that its first seconds are
    // normalised as well as the rest.
    let mut first = Frontend::new(None);
    first.push(samples);
    let mut front = Frontend::new(Some(first.mean()));
    let features = front.push(samples);
    let mut model = VoiceModel::fit(&features, &phones, front.mean())?;
    model.passage_language = kept;
    Ok((model, recognition, notes))
}

/// The last [`CUT_OFF_FRAMES`] of voice activity a recording ends in when its speaker was
/// still reading: half of them or more voiced.
const CUT_OFF_FRAMES: usize = 30;

/// Whether `sound` ends while its speaker is still speaking (voice in half or more of its last
/// [`CUT_OFF_FRAMES`] frames): a calibration that ended in the middle of the passage.
fn cut_off(sound: &Sound) -> bool {
    let voiced = sound.voice_activity();
    voiced.len() >= CUT_OFF_FRAMES
        && 2 * voiced[voiced.len() - CUT_OFF_FRAMES..]
            .iter()
            .filter(|v| **v)
            .count()
            >= CUT_OFF_FRAMES
}

/// `model` refined by a stretch of live speech (`samples`) in `language`, recognised without
/// a transcript (English by its words, other languages by their phones); `mean` is the
/// speaker's cepstral mean when the stretch began. Without a model, the stretch makes the
/// first one. A model learned from a passage in `language`, when that is not English
/// ([`VoiceModel::passage_language`]), keeps its classes and takes only the speaker's mean.
///
/// # Errors
/// [`ListenError`] when the language is not one eSpeak NG speaks, no voice was heard in the
/// stretch, too few visemes, or the recogniser fails.
pub fn refine(
    model: Option<&VoiceModel>,
    samples: &[i16],
    mean: [f32; CEPSTRA],
    language: &str,
) -> Result<VoiceModel, ListenError> {
    let language = crate::recognition::check_language(language).map_err(SpeechError::from)?;
    let mut front = Frontend::new(Some(mean));
    let features = front.push(samples);
    if let Some(model) = model.filter(|m| m.passage_language.as_ref() == Some(&language)) {
        let mut next = model.clone();
        next.mean = front.mean();
        return Ok(next);
    }
    let sound = Sound {
        samples: samples.to_vec(),
    };
    let (phones, _, _) =
        crate::recognition::recognise(&sound, None, Some(&language), Recognition::Words)
            .map_err(SpeechError::from)?;
    match model {
        Some(model) => {
            let mut next = model.clone();
            next.refine(&features, &phones, front.mean())?;
            Ok(next)
        }
        None => VoiceModel::fit(&features, &phones, front.mean()),
    }
}
