//! Domain randomisation of the training renders, so the adapter learns the expression rather
//! than one camera's and one light's landmarks.
//!
//! Samples come in small groups that share one [`Condition`]:
//! - a person ([`Identity`]): smooth, face-sized changes of the character's proportions (the
//!   face wider or narrower, longer or shorter, deeper; eyes further apart, a longer nose, a
//!   wider jaw — symmetric bumps of a random field), applied to the neutral face and every
//!   shape alike, so the adapter learns the expression and not one face;
//! - a lens: from wide angle (the camera at 0.6× the front camera's distance) to long
//!   (4×, nearly parallel rays), or orthographic (one group in [`ORTHOGRAPHIC_ONE_IN`]); the
//!   field of view that frames the face goes with the distance; yaw, pitch and roll up to ±25°;
//! - a light rig: key and fill direction, intensity and colour, ambient level, rim, a specular
//!   highlight from matte to glossy, smooth or flat (faceted) shading;
//! - the skin's albedo, textures on or off, a background (a colour or a gradient);
//! - the picture's degradation: the face 100–256 pixels across, blur up to 1 pixel, noise,
//!   JPEG at quality 50–95.
//!
//! One group in [`FRONT_EVERY`] is the plain front render of the character itself instead. The
//! group's neutral face is rendered under the same condition and identity, for neutral
//! calibration. Within a group, each sample's crop is jittered (position and scale) as a
//! tracker's crop from the previous frame's landmarks would be, and, in varied groups, the head
//! turns from the neutral's pose (up to 15° of yaw, 12° of pitch) as it does between a take's
//! neutral frame and its other frames. The crop is levelled by the
//! eyes, as MediaPipe's region is, so the camera's roll leaves a residual tilt of a few degrees
//! in the crop.
//!
//! Everything is drawn from a seeded generator: a seed gives the same pictures every time.

use faceanim_render::{Background, Camera, Image, Light, Shading};
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// Whether training renders vary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Augmentation {
    /// Every sample from the one front camera in the studio's light (the first version).
    None,
    /// Camera, light, skin, background and picture quality drawn per group of samples (the
    /// default).
    #[default]
    Randomised,
}

impl Augmentation {
    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Augmentation::None => "none",
            Augmentation::Randomised => "randomised",
        }
    }
}

/// Samples that share one condition (and one neutral render).
pub const GROUP: usize = 8;

/// One group in this many is rendered from the front in the studio's light at full quality
/// (the first version's pictures): the adapter keeps learning them, and every training set can
/// say how it does on them.
pub const FRONT_EVERY: usize = 8;

/// One group in this many is seen through an orthographic camera (among the varied groups).
pub const ORTHOGRAPHIC_ONE_IN: u32 = 6;

/// Symmetric pairs of bumps in an [`Identity`].
const BUMPS: usize = 5;

/// One smooth bump of an identity's displacement field, in face units (the crop's side),
/// relative to the face's centre: points near `centre` (within about `radius`) move by
/// `offset`, fading as a Gaussian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bump {
    /// Where the bump is, face units from the face's centre (x right, y up, z forward).
    pub centre: Vec3,
    /// Its reach, face units.
    pub radius: f32,
    /// How far its centre moves, face units.
    pub offset: Vec3,
}

/// Another person's proportions, as a smooth displacement of the character's posed vertices:
/// the face scaled along its three axes about its centre, plus symmetric pairs of Gaussian
/// bumps (each bump mirrored across the face's middle with its offset mirrored). Applied to
/// the posed mesh, it changes the neutral face and every shape alike: a shape's displacement
/// is carried by the warp (a wider mouth smiles wider).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Identity {
    /// Scale across, up and forward.
    pub scale: Vec3,
    /// The bumps (each also applied mirrored).
    pub bumps: [Bump; BUMPS],
}

impl Identity {
    /// The character as it is.
    pub const NONE: Identity = Identity {
        scale: Vec3::ONE,
        bumps: [Bump {
            centre: Vec3::ZERO,
            radius: 1.0,
            offset: Vec3::ZERO,
        }; BUMPS],
    };

