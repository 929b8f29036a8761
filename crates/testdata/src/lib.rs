//! # faceanim-testdata: the shared test data, for tests and benchmarks only
//!
//! The realistic test heads and images live in `../shared` beside the repository (or wherever
//! `FACEANIM_SHARED` points), never inside the product. This crate finds them, says clearly
//! when they are missing, and caches the parsed ICT head so a test binary imports it once.
#![deny(missing_docs)]

pub mod avatar;
pub mod glb;
pub mod producers;

use std::path::PathBuf;
use std::sync::OnceLock;

use faceanim_rig::Character;
use faceanim_rig::import::{NoExternalResources, import_gltf};

/// `../shared/<rel>` beside the repository, or under `FACEANIM_SHARED`.
///
/// # Panics
/// When the file is missing, with a message saying where it was expected.
#[must_use]
#[expect(
    clippy::panic,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn shared(rel: &str) -> PathBuf {
    let base = std::env::var_os("FACEANIM_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
    let path = base.join(rel);
    if !path.exists() {
        panic!(
            "test data {} is missing: the shared/ folder must sit beside the repository",
            path.display()
        );
    }
    path
}

/// The bytes of `../shared/characters/ict-face.glb`, read once.
///
/// # Panics
/// When the file is missing or unreadable.
#[must_use]
pub fn ict_bytes() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    read_once(&BYTES, || shared("characters/ict-face.glb"))
}

/// The bytes of the file at `path()`, read into `cell` the first time.
///
/// # Panics
/// When the file is missing or unreadable, naming it.
#[expect(
    clippy::panic,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub(crate) fn read_once(
    cell: &'static OnceLock<Vec<u8>>,
    path: impl FnOnce() -> PathBuf,
) -> &'static [u8] {
    cell.get_or_init(|| {
        let path = path();
        std::fs::read(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
    })
}

/// The ICT head (24,591 vertices, 53 blendshapes), imported once.
///
/// # Panics
/// When the file is missing or does not import.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn ict() -> &'static Character {
    static ICT: OnceLock<Character> = OnceLock::new();
    ICT.get_or_init(|| {
        import_gltf(ict_bytes(), "ict-face.glb", &NoExternalResources)
            .expect("ict-face.glb imports")
            .character
    })
}

/// Encodes RGB `frames` (`width × height × 3` bytes each) at `fps` into `path` with the real
/// `ffmpeg` program, `codec` being its output options (for example `["-c:v", "ffv1"]`): how the
/// tests make the videos users would bring.
///
/// # Panics
/// When ffmpeg is missing or fails.
#[expect(
    clippy::panic,
    clippy::expect_used,
    reason = "test support: a video that cannot be made must stop the test loudly"
)]
pub fn encode_video<'a>(
    path: &std::path::Path,
    (width, height): (usize, usize),
    fps: u32,
    codec: &[&str],
    frames: impl IntoIterator<Item = &'a [u8]>,
) {
    use std::io::Write as _;
    let mut child = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
        .args([
            "-s",
            &format!("{width}x{height}"),
            "-r",
            &fps.to_string(),
            "-i",
            "-",
        ])
        .args(codec)
        .arg(path)
        .stdin(std::process::Stdio::piped())
        .spawn()
        .expect("ffmpeg must be installed for these tests (scripts/setup.sh installs it)");
    let mut stdin = child.stdin.take().expect("ffmpeg's stdin");
    for frame in frames {
        stdin.write_all(frame).expect("writing a frame to ffmpeg");
    }
    drop(stdin);
    let status = child.wait().expect("waiting for ffmpeg");
    if !status.success() {
        panic!("ffmpeg could not write {}: {status}", path.display());
    }
}

/// The ICT head with another identity (same mesh and blendshapes, other face), imported once.
///
/// # Panics
/// When the file is missing or does not import.
#[must_use]
pub fn ict_id7() -> &'static Character {
    ict_identity("ict-face-id7.glb")
}

/// The four ICT identities in `../shared/characters`: the generic face and three real people,
/// none exactly symmetric (same topology and expression deltas).
pub const ICT_IDENTITIES: [&str; 4] = [
    "ict-face.glb",
    "ict-face-id7.glb",
    "ict-face-id3.glb",
    "ict-face-id48.glb",
];

