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
