//! Phone trackers' own protocols, end to end on loopback: a real Live Link Face recording
//! replayed as the app sent it, and iFacialMocap and VTube Studio phones written here from
//! their published grammars, each asked for frames as the real apps must be.
#![allow(clippy::unwrap_used, clippy::float_cmp, reason = "tests")]

use std::io::Read as _;
use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

use faceanim_live::phone::{Protocol, VTUBE_STUDIO_PORT};
use faceanim_live::{Marionette, Names, Performer, Source, SourceSettings};

const WAIT: Duration = Duration::from_secs(10);

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| (*s).to_owned()).collect()
}

/// A marionette on a free loopback port for `protocol`, asking `phone` when given.
fn listening(protocol: Protocol, phone: Option<SocketAddr>, character: &[String]) -> Marionette {
    let source = Source {
        protocol,
        phone,
        settings: SourceSettings::of(protocol),
    };
    Marionette::listen_to(&source, "127.0.0.1:0".parse().unwrap(), character).unwrap()
}

/// The datagrams of LLV's recording (see `data/llv/README.md`).
fn llv_recording() -> Vec<Vec<u8>> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/llv/dao.gesichter");
    let mut raw = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(path).unwrap())
        .read_to_end(&mut raw)
        .unwrap();
    assert_eq!(raw[0], 6);
    let count = u32::from_be_bytes(raw[1..5].try_into().unwrap()) as usize;
    let mut at = 5;
    let mut frames = Vec::new();
    for _ in 0..count {
        let size = u32::from_be_bytes(raw[at..at + 4].try_into().unwrap()) as usize;
        frames.push(raw[at + 4..at + 4 + size].to_vec());
        at += 4 + size;
    }
    assert_eq!(at, raw.len());
    frames
}

