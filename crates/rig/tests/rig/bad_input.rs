//! Broken files get clear errors that name the file and the problem — never a panic.
//!
//! Each case here is also written to `tests/corpus/` (with FACEANIM_WRITE_CORPUS=1), the seed
//! corpus that `fuzz_import.rs` replays and mutates.

use crate::support::{GltfBuilder, tiny_face, tiny_face_gltf};
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_testdata::ict_bytes;
use serde_json::{Value, json};

fn error_of(name: &str, bytes: &[u8]) -> String {
    // Only small cases go into the corpus; the truncated 17 MB head stays out of git.
    if std::env::var_os("FACEANIM_WRITE_CORPUS").is_some() && bytes.len() < 64 * 1024 {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    match import_gltf(bytes, name, &NoExternalResources) {
        Ok(_) => panic!("{name} was accepted"),
        Err(e) => e.to_string(),
    }
}

fn tiny(edit: impl FnOnce(&mut serde_json::Value, &mut GltfBuilder)) -> Vec<u8> {
    let mut b = GltfBuilder::default();
    let mut root = tiny_face_gltf(&mut b, &tiny_face(), false);
    edit(&mut root, &mut b);
    b.glb(root)
}

/// Gives the first primitive a material whose base colour is the texture of `image`.
fn textured(root: &mut Value, image: Value) {
    root["images"] = json!([image]);
    root["textures"] = json!([{"source": 0}]);
    root["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    root["meshes"][0]["primitives"][0]["material"] = json!(0);
}

#[test]
fn not_gltf() {
    assert_eq!(
        error_of("photo.glb", b"\x89PNG\r\n\x1a\n0000"),
        "photo.glb: not a glTF file: it starts with bytes [89 50 4e 47 0d 0a 1a 0a], neither the GLB magic 'glTF' nor a JSON object"
    );
    assert_eq!(
        error_of("empty.glb", b""),
        "empty.glb: not a glTF file: it starts with bytes [], neither the GLB magic 'glTF' nor a JSON object"
    );
    assert!(
        error_of("broken.gltf", b"{\"asset\": ")
            .starts_with("broken.gltf: invalid glTF JSON: EOF while parsing")
    );
}

#[test]
fn truncated() {
    let ict = ict_bytes();
    assert_eq!(
        error_of("ict-head-only.glb", &ict[..10]),
        "ict-head-only.glb: truncated: the GLB ends at byte 10 inside its headers"
    );
    assert_eq!(
        error_of("ict-half.glb", &ict[..ict.len() / 2]),
        format!(
            "ict-half.glb: truncated: the GLB header says {} bytes but there are {}",
            ict.len(),
            ict.len() / 2
        )
    );
}

/// Channels the glTF crate cannot read — a material animated through `KHR_animation_pointer`
/// (path `pointer`, as Blender 4 exports it), a misspelt path, a node the file does not have —
/// are left out with a warning each: the head and its other channels still read (the glTF
/// crate panicked on such a channel).
#[test]
fn animation_channels_of_unknown_paths_are_left_out_with_a_warning() {
    let bytes = tiny(|root, b| {
        let times = b.raw(
            &[0.0f32, 1.0].map(f32::to_le_bytes).concat(),
            5126,
            2,
            "SCALAR",
        );
        b.accessors[times]["min"] = json!([0.0]);
        b.accessors[times]["max"] = json!([1.0]);
        let weights = b.raw(
            &[0.0f32; 6].map(f32::to_le_bytes).concat(),
            5126,
            6,
            "SCALAR",
        );
        let colour = b.raw(&[1.0f32; 8].map(f32::to_le_bytes).concat(), 5126, 2, "VEC4");
        root["extensionsUsed"] = json!(["KHR_animation_pointer"]);
        root["animations"] = json!([{ "name": "take", "samplers": [
            { "input": times, "output": weights },
            { "input": times, "output": colour }
        ], "channels": [
            { "sampler": 1, "target": { "path": "pointer", "extensions": { "KHR_animation_pointer":
                { "pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor" } } } },
            { "sampler": 0, "target": { "node": 0, "path": "weightz" } },
            { "sampler": 0, "target": { "node": 9, "path": "weights" } },
            { "sampler": 0, "target": { "node": 0, "path": "weights" } }
        ] }]);
    });
    let imported = import_gltf(&bytes, "pointer.glb", &NoExternalResources).unwrap();
    let said = imported.warnings.join("\n");
    for expected in [
        "animations[0].channels[0]: it animates 'pointer'",
        "animations[0].channels[1]: it animates 'weightz'",
        "animations[0].channels[2]: it animates node 9, which the file does not have",
    ] {
        assert!(said.contains(expected), "{said}");
    }
    assert_eq!(imported.character.blendshapes().len(), 3);
    let source = imported.character.source().unwrap();
    assert_eq!(source.animations().len(), 1, "{said}");
}

#[test]
fn a_head_without_morph_targets_imports_and_says_how_to_get_them() {
    // A scan or an avatar exported without shape keys is a character to make shapes for
    // (`faceanim generate-shapes`), not a broken file.
    let bytes = tiny(|root, _| {
        root["meshes"][0]["primitives"][0]
            .as_object_mut()
            .unwrap()
            .remove("targets");
        root["meshes"][0].as_object_mut().unwrap().remove("extras");
    });
    let imported = import_gltf(&bytes, "static.glb", &NoExternalResources).unwrap();
    assert!(imported.character.blendshapes().is_empty());
    assert!(
        imported
            .warnings
            .iter()
            .any(|w| w.contains("no morph targets") && w.contains("faceanim generate-shapes")),
        "{:?}",
        imported.warnings
    );
}

#[test]
fn counts_that_disagree() {
    let bytes = tiny(|root, b| {
        let short = b.vec3(&[[0.0, 0.1, 0.0]; 5]);
        root["meshes"][0]["primitives"][0]["targets"][1]["POSITION"] = json!(short);
    });
    assert_eq!(
        error_of("short-target.glb", &bytes),
        "short-target.glb: counts disagree: morph target 1 ('blink_R') POSITION of mesh 0 'face' primitive 0 (accessor 5) has 5 elements but POSITION has 81"
    );
    let bytes = tiny(|root, b| {
        let idx = b.indices(&[0, 1, 200]);
        root["meshes"][0]["primitives"][0]["indices"] = json!(idx);
    });
    assert_eq!(
        error_of("bad-index.glb", &bytes),
        "bad-index.glb: counts disagree: mesh 0 'face' primitive 0 uses vertex 200 but has only 81 vertices"
    );
}

#[test]
fn nan_and_infinity() {
    let face = tiny_face();
    let mut b = GltfBuilder::default();
    let mut root = tiny_face_gltf(&mut b, &face, false);
    let mut nan_positions = face.positions.clone();
    nan_positions[7][1] = f32::NAN;
    root["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(b.vec3(&nan_positions));
    // min/max of a NaN column are not numbers either; keep the JSON valid.
    let last = b.accessors.len() - 1;
    b.accessors[last]["min"] = json!([-1.0, -1.0, 0.0]);
    b.accessors[last]["max"] = json!([1.0, 1.0, 0.3]);
    assert_eq!(
        error_of("nan.glb", &b.glb(root)),
        "nan.glb: POSITION of mesh 0 'face' primitive 0 [7] is not a finite number"
    );

    let bytes = tiny(|root, b| {
        let mut d = vec![[0.0f32; 3]; 81];
        d[3] = [f32::INFINITY, 0.0, 0.0];
        let acc = b.vec3(&d);
        let last = b.accessors.len() - 1;
        b.accessors[last]["min"] = json!([0.0, 0.0, 0.0]);
        b.accessors[last]["max"] = json!([1.0, 0.0, 0.0]);
        root["meshes"][0]["primitives"][0]["targets"][2]["POSITION"] = json!(acc);
    });
    assert_eq!(
        error_of("inf.glb", &bytes),
        "inf.glb: morph target 2 ('open') POSITION of mesh 0 'face' primitive 0 [3] is not a finite number"
    );
}

#[test]
fn absurd_sizes_and_lying_layouts() {
    let bytes = tiny(|_, b| {
        b.accessors[0]["count"] = json!(4_000_000_000u64);
    });
    assert_eq!(
        error_of("huge-count.glb", &bytes),
        "huge-count.glb: too large: mesh 0 'face' primitive 0 declares 4000000000 vertices (0 before it; at most 16777216 in all)"
    );

    let bytes = tiny(|_, b| {
        b.views[0]["byteLength"] = json!(100_000_000u64);
    });
    let e = error_of("long-view.glb", &bytes);
    assert!(e.starts_with("long-view.glb: accessor 0 (POSITION of mesh 0 'face' primitive 0): buffer view 0 ends at byte 100000000, past the end of buffer 0"), "{e}");

    let bytes = tiny(|_, b| {
        b.accessors[0]["byteOffset"] = json!(960);
    });
    let e = error_of("offset.glb", &bytes);
    assert!(
        e.contains("81 elements need 1932 bytes from offset 960, but buffer view 0 has 972"),
        "{e}"
    );
}

#[test]
fn schema_errors_and_cycles() {
    // An accessor that is not an object is named, not indexed into.
    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), false);
    let mut file: serde_json::Value = serde_json::from_slice(&b.gltf_data_uri(root)).unwrap();
    file["accessors"].as_array_mut().unwrap().push(json!(7));
    let e = error_of("number-accessor.gltf", &serde_json::to_vec(&file).unwrap());
    assert!(
        e.starts_with("number-accessor.gltf: invalid glTF JSON: ") && e.contains("accessors["),
        "{e}"
    );
    let bytes = tiny(|root, _| root["meshes"][0]["primitives"][0]["indices"] = json!(99));
    assert_eq!(
        error_of("dangling.glb", &bytes),
        "dangling.glb: invalid glTF JSON: meshes[0].primitives[0].indices: Index out of bounds"
    );

    let bytes = tiny(|root, _| {
        root["nodes"] = json!([{"children": [1], "mesh": 0}, {"children": [0]}]);
    });
    let e = error_of("cycle.glb", &bytes);
    assert!(e.starts_with("cycle.glb: invalid glTF JSON: node"), "{e}");

    let mut b = GltfBuilder::default();
    let root = tiny_face_gltf(&mut b, &tiny_face(), false);
    let mut old: serde_json::Value = serde_json::from_slice(&b.gltf_data_uri(root)).unwrap();
    old["asset"]["version"] = json!("1.0");
    let bytes = serde_json::to_vec(&old).unwrap();
    assert_eq!(
        error_of("gltf1.glb", &bytes),
        "gltf1.glb: unsupported: glTF version 1.0 (faceanim reads glTF 2.0)"
    );
    // An embedded image without its mimeType (gltf's own accessor would panic on it).
    let bytes = tiny(|root, b| {
        let view = b.view(&[0x89, b'P', b'N', b'G']);
        textured(root, json!({"bufferView": view}));
    });
    assert_eq!(
        error_of("no-mime.glb", &bytes),
        "no-mime.glb: invalid glTF JSON: images[0].mimeType: an image stored in a buffer view needs its mimeType (image/png or image/jpeg)"
    );
    // An image with neither a uri nor a buffer view (gltf's accessor would panic on it too).
    let bytes = tiny(|root, _| {
        textured(root, json!({"mimeType": "image/png"}));
    });
    assert_eq!(
        error_of("no-source.glb", &bytes),
        "no-source.glb: invalid glTF JSON: images[0]: an image needs a uri or a bufferView, and it has neither"
    );
    let mut v1 = ict_bytes()[..64].to_vec();
    v1[4] = 1;
    assert_eq!(
        error_of("v1.glb", &v1),
        "v1.glb: unsupported: GLB version 1 (faceanim reads version 2)"
    );
}
