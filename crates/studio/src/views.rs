//! What the API answers, as types: the page, scripts and `API.md` all read these shapes.

use std::collections::BTreeMap;

use faceanim_rig::Character;
use faceanim_sketch::engine::{Action, Side, Target};
use faceanim_sketch::settings::{Resolved, Settings};
use faceanim_take::EstimatorSource;
use serde::Serialize;

/// What a stroke's end goes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Goal {
    /// A blendshape (named in `target`).
    Blendshape,
    /// Back to where the chain started (no blendshape of the chain active).
    Neutral,
    /// Every weight solved at once (multi-blendshape strokes).
    Multi,
}

/// A target as the page shows it: the goal, and the blendshape's name when it is one.
fn target_of(character: &Character, target: Target) -> (Goal, Option<String>) {
    match target {
        Target::Blendshape(id) => (
            Goal::Blendshape,
            character.blendshape(id).map(|b| b.name().to_owned()),
        ),
        Target::Neutral => (Goal::Neutral, None),
        Target::Multi => (Goal::Multi, None),
    }
}

/// `GET /api/state`: everything the page draws of the sketch.
#[derive(Debug, Serialize)]
pub struct StateView {
    /// The character's name.
    pub character: String,
    /// The project's frame rate.
    pub fps: f32,
    /// The last frame with animation.
    pub last_frame: f32,
    /// The project's settings as saved (`null` distances follow the character's size).
    pub settings: Settings,
    /// The settings in use, distances resolved.
    pub resolved: Resolved,
    /// One per stroke that made an action.
    pub actions: Vec<ActionView>,
    /// Strokes that made none, with the reason.
    pub rejected: Vec<RejectedView>,
    /// Problems with the project as a whole.
    pub warnings: Vec<String>,
    /// Whether undo has something to undo.
    pub can_undo: bool,
    /// Whether redo has something to redo.
    pub can_redo: bool,
    /// Where Save writes.
    pub project_path: String,
    /// After `POST /api/strokes`: the new stroke's index.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub added: Option<usize>,
}

/// A stroke's action.
#[derive(Debug, Serialize)]
pub struct ActionView {
    /// The stroke's index in the project.
    pub stroke: usize,
    /// Its display name (`mouthSmile_L 0.80`).
    pub name: String,
    /// The chain it belongs to.
    pub chain: usize,
    /// The action it continues.
    pub previous: Option<usize>,
    /// First frame.
    pub start_frame: f32,
    /// Last frame.
    pub end_frame: f32,
    /// The easing handle's position α.
    pub ease: f32,
    /// How far the action has gone (0 to 1) at 17 evenly spaced moments from its start to its
    /// end: its timing curve, drawing speed and easing together, as the engine plays it.
    pub progress: Vec<f32>,
    /// Whether it has a mirrored side.
    pub symmetric: bool,
    /// Why it is not mirrored although it asked to be.
    pub unmirrored: Option<String>,
    /// The stroke's own side, then its mirror.
    pub sides: Vec<SideView>,
}

/// One side of an action.
#[derive(Debug, Serialize)]
pub struct SideView {
    /// What the end goes to.
    pub goal: Goal,
    /// The blendshape's name (`null` for the neutral and multi goals).
    pub target: Option<String>,
    /// The blendshape's weight.
    pub weight: f32,
    /// Length of the exaggeration offset.
    pub exaggeration: f32,
    /// The stroke's start (A).
    pub start: [f32; 3],
    /// Its middle (B, the sphere).
    pub mid: [f32; 3],
    /// Its end (C, the arrow).
    pub end: [f32; 3],
    /// Where the reference vertex goes at full weight.
    pub target_position: [f32; 3],
    /// Whether the path is a straight line.
    pub straight: bool,
    /// 25 points along the path.
    pub path: Vec<[f32; 3]>,
}

/// A stroke that made no action.
#[derive(Debug, Serialize)]
pub struct RejectedView {
    /// The stroke's index.
    pub stroke: usize,
    /// Why.
    pub reason: String,
}

