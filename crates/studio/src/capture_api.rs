//! The capture mode's HTTP/JSON API (`/api/capture/…`, documented in `crates/studio/API.md`).

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use axum::Router;
use axum::body::Bytes;
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, put};
use faceanim_anim::filter::OneEuro;
use faceanim_export::{Animation, Format};
use faceanim_media::raw::{PixelLayout, YuvMatrix, YuvRange, raw_to_image};
use faceanim_take::{Filtering, TakeError};
use serde::Deserialize;

use crate::capture::{self, CaptureDesk, SharedDesk};
use crate::error::{Answer, ApiError};
use crate::http::{self, Unread, download, json_body, uploaded_name};
use crate::views::{CaptureView, TranscriptView};
use crate::{Studio, lock};

/// `400` with `message`: a request that names a wrong field or file.
fn bad(message: impl Into<String>) -> ApiError {
    ApiError::Invalid(message.into())
}

/// Uploaded videos may be this large.
const INPUT_LIMIT: usize = 2 * 1024 * 1024 * 1024;
/// One webcam frame (RGBA) may be this large (1920×1080×4 and some).
const FRAME_LIMIT: usize = 16 * 1024 * 1024;

#[derive(Clone)]
pub struct Both {
    pub studio: Arc<Mutex<Studio>>,
    pub desk: SharedDesk,
}

impl Both {
    fn studio(&self) -> MutexGuard<'_, Studio> {
        lock(&self.studio)
    }
    fn desk(&self) -> MutexGuard<'_, CaptureDesk> {
        lock(&self.desk)
    }
}

/// Where the page downloads the take in each format.
const EXPORTS: [(&str, Format); 6] = [
    ("/api/capture/session.json", Format::Session),
    ("/api/capture/export.glb", Format::Glb),
    ("/api/capture/export.json", Format::ClipJson),
    ("/api/capture/export.csv", Format::LiveLinkCsv),
    ("/api/capture/export.byoc.csv", Format::SeedCsv),
    ("/api/capture/export.vrma", Format::Vrma),
];

pub fn router(both: Both) -> Router {
    let api = Router::new()
        .route("/api/capture/state", get(view))
        .route("/api/capture/open", post(open_path))
        .route("/api/capture/close", post(close))
        .route("/api/capture/cancel", post(cancel))
        .route("/api/capture/frame/{index}", get(preview))
        .route("/api/capture/sound", get(sound))
        .route("/api/capture/correct", post(correct))
        .route("/api/capture/uncorrect", post(uncorrect))
        .route("/api/capture/keyframe", post(keyframe))
        .route("/api/capture/preference", post(preference))
        .route("/api/capture/undo", post(undo))
        .route("/api/capture/redo", post(redo))
        .route("/api/capture/filtering", put(filtering))
        .route("/api/capture/still", put(still))
        .route("/api/capture/adapter/train", post(train))
        .route("/api/capture/adapter/finetune", post(finetune))
        .route("/api/capture/retarget", post(make_map))
        .route("/api/capture/retarget/row", put(map_row))
        .route("/api/capture/face-points", put(face_points))
        .route("/api/capture/live/start", post(live_start))
        .route("/api/capture/live/stop", post(live_stop))
        .route("/api/capture/live/record", post(live_record))
        .route("/api/capture/live/calibrate", post(live_calibrate))
        .route("/api/capture/transcript", post(transcript))
        .route("/api/capture/voice", put(voice))
        .route("/api/capture/visemes", get(visemes).put(put_visemes))
        .route("/api/capture/voice/calibrate", post(voice_calibrate))
        .route("/api/capture/voice/record", post(voice_record))
        .route("/api/capture/voice/chunk", post(voice_chunk))
        .route("/api/capture/neutral", post(neutral))
        .route("/api/capture/vmc", get(vmc_view))
        .route("/api/capture/vmc/record", post(vmc_record))
        .route("/api/capture/vmc/send", post(vmc_send))
        .route("/api/capture/vmc/neutral", post(vmc_neutral));
    let api = EXPORTS
        .into_iter()
        .fold(api, |api, (path, format)| {
            api.route(
                path,
                get(move |b: State<Both>, q: Query<Layers>| export(b, q, format)),
            )
        })
        .with_state(both.clone());
    let upload = http::body_limit(
        Router::new().route("/api/capture/upload", post(upload)),
        INPUT_LIMIT,
    )
    .with_state(both.clone());
    let live = http::body_limit(
        Router::new().route("/api/capture/live/frame", post(live_frame)),
        FRAME_LIMIT,
    )
    .with_state(both);
    Router::new().merge(api).merge(upload).merge(live)
}

