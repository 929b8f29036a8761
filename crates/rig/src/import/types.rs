//! What every importer shares: the limits a file may declare, where external resources come
//! from, what an import gives back, and its errors.

use crate::character::{Character, ModelError};

/// The largest vertex count (and accessor element count) a file may declare.
pub const MAX_VERTICES: usize = 1 << 24;
/// The largest triangle count.
pub const MAX_TRIANGLES: usize = 1 << 25;
/// The largest number of blendshapes.
pub const MAX_BLENDSHAPES: usize = 4096;

/// Loads resources that a glTF file refers to by relative URI (`.bin` buffers, images).
pub trait Resources {
    /// The bytes of `uri` (already percent-decoded), or a reason it cannot be read.
    ///
    /// # Errors
    /// A human-readable reason, shown to the user with the URI.
    fn load(&self, uri: &str) -> Result<Vec<u8>, String>;
}

/// For self-contained sources (GLB, data URIs): any external URI is an error.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoExternalResources;

impl Resources for NoExternalResources {
    fn load(&self, uri: &str) -> Result<Vec<u8>, String> {
        Err(format!(
            "external resource '{uri}' cannot be loaded from here (give the .gltf file's path)"
        ))
    }
}

/// An imported character and what the importer had to work around.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The character.
    pub character: Character,
    /// Things that were skipped or renamed, one sentence each.
    pub warnings: Vec<String>,
}

/// Why a file could not be imported: the source's name and the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: {kind}")]
pub struct ImportError {
    /// The file (or other source) name given to the importer.
    pub source_name: String,
    /// What is wrong.
    pub kind: ImportErrorKind,
}

/// What is wrong with an imported file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ImportErrorKind {
    /// Neither GLB nor glTF JSON.
    #[error("not a glTF file: {0}")]
    NotGltf(String),
    /// An OBJ file without a mesh in it.
    #[error("not an OBJ mesh: {0}")]
    NotObj(String),
    /// The data ends before what its headers declare.
    #[error("truncated: {0}")]
    Truncated(String),
    /// The JSON does not parse or does not follow the glTF schema.
    #[error("invalid glTF JSON: {0}")]
    InvalidJson(String),
    /// A buffer or image could not be loaded.
    #[error("buffer {index} ('{uri}') is missing: {reason}")]
    MissingBuffer {
        /// The buffer's index.
        index: usize,
        /// Its URI.
        uri: String,
        /// Why it could not be read.
        reason: String,
    },
    /// An accessor's layout does not fit its data.
    #[error("accessor {accessor} ({role}): {problem}")]
    BadAccessor {
        /// The accessor's index.
        accessor: usize,
        /// What it is used for, e.g. `POSITION of mesh 'face' primitive 0`.
        role: String,
        /// What is wrong.
        problem: String,
    },
    /// The file has no triangle geometry.
    #[error("no triangle meshes found")]
    NoMeshes,
    /// Two things that must agree in count do not.
    #[error("counts disagree: {0}")]
    CountMismatch(String),
    /// A NaN or infinite number.
    #[error("{what} [{index}] is not a finite number")]
    NonFinite {
        /// Which data.
        what: String,
        /// Which element.
        index: usize,
    },
    /// A declared size beyond what faceanim accepts.
    #[error("too large: {0}")]
    TooLarge(String),
    /// A glTF feature faceanim does not read.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A syntax error in an OBJ file.
    #[error("line {line}: {problem}")]
    Obj {
        /// The OBJ file.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// The assembled mesh is inconsistent.
    #[error("{0}")]
    Model(#[from] ModelError),
}
