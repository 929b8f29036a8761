//! The face on the mesh: the character rendered neutral from the front, MediaPipe's 478 face
//! landmarks found on the render, and each landmark's pixel followed back along the camera's
//! ray to the first triangle it meets.

use faceanim_render::{Appearance, Camera};
use faceanim_rig::{Aabb, Character};
use faceanim_track::{FaceModels, Frame};
use glam::Vec3;

use crate::FitError;

/// The render's side in pixels: the landmark model reads a 256-pixel crop of the face, which
/// at this size is well inside the picture.
const RENDER: u32 = 512;

/// Landmarks that lie on skin on every face: nose tip and bridge, forehead, chin, cheeks,
/// mouth corners, brows.
const SKIN: [usize; 12] = [1, 4, 10, 152, 234, 454, 61, 291, 105, 334, 50, 280];
/// The first iris landmark: those from here on lie on the eyes.
pub(crate) const IRISES: usize = 468;
/// A face found on a front render turned or tilted further than this (degrees) is no face
/// looking along +Z.
const UPRIGHT_DEGREES: f32 = 40.0;

/// A point on a character's surface: a triangle and barycentric weights of its corners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Index into [`Character::triangles`].
    pub triangle: u32,
    /// Weights of the triangle's three vertices (sum 1).
    pub weights: [f32; 3],
}

impl SurfacePoint {
    /// The point on `positions` (the character's or a deformed copy), or the same weights
    /// applied to other per-vertex values (a blendshape's deltas).
    #[must_use]
    pub fn on(&self, triangles: &[[u32; 3]], positions: &[Vec3]) -> Vec3 {
        let t = triangles[self.triangle as usize];
        (0..3).fold(Vec3::ZERO, |sum, k| {
            sum + self.weights[k] * positions[t[k] as usize]
        })
    }
}

/// MediaPipe's 478 face landmarks on a character's neutral mesh.
#[derive(Debug, Clone)]
pub struct FaceLandmarks {
    /// Per landmark, where its ray met the mesh; `None` where it met nothing (a landmark
    /// beside the silhouette).
    pub points: Vec<Option<SurfacePoint>>,
}

impl FaceLandmarks {
    /// Finds the face on `character`'s neutral front render and lifts the landmarks onto it.
    ///
    /// # Errors
    /// [`FitError::NoFace`] when the landmark model finds no face on the render (a face it
    /// cannot read: too stylised, turned away, hidden), [`FitError::Model`] if a model fails.
    pub fn find(character: &Character, models: &FaceModels) -> Result<FaceLandmarks, FitError> {
        detect(character, models, &views(character))?
            .ok_or_else(|| FitError::NoFace(character.name().to_owned()))
    }

    /// How many landmarks met the mesh.
    #[must_use]
    pub fn found(&self) -> usize {
        self.points.iter().flatten().count()
    }
}

/// Where to look for the face, in turn: the head box (a head, or a character whose shapes
/// show where its face is), then, when that box is the whole character (a full body without
/// shapes), the top of it at shrinking heights: a head is the top fifth to tenth of a body.
/// Holes of at most this many edges are closed for the render.
const SMALL_HOLE: usize = 8;

/// `character` with its small holes closed, when it has any.
fn patched(character: &Character) -> Option<Character> {
    let fill = crate::mesh::small_hole_fill(character.triangles(), SMALL_HOLE);
    if fill.is_empty() {
        return None;
    }
    let mut parts = character.to_parts();
    // Each fill triangle joins the material run of the triangle beside its hole.
    let mut runs: Vec<std::ops::Range<usize>> =
        parts.parts.iter().map(|p| p.triangles.clone()).collect();
    if runs.is_empty() {
        runs.push(0..parts.triangles.len());
    }
    let mut triangles = Vec::with_capacity(parts.triangles.len() + fill.len());
    for (k, run) in runs.iter().enumerate() {
        let start = triangles.len();
        triangles.extend_from_slice(&parts.triangles[run.clone()]);
        triangles.extend(
            fill.iter()
                .filter(|(t, _)| run.contains(t))
                .map(|(_, f)| *f),
        );
        if let Some(part) = parts.parts.get_mut(k) {
            part.triangles = start..triangles.len();
        }
    }
    parts.triangles = triangles;
    Character::new(parts).ok()
}

