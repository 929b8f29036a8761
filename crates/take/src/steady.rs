//! Frames recorded as they arrived, put on a steady rate by their times.
//!
//! A phone over Wi-Fi loses datagrams and delivers others in bursts; a webcam in the studio is
//! tracked as fast as the machine allows, which changes with the load. Frames kept one after
//! another at one rate would replay the performance warped: a lost half second pulls everything
//! after it early, and a stretch tracked slowly plays fast. So a recording becomes a steady
//! take: frame `k` at `k / fps` seconds from the first arrival, each the blend of the two
//! arrivals around its time ([`Steady::blend`]) or the nearer of them ([`Steady::nearest`], for
//! what cannot be blended, such as a camera frame's landmarks). Across a gap longer than
//! [`MAX_BLEND_SECONDS`] the frame before it is held, as the character held it live.
//!
//! ```
//! use faceanim_take::steady::Steady;
//!
//! // Twelve frames sent at 60 fps; the fifth and sixth were lost on the way.
//! let sent: Vec<usize> = (0..12).filter(|k| !(4..6).contains(k)).collect();
//! let times: Vec<f64> = sent.iter().map(|&k| k as f64 / 60.0).collect();
//! let steady = Steady::of(&times);
//! assert_eq!((steady.fps, steady.len()), (60.0, 12));
//! // Each frame sent is where it was, and the lost ones are blended from their neighbours.
//! let rows: Vec<[f32; 1]> = sent.iter().map(|&k| [k as f32 / 10.0]).collect();
//! let steady_rows = steady.blend(&rows);
//! assert!((steady_rows[4][0] - 0.4).abs() < 1e-6);
//! assert!((steady_rows[9][0] - 0.9).abs() < 1e-6);
//! ```

/// The longest gap between arrivals blended across, seconds; across a longer one (the sender
/// stopped, the network dropped out) the frame before the gap is held until the next arrives.
pub const MAX_BLEND_SECONDS: f64 = 0.25;

/// The highest rate a recording is put on, frames per second.
pub const MAX_RECORDED_FPS: f32 = 120.0;

/// The rate of frames recorded as they arrived, first at `first` and last at `last` seconds:
/// frames per second over the recording, rounded, 1 to [`MAX_RECORDED_FPS`] (30 for a single
/// frame).
fn recorded_fps(first: f64, last: f64, frames: usize) -> f32 {
    let duration = last - first;
    if frames > 1 && duration > 0.0 {
        (((frames - 1) as f64 / duration).round() as f32).clamp(1.0, MAX_RECORDED_FPS)
    } else {
        30.0
    }
}

/// Where one frame of a steady take falls among the arrivals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    /// The last arrival at or before the frame's time.
    pub before: usize,
    /// The first arrival after it (`before` at the end).
    pub after: usize,
    /// How far the frame's time is from `before` toward `after`, 0 to 1 (0 across a gap longer
    /// than [`MAX_BLEND_SECONDS`]).
    pub toward_after: f32,
}

impl Slot {
    /// The arrival nearer the frame's time.
    #[must_use]
    pub fn nearest(self) -> usize {
        if self.toward_after < 0.5 {
            self.before
        } else {
            self.after
        }
    }
}

/// A recording's steady rate and, for each of its frames, where it falls among the arrivals.
#[derive(Debug, Clone, PartialEq)]
pub struct Steady {
    /// Frames per second.
    pub fps: f32,
    /// One per frame of the steady take, frame `k` at `k / fps` seconds from the first arrival.
    pub slots: Vec<Slot>,
}

