//! What the renderer promises users and the adapter's training set: base-colour textures show
//! where the UVs put them, and a cropped camera gives the same picture as cutting the square
//! out of a full render.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::sync::Arc;

use faceanim_render::{Appearance, Camera, Image, render};
use faceanim_rig::{Character, CharacterParts, Material, MaterialId, Part, Texture};
use glam::Vec3;

/// A PNG of `width × 1` pixels of the given colours.
fn png(colours: &[[u8; 3]]) -> Vec<u8> {
    let image = Image {
        width: colours.len() as u32,
        height: 1,
        rgb: colours.concat(),
    };
    image.to_png().unwrap()
}

/// A square facing +Z, UVs across it, with a material of `texture` (or none).
fn card(texture: Option<Vec<u8>>) -> Character {
    card_of(texture, "image/png", faceanim_rig::AlphaMode::Opaque)
}

/// [`card`] with a texture of any type and the material's alpha mode.
fn card_of(texture: Option<Vec<u8>>, mime: &str, alpha: faceanim_rig::AlphaMode) -> Character {
    Character::new(CharacterParts {
        name: "card".into(),
        positions: vec![
            Vec3::new(-0.1, -0.1, 0.0),
            Vec3::new(0.1, -0.1, 0.0),
            Vec3::new(0.1, 0.1, 0.0),
            Vec3::new(-0.1, 0.1, 0.0),
        ],
        normals: None,
        uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
        colors: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![Material {
            name: "paper".into(),
            base_color_texture: texture.map(|bytes| Texture {
                mime_type: mime.into(),
                bytes: Arc::from(bytes),
            }),
            alpha,
            ..Material::default()
        }],
        parts: vec![Part {
            name: "card".into(),
            material: MaterialId(0),
            triangles: 0..2,
        }],
        blendshapes: Vec::new(),
        normal_deltas: None,
    })
    .unwrap()
}

fn pixel(image: &Image, x: u32, y: u32) -> [u8; 3] {
    let i = ((y * image.width + x) * 3) as usize;
    [image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]]
}

/// `card` from the front, 128 pixels square, its texture decoded without a warning.
fn front(card: &Character) -> Image {
    let appearance = Appearance::of(card);
    assert!(
        appearance.warnings().is_empty(),
        "{:?}",
        appearance.warnings()
    );
    let camera = Camera::front(&card.bounds(), 1.0);
    render(card, &card.pose(&[]), &camera, &appearance, 128)
}

#[test]
fn a_texture_shows_where_its_uvs_put_it() {
    let image = front(&card(Some(png(&[[220, 30, 30], [30, 30, 220]]))));
    // The left half of the card is red, the right half blue (texels are blended only in the
    // middle).
    let [r, _, b] = pixel(&image, 45, 70);
    assert!(r > 2 * b, "left {:?}", pixel(&image, 45, 70));
    let [r, _, b] = pixel(&image, 83, 70);
    assert!(b > 2 * r, "right {:?}", pixel(&image, 83, 70));
}

#[test]
fn a_cut_out_texture_shows_what_is_behind_where_its_alpha_is_low() {
    // A WebP (image-webp's encoder): the left texel opaque red, the right one transparent blue,
    // as lashes and brows are painted.
    let mut webp = Vec::new();
    image_webp::WebPEncoder::new(&mut webp)
        .encode(
            &[220, 30, 30, 255, 30, 30, 220, 0],
            2,
            1,
            image_webp::ColorType::Rgba8,
        )
        .unwrap();
    let shown = |alpha| {
        let image = front(&card_of(Some(webp.clone()), "image/webp", alpha));
        (pixel(&image, 45, 70), pixel(&image, 83, 70))
    };
    // Opaque: both halves drawn.
    let (left, right) = shown(faceanim_rig::AlphaMode::Opaque);
    assert!(
        left[0] > 2 * left[2] && right[2] > 2 * right[0],
        "{left:?} {right:?}"
    );
    // Cut out: the right half is the background, the left still red.
    let background = pixel(&front(&card(None)), 2, 2);
    for alpha in [
        faceanim_rig::AlphaMode::Mask { cutoff: 0.5 },
        faceanim_rig::AlphaMode::Blend,
    ] {
        let (left, right) = shown(alpha);
        assert!(left[0] > 2 * left[2], "{alpha:?}: {left:?}");
        assert_eq!(right, background, "{alpha:?}: the cut-out half is drawn");
    }
}

#[test]
fn a_broken_texture_is_reported_and_the_base_colour_shown() {
    let card = card(Some(b"not a png".to_vec()));
    let appearance = Appearance::of(&card);
    let warning = appearance.warnings().join("\n");
    assert!(warning.contains("material 'paper'"), "{warning}");
    let camera = Camera::front(&card.bounds(), 1.0);
    let image = render(&card, &card.pose(&[]), &camera, &appearance, 64);
    let [r, g, b] = pixel(&image, 32, 36);
    assert!(
        r > 100
            && (i32::from(r) - i32::from(b)).abs() < 10
            && (i32::from(r) - i32::from(g)).abs() < 10
    );
}

#[test]
fn a_cropped_camera_renders_the_square_it_was_given() {
    let card = card(Some(png(&[[220, 30, 30], [30, 200, 30], [30, 30, 220]])));
    let appearance = Appearance::of(&card);
    let camera = Camera::front(&card.bounds(), 1.0);
    let pose = card.pose(&[]);
    let full = render(&card, &pose, &camera, &appearance, 256);
    // The 64-pixel square centred at (100, 140), rendered on its own at 64×64.
    let crop = render(
        &card,
        &pose,
        &camera.cropped(256.0, 100.0, 140.0, 64.0, 0.0),
        &appearance,
        64,
    );
    let mut worst = 0;
    for y in 2..62 {
        for x in 2..62 {
            let (a, b) = (pixel(&crop, x, y), pixel(&full, 68 + x, 108 + y));
            for k in 0..3 {
                worst = worst.max((i32::from(a[k]) - i32::from(b[k])).abs());
            }
        }
    }
    assert!(
        worst <= 24,
        "crop differs from the full render by up to {worst}"
    );
    // Turned a quarter clockwise on screen: the crop's top row now shows the picture's right.
    let turned = render(
        &card,
        &pose,
        &camera.cropped(256.0, 128.0, 128.0, 128.0, std::f32::consts::FRAC_PI_2),
        &appearance,
        64,
    );
    let top = pixel(&turned, 32, 4);
    assert!(
        top[2] > 2 * top[0],
        "the blue right edge is at the top: {top:?}"
    );
}