/// The ICT identity `file` (one of [`ICT_IDENTITIES`]), imported once per test binary.
///
/// # Panics
/// When the file is missing or does not import.
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: a missing fixture must stop the test loudly"
)]
pub fn ict_identity(file: &str) -> &'static Character {
    static LOADED: std::sync::Mutex<Vec<(String, &'static Character)>> =
        std::sync::Mutex::new(Vec::new());
    let mut loaded = LOADED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, c)) = loaded.iter().find(|(f, _)| f == file) {
        return c;
    }
    let bytes =
        std::fs::read(shared(&format!("characters/{file}"))).expect("the identity is readable");
    let character = import_gltf(&bytes, file, &NoExternalResources)
        .expect("the identity imports")
        .character;
    let leaked: &'static Character = Box::leak(Box::new(character));
    loaded.push((file.to_owned(), leaked));
    leaked
}

/// `character` with its blendshapes renamed `shape_1…shape_N` and shuffled (a fixed
/// permutation from `seed`): a rig whose names say nothing. Returns the character and, for each
/// new position, the original blendshape's index.
///
/// # Panics
/// When the shuffled parts do not make a character (they always do).
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: reordering a valid character's shapes keeps it valid"
)]
pub fn renamed_and_shuffled(character: &Character, seed: u64) -> (Character, Vec<usize>) {
    let mut parts = character.to_parts();
    let n = parts.blendshapes.len();
    // A small deterministic shuffle (xorshift), so the fixture needs no random crate.
    let mut order: Vec<usize> = (0..n).collect();
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    for k in (1..n).rev() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        order.swap(k, (state % (k as u64 + 1)) as usize);
    }
    let shapes = std::mem::take(&mut parts.blendshapes);
    parts.blendshapes = order
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            faceanim_rig::Blendshape::from_sparse(
                format!("shape_{}", k + 1),
                shapes[i].indices().to_vec(),
                shapes[i].deltas().to_vec(),
            )
        })
        .collect();
    if let Some(normals) = parts.normal_deltas.take() {
        parts.normal_deltas = Some(order.iter().map(|&i| normals[i].clone()).collect());
    }
    parts.name = format!("{} (renamed, shuffled)", character.name());
    (
        Character::new(parts).expect("a shuffled character is valid"),
        order,
    )
}

/// Runs npm `gltfpack` (installed in `tools/` by `scripts/setup.sh`) on `input` with `args`
/// and returns the bytes it wrote, as the compressed avatars people download are made.
///
/// # Panics
/// When node or gltfpack is missing or gltfpack fails, with its output.
#[must_use]
pub fn gltfpack(input: &[u8], args: &[&str]) -> Vec<u8> {
    node_tool(
        "node_modules/gltfpack/cli.js",
        "gltfpack",
        input,
        |src, out| {
            let mut all: Vec<std::ffi::OsString> =
                vec!["-i".into(), src.into(), "-o".into(), out.into()];
            all.extend(args.iter().map(Into::into));
            all
        },
    )
}

/// Runs npm `@gltf-transform/cli` (installed in `tools/` by `scripts/setup.sh`) as
/// `gltf-transform COMMAND in.glb out.glb` on `input` and returns the bytes it wrote
/// (`draco` makes a Draco-compressed file, `meshopt` a meshopt-compressed one, `webp` WebP
/// textures).
///
/// # Panics
/// When node or the tool is missing or it fails, with its output.
#[must_use]
pub fn gltf_transform(input: &[u8], command: &str) -> Vec<u8> {
    node_tool(
        "node_modules/@gltf-transform/cli/bin/cli.js",
        "gltf-transform",
        input,
        |src, out| vec![command.into(), src.into(), out.into()],
    )
}

