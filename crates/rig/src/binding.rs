//! What a blendshape drives in the user's file: its morph targets, each with a weight.

/// One morph target a blendshape drives, with its weight (1 for a raw target; a VRM binding's
/// weight for an expression).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Binding {
    /// The mesh's index in the file.
    pub mesh: u32,
    /// The morph target's index in that mesh.
    pub target: u32,
    /// How much of it the blendshape at weight 1 applies.
    pub weight: f32,
}