fn views(character: &Character) -> Vec<Aabb> {
    let head = character.head_bounds();
    let mut views = vec![head];
    if head != character.bounds() {
        return views;
    }
    let height = head.max.y - head.min.y;
    for share in [0.3, 0.2, 0.14, 0.1] {
        let floor = head.max.y - share * height;
        let top: Vec<Vec3> = character
            .positions()
            .iter()
            .copied()
            .filter(|p| p.y >= floor)
            .collect();
        if top.len() >= 3 {
            views.push(Aabb::around(&top));
        }
    }
    views
}

/// The face found on a front render of each of `views` in turn, its landmarks lifted onto the
/// mesh; `None` when no view shows one.
pub(crate) fn detect(
    character: &Character,
    models: &FaceModels,
    views: &[Aabb],
) -> Result<Option<FaceLandmarks>, FitError> {
    let neutral = character.pose(&[]);
    // Small holes (a few triangles missing) would show the background through the face
    // and hide it from the face model: the render closes them; the landmarks are still
    // lifted onto the character's own triangles.
    let patched = patched(character);
    let shown = patched.as_ref().unwrap_or(character);
    let appearance = Appearance::of(shown);
    let mut found = None;
    for view in views {
        let camera = Camera::front(view, 0.75);
        let image = faceanim_render::render(shown, &neutral, &camera, &appearance, RENDER);
        let frame = Frame {
            width: RENDER as usize,
            height: RENDER as usize,
            rgb: &image.rgb,
        };
        let face = models
            .find_face(&frame)
            .map_err(|e| FitError::Model(e.to_string()))?
            .filter(|f| f.presence >= 0.5 && upright(character, f));
        if let Some(face) = face {
            found = Some((camera, face));
            break;
        }
    }
    let Some((camera, face)) = found else {
        return Ok(None);
    };
    let triangles = character.triangles();
    let caster = RayCaster::new(character.positions(), triangles, &camera);
    let cast = |p: &[f32; 3], on: &dyn Fn(u32) -> bool| {
        caster.cast(&camera, RENDER as f32, p[0], p[1], on)
    };
    // The skin: the pieces of the mesh under landmarks that can only be skin. A landmark
    // on the lid's edge can see past it to the eyeball; cast again, it lands on the lid.
    let (piece, _) = crate::mesh::pieces(triangles, &crate::mesh::copies_in_parts(character));
    let piece_of = |t: u32| piece[triangles[t as usize][0] as usize];
    let skin: Vec<u32> = SKIN
        .iter()
        .filter_map(|&i| face.landmarks.get(i))
        .filter_map(|p| cast(p, &|_| true))
        .map(|hit| piece_of(hit.triangle))
        .collect();
    let on_skin = |t: u32| skin.is_empty() || skin.contains(&piece_of(t));
    let points = face
        .landmarks
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if i < IRISES {
                cast(p, &on_skin)
            } else {
                cast(p, &|_| true)
            }
        })
        .collect();
    Ok(Some(FaceLandmarks { points }))
}

/// Whether `face`, found on a front render of `character` at rest, looks at the camera
/// upright. The model can read a face into a profile or the back of a head; it reports such
/// a face turned or tilted far (a quarter-turned ICT head: yaw 22°, pitch 28°, roll 49°,
/// where faces that are there read within a few degrees of 0).
fn upright(character: &Character, face: &faceanim_track::Face) -> bool {
    let Some(pose) = face.pose else {
        return true;
    };
    let turned = [pose.yaw, pose.pitch, pose.roll]
        .iter()
        .any(|a| a.abs() > UPRIGHT_DEGREES);
    if turned {
        tracing::info!(
            "{}: the face the model found on a front render is turned (yaw {:.0}°, pitch {:.0}°, roll {:.0}°): not taken",
            character.name(),
            pose.yaw,
            pose.pitch,
            pose.roll
        );
    }
    !turned
}

/// Triangles binned by where they fall on the picture, so a ray tests only its own cell's.
struct RayCaster<'a> {
    positions: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    cells: Vec<Vec<u32>>,
}

/// Cells across the picture.
const CELLS: usize = 64;

