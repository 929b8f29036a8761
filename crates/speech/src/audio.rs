//! Speech as the recogniser wants it: 16 kHz, mono, 16-bit.
//!
//! A WAV file in 8-, 16-, 24- or 32-bit PCM or 32-bit float, of any channels and any rate
//! (what recorders, TTS voices, editors and telephone systems write) is read here: its
//! channels mixed and resampled by band-limited interpolation ([`resample`]), with no other
//! program on any platform and no process started. Anything else — MP3, Ogg, FLAC, the sound
//! of a video, a WAV in another encoding — is converted by the `ffmpeg` program. How each was
//! chosen, on `scripts/bench-lipsync.py`'s lines: from 22,050 Hz (eSpeak NG's m3, f2 and
//! whisperf, clean and in a noisy room) the recogniser reads the same viseme classes from
//! either conversion (agreement within ±0.01 with the transcript and ±0.025 without, and half
//! the command's time with the transcript: 0.04× real time against 0.08–0.09×). From 8 kHz
//! (the bench's telephone effect on flite's slt, rms and awb and eSpeak NG's en-us, m1, m3, m7
//! and whisperf) the classes read without the transcript differ by a decision or two of a
//! recogniser sensitive to the least change, neither way better (mean agreement 0.663 from
//! ffmpeg's conversion, 0.659 from [`resample`]; lips closed for 181 and 183 of 232 P, B and
//! M), while starting ffmpeg cost 0.06–0.08 s of every line's command (on a Harvard
//! sentence, 0.03× of its real time).
//!
//! Errors name the file and what is wrong with it: not audio, no sound in it, longer than
//! [`MAX_SECONDS`].

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

pub use faceanim_sphinx_sys::{FRAME_RATE, SAMPLE_RATE};

/// The longest sound accepted: an hour.
pub const MAX_SECONDS: f32 = 3600.0;

/// Samples per recogniser frame (10 ms).
pub const FRAME_SAMPLES: usize = (SAMPLE_RATE / FRAME_RATE) as usize;

/// Mono 16 kHz speech.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sound {
    /// The samples.
    pub samples: Vec<i16>,
}

/// Why a sound could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AudioError {
    /// The file could not be read.
    #[error("{path}: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// `ffmpeg` is not installed.
    #[error(
        "{0}: reading this kind of audio needs the ffmpeg program (apt-get install ffmpeg), or give a PCM WAV (any rate, any channels)"
    )]
    NoFfmpeg(PathBuf),
    /// The file holds no sound.
    #[error("{0}: there is no sound in it")]
    Empty(PathBuf),
    /// The sound is too long.
    #[error("{path}: {} of sound; at most {max:.0} s are read at once (cut it into parts)", long(*.seconds), max = MAX_SECONDS)]
    TooLong {
        /// The file.
        path: PathBuf,
        /// Its length ([`f32::INFINITY`] where only "longer than the limit" is known).
        seconds: f32,
    },
}

/// A length too long to read, in words.
fn long(seconds: f32) -> String {
    if seconds.is_finite() {
        format!("{seconds:.0} s")
    } else {
        format!("more than {MAX_SECONDS:.0} s")
    }
}

/// The offset (in samples' units, of 32,768) up to which a sound is kept as it is: 0.3 % of
/// full scale (−50 dBFS), as flite's own voices carry (awb's lines: 76 to 158).
const OFFSET: i32 = 100;

impl Sound {
    /// Reads `path`.
    ///
    /// # Errors
    /// [`AudioError`] naming the file.
    pub fn read(path: &Path) -> Result<Sound, AudioError> {
        let bad = |message: String| AudioError::Read {
            path: path.to_owned(),
            message,
        };
        let metadata = std::fs::metadata(path).map_err(|e| bad(e.to_string()))?;
        if metadata.is_dir() {
            return Err(bad("is a folder, not a sound".into()));
        }
        if metadata.len() == 0 {
            return Err(AudioError::Empty(path.to_owned()));
        }
        let sound = match read_wav(path).map_err(bad)? {
            Wav::Plain(sound) => sound,
            Wav::Other(header) => {
                header.check().map_err(bad)?;
                if header.seconds() > f64::from(MAX_SECONDS) {
                    return Err(AudioError::TooLong {
                        path: path.to_owned(),
                        seconds: header.seconds() as f32,
                    });
                }
                // An encoding not read here (µ-law, ADPCM, …): ffmpeg's.
                convert(path)?
            }
            Wav::Elsewhere => convert(path)?,
        };
        sound.checked(path).map(Sound::without_offset)
    }

