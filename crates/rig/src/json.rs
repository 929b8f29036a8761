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
    let mut reader = serde_json::Deserializer::from_slice(bytes);
    let value = serde_path_to_error::deserialize(&mut reader).map_err(JsonError::of)?;
    reader.end().map_err(|e| JsonError {
        path: None,
        message: e.to_string(),
    })?;
    Ok(value)
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
