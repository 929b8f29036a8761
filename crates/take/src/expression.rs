//! The generic expression of one face: what capture measured, before any character — the 52
//! expression scores and the landmarks with the head pose taken out.
//!
//! Landmarks are made independent of where the head is and how it is turned: centred, rotated
//! back by the fitted head pose and scaled to unit spread, so a frontal render and a turned
//! webcam face give comparable numbers. Estimators (by name, by a character's adapter) read
//! expressions; sessions keep them for re-estimating and fine-tuning.

use faceanim_track::BLENDSHAPE_LANDMARKS;
use serde::{Deserialize, Serialize};

/// Number of expression scores (MediaPipe's 52, `_neutral` first).
pub const SCORES: usize = 52;
/// Number of landmark coordinates: x, y, z of the blendshape model's 146 landmarks.
pub const LANDMARK_COORDINATES: usize = BLENDSHAPE_LANDMARKS.len() * 3;

/// The generic expression of one face: what capture measured, before any character.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Expression {
    /// The 52 scores in MediaPipe's order.
    pub scores: Vec<f32>,
    /// [`LANDMARK_COORDINATES`] pose-normalised coordinates.
    pub landmarks: Vec<f32>,
}

impl Expression {
    /// From one captured face: its 52 scores, 478 landmarks (image pixels) and head pose
    /// (yaw, pitch, roll in degrees; `None` leaves the rotation in). `None` when the face is
    /// incomplete or degenerate.
    #[must_use]
    pub fn from_face(
        scores: &[f32],
        landmarks: &[[f32; 3]],
        head: Option<[f32; 3]>,
    ) -> Option<Expression> {
        if scores.len() != SCORES || landmarks.len() < 468 {
            return None;
        }
        Some(Expression {
            scores: scores.to_vec(),
            landmarks: normalised_landmarks(landmarks, head)?,
        })
    }

    /// How far the face is from rest: the sum of its 51 ARKit scores (MediaPipe's `_neutral`
    /// left out). A relaxed face scores near 0.
    #[must_use]
    pub fn energy(&self) -> f32 {
        self.scores.iter().skip(1).map(|s| s.clamp(0.0, 1.0)).sum()
    }

    /// From one frame capture recorded (see [`Expression::from_face`]).
    #[must_use]
    pub fn from_record(record: &faceanim_capture::FrameRecord) -> Option<Expression> {
        let scores: Vec<f32> = record.scores.iter().map(|s| s.1).collect();
        Expression::from_face(&scores, &record.landmarks, record.head)
    }
}

/// The parts of a face that come to rest on their own. A person seldom has every part at rest
/// in the same frame (the eyes wide open while the mouth is mid-word, the brows up while
/// listening, the eyes on a screen below the camera), so a take's automatic neutral face takes
/// each part from the frame where that part is calmest ([`calmest_parts`], [`rest_face`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FacePart {
    /// The eyelids (blinking, squinting, widening), wherever the eyes look.
    Lids,
    /// Where the eyes look: the eyeLook scores and the irises.
    Gaze,
    /// The brows.
    Brows,
    /// The rest: mouth, jaw, cheeks and nose, and the face's outline.
    Mouth,
}

/// MediaPipe's landmarks (indices into the 478) of the two eyelids' contours.
const LIDS: [usize; 32] = [
    33, 7, 163, 144, 145, 153, 154, 155, 133, 173, 157, 158, 159, 160, 161, 246, 263, 249, 390,
    373, 374, 380, 381, 382, 362, 398, 384, 385, 386, 387, 388, 466,
];
/// MediaPipe's landmarks of the two brows.
const BROWS: [usize; 20] = [
    46, 52, 53, 55, 63, 65, 66, 70, 105, 107, 276, 282, 283, 285, 293, 295, 296, 300, 334, 336,
];
/// MediaPipe's iris landmarks (centre and four points, each eye).
const IRISES: std::ops::RangeInclusive<usize> = 468..=477;

impl FacePart {
    /// Every part.
    pub const ALL: [FacePart; 4] = [
        FacePart::Lids,
        FacePart::Gaze,
        FacePart::Brows,
        FacePart::Mouth,
    ];

