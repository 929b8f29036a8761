//! The strokes file (docs/formats.md, "Strokes / sketch project"), its validation, and validated
//! [`Stroke`]s.
//!
//! Malformed data (NaN, time running backwards, unknown fields, a bad version) is an error that
//! lists every problem with its path (`strokes[2].samples[14].t`). A stroke that the paper's
//! interface would simply have ignored — a click with one sample, an empty stroke — becomes a
//! warning naming it, and is skipped.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::settings::Settings;

/// A whole sketch as saved and replayed: settings, frame rate and strokes with their edits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProjectFile {
    /// Format version; 1.
    pub version: u32,
    /// Frames per second of the animation.
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// Sketching parameters.
    #[serde(default)]
    pub settings: Settings,
    /// Strokes in the order they were drawn.
    #[serde(default)]
    pub strokes: Vec<StrokeFile>,
}

fn default_fps() -> f32 {
    30.0
}

/// One drawn stroke and the edits applied to it afterwards.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrokeFile {
    /// Pen positions in character space (metres) with their times (seconds from the first).
    pub samples: Vec<SampleFile>,
    /// Where the action starts on the timeline; `null`: frame 0, or the end of the previous
    /// action for a stroke that continues a chain.
    #[serde(default)]
    pub start_frame: Option<f32>,
    /// Length of the action in frames after rescaling on the timeline; `null`: as drawn.
    #[serde(default)]
    pub duration: Option<f32>,
    /// The end (red arrow) handle moved here.
    #[serde(default)]
    pub end: Option<[f32; 3]>,
    /// The middle (yellow sphere) handle moved here.
    #[serde(default)]
    pub mid: Option<[f32; 3]>,
    /// The easing handle's position α along the stroke, in [0, 1] (0.5 = as drawn).
    #[serde(default)]
    pub ease: Option<f32>,
    /// Mirror this stroke; `null` follows the settings.
    #[serde(default)]
    pub symmetry: Option<bool>,
}

/// One pen sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SampleFile {
    /// Seconds since the stroke's first sample.
    pub t: f32,
    /// Position in character space.
    pub p: [f32; 3],
}

/// Why a strokes file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProjectError {
    /// Not JSON, or not the strokes format (unknown or missing fields, wrong types).
    #[error("not a strokes file: {0}")]
    Syntax(String),
    /// Values that cannot be used, each with its path.
    #[error("invalid strokes file: {}", .0.join("; "))]
    Invalid(Vec<String>),
}

/// A pen sample of a validated stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Seconds since the first sample.
    pub t: f32,
    /// Position in character space.
    pub p: Vec3,
}

/// A stroke with at least two samples, finite values and strictly increasing times from 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    samples: Vec<Sample>,
}

impl Stroke {
    /// Validates samples; `path` prefixes the problems (`strokes[3]`).
    ///
    /// # Errors
    /// Every problem found, with its path.
    pub fn new(samples: Vec<Sample>, path: &str) -> Result<Stroke, Vec<String>> {
        let mut problems = Vec::new();
        if samples.len() < 2 {
            problems.push(format!(
                "{path}.samples: a stroke needs at least 2 samples, found {}",
                samples.len()
            ));
        }
        for (i, s) in samples.iter().enumerate() {
            if !s.t.is_finite() {
                problems.push(format!("{path}.samples[{i}].t: not a finite number"));
            }
            if !s.p.is_finite() {
                problems.push(format!("{path}.samples[{i}].p: not a finite position"));
            }
        }
        for (i, w) in samples.windows(2).enumerate() {
            if w[1].t <= w[0].t {
                problems.push(format!(
                    "{path}.samples[{}].t: time must increase, but {} follows {}",
                    i + 1,
                    w[1].t,
                    w[0].t
                ));
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let t0 = samples[0].t;
        let samples = samples
            .into_iter()
            .map(|s| Sample {
                t: s.t - t0,
                p: s.p,
            })
            .collect();
        Ok(Stroke { samples })
    }

    /// The samples, times starting at 0.
    #[must_use]
    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }

    /// The first sample's position.
    #[must_use]
    pub fn start(&self) -> Vec3 {
        self.samples[0].p
    }

    /// The last sample's position.
    #[must_use]
    pub fn end(&self) -> Vec3 {
        self.samples[self.samples.len() - 1].p
    }

    /// The middle sample (by index), the paper's point B.
    #[must_use]
    pub fn middle(&self) -> Vec3 {
        self.samples[self.samples.len() / 2].p
    }

    /// How long the stroke took to draw, in seconds.
    #[must_use]
    pub fn duration(&self) -> f32 {
        self.samples[self.samples.len() - 1].t
    }

    /// Arc length from the first sample to each sample.
    #[must_use]
    pub fn cumulative_length(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.samples.len());
        let mut total = 0.0;
        out.push(0.0);
        for w in self.samples.windows(2) {
            total += (w[1].p - w[0].p).length();
            out.push(total);
        }
        out
    }

