//! The desk's VMC link: opened and closed, frames sent out, and takes recorded from what comes in.

use faceanim_live::Marionette;
use faceanim_rig::Character;
use faceanim_take::Take;

use super::CaptureDesk;
use crate::capture::open_take::Previews;
use crate::capture::vmc::{Vmc, VmcConfig};
use crate::error::ApiError;
use crate::views::{VmcView, names};

impl CaptureDesk {
    /// Opens the VMC links of `config` for `character` (again, after the character changed).
    ///
    /// # Errors
    /// [`ApiError::Vmc`] when the port cannot be bound or the names cover none of the
    /// character's shapes.
    pub fn open_vmc(&mut self, config: VmcConfig, character: &Character) -> Result<(), ApiError> {
        // The old socket goes first: the new one binds the same port.
        self.vmc = Vmc::default();
        self.vmc = Vmc::open(config, &names(character), self.map.clone())?;
        Ok(())
    }

    /// The VMC links' state, when there are any.
    #[must_use]
    pub fn vmc_view(&self) -> Option<VmcView> {
        self.vmc.view(self.skeleton.as_deref())
    }

    /// Sends one frame of the face of a character whose blendshapes are `names` (what the
    /// page shows while playing a take or the sketch) to the marionette, with the head, gaze and
    /// jaw of `pose` (a take's; the gaze and jaw the pose lacks from `weights`); false when the
    /// network refused it.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not send VMC, [`ApiError::Invalid`] for weights
    /// that are not one finite number per blendshape, or a pose out of range.
    pub fn send_vmc_frame(
        &self,
        weights: &[f32],
        pose: faceanim_live::Pose,
        names: &[String],
    ) -> Result<bool, ApiError> {
        self.vmc.send(weights, pose, names)
    }

    /// Takes the phone's face as it is now for its neutral, from now on and in later runs.
    ///
    /// # Errors
    /// [`ApiError::Live`] when nothing listens or no phone face arrived yet,
    /// [`ApiError::Disk`] when the settings cannot be saved.
    pub fn calibrate_phone(&self) -> Result<(), ApiError> {
        self.vmc.calibrate()
    }

    fn marionette(&self) -> Result<&Marionette, ApiError> {
        self.vmc.marionette()
    }

    /// Starts recording the frames that arrive over VMC.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not listen for VMC.
    pub fn start_vmc_recording(&self) -> Result<(), ApiError> {
        self.marionette()?.start_recording();
        Ok(())
    }

    /// Stops recording and makes the frames the take, on a steady rate by their times (the
    /// sender's where sound, else their arrival: [`faceanim_live::Marionette::stop_recording`],
    /// [`Take::from_received`]); returns how many arrived.
    ///
    /// # Errors
    /// [`ApiError::Live`] when it was not recording or nothing arrived.
    pub fn stop_vmc_recording(&mut self, character: &Character) -> Result<usize, ApiError> {
        let frames = self
            .marionette()?
            .stop_recording()
            .ok_or(ApiError::Live("not recording VMC"))?;
        if frames.is_empty() {
            return Err(ApiError::Live("nothing arrived over VMC while recording"));
        }
        let count = frames.len();
        let take = Take::from_received(character, "vmc", frames, self.filtering)?;
        self.set_take(take, Previews::new());
        Ok(count)
    }
}
