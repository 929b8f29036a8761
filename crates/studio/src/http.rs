//! What every route shares, below the routes: the rules for requests (only this studio's own
//! page may call it), for bodies and upload names, and for answers (every error is
//! `{"error": …}` JSON, a handler's panic included, and downloads carry their file name).
//! The route modules ([`crate::api`], [`crate::capture_api`]) import from here, never from
//! each other.

use std::fmt::Write as _;
use std::panic::AssertUnwindSafe;

use axum::extract::Request;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use faceanim_export::{Exported, Format};
use futures_util::FutureExt as _;

use crate::error::ApiError;

/// The body of a request that takes nothing from it (the page may send `{}`), read all the
/// same: a body left unread when the answer closes the connection turns the close into a
/// reset, and the client may lose the answer.
pub(crate) type Unread = axum::body::Bytes;

/// The longest upload name kept, in characters (the extension included).
pub const NAME_CHARS: usize = 120;

/// A JSON body as `T`, or [`ApiError::Invalid`] naming `what` and the field that is wrong.
pub(crate) fn json_body<T: serde::de::DeserializeOwned>(
    bytes: &[u8],
    what: &str,
) -> Result<T, ApiError> {
    faceanim_rig::json::from_slice(bytes).map_err(|e| ApiError::Invalid(format!("{what}: {e}")))
}

/// The name an upload was sent with, as the user knows it: header `x-filename` (UTF-8, the
/// page percent-encodes it), else `fallback`. Folders are dropped, control characters
/// replaced and a long name cut to [`NAME_CHARS`] characters keeping its extension; refused,
/// naming it, when the file is empty or the name is not text.
pub(crate) fn uploaded_name(
    headers: &HeaderMap,
    body: &[u8],
    fallback: &str,
) -> Result<String, ApiError> {
    let name = match headers.get("x-filename") {
        Some(value) => {
            let raw = std::str::from_utf8(value.as_bytes()).map_err(|_| {
                ApiError::Invalid("x-filename: the file name is not UTF-8 text".into())
            })?;
            clean_name(&percent_decoded(raw))
        }
        None => fallback.to_owned(),
    };
    if name.is_empty() {
        return Err(ApiError::Invalid(
            "x-filename: the file name is empty".into(),
        ));
    }
    if body.is_empty() {
        return Err(ApiError::Invalid(format!("{name}: the file is empty")));
    }
    Ok(name)
}

/// `%XX` sequences decoded when they make UTF-8 text; the text as it came otherwise.
fn percent_decoded(raw: &str) -> String {
    if !raw.contains('%') {
        return raw.to_owned();
    }
    let bytes = raw.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut at = 0;
    while at < bytes.len() {
        let hex = |k: usize| {
            bytes
                .get(k)
                .and_then(|&b| char::from(b).to_digit(16))
                .and_then(|d| u8::try_from(d).ok())
        };
        match (bytes[at], hex(at + 1), hex(at + 2)) {
            (b'%', Some(high), Some(low)) => {
                out.push(high * 16 + low);
                at += 3;
            }
            (b, _, _) => {
                out.push(b);
                at += 1;
            }
        }
    }
    String::from_utf8(out).unwrap_or_else(|_| raw.to_owned())
}

/// A file name as the studio shows and keeps it: the last part of a path, without control
/// characters, at most [`NAME_CHARS`] characters with its extension kept.
fn clean_name(name: &str) -> String {
    let last = name.rsplit(['/', '\\']).next().unwrap_or(name);
    let clean: String = last
        .chars()
        .map(|c| if c.is_control() { '_' } else { c })
        .collect();
    let clean = clean.trim();
    if clean.chars().count() <= NAME_CHARS {
        return clean.to_owned();
    }
    let extension = clean
        .rsplit_once('.')
        .map(|(_, e)| e)
        .filter(|e| (1..=12).contains(&e.chars().count()))
        .unwrap_or("");
    let keep = NAME_CHARS - extension.chars().count() - 2;
    let head: String = clean.chars().take(keep).collect();
    if extension.is_empty() {
        format!("{head}…")
    } else {
        format!("{head}….{extension}")
    }
}

/// The header that carries an export's notes (what the file carries, what it left out) to the
/// page, as a JSON array of strings in ASCII.
pub const NOTES_HEADER: &str = "x-faceanim-notes";