    /// The same stroke starting at `start` (a chain's hook point) instead of its first sample:
    /// the first sample moves there, the rest is kept.
    #[must_use]
    pub fn hooked_to(&self, start: Vec3) -> Stroke {
        let mut samples = self.samples.clone();
        samples[0].p = start;
        Stroke { samples }
    }

    /// The stroke reflected by `mirror` (a point reflection across the symmetry plane).
    #[must_use]
    pub fn mirrored(&self, mirror: impl Fn(Vec3) -> Vec3) -> Stroke {
        Stroke {
            samples: self
                .samples
                .iter()
                .map(|s| Sample {
                    t: s.t,
                    p: mirror(s.p),
                })
                .collect(),
        }
    }
}

/// A parsed strokes file: settings, and for each stroke either a validated stroke with its edits
/// or the reason it is skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct Project {
    /// Frames per second.
    pub fps: f32,
    /// Parameters.
    pub settings: Settings,
    /// Strokes in drawing order (`None` where the stroke is skipped; see `warnings`).
    pub strokes: Vec<Option<StrokeSpec>>,
    /// Strokes skipped as the paper's interface would have ignored them, one sentence each.
    pub warnings: Vec<String>,
}

/// A stroke plus every edit made to it since it was drawn: what an action is solved from.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// The drawn stroke.
    pub stroke: Stroke,
    /// Timeline start (`None`: automatic).
    pub start_frame: Option<f32>,
    /// Timeline length in frames (`None`: as drawn).
    pub duration: Option<f32>,
    /// Moved end handle.
    pub end: Option<Vec3>,
    /// Moved middle handle.
    pub mid: Option<Vec3>,
    /// Easing handle α (0.5: as drawn).
    pub ease: Option<f32>,
    /// Symmetry override (`None`: follow the settings).
    pub symmetry: Option<bool>,
}

/// A stroke of a file, with its position there (`strokes[index]`) for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct StrokeSpec {
    /// Position in the file.
    pub index: usize,
    /// The stroke and its edits.
    pub input: Input,
}

impl Project {
    /// Parses and validates a strokes file.
    ///
    /// # Errors
    /// [`ProjectError::Syntax`] for JSON that is not the format, [`ProjectError::Invalid`]
    /// listing every bad value with its path.
    pub fn from_json(bytes: &[u8]) -> Result<Project, ProjectError> {
        let file: ProjectFile = faceanim_rig::json::from_slice(bytes)
            .map_err(|e| ProjectError::Syntax(e.to_string()))?;
        Project::from_file(file)
    }

