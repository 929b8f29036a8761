//! The sketch engine: strokes in, actions out (sections 3.2–3.8).
//!
//! A [`Sketch`] keeps, for every stroke, its *input* (the drawn samples plus handle and
//! timeline edits) and the *action* solved from it. Solving is deterministic and depends only
//! on the inputs that came before, so a session in the studio and the same strokes file
//! replayed on the command line give the same animation. Editing an input re-solves that action
//! and those created after it.
//!
//! Semantics of chains and layers: a stroke that starts within `hook_radius` of the
//! end of a chain's last action continues that chain — it snaps to that point, inherits the
//! reference vertex, starts from the previous target pose and, unless placed, begins when the
//! previous action ends. Within a chain each action moves the face from the previous action's
//! target pose to its own (the previous blendshape fades out while the new one fades in). A
//! stroke anywhere else starts a new chain; chains are layers whose contributions add up.

use faceanim_rig::Character;
use glam::Vec3;

pub use crate::action::{Action, ActionId, Side, Target};
use crate::arc::{Arc, Path};
use crate::layer::{Layer, Offsets};
pub use crate::project::Input;
use crate::project::{Project, Stroke};
use crate::settings::{Resolved, Selection, Settings, StrokeMode};
use crate::surface::{Surface, edge_distances};
use crate::timing::Timing;

/// A possible target of a stroke from a given start: a sphere in the studio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// What ending the stroke here selects.
    pub target: Target,
    /// Where the reference vertex goes with it at full weight.
    pub position: Vec3,
}

/// The reference vertex picked for a stroke start, and the candidates it offers.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidates {
    /// The vertex of the displayed pose nearest the start.
    pub reference: u32,
    /// Its displayed position.
    pub reference_position: Vec3,
    /// Where it is with this stroke's chain at rest (targets are relative to this).
    pub base: Vec3,
    /// The targets, nearest first is not implied.
    pub candidates: Vec<Candidate>,
    /// The chain this stroke would continue, if it starts at a chain's end.
    pub continues: Option<ActionId>,
}

/// Why a stroke made no action (the paper's interface would ignore it).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Rejected {
    /// The stroke starts too far from the face.
    #[error(
        "it starts {distance:.4} from the face, farther than the pen distance {pen_distance:.4}"
    )]
    FarFromFace {
        /// Distance from the nearest vertex.
        distance: f32,
        /// The limit.
        pen_distance: f32,
    },
    /// No blendshape moves the reference vertex enough.
    #[error(
        "no blendshape moves vertex {reference} by more than the candidate radius {candidate_radius:.4}"
    )]
    NoCandidates {
        /// The reference vertex.
        reference: u32,
        /// The limit.
        candidate_radius: f32,
    },
    /// The action was deleted.
    #[error("deleted")]
    Deleted,
}

/// Strokes and the actions they became, for one character. See the module docs.
#[derive(Debug)]
pub struct Sketch<'c> {
    character: &'c Character,
    settings: Settings,
    resolved: Resolved,
    fps: f32,
    surface: Surface,
    inputs: Vec<Option<Input>>,
    actions: Vec<Result<Action, Rejected>>,
}

impl<'c> Sketch<'c> {
    /// An empty sketch.
    #[must_use]
    pub fn new(character: &'c Character, settings: Settings, fps: f32) -> Sketch<'c> {
        let resolved = settings.resolve(character.size());
        Sketch {
            character,
            settings,
            resolved,
            fps,
            surface: Surface::new(character),
            inputs: Vec::new(),
            actions: Vec::new(),
        }
    }

    /// Replays a strokes file; the warnings name strokes that made no action and why.
    #[must_use]
    pub fn from_project(character: &'c Character, project: &Project) -> (Sketch<'c>, Vec<String>) {
        let mut sketch = Sketch::new(character, project.settings.clone(), project.fps);
        let mut warnings = project.warnings.clone();
        for spec in project.strokes.iter().flatten() {
            if let Err(why) = sketch.add(spec.input.clone()).1 {
                warnings.push(format!("strokes[{}]: skipped, {why}", spec.index));
            }
        }
        (sketch, warnings)
    }

    /// The character.
    #[must_use]
    pub fn character(&self) -> &'c Character {
        self.character
    }

    /// Frames per second.
    #[must_use]
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// The settings as given.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The settings resolved for this character.
    #[must_use]
    pub fn resolved(&self) -> &Resolved {
        &self.resolved
    }

