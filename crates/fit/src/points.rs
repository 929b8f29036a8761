//! The face placed by hand, where the face model finds none (a stylised face, a head that
//! does not look along +Z, a face hidden by hair in the front render): the user marks ten
//! points on the character's face ([`FacePoint`]) and the rest of MediaPipe's landmarks are
//! carried over from the template's face by the warp those ten define.
//!
//! 1. The points frame a front render of the face; when the face model finds a face there
//!    whose own points agree with the user's, its landmarks are used as found.
//! 2. Otherwise the template's landmarks are moved onto the character: the similarity that
//!    best takes the template's ten points onto the user's, then a thin-plate spline through
//!    what is left, so each mark lands where the user put it; every other landmark is
//!    snapped to the nearest point of the skin the user marked (the pieces of the mesh under
//!    the nose tip and the chin), never to an eyeball or a lash.
//!
//! The points are kept beside the character as `NAME.face-points.json` ([`FacePoints`]), in
//! the character's own space (its file's units, +Y up):
//!
//! ```json
//! { "version": 1, "points": { "nose_tip": [0.0, 1.62, 0.11], "chin": [0.0, 1.5, 0.08], "…": [] } }
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use faceanim_rig::Character;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::FitError;
use crate::landmarks::{FaceLandmarks, IRISES, SurfacePoint, detect};
use crate::mesh;
use faceanim_rig::Aabb;
use faceanim_track::FaceModels;

/// The file's format version.
pub const VERSION: u32 = 1;

/// Where a character's points live: `NAME.face-points.json` in `folder` (its file's folder),
/// or in the current folder.
#[must_use]
pub fn default_path(folder: Option<&Path>, character_name: &str) -> PathBuf {
    let file = format!("{character_name}.face-points.json");
    folder.map_or_else(|| PathBuf::from(&file), |dir| dir.join(&file))
}

/// A point the user marks on the face: left and right are the character's own (its right
/// eye is on the viewer's left when it faces the viewer).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FacePoint {
    /// The outer corner of the right eye.
    RightEyeOuter,
    /// The inner corner of the right eye.
    RightEyeInner,
    /// The inner corner of the left eye.
    LeftEyeInner,
    /// The outer corner of the left eye.
    LeftEyeOuter,
    /// The tip of the nose.
    NoseTip,
    /// The right corner of the mouth.
    MouthRight,
    /// The left corner of the mouth.
    MouthLeft,
    /// The middle of the upper lip's top edge.
    UpperLip,
    /// The middle of the lower lip's bottom edge.
    LowerLip,
    /// The bottom of the chin.
    Chin,
}

impl FacePoint {
    /// Every point, in the order the studio asks for them.
    pub const ALL: [FacePoint; 10] = [
        FacePoint::RightEyeOuter,
        FacePoint::RightEyeInner,
        FacePoint::LeftEyeInner,
        FacePoint::LeftEyeOuter,
        FacePoint::NoseTip,
        FacePoint::MouthRight,
        FacePoint::MouthLeft,
        FacePoint::UpperLip,
        FacePoint::LowerLip,
        FacePoint::Chin,
    ];

    /// The index of the same point among MediaPipe's 478 face landmarks.
    #[must_use]
    pub fn landmark(self) -> usize {
        match self {
            FacePoint::RightEyeOuter => 33,
            FacePoint::RightEyeInner => 133,
            FacePoint::LeftEyeInner => 362,
            FacePoint::LeftEyeOuter => 263,
            FacePoint::NoseTip => 1,
            FacePoint::MouthRight => 61,
            FacePoint::MouthLeft => 291,
            FacePoint::UpperLip => 0,
            FacePoint::LowerLip => 17,
            FacePoint::Chin => 152,
        }
    }

