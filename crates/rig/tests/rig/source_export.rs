//! Exports into the user's own file: a full-body avatar (built in code from the ICT head) keeps
//! every node, mesh, skin, material, texture and image with its name; the animation drives
//! every mesh that carries the animated targets; a baked corrective target lands on the meshes
//! it moves; a VRM stays a VRM; a meshopt-compressed avatar is written decompressed.

use faceanim_export::glb::export_into_source;
use faceanim_rig::Blendshape;
use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::glam::Vec3;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_testdata::avatar::{Expression, VrmKind, full_body_glb};
use faceanim_testdata::glb::{assert_kept, json};
use faceanim_testdata::{gltfpack, ict};

fn animation(shapes: usize, frames: usize, drive: &[usize]) -> MorphAnimation {
    MorphAnimation {
        name: "take".into(),
        times: (0..frames).map(|f| f as f32 / 30.0).collect(),
        weights: (0..frames)
            .map(|f| {
                let mut w = vec![0.0; shapes];
                for &s in drive {
                    w[s] = (f as f32 / (frames - 1) as f32).min(1.0);
                }
                w
            })
            .collect(),
        rotations: Some(
            (0..frames)
                .map(|f| glam::Quat::from_rotation_y(0.3 * f as f32 / frames as f32).to_array())
                .collect(),
        ),
    }
}

/// The character of the glTF `bytes`, read as a file called `name`.
fn read(bytes: &[u8], name: &str) -> faceanim_rig::Character {
    import_gltf(bytes, name, &NoExternalResources)
        .unwrap()
        .character
}

#[test]
fn the_users_avatar_comes_back_whole_with_the_animation() {
    let input = full_body_glb(ict(), VrmKind::None, &[]);
    let c = read(&input, "avatar.glb");
    let jaw = c.find_blendshape("jawOpen").unwrap().index();
    let out = export_into_source(&c, &[animation(c.blendshapes().len(), 300, &[jaw])]).unwrap();
    let (before, after) = (json(&input), json(&out));
    assert_kept(&before, &after, "the export");
    let animations = after["animations"].as_array().unwrap();
    assert_eq!(animations.len(), 1);
    let channels = animations[0]["channels"].as_array().unwrap();
    let weights: Vec<_> = channels
        .iter()
        .filter(|c| c["target"]["path"] == "weights")
        .collect();
    // Every head piece carries jawOpen's target (some with zero deltas): all four move together.
    assert_eq!(weights.len(), 4, "{channels:?}");
    // The head turn is shared between the bones above the shoulders.
    let turned: Vec<&str> = channels
        .iter()
        .filter(|c| c["target"]["path"] == "rotation")
        .map(|c| {
            after["nodes"][c["target"]["node"].as_u64().unwrap() as usize]["name"]
                .as_str()
                .unwrap()
        })
        .collect();
    assert!(turned.contains(&"Head"), "the head bone turns: {turned:?}");
    assert!(turned.contains(&"Neck"), "the neck takes half: {turned:?}");
    assert!(
        turned.contains(&"Chest"),
        "the upper spine follows: {turned:?}"
    );
    // Read back: the same character, blendshapes and all.
    let back = read(&out, "back.glb");
    assert_eq!(back.vertex_count(), c.vertex_count());
    assert_eq!(back.blendshapes().len(), c.blendshapes().len());
}

