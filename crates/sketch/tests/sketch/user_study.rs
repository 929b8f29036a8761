//! The four tasks of the paper's user study (section 4.2) on the ICT head, with strokes drawn
//! in code; each baked clip is compared with the intended reference animation by DTW, and arcs
//! and timing are checked where the task is about them.

use crate::support::{
    bow, draw, handle_vertex, ict, id, line, near, position, project, target_of, uniform,
};
use faceanim_anim::Clip;
use faceanim_anim::metrics::compare;
use faceanim_sketch::{Project, Settings, Sketch, Target};
use glam::Vec3;

fn sketch(project: &Project) -> Sketch<'static> {
    let (sketch, warnings) = Sketch::from_project(ict(), project);
    assert!(warnings.is_empty(), "{warnings:?}");
    sketch
}

/// A reference clip over the character's blendshapes from per-name weight curves.
fn reference(frames: usize, curves: &[(&str, &dyn Fn(f32) -> f32)]) -> Clip {
    let names: Vec<String> = ict().blendshape_names();
    let frames = (0..frames)
        .map(|f| {
            let mut row = vec![0.0; names.len()];
            for (name, curve) in curves {
                row[id(name).index()] = curve(f as f32);
            }
            row
        })
        .collect();
    Clip {
        fps: 30.0,
        blendshapes: names,
        frames,
        head: None,
        head_position: None,
        presence: None,
        arkit: None,
    }
}

fn weight(clip: &Clip, frame: usize, name: &str) -> f32 {
    clip.frames[frame][id(name).index()]
}

#[test]
fn task_1_left_eye_blink_with_two_strokes() {
    let lid = handle_vertex("eyeBlink_L");
    let closed = target_of("eyeBlink_L", lid);
    // Down in 0.3 s, then back up from where the first stroke ended, in 0.4 s.
    let down = draw(0.3, line(near(lid), closed), uniform);
    let up = draw(0.4, line(closed, position(lid)), uniform);
    let sketch = sketch(&project(Settings::default(), vec![down, up]));
    let actions: Vec<_> = sketch.actions().collect();
    assert_eq!(actions.len(), 2);
    assert_eq!(
        actions[0].1.sides[0].target,
        Target::Blendshape(id("eyeBlink_L"))
    );
    assert!(
        actions[0].1.sides[0].weight > 0.95,
        "{}",
        actions[0].1.sides[0].weight
    );
    assert_eq!(
        actions[1].1.previous,
        Some(actions[0].0),
        "the second stroke continues the first"
    );
    assert_eq!(actions[1].1.sides[0].target, Target::Neutral);
    assert_eq!(
        actions[1].1.start_frame, 9.0,
        "it starts when the first ends (0.3 s at 30 fps)"
    );

    let clip = sketch.bake_clip();
    assert_eq!(clip.frames.len(), 22);
    let expected = reference(
        22,
        &[("eyeBlink_L", &|f| {
            if f <= 9.0 {
                f / 9.0
            } else {
                (1.0 - (f - 9.0) / 12.0).max(0.0)
            }
        })],
    );
    let c = compare(&clip, &expected);
    assert!(c.dtw_per_frame < 0.1, "{c:?}");
    assert!(weight(&clip, 9, "eyeBlink_L") > 0.95);
    assert!(weight(&clip, 21, "eyeBlink_L") < 0.01);
    assert!(
        weight(&clip, 9, "eyeBlink_R") == 0.0,
        "without symmetry the right eye stays open"
    );
}

