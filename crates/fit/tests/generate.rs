//! Shapes made on heads stripped of theirs, compared shape by shape with the originals
//! (relative vertex error: the sum of the differences' lengths over the sum of the
//! original's displacements), as issue 30 measures them:
//! - **held out**: ICT-FaceKit identity 48 (a realistic head no template is made from) from
//!   the default templates;
//! - across topologies: the same head from the built-in head alone, and the built-in head
//!   from the realistic template.
//!
//! Each blink must close its eye as the artist's does, read from a render the way capture reads
//! a person: MediaPipe's eyeBlink score of the front render with the blink on.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

use faceanim_fit::{Generated, Options, Template, channel_deltas, generate, relative_error};
use faceanim_rig::{Character, CharacterParts};
use glam::Vec3;

/// `character` with its blendshapes removed: a head as a scanner or sculptor leaves it.
fn stripped(character: &Character) -> Character {
    Character::new(CharacterParts {
        blendshapes: Vec::new(),
        normal_deltas: None,
        ..character.to_parts()
    })
    .unwrap()
}

/// Per shape the original has, the relative error of the generated one; printed, and their
/// mean returned.
fn compare(what: &str, original: &Character, generated: &Generated) -> f64 {
    let reference = channel_deltas(original);
    let mut errors = Vec::new();
    let mut line = String::new();
    for shape in &generated.shapes {
        let Some((_, theirs)) = reference.iter().find(|(n, _)| n == shape.name()) else {
            continue;
        };
        let mut ours = vec![Vec3::ZERO; original.vertex_count()];
        shape.write_dense(&mut ours);
        let error = relative_error(&ours, theirs);
        line.push_str(&format!("{} {error:.2}, ", shape.name()));
        errors.push(error);
    }
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    eprintln!(
        "{what}: mean relative error {mean:.3} over {} shapes; templates {:?}\n  {line}",
        errors.len(),
        generated
            .templates
            .iter()
            .map(|t| (&t.name, t.shapes.len(), t.residual, t.corresponding))
            .collect::<Vec<_>>()
    );
    mean
}

/// MediaPipe's `channel` score on `character`'s front render with `shape` at full weight (or
/// neutral).
fn blink(
    character: &Character,
    shape: Option<&str>,
    channel: &str,
    models: &faceanim_track::FaceModels,
) -> f32 {
    let mut weights = vec![0.0; character.blendshapes().len()];
    if let Some(shape) = shape {
        weights[character.find_blendshape(shape).unwrap().index()] = 1.0;
    }
    let camera = faceanim_render::Camera::front(&character.head_bounds(), 0.75);
    let appearance = faceanim_render::Appearance::of(character);
    let image = faceanim_render::render(
        character,
        &character.pose(&weights),
        &camera,
        &appearance,
        512,
    );
    let frame = faceanim_track::Frame {
        width: 512,
        height: 512,
        rgb: &image.rgb,
    };
    let face = models
        .find_face(&frame)
        .unwrap()
        .expect("a face on the render");
    face.scores.iter().find(|(n, _)| *n == channel).unwrap().1
}

#[test]
fn shapes_on_a_held_out_head_follow_its_artists() {
    let models = faceanim_track::FaceModels::load().unwrap();
    let original = faceanim_testdata::ict_identity("ict-face-id48.glb");
    let head = stripped(original);
    let templates = Template::Realistic.characters().unwrap();
    let templates: Vec<&Character> = templates.iter().collect();
    let generated = generate(&head, &templates, &models, &Options::default()).unwrap();
    assert_eq!(generated.shapes.len(), 52);
    let mean = compare("held out, default templates", original, &generated);
    assert!(mean <= 0.35, "mean relative error {mean}");
    // Each blink closes its eye (on the software render, MediaPipe reads a closed eye at
    // about 0.5): at least 70 % of the way the artist's own does, from rest.
    let with = head
        .with_extra_blendshapes(generated.shapes.clone())
        .unwrap();
    for (side, name) in [("Left", "eyeBlink_L"), ("Right", "eyeBlink_R")] {
        let channel = format!("eyeBlink{side}");
        let ours = blink(&with, Some(&channel), &channel, &models);
        let artists = blink(original, Some(name), &channel, &models);
        let neutral = blink(original, None, &channel, &models);
        eprintln!(
            "{channel}: MediaPipe reads {ours:.2} on ours, {artists:.2} on the artist's, {neutral:.2} at rest"
        );
        assert!(
            ours - neutral >= 0.7 * (artists - neutral),
            "{channel}: {ours} against {artists} (rest {neutral})"
        );
    }
    // Across topologies, reported: the built-in head alone onto this head, and the realistic
    // template onto the built-in head.
    let stylised = Template::Stylised.characters().unwrap();
    let from_builtin = generate(&head, &[&stylised[0]], &models, &Options::default()).unwrap();
    compare(
        "held out, built-in head as the template",
        original,
        &from_builtin,
    );
    let builtin = &stylised[0];
    let bare = stripped(builtin);
    let realistic = faceanim_fit::templates::realistic().unwrap();
    let onto_builtin = generate(&bare, &[&realistic], &models, &Options::default()).unwrap();
    compare(
        "the built-in head from the realistic template",
        builtin,
        &onto_builtin,
    );
}

