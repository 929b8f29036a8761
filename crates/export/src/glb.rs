//! Writing a character (and optional morph-weight animations) as a binary glTF 2.0 file, two
//! ways: [`export_into_source`] writes the user's own file back with the animation added (see
//! there), and [`export_glb`] writes the character as faceanim sees it, one mesh.
//!
//! Layout choices of the one-mesh file, each for interchange with Blender, Unity, Unreal and
//! three.js:
//! - one node, one mesh, one primitive per material part; all primitives share the same vertex
//!   accessors, so vertex order and count survive a round trip exactly;
//! - morph targets as *sparse* accessors holding only moved vertices (compact, and read by all
//!   four), with `mesh.extras.targetNames` naming them;
//! - animations as `weights` channels with LINEAR interpolation, one key per clip frame, and
//!   optionally a `rotation` channel on the same node (a captured head pose); each marked as
//!   faceanim's in its `extras` (`{"faceanim": {"take": true}}`), so that the file opens again
//!   as that take and a later export replaces it rather than adding a copy.

use glam::Vec3;
use serde_json::{Value, json};

use faceanim_rig::Character;
use faceanim_rig::animation::MorphAnimation;

/// Why an export could not be written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GlbError {
    /// An animation's data does not fit the character.
    #[error("animation '{name}': {problem}")]
    BadAnimation {
        /// The animation.
        name: String,
        /// What is wrong.
        problem: String,
    },
    /// The binary chunk would exceed the 4 GiB a GLB can address.
    #[error("the file would exceed 4 GiB")]
    TooLarge,
    /// Writing into the user's file, for a character that did not come from one.
    #[error("{0} was not imported from a glTF file, so there is no file of its own to write into")]
    NoSource(String),
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// The binary chunk and the buffer views and accessors that describe it.
#[derive(Default)]
pub(crate) struct Bin {
    pub(crate) bytes: Vec<u8>,
    pub(crate) views: Vec<Value>,
    pub(crate) accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut view =
            json!({ "buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len() });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bytes.extend_from_slice(data);
        self.views.push(view);
        self.views.len() - 1
    }

    fn accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    pub(crate) fn floats(
        &mut self,
        values: &[f32],
        kind: &str,
        target: Option<u32>,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let components = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "MAT4" => 16,
            _ => 4,
        };
        let view = self.view(&f32_bytes(values), target);
        let mut accessor = json!({ "bufferView": view, "componentType": FLOAT, "count": values.len() / components, "type": kind });
        if let Some((min, max)) = bounds {
            accessor["min"] = exact(&min);
            accessor["max"] = exact(&max);
        }
        self.accessor(accessor)
    }

    /// An animation's key times (checked non-empty and increasing), with the min and max an
    /// animation sampler's input needs.
    pub(crate) fn key_times(&mut self, times: &[f32]) -> usize {
        let (first, last) = (times[0], times[times.len() - 1]);
        self.floats(times, "SCALAR", None, Some((vec![first], vec![last])))
    }

    /// A VEC3 accessor of `count` elements, zero except at `indices`; min/max when asked.
    fn sparse_vec3(
        &mut self,
        count: usize,
        indices: &[u32],
        values: &[Vec3],
        with_bounds: bool,
    ) -> usize {
        let mut accessor = json!({ "componentType": FLOAT, "count": count, "type": "VEC3" });
        if with_bounds {
            // Unmoved vertices contribute zeros to the bounds.
            let (mut min, mut max) = if indices.len() < count {
                (Vec3::ZERO, Vec3::ZERO)
            } else {
                (Vec3::INFINITY, Vec3::NEG_INFINITY)
            };
            for v in values {
                min = min.min(*v);
                max = max.max(*v);
            }
            accessor["min"] = exact(&min.to_array());
            accessor["max"] = exact(&max.to_array());
        }
        // An all-zero target still gets one explicit (zero) entry: some readers reject an
        // accessor with neither a buffer view nor sparse data, although the spec allows it.
        let (indices, values) = if indices.is_empty() {
            (&[0u32][..], &[Vec3::ZERO][..])
        } else {
            (indices, values)
        };
        let index_view = self.view(&u32_bytes(indices), None);
        let flat: Vec<f32> = values.iter().flat_map(|v| v.to_array()).collect();
        let value_view = self.view(&f32_bytes(&flat), None);
        accessor["sparse"] = json!({
            "count": indices.len(),
            "indices": { "bufferView": index_view, "componentType": UNSIGNED_INT },
            "values": { "bufferView": value_view },
        });
        self.accessor(accessor)
    }
}

