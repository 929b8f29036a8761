//! Full-body avatars as people have them (built in code from the ICT head: a skinned, textured
//! body, the head split into head, teeth and eye meshes that share target names, sparse
//! targets, VRM 0.x and 1.0 expressions, gltfpack compression): they import with the head's
//! blendshapes, the face region is found, and the size that default distances scale with is
//! the head's, not the body's.

use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_testdata::avatar::{HEAD_HEIGHT, ICT_EXPRESSIONS, VrmKind, full_body_glb};
use faceanim_testdata::{gltfpack, ict};

fn import(bytes: &[u8], name: &str) -> (Character, Vec<String>) {
    let imported =
        import_gltf(bytes, name, &NoExternalResources).unwrap_or_else(|e| panic!("{name}: {e}"));
    (imported.character, imported.warnings)
}

/// The avatar has the head's blendshapes, more vertices than the head, its face up at head
/// height and facing +Z, and the head's size.
fn assert_avatar(c: &Character, what: &str) {
    let head = ict();
    for shape in head.blendshapes() {
        assert!(
            c.find_blendshape(shape.name()).is_some(),
            "{what}: {} missing",
            shape.name()
        );
    }
    assert!(
        c.vertex_count() > head.vertex_count(),
        "{what}: the body is there"
    );
    let (face, whole) = (c.face_bounds(), c.bounds());
    assert!(
        whole.max.y - whole.min.y > 1.5,
        "{what}: a full body is over 1.5 m tall: {whole:?}"
    );
    let head_face = head.face_bounds();
    let lifted = |y: f32| y + HEAD_HEIGHT;
    assert!(
        (face.min.y - lifted(head_face.min.y)).abs() < 0.01
            && (face.max.y - lifted(head_face.max.y)).abs() < 0.01,
        "{what}: face region {face:?}, the head's lifted by {HEAD_HEIGHT}: {head_face:?}"
    );
    assert!(
        (face.max.z - head_face.max.z).abs() < 0.01,
        "{what}: the face looks towards +Z ({face:?})"
    );
    let ratio = c.size() / head.size();
    assert!(
        (0.85..1.15).contains(&ratio),
        "{what}: size {} against the bare head's {} (the body's diagonal is {})",
        c.size(),
        head.size(),
        whole.diagonal()
    );
    // Each blendshape moves the same largest distance as on the bare head (all pieces together).
    for name in ["jawOpen", "eyeBlink_L", "mouthSmile_L", "browDown_L"] {
        let largest = |c: &Character| {
            let id = c.find_blendshape(name).unwrap();
            c.blendshapes()[id.index()]
                .deltas()
                .iter()
                .map(|d| d.length())
                .fold(0.0f32, f32::max)
        };
        assert!((largest(c) - largest(head)).abs() < 1e-4, "{what}: {name}");
    }
}

#[test]
fn a_full_body_avatar_imports_with_the_heads_blendshapes_and_size() {
    let bytes = full_body_glb(ict(), VrmKind::None, &[]);
    let (c, warnings) = import(&bytes, "avatar.glb");
    assert_avatar(&c, "avatar.glb");
    assert_eq!(
        c.blendshapes().len(),
        ict().blendshapes().len(),
        "{warnings:?}"
    );
    assert!(
        c.materials().iter().any(|m| m.base_color_texture.is_some()),
        "the outfit's texture is kept"
    );
    assert!(c.symmetry().plane().is_some(), "the avatar is symmetric");
}

#[test]
fn a_compressed_full_body_avatar_imports() {
    let bytes = full_body_glb(ict(), VrmKind::None, &[]);
    let packed = gltfpack(&bytes, &["-cc", "-kn"]);
    let (c, _) = import(&packed, "avatar-meshopt.glb");
    assert_avatar(&c, "avatar-meshopt.glb");
}

#[test]
fn vrm_expressions_become_blendshapes_in_both_versions() {
    for (kind, file) in [(VrmKind::V0, "avatar-0.vrm"), (VrmKind::V1, "avatar-1.vrm")] {
        let bytes = full_body_glb(ict(), kind, ICT_EXPRESSIONS);
        let (c, warnings) = import(&bytes, file);
        assert_avatar(&c, file);
        for e in ICT_EXPRESSIONS {
            let id = c
                .find_blendshape(e.name)
                .unwrap_or_else(|| panic!("{file}: expression {} missing ({warnings:?})", e.name));
            // The expression moves what its bound targets move together.
            let mut expected = vec![faceanim_rig::glam::Vec3::ZERO; c.vertex_count()];
            for bound in e.binds {
                let b = c.find_blendshape(bound).unwrap();
                for (v, d) in c.blendshapes()[b.index()].moves() {
                    expected[v as usize] += d;
                }
            }
            let mut got = vec![faceanim_rig::glam::Vec3::ZERO; c.vertex_count()];
            c.blendshapes()[id.index()].write_dense(&mut got);
            let worst = got
                .iter()
                .zip(&expected)
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0f32, f32::max);
            assert!(
                worst < 1e-4,
                "{file}: {} differs from its binds by {worst}",
                e.name
            );
        }
    }
}

/// `KHR_texture_transform` on a base-colour texture is baked into the UVs: the outfit's UVs of
/// an avatar whose material scales its texture by 2 and shifts it by ½ are the plain ones so
/// transformed.
#[test]
fn a_texture_transform_is_baked_into_the_uvs() {
    let glb = full_body_glb(ict(), VrmKind::None, &[]);
    let (mut json, bin) = faceanim_testdata::glb::parts(&glb);
    json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = serde_json::json!({ "KHR_texture_transform": { "scale": [2.0, 2.0], "offset": [0.5, 0.0] } });
    json["extensionsUsed"] = serde_json::json!(["KHR_texture_transform"]);
    let transformed = faceanim_testdata::glb::assemble(&json, &bin);
    let (plain, _) = import(&glb, "avatar.glb");
    let (moved, _) = import(&transformed, "avatar-transformed.glb");
    let (a, b) = (plain.uvs().unwrap(), moved.uvs().unwrap());
    // The body comes first in the file; its UVs are the ones the outfit's material transforms.
    let body = plain.vertex_count() - ict().vertex_count();
    assert!(body > 0);
    for v in 0..body {
        let want = [2.0 * a[v][0] + 0.5, 2.0 * a[v][1]];
        assert!(
            (b[v][0] - want[0]).abs() < 1e-6 && (b[v][1] - want[1]).abs() < 1e-6,
            "vertex {v}: {:?} for {:?}",
            b[v],
            a[v]
        );
    }
    // The head's material has no transform: its UVs stay.
    assert_eq!(a[body..], b[body..]);
}
