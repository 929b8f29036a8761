//! The marionette: frames in from a phone tracker (VMC, or the phone apps' own protocols, see
//! [`crate::phone`]) or another performer.

use std::collections::{HashMap, VecDeque};
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use rosc::{OscMessage, OscPacket, OscType};

use faceanim_rig::names::{Drive, Expression, Viseme};

use crate::phone::{self, AngleUnit, Packet, Protocol, Reading};
use crate::{LiveError, Performer, head_angles};

/// Datagrams larger than this are not VMC frames (a frame of 124 blendshapes is about 6 KiB).
const MAX_DATAGRAM: usize = 32 * 1024;
/// Bundles nested deeper than this are refused.
const MAX_DEPTH: usize = 8;
/// ARKit's channels.
const ARKIT_COUNT: usize = faceanim_rig::names::ARKIT_52.len();
/// Names whose meaning is kept (a sender of ever new names cannot grow the table further).
const MAX_NAMES: usize = 4096;
/// How long (seconds) a channel the sender named stays its own: longer than a sender of only
/// what changed goes without sending it again (faceanim's performer: 30 frames).
const NAMED_FOR: f64 = 3.0;
/// Frames kept for [`Marionette::wait_for_frames`].
const HISTORY: usize = 1024;
/// How often the receiving thread looks at its stop flag.
const POLL: Duration = Duration::from_millis(50);
/// How often a phone that must be asked is asked again (VTube Studio's request lasts a little
/// longer, so that a late one leaves no gap).
const ASK_EVERY: Duration = Duration::from_secs(1);
/// Frames whose forwarding delay is kept for the median and 95th percentile.
const DELAYS: usize = 4096;
/// Names listed in [`Traffic::unmatched_names`], at most.
const MAX_UNMATCHED_NAMES: usize = 32;
/// A value above this is motion: its name is listed when it reaches nothing (a sender sends
/// every name it knows each frame, most of them at rest).
const MOTION: f32 = 0.05;

/// A source's neutral face: the head pose and ARKit values of a relaxed face, taken away from
/// what arrives (a value at rest reads 0 and full still reads 1).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Neutral {
    /// Head yaw, pitch, roll in degrees.
    pub head: [f32; 3],
    /// ARKit's 52 values, in `ARKIT_52`'s order.
    pub channels: Vec<f32>,
}

impl Neutral {
    fn value(&self, channel: usize, value: f32) -> f32 {
        let rest = self.channels.get(channel).copied().unwrap_or(0.0);
        if rest <= 0.0 || rest >= 0.95 {
            return value;
        }
        ((value - rest) / (1.0 - rest)).clamp(0.0, 1.0)
    }
}

/// How a source's angles are read and what its neutral face is: a user's settings, kept
/// between runs (see `faceanim studio --phone`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSettings {
    /// The head's angles' unit.
    pub head_unit: AngleUnit,
    /// The eyes' angles' unit.
    pub eye_unit: AngleUnit,
    /// The neutral face, once calibrated.
    #[serde(default)]
    pub neutral: Option<Neutral>,
}

impl SourceSettings {
    /// The protocol's own units, no neutral.
    #[must_use]
    pub fn of(protocol: Protocol) -> SourceSettings {
        SourceSettings {
            head_unit: protocol.default_units(),
            eye_unit: protocol.default_units(),
            neutral: None,
        }
    }
}

/// What a marionette listens to.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The protocol.
    pub protocol: Protocol,
    /// The phone to ask for frames (iFacialMocap's handshake, VTube Studio's request); the
    /// others send unasked.
    pub phone: Option<SocketAddr>,
    /// Units and neutral.
    pub settings: SourceSettings,
}

impl Source {
    /// VMC, as performers send it.
    #[must_use]
    pub fn vmc() -> Source {
        Source {
            protocol: Protocol::Vmc,
            phone: None,
            settings: SourceSettings::of(Protocol::Vmc),
        }
    }
}

/// How long frames took from their datagram's arrival to leaving again over VMC.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Forwarding {
    /// Frames sent on.
    pub frames: u64,
    /// Frames the network refused.
    pub dropped: u64,
    /// The median delay of the last frames, in milliseconds.
    pub median_ms: f64,
    /// Their 95th percentile, in milliseconds.
    pub p95_ms: f64,
}

/// One frame received: the character's weights (every blendshape, in its order, holding the
/// last value sent), the head pose and when it arrived.
#[derive(Debug, Clone, PartialEq)]
pub struct ReceivedFrame {
    /// Seconds from when the marionette started listening to the frame's arrival; in a
    /// recording ([`Marionette::stop_recording`]), on the sender's clock where it is sound
    /// (a take made of frames counts from its first, on any clock).
    pub time: f64,
    /// The character's weights.
    pub weights: Vec<f32>,
    /// Head yaw, pitch, roll in degrees, once a head pose arrived.
    pub head: Option<[f32; 3]>,
    /// The ARKit values of a phone, or of a VMC sender that names ARKit's channels (a
    /// "perfect sync" tracker) or sends eye or jaw bones (their eyeLook and jawOpen values),
    /// ARKit's 52 channels in [`faceanim_rig::names::ARKIT_52`]'s order, each clamped to 0..1,
    /// a channel not sent at its last value (what [`ReceivedFrame::eyes`] and
    /// [`ReceivedFrame::jaw`] are read from).
    pub arkit: Option<Vec<f32>>,
}

impl ReceivedFrame {
    /// Each eye's gaze `[yaw, pitch]` in degrees (left, right), from the eyeLook values of
    /// [`ReceivedFrame::arkit`], as exports turn eye bones: the phone apps' own eye angles
    /// differ in sign and unit from one app to the next, and Live Link Face's are those values
    /// at the same range (tests/phones.rs).
    #[must_use]
    pub fn eyes(&self) -> Option<[[f32; 2]; 2]> {
        let arkit = self.arkit.as_deref()?;
        Some(faceanim_rig::bones::gaze_from_arkit(|c| channel(arkit, c)))
    }

    /// `jawOpen`, of [`ReceivedFrame::arkit`].
    #[must_use]
    pub fn jaw(&self) -> Option<f32> {
        Some(channel(self.arkit.as_deref()?, "jawOpen"))
    }

    /// The head, gaze and jaw, as a performer sends them on.
    #[must_use]
    pub fn pose(&self) -> crate::Pose {
        crate::Pose {
            head: self.head,
            eyes: self.eyes(),
            jaw: self.jaw(),
        }
    }
}

/// ARKit channel `name`'s value in a row of ARKit's 52 (0 for a name that is none of them).
fn channel(arkit: &[f32], name: &str) -> f32 {
    faceanim_retarget::channel_index(name)
        .and_then(|i| arkit.get(i))
        .copied()
        .unwrap_or(0.0)
}

