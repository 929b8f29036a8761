//! The head's geometry: a closed skin shell (a latitude–longitude grid cast onto the field,
//! denser over the face) with almond eye openings whose lids hug the eyeballs and a mouth slit,
//! plus eyeballs with iris and pupil, upper and lower teeth, a dark mouth cavity and a tongue.
//! The right half is the exact mirror of the left, vertex for vertex.

use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, PI};

use glam::Vec3;

use crate::field::{EYE_RADIUS, LEFT_EYE, LID_RADIUS, MOUTH_Y, bump, cast, left, smoothstep};

/// Which part of the head a vertex belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The skin shell.
    Skin,
    /// An eyeball; `true` for the character's left (+X).
    Eye(bool),
    /// Upper teeth (fixed to the skull).
    UpperTeeth,
    /// Lower teeth (moving with the jaw).
    LowerTeeth,
    /// The dark mouth cavity.
    Cavity,
    /// The tongue.
    Tongue,
}

/// A vertex with what the blendshapes need to know about it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Neutral position.
    pub p: Vec3,
    /// Its part.
    pub part: Part,
    /// On the lower-lip side of the mouth slit (the copies made by the cut).
    pub lower_lip_copy: bool,
    /// On the upper-lip side of the slit (the originals along the cut).
    pub upper_lip_edge: bool,
}

/// The built geometry.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Vertices.
    pub vertices: Vec<Vertex>,
    /// Triangles, counter-clockwise from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Linear RGBA colour per vertex.
    pub colours: Vec<[f32; 4]>,
    /// The vertex at each vertex's mirrored position (same part and slit side).
    pub mirror: Vec<u32>,
}

const COLUMNS: usize = 160;
const ROWS: usize = 120;
/// Rays are cast from here (inside the head, so every surface point is visible from it).
const RAY_ORIGIN: Vec3 = Vec3::new(0.0, -0.01, 0.03);
/// Half-width of the mouth: the slit ends at the corners.
pub const MOUTH_HALF_WIDTH: f32 = 0.0235;
/// Half-width of the eye opening, as a yaw angle on the lid shell.
const EYE_HALF_WIDTH: f32 = 1.15;

/// Longitude of grid column `j`: 0 at the front, ±π at the back, denser at the front.
fn longitude(j: usize) -> f32 {
    let u = (j as f32 - (COLUMNS / 2) as f32) / (COLUMNS / 2) as f32;
    let a = 1.8f32;
    PI * (a * u).sinh() / a.sinh()
}

/// Latitudes of the grid rows, +π/2 (crown) to −π/2 (base of the neck), denser over the face.
fn latitudes() -> Vec<f32> {
    let n = 4096;
    let density = |phi: f32| 1.0 + 2.4 * (-((phi + 0.12) / 0.5).powi(2)).exp();
    let phis: Vec<f32> = (0..=n)
        .map(|k| FRAC_PI_2 - PI * k as f32 / n as f32)
        .collect();
    let mut cumulative = vec![0.0f32; n + 1];
    for k in 1..=n {
        cumulative[k] = cumulative[k - 1] + 0.5 * (density(phis[k - 1]) + density(phis[k]));
    }
    let total = cumulative[n];
    (0..=ROWS)
        .map(|i| {
            let target = total * i as f32 / ROWS as f32;
            let k = cumulative.partition_point(|&c| c < target).clamp(1, n);
            let t = (target - cumulative[k - 1])
                / (cumulative[k] - cumulative[k - 1]).max(f32::MIN_POSITIVE);
            phis[k - 1] + (phis[k] - phis[k - 1]) * t
        })
        .collect()
}

/// Eye-local angles of `p` around the left eye: yaw `u` (positive outwards), pitch `v`, radius.
#[must_use]
pub fn eye_angles(p: Vec3) -> (f32, f32, f32) {
    let d = p - LEFT_EYE;
    let r = d.length();
    (
        d.x.atan2(d.z),
        (d.y / r.max(f32::MIN_POSITIVE)).clamp(-1.0, 1.0).asin(),
        r,
    )
}

/// A point on a sphere around the left eye from its angles.
#[must_use]
pub fn eye_point(u: f32, v: f32, r: f32) -> Vec3 {
    LEFT_EYE + r * Vec3::new(v.cos() * u.sin(), v.sin(), v.cos() * u.cos())
}

