//! `faceanim stream`: plays a clip or a take to a VMC marionette (VSeeFace, Warudo, VNyan,
//! Unity's or Unreal's VMC receiver) at a steady rate.

use std::net::{SocketAddr, ToSocketAddrs as _};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use faceanim_anim::Clip;
use faceanim_export::bones::BoneKeys;
use faceanim_live::{Names, Performer, Pose};

/// The fastest rate frames are sent at.
const MAX_FPS: f32 = 120.0;

/// Which names the stream uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NameChoice {
    /// The character's own blendshape names.
    Own,
    /// ARKit's 52 names (`EyeBlinkLeft`…), for perfect-sync avatars and phone-tracking setups.
    Arkit,
    /// VRM 0.x presets (A I U E O Blink Blink_L Blink_R Joy Angry Sorrow Fun).
    Vrm,
}

impl From<NameChoice> for Names {
    fn from(choice: NameChoice) -> Names {
        match choice {
            NameChoice::Own => Names::Own,
            NameChoice::Arkit => Names::Arkit,
            NameChoice::Vrm => Names::VrmPresets,
        }
    }
}

/// `faceanim stream`'s arguments.
#[derive(Debug, clap::Args)]
pub struct StreamArgs {
    /// A clip (.json), a session (.session.json, from the studio or `faceanim track`), or
    /// what `export --clip` reads: a Live Link Face CSV (the app's recordings), a VRM
    /// Animation (.vrma), a GLB's or VRM's morph-weight animation.
    pub input: PathBuf,
    /// Put the clip on this character first (its names are then the ones sent).
    #[arg(long)]
    pub character: Option<PathBuf>,
    /// The character's retarget map, through which the clip's ARKit channels reach a rig
    /// whose names say nothing (default: NAME.retarget.json beside the character; made and
    /// saved there when the clip has ARKit channels the rig's names leave without a shape).
    #[arg(long, value_name = "MAP", requires = "character")]
    pub retarget: Option<PathBuf>,
    /// The marionette: HOST:PORT (VMC's default port is 39539).
    #[arg(long)]
    pub to: String,
    /// Frames per second sent (default: the clip's own rate, or 120 for a faster clip; at
    /// most 120).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Start again at the end, until stopped.
    #[arg(long = "loop")]
    pub repeat: bool,
    /// The names sent.
    #[arg(long, value_enum, default_value_t = NameChoice::Own)]
    pub names: NameChoice,
}

pub fn run(args: StreamArgs) -> anyhow::Result<()> {
    // A session's gaze and jaw from what it was made of (MediaPipe's scores, a phone's values),
    // as its export turns eye and jaw bones; and those values, for the ARKit channels (or VRM
    // presets) the character's shapes cannot make. A recording (Live Link Face's CSV) or an
    // animation file, as `export --clip` reads them, is a clip.
    let (clip, arkit) = if crate::input::is_animation_file(&args.input) {
        (crate::input::clip(&args.input)?, None)
    } else {
        let bytes = faceanim_files::read_bytes(&args.input)?;
        match Clip::from_json(&bytes) {
            // A clip JSON keeps what its take was made of where its names leave channels out.
            Ok(clip) => {
                let arkit = clip.arkit_clip();
                (clip, arkit)
            }
            Err(clip_error) => faceanim_take::Session::from_json(&bytes)
                .map(|session| (session.clip(), session.arkit_clip()))
                .map_err(|session_error| {
                    anyhow::anyhow!(
                        "{}: neither a clip ({clip_error}) nor a session ({session_error})",
                        args.input.display()
                    )
                })?,
        }
    };
    let keys = BoneKeys::of_take(&clip, arkit.as_ref());
    let arkit = arkit.map(|a| a.arkit_rows());
    let clip = match &args.character {
        Some(path) => {
            let character = crate::input::load(path)?.character;
            let clip = clip.for_character(&character);
            let map =
                crate::retarget::for_clip(&character, Some(path), args.retarget.as_deref(), &clip)?;
            faceanim_export::Animation::from_clip_through(&character, &clip, "stream", map.as_ref())
                .with_context(|| format!("putting {} on {}", args.input.display(), path.display()))?
                .clip
        }
        None => clip,
    };
    anyhow::ensure!(
        !clip.frames.is_empty(),
        "{}: the clip has no frames",
        args.input.display()
    );
    if let Some(fps) = args.fps {
        anyhow::ensure!(
            fps.is_finite() && fps > 0.0 && fps <= MAX_FPS,
            "--fps must be above 0 and at most {MAX_FPS}, got {fps}"
        );
    }
    // A clip made faster than receivers take frames (a lip sync at 240) is sent at the most.
    let fps = args.fps.unwrap_or(clip.fps.min(MAX_FPS));
    let destination = destination(&args.to)?;
    let mut performer = match arkit {
        Some(_) => Performer::with_arkit(destination, &clip.blendshapes, args.names.into())?,
        None => Performer::new(destination, &clip.blendshapes, args.names.into())?,
    };

    let duration = (clip.frames.len() - 1) as f32 / clip.fps.max(1e-3);
    let frames = (duration * fps).round() as usize + 1;
    eprintln!(
        "streaming {} ({} frames at {fps} fps{}) to {destination}; Ctrl+C stops",
        args.input.display(),
        frames,
        if args.repeat { ", looping" } else { "" }
    );
    let started = Instant::now();
    let mut sending = Duration::ZERO;
    let mut slowest = Duration::ZERO;
    let mut k: u64 = 0;
    loop {
        let f = (k % frames as u64) as usize;
        if f == 0 && k > 0 && !args.repeat {
            break;
        }
        // Each frame on its own schedule, so time does not drift with the sending.
        let due = started + Duration::from_secs_f64(k as f64 / f64::from(fps));
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let at = f as f32 / fps;
        let (weights, pose) = sample(&clip, &keys, at);
        let before = Instant::now();
        let time = started.elapsed().as_secs_f32();
        match &arkit {
            Some(rows) => {
                let values = between(rows, clip.fps, at);
                performer.send_with_arkit(&weights, &values, pose, time)
            }
            None => performer.send_pose(&weights, pose, time),
        };
        let took = before.elapsed();
        sending += took;
        slowest = slowest.max(took);
        k += 1;
    }
    let stats = performer.stats();
    let summary = serde_json::json!({
        "frames": stats.frames,
        "sent": stats.sent,
        "dropped": stats.dropped,
        "last_error": stats.last_error,
        "seconds": started.elapsed().as_secs_f64(),
        "fps": fps,
        "send_ms_mean": sending.as_secs_f64() * 1000.0 / stats.frames.max(1) as f64,
        "send_ms_max": slowest.as_secs_f64() * 1000.0,
    });
    outln!("{summary}");
    if stats.dropped > 0 {
        eprintln!(
            "warning: {} of {} frames were refused by the network ({}); is the marionette listening on {destination}?",
            stats.dropped,
            stats.frames,
            stats.last_error.as_deref().unwrap_or("no reason given")
        );
    }
    Ok(())
}