/// What arrived so far.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Traffic {
    /// Datagrams received.
    pub packets: u64,
    /// Frames completed (`/VMC/Ext/Blend/Apply`).
    pub frames: u64,
    /// What is listened to.
    pub protocol: Option<Protocol>,
    /// Datagrams that are not OSC, truncated, or whose messages have the wrong arguments
    /// (a phone's frame cut short or with a field that cannot be read).
    pub malformed: u64,
    /// Datagrams of another kind (Live Link Face's MetaHuman Animator packets, another
    /// protocol).
    pub foreign: u64,
    /// Times the tracker said it lost the face (the character went back to neutral).
    pub faces_lost: u64,
    /// Messages with addresses the marionette does not know.
    pub unknown: u64,
    /// Datagrams too large to be a frame.
    pub oversized: u64,
    /// Blendshape values that reached nothing: for names the character has no shape of, by
    /// name or meaning, with no retarget map to carry them.
    pub unmatched: u64,
    /// The names of those values that moved (a value above 0.05: a sender sends every name it
    /// knows, most at rest), each once, in the order first lost, at most 32. Cleared when a
    /// map is set, which carries ARKit's names on.
    pub unmatched_names: Vec<String>,
    /// Who sent the last datagram.
    pub sender: Option<SocketAddr>,
    /// Datagrams in the last second.
    pub rate: f32,
    /// Milliseconds since the last datagram.
    pub last_packet_ms: Option<f64>,
    /// Frames sent on over VMC as they arrived, and how long that took.
    pub forwarded: Option<Forwarding>,
}

impl Traffic {
    /// Counts a value for `name` that reached nothing, and lists the name when it moved.
    fn lost(&mut self, name: &str, value: f32) {
        self.unmatched += 1;
        if value > MOTION
            && self.unmatched_names.len() < MAX_UNMATCHED_NAMES
            && !self.unmatched_names.iter().any(|n| n == name)
        {
            self.unmatched_names.push(name.to_owned());
        }
    }
}

#[derive(Debug)]
struct State {
    started: Instant,
    traffic: Traffic,
    arrivals: VecDeque<Instant>,
    last_arrival: Option<Instant>,
    /// Each name received → what it means for the character, as names arrive (at most
    /// [`MAX_NAMES`]).
    lookup: HashMap<String, Meaning>,
    /// The character's shapes each ARKit channel drives by name (for other spellings).
    arkit: HashMap<&'static str, Vec<usize>>,
    /// The character's shapes that are each viseme by name (VRM's vowels drive them).
    visemes: HashMap<Viseme, Vec<usize>>,
    /// The character's own names.
    own: HashMap<String, usize>,
    /// The character's retarget map: ARKit values it has no shape named for reach its shapes
    /// through it.
    map: Option<Arc<faceanim_retarget::RetargetMap>>,
    /// ARKit's 52 channel values as they arrived (for the map, and the frames' `arkit`).
    channels: Vec<f32>,
    /// Whether any ARKit value arrived since listening started (then frames carry them).
    heard_arkit: bool,
    /// When each ARKit channel last arrived by name (seconds since listening started; VMC's
    /// eye and jaw bones and VRM's presets stand for the others, see [`State::named`]).
    named_at: Vec<f64>,
    /// Which ARKit channels a vowel's own shapes show (a map leaves them).
    shown: Vec<bool>,
    /// The gaze `[yaw, pitch]` of VMC's `LeftEye` and `RightEye` bones, once sent.
    eye_bones: [Option<[f32; 2]>; 2],
    /// How open VMC's `Jaw` bone is (0..1 at [`crate::JAW_DEGREES`]), once sent.
    jaw_bone: Option<f32>,
    /// Whether an ARKit value arrived under a name that is none of the character's own (then
    /// a map makes the frame).
    through_map: bool,
    /// The shapes set by their own names, which the map leaves as sent.
    direct: Vec<bool>,
    current: Vec<f32>,
    head: Option<[f32; 3]>,
    /// The neck's rotation in this frame (Unity's), which the head's follows.
    neck: Option<[f32; 4]>,
    history: VecDeque<ReceivedFrame>,
    /// The frames recorded, and when their senders say each was made.
    recording: Option<(Vec<ReceivedFrame>, Vec<Option<f64>>)>,
    /// Units and neutral of a phone's frames.
    settings: SourceSettings,
    /// The last face a phone sent, as sent (for calibrating).
    raw: Option<Reading>,
    /// The sender's time of the frame being made, when it said.
    sent: Option<f64>,
    /// Where frames go on as they arrive, and the delays of the last ones (ms).
    forward: Option<Arc<Mutex<Performer>>>,
    delays: VecDeque<f64>,
    forwarding: Forwarding,
}

