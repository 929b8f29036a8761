//! The user's own glTF file, kept beside the character so that an export can be that file with
//! the animation added (see `faceanim_export`'s GLB writer).
//!
//! faceanim works on one merged mesh ([`crate::Character`]); the user's file has many nodes,
//! meshes, skins and materials. [`GltfSource`] keeps the file's JSON and its one binary buffer
//! (meshopt-compressed views decoded, external buffers and images embedded), and how the
//! character maps onto it: which morph targets of which meshes each blendshape drives (a raw
//! target name shared by several meshes drives all of them; a VRM expression drives its
//! bindings with their weights), where each vertex came from (mesh, position accessor, index,
//! and the transform that placed it), and which node turns with a captured head pose.

use std::sync::Arc;

use glam::{Mat3, Mat4, Quat};
use serde_json::Value;

pub use crate::binding::Binding;

/// Where a character vertex came from in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Origin {
    /// The mesh's index.
    pub mesh: u32,
    /// The `POSITION` accessor of the primitive(s) holding it.
    pub accessor: u32,
    /// Its index in that accessor.
    pub local: u32,
    /// Maps a displacement in character space back into the mesh's own space (the inverse of
    /// the node transform or rest-pose skinning that placed it).
    pub to_local: Mat3,
    /// The nodes that place it and each one's share (the skin's joints and `WEIGHTS_0`, or its
    /// mesh's node with all of it); unused entries have share 0.
    pub placed_by: [(u32, f32); 4],
}

/// The user's file and how the character maps onto it. See the module docs.
#[derive(Clone, PartialEq)]
pub struct GltfSource {
    pub(crate) document: Value,
    pub(crate) bin: Arc<[u8]>,
    pub(crate) shapes: Vec<Vec<Binding>>,
    pub(crate) vertices: Vec<Option<Origin>>,
    pub(crate) bones: crate::bones::FaceBones,
    /// Applied by the importer before the file's own transforms (VRM 0.x's half turn).
    pub(crate) root_transform: Mat4,
    /// The file's morph-weight animations, as stored.
    pub(crate) animations: Vec<crate::file_animation::FileAnimation>,
    /// Whether the file's buffer views were meshopt-compressed.
    pub(crate) meshopt: bool,
}

impl std::fmt::Debug for GltfSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GltfSource")
            .field("nodes", &self.count("nodes"))
            .field("meshes", &self.count("meshes"))
            .field("bin_bytes", &self.bin.len())
            .field("shapes", &self.shapes.len())
            .field("bones", &self.bones)
            .finish_non_exhaustive()
    }
}

/// A VRM expression of the user's file ([`GltfSource::vrm_expressions`]).
#[derive(Debug, Clone, PartialEq)]
pub struct VrmExpression {
    /// Its name: a preset's in VRM 1.0's spelling (`aa`, `blinkLeft`, `happy`; VRM 0.x's `a`,
    /// `blink_l`, `joy` are read so), a custom one's as the file names it.
    pub name: String,
    /// Whether it is named as one of VRM 1.0's presets (in either version: a VRM 0.x custom
    /// `surprised` is VRM 1.0's preset; a custom expression may not take a preset's name).
    pub preset: bool,
    /// The morph targets it binds, each with its weight (0–1).
    pub binds: Vec<Binding>,
}

/// Which of a file's blendshapes `faceanim generate-shapes` made, and from which template: kept
/// in the file itself, as `asset.extras.faceanim.generated` (`{"shapes": [...], "template":
/// "..."}`), so that every tool that reads the file back can say so.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct GeneratedShapes {
    /// The generated shapes' names.
    pub shapes: Vec<String>,
    /// The template(s) they came from.
    pub template: String,
}

impl GltfSource {
    /// Whether the file's buffer views were compressed with meshopt (`EXT_meshopt_compression`,
    /// as gltfpack and VRoid's optimisers write): the GLB exporter compresses them again.
    #[must_use]
    pub fn meshopt(&self) -> bool {
        self.meshopt
    }

    /// The file's animations that move morph targets (a take or sketch exported before, or the
    /// file's own), those faceanim wrote on bones alone (a body with no blendshapes), and those
    /// that move nothing but the turns of the face's bones (keyed in another tool), in the
    /// file's order.
    #[must_use]
    pub fn animations(&self) -> &[crate::file_animation::FileAnimation] {
        &self.animations
    }

    /// The file's JSON document, as read (compression decoded, resources embedded).
    #[must_use]
    pub fn document(&self) -> &Value {
        &self.document
    }

    /// The file's one binary buffer (external buffers and images embedded).
    #[must_use]
    pub fn bin(&self) -> &[u8] {
        &self.bin
    }

    /// What the file records of generated shapes, if anything.
    #[must_use]
    pub fn generated_shapes(&self) -> Option<GeneratedShapes> {
        let record = self.document.pointer("/asset/extras/faceanim/generated")?;
        let shapes: Vec<String> = record
            .get("shapes")?
            .as_array()?
            .iter()
            .filter_map(|s| s.as_str().map(str::to_owned))
            .collect();
        let template = record
            .get("template")
            .and_then(Value::as_str)
            .unwrap_or_default()
            .to_owned();
        Some(GeneratedShapes { shapes, template })
    }