/// The upper and lower lid lines of the open eye at yaw `u`: an almond, outer corner higher.
#[must_use]
pub fn lid_lines(u: f32) -> (f32, f32) {
    let t = (u.abs() / EYE_HALF_WIDTH).min(1.0);
    let tilt = 0.10 * (u / EYE_HALF_WIDTH).clamp(-1.0, 1.0);
    let upper = 0.42 * (1.0 - t * t).powf(0.6) - 0.07 + tilt;
    let lower = -0.30 * (1.0 - t * t).powf(0.8) - 0.07 + tilt;
    (upper, lower)
}

fn in_eye_opening(p: Vec3) -> bool {
    let (u, v, r) = eye_angles(p);
    let (upper, lower) = lid_lines(u);
    r < 0.03 && p.z > LEFT_EYE.z && u.abs() < EYE_HALF_WIDTH && v < upper && v > lower
}

/// Skin near the left eye slides onto the lid shell; 1 on the rim, 0 half a radian away.
fn lid_snap(p: Vec3) -> Vec3 {
    let (u, v, r) = eye_angles(p);
    if r > 0.03 || p.z < LEFT_EYE.z {
        return p;
    }
    let (upper, lower) = lid_lines(u);
    let outside = (v - upper)
        .max(lower - v)
        .max(u.abs() - EYE_HALF_WIDTH)
        .max(0.0);
    let b = 1.0 - smoothstep(0.0, 0.5, outside);
    p.lerp(eye_point(u, v, LID_RADIUS), b)
}

/// Applies `f` (defined for the left side) to `p` mirrored to the left and back.
fn on_left(p: Vec3, f: impl Fn(Vec3) -> Vec3) -> Vec3 {
    if p.x >= 0.0 {
        f(p)
    } else {
        let q = f(Vec3::new(-p.x, p.y, p.z));
        Vec3::new(-q.x, q.y, q.z)
    }
}

struct Builder {
    vertices: Vec<Vertex>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn push(&mut self, p: Vec3, part: Part) -> u32 {
        self.vertices.push(Vertex {
            p,
            part,
            lower_lip_copy: false,
            upper_lip_edge: false,
        });
        (self.vertices.len() - 1) as u32
    }

    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        // a-b-c-d counter-clockwise from outside.
        self.triangles.push([a, b, c]);
        self.triangles.push([a, c, d]);
    }
}

