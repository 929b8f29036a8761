//! Meshopt compression of a GLB's buffer views (`EXT_meshopt_compression`), so that a file
//! read with it is written back with it: the user's avatar keeps its size.
//!
//! Every view an accessor reads is a candidate: triangle index views with the index codec
//! (`TRIANGLES`), the rest with the vertex codec (`ATTRIBUTES`) when its element stride is a
//! multiple of 4 up to 256 (geometry, morph targets, skins, the animation's keys and weights).
//! Version 0 of the vertex codec is written, which every `EXT_meshopt_compression` decoder
//! reads; filters are not applied (the data is kept bit for bit). A view that would not shrink
//! stays as it is, as do views no accessor reads (images: already compressed). The compressed
//! bytes go in the GLB's own buffer; the views point into a second buffer, the extension's
//! `fallback`, which holds no bytes, so the extension is required.

use serde_json::{Value, json};

const EXTENSION: &str = "EXT_meshopt_compression";

/// How one view is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Attributes { stride: usize },
    Triangles { index_size: usize },
}

fn component_size(component_type: u64) -> Option<usize> {
    match component_type {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

fn components(kind: &str) -> Option<usize> {
    Some(match kind {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    })
}

fn index(value: &Value, key: &str) -> Option<usize> {
    value
        .get(key)
        .and_then(Value::as_u64)
        .and_then(|n| usize::try_from(n).ok())
}

/// Per view: how it can be encoded, or `None` when it cannot (or is read as two things).
fn modes(doc: &Value) -> Vec<Option<Mode>> {
    let views = doc
        .get("bufferViews")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let accessors: &[Value] = doc
        .get("accessors")
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice);
    // Accessors read as triangle lists' indices.
    let mut triangle_indices = std::collections::HashSet::new();
    for mesh in doc
        .get("meshes")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
    {
        for primitive in mesh
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if let Some(i) = index(primitive, "indices")
                && primitive.get("mode").and_then(Value::as_u64).unwrap_or(4) == 4
            {
                triangle_indices.insert(i);
            }
        }
    }
    // Each view's uses: (mode it asks for).
    let mut wanted: Vec<Vec<Option<Mode>>> = vec![Vec::new(); views];
    let mut note = |view: Option<usize>, mode: Option<Mode>| {
        if let Some(slot) = view.and_then(|v| wanted.get_mut(v)) {
            slot.push(mode);
        }
    };
    for (a, accessor) in accessors.iter().enumerate() {
        let element = accessor
            .get("componentType")
            .and_then(Value::as_u64)
            .and_then(component_size)
            .zip(
                accessor
                    .get("type")
                    .and_then(Value::as_str)
                    .and_then(components),
            )
            .map(|(size, count)| (size, size * count));
        let mode = element.map(|(size, bytes)| {
            if triangle_indices.contains(&a) {
                Mode::Triangles { index_size: size }
            } else {
                Mode::Attributes { stride: bytes }
            }
        });
        note(index(accessor, "bufferView"), mode);
        if let Some(sparse) = accessor.get("sparse") {
            let indices = sparse.get("indices");
            note(
                indices.and_then(|i| index(i, "bufferView")),
                indices
                    .and_then(|i| i.get("componentType").and_then(Value::as_u64))
                    .and_then(component_size)
                    .map(|size| Mode::Attributes { stride: size }),
            );
            note(
                sparse.get("values").and_then(|v| index(v, "bufferView")),
                element.map(|(_, bytes)| Mode::Attributes { stride: bytes }),
            );
        }
    }
    let list: &[Value] = doc
        .get("bufferViews")
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice);
    wanted
        .into_iter()
        .zip(list)
        .map(|(uses, view)| {
            let first = (*uses.first()?)?;
            if uses.iter().any(|u| *u != Some(first)) {
                return None;
            }
            let length = index(view, "byteLength")?;
            match first {
                // A strided view's elements are its stride apart, whatever each accessor reads.
                Mode::Attributes { stride } => {
                    let stride = index(view, "byteStride").unwrap_or(stride);
                    (stride.is_multiple_of(4) && stride <= 256 && length.is_multiple_of(stride))
                        .then_some(Mode::Attributes { stride })
                }
                Mode::Triangles { index_size } => ((index_size == 2 || index_size == 4)
                    && index(view, "byteStride").is_none()
                    && length.is_multiple_of(3 * index_size))
                .then_some(first),
            }
        })
        .collect()
}