fn state_of(both: &Both) -> axum::Json<CaptureView> {
    let character = both.studio().character.clone();
    axum::Json(both.desk().view(&character))
}

async fn view(State(both): State<Both>) -> axum::Json<CaptureView> {
    state_of(&both)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OpenPath {
    path: PathBuf,
}

async fn open_path(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let OpenPath { path } = json_body(&body, "open")?;
    if !path.exists() {
        return Err(bad(format!("path: {} does not exist", path.display())));
    }
    let character = both.studio().character.clone();
    let shown = path.display().to_string();
    if is_take(&shown) {
        let bytes = faceanim_files::read_bytes(&path)?;
        return open_take(&both, character, bytes.into(), shown).await;
    }
    capture::start_capture(&both.desk, character, path, shown)?;
    Ok(state_of(&both))
}

/// Opens `bytes` (the file `shown`) as the take: a session or clip JSON at once, a GLB, VRM
/// or Live Link CSV read off the async threads (a full-body avatar takes a moment); a clip
/// whose ARKit channels need the character's retarget map after the map is made, as a job.
/// The answer is read under the lock that opened the take, so a file opened at the same
/// moment never answers for this one.
async fn open_take(
    both: &Both,
    character: Arc<faceanim_rig::Character>,
    bytes: Bytes,
    shown: String,
) -> Answer<CaptureView> {
    if !faceanim_export::reopen::reads(&shown) {
        return match capture::TakeJson::read(&bytes, &shown)? {
            capture::TakeJson::Session(session) => {
                let mut desk = both.desk();
                desk.open_session(&character, *session, &shown)?;
                Ok(axum::Json(desk.view(&character)))
            }
            capture::TakeJson::Clip(clip) => {
                capture::open_clip(&both.desk, character, clip, shown, None).map(axum::Json)
            }
        };
    }
    let name = shown.clone();
    let reopened =
        tokio::task::spawn_blocking(move || faceanim_export::reopen::clip_of_file(&name, &bytes))
            .await
            .map_err(|e| ApiError::Internal(e.to_string()))??;
    let opened = format!(
        "Opened {}'s {} as the take.",
        faceanim_rig::excerpt(&shown),
        reopened.what
    );
    capture::open_clip(&both.desk, character, reopened.clip, shown, Some(opened)).map(axum::Json)
}

/// Whether a file named `name` opens as a take (a session or clip JSON, an animated GLB or VRM,
/// a Live Link Face CSV) rather than being footage to capture.
fn is_take(name: &str) -> bool {
    faceanim_export::reopen::reads(name)
        || std::path::Path::new(name)
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// Several photos sent as one sequence: each names the batch, its place and the count; the
/// last one starts reading the folder. Speech may come with its transcript, its language (an
/// eSpeak NG voice name) and whose voice it is, as `faceanim lipsync --text --language
/// --voice` takes them.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Batch {
    batch: Option<String>,
    #[serde(default)]
    index: usize,
    #[serde(default)]
    count: usize,
    text: Option<String>,
    language: Option<String>,
    voice: Option<String>,
}

/// The largest transcript read, in bytes (the command line's limit for `--text`).
const MAX_TRANSCRIPT_BYTES: usize = 1 << 20;

#[derive(Debug, Deserialize)]
struct TranscriptQuery {
    language: Option<String>,
}

/// A transcript file the user picked for the speech field (plain text or a subtitle), read
/// as the command line reads `--text`: Unicode, or the legacy code page its bytes and the
/// language suggest (a Japanese subtitle in Shift_JIS, Notepad's UTF-16), which the page
/// could not tell apart itself.
async fn transcript(
    Query(query): Query<TranscriptQuery>,
    headers: HeaderMap,
    body: Bytes,
) -> Answer<TranscriptView> {
    let language = query.language.as_deref().map(str::trim);
    transcript_of(
        &uploaded_name(&headers, &body, "transcript")?,
        &body,
        language,
    )
    .map(axum::Json)
}

/// The view of transcript `bytes` from the file `name`, in `language` (ignored when empty or
/// too long for one).
fn transcript_of(
    name: &str,
    bytes: &[u8],
    language: Option<&str>,
) -> Result<TranscriptView, ApiError> {
    if bytes.len() > MAX_TRANSCRIPT_BYTES {
        return Err(bad(format!(
            "{name}: {} bytes; a transcript is at most {MAX_TRANSCRIPT_BYTES} bytes",
            bytes.len()
        )));
    }
    let language = language.filter(|l| !l.is_empty() && l.len() <= 40);
    let read =
        faceanim_files::text::decode(bytes, faceanim_files::text::Accept::Legacy { language })
            .map_err(|e| bad(format!("{name}: {e}")))?;
    let note = read.note(
        name,
        language.map(|l| format!("the language {l}")).as_deref(),
    );
    Ok(TranscriptView {
        text: read.text,
        encoding: read.encoding,
        note,
    })
}

async fn upload(
    State(both): State<Both>,
    Query(batch): Query<Batch>,
    headers: HeaderMap,
    body: Bytes,
) -> Answer<CaptureView> {
    let name = uploaded_name(&headers, &body, "upload")?;
    if is_take(&name) {
        if batch.batch.is_some() {
            return Err(bad(format!(
                "{name}: a take opens on its own, not in a sequence of photos"
            )));
        }
        let character = both.studio().character.clone();
        return open_take(&both, character, body, name).await;
    }
    if let Some(mime) = capture::audio_mime(&name) {
        if batch.batch.is_some() {
            return Err(bad(format!(
                "{name}: speech opens on its own, not in a sequence of photos"
            )));
        }
        let text = batch.text.filter(|t| !t.trim().is_empty());
        let language = batch.language.filter(|l| !l.trim().is_empty());
        // Any spelling eSpeak NG or other software gives a language (`en_US.UTF-8`, `sr@latin`)
        // is checked by name below; only a text too long for one is refused here.
        if let Some(language) = &language
            && language.len() > 40
        {
            return Err(bad(format!(
                "language: '{}' is not a language name (en-us, es, ja, …)",
                faceanim_rig::excerpt(language)
            )));
        }
        // As eSpeak NG names it (`ja-JP`: `ja`).
        let language = language
            .map(|l| {
                faceanim_speech::recognition::check_language(&l)
                    .map_err(|e| bad(format!("language: {e}")))
            })
            .transpose()?;
        let voice: faceanim_speech::Voice = match batch.voice.as_deref().map(str::trim) {
            None | Some("") => faceanim_speech::Voice::Auto,
            Some(voice) => voice.parse().map_err(|e| bad(format!("voice: {e}")))?,
        };
        let stored = both.desk().store_upload(&name, &body, None)?;
        let speech = capture::Speech {
            stored,
            mime,
            shown: name,
            text,
            language,
            voice,
        };
        let character = both.studio().character.clone();
        // A rig whose names say nothing of a mouth is reached through its retarget map: made
        // first, as a job, where it has none yet (as `faceanim lipsync` makes it).
        if let Some(view) = capture::speech_after_map(&both.desk, character.clone(), &speech)? {
            return Ok(axum::Json(view));
        }
        let (line, desk) = (speech.clone(), both.desk.clone());
        // Recognition takes seconds (and reading the mouth through an adapter a moment): off
        // the async threads.
        let lip_sync = tokio::task::spawn_blocking(move || {
            let mouth = lock(&desk).mouth(&character)?;
            line.lip_sync(&mouth)
        })
        .await
        .map_err(|e| bad(format!("{}: lip sync stopped: {e}", speech.shown)))?
        .map_err(|e| speech.named(e))?;
        // The answer is this line's take, read under the lock that opened it: a line
        // uploaded at the same moment may open next, but never answers for this one.
        let character = both.studio().character.clone();
        let mut desk = both.desk();
        desk.open_speech(&character, &lip_sync, &speech)?;
        return Ok(axum::Json(desk.view(&character)));
    }
    if batch.batch.is_some() && batch.index >= batch.count {
        return Err(bad(format!(
            "index: {} is not below count {}",
            batch.index, batch.count
        )));
    }
    let path = both
        .desk()
        .store_upload(&name, &body, batch.batch.as_deref())?;
    let (path, shown) = match batch.batch {
        // More photos of the sequence are coming.
        Some(_) if batch.index + 1 < batch.count => return Ok(state_of(&both)),
        Some(_) => {
            let folder = path
                .parent()
                .map(std::path::Path::to_path_buf)
                .unwrap_or(path);
            (folder, format!("{} photos", batch.count))
        }
        None => (path, name),
    };
    let character = both.studio().character.clone();
    capture::start_capture(&both.desk, character, path, shown)?;
    Ok(state_of(&both))
}

async fn close(State(both): State<Both>) -> axum::Json<CaptureView> {
    both.desk().close();
    state_of(&both)
}

async fn cancel(State(both): State<Both>) -> axum::Json<CaptureView> {
    both.desk().cancel();
    state_of(&both)
}

async fn preview(
    State(both): State<Both>,
    Path(index): Path<String>,
) -> Result<Response, ApiError> {
    let index = index.trim_end_matches(".png").parse::<usize>().ok();
    let desk = both.desk();
    let open = desk
        .take()
        .ok_or(ApiError::NoPreview("no capture is open"))?;
    let png = index
        .and_then(|i| open.previews.get(i))
        .ok_or(ApiError::NoPreview("no such frame"))?;
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static("image/png"));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    Ok((headers, png).into_response())
}