#[test]
fn task_2_smile_with_raised_brows_on_a_curved_path_with_symmetry() {
    let corner = handle_vertex("mouthSmile_L");
    let smile_end = target_of("mouthSmile_L", corner);
    let brow = handle_vertex("browOuterUp_L");
    let brow_end = target_of("browOuterUp_L", brow);
    // The corner sweeps outwards and up in a clear bow (5 mm off the chord).
    let chord = smile_end - position(corner);
    let bulge = chord.cross(Vec3::Z).normalize() * -0.005;
    let smile = draw(0.6, bow(near(corner), smile_end, bulge), uniform);
    let brows = draw(0.5, line(near(brow), brow_end), uniform);
    let settings = Settings {
        symmetry: true,
        ..Settings::default()
    };
    let sketch = sketch(&project(settings, vec![smile, brows]));
    let actions: Vec<_> = sketch.actions().map(|(_, a)| a).collect();
    assert_eq!(actions.len(), 2);
    let targets: Vec<Target> = actions[0].sides.iter().map(|s| s.target).collect();
    assert_eq!(
        targets,
        [
            Target::Blendshape(id("mouthSmile_L")),
            Target::Blendshape(id("mouthSmile_R"))
        ],
        "mirrored"
    );
    assert_eq!(
        actions[1].sides[1].target,
        Target::Blendshape(id("browOuterUp_R"))
    );

    let clip = sketch.bake_clip();
    let frames = clip.frames.len();
    let ramp = |n: f32| move |f: f32| (f / n).min(1.0);
    let smile_ramp = ramp(18.0);
    let brow_ramp = ramp(15.0);
    let expected = reference(
        frames,
        &[
            ("mouthSmile_L", &smile_ramp),
            ("mouthSmile_R", &smile_ramp),
            ("browOuterUp_L", &brow_ramp),
            ("browOuterUp_R", &brow_ramp),
        ],
    );
    let c = compare(&clip, &expected);
    assert!(c.dtw_per_frame < 0.25, "{c:?}");
    let last = frames - 1;
    for name in [
        "mouthSmile_L",
        "mouthSmile_R",
        "browOuterUp_L",
        "browOuterUp_R",
    ] {
        assert!(
            weight(&clip, last, name) > 0.9,
            "{name}: {}",
            weight(&clip, last, name)
        );
    }

    // The arc: halfway through, the corner is on the circle through the stroke, not the chord.
    let action = actions[0];
    let arc = Sketch::arc(action, 0).expect("a bowed stroke makes an arc");
    let half_frame = (0..=18)
        .map(|f| f as f32)
        .min_by(|a, b| {
            (action.progress(*a) - 0.5)
                .abs()
                .total_cmp(&(action.progress(*b) - 0.5).abs())
        })
        .unwrap();
    let s = action.progress(half_frame);
    let at = sketch.frame(half_frame).positions(ict())[corner as usize];
    let side = &action.sides[0];
    let on_chord = side.start_position.lerp(side.c, s);
    let on_arc = arc.point(s) + (side.start_position - side.a) * (1.0 - s);
    assert!(
        at.distance(on_arc) < 2e-4,
        "{} m from the arc",
        at.distance(on_arc)
    );
    assert!(
        at.distance(on_chord) > 2e-3,
        "only {} m from the chord",
        at.distance(on_chord)
    );
    // The mirrored corner follows the mirrored arc.
    let mirror = ict().symmetry().mirror_vertex(corner).unwrap();
    let plane = ict().symmetry().plane().unwrap();
    let mirrored_at = sketch.frame(half_frame).positions(ict())[mirror as usize];
    assert!(mirrored_at.distance(plane.reflect_point(at)) < 2e-3);
}

#[test]
fn task_3_mouth_opening_that_starts_slowly_and_speeds_up() {
    let chin = handle_vertex("jawOpen");
    let open = target_of("jawOpen", chin);
    // Drawn accelerating: distance ∝ t², over a second.
    let stroke = draw(1.0, line(near(chin), open), |x| x * x);
    let sketch = sketch(&project(Settings::default(), vec![stroke]));
    let (_, action) = sketch.actions().next().unwrap();
    assert_eq!(action.sides[0].target, Target::Blendshape(id("jawOpen")));
    let clip = sketch.bake_clip();
    assert_eq!(clip.frames.len(), 31);
    // The timing follows the drawing speed: a quarter after half the time, slow then steep.
    let mid = weight(&clip, 15, "jawOpen");
    assert!((mid - 0.25).abs() < 0.05, "{mid}");
    let early_step = weight(&clip, 5, "jawOpen") - weight(&clip, 4, "jawOpen");
    let late_step = weight(&clip, 29, "jawOpen") - weight(&clip, 28, "jawOpen");
    assert!(
        late_step > 4.0 * early_step,
        "{early_step} then {late_step}"
    );
    let expected = reference(31, &[("jawOpen", &|f: f32| (f / 30.0).powi(2))]);
    let c = compare(&clip, &expected);
    assert!(c.dtw_per_frame < 0.05 && c.mae.unwrap() < 0.01, "{c:?}");
    // Drawn at constant speed instead, the same stroke is linear: the drawing is the easing.
    let steady = draw(1.0, line(near(chin), open), uniform);
    let linear = Sketch::from_project(ict(), &project(Settings::default(), vec![steady]))
        .0
        .bake_clip();
    assert!((weight(&linear, 15, "jawOpen") - 0.5).abs() < 0.05);
}