/// A byte block of `N` bytes: one element for the vertex codec, whose element size is a type
/// parameter in the `meshopt` crate.
#[derive(Clone, Copy)]
struct Block<const N: usize>([u8; N]);

fn encode_blocks<const N: usize>(data: &[u8]) -> Option<Vec<u8>> {
    let blocks: Vec<Block<N>> = data
        .chunks_exact(N)
        .map(|c| Block(c.try_into().unwrap_or([0; N])))
        .collect();
    meshopt::encoding::encode_vertex_buffer_level(&blocks, 2, Some(0)).ok()
}

fn encode(data: &[u8], mode: Mode) -> Option<Vec<u8>> {
    match mode {
        Mode::Attributes { stride } => {
            macro_rules! strides {
                ($($n:literal)*) => {
                    match stride {
                        $($n => encode_blocks::<$n>(data),)*
                        _ => None,
                    }
                };
            }
            strides!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100
                104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180
                184 188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
        }
        Mode::Triangles { index_size } => {
            let indices: Vec<u32> = match index_size {
                2 => data
                    .chunks_exact(2)
                    .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
                    .collect(),
                _ => data
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            };
            let vertices = indices.iter().max().map_or(0, |&m| m as usize + 1);
            meshopt::encoding::encode_index_buffer(&indices, vertices).ok()
        }
    }
}

