//! # faceanim-render: pictures of a character without a GPU
//!
//! A small deterministic software rasteriser: the character at given weights, seen by a front
//! camera that frames its head, lit by a key, a fill and a rim light with Gouraud shading over
//! vertex colours, material base colours and base-colour textures, anti-aliased by
//! supersampling. It runs on machines with no GPU and no display, and the same inputs give the
//! same bytes. [`Camera::cropped`] narrows a camera to a square of its picture, so a face crop
//! can be rendered directly at the size a network wants. On top of it, [`contact_sheet`] lays
//! out the neutral face and every blendshape at weight 1, labelled.
#![deny(missing_docs)]

use faceanim_rig::{Aabb, Character, Pose};
use glam::{Mat4, Vec3, Vec4};

/// An RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height × 3` bytes.
    pub rgb: Vec<u8>,
}

/// Why an image could not be encoded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
}

impl Image {
    /// A blank image of one colour.
    #[must_use]
    pub fn filled(width: u32, height: u32, colour: [u8; 3]) -> Image {
        Image {
            width,
            height,
            rgb: colour.repeat((width * height) as usize),
        }
    }

    /// The image as PNG bytes.
    ///
    /// # Errors
    /// [`RenderError::Png`] if encoding fails.
    pub fn to_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.rgb)?;
        writer.finish()?;
        Ok(out)
    }

    /// Copies `other` into this image with its top-left corner at (`x`, `y`).
    pub fn blit(&mut self, other: &Image, x: u32, y: u32) {
        for row in 0..other.height {
            let ty = y + row;
            if ty >= self.height {
                break;
            }
            for col in 0..other.width {
                let tx = x + col;
                if tx >= self.width {
                    break;
                }
                let s = ((row * other.width + col) * 3) as usize;
                let d = ((ty * self.width + tx) * 3) as usize;
                self.rgb[d..d + 3].copy_from_slice(&other.rgb[s..s + 3]);
            }
        }
    }

    /// Writes `text` with an 8×8 pixel font scaled by `scale`, top-left at (`x`, `y`).
    pub fn text(&mut self, text: &str, x: u32, y: u32, scale: u32, colour: [u8; 3]) {
        use font8x8::UnicodeFonts as _;
        for (k, ch) in text.chars().enumerate() {
            let glyph = font8x8::BASIC_FONTS
                .get(ch)
                .or_else(|| font8x8::BASIC_FONTS.get('?'))
                .unwrap_or([0; 8]);
            let gx = x + k as u32 * 8 * scale;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8u32 {
                    if bits & (1 << col) == 0 {
                        continue;
                    }
                    for dy in 0..scale {
                        for dx in 0..scale {
                            let px = gx + col * scale + dx;
                            let py = y + row as u32 * scale + dy;
                            if px < self.width && py < self.height {
                                let d = ((py * self.width + px) * 3) as usize;
                                self.rgb[d..d + 3].copy_from_slice(&colour);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Where the camera looks from: the front, framing the character's bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// World to clip space.
    pub view_projection: Mat4,
    /// Camera position (for the rim light).
    pub eye: Vec3,
}

impl Camera {
    /// A camera in front of the character (+Z, glTF's facing direction) with a 30° vertical field
    /// of view, looking at the upper part of its bounds (the face of a head-and-neck model) and
    /// far enough to fit `framing` of the height.
    #[must_use]
    pub fn front(bounds: &Aabb, framing: f32) -> Camera {
        let size = bounds.max - bounds.min;
        let target = Vec3::new(
            bounds.center().x,
            bounds.min.y + 0.58 * size.y,
            bounds.center().z,
        );
        let half_height = 0.5 * size.y.max(size.x) * framing;
        let fov = 30f32.to_radians();
        let distance = half_height / (0.5 * fov).tan() + 0.5 * size.z;
        let eye = target + Vec3::new(0.0, 0.0, distance);
        let view = Mat4::look_at_rh(eye, target, Vec3::Y);
        let projection = Mat4::perspective_rh_gl(fov, 1.0, distance * 0.05, distance * 4.0);
        Camera {
            view_projection: projection * view,
            eye,
        }
    }

    /// A square-picture camera at `eye` looking at `target` with `up` roughly up and a vertical
    /// field of view of `fov` radians; `depth` is how far behind the target the scene reaches.
    #[must_use]
    pub fn looking_at(eye: Vec3, target: Vec3, up: Vec3, fov: f32, depth: f32) -> Camera {
        Camera::aimed(
            eye,
            target,
            up,
            |near, far| Mat4::perspective_rh_gl(fov, 1.0, near, far),
            depth,
        )
    }

    /// A camera at `eye` looking at `target`, `projection(near, far)` its lens, seeing from a
    /// twentieth of the distance to `depth` behind the target.
    fn aimed(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        projection: impl Fn(f32, f32) -> Mat4,
        depth: f32,
    ) -> Camera {
        let distance = (target - eye).length().max(f32::EPSILON);
        let view = Mat4::look_at_rh(eye, target, up);
        Camera {
            view_projection: projection(distance * 0.05, distance + depth) * view,
            eye,
        }
    }

    /// A square-picture orthographic camera (parallel rays: an infinitely long lens) at `eye`
    /// looking at `target` with `up` roughly up, seeing a square of `side` world units around
    /// the target; `depth` is how far behind the target the scene reaches.
    #[must_use]
    pub fn orthographic(eye: Vec3, target: Vec3, up: Vec3, side: f32, depth: f32) -> Camera {
        let half = 0.5 * side;
        Camera::aimed(
            eye,
            target,
            up,
            |near, far| Mat4::orthographic_rh_gl(-half, half, -half, half, near, far),
            depth,
        )
    }

    /// The ray through pixel (`x`, `y`) of a `size`×`size` picture: where it leaves the near
    /// plane, and its unit direction into the scene; `None` if the camera cannot be inverted.
    #[must_use]
    pub fn ray(&self, size: f32, x: f32, y: f32) -> Option<(Vec3, Vec3)> {
        let inverse = self.view_projection.inverse();
        if !inverse.is_finite() {
            return None;
        }
        let (nx, ny) = (2.0 * x / size - 1.0, 1.0 - 2.0 * y / size);
        let near = inverse.project_point3(Vec3::new(nx, ny, -1.0));
        let far = inverse.project_point3(Vec3::new(nx, ny, 1.0));
        Some((near, (far - near).normalize_or_zero()))
    }

    /// The point of the world seen at pixel (`x`, `y`) of a `size`×`size` picture, on the plane
    /// through `on` facing the camera; `None` if the camera cannot be inverted.
    #[must_use]
    pub fn unproject(&self, size: f32, x: f32, y: f32, on: Vec3) -> Option<Vec3> {
        let (near, direction) = self.ray(size, x, y)?;
        let normal = (self.eye - on).normalize_or_zero();
        let along = direction.dot(normal);
        if along.abs() < 1e-6 {
            return None;
        }
        let t = (on - near).dot(normal) / along;
        Some(near + direction * t)
    }

    /// This camera narrowed to a square of its `size`×`size` picture: centre (`cx`, `cy`) and
    /// side `side` in pixels, turned by `rotation` radians (clockwise on screen, about the
    /// centre). Rendering the result at any size gives that square, upright, as if cut out of
    /// a full render and resampled.
    #[must_use]
    pub fn cropped(&self, size: f32, cx: f32, cy: f32, side: f32, rotation: f32) -> Camera {
        // In normalised device coordinates (y up) the square's centre, half side and axes.
        let centre = glam::Vec2::new(2.0 * cx / size - 1.0, 1.0 - 2.0 * cy / size);
        let half = side / size;
        let (sin, cos) = rotation.sin_cos();
        // The crop's x axis runs along (cos, sin) on screen (y down), (cos, −sin) with y up;
        // its y axis (up) is perpendicular to it.
        let x_axis = glam::Vec2::new(cos, -sin);
        let y_axis = glam::Vec2::new(sin, cos);
        // Acting on clip coordinates (x, y, z, w): x' = x_axis · ((x, y) − centre·w) / half.
        let crop = Mat4::from_cols(
            Vec4::new(x_axis.x / half, y_axis.x / half, 0.0, 0.0),
            Vec4::new(x_axis.y / half, y_axis.y / half, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 1.0, 0.0),
            Vec4::new(
                -x_axis.dot(centre) / half,
                -y_axis.dot(centre) / half,
                0.0,
                1.0,
            ),
        );
        Camera {
            view_projection: crop * self.view_projection,
            eye: self.eye,
        }
    }
}

/// A decoded base-colour texture, sRGB bytes.
#[derive(Debug, Clone)]
struct Texels {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
    /// Per texel, its alpha, for a material that cuts out by it (`None`: opaque).
    alpha: Option<Vec<u8>>,
    /// The alpha below which nothing is drawn: the material's `MASK` cutoff (a `BLEND`
    /// material is drawn where its alpha is at least a half).
    cutoff: f32,
}

impl Texels {
    /// Whether the texel nearest (`u`, `v`) is cut out.
    fn cut(&self, u: f32, v: f32) -> bool {
        let Some(alpha) = &self.alpha else {
            return false;
        };
        let x = ((u.rem_euclid(1.0) * self.width as f32) as usize).min(self.width - 1);
        let y = ((v.rem_euclid(1.0) * self.height as f32) as usize).min(self.height - 1);
        f32::from(alpha[y * self.width + x]) < self.cutoff * 255.0
    }

    /// Bilinear sample at (`u`, `v`) with glTF's repeat wrapping, in display (sRGB) space, 0..1.
    fn sample(&self, u: f32, v: f32) -> Vec3 {
        let x = u.rem_euclid(1.0) * self.width as f32 - 0.5;
        let y = v.rem_euclid(1.0) * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let wrap = |i: f32, n: usize| (i as i64).rem_euclid(n as i64) as usize;
        let mut sum = Vec3::ZERO;
        for (dx, dy, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let i = (wrap(y0 + dy, self.height) * self.width + wrap(x0 + dx, self.width)) * 3;
            let t = &self.rgb[i..i + 3];
            sum += w * Vec3::new(f32::from(t[0]), f32::from(t[1]), f32::from(t[2]));
        }
        sum / 255.0
    }
}

/// How a character looks to the renderer: vertex colours, and per triangle its material's
/// base colour and decoded base-colour texture. Built once per character (decoding textures is
/// the slow part), then shared by every frame.
#[derive(Debug, Clone)]
pub struct Appearance {
    /// Linear vertex colours (white where the character has none).
    vertex_colours: Vec<Vec3>,
    /// Per material: `base_color^(1/2.2)`, the factor in display space.
    material_factors: Vec<Vec3>,
    /// Per material: its texture, when it has one that decoded.
    textures: Vec<Option<Texels>>,
    /// Per triangle: its material.
    triangle_materials: Vec<u32>,
    /// Textures that could not be used, with why (the material then shows its base colour).
    warnings: Vec<String>,
}

impl Appearance {
    /// Gathers the character's colours and decodes its textures.
    #[must_use]
    pub fn of(character: &Character) -> Appearance {
        let vertex_colours = match character.colors() {
            Some(c) => c.iter().map(|c| Vec3::new(c[0], c[1], c[2])).collect(),
            None => vec![Vec3::ONE; character.vertex_count()],
        };
        let mut warnings = Vec::new();
        let uvs = character.uvs();
        let mut textures = Vec::with_capacity(character.materials().len());
        let mut material_factors = Vec::with_capacity(character.materials().len());
        for (index, material) in character.materials().iter().enumerate() {
            let [r, g, b, _] = material.base_color;
            material_factors.push(Vec3::new(r, g, b).max(Vec3::ZERO).powf(1.0 / 2.2));
            let label = if material.name.is_empty() {
                format!("material {index}")
            } else {
                format!("material '{}'", material.name)
            };
            let texels = material.base_color_texture.as_ref().and_then(|texture| {
                if uvs.is_none() {
                    warnings.push(format!(
                        "{label}: base-colour texture ignored, the mesh has no TEXCOORD_0"
                    ));
                    return None;
                }
                let name = std::path::PathBuf::from(format!("{label} base-colour texture"));
                // Lashes, brows and hair cards cut out by their alpha, as the material says.
                let cutoff = match material.alpha {
                    faceanim_rig::AlphaMode::Opaque => None,
                    faceanim_rig::AlphaMode::Mask { cutoff } => Some(cutoff),
                    faceanim_rig::AlphaMode::Blend => Some(0.5),
                };
                match faceanim_media::decode_image_alpha(&name, &texture.bytes) {
                    Ok((image, alpha)) => Some(Texels {
                        width: image.width,
                        height: image.height,
                        rgb: image.rgb,
                        alpha: alpha.filter(|_| cutoff.is_some()),
                        cutoff: cutoff.unwrap_or(0.0),
                    }),
                    Err(error) => {
                        warnings.push(format!("{error}; showing its base colour instead"));
                        None
                    }
                }
            });
            textures.push(texels);
        }
        let mut triangle_materials = vec![0; character.triangles().len()];
        for part in character.parts() {
            triangle_materials[part.triangles.clone()].fill(part.material.0);
        }
        Appearance {
            vertex_colours,
            material_factors,
            textures,
            triangle_materials,
            warnings,
        }
    }

    /// Textures that could not be decoded or mapped, each naming its material.
    #[must_use]
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// A light: the direction it comes from (towards the light, world space) and its colour
/// times intensity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Unit vector from the surface towards the light.
    pub direction: Vec3,
    /// Linear colour times intensity.
    pub colour: Vec3,
}

/// What fills the picture behind the character.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Background {
    /// One colour (display space, 0..1).
    Solid(Vec3),
    /// A vertical blend from `top` to `bottom` (display space).
    Gradient {
        /// Colour of the top row.
        top: Vec3,
        /// Colour of the bottom row.
        bottom: Vec3,
    },
}

/// How a picture is lit and coloured: a key and a fill light, ambient light, a rim term, the
/// background, a tint multiplying the character's colours (its albedo) and whether its
/// textures are used. [`Shading::default`] is the studio look every picture had before.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shading {
    /// The main light.
    pub key: Light,
    /// The secondary light.
    pub fill: Light,
    /// Light reaching every surface.
    pub ambient: Vec3,
    /// Strength of the grazing-angle rim term.
    pub rim: f32,
    /// Behind the character.
    pub background: Background,
    /// Multiplies vertex colours, material colours and textures (linear).
    pub albedo: Vec3,
    /// Whether base-colour textures are drawn (off: their material's colour).
    pub textures: bool,
    /// Samples per pixel along each axis (anti-aliasing; 1 is fastest, 2 the default).
    pub supersample: u32,
    /// Flat shading: each triangle lit by its own normal at its centre (a faceted look, as
    /// some renderers and exporters give), instead of normals interpolated between vertices.
    pub faceted: bool,
    /// Strength of a Blinn–Phong highlight from the key light (0: matte, the default).
    pub specular: f32,
    /// The highlight's exponent (larger: smaller, sharper highlights).
    pub shininess: f32,
}

impl Default for Shading {
    fn default() -> Shading {
        Shading {
            key: Light {
                direction: Vec3::new(-0.4, 0.55, 0.75).normalize(),
                colour: Vec3::splat(0.75),
            },
            fill: Light {
                direction: Vec3::new(0.6, 0.1, 0.5).normalize(),
                colour: Vec3::splat(0.25),
            },
            ambient: Vec3::splat(0.22),
            rim: 0.25,
            background: Background::Solid(Vec3::new(0.16, 0.17, 0.19)),
            albedo: Vec3::ONE,
            textures: true,
            supersample: 2,
            faceted: false,
            specular: 0.0,
            shininess: 32.0,
        }
    }
}

impl Shading {
    /// The lit colour, in display space, of a surface point at `p` with unit normal `n` and
    /// colour `c` (linear), seen from `eye`.
    fn light(&self, p: Vec3, n: Vec3, c: Vec3, eye: Vec3) -> Vec3 {
        let view = (eye - p).normalize_or_zero();
        let rim = (1.0 - n.dot(view).max(0.0)).powi(3) * self.rim;
        let (key, fill) = (self.key, self.fill);
        let diffuse = self.ambient
            + key.colour * n.dot(key.direction).max(0.0)
            + fill.colour * n.dot(fill.direction).max(0.0)
            + Vec3::splat(rim);
        let mut linear = c * self.albedo * diffuse;
        if self.specular > 0.0 {
            let half = (key.direction + view).normalize_or_zero();
            let facing = n.dot(key.direction) > 0.0;
            if facing {
                linear += key.colour * self.specular * n.dot(half).max(0.0).powf(self.shininess);
            }
        }
        let linear = linear.max(Vec3::ZERO);
        Vec3::new(display(linear.x), display(linear.y), display(linear.z))
    }
}

/// Entries of the display-gamma table, over linear values 0 to [`GAMMA_RANGE`].
const GAMMA_STEPS: usize = 4096;
/// The largest linear value the table covers (lights add up past 1; the picture is clamped
/// to 1 after textures and material colours multiply in).
const GAMMA_RANGE: f32 = 4.0;

/// `linear^(1/2.2)`, from a table with linear interpolation (within 2e-4 of `powf` above 0.01,
/// and several times faster: the renderer's per-vertex cost was mostly this).
fn display(linear: f32) -> f32 {
    static TABLE: std::sync::LazyLock<Vec<f32>> = std::sync::LazyLock::new(|| {
        (0..=GAMMA_STEPS)
            .map(|k| (k as f32 * GAMMA_RANGE / GAMMA_STEPS as f32).powf(1.0 / 2.2))
            .collect()
    });
    let x = (linear.clamp(0.0, GAMMA_RANGE) / GAMMA_RANGE) * GAMMA_STEPS as f32;
    let k = (x as usize).min(GAMMA_STEPS - 1);
    let t = x - k as f32;
    TABLE[k] * (1.0 - t) + TABLE[k + 1] * t
}

/// The first and last of `count` pixels whose centres (i + ½) lie in `[low, high]`, or `None`
/// when there are none. Casts, not `floor`/`ceil` (library calls on x86-64's baseline): `as`
/// saturates, and truncation is the floor of a value that is not negative.
fn centres_between(low: f32, high: f32, count: u32) -> Option<(u32, u32)> {
    let (low, high) = (low - 0.5, high - 0.5);
    if high < 0.0 || low.is_nan() || high.is_nan() {
        return None;
    }
    let low = low.max(0.0);
    let first = low as u32 + u32::from((low as u32 as f32) < low);
    let last = (high as u32).min(count - 1);
    (first <= last).then_some((first, last))
}

/// Renders `pose` of `character` at `size`×`size` pixels, in the studio's light.
#[must_use]
pub fn render(
    character: &Character,
    pose: &Pose,
    camera: &Camera,
    appearance: &Appearance,
    size: u32,
) -> Image {
    render_shaded(
        character,
        pose,
        camera,
        appearance,
        &Shading::default(),
        size,
    )
}

/// Renders `pose` of `character` at `size`×`size` pixels, lit and coloured by `shading`.
#[must_use]
pub fn render_shaded(
    character: &Character,
    pose: &Pose,
    camera: &Camera,
    appearance: &Appearance,
    shading: &Shading,
    size: u32,
) -> Image {
    let supersample = shading.supersample.clamp(1, 4);
    let s = size * supersample;
    let mut colour = Vec::with_capacity((s * s) as usize);
    for y in 0..s {
        let row = match shading.background {
            Background::Solid(c) => c,
            Background::Gradient { top, bottom } => top.lerp(bottom, (y as f32 + 0.5) / s as f32),
        };
        colour.extend(std::iter::repeat_n(row, s as usize));
    }
    let mut depth = vec![f32::INFINITY; (s * s) as usize];
    // Lit vertex colour in display space; material factors and textures multiply it there
    // (sRGB is close enough to a 2.2 gamma that this equals shading the product in linear).
    let shade: Vec<Vec3> = if shading.faceted {
        Vec::new()
    } else {
        pose.positions
            .iter()
            .zip(&pose.normals)
            .zip(&appearance.vertex_colours)
            .map(|((p, n), c)| shading.light(*p, *n, *c, camera.eye))
            .collect()
    };
    let screen: Vec<Vec4> = pose
        .positions
        .iter()
        .map(|p| {
            let clip = camera.view_projection * p.extend(1.0);
            let ndc = clip / clip.w;
            Vec4::new(
                (ndc.x * 0.5 + 0.5) * s as f32,
                (0.5 - ndc.y * 0.5) * s as f32,
                ndc.z,
                clip.w,
            )
        })
        .collect();
    let uvs = character.uvs();

    for (t, tri) in character.triangles().iter().enumerate() {
        let [a, b, c] = tri.map(|v| v as usize);
        let (pa, pb, pc) = (screen[a], screen[b], screen[c]);
        if pa.w <= 0.0 || pb.w <= 0.0 || pc.w <= 0.0 {
            continue;
        }
        let area = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
        // Counter-clockwise in the world is clockwise here (y points down): cull back faces.
        if area >= 0.0 {
            continue;
        }
        let inverse_area = 1.0 / area;
        let material = appearance.triangle_materials[t] as usize;
        let factor = appearance
            .material_factors
            .get(material)
            .copied()
            .unwrap_or(Vec3::ONE);
        let texture = appearance
            .textures
            .get(material)
            .and_then(Option::as_ref)
            .filter(|_| shading.textures)
            .zip(uvs);
        // The pixels whose centres lie in the triangle's box; most triangles of a detailed
        // head are smaller than a pixel and have none.
        let Some((min_x, max_x)) =
            centres_between(pa.x.min(pb.x).min(pc.x), pa.x.max(pb.x).max(pc.x), s)
        else {
            continue;
        };
        let Some((min_y, max_y)) =
            centres_between(pa.y.min(pb.y).min(pc.y), pa.y.max(pb.y).max(pc.y), s)
        else {
            continue;
        };
        // Flat shading: one colour for the whole triangle, from its own normal at its centre
        // (worked out only for triangles that cover a pixel).
        let flat = shading.faceted.then(|| {
            let [wa, wb, wc] = [a, b, c].map(|v| pose.positions[v]);
            let normal = (wb - wa).cross(wc - wa).normalize_or_zero();
            let colour = (appearance.vertex_colours[a]
                + appearance.vertex_colours[b]
                + appearance.vertex_colours[c])
                / 3.0;
            shading.light((wa + wb + wc) / 3.0, normal, colour, camera.eye)
        });
        // Barycentric weights step by a constant from one pixel to the next in a row.
        let (step0, step1) = ((pb.y - pc.y) * inverse_area, (pc.y - pa.y) * inverse_area);
        for y in min_y..=max_y {
            let (px, py) = (min_x as f32 + 0.5, y as f32 + 0.5);
            let mut w0 = ((pb.x - px) * (pc.y - py) - (pb.y - py) * (pc.x - px)) * inverse_area;
            let mut w1 = ((pc.x - px) * (pa.y - py) - (pc.y - py) * (pa.x - px)) * inverse_area;
            let mut entered = false;
            for x in min_x..=max_x {
                let (u0, u1) = (w0, w1);
                w0 += step0;
                w1 += step1;
                let w2 = 1.0 - u0 - u1;
                if u0 < 0.0 || u1 < 0.0 || w2 < 0.0 {
                    if entered {
                        break; // a triangle's row is one run of pixels
                    }
                    continue;
                }
                entered = true;
                let (w0, w1) = (u0, u1);
                let z = w0 * pa.z + w1 * pb.z + w2 * pc.z;
                let i = (y * s + x) as usize;
                if z < depth[i] {
                    // Perspective-correct texture coordinates: uv/w and 1/w interpolated in
                    // screen space.
                    let uv = texture.map(|(texels, uvs)| {
                        let (qa, qb, qc) = (w0 / pa.w, w1 / pb.w, w2 / pc.w);
                        let q = qa + qb + qc;
                        let (ua, ub, uc) = (uvs[a], uvs[b], uvs[c]);
                        let u = (qa * ua[0] + qb * ub[0] + qc * uc[0]) / q;
                        let v = (qa * ua[1] + qb * ub[1] + qc * uc[1]) / q;
                        (texels, u, v)
                    });
                    if uv.is_some_and(|(texels, u, v)| texels.cut(u, v)) {
                        continue; // cut out: what is behind shows through
                    }
                    depth[i] = z;
                    let lit = flat.unwrap_or_else(|| shade[a] * w0 + shade[b] * w1 + shade[c] * w2);
                    colour[i] = match uv {
                        None => lit * factor,
                        Some((texels, u, v)) => lit * factor * texels.sample(u, v),
                    };
                }
            }
        }
    }

    let mut rgb = Vec::with_capacity((size * size * 3) as usize);
    for y in 0..size {
        for x in 0..size {
            let mut sum = Vec3::ZERO;
            for dy in 0..supersample {
                for dx in 0..supersample {
                    sum += colour[((y * supersample + dy) * s + x * supersample + dx) as usize];
                }
            }
            let c = (sum / (supersample * supersample) as f32).clamp(Vec3::ZERO, Vec3::ONE) * 255.0
                + Vec3::splat(0.5);
            // Rounded by truncating the value plus a half (it is not negative): no libm call.
            rgb.extend_from_slice(&[c.x as u8, c.y as u8, c.z as u8]);
        }
    }
    Image {
        width: size,
        height: size,
        rgb,
    }
}

/// The neutral face and every blendshape at weight 1, in a labelled grid.
#[must_use]
pub fn contact_sheet(character: &Character, cell: u32) -> Image {
    let count = character.blendshapes().len() + 1;
    let columns = (count as f32).sqrt().ceil() as u32;
    let rows = (count as u32).div_ceil(columns);
    let label_height = 20;
    let mut sheet = Image::filled(columns * cell, rows * (cell + label_height), [24, 25, 28]);
    let camera = Camera::front(&character.head_bounds(), 0.75);
    let appearance = Appearance::of(character);
    let mut weights = vec![0.0; character.blendshapes().len()];
    let mut pose = Pose::default();
    for k in 0..count {
        weights.iter_mut().for_each(|w| *w = 0.0);
        let label = if k == 0 {
            "neutral".to_owned()
        } else {
            weights[k - 1] = 1.0;
            character.blendshapes()[k - 1].name().to_owned()
        };
        character.pose_into(&weights, &mut pose);
        let image = render(character, &pose, &camera, &appearance, cell);
        let (x, y) = (
            (k as u32 % columns) * cell,
            (k as u32 / columns) * (cell + label_height),
        );
        sheet.blit(&image, x, y);
        let max_chars = (cell / 8).max(1) as usize;
        let shown: String = label.chars().take(max_chars).collect();
        sheet.text(&shown, x + 2, y + cell + 6, 1, [230, 230, 230]);
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gamma_table_is_powf_within_a_hair() {
        for k in 1..=4000 {
            let x = k as f32 / 1000.0;
            let exact = x.powf(1.0 / 2.2);
            assert!(
                (display(x) - exact).abs() < 2e-4,
                "{x}: {} vs {exact}",
                display(x)
            );
        }
        assert!(display(-1.0).abs() < 1e-9);
        assert!((display(9.0) - GAMMA_RANGE.powf(1.0 / 2.2)).abs() < 1e-5);
    }

    #[test]
    fn unprojecting_a_projected_point_finds_it_again() {
        let camera = Camera::looking_at(
            Vec3::new(0.3, 1.7, 0.9),
            Vec3::new(0.0, 1.6, 0.0),
            Vec3::Y,
            40f32.to_radians(),
            0.5,
        );
        let point = Vec3::new(0.05, 1.63, 0.02);
        let ndc = camera.view_projection.project_point3(point);
        let (x, y) = ((ndc.x + 1.0) * 128.0, (1.0 - ndc.y) * 128.0);
        let found = camera.unproject(256.0, x, y, point).unwrap();
        assert!(found.distance(point) < 1e-4, "{found} vs {point}");
    }
}
