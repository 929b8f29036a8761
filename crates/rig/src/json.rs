//! Reading JSON the way every faceanim format does: a value of the wrong type is named by its
//! path (`frames[3].head[0]`), and serde's message — which quotes the offending value whole —
//! is cut, so that a 10 MB string in a file never becomes a 10 MB error.

use crate::excerpt::excerpt;

/// Why JSON could not be read as the type asked for.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", match .path.as_deref() { Some(path) => format!("{path}: {message}"), None => message.clone() })]
pub struct JsonError {
    /// Where in the document (`None` for the document itself, or text that is not JSON).
    pub path: Option<String>,
    /// What is wrong, with long quoted values cut.
    pub message: String,
}

/// The longest message kept from serde, in characters.
const MESSAGE_CHARS: usize = 300;

impl JsonError {
    fn of<E: std::fmt::Display>(e: serde_path_to_error::Error<E>) -> JsonError {
        let path = e.path().to_string();
        let message = e.into_inner().to_string();
        let message = if message.chars().count() > MESSAGE_CHARS {
            format!(
                "{}…",
                message.chars().take(MESSAGE_CHARS).collect::<String>()
            )
        } else {
            message
        };
        JsonError {
            path: (path != ".").then(|| excerpt(&path).into_owned()),
            message,
        }
    }
}

/// `bytes` as a `T`.
///
/// # Errors
/// [`JsonError`] with the path of the value that is wrong.
///
/// ```
/// #[derive(serde::Deserialize, Debug)]
/// struct Frame { head: [f32; 3] }
/// #[derive(serde::Deserialize, Debug)]
/// struct Take { frames: Vec<Frame> }
/// let e = faceanim_rig::json::from_slice::<Take>(br#"{"frames": [{"head": [0, "up", 0]}]}"#);
/// assert!(e.unwrap_err().to_string().starts_with("frames[0].head[1]: invalid type"));
/// ```
pub fn from_slice<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, JsonError> {
    let mut reader = serde_json::Deserializer::from_slice(unmarked(bytes)?);
    let value = serde_path_to_error::deserialize(&mut reader).map_err(JsonError::of)?;
    reader.end().map_err(|e| JsonError {
        path: None,
        message: e.to_string(),
    })?;
    Ok(value)
}

/// JSON's bytes as RFC 8259 lets a reader take them: UTF-8, with a byte-order mark before it
/// ignored (older Notepad and PowerShell's `Out-File -Encoding utf8` write one, and serde
/// reads it as a character out of place). UTF-16, which PowerShell 5's `>` writes, is not
/// JSON's, and is refused by name rather than as "expected value at line 1 column 1".
fn unmarked(bytes: &[u8]) -> Result<&[u8], JsonError> {
    if let Some(rest) = bytes.strip_prefix(b"\xef\xbb\xbf") {
        return Ok(rest);
    }
    if bytes.starts_with(b"\xff\xfe") || bytes.starts_with(b"\xfe\xff") {
        return Err(JsonError {
            path: None,
            message: "UTF-16 text (its byte-order mark says so): JSON is UTF-8; save it as UTF-8"
                .to_owned(),
        });
    }
    Ok(bytes)
}

/// `value` as a `T`.
///
/// # Errors
/// [`JsonError`] with the path of the value that is wrong.
pub fn from_value<T: serde::de::DeserializeOwned>(
    value: serde_json::Value,
) -> Result<T, JsonError> {
    serde_path_to_error::deserialize(value).map_err(JsonError::of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug, PartialEq)]
    struct Row {
        name: String,
    }

    #[test]
    fn a_byte_order_mark_is_ignored_and_utf16_is_refused_by_name() {
        let marked = b"\xef\xbb\xbf{\"name\": \"jaw\"}";
        assert_eq!(
            from_slice::<Row>(marked),
            Ok(Row {
                name: "jaw".to_owned()
            })
        );
        // As PowerShell 5 writes `{"name": "jaw"}` with `>`.
        let utf16: Vec<u8> = [0xff, 0xfe]
            .into_iter()
            .chain("{\"name\": \"jaw\"}".bytes().flat_map(|b| [b, 0]))
            .collect();
        let error = from_slice::<Row>(&utf16).unwrap_err().to_string();
        assert!(error.contains("UTF-16"), "{error}");
    }
}
