//! Handles, exaggeration, layers, multi-blendshape strokes, path selection, warnings, and the
//! glTF bake matching the engine at every frame.

use crate::support::{
    bow, draw, handle_vertex, ict, id, line, near, position, project, target_of, uniform,
};
use faceanim_export::glb::export_glb;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_sketch::bake::EXPORT_TOLERANCE;
use faceanim_sketch::engine::Input;
use faceanim_sketch::settings::{Selection, StrokeMode};
use faceanim_sketch::{Settings, Sketch, Target};
use glam::Vec3;

fn input(sketch: &Sketch<'_>, k: usize) -> Input {
    sketch.inputs()[k].clone().unwrap()
}

#[test]
fn moving_the_end_handle_changes_target_weight_and_exaggeration() {
    // Eq. 1 and Eq. 2: for any end, the target is the nearest sphere and the weight the end's
    // projection on that blendshape's motion.
    let chin = handle_vertex("jawOpen");
    let open = target_of("jawOpen", chin);
    for fraction in [0.3f32, 0.5, 0.7, 0.85] {
        let end = position(chin).lerp(open, fraction);
        let stroke = draw(0.5, line(near(chin), end), uniform);
        let sketch = Sketch::from_project(ict(), &project(Settings::default(), vec![stroke])).0;
        let side = sketch.actions().next().unwrap().1.sides[0].clone();
        let spheres = sketch.candidates(near(chin), 0.0).unwrap();
        let nearest = spheres
            .candidates
            .iter()
            .min_by(|a, b| {
                a.position
                    .distance(end)
                    .total_cmp(&b.position.distance(end))
            })
            .unwrap();
        assert_eq!(side.target, nearest.target, "at {fraction}");
        let Target::Blendshape(b) = side.target else {
            panic!("a blendshape")
        };
        let delta = ict().blendshape(b).unwrap().delta_of(side.reference);
        let projection = ((end - spheres.base).dot(delta) / delta.length_squared()).clamp(0.0, 1.0);
        assert!((side.weight - projection).abs() < 1e-5);
    }
    // Near the jaw's sphere it is the jaw, at the drawn fraction.
    let stroke = draw(
        0.5,
        line(near(chin), position(chin).lerp(open, 0.85)),
        uniform,
    );
    let mut sketch = Sketch::from_project(ict(), &project(Settings::default(), vec![stroke])).0;
    let (id0, action) = sketch.actions().next().unwrap();
    assert_eq!(action.sides[0].target, Target::Blendshape(id("jawOpen")));
    assert!(
        (action.sides[0].weight - 0.85).abs() < 0.03,
        "{}",
        action.sides[0].weight
    );
    let mut edited = input(&sketch, 0);
    edited.end = Some(open);
    sketch.edit(id0, edited);
    assert!(
        (sketch.action(id0).unwrap().sides[0].weight - 1.0).abs() < 1e-3,
        "dragged to the sphere: weight 1"
    );

    // On the lip corner, drawn to the smile's sphere.
    let corner = handle_vertex("mouthSmile_L");
    let end = target_of("mouthSmile_L", corner);
    let stroke = draw(0.5, line(near(corner), end), uniform);
    let mut sketch = Sketch::from_project(ict(), &project(Settings::default(), vec![stroke])).0;
    let (id0, _) = sketch.actions().next().unwrap();
    let mut edited = input(&sketch, 0);
    let side = &sketch.action(id0).unwrap().sides[0];
    assert_eq!(side.target, Target::Blendshape(id("mouthSmile_L")));
    assert!((side.weight - 1.0).abs() < 1e-3);

    // Beyond it: still weight 1, the rest is exaggeration, and the corner lands on the arrow.
    let beyond = end + (end - position(corner)) * 0.5;
    edited.end = Some(beyond);
    sketch.edit(id0, edited.clone());
    let action = sketch.action(id0).unwrap();
    assert_eq!(action.sides[0].weight, 1.0);
    assert!(action.sides[0].exaggeration.length() > 1e-3);
    let last = sketch.last_frame();
    let corner_at_end = sketch.frame(last).positions(ict())[corner as usize];
    assert!(
        corner_at_end.distance(beyond) < 1e-5,
        "the reference vertex lands on the stroke end"
    );
    // The exaggeration fades with distance along the mesh: neighbours move less, far vertices not at all.
    let offsets = &action.to.offsets;
    let at_corner = offsets.get(corner).length();
    let neighbour = ict().graph().neighbours(corner)[0];
    assert!(offsets.get(neighbour).length() < at_corner);
    let nose_tip = (0..ict().vertex_count() as u32)
        .max_by(|a, b| position(*a).z.total_cmp(&position(*b).z))
        .unwrap();
    assert_eq!(offsets.get(nose_tip), Vec3::ZERO);

    // Dragged to the jaw's target instead: the target changes.
    edited.end = Some(target_of("jawOpen", corner));
    sketch.edit(id0, edited);
    assert_eq!(
        sketch.action(id0).unwrap().sides[0].target,
        Target::Blendshape(id("jawOpen"))
    );
}

