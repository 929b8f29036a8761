//! # faceanim-sphinx-sys: CMU PocketSphinx, as Debian ships it or built from its sources
//!
//! Thin bindings to `libpocketsphinx` (BSD licence), the maintained offline recogniser whose
//! acoustic model, phone language model and pronouncing dictionary come from a package
//! registry: Debian's 0.8 (`apt-get install libpocketsphinx-dev pocketsphinx-en-us`), or, on a
//! machine without it (macOS, Windows, other Linux), 5.1.0 compiled from its PyPI source
//! package with the US English models inside it (`scripts/setup.sh libraries` fetches it;
//! the build script says where it looks). The old
//! `pocketsphinx-sys` crates target other versions and are unmaintained; these bindings declare
//! only the functions faceanim calls ([`ffi`]) and wrap them in one safe call,
//! [`decode`]: 16 kHz mono speech in, time-aligned labels out (phones from a phone loop, words
//! recognised, or words from a grammar for forced alignment), one frame every 10 ms; or in two
//! steps, a [`Recogniser`] loaded before the speech is at hand, then decoding it (and, for a
//! second pass, its front end's cepstra and a speaker adaptation of its model: [`model`]). A word search
//! reads the pronouncing dictionary cut to its language model's words, kept in the user's
//! cache folder.
//!
//! Built where the library is missing, the crate still compiles and [`decode`] returns
//! [`SphinxError::NotInstalled`], so the rest of faceanim builds and runs on any machine.
//!
//! ```no_run
//! use faceanim_sphinx_sys::{decode, Search, EN_US};
//! let speech: Vec<i16> = vec![0; 16_000];
//! let phones = decode(&EN_US.phone_loop(), &speech)?;
//! for p in phones {
//!     println!("{} {}..{}", p.label, p.start, p.end);
//! }
//! # Ok::<(), faceanim_sphinx_sys::SphinxError>(())
//! ```
#![deny(missing_docs)]

use std::path::{Path, PathBuf};

#[cfg(pocketsphinx)]
mod known;
pub mod model;

pub use model::{Codebooks, ModelError, Transform};

/// Samples per second the models expect.
pub const SAMPLE_RATE: u32 = 16_000;
/// Decoder frames per second (one every 10 ms).
pub const FRAME_RATE: u32 = 100;

/// The samples each frame moves on by when the decoder reads `frame_rate` frames a second
/// ([`Search::warped`]), rounded to whole samples as PocketSphinx rounds them (83 frames a
/// second: 193, not 192.77).
#[must_use]
pub const fn frame_shift(frame_rate: u32) -> u32 {
    let frame_rate = if frame_rate == 0 {
        FRAME_RATE
    } else {
        frame_rate
    };
    (SAMPLE_RATE + frame_rate / 2) / frame_rate
}

/// Where Debian's `pocketsphinx-en-us` puts US English.
#[cfg(not(pocketsphinx_source))]
pub const EN_US: Models<'static> = Models {
    acoustic: "/usr/share/pocketsphinx/model/en-us/en-us",
    language_model: "/usr/share/pocketsphinx/model/en-us/en-us.lm.bin",
    phone_lm: "/usr/share/pocketsphinx/model/en-us/en-us-phone.lm.bin",
    dictionary: "/usr/share/pocketsphinx/model/en-us/cmudict-en-us.dict",
};

/// US English in the source package the library was compiled from (`model/en-us`: Debian's
/// acoustic and language models byte for byte, a newer revision of the dictionary).
#[cfg(pocketsphinx_source)]
pub const EN_US: Models<'static> = Models {
    acoustic: concat!(env!("FACEANIM_POCKETSPHINX_MODEL"), "/en-us"),
    language_model: concat!(env!("FACEANIM_POCKETSPHINX_MODEL"), "/en-us.lm.bin"),
    phone_lm: concat!(env!("FACEANIM_POCKETSPHINX_MODEL"), "/en-us-phone.lm.bin"),
    dictionary: concat!(env!("FACEANIM_POCKETSPHINX_MODEL"), "/cmudict-en-us.dict"),
};

/// A language's model files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Models<'a> {
    /// The acoustic model's folder (`-hmm`).
    pub acoustic: &'a str,
    /// The word language model (`-lm`).
    pub language_model: &'a str,
    /// The phone language model for a phone loop (`-allphone`).
    pub phone_lm: &'a str,
    /// The pronouncing dictionary (`-dict`).
    pub dictionary: &'a str,
}

