//! Full-body avatars, as animators have them, through the command line: built in code from the
//! ICT head (a skinned, textured body; head, teeth and eyes as meshes sharing target names),
//! as plain glTF, VRM 0.x, VRM 1.0 and gltfpack's meshopt compression. `faceanim info` lists
//! their blendshapes and VRM expressions; `faceanim export --clip` writes the user's own file
//! with the animation added, which the Khronos validator passes with no errors, which keeps
//! every node, mesh, skin, material, texture and image by name, and which Blender 3.4 and
//! three.js open with the armature, the shape keys, the texture and the moving face.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use faceanim_testdata::avatar::{ICT_EXPRESSIONS, VrmKind, full_body_glb, full_body_glb_textured};
use faceanim_testdata::glb::assert_kept;
use faceanim_testdata::{gltf_transform, gltfpack, ict, ktx2};
use serde_json::Value;
use support::{
    assert_avatar_drawn, assert_valid_gltf, blender_report, export_with_clip, faceanim_ok,
    output_dir, threejs_render,
};

/// The four avatars, written once per test into `dir`.
fn avatars(dir: &Path) -> Vec<PathBuf> {
    let plain = full_body_glb(ict(), VrmKind::None, &[]);
    let files = [
        ("avatar.glb", plain.clone()),
        (
            "avatar-0.vrm",
            full_body_glb(ict(), VrmKind::V0, ICT_EXPRESSIONS),
        ),
        (
            "avatar-1.vrm",
            full_body_glb(ict(), VrmKind::V1, ICT_EXPRESSIONS),
        ),
        ("avatar-meshopt.glb", gltfpack(&plain, &["-cc", "-kn"])),
    ];
    files
        .into_iter()
        .map(|(name, bytes)| {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            path
        })
        .collect()
}

/// The JSON chunk of a GLB or VRM file.
fn json_chunk(file: &Path) -> Value {
    faceanim_testdata::glb::json(&std::fs::read(file).unwrap())
}

