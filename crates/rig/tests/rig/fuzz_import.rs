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
        let _ = faceanim_rig::export::export_glb(&c, &[]).unwrap();
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

const HOSTILE: [i64; 10] = [0, 1, 3, 4, 5121, 5126, -1, 65_535, 4_294_967_295, 1 << 40];

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
    fn truncations(sparse: bool, keep in any::<prop::sample::Index>()) {
        let bytes = valid_glb(sparse);
        import_must_not_panic(&bytes[..keep.index(bytes.len())]);
    }

    #[test]
    fn hostile_json_fields(
        sparse: bool,
        edits in prop::collection::vec((0usize..8, 0usize..12, prop::sample::select(&HOSTILE[..])), 1..4),
    ) {
        let mut root = valid_json(sparse);
        for (field, which, value) in edits {
            let (array, key) = match field {
                0 => ("accessors", "count"),
                1 => ("accessors", "byteOffset"),
                2 => ("accessors", "bufferView"),
                3 => ("accessors", "componentType"),
                4 => ("bufferViews", "byteOffset"),
                5 => ("bufferViews", "byteLength"),
                6 => ("bufferViews", "byteStride"),
                _ => ("buffers", "byteLength"),
            };
            if let Some(items) = root[array].as_array_mut()
                && !items.is_empty() {
                    let n = items.len();
                    items[which % n][key] = json!(value);
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