impl Steady {
    /// The steady frames of arrivals at `times` (seconds on any clock, in the order they
    /// arrived; a time earlier than the one before it, or not a number, counts as the one
    /// before). The rate is the one the frames were sent at, counting those lost on the way
    /// (from the typical interval between arrivals), where at most a fifth of them went
    /// missing; otherwise (arrivals in bursts, whose typical interval is none of the sender's)
    /// the count of frames that arrived over the time they kept arriving (gaps longer than
    /// [`MAX_BLEND_SECONDS`] left out); rounded either way.
    #[must_use]
    pub fn of(times: &[f64]) -> Steady {
        let mut latest = times.iter().copied().find(|t| t.is_finite()).unwrap_or(0.0);
        let rising: Vec<f64> = times
            .iter()
            .map(|&t| {
                if t.is_finite() {
                    latest = latest.max(t);
                }
                latest
            })
            .collect();
        let (Some(&first), Some(&last)) = (rising.first(), rising.last()) else {
            return Steady {
                fps: 30.0,
                slots: Vec::new(),
            };
        };
        let counted =
            arriving_fps(&rising).unwrap_or_else(|| recorded_fps(first, last, rising.len()));
        let fps = sent_fps(&rising)
            .filter(|&sent| sent >= counted && sent <= counted * 1.25)
            .unwrap_or(counted);
        let step = 1.0 / f64::from(fps);
        let frames = ((last - first) / step).round() as usize + 1;
        let mut slots = Vec::with_capacity(frames);
        let mut before = 0;
        for k in 0..frames {
            let time = (first + k as f64 * step).min(last);
            while before + 1 < rising.len() && rising[before + 1] <= time {
                before += 1;
            }
            let after = (before + 1).min(rising.len() - 1);
            let gap = rising[after] - rising[before];
            let toward_after = if gap > 0.0 && gap <= MAX_BLEND_SECONDS {
                ((time - rising[before]) / gap).clamp(0.0, 1.0) as f32
            } else {
                0.0
            };
            slots.push(Slot {
                before,
                after,
                toward_after,
            });
        }
        Steady { fps, slots }
    }

    /// How many frames the steady take has.
    #[must_use]
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether it has none (nothing arrived).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The steady frames of `rows` (one per arrival, of equal length): each the blend of the
    /// two arrivals around its time.
    #[must_use]
    pub fn blend<R: AsRef<[f32]>>(&self, rows: &[R]) -> Vec<Vec<f32>> {
        self.slots
            .iter()
            .map(|slot| {
                let a = rows[slot.before].as_ref();
                let b = rows[slot.after].as_ref();
                let t = slot.toward_after;
                a.iter().zip(b).map(|(a, b)| a + (b - a) * t).collect()
            })
            .collect()
    }

    /// For each steady frame, the arrival nearer its time (for what cannot be blended).
    #[must_use]
    pub fn nearest(&self) -> Vec<usize> {
        self.slots.iter().map(|slot| slot.nearest()).collect()
    }
}

/// The rate frames arrived at `times` (rising) while they kept arriving: their intervals up to
/// [`MAX_BLEND_SECONDS`] counted over their length, rounded, 1 to [`MAX_RECORDED_FPS`].
fn arriving_fps(times: &[f64]) -> Option<f32> {
    let (count, span) = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d <= MAX_BLEND_SECONDS)
        .fold((0usize, 0.0f64), |(n, s), d| (n + 1, s + d));
    (span > 0.0).then(|| ((count as f64 / span).round() as f32).clamp(1.0, MAX_RECORDED_FPS))
}

/// The rate the frames arriving at `times` (rising) were sent at: the typical interval between
/// arrivals (their median) is one frame, an interval of about `n` of them lost `n - 1` on the
/// way, and the frames so counted over the time they kept arriving (gaps longer than
/// [`MAX_BLEND_SECONDS`] left out), rounded, 1 to [`MAX_RECORDED_FPS`].
fn sent_fps(times: &[f64]) -> Option<f32> {
    let mut intervals: Vec<f64> = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0.0 && d <= MAX_BLEND_SECONDS)
        .collect();
    if intervals.len() < 2 {
        return None;
    }
    let middle = intervals.len() / 2;
    let (_, &mut typical, _) = intervals.select_nth_unstable_by(middle, f64::total_cmp);
    let frames: f64 = intervals
        .iter()
        .map(|d| (d / typical).round().max(1.0))
        .sum();
    let span: f64 = intervals.iter().sum();
    let fps = (frames / span).round() as f32;
    (1.0..=MAX_RECORDED_FPS).contains(&fps).then_some(fps)
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "whole rates and times copied exactly")]
mod tests {
    use super::*;