/// A ten-second clip: the jaw opens and closes, the left smile rises, the eyes blink (VRM
/// `blink` where the avatar has it).
fn clip(dir: &Path) -> PathBuf {
    let mut frames = String::new();
    for f in 0..300 {
        let t = f as f32 / 30.0;
        let jaw = (0.5 - 0.5 * (t * 1.3).cos()).clamp(0.0, 1.0);
        let blink = if (t % 3.0) < 0.2 { 1.0 } else { 0.0 };
        let _ = write!(
            frames,
            "{}[{jaw}, {}, {blink}, {blink}]",
            if f > 0 { "," } else { "" },
            t / 10.0
        );
    }
    let path = dir.join("ten-seconds.json");
    std::fs::write(
        &path,
        format!(r#"{{"fps": 30, "blendshapes": ["jawOpen", "mouthSmileLeft", "eyeBlinkLeft", "eyeBlinkRight"], "frames": [{frames}]}}"#),
    )
    .unwrap();
    path
}

#[test]
fn info_lists_the_blendshapes_and_vrm_expressions() {
    let dir = output_dir("avatars-info");
    for file in avatars(&dir) {
        let report: Value =
            serde_json::from_str(&faceanim_ok(&["info", file.to_str().unwrap(), "--json"]))
                .unwrap();
        let listed: Vec<&str> = report["blendshapes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["name"].as_str().unwrap())
            .collect();
        for shape in ict().blendshapes() {
            assert!(
                listed.contains(&shape.name()),
                "{}: {} missing",
                file.display(),
                shape.name()
            );
        }
        if file.extension().is_some_and(|e| e == "vrm") {
            for e in ICT_EXPRESSIONS {
                assert!(
                    listed.contains(&e.name),
                    "{}: expression {} missing",
                    file.display(),
                    e.name
                );
            }
        }
    }
}

#[test]
fn exports_are_the_users_file_with_the_animation_and_open_everywhere() {
    let dir = output_dir("avatars-export");
    let clip = clip(&dir);
    let mut outputs = Vec::new();
    for file in avatars(&dir) {
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let ext = file.extension().unwrap().to_string_lossy().into_owned();
        // The test avatars are valid glTF themselves.
        let input = dir.join(format!("{stem}-input-{ext}.glb"));
        std::fs::copy(&file, &input).unwrap();
        assert_valid_gltf(&input);
        let out = dir.join(format!("{stem}-animated.{ext}"));
        export_with_clip(&file, &out, &clip);
        // The validator reads .glb; a .vrm is a GLB by another name.
        let checked = dir.join(format!("{stem}-animated-{ext}.glb"));
        std::fs::copy(&out, &checked).unwrap();
        let report = assert_valid_gltf(&checked);
        assert_eq!(report["info"]["animationCount"], 1, "{}", out.display());
        let (before, after) = (json_chunk(&file), json_chunk(&out));
        assert_kept(&before, &after, &out.display().to_string());
        outputs.push(checked);
    }

    // Blender 3.4 opens the plain avatar's export with its armature and its shape keys.
    let report = blender_report(&outputs[0]);
    let armatures = report["armatures"].as_array().unwrap();
    assert_eq!(armatures.len(), 1, "{report}");
    assert_eq!(armatures[0]["bones"], 5, "{report}");
    let objects = report["objects"].as_array().unwrap();
    let head = objects
        .iter()
        .find(|o| o["name"] == "Head")
        .unwrap_or_else(|| panic!("{report}"));
    assert_eq!(
        head["shape_keys"].as_array().unwrap().len(),
        ict().blendshapes().len()
    );
    assert!(objects.iter().any(|o| o["name"] == "Body"), "{report}");
    assert!(
        !report["actions"].as_array().unwrap().is_empty(),
        "{report}"
    );

    // three.js (the studio's own copy) in Chromium: the textured, skinned avatar with its face
    // moving at second 5 of the clip (the jaw is open there).
    for file in [&outputs[0], &outputs[2]] {
        assert_avatar_drawn(&threejs_render(file, "2.4"), 5, 5, 10_000);
    }
}

/// A Draco-compressed avatar (made by @gltf-transform/cli) is decoded natively: it imports with
/// every blendshape as the uncompressed one has it, and its export is written decompressed and
/// valid.
#[test]
fn draco_is_decoded() {
    let dir = output_dir("avatars-draco");
    let plain = full_body_glb(ict(), VrmKind::None, &[]);
    let draco = dir.join("avatar-draco.glb");
    std::fs::write(&draco, gltf_transform(&plain, "draco")).unwrap();
    assert!(
        json_chunk(&draco)["extensionsRequired"]
            .to_string()
            .contains("KHR_draco_mesh_compression")
    );
    let report: Value =
        serde_json::from_str(&faceanim_ok(&["info", draco.to_str().unwrap(), "--json"])).unwrap();
    let original = glb_character(&plain, "avatar.glb");
    assert_eq!(report["vertices"], original.vertex_count());
    let shapes = report["blendshapes"].as_array().unwrap();
    assert_eq!(shapes.len(), original.blendshapes().len());
    for (listed, shape) in shapes.iter().zip(original.blendshapes()) {
        assert_eq!(listed["name"], shape.name());
        let d = listed["max_displacement"].as_f64().unwrap() - f64::from(shape.max_displacement());
        assert!(d.abs() < 1e-4, "{}: {d}", shape.name());
    }
    let out = dir.join("animated.glb");
    export_with_clip(&draco, &out, &clip(&dir));
    assert_valid_gltf(&out);
    assert!(
        !json_chunk(&out)
            .to_string()
            .contains("KHR_draco_mesh_compression")
    );
}

/// An avatar packed as VRoid Studio ships them: WebP textures (`EXT_texture_webp`, made by
/// gltf-transform) and meshopt compression with quantization (gltfpack), all three required.
/// It imports with its WebP texture, exports valid, and the studio's own view of it declares
/// the WebP extension so browsers show the texture.
#[test]
fn a_webp_meshopt_quantized_avatar_like_vroids() {
    let dir = output_dir("avatars-webp");
    let webp = gltf_transform(&full_body_glb(ict(), VrmKind::None, &[]), "webp");
    let packed = gltfpack(&webp, &["-cc", "-kn"]);
    let file = dir.join("avatar-webp-meshopt.glb");
    std::fs::write(&file, &packed).unwrap();
    let required = json_chunk(&file)["extensionsRequired"].to_string();
    for ext in [
        "EXT_texture_webp",
        "EXT_meshopt_compression",
        "KHR_mesh_quantization",
    ] {
        assert!(required.contains(ext), "{required}");
    }
    let character = glb_character(&packed, "avatar-webp-meshopt.glb");
    assert!(
        character.materials().iter().any(|m| m
            .base_color_texture
            .as_ref()
            .is_some_and(|t| t.mime_type == "image/webp")),
        "the WebP texture is kept"
    );
    // The software renderer (the face's renders for generate-shapes, the retarget map and the
    // adapter) draws it: gltf-transform's WebP (libwebp through sharp) decodes.
    let report = drawn_and_viewed(&character, &dir.join("view.glb"));
    assert!(
        report["info"]["extensionsRequired"]
            .to_string()
            .contains("EXT_texture_webp"),
        "{report}"
    );
    // The export keeps the compression it was read with (issue 48: 2.3 MB became 9.4 MB):
    // within 1.5 times the input with ten seconds of animation added, valid, and it reads
    // back to the same character and animation; `--uncompressed` writes it plain.
    let clip = clip(&dir);
    let out = dir.join("animated.glb");
    export_with_clip(&file, &out, &clip);
    assert_valid_gltf(&out);
    let after = json_chunk(&out)["extensionsRequired"].to_string();
    assert!(
        after.contains("EXT_texture_webp") && after.contains("EXT_meshopt_compression"),
        "{after}"
    );
    let (input, output) = (
        packed.len(),
        std::fs::metadata(&out).unwrap().len() as usize,
    );
    assert!(
        output * 2 <= input * 3,
        "the export is {output} bytes for an input of {input}"
    );
    let plain = dir.join("animated-plain.glb");
    support::export_with_clip_and(&file, &plain, &clip, &["--uncompressed"]);
    let plain_bytes = std::fs::read(&plain).unwrap();
    assert!(
        !json_chunk(&plain)["extensionsUsed"]
            .to_string()
            .contains("meshopt"),
        "--uncompressed kept meshopt"
    );
    eprintln!(
        "meshopt avatar: input {input} bytes, export {output}, --uncompressed {}",
        plain_bytes.len()
    );
    let compressed = glb_character(&std::fs::read(&out).unwrap(), "animated.glb");
    let uncompressed = glb_character(&plain_bytes, "animated-plain.glb");
    assert_eq!(compressed.positions(), uncompressed.positions());
    // The index codec may rotate a triangle's corners (its winding kept).
    let turned = |c: &faceanim_rig::Character| -> Vec<[u32; 3]> {
        c.triangles()
            .iter()
            .map(|&[a, b, c]| match a.min(b).min(c) {
                m if m == a => [a, b, c],
                m if m == b => [b, c, a],
                _ => [c, a, b],
            })
            .collect()
    };
    assert_eq!(turned(&compressed), turned(&uncompressed));
    assert_eq!(
        compressed.blendshapes().len(),
        uncompressed.blendshapes().len()
    );
    let (a, b) = (
        compressed.source().unwrap().take().unwrap(),
        uncompressed.source().unwrap().take().unwrap(),
    );
    assert_eq!(a, b, "the animation reads back differently");
}

/// An avatar whose texture ships as KTX2 (`KHR_texture_basisu`, required), as asset pipelines
/// compress them, in both of Basis Universal's codecs, made by Binomial's own encoder: ETC1S
/// with BasisLZ and UASTC with Zstandard. The texture is read and decodes to the picture that
/// was encoded (within the codec's loss: a 256-pixel grainy checker), the renderer (the face's
/// renders for the retarget map and the adapter) draws it, the studio's view carries it as PNG
/// so that browsers show it without a transcoder, and the export keeps the user's KTX2.
#[test]
fn ktx2_textures_are_decoded_drawn_shown_and_kept() {
    let dir = output_dir("avatars-ktx2");
    let plain = full_body_glb_textured(ict(), VrmKind::None, &[], 256);
    let texture_of = |c: &faceanim_rig::Character| {
        c.materials()
            .iter()
            .find_map(|m| m.base_color_texture.clone())
            .expect("the outfit's texture")
    };
    let encoded = texture_of(&glb_character(&plain, "plain.glb"));
    let picture = faceanim_media::decode_image(Path::new("outfit.png"), &encoded.bytes).unwrap();
    let clip = clip(&dir);
    // Mean absolute error per channel (0..255) each codec is allowed on the picture's pixels
    // (ETC1S drops the grain, as it is made to) and on its 8×8 blocks' means (what a codec
    // keeps; a decoder that misread blocks, endpoints or colours would be far off).
    for (uastc, codec, loss, block_loss) in [(false, "etc1s", 20.0, 4.0), (true, "uastc", 3.0, 1.0)]
    {
        let packed = ktx2(&plain, uastc);
        let file = dir.join(format!("avatar-{codec}.glb"));
        std::fs::write(&file, &packed).unwrap();
        let required = json_chunk(&file)["extensionsRequired"].to_string();
        assert!(
            required.contains("KHR_texture_basisu"),
            "{codec}: {required}"
        );
        let character = glb_character(&packed, "avatar-ktx2.glb");
        let texture = texture_of(&character);
        assert_eq!(texture.mime_type, "image/ktx2", "{codec}");
        let decoded = faceanim_media::decode_image(&file, &texture.bytes).unwrap();
        assert_eq!(
            (decoded.width, decoded.height),
            (picture.width, picture.height),
            "{codec}"
        );
        let error = decoded
            .rgb
            .iter()
            .zip(&picture.rgb)
            .map(|(&a, &b)| f64::from(a.abs_diff(b)))
            .sum::<f64>()
            / picture.rgb.len() as f64;
        let blocks = block_means(&decoded);
        let block_error = blocks
            .iter()
            .zip(block_means(&picture))
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            / blocks.len() as f64;
        eprintln!(
            "{codec}: mean error {error:.2} of 255 per channel, {block_error:.2} on 8×8 blocks"
        );
        assert!(
            error < loss,
            "{codec}: the KTX2 decodes {error:.2} away from the picture"
        );
        assert!(
            block_error < block_loss,
            "{codec}: the KTX2's 8×8 blocks decode {block_error:.2} away from the picture's"
        );
        let view = dir.join(format!("view-{codec}.glb"));
        drawn_and_viewed(&character, &view);
        let shown = json_chunk(&view);
        assert!(
            shown["images"]
                .as_array()
                .unwrap()
                .iter()
                .all(|i| i["mimeType"] == "image/png"),
            "{codec}: {}",
            shown["images"]
        );
        let out = dir.join(format!("animated-{codec}.glb"));
        export_with_clip(&file, &out, &clip);
        assert_valid_gltf(&out);
        let kept = json_chunk(&out);
        assert!(
            kept["extensionsRequired"]
                .to_string()
                .contains("KHR_texture_basisu"),
            "{codec}: {}",
            kept["extensionsRequired"]
        );
        assert_eq!(
            texture_of(&glb_character(&std::fs::read(&out).unwrap(), "out.glb")).bytes,
            texture.bytes,
            "{codec}: the export re-encoded the user's texture"
        );
    }
}

/// Asserts that faceanim's software renderer draws `character`'s textures without a warning,
/// and writes the studio's view of it to `view`: the validator's report, which has no errors.
fn drawn_and_viewed(character: &faceanim_rig::Character, view: &Path) -> Value {
    let appearance = faceanim_render::Appearance::of(character);
    assert!(
        appearance.warnings().is_empty(),
        "{}: {:?}",
        view.display(),
        appearance.warnings()
    );
    std::fs::write(view, faceanim_export::view_glb(character, None).unwrap()).unwrap();
    assert_valid_gltf(view)
}

/// The mean of each channel over each 8×8 block of `image` (its sides a multiple of 8).
fn block_means(image: &faceanim_media::Image) -> Vec<f64> {
    let mut means = Vec::new();
    for by in (0..image.height).step_by(8) {
        for bx in (0..image.width).step_by(8) {
            for c in 0..3 {
                let sum: u32 = (by..by + 8)
                    .flat_map(|y| (bx..bx + 8).map(move |x| (y, x)))
                    .map(|(y, x)| u32::from(image.rgb[(y * image.width + x) * 3 + c]))
                    .sum();
                means.push(f64::from(sum) / 64.0);
            }
        }
    }
    means
}

/// The character in a GLB's bytes, named `name`.
fn glb_character(bytes: &[u8], name: &str) -> faceanim_rig::Character {
    faceanim_rig::import::import_gltf(bytes, name, &faceanim_rig::import::NoExternalResources)
        .unwrap()
        .character
}
