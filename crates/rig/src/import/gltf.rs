//! glTF 2.0 import: GLB or JSON, every mesh instance in the scene with its node transform (or
//! rest-pose skinning), all primitives merged into one vertex array, morph targets merged across
//! meshes by name.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::Dimensions;
use gltf::mesh::Mode;

use super::accessor::{Buffers, read_floats, read_indices};
use super::types::{
    ImportError, ImportErrorKind, Imported, MAX_BLENDSHAPES, MAX_TRIANGLES, MAX_VERTICES, Resources,
};
use crate::blendshape::{Blendshape, SPARSE_DELTA_THRESHOLD};
use crate::character::{Character, CharacterParts, Material, MaterialId, Part, Texture};

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Imports a `.glb` or `.gltf` from its bytes. `source_name` names the file in errors;
/// `resources` loads external buffers and images.
///
/// # Errors
/// An [`ImportError`] naming `source_name` and the problem.
pub fn import_gltf(
    bytes: &[u8],
    source_name: &str,
    resources: &dyn Resources,
) -> Result<Imported, ImportError> {
    import(bytes, source_name, resources).map_err(|kind| ImportError {
        source_name: source_name.to_owned(),
        kind,
    })
}

fn import(
    bytes: &[u8],
    source_name: &str,
    resources: &dyn Resources,
) -> Result<Imported, ImportErrorKind> {
    let (json, bin) = split_container(bytes)?;
    let prepared = super::extensions::prepare(json, bin, resources)?;
    let root = prepared.root;
    if !root.asset.version.starts_with("2.") {
        return Err(ImportErrorKind::Unsupported(format!(
            "glTF version {} (faceanim reads glTF 2.0)",
            root.asset.version
        )));
    }
    check_position_indices(&root)?;
    check_embedded_images(&root)?;
    let document = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(problems) => ImportErrorKind::InvalidJson(
            problems
                .iter()
                .take(8)
                .map(|(path, err)| format!("{path}: {err}"))
                .collect::<Vec<_>>()
                .join("; "),
        ),
        other => ImportErrorKind::InvalidJson(other.to_string()),
    })?;
    let buffers = prepared.buffers;
    if buffers.0.len() != document.buffers().len() {
        return Err(ImportErrorKind::InvalidJson(format!(
            "{} buffers were loaded for {} declared",
            buffers.0.len(),
            document.buffers().len()
        )));
    }
    let mut builder = Builder::new(source_name);
    builder.bones = crate::bones::find(&prepared.kept.0);
    builder.kept = Some(prepared.kept);
    builder.meshopt = prepared.meshopt;
    builder.warnings = prepared.warnings;
    builder.uv_transforms = prepared.uv_transforms;
    if prepared
        .vrm
        .as_ref()
        .is_some_and(|v| v.version == super::vrm::Version::V0)
    {
        // VRM 0.x avatars face −Z; faceanim's characters face +Z (as VRM 1.0's do).
        builder.root_transform = Mat4::from_rotation_y(std::f32::consts::PI);
    }
    builder.read_scene(&document, &buffers, resources)?;
    builder.animations =
        super::animations::read(&document, &buffers, &builder.bones, &mut builder.warnings);
    if let Some(vrm) = &prepared.vrm {
        builder.add_expressions(vrm)?;
    }
    builder.finish()
}

