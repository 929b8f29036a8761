//! The HTTP/JSON API (documented in `crates/studio/API.md`) and the embedded page.

use std::sync::{Arc, Mutex};

use axum::Router;
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path, Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, put};
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_sketch::project::StrokeFile;
use faceanim_sketch::settings::Settings;
use glam::Vec3;
use serde::Deserialize;
use serde_json::{Value, json};

use crate::capture_api::Both;
use crate::{Studio, lock};

/// The page, embedded at build time so the binary needs nothing beside it.
#[derive(rust_embed::Embed)]
#[folder = "$CARGO_MANIFEST_DIR/../../web"]
struct Page;

type Shared = Arc<Mutex<Studio>>;

/// JSON requests (projects, strokes) may be this large.
const JSON_LIMIT: usize = 16 * 1024 * 1024;
/// Character uploads may be this large.
const CHARACTER_LIMIT: usize = 512 * 1024 * 1024;

/// An error answer: the status and a message naming the field or file.
pub(crate) struct ApiError(pub(crate) StatusCode, pub(crate) String);

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.0, axum::Json(json!({ "error": self.1 }))).into_response()
    }
}

/// `400` with `message`.
pub(crate) fn bad(message: impl Into<String>) -> ApiError {
    ApiError(StatusCode::BAD_REQUEST, message.into())
}

/// A JSON body as `T`, or `400` naming `what` and the problem.
pub(crate) fn json_body<T: serde::de::DeserializeOwned>(
    bytes: &[u8],
    what: &str,
) -> Result<T, ApiError> {
    serde_json::from_slice(bytes).map_err(|e| bad(format!("{what}: {e}")))
}

pub fn router(both: Both, port: u16) -> Router {
    let shared = both.studio.clone();
    let api = Router::new()
        .route("/api/state", get(view))
        .route("/api/character", get(character_info))
        .route("/api/character/anchors", get(anchors))
        .route("/api/project", get(project).put(put_project))
        .route("/api/project/new", post(new_project))
        .route("/api/project/save", post(save))
        .route("/api/project/reopen", post(reopen))
        .route("/api/settings", put(put_settings))
        .route("/api/fps", put(put_fps))
        .route("/api/strokes", post(add_stroke))
        .route(
            "/api/strokes/{index}",
            axum::routing::patch(edit_stroke).delete(delete_stroke),
        )
        .route("/api/candidates", post(candidates))
        .route("/api/undo", post(undo))
        .route("/api/redo", post(redo))
        .route("/api/export.glb", get(export_glb))
        .route("/api/export.json", get(export_clip))
        .route("/api/export.csv", get(export_csv))
        .layer(DefaultBodyLimit::max(JSON_LIMIT))
        .with_state(shared.clone());
    let upload = Router::new()
        .route("/api/character/upload", post(upload_character))
        .layer(DefaultBodyLimit::max(CHARACTER_LIMIT))
        .with_state(both.clone());
    Router::new()
        .merge(api)
        .merge(upload)
        .merge(crate::capture_api::router(both))
        .fallback(get(page))
        .layer(middleware::from_fn(move |request, next| {
            only_local(port, request, next)
        }))
}

/// Refuses requests not addressed to this studio by its own name (DNS rebinding) and
/// cross-site requests from other origins.
async fn only_local(port: u16, request: Request, next: Next) -> Response {
    let allowed_hosts = [
        format!("127.0.0.1:{port}"),
        format!("localhost:{port}"),
        format!("[::1]:{port}"),
    ];
    let host = request
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("");
    if !allowed_hosts.iter().any(|a| a == host) {
        return (
            StatusCode::FORBIDDEN,
            format!("host '{host}' is not this studio"),
        )
            .into_response();
    }
    if let Some(origin) = request.headers().get(header::ORIGIN) {
        let origin = origin.to_str().unwrap_or("");
        if !allowed_hosts
            .iter()
            .any(|a| origin == format!("http://{a}"))
        {
            return (
                StatusCode::FORBIDDEN,
                format!("origin '{origin}' is not this studio"),
            )
                .into_response();
        }
    }
    next.run(request).await
}

async fn page(uri: axum::http::Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    // rust-embed only knows the embedded files: there is no file system to traverse.
    match Page::get(path) {
        Some(file) => {
            let mime = mime_guess::from_path(path).first_or_octet_stream();
            let mut headers = HeaderMap::new();
            if let Ok(value) = HeaderValue::from_str(mime.as_ref()) {
                headers.insert(header::CONTENT_TYPE, value);
            }
            headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
            (headers, file.data.into_owned()).into_response()
        }
        None => (StatusCode::NOT_FOUND, format!("no page '{path}'")).into_response(),
    }
}

