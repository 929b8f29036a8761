//! What real avatars are made of, before the `gltf` crate sees the file.
//!
//! The `gltf` crate refuses any file whose `extensionsRequired` names an extension it does not
//! implement (gltf-rs issue 400), which is every compressed or quantized avatar. So the JSON is
//! read here first, as plain JSON:
//!
//! - every required extension is checked against what faceanim reads, and one it does not is
//!   an error that names it;
//! - buffers are loaded (the GLB chunk, data URIs, files next to a `.gltf`), and a buffer that
//!   only exists as an `EXT_meshopt_compression` fallback is left empty;
//! - `EXT_meshopt_compression` buffer views are decoded (the `meshopt` crate: the vertex and
//!   index codecs and the octahedral, quaternion, exponential and colour filters) into one new
//!   buffer, and the views point there;
//! - `KHR_draco_mesh_compression` primitives are decoded natively (see [`super::draco`]);
//! - `KHR_mesh_quantization` needs nothing but to be allowed: the accessor reader already reads
//!   normalized and plain integers, and node transforms carry the dequantization;
//! - `EXT_texture_webp` and `KHR_texture_basisu` textures get their image as `source`;
//!   `KHR_texture_transform` on a base-colour texture is recorded so the importer can bake it
//!   into the UVs;
//! - VRM 0.x (`VRM`) and 1.0 (`VRMC_vrm`) expressions are read (see [`super::vrm`]);
//! - an accessor with neither a buffer view nor sparse values, which the specification makes
//!   all zeros (glTF Transform writes a morph target that does not move a primitive so), gets
//!   one sparse zero, as the `gltf` crate requires one or the other.
//!
//! Then the JSON, rewritten, goes to the `gltf` crate's own validation as before.

use std::borrow::Cow;
use std::collections::HashMap;

use serde_json::Value;

use super::accessor::Buffers;
use super::types::ImportErrorKind;

/// Required extensions faceanim reads (a `KHR_materials_*` extension only changes how a
/// surface looks, so it is read as the plain PBR material underneath).
const UNDERSTOOD: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_texture_transform",
    "EXT_texture_webp",
    "KHR_texture_basisu",
    "KHR_draco_mesh_compression",
];

/// The JSON and buffers, ready for the `gltf` crate, with what was read from extensions.
pub(crate) struct Prepared<'a> {
    /// The rewritten glTF JSON.
    pub root: gltf::json::Root,
    /// One entry per buffer of `root` (decoded meshopt data last).
    pub buffers: Buffers<'a>,
    /// `KHR_texture_transform` of each material's base-colour texture, by material index.
    pub uv_transforms: HashMap<usize, UvTransform>,
    /// The VRM extension's expressions and facing, if the file is a VRM.
    pub vrm: Option<super::vrm::Vrm>,
    /// The file as it will be written back: its JSON (meshopt views decoded, one buffer,
    /// images embedded) and that buffer's bytes.
    pub kept: (Value, Vec<u8>),
    /// What was worked around, one sentence each.
    pub warnings: Vec<String>,
    /// Whether the file's buffer views were meshopt-compressed (exports compress them again).
    pub meshopt: bool,
}

/// A texture-coordinate transform (`KHR_texture_transform`): scale, then rotate, then offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct UvTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl UvTransform {
    /// The transformed coordinate, as the extension's matrix T · R · S applies it.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.rotation.sin_cos();
        let x = uv[0] * self.scale[0];
        let y = uv[1] * self.scale[1];
        [
            c * x + s * y + self.offset[0],
            -s * x + c * y + self.offset[1],
        ]
    }
}

