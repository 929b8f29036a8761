//! Where one training sample's time goes (pose, render, degrade, landmarks + scores), on the
//! ICT head: `cargo run --release -p faceanim-adapt --example stage_times`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use std::time::Instant;

mod common;

use faceanim_adapt::augment::{Condition, Jitter};
use faceanim_track::{Frame, Region};
use rand::SeedableRng as _;

fn main() {
    let (models, ict, camera, draws) = common::ict_training(64, 3);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut pose = faceanim_rig::Pose::default();
    let (mut t_pose, mut t_render, mut t_models) = (0.0, 0.0, 0.0);
    let n = 64;
    for w in &draws {
        let condition = Condition::draw(&mut rng);
        let t = Instant::now();
        ict.pose_into(w, &mut pose);
        t_pose += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let image = camera.picture(ict, &pose, &condition, Jitter::NONE, &mut rng);
        t_render += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let frame = Frame {
            width: 256,
            height: 256,
            rgb: &image.rgb,
        };
        let whole = Region {
            cx: 128.0,
            cy: 128.0,
            size: 256.0,
            rotation: 0.0,
        };
        let _ = models.face_in_region(&frame, whole, 1.0).unwrap();
        t_models += t.elapsed().as_secs_f64();
    }
    let ms = |s: f64| s * 1000.0 / n as f64;
    println!(
        "per sample: pose {:.2} ms, render+degrade {:.2} ms, landmarks+scores+pose fit {:.2} ms",
        ms(t_pose),
        ms(t_render),
        ms(t_models)
    );
}