    /// This sound without a DC offset (a cheap sound card's, or one drifting slowly), where it
    /// has one — the median 10 ms frame's mean over `OFFSET` — through a one-pole high-pass
    /// at about 13 Hz, under any voice; a sound without one is kept as it is. An offset of a
    /// tenth of full scale otherwise made every frame as loud as the voice, so that none was
    /// heard as one and the mouth stayed shut.
    #[must_use]
    pub fn without_offset(self) -> Sound {
        let mut offsets: Vec<i32> = self
            .samples
            .chunks(FRAME_SAMPLES)
            .map(|frame| {
                let sum: i64 = frame.iter().map(|&s| i64::from(s)).sum();
                (sum / frame.len() as i64)
                    .unsigned_abs()
                    .min(i32::MAX as u64) as i32
            })
            .collect();
        offsets.sort_unstable();
        if offsets
            .get(offsets.len() / 2)
            .is_none_or(|&median| median <= OFFSET)
        {
            return self;
        }
        // y[n] = x[n] - x[n-1] + R y[n-1]: the pole's radius sets the cut-off (16 kHz).
        const R: f32 = 0.995;
        // Started as if the first sample had always been: an offset there from the start
        // leaves no click.
        let first = self.samples.first().map_or(0.0, |&s| f32::from(s));
        let (mut before, mut out) = (first, 0.0f32);
        let samples = self
            .samples
            .iter()
            .map(|&s| {
                let x = f32::from(s);
                out = x - before + R * out;
                before = x;
                out.round().clamp(-32768.0, 32767.0) as i16
            })
            .collect();
        Sound { samples }
    }

    fn checked(self, path: &Path) -> Result<Sound, AudioError> {
        // Less than one 10 ms frame holds nothing to hear.
        if self.samples.len() < FRAME_SAMPLES {
            return Err(AudioError::Empty(path.to_owned()));
        }
        let seconds = self.seconds();
        if seconds > MAX_SECONDS {
            return Err(AudioError::TooLong {
                path: path.to_owned(),
                seconds,
            });
        }
        Ok(self)
    }

    /// This sound played as if recorded at `rate` samples a second, at 16 kHz again: faster
    /// and higher above 16,000 (every frequency times `rate` / 16,000), slower and lower under
    /// it.
    #[must_use]
    pub fn played_at(&self, rate: u32) -> Sound {
        if rate == SAMPLE_RATE {
            return self.clone();
        }
        Sound {
            samples: resample_pcm(&self.samples, rate),
        }
    }

    /// Its length in seconds.
    #[must_use]
    pub fn seconds(&self) -> f32 {
        self.samples.len() as f32 / SAMPLE_RATE as f32
    }

    /// The loudness of each 10 ms frame, in dB relative to full scale (−100 for silence).
    #[must_use]
    pub fn frame_levels(&self) -> Vec<f32> {
        self.samples
            .chunks(FRAME_SAMPLES)
            .map(|frame| {
                let power = frame
                    .iter()
                    .map(|&s| {
                        let v = f64::from(s) / 32768.0;
                        v * v
                    })
                    .sum::<f64>()
                    / frame.len().max(1) as f64;
                if power <= 1e-10 {
                    -100.0
                } else {
                    (10.0 * power.log10()) as f32
                }
            })
            .collect()
    }

    /// Per 10 ms frame, whether a voice may be heard: louder than the recording's own noise
    /// floor (`noise_floor`) by a share of its range, and than 35 dB under its peak or −55
    /// dBFS, whichever is lower. A recording without a clear difference between its quiet and
    /// loud parts (silence, steady noise, hum), or whose loudest is under −70 dBFS, has none. A
    /// quiet recording (a distant microphone, a badly set gain: a voice peaking at −50 dBFS) is
    /// heard as a loud one is; before, nothing under −55 dBFS was a voice. A line trimmed to
    /// its words (a synthesiser's, a game's voice line) is heard through its quieter vowels.
    #[must_use]
    pub fn voice_activity(&self) -> Vec<bool> {
        let levels = self.frame_levels();
        if levels.is_empty() {
            return Vec::new();
        }
        let mut sorted = levels.clone();
        sorted.sort_by(f32::total_cmp);
        let peak = level_under(&sorted, 98);
        let floor = noise_floor(&sorted, peak);
        match voice_threshold(floor, peak, (peak - 35.0).min(-55.0), -70.0) {
            Some(threshold) => levels.iter().map(|&l| l > threshold).collect(),
            None => vec![false; levels.len()],
        }
    }
}

/// The share of a recording's frames, in percent, assumed to be pauses: the noise floor is
/// the level this share of frames lies under.
const PAUSE_PERCENT: usize = 10;
/// The share, in percent, a line trimmed to its words is assumed to rest in: its stop
/// closures, a breath between words.
const TRIMMED_PAUSE_PERCENT: usize = 3;
/// How far under a recording's peak (dB) its pauses lie at least: in every recording here
/// 26 dB or more (LibriVox readings 26–31, Debian's other test recordings 31–44, flite's
/// lines 48–58, and 28–41 in pink noise 15 dB under the voice), while a voice's own quiet
/// sounds — a nasal, a fricative — lie 16–25 dB under its vowels. A tenth of the frames
/// nearer the peak than this are those sounds.
const PAUSE_UNDER_PEAK_DB: f32 = 25.0;
/// How far (dB) the quietest [`TRIMMED_PAUSE_PERCENT`] of the frames may lie under the
/// quietest [`PAUSE_PERCENT`] and the two still be one floor: a recording's noise in its
/// pauses varies by 2–3 dB (pink noise) to 4–8.5 (LibriVox's MP3s); under a synthesiser's
/// exact silences in its stop closures the rest of its quiet lies 30–70 dB higher.
const ONE_FLOOR_DB: f32 = 10.0;

