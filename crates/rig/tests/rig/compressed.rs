//! Compressed and quantized glTF, as avatars are shipped: the ICT head packed by npm
//! `gltfpack` (meshopt compression, `KHR_mesh_quantization`, both) imports with its
//! blendshapes, so does gltf-transform's Draco compression (decoded natively), and extensions
//! faceanim does not read are refused by name.

use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_testdata::{gltf_transform, gltfpack, ict, ict_bytes};

/// The packed head has the same shapes, size and motion as the original, within
/// the quantization's precision (14-bit positions: about 0.03 mm on a 0.45 m head).
fn assert_same_head(packed: &[u8], what: &str) {
    let original = ict();
    let c = import_gltf(packed, what, &NoExternalResources)
        .unwrap_or_else(|e| panic!("{what}: {e}"))
        .character;
    assert_eq!(c.triangles().len(), original.triangles().len(), "{what}");
    assert_eq!(
        c.blendshapes().len(),
        original.blendshapes().len(),
        "{what}"
    );
    let (a, b) = (c.bounds(), original.bounds());
    assert!(
        (a.min - b.min).abs().max_element() < 1e-3 && (a.max - b.max).abs().max_element() < 1e-3,
        "{what}: bounds {a:?} against {b:?}"
    );
    for shape in original.blendshapes() {
        let id = c
            .find_blendshape(shape.name())
            .unwrap_or_else(|| panic!("{what}: {} is missing", shape.name()));
        let largest = |s: &faceanim_rig::Blendshape| {
            s.deltas().iter().map(|d| d.length()).fold(0.0f32, f32::max)
        };
        let (got, want) = (largest(&c.blendshapes()[id.index()]), largest(shape));
        assert!(
            (got - want).abs() <= 0.02 * want + 1e-4,
            "{what}: {} moves {got} m at most, the original {want} m",
            shape.name()
        );
    }
}

#[test]
fn meshopt_compressed_and_quantized_head_imports() {
    let packed = gltfpack(ict_bytes(), &["-cc", "-kn"]);
    let text = String::from_utf8_lossy(&packed[..4096.min(packed.len())]).into_owned();
    assert!(text.contains("EXT_meshopt_compression") && text.contains("KHR_mesh_quantization"));
    assert_same_head(&packed, "ict-meshopt.glb");
}

#[test]
fn quantized_head_without_compression_imports() {
    let packed = gltfpack(ict_bytes(), &["-kn"]);
    assert_same_head(&packed, "ict-quantized.glb");
}

#[test]
fn meshopt_with_float_positions_imports() {
    let packed = gltfpack(ict_bytes(), &["-c", "-kn", "-vpf"]);
    assert_same_head(&packed, "ict-meshopt-float.glb");
}

fn minimal_with(required: &str) -> Vec<u8> {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["{required}"],"extensionsRequired":["{required}"],"meshes":[]}}"#
    )
    .into_bytes()
}

#[test]
fn draco_compressed_head_imports() {
    let packed = gltf_transform(ict_bytes(), "draco");
    let required = faceanim_testdata::glb::json(&packed)["extensionsRequired"].to_string();
    assert!(
        required.contains("KHR_draco_mesh_compression"),
        "{required}"
    );
    assert_same_head(&packed, "ict-draco.glb");
}

/// A Draco stream that does not decode is an error naming the primitive, not a panic.
#[test]
fn a_broken_draco_stream_is_named() {
    use base64::Engine as _;
    let junk =
        base64::engine::general_purpose::STANDARD.encode(b"DRACO\x02\x02\x01 not a mesh at all");
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},
            "extensionsUsed":["KHR_draco_mesh_compression"],
            "extensionsRequired":["KHR_draco_mesh_compression"],
            "buffers":[{{"byteLength":26,"uri":"data:application/octet-stream;base64,{junk}"}}],
            "bufferViews":[{{"buffer":0,"byteLength":26}}],
            "accessors":[{{"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},
                "extensions":{{"KHR_draco_mesh_compression":{{"bufferView":0,"attributes":{{"POSITION":0}}}}}}}}]}}],
            "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}]}}"#
    );
    let err = import_gltf(gltf.as_bytes(), "broken-draco.gltf", &NoExternalResources).unwrap_err();
    let text = err.to_string();
    assert!(text.starts_with("broken-draco.gltf: "), "{text}");
    assert!(
        text.contains("meshes[0].primitives[0].extensions.KHR_draco_mesh_compression"),
        "{text}"
    );
}

#[test]
fn an_unknown_required_extension_is_named() {
    let err = import_gltf(
        &minimal_with("VENDOR_mystery_geometry"),
        "odd.gltf",
        &NoExternalResources,
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("requires the glTF extension VENDOR_mystery_geometry"),
        "{err}"
    );
}