    /// The part MediaPipe's score `name` (one of [`faceanim_track::BLENDSHAPE_NAMES`]) belongs
    /// to.
    #[must_use]
    pub fn of_score(name: &str) -> FacePart {
        use faceanim_rig::names::Region;
        match faceanim_rig::names::region(name) {
            Region::Gaze => FacePart::Gaze,
            Region::Lids => FacePart::Lids,
            Region::Brows => FacePart::Brows,
            Region::Cheeks | Region::Nose | Region::Jaw | Region::Mouth | Region::Tongue => {
                FacePart::Mouth
            }
        }
    }

    /// The part MediaPipe's landmark `index` (into the 478) belongs to.
    #[must_use]
    pub fn of_landmark(index: usize) -> FacePart {
        if IRISES.contains(&index) {
            FacePart::Gaze
        } else if LIDS.contains(&index) {
            FacePart::Lids
        } else if BROWS.contains(&index) {
            FacePart::Brows
        } else {
            FacePart::Mouth
        }
    }

    /// How far apart two expressions are in this part: the summed differences of its ARKit
    /// scores (MediaPipe's `_neutral` left out).
    #[must_use]
    pub fn distance(self, a: &Expression, b: &Expression) -> f32 {
        score_parts()
            .iter()
            .zip(a.scores.iter().zip(&b.scores))
            .skip(1)
            .filter(|(part, _)| **part == self)
            .map(|(_, (x, y))| (x - y).abs())
            .sum()
    }

    /// How far this part of `expression` is from rest: the sum of its ARKit scores (MediaPipe's
    /// `_neutral` left out), as [`Expression::energy`] sums the whole face's.
    #[must_use]
    pub fn energy(self, expression: &Expression) -> f32 {
        score_parts()
            .iter()
            .zip(&expression.scores)
            .skip(1)
            .filter(|(part, _)| **part == self)
            .map(|(_, s)| s.clamp(0.0, 1.0))
            .sum()
    }
}

/// The part of each of MediaPipe's scores, in their order ([`FacePart::of_score`] worked out
/// once: a take's neutral is found over every frame each time a view asks for it).
fn score_parts() -> &'static [FacePart; SCORES] {
    static PARTS: std::sync::LazyLock<[FacePart; SCORES]> =
        std::sync::LazyLock::new(|| faceanim_track::BLENDSHAPE_NAMES.map(FacePart::of_score));
    &PARTS
}

/// The frame each [`FacePart`] of a neutral face comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartFrames {
    /// The eyelids' frame.
    pub lids: usize,
    /// The gaze's frame.
    pub gaze: usize,
    /// The brows' frame.
    pub brows: usize,
    /// The mouth's (and the rest of the face's) frame.
    pub mouth: usize,
}

impl PartFrames {
    /// Every part from `frame`.
    #[must_use]
    pub fn all(frame: usize) -> PartFrames {
        PartFrames {
            lids: frame,
            gaze: frame,
            brows: frame,
            mouth: frame,
        }
    }

    /// The frame of `part`.
    #[must_use]
    pub fn of(self, part: FacePart) -> usize {
        match part {
            FacePart::Lids => self.lids,
            FacePart::Gaze => self.gaze,
            FacePart::Brows => self.brows,
            FacePart::Mouth => self.mouth,
        }
    }

    /// Whether every part comes from the same frame.
    #[must_use]
    pub fn is_one_frame(self) -> bool {
        FacePart::ALL.iter().all(|p| self.of(*p) == self.mouth)
    }
}

impl std::fmt::Display for PartFrames {
    /// `frame N` when every part comes from it, else `lids 3, gaze 9, brows 3, mouth 12`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_one_frame() {
            write!(f, "frame {}", self.mouth)
        } else {
            write!(
                f,
                "lids {}, gaze {}, brows {}, mouth {}",
                self.lids, self.gaze, self.brows, self.mouth
            )
        }
    }
}

