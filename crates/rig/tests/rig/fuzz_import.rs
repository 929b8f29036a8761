//! Property-based fuzzing of the importers: whatever bytes arrive, import returns a character or
//! an error — it never panics, hangs or allocates without bound.
//!
//! Inputs are mutations of valid files (byte flips, truncations, JSON fields set to hostile
//! numbers) and the seed corpus in `tests/corpus/` (broken files from `bad_input.rs`); proptest
//! keeps any failing case in `fuzz_import.proptest-regressions` beside this file, so it is
//! replayed forever after.

use crate::support::{GltfBuilder, tiny_face, tiny_face_gltf};
use faceanim_rig::import::{NoExternalResources, ObjSource, import_gltf, import_obj_set};
use proptest::prelude::*;
use serde_json::json;

fn valid_glb(sparse: bool) -> Vec<u8> {
    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), sparse);
    b.glb(root)
}

fn valid_json(sparse: bool) -> serde_json::Value {
    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), sparse);
    serde_json::from_slice(&b.gltf_data_uri(root)).unwrap()
}

/// Imports and, on success, checks the result is self-consistent enough to use.
fn import_must_not_panic(bytes: &[u8]) {
    if let Ok(imported) = import_gltf(bytes, "fuzz.glb", &NoExternalResources) {
        let c = imported.character;
        let _ = c.pose(&vec![1.0; c.blendshapes().len()]);
        let _ = faceanim_export::glb::export_glb(&c, &[]).unwrap();
    }
}

#[test]
fn the_seed_corpus_imports_without_panicking() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let result = import_gltf(&bytes, &path.display().to_string(), &NoExternalResources);
        if let Err(e) = result {
            assert!(
                e.to_string().starts_with(&path.display().to_string()),
                "{e}"
            );
        }
        count += 1;
    }
    assert!(
        count >= 10,
        "the corpus in {} has only {count} files",
        dir.display()
    );
}

/// Item `which` (modulo their count) of the top-level array `array`, if it has any.
fn item<'a>(
    root: &'a mut serde_json::Value,
    array: &str,
    which: usize,
) -> Option<&'a mut serde_json::Value> {
    let items = root[array].as_array_mut()?;
    let n = items.len();
    items.get_mut(which % n.max(1))
}

/// A small full-body avatar around the tiny face: skinned, textured, the face split into
/// meshes sharing target names, sparse targets, with a VRM 0.x or 1.0 extension or none,
/// optionally meshopt-compressed and quantized by gltfpack (made once per kind).
fn avatar(kind: u8) -> &'static [u8] {
    use faceanim_testdata::avatar::{Expression, VrmKind, full_body_glb};
    static MADE: std::sync::OnceLock<Vec<Vec<u8>>> = std::sync::OnceLock::new();
    let made = MADE.get_or_init(|| {
        let face = import_gltf(&valid_glb(false), "tiny.glb", &NoExternalResources)
            .unwrap()
            .character;
        let first = face.blendshapes()[0].name().to_owned();
        let binds = [first.as_str()];
        let expressions = [Expression {
            name: "blink",
            v0_preset: "blink",
            binds: &binds,
        }];
        let v0 = full_body_glb(&face, VrmKind::V0, &expressions);
        let v1 = full_body_glb(&face, VrmKind::V1, &expressions);
        let packed = faceanim_testdata::gltfpack(&v1, &["-cc", "-kn"]);
        vec![v0, v1, packed]
    });
    &made[usize::from(kind) % made.len()]
}

#[test]
fn the_avatars_import_before_mutation() {
    for kind in 0..3 {
        import_gltf(avatar(kind), "avatar.glb", &NoExternalResources).unwrap();
    }
}

const HOSTILE: [i64; 10] = [0, 1, 3, 4, 5121, 5126, -1, 65_535, 4_294_967_295, 1 << 40];

