//! The paper's four user-study tasks with symmetry on, on each of the four ICT identities in
//! `../shared` (the generic face and three real people, none exactly symmetric), once with the
//! rig's own `_L`/`_R` names and once with every name replaced by `shape_N` (so the mirrored
//! stroke finds its partner shape by geometry alone): every task moves both sides.

use faceanim_rig::Character;
use faceanim_sketch::project::StrokeFile;
use faceanim_sketch::{Settings, Sketch};
use faceanim_testdata::{ICT_IDENTITIES, ict_identity, renamed_and_shuffled};
use glam::Vec3;

use crate::support::{bow, draw, line, most_moved, project, uniform};

/// A face to draw on, and how its shapes map back to the ICT names.
struct Face {
    character: &'static Character,
    /// For each of `character`'s shapes, the ICT name it had.
    original: Vec<String>,
    what: String,
}

impl Face {
    fn index(&self, name: &str) -> usize {
        self.original
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("{}: no {name}", self.what))
    }

    /// Just off the vertex `name` moves most, and where weight 1 takes it.
    fn handle(&self, name: &str) -> (u32, Vec3, Vec3) {
        let c = self.character;
        let shape = &c.blendshapes()[self.index(name)];
        let v = most_moved(c, shape.name());
        let p = c.positions()[v as usize];
        (
            v,
            p + c.normals()[v as usize] * 0.001,
            p + shape.delta_of(v),
        )
    }

    fn sketch(&self, strokes: Vec<StrokeFile>) -> faceanim_anim::Clip {
        let settings = Settings {
            symmetry: true,
            ..Settings::default()
        };
        let (sketch, warnings) = Sketch::from_project(self.character, &project(settings, strokes));
        assert!(warnings.is_empty(), "{}: {warnings:?}", self.what);
        sketch.bake_clip()
    }

    fn weight(&self, clip: &faceanim_anim::Clip, frame: usize, name: &str) -> f32 {
        clip.frames[frame.min(clip.frames.len() - 1)][self.index(name)]
    }
}

fn faces() -> Vec<Face> {
    let mut faces = Vec::new();
    for file in ICT_IDENTITIES {
        let named = ict_identity(file);
        let names: Vec<String> = named.blendshape_names();
        faces.push(Face {
            character: named,
            original: names.clone(),
            what: format!("{file} (ICT names)"),
        });
        let (renamed, order) = renamed_and_shuffled(named, 11);
        faces.push(Face {
            character: Box::leak(Box::new(renamed)),
            original: order.iter().map(|&i| names[i].clone()).collect(),
            what: format!("{file} (shape_N names)"),
        });
    }
    faces
}

/// Task 1 (a blink drawn on the left eye, down then up) closes both eyes, then opens them.
fn task_1(face: &Face) {
    let (v, near, closed) = face.handle("eyeBlink_L");
    let open = face.character.positions()[v as usize];
    let clip = face.sketch(vec![
        draw(0.3, line(near, closed), uniform),
        draw(0.4, line(closed, open), uniform),
    ]);
    for name in ["eyeBlink_L", "eyeBlink_R"] {
        let shut = face.weight(&clip, 9, name);
        let after = face.weight(&clip, 21, name);
        assert!(
            shut > 0.8 && after < 0.1,
            "{}: task 1, {name} {shut} then {after}",
            face.what
        );
    }
}

/// Task 2 (a bowed smile, then raised brows, drawn on the left) smiles and raises both sides.
fn task_2(face: &Face) {
    let (_, near_corner, smile_end) = face.handle("mouthSmile_L");
    let bulge = (smile_end - near_corner).cross(Vec3::Z).normalize() * -0.005;
    let (_, near_brow, brow_end) = face.handle("browOuterUp_L");
    let clip = face.sketch(vec![
        draw(0.6, bow(near_corner, smile_end, bulge), uniform),
        draw(0.5, line(near_brow, brow_end), uniform),
    ]);
    let last = clip.frames.len() - 1;
    for name in [
        "mouthSmile_L",
        "mouthSmile_R",
        "browOuterUp_L",
        "browOuterUp_R",
    ] {
        let w = face.weight(&clip, last, name);
        assert!(w > 0.6, "{}: task 2, {name} ends at {w}", face.what);
    }
}

/// Task 3 (the jaw opening, slowly then fast) opens the jaw, its own mirror image.
fn task_3(face: &Face) {
    let (_, near, open) = face.handle("jawOpen");
    let clip = face.sketch(vec![draw(1.0, line(near, open), |x| x * x)]);
    let (mid, end) = (
        face.weight(&clip, 15, "jawOpen"),
        face.weight(&clip, 30, "jawOpen"),
    );
    assert!(
        end > 0.9 && mid < 0.4,
        "{}: task 3, jaw {mid} then {end}",
        face.what
    );
}

/// Task 4 (a chain from neutral to a smile to a frown, drawn on the left corner) does it on
/// both corners.
fn task_4(face: &Face) {
    let (v, near, smile_end) = face.handle("mouthSmile_L");
    let frown_end = face.character.positions()[v as usize]
        + face.character.blendshapes()[face.index("mouthFrown_L")].delta_of(v);
    let clip = face.sketch(vec![
        draw(0.5, line(near, smile_end), uniform),
        draw(0.5, line(smile_end, frown_end), uniform),
    ]);
    for side in ["_L", "_R"] {
        let smile = format!("mouthSmile{side}");
        let frown = format!("mouthFrown{side}");
        let (s15, s30) = (
            face.weight(&clip, 15, &smile),
            face.weight(&clip, 30, &smile),
        );
        let f30 = face.weight(&clip, 30, &frown);
        assert!(
            s15 > 0.6 && s30 < 0.2 && f30 > 0.6,
            "{}: task 4, {smile} {s15} then {s30}, {frown} {f30}",
            face.what
        );
    }
}

#[test]
fn the_four_tasks_move_both_sides_on_every_identity() {
    for face in faces() {
        task_1(&face);
        task_2(&face);
        task_3(&face);
        task_4(&face);
    }
}