/// Writes `character` and `animations` as a GLB.
///
/// # Errors
/// An animation whose key count, weight count or times do not fit, or a file over 4 GiB.
pub fn export_glb(
    character: &Character,
    animations: &[MorphAnimation],
) -> Result<Vec<u8>, GlbError> {
    export_glb_skinned(character, animations, None)
}

/// [`export_glb`], the mesh skinned to `skeleton` where one is given (the studio's view: see
/// [`crate::bones::ViewRig`]); its joints are nodes 1 onwards, named `faceanim_` and the bone (`faceanim_head`).
///
/// # Errors
/// As [`export_glb`].
pub fn export_glb_skinned(
    character: &Character,
    animations: &[MorphAnimation],
    skeleton: Option<&crate::bones::ViewRig>,
) -> Result<Vec<u8>, GlbError> {
    let shape_count = character.blendshapes().len();
    for animation in animations {
        check_animation(animation, shape_count)?;
    }
    let n = character.vertex_count();
    let mut bin = Bin::default();

    let positions: Vec<f32> = character
        .positions()
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    let bounds = character.bounds();
    let position = bin.floats(
        &positions,
        "VEC3",
        Some(ARRAY_BUFFER),
        Some((
            bounds.min.to_array().to_vec(),
            bounds.max.to_array().to_vec(),
        )),
    );
    let normals: Vec<f32> = character
        .normals()
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    let normal = bin.floats(&normals, "VEC3", Some(ARRAY_BUFFER), None);
    let mut attributes = json!({ "POSITION": position, "NORMAL": normal });
    if let Some(uvs) = character.uvs() {
        let flat: Vec<f32> = uvs.iter().flatten().copied().collect();
        attributes["TEXCOORD_0"] = json!(bin.floats(&flat, "VEC2", Some(ARRAY_BUFFER), None));
    }
    if let Some(colors) = character.colors() {
        let flat: Vec<f32> = colors.iter().flatten().copied().collect();
        attributes["COLOR_0"] = json!(bin.floats(&flat, "VEC4", Some(ARRAY_BUFFER), None));
    }
    let skin = skeleton.map(|rig| {
        let (joints, weights) = rig.skin(character);
        let flat: Vec<u8> = joints.iter().flatten().copied().collect();
        let view = bin.view(&flat, Some(ARRAY_BUFFER));
        attributes["JOINTS_0"] = json!(bin.accessor(
            json!({ "bufferView": view, "componentType": UNSIGNED_BYTE, "count": n, "type": "VEC4" })
        ));
        let flat: Vec<f32> = weights.iter().flatten().copied().collect();
        attributes["WEIGHTS_0"] = json!(bin.floats(&flat, "VEC4", Some(ARRAY_BUFFER), None));
        skin_json(rig, &mut bin)
    });

    let targets: Vec<Value> = character
        .blendshapes()
        .iter()
        .zip(character.normal_deltas())
        .map(|(shape, normal_deltas)| {
            let p = bin.sparse_vec3(n, shape.indices(), shape.deltas(), true);
            let nd = bin.sparse_vec3(n, &normal_deltas.indices, &normal_deltas.deltas, false);
            json!({ "POSITION": p, "NORMAL": nd })
        })
        .collect();

    let (materials, images, textures) = materials_json(character, &mut bin);
    let small_indices = n <= usize::from(u16::MAX);
    let mut primitives = Vec::new();
    for part in character.parts() {
        let tris = &character.triangles()[part.triangles.clone()];
        if tris.is_empty() {
            continue;
        }
        let flat: Vec<u32> = tris.iter().flatten().copied().collect();
        let (bytes, component) = if small_indices {
            (
                flat.iter()
                    .flat_map(|&i| (i as u16).to_le_bytes())
                    .collect(),
                UNSIGNED_SHORT,
            )
        } else {
            (u32_bytes(&flat), UNSIGNED_INT)
        };
        let view = bin.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        let indices = bin.accessor(json!({ "bufferView": view, "componentType": component, "count": flat.len(), "type": "SCALAR" }));
        let mut primitive = json!({ "attributes": attributes, "indices": indices, "material": part.material.0, "mode": 4 });
        if !targets.is_empty() {
            primitive["targets"] = json!(targets);
        }
        primitives.push(primitive);
    }

    let names: Vec<&str> = character.blendshapes().iter().map(|b| b.name()).collect();
    let mut mesh = json!({ "name": character.name(), "primitives": primitives });
    if shape_count > 0 {
        mesh["weights"] = json!(vec![0.0; shape_count]);
        mesh["extras"] = json!({ "targetNames": names });
    }

    let animations_json: Vec<Value> = animations
        .iter()
        .map(|animation| {
            let input = bin.key_times(&animation.times);
            let flat: Vec<f32> = animation.weights.iter().flatten().copied().collect();
            let output = bin.floats(&flat, "SCALAR", None, None);
            let mut samplers =
                vec![json!({ "input": input, "output": output, "interpolation": "LINEAR" })];
            let mut channels =
                vec![json!({ "sampler": 0, "target": { "node": 0, "path": "weights" } })];
            if let Some(rotations) = &animation.rotations {
                let flat: Vec<f32> = rotations.iter().flatten().copied().collect();
                let output = bin.floats(&flat, "VEC4", None, None);
                samplers
                    .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
                channels.push(json!({ "sampler": 1, "target": { "node": 0, "path": "rotation" } }));
            }
            // The eyes and the jaw on the skeleton's joints, as the export turns the file's.
            for (joint, turns) in skeleton.map(|rig| rig.turns(character, animation)).unwrap_or_default() {
                let flat: Vec<f32> = turns.iter().flatten().copied().collect();
                let output = bin.floats(&flat, "VEC4", None, None);
                samplers
                    .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
                channels.push(json!({ "sampler": samplers.len() - 1, "target": { "node": joint + 1, "path": "rotation" } }));
            }
            json!({ "name": animation.name, "samplers": samplers, "channels": channels,
                    "extras": { faceanim_rig::file_animation::EXTRAS_KEY: { "take": true } } })
        })
        .collect();

    let mut nodes = vec![json!({ "name": character.name(), "mesh": 0 })];
    let mut scene_nodes = vec![0];
    if let Some((skin_nodes, _)) = &skin {
        nodes[0]["skin"] = json!(0);
        scene_nodes.push(1);
        nodes.extend(skin_nodes.iter().cloned());
    }
    let mut root = json!({
        "asset": { "version": "2.0", "generator": concat!("faceanim ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "nodes": scene_nodes }],
        "nodes": nodes,
        "meshes": [mesh],
        "materials": materials,
        "accessors": bin.accessors,
        "bufferViews": bin.views,
        "buffers": [{ "byteLength": bin.bytes.len() }],
    });
    if !animations_json.is_empty() {
        root["animations"] = json!(animations_json);
    }
    if let Some((_, skin)) = skin {
        root["skins"] = json!([skin]);
    }
    if textures.iter().any(|t| t.get("extensions").is_some()) {
        root["extensionsUsed"] = json!(["EXT_texture_webp"]);
        root["extensionsRequired"] = json!(["EXT_texture_webp"]);
    }
    if !images.is_empty() {
        root["images"] = json!(images);
        root["textures"] = json!(textures);
        root["samplers"] =
            json!([{ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 }]);
    }
    glb(&root, bin.bytes)
}

/// The joint nodes (numbered from 1, the rest first) and the skin of `rig`: each joint at its
/// place, unturned, its inverse bind matrix the move back from there.
fn skin_json(rig: &crate::bones::ViewRig, bin: &mut Bin) -> (Vec<Value>, Value) {
    let mut nodes: Vec<Value> = rig
        .joints
        .iter()
        .map(|joint| {
            let above = joint
                .parent
                .and_then(|p| rig.joints.get(p))
                .map_or(Vec3::ZERO, |p| p.pivot);
            let name = joint.bone.map_or("rest", faceanim_rig::bones::Bone::name);
            json!({ "name": format!("faceanim_{name}"),
                    "translation": exact(&(joint.pivot - above).to_array()) })
        })
        .collect();
    for (j, joint) in rig.joints.iter().enumerate() {
        if let Some(node) = joint.parent.and_then(|p| nodes.get_mut(p)) {
            let children = node
                .as_object_mut()
                .map(|o| o.entry("children").or_insert_with(|| json!([])));
            if let Some(Value::Array(list)) = children {
                list.push(json!(j + 1));
            }
        }
    }
    let inverse: Vec<f32> = rig
        .joints
        .iter()
        .flat_map(|j| glam::Mat4::from_translation(-j.pivot).to_cols_array())
        .collect();
    let matrices = bin.floats(&inverse, "MAT4", None, None);
    let joints: Vec<usize> = (1..=rig.joints.len()).collect();
    let skin = json!({ "joints": joints, "inverseBindMatrices": matrices, "skeleton": 1 });
    (nodes, skin)
}

pub(crate) fn check_animation(
    animation: &MorphAnimation,
    shape_count: usize,
) -> Result<(), GlbError> {
    let bad = |problem: String| GlbError::BadAnimation {
        name: animation.name.clone(),
        problem,
    };
    if animation.times.is_empty() {
        return Err(bad("it has no keys".into()));
    }
    if animation.times.len() != animation.weights.len() {
        return Err(bad(format!(
            "{} key times but {} weight vectors",
            animation.times.len(),
            animation.weights.len()
        )));
    }
    if let Some(k) = animation.times.iter().position(|t| !t.is_finite()) {
        return Err(bad(format!("key time {k} is not a finite number")));
    }
    if let Some(k) = animation.times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(bad(format!(
            "key times are not increasing at key {}",
            k + 1
        )));
    }
    for (k, w) in animation.weights.iter().enumerate() {
        if w.len() != shape_count {
            return Err(bad(format!(
                "key {k} has {} weights but the character has {shape_count} blendshapes",
                w.len()
            )));
        }
        if w.iter().any(|x| !x.is_finite()) {
            return Err(bad(format!(
                "key {k} has a weight that is not a finite number"
            )));
        }
    }
    if let Some(rotations) = &animation.rotations {
        if rotations.len() != animation.times.len() {
            return Err(bad(format!(
                "{} key times but {} rotations",
                animation.times.len(),
                rotations.len()
            )));
        }
        if let Some(k) = rotations.iter().position(|q| {
            let length = q.iter().map(|x| x * x).sum::<f32>().sqrt();
            !length.is_finite() || (length - 1.0).abs() > 1e-3
        }) {
            return Err(bad(format!("rotation {k} is not a unit quaternion")));
        }
    }
    Ok(())
}

fn materials_json(character: &Character, bin: &mut Bin) -> (Vec<Value>, Vec<Value>, Vec<Value>) {
    let mut images = Vec::new();
    let mut textures = Vec::new();
    let materials = character
        .materials()
        .iter()
        .map(|m| {
            let mut pbr = json!({
                "baseColorFactor": exact(&m.base_color),
                "metallicFactor": f64::from(m.metallic.clamp(0.0, 1.0)),
                "roughnessFactor": f64::from(m.roughness.clamp(0.0, 1.0)),
            });
            // A browser shows KTX2 only through a transcoder the page does not carry: it goes
            // as PNG. One that does not decode is left out (the render says so; an export
            // into the user's own file keeps it as it was).
            let shown = m.base_color_texture.as_ref().and_then(|texture| {
                match faceanim_media::browser_image(std::path::Path::new(&m.name), &texture.bytes)
                {
                    Ok(Some(png)) => Some((std::borrow::Cow::Owned(png), "image/png")),
                    Ok(None) => Some((
                        std::borrow::Cow::Borrowed(&*texture.bytes),
                        texture.mime_type.as_str(),
                    )),
                    Err(_) => None,
                }
            });
            if let Some((bytes, mime_type)) = shown {
                let view = bin.view(&bytes, None);
                images.push(json!({ "bufferView": view, "mimeType": mime_type }));
                textures.push(if mime_type == "image/webp" {
                    json!({ "sampler": 0, "extensions": { "EXT_texture_webp": { "source": images.len() - 1 } } })
                } else {
                    json!({ "source": images.len() - 1, "sampler": 0 })
                });
                pbr["baseColorTexture"] = json!({ "index": textures.len() - 1 });
            }
            let mut material = json!({ "pbrMetallicRoughness": pbr });
            if !m.name.is_empty() {
                material["name"] = json!(m.name);
            }
            if m.double_sided {
                material["doubleSided"] = json!(true);
            }
            match m.alpha {
                // Lashes, brows and hair cut out by their texture (as VRoid writes them).
                faceanim_rig::AlphaMode::Mask { cutoff } => {
                    material["alphaMode"] = json!("MASK");
                    material["alphaCutoff"] = json!(f64::from(cutoff));
                }
                faceanim_rig::AlphaMode::Blend => material["alphaMode"] = json!("BLEND"),
                faceanim_rig::AlphaMode::Opaque if m.base_color[3] < 1.0 => {
                    material["alphaMode"] = json!("BLEND");
                }
                faceanim_rig::AlphaMode::Opaque => {}
            }
            material
        })
        .collect();
    (materials, images, textures)
}

/// f32s written as the f64 of the same value, so min/max compare exactly with the data.
pub(crate) fn exact(values: &[f32]) -> Value {
    json!(values.iter().map(|&v| f64::from(v)).collect::<Vec<f64>>())
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn u32_bytes(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

pub(crate) fn glb(root: &Value, mut bin: Vec<u8>) -> Result<Vec<u8>, GlbError> {
    let mut json = serde_json::to_vec(root).map_err(|_| GlbError::TooLarge)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total32 = u32::try_from(total).map_err(|_| GlbError::TooLarge)?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    Ok(out)
}

/// `bytes` (a GLB this module wrote) with `strokes` kept in the `extras` of the animation
/// named `name` that faceanim wrote (`{"faceanim": {"take": true, "strokes": …}}`), so that a
/// sketch opens again as its strokes. Unchanged when there is no such animation.
///
/// # Errors
/// [`GlbError::TooLarge`] past 4 GiB.
pub fn with_strokes(bytes: Vec<u8>, name: &str, strokes: &Value) -> Result<Vec<u8>, GlbError> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .and_then(|b| b.try_into().ok())
            .map(|b: [u8; 4]| u32::from_le_bytes(b) as usize)
    };
    let Some(json_len) = word(12) else {
        return Ok(bytes);
    };
    let Some(mut root) = bytes
        .get(20..20 + json_len)
        .and_then(|j| serde_json::from_slice::<Value>(j).ok())
    else {
        return Ok(bytes);
    };
    let bin_at = 20 + json_len;
    let bin = word(bin_at)
        .and_then(|len| bytes.get(bin_at + 8..bin_at + 8 + len))
        .map_or_else(Vec::new, <[u8]>::to_vec);
    let key = faceanim_rig::file_animation::EXTRAS_KEY;
    let target = root
        .get_mut("animations")
        .and_then(Value::as_array_mut)
        .and_then(|list| {
            list.iter_mut()
                .rev()
                .find(|a| a["name"] == name && a.pointer(&format!("/extras/{key}")).is_some())
        })
        .and_then(|a| a.pointer_mut(&format!("/extras/{key}")))
        .and_then(Value::as_object_mut);
    let Some(ours) = target else {
        return Ok(bytes);
    };
    ours.insert(
        faceanim_rig::file_animation::STROKES_KEY.to_owned(),
        strokes.clone(),
    );
    glb(&root, bin)
}

/// Writes `animations` into the user's own file: every node, mesh, skin, material, texture,
/// image, sampler, camera, extension and `extras` of the file stays as it was (same counts,
/// names and order; the file's animations are kept, and one faceanim wrote before under the
/// same name is replaced); the weight channels go on each node
/// whose mesh carries an animated target (all meshes that share a target name move together;
/// a VRM expression moves its bindings); blendshapes the character has beyond the file's own
/// (the sketch's baked corrective targets) are appended as morph targets to the meshes whose
/// vertices they move, with `targetNames` extended; a head turn goes on the neck and head bones
/// and a share of it on the upper spine (see [`crate::bones`]; without a head bone, on the
/// scene's root node). Meshopt-compressed input is written compressed again (see
/// [`Compression`]).
///
/// # Errors
/// [`GlbError::NoSource`] for a character made in code or from OBJ files,
/// [`GlbError::BadAnimation`] when an animation does not fit, [`GlbError::TooLarge`] past
/// 4 GiB.
pub fn export_into_source(
    character: &Character,
    animations: &[MorphAnimation],
) -> Result<Vec<u8>, GlbError> {
    export_into_source_with(character, animations, &[], Compression::AsRead)
}

/// How a GLB written into the user's own file is compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// As the file was read: meshopt-compressed views (`EXT_meshopt_compression`) compressed
    /// again, so the avatar keeps its size; a plain file stays plain.
    #[default]
    AsRead,
    /// Plain buffer views, for tools without a meshopt decoder (Blender's importer).
    None,
}