/// The level of a recording's quiet, in dBFS, from its frames' levels in ascending order
/// (at least one), given its `peak`: the level a tenth of its frames lie under
/// ([`PAUSE_PERCENT`]), unless that tenth is not its pauses — nearer the peak than pauses
/// lie ([`PAUSE_UNDER_PEAK_DB`]), or far above its quietest frames ([`ONE_FLOOR_DB`]). Then
/// the line is trimmed to its words (eSpeak NG's lines: 1 to 7 in 100 of their frames are
/// pauses), a tenth of it is the voice's own quiet sounds, and a floor there put the quieter
/// vowels under the threshold (the mouth shut through the final vowel of Hindi `लाई`, 17 of
/// 17 frames); its floor is the level its closures ([`TRIMMED_PAUSE_PERCENT`]) lie under.
fn noise_floor(sorted: &[f32], peak: f32) -> f32 {
    let (pauses, closures) = (
        level_under(sorted, PAUSE_PERCENT),
        level_under(sorted, TRIMMED_PAUSE_PERCENT),
    );
    if peak - pauses < PAUSE_UNDER_PEAK_DB || pauses - closures > ONE_FLOOR_DB {
        closures
    } else {
        pauses
    }
}

/// The level `percent` of the frames lie under, from their levels in ascending order (at
/// least one).
fn level_under(sorted: &[f32], percent: usize) -> f32 {
    sorted[(sorted.len() * percent / 100).min(sorted.len() - 1)]
}

/// The runs of `value` in `flags` (one per 10 ms frame, as [`Sound::voice_activity`] gives
/// them) at least `shortest` frames long, as frame ranges in order.
pub(crate) fn runs(flags: &[bool], value: bool, shortest: usize) -> Vec<std::ops::Range<usize>> {
    let mut found = Vec::new();
    let mut k = 0;
    while k < flags.len() {
        if flags[k] != value {
            k += 1;
            continue;
        }
        let start = k;
        while k < flags.len() && flags[k] == value {
            k += 1;
        }
        if k - start >= shortest {
            found.push(start..k);
        }
    }
    found
}

/// The level (dBFS) above which a voice is heard, between a quiet `floor` and a loud `peak`:
/// a share of their range above the floor, and never under `quietest`. `None` when quiet and
/// loud differ too little (silence, steady noise, hum) or nothing reaches `faintest` (the
/// quietest peak a voice has). The rule of both [`Sound::voice_activity`] and the live
/// listener's gate.
pub(crate) fn voice_threshold(floor: f32, peak: f32, quietest: f32, faintest: f32) -> Option<f32> {
    let range = peak - floor;
    if range < 12.0 || peak < faintest {
        return None;
    }
    Some((floor + (0.3 * range).max(8.0)).max(quietest))
}

/// What a file's WAV header says.
enum Wav {
    /// A PCM or float WAV, read here.
    Plain(Sound),
    /// A WAV of another format (ffmpeg converts it) or too long, checked first.
    Other(WavHeader),
    /// Not a WAV: ffmpeg reads it.
    Elsewhere,
}

/// The format and length a WAV file declares.
struct WavHeader {
    channels: u16,
    rate: u32,
    bits: u16,
    data_bytes: usize,
}

/// The lowest and highest sample rates a sound may have: telephone speech is 8 kHz, studio
/// recordings up to 384 kHz.
const RATES: std::ops::RangeInclusive<u32> = 4_000..=384_000;

impl WavHeader {
    /// Refuses, before ffmpeg is run, a header no recorder writes: a rate that would make
    /// ffmpeg produce hours of samples from a small file, no channels, no sample size.
    fn check(&self) -> Result<(), String> {
        if !RATES.contains(&self.rate) {
            return Err(format!(
                "the WAV header says {} Hz; sound is {} to {} Hz",
                self.rate,
                RATES.start(),
                RATES.end()
            ));
        }
        if !(1..=32).contains(&self.channels) {
            return Err(format!("the WAV header says {} channels", self.channels));
        }
        if !(1..=64).contains(&self.bits) {
            return Err(format!("the WAV header says {}-bit samples", self.bits));
        }
        Ok(())
    }

    /// The length the header declares.
    fn seconds(&self) -> f64 {
        let frame = f64::from(self.channels) * f64::from(self.bits).div_euclid(8.0).max(1.0);
        self.data_bytes as f64 / frame / f64::from(self.rate.max(1))
    }
}

