//! The take being edited, with what the server keeps beside it: its frames' previews and its
//! sound.

use std::sync::atomic::{AtomicU64, Ordering};

use faceanim_take::Take;

use crate::error::ApiError;

/// Input previews are at most this tall: enough to judge an expression beside the character.
pub(super) const PREVIEW_HEIGHT: usize = 360;
/// Live takes keep smaller previews, made between camera frames.
pub(super) const LIVE_PREVIEW_HEIGHT: usize = 240;

/// A take file in JSON: a session (`faceanim track --session`, this tab's export), or a clip
/// (`faceanim track -o take.json`, `lipsync`, this tab's Clip JSON), which opens as a take of
/// its frames.
#[derive(Debug)]
pub enum TakeJson {
    /// A session, with its estimates, corrections and keyframes.
    Session(Box<faceanim_take::Session>),
    /// A clip of weights by name.
    Clip(faceanim_anim::Clip),
}

impl TakeJson {
    /// Reads `bytes` of the file `shown`: a session, else a clip.
    ///
    /// # Errors
    /// [`ApiError::Session`] naming `shown` (with why it is not a session) when it is neither.
    pub fn read(bytes: &[u8], shown: &str) -> Result<TakeJson, ApiError> {
        match faceanim_take::Session::from_json(bytes) {
            Ok(session) => Ok(TakeJson::Session(Box::new(session))),
            Err(source) => faceanim_anim::Clip::from_json(bytes)
                .map(TakeJson::Clip)
                .map_err(|_| ApiError::Session {
                    what: faceanim_rig::excerpt(shown).into_owned(),
                    source,
                }),
        }
    }
}

/// A take's sound: the uploaded file as it came, for the page to play.
#[derive(Debug, Clone)]
pub struct Sound {
    /// Where the upload was stored.
    pub path: std::path::PathBuf,
    /// Its media type.
    pub mime: &'static str,
}

/// The media type of an audio file by its name; `None` for a file that is not sound.
#[must_use]
pub fn audio_mime(name: &str) -> Option<&'static str> {
    let extension = std::path::Path::new(name)
        .extension()?
        .to_string_lossy()
        .to_ascii_lowercase();
    Some(match extension.as_str() {
        "wav" => "audio/wav",
        "mp3" => "audio/mpeg",
        "ogg" | "oga" | "opus" => "audio/ogg",
        "flac" => "audio/flac",
        "m4a" | "aac" => "audio/mp4",
        _ => return None,
    })
}

/// The take being edited, with what the server keeps beside it.
#[derive(Debug)]
pub struct OpenTake {
    /// The take: session, estimates' source, undo history.
    pub take: Take,
    /// A PNG preview of each input frame.
    pub previews: Previews,
    /// The speech a lip-sync take was made from, played with it.
    pub sound: Option<Sound>,
    /// Different for every take this process opened: the page tells takes apart by it (two
    /// uploads of `clip.mp4` are different takes).
    id: u64,
}

impl OpenTake {
    pub(super) fn new(take: Take, previews: Previews) -> OpenTake {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        OpenTake {
            take,
            previews,
            sound: None,
            id: NEXT.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// The take with the speech it was made from.
    #[must_use]
    pub(super) fn with_sound(self, sound: Sound) -> OpenTake {
        OpenTake {
            sound: Some(sound),
            ..self
        }
    }

    /// Tells this take from every other this process opened.
    #[must_use]
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The name downloads get: the input's file stem.
    #[must_use]
    pub fn name(&self) -> String {
        std::path::Path::new(&self.take.session.source)
            .file_stem()
            .map_or_else(
                || "capture".to_owned(),
                |s| s.to_string_lossy().into_owned(),
            )
    }
}

/// A take's frame previews: PNG files in a private temporary folder (a long video's previews
/// would not fit in memory), removed with the take.
#[derive(Debug, Default)]
pub struct Previews {
    dir: Option<tempfile::TempDir>,
    count: usize,
}

impl Previews {
    /// An empty set, its folder made on the first frame.
    #[must_use]
    pub fn new() -> Previews {
        Previews::default()
    }

    /// Adds the next frame's preview.
    ///
    /// # Errors
    /// [`ApiError::Scratch`] naming the file.
    pub fn push(&mut self, png: &[u8]) -> Result<(), ApiError> {
        let dir = private_dir(&mut self.dir, "faceanim-previews-", "previews")?;
        let path = dir.join(format!("{}.png", self.count));
        std::fs::write(&path, png).map_err(|source| ApiError::Scratch {
            what: path.display().to_string(),
            source,
        })?;
        self.count += 1;
        Ok(())
    }

    /// Adds the next frame's preview: `image` scaled to at most `height` pixels tall.
    ///
    /// # Errors
    /// [`ApiError::Scratch`] naming the file, or [`ApiError::Internal`] if encoding fails.
    pub fn push_image(
        &mut self,
        image: &faceanim_media::Image,
        height: usize,
    ) -> Result<(), ApiError> {
        let png = image
            .preview(height)
            .to_png()
            .map_err(|e| ApiError::Internal(format!("encoding a preview: {e}")))?;
        self.push(&png)
    }

    /// How many frames have a preview (the first ones).
    #[must_use]
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether no frame has a preview.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The previews of frames `chosen` (indices into these, repeated where a frame is), in
    /// that order, linked rather than copied where the folder allows; frames without a preview
    /// end them.
    ///
    /// # Errors
    /// [`ApiError::Scratch`] naming the file.
    pub fn chosen(&self, chosen: &[usize]) -> Result<Previews, ApiError> {
        let mut previews = Previews::new();
        let Some(from) = self.dir.as_ref() else {
            return Ok(previews);
        };
        for &index in chosen.iter().take_while(|&&i| i < self.count) {
            let source = from.path().join(format!("{index}.png"));
            let dir = private_dir(&mut previews.dir, "faceanim-previews-", "previews")?;
            let path = dir.join(format!("{}.png", previews.count));
            std::fs::hard_link(&source, &path)
                .or_else(|_| std::fs::copy(&source, &path).map(drop))
                .map_err(|source| ApiError::Scratch {
                    what: path.display().to_string(),
                    source,
                })?;
            previews.count += 1;
        }
        Ok(previews)
    }

    /// Frame `index`'s preview, if there is one.
    #[must_use]
    pub fn get(&self, index: usize) -> Option<Vec<u8>> {
        let dir = self.dir.as_ref()?;
        (index < self.count)
            .then(|| std::fs::read(dir.path().join(format!("{index}.png"))).ok())
            .flatten()
    }
}

/// The private temporary folder kept in `slot`, made on first use (named `prefix…`; `what` it
/// holds names it in the error).
pub(super) fn private_dir<'a>(
    slot: &'a mut Option<tempfile::TempDir>,
    prefix: &str,
    what: &str,
) -> Result<&'a std::path::Path, ApiError> {
    let dir = match slot.take() {
        Some(dir) => dir,
        None => crate::scratch::private_dir(prefix).map_err(|source| ApiError::Scratch {
            what: format!("making a folder for {what}"),
            source,
        })?,
    };
    Ok(slot.insert(dir).path())
}
