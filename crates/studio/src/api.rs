//! The HTTP/JSON API of the sketch (documented in `crates/studio/API.md`) and the embedded
//! page. Answers are the view types of [`crate::views`]; errors are [`ApiError`]s.

use std::sync::{Arc, Mutex};

use axum::Router;
use axum::body::Bytes;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, put};
use faceanim_export::{Animation, Format};
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_sketch::project::StrokeFile;
use faceanim_sketch::settings::Settings;
use glam::Vec3;
use serde::{Deserialize, Deserializer};

use crate::capture_api::Both;
use crate::error::{Answer, ApiError};
use crate::http::{self, Unread, download, json_body, uploaded_name};
use crate::views::{
    AnchorView, CandidatesView, CharacterView, GeneratedView, SavedView, StateView, UploadView,
};
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

pub fn router(both: Both, port: u16) -> Router {
    let shared = both.studio.clone();
    let api = http::body_limit(
        Router::new()
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
            .route(
                "/api/export.glb",
                get(|s: State<Shared>| export(s, Format::Glb)),
            )
            .route("/api/view.glb", get(view_glb))
            .route(
                "/api/export.json",
                get(|s: State<Shared>| export(s, Format::ClipJson)),
            )
            .route(
                "/api/export.csv",
                get(|s: State<Shared>| export(s, Format::LiveLinkCsv)),
            )
            .route(
                "/api/export.vrma",
                get(|s: State<Shared>| export(s, Format::Vrma)),
            ),
        JSON_LIMIT,
    )
    .with_state(shared.clone());
    let upload = http::body_limit(
        Router::new()
            .route("/api/character/upload", post(upload_character))
            .route("/api/character/generate-shapes", post(generate_shapes)),
        CHARACTER_LIMIT,
    )
    .with_state(both.clone());
    Router::new()
        .merge(api)
        .merge(upload)
        .merge(crate::capture_api::router(both))
        .fallback(get(page))
        .layer(middleware::from_fn(http::catch_panics))
        .layer(middleware::from_fn(http::json_errors))
        .layer(middleware::from_fn(move |request, next| {
            http::only_local(port, request, next)
        }))
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
        None => http::error_answer(
            StatusCode::NOT_FOUND,
            format!("no page '{}'", faceanim_rig::excerpt(path)),
        ),
    }
}

async fn view(State(shared): State<Shared>) -> axum::Json<StateView> {
    axum::Json(lock(&shared).view())
}

async fn character_info(State(shared): State<Shared>) -> axum::Json<CharacterView> {
    axum::Json(CharacterView::of(&lock(&shared).character))
}

async fn anchors(State(shared): State<Shared>) -> axum::Json<Vec<AnchorView>> {
    axum::Json(lock(&shared).blendshape_anchors())
}

async fn upload_character(
    State(both): State<Both>,
    headers: HeaderMap,
    body: Bytes,
) -> Answer<UploadView> {
    let name = uploaded_name(&headers, &body, "uploaded file")?;
    // Import off the async threads: a large character takes a moment.
    let imported =
        tokio::task::spawn_blocking(move || import_gltf(&body, &name, &NoExternalResources))
            .await
            .map_err(|e| ApiError::Internal(e.to_string()))??;
    Ok(axum::Json(UploadView {
        warnings: imported.warnings.iter().map(ToString::to_string).collect(),
        state: open_character(&both, imported.character),
    }))
}

/// Generates ARKit's blendshapes on a character that has none (`faceanim generate-shapes` with
/// the default templates), writes the result beside the project as `NAME.shapes.glb` (the
/// user's own file is never written), and opens it as the character.
async fn generate_shapes(State(both): State<Both>, _unread: Unread) -> Answer<GeneratedView> {
    let (character, folder) = {
        let studio = lock(&both.studio);
        (
            Arc::clone(&studio.character),
            studio.project_path.parent().map_or_else(
                || std::path::PathBuf::from("."),
                std::path::Path::to_path_buf,
            ),
        )
    };
    // Where the user marked the face, when the face model could not find it.
    let points = lock(&both.desk).face_points().cloned();
    let (imported, path, shapes) = tokio::task::spawn_blocking(move || {
        let models =
            faceanim_track::FaceModels::load().map_err(|e| ApiError::Models(e.to_string()))?;
        let templates = faceanim_fit::Template::Realistic.characters()?;
        let templates: Vec<&faceanim_rig::Character> = templates.iter().collect();
        let (with, generated) = faceanim_fit::with_generated_shapes(
            &character,
            &templates,
            &models,
            &faceanim_fit::Options { only: None, points },
        )?;
        let shapes: Vec<String> = generated
            .shapes
            .iter()
            .map(|s| s.name().to_owned())
            .collect();
        let bytes = faceanim_export::glb(&with, None)?;
        let name = format!("{}.shapes.glb", character.name());
        let path = folder.join(&name);
        faceanim_files::write_atomic(&path, &bytes)?;
        let imported = import_gltf(&bytes, &name, &NoExternalResources)?;
        Ok::<_, ApiError>((imported, path, shapes))
    })
    .await
    .map_err(|e| ApiError::Internal(e.to_string()))??;
    Ok(axum::Json(GeneratedView {
        written: path.display().to_string(),
        shapes,
        state: open_character(&both, imported.character),
    }))
}

