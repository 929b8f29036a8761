//! Head pose: a weighted rigid fit (rotation, uniform scale, translation) of MediaPipe's
//! canonical face to the landmarks of one frame.
//!
//! The canonical face and the landmark weights come from the bundle's
//! `geometry_pipeline_metadata_landmarks.binarypb` (a protobuf: the canonical mesh's vertices in
//! centimetres, and the "Procrustes basis" of landmarks that barely move with expression, with
//! their weights). The fit is Horn's closed form: the rotation is the dominant eigenvector, as a
//! quaternion, of a 4×4 matrix built from the weighted cross-covariance; a Jacobi sweep finds it.
//!
//! Frames: landmarks come in image pixels (x right, y down, z away from the camera, all in
//! pixels); the fit works in a right-handed, y-up frame (x right, y up, z towards the camera),
//! the frame of the canonical face and of a glTF character facing the viewer, so the rotation
//! can be put on a character's root as it is.

use glam::{DMat3, DQuat, DVec3};

/// Where a face is and how it is turned, relative to the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadPose {
    /// Turn about the vertical axis, degrees; positive turns the face towards the subject's
    /// own left (the image's right on an unmirrored picture).
    pub yaw: f32,
    /// Nod about the horizontal axis, degrees; positive lifts the chin (looks up).
    pub pitch: f32,
    /// Tilt about the viewing axis, degrees; positive is anticlockwise as the camera sees it
    /// (the top of the head moves towards the image's left).
    pub roll: f32,
    /// Position of the canonical face's origin (between the ears, behind the nose) in metres,
    /// camera at the origin, x right, y up, z towards the viewer (so z is negative). Depth comes
    /// from the face's apparent size under [`HeadPose::VERTICAL_FOV_DEGREES`].
    pub translation: [f32; 3],
    /// Image pixels per centimetre of the canonical face (the fit's scale).
    pub pixels_per_cm: f32,
}

impl HeadPose {
    /// The camera's assumed vertical field of view (MediaPipe's default for its face geometry).
    pub const VERTICAL_FOV_DEGREES: f32 = 63.0;

    /// The rotation as a quaternion `[x, y, z, w]` (the order glTF uses), in the y-up frame.
    #[must_use]
    pub fn rotation_quaternion(&self) -> [f32; 4] {
        let q = euler_to_quat(
            f64::from(self.yaw),
            f64::from(self.pitch),
            f64::from(self.roll),
        );
        [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
    }
}

/// `R = Ry(yaw) · Rx(−pitch) · Rz(roll)`: yaw about +y, then pitch (sign flipped so that positive
/// is "looking up": rotating about +x moves the nose, on +z, down), then roll about +z.
fn euler_to_quat(yaw: f64, pitch: f64, roll: f64) -> DQuat {
    DQuat::from_rotation_y(yaw.to_radians())
        * DQuat::from_rotation_x(-pitch.to_radians())
        * DQuat::from_rotation_z(roll.to_radians())
}

fn quat_to_euler(q: DQuat) -> (f64, f64, f64) {
    let m = DMat3::from_quat(q);
    // For R = Ry(a) Rx(b) Rz(c): m[2][1] (row 1, column 2 in glam's column-major) = −sin b.
    let sin_b = (-m.z_axis.y).clamp(-1.0, 1.0);
    let b = sin_b.asin();
    let a = m.z_axis.x.atan2(m.z_axis.z);
    let c = m.x_axis.y.atan2(m.y_axis.y);
    (a.to_degrees(), -b.to_degrees(), c.to_degrees())
}

/// The canonical face and the weighted landmarks used for the fit.
#[derive(Debug, Clone)]
pub struct CanonicalFace {
    /// Canonical vertices in centimetres, y up, z towards the viewer (468: the mesh has no iris
    /// points).
    pub vertices: Vec<[f32; 3]>,
    /// `(landmark index, weight)` of the landmarks the fit uses.
    pub basis: Vec<(usize, f32)>,
}

/// A minimal protobuf reader: enough for the three messages of the geometry metadata.
struct Proto<'a> {
    bytes: &'a [u8],
    at: usize,
}

enum Value<'a> {
    Varint(u64),
    Fixed32(u32),
    Bytes(&'a [u8]),
}

impl<'a> Proto<'a> {
    fn varint(&mut self) -> Result<u64, String> {
        let mut value = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = *self.bytes.get(self.at).ok_or("truncated varint")?;
            self.at += 1;
            value |= u64::from(byte & 0x7f) << shift;
            if byte < 0x80 {
                return Ok(value);
            }
        }
        Err("varint too long".into())
    }

    fn next(&mut self) -> Result<Option<(u64, Value<'a>)>, String> {
        if self.at >= self.bytes.len() {
            return Ok(None);
        }
        let key = self.varint()?;
        let value = match key & 7 {
            0 => Value::Varint(self.varint()?),
            5 => {
                let raw = self
                    .bytes
                    .get(self.at..self.at + 4)
                    .ok_or("truncated fixed32")?;
                self.at += 4;
                Value::Fixed32(u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]))
            }
            2 => {
                let len = usize::try_from(self.varint()?).map_err(|_| "length overflow")?;
                let end = self.at.checked_add(len).ok_or("length overflow")?;
                let raw = self.bytes.get(self.at..end).ok_or("truncated field")?;
                self.at = end;
                Value::Bytes(raw)
            }
            1 => {
                self.at += 8;
                Value::Varint(0)
            }
            other => return Err(format!("unsupported wire type {other}")),
        };
        Ok(Some((key >> 3, value)))
    }
}