#[test]
fn moving_the_middle_handle_bends_or_straightens_and_easing_retimes() {
    let chin = handle_vertex("jawOpen");
    let open = target_of("jawOpen", chin);
    let stroke = draw(
        1.0,
        bow(near(chin), open, Vec3::new(0.0, 0.0, 0.01)),
        uniform,
    );
    let mut sketch = Sketch::from_project(ict(), &project(Settings::default(), vec![stroke])).0;
    let (id0, action) = sketch.actions().next().unwrap();
    assert!(
        !action.sides[0].path.is_straight(),
        "a bowed stroke is an arc"
    );
    let swing_before = action.swing.len();
    assert!(swing_before > 100);

    // The sphere moved onto the chord's midpoint (within the snap distance): straight, green.
    let side = action.sides[0].clone();
    let mut edited = input(&sketch, 0);
    edited.mid =
        Some((side.a + side.c) * 0.5 + Vec3::new(0.0, 0.0, sketch.resolved().snap_distance * 0.5));
    sketch.edit(id0, edited.clone());
    let action = sketch.action(id0).unwrap();
    assert!(action.sides[0].path.is_straight());
    assert!(action.swing.is_empty());

    // Easing: α = 0 front-loads the motion, α = 1 back-loads it; the drawn timing is kept inside.
    let mid_progress = |sketch: &Sketch<'_>| sketch.action(id0).unwrap().progress(15.0);
    assert!(
        (mid_progress(&sketch) - 0.5).abs() < 0.05,
        "{}",
        mid_progress(&sketch)
    );
    edited.ease = Some(0.0);
    sketch.edit(id0, edited.clone());
    assert!(mid_progress(&sketch) > 0.8, "{}", mid_progress(&sketch));
    edited.ease = Some(1.0);
    sketch.edit(id0, edited.clone());
    assert!(mid_progress(&sketch) < 0.2, "{}", mid_progress(&sketch));

    // Timeline: moved and rescaled.
    edited.ease = None;
    edited.start_frame = Some(10.0);
    edited.duration = Some(60.0);
    sketch.edit(id0, edited);
    let action = sketch.action(id0).unwrap();
    assert_eq!((action.start_frame, action.end_frame()), (10.0, 70.0));
    assert_eq!(sketch.bake_clip().frames.len(), 71);
}

#[test]
fn moving_a_shared_point_edits_both_actions_of_a_chain() {
    let corner = handle_vertex("mouthSmile_L");
    let smile = target_of("mouthSmile_L", corner);
    let frown = target_of("mouthFrown_L", corner);
    let strokes = vec![
        draw(0.5, line(near(corner), smile), uniform),
        draw(0.5, line(smile, frown), uniform),
    ];
    let mut sketch = Sketch::from_project(ict(), &project(Settings::default(), strokes)).0;
    let ids: Vec<_> = sketch.actions().map(|(id, _)| id).collect();
    let mut edited = input(&sketch, 0);
    // The shared point pulled a little beyond the smile: the first action exaggerates...
    let moved = smile + Vec3::new(0.002, 0.001, 0.0);
    edited.end = Some(moved);
    sketch.edit(ids[0], edited);
    let first = sketch.action(ids[0]).unwrap();
    let second = sketch.action(ids[1]).unwrap();
    assert_eq!(first.sides[0].c, moved);
    assert!(first.sides[0].exaggeration.length() > 1e-3);
    // ...and the second starts from there, from the first's (exaggerated) target pose.
    assert_eq!(
        second.sides[0].a, moved,
        "the next stroke now starts where the first ends"
    );
    assert_eq!(second.previous, Some(ids[0]));
    assert_eq!(second.from, first.to);
}