/// Makes `character` the studio's (an empty project on it) and tells capture; its adapter
/// lives beside the project. The new state.
fn open_character(both: &Both, character: faceanim_rig::Character) -> StateView {
    let mut studio = lock(&both.studio);
    studio.replace_character(character);
    let adapter_path =
        faceanim_adapt::default_adapter_path(studio.project_path.parent(), studio.character.name());
    lock(&both.desk).character_changed(&studio.character, adapter_path);
    crate::capture::map_for_listeners(&both.desk, studio.character.clone());
    studio.view()
}

async fn project(
    State(shared): State<Shared>,
) -> axum::Json<faceanim_sketch::project::ProjectFile> {
    axum::Json(lock(&shared).project().clone())
}

async fn put_project(State(shared): State<Shared>, body: Bytes) -> Answer<StateView> {
    let file = Studio::parse(&body, "project")?;
    let mut studio = lock(&shared);
    studio.change(file)?;
    Ok(axum::Json(studio.view()))
}

async fn new_project(State(shared): State<Shared>, _unread: Unread) -> axum::Json<StateView> {
    let mut studio = lock(&shared);
    studio.new_project();
    axum::Json(studio.view())
}

async fn save(State(shared): State<Shared>, _unread: Unread) -> Answer<SavedView> {
    let studio = lock(&shared);
    studio.save()?;
    Ok(axum::Json(SavedView {
        saved: studio.project_path.display().to_string(),
    }))
}

async fn reopen(State(shared): State<Shared>, _unread: Unread) -> Answer<StateView> {
    let mut studio = lock(&shared);
    studio.reopen()?;
    Ok(axum::Json(studio.view()))
}

/// `change` made to the project as one undoable edit; the new state.
fn edit_project(
    shared: &Shared,
    change: impl FnOnce(&mut faceanim_sketch::project::ProjectFile),
) -> Answer<StateView> {
    let mut studio = lock(shared);
    studio.edit(None, |next| {
        change(next);
        Ok(())
    })?;
    Ok(axum::Json(studio.view()))
}

async fn put_settings(State(shared): State<Shared>, body: Bytes) -> Answer<StateView> {
    let settings: Settings = json_body(&body, "settings")?;
    edit_project(&shared, |next| next.settings = settings)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Fps {
    fps: f32,
}

/// The project's rate; the project's own validation says which rates are allowed.
async fn put_fps(State(shared): State<Shared>, body: Bytes) -> Answer<StateView> {
    let Fps { fps } = json_body(&body, "fps")?;
    edit_project(&shared, |next| next.fps = fps)
}

async fn add_stroke(State(shared): State<Shared>, body: Bytes) -> Answer<StateView> {
    let stroke: StrokeFile = json_body(&body, "stroke")?;
    let mut studio = lock(&shared);
    let index = studio.add_stroke(stroke)?;
    Ok(axum::Json(StateView {
        added: Some(index),
        ..studio.view()
    }))
}

/// What handles and the timeline change of a stroke: each field present is set (a present
/// `null` clears that edit); absent fields stay as they are.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct StrokeEdit {
    #[serde(default, deserialize_with = "present")]
    start_frame: Option<Option<f32>>,
    #[serde(default, deserialize_with = "present")]
    duration: Option<Option<f32>>,
    #[serde(default, deserialize_with = "present")]
    end: Option<Option<[f32; 3]>>,
    #[serde(default, deserialize_with = "present")]
    mid: Option<Option<[f32; 3]>>,
    #[serde(default, deserialize_with = "present")]
    ease: Option<Option<f32>>,
    #[serde(default, deserialize_with = "present")]
    symmetry: Option<Option<bool>>,
}

/// A field that is present (even as `null`) becomes `Some`.
fn present<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    deserializer: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(deserializer).map(Some)
}

impl StrokeEdit {
    fn apply(self, stroke: &mut StrokeFile) {
        fn set<T>(field: &mut T, change: Option<T>) {
            if let Some(value) = change {
                *field = value;
            }
        }
        set(&mut stroke.start_frame, self.start_frame);
        set(&mut stroke.duration, self.duration);
        set(&mut stroke.end, self.end);
        set(&mut stroke.mid, self.mid);
        set(&mut stroke.ease, self.ease);
        set(&mut stroke.symmetry, self.symmetry);
    }
}

