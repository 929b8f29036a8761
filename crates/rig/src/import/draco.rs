//! `KHR_draco_mesh_compression`: Draco-compressed primitives decoded natively, with the pure-Rust
//! `draco-core` decoder, before the `gltf` crate sees the file.
//!
//! A compressed primitive keeps its accessors (count, component type, bounds) but they have no
//! buffer view: the extension names a buffer view holding the Draco bitstream, and which Draco
//! attribute (by unique id) fills which glTF attribute. Each primitive's stream is decoded, and
//! its attributes and triangle indices are written, in the accessors' own component types, into
//! one new buffer that the accessors then point at; the extension is dropped from the primitive
//! and from the file. Morph targets are never Draco-compressed (encoders keep the vertex order
//! of a primitive that has them), so they stay as they are. The file written back by an export
//! is the decoded one, as for meshopt.

use std::borrow::Cow;

use serde_json::Value;

use super::types::ImportErrorKind;

const EXTENSION: &str = "KHR_draco_mesh_compression";

/// Per-component minimum and maximum of an accessor's values.
type Bounds = (Vec<f32>, Vec<f32>);

/// Decodes every Draco-compressed primitive of `value` into a new buffer (appended to
/// `buffers`), pointing the primitives' accessors at it.
pub(super) fn decode(
    value: &mut Value,
    buffers: &mut Vec<Cow<'_, [u8]>>,
) -> Result<(), ImportErrorKind> {
    let new_buffer = buffers.len();
    let mut decoded: Vec<u8> = Vec::new();
    let mut new_views: Vec<Value> = Vec::new();
    let first_view = value
        .get("bufferViews")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    // (accessor, bytes) to point at new views, gathered first so `value` is read while borrowed.
    let mut filled: Vec<(usize, Vec<u8>)> = Vec::new();
    // The decoded values' own bounds: dequantization moves them by a fraction of the
    // quantization step, and a declared min/max must be the data's exactly.
    let mut bounds: Vec<(usize, Bounds)> = Vec::new();
    let mut streams: Vec<(String, usize, Value, Value)> = Vec::new();
    if let Some(Value::Array(meshes)) = value.get_mut("meshes") {
        for (m, mesh) in meshes.iter_mut().enumerate() {
            let Some(Value::Array(primitives)) = mesh.get_mut("primitives") else {
                continue;
            };
            for (p, primitive) in primitives.iter_mut().enumerate() {
                let Some(extensions) = primitive
                    .get_mut("extensions")
                    .and_then(Value::as_object_mut)
                else {
                    continue;
                };
                let Some(ext) = extensions.remove(EXTENSION) else {
                    continue;
                };
                if extensions.is_empty()
                    && let Some(object) = primitive.as_object_mut()
                {
                    object.remove("extensions");
                }
                let at = format!("meshes[{m}].primitives[{p}].extensions.{EXTENSION}");
                let view = ext
                    .get("bufferView")
                    .and_then(Value::as_u64)
                    .and_then(|v| usize::try_from(v).ok())
                    .ok_or_else(|| {
                        ImportErrorKind::InvalidJson(format!("{at}.bufferView: missing"))
                    })?;
                streams.push((at, view, ext, primitive.clone()));
            }
        }
    }
    if streams.is_empty() {
        return Ok(());
    }
    for (at, view, ext, primitive) in &streams {
        let bytes = view_bytes(value, buffers, *view).map_err(|problem| {
            ImportErrorKind::InvalidJson(format!("{at}.bufferView: {problem}"))
        })?;
        let mut mesh = draco_core::mesh::Mesh::new();
        let mut buffer = draco_core::decoder_buffer::DecoderBuffer::new(bytes);
        draco_core::mesh_decoder::MeshDecoder::new()
            .decode(&mut buffer, &mut mesh)
            .map_err(|e| {
                ImportErrorKind::InvalidJson(format!(
                    "{at}: the Draco stream does not decode: {e:?}"
                ))
            })?;
        let points = mesh.num_points();
        let Some(attributes) = ext.get("attributes").and_then(Value::as_object) else {
            return Err(ImportErrorKind::InvalidJson(format!(
                "{at}.attributes: missing"
            )));
        };
        for (semantic, id) in attributes {
            let id = id
                .as_u64()
                .and_then(|i| u32::try_from(i).ok())
                .ok_or_else(|| {
                    ImportErrorKind::InvalidJson(format!("{at}.attributes.{semantic}: not an id"))
                })?;
            let Some(accessor) = primitive
                .pointer(&format!("/attributes/{semantic}"))
                .and_then(Value::as_u64)
                .and_then(|a| usize::try_from(a).ok())
            else {
                continue;
            };
            let attribute = mesh.attribute_by_unique_id(id).ok_or_else(|| {
                ImportErrorKind::InvalidJson(format!(
                    "{at}.attributes.{semantic}: the Draco stream has no attribute {id}"
                ))
            })?;
            let (component_type, components, count) =
                accessor_shape(value, accessor).map_err(|problem| {
                    ImportErrorKind::InvalidJson(format!(
                        "accessors[{accessor}] ({semantic} of {at}): {problem}"
                    ))
                })?;
            if count != points {
                return Err(ImportErrorKind::CountMismatch(format!(
                    "accessors[{accessor}] ({semantic} of {at}) has {count} elements but its Draco stream decodes {points} points"
                )));
            }
            let mut values = attribute.read_f32s(points, components);
            if semantic.starts_with("WEIGHTS_") {
                renormalize(&mut values, components, component_type);
            }
            if component_type != 5126 {
                for v in &mut values {
                    *v = v.round();
                }
            }
            bounds.push((accessor, bounds_of(&values, components)));
            filled.push((accessor, encode(&values, component_type)));
        }
        if let Some(indices) = primitive
            .get("indices")
            .and_then(Value::as_u64)
            .and_then(|a| usize::try_from(a).ok())
        {
            let (component_type, _, count) = accessor_shape(value, indices).map_err(|problem| {
                ImportErrorKind::InvalidJson(format!(
                    "accessors[{indices}] (indices of {at}): {problem}"
                ))
            })?;
            let flat: Vec<f32> = mesh
                .faces()
                .iter()
                .flat_map(|face| face.iter().map(|p| p.0 as f32))
                .collect();
            if flat.len() != count {
                return Err(ImportErrorKind::CountMismatch(format!(
                    "accessors[{indices}] (indices of {at}) has {count} elements but its Draco stream decodes {} triangles",
                    flat.len() / 3
                )));
            }
            let exact: Vec<u8> = match component_type {
                5125 => mesh
                    .faces()
                    .iter()
                    .flat_map(|face| face.iter().flat_map(|p| p.0.to_le_bytes()))
                    .collect(),
                other => encode(&flat, other),
            };
            filled.push((indices, exact));
        }
    }
    let Some(Value::Array(accessors)) = value.get_mut("accessors") else {
        return Err(ImportErrorKind::InvalidJson(
            "Draco-compressed primitives but no accessors".into(),
        ));
    };
    for (accessor, (min, max)) in bounds {
        if let Some(a) = accessors.get_mut(accessor).and_then(Value::as_object_mut) {
            for (key, values) in [("min", min), ("max", max)] {
                if a.contains_key(key) {
                    a.insert(
                        key.into(),
                        serde_json::json!(values.iter().map(|&v| f64::from(v)).collect::<Vec<_>>()),
                    );
                }
            }
        }
    }
    for (accessor, bytes) in filled {
        while !decoded.len().is_multiple_of(16) {
            decoded.push(0);
        }
        let view = first_view + new_views.len();
        new_views.push(serde_json::json!({
            "buffer": new_buffer, "byteOffset": decoded.len(), "byteLength": bytes.len()
        }));
        decoded.extend_from_slice(&bytes);
        if let Some(a) = accessors.get_mut(accessor).and_then(Value::as_object_mut) {
            a.insert("bufferView".into(), Value::from(view));
            a.remove("byteOffset");
        }
    }
    match value.get_mut("bufferViews") {
        Some(Value::Array(views)) => views.extend(new_views),
        _ => value["bufferViews"] = Value::Array(new_views),
    }
    super::buffers::push_buffer(value, buffers, decoded);
    for list in ["extensionsRequired", "extensionsUsed"] {
        if let Some(Value::Array(names)) = value.get_mut(list) {
            names.retain(|n| n.as_str() != Some(EXTENSION));
        }
    }
    Ok(())
}

