//! `faceanim retarget`: the character's retarget map — which of its own shapes answer to each
//! of ARKit's channels (by name, by geometry, or as the user says), calibrated on the
//! character — made in seconds, shown, edited and saved beside it; and the map that every
//! capture command uses by default.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use faceanim_retarget::{RetargetMap, RowSource};
use faceanim_rig::Character;
use faceanim_track::FaceModels;

/// `faceanim retarget`'s arguments.
#[derive(Debug, clap::Args)]
pub struct RetargetArgs {
    /// The character (default: the built-in head).
    pub character: Option<PathBuf>,
    /// The map file (default: NAME.retarget.json beside the character).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Make the map again even if one is there (rows you set are kept).
    #[arg(long)]
    pub remake: bool,
    /// Set a channel's row: `CHANNEL=SHAPE:WEIGHT[,SHAPE:WEIGHT…]` (a weight of 1 may be left
    /// out), or `CHANNEL=` for nothing; repeatable. The channel then moves those shapes alone.
    #[arg(long = "set", value_name = "CHANNEL=SHAPES")]
    pub set: Vec<String>,
    /// Where the character's face is, when the face model cannot find it: a file of ten points
    /// marked on it (default: NAME.face-points.json beside the character, when there is one;
    /// the studio writes it).
    #[arg(long, value_name = "FILE")]
    pub face_points: Option<PathBuf>,
    /// Skip the calibration on the character's renders (MediaPipe's scores are used as they
    /// are).
    #[arg(long)]
    pub no_calibration: bool,
    /// Also measure the map on stills of the character by another renderer (a folder with
    /// truth.json, as `faceanim adapt --eval-dir` reads); repeatable.
    #[arg(long = "eval-dir", value_name = "DIR")]
    pub eval_dirs: Vec<PathBuf>,
    /// Print the map's rows and measures as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: RetargetArgs) -> anyhow::Result<()> {
    let character = crate::input::load_or_default(args.character.as_deref())?.character;
    let path = args
        .output
        .clone()
        .unwrap_or_else(|| default_path(args.character.as_deref(), &character));
    faceanim_files::check_output(&path)?;
    let models = FaceModels::load().context("loading the face models")?;
    let names = character.blendshape_names();
    let existing = read(&path, &names)?;
    let points = face_points(
        args.character.as_deref(),
        &character,
        args.face_points.as_deref(),
    )?;
    let mut map = match existing {
        Some(map) if !args.remake && (map.calibration.is_some() || args.no_calibration) => map,
        previous => make(
            &character,
            &models,
            previous.as_ref(),
            points.as_ref(),
            !args.no_calibration,
        )?,
    };
    for set in &args.set {
        let (channel, shapes) = parse_set(set)?;
        map.set_row(&channel, shapes)
            .map_err(|e| anyhow::anyhow!("--set {set}: {e}"))?;
    }
    faceanim_files::write_output(&path, map.to_json().as_bytes())?;
    eprintln!("wrote {}", path.display());
    let mut evaluations = Vec::new();
    if !args.eval_dirs.is_empty() {
        let estimator = faceanim_take::Retargeted::new(std::sync::Arc::new(map.clone()));
        for dir in &args.eval_dirs {
            let held_out = faceanim_adapt::heldout::HeldOut::read(dir, &names)?;
            let e = held_out.evaluate(&estimator, &models)?;
            eprintln!(
                "{}: MAE {:.4} over {} of {} stills (always the mean: {:.4}; all zeros: {:.4}; neutral {:?})",
                dir.display(),
                e.mae,
                e.faces,
                e.stills,
                e.mae_mean_baseline,
                e.mae_zero_baseline,
                e.neutral
            );
            evaluations.push(e);
        }
    }
    if args.json {
        outln!(
            "{}",
            serde_json::json!({
                "map": path,
                "rows": map.rows,
                "mode": map.mode,
                "calibrated": map.calibration.as_ref().map(|c| c.channels.keys().collect::<Vec<_>>()),
                "made": map.made,
                "heldout": evaluations,
            })
        );
    } else {
        out!("{}", table(&map));
    }
    Ok(())
}

