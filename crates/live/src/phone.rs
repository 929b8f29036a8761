//! Phone face trackers' own protocols: what one datagram of Live Link Face, iFacialMocap (and
//! the apps that speak it: MeowFace, Facemotion3d) or VTube Studio's phone app says.
//!
//! Each decoder reads one datagram into a [`Packet`] — a face's ARKit values with the head and
//! eye angles that came with it, a lost face, or nothing of interest — or refuses it with the
//! reason ([`Refused`]), which the listener counts. Values are clamped to 0..1 and angles
//! converted to degrees with the source's [`AngleUnit`]s; a key the sender left out is *no
//! data* (the channel keeps its last value), never a zero.

use faceanim_rig::names::ARKIT_52;

/// The apps a [`crate::Marionette`] listens to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Protocol {
    /// The VMC protocol (OSC): VSeeFace, Waidayo, iFacialMocap's Windows edition, another
    /// faceanim.
    Vmc,
    /// Epic's Live Link Face in ARKit mode: version 6 binary packets to port 11111.
    LiveLinkFace,
    /// iFacialMocap's text frames (also MeowFace, Facemotion3d), port 49983, after a handshake
    /// sent to the phone.
    IFacialMocap,
    /// VTube Studio's phone app: JSON frames, asked for every second at the phone's port 21412.
    VTubeStudio,
}

impl Protocol {
    /// Every protocol, in the order the docs list them.
    pub const ALL: [Protocol; 4] = [
        Protocol::Vmc,
        Protocol::LiveLinkFace,
        Protocol::IFacialMocap,
        Protocol::VTubeStudio,
    ];

    /// The port this side listens on unless told otherwise (each app's own default).
    #[must_use]
    pub const fn default_port(self) -> u16 {
        match self {
            Protocol::Vmc => crate::DEFAULT_PORT,
            Protocol::LiveLinkFace => 11111,
            Protocol::IFacialMocap => 49983,
            Protocol::VTubeStudio => VTUBE_STUDIO_PORT,
        }
    }

    /// The app's name, as its users know it.
    #[must_use]
    pub const fn label(self) -> &'static str {
        match self {
            Protocol::Vmc => "VMC",
            Protocol::LiveLinkFace => "Live Link Face",
            Protocol::IFacialMocap => "iFacialMocap",
            Protocol::VTubeStudio => "VTube Studio",
        }
    }

    /// The units its head and eye angles come in unless the user says otherwise: Live Link
    /// Face sends radians (a real recording's head turns stay within ±0.45), the text and JSON
    /// protocols degrees.
    #[must_use]
    pub const fn default_units(self) -> AngleUnit {
        match self {
            Protocol::LiveLinkFace => AngleUnit::Radians,
            _ => AngleUnit::Degrees,
        }
    }

    /// Whether the phone must be asked to send (iFacialMocap's handshake, VTube Studio's
    /// request): then the listener needs the phone's address.
    #[must_use]
    pub const fn asks_the_phone(self) -> bool {
        matches!(self, Protocol::IFacialMocap | Protocol::VTubeStudio)
    }
}

/// The port VTube Studio's phone app takes requests on.
pub const VTUBE_STUDIO_PORT: u16 = 21412;

/// What iFacialMocap's app waits for before it sends (with the request for its second text
/// version, which separates names from values with `&`).
pub const IFACIALMOCAP_HANDSHAKE: &str =
    "iFacialMocap_sahuasouryya9218sauhuiayeta91555dy3719|sendDataVersion=v2";

/// VTube Studio's request for `seconds` more of tracking data, sent to `port` on this side.
#[must_use]
pub fn vtube_studio_request(port: u16, seconds: f32) -> String {
    format!(
        r#"{{"messageType":"iOSTrackingDataRequest","time":{seconds},"sentBy":"faceanim","ports":[{port}]}}"#
    )
}

/// How a source's angles are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AngleUnit {
    /// Degrees.
    Degrees,
    /// Radians.
    Radians,
}