    /// Its name in the file.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            FacePoint::RightEyeOuter => "right_eye_outer",
            FacePoint::RightEyeInner => "right_eye_inner",
            FacePoint::LeftEyeInner => "left_eye_inner",
            FacePoint::LeftEyeOuter => "left_eye_outer",
            FacePoint::NoseTip => "nose_tip",
            FacePoint::MouthRight => "mouth_right",
            FacePoint::MouthLeft => "mouth_left",
            FacePoint::UpperLip => "upper_lip",
            FacePoint::LowerLip => "lower_lip",
            FacePoint::Chin => "chin",
        }
    }

    /// What to click, in words.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            FacePoint::RightEyeOuter => {
                "the outer corner of the character's right eye (on your left as it faces you)"
            }
            FacePoint::RightEyeInner => "the inner corner of the character's right eye",
            FacePoint::LeftEyeInner => "the inner corner of the character's left eye",
            FacePoint::LeftEyeOuter => {
                "the outer corner of the character's left eye (on your right)"
            }
            FacePoint::NoseTip => "the tip of the nose",
            FacePoint::MouthRight => "the right corner of the mouth (on your left)",
            FacePoint::MouthLeft => "the left corner of the mouth (on your right)",
            FacePoint::UpperLip => "the middle of the upper lip's top edge",
            FacePoint::LowerLip => "the middle of the lower lip's bottom edge",
            FacePoint::Chin => "the bottom of the chin",
        }
    }
}

/// Why a points file was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PointsError {
    /// Not the format (a wrong type, an unknown point), with the JSON path of what is wrong.
    #[error("{0}")]
    Format(#[from] faceanim_rig::json::JsonError),
    /// A version this build does not read.
    #[error("version: {0} is not a face-points version this faceanim reads ({VERSION})")]
    Version(u32),
    /// A point is missing.
    #[error("points.{0}: missing ({1} is needed)")]
    Missing(&'static str, &'static str),
    /// A coordinate is not a finite number.
    #[error("points.{0}: the coordinates must be finite numbers")]
    NotFinite(&'static str),
    /// The points do not make a face (eyes on one spot, the mouth above the eyes).
    #[error("points: {0}")]
    NoFace(String),
}

/// The ten points of one character's face, in its own space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FacePoints {
    /// [`VERSION`].
    pub version: u32,
    /// Each point.
    pub points: BTreeMap<FacePoint, [f32; 3]>,
}

impl FacePoints {
    /// Checked points.
    ///
    /// # Errors
    /// [`PointsError`] naming the point that is missing or wrong, or why the points are not
    /// a face.
    pub fn new(points: BTreeMap<FacePoint, [f32; 3]>) -> Result<FacePoints, PointsError> {
        let points = FacePoints {
            version: VERSION,
            points,
        };
        points.check()?;
        Ok(points)
    }

    /// Reads a points file.
    ///
    /// # Errors
    /// [`PointsError`] with the JSON path of what is wrong.
    pub fn from_json(bytes: &[u8]) -> Result<FacePoints, PointsError> {
        let points: FacePoints = faceanim_rig::json::from_slice(bytes)?;
        if points.version != VERSION {
            return Err(PointsError::Version(points.version));
        }
        points.check()?;
        Ok(points)
    }

