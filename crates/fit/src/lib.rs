//! # faceanim-fit: blendshapes for a head that has none
//!
//! Scanned and sculpted heads, and avatars exported without shape keys, have no blendshapes
//! for capture, sketching or lip sync to move. This crate makes ARKit's 52 on the head's own
//! vertices, from a template that has them (the built-in head, or any character):
//!
//! 1. **The face** ([`landmarks`]): both heads are rendered neutral from the front, MediaPipe's
//!    face landmark model reads each render, and each of the 478 landmarks is followed back
//!    along its camera ray onto the mesh. Where the model finds no face, the user marks ten
//!    points on it and the template's landmarks are carried there ([`points`]).
//! 2. **Registration** ([`register`]): the similarity that best maps the template's landmarks
//!    onto the head's, then non-rigid ICP with a stiffness schedule, so that the template's
//!    surface lies on the head's.
//! 3. **Transfer** (deformation transfer, Sumner & Popović 2004): each of the head's
//!    triangles takes the deformation of the template triangle it lies on, and the head's
//!    vertices follow in least squares (faer's sparse Cholesky, one factorisation for every
//!    shape). The head keeps its topology; pieces the template has no counterpart for stay.
//!
//! The shapes come out under ARKit's names, ready for [`faceanim_rig::Character::with_extra_blendshapes`]
//! and the exporter that writes them into the user's own file.
#![deny(missing_docs)]

pub mod landmarks;
mod mapping;
mod mesh;
pub mod points;
pub mod register;
mod sparse;
pub mod templates;
mod transfer;

use faceanim_rig::names::{Drive, drive};
use faceanim_rig::{Blendshape, Character};
use faceanim_track::FaceModels;
use glam::Vec3;

pub use landmarks::{FaceLandmarks, SurfacePoint};
pub use mapping::{MIN_EXPLAINED, SPARSITY, retarget_map};
pub use points::{FacePoint, FacePoints, PointsError};
pub use register::Similarity;
pub use templates::Template;

/// Why shapes could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The landmark model found no face on the character's front render.
    #[error(
        "{0}: no face was found on its front render (the face must look along +Z, glTF's \
         front, and be readable as a face); mark ten points on its face instead: in the \
         studio (Capture, Retarget map, Mark the face), or in {0}.face-points.json beside its \
         file (docs/characters.md)"
    )]
    NoFace(String),
    /// Too few landmarks landed on both meshes to place the template.
    #[error(
        "only {found} face landmarks landed on both {user} and the template (at least {needed} are needed)"
    )]
    TooFewLandmarks {
        /// The user's character.
        user: String,
        /// Landmarks on both.
        found: usize,
        /// The least that will do.
        needed: usize,
    },
    /// The character already drives, by its own shapes, every channel asked for.
    #[error(
        "{user} already has every shape asked for ({wanted}): its own shapes drive all {count} of them by name, so there is nothing to generate"
    )]
    AlreadyHas {
        /// The user's character.
        user: String,
        /// What was asked for.
        wanted: String,
        /// How many channels it drives.
        count: usize,
    },
    /// The template has none of the shapes asked for.
    #[error("the template {template} has none of the shapes to make ({wanted})")]
    NothingToMake {
        /// The template's name.
        template: String,
        /// What was asked for.
        wanted: String,
    },
    /// A shipped template does not import (a broken build).
    #[error("the built-in template does not import: {0}")]
    Template(String),
    /// A generated shape did not fit the character (a bug, reported rather than hidden).
    #[error("adding the shapes: {0}")]
    Shapes(faceanim_rig::ModelError),
    /// A face model failed.
    #[error("face model: {0}")]
    Model(String),
    /// The sparse solver failed (a degenerate mesh).
    #[error("the least-squares solve failed: {0}")]
    Solve(String),
}

/// Which shapes to make.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Only these ARKit channels (canonical names); every one the templates have when `None`.
    pub only: Option<Vec<String>>,
    /// Where the user marked the face, when the face model cannot find it (see [`points`]).
    pub points: Option<FacePoints>,
}