impl ActionView {
    /// The view of stroke `stroke`'s action.
    #[must_use]
    pub fn of(character: &Character, stroke: usize, action: &Action) -> ActionView {
        ActionView {
            stroke,
            name: action.name(character),
            chain: action.chain.0,
            previous: action.previous.map(|p| p.0),
            start_frame: action.start_frame,
            end_frame: action.end_frame(),
            ease: action.ease,
            progress: (0..=16)
                .map(|k| action.progress(action.start_frame + action.duration * k as f32 / 16.0))
                .collect(),
            symmetric: action.sides.len() > 1,
            unmirrored: action.unmirrored.clone(),
            sides: action
                .sides
                .iter()
                .map(|side| SideView::of(character, side))
                .collect(),
        }
    }
}

impl SideView {
    fn of(character: &Character, side: &Side) -> SideView {
        let (goal, target) = target_of(character, side.target);
        SideView {
            goal,
            target,
            weight: side.weight,
            exaggeration: side.exaggeration.length(),
            start: side.a.to_array(),
            mid: side.b.to_array(),
            end: side.c.to_array(),
            target_position: side.target_position.to_array(),
            straight: side.path.is_straight(),
            path: (0..=24)
                .map(|k| side.path.point(side.a, side.c, k as f32 / 24.0).to_array())
                .collect(),
        }
    }
}

/// `POST /api/candidates`: what a stroke starting at a point can reach.
#[derive(Debug, Serialize)]
pub struct CandidatesView {
    /// The reference vertex.
    pub reference: u32,
    /// Its displayed position.
    pub reference_position: [f32; 3],
    /// The action whose chain the stroke would continue.
    pub continues: Option<usize>,
    /// The targets.
    pub candidates: Vec<CandidateView>,
}

/// One candidate target (a sphere in the page).
#[derive(Debug, Serialize)]
pub struct CandidateView {
    /// What it goes to.
    pub goal: Goal,
    /// The blendshape's name (`null` for the neutral and multi goals).
    pub name: Option<String>,
    /// Where the reference vertex goes.
    pub position: [f32; 3],
}

impl CandidatesView {
    /// The view of `found`.
    #[must_use]
    pub fn of(character: &Character, found: &faceanim_sketch::engine::Candidates) -> Self {
        CandidatesView {
            reference: found.reference,
            reference_position: found.reference_position.to_array(),
            continues: found.continues.map(|a| a.0),
            candidates: found
                .candidates
                .iter()
                .map(|c| {
                    let (goal, name) = target_of(character, c.target);
                    CandidateView {
                        goal,
                        name,
                        position: c.position.to_array(),
                    }
                })
                .collect(),
        }
    }
}

/// `GET /api/character`.
#[derive(Debug, Serialize)]
pub struct CharacterView {
    /// Its name.
    pub name: String,
    /// Vertex count.
    pub vertices: usize,
    /// Blendshape names, in order.
    pub blendshapes: Vec<String>,
    /// Bounding box of the whole character.
    pub bounds: BoundsView,
    /// The head: the box the camera frames first (the whole character for a bare head, a
    /// head-sized box around the face on a full-body avatar).
    pub head: BoundsView,
    /// The character's size `D` (the head box's diagonal), that default distances scale with.
    pub diagonal: f32,
    /// The shapes `faceanim generate-shapes` made, as its file records them, and the template.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generated: Option<GeneratedShapesView>,
    /// Whether it is a VRM avatar (0.x or 1.0): its animation also leaves as a VRM Animation.
    pub vrm: bool,
}

/// Shapes a character's file records as generated.
#[derive(Debug, Serialize)]
pub struct GeneratedShapesView {
    /// How many.
    pub count: usize,
    /// The template they came from.
    pub template: String,
}

/// An axis-aligned box.
#[derive(Debug, Serialize)]
pub struct BoundsView {
    /// Smallest corner.
    pub min: [f32; 3],
    /// Largest corner.
    pub max: [f32; 3],
}

