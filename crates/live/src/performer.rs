//! The performer: the character's face out to a VMC marionette.

use std::net::{SocketAddr, UdpSocket};

use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

use crate::names::{Names, Source};
use crate::{LiveError, unity_rotation};

/// What a frame sends besides the blendshapes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// The head pose `[yaw, pitch, roll]` in degrees (faceanim's convention), sent as `Neck`
    /// and `Head`.
    pub head: Option<[f32; 3]>,
    /// Each eye's gaze `[yaw, pitch]` in degrees, left eye then right, relative to the head
    /// (yaw towards the character's left, pitch up), sent as `LeftEye` and `RightEye`.
    pub eyes: Option<[[f32; 2]; 2]>,
    /// How open the jaw is (ARKit `jawOpen`, 0..1), sent as the `Jaw` bone turned down by
    /// [`JAW_DEGREES`] at 1 — for avatars whose mouth opens with a jaw bone.
    pub jaw: Option<f32>,
}

/// How far the `Jaw` bone turns at `jawOpen` 1 (the receiving avatar is not known here: the
/// exporter's default for a jaw without a jaw-open shape to measure).
pub const JAW_DEGREES: f32 = 20.0;

/// Every this many frames all values are sent, moved or not, so a marionette that starts late
/// or lost a datagram catches up.
const REFRESH_EVERY: u64 = 30;
/// Values closer than this to the last one sent have not moved.
const MOVED: f32 = 1e-6;

/// How sending went so far.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SendStats {
    /// Frames given to [`Performer::send`].
    pub frames: u64,
    /// Datagrams the socket took.
    pub sent: u64,
    /// Datagrams the network refused (nobody listening, unreachable), dropped.
    pub dropped: u64,
    /// The last refusal's reason.
    pub last_error: Option<String>,
}

/// Sends frames of a character's face to one marionette (see the crate docs).
#[derive(Debug)]
pub struct Performer {
    socket: UdpSocket,
    destination: SocketAddr,
    table: Vec<(String, Source)>,
    last: Vec<Option<f32>>,
    /// Under ARKit names or VRM presets, the values the character's shapes cannot make, made
    /// from a frame's ARKit values where it has them ([`Performer::with_arkit`]).
    from_arkit: Vec<(String, Source)>,
    last_from_arkit: Vec<Option<f32>>,
    stats: SendStats,
}

impl Performer {
    /// A performer sending the face of a character whose blendshapes are `blendshapes` (the
    /// weights given to [`Performer::send`] follow their order) under `names` to
    /// `destination`. A character with no blendshapes at all (a body moved by its bones) sends
    /// its head, gaze and jaw as bones alone.
    ///
    /// # Errors
    /// [`LiveError::Socket`] when no UDP socket can be opened, [`LiveError::NoNames`] when the
    /// character has blendshapes but none of the names asked for.
    pub fn new(
        destination: SocketAddr,
        blendshapes: &[String],
        names: Names,
    ) -> Result<Performer, LiveError> {
        if !blendshapes.is_empty() && names.table(blendshapes).is_empty() {
            return Err(LiveError::NoNames {
                what: names.describe(),
            });
        }
        let mut performer = Performer::with_arkit(destination, blendshapes, names)?;
        performer.from_arkit.clear();
        performer.last_from_arkit.clear();
        Ok(performer)
    }

