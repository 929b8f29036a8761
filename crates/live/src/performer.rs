//! The performer: the character's face out to a VMC marionette.

use std::net::{SocketAddr, UdpSocket};

use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

use crate::names::{Names, Source};
use crate::{LiveError, unity_rotation};

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
    stats: SendStats,
}

impl Performer {
    /// A performer sending the face of a character whose blendshapes are `blendshapes` (the
    /// weights given to [`Performer::send`] follow their order) under `names` to
    /// `destination`.
    ///
    /// # Errors
    /// [`LiveError::Socket`] when no UDP socket can be opened, [`LiveError::NoNames`] when the
    /// character has none of the names asked for.
    pub fn new(
        destination: SocketAddr,
        blendshapes: &[String],
        names: Names,
    ) -> Result<Performer, LiveError> {
        let table = names.table(blendshapes);
        if table.is_empty() {
            return Err(LiveError::NoNames {
                what: names.describe(),
            });
        }
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
            stats: SendStats::default(),
        })
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

    /// The bundle for one frame: `weights` (the character's, in its order), the head pose
    /// (`[yaw, pitch, roll]` in degrees) and the performer's clock `time` in seconds.
    pub fn bundle(&mut self, weights: &[f32], head: Option<[f32; 3]>, time: f32) -> OscBundle {
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

        for ((name, source), last) in self.table.iter().zip(&mut self.last) {
            let value = source.value(weights).clamp(0.0, 1.0);
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
        let bundle = self.bundle(weights, head, time);
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