impl CharacterView {
    /// The view of `character`.
    #[must_use]
    pub fn of(character: &Character) -> CharacterView {
        let view = |b: faceanim_rig::Aabb| BoundsView {
            min: b.min.to_array(),
            max: b.max.to_array(),
        };
        CharacterView {
            name: character.name().to_owned(),
            vertices: character.vertex_count(),
            blendshapes: names(character),
            bounds: view(character.bounds()),
            head: view(character.head_bounds()),
            diagonal: character.size(),
            generated: character
                .source()
                .and_then(faceanim_rig::source::GltfSource::generated_shapes)
                .map(|g| GeneratedShapesView {
                    count: g.shapes.len(),
                    template: g.template,
                }),
            vrm: character
                .source()
                .is_some_and(faceanim_rig::source::GltfSource::is_vrm),
        }
    }
}

/// The character's blendshape names, in order.
#[must_use]
pub fn names(character: &Character) -> Vec<String> {
    character.blendshape_names()
}

/// `GET /api/character/anchors`: where a blendshape moves the most.
#[derive(Debug, Serialize)]
pub struct AnchorView {
    /// The blendshape.
    pub name: String,
    /// The vertex it moves most (`null` for a shape that moves nothing).
    pub vertex: Option<u32>,
    /// That vertex at rest.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rest: Option<[f32; 3]>,
    /// Where weight 1 takes it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<[f32; 3]>,
}

/// `POST /api/character/upload`.
#[derive(Debug, Serialize)]
pub struct UploadView {
    /// The importer's warnings.
    pub warnings: Vec<String>,
    /// The new state.
    pub state: StateView,
}

/// `POST /api/character/generate-shapes`.
#[derive(Debug, Serialize)]
pub struct GeneratedView {
    /// Where the character with its new shapes was written.
    pub written: String,
    /// The shapes made.
    pub shapes: Vec<String>,
    /// The new state (an empty project on the new character).
    pub state: StateView,
}

/// `POST /api/project/save`.
#[derive(Debug, Serialize)]
pub struct SavedView {
    /// Where the project was written.
    pub saved: String,
}

// ---------- capture mode ----------

/// `POST /api/capture/transcript`: a transcript file's words for the speech field, read in the
/// encoding it was saved in.
#[derive(Debug, Serialize)]
pub struct TranscriptView {
    /// The text, as the file holds it (a subtitle's cues and times included: lip sync reads
    /// them).
    pub text: String,
    /// The encoding it was read in (`UTF-8`, `UTF-16LE`, `Shift_JIS`, …).
    pub encoding: &'static str,
    /// Said when the encoding was guessed from the bytes (a legacy code page): the guess may
    /// be wrong, and the user should know which was taken.
    pub note: Option<String>,
}

/// `GET /api/capture/state`: everything the page shows of capture mode.
#[derive(Debug, Serialize)]
pub struct CaptureView {
    /// The character's blendshapes.
    pub blendshapes: Vec<String>,
    /// Their ARKit families, for grouping the sliders.
    pub groups: Vec<Group>,
    /// Each one's left/right partner (an index into `blendshapes`), where it has one.
    pub partners: Vec<Option<usize>>,
    /// The adapter.
    pub adapter: AdapterView,
    /// The current or last long job.
    pub job: Option<JobView>,
    /// The smoothing and keyframe spacing new takes get.
    pub filtering: FilteringView,
    /// Live tracking, while on.
    pub live: Option<LiveView>,
    /// The live microphone, while on.
    pub voice: Option<VoiceView>,
    /// The take, when one is open.
    pub take: Option<TakeView>,
    /// VMC in and out, when the studio was started with them.
    pub vmc: Option<VmcView>,
    /// Something the user should know that no request asked about: the autosaved take that
    /// could not be opened, and where it was set aside.
    pub notice: Option<String>,
    /// The character's retarget map.
    pub retarget: RetargetView,
}