/// Reads and rewrites the JSON, loads and decodes the buffers.
pub(crate) fn prepare<'a>(
    json: &[u8],
    bin: Option<&'a [u8]>,
    resources: &dyn super::types::Resources,
) -> Result<Prepared<'a>, ImportErrorKind> {
    let mut value: Value =
        serde_json::from_slice(json).map_err(|e| ImportErrorKind::InvalidJson(e.to_string()))?;
    if !value.is_object() {
        return Err(ImportErrorKind::InvalidJson(
            "the top level is not a JSON object".into(),
        ));
    }
    check_required(&value)?;
    let mut warnings = Vec::new();
    let mut buffers = load_buffers(&value, bin, resources)?;
    let meshopt = value
        .get("extensionsUsed")
        .and_then(Value::as_array)
        .is_some_and(|used| {
            used.iter().any(|e| {
                e.as_str().is_some_and(|e| {
                    e == "EXT_meshopt_compression" || e == "KHR_meshopt_compression"
                })
            })
        });
    decode_meshopt(&mut value, &mut buffers)?;
    super::draco::decode(&mut value, &mut buffers)?;
    let kept = keep(&value, &buffers, resources, &mut warnings);
    zeros_as_sparse(&mut value, &mut buffers);
    resolve_texture_sources(&mut value);
    let uv_transforms = uv_transforms(&value);
    let vrm = super::vrm::read(&value, &mut warnings);
    unread_channels_dropped(&mut value, &mut warnings);
    // What is handled here must not reach the `gltf` crate's extension check.
    drop_extensions(&mut value, |name| UNDERSTOOD.contains(&name));
    // A value of the wrong type is named by its path (`meshes[0].primitives[1].indices`).
    let root: gltf::json::Root =
        crate::json::from_value(value).map_err(|e| ImportErrorKind::InvalidJson(e.to_string()))?;
    Ok(Prepared {
        root,
        buffers: Buffers(buffers),
        uv_transforms,
        vrm,
        kept,
        warnings,
        meshopt,
    })
}

/// The file rewritten to be written back as one GLB: every buffer's bytes in one, the views
/// moved onto it, external and data-URI images embedded, the meshopt extension dropped (its
/// views are decoded).
fn keep(
    value: &Value,
    buffers: &[Cow<'_, [u8]>],
    resources: &dyn super::types::Resources,
    warnings: &mut Vec<String>,
) -> (Value, Vec<u8>) {
    let mut doc = value.clone();
    let mut bin: Vec<u8> = Vec::new();
    let mut base = Vec::with_capacity(buffers.len());
    for data in buffers {
        while !bin.len().is_multiple_of(16) {
            bin.push(0);
        }
        base.push(bin.len());
        bin.extend_from_slice(data);
    }
    if let Some(Value::Array(views)) = doc.get_mut("bufferViews") {
        for view in views {
            let buffer = view
                .get("buffer")
                .and_then(Value::as_u64)
                .and_then(|b| usize::try_from(b).ok());
            let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
            if let Some(&start) = buffer.and_then(|b| base.get(b)) {
                view["buffer"] = Value::from(0);
                view["byteOffset"] = Value::from(start as u64 + offset);
            }
        }
    }
    let mut new_views = Vec::new();
    if let Some(Value::Array(images)) = doc.get_mut("images") {
        for (i, image) in images.iter_mut().enumerate() {
            let Some(uri) = image.get("uri").and_then(Value::as_str).map(str::to_owned) else {
                continue;
            };
            match super::uri::load_uri(&uri, resources) {
                Ok(bytes) => {
                    while !bin.len().is_multiple_of(4) {
                        bin.push(0);
                    }
                    new_views.push(serde_json::json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len() }));
                    bin.extend_from_slice(&bytes);
                    let mime = super::uri::sniff_image(&bytes)
                        .map(str::to_owned)
                        .or_else(|| {
                            image
                                .get("mimeType")
                                .and_then(Value::as_str)
                                .map(str::to_owned)
                        })
                        .unwrap_or_else(|| "image/png".to_owned());
                    if let Some(object) = image.as_object_mut() {
                        object.remove("uri");
                        object.insert("mimeType".into(), Value::from(mime));
                        object.insert("bufferView".into(), Value::Null);
                    }
                }
                Err(reason) => warnings.push(format!(
                    "image {i} ('{}') cannot be embedded in exports: {reason}",
                    crate::excerpt(&uri).into_owned()
                )),
            }
        }
    }
    if !new_views.is_empty() {
        let first = doc
            .get("bufferViews")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        let mut next = first;
        if let Some(Value::Array(images)) = doc.get_mut("images") {
            for image in images
                .iter_mut()
                .filter(|i| i.get("bufferView") == Some(&Value::Null))
            {
                image["bufferView"] = Value::from(next);
                next += 1;
            }
        }
        match doc.get_mut("bufferViews") {
            Some(Value::Array(views)) => views.extend(new_views),
            _ => doc["bufferViews"] = Value::Array(new_views),
        }
    }
    doc["buffers"] = serde_json::json!([{ "byteLength": bin.len() }]);
    drop_extensions(&mut doc, |name| {
        name == "EXT_meshopt_compression" || name == "KHR_meshopt_compression"
    });
    (doc, bin)
}

