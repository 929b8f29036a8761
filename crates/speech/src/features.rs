//! Speech features: 25 ms windows every 10 ms, pre-emphasised, through 26 mel bands to 12
//! cepstra — streaming, with the speaker's running mean removed and their change added (what
//! the live classifier of [`crate::listen`] reads), or over a whole recording without
//! normalising (what an alignment by synthesis warps, [`crate::synthesis`]), heard through
//! an adult's vocal tract or a shorter or longer one ([`Frontend::heard_through`]).

use std::collections::VecDeque;
use std::sync::Arc;

use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};

use crate::audio::{FRAME_SAMPLES, voice_threshold};

/// Samples per analysis window (25 ms at 16 kHz).
pub const WINDOW: usize = 400;
/// Samples between frames (10 ms).
pub const HOP: usize = FRAME_SAMPLES;
const FFT_SIZE: usize = 512;
const MEL_BANDS: usize = 26;
/// Cepstra per frame.
pub const CEPSTRA: usize = 12;
/// Features per frame: 12 cepstra, their change over two frames, and the loudness above the
/// noise floor.
pub const DIMS: usize = 2 * CEPSTRA + 1;

/// One frame's features.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Features {
    /// The window's centre, seconds from the start of the stream.
    pub time: f32,
    /// Loudness, dB relative to full scale.
    pub level_db: f32,
    /// Whether a voice is heard (louder than the noise floor by a share of the range).
    pub voiced: bool,
    /// How open the voice's loudness says the mouth is, 0..1 (0 when not voiced).
    pub open: f32,
    /// The classifier's input.
    pub vector: [f32; DIMS],
}

/// Follows the room's noise floor and the voice's peaks, frame by frame, as
/// [`crate::audio::Sound::voice_activity`] does over a whole recording.
#[derive(Debug, Clone, Copy)]
struct Gate {
    floor: f32,
    peak: f32,
    started: bool,
}

impl Gate {
    /// The floor rises 1 dB a second when the room gets louder; peaks fade 3 dB a second.
    const RISE: f32 = 0.01;
    const FADE: f32 = 0.03;
    /// Nothing quieter is a voice, dBFS (a live microphone without gain control can be
    /// quieter than a recording, so lower than [`crate::audio::Sound::voice_activity`]'s −55).
    const QUIETEST: f32 = -65.0;
    /// The quietest peak a voice reaches at the microphone, dBFS.
    const FAINTEST: f32 = -45.0;

    /// (voiced, open) of a frame at `level` dB.
    fn observe(&mut self, level: f32) -> (bool, f32) {
        if !self.started {
            (self.floor, self.peak, self.started) = (level, level, true);
        }
        self.floor = if level < self.floor {
            level
        } else {
            self.floor + Self::RISE
        };
        self.peak = if level > self.peak {
            level
        } else {
            (self.peak - Self::FADE).max(self.floor)
        };
        let Some(threshold) =
            voice_threshold(self.floor, self.peak, Self::QUIETEST, Self::FAINTEST)
        else {
            return (false, 0.0);
        };
        if level <= threshold {
            return (false, 0.0);
        }
        let above = ((level - threshold) / (self.peak - threshold).max(6.0)).clamp(0.0, 1.0);
        (true, 0.4 + 0.6 * above)
    }
}

/// Samples to features, streaming.
pub struct Frontend {
    fft: Arc<dyn Fft<f32>>,
    window: Vec<f32>,
    /// Per mel band: (first FFT bin, weights).
    bands: Vec<(usize, Vec<f32>)>,
    /// DCT-II rows for cepstra 1..=12.
    dct: Vec<[f32; MEL_BANDS]>,
    /// Pre-emphasised samples not yet consumed by a whole window, and the same samples as
    /// they came (for loudness).
    pending: VecDeque<f32>,
    raw: VecDeque<f32>,
    previous: f32,
    /// Frames produced so far.
    frames: u64,
    /// The speaker's cepstral mean, and how many voiced frames it has seen.
    mean: [f32; CEPSTRA],
    seen: f32,
    history: VecDeque<[f32; CEPSTRA]>,
    gate: Gate,
}

impl std::fmt::Debug for Frontend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Frontend")
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

fn mel(hz: f32) -> f32 {
    2595.0 * (1.0 + hz / 700.0).log10()
}

fn hz(mel: f32) -> f32 {
    700.0 * (10f32.powf(mel / 2595.0) - 1.0)
}

impl Frontend {
    /// A front end starting from the speaker's cepstral mean `mean` (a model's) or none.
    #[must_use]
    pub fn new(mean: Option<[f32; CEPSTRA]>) -> Frontend {
        Frontend::heard_through(mean, 1.0)
    }