/// The character's retarget map: which of its shapes answer to each ARKit channel.
#[derive(Debug, Serialize)]
pub struct RetargetView {
    /// Where it is read from and saved to.
    pub path: String,
    /// Whether there is one.
    pub loaded: bool,
    /// Whether the rig's names leave channels MediaPipe reads without a shape (then capture
    /// makes the map before its first take).
    pub needed: bool,
    /// Whether it reads capture now (it does unless an adapter does).
    pub in_use: bool,
    /// Why the one beside the character is not used.
    pub note: Option<String>,
    /// How long making it took.
    pub seconds: Option<f32>,
    /// The 52 channels in ARKit's order.
    pub rows: Vec<RetargetRowView>,
    /// The points the user marks on the face where the face model finds none, in the order
    /// they are asked for.
    pub marks: Vec<FaceMarkView>,
    /// Where the user marked them, in the character's space, when they did.
    pub face_points: Option<std::collections::BTreeMap<faceanim_fit::FacePoint, [f32; 3]>>,
    /// The last map was not made because the face model found no face: the page asks for
    /// the marks.
    pub no_face: bool,
}

/// A point the user marks on the face.
#[derive(Debug, Serialize)]
pub struct FaceMarkView {
    /// Its name (the key the page sends it under).
    pub point: faceanim_fit::FacePoint,
    /// What to click, in words.
    pub describe: &'static str,
}

/// One ARKit channel's row of the map.
#[derive(Debug, Serialize)]
pub struct RetargetRowView {
    /// The channel, in ARKit's spelling.
    pub channel: String,
    /// By name, by geometry, set by the user, or nothing.
    pub from: faceanim_retarget::RowSource,
    /// The shapes answering to the channel at 1, with their weights.
    pub shapes: Vec<(String, f32)>,
    /// For a geometric row: the share of the channel's displacement the shapes reproduce
    /// (of both sides' together where it shares its shapes with its twin).
    pub explained: Option<f32>,
    /// The channel on the other side of the face this row shares its shapes with, made
    /// together by geometry ([`faceanim_retarget::RetargetMap::shares_with_twin`]).
    pub with_twin: Option<&'static str>,
    /// Whether the channel's scores are scaled to the character on its renders.
    pub calibrated: bool,
}

/// VMC in (`--vmc-listen`) and out (`--vmc-send`).
#[derive(Debug, Serialize)]
pub struct VmcView {
    /// The address listened on, when listening.
    pub listening: Option<String>,
    /// What is listened to (`VMC`, `Live Link Face`, `iFacialMocap`, `VTube Studio`).
    pub source: Option<&'static str>,
    /// The phone asked for frames, for the protocols that ask.
    pub phone: Option<String>,
    /// This machine's addresses on the local network, to type into the phone app.
    pub this_machine: Vec<String>,
    /// Whether a neutral face is calibrated (and taken away from every frame).
    pub neutral: bool,
    /// What arrived: datagrams, frames, the dropped `malformed`, `unknown` and `oversized`
    /// ones, `unmatched` values and the `unmatched_names` that moved (less those the
    /// character's eye and jaw bones show), the `sender`, the `rate` and the `last_packet_ms`.
    #[serde(flatten)]
    pub traffic: faceanim_live::Traffic,
    /// Frames recorded, while recording.
    pub recording: Option<usize>,
    /// The character's weights in the last frame.
    pub weights: Option<Vec<f32>>,
    /// The head pose in the last frame (yaw, pitch, roll in degrees).
    pub head: Option<[f32; 3]>,
    /// The view's bones in the last frame (see [`TakeView::bones`]).
    pub bones: Option<Vec<[f32; 4]>>,
    /// Sending, when the studio sends the live face.
    pub sending: Option<VmcSendView>,
}

/// The live face going out over VMC.
#[derive(Debug, Serialize)]
pub struct VmcSendView {
    /// The marionette's address.
    pub to: String,
    /// Frames sent.
    pub frames: u64,
    /// Frames the network refused.
    pub dropped: u64,
    /// The last refusal's reason.
    pub last_error: Option<String>,
}

/// The ARKit family a blendshape belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Group {
    /// `eye…`
    Eye,
    /// `brow…`
    Brow,
    /// `jaw…`
    Jaw,
    /// `mouth…`
    Mouth,
    /// `cheek…`
    Cheek,
    /// `nose…`
    Nose,
    /// `tongue…`
    Tongue,
    /// Not an ARKit name.
    Other,
}

