//! The paper's parameters (section 3.9), with defaults relative to the character's size `D`
//! (the diagonal of its bounding box), as the authors' code sets them.

use serde::{Deserialize, Serialize};

/// How an exaggeration fades from the reference vertex to the edge of the editing radius, as a
/// function of `t = 1 − d/R` (1 at the reference vertex, 0 at the radius), where `d` is the
/// distance along the mesh's edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Falloff {
    /// `3t² − 2t³`: smooth at both ends (the default).
    #[default]
    Smooth,
    /// `t`.
    Linear,
    /// `t²`: a pointed peak.
    Sharp,
    /// `√t`: a broad plateau.
    Root,
    /// `√(2t − t²)`: a spherical cap.
    Sphere,
    /// `1` everywhere inside the radius.
    Constant,
}

impl Falloff {
    /// The influence at edge-graph distance `distance` from the reference vertex.
    #[must_use]
    pub fn weight(self, distance: f32, radius: f32) -> f32 {
        if radius <= 0.0 || distance >= radius {
            return if distance <= 0.0 { 1.0 } else { 0.0 };
        }
        let t = (1.0 - distance / radius).clamp(0.0, 1.0);
        match self {
            Falloff::Smooth => t * t * (3.0 - 2.0 * t),
            Falloff::Linear => t,
            Falloff::Sharp => t * t,
            Falloff::Root => t.sqrt(),
            Falloff::Sphere => (2.0 * t - t * t).max(0.0).sqrt(),
            Falloff::Constant => 1.0,
        }
    }
}

/// One stroke picks one blendshape (the paper), or solves all weights at once (direct
/// manipulation, Lewis & Anjyo 2010; the paper's future work).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StrokeMode {
    /// The blendshape whose target is nearest the stroke end (Eq. 1).
    #[default]
    Single,
    /// Bounded least squares over all weights so the reference vertex reaches the stroke end.
    Multi,
}

/// How the target blendshape is chosen among the candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Selection {
    /// Nearest target position to the stroke end (the paper's Eq. 1).
    #[default]
    End,
    /// The end, plus how closely the whole drawn path follows each candidate's motion.
    Path,
    /// The candidate whose motion (the segment from rest to full weight) passes nearest the
    /// end, so a stroke stopped part-way selects that blendshape at a partial weight instead
    /// of whichever smaller blendshape's full target happens to be nearer (Eq. 1's weakness).
    Segment,
}

/// Sketching parameters as stored in a strokes file; `None` means "derived from the size".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Blendshapes moving the reference vertex by more than this are candidates (`D/200`).
    ///
    /// The authors used `D/65` on a face-only model. Measured on a whole head (the ICT head's
    /// diagonal spans skull and neck), `D/65` is 7.3 mm and hides shapes that visibly move the
    /// lip corner (mouthFrown 6.1 mm, mouthPress 4.3 mm); `D/200` (2.4 mm) keeps them.
    pub candidate_radius: Option<f32>,
    /// A stroke must start this close to the mesh (`D/10`).
    pub pen_distance: Option<f32>,
    /// Radius of the exaggeration falloff, along the mesh (`D/16`).
    ///
    /// The authors used `D/6.5` on a face-only model; on a whole head (ICT: 7.3 cm) that bends
    /// the nose when a lip corner is exaggerated. `D/16` (3 cm on ICT) covers the feature drawn
    /// on, as an animator's proportional-editing radius would.
    pub edit_radius: Option<f32>,
    /// A stroke starting this close to a chain's end continues that chain (`D/200`).
    pub hook_radius: Option<f32>,
    /// The middle handle snaps to straight within this distance of the chord's midpoint (`D/100`).
    pub snap_distance: Option<f32>,
    /// Drawn line width in the studio (`D/400`); no effect on the animation.
    pub stroke_thickness: Option<f32>,
    /// A keyframe every this many samples (the paper's sampling setting).
    pub subsample: u32,
    /// Exaggeration falloff.
    pub falloff: Falloff,
    /// Mirror strokes whose blendshape has a left/right partner.
    pub symmetry: bool,
    /// Single- or multi-blendshape strokes.
    pub mode: StrokeMode,
    /// Target selection rule.
    pub selection: Selection,
    /// `St_Max` of Eq. 4: the steepest ease-in exponent (α = 0).
    pub steepness_max: f32,
    /// `St_min` of Eq. 4: the gentlest exponent (α = 1).
    pub steepness_min: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            candidate_radius: None,
            pen_distance: None,
            edit_radius: None,
            hook_radius: None,
            snap_distance: None,
            stroke_thickness: None,
            subsample: 3,
            falloff: Falloff::Smooth,
            symmetry: false,
            mode: StrokeMode::Single,
            selection: Selection::End,
            steepness_max: 5.0,
            steepness_min: 0.01,
        }
    }
}