    /// The file's text.
    #[must_use]
    pub fn to_json(&self) -> String {
        // A map of arrays of numbers always serialises.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Where `point` is.
    #[must_use]
    pub fn at(&self, point: FacePoint) -> Vec3 {
        self.points
            .get(&point)
            .map_or(Vec3::ZERO, |p| Vec3::from_array(*p))
    }

    fn check(&self) -> Result<(), PointsError> {
        for point in FacePoint::ALL {
            let p = self
                .points
                .get(&point)
                .ok_or(PointsError::Missing(point.key(), point.describe()))?;
            if !p.iter().all(|c| c.is_finite()) {
                return Err(PointsError::NotFinite(point.key()));
            }
        }
        let eyes = self
            .at(FacePoint::RightEyeOuter)
            .distance(self.at(FacePoint::LeftEyeOuter));
        let mouth = self
            .at(FacePoint::MouthRight)
            .distance(self.at(FacePoint::MouthLeft));
        if eyes <= 0.0 || mouth <= 0.0 {
            return Err(PointsError::NoFace(
                "the eyes' outer corners, or the mouth's corners, are on one spot".into(),
            ));
        }
        let eye_line = (self.at(FacePoint::RightEyeOuter) + self.at(FacePoint::LeftEyeOuter)) / 2.0;
        let mouth_line = (self.at(FacePoint::MouthRight) + self.at(FacePoint::MouthLeft)) / 2.0;
        let chin = self.at(FacePoint::Chin);
        let (down, up) = (mouth_line - eye_line, chin - mouth_line);
        if down.dot(up) <= 0.0 {
            return Err(PointsError::NoFace(
                "from the eyes the mouth and then the chin must come in turn".into(),
            ));
        }
        Ok(())
    }
}

impl FaceLandmarks {
    /// The face on `character`: where the user marked it when `points` are given
    /// ([`FaceLandmarks::placed`], carried from the first of `templates`), else found.
    ///
    /// # Errors
    /// As [`FaceLandmarks::find`] and [`FaceLandmarks::placed`].
    pub fn locate(
        character: &Character,
        models: &FaceModels,
        points: Option<&FacePoints>,
        templates: &[&Character],
    ) -> Result<FaceLandmarks, FitError> {
        match (points, templates.first()) {
            (Some(points), Some(template)) => {
                FaceLandmarks::placed(character, models, points, template)
            }
            _ => FaceLandmarks::find(character, models),
        }
    }

