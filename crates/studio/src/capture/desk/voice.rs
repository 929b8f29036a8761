//! The desk's microphone: started, calibrated, delayed, and recorded as a take.

use faceanim_rig::Character;

use super::CaptureDesk;
use crate::capture::open_take::{OpenTake, Previews, Sound, private_dir};
use crate::capture::voice::{RATE, RECORDED_FPS, Voice, VoiceHandle};
use crate::error::ApiError;
use crate::lock;
use crate::views::VoiceView;

impl CaptureDesk {
    /// Starts (or restarts) the live microphone, its mouth held back by `delay_ms`. A voice
    /// learned earlier in this process is kept.
    ///
    /// On a rig whose names say nothing of a mouth, with no adapter and no retarget map yet
    /// (the desk's `lacks_map`), the microphone starts with a mouth that waits for the map
    /// and returns `true`: the caller has the map made ([`super::retarget::map_for_live`],
    /// unless it is already being made), and the mouth moves by it once it is there.
    ///
    /// # Errors
    /// [`ApiError::Invalid`] when the character has no mouth to drive ([`CaptureDesk::mouth`])
    /// and no map can be made for it, or the delay is out of range; [`ApiError::Busy`] when
    /// the map is wanted while another job runs.
    pub fn start_voice(
        &mut self,
        character: &Character,
        delay_ms: u32,
        language: Option<&str>,
    ) -> Result<bool, ApiError> {
        let (mouth, awaits_map) = match self.mouth(character) {
            Ok(mouth) => (mouth, false),
            Err(no_mouth) if self.adapter.is_none() && self.lacks_map(character) => {
                if !self.making_map() {
                    self.busy()?;
                }
                tracing::info!("{no_mouth}: the mouth waits for the retarget map");
                let shapes = character.blendshapes().len();
                (faceanim_speech::Mouth::before_map(shapes), true)
            }
            Err(e) => return Err(e),
        };
        let mut slot = lock(&self.voice);
        let model = slot
            .as_ref()
            .and_then(|v| v.model().cloned())
            .or_else(|| self.voice_model.clone());
        let mut voice = Voice::start(
            mouth,
            &self.visemes,
            model,
            delay_ms,
            language,
            self.vmc.performer.clone(),
        )?;
        if awaits_map {
            voice.wait_for_map();
        }
        *slot = Some(voice);
        Ok(awaits_map)
    }

    /// Stops the microphone (a recording in progress is dropped); the learned voice is kept
    /// for the next start.
    pub fn stop_voice(&mut self) {
        if let Some(voice) = lock(&self.voice).take()
            && let Some(model) = voice.into_model()
        {
            self.voice_model = Some(model);
        }
    }

    /// The microphone's state, while on.
    #[must_use]
    pub fn voice_view(&self) -> Option<VoiceView> {
        lock(&self.voice).as_ref().map(Voice::view)
    }

    /// Holds the mouth back by `delay_ms` from now on.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the microphone is off; [`ApiError::Invalid`] out of range.
    pub fn set_voice_delay(&mut self, delay_ms: u32) -> Result<(), ApiError> {
        lock(&self.voice)
            .as_mut()
            .ok_or(ApiError::Live("start the microphone first"))?
            .set_delay(delay_ms)
    }

    /// Hears `language` from now on: its passage calibrates, its speech refines.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the microphone is off; [`ApiError::Invalid`] naming a language
    /// eSpeak NG does not speak.
    pub fn set_voice_language(&mut self, language: &str) -> Result<(), ApiError> {
        lock(&self.voice)
            .as_mut()
            .ok_or(ApiError::Live("start the microphone first"))?
            .set_language(language)
    }

    /// Treats what the microphone hears next (a calibration's length) as the passage read aloud.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the microphone is off or calibration is already under way.
    pub fn calibrate_voice(&mut self) -> Result<(), ApiError> {
        lock(&self.voice)
            .as_mut()
            .ok_or(ApiError::Live("start the microphone first"))?
            .calibrate()
    }

    /// Starts or stops recording the microphone; stopping makes the recording the take, with
    /// its sound.
    ///
    /// # Errors
    /// [`ApiError::Live`] when the microphone is off, not recording, or nothing was heard;
    /// the take's or the scratch file's error.
    pub fn record_voice(&mut self, character: &Character, on: bool) -> Result<(), ApiError> {
        if !on {
            // Before the recording is taken: a busy desk keeps it for the next try.
            self.busy()?;
        }
        let recorded = {
            let mut slot = lock(&self.voice);
            let voice = slot
                .as_mut()
                .ok_or(ApiError::Live("start the microphone first"))?;
            if on {
                voice.start_recording();
                return Ok(());
            }
            voice.stop_recording()?
        };
        let dir = private_dir(&mut self.uploads, "faceanim-uploads-", "uploads")?;
        let path = dir.join(format!("microphone-{}.wav", std::process::id()));
        faceanim_files::write_atomic(
            &path,
            &faceanim_speech::audio::wav_bytes(&recorded.sound, RATE as u32, 1),
        )
        .map_err(ApiError::Disk)?;
        // What it is made of goes with it (Live Link Face's curves, a jaw bone's opening), as
        // a lip sync's does.
        let take = faceanim_take::Take::from_weights(
            character,
            "microphone.wav",
            RECORDED_FPS,
            &recorded.weights,
            None,
        )?
        .made_of_arkit(recorded.arkit)?;
        let sound = Sound {
            path,
            mime: "audio/wav",
        };
        let sound = self.keep_sound(sound);
        self.take = Some(OpenTake::new(take, Previews::new()).with_sound(sound));
        self.save_take();
        Ok(())
    }

    /// The live microphone, to hear chunks without holding the desk.
    #[must_use]
    pub fn voice_handle(&self) -> VoiceHandle {
        VoiceHandle::new(self.voice.clone(), self.skeleton.clone())
    }
}