async fn view(State(shared): State<Shared>) -> axum::Json<Value> {
    axum::Json(lock(&shared).view())
}

async fn character_info(State(shared): State<Shared>) -> axum::Json<Value> {
    let studio = lock(&shared);
    let c = &studio.character;
    let bounds = c.bounds();
    axum::Json(json!({
        "name": c.name(),
        "vertices": c.vertex_count(),
        "blendshapes": c.blendshapes().iter().map(|b| b.name()).collect::<Vec<_>>(),
        "bounds": { "min": bounds.min.to_array(), "max": bounds.max.to_array() },
        "diagonal": (bounds.max - bounds.min).length(),
    }))
}

async fn anchors(State(shared): State<Shared>) -> axum::Json<Value> {
    axum::Json(lock(&shared).blendshape_anchors())
}

async fn upload_character(
    State(both): State<Both>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let name = uploaded_name(&headers, &body, "uploaded file")?;
    // Import off the async threads: a large character takes a moment.
    let imported =
        tokio::task::spawn_blocking(move || import_gltf(&body, &name, &NoExternalResources))
            .await
            .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
            .map_err(|e| bad(e.to_string()))?;
    let mut studio = lock(&both.studio);
    studio.replace_character(imported.character);
    // An uploaded character's adapter lives beside the project.
    let adapter_path =
        faceanim_adapt::default_adapter_path(studio.project_path.parent(), studio.character.name());
    lock(&both.desk).character_changed(&studio.character, adapter_path);
    Ok(axum::Json(json!({
        "warnings": imported.warnings.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "state": studio.view(),
    })))
}

async fn project(State(shared): State<Shared>) -> axum::Json<Value> {
    axum::Json(serde_json::to_value(lock(&shared).project()).unwrap_or(Value::Null))
}