async fn edit_stroke(
    State(shared): State<Shared>,
    Path(index): Path<usize>,
    headers: HeaderMap,
    body: Bytes,
) -> Answer<StateView> {
    let gesture = headers
        .get("x-gesture")
        .and_then(|h| h.to_str().ok())
        .map(str::to_owned);
    let edit: StrokeEdit = json_body(&body, "edit")?;
    let mut studio = lock(&shared);
    no_such_stroke(&studio, index)?;
    studio.edit(gesture, |next| {
        edit.apply(&mut next.strokes[index]);
        Ok(())
    })?;
    Ok(axum::Json(studio.view()))
}

/// [`ApiError::NoStroke`] when the project has no stroke `index`.
fn no_such_stroke(studio: &Studio, index: usize) -> Result<(), ApiError> {
    let count = studio.project().strokes.len();
    if index < count {
        return Ok(());
    }
    Err(ApiError::NoStroke { index, count })
}

async fn delete_stroke(
    State(shared): State<Shared>,
    Path(index): Path<usize>,
) -> Answer<StateView> {
    let mut studio = lock(&shared);
    no_such_stroke(&studio, index)?;
    // Later strokes shift down one index; the page redraws everything from the returned state.
    studio.edit(None, |next| {
        next.strokes.remove(index);
        Ok(())
    })?;
    Ok(axum::Json(studio.view()))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CandidateQuery {
    point: [f32; 3],
    #[serde(default)]
    frame: f32,
}

async fn candidates(State(shared): State<Shared>, body: Bytes) -> Answer<Option<CandidatesView>> {
    let query: CandidateQuery = json_body(&body, "candidates")?;
    if query.point.iter().any(|x| !x.is_finite()) || !query.frame.is_finite() {
        return Err(ApiError::Invalid(
            "candidates: point and frame must be finite numbers".into(),
        ));
    }
    Ok(axum::Json(
        lock(&shared).candidates(Vec3::from_array(query.point), query.frame),
    ))
}

async fn undo(State(shared): State<Shared>, _unread: Unread) -> axum::Json<StateView> {
    let mut studio = lock(&shared);
    studio.undo();
    axum::Json(studio.view())
}

async fn redo(State(shared): State<Shared>, _unread: Unread) -> axum::Json<StateView> {
    let mut studio = lock(&shared);
    studio.redo();
    axum::Json(studio.view())
}

/// An export the browser saves as `NAME.EXTENSION` (its notes go to the log); `extension` is
/// the format's for this character ([`Format::extension_for`]: a VRM stays `.vrm`).
fn file_stem(studio: &Studio) -> String {
    // A sketch the character's file kept is written back under its own name, replacing it.
    if let Some(name) = studio.file_sketch_name() {
        return name.to_owned();
    }
    studio.project_path.file_stem().map_or_else(
        || "faceanim".to_owned(),
        |s| s.to_string_lossy().replace('"', ""),
    )
}

/// What the page plays: the character as faceanim sees it (one mesh, the character's own
/// vertex and target order) with the baked corrective targets and the animation, the same
/// weights as the GLB download writes into the user's own file.
async fn view_glb(State(shared): State<Shared>) -> Result<Response, ApiError> {
    let studio = lock(&shared);
    let (sketch, _) = studio.sketch();
    let name = file_stem(&studio);
    let baked = sketch.bake(&name)?;
    let bytes = faceanim_export::view_glb(&baked.character, Some(&baked.animation))?;
    let mut headers = HeaderMap::new();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static(Format::Glb.mime()),
    );
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    Ok((headers, bytes).into_response())
}

/// The sketch in `format`: the GLB carries the baked corrective targets of arcs and
/// exaggerations; the clip and the CSV need only the weights.
async fn export(State(shared): State<Shared>, format: Format) -> Result<Response, ApiError> {
    let studio = lock(&shared);
    let (sketch, _) = studio.sketch();
    let name = file_stem(&studio);
    let clip = sketch.bake_clip();
    let exported = if format == Format::Glb {
        let baked = sketch.bake(&name)?;
        faceanim_export::export(
            format,
            &Animation {
                character: Some(&baked.character),
                animation: baked.animation,
                clip,
                arkit: None,
                session: None,
                bones: None,
                // The strokes go with the sketch, so the file opens again as them.
                strokes: serde_json::to_value(studio.project()).ok(),
                bones_only: false,
            },
        )?
    } else {
        faceanim_export::export(
            format,
            &Animation::from_clip(&studio.character, &clip, &name)?,
        )?
    };
    let extension = format.extension_for(Some(&studio.character));
    Ok(download(format, extension, &name, exported))
}