/// Builds the whole head.
#[must_use]
pub fn build() -> Mesh {
    let mut b = Builder {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    skin(&mut b);
    eye(&mut b, true);
    eye(&mut b, false);
    teeth(&mut b, Part::UpperTeeth, 0.058, 0.0225, -0.0590, -0.0500);
    teeth(&mut b, Part::LowerTeeth, 0.056, 0.0205, -0.0690, -0.0600);
    // The mouth's dark cavity, then the tongue lying in it: centre, radii, segments, rings.
    for (part, centre, radii, segments, rings) in [
        (
            Part::Cavity,
            [0.0, -0.061, 0.050],
            [0.025, 0.017, 0.026],
            24,
            12,
        ),
        (
            Part::Tongue,
            [0.0, -0.0655, 0.050],
            [0.0155, 0.0055, 0.021],
            20,
            10,
        ),
    ] {
        ellipsoid(
            &mut b,
            part,
            Vec3::from(centre),
            Vec3::from(radii),
            segments,
            rings,
        );
    }
    let (vertices, triangles) = compact(b.vertices, b.triangles);
    let mirror = mirror_map(&vertices);
    let colours = vertices.iter().map(colour).collect();
    Mesh {
        vertices,
        triangles,
        colours,
        mirror,
    }
}

fn skin(b: &mut Builder) {
    let phis = latitudes();
    // Cast the left half (and the two midline columns); mirror the rest exactly.
    let mut grid = vec![Vec3::ZERO; (ROWS - 1) * COLUMNS];
    for i in 1..ROWS {
        let phi = phis[i];
        for j in (COLUMNS / 2)..=COLUMNS {
            let lambda = longitude(j % COLUMNS);
            let lambda = if j == COLUMNS { PI } else { lambda };
            let dir = Vec3::new(
                phi.cos() * lambda.sin(),
                phi.sin(),
                phi.cos() * lambda.cos(),
            );
            let mut p = lid_snap(cast(RAY_ORIGIN, dir));
            if j == COLUMNS / 2 || j == COLUMNS {
                p.x = 0.0;
            }
            grid[(i - 1) * COLUMNS + j % COLUMNS] = p;
        }
        for j in 1..COLUMNS / 2 {
            let q = grid[(i - 1) * COLUMNS + (COLUMNS - j)];
            grid[(i - 1) * COLUMNS + j] = Vec3::new(-q.x, q.y, q.z);
        }
    }
    let top = cast(RAY_ORIGIN, Vec3::Y) * Vec3::new(0.0, 1.0, 1.0);
    let bottom = cast(RAY_ORIGIN, -Vec3::Y) * Vec3::new(0.0, 1.0, 1.0);

    // The mouth line: the grid row nearest it at the front, cut between the corners.
    let front = COLUMNS / 2;
    let mouth_row = (1..ROWS).min_by(|&a, &c| {
        (grid[(a - 1) * COLUMNS + front].y - MOUTH_Y)
            .abs()
            .total_cmp(&(grid[(c - 1) * COLUMNS + front].y - MOUTH_Y).abs())
    });
    let mouth_row = mouth_row.unwrap_or(ROWS / 2);
    let in_slit = |j: usize, grid: &[Vec3]| {
        let p = grid[(mouth_row - 1) * COLUMNS + j];
        p.z > 0.06 && p.x.abs() < MOUTH_HALF_WIDTH
    };
    for j in 0..COLUMNS {
        if in_slit(j, &grid) {
            let p = &mut grid[(mouth_row - 1) * COLUMNS + j];
            let t = p.x / MOUTH_HALF_WIDTH;
            p.y = MOUTH_Y - 0.0015 * t * t;
        }
    }

    let base = b.vertices.len() as u32;
    for p in &grid {
        b.push(*p, Part::Skin);
    }
    let top_index = b.push(top, Part::Skin);
    let bottom_index = b.push(bottom, Part::Skin);
    let at = |i: usize, j: usize| base + ((i - 1) * COLUMNS + j % COLUMNS) as u32;
    let mut lower_copy: HashMap<usize, u32> = HashMap::new();
    for j in 0..COLUMNS {
        if in_slit(j, &grid) {
            let original = at(mouth_row, j) as usize;
            b.vertices[original].upper_lip_edge = true;
            let p = b.vertices[original].p;
            let copy = b.push(p, Part::Skin);
            b.vertices[copy as usize].lower_lip_copy = true;
            lower_copy.insert(j, copy);
        }
    }

    // Faces, leaving out the eye openings.
    let hole = |a: Vec3, c: Vec3, d: Vec3, e: Vec3| in_eye_opening(left((a + c + d + e) * 0.25));
    let mut in_removed = vec![false; b.vertices.len()];
    for j in 0..COLUMNS {
        let k = (j + 1) % COLUMNS;
        // Columns run west to east seen from outside when j increases towards the front from the
        // back on the right side: longitude grows with j, so (i, j) → (i, k) is eastward.
        b.triangles.push([top_index, at(1, j), at(1, k)]);
        for i in 1..ROWS - 1 {
            let (p00, p01, p10, p11) = (at(i, j), at(i, k), at(i + 1, j), at(i + 1, k));
            let v = &b.vertices;
            if hole(
                v[p00 as usize].p,
                v[p01 as usize].p,
                v[p10 as usize].p,
                v[p11 as usize].p,
            ) {
                for q in [p00, p01, p10, p11] {
                    in_removed[q as usize] = true;
                }
                continue;
            }
            let (p00, p01) = if i == mouth_row {
                (
                    lower_copy.get(&j).copied().unwrap_or(p00),
                    lower_copy.get(&k).copied().unwrap_or(p01),
                )
            } else {
                (p00, p01)
            };
            b.quad(p00, p10, p11, p01);
        }
        b.triangles
            .push([bottom_index, at(ROWS - 1, k), at(ROWS - 1, j)]);
    }

    // Smooth the rims of the openings: vertices shared by kept and removed faces slide onto
    // the almond's lid lines, so the openings are not stair-stepped along the grid.
    let mut in_kept = vec![false; b.vertices.len()];
    for t in &b.triangles {
        for &v in t {
            in_kept[v as usize] = true;
        }
    }
    for (i, v) in b.vertices.iter_mut().enumerate() {
        if v.part != Part::Skin || !(in_kept[i] && in_removed.get(i).copied().unwrap_or(false)) {
            continue;
        }
        v.p = on_left(v.p, |p| {
            let (u, pitch, _) = eye_angles(p);
            let u = u.clamp(-EYE_HALF_WIDTH, EYE_HALF_WIDTH);
            let (upper, lower) = lid_lines(u);
            let snapped = if pitch > 0.5 * (upper + lower) {
                upper
            } else {
                lower
            };
            eye_point(u, snapped, LID_RADIUS)
        });
    }
}

/// An eyeball: a sphere with its pole looking forward (+Z), rings placed at the pupil and iris
/// edges so that their colours stay crisp; the cornea bulges slightly.
fn eye(b: &mut Builder, left_side: bool) {
    let rings = [
        0.0f32, 0.08, 0.16, 0.18, 0.28, 0.38, 0.40, 0.52, 0.7, 0.9, 1.1, 1.35, 1.6, 1.9, 2.2, 2.5,
        2.8, PI,
    ];
    let segments = 28;
    let centre = if left_side {
        LEFT_EYE
    } else {
        Vec3::new(-LEFT_EYE.x, LEFT_EYE.y, LEFT_EYE.z)
    };
    let start = b.vertices.len() as u32;
    let part = Part::Eye(left_side);
    let point = |theta: f32, psi: f32| {
        let bulge = 1.0 + 0.06 * ((theta.cos() - 0.4f32.cos()) / (1.0 - 0.4f32.cos())).max(0.0);
        let local = Vec3::new(
            theta.sin() * psi.cos(),
            theta.sin() * psi.sin(),
            theta.cos(),
        ) * EYE_RADIUS
            * bulge;
        let local = if left_side {
            local
        } else {
            Vec3::new(-local.x, local.y, local.z)
        };
        centre + local
    };
    b.push(point(0.0, 0.0), part);
    for &theta in &rings[1..rings.len() - 1] {
        for s in 0..segments {
            b.push(point(theta, 2.0 * PI * s as f32 / segments as f32), part);
        }
    }
    b.push(point(PI, 0.0), part);
    let ring = |k: usize, s: usize| start + 1 + ((k - 1) * segments + s % segments) as u32;
    let last = start + 1 + ((rings.len() - 2) * segments) as u32;
    let mut tris = Vec::new();
    for s in 0..segments {
        tris.push([start, ring(1, s), ring(1, s + 1)]);
        for k in 1..rings.len() - 2 {
            let (a, c, d, e) = (
                ring(k, s),
                ring(k + 1, s),
                ring(k + 1, s + 1),
                ring(k, s + 1),
            );
            tris.push([a, c, d]);
            tris.push([a, d, e]);
        }
        tris.push([last, ring(rings.len() - 2, s + 1), ring(rings.len() - 2, s)]);
    }
    for t in tris {
        // Mirroring turns the winding inside out.
        b.triangles
            .push(if left_side { t } else { [t[0], t[2], t[1]] });
    }
}

/// A horseshoe of teeth: a closed box swept along an arc around the vertical axis.
fn teeth(b: &mut Builder, part: Part, centre_z: f32, radius: f32, y0: f32, y1: f32) {
    let n = 24;
    let half_angle = 1.05f32;
    let start = b.vertices.len() as u32;
    let depth = 0.0035;
    let mut corners = Vec::with_capacity((n + 1) * 4);
    for k in 0..=n {
        let a = -half_angle + 2.0 * half_angle * k as f32 / n as f32;
        let at = |r: f32, y: f32| {
            let x = if 2 * k == n { 0.0 } else { r * a.sin() };
            Vec3::new(x, y, centre_z + r * a.cos())
        };
        corners.push([
            at(radius, y0),
            at(radius, y1),
            at(radius - depth, y1),
            at(radius - depth, y0),
        ]);
    }
    // Exact symmetry: the right half mirrors the left.
    for k in 0..n / 2 {
        let m = corners[n - k];
        corners[k] = m.map(|p| Vec3::new(-p.x, p.y, p.z));
    }
    for c in &corners {
        for p in c {
            b.push(*p, part);
        }
    }
    let v = |k: usize, c: usize| start + (k * 4 + c) as u32;
    for k in 0..n {
        // outer (0,1), top (1,2), inner (2,3), bottom (3,0), as seen from outside.
        for c in 0..4 {
            let d = (c + 1) % 4;
            b.quad(v(k, c), v(k + 1, c), v(k + 1, d), v(k, d));
        }
    }
    b.quad(v(0, 0), v(0, 1), v(0, 2), v(0, 3));
    b.quad(v(n, 3), v(n, 2), v(n, 1), v(n, 0));
}

/// A closed ellipsoid with its poles on the Y axis and a longitude seam at the back.
fn ellipsoid(
    b: &mut Builder,
    part: Part,
    centre: Vec3,
    radii: Vec3,
    segments: usize,
    rings: usize,
) {
    let start = b.vertices.len() as u32;
    b.push(centre + Vec3::new(0.0, radii.y, 0.0), part);
    for r in 1..rings {
        let phi = FRAC_PI_2 - PI * r as f32 / rings as f32;
        let mut row = vec![Vec3::ZERO; segments];
        for (s, slot) in row.iter_mut().enumerate().take(segments / 2 + 1) {
            let psi = 2.0 * PI * s as f32 / segments as f32;
            let x = if s == 0 || 2 * s == segments {
                0.0
            } else {
                radii.x * phi.cos() * psi.sin()
            };
            *slot = centre + Vec3::new(x, radii.y * phi.sin(), radii.z * phi.cos() * psi.cos());
        }
        for s in segments / 2 + 1..segments {
            let q = row[segments - s];
            row[s] = Vec3::new(-q.x, q.y, q.z);
        }
        for p in row {
            b.push(p, part);
        }
    }
    let bottom = b.push(centre - Vec3::new(0.0, radii.y, 0.0), part);
    let at = |r: usize, s: usize| start + 1 + ((r - 1) * segments + s % segments) as u32;
    for s in 0..segments {
        b.triangles.push([start, at(1, s), at(1, s + 1)]);
        for r in 1..rings - 1 {
            b.quad(at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s + 1));
        }
        b.triangles
            .push([bottom, at(rings - 1, s + 1), at(rings - 1, s)]);
    }
}