    /// Validates an already parsed file.
    ///
    /// # Errors
    /// [`ProjectError::Invalid`] listing every bad value with its path.
    pub fn from_file(file: ProjectFile) -> Result<Project, ProjectError> {
        let mut problems = Vec::new();
        let mut warnings = Vec::new();
        if file.version != 1 {
            problems.push(format!(
                "version: faceanim reads version 1, found {}",
                file.version
            ));
        }
        if !(file.fps.is_finite() && file.fps > 0.0 && file.fps <= 1000.0) {
            problems.push(format!("fps: must be in (0, 1000], found {}", file.fps));
        }
        problems.extend(file.settings.problems());
        let mut strokes = Vec::new();
        for (index, s) in file.strokes.into_iter().enumerate() {
            let path = format!("strokes[{index}]");
            let before = problems.len();
            if let Some(f) = s.start_frame
                && !(f.is_finite() && f >= 0.0)
            {
                problems.push(format!(
                    "{path}.start_frame: must be a frame ≥ 0 or null, found {f}"
                ));
            }
            if let Some(d) = s.duration
                && !(d.is_finite() && d >= 1.0)
            {
                problems.push(format!(
                    "{path}.duration: must be at least 1 frame or null, found {d}"
                ));
            }
            if let Some(a) = s.ease
                && !(a.is_finite() && (0.0..=1.0).contains(&a))
            {
                problems.push(format!("{path}.ease: must be in [0, 1] or null, found {a}"));
            }
            for (name, handle) in [("end", s.end), ("mid", s.mid)] {
                if let Some(h) = handle
                    && !h.iter().all(|x| x.is_finite())
                {
                    problems.push(format!("{path}.{name}: not a finite position"));
                }
            }
            if s.samples.len() < 2 {
                warnings.push(format!(
                    "{path}: skipped, a stroke needs at least 2 samples (found {}); the interface ignores clicks",
                    s.samples.len()
                ));
                strokes.push(None);
                continue;
            }
            let samples = s
                .samples
                .iter()
                .map(|x| Sample {
                    t: x.t,
                    p: Vec3::from(x.p),
                })
                .collect();
            match Stroke::new(samples, &path) {
                Ok(stroke) if problems.len() == before => strokes.push(Some(StrokeSpec {
                    index,
                    input: Input {
                        stroke,
                        start_frame: s.start_frame,
                        duration: s.duration,
                        end: s.end.map(Vec3::from),
                        mid: s.mid.map(Vec3::from),
                        ease: s.ease,
                        symmetry: s.symmetry,
                    },
                })),
                Ok(_) => strokes.push(None),
                Err(mut p) => {
                    problems.append(&mut p);
                    strokes.push(None);
                }
            }
        }
        if !problems.is_empty() {
            let extra = problems.len().saturating_sub(20);
            problems.truncate(20);
            if extra > 0 {
                problems.push(format!("and {extra} more"));
            }
            return Err(ProjectError::Invalid(problems));
        }
        Ok(Project {
            fps: file.fps,
            settings: file.settings,
            strokes,
            warnings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_problem_has_a_path() {
        let json = br#"{"version": 1, "fps": 30, "strokes": [
            {"samples": [{"t": 0, "p": [0, 0, 0]}, {"t": 0.1, "p": [0, 0, 0.1]}]},
            {"samples": [{"t": 0, "p": [0, 0, 0]}, {"t": 0.0, "p": [0, 1, 0]}, {"t": 0.2, "p": [0, 1, 0]}]},
            {"samples": [{"t": 0, "p": [0, 0, 0]}, {"t": 0.1, "p": [0, 0, 0.1]}], "ease": 2}
        ]}"#;
        let Err(ProjectError::Invalid(problems)) = Project::from_json(json) else {
            panic!("accepted")
        };
        assert_eq!(
            problems,
            [
                "strokes[1].samples[1].t: time must increase, but 0 follows 0",
                "strokes[2].ease: must be in [0, 1] or null, found 2",
            ]
        );
    }

    #[test]
    fn numbers_json_cannot_hold_are_syntax_errors() {
        let json = br#"{"version": 1, "strokes": [{"samples": [{"t": 0, "p": [0, 1e999, 0]}, {"t": 1, "p": [0, 0, 0]}]}]}"#;
        assert!(
            matches!(Project::from_json(json), Err(ProjectError::Syntax(m)) if m.contains("number out of range"))
        );
        // Values built in code (the studio's API) are checked too.
        let samples = vec![
            Sample {
                t: 0.0,
                p: Vec3::NAN,
            },
            Sample {
                t: f32::NAN,
                p: Vec3::ZERO,
            },
        ];
        assert_eq!(
            Stroke::new(samples, "strokes[0]"),
            Err(vec![
                "strokes[0].samples[0].p: not a finite position".to_owned(),
                "strokes[0].samples[1].t: not a finite number".to_owned()
            ])
        );
    }

    #[test]
    fn clicks_are_skipped_with_a_warning() {
        let json = br#"{"version": 1, "strokes": [{"samples": [{"t": 0, "p": [0, 0, 0]}]}, {"samples": []}]}"#;
        let project = Project::from_json(json).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(project.strokes, vec![None, None]);
        assert_eq!(project.warnings.len(), 2);
        assert!(project.warnings[0].starts_with("strokes[0]: skipped"));
    }

    #[test]
    fn unknown_fields_are_errors() {
        let json = br#"{"version": 1, "strokes": [{"samples": [], "colour": "red"}]}"#;
        assert!(
            matches!(Project::from_json(json), Err(ProjectError::Syntax(m)) if m.contains("unknown field `colour`"))
        );
        let json = br#"{"version": 1, "settings": {"edit_radiuss": 1}}"#;
        assert!(
            matches!(Project::from_json(json), Err(ProjectError::Syntax(m)) if m.contains("unknown field `edit_radiuss`"))
        );
    }
}