/// Listens for VMC or a phone's protocol on a UDP port (see the crate docs). Stops listening
/// when dropped.
#[derive(Debug)]
pub struct Marionette {
    address: SocketAddr,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl State {
    /// Whether the sender names ARKit channel `c` itself: it did within the last
    /// [`NAMED_FOR`] (a sender that stops, a tracker switched from perfect sync to VRM's
    /// presets, gives the channel back to what stands for it).
    fn named(&self, c: usize, now: f64) -> bool {
        now - self.named_at[c] < NAMED_FOR
    }
}

fn lock(state: &Mutex<State>) -> MutexGuard<'_, State> {
    state
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl Marionette {
    /// Listens on `address` (port 0 picks a free one) for the face of a character whose
    /// blendshapes are `blendshapes`: values named as they are, or in another ARKit spelling
    /// for its ARKit-named shapes (`EyeBlinkLeft` for `eyeBlink_L`).
    ///
    /// # Errors
    /// [`LiveError::Socket`] when the address cannot be bound.
    pub fn listen(address: SocketAddr, blendshapes: &[String]) -> Result<Marionette, LiveError> {
        Marionette::listen_to(&Source::vmc(), address, blendshapes)
    }

    /// Listens on `address` for `source`: VMC as [`Marionette::listen`] does, or a phone
    /// app's own frames (ARKit values, reaching shapes named otherwise by their ARKit meaning
    /// or through the map), asking the phone for them when its protocol needs that.
    ///
    /// # Errors
    /// [`LiveError::Socket`] when the address cannot be bound.
    pub fn listen_to(
        source: &Source,
        address: SocketAddr,
        blendshapes: &[String],
    ) -> Result<Marionette, LiveError> {
        let socket_error = |source| LiveError::Socket { address, source };
        let socket = UdpSocket::bind(address).map_err(socket_error)?;
        socket.set_read_timeout(Some(POLL)).map_err(socket_error)?;
        let bound = socket.local_addr().map_err(socket_error)?;
        // An ARKit channel drives every shape the name table gives it (both halves of ICT's
        // browInnerUp_L/_R, a merged mouthSmile).
        let mut arkit: HashMap<&'static str, Vec<usize>> = HashMap::new();
        // And a viseme (VRoid's `Fcl_MTH_A`) the shapes that are it, for VRM's vowels.
        let mut visemes: HashMap<Viseme, Vec<usize>> = HashMap::new();
        let map = faceanim_rig::name_map::NameMap::from_names(blendshapes, &[]);
        for (i, drive) in map.driven_drives() {
            if let Drive::Expression(expression) = drive {
                if let Expression::Viseme(viseme) = expression {
                    visemes.entry(viseme).or_default().push(i);
                }
                continue;
            }
            for c in drive.channels() {
                arkit.entry(c.name()).or_default().push(i);
            }
        }
        let state = Arc::new(Mutex::new(State {
            started: Instant::now(),
            traffic: Traffic {
                protocol: Some(source.protocol),
                ..Traffic::default()
            },
            arrivals: VecDeque::new(),
            last_arrival: None,
            lookup: HashMap::new(),
            arkit,
            visemes,
            own: blendshapes
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), i))
                .collect(),
            map: None,
            channels: vec![0.0; faceanim_rig::names::ARKIT_52.len()],
            heard_arkit: false,
            named_at: vec![f64::NEG_INFINITY; ARKIT_COUNT],
            shown: vec![false; ARKIT_COUNT],
            eye_bones: [None; 2],
            jaw_bone: None,
            through_map: false,
            direct: vec![false; blendshapes.len()],
            current: vec![0.0; blendshapes.len()],
            head: None,
            neck: None,
            history: VecDeque::new(),
            recording: None,
            settings: source.settings.clone(),
            raw: None,
            sent: None,
            forward: None,
            delays: VecDeque::new(),
            forwarding: Forwarding::default(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (state, stop) = (state.clone(), stop.clone());
            let (protocol, phone) = (source.protocol, source.phone);
            std::thread::Builder::new()
                .name(format!("{} {bound}", protocol.label()))
                .spawn(move || receive(&socket, protocol, phone, &state, &stop))
                .map_err(socket_error)?
        };
        tracing::info!("listening for {} on {bound}", source.protocol.label());
        Ok(Marionette {
            address: bound,
            state,
            stop,
            thread: Some(thread),
        })
    }

    /// Reads ARKit values through `map` from now on (`None`: by name alone): a channel the
    /// character has no shape named for reaches the shapes the map gives it (a phone's
    /// `jawOpen` opening a VRoid mouth), while values named as the character's own shapes
    /// set those shapes as sent. A map of other shapes is ignored, with a warning.
    pub fn set_map(&self, map: Option<Arc<faceanim_retarget::RetargetMap>>) {
        let mut state = lock(&self.state);
        if let Some(m) = &map
            && m.blendshapes.len() != state.current.len()
        {
            tracing::warn!(
                "a retarget map of {} shapes does not fit this character",
                m.blendshapes.len()
            );
            return;
        }
        if map.is_some() {
            state.traffic.unmatched_names.clear();
        }
        state.map = map;
    }

    /// The address it listens on.
    #[must_use]
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Sends every frame on to `performer` as soon as it is made (the phone's face out to a
    /// VTuber app), timing each from its datagram's arrival; `None` stops.
    pub fn forward_to(&self, performer: Option<Arc<Mutex<Performer>>>) {
        lock(&self.state).forward = performer;
    }

    /// Takes the phone's last face as its neutral from now on and returns the settings to
    /// keep; `None` when no phone face has arrived yet.
    #[must_use]
    pub fn calibrate(&self) -> Option<SourceSettings> {
        let mut state = lock(&self.state);
        let raw = state.raw.clone()?;
        let mut channels = state
            .settings
            .neutral
            .as_ref()
            .map_or_else(|| vec![0.0; ARKIT_COUNT], |n| n.channels.clone());
        channels.resize(ARKIT_COUNT, 0.0);
        for &(c, v) in &raw.channels {
            channels[c] = v;
        }
        state.settings.neutral = Some(Neutral {
            head: raw.head.unwrap_or_default(),
            channels,
        });
        Some(state.settings.clone())
    }

    /// The source's settings as they are now.
    #[must_use]
    pub fn settings(&self) -> SourceSettings {
        lock(&self.state).settings.clone()
    }

    /// What arrived so far, with the packet rate and the last packet's age now.
    #[must_use]
    pub fn traffic(&self) -> Traffic {
        let mut state = lock(&self.state);
        let now = Instant::now();
        forget_old(&mut state.arrivals, now);
        let mut traffic = state.traffic.clone();
        traffic.rate = state.arrivals.len() as f32;
        traffic.last_packet_ms = state
            .last_arrival
            .map(|t| now.duration_since(t).as_secs_f64() * 1000.0);
        if state.forward.is_some() || state.forwarding.frames > 0 {
            let mut delays: Vec<f64> = state.delays.iter().copied().collect();
            delays.sort_by(f64::total_cmp);
            let at = |q: f64| {
                delays
                    .get(((delays.len() as f64 - 1.0) * q).round() as usize)
                    .copied()
                    .unwrap_or(0.0)
            };
            traffic.forwarded = Some(Forwarding {
                median_ms: at(0.5),
                p95_ms: at(0.95),
                ..state.forwarding.clone()
            });
        }
        traffic
    }

    /// The last frame received, if any.
    #[must_use]
    pub fn latest(&self) -> Option<ReceivedFrame> {
        lock(&self.state).history.back().cloned()
    }

    /// Starts keeping every frame that arrives (a take being recorded).
    pub fn start_recording(&self) {
        lock(&self.state).recording = Some((Vec::new(), Vec::new()));
    }

    /// Frames recorded so far, while recording.
    #[must_use]
    pub fn recorded(&self) -> Option<usize> {
        lock(&self.state).recording.as_ref().map(|(f, _)| f.len())
    }

    /// Stops recording and returns the frames kept, or `None` when it was not recording. They
    /// are timed by the sender's own clock where it gave one for nine frames in ten and it is
    /// sound (VMC's `/VMC/Ext/T`, Live Link Face's frame times, VTube Studio's timestamps: free
    /// of the network's delays and bursts), else by their arrival.
    #[must_use]
    pub fn stop_recording(&self) -> Option<Vec<ReceivedFrame>> {
        let (mut frames, sent) = lock(&self.state).recording.take()?;
        let arrived: Vec<f64> = frames.iter().map(|f| f.time).collect();
        for (frame, time) in frames.iter_mut().zip(crate::clock::clock(&arrived, &sent)) {
            frame.time = time;
        }
        Some(frames)
    }

    /// Waits up to `timeout` for `count` frames to have arrived and returns the first `count`
    /// still kept (fewer when the time ran out).
    #[must_use]
    pub fn wait_for_frames(&self, count: usize, timeout: Duration) -> Vec<ReceivedFrame> {
        let until = Instant::now() + timeout;
        loop {
            {
                let state = lock(&self.state);
                if state.history.len() >= count || Instant::now() >= until {
                    return state.history.iter().take(count).cloned().collect();
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

impl Drop for Marionette {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn forget_old(arrivals: &mut VecDeque<Instant>, now: Instant) {
    while arrivals
        .front()
        .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
    {
        arrivals.pop_front();
    }
}

/// The receiving thread: every datagram is counted, decoded and applied, or counted as
/// dropped; a phone that must be asked is asked every second.
fn receive(
    socket: &UdpSocket,
    protocol: Protocol,
    phone: Option<SocketAddr>,
    state: &Mutex<State>,
    stop: &AtomicBool,
) {
    // One byte more than the largest accepted datagram tells an oversized one from a full one.
    let mut buffer = vec![0u8; MAX_DATAGRAM + 1];
    let mut asked: Option<Instant> = None;
    while !stop.load(Ordering::Relaxed) {
        if let Some(phone) = phone
            && asked.is_none_or(|t| t.elapsed() >= ASK_EVERY)
        {
            ask(socket, protocol, phone, state);
            asked = Some(Instant::now());
        }
        let (length, sender) = match socket.recv_from(&mut buffer) {
            Ok(received) => received,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(e) => {
                tracing::debug!("vmc: {e}");
                continue;
            }
        };
        let now = Instant::now();
        let mut state = lock(state);
        state.traffic.packets += 1;
        state.traffic.sender = Some(sender);
        state.last_arrival = Some(now);
        state.arrivals.push_back(now);
        forget_old(&mut state.arrivals, now);
        if length > MAX_DATAGRAM {
            state.traffic.oversized += 1;
            continue;
        }
        let time = now.duration_since(state.started).as_secs_f64();
        let made = state.traffic.frames;
        if protocol == Protocol::Vmc {
            match rosc::decoder::decode_udp(&buffer[..length]) {
                Ok((_, packet)) => {
                    if !apply(&mut state, &packet, time, 0) {
                        state.traffic.malformed += 1;
                    }
                }
                Err(_) => state.traffic.malformed += 1,
            }
        } else {
            let units = (state.settings.head_unit, state.settings.eye_unit);
            match phone::decode(protocol, &buffer[..length], units.0, units.1) {
                Ok(Packet::Face(reading)) => apply_reading(&mut state, reading, time),
                Ok(Packet::FaceLost) => {
                    state.traffic.faces_lost += 1;
                    state.raw = None;
                    state.channels.fill(0.0);
                    state.current.fill(0.0);
                    state.head = Some([0.0; 3]);
                    complete_frame(&mut state, time);
                }
                Err(refused) => {
                    tracing::debug!("{refused}");
                    match refused {
                        phone::Refused::Foreign { .. } => state.traffic.foreign += 1,
                        _ => state.traffic.malformed += 1,
                    }
                }
            }
        }
        if state.traffic.frames > made {
            forward(&mut state, now);
        }
    }
}

/// Asks the phone for frames: iFacialMocap's handshake until frames come, VTube Studio's
/// request every second.
fn ask(socket: &UdpSocket, protocol: Protocol, phone: SocketAddr, state: &Mutex<State>) {
    let request = match protocol {
        Protocol::IFacialMocap => {
            let quiet = lock(state)
                .last_arrival
                .is_none_or(|t| t.elapsed() > 2 * ASK_EVERY);
            if !quiet {
                return;
            }
            phone::IFACIALMOCAP_HANDSHAKE.to_owned()
        }
        Protocol::VTubeStudio => {
            let port = socket.local_addr().map_or(0, |a| a.port());
            phone::vtube_studio_request(port, 1.5 * ASK_EVERY.as_secs_f32())
        }
        Protocol::Vmc | Protocol::LiveLinkFace => return,
    };
    if let Err(e) = socket.send_to(request.as_bytes(), phone) {
        tracing::debug!("asking {phone} for frames: {e}");
    }
}

/// A phone's face: its values become the character's weights (by name, or through the map)
/// and a frame is made.
fn apply_reading(state: &mut State, reading: Reading, time: f64) {
    let neutral = state.settings.neutral.clone();
    for &(channel, value) in &reading.channels {
        let value = neutral.as_ref().map_or(value, |n| n.value(channel, value));
        state.channels[channel] = value;
        state.heard_arkit = true;
        state.named_at[channel] = time;
        state.through_map = true;
        let name = faceanim_rig::names::ARKIT_52[channel];
        if let Some(shapes) = state.arkit.get(name) {
            for &i in shapes {
                state.current[i] = value;
            }
        } else if let Some(&i) = state.own.get(name) {
            state.current[i] = value;
        } else if state.map.is_none() {
            state.traffic.lost(name, value);
        }
    }
    if let Some(head) = reading.head {
        let rest = neutral.as_ref().map_or([0.0; 3], |n| n.head);
        state.head = Some([head[0] - rest[0], head[1] - rest[1], head[2] - rest[2]]);
    }
    state.sent = reading.time;
    state.raw = Some(reading);
    complete_frame(state, time);
}

/// Sends the frame just made on over VMC, timing it from its datagram's arrival.
fn forward(state: &mut State, arrived: Instant) {
    let Some(performer) = state.forward.clone() else {
        return;
    };
    let Some(frame) = state.history.back() else {
        return;
    };
    let mut performer = lock_performer(&performer);
    let time = frame.time as f32;
    let sent = match &frame.arkit {
        Some(arkit) => performer.send_with_arkit(&frame.weights, arkit, frame.pose(), time),
        None => performer.send_pose(&frame.weights, frame.pose(), time),
    };
    drop(performer);
    if sent {
        state.forwarding.frames += 1;
        if state.delays.len() >= DELAYS {
            state.delays.pop_front();
        }
        state
            .delays
            .push_back(arrived.elapsed().as_secs_f64() * 1000.0);
    } else {
        state.forwarding.dropped += 1;
    }
}

fn lock_performer(performer: &Mutex<Performer>) -> MutexGuard<'_, Performer> {
    performer
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Applies a packet; false when it is malformed (bad arguments, bundles nested too deep).
fn apply(state: &mut State, packet: &OscPacket, time: f64, depth: usize) -> bool {
    match packet {
        OscPacket::Bundle(bundle) => {
            depth < MAX_DEPTH
                && bundle
                    .content
                    .iter()
                    .all(|p| apply(state, p, time, depth + 1))
        }
        OscPacket::Message(message) => apply_message(state, message, time),
    }
}

fn apply_message(state: &mut State, message: &OscMessage, time: f64) -> bool {
    let float = |arg: Option<&OscType>| match arg {
        Some(OscType::Float(v)) if v.is_finite() => Some(*v),
        Some(OscType::Double(v)) if v.is_finite() => Some(*v as f32),
        _ => None,
    };
    match message.addr.as_str() {
        "/VMC/Ext/Blend/Val" => {
            let (Some(OscType::String(name)), Some(value)) =
                (message.args.first(), float(message.args.get(1)))
            else {
                return false;
            };
            let value = value.clamp(0.0, 1.0);
            // What the name means for this character, worked out once per name (a sender
            // sends each name 30–60 times a second).
            if !state.lookup.contains_key(name.as_str()) && state.lookup.len() < MAX_NAMES {
                let meaning = Meaning::of(name, &state.own, &state.arkit, &state.visemes);
                state.lookup.insert(name.clone(), meaning);
            }
            let uncached;
            let meaning = match state.lookup.get(name.as_str()) {
                Some(meaning) => meaning,
                None => {
                    uncached = Meaning::of(name, &state.own, &state.arkit, &state.visemes);
                    &uncached
                }
            };
            // Kept with or without a map, so that a map given mid-stream starts from every
            // channel's last value (a sender sends only what changed), and for the frames'
            // eyes, jaw and ARKit values (a body with no shapes follows them by its bones).
            if let Some(c) = meaning.channel {
                state.channels[c] = value;
                state.heard_arkit = true;
                state.named_at[c] = time;
            }
            // A name for several channels (VRM's presets, as VSeeFace and VMagicMirror send
            // them: `Blink`, `Joy`, `A`) gives each the value, where the sender does not name
            // the channel itself.
            for &(c, _) in &meaning.stands_for {
                if !state.named(c, time) {
                    state.channels[c] = value;
                }
                state.heard_arkit = true;
            }
            if let Some(i) = meaning.own {
                state.current[i] = value;
                state.direct[i] = true;
                // A preset's own shape (`blink`, `happy`) shows the channels it stands for:
                // a map does not make them again.
                for &(c, _) in &meaning.stands_for {
                    state.shown[c] = true;
                }
                return true;
            }
            if meaning.viseme {
                // A vowel sets the shapes that are it as sent, map or not; the channels it
                // stands for are shown by them, so a map does not open the mouth again.
                for &i in &meaning.shapes {
                    state.current[i] = value;
                    state.direct[i] = true;
                }
                for &(c, _) in &meaning.stands_for {
                    state.shown[c] = true;
                }
                return true;
            }
            if meaning.channel.is_some() || !meaning.stands_for.is_empty() {
                state.through_map = true;
                if state.map.is_some() {
                    return true;
                }
            }
            for &i in &meaning.shapes {
                state.current[i] = value;
            }
            // A preset's channels set their shapes, where the sender does not name them.
            let mut matched = !meaning.shapes.is_empty();
            if meaning.shapes.is_empty() {
                for (c, shapes) in &meaning.stands_for {
                    matched |= !shapes.is_empty();
                    if !state.named(*c, time) {
                        for &i in shapes {
                            state.current[i] = value;
                        }
                    }
                }
            }
            if !matched {
                state.traffic.lost(name, value);
            }
            true
        }
        "/VMC/Ext/Blend/Apply" => {
            complete_frame(state, time);
            state.neck = None;
            true
        }
        "/VMC/Ext/Bone/Pos" => {
            let Some(OscType::String(bone)) = message.args.first() else {
                return false;
            };
            let values: Option<Vec<f32>> = (1..8).map(|k| float(message.args.get(k))).collect();
            let Some(values) = values else {
                return false;
            };
            let rotation = [values[3], values[4], values[5], values[6]];
            match bone.as_str() {
                // A sender that shares the turn with the neck sends it first.
                "Neck" => state.neck = Some(rotation),
                "Head" => {
                    let turn = match state.neck {
                        Some(neck) => (glam::Quat::from_array(neck)
                            * glam::Quat::from_array(rotation))
                        .to_array(),
                        None => rotation,
                    };
                    state.head = head_angles(turn);
                }
                // The gaze and the jaw as faceanim's performer sends them (trackers that send
                // VRM's presets send the gaze so): each bone's turn from its rest.
                "LeftEye" | "RightEye" => {
                    let side = usize::from(bone == "RightEye");
                    state.eye_bones[side] =
                        head_angles(rotation).map(|[yaw, pitch, _]| [yaw, pitch]);
                }
                "Jaw" => {
                    state.jaw_bone = head_angles(rotation)
                        .map(|[_, pitch, _]| (-pitch / crate::JAW_DEGREES).clamp(0.0, 1.0));
                }
                _ => {}
            }
            true
        }
        "/VMC/Ext/T" => {
            // The sender's time of the frame this bundle makes.
            state.sent = message
                .args
                .first()
                .and_then(|t| match t {
                    OscType::Double(t) => Some(*t),
                    other => float(Some(other)).map(f64::from),
                })
                .filter(|t| t.is_finite());
            true
        }
        "/VMC/Ext/OK" | "/VMC/Ext/Root/Pos" | "/VMC/Ext/Blend/Apply/All" => true,
        other if other.starts_with("/VMC/Ext/") => true,
        _ => {
            state.traffic.unknown += 1;
            true
        }
    }
}

/// The ARKit values of the frame being made, once any arrived: each channel's last value,
/// clamped to 0..1; VMC's eye and jaw bones give the eyeLook and jawOpen values the sender does
/// not name.
fn arkit_row(state: &State, time: f64) -> Option<Vec<f32>> {
    let [left, right] = state.eye_bones;
    let gaze = left
        .or(right)
        .map(|one| [left.unwrap_or(one), right.unwrap_or(one)]);
    if !state.heard_arkit && gaze.is_none() && state.jaw_bone.is_none() {
        return None;
    }
    let mut row: Vec<f32> = state.channels.iter().map(|w| w.clamp(0.0, 1.0)).collect();
    let from_bones = gaze
        .map(faceanim_rig::bones::arkit_from_gaze)
        .into_iter()
        .flatten()
        .chain(state.jaw_bone.map(|open| ("jawOpen", open)));
    for (name, value) in from_bones {
        if let Some(c) = faceanim_retarget::channel_index(name).filter(|&c| !state.named(c, time)) {
            row[c] = value;
        }
    }
    Some(row)
}

/// What a received name means for the character, worked out once per name.
#[derive(Debug, Clone, Default)]
struct Meaning {
    /// The ARKit channel the name is, in any spelling.
    channel: Option<usize>,
    /// When it is no channel, the channels it stands for ([`faceanim_rig::names::stands_for`]: both of
    /// a pair, a vowel's), each with the shapes that channel drives by name.
    stands_for: Vec<(usize, Vec<usize>)>,
    /// The character's own shape of that very name, or of the same VRM preset.
    own: Option<usize>,
    /// The shapes the name sets by itself: those its ARKit channel drives, or for a vowel
    /// (`A`) the shapes that are its viseme.
    shapes: Vec<usize>,
    /// Whether `shapes` are a vowel's viseme shapes.
    viseme: bool,
}

impl Meaning {
    fn of(
        name: &str,
        own: &HashMap<String, usize>,
        arkit: &HashMap<&'static str, Vec<usize>>,
        visemes: &HashMap<Viseme, Vec<usize>>,
    ) -> Meaning {
        let driven = |channel: &str| arkit.get(channel).cloned().unwrap_or_default();
        let arkit_name = faceanim_rig::names::arkit_name(name);
        let stands_for = match arkit_name {
            Some(_) => Vec::new(),
            None => faceanim_rig::names::stands_for(name)
                .into_iter()
                .map(|c| (c.index(), driven(c.name())))
                .collect(),
        };
        let viseme_shapes = match arkit_name {
            Some(_) => None,
            None => match faceanim_rig::names::drive(name) {
                Some(Drive::Expression(Expression::Viseme(viseme))) => visemes.get(&viseme),
                _ => None,
            },
        };
        Meaning {
            channel: arkit_name.and_then(faceanim_retarget::channel_index),
            stands_for,
            // VRM's presets by either version's name: VSeeFace's `Fun` is a VRM avatar's
            // `relaxed` (faceanim reads a VRM 0.x avatar's presets under VRM 1.0's names).
            own: own.get(name).copied().or_else(|| {
                faceanim_rig::names::vrm_preset(name).and_then(|preset| own.get(preset).copied())
            }),
            shapes: match (arkit_name, viseme_shapes) {
                (Some(channel), _) => driven(channel),
                (None, Some(shapes)) => shapes.clone(),
                (None, None) => Vec::new(),
            },
            viseme: viseme_shapes.is_some_and(|shapes| !shapes.is_empty()),
        }
    }
}

/// The weights and head of what arrived so far become a frame (kept, and recorded while
/// recording).
fn complete_frame(state: &mut State, time: f64) {
    state.traffic.frames += 1;
    let weights = match &state.map {
        Some(map) if state.through_map => {
            // A channel a vowel's shapes show, and the sender does not name, is left out.
            let left_out = |c: usize| state.shown[c] && !state.named(c, time);
            let mut weights = if (0..ARKIT_COUNT).any(left_out) {
                let channels: Vec<f32> = (state.channels.iter().enumerate())
                    .map(|(c, &v)| if left_out(c) { 0.0 } else { v })
                    .collect();
                map.weights(&channels)
            } else {
                map.weights(&state.channels)
            };
            for (i, w) in weights.iter_mut().enumerate() {
                if state.direct[i] {
                    *w = state.current[i];
                }
            }
            weights
        }
        _ => state.current.clone(),
    };
    let sent = state.sent.take();
    let frame = ReceivedFrame {
        time,
        weights,
        head: state.head,
        arkit: arkit_row(state, time),
    };
    if let Some((frames, times)) = state.recording.as_mut() {
        frames.push(frame.clone());
        times.push(sent);
    }
    if state.history.len() >= HISTORY {
        state.history.pop_front();
    }
    state.history.push_back(frame);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Names, Performer};

    #[test]
    fn arkit_values_reach_shapes_named_otherwise_through_the_map() {
        let theirs: Vec<String> = ["jawOpen", "eyeBlinkLeft"].map(String::from).to_vec();
        let ours: Vec<String> = ["Fcl_MTH_A", "Fcl_EYE_Close_L"].map(String::from).to_vec();
        let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &ours).unwrap();
        let mut performer = Performer::new(marionette.address(), &theirs, Names::Arkit).unwrap();
        let wait = |marionette: &Marionette, count: usize| {
            let frames = marionette.wait_for_frames(count, Duration::from_secs(5));
            assert_eq!(frames.len(), count);
            frames[count - 1].clone()
        };
        // By name alone the blink arrives and the mouth, named otherwise, does not.
        performer.send(&[0.5, 1.0], None, 0.0);
        let frame = wait(&marionette, 1);
        assert_eq!(frame.weights, vec![0.0, 1.0]);
        // Through the map: the row the user set (or geometry found) opens the mouth.
        let mut map = faceanim_retarget::RetargetMap::by_name("vroid", &ours, &[]);
        map.set_row("jawOpen", [("Fcl_MTH_A".to_owned(), 0.8)].into())
            .unwrap();
        marionette.set_map(Some(Arc::new(map)));
        performer.send(&[0.6, 1.0], None, 1.0);
        let frame = wait(&marionette, 2);
        assert!(
            (frame.weights[0] - 0.48).abs() < 1e-5,
            "{:?}",
            frame.weights
        );
        assert!((frame.weights[1] - 1.0).abs() < 1e-5, "{:?}", frame.weights);
        // A map of other shapes is ignored.
        let other = faceanim_retarget::RetargetMap::by_name("x", &theirs[..1], &[]);
        marionette.set_map(Some(Arc::new(other)));
    }

    /// A VMC tracker sending ARKit's names ("perfect sync") gives its frames the eyes, the jaw
    /// and the ARKit values a phone's frames carry, whether the character has shapes of those
    /// names or none at all (a body moved by its bones); one sending VRM's presets gives them
    /// by the channels each preset stands for (`A` opens the jaw).
    #[test]
    fn a_vmc_sender_of_arkit_names_gives_eyes_jaw_and_arkit_values() {
        let theirs: Vec<String> = ["jawOpen", "eyeLookOutLeft", "eyeLookInRight", "A"]
            .map(String::from)
            .to_vec();
        let jaw = faceanim_retarget::channel_index("jawOpen").unwrap();
        for ours in [vec![], vec!["jawOpen".to_owned()]] {
            let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &ours).unwrap();
            let mut performer =
                Performer::new(marionette.address(), &theirs[..3], Names::Arkit).unwrap();
            performer.send(&[0.6, 0.5, 0.5], None, 0.0);
            let frames = marionette.wait_for_frames(1, Duration::from_secs(5));
            let frame = &frames[0];
            assert_eq!(frame.jaw(), Some(0.6), "{ours:?}");
            let arkit = frame.arkit.as_ref().expect("ARKit values");
            assert_eq!((arkit.len(), arkit[jaw]), (52, 0.6), "{ours:?}");
            // Both eyes look to the character's left, by half their range.
            let [left, right] = frame.eyes().expect("eyes");
            let half = faceanim_rig::bones::EYE_RANGE[0] / 2.0;
            assert_eq!((left[0], right[0]), (half, half), "{ours:?}");
            assert_eq!(frame.weights, vec![0.6; ours.len()]);
        }
        let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &[]).unwrap();
        let mut performer = Performer::new(marionette.address(), &theirs[3..], Names::Own).unwrap();
        performer.send(&[0.75], None, 0.0);
        let frames = marionette.wait_for_frames(1, Duration::from_secs(5));
        assert_eq!(frames[0].jaw(), Some(0.75));
    }

    /// What VSeeFace and VMagicMirror send without perfect sync, VRM's presets, drives any
    /// character: an ARKit-named one by the channels each preset stands for (`Blink` both lids,
    /// `Joy` both corners, `A` the jaw), a VRoid one by its own shapes (`A` its `Fcl_MTH_A`,
    /// `Blink` its lids), and a value the sender also names in ARKit wins.
    #[test]
    #[allow(clippy::float_cmp, reason = "values are copied through, not computed")]
    fn vrm_presets_from_a_sender_drive_any_character() {
        let presets: Vec<String> = ["A", "Blink", "Joy", "Blink_L"].map(String::from).to_vec();
        let sent = [0.5, 1.0, 0.25, 0.75];
        for (ours, want) in [
            (
                vec![
                    "jawOpen",
                    "eyeBlinkLeft",
                    "eyeBlinkRight",
                    "mouthSmile_L",
                    "mouthSmile_R",
                ],
                vec![0.5, 0.75, 1.0, 0.25, 0.25],
            ),
            (
                // Its both-lids shape gives way to the one-sided ones (nothing moves twice).
                vec![
                    "Fcl_MTH_A",
                    "Fcl_EYE_Close",
                    "Fcl_EYE_Close_L",
                    "Fcl_EYE_Close_R",
                    "Fcl_MTH_Joy",
                    "Fcl_MTH_O",
                ],
                vec![0.5, 0.0, 0.75, 1.0, 0.25, 0.0],
            ),
        ] {
            let ours: Vec<String> = ours.into_iter().map(String::from).collect();
            let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &ours).unwrap();
            let mut performer = Performer::new(marionette.address(), &presets, Names::Own).unwrap();
            performer.send(&sent, None, 0.0);
            let frame = marionette
                .wait_for_frames(1, Duration::from_secs(5))
                .remove(0);
            assert_eq!(frame.weights, want, "{ours:?}");
            let arkit = frame.arkit.expect("ARKit values");
            let at = |name: &str| arkit[faceanim_retarget::channel_index(name).unwrap()];
            // Blink_L names eyeBlinkLeft itself: it wins over Blink's.
            assert_eq!(
                [
                    at("jawOpen"),
                    at("eyeBlinkLeft"),
                    at("eyeBlinkRight"),
                    at("mouthSmileRight")
                ],
                [0.5, 0.75, 1.0, 0.25],
                "{ours:?}"
            );
        }
    }

    /// A vowel sent to a character with shapes that are it sets them as sent even through a
    /// map, and the map does not open the mouth again from the channels the vowel stands for;
    /// the other presets still reach their shapes through it.
    #[test]
    #[allow(clippy::float_cmp, reason = "values are copied through, not computed")]
    fn a_vowel_sets_the_shapes_that_are_it_even_through_a_map() {
        let ours: Vec<String> = ["Fcl_MTH_A", "Fcl_MTH_O", "Fcl_EYE_Close"]
            .map(String::from)
            .to_vec();
        let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &ours).unwrap();
        let mut map = faceanim_retarget::RetargetMap::by_name("vroid", &ours, &[]);
        map.set_row(
            "jawOpen",
            [("Fcl_MTH_A".to_owned(), 0.8), ("Fcl_MTH_O".to_owned(), 0.3)].into(),
        )
        .unwrap();
        marionette.set_map(Some(Arc::new(map)));
        let presets: Vec<String> = ["A", "Blink"].map(String::from).to_vec();
        let mut performer = Performer::new(marionette.address(), &presets, Names::Own).unwrap();
        performer.send(&[0.5, 1.0], None, 0.0);
        let frame = marionette
            .wait_for_frames(1, Duration::from_secs(5))
            .remove(0);
        assert_eq!(frame.weights[..2], [0.5, 0.0], "{:?}", frame.weights);
        assert!(frame.weights[2] > 0.99, "{:?}", frame.weights);
        // The frame's ARKit values still carry the vowel's channels (a body's jaw follows).
        assert_eq!(frame.jaw(), Some(0.5));
        // Named by the sender, the channel goes through the map again.
        let arkit: Vec<String> = ["jawOpen"].map(String::from).to_vec();
        let mut named = Performer::new(marionette.address(), &arkit, Names::Arkit).unwrap();
        named.send(&[1.0], None, 1.0);
        let frame = marionette
            .wait_for_frames(2, Duration::from_secs(5))
            .remove(1);
        assert_eq!(frame.weights[1], 0.3, "{:?}", frame.weights);
    }

    /// A marionette on loopback for a character with blendshapes `names`.
    fn listening_as(names: &[&str]) -> Marionette {
        let names: Vec<String> = names.iter().map(|&n| n.to_owned()).collect();
        Marionette::listen("127.0.0.1:0".parse().unwrap(), &names).unwrap()
    }

    /// The weights of the frame made of `sent` blendshape values arriving at `time`, then
    /// VMC's apply.
    fn blend_frame(state: &mut State, sent: &[(&str, f32)], time: f64) -> Vec<f32> {
        for &(name, value) in sent {
            let message = OscMessage {
                addr: "/VMC/Ext/Blend/Val".to_owned(),
                args: vec![OscType::String(name.to_owned()), OscType::Float(value)],
            };
            assert!(apply_message(state, &message, time));
        }
        let apply = OscMessage {
            addr: "/VMC/Ext/Blend/Apply".to_owned(),
            args: Vec::new(),
        };
        assert!(apply_message(state, &apply, time));
        state.history.back().unwrap().weights.clone()
    }

    /// VRM's whole-face presets on an ARKit head: `Surprised` the brows and eyes it is read
    /// from; `Fun` (faceanim's performer sends it from the cheeks) and VRM 1.0's name for it,
    /// `relaxed`, the cheeks. On a VRM avatar, each preset its own expression by either
    /// version's name. Before, `Fun` and `Surprised` reached nothing on either.
    #[test]
    #[allow(clippy::float_cmp, reason = "values are copied through, not computed")]
    fn whole_face_presets_set_the_channels_they_stand_for() {
        let ours = [
            "browInnerUp",
            "eyeWideLeft",
            "eyeWideRight",
            "cheekSquintLeft",
            "cheekSquintRight",
        ];
        let marionette = listening_as(&ours);
        {
            let mut state = lock(&marionette.state);
            let mut frame = |sent: &[(&str, f32)], time: f64| blend_frame(&mut state, sent, time);
            assert_eq!(frame(&[("Surprised", 0.5)], 0.0), [0.5, 0.5, 0.5, 0.0, 0.0]);
            assert_eq!(
                frame(&[("relaxed", 0.75)], 0.1),
                [0.5, 0.5, 0.5, 0.75, 0.75]
            );
            assert_eq!(
                frame(&[("Surprised", 0.0)], 0.2),
                [0.0, 0.0, 0.0, 0.75, 0.75]
            );
        }
        // A VRM avatar (its presets read under VRM 1.0's names) takes VRM 0.x's names, as
        // VSeeFace and VMagicMirror send them, as its own expressions: `Blink` its `blink`
        // alone (not also `blinkLeft` and `blinkRight`, which its channels drive).
        let vrm = listening_as(&[
            "relaxed",
            "happy",
            "surprised",
            "blink",
            "blinkLeft",
            "blinkRight",
        ]);
        {
            let mut state = lock(&vrm.state);
            let sent = [
                ("Fun", 0.25),
                ("Joy", 0.5),
                ("Surprised", 0.75),
                ("Blink", 1.0),
            ];
            assert_eq!(
                blend_frame(&mut state, &sent, 0.0),
                [0.25, 0.5, 0.75, 1.0, 0.0, 0.0]
            );
        }
        // What faceanim's performer sends as VRM's presets from the cheeks comes back to them.
        let ours = ours.map(String::from);
        let mut performer = Performer::new(marionette.address(), &ours, Names::VrmPresets).unwrap();
        performer.send(&[0.0, 0.0, 0.0, 0.25, 0.25], None, 1.0);
        let frames = marionette.wait_for_frames(4, Duration::from_secs(5));
        assert_eq!(frames[3].weights, [0.0, 0.0, 0.0, 0.25, 0.25]);
    }

    /// What reaches nothing on the character is counted, and its names listed once each where
    /// they moved: VSeeFace's whole-face `Fcl_ALL_Fun` on an ARKit head, a phone's JawOpen on a
    /// VRoid avatar with no map. A name at rest, one the character has, and an ARKit name a
    /// map carries are not; setting a map forgets the ARKit names it now carries.
    #[test]
    fn names_that_moved_and_reach_nothing_are_listed_once() {
        let sent = [
            ("EyeBlinkLeft", 1.0),
            ("Fcl_ALL_Fun", 0.5),
            ("Neutral", 0.0),
            ("JawOpen", 0.3),
            ("Extra", 0.01),
        ];
        let marionette = listening_as(&["eyeBlinkLeft", "Fcl_MTH_A"]);
        let mut state = lock(&marionette.state);
        for time in [0.0, 0.1] {
            blend_frame(&mut state, &sent, time);
        }
        assert_eq!(state.traffic.unmatched, 8);
        assert_eq!(state.traffic.unmatched_names, ["Fcl_ALL_Fun", "JawOpen"]);
        // A phone's channels the same way, by their ARKit names.
        let reading = |value: f32| crate::phone::Reading {
            channels: vec![(0, value), (17, value), (23, value)],
            head: None,
            eyes: None,
            time: None,
        };
        apply_reading(&mut state, reading(0.02), 0.2);
        assert_eq!(state.traffic.unmatched, 10);
        apply_reading(&mut state, reading(0.4), 0.3);
        assert_eq!(
            state.traffic.unmatched_names,
            ["Fcl_ALL_Fun", "JawOpen", "jawOpen", "mouthSmileLeft"]
        );
        // A map carries every ARKit name: only the name that means nothing is lost again.
        drop(state);
        let ours = ["eyeBlinkLeft", "Fcl_MTH_A"].map(String::from);
        marionette.set_map(Some(Arc::new(faceanim_retarget::RetargetMap::by_name(
            "vroid",
            &ours,
            &[],
        ))));
        let mut state = lock(&marionette.state);
        assert!(state.traffic.unmatched_names.is_empty());
        blend_frame(&mut state, &sent, 0.4);
        apply_reading(&mut state, reading(0.4), 0.5);
        assert_eq!(state.traffic.unmatched_names, ["Fcl_ALL_Fun"]);
    }

    /// A channel the sender named stays its own while it keeps naming it; once it has not for
    /// a while (a tracker switched from perfect sync to VRM's presets), a preset sets it again.
    #[test]
    #[allow(clippy::float_cmp, reason = "values are copied through, not computed")]
    fn a_channel_the_sender_stopped_naming_goes_back_to_the_presets() {
        let ours: Vec<String> = ["eyeBlinkLeft", "eyeBlinkRight"].map(String::from).to_vec();
        let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &ours).unwrap();
        let mut state = lock(&marionette.state);
        let mut frame = |sent: &[(&str, f32)], time: f64| blend_frame(&mut state, sent, time);
        assert_eq!(frame(&[("EyeBlinkLeft", 0.2)], 0.0), [0.2, 0.0]);
        assert_eq!(frame(&[("Blink", 1.0)], 1.0), [0.2, 1.0]);
        // Not named for longer than NAMED_FOR (3 s).
        assert_eq!(frame(&[("Blink", 0.8)], 4.5), [0.8, 0.8]);
    }

    /// A VMC sender's eye and jaw bones (as faceanim's performer and trackers sending VRM's
    /// presets send the gaze) give the frame's gaze, jaw and the eyeLook and jawOpen values it
    /// does not name; a named value wins over its bone.
    #[test]
    fn vmc_eye_and_jaw_bones_are_read_where_values_are_not_named() {
        let marionette = Marionette::listen("127.0.0.1:0".parse().unwrap(), &[]).unwrap();
        let theirs: Vec<String> = ["Blink"].map(String::from).to_vec();
        let mut performer = Performer::new(marionette.address(), &theirs, Names::Own).unwrap();
        let eyes = [[10.0, -5.0], [12.0, -5.0]];
        let pose = crate::Pose {
            head: None,
            eyes: Some(eyes),
            jaw: Some(0.4),
        };
        performer.send_pose(&[1.0], pose, 0.0);
        let frame = marionette
            .wait_for_frames(1, Duration::from_secs(5))
            .remove(0);
        let got = frame.eyes().expect("eyes");
        for (sent, got) in eyes.iter().flatten().zip(got.iter().flatten()) {
            assert!((sent - got).abs() < 1e-3, "{eyes:?} sent, {got:?} read");
        }
        assert!(
            (frame.jaw().unwrap() - 0.4).abs() < 1e-4,
            "{:?}",
            frame.jaw()
        );
        let arkit = frame.arkit.expect("ARKit values");
        let at = |name: &str| arkit[faceanim_retarget::channel_index(name).unwrap()];
        assert!((at("eyeLookOutLeft") - 10.0 / faceanim_rig::bones::EYE_RANGE[0]).abs() < 1e-4);
        assert!((at("jawOpen") - 0.4).abs() < 1e-4);
        // ARKit names and bones together (faceanim's performer sends both): the names win.
        let arkit_names: Vec<String> = ["jawOpen"].map(String::from).to_vec();
        let mut both = Performer::new(marionette.address(), &arkit_names, Names::Arkit).unwrap();
        let pose = crate::Pose {
            jaw: Some(1.0),
            ..pose
        };
        both.send_pose(&[0.25], pose, 1.0);
        let frame = marionette
            .wait_for_frames(2, Duration::from_secs(5))
            .remove(1);
        assert_eq!(frame.jaw(), Some(0.25));
    }
}