/// A head the face model cannot find: the held-out ICT head turned a quarter round (it looks
/// along +X, as a file exported with the wrong forward axis does), so its front render shows
/// a profile. Generating refuses, saying to mark the face; with ten marks where a user would
/// click them (MediaPipe's points on the head before it was turned, each moved by a few
/// percent of the eyes' span, as a hand is not exact), the shapes come out as they do on the
/// head the face model reads.
#[test]
fn a_face_the_model_cannot_find_is_placed_by_ten_marks() {
    use faceanim_fit::{FaceLandmarks, FacePoint, FacePoints};
    let models = faceanim_track::FaceModels::load().unwrap();
    let original = faceanim_testdata::ict_identity("ict-face-id48.glb");
    let head = stripped(original);
    let turn = glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let turned = Character::new(CharacterParts {
        positions: head.positions().iter().map(|p| turn * *p).collect(),
        normals: None,
        ..head.to_parts()
    })
    .unwrap();
    let templates = Template::Realistic.characters().unwrap();
    let templates: Vec<&Character> = templates.iter().collect();
    let refused = generate(&turned, &templates, &models, &Options::default())
        .expect_err("no face on a profile");
    assert!(refused.to_string().contains("mark ten points"), "{refused}");

    let found = FaceLandmarks::find(&head, &models).unwrap();
    let at = |p: FacePoint| {
        found.points[p.landmark()]
            .unwrap()
            .on(head.triangles(), head.positions())
    };
    let span = at(FacePoint::RightEyeOuter).distance(at(FacePoint::LeftEyeOuter));
    let points = FacePoints::new(
        FacePoint::ALL
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                // A hand's error: up to 4 % of the eyes' span, a different way for each mark.
                let angle = k as f32 * 2.4;
                let slip = 0.04 * span * Vec3::new(angle.cos(), angle.sin(), 0.0);
                (p, (turn * (at(p) + slip)).to_array())
            })
            .collect(),
    )
    .unwrap();
    let options = Options {
        points: Some(points),
        ..Options::default()
    };
    let marked = generate(&turned, &templates, &models, &options).unwrap();
    assert_eq!(marked.shapes.len(), 52);
    // Back in the head's own frame, shape by shape against the artist's.
    let back = Generated {
        shapes: marked
            .shapes
            .iter()
            .map(|s| {
                faceanim_rig::Blendshape::from_sparse(
                    s.name(),
                    s.indices().to_vec(),
                    s.deltas().iter().map(|d| turn.inverse() * *d).collect(),
                )
            })
            .collect(),
        ..marked
    };
    let by_marks = compare("held out, turned, placed by ten marks", original, &back);
    let by_model = compare(
        "held out, found by the face model",
        original,
        &generate(&head, &templates, &models, &Options::default()).unwrap(),
    );
    assert!(
        by_marks <= 0.35 && by_marks <= by_model + 0.05,
        "by marks {by_marks}, by the face model {by_model}"
    );
}

/// A head split along every edge, as a flat-shaded export is (glTF Transform's `unweld` gives
/// each triangle three vertices of its own; exporters split a mesh the same way along its UV
/// seams and hard edges): it is still one face. Each landmark lands where it lands on the
/// head as its artist saved it (before, the skin was taken to be only the triangles under the
/// nose and chin, 12 of the 478 landmarks landed on it and the map refused the head).
#[test]
fn a_head_split_along_every_edge_is_still_one_face() {
    use faceanim_rig::import::{NoExternalResources, import_gltf};
    let models = faceanim_track::FaceModels::load().unwrap();
    let file = "ict-face-id3.glb";
    let saved = std::fs::read(faceanim_testdata::shared(&format!("characters/{file}"))).unwrap();
    let split = faceanim_testdata::gltf_transform(&saved, "unweld");
    let [saved, split] = [&saved, &split].map(|bytes| {
        import_gltf(bytes, file, &NoExternalResources)
            .unwrap()
            .character
    });
    assert_eq!(split.vertex_count(), 3 * split.triangles().len());
    let [on_saved, on_split] = [&saved, &split].map(|head| {
        let marks = faceanim_fit::FaceLandmarks::find(head, &models).unwrap();
        marks
            .points
            .iter()
            .map(|p| p.map(|p| p.on(head.triangles(), head.positions())))
            .collect::<Vec<_>>()
    });
    let landed = on_saved.iter().flatten().count();
    assert!(landed >= 450, "{landed} landmarks landed on the saved head");
    let size = saved.size();
    let apart = on_saved
        .iter()
        .zip(&on_split)
        .filter(|(a, b)| match (a, b) {
            (Some(a), Some(b)) => a.distance(*b) > 0.01 * size,
            (a, b) => a.is_some() != b.is_some(),
        })
        .count();
    assert!(
        apart <= 5,
        "{apart} landmarks land elsewhere on the split head"
    );
}
