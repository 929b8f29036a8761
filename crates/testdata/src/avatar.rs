//! Full-body test avatars assembled in code from an openly licensed head (the ICT heads, the
//! built-in head): the kind of file Ready Player Me, VRoid or Character Creator export, made
//! here so that no third-party avatar is committed.
//!
//! The avatar is a GLB with a five-joint skeleton (Hips, Spine, Chest, Neck, Head), a textured
//! body skinned to the lower joints, and the head split into up to four meshes (head, teeth,
//! left eye, right eye) that share one list of target names, skinned to the Head joint and
//! placed at `HEAD_HEIGHT` through that joint. Some targets are written as sparse accessors.
//! It can carry a VRM 0.x or 1.0 extension whose expressions bind the head's targets.

use std::collections::HashMap;

use faceanim_rig::Character;
use faceanim_rig::glam::Vec3;
use serde_json::{Value, json};

/// Where the head joint puts the head's origin, in metres above the feet.
pub const HEAD_HEIGHT: f32 = 1.5;

/// Which VRM extension, if any, the avatar carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VrmKind {
    /// A plain glTF avatar.
    None,
    /// VRM 0.x: `VRM.blendShapeMaster`, weights 0–100, the model turned to face −Z.
    V0,
    /// VRM 1.0: `VRMC_vrm.expressions`, bound by node, weights 0–1.
    V1,
}

/// An expression for the VRM extension: its preset or custom name and the head targets
/// (by name) it binds at full weight.
pub struct Expression<'a> {
    /// VRM 1.0 preset name (`blink`, `aa`, `happy`) or a custom name.
    pub name: &'a str,
    /// VRM 0.x preset name (`blink`, `a`, `joy`), or `unknown` for a custom one.
    pub v0_preset: &'a str,
    /// The head's blendshape names it binds, each at weight 1.
    pub binds: &'a [&'a str],
}

/// Expressions over the ICT head's blendshapes, as a VRM avatar made from it has them: three
/// presets (`blink`, `aa`, `happy`) and a custom one (`smirk`).
pub const ICT_EXPRESSIONS: &[Expression<'static>] = &[
    Expression {
        name: "blink",
        v0_preset: "blink",
        binds: &["eyeBlink_L", "eyeBlink_R"],
    },
    Expression {
        name: "aa",
        v0_preset: "a",
        binds: &["jawOpen"],
    },
    Expression {
        name: "happy",
        v0_preset: "joy",
        binds: &["mouthSmile_L", "mouthSmile_R"],
    },
    Expression {
        name: "smirk",
        v0_preset: "unknown",
        binds: &["mouthSmile_L"],
    },
];