    /// A random person: across and up scaled by up to ±10 %, depth by ±15 %, and bumps of
    /// 8–22 % of the face moving by up to 5.5 % of it (eye distance, nose length, jaw width and
    /// the like). Chosen on three.js stills of another ICT identity and on the real footage
    /// (larger than ±7 % and 3.5 %: real-footage correlation 0.85 → 0.88, those stills' MAE
    /// 0.069 → 0.074).
    pub fn draw(rng: &mut impl rand::Rng) -> Identity {
        let scale = Vec3::new(
            rng.random_range(0.9..1.1),
            rng.random_range(0.9..1.1),
            rng.random_range(0.85..1.15),
        );
        let bumps = std::array::from_fn(|_| {
            let direction = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::X);
            Bump {
                centre: Vec3::new(
                    rng.random_range(0.0..0.35),
                    rng.random_range(-0.4..0.35),
                    rng.random_range(-0.15..0.1),
                ),
                radius: rng.random_range(0.08..0.22),
                offset: direction * rng.random_range(0.0..0.055),
            }
        });
        Identity { scale, bumps }
    }

    /// Whether this is [`Identity::NONE`] (nothing moves).
    #[must_use]
    pub fn is_none(&self) -> bool {
        self.scale == Vec3::ONE && self.bumps.iter().all(|b| b.offset == Vec3::ZERO)
    }

    /// Moves `positions` (world) of a face framed by `face` (the face's middle at its centre's
    /// x, looking along +z) to this person's proportions.
    pub fn apply(&self, face: &FaceFrame, positions: &mut [Vec3]) {
        if self.is_none() {
            return;
        }
        let side = face.side.max(f32::EPSILON);
        let mirror = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        // Per bump, once: its fall-off, and the mirrored bump's centre and offset.
        let bumps = self.bumps.map(|b| {
            (
                -0.5 / (b.radius * b.radius),
                b.centre,
                b.offset,
                mirror(b.centre),
                mirror(b.offset),
            )
        });
        for p in positions {
            let local = (*p - face.centre) / side;
            let mut moved = local * self.scale;
            for &(fall, centre, offset, mirrored, mirrored_offset) in &bumps {
                let near = (local - centre).length_squared();
                let far = (local - mirrored).length_squared();
                moved += offset * (fall * near).exp() + mirrored_offset * (fall * far).exp();
            }
            *p = face.centre + moved * side;
        }
    }
}

/// Where the face is in the world: the centre of the tracker's crop on the face, and the
/// crop's side, both measured on the character's neutral front render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceFrame {
    /// Centre of the crop, on the plane of the face.
    pub centre: Vec3,
    /// Side of the crop, world units.
    pub side: f32,
    /// Distance of the front camera from `centre`.
    pub distance: f32,
    /// How far the head reaches behind `centre`.
    pub depth: f32,
}

/// One group's camera, light and picture quality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Condition {
    /// Unit vector from the face towards the camera.
    pub direction: Vec3,
    /// Camera distance, as a multiple of the front camera's.
    pub distance: f32,
    /// Parallel rays (the crop's side is kept) instead of a perspective lens.
    pub orthographic: bool,
    /// Whose proportions the face has.
    pub identity: Identity,
    /// Tilt left in the crop after levelling, radians.
    pub tilt: f32,
    /// Light, background, albedo, textures.
    pub shading: Shading,
    /// Pixels the face is rendered at before being scaled to the network's 256.
    pub resolution: u32,
    /// Gaussian blur, pixels (of the 256 crop).
    pub blur: f32,
    /// Gaussian noise, in 0..255 units.
    pub noise: f32,
    /// JPEG quality, when the picture is compressed.
    pub jpeg: Option<u8>,
}