/// A download of `exported`, named `name.extension`, its notes in [`NOTES_HEADER`].
pub(crate) fn download(
    format: Format,
    extension: &str,
    name: &str,
    exported: Exported,
) -> Response {
    for note in &exported.notes {
        tracing::info!("{name}.{extension}: {note}");
    }
    let mut headers = HeaderMap::new();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static(format.mime()),
    );
    if let Ok(value) = HeaderValue::from_str(&disposition(&format!("{name}.{extension}"))) {
        headers.insert(header::CONTENT_DISPOSITION, value);
    }
    if let Ok(value) = HeaderValue::from_str(&ascii_json(&exported.notes)) {
        headers.insert(NOTES_HEADER, value);
    }
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    (headers, exported.bytes).into_response()
}

/// `Content-Disposition` for a file named `file`: the name in ASCII (what is not, `_`) for
/// every client, and exactly, percent-encoded UTF-8 (RFC 6266's `filename*`), for those that
/// read it — every browser — so a character named in Japanese downloads under its own name.
fn disposition(file: &str) -> String {
    let ascii: String = file
        .chars()
        .map(|c| {
            if c.is_ascii_graphic() && c != '"' && c != '\\' || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut exact = String::new();
    for byte in file.bytes() {
        if byte.is_ascii_alphanumeric() || b"!#$&+-.^_`|~".contains(&byte) {
            exact.push(char::from(byte));
        } else {
            let _ = write!(exact, "%{byte:02X}");
        }
    }
    format!("attachment; filename=\"{ascii}\"; filename*=UTF-8''{exact}")
}

/// `strings` as a JSON array in ASCII: what is not, escaped as JSON's `\uXXXX`, so that it
/// fits in a header.
fn ascii_json(strings: &[String]) -> String {
    let json = serde_json::to_string(strings).unwrap_or_else(|_| "[]".to_owned());
    let mut out = String::with_capacity(json.len());
    let mut units = [0u16; 2];
    for c in json.chars() {
        if (' '..='~').contains(&c) {
            out.push(c);
        } else {
            for unit in c.encode_utf16(&mut units) {
                let _ = write!(out, "\\u{unit:04x}");
            }
        }
    }
    out
}

/// `router` with its bodies limited to `max` bytes. A request that declares a longer body
/// (`Content-Length`) is refused with 413 before any of it is read, so a client that waits
/// for the go-ahead (`Expect: 100-continue`) is never told to send it; one that streams
/// without declaring its length is cut off by axum's own limit at `max`.
pub(crate) fn body_limit<S: Clone + Send + Sync + 'static>(
    router: axum::Router<S>,
    max: usize,
) -> axum::Router<S> {
    router
        .layer(axum::extract::DefaultBodyLimit::max(max))
        .layer(axum::middleware::from_fn(
            move |request: Request, next: Next| refuse_declared_over(max, request, next),
        ))
}

async fn refuse_declared_over(max: usize, request: Request, next: Next) -> Response {
    let declared = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    match declared {
        Some(length) if length > max as u64 => {
            let mut answer = error_answer(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("the body is {length} bytes; this route takes at most {max}"),
            );
            // The unread body is not wanted: say so, so the client stops sending it.
            answer
                .headers_mut()
                .insert(header::CONNECTION, HeaderValue::from_static("close"));
            answer
        }
        _ => next.run(request).await,
    }
}

/// Refuses requests not addressed to this studio by its own name (DNS rebinding) and
/// cross-site requests from other origins.
pub(crate) async fn only_local(port: u16, request: Request, next: Next) -> Response {
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
        return error_answer(
            StatusCode::FORBIDDEN,
            format!("host '{}' is not this studio", faceanim_rig::excerpt(host)),
        );
    }
    if let Some(origin) = request.headers().get(header::ORIGIN) {
        let origin = origin.to_str().unwrap_or("");
        if !allowed_hosts
            .iter()
            .any(|a| origin == format!("http://{a}"))
        {
            return error_answer(
                StatusCode::FORBIDDEN,
                format!(
                    "origin '{}' is not this studio",
                    faceanim_rig::excerpt(origin)
                ),
            );
        }
    }
    next.run(request).await
}

/// A handler that panics (a bug) answers 500 with what it said, and only that request fails:
/// the connection is answered, the other routes go on, and so does the studio.
pub(crate) async fn catch_panics(request: Request, next: Next) -> Response {
    let route = request.uri().path().to_owned();
    match AssertUnwindSafe(next.run(request)).catch_unwind().await {
        Ok(response) => response,
        Err(panic) => {
            let said = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".to_owned());
            tracing::error!("{route} panicked: {said}");
            error_answer(
                StatusCode::INTERNAL_SERVER_ERROR,
                format!(
                    "internal error in {route}: {}; the studio goes on",
                    faceanim_rig::excerpt(&said)
                ),
            )
        }
    }
}