struct Writer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Writer {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view =
            json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(view);
        self.views.len() - 1
    }

    fn vec3(&mut self, values: &[Vec3], bounds: bool) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flat_map(|v| v.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let view = self.view(&bytes, Some(34962));
        let mut accessor = json!({ "bufferView": view, "componentType": 5126, "count": values.len(), "type": "VEC3" });
        if bounds {
            let lo = values.iter().fold(Vec3::splat(f32::MAX), |a, b| a.min(*b));
            let hi = values.iter().fold(Vec3::splat(f32::MIN), |a, b| a.max(*b));
            accessor["min"] = json!(lo.to_array());
            accessor["max"] = json!(hi.to_array());
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A morph target's deltas as a sparse accessor (no base view: zeros elsewhere).
    fn sparse_vec3(&mut self, count: usize, entries: &[(u32, Vec3)]) -> usize {
        let indices: Vec<u8> = entries.iter().flat_map(|(i, _)| i.to_le_bytes()).collect();
        let values: Vec<u8> = entries
            .iter()
            .flat_map(|(_, d)| d.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let iv = self.view(&indices, None);
        let vv = self.view(&values, None);
        let mut lo = if entries.len() < count {
            Vec3::ZERO
        } else {
            Vec3::splat(f32::MAX)
        };
        let mut hi = if entries.len() < count {
            Vec3::ZERO
        } else {
            Vec3::splat(f32::MIN)
        };
        for (_, d) in entries {
            lo = lo.min(*d);
            hi = hi.max(*d);
        }
        self.accessors.push(json!({
            "componentType": 5126, "count": count, "type": "VEC3",
            "min": lo.to_array(), "max": hi.to_array(),
            "sparse": { "count": entries.len(),
                        "indices": { "bufferView": iv, "componentType": 5125 },
                        "values": { "bufferView": vv } }
        }));
        self.accessors.len() - 1
    }

    fn raw(
        &mut self,
        bytes: &[u8],
        component: u32,
        count: usize,
        kind: &str,
        target: Option<u32>,
    ) -> usize {
        let view = self.view(bytes, target);
        self.accessors.push(
            json!({ "bufferView": view, "componentType": component, "count": count, "type": kind }),
        );
        self.accessors.len() - 1
    }
}

/// Splits the head's triangles into connected pieces: the largest is the head; the others are
/// eyes (by side) or teeth (in the middle).
fn pieces(character: &Character) -> Vec<(&'static str, Vec<usize>)> {
    let n = character.vertex_count();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for t in character.triangles() {
        let a = root(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let b = root(&mut parent, v as usize);
            parent[b] = a;
        }
    }
    let mut by_root: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, t) in character.triangles().iter().enumerate() {
        by_root
            .entry(root(&mut parent, t[0] as usize))
            .or_default()
            .push(k);
    }
    let mut groups: Vec<Vec<usize>> = by_root.into_values().collect();
    groups.sort_by_key(|g| std::cmp::Reverse(g.len()));
    let mut named: HashMap<&'static str, Vec<usize>> = HashMap::new();
    let width = character.bounds().max.x - character.bounds().min.x;
    for (g, group) in groups.into_iter().enumerate() {
        let name = if g == 0 {
            "Head"
        } else {
            let centre: f32 = group
                .iter()
                .map(|&k| character.positions()[character.triangles()[k][0] as usize].x)
                .sum::<f32>()
                / group.len() as f32;
            if centre > 0.05 * width {
                "EyeLeft"
            } else if centre < -0.05 * width {
                "EyeRight"
            } else {
                "Teeth"
            }
        };
        named.entry(name).or_default().extend(group);
    }
    ["Head", "Teeth", "EyeLeft", "EyeRight"]
        .into_iter()
        .filter_map(|name| named.remove(name).map(|t| (name, t)))
        .collect()
}

/// A `side`×`side` checker PNG for the body's texture (4×4 squares), with a little
/// deterministic grain, so a large one weighs what a real outfit texture does.
fn checker_png(side: u32) -> Vec<u8> {
    let mut pixels = Vec::with_capacity((side * side * 3) as usize);
    let mut state: u32 = 0x1234_5678;
    for y in 0..side {
        for x in 0..side {
            let on = (x * 4 / side + y * 4 / side).is_multiple_of(2);
            let base: [u8; 3] = if on { [40, 90, 160] } else { [220, 220, 230] };
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let grain = if side > 16 { (state % 128) as u8 } else { 0 };
            pixels.extend(base.iter().map(|c| c.saturating_sub(grain)));
        }
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, side, side);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        if let Ok(mut writer) = encoder.write_header() {
            let _ = writer.write_image_data(&pixels);
        }
    }
    out
}

/// A box from `lo` to `hi` (24 vertices, 12 triangles) appended to `positions`/`triangles`.
fn cuboid(
    lo: Vec3,
    hi: Vec3,
    positions: &mut Vec<Vec3>,
    uvs: &mut Vec<[f32; 2]>,
    triangles: &mut Vec<[u32; 3]>,
) {
    let corners = |axis: usize, sign: f32| -> [Vec3; 4] {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut out = [Vec3::ZERO; 4];
        for (k, (a, b)) in [(0., 0.), (1., 0.), (1., 1.), (0., 1.)]
            .into_iter()
            .enumerate()
        {
            let mut p = Vec3::ZERO;
            p[axis] = if sign > 0.0 { hi[axis] } else { lo[axis] };
            p[u] = lo[u] + a * (hi[u] - lo[u]);
            p[v] = lo[v] + b * (hi[v] - lo[v]);
            out[k] = p;
        }
        out
    };
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let base = positions.len() as u32;
            positions.extend(corners(axis, sign));
            uvs.extend([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
            if sign > 0.0 {
                triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            } else {
                triangles.extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]);
            }
        }
    }
}