/// gltf-json 1.4.1's validation reads `accessors[POSITION]` before checking that the index
/// exists, and panics when it does not (found by `tests/fuzz_import.rs`); check it first.
fn check_position_indices(root: &gltf::json::Root) -> Result<(), ImportErrorKind> {
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions))
                && index.value() >= root.accessors.len()
            {
                return Err(ImportErrorKind::InvalidJson(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist ({} accessors)",
                    index.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// gltf 1.4's `Image::source` unwraps the `mimeType` of an image stored in a buffer view, and
/// the `uri` of one that is not, which the schema requires but a broken file may lack (panics
/// found by fuzzing full-body avatars); refuse such an image first, naming it.
fn check_embedded_images(root: &gltf::json::Root) -> Result<(), ImportErrorKind> {
    for (i, image) in root.images.iter().enumerate() {
        if image.buffer_view.is_none() && image.uri.is_none() {
            return Err(ImportErrorKind::InvalidJson(format!(
                "images[{i}]: an image needs a uri or a bufferView, and it has neither"
            )));
        }
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            return Err(ImportErrorKind::InvalidJson(format!(
                "images[{i}].mimeType: an image stored in a buffer view needs its mimeType (image/png or image/jpeg)"
            )));
        }
    }
    Ok(())
}

/// Splits a GLB into its JSON and BIN chunks, or returns glTF JSON as it is.
pub(super) fn split_container(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), ImportErrorKind> {
    if bytes.len() >= 4 && &bytes[..4] == GLB_MAGIC {
        let word = |at: usize| -> Result<u32, ImportErrorKind> {
            bytes
                .get(at..at + 4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or_else(|| {
                    ImportErrorKind::Truncated(format!(
                        "the GLB ends at byte {} inside its headers",
                        bytes.len()
                    ))
                })
        };
        let version = word(4)?;
        if version != 2 {
            return Err(ImportErrorKind::Unsupported(format!(
                "GLB version {version} (faceanim reads version 2)"
            )));
        }
        let declared = word(8)? as usize;
        if declared > bytes.len() {
            return Err(ImportErrorKind::Truncated(format!(
                "the GLB header says {declared} bytes but there are {}",
                bytes.len()
            )));
        }
        let bytes = &bytes[..declared];
        let json_len = word(12)? as usize;
        if word(16)? != CHUNK_JSON {
            return Err(ImportErrorKind::NotGltf(
                "the first GLB chunk is not JSON".into(),
            ));
        }
        // The end of a chunk's data starting at `start`, or why it does not fit.
        let chunk_end = |start: usize, len: usize, what: &str| {
            start
                .checked_add(len)
                .filter(|&e| e <= bytes.len())
                .ok_or_else(|| {
                    ImportErrorKind::Truncated(format!(
                        "{what} claims {len} bytes but the GLB has {}",
                        bytes.len()
                    ))
                })
        };
        let json_end = chunk_end(20, json_len, "the JSON chunk")?;
        let json = &bytes[20..json_end];
        let mut bin = None;
        let mut at = json_end;
        while at + 8 <= bytes.len() {
            let len = word(at)? as usize;
            let kind = word(at + 4)?;
            let end = chunk_end(at + 8, len, &format!("a chunk at byte {at}"))?;
            if kind == CHUNK_BIN && bin.is_none() {
                bin = Some(&bytes[at + 8..end]);
            }
            at = end;
        }
        return Ok((json, bin));
    }
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if first == Some(&b'{') {
        return Ok((bytes, None));
    }
    let shown: String = bytes
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ");
    Err(ImportErrorKind::NotGltf(format!(
        "it starts with bytes [{shown}], neither the GLB magic 'glTF' nor a JSON object"
    )))
}

/// How one mesh instance is placed: by its node's matrix, or by a skin whose joints' rest
/// matrices each primitive's own `JOINTS_0`/`WEIGHTS_0` blend per vertex.
enum Instance {
    /// Placed by a node's world matrix (the node, when one places it).
    Rigid(Mat4, Option<u32>),
    Skinned {
        /// `joint_world · inverse_bind` of each joint, in the skin's order.
        joints: Vec<Mat4>,
        /// Each joint's node, in the skin's order.
        joint_nodes: Vec<u32>,
        /// The node's own world matrix, for a vertex with no weights (or a primitive without them).
        node: Mat4,
        /// That node's index.
        node_index: u32,
    },
}

impl Instance {
    /// The per-vertex placement of one primitive of this instance.
    fn placement(
        &self,
        primitive: &gltf::Primitive<'_>,
        label: &str,
        buffers: &Buffers<'_>,
    ) -> Result<Placement, ImportErrorKind> {
        let (joints, joint_nodes, node, node_index) = match self {
            Instance::Rigid(m, node) => return Ok(Placement::Rigid(*m, *node)),
            Instance::Skinned {
                joints,
                joint_nodes,
                node,
                node_index,
            } => (joints, joint_nodes, *node, *node_index),
        };
        let (Some(j_acc), Some(w_acc)) = (
            primitive.get(&gltf::Semantic::Joints(0)),
            primitive.get(&gltf::Semantic::Weights(0)),
        ) else {
            return Ok(Placement::Rigid(node, Some(node_index)));
        };
        if let Some(positions) = primitive.get(&gltf::Semantic::Positions) {
            check_count(&j_acc, positions.count(), &format!("JOINTS_0 of {label}"))?;
            check_count(&w_acc, positions.count(), &format!("WEIGHTS_0 of {label}"))?;
        }
        let joint_index = read_indices(buffers, &j_acc)?;
        let weights = read_floats(buffers, &w_acc, Some(Dimensions::Vec4))?;
        check_finite(&weights, 4, &format!("WEIGHTS_0 of {label}"))?;
        let count = j_acc.count().min(w_acc.count());
        let mut per_vertex = Vec::with_capacity(count);
        let mut shares = Vec::with_capacity(count);
        for v in 0..count {
            let mut m = Mat4::ZERO;
            let mut total = 0.0;
            let mut by = [(node_index, 0.0); 4];
            for (k, slot) in by.iter_mut().enumerate() {
                let w = weights.get(4 * v + k).copied().unwrap_or(0.0);
                if w == 0.0 {
                    continue;
                }
                let j = joint_index.get(4 * v + k).copied().unwrap_or(0) as usize;
                let jm = joints.get(j).ok_or_else(|| {
                    ImportErrorKind::CountMismatch(format!(
                        "JOINTS_0 of {label}: vertex {v} uses joint {j} but the skin has {}",
                        joints.len()
                    ))
                })?;
                m += *jm * w;
                total += w;
                *slot = (joint_nodes.get(j).copied().unwrap_or(node_index), w);
            }
            if total > 0.0 {
                per_vertex.push(m * (1.0 / total));
                shares.push(by.map(|(n, w)| (n, w / total)));
            } else {
                per_vertex.push(node);
                shares.push(wholly(node_index));
            }
        }
        Ok(Placement::Skinned(per_vertex, shares))
    }
}

/// A vertex placed by `node` alone (its share 1, the other entries unused).
fn wholly(node: u32) -> [(u32, f32); 4] {
    let mut shares = [(node, 0.0); 4];
    shares[0].1 = 1.0;
    shares
}

/// Per-vertex transform of one primitive: one matrix (and the node that places it), or
/// per-vertex skinning matrices (and the joints' nodes and shares).
enum Placement {
    Rigid(Mat4, Option<u32>),
    Skinned(Vec<Mat4>, Vec<[(u32, f32); 4]>),
}

impl Placement {
    /// The linear part, for directions such as blendshape deltas.
    fn linear(&self, vertex: usize) -> Mat3 {
        Mat3::from_mat4(self.matrix(vertex))
    }

    fn matrix(&self, vertex: usize) -> Mat4 {
        match self {
            Placement::Rigid(m, _) => *m,
            Placement::Skinned(per_vertex, _) => {
                per_vertex.get(vertex).copied().unwrap_or(Mat4::IDENTITY)
            }
        }
    }

    /// The nodes that place `vertex` and their shares (none for meshes no node places).
    fn placed_by(&self, vertex: usize) -> [(u32, f32); 4] {
        match self {
            Placement::Rigid(_, node) => node.map_or([(u32::MAX, 0.0); 4], wholly),
            Placement::Skinned(_, shares) => {
                shares.get(vertex).copied().unwrap_or([(u32::MAX, 0.0); 4])
            }
        }
    }
}

/// Accumulates vertices, triangles, parts and blendshapes over all primitives.
struct Builder {
    name: String,
    positions: Vec<Vec3>,
    normals: Vec<Option<Vec3>>,
    uvs: Vec<[f32; 2]>,
    any_uv: bool,
    colors: Vec<[f32; 4]>,
    any_color: bool,
    triangles: Vec<[u32; 3]>,
    parts: Vec<Part>,
    materials: Vec<Material>,
    material_map: HashMap<Option<usize>, MaterialId>,
    shape_names: Vec<String>,
    shape_index: HashMap<String, usize>,
    shape_indices: Vec<Vec<u32>>,
    shape_deltas: Vec<Vec<Vec3>>,
    warnings: Vec<String>,
    saw_targets: bool,
    /// `KHR_texture_transform` of a material's base-colour texture, baked into the UVs.
    uv_transforms: HashMap<usize, super::extensions::UvTransform>,
    /// Applied before every node's own transform (VRM 0.x's turn to face +Z).
    root_transform: Mat4,
    /// Each mesh's morph targets as blendshape slots, by mesh index (for VRM bindings).
    mesh_slots: HashMap<usize, Vec<usize>>,
    /// Where each vertex came from in the file.
    origins: Vec<Option<crate::source::Origin>>,
    /// The VRM expressions' bindings, by blendshape slot.
    expression_binds: Vec<(usize, Vec<crate::source::Binding>)>,
    /// The file to write back, and the node a head pose turns.
    kept: Option<(serde_json::Value, Vec<u8>)>,
    bones: crate::bones::FaceBones,
    /// The file's morph-weight animations.
    animations: Vec<crate::file_animation::FileAnimation>,
    /// Whether the file was meshopt-compressed.
    meshopt: bool,
}

impl Builder {
    fn new(source_name: &str) -> Builder {
        let stem = std::path::Path::new(source_name).file_stem().map_or_else(
            || source_name.to_owned(),
            |s| s.to_string_lossy().into_owned(),
        );
        Builder {
            name: stem,
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            any_uv: false,
            colors: Vec::new(),
            any_color: false,
            triangles: Vec::new(),
            parts: Vec::new(),
            materials: Vec::new(),
            material_map: HashMap::new(),
            shape_names: Vec::new(),
            shape_index: HashMap::new(),
            shape_indices: Vec::new(),
            shape_deltas: Vec::new(),
            warnings: Vec::new(),
            saw_targets: false,
            uv_transforms: HashMap::new(),
            root_transform: Mat4::IDENTITY,
            mesh_slots: HashMap::new(),
            origins: Vec::new(),
            expression_binds: Vec::new(),
            kept: None,
            bones: crate::bones::FaceBones::default(),
            animations: Vec::new(),
            meshopt: false,
        }
    }

    fn read_scene(
        &mut self,
        doc: &gltf::Document,
        buffers: &Buffers<'_>,
        resources: &dyn Resources,
    ) -> Result<(), ImportErrorKind> {
        let world: Vec<Mat4> = world_matrices(doc)?
            .into_iter()
            .map(|m| self.root_transform * m)
            .collect();
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => {
                let mut has_parent = vec![false; doc.nodes().len()];
                for node in doc.nodes() {
                    for child in node.children() {
                        has_parent[child.index()] = true;
                    }
                }
                (0..has_parent.len()).filter(|&i| !has_parent[i]).collect()
            }
        };
        // Depth-first over the scene, guarding against cycles the schema cannot rule out.
        let nodes: Vec<gltf::Node<'_>> = doc.nodes().collect();
        let mut visited = vec![false; nodes.len()];
        let mut stack: Vec<usize> = roots.into_iter().rev().collect();
        let mut instances: Vec<(gltf::Node<'_>, gltf::Mesh<'_>)> = Vec::new();
        while let Some(i) = stack.pop() {
            if std::mem::replace(&mut visited[i], true) {
                continue;
            }
            let node = nodes[i].clone();
            if let Some(mesh) = node.mesh() {
                instances.push((node.clone(), mesh));
            }
            stack.extend(
                node.children()
                    .map(|c| c.index())
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev(),
            );
        }
        if instances.is_empty() {
            // Meshes that no node places: take them as they are.
            for mesh in doc.meshes() {
                self.read_mesh(
                    &mesh,
                    &Instance::Rigid(self.root_transform, None),
                    buffers,
                    resources,
                )?;
            }
        }
        for (node, mesh) in instances {
            let instance = match node.skin() {
                Some(skin) => skin_instance(&skin, &node, &world, buffers)?,
                None => Instance::Rigid(world[node.index()], Some(node.index() as u32)),
            };
            self.read_mesh(&mesh, &instance, buffers, resources)?;
        }
        Ok(())
    }

    fn read_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        instance: &Instance,
        buffers: &Buffers<'_>,
        resources: &dyn Resources,
    ) -> Result<(), ImportErrorKind> {
        let mesh_label = match mesh.name() {
            Some(name) => format!("mesh {} '{name}'", mesh.index()),
            None => format!("mesh {}", mesh.index()),
        };
        // The spec asks every primitive for the same targets; exporters that leave a primitive
        // with no morph at all out of them are read too (its vertices simply do not move).
        let target_count_hint = mesh
            .primitives()
            .map(|p| p.morph_targets().count())
            .max()
            .unwrap_or(0);
        let target_names = self.resolved_target_names(mesh, &mesh_label, target_count_hint);
        let slots = target_names
            .iter()
            .map(|name| self.shape_slot(name))
            .collect::<Result<Vec<_>, _>>()?;
        self.mesh_slots.insert(mesh.index(), slots);
        // Primitives that share attribute accessors share vertices (faceanim's own exports do).
        let mut shared: HashMap<Vec<usize>, (u32, Placement)> = HashMap::new();

        for primitive in mesh.primitives() {
            let label = format!("{mesh_label} primitive {}", primitive.index());
            let targets: Vec<_> = primitive.morph_targets().collect();
            if !targets.is_empty() && targets.len() != target_count_hint {
                return Err(ImportErrorKind::CountMismatch(format!(
                    "{label} has {} morph targets but another primitive of the mesh has {target_count_hint}",
                    targets.len()
                )));
            }
            let mode = primitive.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warnings.push(format!(
                    "{label}: skipped {mode:?} (only triangles are animated)"
                ));
                continue;
            }
            let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
                self.warnings
                    .push(format!("{label}: skipped, it has no POSITION"));
                continue;
            };
            let key: Vec<usize> = std::iter::once(position_accessor.index())
                .chain(
                    [
                        gltf::Semantic::Normals,
                        gltf::Semantic::TexCoords(0),
                        gltf::Semantic::Colors(0),
                        gltf::Semantic::Joints(0),
                        gltf::Semantic::Weights(0),
                    ]
                    .iter()
                    .map(|s| primitive.get(s).map_or(usize::MAX, |a| a.index())),
                )
                .chain(
                    targets
                        .iter()
                        .map(|t| t.positions().map_or(usize::MAX, |a| a.index())),
                )
                .collect();
            if !shared.contains_key(&key) {
                let placement = instance.placement(&primitive, &label, buffers)?;
                let base = self.read_vertices(
                    mesh.index(),
                    &primitive,
                    &label,
                    &targets,
                    &target_names,
                    &placement,
                    buffers,
                )?;
                shared.insert(key.clone(), (base, placement));
            }
            let Some((base, placement)) = shared.get(&key) else {
                continue;
            };
            let local_count = position_accessor.count();
            self.read_triangles(&primitive, &label, *base, local_count, placement, buffers)?;
            let first_triangle = self.parts.last().map_or(0, |p| p.triangles.end);
            let material = self.material(&primitive.material(), resources, buffers);
            self.parts.push(Part {
                name: mesh.name().unwrap_or("mesh").to_owned(),
                material,
                triangles: first_triangle..self.triangles.len(),
            });
        }
        Ok(())
    }

    /// Appends a primitive's vertices and morph-target deltas; returns the first vertex index.
    #[expect(clippy::too_many_arguments, reason = "one primitive's whole context")]
    fn read_vertices(
        &mut self,
        mesh_index: usize,
        primitive: &gltf::Primitive<'_>,
        label: &str,
        targets: &[gltf::mesh::MorphTarget<'_>],
        target_names: &[String],
        placement: &Placement,
        buffers: &Buffers<'_>,
    ) -> Result<u32, ImportErrorKind> {
        let role = |what: &str| format!("{what} of {label}");
        let with_role = |what: String| {
            move |e: ImportErrorKind| match e {
                ImportErrorKind::BadAccessor {
                    accessor, problem, ..
                } => ImportErrorKind::BadAccessor {
                    accessor,
                    role: what.clone(),
                    problem,
                },
                other => other,
            }
        };
        let position_accessor = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or(ImportErrorKind::NoMeshes)?;
        let count = position_accessor.count();
        let base = self.positions.len();
        if count > MAX_VERTICES || base + count > MAX_VERTICES {
            return Err(ImportErrorKind::TooLarge(format!(
                "{label} declares {count} vertices ({base} before it; at most {MAX_VERTICES} in all)"
            )));
        }
        let raw = read_floats(buffers, &position_accessor, Some(Dimensions::Vec3))
            .map_err(with_role(role("POSITION")))?;
        check_finite(&raw, 3, &role("POSITION"))?;
        let local: Vec<Vec3> = raw
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        for (i, p) in local.iter().enumerate() {
            self.positions
                .push(placement.matrix(i).transform_point3(*p));
            let to_local = placement.linear(i).inverse();
            self.origins
                .push(to_local.is_finite().then_some(crate::source::Origin {
                    mesh: mesh_index as u32,
                    accessor: position_accessor.index() as u32,
                    local: i as u32,
                    to_local,
                    placed_by: placement.placed_by(i),
                }));
        }

        let normals = match primitive.get(&gltf::Semantic::Normals) {
            Some(acc) => {
                check_count(&acc, count, &role("NORMAL"))?;
                let raw = read_floats(buffers, &acc, Some(Dimensions::Vec3))
                    .map_err(with_role(role("NORMAL")))?;
                check_finite(&raw, 3, &role("NORMAL"))?;
                Some(raw)
            }
            None => None,
        };
        for i in 0..count {
            let n = normals.as_ref().map(|raw| {
                let n = Vec3::new(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]);
                let m = Mat3::from_mat4(placement.matrix(i)).inverse().transpose();
                let t = m * n;
                crate::normals::unit_or_up(if t.is_finite() { t } else { n })
            });
            self.normals.push(n);
        }

        match primitive.get(&gltf::Semantic::TexCoords(0)) {
            Some(acc) => {
                check_count(&acc, count, &role("TEXCOORD_0"))?;
                let raw = read_floats(buffers, &acc, Some(Dimensions::Vec2))
                    .map_err(with_role(role("TEXCOORD_0")))?;
                check_finite(&raw, 2, &role("TEXCOORD_0"))?;
                self.any_uv = true;
                let transform = primitive
                    .material()
                    .index()
                    .and_then(|m| self.uv_transforms.get(&m).copied());
                self.uvs.extend(raw.chunks_exact(2).map(|c| {
                    let uv = [c[0], c[1]];
                    transform.map_or(uv, |t| t.apply(uv))
                }));
            }
            None => self.uvs.extend(std::iter::repeat_n([0.0, 0.0], count)),
        }

        match primitive.get(&gltf::Semantic::Colors(0)) {
            Some(acc) => {
                check_count(&acc, count, &role("COLOR_0"))?;
                let dims = acc.dimensions();
                let raw = read_floats(buffers, &acc, None).map_err(with_role(role("COLOR_0")))?;
                check_finite(&raw, 1, &role("COLOR_0"))?;
                self.any_color = true;
                match dims {
                    Dimensions::Vec3 => self
                        .colors
                        .extend(raw.chunks_exact(3).map(|c| [c[0], c[1], c[2], 1.0])),
                    Dimensions::Vec4 => self
                        .colors
                        .extend(raw.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]])),
                    other => {
                        return Err(ImportErrorKind::BadAccessor {
                            accessor: acc.index(),
                            role: role("COLOR_0"),
                            problem: format!("type is {other:?}, expected Vec3 or Vec4"),
                        });
                    }
                }
            }
            None => self
                .colors
                .extend(std::iter::repeat_n([1.0, 1.0, 1.0, 1.0], count)),
        }

        for (t, target) in targets.iter().enumerate() {
            self.saw_targets = true;
            let name = target_names
                .get(t)
                .cloned()
                .unwrap_or_else(|| format!("target_{t}"));
            let shape = self.shape_slot(&name)?;
            let Some(acc) = target.positions() else {
                continue;
            };
            let what = format!("morph target {t} ('{name}') POSITION of {label}");
            check_count(&acc, count, &what)?;
            let raw = read_floats(buffers, &acc, Some(Dimensions::Vec3))
                .map_err(with_role(what.clone()))?;
            check_finite(&raw, 3, &what)?;
            for (i, c) in raw.chunks_exact(3).enumerate() {
                let d = Vec3::new(c[0], c[1], c[2]);
                if d != Vec3::ZERO {
                    self.push_delta(shape, (base + i) as u32, placement.linear(i) * d);
                }
            }
        }
        Ok(base as u32)
    }

    fn read_triangles(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        label: &str,
        base: u32,
        local_count: usize,
        placement: &Placement,
        buffers: &Buffers<'_>,
    ) -> Result<(), ImportErrorKind> {
        let indices: Vec<u32> = match primitive.indices() {
            Some(acc) => read_indices(buffers, &acc).map_err(|e| match e {
                ImportErrorKind::BadAccessor {
                    accessor, problem, ..
                } => ImportErrorKind::BadAccessor {
                    accessor,
                    role: format!("indices of {label}"),
                    problem,
                },
                other => other,
            })?,
            None => (0..local_count as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= local_count) {
            return Err(ImportErrorKind::CountMismatch(format!(
                "{label} uses vertex {bad} but has only {local_count} vertices"
            )));
        }
        let mut local: Vec<[u32; 3]> = Vec::with_capacity(indices.len() / 3);
        match primitive.mode() {
            Mode::TriangleStrip => {
                for i in 0..indices.len().saturating_sub(2) {
                    let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                    local.push(if i % 2 == 0 { [a, b, c] } else { [b, a, c] });
                }
            }
            Mode::TriangleFan => {
                for i in 1..indices.len().saturating_sub(1) {
                    local.push([indices[0], indices[i], indices[i + 1]]);
                }
            }
            _ => local.extend(indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
        }
        if self.triangles.len() + local.len() > MAX_TRIANGLES {
            return Err(ImportErrorKind::TooLarge(format!(
                "more than {MAX_TRIANGLES} triangles in all"
            )));
        }
        for [a, b, c] in local {
            if a == b || b == c || a == c {
                continue;
            }
            // A mirroring transform turns the winding inside out; keep faces facing outwards.
            let flip = Mat3::from_mat4(placement.matrix(a as usize)).determinant() < 0.0;
            let tri = if flip { [c, b, a] } else { [a, b, c] };
            self.triangles.push(tri.map(|v| v + base));
        }
        Ok(())
    }

    /// The mesh's target names (`target_N` where missing), unique within the mesh: a repeated
    /// name gets a `.001` suffix so that two targets never merge into one blendshape.
    fn resolved_target_names(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        label: &str,
        count: usize,
    ) -> Vec<String> {
        let given = target_names(mesh);
        if !given.is_empty() && given.len() != count {
            self.warnings.push(format!(
                "{label}: {} targetNames for {count} morph targets",
                given.len()
            ));
        }
        let mut seen = std::collections::HashSet::new();
        (0..count)
            .map(|t| {
                let name = given
                    .get(t)
                    .cloned()
                    .flatten()
                    .unwrap_or_else(|| format!("target_{t}"));
                if seen.insert(name.clone()) {
                    return name;
                }
                let unique = (1..)
                    .map(|n| format!("{name}.{n:03}"))
                    .find(|c| !seen.contains(c))
                    .unwrap_or_default();
                self.warnings.push(format!(
                    "{label}: morph target {t} repeats the name '{name}'; renamed '{unique}'"
                ));
                seen.insert(unique.clone());
                unique
            })
            .collect()
    }

    fn shape_slot(&mut self, name: &str) -> Result<usize, ImportErrorKind> {
        if let Some(&i) = self.shape_index.get(name) {
            return Ok(i);
        }
        if self.shape_names.len() >= MAX_BLENDSHAPES {
            return Err(ImportErrorKind::TooLarge(format!(
                "more than {MAX_BLENDSHAPES} morph targets"
            )));
        }
        let i = self.shape_names.len();
        self.shape_names.push(name.to_owned());
        self.shape_index.insert(name.to_owned(), i);
        self.shape_indices.push(Vec::new());
        self.shape_deltas.push(Vec::new());
        Ok(i)
    }

    /// Records a delta; the threshold is applied once the size is known, in `finish`.
    fn push_delta(&mut self, shape: usize, vertex: u32, delta: Vec3) {
        if delta != Vec3::ZERO {
            self.shape_indices[shape].push(vertex);
            self.shape_deltas[shape].push(delta);
        }
    }

    fn material(
        &mut self,
        material: &gltf::Material<'_>,
        resources: &dyn Resources,
        buffers: &Buffers<'_>,
    ) -> MaterialId {
        let key = material.index();
        if let Some(&id) = self.material_map.get(&key) {
            return id;
        }
        let pbr = material.pbr_metallic_roughness();
        let base_color_texture = pbr.base_color_texture().and_then(|info| {
            let image = info.texture().source();
            match load_image(&image, resources, buffers) {
                Ok(texture) => Some(texture),
                Err(reason) => {
                    self.warnings.push(format!(
                        "base-colour texture of material {key:?} dropped: {reason}"
                    ));
                    None
                }
            }
        });
        let id = MaterialId(self.materials.len() as u32);
        self.materials.push(Material {
            name: material.name().unwrap_or_default().to_owned(),
            base_color: pbr.base_color_factor(),
            base_color_texture,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            double_sided: material.double_sided(),
            alpha: match material.alpha_mode() {
                gltf::material::AlphaMode::Opaque => crate::AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => crate::AlphaMode::Mask {
                    cutoff: material.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => crate::AlphaMode::Blend,
            },
        });
        self.material_map.insert(key, id);
        id
    }

    /// Adds each VRM expression as a blendshape: the weighted sum of the morph targets it
    /// binds. An expression that binds nothing (a material-only or bone-driven one) is skipped
    /// with a warning; one whose name a raw morph target already has gets ` (VRM)` appended.
    fn add_expressions(&mut self, vrm: &super::vrm::Vrm) -> Result<(), ImportErrorKind> {
        for expression in &vrm.expressions {
            let mut sum: HashMap<u32, Vec3> = HashMap::new();
            for bind in &expression.binds {
                let Some(&slot) = self
                    .mesh_slots
                    .get(&bind.mesh)
                    .and_then(|slots| slots.get(bind.target))
                else {
                    continue;
                };
                for (&v, &d) in self.shape_indices[slot]
                    .iter()
                    .zip(&self.shape_deltas[slot])
                {
                    *sum.entry(v).or_insert(Vec3::ZERO) += d * bind.weight;
                }
            }
            if sum.is_empty() {
                if expression.name != "neutral" {
                    self.warnings.push(format!(
                        "VRM expression '{}' moves no morph target (material or bone only); not a blendshape",
                        expression.name
                    ));
                }
                continue;
            }
            let mut name = expression.name.clone();
            if self.shape_index.contains_key(&name) {
                name = format!("{name} (VRM)");
                if self.shape_index.contains_key(&name) {
                    continue;
                }
            }
            let slot = self.shape_slot(&name)?;
            self.expression_binds.push((
                slot,
                expression
                    .binds
                    .iter()
                    .map(|b| crate::source::Binding {
                        mesh: b.mesh as u32,
                        target: b.target as u32,
                        weight: b.weight,
                    })
                    .collect(),
            ));
            let mut entries: Vec<(u32, Vec3)> = sum.into_iter().collect();
            entries.sort_unstable_by_key(|(v, _)| *v);
            for (v, d) in entries {
                self.push_delta(slot, v, d);
            }
        }
        Ok(())
    }

    fn finish(self) -> Result<Imported, ImportErrorKind> {
        if self.positions.is_empty() || self.triangles.is_empty() {
            return Err(ImportErrorKind::NoMeshes);
        }
        let mut warnings = self.warnings;
        if !self.saw_targets {
            // A body with face bones is still captured, lip-synced and sent by them.
            let bones = if self.bones.found().next().is_some() {
                "capture and phones turn its head, eye and jaw bones, lip sync its jaw; for \
                 the face itself "
            } else {
                ""
            };
            warnings.push(format!(
                "no morph targets (blendshapes): {bones}make ARKit's 52 on this head with \
                 `faceanim generate-shapes` (or export it with its shape keys)"
            ));
        }
        // Parts are recorded per primitive; their triangle ranges are contiguous by construction.
        let size = crate::bounds::Aabb::around(&self.positions).diagonal();
        let threshold = SPARSE_DELTA_THRESHOLD * size;
        let blendshapes = self
            .shape_names
            .iter()
            .zip(self.shape_indices.into_iter().zip(self.shape_deltas))
            .map(|(name, (indices, deltas))| {
                let (indices, deltas): (Vec<u32>, Vec<Vec3>) = indices
                    .into_iter()
                    .zip(deltas)
                    .filter(|(_, d)| d.length() > threshold)
                    .unzip();
                Blendshape::from_sparse(name.clone(), indices, deltas)
            })
            .collect();
        let normals = if self.normals.iter().all(Option::is_some) {
            Some(self.normals.into_iter().flatten().collect())
        } else {
            None
        };
        let character = Character::new(CharacterParts {
            name: self.name,
            positions: self.positions,
            normals,
            uvs: self.any_uv.then_some(self.uvs),
            colors: self.any_color.then_some(self.colors),
            triangles: self.triangles,
            materials: self.materials,
            parts: self.parts,
            blendshapes,
            normal_deltas: None,
        })?;
        let character = match self.kept {
            Some((document, bin)) => {
                let mut shapes = vec![Vec::new(); self.shape_names.len()];
                let mut meshes: Vec<_> = self.mesh_slots.into_iter().collect();
                meshes.sort_unstable_by_key(|(m, _)| *m);
                for (mesh, slots) in meshes {
                    for (target, slot) in slots.into_iter().enumerate() {
                        if let Some(list) = shapes.get_mut(slot) {
                            list.push(crate::source::Binding {
                                mesh: mesh as u32,
                                target: target as u32,
                                weight: 1.0,
                            });
                        }
                    }
                }
                for (slot, binds) in self.expression_binds {
                    if let Some(list) = shapes.get_mut(slot) {
                        *list = binds;
                    }
                }
                character.with_source(crate::source::GltfSource {
                    document,
                    bin: bin.into(),
                    shapes,
                    vertices: self.origins,
                    bones: self.bones,
                    root_transform: self.root_transform,
                    animations: self.animations,
                    meshopt: self.meshopt,
                })
            }
            None => character,
        };
        Ok(Imported {
            character,
            warnings,
        })
    }
}

fn target_names(mesh: &gltf::Mesh<'_>) -> Vec<Option<String>> {
    let Some(extras) = mesh.extras() else {
        return Vec::new();
    };
    let Ok(value) = serde_json::from_str::<serde_json::Value>(extras.get()) else {
        return Vec::new();
    };
    match value.get("targetNames").and_then(|v| v.as_array()) {
        Some(names) => names
            .iter()
            .map(|n| n.as_str().map(str::to_owned))
            .collect(),
        None => Vec::new(),
    }
}

fn check_count(
    accessor: &gltf::Accessor<'_>,
    expected: usize,
    what: &str,
) -> Result<(), ImportErrorKind> {
    if accessor.count() == expected {
        Ok(())
    } else {
        Err(ImportErrorKind::CountMismatch(format!(
            "{what} (accessor {}) has {} elements but POSITION has {expected}",
            accessor.index(),
            accessor.count()
        )))
    }
}

fn check_finite(values: &[f32], components: usize, what: &str) -> Result<(), ImportErrorKind> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(ImportErrorKind::NonFinite {
            what: what.to_owned(),
            index: i / components,
        }),
        None => Ok(()),
    }
}

