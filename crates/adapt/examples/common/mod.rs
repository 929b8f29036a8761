//! What the adapter's examples share: the ICT head framed for its training camera, and
//! expressions drawn as training draws them.
use faceanim_adapt::FaceCamera;
use faceanim_adapt::sampling::{WeightSampler, exclusive_pairs};
use faceanim_track::FaceModels;

/// The face models, the ICT head, its training camera, and `count` expressions drawn with
/// `seed`.
pub fn ict_training(
    count: usize,
    seed: u64,
) -> (
    FaceModels,
    &'static faceanim_rig::Character,
    FaceCamera,
    Vec<Vec<f32>>,
) {
    let models = FaceModels::load().unwrap();
    let ict = faceanim_testdata::ict();
    let camera = FaceCamera::frame(ict, &models).unwrap();
    let pairs = exclusive_pairs(ict, &[]).unwrap();
    let draws = WeightSampler::new(ict.blendshapes().len(), &pairs).draw(count, seed);
    (models, ict, camera, draws)
}