/// A marionette's address, `HOST:PORT`.
pub fn destination(text: &str) -> anyhow::Result<SocketAddr> {
    text.to_socket_addrs()
        .with_context(|| format!("{text}: not a HOST:PORT"))?
        .next()
        .with_context(|| format!("{text}: no address"))
}

/// Where to listen for VMC: `PORT` (every interface: phones send over the local network) or
/// `ADDR:PORT`.
pub fn listen_address(text: &str) -> anyhow::Result<SocketAddr> {
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from(([0, 0, 0, 0], port)));
    }
    text.parse()
        .with_context(|| format!("--vmc-listen {text}: give a PORT or ADDR:PORT"))
}

/// The frames `a` and `b` around `time` seconds in `count` frames at `fps`, and how far
/// between them it lies.
fn around(count: usize, fps: f32, time: f32) -> (usize, usize, f32) {
    let last = count.saturating_sub(1);
    let position = (time * fps).clamp(0.0, last as f32);
    let a = position.floor() as usize;
    (a, (a + 1).min(last), position - a as f32)
}

/// `rows` (one per frame at `fps`) at `time` seconds, between frames linearly.
fn between(rows: &[Vec<f32>], fps: f32, time: f32) -> Vec<f32> {
    let (a, b, u) = around(rows.len(), fps, time);
    rows[a]
        .iter()
        .zip(&rows[b])
        .map(|(&x, &y)| x + (y - x) * u)
        .collect()
}

/// The clip's weights and its head, gaze and jaw (`keys`, one per frame) at `time` seconds,
/// between its frames linearly.
fn sample(clip: &Clip, keys: &BoneKeys, time: f32) -> (Vec<f32>, Pose) {
    let (a, b, u) = around(clip.frames.len(), clip.fps, time);
    let lerp = |x: f32, y: f32| x + (y - x) * u;
    let weights = between(&clip.frames, clip.fps, time);
    let head = clip.head.as_ref().and_then(|h| {
        let (x, y) = (h.get(a)?, h.get(b)?);
        Some([lerp(x[0], y[0]), lerp(x[1], y[1]), lerp(x[2], y[2])])
    });
    let eyes = keys.gaze.as_ref().and_then(|g| {
        let (x, y) = (g.get(a)?, g.get(b)?);
        Some(std::array::from_fn(|e| {
            std::array::from_fn(|i| lerp(x[e][i], y[e][i]))
        }))
    });
    let jaw = keys
        .jaw
        .as_ref()
        .and_then(|j| Some(lerp(*j.get(a)?, *j.get(b)?)));
    (weights, Pose { head, eyes, jaw })
}