/// Where the avatar fuzzing writes hostile values: (top-level array, JSON pointer in an item).
const AVATAR_FIELDS: [(&str, &str); 10] = [
    ("bufferViews", "/extensions/EXT_meshopt_compression/count"),
    (
        "bufferViews",
        "/extensions/EXT_meshopt_compression/byteStride",
    ),
    (
        "bufferViews",
        "/extensions/EXT_meshopt_compression/byteLength",
    ),
    (
        "bufferViews",
        "/extensions/EXT_meshopt_compression/byteOffset",
    ),
    ("bufferViews", "/extensions/EXT_meshopt_compression/buffer"),
    ("skins", "/joints/0"),
    ("skins", "/inverseBindMatrices"),
    ("nodes", "/skin"),
    ("accessors", "/count"),
    ("meshes", "/primitives/0/targets/0/POSITION"),
];

/// Where the glTF fuzzing writes hostile values: (top-level array, key of an item).
const GLTF_FIELDS: [(&str, &str); 8] = [
    ("accessors", "count"),
    ("accessors", "byteOffset"),
    ("accessors", "bufferView"),
    ("accessors", "componentType"),
    ("bufferViews", "byteOffset"),
    ("bufferViews", "byteLength"),
    ("bufferViews", "byteStride"),
    ("buffers", "byteLength"),
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn byte_flips(sparse: bool, flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        let mut bytes = valid_glb(sparse);
        for (at, value) in flips {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        import_must_not_panic(&bytes);
    }

    #[test]
    fn avatar_byte_flips(kind in 0u8..3, flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        let mut bytes = avatar(kind).to_vec();
        for (at, value) in flips {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        import_must_not_panic(&bytes);
    }

    #[test]
    fn avatar_hostile_fields(
        kind in 0u8..3,
        edits in prop::collection::vec((0..AVATAR_FIELDS.len(), 0usize..64, prop::sample::select(&HOSTILE[..])), 1..4),
    ) {
        let (mut root, bin) = faceanim_testdata::glb::parts(avatar(kind));
        for (field, which, value) in edits {
            let (array, pointer) = AVATAR_FIELDS[field];
            if let Some(slot) = item(&mut root, array, which).and_then(|it| it.pointer_mut(pointer)) {
                *slot = json!(value);
            }
            // The VRM extensions' bindings too.
            if let Some(bind) = root.pointer_mut("/extensions/VRM/blendShapeMaster/blendShapeGroups/0/binds/0/index") {
                *bind = json!(value);
            }
            if let Some(bind) = root.pointer_mut("/extensions/VRMC_vrm/expressions/preset/blink/morphTargetBinds/0/node") {
                *bind = json!(value);
            }
        }
        import_must_not_panic(&faceanim_testdata::glb::assemble(&root, &bin));
    }

    #[test]
    fn truncations(sparse: bool, keep in any::<prop::sample::Index>()) {
        let bytes = valid_glb(sparse);
        import_must_not_panic(&bytes[..keep.index(bytes.len())]);
    }

    #[test]
    fn hostile_json_fields(
        sparse: bool,
        edits in prop::collection::vec((0..GLTF_FIELDS.len(), 0usize..12, prop::sample::select(&HOSTILE[..])), 1..4),
    ) {
        let mut root = valid_json(sparse);
        for (field, which, value) in edits {
            let (array, key) = GLTF_FIELDS[field];
            if let Some(it) = item(&mut root, array, which) {
                it[key] = json!(value);
            }
            // Sparse blocks are a favourite place for lies too.
            if field == 7
                && let Some(acc) = root["accessors"].as_array_mut().and_then(|a| a.iter_mut().find(|a| a.get("sparse").is_some())) {
                    acc["sparse"]["count"] = json!(value);
                }
        }
        import_must_not_panic(&serde_json::to_vec(&root).unwrap());
    }

    #[test]
    fn obj_text(neutral in "(v( -?[0-9]{1,2}(\\.[0-9])?){3}\n|vt [0-9] [0-9]\n|f( -?[0-9]{1,2}(/[0-9]?){0,2}){3,4}\n|usemtl m[0-9]\n|# c\n){0,24}",
                shape in "(v( -?[0-9](\\.[0-9])?){2,4}\n){0,12}") {
        let _ = import_obj_set("fuzz", ObjSource { name: "n.obj", text: &neutral }, &[ObjSource { name: "s.obj", text: &shape }]);
    }
}