/// Each node's parent, from the nodes' children.
pub(super) fn node_parents(doc: &gltf::Document) -> Vec<Option<usize>> {
    let mut parent = vec![None; doc.nodes().len()];
    for node in doc.nodes() {
        for child in node.children() {
            parent[child.index()] = Some(node.index());
        }
    }
    parent
}

/// World matrix of every node (parents first), rejecting cycles and non-finite transforms.
pub(super) fn world_matrices(doc: &gltf::Document) -> Result<Vec<Mat4>, ImportErrorKind> {
    let count = doc.nodes().len();
    let parent = node_parents(doc);
    let local: Vec<Mat4> = doc
        .nodes()
        .map(|n| Mat4::from_cols_array_2d(&n.transform().matrix()))
        .collect();
    if let Some(i) = local.iter().position(|m| !m.is_finite()) {
        return Err(ImportErrorKind::NonFinite {
            what: "node transform".into(),
            index: i,
        });
    }
    let mut world = vec![None::<Mat4>; count];
    for start in 0..count {
        let mut chain = vec![start];
        let mut at = start;
        while let Some(p) = parent[at] {
            if world[p].is_some() {
                break;
            }
            if chain.len() > count {
                return Err(ImportErrorKind::InvalidJson(format!(
                    "node {start} is its own ancestor"
                )));
            }
            chain.push(p);
            at = p;
        }
        for &n in chain.iter().rev() {
            if world[n].is_none() {
                let up = parent[n].and_then(|p| world[p]).unwrap_or(Mat4::IDENTITY);
                world[n] = Some(up * local[n]);
            }
        }
    }
    Ok(world
        .into_iter()
        .map(|m| m.unwrap_or(Mat4::IDENTITY))
        .collect())
}