    /// A performer for faces whose ARKit values are known too (a webcam's, a phone's, a
    /// spoken line's: [`Performer::send_with_arkit`]), for any character: under ARKit names
    /// or VRM presets, what the character's own shapes make goes out as [`Performer::new`]
    /// sends it, and the channels (or presets) they cannot make go out from the ARKit values,
    /// so that a rig whose names say nothing still drives a perfect-sync avatar. Frames sent
    /// without ARKit values (a sketch) send what the shapes make alone.
    ///
    /// # Errors
    /// [`LiveError::Socket`] when no UDP socket can be opened.
    pub fn with_arkit(
        destination: SocketAddr,
        blendshapes: &[String],
        names: Names,
    ) -> Result<Performer, LiveError> {
        let table = names.table(blendshapes);
        let from_arkit = match names {
            Names::Own => Vec::new(),
            Names::Arkit | Names::VrmPresets => {
                let arkit: Vec<String> = faceanim_rig::names::ARKIT_52
                    .iter()
                    .map(|&n| n.to_owned())
                    .collect();
                names
                    .table(&arkit)
                    .into_iter()
                    .filter(|(name, _)| table.iter().all(|(own, _)| own != name))
                    .collect()
            }
        };
        let local: SocketAddr = if destination.is_ipv4() {
            ([0, 0, 0, 0], 0).into()
        } else {
            (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let socket_error = |source| LiveError::Socket {
            address: destination,
            source,
        };
        let socket = UdpSocket::bind(local).map_err(socket_error)?;
        // A slow or absent receiver must never hold up the caller (capture, playback).
        socket.set_nonblocking(true).map_err(socket_error)?;
        Ok(Performer {
            socket,
            destination,
            last: vec![None; table.len()],
            table,
            last_from_arkit: vec![None; from_arkit.len()],
            from_arkit,
            stats: SendStats::default(),
        })
    }

    /// Whether frames without ARKit values send anything by name: the character's shapes make
    /// some of the names asked for.
    #[must_use]
    pub fn sends_weights(&self) -> bool {
        !self.table.is_empty()
    }

    /// Where it sends.
    #[must_use]
    pub fn destination(&self) -> SocketAddr {
        self.destination
    }

    /// How sending went so far.
    #[must_use]
    pub fn stats(&self) -> &SendStats {
        &self.stats
    }

    /// The bundle for one frame: `weights` (the character's, in its order), the frame's ARKit
    /// values where known (`arkit`, ARKit's 52 in [`ARKIT_52`](faceanim_rig::names::ARKIT_52)
    /// order; see [`Performer::with_arkit`]), the `pose` of head and eyes, and the performer's
    /// clock `time` in seconds.
    pub fn bundle(
        &mut self,
        weights: &[f32],
        arkit: Option<&[f32]>,
        pose: Pose,
        time: f32,
    ) -> OscBundle {
        let Pose { head, eyes, jaw } = pose;
        let refresh = self.stats.frames.is_multiple_of(REFRESH_EVERY);
        self.stats.frames += 1;
        let message = |addr: &str, args: Vec<OscType>| {
            OscPacket::Message(OscMessage {
                addr: addr.to_owned(),
                args,
            })
        };
        let mut content = vec![
            message(
                "/VMC/Ext/OK",
                // Loaded, calibrated, normal calibration mode, tracking well.
                vec![
                    OscType::Int(1),
                    OscType::Int(3),
                    OscType::Int(0),
                    OscType::Int(1),
                ],
            ),
            message("/VMC/Ext/T", vec![OscType::Float(time)]),
        ];
        // The head before the values and their Apply, so a marionette shows them together.
        let pose = |name: &str, q: [f32; 4]| {
            let mut args = vec![OscType::String(name.to_owned())];
            args.extend([0.0, 0.0, 0.0].into_iter().chain(q).map(OscType::Float));
            args
        };
        content.push(message(
            "/VMC/Ext/Root/Pos",
            pose("root", [0.0, 0.0, 0.0, 1.0]),
        ));
        // The turn shared between neck and head, half each (as VMagicMirror does): each
        // bone's local rotation, the head's after the neck's.
        if let Some(head) = head {
            let [neck, head] = crate::neck_and_head(unity_rotation(head));
            content.push(message("/VMC/Ext/Bone/Pos", pose("Neck", neck)));
            content.push(message("/VMC/Ext/Bone/Pos", pose("Head", head)));
        }
        if let Some(eyes) = eyes {
            for (bone, [yaw, pitch]) in ["LeftEye", "RightEye"].into_iter().zip(eyes) {
                let turn = unity_rotation([yaw, pitch, 0.0]);
                content.push(message("/VMC/Ext/Bone/Pos", pose(bone, turn)));
            }
        }
        if let Some(open) = jaw {
            let turn = unity_rotation([0.0, -JAW_DEGREES * open.clamp(0.0, 1.0), 0.0]);
            content.push(message("/VMC/Ext/Bone/Pos", pose("Jaw", turn)));
        }

        let own = self.table.iter().zip(&mut self.last).map(|t| (t, weights));
        let from_arkit = arkit
            .map(|values| {
                self.from_arkit
                    .iter()
                    .zip(&mut self.last_from_arkit)
                    .map(move |t| (t, values))
            })
            .into_iter()
            .flatten();
        for (((name, source), last), values) in own.chain(from_arkit) {
            let value = source.value(values).clamp(0.0, 1.0);
            let moved = last.is_none_or(|l| (l - value).abs() > MOVED);
            if moved || refresh {
                content.push(message(
                    "/VMC/Ext/Blend/Val",
                    vec![OscType::String(name.clone()), OscType::Float(value)],
                ));
                *last = Some(value);
            }
        }
        content.push(message("/VMC/Ext/Blend/Apply", Vec::new()));
        OscBundle {
            timetag: OscTime::from((0, 1)),
            content,
        }
    }

    /// Sends one frame (see [`Performer::bundle`]); false when the network refused it, which is
    /// counted and never blocks.
    pub fn send(&mut self, weights: &[f32], head: Option<[f32; 3]>, time: f32) -> bool {
        self.send_pose(
            weights,
            Pose {
                head,
                ..Pose::default()
            },
            time,
        )
    }

    /// [`Performer::send`] with the eyes' gaze and the jaw too, as the `LeftEye`, `RightEye`
    /// and `Jaw` bones.
    pub fn send_pose(&mut self, weights: &[f32], pose: Pose, time: f32) -> bool {
        self.send_bundle(weights, None, pose, time)
    }

    /// [`Performer::send_pose`] for a face whose ARKit values are known too (`arkit`: ARKit's
    /// 52 in [`ARKIT_52`](faceanim_rig::names::ARKIT_52) order), which make what the
    /// character's shapes cannot (see [`Performer::with_arkit`]).
    pub fn send_with_arkit(
        &mut self,
        weights: &[f32],
        arkit: &[f32],
        pose: Pose,
        time: f32,
    ) -> bool {
        self.send_bundle(weights, Some(arkit), pose, time)
    }

    fn send_bundle(
        &mut self,
        weights: &[f32],
        arkit: Option<&[f32]>,
        pose: Pose,
        time: f32,
    ) -> bool {
        let bundle = self.bundle(weights, arkit, pose, time);
        let sent = rosc::encoder::encode(&OscPacket::Bundle(bundle))
            .map_err(|e| e.to_string())
            .and_then(|bytes| {
                self.socket
                    .send_to(&bytes, self.destination)
                    .map_err(|e| e.to_string())
            });
        match sent {
            Ok(_) => {
                self.stats.sent += 1;
                true
            }
            Err(e) => {
                self.stats.dropped += 1;
                self.stats.last_error = Some(e);
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Names;

    #[test]
    fn the_head_goes_on_neck_and_head_and_the_gaze_on_the_eyes() {
        let names = vec!["jawOpen".to_owned()];
        let mut performer =
            Performer::new("127.0.0.1:9".parse().unwrap(), &names, Names::Own).unwrap();
        let pose = Pose {
            head: Some([20.0, 0.0, 0.0]),
            eyes: Some([[30.0, 0.0], [0.0, 10.0]]),
            jaw: Some(0.5),
        };
        let bundle = performer.bundle(&[0.5], None, pose, 0.0);
        let bones: Vec<(String, [f32; 4])> = bundle
            .content
            .iter()
            .filter_map(|p| match p {
                OscPacket::Message(m) if m.addr == "/VMC/Ext/Bone/Pos" => {
                    let name = match &m.args[0] {
                        OscType::String(s) => s.clone(),
                        _ => return None,
                    };
                    let f = |k: usize| match m.args[k] {
                        OscType::Float(v) => v,
                        _ => f32::NAN,
                    };
                    Some((name, [f(4), f(5), f(6), f(7)]))
                }
                _ => None,
            })
            .collect();
        let names: Vec<&str> = bones.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["Neck", "Head", "LeftEye", "RightEye", "Jaw"]);
        // Half the yaw on each of neck and head; each eye its own gaze.
        let expected = [
            [10.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [30.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            // The jaw half open: turned down half of its range.
            [0.0, -JAW_DEGREES / 2.0, 0.0],
        ];
        for ((bone, q), angles) in bones.iter().zip(expected) {
            let want = unity_rotation(angles);
            assert!(
                q.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-5),
                "{bone}: {q:?}, expected {want:?}"
            );
        }
    }

    /// A body with no blendshapes sends its bones alone; a character with shapes but none of
    /// the names asked for is refused, naming them.
    #[test]
    fn a_body_with_no_shapes_sends_bones_and_names_that_cover_nothing_are_refused() {
        let to: SocketAddr = "127.0.0.1:9".parse().unwrap();
        let mut bare = Performer::new(to, &[], Names::Arkit).unwrap();
        let pose = Pose {
            jaw: Some(1.0),
            ..Pose::default()
        };
        let bundle = bare.bundle(&[], None, pose, 0.0);
        let jaw = bundle.content.iter().any(|p| {
            matches!(p, OscPacket::Message(m) if m.addr == "/VMC/Ext/Bone/Pos"
                && m.args.first() == Some(&OscType::String("Jaw".to_owned())))
        });
        assert!(jaw);
        let shaped = ["Fcl_MTH_A".to_owned()];
        let refused = Performer::new(to, &shaped, Names::Arkit).unwrap_err();
        assert!(refused.to_string().contains("ARKit"), "{refused}");
    }

    /// The values of `bundle`'s `/VMC/Ext/Blend/Val` messages by name.
    fn values(bundle: &OscBundle) -> std::collections::BTreeMap<String, f32> {
        bundle
            .content
            .iter()
            .filter_map(|p| match p {
                OscPacket::Message(m) if m.addr == "/VMC/Ext/Blend/Val" => match &m.args[..] {
                    [OscType::String(name), OscType::Float(v)] => Some((name.clone(), *v)),
                    _ => None,
                },
                _ => None,
            })
            .collect()
    }

    /// Given a face's ARKit values, what the character's shapes cannot make goes out from them:
    /// under ARKit names every other channel, under VRM presets every other preset; what the
    /// shapes make still comes from the weights, and a frame without ARKit values sends that
    /// alone. Under its own names nothing changes.
    #[test]
    #[allow(clippy::float_cmp, reason = "values sent are copied, not computed")]
    fn a_face_known_in_arkit_sends_what_the_shapes_cannot_make() {
        let to: SocketAddr = "127.0.0.1:9".parse().unwrap();
        let shapes = ["jawOpen".to_owned(), "Fcl_MTH_A".to_owned()];
        let mut arkit = [0.0f32; 52];
        let channel = |n: &str| faceanim_rig::names::Channel::named(n).unwrap().index();
        arkit[channel("jawOpen")] = 0.9;
        arkit[channel("eyeBlinkLeft")] = 0.8;
        arkit[channel("eyeBlinkRight")] = 0.6;
        arkit[channel("mouthSmileLeft")] = 0.4;
        let weights = [0.25, 1.0];

        let mut performer = Performer::with_arkit(to, &shapes, Names::Arkit).unwrap();
        let sent = values(&performer.bundle(&weights, Some(&arkit), Pose::default(), 0.0));
        assert_eq!(sent.len(), 52, "{sent:?}");
        assert_eq!(
            sent["JawOpen"], 0.25,
            "the character's own jawOpen, not the capture's"
        );
        assert_eq!(sent["EyeBlinkLeft"], 0.8);
        assert_eq!(sent["MouthSmileLeft"], 0.4);
        assert_eq!(sent["BrowInnerUp"], 0.0);
        // (Values that did not move are not sent again: the jaw moves.)
        let alone = values(&performer.bundle(&[0.3, 1.0], None, Pose::default(), 0.0));
        assert_eq!(alone.keys().collect::<Vec<_>>(), ["JawOpen"]);

        let mut presets = Performer::with_arkit(to, &shapes, Names::VrmPresets).unwrap();
        let sent = values(&presets.bundle(&weights, Some(&arkit), Pose::default(), 0.0));
        assert_eq!(sent.len(), crate::VRM_PRESETS.len(), "{sent:?}");
        assert_eq!(sent["A"], 0.25);
        assert_eq!(sent["Blink"], 0.6, "the smaller lid: a wink is not a blink");
        assert!((sent["Joy"] - 0.2).abs() < 1e-6, "{}", sent["Joy"]);

        let mut own = Performer::with_arkit(to, &shapes, Names::Own).unwrap();
        let sent = values(&own.bundle(&weights, Some(&arkit), Pose::default(), 0.0));
        assert_eq!(sent.keys().collect::<Vec<_>>(), ["Fcl_MTH_A", "jawOpen"]);
        // A rig none of whose names means anything is not refused: captured faces drive it.
        let nameless = ["shape_1".to_owned()];
        let mut any = Performer::with_arkit(to, &nameless, Names::Arkit).unwrap();
        assert!(!any.sends_weights());
        let sent = values(&any.bundle(&[1.0], Some(&arkit), Pose::default(), 0.0));
        assert_eq!(sent["JawOpen"], 0.9);
    }
}