/// Reads `path`'s WAV header: a canonical 16 kHz mono 16-bit PCM WAV is read whole here, and
/// any other PCM or float WAV is mixed to mono and resampled to 16 kHz here; an error for a
/// WAV that is cut short or lacks its format.
fn read_wav(path: &Path) -> Result<Wav, String> {
    // The header first: an MP3 or a video is left to ffmpeg without being read here.
    let mut header = [0u8; 12];
    let mut file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    if std::io::Read::read_exact(&mut file, &mut header).is_err()
        || &header[0..4] != b"RIFF"
        || &header[8..12] != b"WAVE"
    {
        return Ok(Wav::Elsewhere);
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let (mut at, mut format, mut data) = (12usize, None, None);
    while at + 8 <= bytes.len() {
        let id = &bytes[at..at + 4];
        let size = u32::from_le_bytes([bytes[at + 4], bytes[at + 5], bytes[at + 6], bytes[at + 7]])
            as usize;
        let body = at + 8;
        let end = body.saturating_add(size);
        if id == b"fmt " && size >= 16 && end <= bytes.len() {
            let u16_at = |k: usize| u16::from_le_bytes([bytes[body + k], bytes[body + k + 1]]);
            let rate = u32::from_le_bytes([
                bytes[body + 4],
                bytes[body + 5],
                bytes[body + 6],
                bytes[body + 7],
            ]);
            // WAVE_FORMAT_EXTENSIBLE (what ffmpeg and DAWs write past 16 bits or 2
            // channels) names its encoding in its sub-format's first two bytes.
            let tag = match u16_at(0) {
                0xFFFE if size >= 40 => u16_at(24),
                tag => tag,
            };
            format = Some((tag, u16_at(2), rate, u16_at(14)));
        } else if id == b"data" {
            // Streams written live often leave the size 0 or too large: read what is there.
            // A size larger than the file (short of those placeholders, 0x7FFFFFFF and
            // 0xFFFFFFFF) is also a recording cut short — a crash, a copy interrupted — and
            // is said, so that its missing end is not lost silently.
            let end = if size == 0 {
                bytes.len()
            } else {
                if end > bytes.len() && size < 0x7FFF_FFFF {
                    tracing::warn!(
                        "{}: the WAV is cut short: {} of the {size} bytes of sound its header names are there",
                        path.display(),
                        bytes.len() - body
                    );
                }
                end.min(bytes.len())
            };
            data = Some(&bytes[body..end]);
            break;
        }
        at = end.saturating_add(size & 1);
    }
    match (format, data) {
        (Some((1, 1, SAMPLE_RATE, 16)), Some(data)) => Ok(Wav::Plain(Sound {
            samples: data
                .chunks_exact(2)
                .map(|b| i16::from_le_bytes([b[0], b[1]]))
                .collect(),
        })),
        (Some((tag, channels, rate, bits)), data) => {
            let header = WavHeader {
                channels,
                rate,
                bits,
                data_bytes: data.map_or(0, <[u8]>::len),
            };
            let encoding = Encoding::of(tag, bits);
            match (encoding, data) {
                (Some(encoding), Some(data))
                    if header.check().is_ok() && header.seconds() <= f64::from(MAX_SECONDS) =>
                {
                    let mono = mixed(data, encoding, usize::from(channels));
                    Ok(Wav::Plain(Sound {
                        samples: resample(&mono, rate),
                    }))
                }
                _ => Ok(Wav::Other(header)),
            }
        }
        (None, _) => Err("a WAV file without its format chunk".into()),
    }
}

/// How a WAV's samples are stored (its format tag and sample size), where read here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    /// Unsigned 8-bit PCM.
    U8,
    /// Signed little-endian PCM of 2, 3 or 4 bytes.
    Int(usize),
    /// 32-bit IEEE float.
    Float,
}

impl Encoding {
    /// The encoding of WAV format `tag` (an extensible WAV's sub-format) with `bits` per
    /// sample; `None` for what only ffmpeg reads (compressed, 64-bit).
    fn of(tag: u16, bits: u16) -> Option<Encoding> {
        match (tag, bits) {
            (1, 8) => Some(Encoding::U8),
            (1, 16 | 24 | 32) => Some(Encoding::Int(usize::from(bits / 8))),
            (3, 32) => Some(Encoding::Float),
            _ => None,
        }
    }

    fn bytes(self) -> usize {
        match self {
            Encoding::U8 => 1,
            Encoding::Int(n) => n,
            Encoding::Float => 4,
        }
    }