/// Drops vertices no triangle uses (inside the eye openings) and renumbers.
fn compact(vertices: Vec<Vertex>, triangles: Vec<[u32; 3]>) -> (Vec<Vertex>, Vec<[u32; 3]>) {
    let mut used = vec![false; vertices.len()];
    for t in &triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut new_index = vec![u32::MAX; vertices.len()];
    let mut kept = Vec::new();
    for (i, v) in vertices.into_iter().enumerate() {
        if used[i] {
            new_index[i] = kept.len() as u32;
            kept.push(v);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    (kept, triangles)
}

/// Pairs each vertex with the one at its mirrored position (and same part and slit side).
fn mirror_map(vertices: &[Vertex]) -> Vec<u32> {
    let key = |p: Vec3, v: &Vertex| {
        (
            [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f32::to_bits),
            v.lower_lip_copy,
            part_key(v.part),
        )
    };
    let index: HashMap<_, u32> = vertices
        .iter()
        .enumerate()
        .map(|(i, v)| (key(v.p, v), i as u32))
        .collect();
    vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let m = Vec3::new(-v.p.x, v.p.y, v.p.z);
            index.get(&key(m, v)).copied().unwrap_or(i as u32)
        })
        .collect()
}

/// Parts as compared across the mirror (the two eyes are one class; positions tell them apart).
fn part_key(part: Part) -> u8 {
    match part {
        Part::Skin => 0,
        Part::Eye(_) => 1,
        Part::UpperTeeth => 3,
        Part::LowerTeeth => 4,
        Part::Cavity => 5,
        Part::Tongue => 6,
    }
}