/// [`export_into_source`], with what each animation does to the eyes and the jaw (`keys`, by
/// animation; missing ones do nothing): gaze on the eye bones and `jawOpen` on the jaw bone
/// where the file has them (see [`crate::bones`]); a head turn is shared between upper spine,
/// neck and head; compressed as `compression` says.
///
/// # Errors
/// As [`export_into_source`].
#[expect(clippy::too_many_lines, reason = "one document, amended top to bottom")]
pub fn export_into_source_with(
    character: &Character,
    animations: &[MorphAnimation],
    keys: &[Option<&crate::bones::BoneKeys>],
    compression: Compression,
) -> Result<Vec<u8>, GlbError> {
    let Some(source) = character.source() else {
        return Err(GlbError::NoSource(character.name().to_owned()));
    };
    let shape_count = character.blendshapes().len();
    for animation in animations {
        check_animation(animation, shape_count)?;
    }
    let mut doc = source.document().clone();
    let mut take_array = |key: &str| match doc.get_mut(key).map(Value::take) {
        Some(Value::Array(items)) => items,
        _ => Vec::new(),
    };
    let mut bin = Bin {
        bytes: source.bin().to_vec(),
        views: take_array("bufferViews"),
        accessors: take_array("accessors"),
    };
    let mut meshes = take_array("meshes");
    let mut nodes = take_array("nodes");
    // A primitive that its exporter left without the targets its siblings have (which the
    // importer reads as not moving) gets zero targets, so that the file written is valid.
    for mesh in &mut meshes {
        pad_missing_targets(mesh, &mut bin);
    }

    let own = source.shapes().len().min(shape_count);

    // Per mesh: each of its targets as (character blendshape, weight) contributions.
    let mut contributions: std::collections::BTreeMap<usize, Vec<Vec<(usize, f32)>>> =
        std::collections::BTreeMap::new();
    let target_count = |mesh: &Value| {
        mesh.pointer("/primitives/0/targets")
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    };
    for (shape, bindings) in source.shapes()[..own].iter().enumerate() {
        for b in bindings {
            let (m, t) = (b.mesh as usize, b.target as usize);
            let Some(mesh) = meshes.get(m) else { continue };
            let slots = contributions
                .entry(m)
                .or_insert_with(|| vec![Vec::new(); target_count(mesh)]);
            if let Some(slot) = slots.get_mut(t) {
                slot.push((shape, b.weight));
            }
        }
    }

    // The corrective targets, appended to the meshes whose vertices they move.
    for extra in own..shape_count {
        let shape = &character.blendshapes()[extra];
        // (mesh, position accessor) → local index → local delta.
        let mut moved: std::collections::BTreeMap<(usize, usize), Vec<(u32, Vec3)>> =
            std::collections::BTreeMap::new();
        let mut seen = std::collections::HashSet::new();
        for (v, d) in shape.moves() {
            let Some(Some(origin)) = source.origins().get(v as usize) else {
                continue;
            };
            if !seen.insert((origin.mesh, origin.accessor, origin.local)) {
                continue;
            }
            let local = origin.to_local * d;
            if local.is_finite() {
                moved
                    .entry((origin.mesh as usize, origin.accessor as usize))
                    .or_default()
                    .push((origin.local, local));
            }
        }
        let touched: std::collections::BTreeSet<usize> = moved.keys().map(|(m, _)| *m).collect();
        for m in touched {
            let Some(mesh) = meshes.get_mut(m) else {
                continue;
            };
            let before = target_count(mesh);
            let slots = contributions
                .entry(m)
                .or_insert_with(|| vec![Vec::new(); before]);
            slots.push(vec![(extra, 1.0)]);
            let mut made: std::collections::HashMap<usize, Value> =
                std::collections::HashMap::new();
            let Some(primitives) = mesh.get_mut("primitives").and_then(Value::as_array_mut) else {
                continue;
            };
            for primitive in primitives.iter_mut() {
                let Some(accessor) = primitive
                    .pointer("/attributes/POSITION")
                    .and_then(Value::as_u64)
                    .map(|a| a as usize)
                else {
                    continue;
                };
                let target = match made.get(&accessor) {
                    Some(target) => target.clone(),
                    None => {
                        let count = bin
                            .accessors
                            .get(accessor)
                            .and_then(|a| a.get("count"))
                            .and_then(Value::as_u64)
                            .unwrap_or(0) as usize;
                        let mut entries = moved.get(&(m, accessor)).cloned().unwrap_or_default();
                        entries.sort_unstable_by_key(|(i, _)| *i);
                        entries.retain(|(i, _)| (*i as usize) < count);
                        let (indices, deltas): (Vec<u32>, Vec<Vec3>) = entries.into_iter().unzip();
                        let position = bin.sparse_vec3(count, &indices, &deltas, true);
                        // Every target of a primitive has the same attributes: the others zero.
                        let mut target = json!({ "POSITION": position });
                        let first = primitive
                            .pointer("/targets/0")
                            .cloned()
                            .unwrap_or(Value::Null);
                        for attribute in ["NORMAL", "TANGENT"] {
                            if first.get(attribute).is_some() {
                                target[attribute] = json!(bin.sparse_vec3(count, &[], &[], false));
                            }
                        }
                        made.insert(accessor, target.clone());
                        target
                    }
                };
                match primitive.get_mut("targets").and_then(Value::as_array_mut) {
                    Some(targets) => targets.push(target),
                    None => primitive["targets"] = json!([target]),
                }
            }
            let after = before + 1;
            if let Some(weights) = mesh.get_mut("weights").and_then(Value::as_array_mut) {
                weights.resize(after, json!(0.0));
            }
            let mut names: Vec<Value> = mesh
                .pointer("/extras/targetNames")
                .and_then(Value::as_array)
                .cloned()
                .unwrap_or_default();
            names.resize_with(before, || Value::Null);
            for (k, name) in names.iter_mut().enumerate() {
                if name.is_null() {
                    *name = json!(format!("target_{k}"));
                }
            }
            names.push(json!(shape.name()));
            if !mesh.get("extras").is_some_and(Value::is_object) {
                mesh["extras"] = json!({});
            }
            mesh["extras"]["targetNames"] = json!(names);
        }
    }

    // The nodes that show each animated mesh.
    let mut channels_for: Vec<(usize, usize)> = Vec::new();
    for (n, node) in nodes.iter().enumerate() {
        if let Some(m) = node.get("mesh").and_then(Value::as_u64).map(|m| m as usize)
            && contributions
                .get(&m)
                .is_some_and(|slots| slots.iter().any(|s| !s.is_empty()))
        {
            channels_for.push((n, m));
        }
    }
    // The bones the animations turn, as TRS (an animated node may not have a matrix).
    let key_of = |a: usize| keys.get(a).copied().flatten();
    let wants = [
        animations.iter().any(|a| a.rotations.is_some()),
        (0..animations.len()).any(|a| key_of(a).is_some_and(|k| k.gaze.is_some())),
        (0..animations.len()).any(|a| key_of(a).is_some_and(|k| k.jaw.is_some())),
    ];
    // What opens the mouth through the retarget map, where an animation's keys carry it.
    let opening = (0..animations.len()).find_map(|a| key_of(a).and_then(|k| k.opening.as_deref()));
    let rig = crate::bones::Rig::prepare(character, source, &mut nodes, wants, opening);
    // Where the eye bones turn with the gaze, the eyeLook shapes hold still: the eyes turn
    // once (by bone, as VRM's lookAt says), not twice.
    let looks: Vec<bool> = character
        .blendshape_names()
        .iter()
        .map(|n| faceanim_rig::names::arkit_name(n).is_some_and(faceanim_rig::names::is_gaze))
        .collect();

    let mut new_animations = Vec::new();
    for (a, animation) in animations.iter().enumerate() {
        let input = bin.key_times(&animation.times);
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        let eyes_by_bone = rig.turns_eyes() && key_of(a).is_some_and(|k| k.gaze.is_some());
        let moves = |shape: usize| !(eyes_by_bone && looks.get(shape).copied().unwrap_or(false));
        for &(node, mesh) in &channels_for {
            let slots = &contributions[&mesh];
            let mut flat = Vec::with_capacity(animation.weights.len() * slots.len());
            for key in &animation.weights {
                for slot in slots {
                    flat.push(
                        slot.iter()
                            .filter(|&&(shape, _)| moves(shape))
                            .map(|&(shape, w)| key[shape] * w)
                            .sum::<f32>(),
                    );
                }
            }
            let output = bin.floats(&flat, "SCALAR", None, None);
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1, "target": { "node": node, "path": "weights" } }));
        }
        for (node, rotations) in
            rig.channels(&animation.times, animation.rotations.as_deref(), key_of(a))
        {
            let flat: Vec<f32> = rotations.iter().flatten().copied().collect();
            let output = bin.floats(&flat, "VEC4", None, None);
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1, "target": { "node": node, "path": "rotation" } }));
        }
        if !channels.is_empty() {
            new_animations.push(
                json!({ "name": animation.name, "samplers": samplers, "channels": channels,
                        "extras": { faceanim_rig::file_animation::EXTRAS_KEY: { "take": true } } }),
            );
        }
    }

    doc["meshes"] = json!(meshes);
    doc["nodes"] = json!(nodes);
    doc["accessors"] = json!(bin.accessors);
    doc["bufferViews"] = json!(bin.views);
    doc["buffers"] = json!([{ "byteLength": bin.bytes.len() }]);
    if !new_animations.is_empty() {
        match doc.get_mut("animations").and_then(Value::as_array_mut) {
            // An animation faceanim wrote under the same name is the one this export remakes
            // (a take reopened and exported again): replaced, not duplicated. The file's own
            // animations are kept whatever their names.
            Some(list) => {
                let ours = |a: &Value| {
                    a.pointer(&format!(
                        "/extras/{}",
                        faceanim_rig::file_animation::EXTRAS_KEY
                    ))
                    .is_some()
                };
                list.retain(|old| {
                    !(ours(old) && new_animations.iter().any(|new| new["name"] == old["name"]))
                });
                list.extend(new_animations);
            }
            None => doc["animations"] = json!(new_animations),
        }
    }
    let bytes = match compression {
        Compression::AsRead if source.meshopt() => crate::meshopt::compress(&mut doc, bin.bytes),
        _ => bin.bytes,
    };
    glb(&doc, bytes)
}

/// Gives each primitive of `mesh` that has no morph targets as many all-zero ones as its
/// siblings have (glTF asks every primitive of a mesh for the same targets).
fn pad_missing_targets(mesh: &mut Value, bin: &mut Bin) {
    let Some(primitives) = mesh.get_mut("primitives").and_then(Value::as_array_mut) else {
        return;
    };
    let count_of = |p: &Value| {
        p.get("targets")
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    };
    let wanted = primitives.iter().map(count_of).max().unwrap_or(0);
    for primitive in primitives.iter_mut().filter(|p| count_of(p) == 0) {
        if wanted == 0 {
            break;
        }
        let Some(vertices) = primitive
            .pointer("/attributes/POSITION")
            .and_then(Value::as_u64)
            .and_then(|a| bin.accessors.get(a as usize))
            .and_then(|a| a.get("count"))
            .and_then(Value::as_u64)
        else {
            continue;
        };
        let zero = bin.sparse_vec3(vertices as usize, &[], &[], true);
        primitive["targets"] = json!(vec![json!({ "POSITION": zero }); wanted]);
    }
}
