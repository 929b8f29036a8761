//! Which clock a recording of received frames goes by.

/// The times frames are put on by: the sender's own (`sent`, one per frame), when it gave
/// one for at least nine frames in ten and they are sound — never going back, hardly ever
/// standing still (at most one step in a hundred), and spanning the time the arrivals span to
/// within 2 % and a tenth of a second — otherwise the arrival times (`arrived`). A frame the
/// sender gave no time for (Live Link Face's "face lost" packet has none) gets its arrival
/// moved onto the sender's clock, kept between its neighbours. A phone's camera clock is free
/// of the network's delays and bursts; a sender whose clock is something else (a timecode
/// counted in milliseconds, a constant) is caught by the checks.
#[must_use]
pub(crate) fn clock(arrived: &[f64], sent: &[Option<f64>]) -> Vec<f64> {
    match on_senders_clock(arrived, sent) {
        Some(times) if sound(&times, arrived) => times,
        _ => arrived.to_vec(),
    }
}

/// Every frame's time on the sender's clock: its own, or its arrival moved by the median
/// offset between the two clocks and kept between its neighbours; `None` when more than one
/// frame in ten had none, or the lengths differ.
fn on_senders_clock(arrived: &[f64], sent: &[Option<f64>]) -> Option<Vec<f64>> {
    let given: Vec<Option<f64>> = sent.iter().map(|s| s.filter(|t| t.is_finite())).collect();
    let mut offsets: Vec<f64> = given
        .iter()
        .zip(arrived)
        .filter_map(|(s, a)| s.map(|s| s - a))
        .collect();
    if sent.len() != arrived.len() || offsets.is_empty() || offsets.len() * 10 < sent.len() * 9 {
        return None;
    }
    let middle = offsets.len() / 2;
    let (_, &mut offset, _) = offsets.select_nth_unstable_by(middle, f64::total_cmp);
    // For each frame, the next time the sender gave after it.
    let mut later: Vec<Option<f64>> = vec![None; given.len()];
    for k in (1..given.len()).rev() {
        later[k - 1] = given[k].or(later[k]);
    }
    let mut times: Vec<f64> = Vec::with_capacity(given.len());
    for (k, (s, a)) in given.iter().zip(arrived).enumerate() {
        let time = s.unwrap_or_else(|| {
            let earliest = times.last().copied().unwrap_or(f64::NEG_INFINITY);
            let latest = later[k].unwrap_or(f64::INFINITY).max(earliest);
            (a + offset).clamp(earliest, latest)
        });
        times.push(time);
    }
    Some(times)
}

/// Whether the sender's `times` can be gone by (see [`clock`]).
fn sound(times: &[f64], arrived: &[f64]) -> bool {
    let steps = || times.windows(2).map(|w| w[1] - w[0]);
    let still = steps().filter(|&d| d == 0.0).count();
    let span = |t: &[f64]| t.last().zip(t.first()).map_or(0.0, |(l, f)| l - f);
    let (theirs, ours) = (span(times), span(arrived));
    steps().all(|d| d >= 0.0)
        && still * 100 <= times.len()
        && (theirs - ours).abs() <= 0.02 * ours + 0.1
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "times copied exactly")]
mod tests {
    use super::*;

    #[test]
    fn the_senders_clock_where_it_is_sound() {
        // Arrivals bunched by the network; the sender's steady 60 fps.
        let arrived: Vec<f64> = (0..120).map(|k| f64::from(k / 3) * 0.05 + 0.3).collect();
        let sent: Vec<Option<f64>> = (0..120)
            .map(|k| Some(100.0 + f64::from(k) / 60.0))
            .collect();
        assert_eq!(clock(&arrived, &sent)[7], 100.0 + 7.0 / 60.0);
        // A sender's clock that goes back (a millisecond counter read as frames), stands still,
        // runs at another speed or is missing for a frame: the arrivals.
        let back: Vec<Option<f64>> = (0..120).map(|k| Some(f64::from(k % 60) * 0.016)).collect();
        let still: Vec<Option<f64>> = (0..120).map(|k| Some(f64::from(k / 2) / 30.0)).collect();
        let fast: Vec<Option<f64>> = (0..120).map(|k| Some(f64::from(k) / 30.0)).collect();
        let mut missing = sent.clone();
        for k in (0..120).step_by(8) {
            missing[k] = None;
        }
        for times in [back, still, fast, missing] {
            assert_eq!(clock(&arrived, &times), arrived);
        }
        // A few frames without a time (a face lost for a moment): moved onto the sender's
        // clock by the offset between the clocks, between their neighbours.
        let mut lost = sent.clone();
        lost[40] = None;
        lost[41] = None;
        let times = clock(&arrived, &lost);
        assert_eq!(times[39], sent[39].unwrap());
        assert!(times[39] <= times[40] && times[40] <= times[41] && times[41] <= times[42]);
        assert!(
            (times[41] - sent[41].unwrap()).abs() < 0.05,
            "{}",
            times[41]
        );
    }
}