/// What was made, and how well each template fitted.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The new blendshapes, under ARKit's names, on the user's vertices.
    pub shapes: Vec<Blendshape>,
    /// ARKit channels the character already drove by name, left as they were.
    pub kept: Vec<String>,
    /// Landmarks that landed on the user's mesh.
    pub landmarks: usize,
    /// Each template used, in order.
    pub templates: Vec<TemplateFit>,
}

/// How one template was fitted, and what it gave.
#[derive(Debug, Clone)]
pub struct TemplateFit {
    /// The template's name.
    pub name: String,
    /// Landmarks that landed on the template and on both meshes.
    pub landmarks: [usize; 2],
    /// The template's scale onto the user's head.
    pub scale: f32,
    /// Mean distance from the fitted template's paired vertices to the user's surface, as a
    /// fraction of the user's head size.
    pub residual: f32,
    /// The user's vertices with a point on the fitted template.
    pub corresponding: usize,
    /// The shapes it gave.
    pub shapes: Vec<String>,
}

/// Landmarks used to place the template: the 468 of the face mesh (the iris points follow
/// the eyes' gaze, which need not match).
const FACE_LANDMARKS: usize = 468;
/// Fewer landmarks than this on both meshes cannot place the template reliably.
const MIN_LANDMARKS: usize = 100;
/// A user point pairs with the fitted template within this fraction of the head's size.
const REACH: f32 = 0.02;

/// Makes ARKit shapes on `user`'s vertices from `templates`, each channel from the first
/// template that has it. See the crate docs.
///
/// # Errors
/// A [`FitError`]: no face on a render, too few landmarks, nothing to make, a failing model
/// or solve.
pub fn generate(
    user: &Character,
    templates: &[&Character],
    models: &FaceModels,
    options: &Options,
) -> Result<Generated, FitError> {
    // Channels the character already drives by name (its own shape, or halves of it).
    let mut kept: Vec<String> = Vec::new();
    for shape in user.blendshapes() {
        let channels = match drive(shape.name()) {
            Some(d @ (Drive::Channel(_) | Drive::Split(..) | Drive::Merge(..))) => d.channels(),
            _ => Vec::new(),
        };
        for c in channels {
            if !kept.iter().any(|k| k == c.name()) {
                kept.push(c.name().to_owned());
            }
        }
    }
    let mut done = kept.clone();
    let mut work = Vec::new();
    for template in templates {
        let channels = template_channels(template, options, &done);
        if !channels.is_empty() {
            done.extend(channels.iter().map(|(name, _)| name.clone()));
            work.push((*template, channels));
        }
    }
    if work.is_empty() {
        let wanted = options
            .only
            .as_ref()
            .map_or_else(|| "any ARKit shape".to_owned(), |o| o.join(", "));
        // Nothing left to make because the character has it all, or because no template
        // has what was asked for: two different things to tell the user.
        let mut asked: Vec<String> = match &options.only {
            Some(only) => only.clone(),
            None => templates
                .iter()
                .flat_map(|t| template_channels(t, options, &[]))
                .map(|(name, _)| name)
                .collect(),
        };
        asked.sort();
        asked.dedup();
        if !asked.is_empty() && asked.iter().all(|a| kept.contains(a)) {
            return Err(FitError::AlreadyHas {
                user: user.name().to_owned(),
                wanted,
                count: asked.len(),
            });
        }
        return Err(FitError::NothingToMake {
            template: templates
                .iter()
                .map(|t| t.name())
                .collect::<Vec<_>>()
                .join(", "),
            wanted,
        });
    }
    let user_marks = FaceLandmarks::locate(user, models, options.points.as_ref(), templates)?;
    let on_user = OnUser::new(user)?;
    let mut shapes = Vec::new();
    let mut fits = Vec::new();
    for (template, channels) in work {
        let registered = on_user.register(&user_marks, template, models)?;
        let (names, deltas): (Vec<String>, Vec<Vec<Vec3>>) = channels.into_iter().unzip();
        let moved = on_user.transfer(&registered, template, &deltas);
        // A displacement under a millionth of the head is no movement.
        let threshold = 1e-6 * on_user.size;
        shapes.extend(
            names
                .iter()
                .zip(&moved)
                .map(|(name, dense)| Blendshape::from_dense(name.clone(), dense, threshold)),
        );
        fits.push(registered.report(template, names));
    }
    Ok(Generated {
        shapes,
        kept,
        landmarks: user_marks.found(),
        templates: fits,
    })
}