impl Group {
    /// The family of `name` (`Other` when it is not an ARKit name).
    #[must_use]
    pub fn of(name: &str) -> Group {
        use faceanim_rig::names::Region;
        let Some(arkit) = faceanim_rig::names::arkit_name(name) else {
            return Group::Other;
        };
        match faceanim_rig::names::region(arkit) {
            Region::Gaze | Region::Lids => Group::Eye,
            Region::Brows => Group::Brow,
            Region::Jaw => Group::Jaw,
            Region::Mouth => Group::Mouth,
            Region::Cheeks => Group::Cheek,
            Region::Nose => Group::Nose,
            Region::Tongue => Group::Tongue,
        }
    }
}

/// The character's adapter.
#[derive(Debug, Serialize)]
pub struct AdapterView {
    /// Where it is read from and saved to.
    pub path: String,
    /// Whether one is in use.
    pub loaded: bool,
    /// Why the one beside the character is not used, or that it fits another shape.
    pub note: Option<String>,
    /// How its training went.
    pub report: Option<faceanim_adapt::TrainingReport>,
    /// Whether it reads faces relative to a neutral one (then the take's neutral frame and
    /// live calibration matter).
    pub calibrated: bool,
    /// Whether it was trained on top of the character's retarget map (it refines the map's
    /// estimate), rather than alone.
    pub on_map: bool,
    /// The character's shapes capture cannot drive (each shown alone, not read by the
    /// adapter): the animator sketches them or corrects frames.
    pub unseen: Vec<String>,
    /// Renders training draws when the page does not say how many.
    pub default_samples: usize,
}

/// A long job.
#[derive(Debug, Serialize)]
pub struct JobView {
    /// What it does.
    pub kind: JobKind,
    /// The same, in words for the page.
    pub title: String,
    /// Its current stage.
    pub stage: String,
    /// Steps of the stage done.
    pub done: usize,
    /// Steps of the stage.
    pub total: usize,
    /// Whether it still runs.
    pub running: bool,
    /// Whether it was asked to stop.
    pub cancelling: bool,
    /// Seconds since it started.
    pub seconds: f64,
    /// How it ended well.
    pub result: Option<String>,
    /// How it failed.
    pub error: Option<String>,
}

/// One Euro settings.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SmoothingView {
    /// Cutoff at rest, Hz.
    pub min_cutoff: f32,
    /// Speed coefficient.
    pub beta: f32,
    /// Cutoff of the speed estimate, Hz.
    pub derivative_cutoff: f32,
}

impl From<faceanim_anim::filter::OneEuro> for SmoothingView {
    fn from(s: faceanim_anim::filter::OneEuro) -> SmoothingView {
        SmoothingView {
            min_cutoff: s.min_cutoff,
            beta: s.beta,
            derivative_cutoff: s.derivative_cutoff,
        }
    }
}

/// The filtering new takes get.
#[derive(Debug, Serialize)]
pub struct FilteringView {
    /// Keyframe spacing.
    pub keyframe_every: usize,
    /// One Euro smoothing, when on.
    pub smoothing: Option<SmoothingView>,
    /// What the page offers when smoothing is turned on.
    pub default_smoothing: SmoothingView,
}

/// Live tracking.
#[derive(Debug, Serialize)]
pub struct LiveView {
    /// Frames tracked.
    pub frames: usize,
    /// Frames recorded, while recording.
    pub recording: Option<usize>,
    /// Who chose the performer's neutral face (`null`: none yet; hold still or calibrate).
    pub neutral: Option<faceanim_take::NeutralChoice>,
    /// Calibrate was pressed and the next face will be the neutral.
    pub calibrating: bool,
}