#[test]
fn task_4_chain_neutral_smile_sad() {
    let corner = handle_vertex("mouthSmile_L");
    let smile_end = target_of("mouthSmile_L", corner);
    let frown_end = target_of("mouthFrown_L", corner);
    let to_smile = draw(0.5, line(near(corner), smile_end), uniform);
    let to_frown = draw(0.5, line(smile_end, frown_end), uniform);
    let sketch = sketch(&project(Settings::default(), vec![to_smile, to_frown]));
    let actions: Vec<_> = sketch.actions().map(|(_, a)| a).collect();
    assert_eq!(
        actions[0].sides[0].target,
        Target::Blendshape(id("mouthSmile_L"))
    );
    assert_eq!(
        actions[1].sides[0].target,
        Target::Blendshape(id("mouthFrown_L"))
    );
    assert_eq!(
        actions[1].sides[0].reference, actions[0].sides[0].reference,
        "the chain keeps its reference vertex"
    );
    let clip = sketch.bake_clip();
    assert_eq!(clip.frames.len(), 31);
    // The smile fades out as the frown fades in.
    assert!(weight(&clip, 15, "mouthSmile_L") > 0.95);
    assert!(
        (weight(&clip, 22, "mouthSmile_L") + weight(&clip, 22, "mouthFrown_L") - 1.0).abs() < 0.05
    );
    assert!(weight(&clip, 30, "mouthSmile_L") < 0.01 && weight(&clip, 30, "mouthFrown_L") > 0.95);
    let expected = reference(
        31,
        &[
            ("mouthSmile_L", &|f: f32| {
                if f <= 15.0 {
                    f / 15.0
                } else {
                    1.0 - (f - 15.0) / 15.0
                }
            }),
            ("mouthFrown_L", &|f: f32| {
                if f <= 15.0 { 0.0 } else { (f - 15.0) / 15.0 }
            }),
        ],
    );
    let c = compare(&clip, &expected);
    assert!(c.dtw_per_frame < 0.1, "{c:?}");
}

/// A stroke drawn with symmetry on says why it is one-sided when it has to be: a blendshape
/// without a partner on the other side (here the ICT head without mouthSmile_R); a shape in
/// the middle of the face (jawOpen) is its own mirror, and a paired one is mirrored.
#[test]
fn a_stroke_that_cannot_be_mirrored_says_why() {
    let settings = Settings {
        symmetry: true,
        ..Settings::default()
    };
    let stroke = |name: &str| {
        let v = handle_vertex(name);
        draw(0.5, line(near(v), target_of(name, v)), uniform)
    };
    let sketch = sketch(&project(
        settings.clone(),
        vec![stroke("jawOpen"), stroke("mouthSmile_L")],
    ));
    let actions: Vec<_> = sketch.actions().map(|(_, a)| a).collect();
    assert_eq!(actions.len(), 2);
    assert_eq!(actions[0].unmirrored, None, "jawOpen is its own mirror");
    assert_eq!(
        (actions[1].sides.len(), actions[1].unmirrored.as_deref()),
        (2, None)
    );

    // The same head without mouthSmile_R: the left smile stays one-sided, and says so.
    let head = ict();
    let without = faceanim_rig::Character::new(faceanim_rig::CharacterParts {
        name: "ict without mouthSmile_R".into(),
        positions: head.positions().to_vec(),
        normals: None,
        uvs: None,
        colors: None,
        triangles: head.triangles().to_vec(),
        materials: Vec::new(),
        parts: Vec::new(),
        blendshapes: head
            .blendshapes()
            .iter()
            .filter(|b| b.name() != "mouthSmile_R")
            .cloned()
            .collect(),
        normal_deltas: None,
    })
    .unwrap();
    let project = project(settings, vec![stroke("mouthSmile_L")]);
    let (one_sided, _) = Sketch::from_project(&without, &project);
    let action = one_sided.actions().next().unwrap().1;
    assert_eq!(action.sides.len(), 1);
    let why = action.unmirrored.as_deref().unwrap_or_default();
    assert!(why.contains("mouthSmile_L has no partner"), "{why}");
}