#[test]
fn separate_chains_are_layers_that_add_up() {
    let corner = handle_vertex("mouthSmile_L");
    let lid = handle_vertex("eyeBlink_L");
    let strokes = vec![
        draw(
            0.5,
            line(near(corner), target_of("mouthSmile_L", corner)),
            uniform,
        ),
        draw(0.5, line(near(lid), target_of("eyeBlink_L", lid)), uniform),
    ];
    let sketch = Sketch::from_project(ict(), &project(Settings::default(), strokes)).0;
    let actions: Vec<_> = sketch.actions().map(|(_, a)| a).collect();
    assert_eq!(
        actions[1].previous, None,
        "far from the first stroke's end: a new chain"
    );
    assert_eq!(
        actions[1].start_frame, 0.0,
        "new chains start at frame 0 unless placed"
    );
    let clip = sketch.bake_clip();
    let last = clip.frames.len() - 1;
    assert!(
        clip.frames[last][id("mouthSmile_L").index()] > 0.95
            && clip.frames[last][id("eyeBlink_L").index()] > 0.95
    );
}

#[test]
fn multi_blendshape_strokes_solve_all_weights_at_once() {
    let corner = handle_vertex("mouthSmile_L");
    // A goal between the smile and the stretch targets: no single blendshape reaches it.
    let goal = target_of("mouthSmile_L", corner).lerp(target_of("mouthStretch_L", corner), 0.5);
    let settings = Settings {
        mode: StrokeMode::Multi,
        ..Settings::default()
    };
    let sketch = Sketch::from_project(
        ict(),
        &project(settings, vec![draw(0.5, line(near(corner), goal), uniform)]),
    )
    .0;
    let (_, action) = sketch.actions().next().unwrap();
    assert!(action.to.weights.len() >= 2, "{:?}", action.to.weights);
    // The blendshapes get the corner most of the way; the exaggeration covers only the rest.
    assert!(
        action.sides[0].exaggeration.length() < 0.25 * (goal - position(corner)).length(),
        "{}",
        action.sides[0].exaggeration.length()
    );
    let landed = sketch.frame(sketch.last_frame()).positions(ict())[corner as usize];
    assert!(landed.distance(goal) < 1e-5);
}

#[test]
fn segment_selection_gives_partial_weights_where_eq_1_picks_a_smaller_shape() {
    // Half-way to the smile's sphere from the lip corner: Eq. 1 picks a smaller shape whose full
    // target is nearer; segment selection picks the smile at half weight.
    let corner = handle_vertex("mouthSmile_L");
    let end = position(corner).lerp(target_of("mouthSmile_L", corner), 0.5);
    let strokes = vec![draw(0.5, line(near(corner), end), uniform)];
    let pick = |selection| {
        let settings = Settings {
            selection,
            ..Settings::default()
        };
        let sketch = Sketch::from_project(ict(), &project(settings, strokes.clone())).0;
        sketch.actions().next().unwrap().1.sides[0].clone()
    };
    assert_ne!(
        pick(Selection::End).target,
        Target::Blendshape(id("mouthSmile_L")),
        "Eq. 1's known weakness"
    );
    let side = pick(Selection::Segment);
    assert_eq!(side.target, Target::Blendshape(id("mouthSmile_L")));
    assert!((side.weight - 0.5).abs() < 0.05, "{}", side.weight);
}

