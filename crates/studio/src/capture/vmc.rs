//! Live links in the studio: a marionette that a phone tracker (in its own protocol: Live Link
//! Face, iFacialMocap, VTube Studio; or over VMC: Waidayo) or another performer drives live,
//! recorded as takes like the webcam's; and a performer that sends the live face (webcam or
//! phone) out to VTuber apps and engines.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use crate::error::ApiError;
use crate::lock;
use crate::views::{VmcSendView, VmcView};
use faceanim_live::{Marionette, Names, Performer, Source};

/// What the studio listens to, as it was started.
#[derive(Debug, Clone)]
pub struct Listen {
    /// The address.
    pub address: SocketAddr,
    /// The protocol, the phone to ask and the user's settings (units, neutral).
    pub source: Source,
    /// Where a calibrated neutral is kept (`--phone-settings`); none for VMC.
    pub settings_file: Option<PathBuf>,
}

/// Where live frames go in and out, as the studio was started.
#[derive(Debug, Clone, Default)]
pub struct VmcConfig {
    /// Listen here (`--vmc-listen`, `--phone`).
    pub listen: Option<Listen>,
    /// Send the live face here under these names (`--vmc-send`, `--vmc-names`).
    pub send: Option<(SocketAddr, Names)>,
}

/// A frame of the open take the page shows while it plays: the take's id and the frame.
#[derive(Debug, Clone, Copy, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TakeFrame {
    /// The take ([`crate::views::TakeView::id`]).
    pub id: u64,
    /// The frame.
    pub frame: usize,
}

/// What a take plays at one frame besides its weights: its gaze and jaw, as its export turns
/// bones, and its ARKit values where it was made of them.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Played {
    eyes: Option<[[f32; 2]; 2]>,
    jaw: Option<f32>,
    arkit: Option<Vec<f32>>,
}

impl Played {
    /// Frame `frame` of `session`: from the capture's own ARKit values, else from the frames
    /// by their names' ARKit meaning ([`faceanim_export::bones::BoneKeys::of_take`]'s rule);
    /// `None` past its last frame.
    pub(super) fn of(session: &faceanim_take::Session, frame: usize) -> Option<Played> {
        Some(match session.arkit_clip() {
            Some(arkit) => {
                let row = arkit.frames.get(frame)?;
                let (eyes, jaw) = faceanim_export::bones::BoneKeys::of_row(&arkit.blendshapes, row);
                Played {
                    eyes,
                    jaw,
                    arkit: arkit.arkit_row(frame),
                }
            }
            None => {
                let clip = session.clip();
                let row = clip.frames.get(frame)?;
                let (eyes, jaw) = faceanim_export::bones::BoneKeys::of_row(&clip.blendshapes, row);
                Played {
                    eyes,
                    jaw,
                    arkit: None,
                }
            }
        })
    }
}

/// The desk's VMC links.
#[derive(Debug)]
pub(super) struct Vmc {
    config: VmcConfig,
    marionette: Option<Marionette>,
    pub(super) performer: Option<Arc<Mutex<Performer>>>,
    /// This machine's LAN addresses, found once when listening starts (the page polls the
    /// view every frame while live).
    this_machine: Vec<String>,
    /// The clock of the frames the page sends.
    started: std::time::Instant,
}

