//! Reading and writing the GLB container in tests: the JSON chunk parsed, a document packed
//! back with its binary chunk, and the names of a document's nodes, meshes, skins… to compare
//! a file before and after faceanim wrote it ([`assert_kept`]).

use serde_json::Value;

/// The JSON chunk of a GLB, parsed, and its binary chunk (empty when there is none).
///
/// # Panics
/// When the bytes are not a GLB with a JSON chunk (test input is).
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: the GLBs given are the tests' own"
)]
pub fn parts(glb: &[u8]) -> (Value, Vec<u8>) {
    let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    let json = serde_json::from_slice(&glb[20..20 + len]).expect("the JSON chunk parses");
    let bin = glb
        .get(20 + len + 8..)
        .map_or_else(Vec::new, <[u8]>::to_vec);
    (json, bin)
}

/// The JSON chunk of a GLB, parsed.
///
/// # Panics
/// As [`parts`].
#[must_use]
pub fn json(glb: &[u8]) -> Value {
    parts(glb).0
}

/// Packs a glTF document and its binary chunk into a GLB (both padded to 4 bytes).
#[must_use]
pub fn assemble(root: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(root).unwrap_or_default();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// The `name` of each entry of a document's top-level array `key` (`nodes`, `meshes`, …), in
/// order (`null` where one has none).
#[must_use]
pub fn names(doc: &Value, key: &str) -> Vec<Value> {
    doc[key]
        .as_array()
        .map(|a| a.iter().map(|x| x["name"].clone()).collect())
        .unwrap_or_default()
}

/// The index of the entry of a document's top-level array `key` (`nodes`, `meshes`,
/// `materials`, …) whose `name` is `name`: the first, if several are.
#[must_use]
pub fn index_of(doc: &Value, key: &str, name: &str) -> Option<usize> {
    doc[key]
        .as_array()?
        .iter()
        .position(|x| x["name"].as_str() == Some(name))
}

/// Asserts that `output` keeps what the user's file `input` had: the same nodes, meshes, skins,
/// materials, textures, images, samplers and scenes with the same names in the same order, each
/// skin's joints, and the top-level extensions (a VRM stays a VRM). `what` names the file in
/// the messages.
///
/// # Panics
/// On the first difference, naming it.
#[expect(clippy::panic, reason = "test support: an assertion")]
pub fn assert_kept(input: &Value, output: &Value, what: &str) {
    for key in [
        "nodes",
        "meshes",
        "skins",
        "materials",
        "textures",
        "images",
        "samplers",
        "scenes",
    ] {
        let (a, b) = (names(input, key), names(output, key));
        if a != b {
            panic!("{what}: {key} were {a:?}, now {b:?}");
        }
    }
    let skins = |doc: &Value| doc["skins"].as_array().cloned().unwrap_or_default();
    for (k, (a, b)) in skins(input).iter().zip(&skins(output)).enumerate() {
        if a["joints"] != b["joints"] {
            panic!("{what}: skin {k}'s joints changed");
        }
    }
    if input["extensions"] != output["extensions"] {
        panic!("{what}: the extensions changed (a VRM must stay a VRM)");
    }
}
