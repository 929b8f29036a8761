//! The ICT-FaceKit heads from `../shared`: import, symmetry, ARKit coverage, exact round trips.

use faceanim_export::glb::export_glb;
use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_rig::symmetry::PairSource;
use faceanim_rig::{Blendshape, Character};
use faceanim_testdata::{ict, ict_bytes, shared};
use glam::Vec3;

#[test]
fn both_heads_import_with_their_published_counts() {
    for file in ["characters/ict-face.glb", "characters/ict-face-id7.glb"] {
        let bytes = std::fs::read(shared(file)).unwrap();
        let c = import_gltf(&bytes, file, &NoExternalResources)
            .unwrap()
            .character;
        assert_eq!(c.vertex_count(), 24_591, "{file}");
        assert_eq!(c.triangles().len(), 48_836, "{file}");
        assert_eq!(c.blendshapes().len(), 53, "{file}");
        assert!(c.colors().is_some(), "{file} keeps its vertex colours");
        let size = c.size();
        assert!(
            (0.3..0.6).contains(&size),
            "{file}: a human head is about 0.45 m across its box, got {size}"
        );
    }
}

#[test]
fn twenty_two_pairs_by_name_and_49_arkit_names() {
    let c = ict();
    let names = |p: &faceanim_rig::symmetry::BlendshapePair| {
        (
            c.blendshapes()[p.left.index()].name().to_owned(),
            c.blendshapes()[p.right.index()].name().to_owned(),
        )
    };
    let pairs: Vec<_> = c.symmetry().pairs().iter().map(names).collect();
    assert_eq!(pairs.len(), 22, "{pairs:?}");
    assert!(pairs.contains(&("jawLeft".into(), "jawRight".into())));
    assert!(pairs.contains(&("mouthLeft".into(), "mouthRight".into())));
    assert!(pairs.contains(&("eyeBlink_L".into(), "eyeBlink_R".into())));
    assert_eq!(
        pairs
            .iter()
            .filter(|(l, r)| l.ends_with("_L") && r.ends_with("_R"))
            .count(),
        20
    );
    // ICT splits browInnerUp and cheekPuff per side and has no tongueOut: 49 of the 52.
    assert_eq!(c.arkit_coverage().len(), 49);
    let plane = c.symmetry().plane().expect("the ICT head is symmetric");
    assert!(plane.offset.abs() < 1e-3, "{plane:?}");
    assert!(c.symmetry().mirrored_fraction() > 0.95);
}

#[test]
fn pairs_are_found_from_geometry_when_names_say_nothing() {
    let c = ict();
    // Rename every blendshape shape_1..shape_53, in a shuffled order.
    let mut parts = c.to_parts();
    let order: Vec<usize> = (0..53).map(|i| (i * 17 + 5) % 53).collect();
    parts.blendshapes = order
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            let b = &c.blendshapes()[i];
            Blendshape::from_sparse(
                format!("shape_{}", k + 1),
                b.indices().to_vec(),
                b.deltas().to_vec(),
            )
        })
        .collect();
    parts.normal_deltas = None;
    let anonymous = Character::new(parts).unwrap();
    let pairs = anonymous.symmetry().pairs();
    assert!(pairs.iter().all(|p| p.source == PairSource::Geometry));
    // Map back to the original names: every geometric pair must be a true pair.
    let original =
        |id: faceanim_rig::BlendshapeId| c.blendshapes()[order[id.index()]].name().to_owned();
    let found: Vec<(String, String)> = pairs
        .iter()
        .map(|p| (original(p.left), original(p.right)))
        .collect();
    for (l, r) in &found {
        let true_pair = c.symmetry().pairs().iter().any(|p| {
            c.blendshapes()[p.left.index()].name() == l
                && c.blendshapes()[p.right.index()].name() == r
        });
        assert!(
            true_pair,
            "{l} / {r} is not a real pair (or left and right are swapped)"
        );
    }
    assert_eq!(found.len(), 22, "{found:?}");
}