/// Rest-pose skinning: each vertex is placed by Σ wₖ · joint_worldₖ · inverse_bindₖ, with the
/// weights of the primitive it belongs to (see [`Instance::placement`]).
fn skin_instance(
    skin: &gltf::Skin<'_>,
    node: &gltf::Node<'_>,
    world: &[Mat4],
    buffers: &Buffers<'_>,
) -> Result<Instance, ImportErrorKind> {
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    let inverse_bind: Vec<Mat4> = match skin.inverse_bind_matrices() {
        Some(acc) => {
            let raw = read_floats(buffers, &acc, Some(Dimensions::Mat4))?;
            check_finite(
                &raw,
                16,
                &format!("inverseBindMatrices of skin {}", skin.index()),
            )?;
            raw.chunks_exact(16).map(Mat4::from_cols_slice).collect()
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    Ok(Instance::Skinned {
        joint_nodes: joints.iter().map(|&j| j as u32).collect(),
        node_index: node.index() as u32,
        joints: joints
            .iter()
            .enumerate()
            .map(|(k, &j)| world[j] * inverse_bind.get(k).copied().unwrap_or(Mat4::IDENTITY))
            .collect(),
        node: world[node.index()],
    })
}

/// Loads a glTF image's encoded bytes (from a buffer view, a data URI or an external file).
fn load_image(
    image: &gltf::Image<'_>,
    resources: &dyn Resources,
    buffers: &Buffers<'_>,
) -> Result<Texture, String> {
    let (bytes, declared) = match image.source() {
        gltf::image::Source::View { view, mime_type } => (
            super::accessor::view_bytes(buffers, &view)?.to_vec(),
            Some(mime_type.to_owned()),
        ),
        gltf::image::Source::Uri { uri, mime_type } => (
            super::uri::load_uri(uri, resources)?,
            mime_type.map(str::to_owned),
        ),
    };
    let sniffed = super::uri::sniff_image(&bytes);
    let mime_type = sniffed.map(str::to_owned).ok_or_else(|| match declared {
        Some(declared) => {
            format!("its {declared} image is not one faceanim shows (PNG, JPEG, WebP or KTX2)")
        }
        None => "not a PNG, JPEG, WebP or KTX2 image".to_owned(),
    })?;
    Ok(Texture {
        mime_type,
        bytes: Arc::from(bytes),
    })
}
