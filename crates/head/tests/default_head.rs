//! The built-in head: a valid, symmetric, deterministic character whose 52 ARKit blendshapes
//! each do what their names say, with natural magnitudes.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests; exact symmetry is the point"
)]

use std::sync::OnceLock;

use faceanim_head::field::{LEFT_EYE, MOUTH_Y};
use faceanim_rig::Character;
use faceanim_rig::names::ARKIT_52;
use glam::Vec3;

fn head() -> &'static Character {
    static HEAD: OnceLock<Character> = OnceLock::new();
    HEAD.get_or_init(faceanim_head::default_character)
}

fn delta(name: &str) -> Vec<Vec3> {
    let c = head();
    let mut out = vec![Vec3::ZERO; c.vertex_count()];
    c.blendshape(c.find_blendshape(name).unwrap())
        .unwrap()
        .write_dense(&mut out);
    out
}

/// The skin vertex nearest `p` (not the eyeballs, whose surface lies just inside the lids).
fn nearest(p: Vec3) -> usize {
    let c = head();
    let right_eye = Vec3::new(-LEFT_EYE.x, LEFT_EYE.y, LEFT_EYE.z);
    let skin = |v: usize| {
        let q = c.positions()[v];
        q.distance(LEFT_EYE) > 0.01275 && q.distance(right_eye) > 0.01275
    };
    (0..c.vertex_count())
        .filter(|&v| skin(v))
        .min_by(|&a, &b| {
            c.positions()[a]
                .distance(p)
                .total_cmp(&c.positions()[b].distance(p))
        })
        .unwrap()
}

#[test]
fn it_is_a_full_head_with_all_52_arkit_shapes_and_20_pairs() {
    let c = head();
    assert!(c.vertex_count() >= 5000, "{}", c.vertex_count());
    assert_eq!(c.blendshapes().len(), 52);
    let names: Vec<&str> = c.blendshapes().iter().map(|b| b.name()).collect();
    assert_eq!(names, ARKIT_52, "ARKit names in ARKit's order");
    assert_eq!(c.arkit_coverage().len(), 52);
    assert_eq!(c.symmetry().pairs().len(), 20);
    assert!(
        c.blendshapes().iter().all(|b| b.moved() > 0),
        "every shape moves something"
    );
    // Closed surfaces: every edge is shared by exactly two triangles.
    let mut edges = std::collections::HashMap::new();
    for t in c.triangles() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let open = edges.values().filter(|&&n| n != 2).count();
    assert!(
        open < c.triangles().len() / 100,
        "{open} edges are not shared by two triangles"
    );
    assert!(c.colors().is_some());
}

#[test]
fn the_mesh_and_left_right_shapes_are_exact_mirrors() {
    let c = head();
    let symmetry = c.symmetry();
    assert_eq!(symmetry.mirrored_fraction(), 1.0);
    let plane = symmetry.plane().unwrap();
    assert_eq!(plane.offset, 0.0);
    // The head's own mirror map (exact, and telling apart the coincident vertices of the lip cut).
    let mirror = faceanim_head::mesh::build().mirror;
    for (v, &m) in mirror.iter().enumerate() {
        assert_eq!(
            c.positions()[m as usize],
            plane.reflect_point(c.positions()[v])
        );
    }
    for pair in symmetry.pairs() {
        let (l, r) = (
            c.blendshape(pair.left).unwrap(),
            c.blendshape(pair.right).unwrap(),
        );
        for (v, d) in l.moves() {
            let m = mirror[v as usize];
            assert_eq!(
                r.delta_of(m),
                plane.reflect_vector(d),
                "{} / {} at vertex {v}",
                l.name(),
                r.name()
            );
        }
        assert_eq!(l.moved(), r.moved());
    }
}

#[test]
fn generation_is_deterministic() {
    let a = faceanim_export::glb::export_glb(head(), &[]).unwrap();
    let b = faceanim_export::glb::export_glb(&faceanim_head::default_character(), &[]).unwrap();
    assert!(a == b, "two builds differ");
}