impl CanonicalFace {
    /// Parses `geometry_pipeline_metadata_landmarks.binarypb`.
    ///
    /// # Errors
    /// A message naming what is wrong with the bytes.
    pub fn parse(bytes: &[u8]) -> Result<CanonicalFace, String> {
        let mut floats = Vec::new();
        let mut basis = Vec::new();
        let mut top = Proto { bytes, at: 0 };
        while let Some((field, value)) = top.next()? {
            match (field, value) {
                (1, Value::Bytes(mesh)) => {
                    let mut mesh = Proto { bytes: mesh, at: 0 };
                    while let Some((field, value)) = mesh.next()? {
                        match (field, value) {
                            (3, Value::Fixed32(bits)) => floats.push(f32::from_bits(bits)),
                            (3, Value::Bytes(packed)) => floats.extend(
                                packed
                                    .chunks_exact(4)
                                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
                            ),
                            _ => {}
                        }
                    }
                }
                (2, Value::Bytes(reference)) => {
                    let mut reference = Proto {
                        bytes: reference,
                        at: 0,
                    };
                    let (mut id, mut weight) = (None, None);
                    while let Some((field, value)) = reference.next()? {
                        match (field, value) {
                            (1, Value::Varint(v)) => id = usize::try_from(v).ok(),
                            (2, Value::Fixed32(bits)) => weight = Some(f32::from_bits(bits)),
                            _ => {}
                        }
                    }
                    if let (Some(id), Some(weight)) = (id, weight) {
                        basis.push((id, weight));
                    }
                }
                _ => {}
            }
        }
        // Each vertex is x, y, z, u, v.
        if floats.is_empty() || floats.len() % 5 != 0 {
            return Err(format!(
                "canonical mesh has {} vertex values, not a multiple of 5",
                floats.len()
            ));
        }
        let vertices: Vec<[f32; 3]> = floats.chunks_exact(5).map(|c| [c[0], c[1], c[2]]).collect();
        if basis.len() < 3
            || basis
                .iter()
                .any(|&(i, w)| i >= vertices.len() || w.is_nan() || w <= 0.0)
        {
            return Err(format!(
                "Procrustes basis of {} landmarks does not fit {} vertices",
                basis.len(),
                vertices.len()
            ));
        }
        Ok(CanonicalFace { vertices, basis })
    }

    /// The pose of a face whose 478 landmarks (image pixels) are given, in an image of
    /// `height` pixels (for the depth) and `width` (for the centre). `None` when the landmarks
    /// are degenerate (all in one point, or not finite).
    #[must_use]
    pub fn fit(&self, landmarks: &[[f32; 3]], width: usize, height: usize) -> Option<HeadPose> {
        let to_fit_frame =
            |p: [f32; 3]| DVec3::new(f64::from(p[0]), -f64::from(p[1]), -f64::from(p[2]));
        let mut pairs = Vec::with_capacity(self.basis.len());
        for &(index, weight) in &self.basis {
            let target = to_fit_frame(*landmarks.get(index)?);
            let source = self.vertices[index].map(f64::from);
            if !target.is_finite() {
                return None;
            }
            pairs.push((DVec3::from_array(source), target, f64::from(weight)));
        }
        let total: f64 = pairs.iter().map(|p| p.2).sum();
        let source_mean = pairs.iter().map(|p| p.0 * p.2).sum::<DVec3>() / total;
        let target_mean = pairs.iter().map(|p| p.1 * p.2).sum::<DVec3>() / total;
        // Cross-covariance S[i][j] = Σ w · a_i · b_j.
        let mut s = [[0.0f64; 3]; 3];
        let (mut source_spread, mut target_spread) = (0.0, 0.0);
        for (a, b, w) in &pairs {
            let (a, b) = (*a - source_mean, *b - target_mean);
            let (a, b) = (a.to_array(), b.to_array());
            for i in 0..3 {
                for j in 0..3 {
                    s[i][j] += w * a[i] * b[j];
                }
            }
            source_spread += w * a.iter().map(|x| x * x).sum::<f64>();
            target_spread += w * b.iter().map(|x| x * x).sum::<f64>();
        }
        if source_spread <= 0.0 || target_spread <= f64::EPSILON {
            return None;
        }
        let rotation = horn_rotation(&s)?;
        // Scale: Σ w b·(R a) / Σ w |a|².
        let mut along = 0.0;
        for (a, b, w) in &pairs {
            along += w * (*b - target_mean).dot(rotation * (*a - source_mean));
        }
        let scale = along / source_spread;
        if scale.is_nan() || scale <= 0.0 {
            return None;
        }
        // Where the canonical origin lands, in pixels (fit frame), then metres from the camera.
        let origin = target_mean - rotation * source_mean * scale;
        let focal = (height as f64 / 2.0)
            / (f64::from(HeadPose::VERTICAL_FOV_DEGREES) / 2.0)
                .to_radians()
                .tan();
        let depth_cm = focal / scale;
        let (cx, cy) = (width as f64 / 2.0, -(height as f64) / 2.0);
        let translation = [
            ((origin.x - cx) / scale / 100.0) as f32,
            ((origin.y - cy) / scale / 100.0) as f32,
            (-depth_cm / 100.0) as f32,
        ];
        let (yaw, pitch, roll) = quat_to_euler(rotation);
        Some(HeadPose {
            yaw: yaw as f32,
            pitch: pitch as f32,
            roll: roll as f32,
            translation,
            pixels_per_cm: scale as f32,
        })
    }
}