impl AngleUnit {
    fn degrees(self, value: f32) -> f32 {
        match self {
            AngleUnit::Degrees => value,
            AngleUnit::Radians => value.to_degrees(),
        }
    }
}

/// One face as a phone saw it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Reading {
    /// ARKit channels sent (index into `ARKIT_52`, value 0..1); channels left out are absent.
    pub channels: Vec<(usize, f32)>,
    /// Head yaw, pitch, roll in degrees, when sent.
    pub head: Option<[f32; 3]>,
    /// Each eye's yaw and pitch in degrees (left, right), when sent.
    pub eyes: Option<[[f32; 2]; 2]>,
    /// When the phone says it took the frame, seconds on its own clock, when it says (Live
    /// Link Face's frame and sub-frame at its rate, VTube Studio's timestamp); a take prefers
    /// it to the arrival time, which the network shifts.
    pub time: Option<f64>,
}

/// What one datagram said.
#[derive(Debug, Clone, PartialEq)]
pub enum Packet {
    /// A face.
    Face(Reading),
    /// The tracker lost the face: the character goes back to neutral.
    FaceLost,
}

/// Why a datagram was dropped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Refused {
    /// Another packet of the same app (Live Link Face's MetaHuman Animator mode, another
    /// version) or another protocol altogether.
    #[error("not a {protocol} frame: {why}")]
    Foreign {
        /// The protocol listened for.
        protocol: &'static str,
        /// What gave it away.
        why: String,
    },
    /// A frame of the protocol, but cut short or with a field that cannot be read.
    #[error("a malformed {protocol} frame: {why}")]
    Malformed {
        /// The protocol listened for.
        protocol: &'static str,
        /// The field.
        why: String,
    },
}

/// Reads one datagram of `protocol` (not [`Protocol::Vmc`], which the listener reads as OSC),
/// its head angles in `head` units and its eye angles in `eyes` units.
///
/// # Errors
/// [`Refused`] naming what is wrong.
pub fn decode(
    protocol: Protocol,
    datagram: &[u8],
    head: AngleUnit,
    eyes: AngleUnit,
) -> Result<Packet, Refused> {
    match protocol {
        Protocol::LiveLinkFace => live_link_face(datagram, head, eyes),
        Protocol::IFacialMocap => ifacialmocap(datagram, head, eyes),
        Protocol::VTubeStudio => vtube_studio(datagram, head, eyes),
        Protocol::Vmc => Err(Refused::Foreign {
            protocol: "VMC",
            why: "VMC is read as OSC by the listener".into(),
        }),
    }
}

/// Live Link Face's values after the header: 52 shapes, head yaw/pitch/roll, left and right
/// eye yaw/pitch/roll.
const LIVE_LINK_VALUES: usize = 61;
/// Frame number, sub-frame, rate numerator and denominator, then the value count.
const LIVE_LINK_TIME: usize = 4 + 4 + 4 + 4 + 1;
/// The longest device id or subject name read.
const LIVE_LINK_NAME: usize = 1024;

