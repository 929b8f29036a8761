//! A morph-weight animation: what sketching bakes, a take becomes and the exporters write.

/// A morph-weight animation: at `times[k]` seconds the weights are `weights[k]` (one per
/// blendshape of the exported character, in its order).
#[derive(Debug, Clone, PartialEq)]
pub struct MorphAnimation {
    /// Animation name shown in DCC tools (an action in Blender).
    pub name: String,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One weight vector per key.
    pub weights: Vec<Vec<f32>>,
    /// Optional rotation of the character's node per key, as a unit quaternion `[x, y, z, w]`
    /// (a head pose from capture); played with spherical interpolation.
    pub rotations: Option<Vec<[f32; 4]>>,
}