    /// Changes the settings and re-solves everything.
    pub fn set_settings(&mut self, settings: Settings) {
        self.resolved = settings.resolve(self.character.size());
        self.settings = settings;
        self.resolve_from(0);
    }

    /// Every input, `None` where deleted.
    #[must_use]
    pub fn inputs(&self) -> &[Option<Input>] {
        &self.inputs
    }

    /// The action of each input, or why there is none.
    pub fn results(&self) -> &[Result<Action, Rejected>] {
        &self.actions
    }

    /// The live actions with their ids.
    pub fn actions(&self) -> impl Iterator<Item = (ActionId, &Action)> {
        self.actions
            .iter()
            .enumerate()
            .filter_map(|(i, a)| a.as_ref().ok().map(|a| (ActionId(i), a)))
    }

    /// The action `id`, if it exists and was not rejected.
    #[must_use]
    pub fn action(&self, id: ActionId) -> Option<&Action> {
        self.actions.get(id.0).and_then(|a| a.as_ref().ok())
    }

    /// Adds a stroke; returns its id and its action or why it made none.
    pub fn add(&mut self, input: Input) -> (ActionId, Result<&Action, Rejected>) {
        let id = ActionId(self.inputs.len());
        self.inputs.push(Some(input));
        let solved = self.solve(id.0);
        self.actions.push(solved);
        (id, self.actions[id.0].as_ref().map_err(Clone::clone))
    }

    /// Replaces the input of `id` (a handle or timeline edit) and re-solves from it on.
    pub fn edit(&mut self, id: ActionId, input: Input) {
        if let Some(slot) = self.inputs.get_mut(id.0) {
            *slot = Some(input);
            self.resolve_from(id.0);
        }
    }

    /// Deletes the action `id`; a chain continuing from it now continues from its predecessor.
    pub fn delete(&mut self, id: ActionId) {
        if let Some(slot) = self.inputs.get_mut(id.0) {
            *slot = None;
            self.resolve_from(id.0);
        }
    }

    fn resolve_from(&mut self, first: usize) {
        self.actions.truncate(first);
        for i in first..self.inputs.len() {
            let solved = self.solve(i);
            self.actions.push(solved);
        }
    }