/// Reads the dense POSITION data of every morph target straight from the GLB, as a reference
/// independent of the importer.
fn raw_ict_targets() -> Vec<(String, Vec<Vec3>)> {
    let bytes = ict_bytes();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let root: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = &bytes[20 + json_len + 8..];
    let mesh = &root["meshes"][0];
    let names = mesh["extras"]["targetNames"].as_array().unwrap();
    let targets = mesh["primitives"][0]["targets"].as_array().unwrap();
    names
        .iter()
        .zip(targets)
        .map(|(name, target)| {
            let accessor = &root["accessors"][target["POSITION"].as_u64().unwrap() as usize];
            let view = &root["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
            let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
                + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
            let count = accessor["count"].as_u64().unwrap() as usize;
            let floats: Vec<f32> = bin[start..start + count * 12]
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                .collect();
            (
                name.as_str().unwrap().to_owned(),
                floats
                    .chunks_exact(3)
                    .map(|c| Vec3::new(c[0], c[1], c[2]))
                    .collect(),
            )
        })
        .collect()
}

#[test]
fn import_export_import_keeps_positions_and_deltas_within_1e_6() {
    let first = ict();
    let glb = export_glb(first, &[]).unwrap();
    let second = import_gltf(&glb, "roundtrip.glb", &NoExternalResources)
        .unwrap()
        .character;
    assert_eq!(second.vertex_count(), first.vertex_count());
    assert_eq!(second.triangles(), first.triangles());
    for (a, b) in first.positions().iter().zip(second.positions()) {
        assert!((*a - *b).abs().max_element() <= 1e-6);
    }
    let raw = raw_ict_targets();
    let mut dense = vec![Vec3::ZERO; second.vertex_count()];
    for ((name, original), shape) in raw.iter().zip(second.blendshapes()) {
        assert_eq!(name, shape.name());
        shape.write_dense(&mut dense);
        let worst = original
            .iter()
            .zip(&dense)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f32::max);
        assert!(
            worst <= 1e-6,
            "{name}: the round trip moved a delta by {worst}"
        );
    }
    // Pairs and colours survive too.
    assert_eq!(second.symmetry().pairs().len(), 22);
    assert_eq!(second.colors(), first.colors());
}

#[test]
fn a_pose_is_neutral_plus_weighted_deltas_with_unit_normals() {
    let c = ict();
    let neutral = c.pose(&[]);
    assert_eq!(neutral.positions, c.positions());
    let jaw = c.find_blendshape("jawOpen").unwrap();
    let mut weights = vec![0.0; c.blendshapes().len()];
    weights[jaw.index()] = 0.5;
    let pose = c.pose(&weights);
    let shape = c.blendshape(jaw).unwrap();
    for (v, d) in shape.moves() {
        let expected = c.positions()[v as usize] + 0.5 * d;
        assert!((pose.positions[v as usize] - expected).length() < 1e-7);
    }
    assert!(pose.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
    // The jaw opening turns the chin's normals: some normals change.
    let changed = pose
        .normals
        .iter()
        .zip(c.normals())
        .filter(|(a, b)| (**a - **b).length() > 1e-3)
        .count();
    assert!(changed > 100, "only {changed} normals changed");
}

#[test]
fn an_exported_animation_survives_import_of_the_character() {
    let c = ict();
    let n = c.blendshapes().len();
    let animation = MorphAnimation {
        name: "test".into(),
        times: vec![0.0, 0.5, 1.0],
        weights: vec![vec![0.0; n], vec![1.0; n], vec![0.0; n]],
        rotations: None,
    };
    let glb = export_glb(c, &[animation]).unwrap();
    let back = import_gltf(&glb, "animated.glb", &NoExternalResources).unwrap();
    assert_eq!(back.character.blendshapes().len(), n);
    // An animation whose rows do not match the blendshapes is refused, not written.
    let bad = MorphAnimation {
        name: "bad".into(),
        times: vec![0.0],
        weights: vec![vec![0.0; n - 1]],
        rotations: None,
    };
    let err = export_glb(c, &[bad]).unwrap_err().to_string();
    assert_eq!(
        err,
        "animation 'bad': key 0 has 52 weights but the character has 53 blendshapes"
    );
}
