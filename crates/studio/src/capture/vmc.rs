//! VMC in the studio: a marionette that phone trackers (iFacialMocap, Waidayo) or other
//! performers drive live, recorded as takes like the webcam's; and a performer that sends the
//! live webcam face out to VTuber apps and engines.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use faceanim_live::{Marionette, Names, Performer};
use faceanim_rig::Character;
use faceanim_take::{ReceivedFrame, Take};

use super::{CaptureDesk, Previews, lock};
use crate::error::ApiError;
use crate::views::{VmcSendView, VmcView, names};

/// Where VMC goes in and out, as the studio was started.
#[derive(Debug, Clone, Copy, Default)]
pub struct VmcConfig {
    /// Listen for a performer here (`--vmc-listen`).
    pub listen: Option<SocketAddr>,
    /// Send the live face here under these names (`--vmc-send`, `--vmc-names`).
    pub send: Option<(SocketAddr, Names)>,
}

/// The desk's VMC links.
#[derive(Debug)]
pub(super) struct Vmc {
    config: VmcConfig,
    marionette: Option<Marionette>,
    pub(super) performer: Option<Arc<Mutex<Performer>>>,
    /// The clock of the frames the page sends.
    started: std::time::Instant,
}

impl Default for Vmc {
    fn default() -> Vmc {
        Vmc {
            config: VmcConfig::default(),
            marionette: None,
            performer: None,
            started: std::time::Instant::now(),
        }
    }
}

impl Vmc {
    /// Gives the marionette, when listening, the character's retarget map.
    pub(super) fn set_map(&self, map: Option<Arc<faceanim_retarget::RetargetMap>>) {
        if let Some(marionette) = &self.marionette {
            marionette.set_map(map);
        }
    }

    /// The links as the studio was started.
    pub(super) fn config(&self) -> VmcConfig {
        self.config
    }
}

impl CaptureDesk {
    /// Opens the VMC links of `config` for `character` (again, after the character changed).
    ///
    /// # Errors
    /// [`ApiError::Vmc`] when the port cannot be bound or the names cover none of the
    /// character's shapes.
    pub fn open_vmc(&mut self, config: VmcConfig, character: &Character) -> Result<(), ApiError> {
        // The old socket goes first: the new one binds the same port.
        self.vmc = Vmc {
            config,
            ..Vmc::default()
        };
        let blendshapes = names(character);
        if let Some(address) = config.listen {
            let marionette = Marionette::listen(address, &blendshapes)?;
            // A phone's ARKit values reach shapes named otherwise through the map.
            marionette.set_map(self.map.clone());
            self.vmc.marionette = Some(marionette);
        }
        if let Some((destination, names)) = config.send {
            let performer = Performer::new(destination, &blendshapes, names)?;
            self.vmc.performer = Some(Arc::new(Mutex::new(performer)));
        }
        Ok(())
    }

    /// The VMC links' state, when there are any.
    #[must_use]
    pub fn vmc_view(&self) -> Option<VmcView> {
        let sending = self.vmc.performer.as_ref().map(|p| {
            let performer = lock(p);
            let stats = performer.stats();
            VmcSendView {
                to: performer.destination().to_string(),
                frames: stats.frames,
                dropped: stats.dropped,
                last_error: stats.last_error.clone(),
            }
        });
        let marionette = self.vmc.marionette.as_ref();
        if marionette.is_none() && sending.is_none() {
            return None;
        }
        let traffic = marionette.map(Marionette::traffic).unwrap_or_default();
        let latest = marionette.and_then(Marionette::latest);
        Some(VmcView {
            listening: marionette.map(|m| m.address().to_string()),
            traffic,
            recording: marionette.and_then(Marionette::recorded),
            weights: latest.as_ref().map(|f| f.weights.clone()),
            head: latest.and_then(|f| f.head),
            sending,
        })
    }

    /// Sends one frame of the character's face (what the page shows while playing a take or
    /// the sketch) to the marionette; false when the network refused it.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not send VMC, [`ApiError::Invalid`] for weights
    /// that are not one finite number per blendshape.
    pub fn send_vmc_frame(
        &self,
        weights: &[f32],
        head: Option<[f32; 3]>,
        blendshapes: usize,
    ) -> Result<bool, ApiError> {
        let performer = self.vmc.performer.as_ref().ok_or(ApiError::Live(
            "the studio does not send VMC: start it with --vmc-send HOST:PORT",
        ))?;
        if weights.len() != blendshapes || weights.iter().any(|w| !w.is_finite()) {
            return Err(ApiError::Invalid(format!(
                "weights: one finite number per blendshape ({blendshapes}), got {} values",
                weights.len()
            )));
        }
        if head.is_some_and(|h| h.iter().any(|a| !a.is_finite())) {
            return Err(ApiError::Invalid(
                "head: three finite angles in degrees".into(),
            ));
        }
        let mut performer = lock(performer);
        let time = self.vmc.started.elapsed().as_secs_f32();
        Ok(performer.send(weights, head, time))
    }

    fn marionette(&self) -> Result<&Marionette, ApiError> {
        self.vmc.marionette.as_ref().ok_or(ApiError::Live(
            "the studio is not listening for VMC: start it with --vmc-listen [PORT]",
        ))
    }

    /// Starts recording the frames that arrive over VMC.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not listen for VMC.
    pub fn start_vmc_recording(&self) -> Result<(), ApiError> {
        self.marionette()?.start_recording();
        Ok(())
    }

    /// Stops recording and makes the frames the take (with their arrival times); returns their
    /// count.
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
        let frames = frames
            .into_iter()
            .map(|f| ReceivedFrame {
                time: f.time,
                weights: f.weights,
                head: f.head,
            })
            .collect();
        let take = Take::from_received(character, "vmc", frames, self.filtering)?;
        self.set_take(take, Previews::new());
        Ok(count)
    }
}