    /// The chain tail whose end is within the hook radius of `start`, among actions before `limit`.
    fn hook(&self, start: Vec3, limit: usize) -> Option<ActionId> {
        let mut best: Option<(f32, ActionId)> = None;
        for (i, action) in self.actions.iter().enumerate().take(limit) {
            let Ok(action) = action else { continue };
            let has_successor = self.actions[i + 1..limit.min(self.actions.len())]
                .iter()
                .any(|b| b.as_ref().is_ok_and(|b| b.previous == Some(ActionId(i))));
            if has_successor {
                continue;
            }
            let d = action.sides[0].c.distance(start);
            if d <= self.resolved.hook_radius && best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, ActionId(i)));
            }
        }
        best.map(|(_, id)| id)
    }

    /// The displayed pose at `frame` from the actions before `limit`, excluding `chain`, as
    /// positions plus the largest distance any vertex moved.
    fn displayed(&self, frame: f32, limit: usize, chain: Option<ActionId>) -> (Vec<Vec3>, f32) {
        let mut pose = crate::evaluate::FramePose::new(self.character);
        let earlier = self
            .actions
            .iter()
            .take(limit)
            .enumerate()
            .filter_map(|(i, a)| a.as_ref().ok().map(|a| (ActionId(i), a)));
        crate::evaluate::evaluate(
            self.character,
            earlier.filter(|(_, a)| Some(a.chain) != chain),
            frame,
            &mut pose,
        );
        let positions = pose.positions(self.character);
        let max_offset = positions
            .iter()
            .zip(self.character.positions())
            .map(|(p, n)| p.distance(*n))
            .fold(0.0, f32::max);
        (positions, max_offset)
    }

    /// The reference vertex and candidate targets for a stroke starting at `start`, drawn at
    /// `frame` (for the spheres shown while hovering and drawing).
    #[must_use]
    pub fn candidates(&self, start: Vec3, frame: f32) -> Option<Candidates> {
        self.candidates_before(start, frame, self.actions.len())
            .ok()
    }

    fn candidates_before(
        &self,
        start: Vec3,
        frame: f32,
        limit: usize,
    ) -> Result<Candidates, Rejected> {
        let continues = self.hook(start, limit);
        let (reference, chain_layer, chain, frame) =
            match continues.and_then(|id| self.action(id).map(|a| (id, a))) {
                Some((_, previous)) => (
                    Some(previous.sides[0].reference),
                    previous.to.clone(),
                    Some(previous.chain),
                    previous.end_frame(),
                ),
                None => (None, Layer::default(), None, frame),
            };
        let (others, max_offset) = self.displayed(frame, limit, chain);
        let (reference, distance) = match reference {
            Some(r) => (r, 0.0),
            None => self
                .surface
                .nearest(start, self.character.positions(), &others, max_offset)
                .unwrap_or((0, f32::INFINITY)),
        };
        if distance > self.resolved.pen_distance {
            return Err(Rejected::FarFromFace {
                distance,
                pen_distance: self.resolved.pen_distance,
            });
        }
        let chain_here = chain_layer.displacement(self.character, reference);
        let base = others[reference as usize];
        let mut candidates: Vec<Candidate> = self
            .character
            .blendshape_ids()
            .filter_map(|id| {
                let delta = self.character.blendshape(id)?.delta_of(reference);
                (delta.length() > self.resolved.candidate_radius).then_some(Candidate {
                    target: Target::Blendshape(id),
                    position: base + delta,
                })
            })
            .collect();
        if chain_here.length() > 1e-9 || !chain_layer.is_neutral() {
            candidates.push(Candidate {
                target: Target::Neutral,
                position: base,
            });
        }
        if candidates.is_empty() {
            return Err(Rejected::NoCandidates {
                reference,
                candidate_radius: self.resolved.candidate_radius,
            });
        }
        Ok(Candidates {
            reference,
            reference_position: base + chain_here,
            base,
            candidates,
            continues,
        })
    }

    fn solve(&self, index: usize) -> Result<Action, Rejected> {
        let Some(input) = self.inputs[index].as_ref() else {
            return Err(Rejected::Deleted);
        };
        let drawn_start = input.stroke.start();
        let frame_hint = input.start_frame.unwrap_or(0.0);
        let found = self.candidates_before(drawn_start, frame_hint, index)?;
        let previous = found
            .continues
            .and_then(|id| self.action(id).map(|a| (id, a)));
        let stroke = match previous {
            Some((_, p)) => input.stroke.hooked_to(p.sides[0].c),
            None => input.stroke.clone(),
        };
        let from = previous.map(|(_, p)| p.to.clone()).unwrap_or_default();
        let a = stroke.start();
        let c = input.end.unwrap_or_else(|| stroke.end());
        // A moved end carries the middle with it: a straight stroke stays straight, a curved one
        // keeps its bend relative to the chord.
        let b = input.mid.unwrap_or_else(|| {
            follow_end(
                a,
                stroke.middle(),
                stroke.end(),
                c,
                self.resolved.snap_distance,
            )
        });
        let symmetric = input.symmetry.unwrap_or(self.resolved.symmetry);

        let mut sides = Vec::new();
        let mut unmirrored = None;
        let mut to = Layer::default();
        let mut offsets: Vec<(u32, Vec3)> = Vec::new();
        let start_position = found.reference_position;
        match self.resolved.mode {
            StrokeMode::Single => {
                let target = self.select(&found, &stroke, c);
                let (weight, target_position, goal) = match target {
                    Target::Blendshape(id) => {
                        let delta = self
                            .character
                            .blendshape(id)
                            .map_or(Vec3::ZERO, |s| s.delta_of(found.reference));
                        let w = ((c - found.base).dot(delta)
                            / delta.length_squared().max(f32::MIN_POSITIVE))
                        .clamp(0.0, 1.0);
                        (w, found.base + delta, found.base + w * delta)
                    }
                    _ => (1.0, found.base, found.base),
                };
                let exaggeration = c - goal;
                if let Target::Blendshape(id) = target {
                    to.weights.push((id, weight));
                }
                self.spread(found.reference, exaggeration, &mut offsets);
                let path = Path::through(a, b, c, self.resolved.snap_distance);
                sides.push(Side {
                    reference: found.reference,
                    target,
                    weight,
                    target_position,
                    exaggeration,
                    a,
                    b,
                    c,
                    path,
                    start_position,
                });
                let partner = match target {
                    Target::Blendshape(id) => self
                        .character
                        .symmetry()
                        .partner(id)
                        .map(Target::Blendshape),
                    other => Some(other),
                };
                let mirror_ref = self.mirror_reference(found.reference, partner);
                if symmetric {
                    unmirrored = self.why_unmirrored(target, partner, mirror_ref);
                }
                if symmetric
                    && let (Some(plane), Some(partner)) =
                        (self.character.symmetry().plane(), partner)
                    && let Some(mirror_ref) = mirror_ref
                {
                    let mirror_exaggeration = plane.reflect_vector(exaggeration);
                    let mirror_target_position = match partner {
                        Target::Blendshape(id) => {
                            let delta = self
                                .character
                                .blendshape(id)
                                .map_or(Vec3::ZERO, |s| s.delta_of(mirror_ref));
                            if to.weights.iter().all(|(b, _)| *b != id) {
                                to.weights.push((id, weight));
                            }
                            plane.reflect_point(found.base) + delta
                        }
                        _ => plane.reflect_point(found.base),
                    };
                    self.spread(mirror_ref, mirror_exaggeration, &mut offsets);
                    let (ma, mb, mc) = (
                        plane.reflect_point(a),
                        plane.reflect_point(b),
                        plane.reflect_point(c),
                    );
                    sides.push(Side {
                        reference: mirror_ref,
                        target: partner,
                        weight,
                        target_position: mirror_target_position,
                        exaggeration: mirror_exaggeration,
                        a: ma,
                        b: mb,
                        c: mc,
                        path: Path::through(ma, mb, mc, self.resolved.snap_distance),
                        start_position: plane.reflect_point(start_position),
                    });
                }
            }
            StrokeMode::Multi => {
                let mut pins = vec![(found.reference, found.base, c)];
                let plane = self.character.symmetry().plane();
                let mirror = self
                    .character
                    .symmetry()
                    .mirror_vertex(found.reference)
                    .filter(|&m| m != found.reference);
                if symmetric {
                    unmirrored = self.why_unmirrored(Target::Multi, Some(Target::Multi), mirror);
                }
                if symmetric && let (Some(plane), Some(m)) = (plane, mirror) {
                    pins.push((m, plane.reflect_point(found.base), plane.reflect_point(c)));
                }
                let weights = crate::solve::direct_manipulation(self.character, &pins, &from);
                to.weights = weights;
                for (k, &(vertex, base, goal)) in pins.iter().enumerate() {
                    let reached = base
                        + to.weights
                            .iter()
                            .map(|&(id, w)| {
                                w * self
                                    .character
                                    .blendshape(id)
                                    .map_or(Vec3::ZERO, |s| s.delta_of(vertex))
                            })
                            .sum::<Vec3>();
                    let exaggeration = goal - reached;
                    self.spread(vertex, exaggeration, &mut offsets);
                    let (sa, sb, sc) = match (k, plane) {
                        (1, Some(plane)) => (
                            plane.reflect_point(a),
                            plane.reflect_point(b),
                            plane.reflect_point(c),
                        ),
                        _ => (a, b, c),
                    };
                    sides.push(Side {
                        reference: vertex,
                        target: Target::Multi,
                        weight: 1.0,
                        target_position: reached,
                        exaggeration,
                        a: sa,
                        b: sb,
                        c: sc,
                        path: Path::through(sa, sb, sc, self.resolved.snap_distance),
                        start_position: if k == 0 {
                            start_position
                        } else {
                            plane.map_or(start_position, |p| p.reflect_point(start_position))
                        },
                    });
                }
            }
        }
        to.offsets = Offsets::from_pairs(offsets);

        let ease = input.ease.unwrap_or(0.5);
        let timing = Timing::from_stroke(
            &input.stroke,
            self.resolved.subsample,
            self.resolved.easing_exponent(ease),
        );
        // Actions start and end on whole frames, where an animator can type them.
        let duration = input
            .duration
            .unwrap_or(input.stroke.duration() * self.fps)
            .round()
            .max(1.0);
        let start_frame = input
            .start_frame
            .map_or_else(|| previous.map_or(0.0, |(_, p)| p.end_frame()), f32::round);
        let swing = self.swing(&from, &to, &sides);
        Ok(Action {
            chain: previous.map_or(ActionId(index), |(_, p)| p.chain),
            previous: previous.map(|(id, _)| id),
            start_frame,
            duration,
            sides,
            from,
            to,
            timing,
            swing,
            ease,
            unmirrored,
        })
    }

    /// The mirrored stroke's reference vertex: the stroke's own reflected across the plane and
    /// snapped to the nearest vertex that the partner blendshape moves (on a real face the
    /// reflection lands a few millimetres off its counterpart, often beside the moving part),
    /// or, for a stroke back to neutral, the reference's mirror partner.
    fn mirror_reference(&self, reference: u32, partner: Option<Target>) -> Option<u32> {
        let plane = self.character.symmetry().plane()?;
        let mirrored = plane.reflect_point(*self.character.positions().get(reference as usize)?);
        let snapped = match partner {
            Some(Target::Blendshape(id)) => self.character.blendshape(id).and_then(|shape| {
                shape
                    .moves()
                    .filter(|(_, d)| d.length_squared() > 0.0)
                    .map(|(v, _)| v)
                    .min_by(|&a, &b| {
                        let d = |v: u32| {
                            self.character.positions()[v as usize].distance_squared(mirrored)
                        };
                        d(a).total_cmp(&d(b))
                    })
            }),
            _ => None,
        };
        snapped
            .or_else(|| self.character.symmetry().mirror_vertex(reference))
            .filter(|&m| m != reference)
    }

    /// Whether `shape` moves the middle of the face (its displacement's centre lies near the
    /// symmetry plane, within a tenth of how far across it its moved vertices spread).
    fn is_central(&self, shape: &faceanim_rig::Blendshape) -> bool {
        let Some(plane) = self.character.symmetry().plane() else {
            return false;
        };
        let positions = self.character.positions();
        let (mut sum, mut weight, mut spread) = (0.0f32, 0.0f32, 0.0f32);
        for (vertex, delta) in shape.moves() {
            let across = plane.side_of(positions[vertex as usize]);
            let w = delta.length();
            sum += w * across;
            weight += w;
            spread = spread.max(across.abs());
        }
        weight > 0.0 && (sum / weight).abs() <= 0.1 * spread.max(f32::EPSILON)
    }

    /// Why a stroke that asked to be mirrored cannot be: the character has no symmetry plane, its
    /// blendshape `target` has no left/right `partner`, or its vertex no mirror image.
    fn why_unmirrored(
        &self,
        target: Target,
        partner: Option<Target>,
        mirror_vertex: Option<u32>,
    ) -> Option<String> {
        if self.character.symmetry().plane().is_none() {
            return Some(format!(
                "not mirrored: {} has no symmetry plane",
                self.character.name()
            ));
        }
        if let Target::Blendshape(id) = target {
            let shape = self.character.blendshape(id)?;
            // A shape in the middle of the face (jawOpen) is its own mirror: nothing is missing.
            if self.is_central(shape) {
                return None;
            }
            if partner.is_none() {
                return Some(format!(
                    "not mirrored: {} has no partner on the other side (by name or by shape)",
                    shape.name()
                ));
            }
        }
        mirror_vertex.is_none().then(|| {
            "not mirrored: the stroke starts where the face has no mirror image".to_owned()
        })
    }

    /// Eq. 1 (nearest target to the end); with [`Selection::Path`] also how far the drawn path
    /// strays from each candidate's straight motion; with [`Selection::Segment`] the distance
    /// from the end to each candidate's motion segment (ties broken by Eq. 1).
    fn select(&self, found: &Candidates, stroke: &Stroke, end: Vec3) -> Target {
        let start = found.reference_position;
        let cost = |candidate: &Candidate| {
            if self.resolved.selection == Selection::Segment {
                let to_line = distance_to_segment(end, found.base, candidate.position);
                return to_line + 1e-3 * candidate.position.distance(end);
            }
            let mut cost = candidate.position.distance(end);
            if self.resolved.selection == Selection::Path {
                let samples = stroke.samples();
                let n = samples.len();
                let stray: f32 = (1..8)
                    .map(|k| {
                        let q = samples[k * (n - 1) / 8].p - stroke.start() + start;
                        distance_to_segment(q, start, candidate.position)
                    })
                    .sum::<f32>()
                    / 7.0;
                cost += stray;
            }
            cost
        };
        found
            .candidates
            .iter()
            .min_by(|x, y| cost(x).total_cmp(&cost(y)))
            .map_or(Target::Neutral, |c| c.target)
    }

    /// Spreads `offset` at `reference` over its neighbours by edge-graph distance.
    fn spread(&self, reference: u32, offset: Vec3, out: &mut Vec<(u32, Vec3)>) {
        if offset.length() <= 1e-7 * self.character.size() {
            return;
        }
        let radius = self.resolved.edit_radius;
        for (v, d) in edge_distances(self.character, reference, radius) {
            let w = self.resolved.falloff.weight(d, radius);
            if w > 0.0 {
                out.push((v, w * offset));
            }
        }
    }

    /// The vertices that move between `from` and `to`, with their share κ of the motion of the
    /// reference vertex of the side they follow (only sides with an arc).
    fn swing(&self, from: &Layer, to: &Layer, sides: &[Side]) -> Vec<(u32, f32, u8)> {
        let arcs: Vec<(u8, Vec3)> = sides
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.path.is_straight())
            .map(|(k, s)| (k as u8, s.c - s.start_position))
            .filter(|(_, m)| m.length_squared() > 0.0)
            .collect();
        if arcs.is_empty() {
            return Vec::new();
        }
        let mut moving: Vec<u32> = Vec::new();
        for layer in [from, to] {
            moving.extend_from_slice(layer.offsets.indices());
            for &(id, _) in &layer.weights {
                if let Some(shape) = self.character.blendshape(id) {
                    moving.extend_from_slice(shape.indices());
                }
            }
        }
        moving.sort_unstable();
        moving.dedup();
        let mut out = Vec::new();
        for v in moving {
            let motion = to.displacement(self.character, v) - from.displacement(self.character, v);
            let best = arcs
                .iter()
                .map(|&(side, m)| (side, (motion.dot(m) / m.length_squared()).clamp(0.0, 1.0)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((side, kappa)) = best
                && kappa > 1e-4
            {
                out.push((v, kappa, side));
            }
        }
        out
    }

    /// The arc of side `side` of `action`, if it is not straight.
    #[must_use]
    pub fn arc(action: &Action, side: u8) -> Option<Arc> {
        action.arc(side)
    }

    /// Last frame of the animation (end of the latest action), at least 0.
    #[must_use]
    pub fn last_frame(&self) -> f32 {
        self.actions()
            .map(|(_, a)| a.end_frame())
            .fold(0.0, f32::max)
    }
}