/// The animation target paths glTF 2.0 defines.
const PATHS: [&str; 4] = ["translation", "rotation", "scale", "weights"];

/// Leaves out of what is read (the file kept to write back keeps them) the animation channels
/// the `gltf` crate cannot read, each with a warning naming it: a target path glTF 2.0 does not
/// define (`pointer`, by which `KHR_animation_pointer` animates materials and lights, as
/// Blender 4 exports them; a misspelt one) or a target node the file does not have. That crate
/// checks neither and answers such a channel's path or node by panicking.
fn unread_channels_dropped(value: &mut Value, warnings: &mut Vec<String>) {
    let nodes = value
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let Some(animations) = value.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    for (a, animation) in animations.iter_mut().enumerate() {
        let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) else {
            continue;
        };
        let mut c = 0;
        channels.retain(|channel| {
            let at = c;
            c += 1;
            let path = channel.pointer("/target/path").and_then(Value::as_str);
            let node = channel.pointer("/target/node").and_then(Value::as_u64);
            let why = match (path, node) {
                (Some(p), _) if !PATHS.contains(&p) => {
                    Some(format!("it animates '{p}', which faceanim does not read"))
                }
                (Some(_), Some(n)) if n >= nodes as u64 => Some(format!(
                    "it animates node {n}, which the file does not have"
                )),
                (Some(_), None) => Some("it names no node".to_owned()),
                // A path that is no string: the gltf crate's own check names it.
                _ => None,
            };
            if let Some(why) = &why {
                warnings.push(format!("animations[{a}].channels[{at}]: {why}; left out"));
            }
            why.is_none()
        });
    }
}

/// Takes the extensions `drop` says from `extensionsRequired` and `extensionsUsed`, removing a
/// list that ends up empty.
fn drop_extensions(doc: &mut Value, drop: impl Fn(&str) -> bool) {
    for list in ["extensionsRequired", "extensionsUsed"] {
        if let Some(Value::Array(names)) = doc.get_mut(list) {
            names.retain(|n| n.as_str().is_none_or(|n| !drop(n)));
            if names.is_empty()
                && let Some(object) = doc.as_object_mut()
            {
                object.remove(list);
            }
        }
    }
}

/// Refuses a file that requires an extension faceanim does not read, naming it.
fn check_required(value: &Value) -> Result<(), ImportErrorKind> {
    let Some(required) = value.get("extensionsRequired") else {
        return Ok(());
    };
    let Some(required) = required.as_array() else {
        return Err(ImportErrorKind::InvalidJson(
            "extensionsRequired: not an array".into(),
        ));
    };
    for (i, name) in required.iter().enumerate() {
        let Some(name) = name.as_str() else {
            return Err(ImportErrorKind::InvalidJson(format!(
                "extensionsRequired[{i}]: not a string"
            )));
        };
        let known = UNDERSTOOD.contains(&name)
            || name.starts_with("KHR_materials_")
            || gltf::json::extensions::ENABLED_EXTENSIONS.contains(&name);
        if !known {
            return Err(ImportErrorKind::Unsupported(format!(
                "the file requires the glTF extension {name}, which faceanim does not read"
            )));
        }
    }
    Ok(())
}