/// Per sample: where the crop sits around the face, and how the head has turned since the
/// group's neutral face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jitter {
    /// Offset of the crop's centre, as fractions of its side (right, up).
    pub offset: [f32; 2],
    /// Crop side, as a multiple of the face's.
    pub scale: f32,
    /// The head's turn from the neutral face's, radians: yaw (to the camera's right) and
    /// pitch (up). In a take the neutral frame is one moment and every other frame has its own
    /// head pose; the features are read relative to the neutral across that difference.
    pub turn: [f32; 2],
}

impl Jitter {
    /// No jitter: the crop the neutral face gets.
    pub const NONE: Jitter = Jitter {
        offset: [0.0, 0.0],
        scale: 1.0,
        turn: [0.0, 0.0],
    };

    /// A tracker's crop: a few percent off centre and in size; with `turn`, the head also
    /// turned from the neutral's pose by up to 15° of yaw and 12° of pitch.
    pub fn draw(rng: &mut impl rand::Rng, turn: bool) -> Jitter {
        Jitter {
            offset: [rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)],
            scale: rng.random_range(0.92..1.1),
            turn: if turn {
                [degrees(rng, 15.0), degrees(rng, 12.0)]
            } else {
                [0.0, 0.0]
            },
        }
    }
}

fn degrees(rng: &mut impl rand::Rng, limit: f32) -> f32 {
    rng.random_range(-limit..limit).to_radians()
}

fn colour(rng: &mut impl rand::Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(lo..hi),
        rng.random_range(lo..hi),
        rng.random_range(lo..hi),
    )
}

/// A light's colour: white warmed or cooled, times an intensity drawn from `intensity`.
fn temperature(rng: &mut impl rand::Rng, intensity: std::ops::Range<f32>) -> Vec3 {
    let intensity = rng.random_range(intensity);
    let t = rng.random_range(-1.0f32..1.0);
    Vec3::new(1.0 + 0.18 * t, 1.0, 1.0 - 0.18 * t) * intensity
}

/// A direction from the face: `azimuth` to the right of the camera axis, `elevation` up.
fn direction(azimuth: f32, elevation: f32) -> Vec3 {
    Vec3::new(
        azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    )
}

impl Condition {
    /// The front camera in the studio's light, at full quality.
    #[must_use]
    pub fn canonical() -> Condition {
        Condition {
            direction: Vec3::Z,
            distance: 1.0,
            orthographic: false,
            identity: Identity::NONE,
            tilt: 0.0,
            shading: Shading::default(),
            resolution: 256,
            blur: 0.0,
            noise: 0.0,
            jpeg: None,
        }
    }

    /// A random condition (see the module docs for the ranges).
    pub fn draw(rng: &mut impl rand::Rng) -> Condition {
        let (yaw, pitch, roll) = (degrees(rng, 25.0), degrees(rng, 25.0), degrees(rng, 25.0));
        // The crop is levelled by the eyes: of the roll, a few degrees stay.
        let tilt = roll * 0.15 + degrees(rng, 3.0);
        let key = Light {
            direction: direction(
                degrees(rng, 75.0),
                rng.random_range(-25f32..65.0).to_radians(),
            ),
            colour: temperature(rng, 0.3..1.0),
        };
        let fill = Light {
            direction: direction(degrees(rng, 120.0), degrees(rng, 40.0)),
            colour: temperature(rng, 0.0..0.4),
        };
        let ambient = temperature(rng, 0.06..0.4);
        let background = if rng.random_bool(0.5) {
            Background::Solid(colour(rng, 0.0, 1.0))
        } else {
            Background::Gradient {
                top: colour(rng, 0.0, 1.0),
                bottom: colour(rng, 0.0, 1.0),
            }
        };
        // Lighter and darker skin, a little redder or yellower.
        let albedo = Vec3::new(1.0, rng.random_range(0.82..1.0), rng.random_range(0.7..1.0))
            * rng.random_range(0.45f32..1.15);
        let resolution = if rng.random_bool(0.4) {
            256
        } else {
            rng.random_range(100..256)
        };
        let glossy = rng.random_bool(0.5);
        Condition {
            direction: Quat::from_rotation_y(yaw) * Quat::from_rotation_x(-pitch) * Vec3::Z,
            distance: rng.random_range(0.6f32.ln()..4f32.ln()).exp(),
            orthographic: rng.random_ratio(1, ORTHOGRAPHIC_ONE_IN),
            identity: Identity::draw(rng),
            tilt,
            shading: Shading {
                key,
                fill,
                ambient,
                rim: rng.random_range(0.0..0.4),
                background,
                albedo,
                textures: rng.random_bool(0.75),
                // Small renders are scaled up, where aliasing would show; large ones are
                // softened by the scaling, blur and compression anyway.
                supersample: if resolution >= 160 { 1 } else { 2 },
                faceted: rng.random_bool(0.25),
                specular: if glossy {
                    rng.random_range(0.05..0.5)
                } else {
                    0.0
                },
                shininess: rng.random_range(8.0..64.0),
            },
            resolution,
            blur: if rng.random_bool(0.4) {
                rng.random_range(0.3..1.0)
            } else {
                0.0
            },
            noise: rng.random_range(0.0..4.0),
            jpeg: rng.random_bool(0.5).then(|| rng.random_range(50..95)),
        }
    }

