//! `faceanim lipsync`: speech drives the character's mouth.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use clap::Args;
use faceanim_files::text::{Accept, Text};
use faceanim_speech::{Mouth, MouthTable, Sound};
use faceanim_take::Take;

/// `faceanim lipsync`'s arguments.
#[derive(Debug, Args)]
pub struct LipsyncArgs {
    /// The speech: a WAV, MP3, Ogg or FLAC file, or a video with sound.
    pub speech: PathBuf,
    /// The character (default: the built-in head).
    #[arg(long)]
    pub character: Option<PathBuf>,
    /// What was said (the words, or a file holding them): the phones are aligned to it,
    /// which times them better than recognising them blind.
    #[arg(long, value_name = "TEXT|FILE")]
    pub text: Option<String>,
    /// The language spoken, as eSpeak NG names it (`en-us`, `es`, `ja`, `de`, `fr`, `ko`,
    /// `it`, `pt`, … : `espeak-ng --voices`) or as a BCP 47 tag or locale (`ja-JP`, `pt_BR`,
    /// `es-MX`, `zh-Hant-TW`), taken to eSpeak NG's nearest language. A transcript in any of
    /// them is aligned by synthesis; without one, English words are recognised, other
    /// languages by their phones.
    #[arg(long, default_value = faceanim_speech::recognition::ENGLISH)]
    pub language: String,
    #[command(flatten)]
    pub out: crate::outputs::Outputs,
    /// Also write the clip (JSON) here.
    #[arg(long)]
    pub clip: Option<PathBuf>,
    /// Frames per second of the animation.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f32,
    /// Visemes as ARKit channel values for rigs without viseme shapes (JSON:
    /// {"aa": {"jawOpen": 0.7}, …}; visemes left out keep the built-in table).
    #[arg(long, value_name = "FILE")]
    pub viseme_table: Option<PathBuf>,
    /// Read the mouth through the character's adapter (from `faceanim adapt`): each viseme
    /// the built-in head makes, rendered and read by it. For a rig whose shape names say
    /// nothing of a mouth (neither visemes nor ARKit names).
    #[arg(long, value_name = "ADAPTER")]
    pub adapter: Option<PathBuf>,
    /// Without --text: recognise words (English; a quarter to a half of real time on a line
    /// of a few seconds, a fifth on a longer reading) or phones (any language; about a tenth,
    /// a little less exact in English).
    #[arg(long, value_enum, default_value_t = Blind::Words)]
    pub recognise: Blind,
    /// Whose vocal tract the recogniser hears the voice through (its models were trained on
    /// adults and hear a man best): `auto` (by the voice's pitch), `search` (by listening
    /// through warps from 0.8 to 1.6, for a voice raised or lowered whole — an effect, a voice
    /// changer — whose pitch says too little; not for a formant synthesiser's; about a second
    /// more per line), `man` (as it is), `woman`, `child`, or a warp from 0.6 to 1.8 that every
    /// frequency is divided by (under 1 for a voice deeper than a man's: an effect, a
    /// monster's).
    #[arg(
        long,
        default_value = "auto",
        value_name = "auto|search|man|woman|child|WARP"
    )]
    pub voice: faceanim_speech::Voice,
    /// The face around the mouth too: blinks at phrase boundaries and natural rates, brows
    /// raised on accented syllables (ARKit blink and brow channels, on any rig through its
    /// name table), and the head: a nod on each accent and a slight turn per phrase (on the
    /// head and neck bones, or the root).
    #[arg(long)]
    pub face: bool,
    /// Print a JSON summary (timing, phones, visemes) on stdout.
    #[arg(long)]
    pub json: bool,
}

/// How speech without a transcript is recognised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Blind {
    /// English words with the language model, spoken as the dictionary says.
    Words,
    /// Any phone after any other.
    Phones,
}