    /// One sample, in [-1, 1].
    fn value(self, b: &[u8]) -> f32 {
        match self {
            Encoding::U8 => (f32::from(b[0]) - 128.0) / 128.0,
            Encoding::Int(n) => {
                // The sample in the top bytes of an i32, so its sign is right.
                let mut word = [0u8; 4];
                word[4 - n..].copy_from_slice(&b[..n]);
                i32::from_le_bytes(word) as f32 / 2_147_483_648.0
            }
            Encoding::Float => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// `data`'s frames of `channels` interleaved samples, mixed to one channel (their mean).
fn mixed(data: &[u8], encoding: Encoding, channels: usize) -> Vec<f32> {
    let size = encoding.bytes();
    let channels = channels.max(1);
    data.chunks_exact(size * channels)
        .map(|frame| {
            frame
                .chunks_exact(size)
                .map(|b| encoding.value(b))
                .sum::<f32>()
                / channels as f32
        })
        .collect()
}

/// Zero crossings of the interpolation kernel on each side (at the lower of the two rates).
const KERNEL_ZEROS: f64 = 16.0;
/// Kernel values per input sample in the lookup table.
const KERNEL_STEPS: f64 = 512.0;
/// The Kaiser window's shape (ffmpeg's resampler's default).
const KAISER_BETA: f64 = 9.0;

/// The modified Bessel function of the first kind, order 0 (its power series, which
/// converges fast for the window's arguments).
fn bessel_i0(x: f64) -> f64 {
    let (mut sum, mut term) = (1.0, 1.0);
    let quarter = x * x / 4.0;
    for k in 1..64 {
        term *= quarter / f64::from(k * k);
        sum += term;
        if term < sum * 1e-16 {
            break;
        }
    }
    sum
}

/// `samples` (in [-1, 1]) at `rate` Hz as 16 kHz 16-bit samples: band-limited interpolation,
/// each output sample the input under a Kaiser-windowed sinc (β 9) whose cutoff is 97 % of the
/// lower of the two Nyquist frequencies (so nothing above 8 kHz folds back into speech), ±16 of
/// its zero crossings wide; the kernel is tabulated and read with linear interpolation, and
/// its weights for each phase of the output against the input (`n × rate / 16,000`, reduced)
/// are read once, not at every output sample.
#[must_use]
pub fn resample(samples: &[f32], rate: u32) -> Vec<i16> {
    resample_tabulating(samples, rate, MAX_PHASES)
}

/// 16-bit `samples` at `rate` Hz as 16 kHz 16-bit samples, by [`resample`].
#[must_use]
pub(crate) fn resample_pcm(samples: &[i16], rate: u32) -> Vec<i16> {
    let floats: Vec<f32> = samples.iter().map(|&s| f32::from(s) / 32768.0).collect();
    resample(&floats, rate)
}

/// [`resample`], with the kernel tabulated for up to `max_phases` phases.
fn resample_tabulating(samples: &[f32], rate: u32, max_phases: u64) -> Vec<i16> {
    let quantise = |v: f64| (v * 32768.0).round().clamp(-32768.0, 32767.0) as i16;
    if rate == SAMPLE_RATE || samples.is_empty() || rate == 0 {
        return samples.iter().map(|&v| quantise(f64::from(v))).collect();
    }
    // Input samples per output sample, and the cutoff in cycles per input sample (×2).
    let step = f64::from(rate) / f64::from(SAMPLE_RATE);
    let cutoff = 0.97 * (1.0 / step).min(1.0);
    let half = KERNEL_ZEROS / cutoff;
    let kernel: Vec<f64> = (0..=(half * KERNEL_STEPS).ceil() as usize + 1)
        .map(|k| {
            let x = k as f64 / KERNEL_STEPS;
            if x >= half {
                return 0.0;
            }
            let u = x / half;
            let window = bessel_i0(KAISER_BETA * (1.0 - u * u).sqrt()) / bessel_i0(KAISER_BETA);
            let arg = std::f64::consts::PI * cutoff * x;
            let sinc = if arg.abs() < 1e-12 {
                1.0
            } else {
                arg.sin() / arg
            };
            cutoff * sinc * window
        })
        .collect();
    let at = |x: f64| {
        let position = x.abs() * KERNEL_STEPS;
        let k = position.floor() as usize;
        let frac = position - k as f64;
        match (kernel.get(k), kernel.get(k + 1)) {
            (Some(a), Some(b)) => a + (b - a) * frac,
            _ => 0.0,
        }
    };
    let outputs = (samples.len() as f64 / step).floor() as usize;
    let last = samples.len() as isize - 1;
    // The output's position in the input, each `n`: `n × rate / 16,000` reduced, so that the
    // kernel's weights repeat every `phases` outputs (160 from 44.1 kHz, 320 from 22.05 kHz,
    // 1 from 48 kHz) and are computed once for each.
    let common = gcd(rate, SAMPLE_RATE);
    let (up, phases) = (u64::from(rate / common), u64::from(SAMPLE_RATE / common));
    let span = |t: f64| ((t - half).ceil() as isize, (t + half).floor() as isize);
    let weights: Vec<(isize, Vec<f64>)> = match phases <= max_phases {
        true => (0..phases)
            .map(|phase| {
                let t = phase as f64 / phases as f64;
                let (first, end) = span(t);
                (first, (first..=end).map(|k| at(t - k as f64)).collect())
            })
            .collect(),
        false => Vec::new(),
    };
    (0..outputs)
        .map(|n| {
            // The input sample at or before the output, and the phase past it.
            let position = n as u64 * up;
            let (whole, phase) = (position / phases, (position % phases) as usize);
            let tabulated = weights.get(phase).and_then(|(offset, weights)| {
                let from = usize::try_from(whole as isize + offset).ok()?;
                Some((samples.get(from..from + weights.len())?, weights))
            });
            let sum: f64 = match tabulated {
                Some((inputs, weights)) => inputs
                    .iter()
                    .zip(weights)
                    .map(|(&v, w)| f64::from(v) * w)
                    .sum(),
                // Near either end (the kernel reaches past the sound), or a rate with too many
                // phases: the kernel read at each input sample.
                None => {
                    let t = n as f64 * step;
                    let (first, end) = span(t);
                    (first.max(0)..=end.min(last))
                        .map(|k| f64::from(samples[k as usize]) * at(t - k as f64))
                        .sum()
                }
            };
            quantise(sum)
        })
        .collect()
}

/// The most kernel phases [`resample`] tabulates (a rate whose ratio to 16 kHz reduces to
/// more is resampled by reading the kernel at each output sample).
const MAX_PHASES: u64 = 2048;

/// The greatest common divisor of `a` and `b`.
fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The sound of any file ffmpeg reads, converted to 16 kHz mono.
fn convert(path: &Path) -> Result<Sound, AudioError> {
    let output = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-i"])
        .arg(path)
        .args([
            "-vn",
            "-ac",
            "1",
            "-ar",
            "16000",
            "-f",
            "s16le",
            "-acodec",
            "pcm_s16le",
        ])
        .args(["-t", &format!("{}", MAX_SECONDS + 1.0), "-"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => AudioError::NoFfmpeg(path.to_owned()),
            _ => AudioError::Read {
                path: path.to_owned(),
                message: format!("running ffmpeg: {e}"),
            },
        })?;
    if !output.status.success() {
        let said = String::from_utf8_lossy(&output.stderr);
        let message = if said.contains("does not contain any stream")
            || said.contains("Output file #0 does not contain")
            || said.contains("matches no streams")
            || said.contains("no audio")
        {
            "not a sound or a video with sound".to_owned()
        } else {
            faceanim_media::ffmpeg::explain(&said)
        };
        return Err(AudioError::Read {
            path: path.to_owned(),
            message,
        });
    }
    let sound = Sound {
        samples: output
            .stdout
            .chunks_exact(2)
            .map(|b| i16::from_le_bytes([b[0], b[1]]))
            .collect(),
    };
    // ffmpeg stops a second past the limit (-t): all that is known is that it is longer.
    if sound.seconds() > MAX_SECONDS {
        return Err(AudioError::TooLong {
            path: path.to_owned(),
            seconds: f32::INFINITY,
        });
    }
    Ok(sound)
}

/// A canonical WAV (RIFF, PCM, 16 bits) of `samples` at `rate` Hz, `channels` interleaved: the
/// one writer of the format the reader above reads (the studio keeps a microphone take's sound
/// in it).
#[must_use]
pub fn wav_bytes(samples: &[i16], rate: u32, channels: u16) -> Vec<u8> {
    let mut out = wav_header(1, channels, rate, 16, samples.len() * 2);
    for s in samples {
        out.extend_from_slice(&s.to_le_bytes());
    }
    out
}

/// The 44 bytes before a WAV's samples: format `tag` (1 PCM, 3 float), `channels`, `rate`,
/// `bits` per sample and `data` bytes of samples to follow.
fn wav_header(tag: u16, channels: u16, rate: u32, bits: u16, data: usize) -> Vec<u8> {
    let data = data as u32;
    let align = channels * bits.div_ceil(8);
    let mut out = Vec::with_capacity(44 + data as usize);
    out.extend_from_slice(b"RIFF");
    out.extend_from_slice(&(36 + data).to_le_bytes());
    out.extend_from_slice(b"WAVEfmt ");
    out.extend_from_slice(&16u32.to_le_bytes());
    out.extend_from_slice(&tag.to_le_bytes());
    out.extend_from_slice(&channels.to_le_bytes());
    out.extend_from_slice(&rate.to_le_bytes());
    out.extend_from_slice(&(rate * u32::from(align)).to_le_bytes());
    out.extend_from_slice(&align.to_le_bytes());
    out.extend_from_slice(&bits.to_le_bytes());
    out.extend_from_slice(b"data");
    out.extend_from_slice(&data.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wav(samples: &[i16], rate: u32) -> Vec<u8> {
        wav_bytes(samples, rate, 1)
    }

    #[test]
    fn a_plain_wav_is_read_without_ffmpeg_and_silence_has_no_voice() {
        let dir = std::env::temp_dir().join(format!("faceanim-audio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("quiet.wav");
        std::fs::write(&path, wav(&vec![0; 16_000], 16_000)).unwrap();
        let sound = Sound::read(&path).unwrap();
        assert_eq!(sound.samples.len(), 16_000);
        assert!((sound.seconds() - 1.0).abs() < 1e-6);
        assert!(sound.voice_activity().iter().all(|v| !v));
        // A tone in the middle second of silence is heard there only.
        let mut samples = vec![0i16; 48_000];
        for (k, s) in samples[16_000..32_000].iter_mut().enumerate() {
            *s = (8000.0 * (k as f32 * 0.1).sin()) as i16;
        }
        let voiced = Sound { samples }.voice_activity();
        assert!(voiced[10..90].iter().all(|v| !v));
        assert!(voiced[110..190].iter().all(|v| *v));
        std::fs::write(dir.join("empty.wav"), []).unwrap();
        let error = Sound::read(&dir.join("empty.wav")).unwrap_err().to_string();
        assert!(error.contains("empty.wav: there is no sound"), "{error}");
        let missing = Sound::read(&dir.join("none.wav")).unwrap_err().to_string();
        assert!(missing.contains("none.wav"), "{missing}");
        std::fs::write(dir.join("cut.wav"), &wav(&[1, 2, 3], 16_000)[..20]).unwrap();
        let cut = Sound::read(&dir.join("cut.wav")).unwrap_err().to_string();
        assert!(cut.contains("cut.wav"), "{cut}");
        // A recording cut short (its header names more sound than is there) is read as far as
        // it goes, as is a stream's whose header names none or the placeholder size.
        let whole = wav(&vec![100; 16_000], 16_000);
        std::fs::write(dir.join("half.wav"), &whole[..44 + 16_000]).unwrap();
        assert_eq!(
            Sound::read(&dir.join("half.wav")).unwrap().samples.len(),
            8_000
        );
        let mut streamed = whole.clone();
        streamed[40..44].copy_from_slice(&u32::MAX.to_le_bytes());
        std::fs::write(dir.join("streamed.wav"), &streamed).unwrap();
        assert_eq!(
            Sound::read(&dir.join("streamed.wav"))
                .unwrap()
                .samples
                .len(),
            16_000
        );
        // Less than one 10 ms frame of it holds nothing to hear.
        std::fs::write(dir.join("crumb.wav"), &whole[..44 + 200]).unwrap();
        let crumb = Sound::read(&dir.join("crumb.wav")).unwrap_err().to_string();
        assert!(crumb.contains("crumb.wav: there is no sound"), "{crumb}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A second of silence, a second of a 200 Hz tone peaking at `peak` (of 32,768), a second
    /// of silence, all raised by `offset`.
    fn line(peak: f32, offset: i16) -> Sound {
        let samples = (0..48_000)
            .map(|k| {
                let tone = match (16_000..32_000).contains(&k) {
                    true => peak * (std::f32::consts::TAU * 200.0 * k as f32 / 16_000.0).sin(),
                    false => 0.0,
                };
                (tone as i16).saturating_add(offset)
            })
            .collect();
        Sound { samples }
    }

    #[test]
    fn a_quiet_recording_is_heard_and_an_offset_is_removed() {
        let heard = |sound: &Sound| {
            let voiced = sound.voice_activity();
            (
                voiced[110..190].iter().all(|v| *v),
                voiced[..90].iter().chain(&voiced[210..]).all(|v| !v),
            )
        };
        // A voice 50 dB under full scale (a distant microphone) is heard where it is; one
        // under −70 dBFS is none.
        assert_eq!(heard(&line(100.0, 0)), (true, true));
        assert!(!heard(&line(8.0, 0)).0);
        // An offset of a tenth of full scale hides the voice until it is removed — with no
        // click where the sound starts, and the tone kept.
        let offset = line(8000.0, 3277);
        assert!(!heard(&offset).0);
        let removed = offset.clone().without_offset();
        assert_eq!(heard(&removed), (true, true));
        assert!(removed.samples[..16_000].iter().all(|s| s.abs() <= 1));
        let kept =
            rms(&removed.samples[16_500..31_500]) / rms(&line(8000.0, 0).samples[16_500..31_500]);
        assert!((kept - 1.0).abs() < 0.02, "{kept}");
        // A sound without an offset is kept as it is.
        let clean = line(8000.0, 40);
        assert_eq!(clean.clone().without_offset().samples, clean.samples);
    }

    /// 10 ms frames of a 200 Hz tone, each at the level (dBFS) given (−100: digital silence).
    fn frames_at(levels: &[f32]) -> Sound {
        let samples = levels
            .iter()
            .flat_map(|&db| {
                // A sine's RMS is its peak over √2.
                let peak = 32768.0 * 10f32.powf(db / 20.0) * std::f32::consts::SQRT_2;
                (0..FRAME_SAMPLES).map(move |k| {
                    let phase = std::f32::consts::TAU * 200.0 * k as f32 / 16_000.0;
                    (peak * phase.sin()).round() as i16
                })
            })
            .collect();
        Sound { samples }
    }

    #[test]
    fn a_line_trimmed_to_its_words_is_heard_through_its_quiet_vowels() {
        // No pause: loud vowels, quieter ones, consonants and four stop closures, interleaved.
        let mut levels = Vec::new();
        for k in 0..100 {
            levels.push(match k % 25 {
                0 => -100.0,
                1..=3 => -30.0,
                4..=9 => -23.0,
                _ => -11.0,
            });
        }
        let voiced = frames_at(&levels).voice_activity();
        for (k, (level, voiced)) in levels.iter().zip(&voiced).enumerate() {
            assert_eq!(*voiced, *level > -50.0, "frame {k} at {level} dB");
        }
        // With a steady room noise in its pauses (2 dB apart), a line's floor is the noise:
        // a sound 6 dB over it is not a voice.
        let mut noisy = vec![-11.0f32; 60];
        noisy.extend((0..30).map(|k| -52.0 + (k % 3) as f32));
        noisy.extend([-44.0; 10]);
        let voiced = frames_at(&noisy).voice_activity();
        assert!(voiced[..60].iter().all(|v| *v));
        assert!(voiced[60..].iter().all(|v| !v));
    }

    /// A WAV of `frames` at `rate` Hz in `encoding`, each frame's channels given.
    fn encoded(frames: &[Vec<f32>], rate: u32, tag: u16, bits: u16) -> Vec<u8> {
        let channels = frames.first().map_or(1, Vec::len) as u16;
        let mut data = Vec::new();
        for frame in frames {
            for &v in frame {
                match (tag, bits) {
                    (3, 32) => data.extend_from_slice(&v.to_le_bytes()),
                    (1, 8) => data.push((v * 127.0 + 128.0).round() as u8),
                    (1, 32) => {
                        data.extend_from_slice(&((v * 2_147_483_647.0) as i32).to_le_bytes())
                    }
                    (1, 24) => {
                        data.extend_from_slice(&((v * 8_388_607.0) as i32).to_le_bytes()[..3])
                    }
                    _ => data.extend_from_slice(&((v * 32767.0) as i16).to_le_bytes()),
                }
            }
        }
        let mut out = wav_header(tag, channels, rate, bits, data.len());
        out.extend_from_slice(&data);
        out
    }

    fn tone(hz: f32, rate: u32, seconds: f32, amplitude: f32) -> Vec<f32> {
        (0..(rate as f32 * seconds) as usize)
            .map(|k| amplitude * (std::f32::consts::TAU * hz * k as f32 / rate as f32).sin())
            .collect()
    }

    /// `path` read as it is without ffmpeg.
    fn here(path: &Path) -> Sound {
        match read_wav(path) {
            Ok(Wav::Plain(sound)) => sound,
            _ => panic!("{} is not read here", path.display()),
        }
    }

    fn rms(samples: &[i16]) -> f64 {
        let middle = &samples[samples.len() / 10..samples.len() * 9 / 10];
        (middle.iter().map(|&s| f64::from(s).powi(2)).sum::<f64>() / middle.len() as f64).sqrt()
    }

    /// The kernel's weights tabulated once per phase give the samples that reading it at every
    /// output sample gives (to the last bit but for a rounding), at each rate recorders write.
    #[test]
    fn a_tabulated_kernel_resamples_as_the_kernel_read_at_each_sample() {
        for rate in [8_000, 11_025, 22_050, 44_100, 48_000, 96_000] {
            let glide: Vec<f32> = (0..rate / 2)
                .map(|k| {
                    let t = k as f32 / rate as f32;
                    0.5 * (std::f32::consts::TAU * (200.0 + 6000.0 * t) * t).sin()
                })
                .collect();
            let tabulated = resample(&glide, rate);
            let read = resample_tabulating(&glide, rate, 0);
            assert_eq!(tabulated.len(), read.len());
            let most = tabulated
                .iter()
                .zip(&read)
                .map(|(a, b)| (i32::from(*a) - i32::from(*b)).abs())
                .max();
            assert!(most <= Some(1), "{rate} Hz: {most:?}");
        }
    }

    /// Every PCM or float WAV is read here (no ffmpeg process is started for it).
    #[test]
    fn wavs_of_any_rate_channels_and_sample_size_are_read_at_16_khz_without_aliasing() {
        let dir = tempfile::tempdir().unwrap();
        // A 1 kHz tone, the same in both channels, at the rates recorders write: its pitch,
        // loudness and length are kept in every encoding.
        for (rate, tag, bits) in [
            (44_100, 1, 16),
            (48_000, 3, 32),
            (22_050, 1, 24),
            (16_000, 1, 24),
            (11_025, 1, 16),
            (8_000, 1, 8),
            (96_000, 1, 32),
        ] {
            let left = tone(1000.0, rate, 1.0, 0.5);
            let frames: Vec<Vec<f32>> = left.iter().map(|&v| vec![v, v]).collect();
            let path = dir.path().join(format!("tone-{rate}-{bits}.wav"));
            std::fs::write(&path, encoded(&frames, rate, tag, bits)).unwrap();
            let sound = here(&path);
            let what = format!("{rate} Hz, {bits} bits");
            assert!(
                (sound.seconds() - 1.0).abs() < 0.01,
                "{what}: {}",
                sound.seconds()
            );
            let expected = 0.5 * 32768.0 / std::f64::consts::SQRT_2;
            assert!(
                (rms(&sound.samples) / expected - 1.0).abs() < 0.03,
                "{what}: {}",
                rms(&sound.samples)
            );
            let crossings = sound.samples[1600..14_400]
                .windows(2)
                .filter(|w| (w[0] < 0) != (w[1] < 0))
                .count();
            // 0.8 s of a 1 kHz tone crosses zero 1,600 times.
            assert!(
                crossings.abs_diff(1600) <= 4,
                "{what}: {crossings} zero crossings"
            );
        }
        // Above 8 kHz nothing is heard: a 10 kHz tone at 44.1 kHz does not fold back to 6 kHz.
        let path = dir.path().join("high.wav");
        let high: Vec<Vec<f32>> = tone(10_000.0, 44_100, 1.0, 0.5)
            .into_iter()
            .map(|v| vec![v])
            .collect();
        std::fs::write(&path, encoded(&high, 44_100, 1, 16)).unwrap();
        let folded = rms(&here(&path).samples);
        assert!(
            folded < 0.5 * 32768.0 * 0.003,
            "a 10 kHz tone reads {folded}"
        );
    }

    #[test]
    fn a_resampled_wav_matches_ffmpegs_conversion() {
        // A gliding tone with noise over it, 22,050 Hz (eSpeak NG's rate), against ffmpeg's
        // own resampler (skipped where ffmpeg is missing: it is the other route's program).
        if Command::new("ffmpeg").arg("-version").output().is_err() {
            eprintln!("ffmpeg is missing: skipped");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let mut seed = 1u32;
        let frames: Vec<Vec<f32>> = (0..44_100)
            .map(|k| {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let noise = (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
                let t = k as f32 / 22_050.0;
                vec![0.4 * (std::f32::consts::TAU * (200.0 + 1500.0 * t) * t).sin() + 0.1 * noise]
            })
            .collect();
        let path = dir.path().join("glide.wav");
        std::fs::write(&path, encoded(&frames, 22_050, 1, 16)).unwrap();
        let ours = here(&path).samples;
        let theirs = convert(&path).unwrap().samples;
        assert!(
            ours.len().abs_diff(theirs.len()) <= 2,
            "{} {}",
            ours.len(),
            theirs.len()
        );
        // Compared away from the ends, where each pads in its own way.
        let n = ours.len().min(theirs.len());
        let (a, b) = (&ours[800..n - 800], &theirs[800..n - 800]);
        let dot = |x: &[i16], y: &[i16]| {
            x.iter()
                .zip(y)
                .map(|(p, q)| f64::from(*p) * f64::from(*q))
                .sum::<f64>()
        };
        let r = dot(a, b) / (dot(a, a) * dot(b, b)).sqrt();
        assert!(r > 0.995, "correlation with ffmpeg's {r}");
    }
}