impl Models<'_> {
    /// Any phone after any other, lightly weighted by the phone language model: recognition
    /// without a transcript, in any language the acoustic model's phones can tell apart.
    ///
    /// Over the context-independent phones with a language weight of 0.5. Chosen on eSpeak NG
    /// lines in Spanish, German and French and on flite's slt, rms, awb and eSpeak NG's en-us
    /// (viseme agreement, audio alone): over triphones with CMU's recommended settings (weight
    /// 2) it was 0.62 and 0.82 there at about 1.5× real time; tightening the triphones' beams
    /// (0.3×) or lowering their weight gained less than this does at 0.05–0.1× real time (0.65
    /// and 0.79). English phonotactics weigh less at a lower weight, which is what another
    /// language needs.
    #[must_use]
    pub fn phone_loop(&self) -> Search {
        Search {
            frame_rate: FRAME_RATE,
            acoustic: PathBuf::from(self.acoustic),
            mode: Mode::PhoneLoop {
                lm: PathBuf::from(self.phone_lm),
            },
        }
    }

    /// Words, weighted by the language model: recognition of what was said (words, which the
    /// dictionary turns into phones), several times faster than a phone loop.
    ///
    /// With the library's own beams. Narrower ones (`-beam 1e-40 -wbeam 1e-24`, or
    /// `-maxhmmpf 3000 -maxwpf 20`) decoded 15–30 % faster and cost clean voices at most
    /// 0.011 viseme agreement (flite slt, rms, awb; eSpeak NG m3, f2), but under pink room
    /// noise 15 dB below the voice they cost flite's slt and rms up to 0.05 agreement and up
    /// to a quarter of their P/B/M closures (slt 0.83 → 0.62 with the narrower beams): real
    /// recordings need the width.
    #[must_use]
    pub fn words(&self) -> Search {
        Search {
            frame_rate: FRAME_RATE,
            acoustic: PathBuf::from(self.acoustic),
            mode: Mode::Words {
                language_model: PathBuf::from(self.language_model),
                dictionary: PathBuf::from(self.dictionary),
            },
        }
    }

    /// Exactly `jsgf` (a JSGF grammar whose words are in the dictionary), with silences and
    /// fillers between words: forced alignment of a transcript.
    #[must_use]
    pub fn grammar(&self, jsgf: String) -> Search {
        Search {
            frame_rate: FRAME_RATE,
            acoustic: PathBuf::from(self.acoustic),
            mode: Mode::Grammar {
                jsgf,
                dictionary: PathBuf::from(self.dictionary),
            },
        }
    }
}

impl Models<'_> {
    /// Exactly `sequence` (ARPAbet phones, as the acoustic model names them: `AH`, `B`), each
    /// as a word of its own, with silences and fillers allowed between them: forced
    /// alignment at the level of phones. Segments come back labelled `ph_` and the phone in
    /// lower case (`ph_ah`).
    #[must_use]
    pub fn phones(&self, sequence: Vec<String>) -> Search {
        Search {
            frame_rate: FRAME_RATE,
            acoustic: PathBuf::from(self.acoustic),
            mode: Mode::Phones(sequence),
        }
    }
}

/// What the decoder searches for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Search {
    acoustic: PathBuf,
    mode: Mode,
    /// Frames a second of the sound decoded: 100, or fewer or more for a sound slowed or
    /// hurried (see [`Search::warped`]).
    frame_rate: u32,
}

impl Search {
    /// The folder of the acoustic model this search decodes with.
    #[must_use]
    pub fn acoustic(&self) -> &Path {
        &self.acoustic
    }

    /// This search over a sound slowed to `100 / frame_rate` of its speed (every frequency
    /// divided as much, as a longer vocal tract would say it), read `frame_rate` frames a
    /// second with each window as much longer: each frame then covers the same 10 ms of the
    /// speech as at 100, so the frames and their times are the unslowed sound's. A rate
    /// outside 40–250 is taken as 100.
    #[must_use]
    pub fn warped(mut self, frame_rate: u32) -> Search {
        self.frame_rate = if (40..=250).contains(&frame_rate) {
            frame_rate
        } else {
            FRAME_RATE
        };
        self
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Mode {
    PhoneLoop {
        lm: PathBuf,
    },
    Words {
        language_model: PathBuf,
        dictionary: PathBuf,
    },
    Grammar {
        jsgf: String,
        dictionary: PathBuf,
    },
    Phones(Vec<String>),
}

/// One decoded label and the frames it covers (both ends included, 10 ms each).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    /// A phone (`AA`, `SIL`, `+NSN+`) or a word (`hello`, `<sil>`, `[NOISE]`).
    pub label: String,
    /// First frame.
    pub start: u32,
    /// Last frame.
    pub end: u32,
}

/// An utterance decoded: its labels, and how well the acoustic model heard it.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// The labels, in order.
    pub segments: Vec<Segment>,
    /// The acoustic score of the labels that are not silence or fillers, per frame they
    /// cover: the acoustic model's log likelihood of the speech along them, in the decoder's
    /// units. Higher for speech the model hears as its own; lower for sound it hears poorly
    /// (a formant synthesiser's buzz). `None` when nothing but silence was decoded.
    pub score_per_frame: Option<f32>,
}

/// Why decoding failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SphinxError {
    /// faceanim was built where libpocketsphinx was not installed.
    #[error(
        "speech recognition needs CMU PocketSphinx: run scripts/setup.sh libraries (Debian's packages where apt-get is, its PyPI sources elsewhere), then build faceanim again"
    )]
    NotInstalled,
    /// A model file is missing.
    #[error("{0}: missing; scripts/setup.sh libraries installs the US English models")]
    MissingModel(PathBuf),
    /// The decoder refused its configuration or failed.
    #[error("the recogniser failed: {0}")]
    Decoder(String),
}

fn check(path: &Path) -> Result<(), SphinxError> {
    if path.exists() {
        Ok(())
    } else {
        Err(SphinxError::MissingModel(path.to_owned()))
    }
}