    /// The camera that renders the crop of `face` under this condition with `jitter`: the
    /// face's crop fills the picture, seen from this condition's direction and distance.
    #[must_use]
    pub fn camera(&self, face: &FaceFrame, jitter: Jitter) -> Camera {
        let distance = face.distance * self.distance;
        // The head turning one way is the camera orbiting the other.
        let turn = Quat::from_rotation_y(-jitter.turn[0]) * Quat::from_rotation_x(jitter.turn[1]);
        let direction = (turn * self.direction).normalize_or(Vec3::Z);
        // Up is the world's, tilted about the viewing axis.
        let right = Vec3::Y.cross(direction).normalize_or(Vec3::X);
        let up = direction.cross(right);
        let up = Quat::from_axis_angle(direction, self.tilt) * up;
        let right = up.cross(direction);
        let side = face.side * jitter.scale;
        let target = face.centre + (right * jitter.offset[0] + up * jitter.offset[1]) * face.side;
        let eye = target + direction * distance;
        if self.orthographic {
            return Camera::orthographic(eye, target, up, side, face.depth + face.side);
        }
        let fov = 2.0 * (0.5 * side / distance).atan();
        Camera::looking_at(eye, target, up, fov, face.depth + face.side)
    }

    /// The picture as the network gets it: rendered at this condition's resolution, scaled to
    /// `size`, blurred, noised and JPEG-compressed as drawn; `rng` draws the noise.
    #[must_use]
    pub fn degrade(&self, image: Image, size: u32, rng: &mut impl rand::Rng) -> Image {
        let mut image = if image.width == size {
            image
        } else {
            resize(&image, size)
        };
        if self.blur > 0.0 {
            blur(&mut image, self.blur);
        }
        if self.noise > 0.0 {
            for v in &mut image.rgb {
                // Nearly normal: the sum of four uniform numbers (one 64-bit draw), centred and
                // scaled to unit deviation — far cheaper than Box–Muller per channel.
                let bits: u64 = rng.random();
                let sum: f32 = (0..4)
                    .map(|k| f32::from((bits >> (16 * k)) as u16) / 65535.0)
                    .sum();
                let n = (sum - 2.0) * 3f32.sqrt();
                *v = to_byte(f32::from(*v) + n * self.noise);
            }
        }
        if let Some(quality) = self.jpeg
            && let Some(decoded) = jpeg_round_trip(&image, quality)
        {
            image = decoded;
        }
        image
    }
}

/// A channel value rounded and clamped to a byte.
fn to_byte(v: f32) -> u8 {
    // `as` saturates: negative values give 0, large ones 255.
    (v + 0.5) as u8
}