/// Every 4xx and 5xx answer is `{"error": …}` JSON: ones that axum makes itself (a body over
/// its limit, a path that is not a number, a method a route lacks) are wrapped here.
pub(crate) async fn json_errors(request: Request, next: Next) -> Response {
    let response = next.run(request).await;
    let status = response.status();
    let is_json = response
        .headers()
        .get(header::CONTENT_TYPE)
        .is_some_and(|t| t.as_bytes().starts_with(b"application/json"));
    if !(status.is_client_error() || status.is_server_error()) || is_json {
        return response;
    }
    let text = match axum::body::to_bytes(response.into_body(), 64 * 1024).await {
        Ok(bytes) if !bytes.is_empty() => String::from_utf8_lossy(&bytes).trim().to_owned(),
        _ => status
            .canonical_reason()
            .unwrap_or("request refused")
            .to_lowercase(),
    };
    error_answer(status, text)
}

/// `{"error": message}` with `status`.
pub(crate) fn error_answer(status: StatusCode, message: String) -> Response {
    #[derive(serde::Serialize)]
    struct ErrorView {
        error: String,
    }
    let mut response = (status, axum::Json(ErrorView { error: message })).into_response();
    // An answer that lost its body to a panic or a limit is not worth keeping open for.
    if status.is_server_error() {
        response
            .headers_mut()
            .insert(header::CONNECTION, HeaderValue::from_static("close"));
    }
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn download_names_and_notes_fit_in_headers_and_come_back_exactly() {
        assert_eq!(
            disposition("take.vrma"),
            "attachment; filename=\"take.vrma\"; filename*=UTF-8''take.vrma"
        );
        // Japanese, a quote, a space and a percent: ASCII for old clients, exact for browsers.
        let named = disposition("アバ\"タ 100%.vrm");
        assert!(HeaderValue::from_str(&named).is_ok(), "{named}");
        assert_eq!(
            named,
            "attachment; filename=\"____ 100%.vrm\"; filename*=UTF-8''%E3%82%A2%E3%83%90%22%E3%82%BF%20100%25.vrm"
        );
        let notes = vec![
            "1 shape … in no VRM expression: \"mouthSmile_L\"".to_owned(),
            "😀\n".to_owned(),
        ];
        let header = ascii_json(&notes);
        assert!(HeaderValue::from_str(&header).is_ok(), "{header}");
        assert!(header.is_ascii());
        let back: Vec<String> = serde_json::from_str(&header).unwrap_or_default();
        assert_eq!(back, notes);
        // The page reads the notes from the header the server writes them in.
        let page = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/downloads.js"),
        )
        .unwrap_or_default();
        assert!(
            page.contains(&format!("const NOTES_HEADER = '{NOTES_HEADER}';")),
            "web/downloads.js reads another header than {NOTES_HEADER}"
        );
    }

    #[test]
    fn upload_names_are_decoded_cut_and_cleaned() {
        let named = |value: &[u8]| {
            let mut headers = HeaderMap::new();
            if let Ok(v) = HeaderValue::from_bytes(value) {
                headers.insert("x-filename", v);
            }
            uploaded_name(&headers, b"x", "upload").map_err(|e| e.to_string())
        };
        assert_eq!(named(b"take.mp4").as_deref(), Ok("take.mp4"));
        // The page percent-encodes; raw UTF-8 from other clients is read too.
        assert_eq!(
            named(b"%E3%83%86%E3%82%A4%E3%82%AF.wav").as_deref(),
            Ok("テイク.wav")
        );
        assert_eq!(named("vidéo.mp4".as_bytes()).as_deref(), Ok("vidéo.mp4"));
        assert_eq!(named(b"100%25 sure.wav").as_deref(), Ok("100% sure.wav"));
        assert_eq!(named(b"50% off.wav").as_deref(), Ok("50% off.wav"));
        // Folders are dropped.
        assert_eq!(named(b"..%2F..%2Fetc%2Fpasswd").as_deref(), Ok("passwd"));
        // A 10 KB name is cut, its extension kept.
        let long = format!("{}.wav", "a".repeat(10_000));
        let cut = named(long.as_bytes()).unwrap_or_default();
        assert_eq!(cut.chars().count(), NAME_CHARS);
        assert!(cut.ends_with("….wav"), "{cut}");
        // Not text, and empty, are refused by name.
        let e = named(&[0xff, 0xfe, b'.', b'w']).err().unwrap_or_default();
        assert!(e.starts_with("x-filename:"), "{e}");
        assert!(named(b"%20").is_err());
        let mut headers = HeaderMap::new();
        headers.insert("x-filename", HeaderValue::from_static("a.wav"));
        let e = uploaded_name(&headers, b"", "upload")
            .err()
            .map(|e| e.to_string());
        assert_eq!(e.as_deref(), Some("a.wav: the file is empty"));
    }
}
