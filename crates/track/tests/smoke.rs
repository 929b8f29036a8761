//! The three models load and run.
#![allow(clippy::unwrap_used, reason = "tests")]

#[test]
fn models_load_and_run() {
    let models = faceanim_track::FaceModels::load().unwrap();
    let (boxes, scores) = models.detect(&vec![0.0; 128 * 128 * 3]).unwrap();
    assert_eq!((boxes.len(), scores.len()), (896 * 16, 896));
    let out = models.landmarks(&vec![0.5; 256 * 256 * 3]).unwrap();
    assert_eq!(out.points.len(), 478);
    let scores = models.blendshapes(&vec![[128.0, 128.0]; 146]).unwrap();
    assert_eq!(scores.len(), 52);
}

/// On an x86-64 host with AVX2 and FMA, tract runs the models' depthwise convolutions with
/// faceanim's vectorised channels-last kernel (`vendor/tract-tflite/src/faceanim_kernels.rs`),
/// not its scalar fallback: the landmark network is a fifth faster with it. Its numbers are
/// checked by `reference.rs` and `mediapipe_stills.rs`, which run through it.
#[cfg(target_arch = "x86_64")]
#[test]
fn tract_runs_the_vectorised_depthwise_kernel() {
    use tract_linalg::isa::{Isa, native};
    use tract_linalg::routines::{Func, best_for};
    let isa = native();
    if !(isa.has(Isa::X86_64Avx2) && isa.has(Isa::X86_64Fma)) {
        return;
    }
    let routine = best_for(
        Func::DepthwiseC,
        tract_tflite::prelude::DatumType::F32,
        &isa,
    )
    .unwrap();
    assert_eq!(routine.name(), "faceanim_x86_64_avx2_fma_depthwise_c_f32");
}
