//! A retarget map calibrated on its character: MediaPipe's scores move with a face but do not
//! reach an artist's weights (a blink the character makes fully may read 0.6). Each channel is
//! shown through the map at [`INTENSITIES`], from the front in the studio's light, and read
//! back through the capture pipeline relative to the neutral render; the rise of the
//! channel's own score at each intensity gives its response, whose monotone inverse
//! ([`faceanim_retarget::Curve`]) turns a score into the value that makes the character look
//! so. About two hundred renders, in parallel.

use faceanim_retarget::{Calibration, Curve, RetargetMap, RowSource};
use faceanim_rig::{Character, Pose};
use faceanim_track::FaceModels;
use rayon::prelude::*;

use crate::{AdaptError, Control, FaceCamera};

/// The strengths each channel is shown at.
pub const INTENSITIES: [f32; 4] = [0.25, 0.5, 0.75, 1.0];

impl FaceCamera {
    /// `map`'s calibration on `character`: every channel MediaPipe scores and the map moves
    /// some shape for, shown at each of [`INTENSITIES`] and read back.
    ///
    /// # Errors
    /// [`AdaptError::Model`] if a network fails, [`AdaptError::NoNeutralFace`] when the
    /// neutral render has no face to read, [`AdaptError::Cancelled`].
    pub fn calibrate(
        &self,
        character: &Character,
        models: &FaceModels,
        map: &RetargetMap,
        control: Control<'_>,
    ) -> Result<Calibration, AdaptError> {
        let Some(neutral) = self
            .expression(character, models, &[], &mut Pose::default())?
            .0
        else {
            return Err(AdaptError::NoNeutralFace);
        };
        let channels: Vec<(usize, usize)> = faceanim_rig::names::ARKIT_52
            .iter()
            .enumerate()
            .filter_map(|(c, name)| {
                let score = faceanim_track::BLENDSHAPE_NAMES
                    .iter()
                    .position(|n| n == name)?;
                let mut unit = vec![0.0; faceanim_retarget::CHANNELS];
                unit[c] = 1.0;
                map.weights(&unit)
                    .iter()
                    .any(|w| *w > 0.0)
                    .then_some((c, score))
            })
            .collect();
        let shown_with: Vec<Option<usize>> = channels
            .iter()
            .map(|&(c, _)| shown_with_twin(map, c))
            .collect();
        let work: Vec<(usize, usize, Option<usize>, f32)> = channels
            .iter()
            .zip(&shown_with)
            .flat_map(|(&(c, score), &twin)| INTENSITIES.iter().map(move |&x| (c, score, twin, x)))
            .collect();
        let total = work.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let rises: Vec<(usize, f32, f32)> = work
            .par_iter()
            .map_init(Pose::default, |pose, &(c, score, twin, x)| {
                if control.cancelled() {
                    return Err(AdaptError::Cancelled);
                }
                let mut values = vec![0.0; faceanim_retarget::CHANNELS];
                values[c] = x;
                if let Some(t) = twin {
                    values[t] = x;
                }
                let weights = map.weights(&values);
                let read = self.expression(character, models, &weights, pose)?.0;
                let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                (control.progress)(finished, total);
                Ok(read.map(|e| (c, x, e.scores[score] - neutral.scores[score])))
            })
            .collect::<Result<Vec<_>, AdaptError>>()?
            .into_iter()
            .flatten()
            .collect();
        let mut calibration = Calibration {
            renders: total + 1,
            ..Calibration::default()
        };
        for &(c, _) in &channels {
            let samples: Vec<(f32, f32)> = rises
                .iter()
                .filter(|(k, _, _)| *k == c)
                .map(|&(_, x, rise)| (x, rise))
                .collect();
            if let Some(curve) = Curve::fit(&samples) {
                calibration
                    .channels
                    .insert(faceanim_rig::names::ARKIT_52[c].to_owned(), curve);
            }
        }
        Ok(calibration)
    }
}

