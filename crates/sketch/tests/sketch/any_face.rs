//! The sketching defaults on the faces people really have: a full-body avatar (the ICT head on
//! a skinned body, built in code) picks the same blendshapes at full weight as the bare head,
//! and on a head that is only roughly symmetric the paper's tasks drawn with symmetry on
//! animate both sides.

use std::sync::OnceLock;

use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_sketch::project::{SampleFile, StrokeFile};
use faceanim_sketch::{Project, ProjectFile, Settings, Sketch, Target};
use faceanim_testdata::avatar::{VrmKind, full_body_glb};
use faceanim_testdata::{asymmetric, ict};
use glam::Vec3;

fn avatar() -> &'static Character {
    static AVATAR: OnceLock<Character> = OnceLock::new();
    AVATAR.get_or_init(|| {
        let bytes = full_body_glb(ict(), VrmKind::None, &[]);
        import_gltf(&bytes, "avatar.glb", &NoExternalResources)
            .unwrap()
            .character
    })
}

fn lopsided() -> &'static Character {
    static HEAD: OnceLock<Character> = OnceLock::new();
    HEAD.get_or_init(|| asymmetric(ict()))
}

fn id(c: &Character, name: &str) -> faceanim_rig::BlendshapeId {
    c.find_blendshape(name)
        .unwrap_or_else(|| panic!("no {name}"))
}

/// The vertex `name` moves most, and where weight 1 takes it.
fn handle(c: &Character, name: &str) -> (Vec3, Vec3) {
    let shape = c.blendshape(id(c, name)).unwrap();
    let k = (0..shape.moved())
        .max_by(|&a, &b| {
            shape.deltas()[a]
                .length()
                .total_cmp(&shape.deltas()[b].length())
        })
        .unwrap();
    let v = shape.indices()[k] as usize;
    let start = c.positions()[v] + c.normals()[v] * 0.001;
    (start, c.positions()[v] + shape.deltas()[k])
}

/// A straight stroke from `a` to `b` drawn at 90 Hz over `seconds`.
fn stroke(a: Vec3, b: Vec3, seconds: f32) -> StrokeFile {
    let n = (seconds * 90.0).round() as usize;
    StrokeFile {
        samples: (0..=n)
            .map(|i| SampleFile {
                t: i as f32 / 90.0,
                p: a.lerp(b, i as f32 / n as f32).to_array(),
            })
            .collect(),
        start_frame: None,
        duration: None,
        end: None,
        mid: None,
        ease: None,
        symmetry: None,
    }
}

fn sketch(c: &'static Character, symmetry: bool, strokes: Vec<StrokeFile>) -> Sketch<'static> {
    let project = Project::from_file(ProjectFile {
        version: 1,
        fps: 30.0,
        settings: Settings {
            symmetry,
            ..Settings::default()
        },
        strokes,
    })
    .unwrap();
    let (sketch, warnings) = Sketch::from_project(c, &project);
    assert!(warnings.is_empty(), "{warnings:?}");
    sketch
}

#[test]
fn default_strokes_pick_full_weights_on_a_full_body_avatar_as_on_the_bare_head() {
    for (what, c) in [("bare head", ict()), ("full-body avatar", avatar())] {
        for name in ["jawOpen", "eyeBlink_L", "mouthSmile_L", "browInnerUp_L"] {
            let (start, end) = handle(c, name);
            let s = sketch(c, false, vec![stroke(start, end, 0.5)]);
            let (_, action) = s
                .actions()
                .next()
                .unwrap_or_else(|| panic!("{what}: no action for {name}"));
            assert_eq!(
                action.sides[0].target,
                Target::Blendshape(id(c, name)),
                "{what}: {name}"
            );
            assert!(
                action.sides[0].weight >= 0.8,
                "{what}: {name} at {}",
                action.sides[0].weight
            );
        }
    }
}

/// Final weight of `name` in the baked clip.
fn last(s: &Sketch<'_>, c: &Character, name: &str) -> f32 {
    let clip = s.bake_clip();
    clip.frames.last().unwrap()[id(c, name).index()]
}

#[test]
fn the_papers_tasks_with_symmetry_animate_both_sides_of_a_roughly_symmetric_head() {
    let c = lopsided();
    // Task 1: the left eye closes with symmetry on: both eyes close.
    let (a, b) = handle(c, "eyeBlink_L");
    let s = sketch(c, true, vec![stroke(a, b, 0.3)]);
    for name in ["eyeBlink_L", "eyeBlink_R"] {
        assert!(
            last(&s, c, name) > 0.9,
            "task 1: {name} {}",
            last(&s, c, name)
        );
    }
    // Task 2: smile and outer brows.
    let (a, b) = handle(c, "mouthSmile_L");
    let (p, q) = handle(c, "browOuterUp_L");
    let s = sketch(c, true, vec![stroke(a, b, 0.6), stroke(p, q, 0.5)]);
    for name in [
        "mouthSmile_L",
        "mouthSmile_R",
        "browOuterUp_L",
        "browOuterUp_R",
    ] {
        assert!(
            last(&s, c, name) > 0.9,
            "task 2: {name} {}",
            last(&s, c, name)
        );
    }
    // Task 3: the jaw opens (its own mirror).
    let (a, b) = handle(c, "jawOpen");
    let s = sketch(c, true, vec![stroke(a, b, 0.8)]);
    assert!(last(&s, c, "jawOpen") > 0.9);
    // Task 4: neutral to smile to sad, chained, on both sides.
    let (a, smile) = handle(c, "mouthSmile_L");
    let corner = {
        let s = c.blendshape(id(c, "mouthSmile_L")).unwrap();
        let k = (0..s.moved())
            .max_by(|&x, &y| s.deltas()[x].length().total_cmp(&s.deltas()[y].length()))
            .unwrap();
        s.indices()[k]
    };
    let frown = c.positions()[corner as usize]
        + c.blendshape(id(c, "mouthFrown_L"))
            .unwrap()
            .delta_of(corner);
    let s = sketch(
        c,
        true,
        vec![stroke(a, smile, 0.5), stroke(smile, frown, 0.5)],
    );
    for name in ["mouthFrown_L", "mouthFrown_R"] {
        assert!(
            last(&s, c, name) > 0.9,
            "task 4: {name} {}",
            last(&s, c, name)
        );
    }
    for name in ["mouthSmile_L", "mouthSmile_R"] {
        assert!(
            last(&s, c, name) < 0.1,
            "task 4: {name} {}",
            last(&s, c, name)
        );
    }
}
