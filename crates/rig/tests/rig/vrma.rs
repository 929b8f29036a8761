//! VRM Animations written as other tools write them read back as a take: a humanoid whose bones
//! rest turned (as a motion-capture rig's do, where faceanim's own files rest unturned), its
//! head's turn read as VRM players turn the normalized bone; expressions by name; the gaze; and
//! broken files refused by name, never a panic.

use crate::support::GltfBuilder;
use faceanim_rig::import::import_vrma;
use glam::{EulerRot, Quat};
use proptest::prelude::*;
use serde_json::json;

/// The turn the head makes in the normalized rig at each of the three keys.
fn turns() -> [Quat; 3] {
    [
        Quat::IDENTITY,
        Quat::from_euler(EulerRot::YXZ, 0.4, -0.2, 0.1),
        Quat::from_euler(EulerRot::YXZ, -0.3, 0.25, 0.0),
    ]
}

/// The neck's and the head's rotation at rest.
fn rests() -> (Quat, Quat) {
    (
        Quat::from_rotation_z(0.3),
        Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
    )
}

fn floats(b: &mut GltfBuilder, values: &[f32], kind: &str) -> usize {
    let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
    let count = values.len()
        / match kind {
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
    b.raw(&bytes, 5126, count, kind)
}

/// A VRM Animation at 30 keys a second: hips, neck and head (the neck and head turned at rest),
/// `aa` and a custom `smirk`, a lookAt; the head's track stores each normalized turn as this
/// rig's local rotation.
fn vrma() -> Vec<u8> {
    let mut b = GltfBuilder::default();
    let times = floats(&mut b, &[0.0, 1.0 / 30.0, 2.0 / 30.0], "SCALAR");
    b.accessors[times]["min"] = json!([0.0]);
    b.accessors[times]["max"] = json!([2.0 / 30.0]);
    let aa = floats(
        &mut b,
        &[0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 1.5, 0.0, 0.0],
        "VEC3",
    );
    let smirk = floats(
        &mut b,
        &[0.2, 0.0, 0.0, 0.4, 0.0, 0.0, 0.6, 0.0, 0.0],
        "VEC3",
    );
    let (neck_rest, head_rest) = rests();
    // A normalized turn N of the head is its local rotation P⁻¹·N·W (P its parent's rest in
    // the world, W its own).
    let world = neck_rest * head_rest;
    let head: Vec<f32> = turns()
        .iter()
        .flat_map(|n| (neck_rest.inverse() * *n * world).normalize().to_array())
        .collect();
    let head = floats(&mut b, &head, "VEC4");
    let look: Vec<f32> = [0.0f32, 10.0, -20.0]
        .iter()
        .flat_map(|yaw| {
            Quat::from_euler(EulerRot::YXZ, yaw.to_radians(), 5f32.to_radians(), 0.0).to_array()
        })
        .collect();
    let look = floats(&mut b, &look, "VEC4");
    let root = json!({
        "extensionsUsed": ["VRMC_vrm_animation"],
        "extensions": { "VRMC_vrm_animation": {
            "specVersion": "1.0",
            "humanoid": { "humanBones": { "hips": { "node": 0 }, "neck": { "node": 1 }, "head": { "node": 2 } } },
            "expressions": { "preset": { "aa": { "node": 3 } }, "custom": { "smirk": { "node": 4 } } },
            "lookAt": { "node": 5 }
        } },
        "scene": 0,
        "scenes": [{ "nodes": [0, 3, 4, 5] }],
        "nodes": [
            { "name": "hips", "translation": [0.0, 1.0, 0.0], "children": [1] },
            { "name": "neck", "translation": [0.0, 0.5, 0.0], "rotation": neck_rest.to_array(), "children": [2] },
            { "name": "head", "translation": [0.0, 0.1, 0.0], "rotation": head_rest.to_array() },
            { "name": "aa" }, { "name": "smirk" }, { "name": "lookAt" }
        ],
        "animations": [{ "name": "hello", "samplers": [
            { "input": times, "output": aa },
            { "input": times, "output": smirk },
            { "input": times, "output": head },
            { "input": times, "output": look }
        ], "channels": [
            { "sampler": 0, "target": { "node": 3, "path": "translation" } },
            { "sampler": 1, "target": { "node": 4, "path": "translation" } },
            { "sampler": 2, "target": { "node": 2, "path": "rotation" } },
            { "sampler": 3, "target": { "node": 5, "path": "rotation" } }
        ] }]
    });
    b.glb(root)
}

#[test]
fn a_vrm_animation_of_a_rig_turned_at_rest_reads_back_as_played() {
    let take = import_vrma(&vrma(), "hello.vrma").unwrap();
    assert_eq!(take.name, "hello");
    assert_eq!(take.fps, 30.0);
    assert_eq!(take.expressions, ["aa", "smirk"]);
    // Weights are clamped to 0..1, as the specification asks.
    assert_eq!(take.frames.len(), 3);
    for (row, want) in take.frames.iter().zip([[0.0, 0.2], [0.5, 0.4], [1.0, 0.6]]) {
        for (got, want) in row.iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{row:?}");
        }
    }
    let head = take.head.unwrap();
    for (got, want) in head.iter().zip(turns()) {
        let got = Quat::from_array(*got);
        assert!(
            got.angle_between(want).to_degrees() < 0.01,
            "{got} for {want}"
        );
    }
    let gaze = take.gaze.unwrap();
    for (got, yaw) in gaze.iter().zip([0.0, 10.0, -20.0]) {
        assert!(
            (got[0] - yaw).abs() < 1e-3 && (got[1] - 5.0).abs() < 1e-3,
            "{got:?}"
        );
    }
}

#[test]
fn what_is_no_vrm_animation_is_refused_by_name() {
    let e = import_vrma(b"not a file at all", "x.vrma").unwrap_err();
    assert!(e.to_string().starts_with("x.vrma"), "{e}");
    let mut plain = json!({});
    plain["scenes"] = json!([{ "nodes": [] }]);
    let glb = GltfBuilder::default().glb(plain);
    let e = import_vrma(&glb, "plain.vrma").unwrap_err();
    assert!(
        e.to_string().contains("plain.vrma") && e.to_string().contains("not a VRM Animation"),
        "{e}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Whatever a VRM Animation's bytes become, reading it answers, never panics.
    #[test]
    fn flipped_bytes_never_panic(flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        let mut bytes = vrma();
        for (at, value) in flips {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        let _ = import_vrma(&bytes, "fuzz.vrma");
    }
}
