//! What an adapter is bound to: the character's blendshape names, its mesh (vertex count and
//! triangles) and its shape (rest positions and blendshape deltas), as short hashes.
//!
//! An adapter maps features to the weights of named shapes, so names must match exactly and a
//! different mesh means a different character: both are refused. The same mesh with another
//! shape (another identity of the same rig, as ICT-FaceKit's heads are) still works, a little
//! less accurately, and is only warned about.

use faceanim_rig::Character;
use serde::{Deserialize, Serialize};

/// Hashes of a character's mesh and shape.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// Vertex count and triangles.
    pub topology: String,
    /// Rest positions and blendshape deltas, to a micrometre.
    pub geometry: String,
}

/// 64-bit FNV-1a: small, stable across platforms and Rust versions (std's hasher is not
/// promised to be).
#[derive(Debug, Clone, Copy)]
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    /// A coordinate to the nearest micrometre (characters are in metres), so a re-export that
    /// only perturbs the last bits of a float keeps its hash.
    fn coordinate(&mut self, v: f32) {
        self.u64(((f64::from(v) * 1e6).round() as i64) as u64);
    }
    fn hex(self) -> String {
        format!("{:016x}", self.0)
    }
}

impl Fingerprint {
    /// The fingerprint of `character`.
    #[must_use]
    pub fn of(character: &Character) -> Fingerprint {
        let mut topology = Fnv::new();
        topology.u64(character.vertex_count() as u64);
        for tri in character.triangles() {
            for &v in tri {
                topology.u64(u64::from(v));
            }
        }
        let mut geometry = Fnv::new();
        for p in character.positions() {
            for c in p.to_array() {
                geometry.coordinate(c);
            }
        }
        for shape in character.blendshapes() {
            for (i, d) in shape.moves() {
                geometry.u64(u64::from(i));
                for c in d.to_array() {
                    geometry.coordinate(c);
                }
            }
        }
        Fingerprint {
            topology: topology.hex(),
            geometry: geometry.hex(),
        }
    }
}
