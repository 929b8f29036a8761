//! The acoustic model adapted to the voice it hears, from the line itself: a first pass's
//! phones say which phone each frame of speech is; the mean of every Gaussian of that phone's
//! codebook is then moved, by one affine map per feature stream (maximum likelihood linear
//! regression, unsupervised: no transcript), toward the frames it explained; a second pass
//! decodes with the moved means.
//!
//! The recogniser's models were trained on people. A formant synthesiser's buzz, a whisper,
//! a voice in another language are heard far from every mean, and its phones are mostly
//! wrong; the same map for every Gaussian keeps the phones apart while it moves them all
//! toward the voice. Chosen on eSpeak NG's en-us, m1, m3, m7, f2, whisperf, klatt and m2,
//! flite's slt, rms and awb, and eSpeak NG in Spanish, German, French and Japanese, from the
//! audio alone (`scripts/bench-lipsync.py`): the eight eSpeak NG voices 0.687 → 0.718 mean
//! agreement and P/B/M closed 0.66 → 0.69, the four languages 0.74 → 0.79 (German 0.67 →
//! 0.77, French 0.64 → 0.75). A voice heard as well as a person's is left as it is
//! ([`ADAPT_BELOW`]): flite's voices and five LibriVox readings are decoded as before.
use std::sync::OnceLock;

use faceanim_sphinx_sys::{Codebooks, Decoded, FRAME_RATE, Recogniser, Transform};

use crate::audio::Sound;
use crate::phones::Phone;

/// The least frames of speech (10 ms) a transform is estimated from: under a second, the
/// first pass's phones say too little about the voice.
const FEWEST_FRAMES: usize = 80;

/// How far the map is held toward the identity: a prior worth this many frames' statistics
/// (scaled as [`estimate`] scales them). Chosen on the voices above: 0 (no prior) and 200
/// both lost agreement or P/B/M closures on some voices against 50.
const PRIOR: f64 = 50.0;

/// A Gaussian whose share of a frame is below this is left out of its statistics.
const SHARE: f64 = 1e-4;

/// The first pass's acoustic score per frame of speech ([`Decoded::score_per_frame`]) under
/// which the model is adapted. A voice heard as well as a person's is not: a phone loop's
/// phones, mostly wrong even on a person, guide the map astray where the model already
/// fits (five LibriVox readings, adapted: agreement with their transcripts' alignments 0.932
/// → 0.915; flite's slt 0.933 → 0.927 and more closures where no bilabial is said). Real
/// readings score −8.5 to −14.0, flite's voices −7 to −13; eSpeak NG's −11 (klatt) to −20.
const ADAPT_BELOW: f32 = -14.5;

/// What a first pass leaves the second: the model adapted to the voice, and the closures of
/// the lips the first pass's silences held ([`crate::holds`]).
#[derive(Debug, Clone)]
pub(crate) struct FirstPass {
    pub(crate) adaptation: Transform,
    pub(crate) closures: Vec<Phone>,
}

/// The first pass `decoded` of `samples` (the start of `sound`, or all of it, heard through a
/// vocal tract `warp` times the model's) by `recogniser`: `None` when the voice is heard
/// well enough ([`ADAPT_BELOW`]) or no adaptation could be estimated ([`for_voice`]).
pub(crate) fn first_pass(
    recogniser: &mut Recogniser,
    samples: &[i16],
    decoded: &Decoded,
    sound: &Sound,
    warp: f32,
) -> Option<FirstPass> {
    if !decoded.score_per_frame.is_some_and(|s| s < ADAPT_BELOW) {
        return None;
    }
    let raw = crate::phones::phones_of(decoded.segments.clone());
    let held = crate::holds::lips_held(sound, raw.clone(), warp);
    let adaptation = for_voice(recogniser, samples, &held)?;
    // The closures heard in silences; not the P, B, M the unadapted model decoded, which the
    // adapted one decodes better (with them too: the eight eSpeak NG voices closed 0.74 of
    // their bilabials, but 57 closures lay away from every bilabial, against 41).
    let closures = held
        .into_iter()
        .filter(|p| {
            let middle = (p.start + p.end) / 2.0;
            bilabial(p)
                && raw
                    .iter()
                    .any(|r| r.label == "SIL" && r.start <= middle && r.end > middle)
        })
        .collect();
    Some(FirstPass {
        adaptation,
        closures,
    })
}