/// The open lip-sync take's sound, as uploaded.
async fn sound(State(both): State<Both>) -> Result<Response, ApiError> {
    let sound = both
        .desk()
        .take()
        .and_then(|open| open.sound.clone())
        .ok_or(ApiError::NoPreview("the open take has no sound"))?;
    let bytes =
        std::fs::read(&sound.path).map_err(|e| bad(format!("{}: {e}", sound.path.display())))?;
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(sound.mime));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    Ok((headers, bytes).into_response())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Correction {
    frame: usize,
    name: String,
    value: f32,
    /// Set the left/right partner of `name` (the character's symmetry pairs) to the same value,
    /// in the same edit.
    #[serde(default)]
    mirror: bool,
}

async fn correct(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let c: Correction = json_body(&body, "correction")?;
    let partner = if c.mirror {
        let character = both.studio().character.clone();
        character
            .find_blendshape(&c.name)
            .and_then(|id| character.symmetry().partner(id))
            .and_then(|id| character.blendshape(id))
            .map(|b| b.name().to_owned())
    } else {
        None
    };
    both.desk().edit_take(|s| {
        s.correct(c.frame, &c.name, c.value)?;
        match &partner {
            Some(other) => s.correct(c.frame, other, c.value),
            None => Ok(()),
        }
    })?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Uncorrect {
    frame: usize,
    #[serde(default)]
    name: Option<String>,
}

async fn uncorrect(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let u: Uncorrect = json_body(&body, "uncorrect")?;
    {
        both.desk()
            .edit_take(|s| s.uncorrect(u.frame, u.name.as_deref()))?;
    }
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Keyframe {
    frame: usize,
    on: bool,
}

async fn keyframe(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let k: Keyframe = json_body(&body, "keyframe")?;
    {
        both.desk().edit_take(|s| {
            if k.on {
                s.add_keyframe(k.frame)
            } else {
                s.remove_keyframe(k.frame)
            }
        })?;
    }
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Switch {
    on: bool,
}

async fn preference(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let Switch { on } = json_body(&body, "preference")?;
    {
        both.desk().edit_take(|s| {
            if !on {
                s.clear_preference();
            } else if s.edits.corrections.is_empty() {
                return Err(TakeError::NothingCorrected);
            } else {
                s.apply_preference();
            }
            Ok(())
        })?;
    }
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NeutralFrame {
    /// The frame, or `null` for each part of the face at its calmest frame.
    frame: Option<usize>,
}

async fn neutral(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let NeutralFrame { frame } = json_body(&body, "neutral")?;
    let character = both.studio().character.clone();
    both.desk().set_neutral(&character, frame)?;
    Ok(state_of(&both))
}

async fn live_calibrate(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    both.desk().calibrate_live()?;
    Ok(state_of(&both))
}

async fn undo(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    both.desk().step_history(true)?;
    Ok(state_of(&both))
}

async fn redo(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    both.desk().step_history(false)?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Smoothing {
    min_cutoff: f32,
    beta: f32,
    #[serde(default = "one")]
    derivative_cutoff: f32,
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilteringBody {
    keyframe_every: usize,
    smoothing: Option<Smoothing>,
}

async fn filtering(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let f: FilteringBody = json_body(&body, "filtering")?;
    let smoothing = f.smoothing.map(|s| OneEuro {
        min_cutoff: s.min_cutoff,
        beta: s.beta,
        derivative_cutoff: s.derivative_cutoff,
    });
    both.desk()
        .set_filtering(Filtering::new(f.keyframe_every, smoothing)?)?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Still {
    frames: usize,
}

async fn still(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let Still { frames } = json_body(&body, "still")?;
    both.desk().edit_take(|s| s.set_still_frames(frames))?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Train {
    #[serde(default = "default_samples")]
    samples: usize,
    #[serde(default = "one_u64")]
    seed: u64,
}

fn default_samples() -> usize {
    faceanim_adapt::DEFAULT_SAMPLES
}

fn one_u64() -> u64 {
    1
}

async fn train(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let t: Train = if body.is_empty() {
        Train {
            samples: default_samples(),
            seed: 1,
        }
    } else {
        json_body(&body, "train")?
    };
    let character = both.studio().character.clone();
    capture::start_training(&both.desk, character, t.samples, t.seed)?;
    Ok(state_of(&both))
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct MakeMap {
    /// Make it again (keeping the rows the user set) when there is one.
    #[serde(default)]
    remake: bool,
}

async fn make_map(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let MakeMap { remake } = if body.is_empty() {
        MakeMap::default()
    } else {
        json_body(&body, "retarget")?
    };
    let character = both.studio().character.clone();
    capture::start_map(&both.desk, character, remake, None)?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MapRow {
    /// An ARKit channel.
    channel: String,
    /// The character's shapes that answer to it at 1, with their weights (none: nothing).
    shapes: std::collections::BTreeMap<String, f32>,
}

async fn map_row(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let MapRow { channel, shapes } = json_body(&body, "retarget row")?;
    let character = both.studio().character.clone();
    both.desk().set_map_row(&character, &channel, shapes)?;
    Ok(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FacePointsBody {
    /// Each point marked on the face, in the character's space.
    points: std::collections::BTreeMap<faceanim_fit::FacePoint, [f32; 3]>,
}

/// Keeps the user's marks on the character's face and makes its map again from them.
async fn face_points(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let FacePointsBody { points } = json_body(&body, "face points")?;
    let character = both.studio().character.clone();
    capture::start_map(&both.desk, character, true, Some(points))?;
    Ok(state_of(&both))
}

async fn finetune(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    let character = both.studio().character.clone();
    capture::start_finetune(&both.desk, character)?;
    Ok(state_of(&both))
}

async fn live_start(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    // Loading the models the first time takes a moment: off the async threads.
    let desk = both.desk.clone();
    let character = both.studio().character.clone();
    let started = character.clone();
    tokio::task::spawn_blocking(move || lock(&desk).start_live(&started))
        .await
        .map_err(|e| ApiError::Internal(e.to_string()))??;
    // A rig whose names say nothing follows the webcam through its map: made now, when it
    // has none yet (the page shows the job; the webcam goes on by name until it is there).
    if capture::map_for_live(&both.desk, character) {
        tracing::info!("making the retarget map for the live webcam");
    }
    Ok(state_of(&both))
}

async fn live_stop(State(both): State<Both>) -> axum::Json<CaptureView> {
    both.desk().stop_live();
    state_of(&both)
}

async fn live_record(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let Switch { on } = json_body(&body, "record")?;
    if on {
        both.desk().start_recording()?;
    } else {
        let character = both.studio().character.clone();
        both.desk().stop_recording(&character)?;
    }
    Ok(state_of(&both))
}

async fn vmc_view(State(both): State<Both>) -> axum::Json<Option<crate::views::VmcView>> {
    axum::Json(both.desk().vmc_view())
}

async fn vmc_record(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let Switch { on } = json_body(&body, "record")?;
    if on {
        both.desk().start_vmc_recording()?;
    } else {
        let character = both.studio().character.clone();
        both.desk().stop_vmc_recording(&character)?;
    }
    Ok(state_of(&both))
}

async fn vmc_neutral(
    State(both): State<Both>,
    _unread: Unread,
) -> Answer<Option<crate::views::VmcView>> {
    let desk = both.desk();
    desk.calibrate_phone()?;
    Ok(axum::Json(desk.vmc_view()))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VmcFrame {
    weights: Vec<f32>,
    #[serde(default)]
    head: Option<[f32; 3]>,
    #[serde(default)]
    take: Option<crate::capture::TakeFrame>,
}

/// What the send of one frame came to.
#[derive(serde::Serialize)]
struct VmcSent {
    sent: bool,
}

async fn vmc_send(State(both): State<Both>, body: Bytes) -> Answer<VmcSent> {
    let frame: VmcFrame = json_body(&body, "frame")?;
    let names = both.studio().character.blendshape_names();
    let sent = both
        .desk()
        .send_vmc_frame(&frame.weights, frame.head, frame.take, &names)?;
    Ok(axum::Json(VmcSent { sent }))
}

fn dimension(headers: &HeaderMap, name: &str) -> Result<usize, ApiError> {
    number_header(headers, name, "the size in pixels")
}

/// The required header `name` as a whole number, or a 400 naming it and saying it must give
/// `what`.
fn number_header(headers: &HeaderMap, name: &str, what: &str) -> Result<usize, ApiError> {
    headers
        .get(name)
        .and_then(|h| h.to_str().ok())
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| bad(format!("header {name} must give {what} as a whole number")))
}

/// The optional header `name`, as text; `default` when absent.
fn text_header<'a>(
    headers: &'a HeaderMap,
    name: &str,
    default: &'a str,
) -> Result<&'a str, ApiError> {
    headers.get(name).map_or(Ok(default), |h| {
        h.to_str()
            .map_err(|_| bad(format!("frame: header {name} is not text")))
    })
}

/// The frame's byte layout from its headers: `x-pixel-format` (RGBA by default, or what the
/// browser's `VideoFrame.format` says), and for YUV `x-yuv-matrix` (bt601, the default, or
/// bt709) and `x-yuv-range` (limited, the default, or full).
fn pixel_layout(headers: &HeaderMap) -> Result<PixelLayout, ApiError> {
    let matrix = match text_header(headers, "x-yuv-matrix", "bt601")? {
        "bt601" => YuvMatrix::Bt601,
        "bt709" => YuvMatrix::Bt709,
        other => {
            return Err(bad(format!(
                "frame: header x-yuv-matrix is {other:?}, not bt601 or bt709"
            )));
        }
    };
    let range = match text_header(headers, "x-yuv-range", "limited")? {
        "limited" => YuvRange::Limited,
        "full" => YuvRange::Full,
        other => {
            return Err(bad(format!(
                "frame: header x-yuv-range is {other:?}, not limited or full"
            )));
        }
    };
    PixelLayout::from_names(
        text_header(headers, "x-pixel-format", "RGBA")?,
        matrix,
        range,
    )
    .map_err(|e| bad(format!("frame: header x-pixel-format: {e}")))
}

async fn live_frame(
    State(both): State<Both>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<axum::Json<capture::LiveResult>, ApiError> {
    let width = dimension(&headers, "x-width")?;
    let height = dimension(&headers, "x-height")?;
    if width == 0 || height == 0 || width > 8192 || height > 8192 {
        return Err(bad(format!(
            "frame: {width}×{height} pixels is not a camera frame (1 to 8192 each way)"
        )));
    }
    let layout = pixel_layout(&headers)?;
    let live = both.desk().live_handle();
    let character = both.studio().character.clone();
    let result = tokio::task::spawn_blocking(move || {
        let image = raw_to_image(layout, width, height, &body)
            .map_err(|e| ApiError::Invalid(format!("frame: {e}")))?;
        live.track(&character, image)
    })
    .await
    .map_err(|e| ApiError::Internal(e.to_string()))??;
    Ok(axum::Json(result))
}

// ---------- lip sync's viseme table ----------

/// The viseme table as the page edits it.
#[derive(serde::Serialize)]
struct VisemesView {
    /// Per viseme, ARKit channel → value.
    visemes: std::collections::BTreeMap<String, std::collections::BTreeMap<String, f32>>,
    /// Whether it is the built-in table.
    default: bool,
    /// How lip sync reaches this character: `visemes`, `arkit`, `adapter`, `retarget`, or `null` when it
    /// cannot (`no_mouth` says why).
    route: Option<faceanim_speech::Route>,
    no_mouth: Option<String>,
}

fn visemes_view(both: &Both) -> axum::Json<VisemesView> {
    let character = both.studio().character.clone();
    let desk = both.desk();
    let (table, default) = desk.visemes();
    let route = faceanim_speech::Mouth::of(&character, table)
        .map(|m| m.route)
        .or_else(|e| {
            if desk.has_adapter() {
                Ok(faceanim_speech::Route::Adapter)
            } else if desk
                .map()
                .is_some_and(|m| faceanim_speech::Mouth::through_map(m, table).moves())
            {
                Ok(faceanim_speech::Route::Retarget)
            } else {
                Err(e.to_string())
            }
        });
    axum::Json(VisemesView {
        visemes: table.visemes.clone(),
        default,
        no_mouth: route.as_ref().err().cloned(),
        route: route.ok(),
    })
}

async fn visemes(State(both): State<Both>) -> axum::Json<VisemesView> {
    visemes_view(&both)
}

async fn put_visemes(State(both): State<Both>, body: Bytes) -> Answer<VisemesView> {
    let text = std::str::from_utf8(&body).map_err(|_| bad("visemes: the body is not UTF-8"))?;
    let character = both.studio().character.clone();
    both.desk().set_visemes(&character, text)?;
    Ok(visemes_view(&both))
}

// ---------- the live microphone ----------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VoiceSwitch {
    on: bool,
    delay_ms: Option<u32>,
    /// The language spoken (any name `faceanim lipsync --language` takes).
    language: Option<String>,
}

/// Turns the microphone on (with its delay) or off; while on, sets the delay.
async fn voice(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let VoiceSwitch {
        on,
        delay_ms,
        language,
    } = json_body(&body, "voice")?;
    let character = both.studio().character.clone();
    let awaits_map = {
        let mut desk = both.desk();
        match (on, desk.voice_view()) {
            (false, _) => {
                desk.stop_voice();
                false
            }
            (true, Some(running)) => {
                desk.set_voice_delay(delay_ms.unwrap_or(running.delay_ms))?;
                if let Some(language) = &language {
                    desk.set_voice_language(language)?;
                }
                false
            }
            (true, None) => {
                desk.start_voice(&character, delay_ms.unwrap_or(0), language.as_deref())?
            }
        }
    };
    // A rig whose names say nothing of a mouth: the mouth moves by the map, made now unless
    // it is already being made (the page shows the job).
    if awaits_map && capture::map_for_live(&both.desk, character) {
        tracing::info!("making the retarget map for the microphone");
    }
    Ok(state_of(&both))
}

async fn voice_calibrate(State(both): State<Both>, _unread: Unread) -> Answer<CaptureView> {
    both.desk().calibrate_voice()?;
    Ok(state_of(&both))
}

async fn voice_record(State(both): State<Both>, body: Bytes) -> Answer<CaptureView> {
    let Switch { on } = json_body(&body, "record")?;
    let character = both.studio().character.clone();
    both.desk().record_voice(&character, on)?;
    Ok(state_of(&both))
}

/// A chunk of the microphone: 16-bit little-endian samples at 16 kHz (`x-sample-rate` says
/// so), at most a second of them.
async fn voice_chunk(
    headers: HeaderMap,
    State(both): State<Both>,
    body: Bytes,
) -> Answer<capture::VoiceResult> {
    let rate = number_header(&headers, "x-sample-rate", "the sound's samples per second")?;
    if rate != capture::VOICE_RATE {
        return Err(bad(format!(
            "x-sample-rate: {rate} Hz; the microphone is sent at {} Hz",
            capture::VOICE_RATE
        )));
    }
    if !body.len().is_multiple_of(2) || body.len() > 2 * capture::VOICE_RATE {
        return Err(bad(format!(
            "chunk: {} bytes is not 16-bit samples of at most a second",
            body.len()
        )));
    }
    let samples: Vec<i16> = body
        .chunks_exact(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .collect();
    let voice = both.desk().voice_handle();
    Ok(axum::Json(voice.hear(&samples)))
}

// ---------- exports ----------

/// Which layers an export of the take holds.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Layers {
    /// The sketch's strokes over the take (`?sketch=false`: the take alone, as the page shows
    /// it with "Sketch over the take" off).
    #[serde(default = "layered")]
    sketch: bool,
}

fn layered() -> bool {
    true
}

/// The take in `format`, with the sketch's strokes layered on top (`faceanim_take::layer`)
/// unless `?sketch=false`: the GLB carries the strokes' baked arcs and exaggerations and the
/// captured head turn; the seed's CSV and the session are the take's own.
async fn export(
    State(both): State<Both>,
    Query(layers): Query<Layers>,
    format: Format,
) -> Result<Response, ApiError> {
    // What the export needs of the take, read under the desk's lock (the session itself only
    // for the formats that are the session's own).
    let (take_clip, arkit, session, name, opening) = {
        let desk = both.desk();
        let open = desk.open_take()?;
        let session = &open.take.session;
        (
            session.clip(),
            session.arkit_clip(),
            format.needs_session().then(|| session.clone()),
            open.name(),
            // What opens the mouth through the map, for the jaw bone's turn.
            desk.map().and_then(faceanim_export::bones::jaw_opening),
        )
    };
    let studio = both.studio();
    let (sketch, _) = studio.sketch();
    // The sketch's corrective targets matter to the GLB only; the rest needs its weights.
    let (sketch_animation, baked_character) =
        if !layers.sketch || studio.project().strokes.is_empty() {
            (None, None)
        } else if format == Format::Glb {
            let baked = sketch.bake(&name)?;
            (Some(baked.animation), Some(baked.character))
        } else {
            let weights = faceanim_rig::animation::MorphAnimation {
                name: name.clone(),
                times: Vec::new(),
                weights: sketch.bake_clip().frames,
                rotations: None,
            };
            (Some(weights), None)
        };
    let character = baked_character.as_ref().unwrap_or(&studio.character);
    let animation = Animation::from_take(
        Some(character),
        &take_clip,
        arkit,
        session.as_ref(),
        sketch_animation.as_ref(),
        &name,
    )?
    .with_opening(opening);
    let exported = faceanim_export::export(format, &animation)?;
    let extension = format.extension_for(Some(&studio.character));
    Ok(download(format, extension, &name, exported))
}
