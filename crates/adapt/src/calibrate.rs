//! A retarget map calibrated on its character: MediaPipe's scores move with a face but do not
//! reach an artist's weights (a blink the character makes fully may read 0.6). Each channel is
//! shown through the map at [`INTENSITIES`], from the front in the studio's light, and read
//! back through the capture pipeline relative to the neutral render; the rise of the
//! channel's own score at each intensity gives its response, whose monotone inverse
//! ([`faceanim_retarget::Curve`]) turns a score into the value that makes the character look
//! so. About two hundred renders, in parallel.

use faceanim_retarget::{Calibration, Curve, RetargetMap};
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
        // A channel made with its twin (one shape for both sides, each at half) is shown with
        // the twin raised too: alone it moves its shape half way.
        let work: Vec<(usize, usize, Option<usize>, f32)> = channels
            .iter()
            .flat_map(|&(c, score)| {
                let twin = map.shares_with_twin(c);
                INTENSITIES.iter().map(move |&x| (c, score, twin, x))
            })
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