impl Sketch<'_> {
    /// The weights and offsets at `frame`.
    #[must_use]
    pub fn frame(&self, frame: f32) -> crate::evaluate::FramePose {
        let mut out = crate::evaluate::FramePose::new(self.character());
        self.frame_into(frame, &mut out);
        out
    }

    /// Like [`Sketch::frame`], into a reused buffer.
    pub fn frame_into(&self, frame: f32, out: &mut crate::evaluate::FramePose) {
        crate::evaluate::evaluate(self.character(), self.actions(), frame, out);
    }

    /// The baked clip: every blendshape's weight at every frame from 0 to the end of the last
    /// action (arcs and exaggerations are not weights; the glTF export carries them).
    #[must_use]
    pub fn bake_clip(&self) -> faceanim_anim::Clip {
        let last = self.last_frame().ceil() as usize;
        let mut pose = crate::evaluate::FramePose::new(self.character());
        let frames = (0..=last)
            .map(|f| {
                self.frame_into(f as f32, &mut pose);
                pose.weights.clone()
            })
            .collect();
        faceanim_anim::Clip {
            fps: self.fps(),
            blendshapes: self.character().blendshape_names(),
            frames,
            head: None,
            head_position: None,
            presence: None,
            arkit: None,
        }
    }
}

fn distance_to_segment(q: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + t * ab)
}

/// Where the middle `b` of a stroke from `a` to `drawn_end` goes when its end moves to `end`:
/// onto the new chord's midpoint when the stroke was straight (within `snap`), else carried by
/// the rotation and scaling that take the old chord to the new one, keeping the bend.
fn follow_end(a: Vec3, b: Vec3, drawn_end: Vec3, end: Vec3, snap: f32) -> Vec3 {
    if end == drawn_end {
        return b;
    }
    if Path::through(a, b, drawn_end, snap).is_straight() {
        return (a + end) * 0.5;
    }
    let (from, to) = (drawn_end - a, end - a);
    let (from_length, to_length) = (from.length(), to.length());
    if from_length <= f32::EPSILON || to_length <= f32::EPSILON {
        return b;
    }
    let turn = glam::Quat::from_rotation_arc(from / from_length, to / to_length);
    a + turn * ((b - a) * (to_length / from_length))
}
