//! An uploaded line of speech and how it is lip-synced: as `faceanim lipsync --text
//! --language --voice` takes them, with messages that name the file the user picked.

use std::path::PathBuf;

use crate::error::ApiError;

/// A line of speech the user uploaded, with what was said, its language and whose voice it
/// is, when given.
#[derive(Debug, Clone)]
pub struct Speech {
    /// Where the upload was stored.
    pub stored: PathBuf,
    /// Its media type.
    pub mime: &'static str,
    /// The file as the user knows it.
    pub shown: String,
    /// What was said.
    pub text: Option<String>,
    /// Its language, as eSpeak NG names it.
    pub language: Option<String>,
    /// Whose voice it is.
    pub voice: faceanim_speech::Voice,
}

impl Speech {
    /// The line lip-synced onto `mouth` at 30 fps (recognition takes seconds: call it off the
    /// async threads).
    ///
    /// # Errors
    /// [`ApiError::Invalid`] when the sound cannot be read (naming the file the user picked),
    /// the transcript does not fit it, or lip sync fails.
    pub fn lip_sync(
        &self,
        mouth: &faceanim_speech::Mouth,
    ) -> Result<faceanim_speech::LipSync, ApiError> {
        let sound = faceanim_speech::Sound::read(&self.stored).map_err(|e| {
            ApiError::Invalid(
                e.to_string()
                    .replace(&self.stored.display().to_string(), &self.shown),
            )
        })?;
        if let Some(text) = &self.text {
            faceanim_speech::phones::transcript_words(text, sound.seconds())
                .map_err(|e| ApiError::Invalid(format!("text: {e}")))?;
        }
        faceanim_speech::lip_sync_with(
            &sound,
            self.text.as_deref(),
            self.language.as_deref(),
            mouth,
            30.0,
            faceanim_speech::Recognition::Words,
            self.voice,
        )
        .map_err(|e| ApiError::Invalid(e.to_string()))
    }

    /// The sound to play with its take.
    #[must_use]
    pub fn sound(&self) -> super::open_take::Sound {
        super::open_take::Sound {
            path: self.stored.clone(),
            mime: self.mime,
        }
    }

    /// `error` named as the user knows the file: a message that does not start with its name
    /// gets it in front.
    #[must_use]
    pub fn named(&self, error: ApiError) -> ApiError {
        match error {
            ApiError::Invalid(message) if message.starts_with(self.shown.as_str()) => {
                ApiError::Invalid(message)
            }
            e => ApiError::Invalid(format!("{}: {e}", self.shown)),
        }
    }
}