/// The avatar as GLB bytes: `head` on a skinned, textured body; with `vrm`, the VRM extension
/// and `expressions`.
#[must_use]
pub fn full_body_glb(head: &Character, vrm: VrmKind, expressions: &[Expression<'_>]) -> Vec<u8> {
    full_body_glb_textured(head, vrm, expressions, 16)
}

/// [`full_body_glb`] with an outfit texture `texture`×`texture` pixels large, grainy enough
/// that PNG keeps it at about 1.6·`texture`² bytes (1152 makes a 3 MB avatar once gltfpack
/// has compressed the ICT head).
#[must_use]
#[expect(
    clippy::too_many_lines,
    reason = "one glTF document, written top to bottom"
)]
pub fn full_body_glb_textured(
    head: &Character,
    vrm: VrmKind,
    expressions: &[Expression<'_>],
    texture: u32,
) -> Vec<u8> {
    let mut w = Writer {
        bin: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let names: Vec<String> = head.blendshape_names();
    // Joints: 0 Hips (0.95), 1 Spine (1.1), 2 Chest (1.25), 3 Neck (1.38), 4 Head (HEAD_HEIGHT).
    let heights = [0.95f32, 1.1, 1.25, 1.38, HEAD_HEIGHT];
    let joint_names = ["Hips", "Spine", "Chest", "Neck", "Head"];

    // Body: legs and torso boxes skinned to Hips/Spine/Chest.
    let (mut bp, mut buv, mut bt) = (Vec::new(), Vec::new(), Vec::new());
    let head_width = head.bounds().max.x - head.bounds().min.x;
    let s = head_width / 0.25;
    cuboid(
        Vec3::new(-0.17 * s, 0.0, -0.08 * s),
        Vec3::new(-0.03 * s, 0.95, 0.08 * s),
        &mut bp,
        &mut buv,
        &mut bt,
    );
    cuboid(
        Vec3::new(0.03 * s, 0.0, -0.08 * s),
        Vec3::new(0.17 * s, 0.95, 0.08 * s),
        &mut bp,
        &mut buv,
        &mut bt,
    );
    cuboid(
        Vec3::new(-0.2 * s, 0.95, -0.1 * s),
        Vec3::new(0.2 * s, 1.36, 0.1 * s),
        &mut bp,
        &mut buv,
        &mut bt,
    );
    let body_joints: Vec<u8> = bp
        .iter()
        .flat_map(|p: &Vec3| {
            let j: u8 = if p.y < 1.05 {
                0
            } else if p.y < 1.2 {
                1
            } else {
                2
            };
            [j, 0, 0, 0]
        })
        .collect();
    let body_weights: Vec<u8> = bp
        .iter()
        .flat_map(|_| [1.0f32, 0.0, 0.0, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    let indices: Vec<u8> = bt
        .iter()
        .flatten()
        .flat_map(|i: &u32| i.to_le_bytes())
        .collect();
    let body_pos = w.vec3(&bp, true);
    let uv_bytes: Vec<u8> = buv
        .iter()
        .flatten()
        .flat_map(|f: &f32| f.to_le_bytes())
        .collect();
    let body_uv = w.raw(&uv_bytes, 5126, buv.len(), "VEC2", Some(34962));
    let body_j = w.raw(&body_joints, 5121, bp.len(), "VEC4", Some(34962));
    let body_w = w.raw(&body_weights, 5126, bp.len(), "VEC4", Some(34962));
    let body_idx = w.raw(&indices, 5125, bt.len() * 3, "SCALAR", Some(34963));
    let mut meshes = vec![json!({
        "name": "Body",
        "primitives": [{ "attributes": { "POSITION": body_pos, "TEXCOORD_0": body_uv, "JOINTS_0": body_j, "WEIGHTS_0": body_w },
                          "indices": body_idx, "material": 0 }]
    })];

    // Head pieces: each its own vertices, all targets, skinned to the Head joint (index 4).
    for (p, (name, tris)) in pieces(head).into_iter().enumerate() {
        let mut remap: HashMap<u32, u32> = HashMap::new();
        let mut local = Vec::new();
        let mut local_tris = Vec::new();
        for &k in &tris {
            let t = head.triangles()[k];
            local_tris.push(t.map(|v| {
                *remap.entry(v).or_insert_with(|| {
                    local.push(v);
                    (local.len() - 1) as u32
                })
            }));
        }
        let positions: Vec<Vec3> = local
            .iter()
            .map(|&v| head.positions()[v as usize])
            .collect();
        let pos = w.vec3(&positions, true);
        let joints: Vec<u8> = local.iter().flat_map(|_| [4u8, 0, 0, 0]).collect();
        let weights: Vec<u8> = local
            .iter()
            .flat_map(|_| [1.0f32, 0.0, 0.0, 0.0])
            .flat_map(f32::to_le_bytes)
            .collect();
        let j = w.raw(&joints, 5121, local.len(), "VEC4", Some(34962));
        let wt = w.raw(&weights, 5126, local.len(), "VEC4", Some(34962));
        let idx_bytes: Vec<u8> = local_tris
            .iter()
            .flatten()
            .flat_map(|i: &u32| i.to_le_bytes())
            .collect();
        let idx = w.raw(
            &idx_bytes,
            5125,
            local_tris.len() * 3,
            "SCALAR",
            Some(34963),
        );
        let mut targets = Vec::new();
        for (t, shape) in head.blendshapes().iter().enumerate() {
            let entries: Vec<(u32, Vec3)> = shape
                .moves()
                .filter_map(|(v, d)| remap.get(&v).map(|&l| (l, d)))
                .collect();
            let accessor = if t % 3 == 1 && !entries.is_empty() {
                let mut sorted = entries;
                sorted.sort_by_key(|(i, _)| *i);
                w.sparse_vec3(local.len(), &sorted)
            } else {
                let mut dense = vec![Vec3::ZERO; local.len()];
                for (l, d) in entries {
                    dense[l as usize] = d;
                }
                w.vec3(&dense, true)
            };
            targets.push(json!({ "POSITION": accessor }));
        }
        meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": { "POSITION": pos, "JOINTS_0": j, "WEIGHTS_0": wt },
                              "indices": idx, "material": 1 + p.min(1), "targets": targets }],
            "weights": vec![0.0; names.len()],
            "extras": { "targetNames": names }
        }));
    }

    let png = checker_png(texture.max(1));
    let image_view = w.view(&png, None);
    // Inverse bind matrices: the inverse of each joint's rest translation.
    let ibm: Vec<u8> = heights
        .iter()
        .flat_map(|&h| {
            faceanim_rig::glam::Mat4::from_translation(Vec3::new(0.0, -h, 0.0)).to_cols_array()
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let ibm_view = w.view(&ibm, None);
    w.accessors
        .push(json!({ "bufferView": ibm_view, "componentType": 5126, "count": 5, "type": "MAT4" }));
    let ibm_accessor = w.accessors.len() - 1;

    // Nodes: 0 Armature root, 1..=5 joints (chain), then one node per mesh.
    let mut nodes = vec![json!({ "name": "Armature", "children": [1] })];
    let mut previous = 0.0f32;
    for (k, (&h, name)) in heights.iter().zip(joint_names).enumerate() {
        let mut node = json!({ "name": name, "translation": [0.0, h - previous, 0.0] });
        if k + 1 < heights.len() {
            node["children"] = json!([k + 2]);
        }
        nodes.push(node);
        previous = h;
    }
    let mesh_nodes: Vec<usize> = (0..meshes.len()).map(|m| nodes.len() + m).collect();
    for (m, mesh) in meshes.iter().enumerate() {
        nodes.push(json!({ "name": mesh["name"].clone(), "mesh": m, "skin": 0 }));
    }
    if vrm == VrmKind::V0 {
        // VRM 0.x models face −Z: the whole avatar turned half a turn.
        nodes[0]["rotation"] = json!([0.0, 1.0, 0.0, 0.0]);
    }
    let mut scene_nodes = vec![0];
    scene_nodes.extend(&mesh_nodes);

    // The head pieces are given in the head's own space, so their skin binds the Head joint
    // with the identity: the joint's rest transform lifts them to HEAD_HEIGHT.
    let head_ibm: Vec<u8> = (0..5)
        .flat_map(|k| {
            if k == 4 {
                faceanim_rig::glam::Mat4::IDENTITY.to_cols_array()
            } else {
                faceanim_rig::glam::Mat4::from_translation(Vec3::new(0.0, -heights[k], 0.0))
                    .to_cols_array()
            }
        })
        .flat_map(f32::to_le_bytes)
        .collect();
    let head_ibm_view = w.view(&head_ibm, None);
    w.accessors.push(
        json!({ "bufferView": head_ibm_view, "componentType": 5126, "count": 5, "type": "MAT4" }),
    );
    let head_ibm_accessor = w.accessors.len() - 1;
    for &n in &mesh_nodes[1..] {
        nodes[n]["skin"] = json!(1);
    }
    let joints: Vec<usize> = (1..=5).collect();

    let mut root = json!({
        "asset": { "version": "2.0", "generator": "faceanim-testdata avatar" },
        "scene": 0,
        "scenes": [{ "nodes": scene_nodes }],
        "nodes": nodes,
        "meshes": meshes,
        "skins": [
            { "name": "Body", "joints": joints, "inverseBindMatrices": ibm_accessor, "skeleton": 1 },
            { "name": "Head", "joints": joints, "inverseBindMatrices": head_ibm_accessor, "skeleton": 1 }
        ],
        "materials": [
            { "name": "Outfit", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0.0 } },
            { "name": "Skin", "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.75, 0.65, 1.0], "metallicFactor": 0.0 } },
            { "name": "EyesAndTeeth", "pbrMetallicRoughness": { "baseColorFactor": [0.95, 0.95, 0.92, 1.0], "metallicFactor": 0.0 } }
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "samplers": [{ "magFilter": 9729, "minFilter": 9987 }],
        "images": [{ "name": "outfit", "bufferView": image_view, "mimeType": "image/png" }],
        "accessors": w.accessors,
        "bufferViews": w.views,
        "buffers": [{ "byteLength": w.bin.len() }]
    });
    let head_mesh = 1usize;
    let bind_index = |name: &str| names.iter().position(|n| n == name);
    match vrm {
        VrmKind::None => {}
        VrmKind::V0 => {
            let groups: Vec<Value> = expressions
                .iter()
                .map(|e| {
                    let binds: Vec<Value> = e
                        .binds
                        .iter()
                        .filter_map(|b| bind_index(b))
                        .map(|i| json!({ "mesh": head_mesh, "index": i, "weight": 100.0 }))
                        .collect();
                    json!({ "name": e.name, "presetName": e.v0_preset, "binds": binds, "isBinary": false })
                })
                .collect();
            root["extensionsUsed"] = json!(["VRM"]);
            root["extensions"] = json!({ "VRM": {
                "exporterVersion": "faceanim-testdata", "specVersion": "0.0",
                "meta": { "title": "test avatar", "licenseName": "CC0" },
                "blendShapeMaster": { "blendShapeGroups": groups } } });
        }
        VrmKind::V1 => {
            let mut preset = serde_json::Map::new();
            let mut custom = serde_json::Map::new();
            for e in expressions {
                let binds: Vec<Value> = e
                    .binds
                    .iter()
                    .filter_map(|b| bind_index(b))
                    .map(|i| json!({ "node": mesh_nodes[head_mesh], "index": i, "weight": 1.0 }))
                    .collect();
                let target = if e.v0_preset == "unknown" {
                    &mut custom
                } else {
                    &mut preset
                };
                target.insert(e.name.to_owned(), json!({ "morphTargetBinds": binds }));
            }
            root["extensionsUsed"] = json!(["VRMC_vrm"]);
            root["extensions"] = json!({ "VRMC_vrm": {
                "specVersion": "1.0",
                "meta": { "name": "test avatar", "licenseUrl": "https://vrm.dev/licenses/1.0/", "authors": ["faceanim"] },
                "humanoid": { "humanBones": { "hips": { "node": 1 }, "spine": { "node": 2 }, "chest": { "node": 3 }, "neck": { "node": 4 }, "head": { "node": 5 } } },
                "expressions": { "preset": preset, "custom": custom } } });
        }
    }
    crate::glb::assemble(&root, &w.bin)
}