/// What `faceanim lipsync --json` prints.
#[derive(serde::Serialize)]
struct Summary<'a> {
    audio_seconds: f32,
    /// Reading the sound, recognising, timing and mapping (not writing).
    seconds: f64,
    real_time_factor: f64,
    frames: usize,
    fps: f32,
    recognition: faceanim_speech::Recognition,
    route: faceanim_speech::Route,
    shapes_moved: usize,
    phones: &'a [faceanim_speech::Phone],
    visemes: &'a [faceanim_speech::visemes::Key],
    /// With --face: the blinks, brow raises, accents and phrases added.
    #[serde(skip_serializing_if = "Option::is_none")]
    gestures: Option<&'a faceanim_speech::face::Gestures>,
    notes: &'a [String],
}

pub fn run(args: LipsyncArgs) -> anyhow::Result<()> {
    let mut outputs = args.out.outputs.clone();
    outputs.extend(args.clip.iter().cloned());
    anyhow::ensure!(
        !outputs.is_empty(),
        "give at least one -o OUTPUT (.glb, .vrm, .vrma, .json, .csv, .session.json) or --clip"
    );
    let formats = crate::outputs::formats_of(&outputs)?;
    anyhow::ensure!(
        args.fps.is_finite() && (1.0..=240.0).contains(&args.fps),
        "--fps must be between 1 and 240, got {}",
        args.fps
    );
    let table = match &args.viseme_table {
        Some(path) => {
            MouthTable::from_json(&read_text(path, "--viseme-table", Accept::Unicode)?.text)
                .map_err(|e| anyhow::anyhow!("--viseme-table {}: {e}", path.display()))?
        }
        None => MouthTable::default(),
    };
    let transcript = args
        .text
        .as_deref()
        .map(|text| transcript(text, &args.language))
        .transpose()?;
    // A character or adapter named by a path that is not there is refused before the speech
    // is read: the character loads beside the recognition, whose hour of speech would
    // otherwise be heard first.
    for path in [args.character.as_deref(), args.adapter.as_deref()]
        .into_iter()
        .flatten()
    {
        std::fs::metadata(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    let started = Instant::now();
    // The character loads while the speech is read: neither needs the other until the
    // visemes are put on the mouth.
    let (character, heard) = std::thread::scope(|scope| {
        let character = scope.spawn(|| crate::input::load_or_default(args.character.as_deref()));
        let heard = read_speech(&args, transcript.as_ref());
        let character = character
            .join()
            .map_err(|_| anyhow::anyhow!("loading the character stopped"));
        (character, heard)
    });
    let character = character??.character;
    crate::outputs::check_for(&outputs, &formats, Some(&character))?;
    let (sound, heard) = heard?;
    // The mouth, and what opens it through the retarget map (for a jaw bone beside it).
    let (mouth, opening) = match &args.adapter {
        Some(path) => (mouth_by_adapter(&character, &table, path)?, None),
        None => match Mouth::of(&character, &table) {
            Ok(mouth) => (mouth, None),
            // Shapes without mouth names: geometry may tell which make a mouth.
            Err(no_mouth @ faceanim_speech::MouthError::NoMouth(_)) => {
                mouth_by_map(&character, args.character.as_deref(), &table)?.ok_or(no_mouth)?
            }
            Err(other) => return Err(other.into()),
        },
    };
    let mut lip_sync = heard.on(&mouth, args.fps);
    if let Some(note) = transcript.as_ref().and_then(|t| t.note.clone()) {
        lip_sync.notes.insert(0, note);
    }
    let gestures = args.face.then(|| {
        let gestures = faceanim_speech::face::gestures(&sound, &lip_sync.phones);
        let moved =
            faceanim_speech::face::add(&mut lip_sync.frames, args.fps, &gestures, &character);
        if moved == 0 {
            lip_sync.notes.push(if faceanim_speech::face::shapes_reached(&character) == 0 {
                format!(
                    "--face: {} has no blink or brow shapes the name table knows",
                    character.name()
                )
            } else {
                // A short, even line: nothing to blink or raise the brows on (not the rig's
                // lack).
                format!(
                    "--face: no blink or brow raise falls in this line (a blink comes at a pause or after {} s without one, a raise on an accented syllable); the head still moves with it",
                    faceanim_speech::face::LONGEST_WITHOUT
                )
            });
        }
        gestures
    });
    let seconds = started.elapsed().as_secs_f64();
    for note in &lip_sync.notes {
        eprintln!("note: {}: {note}", args.speech.display());
    }
    let name = crate::input::stem(&args.speech, "speech");
    // With the face, the head moves too (nods on accents, a turn per phrase).
    let heads: Option<Vec<[f32; 3]>> = gestures.as_ref().map(|gestures| {
        (0..lip_sync.frames.len())
            .map(|k| gestures.head_at(k as f32 / args.fps))
            .collect()
    });
    let take = Take::from_weights(
        &character,
        &name,
        args.fps,
        &lip_sync.frames,
        heads.as_deref(),
    )?
    // What it is made of, whatever the character's shapes: Live Link Face's curves where its
    // own shapes do not carry them, and a jaw bone's opening.
    .made_of_arkit(lip_sync.arkit(&table))?;
    let animation = crate::outputs::take_animation(Some(&character), &take.session, &name)?
        .with_opening(opening);
    crate::outputs::write_all(&outputs, &formats, &animation, args.out.glb)?;
    eprintln!(
        "{:.2} s of sound in {:.2} s ({:.2}× real time): {} phones ({}), {} visemes on {} of {} shapes ({})",
        sound.seconds(),
        seconds,
        seconds / f64::from(sound.seconds()),
        lip_sync.phones.len(),
        match lip_sync.recognition {
            faceanim_speech::Recognition::Transcript => "aligned to the transcript",
            faceanim_speech::Recognition::Synthesis => "the transcript's, aligned by synthesis",
            faceanim_speech::Recognition::Words => "from the words recognised",
            faceanim_speech::Recognition::PhoneLoop => "from a phone loop",
        },
        lip_sync.track.keys.len(),
        lip_sync.shapes_moved,
        character.blendshapes().len(),
        match lip_sync.route {
            faceanim_speech::Route::Visemes => "its viseme shapes",
            faceanim_speech::Route::Arkit => "its ARKit mouth shapes",
            faceanim_speech::Route::Adapter => "its shapes as its adapter reads each viseme",
            faceanim_speech::Route::Retarget => "its shapes as its retarget map places each viseme",
            faceanim_speech::Route::JawBone => "none: it has none, and its jaw bone opens",
        }
    );
    if args.json {
        let summary = Summary {
            audio_seconds: sound.seconds(),
            seconds,
            real_time_factor: seconds / f64::from(sound.seconds()),
            frames: lip_sync.frames.len(),
            fps: args.fps,
            recognition: lip_sync.recognition,
            route: lip_sync.route,
            shapes_moved: lip_sync.shapes_moved,
            phones: &lip_sync.phones,
            visemes: &lip_sync.track.keys,
            gestures: gestures.as_ref(),
            notes: &lip_sync.notes,
        };
        outln!("{}", serde_json::to_string(&summary)?);
    }
    Ok(())
}

/// The sound of `args.speech` and its visemes, aligned to `transcript` (its text, and how to
/// name it) when there is one.
fn read_speech(
    args: &LipsyncArgs,
    transcript: Option<&Transcript>,
) -> anyhow::Result<(Sound, faceanim_speech::Reading)> {
    let blind = match args.recognise {
        Blind::Words => faceanim_speech::Recognition::Words,
        Blind::Phones => faceanim_speech::Recognition::PhoneLoop,
    };
    // As eSpeak NG names it (`ja-JP`: `ja`), for every route below.
    let language = faceanim_speech::recognition::check_language(&args.language)
        .map_err(|e| anyhow::anyhow!("--language {}: {e}", args.language))?;
    let sound = Sound::read(&args.speech)?;
    if let Some(Transcript { text, from, .. }) = transcript {
        faceanim_speech::phones::transcript_words(text, sound.seconds())
            .map_err(|e| anyhow::anyhow!("--text {from}: {e}"))?;
    }
    // Without a transcript the recogniser's models (most of a short line's time) load while
    // the character loads: the ones this voice is heard with (a woman's, a child's, a
    // whisper's), decided from the sound first.
    let loading = transcript.is_none().then(|| {
        faceanim_speech::recognition::Loading::start(&sound, Some(&language), blind, args.voice)
    });
    let heard = faceanim_speech::read_loaded(
        &sound,
        transcript.map(|t| t.text.as_str()),
        Some(&language),
        blind,
        loading,
        args.voice,
    )?;
    Ok((sound, heard))
}

/// The largest transcript or viseme table read, in bytes: a line of dialogue is a few hundred.
const MAX_TEXT_BYTES: u64 = 1 << 20;

/// A transcript given with `--text`.
struct Transcript {
    /// Its words.
    text: String,
    /// How to name it in a message: the file, or "(the words given)".
    from: String,
    /// What the user should know of how it was read: the encoding guessed for a file that is
    /// not Unicode.
    note: Option<String>,
}

/// `--text`: the words themselves, or a file that holds them, in `language` (which a file in a
/// legacy code page is read by: [`faceanim_files::text`]). One word that names a file which is
/// not there (a path, or a name ending in [`faceanim_speech::script::TRANSCRIPT_FILES`]) is an
/// error.
fn transcript(text: &str, language: &str) -> anyhow::Result<Transcript> {
    let path = Path::new(text);
    if !text.contains(char::is_whitespace) {
        if path.is_file() {
            let read = read_text(
                path,
                "--text",
                Accept::Legacy {
                    language: Some(language),
                },
            )?;
            let note = read.note(
                &format!("the transcript {}", path.display()),
                Some(&format!("--language {language}")),
            );
            return Ok(Transcript {
                text: read.text,
                from: path.display().to_string(),
                note,
            });
        }
        // A file's name that names none (mistyped, or relative to another folder) would
        // otherwise be spoken as the words "script dot t x t".
        let named_file = text.contains(['/', '\\'])
            || path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                faceanim_speech::script::TRANSCRIPT_FILES.contains(&e.to_ascii_lowercase().as_str())
            });
        if named_file {
            anyhow::bail!(
                "--text {text}: no such file (give the words themselves, or a file that holds them)"
            );
        }
    }
    Ok(Transcript {
        text: text.to_owned(),
        from: "(the words given)".to_owned(),
        note: None,
    })
}

