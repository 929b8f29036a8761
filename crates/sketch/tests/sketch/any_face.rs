//! The sketching defaults on the faces people really have: a full-body avatar (the ICT head on
//! a skinned body, built in code) picks the same blendshapes at full weight as the bare head,
//! and on a head that is only roughly symmetric the paper's tasks drawn with symmetry on
//! animate both sides.

use std::sync::OnceLock;

use crate::support::{draw, line, most_moved, project, uniform};
use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};
use faceanim_sketch::project::StrokeFile;
use faceanim_sketch::{Settings, Sketch, Target};
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

/// Just off the vertex `name` moves most, and where weight 1 takes that vertex.
fn handle(c: &Character, name: &str) -> (Vec3, Vec3) {
    let v = most_moved(c, name);
    let p = c.positions()[v as usize];
    let target = p + c.blendshape(id(c, name)).unwrap().delta_of(v);
    (p + c.normals()[v as usize] * 0.001, target)
}

/// A straight stroke from `a` to `b` drawn at 90 Hz over `seconds`.
fn stroke(a: Vec3, b: Vec3, seconds: f32) -> StrokeFile {
    draw(seconds, line(a, b), uniform)
}

fn sketch(c: &'static Character, symmetry: bool, strokes: Vec<StrokeFile>) -> Sketch<'static> {
    let settings = Settings {
        symmetry,
        ..Settings::default()
    };
    let (sketch, warnings) = Sketch::from_project(c, &project(settings, strokes));
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

/// Every one of `names` ends above 0.9 in the sketch of `task`.
fn all_full(task: &str, s: &Sketch<'_>, c: &Character, names: &[&str]) {
    let clip = s.bake_clip();
    let end = clip.frames.last().unwrap();
    for name in names {
        let w = end[id(c, name).index()];
        assert!(w > 0.9, "{task}: {name} {w}");
    }
}

#[test]
fn the_papers_tasks_with_symmetry_animate_both_sides_of_a_roughly_symmetric_head() {
    let c = lopsided();
    // Task 1: the left eye closes with symmetry on: both eyes close.
    let (a, b) = handle(c, "eyeBlink_L");
    let s = sketch(c, true, vec![stroke(a, b, 0.3)]);
    all_full("task 1", &s, c, &["eyeBlink_L", "eyeBlink_R"]);
    // Task 2: smile and outer brows.
    let (a, b) = handle(c, "mouthSmile_L");
    let (p, q) = handle(c, "browOuterUp_L");
    let s = sketch(c, true, vec![stroke(a, b, 0.6), stroke(p, q, 0.5)]);
    all_full(
        "task 2",
        &s,
        c,
        &[
            "mouthSmile_L",
            "mouthSmile_R",
            "browOuterUp_L",
            "browOuterUp_R",
        ],
    );
    // Task 3: the jaw opens (its own mirror).
    let (a, b) = handle(c, "jawOpen");
    let s = sketch(c, true, vec![stroke(a, b, 0.8)]);
    all_full("task 3", &s, c, &["jawOpen"]);
    // Task 4: neutral to smile to sad, chained, on both sides.
    let (a, smile) = handle(c, "mouthSmile_L");
    let corner = most_moved(c, "mouthSmile_L");
    let frown = c.positions()[corner as usize]
        + c.blendshape(id(c, "mouthFrown_L"))
            .unwrap()
            .delta_of(corner);
    let s = sketch(
        c,
        true,
        vec![stroke(a, smile, 0.5), stroke(smile, frown, 0.5)],
    );
    all_full("task 4", &s, c, &["mouthFrown_L", "mouthFrown_R"]);
    for name in ["mouthSmile_L", "mouthSmile_R"] {
        let w = last(&s, c, name);
        assert!(w < 0.1, "task 4: {name} {w}");
    }
}
