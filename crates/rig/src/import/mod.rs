//! Reading characters from bytes: glTF 2.0 (`.glb`, `.gltf` with external or data-URI buffers)
//! and OBJ sets (a neutral OBJ plus one OBJ per blendshape, same vertex order).
//!
//! Nothing here touches the file system: external glTF buffers and images come through the
//! [`Resources`] trait, which the caller implements (the `faceanim-files` crate does, for paths).
//! Every problem is an [`ImportError`] naming the source and what is wrong; nothing panics on
//! bad input, which the proptest fuzzer in `tests/fuzz_import.rs` checks.

mod accessor;
mod animations;
mod buffers;
mod draco;
mod extensions;
mod gltf;
mod obj;
mod types;
mod uri;
pub(crate) mod vrm;
mod vrma;

pub use self::gltf::import_gltf;
pub use self::obj::{ObjSource, import_obj_set};
pub use self::vrma::{VrmaTake, import_vrma};

pub use self::types::{
    ImportError, ImportErrorKind, Imported, MAX_BLENDSHAPES, MAX_TRIANGLES, MAX_VERTICES,
    NoExternalResources, Resources,
};
