//! # faceanim-live: the VMC protocol over OSC
//!
//! VTuber apps and engines (VSeeFace, Warudo, VNyan, VMagicMirror, Unity's and Unreal's VMC
//! receivers) and some trackers (Waidayo, iFacialMocap's Windows edition) speak the [VMC
//! protocol](https://protocol.vmc.info/): OSC messages in UDP datagrams, sent by a *performer*
//! (which tracks) to a *marionette* (which shows the avatar), port 39539 by default. The phone
//! apps themselves speak their own protocols, which a marionette also reads ([`phone`]): Live
//! Link Face (binary, port 11111), iFacialMocap, MeowFace and Facemotion3d (text, port 49983,
//! after a handshake to the phone) and VTube Studio's phone app (JSON, asked for at the phone's
//! port 21412 every second).
//!
//! - [`Performer`] sends the character's face: one OSC bundle per frame with `/VMC/Ext/OK`,
//!   `/VMC/Ext/T`, `/VMC/Ext/Root/Pos`, the head pose as `/VMC/Ext/Bone/Pos` `Neck` and `Head`
//!   (half the turn each; Unity's left-handed convention, see [`unity_rotation`]), `/VMC/Ext/Blend/Val` for every blendshape that moved
//!   (every one on every 30th frame, so a late marionette catches up) and
//!   `/VMC/Ext/Blend/Apply`. Names are the character's own, ARKit's or VRM 0.x presets
//!   ([`Names`]). Sending never blocks: a datagram the network refuses is counted and dropped.
//! - [`Marionette`] listens on a UDP port on its own thread and turns what arrives into frames
//!   of the character's weights with the head pose and the arrival time (a recording goes by
//!   the sender's own clock where it is sound: VMC's `/VMC/Ext/T`, a phone's frame times);
//!   malformed, truncated, foreign, unknown and oversized datagrams are counted and dropped,
//!   never a panic. A sender of ARKit values (a phone, a VMC tracker naming ARKit's channels)
//!   gives each frame those values too, with the gaze and jaw read from them, for eye and jaw
//!   bones (a body with no blendshapes follows by them). A phone's frames can go straight on to a [`Performer`]
//!   ([`Marionette::forward_to`]), timed from datagram in to VMC out; a lost face returns the
//!   character to neutral, and a calibrated neutral ([`Marionette::calibrate`]) is taken away
//!   from every frame.
//!
//! ```
//! use faceanim_live::{Marionette, Names, Performer};
//!
//! let blendshapes: Vec<String> = ["jawOpen", "eyeBlinkLeft"].map(String::from).to_vec();
//! let marionette = Marionette::listen("127.0.0.1:0".parse()?, &blendshapes)?;
//! let mut performer = Performer::new(marionette.address(), &blendshapes, Names::Arkit)?;
//! let weights = [0.75, 0.25];
//! let jaw = 0;
//! performer.send(&weights, Some([20.0, 0.0, 0.0]), 0.0);
//! let frame = marionette.wait_for_frames(1, std::time::Duration::from_secs(5)).remove(0);
//! assert_eq!(frame.weights[jaw], 0.75);
//! let [yaw, _, _] = frame.head.unwrap_or_default();
//! assert!((yaw - 20.0).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod clock;
mod marionette;
mod names;
mod performer;
pub mod phone;

pub use marionette::{
    Forwarding, Marionette, Neutral, ReceivedFrame, Source, SourceSettings, Traffic,
};
pub use names::{Names, VRM_PRESETS, VRM_VOWELS};
pub use performer::{JAW_DEGREES, Performer, Pose, SendStats};

/// The VMC protocol's default port (the marionette's).
pub const DEFAULT_PORT: u16 = 39539;

/// Why a live link could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LiveError {
    /// The socket could not be opened or bound.
    #[error("{address}: {source}")]
    Socket {
        /// The address.
        address: std::net::SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// The chosen names cover none of the character's blendshapes.
    #[error("the character has no {what}: nothing would be sent")]
    NoNames {
        /// Which names.
        what: &'static str,
    },
}

/// This machine's addresses on its local network, for the user to type into a phone app
/// (none when it has no route off the machine). Found by asking the system which address it
/// would send from; nothing is sent.
#[must_use]
pub fn lan_addresses() -> Vec<std::net::IpAddr> {
    let mut found = Vec::new();
    // Documentation and private ranges: the route is looked up, no datagram leaves.
    for probe in [
        "192.0.2.1:9",
        "10.255.255.254:9",
        "172.31.255.254:9",
        "192.168.255.254:9",
    ] {
        let Ok(socket) = std::net::UdpSocket::bind("0.0.0.0:0") else {
            continue;
        };
        if socket.connect(probe).is_ok()
            && let Ok(local) = socket.local_addr()
            && !local.ip().is_loopback()
            && !local.ip().is_unspecified()
            && !found.contains(&local.ip())
        {
            found.push(local.ip());
        }
    }
    found
}

/// The head pose `[yaw, pitch, roll]` (degrees, faceanim's convention: see
/// `faceanim_anim::head_rotation`) as a rotation in Unity's left-handed frame, `[x, y, z, w]`, as
/// VMC sends bones. glTF (right-handed, +X left of a character facing the viewer) and Unity
/// (left-handed) differ by a mirror of the X axis, which keeps `x` and `w` and negates `y`
/// and `z`.
#[must_use]
pub fn unity_rotation(head: [f32; 3]) -> [f32; 4] {
    let [x, y, z, w] = faceanim_anim::head_rotation(head);
    [x, -y, -z, w]
}

/// A head turn `q` (`[x, y, z, w]`) shared between neck and head as exports share it
/// ([`faceanim_rig::bones::HeadSplit`], without the spine): the neck's local rotation and the
/// head's after it (their product is `q`).
#[must_use]
pub fn neck_and_head(q: [f32; 4]) -> [[f32; 4]; 2] {
    let [_, neck, head] = faceanim_rig::bones::HeadSplit::default().share(
        glam::Quat::from_array(q),
        0.0,
        false,
        true,
    );
    [neck.to_array(), head.to_array()]
}

/// The inverse of [`unity_rotation`]: a Unity rotation `[x, y, z, w]` as `[yaw, pitch, roll]`
/// in degrees; `None` for a rotation that is not a finite, non-zero quaternion.
#[must_use]
pub fn head_angles(unity: [f32; 4]) -> Option<[f32; 3]> {
    let [x, y, z, w] = unity;
    faceanim_anim::head_angles([x, -y, -z, w])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_angles_round_trip_through_unitys_convention() {
        for head in [[20.0, 0.0, 0.0], [-15.0, 10.0, 5.0], [0.0, -20.0, 12.0]] {
            let back = head_angles(unity_rotation(head)).unwrap_or_default();
            for (a, b) in head.iter().zip(back) {
                assert!((a - b).abs() < 1e-3, "{head:?} came back as {back:?}");
            }
        }
        assert_eq!(head_angles([0.0; 4]), None);
        assert_eq!(head_angles([f32::NAN, 0.0, 0.0, 1.0]), None);
    }
}