/// The map's rows in words: one line per channel that reaches a shape.
pub fn table(map: &RetargetMap) -> String {
    let mut text = String::new();
    for (c, (row, name)) in map
        .rows
        .iter()
        .zip(faceanim_rig::names::ARKIT_52)
        .enumerate()
    {
        if row.shapes.is_empty() {
            continue;
        }
        let shapes: Vec<String> = map
            .answers(c)
            .iter()
            .map(|(s, w)| format!("{s} {w:.2}"))
            .collect();
        let from = match row.from {
            RowSource::ByName => "by name".to_owned(),
            RowSource::Geometry => {
                let share = 100.0 * row.explained.unwrap_or(0.0);
                match map.shares_with_twin(c) {
                    Some(twin) => format!(
                        "geometry with {}, {share:.0}% of both",
                        faceanim_rig::names::ARKIT_52[twin]
                    ),
                    None => format!("geometry, {share:.0}% of it"),
                }
            }
            RowSource::User => "set by you".to_owned(),
            RowSource::None => String::new(),
        };
        let calibrated = map
            .calibration
            .as_ref()
            .is_some_and(|c| c.channels.contains_key(name));
        text.push_str(&format!(
            "{name:<20} {:<40} ({from}{})\n",
            shapes.join(", "),
            if calibrated { ", calibrated" } else { "" }
        ));
    }
    let missing: Vec<&str> = map
        .rows
        .iter()
        .zip(faceanim_rig::names::ARKIT_52)
        .filter(|(row, _)| row.shapes.is_empty())
        .map(|(_, name)| name)
        .collect();
    if !missing.is_empty() {
        text.push_str(&format!(
            "no shape of {} answers to: {}\n",
            map.character,
            missing.join(", ")
        ));
    }
    text
}

/// `CHANNEL=SHAPE:W,SHAPE:W` as the channel and its shapes.
fn parse_set(text: &str) -> anyhow::Result<(String, BTreeMap<String, f32>)> {
    let (channel, list) = text
        .split_once('=')
        .ok_or_else(|| anyhow::anyhow!("--set {text}: write CHANNEL=SHAPE:WEIGHT,…"))?;
    let mut shapes = BTreeMap::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (shape, weight) = match item.rsplit_once(':') {
            Some((shape, w)) => (
                shape,
                w.parse::<f32>()
                    .map_err(|_| anyhow::anyhow!("--set {text}: '{w}' is not a weight"))?,
            ),
            None => (item, 1.0),
        };
        shapes.insert(shape.to_owned(), weight);
    }
    Ok((channel.trim().to_owned(), shapes))
}

/// Where a character's map lives by default: `NAME.retarget.json` beside its file.
pub fn default_path(character_path: Option<&Path>, character: &Character) -> PathBuf {
    faceanim_adapt::bridge::default_map_path(
        character_path.and_then(Path::parent),
        character.name(),
    )
}