    /// [`Frontend::new`], hearing the voice through a vocal tract `warp` times shorter than
    /// an adult man's: each mel band's frequencies are `warp` times the usual ones (up to a
    /// knee, then linear to the band's top), so a voice whose resonances lie `warp` times as
    /// high gives a man's cepstra. A warp outside 0.5–2 is taken as the nearest of them, one
    /// that is not a number as 1.
    #[must_use]
    pub fn heard_through(mean: Option<[f32; CEPSTRA]>, warp: f32) -> Frontend {
        let warp = if warp.is_nan() {
            1.0
        } else {
            warp.clamp(0.5, 2.0)
        };
        let fft = FftPlanner::new().plan_fft_forward(FFT_SIZE);
        let window = (0..WINDOW)
            .map(|n| {
                0.54 - 0.46 * (2.0 * std::f32::consts::PI * n as f32 / (WINDOW - 1) as f32).cos()
            })
            .collect();
        let rate = faceanim_sphinx_sys::SAMPLE_RATE as f32;
        let (low, high) = (mel(130.0), mel(6800.0));
        let top_hz = hz(high);
        let (top, knee) = {
            let top = (top_hz * warp).min(rate / 2.0 - 100.0);
            (top, (0.8 * top / warp).min(top_hz))
        };
        let warped = |f: f32| {
            if f <= knee {
                warp * f
            } else {
                warp * knee + (f - knee) * (top - warp * knee) / (top_hz - knee).max(1.0)
            }
        };
        let edge = |k: usize| warped(hz(low + (high - low) * k as f32 / (MEL_BANDS + 1) as f32));
        let bin_hz = rate / FFT_SIZE as f32;
        let bands = (0..MEL_BANDS)
            .map(|b| {
                let (left, centre, right) = (edge(b), edge(b + 1), edge(b + 2));
                let first = (left / bin_hz).ceil() as usize;
                let last = ((right / bin_hz).floor() as usize).min(FFT_SIZE / 2);
                let weights = (first..=last)
                    .map(|k| {
                        let f = k as f32 * bin_hz;
                        if f <= centre {
                            (f - left) / (centre - left)
                        } else {
                            (right - f) / (right - centre)
                        }
                        .max(0.0)
                    })
                    .collect();
                (first, weights)
            })
            .collect();
        let dct = (1..=CEPSTRA)
            .map(|c| {
                let mut row = [0.0f32; MEL_BANDS];
                for (m, r) in row.iter_mut().enumerate() {
                    *r = (std::f32::consts::PI * c as f32 * (m as f32 + 0.5) / MEL_BANDS as f32)
                        .cos();
                }
                row
            })
            .collect();
        Frontend {
            fft,
            window,
            bands,
            dct,
            pending: VecDeque::with_capacity(2 * WINDOW),
            raw: VecDeque::with_capacity(2 * WINDOW),
            previous: 0.0,
            frames: 0,
            mean: mean.unwrap_or([0.0; CEPSTRA]),
            seen: if mean.is_some() { 100.0 } else { 0.0 },
            history: VecDeque::with_capacity(3),
            gate: Gate {
                floor: -100.0,
                peak: -100.0,
                started: false,
            },
        }
    }

    /// The speaker's cepstral mean so far.
    #[must_use]
    pub fn mean(&self) -> [f32; CEPSTRA] {
        self.mean
    }

    /// The features of every whole window `samples` completes.
    pub fn push(&mut self, samples: &[i16]) -> Vec<Features> {
        let mut out = Vec::with_capacity(samples.len() / HOP + 1);
        self.feed(samples, |frontend| out.push(frontend.frame()));
        out
    }

    /// The cepstra and loudness (dB) of every whole window in `samples` (16 kHz), without the
    /// speaker's mean removed: a recording's features for an offline use (an alignment), which
    /// normalises them over the whole recording.
    #[must_use]
    pub fn cepstra(samples: &[i16]) -> Vec<([f32; CEPSTRA], f32)> {
        Frontend::cepstra_heard_through(samples, 1.0)
    }

    /// [`Frontend::cepstra`], heard through a vocal tract `warp` times shorter than a man's
    /// ([`Frontend::heard_through`]).
    #[must_use]
    pub fn cepstra_heard_through(samples: &[i16], warp: f32) -> Vec<([f32; CEPSTRA], f32)> {
        let mut out = Vec::with_capacity(samples.len() / HOP + 1);
        Frontend::heard_through(None, warp).feed(samples, |frontend| out.push(frontend.analyse()));
        out
    }

    /// Takes `samples` in, calling `window` each time a whole window is pending.
    fn feed(&mut self, samples: &[i16], mut window: impl FnMut(&mut Frontend)) {
        for &s in samples {
            let x = f32::from(s) / 32768.0;
            self.pending.push_back(x - 0.97 * self.previous);
            self.raw.push_back(x);
            self.previous = x;
            if self.pending.len() == WINDOW {
                window(self);
                self.pending.drain(..HOP);
                self.raw.drain(..HOP);
            }
        }
    }