#[test]
fn shapes_do_what_their_names_say() {
    let c = head();
    let chin = nearest(Vec3::new(0.0, -0.105, 0.09));
    let jaw = delta("jawOpen")[chin];
    assert!(
        jaw.y < -0.02 && jaw.length() > 0.025,
        "jawOpen drops the chin {jaw}"
    );

    // The left lip corner rises and draws back with a smile, drops with a frown.
    let corner = nearest(Vec3::new(0.0235, MOUTH_Y, 0.085));
    assert!(delta("mouthSmileLeft")[corner].y > 0.005);
    assert!(delta("mouthSmileLeft")[corner].z < 0.0);
    assert!(delta("mouthFrownLeft")[corner].y < -0.004);
    assert_eq!(
        delta("mouthSmileLeft")[nearest(Vec3::new(-0.0235, MOUTH_Y, 0.085))],
        Vec3::ZERO,
        "the right corner stays"
    );

    // A blink brings the upper lid down over the eye until it meets the lower lid.
    let rim = faceanim_head::mesh::eye_point(
        0.0,
        faceanim_head::mesh::lid_lines(0.0).0,
        faceanim_head::field::LID_RADIUS,
    );
    let lid = nearest(rim);
    assert!(
        c.positions()[lid].distance(rim) < 0.0015,
        "a vertex on the upper lid's rim"
    );
    let blink = delta("eyeBlinkLeft")[lid];
    assert!(blink.y < -0.004, "eyeBlinkLeft moves the upper lid {blink}");
    let upper_rim = c.positions()[lid] + blink;
    assert!(
        upper_rim.y < LEFT_EYE.y,
        "the closed lid passes the eye's centre: {upper_rim}"
    );

    // The irises look where the name says.
    let pupil = (0..c.vertex_count())
        .find(|&v| (c.positions()[v] - LEFT_EYE).normalize().z > 0.999)
        .unwrap();
    assert!(delta("eyeLookUpLeft")[pupil].y > 0.003);
    assert!(delta("eyeLookDownLeft")[pupil].y < -0.003);
    assert!(
        delta("eyeLookInLeft")[pupil].x < -0.003,
        "in = towards the nose"
    );
    assert!(delta("eyeLookOutLeft")[pupil].x > 0.003);

    let brow = nearest(Vec3::new(0.045, 0.036, 0.08));
    assert!(
        delta("browOuterUpLeft")[brow].y > 0.005,
        "{} at {}",
        delta("browOuterUpLeft")[brow],
        c.positions()[brow]
    );
    assert!(delta("browDownLeft")[nearest(Vec3::new(0.025, 0.034, 0.085))].y < -0.004);
    assert!(
        delta("jawLeft")[chin].x > 0.005,
        "the jaw moves to the character's left (+X)"
    );
    let cheek = nearest(Vec3::new(0.05, -0.05, 0.07));
    assert!(delta("cheekPuff")[cheek].x > 0.003);
    let upper_lip = nearest(Vec3::new(0.0, MOUTH_Y + 0.004, 0.095));
    assert!(delta("mouthPucker")[upper_lip].z > 0.005 && delta("mouthFunnel")[upper_lip].z > 0.003);
    let tongue = delta("tongueOut");
    assert!(tongue.iter().any(|d| d.z > 0.03), "the tongue comes out");
}

#[test]
fn the_jaw_opens_onto_teeth_and_a_dark_mouth() {
    // Rendered from the front, the open mouth shows dark and white pixels between the lips.
    let c = head();
    let mut w = vec![0.0; 52];
    w[c.find_blendshape("jawOpen").unwrap().index()] = 1.0;
    let camera = faceanim_render::Camera::front(&c.bounds(), 0.75);
    let colours = faceanim_render::Appearance::of(c);
    let closed = faceanim_render::render(c, &c.pose(&[]), &camera, &colours, 256);
    let open = faceanim_render::render(c, &c.pose(&w), &camera, &colours, 256);
    // Dark pixels (luminance under 70) in the middle of the lower face, which skin fills when closed.
    let dark = |img: &faceanim_render::Image| {
        let mut n = 0;
        for y in 128..210 {
            for x in 100..156 {
                let i = (y * 256 + x) * 3;
                let lum = 0.3 * f32::from(img.rgb[i])
                    + 0.59 * f32::from(img.rgb[i + 1])
                    + 0.11 * f32::from(img.rgb[i + 2]);
                n += usize::from(lum < 70.0);
            }
        }
        n
    };
    assert!(
        dark(&open) > dark(&closed) + 100,
        "open {} vs closed {}",
        dark(&open),
        dark(&closed)
    );
}