/// Bilinear scaling of a square picture to `size`×`size`.
#[must_use]
pub fn resize(image: &Image, size: u32) -> Image {
    let (w, h) = (image.width as usize, image.height as usize);
    // Where each output column and row reads: the two source pixels and the blend between them
    // (the same for every row and column, so worked out once).
    let taps = |n: usize| -> Vec<(usize, usize, f32)> {
        let scale = n as f32 / size as f32;
        (0..size as usize)
            .map(|i| {
                let f = ((i as f32 + 0.5) * scale - 0.5).clamp(0.0, (n - 1) as f32);
                let i0 = f as usize; // not negative: truncation is the floor
                (i0, (i0 + 1).min(n - 1), f - i0 as f32)
            })
            .collect()
    };
    let (columns, rows) = (taps(w), taps(h));
    let mut rgb = Vec::with_capacity((size * size * 3) as usize);
    for &(y0, y1, ty) in &rows {
        let (top, bottom) = (&image.rgb[y0 * w * 3..], &image.rgb[y1 * w * 3..]);
        for &(x0, x1, tx) in &columns {
            for c in 0..3 {
                let at = |row: &[u8], x: usize| f32::from(row[x * 3 + c]);
                let upper = at(top, x0) * (1.0 - tx) + at(top, x1) * tx;
                let lower = at(bottom, x0) * (1.0 - tx) + at(bottom, x1) * tx;
                rgb.push(to_byte(upper * (1.0 - ty) + lower * ty));
            }
        }
    }
    Image {
        width: size,
        height: size,
        rgb,
    }
}