impl<'a> RayCaster<'a> {
    fn new(positions: &'a [Vec3], triangles: &'a [[u32; 3]], camera: &Camera) -> RayCaster<'a> {
        let mut cells = vec![Vec::new(); CELLS * CELLS];
        let screen: Vec<Option<[f32; 2]>> = positions
            .iter()
            .map(|p| {
                let clip = camera.view_projection * p.extend(1.0);
                (clip.w > 1e-9).then(|| {
                    [
                        (0.5 * (clip.x / clip.w + 1.0)) * CELLS as f32,
                        (0.5 * (1.0 - clip.y / clip.w)) * CELLS as f32,
                    ]
                })
            })
            .collect();
        for (index, t) in triangles.iter().enumerate() {
            let Some(corners) = t
                .iter()
                .map(|&v| screen[v as usize])
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let range = |axis: usize| {
                let lo = corners
                    .iter()
                    .map(|c| c[axis])
                    .fold(f32::INFINITY, f32::min);
                let hi = corners
                    .iter()
                    .map(|c| c[axis])
                    .fold(f32::NEG_INFINITY, f32::max);
                let clamp = |v: f32| (v.floor().max(0.0) as usize).min(CELLS - 1);
                (lo < CELLS as f32 && hi >= 0.0).then(|| clamp(lo)..=clamp(hi))
            };
            let (Some(xs), Some(ys)) = (range(0), range(1)) else {
                continue;
            };
            for y in ys {
                for x in xs.clone() {
                    cells[y * CELLS + x].push(index as u32);
                }
            }
        }
        RayCaster {
            positions,
            triangles,
            cells,
        }
    }

    /// The nearest triangle that `on` accepts and the ray through pixel (`x`, `y`) of a
    /// `size`-pixel picture meets.
    fn cast(
        &self,
        camera: &Camera,
        size: f32,
        x: f32,
        y: f32,
        on: &dyn Fn(u32) -> bool,
    ) -> Option<SurfacePoint> {
        let (near, direction) = camera.ray(size, x, y)?;
        let (cx, cy) = (
            (x / size * CELLS as f32).floor(),
            (y / size * CELLS as f32).floor(),
        );
        if !(0.0..CELLS as f32).contains(&cx) || !(0.0..CELLS as f32).contains(&cy) {
            return None;
        }
        let mut best: Option<(f32, SurfacePoint)> = None;
        for &index in &self.cells[cy as usize * CELLS + cx as usize] {
            if !on(index) {
                continue;
            }
            let t = self.triangles[index as usize];
            let [a, b, c] = t.map(|v| self.positions[v as usize]);
            if let Some((distance, u, v)) = intersect(near, direction, a, b, c)
                && best.is_none_or(|(d, _)| distance < d)
            {
                best = Some((
                    distance,
                    SurfacePoint {
                        triangle: index,
                        weights: [1.0 - u - v, u, v],
                    },
                ));
            }
        }
        best.map(|(_, point)| point)
    }
}

/// Möller–Trumbore: the distance along the ray and the barycentric (u, v) of the hit, for
/// either face of the triangle.
fn intersect(origin: Vec3, direction: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<(f32, f32, f32)> {
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some((t, u, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_face_read_into_a_profile_is_not_taken() {
        let character = Character::new(faceanim_rig::CharacterParts {
            name: "head".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            ..faceanim_rig::CharacterParts::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let face = |yaw: f32, pitch: f32, roll: f32| faceanim_track::Face {
            detection_score: 0.9,
            presence: 1.0,
            landmarks: Vec::new(),
            scores: Vec::new(),
            region: faceanim_track::Region {
                cx: 0.0,
                cy: 0.0,
                size: 1.0,
                rotation: 0.0,
            },
            pose: Some(faceanim_track::HeadPose {
                yaw,
                pitch,
                roll,
                translation: [0.0; 3],
                pixels_per_cm: 10.0,
            }),
        };
        // As the model read the real face of ICT identity 3 facing the camera, and a face it
        // read into that head's profile.
        assert!(upright(&character, &face(-1.0, -1.7, -0.8)));
        assert!(!upright(&character, &face(21.8, 28.1, 49.2)));
        assert!(!upright(&character, &face(-60.0, 0.0, 0.0)));
    }

    #[test]
    fn a_ray_meets_the_nearer_of_two_triangles() {
        let square = |z: f32| {
            [
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(0.0, 1.0, z),
            ]
        };
        let hit = |z: f32| {
            let [a, b, c] = square(z);
            intersect(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, a, b, c)
        };
        let (near, far) = (hit(1.0).unwrap(), hit(-1.0).unwrap());
        assert!((near.0 - 4.0).abs() < 1e-5 && (far.0 - 6.0).abs() < 1e-5);
        let [a, b, c] = square(0.0);
        assert!(intersect(Vec3::new(3.0, 0.0, 5.0), Vec3::NEG_Z, a, b, c).is_none());
    }
}