fn bilabial(p: &Phone) -> bool {
    matches!(p.label.as_str(), "P" | "B" | "M")
}

/// How near (seconds) a closure of the second pass must lie to one of the first pass's to be
/// the same closure ([`keep_closures`]): the bench's ±40 ms.
const NEAR: f32 = 0.04;

/// `phones` (a second, adapted pass) with each of the first pass's `closures` of the lips
/// that the second has no closure near: spliced in over whatever the second pass heard there.
/// An adapted model hears a stop's closure and release as a stop (a D, a K) where the model
/// unadapted heard a silence the lips held ([`crate::holds`]), the lips' stops told from the
/// tongue's no better. Chosen on the voices above: adapted alone, the eight eSpeak NG voices
/// closed 0.56 of their P, B, M (0.66 before adapting); with these closures kept, 0.71 (0.69
/// once the voices heard well enough are left unadapted: most of klatt's lines).
pub(crate) fn keep_closures(mut phones: Vec<Phone>, closures: &[Phone]) -> Vec<Phone> {
    for closure in closures.iter().filter(|p| bilabial(p)) {
        if phones
            .iter()
            .any(|p| bilabial(p) && p.start < closure.end + NEAR && p.end > closure.start - NEAR)
        {
            continue;
        }
        let mut spliced = Vec::with_capacity(phones.len() + 2);
        for p in phones {
            if p.end <= closure.start || p.start >= closure.end {
                spliced.push(p);
                continue;
            }
            if p.start < closure.start {
                spliced.push(Phone {
                    end: closure.start,
                    ..p.clone()
                });
            }
            if p.end > closure.end {
                spliced.push(Phone {
                    start: closure.end,
                    ..p
                });
            }
        }
        spliced.push(closure.clone());
        spliced.sort_by(|a, b| a.start.total_cmp(&b.start));
        phones = spliced;
    }
    phones
}

/// The codebooks of the model decoded with, read once (a few megabytes); `None` when the
/// model is not one this adapts (then lines are decoded once, unadapted).
fn codebooks() -> Option<&'static Codebooks> {
    static CODEBOOKS: OnceLock<Option<Codebooks>> = OnceLock::new();
    CODEBOOKS
        .get_or_init(|| {
            let search = crate::phones::blind_search(crate::Recognition::PhoneLoop);
            match Codebooks::read(search.acoustic()) {
                Ok(c) => Some(c),
                Err(e) => {
                    tracing::warn!("the recogniser is not adapted to the voice: {e}");
                    None
                }
            }
        })
        .as_ref()
}

/// The transform that adapts the model to the voice of `samples`, whose first pass by
/// `recogniser` heard the phones `first` (their times the sound's): `None` when too little speech was decoded, the model is not
/// one this adapts, or the statistics leave the map undetermined.
pub(crate) fn for_voice(
    recogniser: &mut Recogniser,
    samples: &[i16],
    first: &[Phone],
) -> Option<Transform> {
    let codebooks = codebooks()?;
    let cepstra = match recogniser.cepstra(samples) {
        Ok(c) => c,
        Err(e) => {
            tracing::warn!("the recogniser is not adapted to the voice: {e}");
            return None;
        }
    };
    let mut labels: Vec<Option<usize>> = vec![None; cepstra.len()];
    for phone in first {
        if phone.label == "SIL" {
            continue;
        }
        let Some(codebook) = codebooks.codebook(&phone.label) else {
            continue;
        };
        let frames = labels.len();
        let frame = |t: f32| ((t * FRAME_RATE as f32).round().max(0.0) as usize).min(frames);
        for label in &mut labels[frame(phone.start)..frame(phone.end).max(frame(phone.start))] {
            *label = Some(codebook);
        }
    }
    if labels.iter().flatten().count() < FEWEST_FRAMES {
        return None;
    }
    estimate(codebooks, &features(&cepstra), &labels)
}