/// The text of `path`, given as `option`, in the encodings `accept` allows: at most
/// [`MAX_TEXT_BYTES`], read only after its size is known; errors name the option and the file.
fn read_text(path: &Path, option: &str, accept: Accept<'_>) -> anyhow::Result<Text> {
    faceanim_files::read_text(path, MAX_TEXT_BYTES, accept)
        .map_err(|e| anyhow::anyhow!("{option} {e}"))
}

/// The mouth of a rig whose names say nothing of one, through its retarget map (the one
/// beside it, or made and saved there now), with what opens it at `jawOpen` 1
/// ([`faceanim_export::bones::jaw_opening`]); `None` when the map moves no shape of it.
fn mouth_by_map(
    character: &faceanim_rig::Character,
    character_path: Option<&Path>,
    table: &MouthTable,
) -> anyhow::Result<Option<(Mouth, Option<Vec<f32>>)>> {
    let models = faceanim_track::FaceModels::load().context("loading the face models")?;
    let Some(map) = crate::retarget::for_capture(character, character_path, None, &models)? else {
        return Ok(None);
    };
    let mouth = Mouth::through_map(&map, table);
    Ok(mouth
        .moves()
        .then(|| (mouth, faceanim_export::bones::jaw_opening(&map))))
}

/// `character`'s mouth read through its adapter at `path`: each viseme the built-in head makes
/// (by `table`), rendered from the front and read by the adapter.
fn mouth_by_adapter(
    character: &faceanim_rig::Character,
    table: &MouthTable,
    path: &Path,
) -> anyhow::Result<Mouth> {
    let adapter = crate::input::adapter(path)?;
    adapter
        .check(character)
        .with_context(|| format!("the adapter {}", path.display()))?;
    let models = faceanim_track::FaceModels::load().context("loading the face models")?;
    let head = faceanim_head::default_character();
    let rows = Mouth::performer_rows(&head, table)?;
    let readings = faceanim_adapt::FaceCamera::frame(&head, &models)?
        .read_performer(&head, &models, &adapter, &rows)?;
    Ok(Mouth::from_readings(
        character.blendshapes().len(),
        &readings,
    ))
}