    /// The pending window's cepstra and loudness (dB).
    fn analyse(&self) -> ([f32; CEPSTRA], f32) {
        let mut buffer: Vec<Complex32> = self
            .pending
            .iter()
            .zip(&self.window)
            .map(|(x, w)| Complex32::new(x * w, 0.0))
            .collect();
        let power_sum: f32 = self.raw.iter().map(|x| x * x).sum();
        buffer.resize(FFT_SIZE, Complex32::new(0.0, 0.0));
        self.fft.process(&mut buffer);
        let power = power_sum / WINDOW as f32;
        let level_db = if power <= 1e-10 {
            -100.0
        } else {
            10.0 * power.log10()
        };
        let mut log_mel = [0.0f32; MEL_BANDS];
        for (out, (first, weights)) in log_mel.iter_mut().zip(&self.bands) {
            let energy: f32 = weights
                .iter()
                .enumerate()
                .map(|(k, w)| w * buffer[first + k].norm_sqr())
                .sum();
            *out = (energy + 1e-10).ln();
        }
        let mut cepstra = [0.0f32; CEPSTRA];
        for (c, row) in cepstra.iter_mut().zip(&self.dct) {
            *c = row.iter().zip(&log_mel).map(|(a, b)| a * b).sum::<f32>() / MEL_BANDS as f32;
        }
        (cepstra, level_db)
    }

    fn frame(&mut self) -> Features {
        let time = (self.frames as f32 * HOP as f32 + WINDOW as f32 / 2.0)
            / faceanim_sphinx_sys::SAMPLE_RATE as f32;
        self.frames += 1;
        let (cepstra, level_db) = self.analyse();
        let (voiced, open) = self.gate.observe(level_db);
        if voiced {
            // The mean of the voice, not of the room: a running mean over about three seconds
            // of speech (a plain mean until then).
            self.seen += 1.0;
            let rate = 1.0 / self.seen.min(300.0);
            for (m, c) in self.mean.iter_mut().zip(&cepstra) {
                *m += (c - *m) * rate;
            }
        }
        let mut normalised = cepstra;
        for (n, m) in normalised.iter_mut().zip(&self.mean) {
            *n -= m;
        }
        let before = self.history.front().copied().unwrap_or(normalised);
        self.history.push_back(normalised);
        if self.history.len() > 2 {
            self.history.pop_front();
        }
        let mut vector = [0.0f32; DIMS];
        vector[..CEPSTRA].copy_from_slice(&normalised);
        for k in 0..CEPSTRA {
            vector[CEPSTRA + k] = normalised[k] - before[k];
        }
        vector[DIMS - 1] = ((level_db - self.gate.floor) / 10.0).clamp(0.0, 6.0);
        Features {
            time,
            level_db,
            voiced,
            open,
            vector,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two seconds of a voice at 120 Hz through resonators at `formants` (Hz, bandwidth 80
    /// Hz): an impulse train through two-pole resonators in cascade.
    fn vowel(formants: &[f32]) -> Vec<i16> {
        let rate = faceanim_sphinx_sys::SAMPLE_RATE as f32;
        let mut signal: Vec<f32> = (0..2 * faceanim_sphinx_sys::SAMPLE_RATE as usize)
            .map(|k| if k % 133 == 0 { 1.0 } else { 0.0 })
            .collect();
        for &f in formants {
            let radius = (-std::f32::consts::PI * 80.0 / rate).exp();
            let angle = std::f32::consts::TAU * f / rate;
            let (b1, b2) = (2.0 * radius * angle.cos(), -radius * radius);
            let (mut y1, mut y2) = (0.0, 0.0);
            for x in &mut signal {
                let y = *x + b1 * y1 + b2 * y2;
                (y2, y1) = (y1, y);
                *x = y;
            }
        }
        let peak = signal.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        signal.iter().map(|v| (v / peak * 12000.0) as i16).collect()
    }

    /// The mean cepstra of `samples` heard through `warp`.
    fn mean_cepstra(samples: &[i16], warp: f32) -> [f32; CEPSTRA] {
        let frames = Frontend::cepstra_heard_through(samples, warp);
        let mut mean = [0.0; CEPSTRA];
        for (c, _) in &frames {
            for k in 0..CEPSTRA {
                mean[k] += c[k] / frames.len() as f32;
            }
        }
        mean
    }

    fn distance(a: &[f32; CEPSTRA], b: &[f32; CEPSTRA]) -> f32 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f32>()
            .sqrt()
    }

    #[test]
    fn a_shorter_tracts_vowel_heard_through_it_sounds_like_the_mans() {
        let mans = [550.0, 1450.0, 2450.0, 3400.0];
        let childs = mans.map(|f| f * 1.4);
        let reference = mean_cepstra(&vowel(&mans), 1.0);
        let child = vowel(&childs);
        let as_it_is = distance(&mean_cepstra(&child, 1.0), &reference);
        let heard_through = distance(&mean_cepstra(&child, 1.4), &reference);
        assert!(
            heard_through < 0.5 * as_it_is,
            "heard through a child's tract {heard_through}, as it is {as_it_is}"
        );
        // A warp that is no warp is taken as one that is.
        for warp in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let heard = Frontend::cepstra_heard_through(&child, warp);
            assert_eq!(heard.len(), Frontend::cepstra(&child).len());
            assert!(
                heard
                    .iter()
                    .all(|(c, db)| c.iter().all(|v| v.is_finite()) && db.is_finite()),
                "{warp}"
            );
        }
    }
}
