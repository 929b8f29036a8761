//! The file's buffers as the import extends them: data decoded from a compressed view, or
//! made for an accessor without any, is appended as a buffer of its own.

use std::borrow::Cow;

use serde_json::Value;

/// Appends `bytes` as a new buffer: its entry in the JSON's `buffers` (made if missing) and its
/// bytes beside the others, at index `buffers.len()`, which the caller's new views name.
pub(super) fn push_buffer(value: &mut Value, buffers: &mut Vec<Cow<'_, [u8]>>, bytes: Vec<u8>) {
    if let Some(root) = value.as_object_mut()
        && let Value::Array(list) = root
            .entry("buffers")
            .or_insert_with(|| Value::Array(Vec::new()))
    {
        list.push(serde_json::json!({ "byteLength": bytes.len() }));
    }
    buffers.push(Cow::Owned(bytes));
}