/// Compresses the views of `doc` (whose one buffer is `bin`) and returns the new buffer: see
/// the module docs. Views no accessor reads, or that would not shrink, are copied as they are.
/// Returns `bin` unchanged when nothing shrinks.
pub(crate) fn compress(doc: &mut Value, bin: Vec<u8>) -> Vec<u8> {
    let modes = modes(doc);
    let Some(Value::Array(views)) = doc.get_mut("bufferViews") else {
        return bin;
    };
    let mut out: Vec<u8> = Vec::with_capacity(bin.len() / 2);
    let mut fallback = 0usize;
    let mut any = false;
    for (view, mode) in views.iter_mut().zip(modes) {
        let (Some(offset), Some(length)) = (
            index(view, "byteOffset").or(Some(0)),
            index(view, "byteLength"),
        ) else {
            continue;
        };
        let Some(data) = offset
            .checked_add(length)
            .and_then(|end| bin.get(offset..end))
        else {
            continue;
        };
        let encoded = mode.and_then(|m| Some((m, encode(data, m)?)));
        let align = |bytes: &mut Vec<u8>, to: usize| {
            while !bytes.len().is_multiple_of(to) {
                bytes.push(0);
            }
        };
        align(&mut out, 4);
        let at = out.len();
        match encoded {
            Some((mode, compressed)) if compressed.len() < length => {
                out.extend_from_slice(&compressed);
                while !fallback.is_multiple_of(16) {
                    fallback += 1;
                }
                let (stride, count, name) = match mode {
                    Mode::Attributes { stride } => (stride, length / stride, "ATTRIBUTES"),
                    Mode::Triangles { index_size } => {
                        (index_size, length / index_size, "TRIANGLES")
                    }
                };
                view["buffer"] = json!(1);
                view["byteOffset"] = json!(fallback);
                let extensions = view
                    .as_object_mut()
                    .map(|o| o.entry("extensions").or_insert_with(|| json!({})));
                if let Some(extensions) = extensions {
                    extensions[EXTENSION] = json!({
                        "buffer": 0, "byteOffset": at, "byteLength": compressed.len(),
                        "byteStride": stride, "count": count, "mode": name,
                    });
                }
                fallback += length;
                any = true;
            }
            _ => {
                out.extend_from_slice(data);
                view["buffer"] = json!(0);
                view["byteOffset"] = json!(at);
            }
        }
    }
    if !any {
        // Nothing shrank: the views were moved onto `out` all the same (orphaned bytes left).
        doc["buffers"] = json!([{ "byteLength": out.len() }]);
        return out;
    }
    doc["buffers"] = json!([
        { "byteLength": out.len() },
        { "byteLength": fallback, "extensions": { EXTENSION: { "fallback": true } } },
    ]);
    for key in ["extensionsUsed", "extensionsRequired"] {
        let list = doc
            .as_object_mut()
            .map(|o| o.entry(key).or_insert_with(|| json!([])));
        if let Some(Value::Array(list)) = list
            && !list.iter().any(|e| e == EXTENSION)
        {
            list.push(json!(EXTENSION));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_compressed_by_what_reads_them_and_decode_to_the_same_bytes() {
        // A float VEC3 attribute of 300 smooth vertices, triangle indices over them, and an
        // image's bytes that no accessor reads.
        let positions: Vec<u8> = (0..300)
            .flat_map(|i| {
                let t = i as f32 * 0.01;
                [t.sin(), t.cos(), t]
            })
            .flat_map(f32::to_le_bytes)
            .collect();
        let indices: Vec<u8> = (0..297u16)
            .flat_map(|i| [i, i + 1, i + 2])
            .flat_map(u16::to_le_bytes)
            .collect();
        let image = vec![7u8; 64];
        let mut bin = positions.clone();
        bin.extend_from_slice(&indices);
        bin.extend_from_slice(&image);
        let mut doc = json!({
            "buffers": [{ "byteLength": bin.len() }],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": positions.len() },
                { "buffer": 0, "byteOffset": positions.len(), "byteLength": indices.len() },
                { "buffer": 0, "byteOffset": positions.len() + indices.len(), "byteLength": 64 },
            ],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 300, "type": "VEC3" },
                { "bufferView": 1, "componentType": 5123, "count": 891, "type": "SCALAR" },
            ],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        });
        let out = compress(&mut doc, bin.clone());
        assert!(out.len() < bin.len(), "{} of {}", out.len(), bin.len());
        assert_eq!(doc["extensionsRequired"], json!([EXTENSION]));
        assert_eq!(doc["buffers"][1]["extensions"][EXTENSION]["fallback"], true);
        let views = doc["bufferViews"].as_array().unwrap();
        let ext = |v: usize| &views[v]["extensions"][EXTENSION];
        assert_eq!(ext(0)["mode"], "ATTRIBUTES");
        assert_eq!(ext(0)["byteStride"], 12);
        assert_eq!(ext(1)["mode"], "TRIANGLES");
        assert!(views[2].get("extensions").is_none());
        // The image is copied as it was.
        let at = views[2]["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(&out[at..at + 64], image.as_slice());
        // Each compressed view decodes back to its bytes.
        let slice = |v: usize| {
            let (o, l) = (
                ext(v)["byteOffset"].as_u64().unwrap() as usize,
                ext(v)["byteLength"].as_u64().unwrap() as usize,
            );
            &out[o..o + l]
        };
        let back: Vec<[u8; 12]> = meshopt::encoding::decode_vertex_buffer(slice(0), 300).unwrap();
        assert_eq!(back.concat(), positions);
        // The index codec keeps the triangles in order, each maybe rotated (winding kept).
        let back: Vec<u16> = meshopt::encoding::decode_index_buffer(slice(1), 891).unwrap();
        for (k, t) in back.chunks_exact(3).enumerate() {
            let want = [k as u16, k as u16 + 1, k as u16 + 2];
            let rotations = [[t[0], t[1], t[2]], [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
            assert!(rotations.contains(&want), "triangle {k}: {t:?}");
        }
    }
}
