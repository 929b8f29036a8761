//! The studio's view turns what the export turns: on an avatar Blender built and exported (spine,
//! chest, neck, head, eye and jaw bones, two skins), a head pose, a gaze and an open jaw exported
//! into the file and posed there (each keyed rotation written as its node's own, the file read
//! again by the importer's full skinning) put every vertex where the view's small skeleton
//! (`ViewRig`: its skin and its poses, as `GET /api/view.glb` and the take's `bones` carry them)
//! puts it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

use faceanim_anim::Clip;
use faceanim_export::bones::{BoneKeys, ViewRig};
use faceanim_export::glb::{Compression, export_into_source_with};
use faceanim_rig::Character;
use faceanim_rig::animation::MorphAnimation;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use glam::{Mat4, Quat, Vec3};
use serde_json::Value;

/// The floats of a plain accessor.
fn floats(json: &Value, bin: &[u8], accessor: usize) -> Vec<f32> {
    let a = &json["accessors"][accessor];
    let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let width = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        _ => 4,
    };
    let count = a["count"].as_u64().unwrap() as usize * width;
    bin[start..start + 4 * count]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// Every vertex skinned by the view's skeleton posed with `pose` (its joints unturned at rest,
/// at their pivots: a joint's place is its parent's times its offset, turned by its rotation).
fn view_positions(character: &Character, rig: &ViewRig, pose: &[[f32; 4]]) -> Vec<Vec3> {
    let (joints, weights) = rig.skin(character);
    // A joint's parent may come after it: place each joint once its parent is placed.
    let mut world: Vec<Option<Mat4>> = vec![None; rig.joints.len()];
    while world.iter().any(Option::is_none) {
        for (k, joint) in rig.joints.iter().enumerate() {
            let parent = match joint.parent {
                None => Mat4::IDENTITY,
                Some(p) => match world[p] {
                    Some(m) => m,
                    None => continue,
                },
            };
            let above = joint.parent.map_or(Vec3::ZERO, |p| rig.joints[p].pivot);
            let local = Mat4::from_rotation_translation(
                Quat::from_array(pose[k]).normalize(),
                joint.pivot - above,
            );
            world[k] = Some(parent * local);
        }
    }
    let world: Vec<Mat4> = world.into_iter().flatten().collect();
    let skinning: Vec<Mat4> = rig
        .joints
        .iter()
        .zip(&world)
        .map(|(j, w)| *w * Mat4::from_translation(-j.pivot))
        .collect();
    character
        .positions()
        .iter()
        .zip(joints.iter().zip(&weights))
        .map(|(p, (js, ws))| {
            js.iter()
                .zip(ws)
                .map(|(&j, &w)| skinning[j as usize].transform_point3(*p) * w)
                .sum()
        })
        .collect()
}