/// The take.
#[derive(Debug, Serialize)]
pub struct TakeView {
    /// Different for every take this process opened.
    pub id: u64,
    /// The input's name.
    pub source: String,
    /// Frames per second.
    pub fps: f32,
    /// Frame count.
    pub frames: usize,
    /// How many frames have an input preview.
    pub previews: usize,
    /// For a single photo: the frames of the 0 → peak → 0 animation it becomes (`null` for
    /// video and sequences).
    pub still: Option<usize>,
    /// For a single photo: that animation's weights, one row per frame (what plays and exports).
    pub ramp: Option<Vec<Vec<f32>>>,
    /// What estimated it.
    pub estimator: EstimatorSource,
    /// Per frame: its name.
    pub names: Vec<String>,
    /// Per frame: face presence.
    pub presence: Vec<f32>,
    /// Per frame: head yaw, pitch, roll.
    pub head: Vec<Option<[f32; 3]>>,
    /// Per frame: the estimate.
    pub estimates: Vec<Vec<f32>>,
    /// Per frame: what plays.
    pub weights: Vec<Vec<f32>>,
    /// Per frame: the mean weight.
    pub mean: Vec<f32>,
    /// The keyframes.
    pub keyframes: Vec<usize>,
    /// Keyframes the user added.
    pub added_keyframes: Vec<usize>,
    /// Automatic keyframes the user removed.
    pub removed_keyframes: Vec<usize>,
    /// Corrected frames.
    pub corrected: Vec<usize>,
    /// Frame → blendshape → value.
    pub corrections: BTreeMap<usize, BTreeMap<String, f32>>,
    /// The preference's offsets, while applied.
    pub preference: Option<Vec<f32>>,
    /// The offsets applying the preference now would give.
    pub preference_pending: Vec<f32>,
    /// Keyframe spacing.
    pub keyframe_every: usize,
    /// Whether undo has something to undo.
    pub can_undo: bool,
    /// Whether redo has something to redo.
    pub can_redo: bool,
    /// Whether the estimate reads each face relative to the take's neutral one (an adapter's
    /// or a retarget map's; by name it does not): then the neutral frame matters and the user
    /// can choose it.
    pub reads_neutral: bool,
    /// The frame faces are read relative to, and who chose it.
    pub neutral: Option<faceanim_take::Neutral>,
    /// How neutral that frame looks to the estimator (`null` when it does not read faces
    /// relative to a neutral one), and the warning to show when it does not look neutral.
    pub neutral_check: Option<faceanim_take::NeutralCheck>,
    /// The warning, in words.
    pub neutral_warning: Option<String>,
    /// For a lip-sync take: where the page fetches its sound to play with it.
    pub sound: Option<String>,
    /// Per frame, for a character whose file has a head bone: each joint of the view's skeleton
    /// (`faceanim_export::bones::ViewRig`, the skin of `GET /api/view.glb`) as its rotation
    /// `[x, y, z, w]`: the head pose shared between spine, neck and head, the gaze on the
    /// eyes, `jawOpen` on the jaw, as the export turns the file's bones.
    pub bones: Option<Vec<Vec<[f32; 4]>>>,
}

impl TakeView {
    /// The view of `take` (numbered `id`, with `previews` input previews), its neutral frame
    /// judged by `estimator`.
    #[must_use]
    pub fn of(
        take: &faceanim_take::Take,
        id: u64,
        previews: usize,
        estimator: &dyn faceanim_take::Estimator,
    ) -> TakeView {
        let session = &take.session;
        let neutral_check = session.neutral_check(estimator);
        let weights = session.weights();
        let mean = weights
            .iter()
            .map(|row| row.iter().sum::<f32>() / row.len().max(1) as f32)
            .collect();
        TakeView {
            id,
            source: session.source.clone(),
            fps: session.fps,
            frames: session.frames.len(),
            previews,
            still: session.edits.still_frames,
            ramp: session.edits.still_frames.map(|_| session.clip().frames),
            estimator: take.estimated_by(),
            names: session.frames.iter().map(|f| f.name.clone()).collect(),
            presence: session.frames.iter().map(|f| f.presence).collect(),
            head: session.frames.iter().map(|f| f.head).collect(),
            estimates: session.frames.iter().map(|f| f.estimate.clone()).collect(),
            weights,
            mean,
            keyframes: session.keyframes(),
            added_keyframes: session.edits.added_keyframes.clone(),
            removed_keyframes: session.edits.removed_keyframes.clone(),
            corrected: session.edits.corrections.keys().copied().collect(),
            corrections: session.edits.corrections.clone(),
            preference: session.edits.preference.clone(),
            preference_pending: session.preference_offsets(),
            keyframe_every: session.edits.keyframe_every,
            can_undo: take.can_undo(),
            can_redo: take.can_redo(),
            reads_neutral: estimator.calibrated(),
            neutral: session.neutral(),
            neutral_warning: neutral_check
                .as_ref()
                .and_then(faceanim_take::NeutralCheck::warning),
            neutral_check,
            sound: None,
            bones: None,
        }
    }
}