/// Settings with every distance resolved for one character.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Resolved {
    /// See [`Settings::candidate_radius`].
    pub candidate_radius: f32,
    /// See [`Settings::pen_distance`].
    pub pen_distance: f32,
    /// See [`Settings::edit_radius`].
    pub edit_radius: f32,
    /// See [`Settings::hook_radius`].
    pub hook_radius: f32,
    /// See [`Settings::snap_distance`].
    pub snap_distance: f32,
    /// See [`Settings::stroke_thickness`].
    pub stroke_thickness: f32,
    /// See [`Settings::subsample`] (at least 1).
    pub subsample: usize,
    /// See [`Settings::falloff`].
    pub falloff: Falloff,
    /// See [`Settings::symmetry`].
    pub symmetry: bool,
    /// See [`Settings::mode`].
    pub mode: StrokeMode,
    /// See [`Settings::selection`].
    pub selection: Selection,
    /// See [`Settings::steepness_max`].
    pub steepness_max: f32,
    /// See [`Settings::steepness_min`].
    pub steepness_min: f32,
}

impl Settings {
    /// Resolves `None` distances against the character size `size` (its bounding-box diagonal).
    #[must_use]
    pub fn resolve(&self, size: f32) -> Resolved {
        Resolved {
            candidate_radius: self.candidate_radius.unwrap_or(size / 200.0),
            pen_distance: self.pen_distance.unwrap_or(size / 10.0),
            edit_radius: self.edit_radius.unwrap_or(size / 16.0),
            hook_radius: self.hook_radius.unwrap_or(size / 200.0),
            snap_distance: self.snap_distance.unwrap_or(size / 100.0),
            stroke_thickness: self.stroke_thickness.unwrap_or(size / 400.0),
            subsample: self.subsample.max(1) as usize,
            falloff: self.falloff,
            symmetry: self.symmetry,
            mode: self.mode,
            selection: self.selection,
            steepness_max: self.steepness_max,
            steepness_min: self.steepness_min,
        }
    }

    /// Every problem with the values, each with its path (`settings.edit_radius`).
    #[must_use]
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (name, value) in [
            ("candidate_radius", self.candidate_radius),
            ("pen_distance", self.pen_distance),
            ("edit_radius", self.edit_radius),
            ("hook_radius", self.hook_radius),
            ("snap_distance", self.snap_distance),
            ("stroke_thickness", self.stroke_thickness),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && v >= 0.0)
            {
                out.push(format!(
                    "settings.{name}: must be a distance ≥ 0 or null, found {v}"
                ));
            }
        }
        if !(self.steepness_max.is_finite() && self.steepness_max >= 1.0) {
            out.push(format!(
                "settings.steepness_max: must be ≥ 1, found {}",
                self.steepness_max
            ));
        }
        if !(self.steepness_min.is_finite()
            && self.steepness_min > 0.0
            && self.steepness_min <= 1.0)
        {
            out.push(format!(
                "settings.steepness_min: must be in (0, 1], found {}",
                self.steepness_min
            ));
        }
        out
    }
}

impl Resolved {
    /// The exponent `p` of the easing remap `y = x^p` for handle position `alpha` (Eq. 4):
    /// `St_Max` at α = 0, 1 at α = 0.5, `St_min` at α = 1, linear in between.
    #[must_use]
    pub fn easing_exponent(&self, alpha: f32) -> f32 {
        let alpha = alpha.clamp(0.0, 1.0);
        if alpha < 0.5 {
            self.steepness_max - 2.0 * alpha * (self.steepness_max - 1.0)
        } else {
            1.0 - 2.0 * (alpha - 0.5) * (1.0 - self.steepness_min)
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "these values are exact by construction")]
mod tests {
    use super::*;

    #[test]
    fn falloffs_are_one_at_the_centre_and_zero_at_the_radius() {
        for f in [
            Falloff::Smooth,
            Falloff::Linear,
            Falloff::Sharp,
            Falloff::Root,
            Falloff::Sphere,
        ] {
            assert!((f.weight(0.0, 2.0) - 1.0).abs() < 1e-6, "{f:?}");
            assert!(f.weight(2.0, 2.0).abs() < 1e-6, "{f:?}");
            assert!(
                f.weight(1.0, 2.0) > 0.0 && f.weight(1.0, 2.0) < 1.0,
                "{f:?}"
            );
        }
        assert_eq!(Falloff::Constant.weight(1.9, 2.0), 1.0);
        assert_eq!(Falloff::Smooth.weight(1.0, 2.0), 0.5);
    }

    #[test]
    fn easing_exponent_matches_the_authors_code() {
        let r = Settings::default().resolve(1.0);
        // p = 5 − 8α below 0.5 and 1 − 1.98(α − 0.5) above, as in the authors' code.
        for alpha in [0.0f32, 0.1, 0.25, 0.4] {
            assert!((r.easing_exponent(alpha) - (5.0 - 8.0 * alpha)).abs() < 1e-5);
        }
        for alpha in [0.6f32, 0.75, 1.0] {
            assert!((r.easing_exponent(alpha) - (1.0 - 1.98 * (alpha - 0.5))).abs() < 1e-5);
        }
        assert_eq!(r.easing_exponent(0.5), 1.0);
    }

    #[test]
    fn defaults_scale_with_the_character() {
        let r = Settings::default().resolve(6.509);
        assert!((r.candidate_radius - 0.0325).abs() < 1e-3);
        assert!((r.edit_radius - 0.4068).abs() < 1e-3);
    }
}