/// The channel `c` is shown with when calibrated: its twin on the other side of the face
/// ([`faceanim_rig::names::Channel::twin`]) when both are made by geometry and most of what
/// the map moves for it (half its weight or more) is shapes it moves for the twin too: a shape
/// that moves both sides, which each side drives at half (`Fcl_BRW_Angry` for both
/// `browDownLeft` and `browDownRight` on a rig whose names say nothing). Shown alone, such a
/// channel moves its shape half way, and the score that half reads would be taken for the
/// whole: a person lowering both brows would move the character's twice as far.
///
/// A name that merges the two sides (`Fcl_MTH_Joy` read as both smiles) is calibrated side by
/// side as before: by-name channels stay as they were. Shown with their twins, the tests'
/// VRoid-style avatar by its own names followed people's lids, lips and lowered brows a little
/// more closely (r +0.01 to +0.02) but its mouth corners less (0.72 → 0.53 and 0.40 → 0.22 on
/// two videos: its smile, calibrated at half the gain, no longer outweighs the corners' drop
/// as the jaw opens).
fn shown_with_twin(map: &RetargetMap, c: usize) -> Option<usize> {
    let twin = faceanim_rig::names::Channel::named(faceanim_rig::names::ARKIT_52[c])?
        .twin()?
        .index();
    let geometric = |c: usize| map.rows[c].from == RowSource::Geometry;
    if !geometric(c) || !geometric(twin) {
        return None;
    }
    let moves = |c: usize| {
        let mut unit = vec![0.0; faceanim_retarget::CHANNELS];
        unit[c] = 1.0;
        map.weights(&unit)
    };
    let (one, other) = (moves(c), moves(twin));
    let shared: f32 = one.iter().zip(&other).map(|(a, b)| a.min(*b)).sum();
    (shared > 0.0 && 2.0 * shared >= one.iter().sum::<f32>()).then_some(twin)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(name: &str) -> usize {
        faceanim_retarget::channel_index(name).unwrap()
    }

    /// A rig whose lowered brows are one shape for both sides, made by geometry with each side
    /// at half: each side is calibrated with the other. A shape for each eye: alone. A name
    /// that merges both sides stays calibrated side by side, as by-name channels were.
    #[test]
    fn a_shape_both_sides_drive_is_calibrated_with_both() {
        let names: Vec<String> = ["shape_0", "shape_1", "shape_2", "Fcl_MTH_Joy"]
            .map(String::from)
            .to_vec();
        let mut map = RetargetMap::by_name("vroid", &names, &[]);
        let row = |channel: &str, shapes: &[(&str, f32)]| faceanim_retarget::Fitted {
            channel: index(channel),
            shapes: shapes.iter().map(|(n, w)| ((*n).to_owned(), *w)).collect(),
            explained: 0.95,
        };
        map.set_geometry(
            vec![
                row("browDownLeft", &[("shape_0", 0.5)]),
                row("browDownRight", &[("shape_0", 0.5)]),
                row("eyeBlinkLeft", &[("shape_1", 1.0)]),
                row("eyeBlinkRight", &[("shape_2", 1.0)]),
            ],
            None,
            faceanim_retarget::Mode::Frame,
        );
        assert_eq!(
            shown_with_twin(&map, index("browDownLeft")),
            Some(index("browDownRight")),
            "{}",
            map.to_json()
        );
        assert_eq!(
            shown_with_twin(&map, index("browDownRight")),
            Some(index("browDownLeft"))
        );
        assert_eq!(shown_with_twin(&map, index("eyeBlinkLeft")), None);
        assert_eq!(shown_with_twin(&map, index("jawOpen")), None);
        assert_eq!(map.rows[index("mouthSmileLeft")].from, RowSource::ByName);
        assert_eq!(shown_with_twin(&map, index("mouthSmileLeft")), None);
    }
}