/// Separable Gaussian blur of standard deviation `sigma` pixels, edges clamped.
pub fn blur(image: &mut Image, sigma: f32) {
    let radius = (2.0 * sigma).ceil() as usize;
    let mut kernel: Vec<f32> = (0..=2 * radius)
        .map(|k| {
            let d = k as f32 - radius as f32;
            (-d * d / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let total: f32 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= total);
    let (w, h) = (image.width as usize, image.height as usize);
    let row_len = w * 3;
    // Across: each row, padded with its edge pixels, convolved.
    let mut across = vec![0.0f32; w * h * 3];
    let mut padded = vec![0.0f32; (w + 2 * radius) * 3];
    for y in 0..h {
        let row = &image.rgb[y * row_len..(y + 1) * row_len];
        for (x, p) in padded.chunks_exact_mut(3).enumerate() {
            let source = x.saturating_sub(radius).min(w - 1) * 3;
            for c in 0..3 {
                p[c] = f32::from(row[source + c]);
            }
        }
        let out = &mut across[y * row_len..(y + 1) * row_len];
        for (k, &weight) in kernel.iter().enumerate() {
            for (o, &v) in out.iter_mut().zip(&padded[k * 3..]) {
                *o += weight * v;
            }
        }
    }
    // Down: each output row a weighted sum of whole rows, the edge rows repeated.
    let mut row = vec![0.0f32; row_len];
    for y in 0..h {
        row.iter_mut().for_each(|v| *v = 0.0);
        for (k, &weight) in kernel.iter().enumerate() {
            let source = (y + k).saturating_sub(radius).min(h - 1);
            for (o, &v) in row
                .iter_mut()
                .zip(&across[source * row_len..(source + 1) * row_len])
            {
                *o += weight * v;
            }
        }
        for (out, &v) in image.rgb[y * row_len..(y + 1) * row_len]
            .iter_mut()
            .zip(&row)
        {
            *out = to_byte(v);
        }
    }
}

/// The picture after a JPEG encoding at `quality` and decoding; `None` if either fails.
fn jpeg_round_trip(image: &Image, quality: u8) -> Option<Image> {
    let mut bytes = Vec::new();
    jpeg_encoder::Encoder::new(&mut bytes, quality)
        .encode(
            &image.rgb,
            u16::try_from(image.width).ok()?,
            u16::try_from(image.height).ok()?,
            jpeg_encoder::ColorType::Rgb,
        )
        .ok()?;
    let decoded =
        faceanim_media::decode_image(std::path::Path::new("augmented.jpg"), &bytes).ok()?;
    (decoded.width == image.width as usize && decoded.height == image.height as usize).then_some(
        Image {
            width: image.width,
            height: image.height,
            rgb: decoded.rgb,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng as _;

    #[test]
    fn conditions_stay_in_their_ranges() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..500 {
            let c = Condition::draw(&mut rng);
            let off_axis = c.direction.angle_between(Vec3::Z).to_degrees();
            assert!(off_axis <= 36.0, "{off_axis}");
            assert!((0.6..=4.0).contains(&c.distance));
            assert!(c.tilt.abs().to_degrees() <= 7.0);
            assert!((100..=256).contains(&c.resolution));
        }
    }

    /// A face's crop 25 cm across, 80 cm from the front camera.
    fn face() -> FaceFrame {
        FaceFrame {
            centre: Vec3::new(0.1, 1.6, 0.05),
            side: 0.25,
            distance: 0.8,
            depth: 0.2,
        }
    }

    #[test]
    fn the_crop_camera_centres_the_face() {
        let face = face();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let c = Condition::draw(&mut rng);
            for orthographic in [false, true] {
                let c = Condition { orthographic, ..c };
                let camera = c.camera(&face, Jitter::NONE);
                let centre = camera.view_projection.project_point3(face.centre);
                assert!(centre.x.abs() < 1e-3 && centre.y.abs() < 1e-3, "{centre}");
                // The crop's side fills the picture.
                let right = Vec3::Y.cross(c.direction).normalize();
                let edge = camera
                    .view_projection
                    .project_point3(face.centre + right * face.side * 0.5);
                let reach = edge.truncate().length();
                assert!(reach > 0.8 && reach < 1.2, "{edge}");
            }
        }
    }

    #[test]
    fn an_identity_is_smooth_symmetric_and_face_sized() {
        let face = face();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        // A grid over the face and its mirror image across the face's middle.
        let grid: Vec<Vec3> = (0..11)
            .flat_map(|i| (0..11).map(move |j| (i, j)))
            .map(|(i, j)| {
                face.centre
                    + Vec3::new(i as f32 / 10.0 * 0.5, j as f32 / 10.0 - 0.5, 0.0) * face.side
            })
            .collect();
        let mirror = |p: Vec3| Vec3::new(2.0 * face.centre.x - p.x, p.y, p.z);
        for _ in 0..20 {
            let identity = Identity::draw(&mut rng);
            let (mut moved, mut mirrored) = (
                grid.clone(),
                grid.iter().map(|&p| mirror(p)).collect::<Vec<_>>(),
            );
            identity.apply(&face, &mut moved);
            identity.apply(&face, &mut mirrored);
            for ((p, m), q) in moved.iter().zip(&mirrored).zip(&grid) {
                // Symmetric: the mirror of a point goes to the mirror of where it went.
                assert!(mirror(*p).distance(*m) < 1e-5, "{p} {m}");
                // Face-sized: nothing moves by more than a fifth of the face.
                assert!(p.distance(*q) < 0.2 * face.side, "{p} {q}");
            }
        }
        let mut same = grid.clone();
        Identity::NONE.apply(&face, &mut same);
        assert_eq!(same, grid);
    }

    #[test]
    fn degrading_keeps_the_size_and_roughly_the_picture() {
        let mut image = Image::filled(120, 120, [200, 120, 80]);
        image.rgb[3 * (60 * 120 + 60)] = 0;
        let condition = Condition {
            resolution: 120,
            blur: 1.0,
            noise: 3.0,
            jpeg: Some(60),
            ..Condition::canonical()
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let out = condition.degrade(image, 256, &mut rng);
        assert_eq!(
            (out.width, out.height, out.rgb.len()),
            (256, 256, 256 * 256 * 3)
        );
        let mean_red = out
            .rgb
            .iter()
            .step_by(3)
            .map(|&v| f32::from(v))
            .sum::<f32>()
            / (256.0 * 256.0);
        assert!((mean_red - 200.0).abs() < 6.0, "{mean_red}");
    }
}