/// Decodes `samples` (16 kHz, mono) as one utterance with `search`: [`Recogniser::load`]
/// then [`Recogniser::decode`].
///
/// # Errors
/// [`SphinxError::NotInstalled`] without the library, [`SphinxError::MissingModel`] naming a
/// missing model file, [`SphinxError::Decoder`] when the recogniser fails.
pub fn decode(search: &Search, samples: &[i16]) -> Result<Vec<Segment>, SphinxError> {
    Recogniser::load(search)?.decode(samples)
}

/// A decoder with its models loaded, ready for speech. Loading is most of a short line's
/// cost (the word search reads a 27 MB language model and 23,000 pronunciations), and
/// needs no speech: a caller can load on one thread while it reads the sound on another.
/// It holds a [`Turn`] of the cores until dropped.
pub struct Recogniser {
    decoder: imp::Decoder,
    _turn: Turn,
}

impl std::fmt::Debug for Recogniser {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recogniser").finish_non_exhaustive()
    }
}

impl Recogniser {
    /// Loads `search`'s models, waiting for a [`Turn`] of the cores first.
    ///
    /// # Errors
    /// As [`decode`].
    pub fn load(search: &Search) -> Result<Recogniser, SphinxError> {
        Recogniser::load_on(search, None)
    }

    /// Loads `search`'s models on `turn` (shared with the other decoders of the same line:
    /// a small phone loop decoded while its word search loads), or on a turn waited for now
    /// when `None`. The models are checked before any wait.
    ///
    /// # Errors
    /// As [`decode`].
    pub fn load_on(search: &Search, turn: Option<&Turn>) -> Result<Recogniser, SphinxError> {
        check(&search.acoustic)?;
        match &search.mode {
            Mode::PhoneLoop { lm, .. } => check(lm)?,
            Mode::Grammar { dictionary, .. } => check(dictionary)?,
            Mode::Phones(sequence) => {
                if sequence.is_empty()
                    || sequence
                        .iter()
                        .any(|p| p.is_empty() || !p.bytes().all(|b| b.is_ascii_uppercase()))
                {
                    return Err(SphinxError::Decoder(format!(
                        "a phone sequence to align must be ARPAbet phones: {sequence:?}"
                    )));
                }
            }
            Mode::Words {
                language_model,
                dictionary,
            } => {
                check(language_model)?;
                check(dictionary)?;
            }
        }
        let turn = turn.map_or_else(Turn::wait, Turn::clone);
        Ok(Recogniser {
            decoder: imp::Decoder::load(search)?,
            _turn: turn,
        })
    }

    /// Decodes `samples` (16 kHz, mono) as one utterance.
    ///
    /// # Errors
    /// [`SphinxError::Decoder`] when the recogniser fails.
    pub fn decode(&mut self, samples: &[i16]) -> Result<Vec<Segment>, SphinxError> {
        Ok(self.decoder.decode(samples)?.segments)
    }

    /// [`Recogniser::decode`], with how well the acoustic model heard the sound.
    ///
    /// # Errors
    /// As [`Recogniser::decode`].
    pub fn decode_scored(&mut self, samples: &[i16]) -> Result<Decoded, SphinxError> {
        self.decoder.decode(samples)
    }

    /// The cepstra of `samples` as this recogniser's front end computes them (its frame rate,
    /// windows and filters; before any normalisation): one row a frame, its frames those of
    /// [`Recogniser::decode`] (the last part-frame left out).
    ///
    /// # Errors
    /// [`SphinxError::Decoder`] when the front end fails.
    pub fn cepstra(&mut self, samples: &[i16]) -> Result<Vec<Vec<f32>>, SphinxError> {
        self.decoder.cepstra(samples)
    }

    /// Decodes from now on with the acoustic model's means moved by `transform` (a speaker
    /// adaptation; it replaces any earlier one).
    ///
    /// # Errors
    /// [`SphinxError::Decoder`] when the decoder refuses the transform (one whose streams are
    /// not its model's).
    pub fn adapt(&mut self, transform: &Transform) -> Result<(), SphinxError> {
        self.decoder.adapt(transform)
    }
}

/// A turn of the cores: at most one line is recognised per core at once (its decoders hold
/// their models, some 250 MB with the language model), so that a burst of requests — a
/// studio's uploads, a batch — queues for the cores instead of multiplying memory. One line's
/// decoders may share a turn ([`Recogniser::load_on`]); it ends when the last of its clones
/// is dropped.
#[derive(Debug, Clone)]
pub struct Turn {
    _held: std::sync::Arc<Held>,
}

/// What a turn's clones share: the count goes down once, when the last is dropped.
#[derive(Debug)]
struct Held;

/// Decoders running now, and the signal that one ended.
static RUNNING: std::sync::Mutex<usize> = std::sync::Mutex::new(0);
static ENDED: std::sync::Condvar = std::sync::Condvar::new();

impl Turn {
    /// Waits until fewer lines are recognised than there are cores, and takes a turn.
    #[must_use]
    pub fn wait() -> Turn {
        let most = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
        let mut running = RUNNING
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        while *running >= most {
            running = ENDED
                .wait(running)
                .unwrap_or_else(std::sync::PoisonError::into_inner);
        }
        *running += 1;
        Turn {
            _held: std::sync::Arc::new(Held),
        }
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        let mut running = RUNNING
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        *running = running.saturating_sub(1);
        ENDED.notify_one();
    }
}