/// Linear RGB colours: skin, lips, brows, hair; white, iris and pupil for the eyes; teeth,
/// a dark mouth and a pink tongue.
fn colour(v: &Vertex) -> [f32; 4] {
    let skin = Vec3::new(0.80, 0.55, 0.43);
    let c = match v.part {
        Part::Eye(_) => {
            let centre = if v.p.x > 0.0 {
                LEFT_EYE
            } else {
                Vec3::new(-LEFT_EYE.x, LEFT_EYE.y, LEFT_EYE.z)
            };
            let theta = ((v.p - centre).normalize_or_zero().z)
                .clamp(-1.0, 1.0)
                .acos();
            if theta < 0.17 {
                Vec3::splat(0.015)
            } else if theta < 0.50 {
                let t = (theta - 0.17) / 0.33;
                Vec3::new(0.10, 0.28, 0.36).lerp(Vec3::new(0.05, 0.14, 0.20), t)
            } else {
                Vec3::new(0.86, 0.83, 0.80)
            }
        }
        Part::UpperTeeth | Part::LowerTeeth => Vec3::new(0.88, 0.86, 0.78),
        Part::Cavity => Vec3::new(0.12, 0.025, 0.03),
        Part::Tongue => Vec3::new(0.70, 0.26, 0.30),
        Part::Skin => {
            let p = left(v.p);
            let lips = lip_mask(p);
            let brows = brow_mask(p);
            let hair = hair_mask(p);
            let blush = 0.35
                * bump(
                    p,
                    Vec3::new(0.045, -0.025, 0.07),
                    Vec3::new(0.02, 0.018, 0.03),
                );
            let mut c = skin.lerp(Vec3::new(0.80, 0.42, 0.38), blush);
            c = c.lerp(Vec3::new(0.55, 0.16, 0.17), lips);
            c = c.lerp(Vec3::new(0.07, 0.045, 0.03), brows);
            c.lerp(Vec3::new(0.06, 0.04, 0.03), hair)
        }
    };
    [c.x, c.y, c.z, 1.0]
}