impl Default for Vmc {
    fn default() -> Vmc {
        Vmc {
            config: VmcConfig::default(),
            marionette: None,
            performer: None,
            this_machine: Vec::new(),
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

    /// Opens the links of `config` for a character with `blendshapes`; a phone's ARKit values
    /// reach shapes named otherwise through `map`.
    ///
    /// # Errors
    /// [`ApiError::Vmc`] when the port cannot be bound or the names cover none of the
    /// character's shapes.
    pub(super) fn open(
        config: VmcConfig,
        blendshapes: &[String],
        map: Option<Arc<faceanim_retarget::RetargetMap>>,
    ) -> Result<Vmc, ApiError> {
        let mut vmc = Vmc {
            config: config.clone(),
            ..Vmc::default()
        };
        if let Some(listen) = &config.listen {
            let marionette = Marionette::listen_to(&listen.source, listen.address, blendshapes)?;
            marionette.set_map(map);
            vmc.marionette = Some(marionette);
            vmc.this_machine = faceanim_live::lan_addresses()
                .iter()
                .map(ToString::to_string)
                .collect();
        }
        if let Some((destination, names)) = config.send {
            // The studio's faces (webcam, phone, microphone) are known in ARKit: what the
            // character's shapes cannot make under the names asked for goes out from them.
            let performer = Performer::with_arkit(destination, blendshapes, names)?;
            if !blendshapes.is_empty() && !performer.sends_weights() {
                tracing::warn!(
                    "the character has no {}: captured faces go out by their ARKit values, a \
                     sketch played sends its head alone",
                    names.describe()
                );
            }
            vmc.performer = Some(Arc::new(Mutex::new(performer)));
        }
        // A phone's face goes out as it arrives, as the webcam's does (a VMC performer's is
        // not echoed back).
        if let (Some(marionette), Some(listen)) = (&vmc.marionette, &config.listen)
            && listen.source.protocol != faceanim_live::phone::Protocol::Vmc
        {
            marionette.forward_to(vmc.performer.clone());
        }
        Ok(vmc)
    }

    /// The links' state, when there are any.
    pub(super) fn view(
        &self,
        skeleton: Option<&faceanim_export::bones::ViewRig>,
    ) -> Option<VmcView> {
        let sending = self.performer.as_ref().map(|p| {
            let performer = lock(p);
            let stats = performer.stats();
            VmcSendView {
                to: performer.destination().to_string(),
                frames: stats.frames,
                dropped: stats.dropped,
                last_error: stats.last_error.clone(),
            }
        });
        let marionette = self.marionette.as_ref();
        if marionette.is_none() && sending.is_none() {
            return None;
        }
        let mut traffic = marionette.map(Marionette::traffic).unwrap_or_default();
        // What the character's bones show (its eyes' gaze, its jaw) is not lost on it.
        if let Some(skeleton) = skeleton {
            traffic.unmatched_names.retain(|name| !skeleton.shows(name));
        }
        let latest = marionette.and_then(Marionette::latest);
        let listen = self.config.listen.as_ref();
        Some(VmcView {
            listening: marionette.map(|m| m.address().to_string()),
            source: listen.map(|l| l.source.protocol.label()),
            phone: listen.and_then(|l| l.source.phone).map(|a| a.to_string()),
            this_machine: self.this_machine.clone(),
            neutral: marionette.is_some_and(|m| m.settings().neutral.is_some()),
            traffic,
            recording: marionette.and_then(Marionette::recorded),
            weights: latest.as_ref().map(|f| f.weights.clone()),
            bones: skeleton
                .zip(latest.as_ref())
                .map(|(s, f)| s.pose(f.head, f.eyes(), f.jaw())),
            head: latest.and_then(|f| f.head),
            sending,
        })
    }

    /// Sends one frame of the face of a character whose blendshapes are `names`, with the
    /// `head` pose, and the gaze, jaw and ARKit values of the take frame `played` where given
    /// (else the gaze and jaw of the weights' ARKit meaning). False when the network refused it.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not send VMC, [`ApiError::Invalid`] for weights
    /// that are not one finite number per blendshape, or a head pose that is not finite.
    pub(super) fn send(
        &self,
        weights: &[f32],
        head: Option<[f32; 3]>,
        played: Option<Played>,
        names: &[String],
    ) -> Result<bool, ApiError> {
        let blendshapes = names.len();
        let performer = self.performer.as_ref().ok_or(ApiError::Live(
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
        // The gaze and the jaw go out as bones too, as the webcam's do (VRM's presets carry no
        // gaze): the take's own where it plays, else by the shapes' ARKit meaning.
        let (eyes, jaw, arkit) = match played {
            Some(p) => (p.eyes, p.jaw, p.arkit),
            None => {
                let (eyes, jaw) = faceanim_export::bones::BoneKeys::of_row(names, weights);
                (eyes, jaw, None)
            }
        };
        let pose = faceanim_live::Pose { head, eyes, jaw };
        let mut performer = lock(performer);
        let time = self.started.elapsed().as_secs_f32();
        Ok(match arkit {
            Some(arkit) => performer.send_with_arkit(weights, &arkit, pose, time),
            None => performer.send_pose(weights, pose, time),
        })
    }

    /// The marionette, when listening.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the studio does not listen for VMC.
    pub(super) fn marionette(&self) -> Result<&Marionette, ApiError> {
        self.marionette.as_ref().ok_or(ApiError::Live(
            "the studio is not listening for a phone or VMC: start it with --phone or --vmc-listen",
        ))
    }

    /// Takes the phone's face as it is now for its neutral, kept in the settings file.
    ///
    /// # Errors
    /// [`ApiError::Live`] when nothing listens or no phone face has arrived,
    /// [`ApiError::Disk`] when the settings cannot be saved.
    pub(super) fn calibrate(&self) -> Result<(), ApiError> {
        let settings = self.marionette()?.calibrate().ok_or(ApiError::Live(
            "no face has arrived from the phone yet: look at it, relaxed, and try again",
        ))?;
        if let Some(path) = self
            .config
            .listen
            .as_ref()
            .and_then(|l| l.settings_file.as_ref())
        {
            let json = serde_json::to_vec_pretty(&settings)
                .map_err(|e| ApiError::Internal(e.to_string()))?;
            if let Some(folder) = path.parent() {
                std::fs::create_dir_all(folder).map_err(|source| {
                    faceanim_files::FileError::Io {
                        path: folder.to_path_buf(),
                        source,
                    }
                })?;
            }
            faceanim_files::write_atomic(path, &json)?;
        }
        Ok(())
    }

    /// The links as the studio was started.
    pub(super) fn config(&self) -> VmcConfig {
        self.config.clone()
    }
}
