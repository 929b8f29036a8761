//! The capture mode's HTTP/JSON API (`/api/capture/…`, documented in `crates/studio/API.md`).

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use axum::Router;
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, put};
use faceanim_anim::Clip;
use faceanim_anim::filter::OneEuro;
use faceanim_media::raw::{PixelLayout, YuvMatrix, YuvRange, raw_to_image};
use faceanim_rig::export::MorphAnimation;
use serde::Deserialize;
use serde_json::Value;

use crate::api::{ApiError, bad, download, json_body, uploaded_name};
use crate::capture::{self, CaptureDesk, SharedDesk};
use crate::{Studio, lock};

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

pub fn router(both: Both) -> Router {
    let api = Router::new()
        .route("/api/capture/state", get(view))
        .route("/api/capture/open", post(open_path))
        .route("/api/capture/close", post(close))
        .route("/api/capture/cancel", post(cancel))
        .route("/api/capture/frame/{index}", get(preview))
        .route("/api/capture/correct", post(correct))
        .route("/api/capture/uncorrect", post(uncorrect))
        .route("/api/capture/keyframe", post(keyframe))
        .route("/api/capture/preference", post(preference))
        .route("/api/capture/undo", post(undo))
        .route("/api/capture/redo", post(redo))
        .route("/api/capture/filtering", put(filtering))
        .route("/api/capture/adapter/train", post(train))
        .route("/api/capture/adapter/finetune", post(finetune))
        .route("/api/capture/live/start", post(live_start))
        .route("/api/capture/live/stop", post(live_stop))
        .route("/api/capture/live/record", post(live_record))
        .route("/api/capture/session.json", get(export_session))
        .route("/api/capture/export.glb", get(export_glb))
        .route("/api/capture/export.json", get(export_clip))
        .route("/api/capture/export.csv", get(export_csv))
        .route("/api/capture/export.byoc.csv", get(export_seed_csv))
        .with_state(both.clone());
    let upload = Router::new()
        .route("/api/capture/upload", post(upload))
        .layer(DefaultBodyLimit::max(INPUT_LIMIT))
        .with_state(both.clone());
    let live = Router::new()
        .route("/api/capture/live/frame", post(live_frame))
        .layer(DefaultBodyLimit::max(FRAME_LIMIT))
        .with_state(both);
    Router::new().merge(api).merge(upload).merge(live)
}

fn state_of(both: &Both) -> Value {
    let character = both.studio().character.clone();
    both.desk().view(&character)
}