/// Whether this build has the recogniser.
#[must_use]
pub fn available() -> bool {
    cfg!(pocketsphinx)
}

#[cfg(not(pocketsphinx))]
mod imp {
    use super::{Decoded, Search, SphinxError};

    /// Never made: without the library, loading fails.
    pub enum Decoder {}

    impl Decoder {
        pub fn load(_: &Search) -> Result<Decoder, SphinxError> {
            Err(SphinxError::NotInstalled)
        }

        pub fn decode(&mut self, _: &[i16]) -> Result<Decoded, SphinxError> {
            match *self {}
        }

        pub fn cepstra(&mut self, _: &[i16]) -> Result<Vec<Vec<f32>>, SphinxError> {
            match *self {}
        }

        pub fn adapt(&mut self, _: &super::Transform) -> Result<(), SphinxError> {
            match *self {}
        }
    }
}

/// The C functions, as `pocketsphinx.h` and `sphinxbase/cmd_ln.h` of 0.8 declare them (5.1
/// declares the same ones the same way, in `pocketsphinx.h` and `util/cmd_ln.h`).
#[cfg(pocketsphinx)]
#[allow(missing_docs, non_camel_case_types, reason = "C's names")]
pub mod ffi {
    use std::os::raw::{c_char, c_int};

    /// C's opaque structures, known only by pointer.
    macro_rules! opaque {
        ($($name:ident),*) => {$(
            #[doc = concat!("`", stringify!($name), "`.")]
            #[repr(C)]
            pub struct $name {
                _opaque: [u8; 0],
            }
        )*};
    }
    opaque!(ps_decoder_t, cmd_ln_t, ps_seg_t, arg_t, fe_t, ps_mllr_t);

    unsafe extern "C" {
        pub fn ps_args() -> *const arg_t;
        pub fn cmd_ln_parse_r(
            inout: *mut cmd_ln_t,
            defn: *const arg_t,
            argc: i32,
            argv: *mut *mut c_char,
            strict: i32,
        ) -> *mut cmd_ln_t;
        /// 5.1 names it `ps_config_free` (and declares the old name without defining it).
        #[cfg_attr(pocketsphinx_source, link_name = "ps_config_free")]
        pub fn cmd_ln_free_r(cmdln: *mut cmd_ln_t) -> c_int;
        pub fn ps_init(config: *mut cmd_ln_t) -> *mut ps_decoder_t;
        pub fn ps_free(ps: *mut ps_decoder_t) -> c_int;
        pub fn ps_start_utt(ps: *mut ps_decoder_t) -> c_int;
        pub fn ps_process_raw(
            ps: *mut ps_decoder_t,
            data: *const i16,
            n_samples: usize,
            no_search: c_int,
            full_utt: c_int,
        ) -> c_int;
        pub fn ps_end_utt(ps: *mut ps_decoder_t) -> c_int;
        pub fn ps_seg_prob(
            seg: *mut ps_seg_t,
            out_ascr: *mut i32,
            out_lscr: *mut i32,
            out_lback: *mut i32,
        ) -> i32;
        pub fn ps_seg_iter(ps: *mut ps_decoder_t) -> *mut ps_seg_t;
        pub fn ps_seg_next(seg: *mut ps_seg_t) -> *mut ps_seg_t;
        pub fn ps_seg_word(seg: *mut ps_seg_t) -> *const c_char;
        pub fn ps_seg_frames(seg: *mut ps_seg_t, out_sf: *mut c_int, out_ef: *mut c_int);
        pub fn ps_seg_free(seg: *mut ps_seg_t);
        pub fn err_set_logfp(stream: *mut std::ffi::c_void);
        pub fn ps_get_fe(ps: *mut ps_decoder_t) -> *mut fe_t;
        pub fn ps_start_stream(ps: *mut ps_decoder_t) -> c_int;
        pub fn fe_start_utt(fe: *mut fe_t) -> c_int;
        /// `mfcc_t` is `float` in both libraries (neither is built for fixed point).
        pub fn fe_process_utt(
            fe: *mut fe_t,
            spch: *const i16,
            nsamps: usize,
            cep_block: *mut *mut *mut f32,
            nframes: *mut i32,
        ) -> c_int;
        pub fn fe_get_output_size(fe: *mut fe_t) -> c_int;
        pub fn fe_free_2d(arr: *mut std::ffi::c_void);
        pub fn ps_mllr_read(file: *const c_char) -> *mut ps_mllr_t;
        pub fn ps_mllr_free(mllr: *mut ps_mllr_t) -> c_int;
        /// 0.8 keeps the caller's reference; 5.1 takes one of its own.
        pub fn ps_update_mllr(ps: *mut ps_decoder_t, mllr: *mut ps_mllr_t) -> *mut ps_mllr_t;
    }
}

#[cfg(pocketsphinx)]
mod imp {
    use std::ffi::{CStr, CString};
    use std::sync::atomic::{AtomicU64, Ordering};

    use super::{Decoded, Mode, Search, Segment, SphinxError, ffi};

    /// The configuration and the decoder made from it, freed together, and the scratch files
    /// its search reads.
    pub struct Decoder {
        config: *mut ffi::cmd_ln_t,
        ps: *mut ffi::ps_decoder_t,
        _scratch: Vec<Scratch>,
    }

