//! The glTF layouts other tools write: external buffers, data URIs, sparse targets, several
//! meshes and primitives under node transforms, skins, strips — all land on the same character.

use std::collections::HashMap;

use crate::support::{GltfBuilder, tiny_face, tiny_face_gltf};
use faceanim_rig::import::{NoExternalResources, Resources, import_gltf};
use glam::Vec3;
use serde_json::json;

struct Files(HashMap<String, Vec<u8>>);

impl Resources for Files {
    fn load(&self, uri: &str) -> Result<Vec<u8>, String> {
        self.0
            .get(uri)
            .cloned()
            .ok_or_else(|| "no such file".to_owned())
    }
}

fn assert_is_tiny_face(c: &faceanim_rig::Character, offset: Vec3) {
    let face = tiny_face();
    assert_eq!(c.vertex_count(), face.positions.len());
    assert_eq!(c.triangles().len(), face.indices.len() / 3);
    for (p, q) in c.positions().iter().zip(&face.positions) {
        assert!((*p - (Vec3::from(*q) + offset)).length() < 1e-6);
    }
    let names: Vec<&str> = c.blendshapes().iter().map(|b| b.name()).collect();
    assert_eq!(names, ["blink_L", "blink_R", "open"]);
    let mut dense = vec![Vec3::ZERO; c.vertex_count()];
    for (shape, (_, expected)) in c.blendshapes().iter().zip(&face.shapes) {
        shape.write_dense(&mut dense);
        for (d, e) in dense.iter().zip(expected) {
            assert!((*d - Vec3::from(*e)).length() < 1e-7);
        }
    }
    assert_eq!(c.symmetry().pairs().len(), 1);
}

#[test]
fn glb_with_dense_and_with_sparse_targets() {
    for sparse in [false, true] {
        let mut b = GltfBuilder::default();
        let root = tiny_face_gltf(&mut b, &tiny_face(), sparse);
        let c = import_gltf(&b.glb(root), "tiny.glb", &NoExternalResources)
            .unwrap()
            .character;
        assert_is_tiny_face(&c, Vec3::ZERO);
    }
}

#[test]
fn gltf_with_an_external_bin_and_with_a_data_uri() {
    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), true);
    let (json, bin) = b.gltf_external(root, "tiny%20face.bin");
    let files = Files(HashMap::from([("tiny face.bin".to_owned(), bin)]));
    assert_is_tiny_face(
        &import_gltf(&json, "tiny.gltf", &files).unwrap().character,
        Vec3::ZERO,
    );
    // The same file without its .bin names the buffer and the reason.
    let err = import_gltf(&json, "tiny.gltf", &Files(HashMap::new())).unwrap_err();
    assert_eq!(
        err.to_string(),
        "tiny.gltf: buffer 0 ('tiny%20face.bin') is missing: no such file"
    );

    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), false);
    let json = b.gltf_data_uri(root);
    assert_is_tiny_face(
        &import_gltf(&json, "tiny.gltf", &NoExternalResources)
            .unwrap()
            .character,
        Vec3::ZERO,
    );
}

#[test]
fn node_transforms_place_the_mesh_and_turn_its_deltas() {
    let mut b = GltfBuilder::default();
    let mut root = tiny_face_gltf(&mut b, &tiny_face(), false);
    // A parent translates by (0, 1, 0); the face node itself is unrotated.
    root["nodes"] =
        json!([{"children": [1], "translation": [0.0, 1.0, 0.0]}, {"mesh": 0, "name": "face"}]);
    root["scenes"] = json!([{"nodes": [0]}]);
    let c = import_gltf(&b.glb(root.clone()), "moved.glb", &NoExternalResources)
        .unwrap()
        .character;
    assert_is_tiny_face(&c, Vec3::Y);

    // A uniform scale of 2 scales positions and deltas.
    root["nodes"] = json!([{"mesh": 0, "scale": [2.0, 2.0, 2.0]}]);
    let mut b2 = GltfBuilder::default();
    let root2 = tiny_face_gltf(&mut b2, &tiny_face(), false);
    let mut root2 = root2;
    root2["nodes"] = root["nodes"].clone();
    let c = import_gltf(&b2.glb(root2), "scaled.glb", &NoExternalResources)
        .unwrap()
        .character;
    let face = tiny_face();
    let open = c.find_blendshape("open").unwrap();
    let v = face.shapes[2]
        .1
        .iter()
        .position(|d| *d != [0.0; 3])
        .unwrap();
    assert!(
        (c.blendshape(open).unwrap().delta_of(v as u32) - 2.0 * Vec3::from(face.shapes[2].1[v]))
            .length()
            < 1e-6
    );
}