/// `input` with every texture re-encoded as KTX2 (`KHR_texture_basisu`, required) by
/// Binomial's Basis Universal encoder (npm `ktx2-encoder`, its WebAssembly build, through
/// glTF Transform: `tools/ktx2.mjs`): `uastc` false for ETC1S with BasisLZ (gltfpack's and
/// toktx's default), true for UASTC with Zstandard (glTF Transform's `uastc`).
///
/// # Panics
/// When node or the tool is missing or it fails, with its output.
#[must_use]
pub fn ktx2(input: &[u8], uastc: bool) -> Vec<u8> {
    node_tool("ktx2.mjs", "ktx2", input, |src, out| {
        let mode = if uastc { "uastc" } else { "etc1s" };
        vec![src.into(), out.into(), mode.into()]
    })
}

/// `input` loaded and written again by three.js (its GLTFLoader and GLTFExporter, in
/// headless Chromium: `tools/threejs-export.mjs`), as web-based editors save an avatar.
#[must_use]
pub fn threejs(input: &[u8]) -> Vec<u8> {
    node_tool("threejs-export.mjs", "threejs", input, |src, out| {
        vec![src.into(), out.into()]
    })
}

/// Runs the node script at `tools/SCRIPT` (a tool's, under `node_modules`, or one of ours)
/// with node on `input`, written to a
/// temporary `in.glb`, with the arguments `args(in, out)`; returns what it wrote to `out.glb`.
#[expect(
    clippy::panic,
    reason = "test support: a missing tool must stop the test loudly"
)]
fn node_tool(
    script: &str,
    name: &str,
    input: &[u8],
    args: impl FnOnce(&std::path::Path, &std::path::Path) -> Vec<std::ffi::OsString>,
) -> Vec<u8> {
    let cli = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tools")
        .join(script);
    if !cli.exists() {
        panic!(
            "{} is missing: run scripts/setup.sh (npm ci in tools/)",
            cli.display()
        );
    }
    static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("faceanim-{name}-{}-{n}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let (src, out) = (dir.join("in.glb"), dir.join("out.glb"));
    if let Err(e) = std::fs::write(&src, input) {
        panic!("cannot write {}: {e}", src.display());
    }
    let args = args(&src, &out);
    let result = std::process::Command::new("node")
        .arg(&cli)
        .args(&args)
        .output();
    let bytes = match result {
        Ok(o) if o.status.success() => std::fs::read(&out).ok(),
        Ok(o) => panic!(
            "{name} {args:?} failed: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!("cannot run node for {name}: {e}"),
    };
    let _ = std::fs::remove_dir_all(&dir);
    bytes.unwrap_or_else(|| panic!("{name} {args:?} wrote no file"))
}

/// `character` made as asymmetric as a scanned face: every vertex moved by a smooth field that
/// is not mirror-symmetric (up to 0.6 % of the size, about 3 mm on a head), and every
/// blendshape 12 % stronger on the character's left than on its right.
///
/// # Panics
/// When the result is not a valid character (it always is).
#[must_use]
#[expect(
    clippy::expect_used,
    reason = "test support: moving a valid character's vertices keeps it valid"
)]
pub fn asymmetric(character: &Character) -> Character {
    let mut parts = character.to_parts();
    let d = character.size();
    let centre = character.bounds().center();
    for p in &mut parts.positions {
        let q = (*p - centre) / d;
        *p += d
            * 0.006
            * faceanim_rig::glam::Vec3::new(
                (9.0 * q.x + 3.0 * q.y).sin(),
                0.5 * (7.0 * q.y + 5.0 * q.x).sin(),
                0.5 * (5.0 * q.x).cos(),
            );
    }
    let positions = parts.positions.clone();
    parts.blendshapes = parts
        .blendshapes
        .iter()
        .map(|b| {
            let deltas = b
                .moves()
                .map(|(v, delta)| {
                    let x = (positions[v as usize].x - centre.x) / (0.02 * d);
                    delta * (1.0 + 0.12 * x.tanh())
                })
                .collect();
            faceanim_rig::Blendshape::from_sparse(b.name().to_owned(), b.indices().to_vec(), deltas)
        })
        .collect();
    parts.normals = None;
    parts.normal_deltas = None;
    parts.name = format!("{} (asymmetric)", character.name());
    Character::new(parts).expect("an asymmetric character is valid")
}