    /// How many entries the file's top-level array `key` (`nodes`, `meshes`, `skins`, …) has.
    #[must_use]
    pub fn count(&self, key: &str) -> usize {
        self.document
            .get(key)
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    }

    /// The morph targets each of the file's own blendshapes drives, in the character's order
    /// (blendshapes after these are ones faceanim added, such as baked corrective targets).
    #[must_use]
    pub fn shapes(&self) -> &[Vec<Binding>] {
        &self.shapes
    }

    /// Where each character vertex came from.
    #[must_use]
    pub fn origins(&self) -> &[Option<Origin>] {
        &self.vertices
    }

    /// The node that turns with a captured head pose: the VRM humanoid's head, else a skin
    /// joint named like a head bone, else none (the scene's root turns instead).
    #[must_use]
    pub fn head_node(&self) -> Option<usize> {
        self.bones.get(crate::bones::Bone::Head)
    }

    /// The face's bones: head, neck, upper spine, eyes and jaw, where the file has them.
    #[must_use]
    pub fn bones(&self) -> crate::bones::FaceBones {
        self.bones
    }

    /// How the file's eyes follow a gaze (VRM's lookAt).
    #[must_use]
    pub fn gaze(&self) -> crate::bones::Gaze {
        crate::bones::gaze(&self.document)
    }

    /// The VRM's expressions (presets named in VRM 1.0's spelling in either version), each with
    /// the morph targets it binds; empty for a file that is no VRM. Those that bind no morph
    /// target (material or bone ones) are kept, with no bindings.
    #[must_use]
    pub fn vrm_expressions(&self) -> Vec<VrmExpression> {
        crate::import::vrm::read(&self.document, &mut Vec::new())
            .map(|vrm| vrm.expressions)
            .unwrap_or_default()
            .into_iter()
            .map(|e| VrmExpression {
                name: e.name,
                preset: e.preset,
                binds: e
                    .binds
                    .iter()
                    .map(|b| Binding {
                        mesh: b.mesh as u32,
                        target: b.target as u32,
                        weight: b.weight,
                    })
                    .collect(),
            })
            .collect()
    }

    /// Whether the file is a VRM (0.x or 1.0).
    #[must_use]
    pub fn is_vrm(&self) -> bool {
        let ext = self.document.get("extensions");
        ext.is_some_and(|e| e.get("VRM").is_some() || e.get("VRMC_vrm").is_some())
    }

    /// The rotation of `node` in character space (its world rotation, after the importer's
    /// root transform), from the file's rest pose.
    #[must_use]
    pub fn world_rotation(&self, node: usize) -> Quat {
        let (_, rotation, _) = self.world_matrix(node).to_scale_rotation_translation();
        if rotation.is_finite() {
            rotation.normalize()
        } else {
            Quat::IDENTITY
        }
    }

    /// `node` as the face's rules turn it (see [`crate::bones::Joint`]), from the file's rest
    /// pose; `None` for a node the file does not have.
    #[must_use]
    pub fn joint(&self, node: usize) -> Option<crate::bones::Joint> {
        let value = self.document.get("nodes")?.as_array()?.get(node)?;
        let (_, rest, _) = local_matrix(value).to_scale_rotation_translation();
        let rest = if rest.is_finite() {
            rest.normalize()
        } else {
            Quat::IDENTITY
        };
        Some(crate::bones::Joint {
            node,
            parent: self.world_rotation(node) * rest.inverse(),
            rest,
        })
    }

    /// The transform of `node` in character space (the importer's root transform and every
    /// ancestor's), from the file's rest pose.
    #[must_use]
    pub fn world_matrix(&self, node: usize) -> Mat4 {
        let nodes = self.document.get("nodes").and_then(Value::as_array);
        let Some(nodes) = nodes.filter(|n| node < n.len()) else {
            return self.root_transform;
        };
        let parent = crate::bones::parents(nodes);
        let mut chain = Vec::new();
        let mut at = Some(node);
        while let Some(i) = at {
            if chain.len() > nodes.len() {
                break;
            }
            chain.push(i);
            at = parent[i];
        }
        let mut world = self.root_transform;
        for &i in chain.iter().rev() {
            world *= local_matrix(&nodes[i]);
        }
        world
    }
}

/// A node's local transform from its `matrix` or TRS.
pub fn local_matrix(node: &Value) -> Mat4 {
    let floats = |key: &str, n: usize| -> Option<Vec<f32>> {
        let a = node.get(key)?.as_array()?;
        (a.len() == n).then(|| a.iter().map(|v| v.as_f64().unwrap_or(0.0) as f32).collect())
    };
    if let Some(m) = floats("matrix", 16) {
        return Mat4::from_cols_slice(&m);
    }
    let t =
        floats("translation", 3).map_or(glam::Vec3::ZERO, |v| glam::Vec3::new(v[0], v[1], v[2]));
    let r =
        floats("rotation", 4).map_or(Quat::IDENTITY, |v| Quat::from_xyzw(v[0], v[1], v[2], v[3]));
    let s = floats("scale", 3).map_or(glam::Vec3::ONE, |v| glam::Vec3::new(v[0], v[1], v[2]));
    let m = Mat4::from_scale_rotation_translation(s, r, t);
    if m.is_finite() { m } else { Mat4::IDENTITY }
}

/// Shared, so that cloning a character (every baked export does) does not copy the file.
pub(crate) type SharedSource = Arc<GltfSource>;