/// The decoder's features of `cepstra` (`1s_c_d_dd`): each cepstrum less the line's mean
/// (batch normalisation), its delta `c[t+2] − c[t−2]` and its acceleration
/// `(c[t+3] − c[t−1]) − (c[t+1] − c[t−3])`, the line's first and last frames repeated past
/// its ends. One row a frame: the three streams one after another.
fn features(cepstra: &[Vec<f32>]) -> Vec<Vec<f64>> {
    let n = cepstra.len();
    let width = cepstra.first().map_or(0, Vec::len);
    if n == 0 || width == 0 {
        return Vec::new();
    }
    let mut mean = vec![0.0f64; width];
    for c in cepstra {
        for (m, v) in mean.iter_mut().zip(c) {
            *m += f64::from(*v) / n as f64;
        }
    }
    let at = |t: isize, k: usize| -> f64 {
        let t = t.clamp(0, n as isize - 1) as usize;
        f64::from(cepstra[t][k]) - mean[k]
    };
    (0..n as isize)
        .map(|t| {
            let mut row = Vec::with_capacity(3 * width);
            row.extend((0..width).map(|k| at(t, k)));
            row.extend((0..width).map(|k| at(t + 2, k) - at(t - 2, k)));
            row.extend(
                (0..width).map(|k| (at(t + 3, k) - at(t - 1, k)) - (at(t + 1, k) - at(t - 3, k))),
            );
            row
        })
        .collect()
}

/// Per stream, the map `mean → A·mean + b` that makes the labelled frames likeliest under
/// their phones' Gaussians, each frame shared among its codebook's Gaussians by how well
/// each explains it (equal weights: the share of the stream alone). Row by row (the
/// variances are diagonal): `[b_i, A_i] = G_i⁻¹ k_i`, with `G_i = Σ γ/σ²_i ξξᵀ`,
/// `k_i = Σ γ o_i/σ²_i ξ`, `ξ = [1, mean]`, and [`PRIOR`] toward the identity.
fn estimate(
    codebooks: &Codebooks,
    features: &[Vec<f64>],
    labels: &[Option<usize>],
) -> Option<Transform> {
    let density = codebooks.density;
    let n_books = codebooks.phones.len();
    let mut streams = Vec::with_capacity(codebooks.streams.len());
    let mut first = 0;
    for (stream, &width) in codebooks.streams.iter().enumerate() {
        // Occupancy and first-order sums per Gaussian: the statistics MLLR needs.
        let mut occupancy = vec![0.0f64; n_books * density];
        let mut sums = vec![0.0f64; n_books * density * width];
        let mut shares = vec![0.0f64; density];
        for (frame, label) in features.iter().zip(labels) {
            let Some(book) = *label else { continue };
            let Some(o) = frame.get(first..first + width) else {
                continue;
            };
            let base = codebooks.offset(book, stream);
            let mut best = f64::MIN;
            for (g, share) in shares.iter_mut().enumerate() {
                let at = base + g * width;
                let mut ll = 0.0;
                for (k, x) in o.iter().enumerate() {
                    let mean = f64::from(codebooks.means[at + k]);
                    let var = f64::from(codebooks.variances[at + k]);
                    ll -= 0.5 * ((x - mean) * (x - mean) / var + var.ln());
                }
                *share = ll;
                best = best.max(ll);
            }
            let total: f64 = shares.iter().map(|l| (l - best).exp()).sum();
            for (g, share) in shares.iter().enumerate() {
                let gamma = (share - best).exp() / total;
                if gamma < SHARE {
                    continue;
                }
                let slot = book * density + g;
                occupancy[slot] += gamma;
                for (k, x) in o.iter().enumerate() {
                    sums[slot * width + k] += gamma * x;
                }
            }
        }
        // Every row's system, filled in one pass over the Gaussians (each one's `ξ` read once).
        let size = width + 1;
        let mut gs = vec![vec![0.0f64; size * size]; width];
        let mut ks = vec![vec![0.0f64; size]; width];
        let mut xi = vec![0.0f64; size];
        for book in 0..n_books {
            let base = codebooks.offset(book, stream);
            for d in 0..density {
                let slot = book * density + d;
                if occupancy[slot] == 0.0 {
                    continue;
                }
                let at = base + d * width;
                xi[0] = 1.0;
                for (x, mean) in xi[1..].iter_mut().zip(&codebooks.means[at..at + width]) {
                    *x = f64::from(*mean);
                }
                for (i, (g, k)) in gs.iter_mut().zip(&mut ks).enumerate() {
                    let var = f64::from(codebooks.variances[at + i]);
                    let w = occupancy[slot] / var;
                    let o = sums[slot * width + i] / var;
                    for r in 0..size {
                        k[r] += o * xi[r];
                        for c in 0..size {
                            g[r * size + c] += w * xi[r] * xi[c];
                        }
                    }
                }
            }
        }
        let mut matrix = Vec::with_capacity(width);
        let mut bias = Vec::with_capacity(width);
        for (i, (mut g, mut k)) in gs.into_iter().zip(ks).enumerate() {
            for r in 0..size {
                g[r * size + r] += PRIOR;
            }
            k[i + 1] += PRIOR;
            let w = solve(&mut g, &mut k, size)?;
            bias.push(w[0] as f32);
            matrix.push(w[1..].iter().map(|v| *v as f32).collect());
        }
        streams.push((matrix, bias));
        first += width;
    }
    Some(Transform { streams })
}

