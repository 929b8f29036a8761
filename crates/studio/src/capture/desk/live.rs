//! The desk's webcam: live tracking started and stopped, and takes recorded from it.

use faceanim_rig::Character;

use super::CaptureDesk;
use crate::capture::live::{Live, LiveHandle};
use crate::error::ApiError;
use crate::lock;

impl CaptureDesk {
    /// Starts (or restarts) live tracking.
    ///
    /// # Errors
    /// [`ApiError::Models`] when the face models cannot be loaded.
    pub fn start_live(&mut self, character: &Character) -> Result<(), ApiError> {
        *lock(&self.live) = Some(Live::start(
            self.estimator(character),
            self.filtering.smoothing,
            self.vmc.performer.clone(),
        )?);
        Ok(())
    }

    /// Takes the next live frame with a face as the neutral one (the performer's Calibrate).
    ///
    /// # Errors
    /// [`ApiError::Live`] when live tracking is off.
    pub fn calibrate_live(&mut self) -> Result<(), ApiError> {
        lock(&self.live)
            .as_mut()
            .ok_or(ApiError::Live("start live mode first"))?
            .calibrate();
        Ok(())
    }

    /// Stops live tracking (a recording in progress is dropped).
    pub fn stop_live(&mut self) {
        *lock(&self.live) = None;
    }

    /// The live state, to track frames without holding the desk.
    #[must_use]
    pub fn live_handle(&self) -> LiveHandle {
        LiveHandle::new(self.live.clone(), self.skeleton.clone())
    }

    /// Starts recording a take from the live frames.
    ///
    /// # Errors
    /// [`ApiError::Live`] when live tracking is off.
    pub fn start_recording(&mut self) -> Result<(), ApiError> {
        lock(&self.live)
            .as_mut()
            .ok_or(ApiError::Live("start live mode first"))?
            .start_recording();
        Ok(())
    }

    /// Stops recording and makes the recording the take; returns its frame count.
    ///
    /// # Errors
    /// [`ApiError::Live`] when nothing was recorded.
    pub fn stop_recording(&mut self, character: &Character) -> Result<usize, ApiError> {
        let (footage, previews) = lock(&self.live)
            .as_mut()
            .ok_or(ApiError::Live("live mode is off"))?
            .stop_recording()?;
        let n = footage.records.len();
        let take = self.take_of(character, footage)?;
        self.set_take(take, previews);
        Ok(n)
    }
}
