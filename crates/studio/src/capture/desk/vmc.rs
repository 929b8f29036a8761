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

    /// Sends one frame the page plays (the `weights` of a character whose blendshapes are
    /// `names`, and the `head` pose) to the marionette; false when the network refused it.
    /// `take` (the open take's id and the frame shown) adds that take's own gaze, jaw and ARKit
    /// values at the frame, as its export turns bones (and, under ARKit names or VRM presets,
    /// for what the character's shapes cannot make); without it, or for a take no longer open,
    /// the gaze and jaw come from the weights.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not send VMC, [`ApiError::Invalid`] for weights
    /// that are not one finite number per blendshape, or a head pose that is not finite.
    pub fn send_vmc_frame(
        &self,
        weights: &[f32],
        head: Option<[f32; 3]>,
        take: Option<crate::capture::TakeFrame>,
        names: &[String],
    ) -> Result<bool, ApiError> {
        let played = take.and_then(|shown| {
            let open = self.take.as_ref().filter(|open| open.id() == shown.id)?;
            crate::capture::vmc::Played::of(&open.take.session, shown.frame)
        });
        self.vmc.send(weights, head, played, names)
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