/// Live Link Face, ARKit mode: big-endian; version (u8, 6), device id and subject name (each
/// an i32 length and UTF-8), frame (i32), sub-frame (f32), rate (i32/i32), count (u8, 61) and
/// 61 f32. A header alone means the face is lost.
fn live_link_face(bytes: &[u8], head: AngleUnit, eyes: AngleUnit) -> Result<Packet, Refused> {
    const NAME: &str = "Live Link Face";
    let foreign = |why: String| Refused::Foreign {
        protocol: NAME,
        why,
    };
    let malformed = |why: &str| Refused::Malformed {
        protocol: NAME,
        why: why.to_owned(),
    };
    let version = *bytes
        .first()
        .ok_or_else(|| foreign("an empty datagram".into()))?;
    if version != 6 {
        return Err(foreign(format!("version {version}, not 6")));
    }
    let mut at = 1;
    for field in ["device id", "subject name"] {
        let length = bytes
            .get(at..at + 4)
            .map(|b| i32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| malformed(&format!("cut short before its {field}")))?;
        let length = usize::try_from(length)
            .ok()
            .filter(|&l| l <= LIVE_LINK_NAME)
            .ok_or_else(|| foreign(format!("a {field} of {length} bytes")))?;
        let text = bytes
            .get(at + 4..at + 4 + length)
            .ok_or_else(|| malformed(&format!("cut short in its {field}")))?;
        std::str::from_utf8(text).map_err(|_| malformed(&format!("its {field} is not UTF-8")))?;
        at += 4 + length;
    }
    let rest = &bytes[at..];
    if rest.is_empty() {
        return Ok(Packet::FaceLost);
    }
    let expected = LIVE_LINK_TIME + 4 * LIVE_LINK_VALUES;
    if rest.len() != expected {
        return Err(foreign(format!(
            "{} bytes after the names, not {expected}",
            rest.len()
        )));
    }
    let count = rest[LIVE_LINK_TIME - 1];
    if usize::from(count) != LIVE_LINK_VALUES {
        return Err(foreign(format!("{count} values, not {LIVE_LINK_VALUES}")));
    }
    let values: Vec<f32> = rest[LIVE_LINK_TIME..]
        .chunks_exact(4)
        .map(|b| f32::from_be_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if values.iter().any(|v| !v.is_finite()) {
        return Err(malformed("a value that is not a finite number"));
    }
    let channels = values[..52]
        .iter()
        .enumerate()
        .map(|(i, v)| (i, v.clamp(0.0, 1.0)))
        .collect();
    let angle = |unit: AngleUnit, i: usize| unit.degrees(values[i]);
    let word = |at: usize| [rest[at], rest[at + 1], rest[at + 2], rest[at + 3]];
    let frame = f64::from(i32::from_be_bytes(word(0)));
    let sub_frame = f64::from(f32::from_be_bytes(word(4)));
    let rate = (
        f64::from(i32::from_be_bytes(word(8))),
        f64::from(i32::from_be_bytes(word(12))),
    );
    // Frame (and the fraction of one) at numerator/denominator frames per second.
    let time = (rate.0 > 0.0 && rate.1 > 0.0 && (0.0..1.0).contains(&sub_frame))
        .then(|| (frame + sub_frame) * rate.1 / rate.0);
    Ok(Packet::Face(Reading {
        channels,
        time,
        head: Some([angle(head, 52), angle(head, 53), angle(head, 54)]),
        eyes: Some([
            [angle(eyes, 55), angle(eyes, 56)],
            [angle(eyes, 58), angle(eyes, 59)],
        ]),
    }))
}

/// iFacialMocap: `name-value|…|=head#rx,ry,rz,px,py,pz|rightEye#x,y,z|leftEye#x,y,z|`, values
/// 0..100, ARKit names with `_L`/`_R`, `&` for `-` in its second version; blocks are found by
/// name and may come in any order or not at all.
fn ifacialmocap(bytes: &[u8], head: AngleUnit, eyes: AngleUnit) -> Result<Packet, Refused> {
    const NAME: &str = "iFacialMocap";
    let text = std::str::from_utf8(bytes).map_err(|_| Refused::Foreign {
        protocol: NAME,
        why: "not text".into(),
    })?;
    let malformed = |why: String| Refused::Malformed {
        protocol: NAME,
        why,
    };
    let (shapes, blocks) = text.split_once('=').unwrap_or((text, ""));
    let mut reading = Reading::default();
    for item in shapes.split('|').map(str::trim).filter(|s| !s.is_empty()) {
        // The last separator: names never hold one, values never do in either version.
        let Some((name, value)) = item.rsplit_once(['&', '-']) else {
            return Err(Refused::Foreign {
                protocol: NAME,
                why: format!("'{}' is not name-value", faceanim_rig::excerpt(item)),
            });
        };
        let value: f32 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f32| v.is_finite())
            .ok_or_else(|| malformed(format!("{name}: '{}'", faceanim_rig::excerpt(value))))?;
        if let Some(channel) = channel_of(name) {
            reading
                .channels
                .push((channel, (value / 100.0).clamp(0.0, 1.0)));
        }
    }
    let mut eye = [None, None];
    for block in blocks.split('|').map(str::trim).filter(|s| !s.is_empty()) {
        let Some((name, numbers)) = block.split_once('#') else {
            return Err(malformed(format!(
                "'{}' is not name#numbers",
                faceanim_rig::excerpt(block)
            )));
        };
        let numbers: Option<Vec<f32>> = numbers
            .split(',')
            .map(|n| n.trim().parse().ok().filter(|v: &f32| v.is_finite()))
            .collect();
        let numbers = numbers.ok_or_else(|| malformed(format!("{name}: not numbers")))?;
        let need = |n: usize| {
            if numbers.len() >= n {
                Ok(())
            } else {
                Err(malformed(format!(
                    "{name}: {} numbers, not {n}",
                    numbers.len()
                )))
            }
        };
        match name {
            // rx nods (pitch), ry turns (yaw), rz tilts (roll).
            "head" => {
                need(3)?;
                reading.head = Some([
                    head.degrees(numbers[1]),
                    head.degrees(numbers[0]),
                    head.degrees(numbers[2]),
                ]);
            }
            "leftEye" | "rightEye" => {
                need(2)?;
                let side = usize::from(name == "rightEye");
                eye[side] = Some([eyes.degrees(numbers[1]), eyes.degrees(numbers[0])]);
            }
            _ => {}
        }
    }
    if let [Some(left), Some(right)] = eye {
        reading.eyes = Some([left, right]);
    }
    if reading.channels.is_empty() && reading.head.is_none() {
        return Err(Refused::Foreign {
            protocol: NAME,
            why: "no blendshape and no head".into(),
        });
    }
    Ok(Packet::Face(reading))
}