#[test]
fn a_baked_corrective_target_lands_on_the_meshes_it_moves() {
    let input = full_body_glb(ict(), VrmKind::None, &[]);
    let c = read(&input, "avatar.glb");
    // A corrective moving the lip-corner region a little, as an exaggeration bakes.
    let smile = c
        .blendshape(c.find_blendshape("mouthSmile_L").unwrap())
        .unwrap();
    let deltas: Vec<Vec3> = smile
        .deltas()
        .iter()
        .map(|d| *d * 0.5 + Vec3::new(0.0, 0.001, 0.0))
        .collect();
    let extra = Blendshape::from_sparse("faceanim_arc_0", smile.indices().to_vec(), deltas.clone());
    let baked = c.with_extra_blendshapes(vec![extra]).unwrap();
    let n = baked.blendshapes().len();
    let out = export_into_source(&baked, &[animation(n, 30, &[n - 1])]).unwrap();
    let after = json(&out);
    let head =
        &after["meshes"][faceanim_testdata::glb::index_of(&after, "meshes", "Head").unwrap()];
    let names = head["extras"]["targetNames"].as_array().unwrap();
    assert_eq!(names.len(), n);
    assert_eq!(names[n - 1], "faceanim_arc_0");
    assert_eq!(
        head["primitives"][0]["targets"].as_array().unwrap().len(),
        n
    );
    // Read back, the corrective moves the same vertices by the same amounts in character space.
    let back = read(&out, "back.glb");
    let id = back
        .find_blendshape("faceanim_arc_0")
        .expect("the corrective is a target");
    let mut got = vec![Vec3::ZERO; back.vertex_count()];
    back.blendshapes()[id.index()].write_dense(&mut got);
    for (&v, d) in smile.indices().iter().zip(&deltas) {
        assert!(
            (got[v as usize] - *d).length() < 1e-5,
            "vertex {v}: {} vs {d}",
            got[v as usize]
        );
    }
}

#[test]
fn a_vrm_stays_a_vrm_and_its_expressions_drive_their_bindings() {
    let expressions = [Expression {
        name: "blink",
        v0_preset: "blink",
        binds: &["eyeBlink_L", "eyeBlink_R"],
    }];
    for kind in [VrmKind::V0, VrmKind::V1] {
        let input = full_body_glb(ict(), kind, &expressions);
        let c = read(&input, "avatar.vrm");
        let blink = c.find_blendshape("blink").unwrap().index();
        let out =
            export_into_source(&c, &[animation(c.blendshapes().len(), 31, &[blink])]).unwrap();
        let after = json(&out);
        assert_kept(&json(&input), &after, "the export");
        // The last key of the head's channel has eyeBlink_L and eyeBlink_R at 1, nothing else.
        let back = read(&out, "back.vrm");
        assert!(back.find_blendshape("blink").is_some(), "{kind:?}");
        let head_node = after["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .position(|n| n["name"] == "Head" && n.get("mesh").is_some())
            .unwrap();
        let channel = after["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["node"] == head_node)
            .unwrap()
            .clone();
        let sampler =
            &after["animations"][0]["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        let output = &after["accessors"][sampler["output"].as_u64().unwrap() as usize];
        assert_eq!(
            output["count"].as_u64().unwrap() as usize,
            31 * ict().blendshapes().len(),
            "{kind:?}"
        );
    }
}

#[test]
fn a_meshopt_avatar_is_written_compressed_as_it_was_read_or_plain_when_asked() {
    use faceanim_export::glb::{Compression, export_into_source_with};
    let input = gltfpack(&full_body_glb(ict(), VrmKind::None, &[]), &["-cc", "-kn"]);
    let c = read(&input, "avatar-meshopt.glb");
    let animations = [animation(c.blendshapes().len(), 30, &[0])];
    let out = export_into_source(&c, &animations).unwrap();
    let (before, after) = (json(&input), json(&out));
    assert_kept(&before, &after, "the export");
    let used = after["extensionsUsed"].to_string();
    assert!(used.contains("EXT_meshopt_compression"), "{used}");
    assert!(
        used.contains("KHR_mesh_quantization"),
        "still quantized: {used}"
    );
    assert!(
        out.len() * 2 < input.len() * 3,
        "{} bytes for an input of {}",
        out.len(),
        input.len()
    );
    let back = read(&out, "back.glb");
    assert_eq!(back.vertex_count(), c.vertex_count());
    assert_eq!(back.positions(), c.positions());
    let plain = export_into_source_with(&c, &animations, &[], Compression::None).unwrap();
    let used = json(&plain)["extensionsUsed"].to_string();
    assert!(!used.contains("meshopt"), "{used}");
    assert_eq!(read(&plain, "plain.glb").positions(), c.positions());
}
