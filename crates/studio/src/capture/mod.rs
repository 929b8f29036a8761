//! Capture mode: a face video, photos or the webcam drive the character (seed 003's toolkit).
//!
//! The domain — the take with its undo, estimates by name or by adapter, the layering rule — is
//! `faceanim-take`'s. This module keeps what a server needs around it: the open take with a
//! small preview of every input frame, the character's adapter (loaded from beside the
//! character, trained or fine-tuned from the page), the long jobs (reading a video, rendering
//! and training) with their progress and cancel flag, and live webcam tracking with recording.

//!
//! The desk ([`CaptureDesk`], in `desk`) owns the state and its methods; the parts it holds —
//! the webcam (`live`), VMC (`vmc`), the microphone (`voice`), the open take with its previews
//! (`open_take`), an uploaded line of speech (`speech`), a long job (`job`) and the face models
//! (`models`) — each keep their own state type and never reach back into the desk.

mod desk;
mod job;
mod live;
mod models;
mod open_take;
mod speech;
mod vmc;
mod voice;

pub use desk::jobs::{open_clip, speech_after_map, start_capture, start_finetune, start_training};
pub use desk::retarget::{map_for_listeners, map_for_live, start_map};
pub use desk::{CaptureDesk, SharedDesk};
pub use live::{LiveHandle, LiveResult};
pub use open_take::{OpenTake, Previews, Sound, TakeJson, audio_mime};
pub use speech::Speech;
pub use vmc::{Listen, TakeFrame, VmcConfig};
pub use voice::{RATE as VOICE_RATE, VoiceHandle, VoiceResult};