/// The points marked on `character`'s face: those in `given`, else those beside its file
/// (`NAME.face-points.json`) when there are any.
///
/// # Errors
/// The file cannot be read, or is not a points file (naming the field).
pub fn face_points(
    character_path: Option<&Path>,
    character: &Character,
    given: Option<&Path>,
) -> anyhow::Result<Option<faceanim_fit::FacePoints>> {
    let path = match given {
        Some(path) => path.to_owned(),
        None => {
            let beside = faceanim_fit::points::default_path(
                character_path.and_then(Path::parent),
                character.name(),
            );
            if !beside.exists() {
                return Ok(None);
            }
            beside
        }
    };
    let bytes = faceanim_files::read_bytes(&path)?;
    let points = faceanim_fit::FacePoints::from_json(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(Some(points))
}

/// The map at `path` if there is one that fits `character` (one of another character is said
/// and ignored).
///
/// # Errors
/// The file cannot be read, or is not a map.
pub fn read_beside(path: &Path, character: &Character) -> anyhow::Result<Option<RetargetMap>> {
    read(path, &character.blendshape_names())
}

/// The map at `path` if there is one that fits the character (a map of another character is
/// said and ignored).
fn read(path: &Path, names: &[String]) -> anyhow::Result<Option<RetargetMap>> {
    if !path.exists() {
        return Ok(None);
    }
    let bytes = faceanim_files::read_bytes(path)?;
    match RetargetMap::from_json(&bytes, names) {
        Ok(map) => Ok(Some(map)),
        Err(e @ faceanim_retarget::RetargetError::OtherCharacter { .. }) => {
            eprintln!("{}: {e}", path.display());
            Ok(None)
        }
        Err(e) => Err(anyhow::anyhow!("{}: {e}", path.display())),
    }
}

/// Makes the map, with a progress bar over the calibration's renders.
fn make(
    character: &Character,
    models: &FaceModels,
    previous: Option<&RetargetMap>,
    points: Option<&faceanim_fit::FacePoints>,
    calibrate: bool,
) -> anyhow::Result<RetargetMap> {
    eprintln!(
        "making the retarget map of {} (the template registered on its face{})",
        character.name(),
        if calibrate {
            ", then each channel calibrated on its renders"
        } else {
            ""
        }
    );
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} calibrating {pos}/{len} renders [{bar:40}] {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let never = std::sync::atomic::AtomicBool::new(false);
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let map = faceanim_adapt::bridge::make_map(
        character,
        models,
        previous,
        points,
        calibrate,
        faceanim_adapt::Control {
            progress: &progress,
            cancel: &never,
        },
    )
    .with_context(|| format!("making the retarget map of {}", character.name()))?;
    bar.finish_and_clear();
    eprintln!(
        "{} of ARKit's 52 channels reach its shapes ({} by name, {} by geometry) in {:.1} s",
        map.answered(),
        map.rows
            .iter()
            .filter(|r| r.from == RowSource::ByName)
            .count(),
        map.rows
            .iter()
            .filter(|r| r.from == RowSource::Geometry)
            .count(),
        map.made.seconds.unwrap_or(0.0)
    );
    Ok(map)
}

/// The map at `path`, given by the user for `character` (whose shapes are `names`): it must
/// be one, and fit it.
fn read_given(path: &Path, character: &Character, names: &[String]) -> anyhow::Result<RetargetMap> {
    read(path, names)?
        .ok_or_else(|| anyhow::anyhow!("{}: not a map of {}", path.display(), character.name()))
}

/// The map a clip goes through onto `character` (loaded from `character_path`): the one at
/// `given` (which must fit it), else the one beside the character when there is one that
/// fits, else — when the clip has ARKit channels (a Live Link Face recording, a take's ARKit
/// values, VRM's presets) that the rig's names leave without a shape — one made now and saved
/// beside it, as capture makes it. `None` for a clip its names take whole, or when the map
/// cannot be made (said, and the clip goes on by name).
///
/// # Errors
/// The file cannot be read, is not a map, or `given` is another character's.
pub fn for_clip(
    character: &Character,
    character_path: Option<&Path>,
    given: Option<&Path>,
    clip: &faceanim_anim::Clip,
) -> anyhow::Result<Option<RetargetMap>> {
    let names = character.blendshape_names();
    if let Some(path) = given {
        return read_given(path, character, &names).map(Some);
    }
    let beside = read(&default_path(character_path, character), &names)?;
    if beside.is_some()
        || !faceanim_adapt::bridge::needs_map(character)
        || !clip.loses_arkit(character)
    {
        return Ok(beside);
    }
    let made = FaceModels::load()
        .context("loading the face models")
        .and_then(|models| for_capture(character, character_path, None, &models));
    match made {
        Ok(map) => Ok(map),
        Err(e) => {
            eprintln!(
                "warning: {} has no retarget map and one could not be made ({e:#}): the clip's ARKit channels reach only the shapes named for them",
                character.name()
            );
            Ok(None)
        }
    }
}

/// The map a capture command uses for `character` (loaded from `character_path`): the one
/// at `given` or beside the character when it fits; made (and saved beside the character)
/// when the rig's names leave channels MediaPipe reads without a shape; `None` for a rig its
/// names drive whole, which is driven by name.
pub fn for_capture(
    character: &Character,
    character_path: Option<&Path>,
    given: Option<&Path>,
    models: &FaceModels,
) -> anyhow::Result<Option<RetargetMap>> {
    let names = character.blendshape_names();
    if let Some(path) = given {
        return read_given(path, character, &names).map(Some);
    }
    let path = default_path(character_path, character);
    if let Some(map) = read(&path, &names)? {
        return Ok(Some(map));
    }
    if !faceanim_adapt::bridge::needs_map(character) {
        return Ok(None);
    }
    // Commands started together on one character (a batch's workers on a day's takes) make
    // its map once: the others wait, then read it.
    let _making = Making::start(&path);
    if let Some(map) = read(&path, &names)? {
        return Ok(Some(map));
    }
    let points = face_points(character_path, character, None)?;
    let map = make(character, models, None, points.as_ref(), true)?;
    match faceanim_files::write_atomic(&path, map.to_json().as_bytes()) {
        Ok(()) => eprintln!(
            "saved {} (edit it, or faceanim retarget --set)",
            path.display()
        ),
        Err(e) => eprintln!("warning: the map was not saved: {e}"),
    }
    Ok(Some(map))
}

/// The lock held while a map is made beside a character (`.NAME.retarget.json.lock`, locked,
/// then removed before it is let go, so that no lock file stays in the user's folder); none
/// where the folder takes no file (then the map is not saved there either).
struct Making {
    path: PathBuf,
    _file: std::fs::File,
}

impl Making {
    fn start(map: &Path) -> Option<Making> {
        let name = map.file_name()?.to_string_lossy();
        let path = map.with_file_name(format!(".{name}.lock"));
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .ok()?;
        file.lock().ok()?;
        Some(Making { path, _file: file })
    }
}

impl Drop for Making {
    fn drop(&mut self) {
        // Removed while still locked: one who waits on it finds the map made once it has the
        // lock; one who comes later finds the map before looking for a lock.
        let _ = std::fs::remove_file(&self.path);
    }
}