fn big_endian_floats(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_be_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// The phone's own time of a Live Link Face datagram, seconds: its frame number and sub-frame
/// at its rate, read here from the packet's layout (after the two length-prefixed names).
fn timecode(datagram: &[u8]) -> f64 {
    let mut at = 1;
    for _ in 0..2 {
        at += 4 + u32::from_be_bytes(datagram[at..at + 4].try_into().unwrap()) as usize;
    }
    let word = |k: usize| -> [u8; 4] { datagram[at + 4 * k..at + 4 * k + 4].try_into().unwrap() };
    let frame = f64::from(i32::from_be_bytes(word(0)));
    let sub_frame = f64::from(f32::from_be_bytes(word(1)));
    let rate = f64::from(i32::from_be_bytes(word(2))) / f64::from(i32::from_be_bytes(word(3)));
    (frame + sub_frame) / rate
}

/// The real recording delivered as Wi-Fi delivers it — paced by the phone's own timecode, but
/// in bunches of four — is recorded on the phone's clock: each frame's time is its timecode
/// (the recording's own gaps included), not when its bunch arrived.
#[test]
fn a_recording_goes_by_the_phones_own_timecode() {
    let recording = llv_recording();
    let sent: Vec<f64> = recording.iter().map(|d| timecode(d)).collect();
    // The app's 60 fps, with frames of its own skipped: steps of one frame and more.
    assert!(sent.windows(2).all(|w| w[1] - w[0] >= 1.0 / 60.0 - 1e-4));
    let marionette = listening(Protocol::LiveLinkFace, None, &names(&["jawOpen"]));
    marionette.start_recording();
    let phone = UdpSocket::bind("127.0.0.1:0").unwrap();
    let start = std::time::Instant::now();
    for (k, bunch) in recording.chunks(4).enumerate() {
        let last = (k * 4 + bunch.len() - 1).min(sent.len() - 1);
        let due = Duration::from_secs_f64(sent[last] - sent[0]);
        std::thread::sleep(due.saturating_sub(start.elapsed()));
        for datagram in bunch {
            phone.send_to(datagram, marionette.address()).unwrap();
            std::thread::sleep(Duration::from_micros(200));
        }
    }
    let arrived = marionette.wait_for_frames(180, WAIT);
    assert_eq!(arrived.len(), 180, "{:?}", marionette.traffic());
    // Arrivals in bunches: within a bunch, well under a frame apart.
    assert!(arrived[1].time - arrived[0].time < 0.01);
    let frames = marionette.stop_recording().unwrap();
    assert_eq!(frames.len(), 180, "{:?}", marionette.traffic());
    for (k, (frame, &time)) in frames.iter().zip(&sent).enumerate() {
        let (got, want) = (frame.time - frames[0].time, time - sent[0]);
        assert!(
            (got - want).abs() < 1e-6,
            "frame {k}: {got} s, the phone's {want} s"
        );
    }
}

#[test]
fn a_real_live_link_face_recording_drives_the_character_and_goes_out_over_vmc() {
    let recording = llv_recording();
    assert_eq!(recording.len(), 180);
    // A VRoid-like character: blinks and a mouth by their ARKit meaning, no ARKit names.
    let character = names(&["Fcl_EYE_Close_L", "Fcl_EYE_Close_R", "jawOpen", "Other"]);
    let marionette = listening(Protocol::LiveLinkFace, None, &character);
    // What arrives goes on over VMC, to a second listener standing in for a VTuber app.
    let app = Marionette::listen("127.0.0.1:0".parse().unwrap(), &character).unwrap();
    let performer = Performer::new(app.address(), &character, Names::Own).unwrap();
    marionette.forward_to(Some(std::sync::Arc::new(std::sync::Mutex::new(performer))));
    let phone = UdpSocket::bind("127.0.0.1:0").unwrap();
    for datagram in &recording {
        phone.send_to(datagram, marionette.address()).unwrap();
        // Not faster than the app: 60 fps would take 3 s; a few ms keeps order and loses none.
        std::thread::sleep(Duration::from_millis(2));
    }
    let frames = marionette.wait_for_frames(180, WAIT);
    assert_eq!(frames.len(), 180, "{:?}", marionette.traffic());
    // Each frame holds the recording's values: the left blink, the jaw and the head yaw (the
    // app's radians, in degrees).
    for (frame, datagram) in frames.iter().zip(&recording) {
        let values = big_endian_floats(&datagram[datagram.len() - 61 * 4..]);
        assert!((frame.weights[0] - values[0].clamp(0.0, 1.0)).abs() < 1e-6);
        assert!((frame.weights[2] - values[17].clamp(0.0, 1.0)).abs() < 1e-6);
        assert_eq!(frame.weights[3], 0.0);
        let [yaw, pitch, roll] = frame.head.unwrap();
        assert!((yaw - values[52].to_degrees()).abs() < 1e-3);
        assert!((pitch - values[53].to_degrees()).abs() < 1e-3);
        assert!((roll - values[54].to_degrees()).abs() < 1e-3);
    }
    let moving = frames.iter().map(|f| f.weights[0]).fold(0.0f32, f32::max);
    assert!(moving > 0.1, "the recording blinks: {moving}");
    // Every frame went on over VMC, timed.
    let out = app.wait_for_frames(180, WAIT);
    assert_eq!(out.len(), 180);
    let traffic = marionette.traffic();
    let forwarded = traffic.forwarded.clone().unwrap();
    assert_eq!(forwarded.frames, 180);
    assert!(forwarded.median_ms >= 0.0 && forwarded.p95_ms >= forwarded.median_ms);
    assert_eq!((traffic.malformed, traffic.foreign), (0, 0));

    // Neutral: the last face becomes the rest pose, kept in the settings returned.
    let settings = marionette.calibrate().unwrap();
    let neutral = settings.neutral.clone().unwrap();
    let last = big_endian_floats(&recording[179][recording[179].len() - 61 * 4..]);
    assert!((neutral.head[0] - last[52].to_degrees()).abs() < 1e-3);
    phone
        .send_to(&recording[179], marionette.address())
        .unwrap();
    let frame = marionette.wait_for_frames(181, WAIT).pop().unwrap();
    let [yaw, pitch, roll] = frame.head.unwrap();
    assert!(yaw.abs() < 1e-3 && pitch.abs() < 1e-3 && roll.abs() < 1e-3);
    assert!(frame.weights[0] < 1e-6, "the rest blink reads 0");
    let json = serde_json::to_string(&settings).unwrap();
    assert_eq!(
        serde_json::from_str::<SourceSettings>(&json).unwrap(),
        settings
    );

    // The header alone: the face is lost and the character returns to neutral.
    let header = &recording[0][..recording[0].len() - 261];
    phone.send_to(header, marionette.address()).unwrap();
    let frame = marionette.wait_for_frames(182, WAIT).pop().unwrap();
    assert!(frame.weights.iter().all(|w| *w == 0.0));
    assert_eq!(frame.head, Some([0.0; 3]));
    // MetaHuman Animator's packets, another version, noise, an OSC bundle: counted, dropped.
    let mut animator = recording[0].clone();
    animator.extend(vec![0u8; 200]);
    let mut version = recording[0].clone();
    version[0] = 5;
    for foreign in [animator, version, b"#bundle\0".to_vec(), vec![0xff; 9000]] {
        phone.send_to(&foreign, marionette.address()).unwrap();
    }
    let until = std::time::Instant::now() + WAIT;
    while marionette.traffic().packets < 186 && std::time::Instant::now() < until {
        std::thread::sleep(Duration::from_millis(5));
    }
    let traffic = marionette.traffic();
    assert_eq!(traffic.packets, 186);
    assert_eq!(traffic.faces_lost, 1);
    assert_eq!(traffic.foreign + traffic.malformed, 4, "{traffic:?}");
    assert_eq!(traffic.frames, 182);
}

/// A phone written from the app's published grammar: it waits for a request, then sends
/// `frames` to whoever asked (to the ports the request names, for VTube Studio).
fn phone_that_answers(
    protocol: Protocol,
    frames: Vec<String>,
) -> (SocketAddr, std::thread::JoinHandle<String>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.set_read_timeout(Some(WAIT)).unwrap();
    let address = socket.local_addr().unwrap();
    let thread = std::thread::spawn(move || {
        let mut buffer = [0u8; 2048];
        let (length, asker) = socket.recv_from(&mut buffer).unwrap();
        let request = String::from_utf8_lossy(&buffer[..length]).into_owned();
        let to = match protocol {
            Protocol::VTubeStudio => {
                let json: serde_json::Value = serde_json::from_str(&request).unwrap();
                assert_eq!(json["messageType"], "iOSTrackingDataRequest");
                let port = json["ports"][0].as_u64().unwrap() as u16;
                SocketAddr::new(asker.ip(), port)
            }
            _ => asker,
        };
        for frame in frames {
            socket.send_to(frame.as_bytes(), to).unwrap();
            std::thread::sleep(Duration::from_millis(2));
        }
        request
    });
    (address, thread)
}

#[test]
fn ifacialmocap_and_vtube_studio_phones_are_asked_and_read() {
    let character = names(&["eyeBlink_L", "jawOpen", "mouthSmile_R"]);
    // iFacialMocap: the handshake asks for its second text version (`&`).
    let frames = vec![
        "eyeBlink_L&100|jawOpen&50|=head#-10,20,5,0,0,0|rightEye#1,2,3|leftEye#1,2,3|".into(),
        "jawOpen&30|=head#0,10,0,0,0,0|".into(),
        "garbage".into(),
    ];
    let (phone, answered) = phone_that_answers(Protocol::IFacialMocap, frames);
    let marionette = listening(Protocol::IFacialMocap, Some(phone), &character);
    let request = answered.join().unwrap();
    assert!(request.starts_with("iFacialMocap_"), "{request}");
    assert!(request.ends_with("sendDataVersion=v2"), "{request}");
    let frames = marionette.wait_for_frames(2, WAIT);
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[0].weights, vec![1.0, 0.5, 0.0]);
    assert_eq!(frames[0].head, Some([20.0, -10.0, 5.0]));
    // The blink was not sent again: it keeps its value (a missing key is no data).
    assert_eq!(frames[1].weights, vec![1.0, 0.3, 0.0]);
    let until = std::time::Instant::now() + WAIT;
    while marionette.traffic().packets < 3 && std::time::Instant::now() < until {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(marionette.traffic().foreign, 1);

    // VTube Studio: the request names this side's port; a lost face is neutral.
    let frames = vec![
        r#"{"FaceFound":true,"Rotation":{"x":1,"y":2,"z":3},"BlendShapes":[{"k":"MouthSmileRight","v":0.7}]}"#.into(),
        r#"{"FaceFound":false,"BlendShapes":[]}"#.into(),
    ];
    let (phone, answered) = phone_that_answers(Protocol::VTubeStudio, frames);
    let marionette = listening(Protocol::VTubeStudio, Some(phone), &character);
    let request = answered.join().unwrap();
    assert!(request.contains(&format!("\"ports\":[{}]", marionette.address().port())));
    let frames = marionette.wait_for_frames(2, WAIT);
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[0].weights, vec![0.0, 0.0, 0.7]);
    assert_eq!(frames[0].head, Some([2.0, 1.0, 3.0]));
    assert_eq!(frames[1].weights, vec![0.0, 0.0, 0.0]);
    assert_eq!(marionette.traffic().faces_lost, 1);
    assert_eq!(Protocol::VTubeStudio.default_port(), VTUBE_STUDIO_PORT);
}