    /// The face where the user marked it (see [`crate::points`]): the face model on a front
    /// render framed by the points, used when its own ten points lie near the user's; else
    /// `template`'s landmarks carried onto the character by the points.
    ///
    /// # Errors
    /// [`FitError::NoFace`] when the template's face is not found, [`FitError::Model`] if a
    /// model fails.
    pub fn placed(
        character: &Character,
        models: &FaceModels,
        points: &FacePoints,
        template: &Character,
    ) -> Result<FaceLandmarks, FitError> {
        let marked: Vec<Vec3> = FacePoint::ALL.iter().map(|p| points.at(*p)).collect();
        let span = points
            .at(FacePoint::RightEyeOuter)
            .distance(points.at(FacePoint::LeftEyeOuter));
        let around = Aabb::around(&marked);
        let (centre, half) = (around.center(), (around.max - around.min).max_element());
        let view = Aabb {
            min: centre - Vec3::splat(half),
            max: centre + Vec3::splat(half),
        };
        let (positions, triangles) = (character.positions(), character.triangles());
        if let Some(found) = detect(character, models, &[view])? {
            let agrees = FacePoint::ALL.iter().zip(&marked).all(|(p, at)| {
                found.points[p.landmark()]
                    .is_some_and(|s| s.on(triangles, positions).distance(*at) < 0.25 * span)
            });
            if agrees {
                return Ok(found);
            }
            tracing::info!(
                "{}: the face found in the marked region does not match the marks; the marks are used",
                character.name()
            );
        }
        let marks = FaceLandmarks::find(template, models)?;
        let on_template: Vec<Option<Vec3>> = marks
            .points
            .iter()
            .map(|p| p.map(|s| s.on(template.triangles(), template.positions())))
            .collect();
        let points = carried(character, points, &on_template[..IRISES])
            .ok_or_else(|| FitError::NoFace(character.name().to_owned()))?;
        Ok(FaceLandmarks { points })
    }
}

/// Where MediaPipe's landmarks lie on `character`, carried from a template's landmarks
/// (`template`: each landmark's point on the template, `None` where it met nothing) by the
/// user's `points`: a similarity and a thin-plate spline through the ten pairs, then each
/// landmark snapped to the skin under the nose tip and the chin. `None` where the template
/// has no landmark, or the template lacks one of the ten.
#[must_use]
pub fn carried(
    character: &Character,
    points: &FacePoints,
    template: &[Option<Vec3>],
) -> Option<Vec<Option<SurfacePoint>>> {
    let from: Vec<Vec3> = FacePoint::ALL
        .iter()
        .map(|p| template.get(p.landmark()).copied().flatten())
        .collect::<Option<_>>()?;
    let to: Vec<Vec3> = FacePoint::ALL.iter().map(|p| points.at(*p)).collect();
    let warp = Warp::fit(&from, &to)?;
    let (positions, triangles) = (character.positions(), character.triangles());
    let (piece, _) = mesh::pieces(triangles, &mesh::copies_in_parts(character));
    let around = mesh::vertex_triangles(triangles, character.vertex_count());
    let nearest_vertex = |p: Vec3, allowed: &dyn Fn(usize) -> bool| {
        positions
            .iter()
            .enumerate()
            .filter(|(v, _)| allowed(*v) && !around[*v].is_empty())
            .min_by(|a, b| a.1.distance_squared(p).total_cmp(&b.1.distance_squared(p)))
            .map(|(v, _)| v)
    };
    let skin: Vec<u32> = [FacePoint::NoseTip, FacePoint::Chin]
        .iter()
        .filter_map(|p| nearest_vertex(points.at(*p), &|_| true))
        .map(|v| piece[v])
        .collect();
    let on_skin = |v: usize| skin.contains(&piece[v]);
    let snap = |p: Vec3| -> Option<SurfacePoint> {
        let v = nearest_vertex(p, &on_skin)?;
        around[v]
            .iter()
            .map(|&t| {
                let [a, b, c] = triangles[t as usize].map(|k| positions[k as usize]);
                let weights = mesh::closest_on_triangle(p, a, b, c);
                let on = weights[0] * a + weights[1] * b + weights[2] * c;
                (
                    on.distance_squared(p),
                    SurfacePoint {
                        triangle: t,
                        weights,
                    },
                )
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, s)| s)
    };
    Some(
        template
            .iter()
            .map(|mark| snap(warp.apply((*mark)?)))
            .collect(),
    )
}

/// A similarity followed by a thin-plate spline (the biharmonic kernel |r| in 3D) that takes
/// each `from` point exactly onto its `to`.
struct Warp {
    similarity: crate::Similarity,
    centres: Vec<Vec3>,
    /// Per centre, the spline's weight (one per axis); then the affine part: the constant
    /// and the columns for x, y and z.
    weights: Vec<Vec3>,
}

impl Warp {
    fn fit(from: &[Vec3], to: &[Vec3]) -> Option<Warp> {
        let similarity = crate::Similarity::fit(from, to)?;
        let centres: Vec<Vec3> = from.iter().map(|p| similarity.apply(*p)).collect();
        let n = centres.len();
        // [K P; Pᵀ 0] [w; a] = [residual; 0], with an affine part a so the spline bends only.
        let size = n + 4;
        let mut a = faer::Mat::<f64>::zeros(size, size);
        let mut b = faer::Mat::<f64>::zeros(size, 3);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = f64::from(centres[i].distance(centres[j]));
            }
            let p = centres[i].as_dvec3();
            for (k, c) in [1.0, p.x, p.y, p.z].into_iter().enumerate() {
                a[(i, n + k)] = c;
                a[(n + k, i)] = c;
            }
            let r = (to[i] - centres[i]).as_dvec3();
            for (axis, value) in [r.x, r.y, r.z].into_iter().enumerate() {
                b[(i, axis)] = value;
            }
        }
        use faer::linalg::solvers::Solve as _;
        let solved = a.full_piv_lu().solve(&b);
        let ok = (0..size).all(|r| (0..3).all(|c| solved[(r, c)].is_finite()));
        if !ok {
            return None;
        }
        let row = |r: usize| {
            Vec3::new(
                solved[(r, 0)] as f32,
                solved[(r, 1)] as f32,
                solved[(r, 2)] as f32,
            )
        };
        let weights: Vec<Vec3> = (0..n).map(row).collect();
        let affine = [row(n), row(n + 1), row(n + 2), row(n + 3)];
        Some(Warp {
            similarity,
            centres,
            weights: weights.into_iter().chain(affine).collect(),
        })
    }

    fn apply(&self, p: Vec3) -> Vec3 {
        let q = self.similarity.apply(p);
        let n = self.centres.len();
        let bend: Vec3 = self
            .centres
            .iter()
            .zip(&self.weights[..n])
            .map(|(c, w)| *w * c.distance(q))
            .sum();
        let affine = &self.weights[n..];
        q + bend + affine[0] + affine[1] * q.x + affine[2] * q.y + affine[3] * q.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_face() -> BTreeMap<FacePoint, [f32; 3]> {
        FacePoint::ALL
            .iter()
            .map(|p| {
                let at = match p {
                    FacePoint::RightEyeOuter => [-0.4, 0.3, 0.0],
                    FacePoint::RightEyeInner => [-0.15, 0.3, 0.05],
                    FacePoint::LeftEyeInner => [0.15, 0.3, 0.05],
                    FacePoint::LeftEyeOuter => [0.4, 0.3, 0.0],
                    FacePoint::NoseTip => [0.0, 0.0, 0.3],
                    FacePoint::MouthRight => [-0.2, -0.3, 0.05],
                    FacePoint::MouthLeft => [0.2, -0.3, 0.05],
                    FacePoint::UpperLip => [0.0, -0.25, 0.1],
                    FacePoint::LowerLip => [0.0, -0.38, 0.08],
                    FacePoint::Chin => [0.0, -0.6, 0.0],
                };
                (*p, at)
            })
            .collect()
    }

    #[test]
    fn points_round_trip_and_bad_files_name_the_field() {
        let points = FacePoints::new(square_face()).unwrap_or_else(|e| panic!("{e}"));
        let again = FacePoints::from_json(points.to_json().as_bytes());
        assert_eq!(again.as_ref().ok(), Some(&points));
        let mut missing = square_face();
        missing.remove(&FacePoint::Chin);
        assert!(
            FacePoints::new(missing)
                .unwrap_err()
                .to_string()
                .starts_with("points.chin: missing")
        );
        let bad = points.to_json().replace("\"nose_tip\"", "\"nose\"");
        let e = FacePoints::from_json(bad.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("points"), "{e}");
        let upside_down: BTreeMap<FacePoint, [f32; 3]> = square_face()
            .into_iter()
            .map(|(p, [x, y, z])| (p, [x, if p == FacePoint::Chin { 1.0 } else { y }, z]))
            .collect();
        assert!(matches!(
            FacePoints::new(upside_down),
            Err(PointsError::NoFace(_))
        ));
        let e = FacePoints::from_json(br#"{"version": 9, "points": {}}"#).unwrap_err();
        assert_eq!(e, PointsError::Version(9));
    }

    #[test]
    fn the_warp_takes_each_mark_onto_its_point_and_keeps_a_similarity() {
        let to: Vec<Vec3> = square_face()
            .values()
            .map(|p| Vec3::from_array(*p))
            .collect();
        // The template: the same face half the size, turned and moved, with its mouth wider.
        let turn = glam::Quat::from_rotation_y(0.4);
        let from: Vec<Vec3> = to
            .iter()
            .enumerate()
            .map(|(k, p)| turn * (*p * 0.5) + Vec3::new(1.0, 2.0, 3.0) + Vec3::X * 0.01 * k as f32)
            .collect();
        let warp = Warp::fit(&from, &to).unwrap_or_else(|| panic!("a warp"));
        for (f, t) in from.iter().zip(&to) {
            assert!(
                warp.apply(*f).distance(*t) < 1e-4,
                "{f} → {}",
                warp.apply(*f)
            );
        }
        // Between the marks the warp is close to the similarity.
        let between = (from[4] + from[9]) / 2.0;
        let expected = (to[4] + to[9]) / 2.0;
        assert!(warp.apply(between).distance(expected) < 0.05);
    }
}