    /// Sphinx's log, off for the whole process once: set per decoder (`-logfn`), each decoder
    /// would reopen the one global log file under any other decoder loading at the time.
    fn quiet() {
        static QUIET: std::sync::Once = std::sync::Once::new();
        // SAFETY: NULL is the documented way to turn the log off; called before any decoder.
        QUIET.call_once(|| unsafe { ffi::err_set_logfp(std::ptr::null_mut()) });
    }

    // SAFETY: a PocketSphinx decoder and its configuration are plain heap structures with no
    // tie to the thread that made them (no thread-local state); `Decoder` is used through
    // `&mut` only, so one thread at a time.
    unsafe impl Send for Decoder {}

    impl Drop for Decoder {
        fn drop(&mut self) {
            // SAFETY: both pointers came from their constructors and are freed once, the
            // decoder (which holds a reference to the configuration) first.
            unsafe {
                if !self.ps.is_null() {
                    ffi::ps_free(self.ps);
                }
                if !self.config.is_null() {
                    ffi::cmd_ln_free_r(self.config);
                }
            }
        }
    }

    /// A grammar or dictionary file that is removed when dropped.
    struct Scratch(std::path::PathBuf);

    impl Scratch {
        /// Writes `text` to a new file in the temporary folder, ending in `.{extension}`.
        fn write(extension: &str, text: &str) -> Result<Scratch, SphinxError> {
            static COUNT: AtomicU64 = AtomicU64::new(0);
            let path = std::env::temp_dir().join(format!(
                "faceanim-{}-{}.{extension}",
                std::process::id(),
                COUNT.fetch_add(1, Ordering::Relaxed)
            ));
            std::fs::write(&path, text)
                .map_err(|e| SphinxError::Decoder(format!("{}: {e}", path.display())))?;
            Ok(Scratch(path))
        }
    }