/// Each [`FacePart`]'s rest frame among `expressions`, the automatic neutral of a take;
/// `None` when fewer than two frames have a face (a single picture is not read against
/// itself: an adapter then uses the neutral face typical of its training).
///
/// In a video (frames that follow on from one another, [`frames_follow_on`]) a part rests at
/// its calmest frame: the least [`FacePart::energy`], the earliest of equals. Among nine or
/// more unrelated photos (a folder of stills) it rests at the most typical of its calmest
/// quarter ([`CALM_SHARE`]): the frame whose scores of that part differ least from theirs.
/// The least energy can be a face pulled the other way there: brows lowered read to MediaPipe
/// as brows less raised, not as `browDown`, on a face whose brows read raised at rest (an ICT
/// head in Cycles: `browInnerUp` 0.73 at rest), and that still, taken as the brows' rest, made
/// every other read its outer brows raised (0.78 too much on average over 40 stills). On a
/// video the same rule made real footage follow MediaPipe less (the weakest shape of two of
/// three videos: r 0.95 → 0.86 and 0.89 → 0.84): a talking face's calmest frame is its rest.
/// Fewer photos say too little of what is typical: their calmest frame.
#[must_use]
pub fn calmest_parts(expressions: &[Option<&Expression>]) -> Option<PartFrames> {
    let faces: Vec<(usize, &Expression)> = expressions
        .iter()
        .enumerate()
        .filter_map(|(k, e)| e.map(|e| (k, e)))
        .collect();
    if faces.len() < 2 {
        return None;
    }
    let in_order: Vec<&Expression> = faces.iter().map(|(_, e)| *e).collect();
    let share = if frames_follow_on(&in_order) {
        None
    } else {
        Some(CALM_SHARE)
    };
    let rest = |part: FacePart| {
        let mut calm: Vec<(usize, &Expression, f32)> =
            faces.iter().map(|&(k, e)| (k, e, part.energy(e))).collect();
        let keep = share.map_or(1, |share| (calm.len() as f32 * share).ceil() as usize);
        // Fewer than three say nothing of what is typical: the calmest, the earliest of equal
        // energies (`min_by` keeps the first), found without sorting a video's every frame.
        if keep < 3 {
            return calm
                .iter()
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map_or(0, |c| c.0);
        }
        // Stable: the earliest of equal energies first.
        calm.sort_by(|a, b| a.2.total_cmp(&b.2));
        calm.truncate(keep);
        // The most typical; of equals, the calmest.
        calm.iter()
            .enumerate()
            .map(|(rank, (k, e, _))| {
                let apart: f32 = calm.iter().map(|(_, o, _)| part.distance(e, o)).sum();
                (apart, rank, *k)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map_or(0, |(_, _, k)| k)
    };
    Some(PartFrames {
        lids: rest(FacePart::Lids),
        gaze: rest(FacePart::Gaze),
        brows: rest(FacePart::Brows),
        mouth: rest(FacePart::Mouth),
    })
}

/// The share of a set of photos, the calmest by each part, among which that part's rest is
/// the most typical ([`calmest_parts`]). A quarter: on stills of the seed's groups (one, two or
/// three shapes, or every shape at once, in turn) most leave any one part at rest.
pub const CALM_SHARE: f32 = 0.25;

/// Frames follow on from one another (a video, a webcam take, a photo made an animation) when
/// consecutive faces differ by less than this share of what faces a quarter, half or three
/// quarters of the take apart do (median distances over their scores). Consecutive frames of
/// a video differ by a tenth to a seventh of that (three real videos: 0.08–0.15); unrelated
/// photos by as much.
pub const FOLLOW_ON: f32 = 0.5;

/// Whether `faces` (in order, faceless frames left out) follow on from one another
/// ([`FOLLOW_ON`]): a video's frames, not a folder of unrelated photos. Faces all alike follow
/// on.
#[must_use]
pub fn frames_follow_on(faces: &[&Expression]) -> bool {
    let n = faces.len();
    if n < 2 {
        return true;
    }
    let median = |mut d: Vec<f32>| {
        d.sort_by(f32::total_cmp);
        d[d.len() / 2]
    };
    let apart = |a: &Expression, b: &Expression| -> f32 {
        a.scores
            .iter()
            .zip(&b.scores)
            .skip(1)
            .map(|(x, y)| (x - y).abs())
            .sum()
    };
    let next = median(faces.windows(2).map(|w| apart(w[0], w[1])).collect());
    // A quarter, half and three quarters of the take apart, so that a video whose face comes
    // back on a beat (a mouth opening and shutting) is not taken for unrelated photos.
    let far = median(
        [n / 4, n / 2, 3 * n / 4]
            .into_iter()
            .filter(|&offset| offset > 0)
            .flat_map(|offset| (0..n).map(move |k| (k, (k + offset) % n)))
            .map(|(a, b)| apart(faces[a], faces[b]))
            .collect(),
    );
    next <= FOLLOW_ON * far
}

/// The neutral face made of each part of `expressions` at its frame in `parts`: scores and
/// landmarks of a part from that part's frame, the landmarks moved onto the mouth's frame by
/// the similarity that takes their own frame's [`RIGID`] landmarks onto the mouth frame's (the
/// pose-normalised landmarks of two frames are placed by the whole face, which an open jaw
/// shifts). `None` when a part's frame has no face.
#[must_use]
pub fn rest_face(expressions: &[Option<&Expression>], parts: PartFrames) -> Option<Expression> {
    let face = |part: FacePart| expressions.get(parts.of(part)).copied().flatten();
    let base = face(FacePart::Mouth)?;
    if parts.is_one_frame() {
        return Some(base.clone());
    }
    let (base_centre, base_spread) = rigid_placement(&base.landmarks);
    let mut rest = base.clone();
    for part in [FacePart::Lids, FacePart::Gaze, FacePart::Brows] {
        let from = face(part)?;
        for ((of, slot), score) in score_parts().iter().zip(&mut rest.scores).zip(&from.scores) {
            if *of == part {
                *slot = *score;
            }
        }
        let (centre, spread) = rigid_placement(&from.landmarks);
        let scale = base_spread / spread;
        for ((landmark, slot), point) in BLENDSHAPE_LANDMARKS
            .iter()
            .zip(rest.landmarks.chunks_exact_mut(3))
            .zip(from.landmarks.chunks_exact(3))
        {
            if FacePart::of_landmark(*landmark) == part {
                let moved = (glam::Vec3::from_slice(point) - centre) * scale + base_centre;
                slot.copy_from_slice(&moved.to_array());
            }
        }
    }
    Some(rest)
}

/// MediaPipe's landmarks (indices into the 478) that expressions hardly move: the nose from
/// bridge to tip, the eyes' inner and outer corners, the forehead and the temples. All are
/// among the blendshape model's landmarks. They place a face's landmarks by its rigid part
/// ([`rigid_frame`]).
pub const RIGID: [usize; 26] = [
    1, 4, 5, 6, 168, 195, 197, 133, 362, 33, 263, 10, 21, 54, 103, 67, 109, 251, 284, 332, 297,
    338, 127, 234, 356, 454,
];

/// The centre and the root mean square spread of the [`RIGID`] landmarks among `landmarks`
/// (an [`Expression`]'s, three coordinates each); a spread of 1 where they have none.
fn rigid_placement(landmarks: &[f32]) -> (glam::Vec3, f32) {
    let point = |k: usize| {
        landmarks
            .get(3 * k..3 * k + 3)
            .map_or(glam::Vec3::ZERO, glam::Vec3::from_slice)
    };
    let rigid: Vec<glam::Vec3> = BLENDSHAPE_LANDMARKS
        .iter()
        .enumerate()
        .filter(|(_, l)| RIGID.contains(l))
        .map(|(k, _)| point(k))
        .collect();
    let centre = rigid.iter().copied().sum::<glam::Vec3>() / rigid.len().max(1) as f32;
    let spread = (rigid
        .iter()
        .map(|p| (*p - centre).length_squared())
        .sum::<f32>()
        / rigid.len().max(1) as f32)
        .sqrt();
    (centre, if spread > f32::EPSILON { spread } else { 1.0 })
}

/// `landmarks` (an [`Expression`]'s, three coordinates each) moved and scaled so that the
/// [`RIGID`] ones are centred at the origin with unit spread. A similarity of the whole-face
/// frame, so it can be applied to features recorded in it.
#[must_use]
pub fn rigid_frame(landmarks: &[f32]) -> Vec<f32> {
    let (centre, spread) = rigid_placement(landmarks);
    let scale = 1.0 / spread;
    landmarks
        .chunks_exact(3)
        .flat_map(|p| ((glam::Vec3::from_slice(p) - centre) * scale).to_array())
        .collect()
}

/// The blendshape model's landmarks with the pose removed: into a y-up frame, centred on the
/// mean of all landmarks, turned back by the head rotation, divided by their RMS distance from
/// the centre. `None` for non-finite or collapsed landmarks.
#[must_use]
pub fn normalised_landmarks(landmarks: &[[f32; 3]], head: Option<[f32; 3]>) -> Option<Vec<f32>> {
    // Image pixels (y down, z away) to the pose fit's frame (y up, z towards the viewer).
    let points: Vec<glam::Vec3> = landmarks
        .iter()
        .map(|p| glam::Vec3::new(p[0], -p[1], -p[2]))
        .collect();
    if points.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let centre = points.iter().copied().sum::<glam::Vec3>() / points.len() as f32;
    let spread = (points
        .iter()
        .map(|p| (*p - centre).length_squared())
        .sum::<f32>()
        / points.len() as f32)
        .sqrt();
    if spread <= f32::EPSILON {
        return None;
    }
    let unturn = match head {
        Some(angles) => glam::Quat::from_array(faceanim_anim::head_rotation(angles)).inverse(),
        None => glam::Quat::IDENTITY,
    };
    let mut out = Vec::with_capacity(LANDMARK_COORDINATES);
    for &index in &BLENDSHAPE_LANDMARKS {
        let p = unturn * (*points.get(index)? - centre) / spread;
        out.extend_from_slice(&p.to_array());
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up face's landmarks as an [`Expression`] stores them (the blendshape model's
    /// 146, three coordinates each), deterministic.
    fn landmarks() -> Vec<f32> {
        (0..LANDMARK_COORDINATES)
            .map(|k| ((k * 53) % 97) as f32 / 40.0 - 1.0)
            .collect()
    }

    /// The landmark positions (into the 146) of one part.
    fn of_part(part: FacePart) -> Vec<usize> {
        (0..BLENDSHAPE_LANDMARKS.len())
            .filter(|k| FacePart::of_landmark(BLENDSHAPE_LANDMARKS[*k]) == part)
            .collect()
    }

    fn score(name: &str) -> usize {
        faceanim_track::BLENDSHAPE_NAMES
            .iter()
            .position(|n| *n == name)
            .unwrap()
    }

    #[test]
    fn every_score_and_landmark_belongs_to_its_part() {
        let part = |name: &str| FacePart::of_score(name);
        assert_eq!(part("eyeBlinkLeft"), FacePart::Lids);
        assert_eq!(part("eyeSquintRight"), FacePart::Lids);
        assert_eq!(part("eyeWideLeft"), FacePart::Lids);
        assert_eq!(part("eyeLookDownRight"), FacePart::Gaze);
        assert_eq!(part("browInnerUp"), FacePart::Brows);
        for mouth in [
            "jawOpen",
            "mouthSmileLeft",
            "cheekSquintLeft",
            "noseSneerRight",
        ] {
            assert_eq!(part(mouth), FacePart::Mouth, "{mouth}");
        }
        // Both eyes' lids, irises and brows, all among the blendshape model's landmarks.
        let counts = FacePart::ALL.map(|p| of_part(p).len());
        assert_eq!(counts[..3], [32, 10, 20], "{counts:?}");
        assert_eq!(counts.iter().sum::<usize>(), BLENDSHAPE_LANDMARKS.len());
    }

    /// Frame 0 has its eyes half shut and its mouth at rest; frame 1 its eyes open and its jaw
    /// open, which moves the whole-face frame its landmarks are stored in (a shift and a
    /// scale). The neutral face takes the open lids of frame 1, placed where they belong in
    /// frame 0, and frame 0's mouth.
    #[test]
    fn each_part_of_the_neutral_face_comes_from_its_calmest_frame() {
        let face = landmarks();
        let (lids, mouth) = (of_part(FacePart::Lids), of_part(FacePart::Mouth));
        let (blink, jaw) = (score("eyeBlinkLeft"), score("jawOpen"));
        let mut shut = Expression {
            scores: vec![0.0; SCORES],
            landmarks: face.clone(),
        };
        shut.scores[blink] = 0.6;
        // The lids close between the eyes' corners, which stay.
        for &k in lids
            .iter()
            .filter(|k| !RIGID.contains(&BLENDSHAPE_LANDMARKS[**k]))
        {
            shut.landmarks[3 * k + 1] -= 0.05;
        }
        let mut open = Expression {
            scores: vec![0.0; SCORES],
            landmarks: face.clone(),
        };
        open.scores[jaw] = 0.7;
        let chin = mouth
            .iter()
            .copied()
            .filter(|k| !RIGID.contains(&BLENDSHAPE_LANDMARKS[*k]));
        for k in chin.clone() {
            open.landmarks[3 * k + 1] -= 0.3;
        }
        // Stored relative to a centre the open jaw lowered, and a spread it widened.
        open.landmarks = open
            .landmarks
            .chunks_exact(3)
            .flat_map(|p| {
                ((glam::Vec3::from_slice(p) - glam::Vec3::new(0.0, -0.1, 0.0)) / 1.2).to_array()
            })
            .collect();
        let faces = [Some(&shut), Some(&open)];
        let parts = calmest_parts(&faces).unwrap();
        assert_eq!(
            parts,
            PartFrames {
                lids: 1,
                gaze: 0,
                brows: 0,
                mouth: 0
            }
        );
        assert_eq!(parts.to_string(), "lids 1, gaze 0, brows 0, mouth 0");
        let rest = rest_face(&faces, parts).unwrap();
        assert_eq!((rest.scores[blink], rest.scores[jaw]), (0.0, 0.0));
        let worst = (0..BLENDSHAPE_LANDMARKS.len())
            .flat_map(|k| (0..3).map(move |c| 3 * k + c))
            .map(|i| (rest.landmarks[i] - face[i]).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-5, "the rest face is off by {worst}");

        // One frame is not read against itself; a frame without a face is never chosen.
        assert_eq!(calmest_parts(&[Some(&shut), None]), None);
        let parts = calmest_parts(&[None, Some(&open), Some(&shut)]).unwrap();
        assert_eq!((parts.lids, parts.mouth), (1, 2));
        assert_eq!(PartFrames::all(4).to_string(), "frame 4");
        assert_eq!(rest_face(&faces, PartFrames::all(1)).unwrap(), open);
    }

    /// Twelve unrelated photos of a face whose brows read raised at rest (`browInnerUp` 0.7,
    /// `browOuterUp` 0.5), each with its own mouth and lids; photo 5 lowers its brows, which
    /// MediaPipe reads only as brows less raised (the least brow energy), photo 2 raises them.
    fn photos() -> Vec<Expression> {
        let (inner, outer) = (score("browInnerUp"), score("browOuterUpLeft"));
        let (jaw, blink) = (score("jawOpen"), score("eyeBlinkLeft"));
        (0..12)
            .map(|k| {
                let mut e = Expression {
                    scores: vec![0.0; SCORES],
                    landmarks: landmarks(),
                };
                e.scores[inner] = 0.7 + 0.01 * (k % 3) as f32;
                e.scores[outer] = match k {
                    5 => 0.15,
                    2 => 0.9,
                    _ => 0.5 + 0.02 * (k % 2) as f32,
                };
                e.scores[jaw] = [0.0, 0.8, 0.1, 0.6, 0.05, 0.9, 0.3, 0.7, 0.5, 0.2, 0.85, 0.4][k];
                e.scores[blink] = [0.9, 0.0, 0.6, 0.1, 0.8, 0.2, 0.7, 0.0, 0.5, 0.9, 0.3, 0.6][k];
                e
            })
            .collect()
    }

    #[test]
    fn unrelated_photos_rest_at_a_typical_calm_face_and_a_video_at_its_calmest() {
        let photos = photos();
        let folder: Vec<Option<&Expression>> = photos.iter().map(Some).collect();
        let faces: Vec<&Expression> = photos.iter().collect();
        assert!(
            !frames_follow_on(&faces),
            "unrelated photos do not follow on"
        );
        let parts = calmest_parts(&folder).unwrap();
        // Not photo 5, whose brows are pulled the other way, nor the raised ones of photo 2.
        assert!(
            ![5, 2].contains(&parts.brows),
            "the brows rest at photo {}",
            parts.brows
        );
        // The mouth rests where it is closed or nearly (photos 0, 2, 4), the lids where they
        // are open or nearly (photos 1, 3, 7).
        assert!([0, 2, 4].contains(&parts.mouth), "{parts}");
        assert!([1, 3, 7].contains(&parts.lids), "{parts}");
        // Eight photos are too few to say what is typical: the calmest.
        let few = &folder[..8];
        assert_eq!(calmest_parts(few).unwrap().brows, 5);

        // The same faces as a video, each held for four frames: its calmest frame is the rest,
        // photo 5's brows included.
        let video: Vec<Option<&Expression>> = photos
            .iter()
            .flat_map(|e| std::iter::repeat_n(Some(e), 4))
            .collect();
        let frames: Vec<&Expression> = video.iter().flatten().copied().collect();
        assert!(frames_follow_on(&frames), "a video follows on");
        let parts = calmest_parts(&video).unwrap();
        assert_eq!(parts.brows, 5 * 4, "{parts}");
        assert_eq!(parts.mouth, 0, "{parts}");
    }

    #[test]
    fn the_rigid_frame_ignores_where_the_face_was_placed_and_how_big_it_was() {
        let landmarks: Vec<f32> = (0..LANDMARK_COORDINATES)
            .map(|k| ((k * 37) % 101) as f32 / 50.0 - 1.0)
            .collect();
        let moved: Vec<f32> = landmarks
            .iter()
            .enumerate()
            .map(|(k, v)| 2.5 * v + [0.3, -1.0, 0.7][k % 3])
            .collect();
        for (a, b) in rigid_frame(&landmarks).iter().zip(rigid_frame(&moved)) {
            assert!((a - b).abs() < 1e-4, "{a} {b}");
        }
    }

    #[test]
    fn an_open_jaw_moves_no_eye_landmark_in_the_rigid_frame() {
        let landmarks: Vec<f32> = (0..LANDMARK_COORDINATES)
            .map(|k| ((k * 53) % 97) as f32 / 40.0 - 1.0)
            .collect();
        // The chin and lower lip drop; nothing else moves.
        let jaw = [17, 14, 152, 148, 176, 377, 400, 84, 314];
        let mut open = landmarks.clone();
        for (k, l) in BLENDSHAPE_LANDMARKS.iter().enumerate() {
            if jaw.contains(l) {
                open[3 * k + 1] -= 0.8;
            }
        }
        let (before, after) = (rigid_frame(&landmarks), rigid_frame(&open));
        let eye = BLENDSHAPE_LANDMARKS
            .iter()
            .position(|l| *l == 145)
            .unwrap_or(0);
        assert!((before[3 * eye + 1] - after[3 * eye + 1]).abs() < 1e-6);
    }

    #[test]
    fn turning_moving_and_scaling_a_face_leaves_its_features() {
        // A made-up face: landmarks on a squashed sphere, deterministic.
        let face: Vec<[f32; 3]> = (0..478)
            .map(|i| {
                let t = i as f32 * 0.37;
                [
                    40.0 * t.sin() * (0.5 * t).cos(),
                    55.0 * (0.5 * t).sin(),
                    30.0 * t.cos(),
                ]
            })
            .collect();
        let head = [25.0, -10.0, 8.0];
        let turn = glam::Quat::from_array(faceanim_anim::head_rotation(head));
        // The same face turned by `head`, scaled 1.7× and moved, in image coordinates.
        let moved: Vec<[f32; 3]> = face
            .iter()
            .map(|p| {
                let fit = glam::Vec3::new(p[0], -p[1], -p[2]);
                let q = turn * fit * 1.7 + glam::Vec3::new(300.0, -200.0, 5.0);
                [q.x, -q.y, -q.z]
            })
            .collect();
        let a = normalised_landmarks(&face, None).unwrap();
        let b = normalised_landmarks(&moved, Some(head)).unwrap();
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-4, "features moved by {worst}");
        assert_eq!(a.len(), LANDMARK_COORDINATES);
    }

    #[test]
    fn degenerate_faces_have_no_features() {
        assert!(normalised_landmarks(&[[1.0, 2.0, 3.0]; 478], None).is_none());
        let mut nan = vec![[0.0, 0.0, 0.0]; 478];
        nan[3] = [f32::NAN, 0.0, 0.0];
        assert!(normalised_landmarks(&nan, None).is_none());
    }
}