#[test]
fn the_view_turns_every_vertex_where_the_exported_file_does() {
    let character = faceanim_testdata::producers::blender_avatar_character();
    let rig = ViewRig::of(&character, None).expect("the Blender avatar has a head bone");
    let names: Vec<&str> = rig
        .joints
        .iter()
        .map(|j| j.bone.map_or("rest", faceanim_rig::bones::Bone::name))
        .collect();
    assert_eq!(
        names,
        [
            "rest",
            "head",
            "neck",
            "upper_spine",
            "left_eye",
            "right_eye",
            "jaw"
        ],
        "the view's joints"
    );
    // Three keys: rest, then the head turned, the eyes to the character's left and the jaw open.
    let heads = [[0.0, 0.0, 0.0], [30.0, -10.0, 5.0], [30.0, -10.0, 5.0]];
    let clip = Clip {
        fps: 30.0,
        blendshapes: [
            "eyeLookOutLeft",
            "eyeLookInRight",
            "eyeLookUpLeft",
            "eyeLookUpRight",
            "jawOpen",
        ]
        .map(String::from)
        .to_vec(),
        frames: vec![
            vec![0.0; 5],
            vec![1.0, 1.0, 0.5, 0.5, 0.8],
            vec![1.0, 1.0, 0.5, 0.5, 0.8],
        ],
        head: Some(heads.to_vec()),
        head_position: None,
        presence: None,
        arkit: None,
    };
    let keys = BoneKeys::from_clip(&clip);
    let animation = MorphAnimation {
        name: "take".into(),
        times: vec![0.0, 1.0 / 30.0, 2.0 / 30.0],
        weights: vec![vec![0.0; character.blendshapes().len()]; 3],
        rotations: Some(heads.map(faceanim_anim::head_rotation).to_vec()),
    };
    let glb = export_into_source_with(
        &character,
        std::slice::from_ref(&animation),
        &[Some(&keys)],
        Compression::None,
    )
    .unwrap();
    let (mut json, bin) = faceanim_testdata::glb::parts(&glb);
    let poses = rig.poses(
        clip.fps,
        &clip
            .head
            .clone()
            .unwrap()
            .into_iter()
            .map(Some)
            .collect::<Vec<_>>(),
        &keys,
    );
    let last = json["animations"].as_array().unwrap().len() - 1;
    let channels = json["animations"][last]["channels"]
        .as_array()
        .unwrap()
        .clone();
    let samplers = json["animations"][last]["samplers"]
        .as_array()
        .unwrap()
        .clone();
    let key = 2;
    let mut turned = 0;
    for channel in &channels {
        if channel["target"]["path"] != "rotation" {
            continue;
        }
        let node = channel["target"]["node"].as_u64().unwrap() as usize;
        let sampler = &samplers[channel["sampler"].as_u64().unwrap() as usize];
        let output = floats(&json, &bin, sampler["output"].as_u64().unwrap() as usize);
        json["nodes"][node]["rotation"] = serde_json::json!(output[4 * key..4 * key + 4]);
        turned += 1;
    }
    assert_eq!(
        turned, 6,
        "spine, neck, head, two eyes and the jaw are keyed"
    );
    json.as_object_mut().unwrap().remove("animations");
    let posed = import_gltf(
        &faceanim_testdata::glb::assemble(&json, &bin),
        "posed.glb",
        &NoExternalResources,
    )
    .unwrap()
    .character;
    let file = posed.positions();
    let view = view_positions(&character, &rig, &poses[key]);
    // Every joint but the jaw (the avatar's jaw opens by its shapes) carries vertices, and each
    // one's turn is needed: without it, the view is off the file.
    let (joints, shares) = rig.skin(&character);
    for (k, joint) in rig.joints.iter().enumerate().skip(1) {
        let carried: f32 = joints
            .iter()
            .zip(&shares)
            .map(|(j, w)| {
                (0..4)
                    .filter(|&i| j[i] as usize == k)
                    .map(|i| w[i])
                    .sum::<f32>()
            })
            .sum();
        if joint.bone == Some(faceanim_rig::bones::Bone::Jaw) {
            continue;
        }
        assert!(
            carried > 10.0,
            "joint {k} ({:?}) carries {carried} vertices",
            joint.bone
        );
        let mut without = poses[key].clone();
        without[k] = [0.0, 0.0, 0.0, 1.0];
        let off = view_positions(&character, &rig, &without)
            .iter()
            .zip(file)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        assert!(
            off > 1e-3 * character.size(),
            "joint {k} ({:?}) turns nothing",
            joint.bone
        );
    }
    assert_eq!(file.len(), view.len());
    let size = character.size();
    let worst = file
        .iter()
        .zip(&view)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    let moved = character
        .positions()
        .iter()
        .zip(file)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    assert!(
        moved > 0.05 * size,
        "the pose moves the head ({moved} of {size})"
    );
    assert!(
        worst < 1e-4 * size,
        "the view puts a vertex {worst} from where the exported file does (size {size})"
    );
    // At rest the view is the character.
    let rest = view_positions(&character, &rig, &poses[0]);
    let still = rest
        .iter()
        .zip(character.positions())
        .map(|(a, b)| a.distance(*b))
        .fold(0.0f32, f32::max);
    assert!(
        still < 1e-5 * size,
        "at rest the view moves a vertex {still}"
    );
}