    /// The settings of a grammar search over `dictionary`'s words, fillers allowed between
    /// them.
    fn grammar_args(dictionary: &str, grammar: &Scratch) -> [String; 6] {
        [
            "-dict".into(),
            dictionary.into(),
            "-jsgf".into(),
            text(&grammar.0),
            "-fsgusefiller".into(),
            "yes".into(),
        ]
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    fn text(path: &std::path::Path) -> String {
        path.to_string_lossy().into_owned()
    }

    impl Decoder {
        pub fn load(search: &Search) -> Result<Decoder, SphinxError> {
            quiet();
            // Every frame is decoded: the library's own voice activity detection drops the frames
            // of a pause (or, after a click, the silence before the speech) and numbers the
            // frames after it as if the pause had not been, so that everything after a pause of
            // 1.5 s was placed 0.7 s early.
            let mut args: Vec<String> = vec!["-hmm".into(), text(&search.acoustic)];
            // 5.1 has no detection of its own to turn off: it decodes every frame it is given.
            #[cfg(not(pocketsphinx_source))]
            args.extend(["-remove_silence".into(), "no".into()]);
            if search.frame_rate != super::FRAME_RATE {
                // The model's 25.625 ms windows, lengthened with the sound; the transform
                // long enough to hold them.
                let window = 0.025_625 * 100.0 / f64::from(search.frame_rate);
                let samples = window * f64::from(super::SAMPLE_RATE);
                args.extend([
                    "-frate".into(),
                    search.frame_rate.to_string(),
                    "-wlen".into(),
                    format!("{window:.6}"),
                    "-nfft".into(),
                    (if samples <= 512.0 { "512" } else { "1024" }).into(),
                ]);
            }
            let scratch = match &search.mode {
                Mode::PhoneLoop { lm } => {
                    args.extend(
                        [
                            "-allphone",
                            &text(lm),
                            "-allphone_ci",
                            "yes",
                            "-backtrace",
                            "no",
                            "-lw",
                            "0.5",
                            "-beam",
                            "1e-20",
                            "-pbeam",
                            "1e-20",
                        ]
                        .map(str::to_owned),
                    );
                    Vec::new()
                }
                Mode::Words {
                    language_model,
                    dictionary,
                } => {
                    let dictionary = super::known::dictionary_for(language_model, dictionary);
                    args.extend(
                        [
                            "-lm",
                            &text(language_model),
                            "-dict",
                            &text(&dictionary),
                            "-fwdflat",
                            "no",
                            "-bestpath",
                            "no",
                        ]
                        .map(str::to_owned),
                    );
                    Vec::new()
                }
                Mode::Grammar { jsgf, dictionary } => {
                    let grammar = Scratch::write("jsgf", jsgf)?;
                    args.extend(grammar_args(&text(dictionary), &grammar));
                    vec![grammar]
                }
                Mode::Phones(sequence) => {
                    let mut distinct: Vec<&String> = sequence.iter().collect();
                    distinct.sort();
                    distinct.dedup();
                    let entries: String = distinct
                        .iter()
                        .map(|p| format!("ph_{} {p}\n", p.to_ascii_lowercase()))
                        .collect();
                    let words: Vec<String> = sequence
                        .iter()
                        .map(|p| format!("ph_{}", p.to_ascii_lowercase()))
                        .collect();
                    let jsgf = format!(
                        "#JSGF V1.0;\ngrammar phones;\npublic <s> = {};\n",
                        words.join(" ")
                    );
                    let dictionary = Scratch::write("dict", &entries)?;
                    let grammar = Scratch::write("jsgf", &jsgf)?;
                    args.extend(grammar_args(&text(&dictionary.0), &grammar));
                    // Silence between phones a fifth as likely as CMU's default (0.005): the
                    // phones are known, and a whisper's quiet vowels otherwise fit the
                    // silence model better than their own (chosen on flite's and eSpeak NG's
                    // voices, a whisper among them).
                    args.extend(["-silprob".into(), "0.001".into()]);
                    vec![dictionary, grammar]
                }
            };
            let owned: Vec<CString> = args
                .iter()
                .map(|a| CString::new(a.as_str()))
                .collect::<Result<_, _>>()
                .map_err(|_| SphinxError::Decoder("a path holds a NUL byte".into()))?;
            let mut argv: Vec<*mut std::os::raw::c_char> =
                owned.iter().map(|a| a.as_ptr().cast_mut()).collect();
            let argc = i32::try_from(argv.len()).unwrap_or(i32::MAX);
            let mut decoder = Decoder {
                config: std::ptr::null_mut(),
                ps: std::ptr::null_mut(),
                _scratch: scratch,
            };
            // SAFETY: argv points at `argc` NUL-terminated strings that outlive the call (the
            // parser copies what it keeps); ps_args() is the library's static definition table.
            decoder.config = unsafe {
                ffi::cmd_ln_parse_r(
                    std::ptr::null_mut(),
                    ffi::ps_args(),
                    argc,
                    argv.as_mut_ptr(),
                    1,
                )
            };
            if decoder.config.is_null() {
                return Err(SphinxError::Decoder(format!(
                    "the settings were refused: {}",
                    args.join(" ")
                )));
            }
            // SAFETY: a valid configuration; the decoder keeps its own reference to it.
            decoder.ps = unsafe { ffi::ps_init(decoder.config) };
            if decoder.ps.is_null() {
                return Err(SphinxError::Decoder(
                "the models could not be loaded (a damaged model or grammar, or a word not in the dictionary)".into(),
            ));
            }
            Ok(decoder)
        }

        pub fn decode(&mut self, samples: &[i16]) -> Result<Decoded, SphinxError> {
            let decoder = self;
            // SAFETY: a live decoder; `samples` is valid for its length during the call.
            let processed = unsafe {
                // The front end's noise estimate from its first frame, as a decoder just
                // loaded starts (it otherwise runs on from the last utterance decoded).
                ffi::ps_start_stream(decoder.ps);
                if ffi::ps_start_utt(decoder.ps) < 0 {
                    return Err(SphinxError::Decoder("could not start the utterance".into()));
                }
                let n = ffi::ps_process_raw(decoder.ps, samples.as_ptr(), samples.len(), 0, 1);
                let end = ffi::ps_end_utt(decoder.ps);
                n.min(end)
            };
            if processed < 0 {
                return Err(SphinxError::Decoder("decoding failed".into()));
            }
            let mut segments = Vec::new();
            // The acoustic score of the frames of speech (silence and fillers left out).
            let (mut score, mut frames) = (0i64, 0u64);
            // SAFETY: the iterator belongs to the live decoder; ps_seg_next frees it when it
            // returns null, and each word pointer is read before the iterator moves on.
            unsafe {
                let mut seg = ffi::ps_seg_iter(decoder.ps);
                while !seg.is_null() {
                    let word = ffi::ps_seg_word(seg);
                    let (mut start, mut end) = (0, 0);
                    ffi::ps_seg_frames(seg, &raw mut start, &raw mut end);
                    if !word.is_null() && end >= start && start >= 0 {
                        let label = CStr::from_ptr(word).to_string_lossy().into_owned();
                        if !is_silence(&label) {
                            let (mut acoustic, mut language, mut backoff) = (0, 0, 0);
                            ffi::ps_seg_prob(
                                seg,
                                &raw mut acoustic,
                                &raw mut language,
                                &raw mut backoff,
                            );
                            score += i64::from(acoustic);
                            frames += u64::from((end - start + 1).unsigned_abs());
                        }
                        segments.push(Segment {
                            label,
                            start: start.unsigned_abs(),
                            end: end.unsigned_abs(),
                        });
                    }
                    seg = ffi::ps_seg_next(seg);
                }
            }
            Ok(Decoded {
                segments,
                score_per_frame: (frames > 0).then(|| score as f32 / frames as f32),
            })
        }
    }

    impl Decoder {
        pub fn cepstra(&mut self, samples: &[i16]) -> Result<Vec<Vec<f32>>, SphinxError> {
            let mut block: *mut *mut f32 = std::ptr::null_mut();
            let mut frames: i32 = 0;
            // SAFETY: a live decoder owns its front end; `samples` is valid for its length
            // during the call; the block the front end allocates is read within its
            // `frames` rows of `width` values, then freed once by the function that pairs
            // with its allocation.
            unsafe {
                // As a decode starts: the noise estimate from the first frame.
                ffi::ps_start_stream(self.ps);
                let fe = ffi::ps_get_fe(self.ps);
                if fe.is_null() || ffi::fe_start_utt(fe) < 0 {
                    return Err(SphinxError::Decoder("the front end could not start".into()));
                }
                let width = usize::try_from(ffi::fe_get_output_size(fe)).unwrap_or(0);
                let done = ffi::fe_process_utt(
                    fe,
                    samples.as_ptr(),
                    samples.len(),
                    &raw mut block,
                    &raw mut frames,
                );
                if block.is_null() {
                    return Err(SphinxError::Decoder("the front end failed".into()));
                }
                let rows = if done < 0 || width == 0 {
                    Vec::new()
                } else {
                    (0..usize::try_from(frames).unwrap_or(0))
                        .map(|f| std::slice::from_raw_parts(*block.add(f), width).to_vec())
                        .collect()
                };
                ffi::fe_free_2d(block.cast());
                if done < 0 {
                    return Err(SphinxError::Decoder("the front end failed".into()));
                }
                Ok(rows)
            }
        }

        pub fn adapt(&mut self, transform: &super::Transform) -> Result<(), SphinxError> {
            let file = Scratch::write("mllr", &transform.text())?;
            let path = CString::new(text(&file.0))
                .map_err(|_| SphinxError::Decoder("a path holds a NUL byte".into()))?;
            // SAFETY: a live decoder; the transform read is handed to it (0.8 keeps this
            // reference, 5.1 takes its own, so ours is freed there).
            unsafe {
                let mllr = ffi::ps_mllr_read(path.as_ptr());
                if mllr.is_null() {
                    return Err(SphinxError::Decoder(
                        "the speaker adaptation could not be read".into(),
                    ));
                }
                ffi::ps_update_mllr(self.ps, mllr);
                #[cfg(pocketsphinx_source)]
                ffi::ps_mllr_free(mllr);
            }
            Ok(())
        }
    }

    /// Whether a label is silence or a filler (`SIL`, `<sil>`, `+NSN+`, `[NOISE]`).
    fn is_silence(label: &str) -> bool {
        label == "SIL" || label.starts_with(['<', '+', '['])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_model_is_named() {
        let models = Models {
            acoustic: "/no/such/model",
            ..EN_US
        };
        let error = decode(&models.phone_loop(), &[0; 1600])
            .unwrap_err()
            .to_string();
        assert!(error.contains("/no/such/model"), "{error}");
    }

    /// "go forward ten meters", 16 kHz raw, from Debian's pocketsphinx-testdata.
    #[cfg(pocketsphinx)]
    fn go_forward() -> Option<Vec<i16>> {
        // The same recording is in PocketSphinx 5.1's source package.
        #[cfg(pocketsphinx_source)]
        let path = concat!(
            env!("FACEANIM_POCKETSPHINX_MODEL"),
            "/../../test/data/goforward.raw"
        );
        #[cfg(not(pocketsphinx_source))]
        let path = "/usr/share/pocketsphinx/test/data/goforward.raw";
        let Ok(bytes) = std::fs::read(path) else {
            // Built from the source package, the recording came with the library tested.
            #[cfg(pocketsphinx_source)]
            panic!("{path} is missing from the source package");
            #[cfg(not(pocketsphinx_source))]
            {
                eprintln!("{path} is missing: apt-get install pocketsphinx-testdata");
                return None;
            }
        };
        Some(
            bytes
                .chunks_exact(2)
                .map(|b| i16::from_le_bytes([b[0], b[1]]))
                .collect(),
        )
    }

    #[test]
    #[cfg(pocketsphinx)]
    fn real_speech_decodes_into_phones() {
        let Some(samples) = go_forward() else {
            return;
        };
        let phones = decode(&EN_US.phone_loop(), &samples).unwrap();
        let labels: Vec<&str> = phones.iter().map(|p| p.label.as_str()).collect();
        assert!(phones.len() > 10, "{labels:?}");
        assert!(labels.contains(&"F"), "forward: {labels:?}");
        // Segments are in order and do not overlap.
        for pair in phones.windows(2) {
            assert!(pair[0].end < pair[1].start, "{pair:?}");
        }
        let words = decode(
            &EN_US.grammar("#JSGF V1.0;\ngrammar t;\npublic <s> = go forward ten meters;\n".into()),
            &samples,
        )
        .unwrap();
        let words: Vec<&str> = words
            .iter()
            .map(|w| w.label.as_str())
            .filter(|w| !w.starts_with('<') && !w.starts_with('['))
            .collect();
        assert_eq!(words, ["go", "forward", "ten", "meters"]);
        // Recognised without being told: the language model's words.
        let heard = decode(&EN_US.words(), &samples).unwrap();
        let heard: Vec<&str> = heard
            .iter()
            .map(|w| w.label.as_str())
            .filter(|w| !w.starts_with('<') && !w.starts_with('['))
            .collect();
        assert!(
            heard.contains(&"forward") && heard.len() >= 3,
            "go forward ten meters: {heard:?}"
        );
    }

    /// Real speech scores as the acoustic model's own (a formant synthesiser's lines score
    /// −15.6 to −20.4 a frame); a line's decoders share its turn, so that a phone loop loads
    /// while every turn is taken by the line it belongs to.
    #[test]
    #[cfg(pocketsphinx)]
    fn speech_is_scored_and_a_lines_decoders_share_its_turn() {
        let Some(samples) = go_forward() else {
            return;
        };
        let most = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
        let turns: Vec<Turn> = (0..most).map(|_| Turn::wait()).collect();
        let (sent, received) = std::sync::mpsc::channel();
        let turn = turns[0].clone();
        std::thread::spawn(move || {
            let decoded = Recogniser::load_on(&EN_US.phone_loop(), Some(&turn))
                .and_then(|mut r| r.decode_scored(&samples));
            let _ = sent.send(decoded);
        });
        let decoded = received
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("a decoder given a turn already held waited for another")
            .unwrap();
        drop(turns);
        let score = decoded.score_per_frame.unwrap();
        assert!((-14.0..0.0).contains(&score), "{score}");
        assert!(decoded.segments.iter().any(|s| s.label == "F"));
    }

    #[test]
    #[cfg(pocketsphinx)]
    fn a_slowed_sound_read_at_fewer_frames_keeps_its_own_frames() {
        let Some(samples) = go_forward() else {
            return;
        };
        // Slowed to 80 % (every frequency 0.8 times), by linear interpolation.
        let slowed: Vec<i16> = (0..samples.len() * 5 / 4)
            .map(|n| {
                let x = n as f32 * 0.8;
                let (k, f) = (x as usize, x.fract());
                let a = f32::from(samples[k.min(samples.len() - 1)]);
                let b = f32::from(samples[(k + 1).min(samples.len() - 1)]);
                (a + (b - a) * f) as i16
            })
            .collect();
        let grammar = "#JSGF V1.0;\ngrammar t;\npublic <s> = go forward ten meters;\n";
        let words = |search: Search, samples: &[i16]| -> Vec<(String, u32, u32)> {
            decode(&search, samples)
                .unwrap()
                .into_iter()
                .filter(|w| !w.label.starts_with('<') && !w.label.starts_with('['))
                .map(|w| (w.label, w.start, w.end))
                .collect()
        };
        let plain = words(EN_US.grammar(grammar.into()), &samples);
        let heard = words(EN_US.grammar(grammar.into()).warped(80), &slowed);
        assert_eq!(plain.len(), 4, "{plain:?}");
        assert_eq!(heard.len(), 4, "{heard:?}");
        for (a, b) in plain.iter().zip(&heard) {
            assert_eq!(a.0, b.0);
            assert!(
                a.1.abs_diff(b.1) <= 3 && a.2.abs_diff(b.2) <= 3,
                "{plain:?} {heard:?}"
            );
        }
        // Out of range: read as it is.
        assert_eq!(EN_US.phone_loop().warped(7), EN_US.phone_loop());
    }

    #[test]
    #[cfg(pocketsphinx)]
    fn a_recogniser_gives_its_cepstra_and_takes_an_adaptation() {
        let Some(samples) = go_forward() else {
            return;
        };
        let codebooks = Codebooks::read(EN_US.phone_loop().acoustic()).unwrap();
        assert_eq!(codebooks.phones.len(), 42);
        assert!(codebooks.codebook("SIL").is_some() && codebooks.codebook("AA").is_some());
        assert_eq!(codebooks.streams, vec![13, 13, 13]);
        assert_eq!(codebooks.means.len(), 42 * 39 * codebooks.density);
        assert!(codebooks.variances.iter().all(|v| *v >= 1e-4));

        let mut recogniser = Recogniser::load(&EN_US.phone_loop()).unwrap();
        let plain = recogniser.decode(&samples).unwrap();
        let cepstra = recogniser.cepstra(&samples).unwrap();
        let frames = plain.last().unwrap().end as usize + 1;
        assert!(
            cepstra.len().abs_diff(frames) <= 2,
            "{} {frames}",
            cepstra.len()
        );
        assert!(cepstra.iter().all(|c| c.len() == 13));
        // c0 follows the energy: louder speech than the silence before it.
        let loudest = cepstra.iter().map(|c| c[0]).fold(f32::MIN, f32::max);
        assert!(loudest > cepstra[0][0] + 1.0);

        let identity = |scale: f32, shift: f32| Transform {
            streams: (0..3)
                .map(|_| {
                    let matrix = (0..13)
                        .map(|i| (0..13).map(|j| if i == j { scale } else { 0.0 }).collect())
                        .collect();
                    (matrix, vec![shift; 13])
                })
                .collect(),
        };
        // The identity: the same phones (the means reloaded and their constants computed
        // again, a boundary may move by a frame).
        recogniser.adapt(&identity(1.0, 0.0)).unwrap();
        let same = recogniser.decode(&samples).unwrap();
        let labels = |d: &[Segment]| d.iter().map(|s| s.label.clone()).collect::<Vec<_>>();
        assert!(
            labels(&same).len().abs_diff(labels(&plain).len()) <= 1,
            "{same:?}"
        );
        assert!(
            same.iter().zip(&plain).filter(|(a, b)| a == b).count() + 3 >= plain.len(),
            "{same:?}"
        );
        // Means moved far from every frame: other phones are heard.
        recogniser.adapt(&identity(0.2, 3.0)).unwrap();
        assert_ne!(labels(&recogniser.decode(&samples).unwrap()), labels(&same));
        // And back: a new transform replaces the last.
        recogniser.adapt(&identity(1.0, 0.0)).unwrap();
        assert_eq!(recogniser.decode(&samples).unwrap(), same);
    }
}