/// Where calibration is.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum Calibration {
    /// Not calibrated (the mouth follows loudness until the first refinement).
    None,
    /// Listening to the passage.
    Listening {
        /// Seconds heard so far.
        seconds: f32,
    },
    /// Aligning the passage and learning the voice.
    Fitting,
    /// The voice is learned.
    Calibrated {
        /// Visemes the model tells apart (silence included).
        visemes: usize,
        /// What was done instead of aligning the passage, if anything.
        notes: Vec<String>,
    },
    /// Calibration failed; the previous model (if any) is kept.
    Failed {
        /// Why.
        message: String,
    },
}

/// The live microphone as the page sees it.
#[derive(Debug, Clone, Serialize)]
pub struct VoiceView {
    /// Seconds of sound received.
    pub seconds: f32,
    /// How far the mouth is held back behind the voice, milliseconds (for streams whose audio
    /// arrives later than the picture).
    pub delay_ms: u32,
    /// The longest delay allowed, milliseconds.
    pub max_delay_ms: u32,
    /// Whether the mouth waits for the character's retarget map, being made (a rig whose names
    /// say nothing of a mouth): the voice is heard and recorded meanwhile, the mouth rests, and
    /// it moves by the map once the map is there.
    pub awaits_map: bool,
    /// Calibration.
    pub calibration: Calibration,
    /// The language the microphone hears (eSpeak NG's name of it: `en-us`, `es`, `ja`, …): its
    /// passage is read to calibrate, and its speech is learned from (English by its words,
    /// other languages by their phones).
    pub language: String,
    /// The passage to read while calibrating, in [`VoiceView::language`]; `None` where faceanim
    /// has none in it (the user speaks freely, and the phones heard teach the voice).
    pub passage: Option<&'static str>,
    /// Stretches of speech the classifier has learned from (calibration and refinements).
    pub learned: usize,
    /// Whether frames are classed into visemes (else loudness alone opens the mouth).
    pub classifying: bool,
    /// The last background refinement's failure, if it failed.
    pub refine_error: Option<String>,
    /// Seconds recorded, while recording.
    pub recording: Option<f32>,
}

/// What a long job does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobKind {
    /// Reading a video, photos or an image folder through the capture pipeline.
    ReadingInput,
    /// Rendering the training set and training the adapter.
    TrainingAdapter,
    /// Fine-tuning the adapter on the take's corrections.
    FineTuning,
    /// Registering the template on the character and calibrating its retarget map.
    MakingMap,
}

impl std::fmt::Display for JobKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            JobKind::ReadingInput => "reading the input",
            JobKind::TrainingAdapter => "training the adapter",
            JobKind::FineTuning => "fine-tuning the adapter",
            JobKind::MakingMap => "making the retarget map",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arkit_families_group_the_sliders() {
        assert_eq!(Group::of("jawOpen"), Group::Jaw);
        assert_eq!(Group::of("EyeBlink_L"), Group::Eye);
        assert_eq!(Group::of("mouthSmile_R"), Group::Mouth);
        assert_eq!(Group::of("browInnerUp"), Group::Brow);
        assert_eq!(Group::of("cheekPuff"), Group::Cheek);
        assert_eq!(Group::of("noseSneerLeft"), Group::Nose);
        assert_eq!(Group::of("shape_017"), Group::Other);
    }
}