#[test]
fn several_meshes_merge_their_morph_targets_by_name() {
    // The face split in two meshes (top rows, bottom rows) at different nodes, as exporters that
    // split by material do; each has the same target names.
    let face = tiny_face();
    let mut b = GltfBuilder::default();
    let half = face.indices.len() / 2;
    let mut meshes = Vec::new();
    for (k, range) in [0..half, half..face.indices.len()].into_iter().enumerate() {
        let position = b.vec3(&face.positions);
        let indices = b.indices(&face.indices[range]);
        let targets: Vec<_> = face
            .shapes
            .iter()
            .map(|(_, d)| json!({"POSITION": b.vec3(d)}))
            .collect();
        let names: Vec<&str> = face.shapes.iter().map(|(n, _)| *n).collect();
        meshes.push(json!({"name": format!("part{k}"), "primitives": [{"attributes": {"POSITION": position}, "indices": indices, "targets": targets}], "extras": {"targetNames": names}}));
    }
    let root = json!({"scene": 0, "scenes": [{"nodes": [0, 1]}], "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [5.0, 0.0, 0.0]}], "meshes": meshes});
    let c = import_gltf(&b.glb(root), "split.glb", &NoExternalResources)
        .unwrap()
        .character;
    assert_eq!(c.vertex_count(), 2 * face.positions.len());
    assert_eq!(c.blendshapes().len(), 3, "targets merged by name");
    assert_eq!(c.parts().len(), 2);
    assert_eq!(
        c.positions()[face.positions.len()],
        Vec3::from(face.positions[0]) + Vec3::new(5.0, 0.0, 0.0)
    );
    let open = c.blendshape(c.find_blendshape("open").unwrap()).unwrap();
    let per_copy = face.shapes[2].1.iter().filter(|d| **d != [0.0; 3]).count();
    assert_eq!(open.moved(), 2 * per_copy, "both copies carry the shape");
}

#[test]
fn a_skinned_mesh_is_placed_by_its_joints_at_rest() {
    let face = tiny_face();
    let mut b = GltfBuilder::default();
    let mut root = tiny_face_gltf(&mut b, &face, false);
    let n = face.positions.len();
    let joints: Vec<u8> = (0..n).flat_map(|_| [0u8, 0, 0, 0]).collect();
    let weights: Vec<u8> = (0..n)
        .flat_map(|_| [1.0f32, 0.0, 0.0, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    let j = b.raw(&joints, 5121, n, "VEC4");
    let w = b.raw(&weights, 5126, n, "VEC4");
    root["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(j);
    root["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = json!(w);
    // The joint sits at z = 3 with an identity inverse bind: the rest pose moves the face by 3.
    // The mesh node's own transform must be ignored for skinned meshes.
    root["nodes"] = json!([{"mesh": 0, "skin": 0, "translation": [100.0, 0.0, 0.0]}, {"translation": [0.0, 0.0, 3.0]}]);
    root["scenes"] = json!([{"nodes": [0, 1]}]);
    root["skins"] = json!([{"joints": [1]}]);
    let c = import_gltf(&b.glb(root), "skinned.glb", &NoExternalResources)
        .unwrap()
        .character;
    assert_is_tiny_face(&c, Vec3::new(0.0, 0.0, 3.0));
}

#[test]
fn triangle_strips_are_triangulated_and_lines_skipped_with_a_warning() {
    let mut b = GltfBuilder::default();
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let p = b.vec3(&positions);
    let t = b.vec3(&[[0.0, 0.0, 0.1]; 4]);
    let root = json!({
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": p}, "mode": 5, "targets": [{"POSITION": t}]},
            {"attributes": {"POSITION": p}, "mode": 1, "targets": [{"POSITION": t}]}
        ]}]
    });
    let imported = import_gltf(&b.glb(root), "strip.glb", &NoExternalResources).unwrap();
    assert_eq!(imported.character.triangles(), &[[0, 1, 2], [2, 1, 3]]);
    assert_eq!(imported.character.blendshapes()[0].name(), "target_0");
    assert_eq!(
        imported.warnings,
        ["mesh 0 primitive 1: skipped Lines (only triangles are animated)"]
    );
}

#[test]
fn duplicate_target_names_stay_distinct() {
    let mut b = GltfBuilder::default();
    let mut root = tiny_face_gltf(&mut b, &tiny_face(), false);
    root["meshes"][0]["extras"]["targetNames"] = json!(["smile", "smile", "open"]);
    let imported = import_gltf(&b.glb(root), "dup.glb", &NoExternalResources).unwrap();
    let names: Vec<&str> = imported
        .character
        .blendshapes()
        .iter()
        .map(|b| b.name())
        .collect();
    // Two targets of one mesh are two blendshapes even under one name.
    assert_eq!(names, ["smile", "smile.001", "open"]);
    assert_eq!(
        imported.warnings,
        ["mesh 0 'face': morph target 1 repeats the name 'smile'; renamed 'smile.001'"]
    );
}