async fn view(State(both): State<Both>) -> axum::Json<Value> {
    axum::Json(state_of(&both))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OpenPath {
    path: PathBuf,
}

async fn open_path(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let OpenPath { path } = json_body(&body, "open")?;
    if !path.exists() {
        return Err(bad(format!("path: {} does not exist", path.display())));
    }
    let character = both.studio().character.clone();
    let shown = path.display().to_string();
    if is_session(&shown) {
        let bytes = std::fs::read(&path).map_err(|e| bad(format!("{shown}: {e}")))?;
        both.desk()
            .open_session(&character, &bytes, &shown)
            .map_err(bad)?;
    } else {
        capture::start_capture(&both.desk, character, path, shown).map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

/// Whether a file named `name` is a session (JSON) rather than a video or an image.
fn is_session(name: &str) -> bool {
    std::path::Path::new(name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// Several photos sent as one sequence: each names the batch, its place and the count; the
/// last one starts reading the folder.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Batch {
    batch: Option<String>,
    #[serde(default)]
    index: usize,
    #[serde(default)]
    count: usize,
}

async fn upload(
    State(both): State<Both>,
    Query(batch): Query<Batch>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let name = uploaded_name(&headers, &body, "upload")?;
    if is_session(&name) {
        if batch.batch.is_some() {
            return Err(bad(format!(
                "{name}: a session opens on its own, not in a sequence of photos"
            )));
        }
        let character = both.studio().character.clone();
        both.desk()
            .open_session(&character, &body, &name)
            .map_err(bad)?;
        return Ok(axum::Json(state_of(&both)));
    }
    if batch.batch.is_some() && batch.index >= batch.count {
        return Err(bad(format!(
            "index: {} is not below count {}",
            batch.index, batch.count
        )));
    }
    let path = both
        .desk()
        .store_upload(&name, &body, batch.batch.as_deref())
        .map_err(bad)?;
    let (path, shown) = match batch.batch {
        // More photos of the sequence are coming.
        Some(_) if batch.index + 1 < batch.count => return Ok(axum::Json(state_of(&both))),
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
    capture::start_capture(&both.desk, character, path, shown).map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
}

async fn close(State(both): State<Both>) -> axum::Json<Value> {
    both.desk().close();
    axum::Json(state_of(&both))
}

async fn cancel(State(both): State<Both>) -> axum::Json<Value> {
    both.desk().cancel();
    axum::Json(state_of(&both))
}

async fn preview(State(both): State<Both>, Path(index): Path<String>) -> Response {
    let index = index.trim_end_matches(".png").parse::<usize>().ok();
    let desk = both.desk();
    match (
        index.and_then(|i| desk.take().map(|t| t.previews.get(i))),
        desk.take(),
    ) {
        (Some(Some(png)), _) => {
            let mut headers = HeaderMap::new();
            headers.insert(header::CONTENT_TYPE, HeaderValue::from_static("image/png"));
            headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
            (headers, png).into_response()
        }
        (_, None) => (StatusCode::NOT_FOUND, "no capture is open").into_response(),
        _ => (StatusCode::NOT_FOUND, "no such frame").into_response(),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Correction {
    frame: usize,
    name: String,
    value: f32,
}

async fn correct(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let c: Correction = json_body(&body, "correction")?;
    {
        both.desk()
            .edit_take(|s| {
                s.correct(c.frame, &c.name, c.value)
                    .map_err(|e| e.to_string())
            })
            .map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Uncorrect {
    frame: usize,
    #[serde(default)]
    name: Option<String>,
}

async fn uncorrect(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let u: Uncorrect = json_body(&body, "uncorrect")?;
    {
        both.desk()
            .edit_take(|s| {
                s.uncorrect(u.frame, u.name.as_deref())
                    .map_err(|e| e.to_string())
            })
            .map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Keyframe {
    frame: usize,
    on: bool,
}

async fn keyframe(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let k: Keyframe = json_body(&body, "keyframe")?;
    {
        both.desk()
            .edit_take(|s| {
                if k.on {
                    s.add_keyframe(k.frame)
                } else {
                    s.remove_keyframe(k.frame)
                }
                .map_err(|e| e.to_string())
            })
            .map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Switch {
    on: bool,
}

async fn preference(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let Switch { on } = json_body(&body, "preference")?;
    {
        both.desk()
            .edit_take(|s| {
                if !on {
                    s.clear_preference();
                } else if s.corrections.is_empty() {
                    return Err("preference: correct at least one frame first".into());
                } else {
                    s.apply_preference();
                }
                Ok(())
            })
            .map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

async fn undo(State(both): State<Both>) -> Result<axum::Json<Value>, ApiError> {
    both.desk().step_history(true).map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
}

async fn redo(State(both): State<Both>) -> Result<axum::Json<Value>, ApiError> {
    both.desk().step_history(false).map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
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
struct Filtering {
    keyframe_every: usize,
    smoothing: Option<Smoothing>,
}

async fn filtering(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let f: Filtering = json_body(&body, "filtering")?;
    let smoothing = f.smoothing.map(|s| OneEuro {
        min_cutoff: s.min_cutoff,
        beta: s.beta,
        derivative_cutoff: s.derivative_cutoff,
    });
    both.desk()
        .set_filtering(f.keyframe_every, smoothing)
        .map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
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
    capture::DEFAULT_SAMPLES
}

fn one_u64() -> u64 {
    1
}

async fn train(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let t: Train = if body.is_empty() {
        Train {
            samples: default_samples(),
            seed: 1,
        }
    } else {
        json_body(&body, "train")?
    };
    let character = both.studio().character.clone();
    capture::start_training(&both.desk, character, t.samples, t.seed).map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
}

async fn finetune(State(both): State<Both>) -> Result<axum::Json<Value>, ApiError> {
    let character = both.studio().character.clone();
    capture::start_finetune(&both.desk, character).map_err(bad)?;
    Ok(axum::Json(state_of(&both)))
}

async fn live_start(State(both): State<Both>) -> Result<axum::Json<Value>, ApiError> {
    // Loading the models the first time takes a moment: off the async threads.
    let desk = both.desk.clone();
    let character = both.studio().character.clone();
    tokio::task::spawn_blocking(move || lock(&desk).start_live(&character))
        .await
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    Ok(axum::Json(state_of(&both)))
}

async fn live_stop(State(both): State<Both>) -> axum::Json<Value> {
    both.desk().stop_live();
    axum::Json(state_of(&both))
}

async fn live_record(State(both): State<Both>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let Switch { on } = json_body(&body, "record")?;
    if on {
        both.desk().start_recording().map_err(bad)?;
    } else {
        let character = both.studio().character.clone();
        both.desk().stop_recording(&character).map_err(bad)?;
    }
    Ok(axum::Json(state_of(&both)))
}

fn dimension(headers: &HeaderMap, name: &str) -> Result<usize, ApiError> {
    headers
        .get(name)
        .and_then(|h| h.to_str().ok())
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| bad(format!("frame: header {name} must give the size in pixels")))
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
        let image =
            raw_to_image(layout, width, height, &body).map_err(|e| format!("frame: {e}"))?;
        live.track(&character, image)
    })
    .await
    .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
    .map_err(bad)?;
    Ok(axum::Json(result))
}

// ---------- exports ----------

fn take_name(desk: &CaptureDesk) -> String {
    desk.take()
        .map(|t| {
            std::path::Path::new(&t.session.source)
                .file_stem()
                .map_or_else(
                    || "capture".to_owned(),
                    |s| s.to_string_lossy().into_owned(),
                )
        })
        .unwrap_or_else(|| "capture".into())
}

/// The take's clip with the sketch's strokes layered on top, and its name.
fn layered_clip(both: &Both) -> Result<(Clip, String), ApiError> {
    let desk = both.desk();
    let take = desk.take().ok_or_else(|| bad("no capture is open"))?;
    let base = take.session.clip();
    let name = take_name(&desk);
    drop(desk);
    let studio = both.studio();
    let sketch = studio.sketch().0.bake_clip();
    let has_strokes = !studio.project().strokes.is_empty();
    let clip = if has_strokes {
        capture::layered_weights(&base, &sketch.frames)
    } else {
        base
    };
    Ok((clip, name))
}

async fn export_clip(State(both): State<Both>) -> Result<Response, ApiError> {
    let (clip, name) = layered_clip(&both)?;
    Ok(download(
        clip.to_json().into_bytes(),
        "application/json",
        &format!("{name}.clip.json"),
    ))
}

async fn export_csv(State(both): State<Both>) -> Result<Response, ApiError> {
    let (clip, name) = layered_clip(&both)?;
    Ok(download(
        faceanim_anim::livelink::to_csv(&clip).into_bytes(),
        "text/csv",
        &format!("{name}.csv"),
    ))
}

async fn export_seed_csv(State(both): State<Both>) -> Result<Response, ApiError> {
    let desk = both.desk();
    let take = desk.take().ok_or_else(|| bad("no capture is open"))?;
    Ok(download(
        take.session.to_seed_csv().into_bytes(),
        "text/csv",
        &format!("{}.byoc.csv", take_name(&desk)),
    ))
}

async fn export_session(State(both): State<Both>) -> Result<Response, ApiError> {
    let desk = both.desk();
    let take = desk.take().ok_or_else(|| bad("no capture is open"))?;
    Ok(download(
        take.session.to_json().into_bytes(),
        "application/json",
        &format!("{}.session.json", take_name(&desk)),
    ))
}

/// The character with the sketch's baked targets and one animation: the take's weights plus
/// the strokes' (clamped), the strokes' arcs and exaggerations, and the captured head turn.
async fn export_glb(State(both): State<Both>) -> Result<Response, ApiError> {
    let (base, name) = {
        let desk = both.desk();
        let take = desk.take().ok_or_else(|| bad("no capture is open"))?;
        (take.session.clip(), take_name(&desk))
    };
    let studio = both.studio();
    let internal = |e: String| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e);
    let retarget = base
        .retarget(&studio.character, &name)
        .map_err(|e| internal(e.to_string()))?;
    let (sketch, _) = studio.sketch();
    let baked = sketch.bake(&name).map_err(|e| internal(e.to_string()))?;
    let animation = layer_animation(
        &retarget.animation,
        &baked.animation,
        studio.character.blendshapes().len(),
        base.fps,
    );
    let glb = faceanim_rig::export::export_glb(&baked.character, std::slice::from_ref(&animation))
        .map_err(|e| internal(e.to_string()))?;
    Ok(download(glb, "model/gltf-binary", &format!("{name}.glb")))
}

/// `base` drives the character's own targets; `sketch` drives them too (added, clamped) and
/// the extra baked targets after them. Each holds its last key beyond its end.
fn layer_animation(
    base: &MorphAnimation,
    sketch: &MorphAnimation,
    own: usize,
    fps: f32,
) -> MorphAnimation {
    let frames = base.weights.len().max(sketch.weights.len()).max(1);
    let targets = sketch.weights.first().map_or(own, Vec::len).max(own);
    let at = |rows: &[Vec<f32>], f: usize| rows.get(f.min(rows.len().saturating_sub(1))).cloned();
    let weights = (0..frames)
        .map(|f| {
            let mut row = vec![0.0; targets];
            if let Some(b) = at(&base.weights, f) {
                for (w, v) in row.iter_mut().zip(b) {
                    *w = v;
                }
            }
            if let Some(s) = at(&sketch.weights, f) {
                for (i, (w, v)) in row.iter_mut().zip(s).enumerate() {
                    *w = if i < own { (*w + v).clamp(0.0, 1.0) } else { v };
                }
            }
            row
        })
        .collect();
    let rotations = base.rotations.as_ref().map(|r| {
        (0..frames)
            .map(|f| {
                r.get(f.min(r.len().saturating_sub(1)))
                    .copied()
                    .unwrap_or([0.0, 0.0, 0.0, 1.0])
            })
            .collect()
    });
    MorphAnimation {
        name: base.name.clone(),
        times: (0..frames).map(|f| f as f32 / fps.max(1e-3)).collect(),
        weights,
        rotations,
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "sums of exact binary fractions")]
mod tests {
    use super::*;

    #[test]
    fn the_export_layers_the_sketch_over_the_take_and_keeps_the_head_turn() {
        let base = MorphAnimation {
            name: "take".into(),
            times: vec![0.0, 0.5],
            weights: vec![vec![0.5, 0.25], vec![0.75, 0.25]],
            rotations: Some(vec![[0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0]]),
        };
        // Two own targets and one baked exaggeration target; three frames.
        let sketch = MorphAnimation {
            name: "sketch".into(),
            times: vec![0.0, 0.5, 1.0],
            weights: vec![
                vec![0.0, 0.0, 0.0],
                vec![0.5, 0.5, 0.5],
                vec![0.25, 0.0, 1.0],
            ],
            rotations: None,
        };
        let layered = layer_animation(&base, &sketch, 2, 2.0);
        assert_eq!(layered.times, vec![0.0, 0.5, 1.0]);
        assert_eq!(
            layered.weights,
            vec![
                vec![0.5, 0.25, 0.0],
                vec![1.0, 0.75, 0.5],
                vec![1.0, 0.25, 1.0],
            ]
        );
        assert_eq!(
            layered.rotations,
            Some(vec![
                [0.0, 0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0]
            ])
        );
    }
}