#[test]
fn path_selection_prefers_the_candidate_whose_motion_the_stroke_follows() {
    use faceanim_rig::{Blendshape, Character, CharacterParts};
    // A small grid whose centre vertex can go up 10 mm ("up") or diagonally ("diag").
    let mut positions = Vec::new();
    for j in 0..9 {
        for i in 0..9 {
            positions.push(Vec3::new(i as f32 * 0.005, j as f32 * 0.005, 0.0));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..8u32 {
        for i in 0..8u32 {
            let a = j * 9 + i;
            triangles.push([a, a + 1, a + 10]);
            triangles.push([a, a + 10, a + 9]);
        }
    }
    let centre = 40u32;
    let shape = |d: Vec3| {
        let dense: Vec<Vec3> = (0..81)
            .map(|v| if v == centre as usize { d } else { Vec3::ZERO })
            .collect();
        dense
    };
    let character = Character::new(CharacterParts {
        name: "grid".into(),
        positions: positions.clone(),
        triangles,
        blendshapes: vec![
            Blendshape::from_dense("up", &shape(Vec3::new(0.0, 0.010, 0.0)), 1e-9),
            Blendshape::from_dense("diag", &shape(Vec3::new(0.007, 0.007, 0.0)), 1e-9),
        ],
        ..CharacterParts::default()
    })
    .unwrap();
    let start = positions[centre as usize];
    // Straight up for most of the way, then a hook right: the end is nearer diag's target.
    let end = start + Vec3::new(0.0045, 0.0085, 0.0);
    let path = move |s: f32| {
        if s < 0.8 {
            start + Vec3::new(0.0, 0.0085 * s / 0.8, 0.0)
        } else {
            start + Vec3::new(0.0045 * (s - 0.8) / 0.2, 0.0085, 0.0)
        }
    };
    let strokes = vec![draw(0.5, path, uniform)];
    let pick = |selection| {
        let settings = Settings {
            selection,
            candidate_radius: Some(0.001),
            ..Settings::default()
        };
        let sketch = Sketch::from_project(&character, &project(settings, strokes.clone())).0;
        sketch.actions().next().unwrap().1.sides[0].target
    };
    assert!(
        end.distance(start + Vec3::new(0.007, 0.007, 0.0))
            < end.distance(start + Vec3::new(0.0, 0.010, 0.0))
    );
    assert_eq!(
        pick(Selection::End),
        Target::Blendshape(character.find_blendshape("diag").unwrap()),
        "Eq. 1"
    );
    assert_eq!(
        pick(Selection::Path),
        Target::Blendshape(character.find_blendshape("up").unwrap()),
        "the path went up"
    );
}

#[test]
fn strokes_the_interface_would_ignore_become_warnings() {
    let far = draw(
        0.3,
        line(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.1, 1.0)),
        uniform,
    );
    let mut click = draw(0.3, line(Vec3::ZERO, Vec3::ZERO), uniform);
    click.samples.truncate(1);
    let (sketch, warnings) =
        Sketch::from_project(ict(), &project(Settings::default(), vec![far, click]));
    assert_eq!(sketch.actions().count(), 0);
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("strokes[0]: skipped, it starts") && w.contains("pen distance")),
        "{warnings:?}"
    );
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("strokes[1]: skipped")),
        "{warnings:?}"
    );
}

#[test]
fn the_glb_bake_matches_the_engine_at_every_frame() {
    // Arcs, an exaggeration, symmetry and a chain together.
    let corner = handle_vertex("mouthSmile_L");
    let smile = target_of("mouthSmile_L", corner);
    let beyond = smile + (smile - position(corner)) * 0.3;
    let chin = handle_vertex("jawOpen");
    let strokes = vec![
        draw(
            0.6,
            bow(near(corner), beyond, Vec3::new(0.0, 0.004, 0.004)),
            uniform,
        ),
        draw(
            0.5,
            bow(
                beyond,
                target_of("mouthFrown_L", corner),
                Vec3::new(0.003, 0.0, 0.003),
            ),
            uniform,
        ),
        draw(
            0.8,
            bow(
                near(chin),
                target_of("jawOpen", chin),
                Vec3::new(0.0, 0.0, 0.012),
            ),
            |x| x * x,
        ),
    ];
    let settings = Settings {
        symmetry: true,
        ..Settings::default()
    };
    let sketch = Sketch::from_project(ict(), &project(settings, strokes)).0;
    assert_eq!(sketch.actions().count(), 3);
    let baked = sketch.bake("take").unwrap();
    let extra = baked.character.blendshapes().len() - ict().blendshapes().len();
    assert!(extra >= 4, "exaggeration and arc targets: {extra}");

    // Through real GLB bytes and back, as any player would read them.
    let glb = export_glb(&baked.character, std::slice::from_ref(&baked.animation)).unwrap();
    let player = import_gltf(&glb, "take.glb", &NoExternalResources)
        .unwrap()
        .character;
    let tolerance = EXPORT_TOLERANCE * ict().size();
    let mut worst = 0.0f32;
    for (f, weights) in baked.animation.weights.iter().enumerate() {
        let engine = sketch.frame(f as f32).positions(ict());
        let played = player.pose(weights).positions;
        let error = engine
            .iter()
            .zip(&played)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        worst = worst.max(error);
        assert!(error <= tolerance, "frame {f}: {error} m > {tolerance} m");
    }
    eprintln!(
        "largest difference between engine and export over {} frames: {worst:e} m",
        baked.animation.weights.len()
    );
}
