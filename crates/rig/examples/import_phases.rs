//! Times the phases of importing a character and of evaluating a pose, and counts the
//! evaluation runs: the measurements behind the layout choices in `normals.rs` and `pose.rs`.
//! Usage: cargo run --release -p faceanim-rig --example import_phases -- FILE.glb
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::time::Instant;

use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_rig::{Character, EdgeGraph};

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: import_phases FILE.glb");
    let t = Instant::now();
    let bytes = std::fs::read(&path).unwrap();
    let read = t.elapsed();
    let t = Instant::now();
    let imported = import_gltf(&bytes, &path, &NoExternalResources).unwrap();
    let total = t.elapsed();
    let c = imported.character;
    let mut parts = c.to_parts();
    parts.normal_deltas = None;
    let t = Instant::now();
    let rebuilt = Character::new(parts.clone()).unwrap();
    let new_all = t.elapsed();
    parts.normal_deltas = Some(c.normal_deltas().to_vec());
    let t = Instant::now();
    let _ = Character::new(parts).unwrap();
    let new_given_normals = t.elapsed();
    let t = Instant::now();
    let _ = EdgeGraph::build(c.positions(), c.triangles());
    let graph = t.elapsed();
    let moved: usize = c.blendshapes().iter().map(|b| b.moved()).sum();
    let normal_entries: usize = rebuilt
        .normal_deltas()
        .iter()
        .map(|n| n.indices.len())
        .sum();
    let small = rebuilt
        .normal_deltas()
        .iter()
        .flat_map(|n| &n.deltas)
        .filter(|d| d.length() < 1e-4)
        .count();
    println!(
        "read {read:?}  import {total:?}  Character::new {new_all:?} (with given normal deltas {new_given_normals:?})  graph {graph:?}"
    );
    let weights = vec![0.5f32; 53];
    let mut pose = faceanim_rig::Pose::default();
    let t = Instant::now();
    for _ in 0..200 {
        rebuilt.pose_into(&weights, &mut pose);
    }
    println!("pose_into {:?}", t.elapsed() / 200);
    let runs_with_gap = |gap: u32, indices: &[u32]| {
        1 + indices.windows(2).filter(|w| w[1] - w[0] > gap + 1).count()
    };
    for gap in [0, 64] {
        let runs: usize = rebuilt
            .blendshapes()
            .iter()
            .map(|b| runs_with_gap(gap, b.indices()))
            .sum();
        let nruns: usize = rebuilt
            .normal_deltas()
            .iter()
            .map(|b| runs_with_gap(gap, &b.indices))
            .sum();
        println!("gaps up to {gap} bridged: {runs} position runs, {nruns} normal runs");
    }
    println!("moved entries {moved}  normal-delta entries {normal_entries} ({small} below 1e-4)");
}