/// The gaze faceanim turns eyes by from ARKit's `eyeLook*` values (`EYE_RANGE` degrees at 1) is
/// the gaze the phone itself reports: in the real recording, Live Link Face's own eye angles
/// are its eyeLook values times one range, sideways and up or down alike, so the eyeLook values
/// (which every app sends) carry the phones' eye angles, and faceanim's range is theirs.
#[test]
fn the_phones_own_eye_angles_are_its_eye_look_values_at_faceanims_gaze_range() {
    use faceanim_live::phone::{AngleUnit, Packet, decode};
    // Per eye and axis: faceanim's gaze from the eyeLook values, and the phone's own angle.
    let mut pairs = vec![Vec::new(); 4];
    let radians = AngleUnit::Radians;
    for datagram in llv_recording() {
        let decoded = decode(Protocol::LiveLinkFace, &datagram, radians, radians);
        let Ok(Packet::Face(reading)) = decoded else {
            continue;
        };
        let value = |channel: &str| {
            reading
                .channels
                .iter()
                .find(|(i, _)| faceanim_rig::names::ARKIT_52[*i] == channel)
                .map_or(0.0, |(_, v)| *v)
        };
        let ours = faceanim_rig::bones::gaze_from_arkit(value);
        let theirs = reading.eyes.unwrap();
        for eye in 0..2 {
            for axis in 0..2 {
                // The app turns yaw towards the character's right and pitch down: the other way.
                pairs[eye * 2 + axis]
                    .push((f64::from(ours[eye][axis]), -f64::from(theirs[eye][axis])));
            }
        }
    }
    for (k, pairs) in pairs.iter().enumerate() {
        let n = pairs.len() as f64;
        let (mx, my) = (
            pairs.iter().map(|p| p.0).sum::<f64>() / n,
            pairs.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxx: f64 = pairs.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pairs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let slope = sxy / sxx;
        // The eyes move (over 10° in the recording), one degree of ours is one of theirs, and
        // past a constant (the eyes' slight convergence) nothing is left over.
        let spread = (sxx / n).sqrt();
        let residual = (pairs
            .iter()
            .map(|p| (p.1 - my - slope * (p.0 - mx)).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let which = ["left yaw", "left pitch", "right yaw", "right pitch"][k];
        assert!(spread > 2.0, "{which}: the eyes hardly move ({spread:.2}°)");
        assert!(
            (0.95..=1.05).contains(&slope),
            "{which}: {slope:.3} of the phone's degrees per one of ours"
        );
        assert!(residual < 0.5, "{which}: {residual:.2}° left over");
    }
}