/// The bytes of buffer view `view`.
fn view_bytes<'b>(
    value: &Value,
    buffers: &'b [Cow<'_, [u8]>],
    view: usize,
) -> Result<&'b [u8], String> {
    let v = value
        .pointer(&format!("/bufferViews/{view}"))
        .ok_or_else(|| format!("buffer view {view} does not exist"))?;
    let number = |key: &str, default: Option<u64>| {
        v.get(key)
            .map_or(default, Value::as_u64)
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| format!("bufferViews[{view}].{key}: missing or not a whole number"))
    };
    let (buffer, offset, length) = (
        number("buffer", None)?,
        number("byteOffset", Some(0))?,
        number("byteLength", None)?,
    );
    let data = buffers
        .get(buffer)
        .ok_or_else(|| format!("bufferViews[{view}].buffer: buffer {buffer} does not exist"))?;
    offset
        .checked_add(length)
        .and_then(|end| data.get(offset..end))
        .ok_or_else(|| format!("bufferViews[{view}] runs past the end of buffer {buffer}"))
}

/// An accessor's component type, components per element and count.
fn accessor_shape(value: &Value, accessor: usize) -> Result<(u64, usize, usize), String> {
    let a = value
        .pointer(&format!("/accessors/{accessor}"))
        .ok_or("it does not exist")?;
    let component_type = a
        .get("componentType")
        .and_then(Value::as_u64)
        .ok_or("componentType: missing")?;
    let components = match a.get("type").and_then(Value::as_str) {
        Some("SCALAR") => 1,
        Some("VEC2") => 2,
        Some("VEC3") => 3,
        Some("VEC4") => 4,
        other => return Err(format!("type {other:?} cannot hold a Draco attribute")),
    };
    let count = a
        .get("count")
        .and_then(Value::as_u64)
        .and_then(|n| usize::try_from(n).ok())
        .ok_or("count: missing")?;
    Ok((component_type, components, count))
}