/// VTube Studio's phone frames: `{"Timestamp": ms, "FaceFound": bool, "Rotation": {x,y,z},
/// "Position": …, "EyeLeft": {x,y,z}, "EyeRight": …, "BlendShapes": [{"k": name, "v": value},
/// …]}`.
fn vtube_studio(bytes: &[u8], head: AngleUnit, eyes: AngleUnit) -> Result<Packet, Refused> {
    const NAME: &str = "VTube Studio";
    #[derive(serde::Deserialize)]
    struct Xyz {
        x: f32,
        y: f32,
        z: f32,
    }
    #[derive(serde::Deserialize)]
    struct Shape {
        k: String,
        v: f32,
    }
    #[derive(serde::Deserialize)]
    #[serde(rename_all = "PascalCase")]
    struct Frame {
        face_found: bool,
        rotation: Option<Xyz>,
        eye_left: Option<Xyz>,
        eye_right: Option<Xyz>,
        #[serde(default)]
        blend_shapes: Vec<Shape>,
        /// Milliseconds on the phone's clock.
        timestamp: Option<f64>,
    }
    let frame: Frame = serde_json::from_slice(bytes).map_err(|e| {
        if e.is_syntax() || e.is_eof() {
            Refused::Foreign {
                protocol: NAME,
                why: "not JSON".into(),
            }
        } else {
            Refused::Malformed {
                protocol: NAME,
                why: e.to_string(),
            }
        }
    })?;
    if !frame.face_found {
        return Ok(Packet::FaceLost);
    }
    let finite = |v: &Xyz| [v.x, v.y, v.z].iter().all(|a| a.is_finite());
    let mut reading = Reading {
        time: frame
            .timestamp
            .filter(|t| t.is_finite())
            .map(|t| t / 1000.0),
        ..Reading::default()
    };
    for shape in &frame.blend_shapes {
        if let Some(channel) = channel_of(&shape.k)
            && shape.v.is_finite()
        {
            reading.channels.push((channel, shape.v.clamp(0.0, 1.0)));
        }
    }
    // x nods (pitch), y turns (yaw), z tilts (roll).
    reading.head = frame
        .rotation
        .filter(finite)
        .map(|r| [head.degrees(r.y), head.degrees(r.x), head.degrees(r.z)]);
    if let (Some(l), Some(r)) = (
        frame.eye_left.filter(finite),
        frame.eye_right.filter(finite),
    ) {
        reading.eyes = Some([
            [eyes.degrees(l.y), eyes.degrees(l.x)],
            [eyes.degrees(r.y), eyes.degrees(r.x)],
        ]);
    }
    Ok(Packet::Face(reading))
}