/// Horn (1987): the unit quaternion maximising Σ w b·(R a) is the eigenvector of the largest
/// eigenvalue of a symmetric 4×4 matrix built from the cross-covariance.
fn horn_rotation(s: &[[f64; 3]; 3]) -> Option<DQuat> {
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = *s;
    let n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (values, vectors) = jacobi_eigen(n);
    let best = (0..4).max_by(|&a, &b| values[a].total_cmp(&values[b]))?;
    let v = [
        vectors[0][best],
        vectors[1][best],
        vectors[2][best],
        vectors[3][best],
    ];
    // Horn's vector is (w, x, y, z).
    let q = DQuat::from_xyzw(v[1], v[2], v[3], v[0]);
    let length = q.length();
    (length.is_finite() && length > 0.0).then(|| q / length)
}

/// Eigen-decomposition of a symmetric 4×4 matrix by cyclic Jacobi rotations: eigenvalues, and
/// eigenvectors as the columns of the second matrix.
fn jacobi_eigen(mut a: [[f64; 4]; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let mut v = [[0.0; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
                let t = sign / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in &mut a {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for k in 0..4 {
                    a[p][k] = c * row_p[k] - s * row_q[k];
                    a[q][k] = s * row_p[k] + c * row_q[k];
                }
                for row in &mut v {
                    let (vkp, vkq) = (row[p], row[q]);
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2], a[3][3]], v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face() -> CanonicalFace {
        let vertices: Vec<[f32; 3]> = (0..40)
            .map(|i| {
                let t = i as f32 * 0.7;
                [
                    t.sin() * 7.0,
                    (t * 1.3).cos() * 9.0,
                    (t * 0.4).sin() * 4.0 + 2.0,
                ]
            })
            .collect();
        let basis = (0..40).map(|i| (i, 1.0 + (i % 3) as f32)).collect();
        CanonicalFace { vertices, basis }
    }

    /// Landmarks (image pixels) of `face` under a known pose.
    fn project(face: &CanonicalFace, yaw: f64, pitch: f64, roll: f64, scale: f64) -> Vec<[f32; 3]> {
        let r = euler_to_quat(yaw, pitch, roll);
        face.vertices
            .iter()
            .map(|v| {
                let p = r * DVec3::from_array(v.map(f64::from)) * scale
                    + DVec3::new(320.0, -240.0, 0.0);
                [p.x as f32, -p.y as f32, -p.z as f32]
            })
            .collect()
    }

    #[test]
    fn recovers_a_known_rotation_and_scale() {
        let face = face();
        for (yaw, pitch, roll) in [
            (0.0, 0.0, 0.0),
            (25.0, -10.0, 5.0),
            (-40.0, 20.0, -15.0),
            (5.0, 35.0, 30.0),
        ] {
            let landmarks = project(&face, yaw, pitch, roll, 12.0);
            let pose = face.fit(&landmarks, 640, 480).unwrap();
            assert!(
                (f64::from(pose.yaw) - yaw).abs() < 1e-3,
                "yaw {} vs {yaw}",
                pose.yaw
            );
            assert!(
                (f64::from(pose.pitch) - pitch).abs() < 1e-3,
                "pitch {} vs {pitch}",
                pose.pitch
            );
            assert!(
                (f64::from(pose.roll) - roll).abs() < 1e-3,
                "roll {} vs {roll}",
                pose.roll
            );
            assert!((pose.pixels_per_cm - 12.0).abs() < 1e-3);
            // Centred in the image: no sideways offset.
            assert!(pose.translation[0].abs() < 1e-4 && pose.translation[1].abs() < 1e-4);
            assert!(pose.translation[2] < 0.0);
        }
    }

    #[test]
    fn degenerate_landmarks_give_no_pose() {
        let face = face();
        assert!(face.fit(&vec![[5.0, 5.0, 0.0]; 40], 640, 480).is_none());
        assert!(
            face.fit(&vec![[f32::NAN, 5.0, 0.0]; 40], 640, 480)
                .is_none()
        );
        assert!(face.fit(&[[0.0; 3]; 3], 640, 480).is_none());
    }

    #[test]
    fn truncated_metadata_is_an_error() {
        assert!(CanonicalFace::parse(&[0x0a, 0x05, 0x1d]).is_err());
        assert!(CanonicalFace::parse(&[]).is_err());
    }
}