    /// Arrivals at 60 fps, `lost` of them not arriving, each late by a jitter of up to `jitter`
    /// seconds (a fixed pattern).
    fn arrivals(frames: usize, lost: &[std::ops::Range<usize>], jitter: f64) -> Vec<(usize, f64)> {
        (0..frames)
            .filter(|k| !lost.iter().any(|r| r.contains(k)))
            .map(|k| {
                let late = jitter * ((k * 7919) % 13) as f64 / 12.0;
                (k, 5.0 + k as f64 / 60.0 + late)
            })
            .collect()
    }

    #[test]
    fn lost_frames_keep_the_rate_and_the_time_of_what_follows() {
        // A tenth of the frames lost, a whole half second among them, and jitter of 4 ms.
        let lost = [100..130, 300..310, 400..420, 600..640];
        let got = arrivals(1000, &lost, 0.004);
        let times: Vec<f64> = got.iter().map(|&(_, t)| t).collect();
        let steady = Steady::of(&times);
        assert_eq!(steady.fps, 60.0);
        assert!((998..=1001).contains(&steady.len()), "{}", steady.len());
        // Each arrived frame is where it was sent: frame k of the steady take is sent frame k
        // (a blend of it and a neighbour, by the jitter).
        let sent: Vec<Vec<f32>> = got.iter().map(|&(k, _)| vec![k as f32]).collect();
        let rows = steady.blend(&sent);
        let after_a_loss = |k: usize| lost.iter().any(|r| r.start <= k && k <= r.end);
        for (k, row) in rows.iter().enumerate().filter(|&(k, _)| !after_a_loss(k)) {
            assert!(
                (row[0] - k as f32).abs() <= 1.0,
                "frame {k} is sent frame {}",
                row[0]
            );
        }
        // Across the half second lost, the frame before it is held.
        assert!(rows[100..130].iter().all(|row| row[0] == 99.0));
        // Across the sixth of a second lost, the frames either side are blended.
        assert!((rows[305][0] - 305.0).abs() < 1.0, "{:?}", rows[305]);
        // Counted by arrivals alone, the rate would be 54: the lost frames would pull the
        // rest early.
        assert_eq!(
            recorded_fps(times[0], *times.last().unwrap(), times.len()),
            54.0
        );
    }

    #[test]
    fn a_long_gap_holds_the_frame_before_it_and_bursts_keep_their_rate() {
        // Two seconds without frames: the last one before is held, then the next one shows.
        let times = [0.0, 0.1, 0.2, 2.2, 2.3];
        let steady = Steady::of(&times);
        assert_eq!(steady.fps, 10.0);
        assert_eq!(steady.len(), 24);
        let rows = steady.blend(&[[0.0], [1.0], [2.0], [3.0], [4.0]]);
        assert_eq!(rows[2], vec![2.0]);
        assert_eq!(rows[21], vec![2.0]);
        assert_eq!(rows[22], vec![3.0]);
        assert_eq!(steady.nearest()[12], 2);
        // Arrivals in pairs (a network that bunches): the rate is the count's, not the pairs'.
        let bunched: Vec<f64> = (0..100)
            .map(|k| f64::from(k / 2) * (2.0 / 30.0) + f64::from(k % 2) * 0.001)
            .collect();
        let steady = Steady::of(&bunched);
        assert_eq!(steady.fps, 30.0);
        // A clock that steps back, and no time at all, do not panic.
        assert_eq!(Steady::of(&[1.0, 0.5, 1.5]).slots.len(), 3);
        assert!(Steady::of(&[]).is_empty());
        assert_eq!(Steady::of(&[f64::NAN, 2.0]).len(), 1);
    }
}