/// The ARKit channel a phone's name spells (`eyeBlink_L`, `EyeBlinkLeft`, `jawOpen`).
fn channel_of(name: &str) -> Option<usize> {
    let arkit = faceanim_rig::names::arkit_name(name)?;
    ARKIT_52.iter().position(|n| *n == arkit)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `datagram` read in degrees.
    fn read(protocol: Protocol, datagram: &[u8]) -> Result<Packet, Refused> {
        decode(protocol, datagram, AngleUnit::Degrees, AngleUnit::Degrees)
    }

    /// `datagram` read as a face, in degrees.
    fn face(protocol: Protocol, datagram: &[u8]) -> Reading {
        match read(protocol, datagram) {
            Ok(Packet::Face(reading)) => reading,
            other => panic!("not a face: {other:?}"),
        }
    }

    /// A Live Link Face packet as the grammar says, written here field by field.
    fn live_link(device: &str, values: Option<&[f32; 61]>) -> Vec<u8> {
        let mut bytes = vec![6u8];
        for text in [device, "iPhone"] {
            bytes.extend(i32::try_from(text.len()).unwrap().to_be_bytes());
            bytes.extend(text.as_bytes());
        }
        if let Some(values) = values {
            bytes.extend(1234i32.to_be_bytes());
            bytes.extend(0.5f32.to_be_bytes());
            bytes.extend(60i32.to_be_bytes());
            bytes.extend(1i32.to_be_bytes());
            bytes.push(61);
            for v in values {
                bytes.extend(v.to_be_bytes());
            }
        }
        bytes
    }

    #[test]
    fn live_link_face_frames_lost_faces_and_other_packets() {
        let mut values = [0.0f32; 61];
        values[17] = 0.5; // jawOpen
        values[0] = 1.5; // eyeBlinkLeft, clamped
        values[52] = 0.1; // head yaw
        values[56] = -0.2; // left eye pitch
        let packet = live_link("0123456789abcdef0123456789abcdef0123", Some(&values));
        let Ok(Packet::Face(reading)) = decode(
            Protocol::LiveLinkFace,
            &packet,
            AngleUnit::Radians,
            AngleUnit::Degrees,
        ) else {
            panic!("not a face");
        };
        assert_eq!(reading.channels.len(), 52);
        assert_eq!(reading.channels[17], (17, 0.5));
        assert_eq!(reading.channels[0], (0, 1.0));
        let [yaw, _, _] = reading.head.unwrap();
        assert!((yaw - 0.1f32.to_degrees()).abs() < 1e-4);
        assert!((reading.eyes.unwrap()[0][1] + 0.2).abs() < 1e-6);
        // Frame 1234 and a half at 60 fps.
        assert!((reading.time.unwrap() - 1234.5 / 60.0).abs() < 1e-9);
        // The header alone: the face is lost.
        let lost = live_link("0123456789abcdef0123456789abcdef0123", None);
        assert_eq!(
            decode(
                Protocol::LiveLinkFace,
                &lost,
                AngleUnit::Radians,
                AngleUnit::Radians
            ),
            Ok(Packet::FaceLost)
        );
        // Another version, another count, another size, a cut: counted, never a panic.
        let mut other = packet.clone();
        other[0] = 7;
        let mut count = packet.clone();
        let at = packet.len() - 61 * 4 - 1;
        count[at] = 62;
        let mut longer = packet.clone();
        longer.extend([0u8; 40]);
        for bad in [
            other,
            count,
            longer,
            packet[..packet.len() - 3].to_vec(),
            vec![],
        ] {
            let refused = decode(
                Protocol::LiveLinkFace,
                &bad,
                AngleUnit::Radians,
                AngleUnit::Radians,
            );
            assert!(refused.is_err(), "{refused:?}");
        }
        for cut in 0..packet.len() {
            let _ = decode(
                Protocol::LiveLinkFace,
                &packet[..cut],
                AngleUnit::Radians,
                AngleUnit::Radians,
            );
        }
    }

    #[test]
    fn ifacialmocap_text_in_both_versions_with_blocks_found_by_name() {
        let v1 = "mouthSmile_R-40|eyeBlink_L-100|jawOpen-25|hapihapi-3|=head#-10.5,20.0,5.0,0.1,0.2,0.3|rightEye#6.0,2.0,0.5|leftEye#6.5,-5.0,0.4|";
        let r = face(Protocol::IFacialMocap, v1.as_bytes());
        let channel = |name: &str| ARKIT_52.iter().position(|n| *n == name).unwrap();
        assert!(r.channels.contains(&(channel("mouthSmileRight"), 0.4)));
        assert!(r.channels.contains(&(channel("eyeBlinkLeft"), 1.0)));
        assert!(r.channels.contains(&(channel("jawOpen"), 0.25)));
        assert_eq!(r.channels.len(), 3, "an unknown name is skipped");
        assert_eq!(r.head, Some([20.0, -10.5, 5.0]));
        assert_eq!(r.eyes, Some([[-5.0, 6.5], [2.0, 6.0]]));
        // Version 2 (`&`), blocks in another order, the eyes left out: no eye data, not zero.
        let v2 = "jawOpen&60|=rightEye#1,2,3|head#1,2,3,0,0,0|";
        let r = face(Protocol::IFacialMocap, v2.as_bytes());
        assert_eq!(r.channels, vec![(channel("jawOpen"), 0.6)]);
        assert_eq!(r.head, Some([2.0, 1.0, 3.0]));
        assert_eq!(r.eyes, None);
        for bad in [
            "",
            "hello",
            "jawOpen-x|",
            "=head#1,a,3|",
            "=head#1|",
            "\u{0}\u{ff}",
        ] {
            assert!(
                read(Protocol::IFacialMocap, bad.as_bytes()).is_err(),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn vtube_studio_json_frames() {
        let frame = br#"{"Timestamp":1764990000123,"Hotkey":-1,"FaceFound":true,"Rotation":{"x":-5,"y":12,"z":3},"Position":{"x":0,"y":0,"z":0},"EyeLeft":{"x":4,"y":-2,"z":0},"EyeRight":{"x":4,"y":-3,"z":0},"BlendShapes":[{"k":"JawOpen","v":0.3},{"k":"EyeBlinkRight","v":0.9},{"k":"Nonsense","v":1}]}"#;
        let r = face(Protocol::VTubeStudio, frame);
        assert_eq!(r.channels.len(), 2);
        assert_eq!(r.head, Some([12.0, -5.0, 3.0]));
        assert_eq!(r.eyes, Some([[-2.0, 4.0], [-3.0, 4.0]]));
        assert!((r.time.unwrap() - 1_764_990_000.123).abs() < 1e-6);
        let lost = br#"{"FaceFound":false,"BlendShapes":[]}"#;
        assert_eq!(
            decode(
                Protocol::VTubeStudio,
                lost,
                AngleUnit::Degrees,
                AngleUnit::Degrees
            ),
            Ok(Packet::FaceLost)
        );
        for bad in [&b"{"[..], b"[1,2]", b"{\"FaceFound\":\"yes\"}", b"\x06\x00"] {
            assert!(
                decode(
                    Protocol::VTubeStudio,
                    bad,
                    AngleUnit::Degrees,
                    AngleUnit::Degrees
                )
                .is_err()
            );
        }
        assert!(vtube_studio_request(21412, 1.5).contains("\"ports\":[21412]"));
    }
}
