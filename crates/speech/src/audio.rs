//! Speech as the recogniser wants it: 16 kHz, mono, 16-bit.
//!
//! A WAV file at 16 kHz in 16-bit PCM (what recorders and TTS voices often write) is read
//! here; anything else — other rates, channels and sample formats, MP3, Ogg, FLAC, or the
//! sound of a video — is converted by the `ffmpeg` program. Errors name the file and what is
//! wrong with it: not audio, no sound in it, longer than [`MAX_SECONDS`].

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
        "{0}: reading this kind of audio needs the ffmpeg program (apt-get install ffmpeg), or give a 16 kHz 16-bit WAV"
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
                convert(path)?
            }
            Wav::Elsewhere => convert(path)?,
        };
        sound.checked(path)
    }

    fn checked(self, path: &Path) -> Result<Sound, AudioError> {
        if self.samples.is_empty() {
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
    /// floor by a share of its range (and than −55 dBFS). A recording without a clear
    /// difference between its quiet and loud parts (silence, steady noise, hum) has none.
    #[must_use]
    pub fn voice_activity(&self) -> Vec<bool> {
        let levels = self.frame_levels();
        if levels.is_empty() {
            return Vec::new();
        }
        let mut sorted = levels.clone();
        sorted.sort_by(f32::total_cmp);
        let floor = sorted[sorted.len() / 10];
        let peak = sorted[(sorted.len() * 98 / 100).min(sorted.len() - 1)];
        match voice_threshold(floor, peak, -55.0) {
            Some(threshold) => levels.iter().map(|&l| l > threshold).collect(),
            None => vec![false; levels.len()],
        }
    }
}

/// The level (dBFS) above which a voice is heard, between a quiet `floor` and a loud `peak`:
/// a share of their range above the floor, and never under `quietest`. `None` when quiet and
/// loud differ too little (silence, steady noise, hum) or nothing is loud. The rule of both
/// [`Sound::voice_activity`] and the live listener's gate.
pub(crate) fn voice_threshold(floor: f32, peak: f32, quietest: f32) -> Option<f32> {
    let range = peak - floor;
    if range < 12.0 || peak < -45.0 {
        return None;
    }
    Some((floor + (0.3 * range).max(8.0)).max(quietest))
}

/// What a file's WAV header says.
enum Wav {
    /// A canonical 16 kHz mono 16-bit PCM WAV, read here.
    Plain(Sound),
    /// A WAV of another format (ffmpeg converts it), checked first.
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

/// Reads `path`'s WAV header: a canonical 16 kHz mono 16-bit PCM WAV is read whole here; an
/// error for a WAV that is cut short or lacks its format.
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
            format = Some((u16_at(0), u16_at(2), rate, u16_at(14)));
        } else if id == b"data" {
            // Streams written live often leave the size 0 or too large: read what is there.
            let end = if size == 0 {
                bytes.len()
            } else {
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
        (Some((_, channels, rate, bits)), data) => Ok(Wav::Other(WavHeader {
            channels,
            rate,
            bits,
            data_bytes: data.map_or(0, <[u8]>::len),
        })),
        (None, _) => Err("a WAV file without its format chunk".into()),
    }
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
    let data = (samples.len() * 2) as u32;
    let mut out = Vec::with_capacity(44 + samples.len() * 2);
    out.extend_from_slice(b"RIFF");
    out.extend_from_slice(&(36 + data).to_le_bytes());
    out.extend_from_slice(b"WAVEfmt ");
    out.extend_from_slice(&16u32.to_le_bytes());
    out.extend_from_slice(&1u16.to_le_bytes());
    out.extend_from_slice(&channels.to_le_bytes());
    out.extend_from_slice(&rate.to_le_bytes());
    out.extend_from_slice(&(rate * 2 * u32::from(channels)).to_le_bytes());
    out.extend_from_slice(&(2 * channels).to_le_bytes());
    out.extend_from_slice(&16u16.to_le_bytes());
    out.extend_from_slice(b"data");
    out.extend_from_slice(&data.to_le_bytes());
    for s in samples {
        out.extend_from_slice(&s.to_le_bytes());
    }
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
        let _ = std::fs::remove_dir_all(&dir);
    }
}