/// The user's head made ready to receive templates: its surface indexed for registration and
/// its mesh factorised for deformation transfer (once for every template and shape).
pub(crate) struct OnUser<'a> {
    user: &'a Character,
    target: register::Target<'a>,
    transfer: transfer::Transfer<'a>,
    /// The user's size (its bounding box's diagonal).
    pub(crate) size: f32,
}

/// One template registered onto the user's head.
pub(crate) struct Registered {
    landmarks: [usize; 2],
    similarity: Similarity,
    residual: f32,
    correspondence: transfer::Correspondence,
}

impl Registered {
    /// How the fit went, for the report.
    fn report(&self, template: &Character, shapes: Vec<String>) -> TemplateFit {
        TemplateFit {
            name: template.name().to_owned(),
            landmarks: self.landmarks,
            scale: self.similarity.scale,
            residual: self.residual,
            corresponding: self.correspondence.vertices.iter().flatten().count(),
            shapes,
        }
    }
}

impl<'a> OnUser<'a> {
    pub(crate) fn new(user: &'a Character) -> Result<OnUser<'a>, FitError> {
        let (positions, triangles) = (user.positions(), user.triangles());
        Ok(OnUser {
            user,
            target: register::Target::new(positions, triangles, &mesh::places(user)),
            transfer: transfer::Transfer::new(positions, triangles)?,
            size: user.size(),
        })
    }

    /// `template` placed on the user's face by their landmarks (`user_marks` on the user),
    /// then fitted to its surface by non-rigid ICP.
    pub(crate) fn register(
        &self,
        user_marks: &FaceLandmarks,
        template: &Character,
        models: &FaceModels,
    ) -> Result<Registered, FitError> {
        let (u_pos, u_tri) = (self.user.positions(), self.user.triangles());
        let template_marks = FaceLandmarks::find(template, models)?;
        let pairs: Vec<(SurfacePoint, SurfacePoint)> = user_marks.points[..FACE_LANDMARKS]
            .iter()
            .zip(&template_marks.points[..FACE_LANDMARKS])
            .filter_map(|(u, t)| Some(((*u)?, (*t)?)))
            .collect();
        let too_few = || FitError::TooFewLandmarks {
            user: self.user.name().to_owned(),
            found: pairs.len(),
            needed: MIN_LANDMARKS,
        };
        if pairs.len() < MIN_LANDMARKS {
            return Err(too_few());
        }
        let (t_pos, t_tri) = (template.positions(), template.triangles());
        let goals: Vec<Vec3> = pairs.iter().map(|(u, _)| u.on(u_tri, u_pos)).collect();
        let sources: Vec<Vec3> = pairs.iter().map(|(_, t)| t.on(t_tri, t_pos)).collect();
        let similarity = Similarity::fit(&sources, &goals).ok_or_else(too_few)?;
        let placed: Vec<Vec3> = t_pos.iter().map(|p| similarity.apply(*p)).collect();
        let landmark_terms: Vec<(Vec<(usize, f64)>, Vec3)> = pairs
            .iter()
            .zip(&goals)
            .map(|((_, t), goal)| {
                let tri = t_tri[t.triangle as usize];
                (
                    (0..3)
                        .map(|k| (tri[k] as usize, f64::from(t.weights[k])))
                        .collect(),
                    *goal,
                )
            })
            .collect();
        let (fitted, residual) =
            register::nonrigid(&placed, t_tri, &landmark_terms, &self.target, self.size)?;
        let correspondence =
            transfer::Correspondence::new(u_pos, u_tri, &fitted, t_tri, REACH * self.size);
        Ok(Registered {
            landmarks: [template_marks.found(), pairs.len()],
            similarity,
            residual: residual / self.size,
            correspondence,
        })
    }

    /// `deltas` (dense, over `template`'s vertices) moved onto the user's vertices.
    pub(crate) fn transfer(
        &self,
        registered: &Registered,
        template: &Character,
        deltas: &[Vec<Vec3>],
    ) -> Vec<Vec<Vec3>> {
        self.transfer.shapes(
            &registered.correspondence,
            (template.positions(), template.triangles()),
            deltas,
            registered.similarity.rotation,
            registered.similarity.scale,
        )
    }
}

/// `user` with the shapes [`generate`] makes added, its file noting them as generated (see
/// [`faceanim_rig::source::GeneratedShapes`]): what `faceanim generate-shapes` and the studio
/// write.
///
/// # Errors
/// As [`generate`]; [`FitError::Shapes`] if a shape does not fit the character (a bug).
pub fn with_generated_shapes(
    user: &Character,
    templates: &[&Character],
    models: &FaceModels,
    options: &Options,
) -> Result<(Character, Generated), FitError> {
    let generated = generate(user, templates, models, options)?;
    let record = faceanim_rig::source::GeneratedShapes {
        shapes: generated
            .shapes
            .iter()
            .map(|s| s.name().to_owned())
            .collect(),
        template: generated
            .templates
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(" + "),
    };
    let with = user
        .with_extra_blendshapes(generated.shapes.clone())
        .map_err(FitError::Shapes)?
        .with_generated_shapes(&record);
    Ok((with, generated))
}

/// The template's shapes per ARKit channel (see [`channel_deltas`]): only those asked for
/// and not already `kept`.
fn template_channels(
    template: &Character,
    options: &Options,
    kept: &[String],
) -> Vec<(String, Vec<Vec3>)> {
    channel_deltas(template)
        .into_iter()
        .filter(|(channel, _)| {
            options
                .only
                .as_ref()
                .is_none_or(|only| only.iter().any(|o| o == channel))
                && !kept.iter().any(|k| k == channel)
        })
        .collect()
}

/// `character`'s shapes per ARKit channel, as dense deltas over its vertices: a channel's own
/// shape, or its halves added (`browInnerUp_L` and `_R`); in the order they first appear.
#[must_use]
pub fn channel_deltas(character: &Character) -> Vec<(String, Vec<Vec3>)> {
    let n = character.vertex_count();
    let mut channels: Vec<(String, Vec<Vec3>)> = Vec::new();
    for shape in character.blendshapes() {
        let channel = match drive(shape.name()) {
            Some(Drive::Channel(c) | Drive::Split(c, _)) => c.name(),
            _ => continue,
        };
        let index = match channels.iter().position(|(name, _)| name == channel) {
            Some(i) => i,
            None => {
                channels.push((channel.to_owned(), vec![Vec3::ZERO; n]));
                channels.len() - 1
            }
        };
        let dense = &mut channels[index].1;
        for (v, d) in shape.moves() {
            dense[v as usize] += d;
        }
    }
    channels
}

/// Relative error of `generated` against `reference` displacements over the same vertices:
/// the sum of the differences' lengths over the sum of the reference's lengths.
#[must_use]
pub fn relative_error(generated: &[Vec3], reference: &[Vec3]) -> f64 {
    let (mut difference, mut total) = (0.0f64, 0.0f64);
    for (g, r) in generated.iter().zip(reference) {
        difference += (g.as_dvec3() - r.as_dvec3()).length();
        total += r.as_dvec3().length();
    }
    if total <= 0.0 {
        return if difference > 0.0 { f64::INFINITY } else { 0.0 };
    }
    difference / total
}
