//! Compressed and quantized glTF, as avatars are shipped: the ICT head packed by npm
//! `gltfpack` (meshopt compression, `KHR_mesh_quantization`, both) imports with its
//! blendshapes, and extensions faceanim does not read are refused by name.

use faceanim_rig::import::{ImportErrorKind, NoExternalResources, import_gltf};
use faceanim_testdata::{gltfpack, ict, ict_bytes};

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
fn draco_is_refused_with_the_conversion_command() {
    let err = import_gltf(
        &minimal_with("KHR_draco_mesh_compression"),
        "draco.gltf",
        &NoExternalResources,
    )
    .unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(err.kind, ImportErrorKind::Unsupported(_)),
        "{text}"
    );
    assert!(text.starts_with("draco.gltf: "), "{text}");
    assert!(text.contains("KHR_draco_mesh_compression"), "{text}");
    assert!(text.contains("gltf-transform"), "{text}");
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