async fn put_project(
    State(shared): State<Shared>,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let file = Studio::parse(&body, "project").map_err(bad)?;
    let mut studio = lock(&shared);
    studio.change(file).map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

async fn new_project(State(shared): State<Shared>) -> axum::Json<Value> {
    let mut studio = lock(&shared);
    studio.new_project();
    axum::Json(studio.view())
}

async fn save(State(shared): State<Shared>) -> Result<axum::Json<Value>, ApiError> {
    let studio = lock(&shared);
    studio
        .save()
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    Ok(axum::Json(
        json!({ "saved": studio.project_path.display().to_string() }),
    ))
}

async fn reopen(State(shared): State<Shared>) -> Result<axum::Json<Value>, ApiError> {
    let mut studio = lock(&shared);
    studio.reopen().map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

async fn put_settings(
    State(shared): State<Shared>,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let settings: Settings = json_body(&body, "settings")?;
    let mut studio = lock(&shared);
    studio
        .edit(None, |next| {
            next.settings = settings;
            Ok(())
        })
        .map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Fps {
    fps: f32,
}

async fn put_fps(State(shared): State<Shared>, body: Bytes) -> Result<axum::Json<Value>, ApiError> {
    let Fps { fps } = json_body(&body, "fps")?;
    if !(fps.is_finite() && (1.0..=240.0).contains(&fps)) {
        return Err(bad(format!("fps: must be between 1 and 240, got {fps}")));
    }
    let mut studio = lock(&shared);
    studio
        .edit(None, |next| {
            next.fps = fps;
            Ok(())
        })
        .map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

async fn add_stroke(
    State(shared): State<Shared>,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let stroke: StrokeFile = json_body(&body, "stroke")?;
    let mut studio = lock(&shared);
    let index = studio.add_stroke(stroke).map_err(bad)?;
    let mut view = studio.view();
    view["added"] = json!(index);
    Ok(axum::Json(view))
}

/// Fields of a stroke that handles and the timeline edit; a present `null` clears an edit.
const EDITABLE: [&str; 6] = ["start_frame", "duration", "end", "mid", "ease", "symmetry"];

async fn edit_stroke(
    State(shared): State<Shared>,
    Path(index): Path<usize>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let gesture = headers
        .get("x-gesture")
        .and_then(|h| h.to_str().ok())
        .map(str::to_owned);
    let changes: serde_json::Map<String, Value> = json_body(&body, "edit")?;
    if let Some(unknown) = changes.keys().find(|k| !EDITABLE.contains(&k.as_str())) {
        return Err(bad(format!(
            "edit: '{unknown}' cannot be edited (only {})",
            EDITABLE.join(", ")
        )));
    }
    let mut studio = lock(&shared);
    no_such_stroke(&studio, index)?;
    studio
        .edit(gesture, |next| {
            let stroke = &mut next.strokes[index];
            let mut value = serde_json::to_value(&*stroke).map_err(|e| e.to_string())?;
            for (key, change) in changes {
                value[key] = change;
            }
            *stroke = serde_json::from_value(value).map_err(|e| format!("edit: {e}"))?;
            Ok(())
        })
        .map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

/// `404` naming the stroke when the project has no stroke `index`.
fn no_such_stroke(studio: &Studio, index: usize) -> Result<(), ApiError> {
    let count = studio.project().strokes.len();
    if index < count {
        return Ok(());
    }
    Err(ApiError(
        StatusCode::NOT_FOUND,
        format!("no stroke {index} (there are {count})"),
    ))
}

async fn delete_stroke(
    State(shared): State<Shared>,
    Path(index): Path<usize>,
) -> Result<axum::Json<Value>, ApiError> {
    let mut studio = lock(&shared);
    no_such_stroke(&studio, index)?;
    // Later strokes shift down one index; the page redraws everything from the returned state.
    studio
        .edit(None, |next| {
            next.strokes.remove(index);
            Ok(())
        })
        .map_err(bad)?;
    Ok(axum::Json(studio.view()))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CandidateQuery {
    point: [f32; 3],
    #[serde(default)]
    frame: f32,
}

async fn candidates(
    State(shared): State<Shared>,
    body: Bytes,
) -> Result<axum::Json<Value>, ApiError> {
    let query: CandidateQuery = json_body(&body, "candidates")?;
    if query.point.iter().any(|x| !x.is_finite()) || !query.frame.is_finite() {
        return Err(bad("candidates: point and frame must be finite numbers"));
    }
    Ok(axum::Json(
        lock(&shared).candidates(Vec3::from_array(query.point), query.frame),
    ))
}

async fn undo(State(shared): State<Shared>) -> axum::Json<Value> {
    let mut studio = lock(&shared);
    studio.undo();
    axum::Json(studio.view())
}

async fn redo(State(shared): State<Shared>) -> axum::Json<Value> {
    let mut studio = lock(&shared);
    studio.redo();
    axum::Json(studio.view())
}

/// A file the browser saves as `name`.
pub(crate) fn download(bytes: Vec<u8>, mime: &'static str, name: &str) -> Response {
    let disposition = format!("attachment; filename=\"{}\"", name.replace('"', ""));
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(mime));
    if let Ok(value) = HeaderValue::from_str(&disposition) {
        headers.insert(header::CONTENT_DISPOSITION, value);
    }
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    (headers, bytes).into_response()
}

/// The name an upload was sent with (header `x-filename`, else `fallback`); `400` naming it
/// when the file is empty.
pub(crate) fn uploaded_name(
    headers: &HeaderMap,
    body: &[u8],
    fallback: &str,
) -> Result<String, ApiError> {
    let name = headers
        .get("x-filename")
        .and_then(|h| h.to_str().ok())
        .unwrap_or(fallback)
        .to_owned();
    if body.is_empty() {
        return Err(bad(format!("{name}: the file is empty")));
    }
    Ok(name)
}

fn file_stem(studio: &Studio) -> String {
    studio.project_path.file_stem().map_or_else(
        || "faceanim".to_owned(),
        |s| s.to_string_lossy().replace('"', ""),
    )
}

async fn export_glb(State(shared): State<Shared>) -> Result<Response, ApiError> {
    let studio = lock(&shared);
    let (sketch, _) = studio.sketch();
    let name = file_stem(&studio);
    let baked = sketch
        .bake(&name)
        .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?;
    let glb =
        faceanim_rig::export::export_glb(&baked.character, std::slice::from_ref(&baked.animation))
            .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?;
    Ok(download(glb, "model/gltf-binary", &format!("{name}.glb")))
}

async fn export_clip(State(shared): State<Shared>) -> Response {
    let studio = lock(&shared);
    let clip = studio.sketch().0.bake_clip();
    download(
        clip.to_json().into_bytes(),
        "application/json",
        &format!("{}.clip.json", file_stem(&studio)),
    )
}

async fn export_csv(State(shared): State<Shared>) -> Response {
    let studio = lock(&shared);
    let clip = studio.sketch().0.bake_clip();
    let csv = faceanim_anim::livelink::to_csv(&clip);
    download(
        csv.into_bytes(),
        "text/csv",
        &format!("{}.csv", file_stem(&studio)),
    )
}
