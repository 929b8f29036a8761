//! Writes a contact sheet of randomised training pictures of the ICT head (what the adapter
//! learns from): `cargo run --release -p faceanim-adapt --example show_conditions -- OUT.png`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
mod common;

use faceanim_adapt::augment::{Condition, Jitter};
use rand::SeedableRng as _;

fn main() {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "conditions.png".into());
    let (_models, ict, camera, draws) = common::ict_training(16, 9);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
    let mut sheet = faceanim_render::Image::filled(4 * 256, 4 * 256, [0, 0, 0]);
    let mut pose = faceanim_rig::Pose::default();
    for (k, w) in draws.iter().enumerate() {
        let condition = Condition::draw(&mut rng);
        let jitter = Jitter::draw(&mut rng, true);
        ict.pose_into(w, &mut pose);
        let picture = camera.picture(ict, &pose, &condition, jitter, &mut rng);
        sheet.blit(&picture, (k as u32 % 4) * 256, (k as u32 / 4) * 256);
    }
    std::fs::write(out, sheet.to_png().unwrap()).unwrap();
}