/// Values as the little-endian bytes of a glTF component type (integers rounded: Draco decodes
/// integer attributes to their stored values, which a normalized accessor keeps as they are).
fn encode(values: &[f32], component_type: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(values.len() * 4);
    for &v in values {
        match component_type {
            5120 => out.extend((v.round().clamp(-128.0, 127.0) as i8).to_le_bytes()),
            5121 => out.extend((v.round().clamp(0.0, 255.0) as u8).to_le_bytes()),
            5122 => out.extend((v.round().clamp(-32768.0, 32767.0) as i16).to_le_bytes()),
            5123 => out.extend((v.round().clamp(0.0, 65535.0) as u16).to_le_bytes()),
            5125 => out.extend((v.round().max(0.0) as u32).to_le_bytes()),
            _ => out.extend(v.to_le_bytes()),
        }
    }
    out
}

/// Per-component minimum and maximum of `values`, `components` to an element.
fn bounds_of(values: &[f32], components: usize) -> Bounds {
    let mut min = vec![f32::INFINITY; components];
    let mut max = vec![f32::NEG_INFINITY; components];
    for element in values.chunks_exact(components.max(1)) {
        for (c, &v) in element.iter().enumerate() {
            min[c] = min[c].min(v);
            max[c] = max[c].max(v);
        }
    }
    (min, max)
}

/// Skinning weights whose quantization left their sum off 1 (or off the normalized integer
/// maximum): scaled back (floats), or the largest weight takes up the difference (integers).
fn renormalize(values: &mut [f32], components: usize, component_type: u64) {
    let full = match component_type {
        5121 => 255.0,
        5123 => 65535.0,
        _ => 1.0,
    };
    for element in values.chunks_exact_mut(components.max(1)) {
        let sum: f32 = element.iter().sum();
        if sum <= 0.0 {
            continue;
        }
        if component_type == 5126 {
            for v in element.iter_mut() {
                *v /= sum;
            }
        } else {
            for v in element.iter_mut() {
                *v = v.round();
            }
            let rounded: f32 = element.iter().sum();
            if let Some(largest) = element.iter_mut().max_by(|a, b| a.total_cmp(b)) {
                *largest += full - rounded;
            }
        }
    }
}