/// A sketch's weights turn the view's eyes and jaw as a GLB export of the same weights turns
/// the file's eye and jaw bones: each joint's rotation in the view is the turn the export's
/// local rotation makes in character space.
#[test]
fn a_sketchs_gaze_and_jaw_turn_the_views_joints_as_the_export_turns_the_bones() {
    let character = faceanim_testdata::producers::blender_avatar_character();
    let rig = ViewRig::of(&character, None).unwrap();
    let names = character.blendshape_names();
    let mut weights = vec![vec![0.0; names.len()]; 2];
    for (name, value) in [
        ("jawOpen", 0.7),
        ("eyeLookOutLeft", 0.6),
        ("eyeLookInRight", 0.6),
    ] {
        // By ARKit meaning: the avatar spells them its own way (eyeLookOut_L).
        let column = names
            .iter()
            .position(|n| faceanim_rig::names::arkit_name(n) == Some(name))
            .unwrap_or_else(|| panic!("{name} in {names:?}"));
        weights[1][column] = value;
    }
    let animation = MorphAnimation {
        name: "sketch".into(),
        times: vec![0.0, 0.5],
        weights: weights.clone(),
        rotations: None,
    };
    let clip = Clip {
        fps: 2.0,
        blendshapes: names.clone(),
        frames: weights,
        head: None,
        head_position: None,
        presence: None,
        arkit: None,
    };
    let exported = export_into_source_with(
        &character,
        std::slice::from_ref(&animation),
        &[Some(&BoneKeys::from_clip(&clip))],
        Compression::None,
    )
    .unwrap();
    let (json, bin) = faceanim_testdata::glb::parts(&exported);
    let last = json["animations"].as_array().unwrap().len() - 1;
    let animation_json = &json["animations"][last];
    let source = character.source().unwrap();
    let view = faceanim_export::view_glb(&character, Some(&animation)).unwrap();
    let (view_json, view_bin) = faceanim_testdata::glb::parts(&view);
    let view_animation = &view_json["animations"][0];
    let turned = |doc: &Value, bin: &[u8], animation: &Value, node: usize| -> Option<Quat> {
        let channel = animation["channels"].as_array().unwrap().iter().find(|c| {
            c["target"]["path"] == "rotation" && c["target"]["node"].as_u64() == Some(node as u64)
        })?;
        let sampler = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        let output = floats(doc, bin, sampler["output"].as_u64().unwrap() as usize);
        Some(Quat::from_slice(&output[4..8]))
    };
    let mut compared = 0;
    for (k, joint) in rig.joints.iter().enumerate() {
        let Some(node) = joint.node else { continue };
        let in_view = turned(&view_json, &view_bin, view_animation, k + 1);
        let in_file = turned(&json, &bin, animation_json, node);
        match (in_view, in_file) {
            (Some(v), Some(f)) => {
                let turn = source.joint(node).unwrap().turn(f);
                assert!(
                    v.angle_between(turn) < 1e-4,
                    "{:?}: the view turns {v:?}, the file {turn:?}",
                    joint.bone
                );
                assert!(
                    v.angle_between(Quat::IDENTITY) > 1f32.to_radians(),
                    "{:?}",
                    joint.bone
                );
                compared += 1;
            }
            (None, None) => {}
            other => panic!(
                "{:?}: only one of view and file turns it: {other:?}",
                joint.bone
            ),
        }
    }
    assert_eq!(compared, 3, "the two eyes and the jaw");
}

/// A VRM Animation of keys that do not fit one another (none at all, weights of another count,
/// a turn too few), as a library caller might hand one over, is refused as the GLB refuses it,
/// never a panic.
#[test]
fn a_vrm_animation_of_keys_that_do_not_fit_is_refused() {
    use faceanim_testdata::avatar::{ICT_EXPRESSIONS, VrmKind, full_body_glb};
    let bytes = full_body_glb(faceanim_testdata::ict(), VrmKind::V1, ICT_EXPRESSIONS);
    let character = import_gltf(&bytes, "avatar.vrm", &NoExternalResources)
        .unwrap()
        .character;
    let shapes = character.blendshapes().len();
    let broken = [
        (vec![], vec![], None),
        (vec![0.0, 0.1], vec![vec![0.0; shapes]], None),
        (
            vec![0.0, 0.1],
            vec![vec![0.0; shapes]; 2],
            Some(vec![[0.0, 0.0, 0.0, 1.0]]),
        ),
    ];
    for (times, weights, rotations) in broken {
        let animation = faceanim_export::Animation {
            character: Some(&character),
            animation: MorphAnimation {
                name: "broken".into(),
                times,
                weights,
                rotations,
            },
            clip: Clip {
                fps: 30.0,
                blendshapes: character.blendshape_names(),
                frames: Vec::new(),
                head: None,
                head_position: None,
                presence: None,
                arkit: None,
            },
            arkit: None,
            session: None,
            bones: None,
            strokes: None,
            bones_only: false,
        };
        let result = faceanim_export::export(faceanim_export::Format::Vrma, &animation);
        assert!(
            matches!(result, Err(faceanim_export::ExportError::Glb(_))),
            "{result:?}"
        );
    }
}