/// The red of the lips: an upper lip with a cupid's bow and a fuller lower lip.
fn lip_mask(p: Vec3) -> f32 {
    if p.z < 0.06 {
        return 0.0;
    }
    let t = (p.x / MOUTH_HALF_WIDTH).min(1.2);
    // Cupid's bow: a dip at the middle, peaks either side.
    let dip = 0.0012 * (-(p.x / 0.004).powi(2)).exp();
    let peak = 0.0009 * (-((p.x - 0.0045) / 0.003).powi(2)).exp();
    let top = MOUTH_Y + 0.0075 - 0.0022 * (t * t) - dip + peak;
    let bottom = MOUTH_Y - 0.0085 + 0.0035 * t * t;
    let width = 1.0 - smoothstep(0.92, 1.05, t);
    let vertical = smoothstep(top + 0.0008, top - 0.0008, p.y)
        * smoothstep(bottom - 0.0008, bottom + 0.0008, p.y);
    width * vertical
}

/// Eyebrows: an arch above each eye, thick at the inner end, thinning outwards.
fn brow_mask(p: Vec3) -> f32 {
    if p.z < 0.04 || !(0.008..0.062).contains(&p.x) {
        return 0.0;
    }
    let s = (p.x - 0.008) / 0.054;
    let centre = 0.0285 + 0.0055 * (PI * s.powf(0.8)).sin();
    let half_thickness = 0.0032 * (1.0 - 0.6 * s);
    let ends = smoothstep(0.0, 0.08, s) * (1.0 - smoothstep(0.85, 1.0, s));
    ends * (1.0
        - smoothstep(
            half_thickness * 0.6,
            half_thickness * 1.3,
            (p.y - centre).abs(),
        ))
}

/// Short hair over the crown and back, with a hairline above the forehead and the ears.
fn hair_mask(p: Vec3) -> f32 {
    let front = (p.z / 0.09).clamp(-1.0, 1.0);
    let hairline = if front > 0.0 {
        0.072 - 0.045 * (1.0 - front).powi(2)
    } else {
        0.027 - 0.06 * front * front
    };
    let over_ear = bump(
        p,
        Vec3::new(0.076, 0.0, -0.005),
        Vec3::new(0.02, 0.03, 0.025),
    );
    smoothstep(hairline - 0.004, hairline + 0.004, p.y) * (1.0 - over_ear)
}