/// `x` with `a·x = b` (`a` is `n`×`n`, row by row), by elimination with partial pivoting;
/// `None` when `a` is singular or the result not finite.
fn solve(a: &mut [f64], b: &mut [f64], n: usize) -> Option<Vec<f64>> {
    for col in 0..n {
        let pivot =
            (col..n).max_by(|&r, &s| a[r * n + col].abs().total_cmp(&a[s * n + col].abs()))?;
        if a[pivot * n + col].abs() < 1e-12 {
            return None;
        }
        if pivot != col {
            for c in 0..n {
                a.swap(pivot * n + c, col * n + c);
            }
            b.swap(pivot, col);
        }
        for r in col + 1..n {
            let f = a[r * n + col] / a[col * n + col];
            if f == 0.0 {
                continue;
            }
            for c in col..n {
                a[r * n + c] -= f * a[col * n + c];
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|c| a[r * n + c] * x[c]).sum();
        x[r] = (b[r] - s) / a[r * n + r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two codebooks of two Gaussians over one stream of two values.
    fn books() -> Codebooks {
        Codebooks {
            phones: vec!["AA".into(), "IY".into()],
            streams: vec![2],
            density: 2,
            means: vec![0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 2.0, 2.0],
            variances: vec![0.1; 8],
        }
    }

    #[test]
    fn frames_where_the_means_are_give_the_identity() {
        let codebooks = books();
        let mut features = Vec::new();
        let mut labels = Vec::new();
        for (book, g) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let at = codebooks.offset(book, 0) + g * 2;
            for _ in 0..100 {
                features.push(
                    codebooks.means[at..at + 2]
                        .iter()
                        .map(|v| f64::from(*v))
                        .collect(),
                );
                labels.push(Some(book));
            }
        }
        let t = estimate(&codebooks, &features, &labels).unwrap();
        let (a, b) = &t.streams[0];
        for (i, (row, bias)) in a.iter().zip(b).enumerate() {
            assert!(bias.abs() < 1e-3, "{t:?}");
            for (j, v) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-3, "{t:?}");
            }
        }
    }

    #[test]
    fn a_voice_shifted_from_the_model_moves_its_means_with_it() {
        let codebooks = books();
        let mut features = Vec::new();
        let mut labels = Vec::new();
        // Every frame 0.5 above its Gaussian in the first value, scaled by 1.5 in the second.
        for _ in 0..50 {
            for (book, g) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                let at = codebooks.offset(book, 0) + g * 2;
                let m = &codebooks.means[at..at + 2];
                features.push(vec![f64::from(m[0]) + 0.5, f64::from(m[1]) * 1.5]);
                labels.push(Some(book));
            }
        }
        // Frames no phone was decoded for count for nothing.
        features.push(vec![100.0, -100.0]);
        labels.push(None);
        let t = estimate(&codebooks, &features, &labels).unwrap();
        let (a, b) = &t.streams[0];
        let moved = |m: [f32; 2]| {
            [
                a[0][0] * m[0] + a[0][1] * m[1] + b[0],
                a[1][0] * m[0] + a[1][1] * m[1] + b[1],
            ]
        };
        for m in [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [2.0, 2.0]] {
            let got = moved(m);
            assert!((got[0] - (m[0] + 0.5)).abs() < 0.1, "{m:?} → {got:?}");
            assert!((got[1] - m[1] * 1.5).abs() < 0.15, "{m:?} → {got:?}");
        }
    }

    #[test]
    fn features_are_normalised_cepstra_with_their_deltas() {
        let cepstra: Vec<Vec<f32>> = (0..10).map(|t| vec![t as f32, 1.0]).collect();
        let f = features(&cepstra);
        assert_eq!(f.len(), 10);
        assert_eq!(f[0].len(), 6);
        // Mean removed.
        assert!((f[5][0] - 0.5).abs() < 1e-9 && f[5][1].abs() < 1e-9);
        // A ramp: delta 4 inside, less at the ends where frames repeat; no acceleration inside.
        assert!((f[5][2] - 4.0).abs() < 1e-9 && (f[0][2] - 2.0).abs() < 1e-9);
        assert!(f[5][4].abs() < 1e-9);
    }

    /// On a voice the model hears poorly (eSpeak NG's m3, a tuning voice), the transform makes
    /// the speech likelier: the adapted phone loop's path scores higher per frame than the
    /// first pass's (−18.9 → −17.0).
    #[test]
    fn the_adapted_model_hears_a_formant_voice_better() {
        if !faceanim_sphinx_sys::available() || !faceanim_espeak_sys::available() {
            return;
        }
        let spoken = faceanim_espeak_sys::speak(
            "Bob brought a big purple map to the bumpy boat.",
            "en-us+m3",
            None,
        )
        .unwrap();
        let sound = Sound {
            samples: crate::audio::resample_pcm(&spoken.samples, spoken.sample_rate),
        };
        let search = crate::phones::blind_search(crate::Recognition::PhoneLoop);
        let mut recogniser = Recogniser::load(&search).unwrap();
        let samples: Vec<i16> = sound.samples.clone();
        let first = recogniser.decode_scored(&samples).unwrap();
        let pass = first_pass(&mut recogniser, &samples, &first, &sound, 1.0)
            .expect("a formant voice is heard poorly and adapted to");
        recogniser.adapt(&pass.adaptation).unwrap();
        let second = recogniser.decode_scored(&samples).unwrap();
        let (before, after) = (
            first.score_per_frame.unwrap(),
            second.score_per_frame.unwrap(),
        );
        eprintln!("score per frame {before:.1} → {after:.1}");
        assert!(after > before + 1.0, "{before:.1} → {after:.1}");
        // Every closure kept is one the first pass's silences held.
        assert!(
            pass.closures.iter().all(|c| c.label == "P"),
            "{:?}",
            pass.closures
        );
    }

    #[test]
    fn a_closure_the_second_pass_lacks_is_spliced_in_and_one_it_has_is_not() {
        let phone = |label: &str, start: f32, end: f32| Phone {
            label: label.into(),
            start,
            end,
        };
        let second = vec![
            phone("AA", 0.0, 0.2),
            phone("D", 0.2, 0.3),
            phone("AA", 0.3, 0.5),
            phone("M", 0.5, 0.6),
        ];
        let closures = [phone("P", 0.22, 0.28), phone("P", 0.47, 0.52)];
        let kept: Vec<String> = keep_closures(second, &closures)
            .iter()
            .map(|p| format!("{} {:.2}–{:.2}", p.label, p.start, p.end))
            .collect();
        // The P inside the D is spliced in; the one beside the M is that M.
        let want = "AA 0.00–0.20, D 0.20–0.22, P 0.22–0.28, D 0.28–0.30, AA 0.30–0.50, M 0.50–0.60";
        assert_eq!(kept.join(", "), want);
    }

    #[test]
    fn a_singular_system_has_no_solution() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        let mut b = vec![1.0, 2.0];
        assert!(solve(&mut a, &mut b, 2).is_none());
        let mut a = vec![2.0, 1.0, 1.0, 3.0];
        let mut b = vec![3.0, 5.0];
        let x = solve(&mut a, &mut b, 2).unwrap();
        assert!((x[0] - 0.8).abs() < 1e-9 && (x[1] - 1.4).abs() < 1e-9);
    }
}
