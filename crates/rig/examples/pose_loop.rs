//! Evaluates the ICT head's pose N times (for profiling pose evaluation).
//! Usage: cargo run --release -p faceanim-rig --example pose_loop -- FILE.glb N
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use faceanim_rig::import::{NoExternalResources, import_gltf};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("usage: pose_loop FILE.glb N");
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(1000);
    let c = import_gltf(&std::fs::read(&path).unwrap(), &path, &NoExternalResources)
        .unwrap()
        .character;
    let weights = vec![0.5f32; c.blendshapes().len()];
    let mut pose = faceanim_rig::Pose::default();
    let t = std::time::Instant::now();
    for _ in 0..n {
        c.pose_into(&weights, &mut pose);
        std::hint::black_box(&pose);
    }
    println!("{:?} per pose", t.elapsed() / n as u32);
}
