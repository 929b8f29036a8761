//! Reading and writing the safetensors files adapters and datasets live in: little-endian f32
//! tensors plus string metadata, so Python tools (and `safetensors` users) can open them too.

use std::collections::HashMap;

use safetensors::{Dtype, SafeTensors, tensor::TensorView};
use serde::de::DeserializeOwned;

use crate::AdaptError;

fn bad(message: impl Into<String>) -> AdaptError {
    AdaptError::Format(message.into())
}

/// Serialises named f32 tensors with their shapes and the metadata.
pub(crate) fn write(
    tensors: &[(&str, &[f32], &[usize])],
    metadata: HashMap<String, String>,
) -> Result<Vec<u8>, AdaptError> {
    let bytes: Vec<Vec<u8>> = tensors
        .iter()
        .map(|(_, data, _)| data.iter().flat_map(|v| v.to_le_bytes()).collect())
        .collect();
    let views = tensors
        .iter()
        .zip(&bytes)
        .map(|((name, _, shape), raw)| {
            TensorView::new(Dtype::F32, shape.to_vec(), raw)
                .map(|view| (*name, view))
                .map_err(|e| bad(format!("tensor {name}: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    safetensors::serialize(views, Some(metadata)).map_err(|e| bad(e.to_string()))
}

/// A parsed file.
pub(crate) struct Read<'a> {
    tensors: SafeTensors<'a>,
    metadata: HashMap<String, String>,
}

impl<'a> Read<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Result<Read<'a>, AdaptError> {
        let (_, header) = SafeTensors::read_metadata(bytes)
            .map_err(|e| bad(format!("not a safetensors file: {e}")))?;
        let tensors = SafeTensors::deserialize(bytes)
            .map_err(|e| bad(format!("not a safetensors file: {e}")))?;
        Ok(Read {
            tensors,
            metadata: header.metadata().clone().unwrap_or_default(),
        })
    }

    pub(crate) fn expect_format(&self, format: &str) -> Result<(), AdaptError> {
        match self.metadata.get("format") {
            Some(f) if f == format => Ok(()),
            Some(other) => Err(bad(format!("format is '{other}', expected '{format}'"))),
            None => Err(bad(format!(
                "no 'format' in the metadata (expected '{format}')"
            ))),
        }
    }

    pub(crate) fn metadata_json<T: DeserializeOwned>(&self, key: &str) -> Result<T, AdaptError> {
        let text = self
            .metadata
            .get(key)
            .ok_or_else(|| bad(format!("metadata has no '{key}'")))?;
        serde_json::from_str(text).map_err(|e| bad(format!("metadata '{key}': {e}")))
    }

    /// A metadata value as it is, when present.
    pub(crate) fn metadata_text(&self, key: &str) -> Option<&str> {
        self.metadata.get(key).map(String::as_str)
    }

    fn tensor(&self, name: &str) -> Result<(Vec<f32>, Vec<usize>), AdaptError> {
        let view = self
            .tensors
            .tensor(name)
            .map_err(|_| bad(format!("no tensor '{name}'")))?;
        if view.dtype() != Dtype::F32 {
            return Err(bad(format!(
                "tensor '{name}' is {:?}, expected F32",
                view.dtype()
            )));
        }
        let values: Vec<f32> = view
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(bad(format!("tensor '{name}' holds NaN or infinite values")));
        }
        Ok((values, view.shape().to_vec()))
    }

    pub(crate) fn matrix(&self, name: &str) -> Result<(Vec<f32>, [usize; 2]), AdaptError> {
        let (values, shape) = self.tensor(name)?;
        match shape[..] {
            [rows, columns] => Ok((values, [rows, columns])),
            _ => Err(bad(format!(
                "tensor '{name}' has shape {shape:?}, expected a matrix"
            ))),
        }
    }

    pub(crate) fn vector(&self, name: &str) -> Result<Vec<f32>, AdaptError> {
        let (values, shape) = self.tensor(name)?;
        match shape[..] {
            [_] => Ok(values),
            _ => Err(bad(format!(
                "tensor '{name}' has shape {shape:?}, expected a vector"
            ))),
        }
    }
}

/// A metadata value as JSON text.
pub(crate) fn json<T: serde::Serialize>(value: &T) -> Result<String, AdaptError> {
    serde_json::to_string(value).map_err(|e| bad(e.to_string()))
}