/// The bytes of every buffer, in order. A GLB's first buffer without a URI is its BIN chunk;
/// a meshopt fallback buffer without a URI has no bytes (its views are decoded instead).
fn load_buffers<'a>(
    value: &Value,
    bin: Option<&'a [u8]>,
    resources: &dyn super::types::Resources,
) -> Result<Vec<Cow<'a, [u8]>>, ImportErrorKind> {
    let Some(list) = value.get("buffers") else {
        return Ok(Vec::new());
    };
    let list = list
        .as_array()
        .ok_or_else(|| ImportErrorKind::InvalidJson("buffers: not an array".into()))?;
    let mut out = Vec::with_capacity(list.len());
    for (index, buffer) in list.iter().enumerate() {
        let declared = buffer
            .get("byteLength")
            .and_then(Value::as_u64)
            .ok_or_else(|| {
                ImportErrorKind::InvalidJson(format!(
                    "buffers[{index}].byteLength: missing or not a whole number"
                ))
            })?;
        let declared = usize::try_from(declared).unwrap_or(usize::MAX);
        let fallback = buffer
            .pointer("/extensions/EXT_meshopt_compression/fallback")
            .or_else(|| buffer.pointer("/extensions/KHR_meshopt_compression/fallback"))
            .and_then(Value::as_bool)
            == Some(true);
        let (data, uri): (Cow<'a, [u8]>, String) = match buffer.get("uri").and_then(Value::as_str) {
            Some(uri) => {
                let data = super::uri::load_uri(uri, resources).map_err(|reason| {
                    ImportErrorKind::MissingBuffer {
                        index,
                        uri: crate::excerpt(uri).into_owned(),
                        reason,
                    }
                })?;
                (Cow::Owned(data), crate::excerpt(uri).into_owned())
            }
            None if fallback => (Cow::Borrowed(&[][..]), String::new()),
            None if index == 0 => {
                let data = bin.ok_or_else(|| ImportErrorKind::MissingBuffer {
                    index,
                    uri: "GLB BIN chunk".into(),
                    reason: "the file has no binary chunk".into(),
                })?;
                (Cow::Borrowed(data), "GLB BIN chunk".to_owned())
            }
            None => {
                return Err(ImportErrorKind::MissingBuffer {
                    index,
                    uri: String::new(),
                    reason: "it has no uri and only a GLB's first buffer may use the BIN chunk"
                        .into(),
                });
            }
        };
        if !fallback && data.len() < declared {
            return Err(ImportErrorKind::Truncated(format!(
                "buffer {index} ('{uri}') has {} bytes but the file declares {declared}",
                data.len()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// Decodes every meshopt-compressed buffer view into one new buffer and points the views at it.
fn decode_meshopt(
    value: &mut Value,
    buffers: &mut Vec<Cow<'_, [u8]>>,
) -> Result<(), ImportErrorKind> {
    let new_index = buffers.len();
    let mut decoded: Vec<u8> = Vec::new();
    let Some(Value::Array(views)) = value.get_mut("bufferViews") else {
        return Ok(());
    };
    for (v, view) in views.iter_mut().enumerate() {
        let Some(extensions) = view.get_mut("extensions").and_then(Value::as_object_mut) else {
            continue;
        };
        let Some(ext) = extensions
            .remove("EXT_meshopt_compression")
            .or_else(|| extensions.remove("KHR_meshopt_compression"))
        else {
            continue;
        };
        let field =
            |name: &str| format!("bufferViews[{v}].extensions.EXT_meshopt_compression.{name}");
        let number = |name: &str, default: Option<u64>| -> Result<usize, ImportErrorKind> {
            ext.get(name)
                .map_or(default, Value::as_u64)
                .and_then(|n| usize::try_from(n).ok())
                .ok_or_else(|| {
                    ImportErrorKind::InvalidJson(format!(
                        "{}: missing or not a whole number",
                        field(name)
                    ))
                })
        };
        let buffer = number("buffer", None)?;
        let offset = number("byteOffset", Some(0))?;
        let length = number("byteLength", None)?;
        let stride = number("byteStride", None)?;
        let count = number("count", None)?;
        let mode = ext.get("mode").and_then(Value::as_str).unwrap_or_default();
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let source = buffers.get(buffer).ok_or_else(|| {
            ImportErrorKind::InvalidJson(format!(
                "{}: buffer {buffer} does not exist",
                field("buffer")
            ))
        })?;
        let source = offset
            .checked_add(length)
            .and_then(|end| source.get(offset..end))
            .ok_or_else(|| {
                ImportErrorKind::Truncated(format!(
                    "{}: bytes {offset}..{} are past the end of buffer {buffer} ({} bytes)",
                    field("byteLength"),
                    offset.saturating_add(length),
                    source.len()
                ))
            })?;
        let total = count
            .checked_mul(stride)
            .filter(|&n| n <= 1 << 31)
            .ok_or_else(|| {
                ImportErrorKind::TooLarge(format!(
                    "{}: {count} elements of {stride} bytes",
                    field("count")
                ))
            })?;
        let bytes = decode_view(source, count, stride, mode, filter).map_err(|problem| {
            ImportErrorKind::InvalidJson(format!("bufferViews[{v}] (meshopt {mode}): {problem}"))
        })?;
        debug_assert_eq!(bytes.len(), total);
        while !decoded.len().is_multiple_of(16) {
            decoded.push(0);
        }
        let at = decoded.len();
        decoded.extend_from_slice(&bytes);
        if extensions.is_empty()
            && let Some(object) = view.as_object_mut()
        {
            object.remove("extensions");
        }
        view["buffer"] = Value::from(new_index);
        view["byteOffset"] = Value::from(at);
        view["byteLength"] = Value::from(total);
    }
    if !decoded.is_empty() {
        super::buffers::push_buffer(value, buffers, decoded);
    }
    Ok(())
}

/// The largest element an accessor has: a float `MAT4`.
const LARGEST_ELEMENT: usize = 64;

/// Every accessor with neither `bufferView` nor `sparse` gets a sparse substitution of one
/// zero at index 0, read from a new buffer of zeros: the specification initialises such an
/// accessor with zeros, and the `gltf` crate's validation refuses it as missing its data.
fn zeros_as_sparse(value: &mut Value, buffers: &mut Vec<Cow<'_, [u8]>>) {
    let Some(Value::Array(accessors)) = value.get("accessors") else {
        return;
    };
    let empty: Vec<usize> = accessors
        .iter()
        .enumerate()
        .filter(|(_, a)| {
            // Anything but an object is left to the `gltf` crate's validation to name.
            a.is_object() && a.get("bufferView").is_none() && a.get("sparse").is_none()
        })
        .map(|(i, _)| i)
        .collect();
    if empty.is_empty() {
        return;
    }
    let buffer = buffers.len();
    let views = value.as_object_mut().map(|root| {
        root.entry("bufferViews")
            .or_insert_with(|| Value::Array(Vec::new()))
    });
    let Some(Value::Array(views)) = views else {
        return;
    };
    let indices = views.len();
    views.push(serde_json::json!({ "buffer": buffer, "byteOffset": 0, "byteLength": 4 }));
    views.push(serde_json::json!({
        "buffer": buffer, "byteOffset": 4, "byteLength": LARGEST_ELEMENT
    }));
    if let Some(Value::Array(accessors)) = value.get_mut("accessors") {
        for i in empty {
            accessors[i]["sparse"] = serde_json::json!({
                "count": 1,
                "indices": { "bufferView": indices, "componentType": 5125 },
                "values": { "bufferView": indices + 1 },
            });
        }
    }
    super::buffers::push_buffer(value, buffers, vec![0; 4 + LARGEST_ELEMENT]);
}

/// A byte block of `N` bytes: one vertex of the meshopt vertex codec, whose element size is a
/// type parameter in the `meshopt` crate.
#[derive(Clone, Copy)]
struct Block<const N: usize>([u8; N]);

impl<const N: usize> Default for Block<N> {
    fn default() -> Self {
        Block([0; N])
    }
}

fn vertices<const N: usize>(source: &[u8], count: usize) -> Result<Vec<u8>, String> {
    let out: Vec<Block<N>> =
        meshopt::encoding::decode_vertex_buffer(source, count).map_err(|e| e.to_string())?;
    Ok(out.into_iter().flat_map(|b| b.0).collect())
}

/// Decodes one view's data: `count` elements of `stride` bytes.
fn decode_view(
    source: &[u8],
    count: usize,
    stride: usize,
    mode: &str,
    filter: &str,
) -> Result<Vec<u8>, String> {
    let mut bytes = match mode {
        "ATTRIBUTES" => {
            macro_rules! strides {
                ($($n:literal)*) => {
                    match stride {
                        $($n => vertices::<$n>(source, count)?,)*
                        other => return Err(format!("byteStride {other} is not a multiple of 4 up to 256")),
                    }
                };
            }
            strides!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100
                104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180
                184 188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
        }
        "TRIANGLES" | "INDICES" => {
            // Decoded as 32-bit indices, then written at the view's width (a 16-bit view's
            // indices fit 16 bits; meshopt keeps the low bits the same way).
            let out: Vec<u32> = if mode == "INDICES" {
                meshopt::encoding::decode_index_sequence(source, count)
            } else {
                meshopt::encoding::decode_index_buffer(source, count)
            }
            .map_err(|e| e.to_string())?;
            match stride {
                2 => out
                    .into_iter()
                    .flat_map(|i| (i as u16).to_le_bytes())
                    .collect(),
                4 => out.into_iter().flat_map(u32::to_le_bytes).collect(),
                other => return Err(format!("index byteStride {other} (2 or 4 expected)")),
            }
        }
        other => return Err(format!("unknown mode '{other}'")),
    };
    if mode == "TRIANGLES" && !count.is_multiple_of(3) {
        return Err(format!("TRIANGLES count {count} is not a multiple of 3"));
    }
    apply_filter(&mut bytes, stride, filter)?;
    Ok(bytes)
}

/// Undoes a meshopt filter in place.
fn apply_filter(bytes: &mut [u8], stride: usize, filter: &str) -> Result<(), String> {
    fn typed<A: bytemuck::Pod>(bytes: &mut [u8], decode: impl Fn(&mut [A])) {
        let mut items: Vec<A> = bytes
            .chunks_exact(std::mem::size_of::<A>())
            .map(bytemuck::pod_read_unaligned)
            .collect();
        decode(&mut items);
        bytes.copy_from_slice(bytemuck::cast_slice(&items));
    }
    match (filter, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => typed::<[i8; 4]>(bytes, meshopt::encoding::decode_filter_oct::<i8>),
        ("OCTAHEDRAL", 8) => typed::<[i16; 4]>(bytes, meshopt::encoding::decode_filter_oct::<i16>),
        ("QUATERNION", 8) => typed::<[i16; 4]>(bytes, meshopt::encoding::decode_filter_quat),
        ("COLOR", 4) => typed::<[i8; 4]>(bytes, meshopt::encoding::decode_filter_color::<i8>),
        ("COLOR", 8) => typed::<[i16; 4]>(bytes, meshopt::encoding::decode_filter_color::<i16>),
        ("EXPONENTIAL", s) if s % 4 == 0 && s <= 16 => match s {
            4 => typed::<[u32; 1]>(bytes, meshopt::encoding::decode_filter_exp::<1>),
            8 => typed::<[u32; 2]>(bytes, meshopt::encoding::decode_filter_exp::<2>),
            12 => typed::<[u32; 3]>(bytes, meshopt::encoding::decode_filter_exp::<3>),
            _ => typed::<[u32; 4]>(bytes, meshopt::encoding::decode_filter_exp::<4>),
        },
        (other, s) => return Err(format!("filter {other} with byteStride {s} is not defined")),
    }
    Ok(())
}

/// Gives textures that carry their image only in `EXT_texture_webp` or `KHR_texture_basisu`
/// that image as `source` (WebP first, over a PNG/JPEG fallback; a KTX2 image only where there
/// is no fallback: the fallback is what the author meant for viewers without a transcoder).
fn resolve_texture_sources(value: &mut Value) {
    let Some(Value::Array(textures)) = value.get_mut("textures") else {
        return;
    };
    for texture in textures.iter_mut() {
        let from_extension = ["EXT_texture_webp", "KHR_texture_basisu"]
            .iter()
            .find_map(|ext| {
                texture
                    .pointer(&format!("/extensions/{ext}/source"))
                    .and_then(Value::as_u64)
                    .map(|s| (*ext, s))
            });
        let has_source = texture.get("source").is_some();
        match from_extension {
            Some(("EXT_texture_webp", source)) => {
                // The WebP image is what the author meant; a PNG/JPEG `source` is a fallback.
                texture["source"] = Value::from(source);
            }
            Some((_, source)) if !has_source => {
                texture["source"] = Value::from(source);
            }
            _ => {}
        }
    }
}

/// `KHR_texture_transform` on each material's base-colour texture (texture coordinate set 0).
fn uv_transforms(value: &Value) -> HashMap<usize, UvTransform> {
    let mut out = HashMap::new();
    let Some(materials) = value.get("materials").and_then(Value::as_array) else {
        return out;
    };
    for (m, material) in materials.iter().enumerate() {
        let Some(t) = material
            .pointer("/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform")
        else {
            continue;
        };
        let pair = |name: &str, default: [f32; 2]| {
            t.get(name)
                .and_then(Value::as_array)
                .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
                .filter(|p| p.iter().all(|v| v.is_finite()))
                .unwrap_or(default)
        };
        let transform = UvTransform {
            offset: pair("offset", [0.0, 0.0]),
            rotation: t
                .get("rotation")
                .and_then(Value::as_f64)
                .map(|r| r as f32)
                .filter(|r| r.is_finite())
                .unwrap_or(0.0),
            scale: pair("scale", [1.0, 1.0]),
        };
        out.insert(m, transform);
    }
    out
}
