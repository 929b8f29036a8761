//! Avatars that no line of faceanim wrote: a full-body character built by Blender 3.4's Python
//! API and written by Blender's own glTF exporter (`tools/blender_avatar.py`, run headless by
//! the test setup: three meshes, one primitive per material each with its own vertices, the
//! face's 108 shape keys on all of its 12 primitives, two skins, a rig in centimetres under a
//! 0.01 scale, `KHR_materials_*`), the same made a VRM 0.x and a VRM 1.0 by adding the
//! extension's JSON as UniVRM lays it out, and compressed by gltfpack and by gltf-transform
//! (meshopt, and Draco, which faceanim decodes natively), made sparse by gltf-transform (its
//! shape keys that leave a primitive still are accessors without data), and saved again by
//! three.js's GLTFExporter, as web editors save it.
//! Each imports, `faceanim info` lists its shapes with what drives them by name, capture by
//! name moves it, strokes through the studio's API animate it, and the export is the user's
//! file with the animation added: counts and names kept, the Khronos validator passes it,
//! Blender reopens it with both armatures and every shape key, three.js plays it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::float_cmp,
    reason = "tests panic to fail, and a shape not driven stays exactly 0"
)]

mod support;

use std::path::{Path, PathBuf};

use faceanim_testdata::avatar::VrmKind;
use faceanim_testdata::glb::assert_kept;
use faceanim_testdata::producers::{
    BLENDER_AVATAR_EXPRESSIONS, Variant, blender_avatar, complete_vrm, with_vrm,
};
use faceanim_testdata::{gltf_transform, gltfpack};
use serde_json::Value;
use support::{
    assert_avatar_drawn, assert_valid_gltf, blender_report, export_with_clip, faceanim_ok,
    output_dir, request, request_bytes, start_on, stroke_along, threejs_render, track_clip,
};

/// The Blender avatar's shape keys.
const SHAPE_KEYS: usize = 108;

/// The seven files, written into `dir`: (file, is a VRM, compressed).
fn variants(dir: &Path) -> Vec<(PathBuf, bool, bool)> {
    let plain = blender_avatar();
    let files: [(&str, Vec<u8>, bool, bool); 7] = [
        ("blender.glb", plain.to_vec(), false, false),
        ("blender-0.vrm", with_vrm(plain, VrmKind::V0), true, false),
        ("blender-1.vrm", with_vrm(plain, VrmKind::V1), true, false),
        (
            "blender-gltfpack.glb",
            gltfpack(plain, &["-cc", "-kn", "-km"]),
            false,
            true,
        ),
        (
            "blender-gltf-transform.glb",
            gltf_transform(plain, "meshopt"),
            false,
            true,
        ),
        (
            "blender-draco.glb",
            gltf_transform(plain, "draco"),
            false,
            true,
        ),
        // Made sparse as `gltf-transform optimize` makes it: a shape key that does not move
        // one of the face's primitives is an accessor with no data (all zeros, as the
        // specification reads it), which the `gltf` crate's validation refused.
        (
            "blender-sparse.glb",
            gltf_transform(plain, "sparse"),
            false,
            false,
        ),
    ];
    files
        .into_iter()
        .map(|(name, bytes, vrm, compressed)| {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            (path, vrm, compressed)
        })
        .collect()
}

fn info(file: &Path) -> Value {
    serde_json::from_str(&faceanim_ok(&["info", file.to_str().unwrap(), "--json"])).unwrap()
}

fn shape<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["blendshapes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["name"] == name)
        .unwrap_or_else(|| panic!("no {name} in {report}"))
}

#[test]
fn blender_avatars_import_with_every_shape_and_say_what_drives_each() {
    let dir = output_dir("made-by-others-info");
    for (file, vrm, compressed) in variants(&dir) {
        let what = file.display().to_string();
        let report = info(&file);
        let shapes = report["blendshapes"].as_array().unwrap();
        let expected = SHAPE_KEYS
            + if vrm {
                BLENDER_AVATAR_EXPRESSIONS.len()
            } else {
                0
            };
        assert_eq!(shapes.len(), expected, "{what}");
        if !compressed {
            assert_eq!(report["file"]["meshes"], 3, "{what}");
            assert_eq!(report["file"]["skins"], 2, "{what}");
            assert_eq!(report["file"]["materials"], 19, "{what}");
        }
        // A full body: the head box frames the face, about 1.45 m up.
        let head = &report["head"];
        assert!(head["min"][1].as_f64().unwrap() > 1.3, "{what}: {head}");
        // The face's shapes move where the face is: the jaw by centimetres, teeth-only keys.
        assert!(
            shape(&report, "jawOpen")["max_displacement"]
                .as_f64()
                .unwrap()
                > 0.01
        );
        assert!(shape(&report, "Fcl_HA_Hide")["moved"].as_u64().unwrap() > 0);
        // The name table: ARKit's single browInnerUp drives ICT's halves; VRoid's duplicates
        // give way to the ARKit-named shapes.
        let brow = &shape(&report, "browInnerUp_L")["arkit"];
        assert_eq!(brow["kind"], "split", "{what}: {brow}");
        assert_eq!(brow["driven"], true, "{what}: {brow}");
        let close = &shape(&report, "Fcl_EYE_Close_L")["arkit"];
        assert_eq!(close["driven"], false, "{what}: {close}");
        assert_eq!(
            report["undriven_channels"],
            serde_json::json!(["tongueOut"]),
            "{what}"
        );
        if vrm {
            assert_eq!(shape(&report, "aa")["arkit"]["driven"], false, "{what}");
        }
        // Left and right found on a real (slightly asymmetric) face.
        assert!(report["pairs"].as_array().unwrap().len() >= 22, "{what}");
    }
}

/// A primitive that its exporter left without the morph targets its siblings carry (the
/// Blender avatar's teeth, with their targets taken out) reads as not moving, and the export
/// gives it zero targets so that the file written is valid glTF.
#[test]
fn a_primitive_without_its_siblings_targets_imports_and_exports_valid() {
    let dir = output_dir("made-by-others-partial-targets");
    let (mut root, bin) = faceanim_testdata::glb::parts(blender_avatar());
    let face = faceanim_testdata::glb::index_of(&root, "meshes", "Face").unwrap();
    let primitive = &mut root["meshes"][face]["primitives"][4];
    primitive.as_object_mut().unwrap().remove("targets");
    let file = dir.join("partial.glb");
    std::fs::write(&file, faceanim_testdata::glb::assemble(&root, &bin)).unwrap();
    let report = info(&file);
    assert_eq!(report["blendshapes"].as_array().unwrap().len(), SHAPE_KEYS);
    let out = dir.join("partial-animated.glb");
    export_with_clip(&file, &out, &clip(&dir));
    assert_valid_gltf(&out);
    let written = faceanim_testdata::glb::json(&std::fs::read(&out).unwrap());
    assert_eq!(
        written["meshes"][face]["primitives"][4]["targets"]
            .as_array()
            .map(Vec::len),
        Some(SHAPE_KEYS)
    );
}

/// A ten-second clip over names in three conventions: ARKit's, ICT's and VRoid's.
fn clip(dir: &Path) -> PathBuf {
    let frames: Vec<Value> = (0..300)
        .map(|f| {
            let t = f as f32 / 30.0;
            let jaw = (0.5 - 0.5 * (t * 1.3).cos()).clamp(0.0, 1.0);
            let blink = if (t % 3.0) < 0.2 { 1.0 } else { 0.0 };
            serde_json::json!([jaw, t / 10.0, blink, blink, 1.0 - jaw])
        })
        .collect();
    let path = dir.join("ten-seconds.json");
    let clip = serde_json::json!({ "fps": 30, "blendshapes": ["jawOpen", "mouthSmile_L", "eyeBlink_L", "eyeBlink_R", "Fcl_MTH_U"], "frames": frames });
    std::fs::write(&path, clip.to_string()).unwrap();
    path
}

#[test]
fn exports_of_blender_avatars_keep_the_file_and_open_everywhere() {
    let dir = output_dir("made-by-others-export");
    let clip = clip(&dir);
    let mut outputs = Vec::new();
    for (file, vrm, _) in variants(&dir) {
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let out = dir.join(format!("{stem}-animated.glb"));
        export_with_clip(&file, &out, &clip);
        let report = assert_valid_gltf(&out);
        assert_eq!(report["info"]["animationCount"], 1, "{}", out.display());
        let input = faceanim_testdata::glb::json(&std::fs::read(&file).unwrap());
        let output = faceanim_testdata::glb::json(&std::fs::read(&out).unwrap());
        assert_kept(&input, &output, &out.display().to_string());
        let used = output["extensionsUsed"].to_string();
        for extension in [
            "KHR_materials_clearcoat",
            "KHR_materials_specular",
            "KHR_materials_ior",
        ] {
            assert!(used.contains(extension), "{}: {used}", out.display());
        }
        if vrm {
            assert!(used.contains("VRM"), "{used}");
        }
        outputs.push(out);
    }

    // gltfpack's and gltf-transform's meshopt files come back meshopt-compressed, as they were
    // read; `--uncompressed` writes gltfpack's plain, for Blender, whose importer has no
    // meshopt decoder.
    for out in [&outputs[3], &outputs[4]] {
        let output = faceanim_testdata::glb::json(&std::fs::read(out).unwrap());
        assert!(
            output["extensionsRequired"]
                .to_string()
                .contains("EXT_meshopt_compression"),
            "{}: {}",
            out.display(),
            output["extensionsRequired"]
        );
    }
    let plain = dir.join("blender-gltfpack-plain.glb");
    support::export_with_clip_and(
        &dir.join("blender-gltfpack.glb"),
        &plain,
        &clip,
        &["--uncompressed"],
    );

    // Blender 3.4 reopens the plain, the VRM 1.0 and gltfpack's exports with both armatures,
    // the face's every shape key (on one object), and the animation.
    for out in [&outputs[0], &outputs[2], &plain] {
        let report = blender_report(out);
        let armatures = report["armatures"].as_array().unwrap();
        assert_eq!(armatures.len(), 2, "{report}");
        let face = report["objects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| !o["shape_keys"].as_array().unwrap().is_empty())
            .unwrap_or_else(|| panic!("{report}"));
        assert_eq!(
            face["shape_keys"].as_array().unwrap().len(),
            SHAPE_KEYS,
            "{report}"
        );
        assert!(
            !report["actions"].as_array().unwrap().is_empty(),
            "{report}"
        );
    }

    // three.js in Chromium (with meshoptimizer's own decoder): every primitive skinned, both
    // rigs' bones, the face moving; the sparse file's export too, its accessors without data
    // kept as they were.
    for out in [&outputs[0], &outputs[1], &outputs[4], &outputs[6]] {
        assert_avatar_drawn(&threejs_render(out, "2.4"), 19, 13, 5_000);
    }
}

/// The Blender avatar as a web editor saves it: loaded and written again by three.js's own
/// GLTFLoader and GLTFExporter (`tools/threejs-export.mjs`: one mesh and one skin per
/// primitive, shape names in each mesh's `extras.targetNames`). It imports with every shape
/// and bone; its export with an animation is valid and keeps the file; and an animation
/// faceanim wrote, saved again by three.js (its weight tracks now on each of the face's meshes),
/// opens again as the same take.
#[test]
fn an_avatar_saved_by_threejs_imports_exports_and_opens_again() {
    let dir = output_dir("made-by-others-threejs");
    let plain = dir.join("blender.glb");
    std::fs::write(&plain, blender_avatar()).unwrap();
    let three = dir.join("blender-threejs.glb");
    std::fs::write(&three, faceanim_testdata::threejs(blender_avatar())).unwrap();
    let report = info(&three);
    assert_eq!(
        report["blendshapes"].as_array().unwrap().len(),
        SHAPE_KEYS,
        "{report}"
    );
    assert_eq!(report["file"]["meshes"], 19, "a mesh per primitive");
    assert!(
        shape(&report, "jawOpen")["max_displacement"]
            .as_f64()
            .unwrap()
            > 0.01
    );
    assert_eq!(
        report["undriven_channels"],
        serde_json::json!(["tongueOut"])
    );
    for (bone, name) in [("head", "Head"), ("jaw", "Jaw"), ("left_eye", "LeftEye")] {
        assert_eq!(report["file"]["bones"][bone], name, "{report}");
    }
    let clip = clip(&dir);
    let animated = dir.join("blender-threejs-animated.glb");
    export_with_clip(&three, &animated, &clip);
    let validated = assert_valid_gltf(&animated);
    assert_eq!(validated["info"]["animationCount"], 1);
    assert_kept(
        &faceanim_testdata::glb::json(&std::fs::read(&three).unwrap()),
        &faceanim_testdata::glb::json(&std::fs::read(&animated).unwrap()),
        &animated.display().to_string(),
    );
    // Ours, saved again by three.js, is the same take.
    let ours = dir.join("blender-animated.glb");
    export_with_clip(&plain, &ours, &clip);
    let ours = std::fs::read(&ours).unwrap();
    let written = faceanim_export::reopen::clip_of_file("blender-animated.glb", &ours).unwrap();
    let resaved = faceanim_testdata::threejs(&ours);
    let back = faceanim_export::reopen::clip_of_file("resaved.glb", &resaved).unwrap();
    assert_eq!(back.clip.fps, written.clip.fps);
    assert_eq!(back.clip.frames.len(), written.clip.frames.len());
    let mut moving = 0;
    for (c, name) in written.clip.blendshapes.iter().enumerate() {
        if written.clip.frames.iter().all(|row| row[c] == 0.0) {
            continue;
        }
        moving += 1;
        let k = back
            .clip
            .column(name)
            .unwrap_or_else(|| panic!("{name} was not read back"));
        for (row, again) in written.clip.frames.iter().zip(&back.clip.frames) {
            assert!(
                (row[c] - again[k]).abs() < 1e-4,
                "{name}: {} then {}",
                row[c],
                again[k]
            );
        }
    }
    assert!(moving >= 4, "{moving} shapes move");
}

/// By name, a photo of a smiling person moves the ARKit-named smile on the Blender avatar and
/// neither VRoid's duplicate keys nor the VRM's expressions, which bind those keys.
#[test]
fn capture_by_name_drives_the_blender_avatar_once() {
    let dir = output_dir("made-by-others-capture");
    let photo = faceanim_testdata::shared("images/astronaut.png");
    for (file, vrm, _) in variants(&dir).into_iter().take(3) {
        let out = dir.join(format!(
            "{}.json",
            file.file_stem().unwrap().to_string_lossy()
        ));
        let clip = track_clip(&photo, &file, &[], &out);
        let names = support::strings(&clip["blendshapes"]);
        let peak = |name: &str| {
            let i = names.iter().position(|n| *n == name).unwrap();
            clip["frames"]
                .as_array()
                .unwrap()
                .iter()
                .map(|row| row[i].as_f64().unwrap())
                .fold(0.0, f64::max)
        };
        let what = file.display();
        assert!(
            peak("mouthSmile_L") > 0.3 && peak("mouthSmile_R") > 0.3,
            "{what}"
        );
        for duplicate in ["Fcl_MTH_Joy", "Fcl_EYE_Close_L", "Fcl_ALL_Joy"] {
            assert_eq!(peak(duplicate), 0.0, "{what}: {duplicate}");
        }
        if vrm {
            assert_eq!(peak("happy"), 0.0, "{what}: happy binds Fcl_ALL_Joy");
        }
    }
}

/// The studio on the Blender avatar: a stroke drawn through the HTTP API from the chin down
/// opens the jaw, and the studio's GLB download is the user's file with the animation.
#[test]
fn strokes_through_the_studio_api_animate_the_blender_avatar() {
    let dir = output_dir("made-by-others-studio");
    for stale in ["project.json", ".project.json.autosave"] {
        let _ = std::fs::remove_file(dir.join(stale));
    }
    let file = dir.join("blender.glb");
    std::fs::write(&file, blender_avatar()).unwrap();
    let character = faceanim_testdata::producers::blender_avatar_character();
    let stroke = stroke_along(&character, "jawOpen", 45, 1.0 / 90.0);

    let studio = start_on(Some(&file), &dir.join("project.json"), &[]);
    // The page's view keeps the brows cut out by their alpha (glTF MASK, as Blender wrote
    // them from an alpha-clip material), so lashes and brows are not drawn as blocks.
    let (status, view) = request_bytes(studio.port, "GET", "/api/view.glb", &[], b"");
    assert_eq!(status, 200);
    let view = faceanim_testdata::glb::json(&view);
    let brows = faceanim_testdata::glb::index_of(&view, "materials", "Face_Brows")
        .map(|i| &view["materials"][i])
        .unwrap_or_else(|| panic!("{}", view["materials"]));
    assert_eq!(brows["alphaMode"], "MASK", "{brows}");
    assert!(
        (brows["alphaCutoff"].as_f64().unwrap() - 0.4).abs() < 1e-6,
        "{brows}"
    );
    let (status, state) = request(studio.port, "POST", "/api/strokes", &[], stroke.as_bytes());
    assert_eq!(status, 200, "{state}");
    let (status, download) = request_bytes(studio.port, "GET", "/api/export.glb", &[], b"");
    assert_eq!(status, 200);
    drop(studio);
    let state: Value = serde_json::from_str(&state).unwrap();
    let action = &state["actions"][0];
    assert_eq!(action["sides"][0]["target"], "jawOpen", "{state}");
    assert!(
        action["sides"][0]["weight"].as_f64().unwrap() > 0.9,
        "{state}"
    );
    let exported = dir.join("studio-export.glb");
    std::fs::write(&exported, download).unwrap();
    let report = assert_valid_gltf(&exported);
    assert_eq!(report["info"]["animationCount"], 1, "{report}");
    let input = faceanim_testdata::glb::json(blender_avatar());
    let output = faceanim_testdata::glb::json(&std::fs::read(&exported).unwrap());
    assert_kept(&input, &output, "the studio's download");
}

/// What Blender reads back of `file`'s bones at `seconds`: each named bone's turn from rest
/// in glTF's frame (Y up), as a quaternion (`tools/blender_bones.py`, Blender's own importer).
fn blender_bone_turns(file: &Path, seconds: f32, bones: &[&str]) -> Vec<(String, glam::Quat)> {
    blender_bone_turns_at(file, &[seconds], bones)
        .pop()
        .unwrap()
}

/// [`blender_bone_turns`] at each of `times` (seconds), from one Blender run.
fn blender_bone_turns_at(
    file: &Path,
    times: &[f32],
    bones: &[&str],
) -> Vec<Vec<(String, glam::Quat)>> {
    let times = times
        .iter()
        .map(f32::to_string)
        .collect::<Vec<_>>()
        .join(",");
    let mut arguments = vec![file.as_os_str(), times.as_ref()];
    arguments.extend(bones.iter().map(std::ffi::OsStr::new));
    let report = support::blender_script("blender_bones.py", &arguments, "FACEANIM_BONES ");
    // Blender holds glTF's +Y as +Z: a turn in Blender's world is C·q·C⁻¹ with C = Rx(90°).
    let c = glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    report["at"]
        .as_array()
        .unwrap()
        .iter()
        .map(|at| {
            bones
                .iter()
                .map(|bone| {
                    let q = &at[*bone];
                    let q = glam::Quat::from_xyzw(
                        q[1].as_f64().unwrap() as f32,
                        q[2].as_f64().unwrap() as f32,
                        q[3].as_f64().unwrap() as f32,
                        q[0].as_f64().unwrap() as f32,
                    );
                    ((*bone).to_owned(), c.inverse() * q * c)
                })
                .collect()
        })
        .collect()
}

/// The angle between two rotations, in degrees.
fn degrees_between(a: glam::Quat, b: glam::Quat) -> f32 {
    2.0 * a.dot(b).abs().min(1.0).acos().to_degrees()
}

/// The Blender avatar made a VRM 0.x (its scene turned to face −Z, lookAt by bone with the
/// specification's default curves: 90° of gaze turns the eyes 10°) and a VRM 1.0: a head pose
/// and a gaze written onto each as bones open again as the same head pose and eyeLook values.
#[test]
fn head_and_gaze_come_back_from_vrm_bones() {
    let dir = output_dir("made-by-others-vrm-bones");
    let head = [-25.0f32, 12.0, -6.0];
    let looks = [
        "eyeLookIn_L",
        "eyeLookOut_R",
        "eyeLookDown_L",
        "eyeLookDown_R",
    ];
    let written = [0.8f32, 0.8, 0.5, 0.5];
    let clip = serde_json::json!({
        "fps": 30,
        "blendshapes": looks,
        "frames": vec![written; 6],
        "head": vec![head; 6],
    });
    let clip_path = dir.join("look.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    for kind in [VrmKind::V0, VrmKind::V1] {
        let name = format!("{kind:?}.vrm");
        let avatar = dir.join(format!("avatar-{name}"));
        std::fs::write(&avatar, with_vrm(blender_avatar(), kind)).unwrap();
        let out = dir.join(&name);
        export_with_clip(&avatar, &out, &clip_path);
        let values: Vec<(&str, f32)> = looks.into_iter().zip(written).collect();
        assert_reopened(&name, &std::fs::read(&out).unwrap(), head, &values);
    }
}

/// A clip exported as a VRM Animation (`.vrma`) for the Blender avatar made a VRM 1.0 and a VRM
/// 0.x (with the arms and feet VRM requires), played by pixiv's three-vrm-animation on that
/// avatar: each key's mouth and custom expression reach the face's morph targets as the clip
/// moves them (a raw target, `Fcl_MTH_A`, through the expression binding it, `aa`; the ARKit
/// blink shape through `blinkLeft`), the head turns as the clip's head pose, and the gaze is
/// the clip's eyeLook values' gaze. A shape no expression binds is named in a note. The VRM
/// 1.0 file opens again in the studio as the same take.
#[test]
fn a_vrm_animation_plays_on_the_avatar_in_three_vrm() {
    let dir = output_dir("made-by-others-vrma");
    let names: Vec<&str> = "Fcl_MTH_A ih surprised eyeBlinkLeft eyeLookOutLeft eyeLookInRight \
                            eyeLookUpLeft eyeLookUpRight mouthSmileLeft"
        .split_whitespace()
        .collect();
    let frames: Vec<[f32; 9]> = (0..45)
        .map(|k| {
            let t = k as f32 / 30.0;
            let side = (t * 3.0).sin().max(0.0) * 0.7;
            [
                (t * 4.0).sin().max(0.0),
                (-(t * 4.0).sin()).max(0.0) * 0.8,
                if k > 30 { 0.6 } else { 0.0 },
                if (10..16).contains(&k) { 1.0 } else { 0.0 },
                side,
                side,
                0.3,
                0.3,
                0.4,
            ]
        })
        .collect();
    let heads: Vec<[f32; 3]> = (0..45)
        .map(|k| {
            let t = k as f32 / 30.0;
            [
                25.0 * (t * 2.0).sin(),
                12.0 * (t * 3.0).sin(),
                6.0 * t.sin(),
            ]
        })
        .collect();
    let clip_path = dir.join("take.json");
    std::fs::write(
        &clip_path,
        serde_json::json!({ "fps": 30, "blendshapes": names, "frames": frames, "head": heads })
            .to_string(),
    )
    .unwrap();
    for kind in [VrmKind::V1, VrmKind::V0] {
        let avatar = dir.join(format!("avatar-{kind:?}.vrm"));
        std::fs::write(&avatar, complete_vrm(&with_vrm(blender_avatar(), kind))).unwrap();
        let out = dir.join(format!("take-{kind:?}.vrma"));
        let said = support::export_with_clip_and(&avatar, &out, &clip_path, &[]);
        // The avatar's own eyeBlink_L is in no expression: it closes the lids through
        // blinkLeft. Its smile shape has no expression to go through.
        let carried = said
            .lines()
            .find(|l| l.contains("carries 4 VRM expressions ("))
            .unwrap_or_else(|| panic!("{said}"));
        for part in [
            "aa",
            "blinkLeft",
            "ih",
            "surprised",
            "the head's turn (chest, neck, head)",
            "the gaze (lookAt)",
        ] {
            assert!(carried.contains(part), "{carried}");
        }
        assert!(
            said.contains("eyeBlink_L, in no VRM expression, closes the lids through blinkLeft"),
            "{said}"
        );
        assert!(said.contains("1 shape the animation moves is in no VRM expression, which is all a VRM Animation moves: mouthSmile_L"), "{said}");
        assert_valid_gltf(&out);
        let played = support::vrma_played(&avatar, &out);
        // three-vrm says nothing of the animation (it warns of a T-pose it violates, a track
        // it ignores); of the avatar's VRM 0.x lookAt curves it may.
        for warning in played["warnings"].as_array().unwrap() {
            assert!(
                !warning.as_str().unwrap().contains("Animation"),
                "{kind:?}: {warning}"
            );
        }
        assert_eq!(played["times"].as_array().unwrap().len(), frames.len());
        // Every primitive of the face holding a target shows it as the clip moves it.
        let influences = |target: &str| -> Vec<Vec<f64>> {
            played["morphs"]
                .as_object()
                .unwrap()
                .values()
                .filter_map(|m| m.get(target))
                .map(|v| {
                    v.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect()
                })
                .collect()
        };
        for (target, column) in [
            ("Fcl_MTH_A", 0),
            ("Fcl_MTH_I", 1),
            ("Fcl_ALL_Surprised", 2),
            ("Fcl_EYE_Close_L", 3),
        ] {
            let shown = influences(target);
            assert!(!shown.is_empty(), "{kind:?}: no mesh shows {target}");
            for primitive in shown {
                for (k, (got, row)) in primitive.iter().zip(&frames).enumerate() {
                    assert!(
                        (got - f64::from(row[column])).abs() < 2e-3,
                        "{kind:?} {target} at key {k}: {got} for {}",
                        row[column]
                    );
                }
            }
        }
        // The head's turn, in the file's space: a VRM 0.x faces −Z, so the turn is seen half a
        // turn about Y.
        let half = if kind == VrmKind::V0 {
            glam::Quat::from_rotation_y(std::f32::consts::PI)
        } else {
            glam::Quat::IDENTITY
        };
        for (k, (q, angles)) in played["head"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&heads)
            .enumerate()
        {
            let got = glam::Quat::from_slice(&support::f32s(q));
            let want = half
                * glam::Quat::from_array(faceanim_anim::head_rotation(*angles))
                * half.inverse();
            let off = degrees_between(got, want);
            assert!(off < 0.5, "{kind:?} head at key {k}: {off}° off");
        }
        if kind == VrmKind::V1 {
            assert_opens_again_in_the_studio(&avatar, &out, &frames, &heads);
            assert_opens_on_an_arkit_head(&out, &frames);
            // Without a head pose the humanoid still stands at its height (three-vrm warns
            // of a VRM Animation whose hips rest on the floor), and turns nothing.
            let still = dir.join("still.json");
            std::fs::write(
                &still,
                serde_json::json!({ "fps": 30, "blendshapes": names, "frames": frames })
                    .to_string(),
            )
            .unwrap();
            let out = dir.join("still.vrma");
            support::export_with_clip_and(&avatar, &out, &still, &[]);
            let played = support::vrma_played(&avatar, &out);
            assert_eq!(
                played["warnings"],
                serde_json::json!([]),
                "{}",
                played["warnings"]
            );
            assert_eq!(played["humanBones"], serde_json::json!([]));
        }
        for (k, (look, row)) in played["lookAt"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&frames)
            .enumerate()
        {
            let value = |channel: &str| {
                names
                    .iter()
                    .position(|n| *n == channel)
                    .map_or(0.0, |c| row[c])
            };
            let [[ly, lp], [ry, rp]] = faceanim_rig::bones::gaze_from_arkit(value);
            let want = [0.5 * (ly + ry), 0.5 * (lp + rp)];
            for (axis, want) in want.into_iter().enumerate() {
                let got = look[axis].as_f64().unwrap() as f32;
                assert!(
                    (got - want).abs() < 0.05,
                    "{kind:?} gaze at key {k}: {look} for {want:?}"
                );
            }
        }
    }
}

/// `animation` (a `.vrma` of `frames` of `Fcl_MTH_A`, `ih`, `surprised`, eyeBlinkLeft and the
/// gaze, and `heads`) opened in the studio's Capture tab on `avatar` is a take of the same
/// expressions (`aa` for `Fcl_MTH_A`, which it binds), head pose and eyeLook values.
fn assert_opens_again_in_the_studio(
    avatar: &Path,
    animation: &Path,
    frames: &[[f32; 9]],
    heads: &[[f32; 3]],
) {
    let dir = animation.with_extension("studio");
    std::fs::create_dir_all(&dir).unwrap();
    let _ = std::fs::remove_file(dir.join("project.json"));
    let studio = start_on(Some(avatar), &dir.join("project.json"), &[]);
    support::open_and_settle(studio.port, animation);
    // Downloaded again, the take is a VRM Animation named after it, with the exporter's notes
    // (what it carries) for the page to show.
    let (head, again) = support::get_with_head(studio.port, "/api/capture/export.vrma");
    assert!(again.starts_with(b"glTF"), "{head}");
    let notes = head
        .lines()
        .find_map(|l| l.strip_prefix("x-faceanim-notes: "))
        .unwrap_or_else(|| panic!("no notes: {head}"));
    let notes: Vec<String> = serde_json::from_str(notes).unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("carries") && n.contains("aa")),
        "{notes:?}"
    );
    let stem = animation.file_stem().unwrap().to_str().unwrap();
    assert!(
        head.contains(&format!("filename*=UTF-8''{stem}.vrma")),
        "{head}"
    );
    let (status, clip) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{clip}");
    let clip: Value = serde_json::from_str(&clip).unwrap();
    assert_eq!(
        clip["frames"].as_array().unwrap().len(),
        frames.len(),
        "{clip}"
    );
    for (name, column) in [("aa", 0), ("ih", 1), ("surprised", 2)] {
        for (k, (got, row)) in support::column(&clip, name).iter().zip(frames).enumerate() {
            assert!(
                (got - f64::from(row[column])).abs() < 2e-3,
                "{name} at frame {k}: {got} for {}",
                row[column]
            );
        }
    }
    for (k, (got, want)) in clip["head"]
        .as_array()
        .unwrap()
        .iter()
        .zip(heads)
        .enumerate()
    {
        for axis in 0..3 {
            let got = got[axis].as_f64().unwrap() as f32;
            assert!(
                (got - want[axis]).abs() < 0.1,
                "head at frame {k}: {got} for {want:?}"
            );
        }
    }
    // Both eyes look left (out of the left, into the right) and up, as the clip's did.
    for (shape, column) in [("eyeLookOut_L", 4), ("eyeLookIn_R", 5), ("eyeLookUp_L", 6)] {
        for (k, (got, row)) in support::column(&clip, shape).iter().zip(frames).enumerate() {
            assert!(
                (got - f64::from(row[column])).abs() < 0.02,
                "{shape} at frame {k}: {got} for {}",
                row[column]
            );
        }
    }
}

/// `animation` (as [`assert_opens_again_in_the_studio`]) opened in the studio on the built-in
/// head, which has ARKit's shapes and no VRM expressions, reaches them by what each expression
/// is: `aa` the jaw, `ih` both stretches, `blinkLeft` the left lid, `surprised` the brows and
/// the eyes it is read from; no expression is left out.
fn assert_opens_on_an_arkit_head(animation: &Path, frames: &[[f32; 9]]) {
    let dir = animation.with_extension("arkit-studio");
    std::fs::create_dir_all(&dir).unwrap();
    let _ = std::fs::remove_file(dir.join("project.json"));
    let studio = start_on(None, &dir.join("project.json"), &[]);
    let state = support::open_and_settle(studio.port, animation);
    let notice = state["notice"].as_str().unwrap_or_default();
    assert!(!notice.contains("answers to"), "{state}");
    let (status, clip) = request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{clip}");
    let clip: Value = serde_json::from_str(&clip).unwrap();
    for (shape, column) in [
        ("jawOpen", 0),
        ("mouthStretchLeft", 1),
        ("mouthStretchRight", 1),
        ("eyeBlinkLeft", 3),
        ("browInnerUp", 2),
        ("eyeWideLeft", 2),
        ("eyeWideRight", 2),
    ] {
        let got = support::column(&clip, shape);
        assert_eq!(got.len(), frames.len(), "{shape}");
        for (k, (got, row)) in got.iter().zip(frames).enumerate() {
            assert!(
                (got - f64::from(row[column])).abs() < 2e-3,
                "{shape} at frame {k}: {got} for {}",
                row[column]
            );
        }
    }
}

/// `file` (its bytes, named `name`) opened again as a take holds the head pose `head` (within
/// 0.05°) and each `(shape, value)` (within 1e-3) at every frame.
fn assert_reopened(name: &str, file: &[u8], head: [f32; 3], values: &[(&str, f32)]) {
    let back = faceanim_export::reopen::clip_of_file(name, file).unwrap();
    let poses = back
        .clip
        .head
        .as_ref()
        .expect("the head pose was not read back");
    for pose in poses {
        for (read, written) in pose.iter().zip(head) {
            assert!(
                (read - written).abs() < 0.05,
                "{name}: head {pose:?}, written {head:?}"
            );
        }
    }
    for &(shape, written) in values {
        let c = back
            .clip
            .column(shape)
            .unwrap_or_else(|| panic!("{name}: no {shape}"));
        for row in &back.clip.frames {
            assert!(
                (row[c] - written).abs() < 1e-3,
                "{name}: {shape} {} for {written}",
                row[c]
            );
        }
    }
}

/// A head pose, gaze and an open jaw exported onto the Blender avatar's bones, read back by
/// Blender: the head turns by the whole pose, shared with the neck (half) and the chest (a share
/// of the yaw); both eyes look left and up on their bones; the jaw opens about its hinge.
#[test]
fn head_eyes_and_jaw_go_on_the_blender_avatars_bones() {
    let dir = output_dir("made-by-others-bones");
    let head = [30.0f32, -10.0, 5.0];
    let frames: Vec<Value> = (0..10)
        .map(|_| serde_json::json!([1.0, 1.0, 1.0, 1.0, 0.6]))
        .collect();
    let clip = serde_json::json!({
        "fps": 30,
        "blendshapes": ["eyeLookOut_L", "eyeLookIn_R", "eyeLookUp_L", "eyeLookUp_R", "jawOpen"],
        "frames": frames,
        "head": vec![head; 10],
    });
    let clip_path = dir.join("look.json");
    std::fs::write(&clip_path, clip.to_string()).unwrap();
    let avatar = faceanim_testdata::producers::blender_avatar_path();
    let out = dir.join("bones.glb");
    export_with_clip(&avatar, &out, &clip_path);
    assert_valid_gltf(&out);
    // `info` finds the bones and the animation just written.
    let info: Value =
        serde_json::from_str(&faceanim_ok(&["info", out.to_str().unwrap(), "--json"])).unwrap();
    let file = &info["file"];
    assert_eq!(file["animations"].as_array().unwrap().len(), 1, "{file}");
    assert!((file["animations"][0]["seconds"].as_f64().unwrap() - 0.3).abs() < 1e-3);
    let bones = [
        ("head", "Head"),
        ("neck", "Neck"),
        ("upper_spine", "Chest"),
        ("left_eye", "LeftEye"),
        ("right_eye", "RightEye"),
        ("jaw", "Jaw"),
    ];
    for (role, bone) in bones {
        assert_eq!(file["bones"][role], bone, "{file}");
    }
    let turns = blender_bone_turns(
        &out,
        0.1,
        &["Chest", "Neck", "Head", "LeftEye", "RightEye", "Jaw"],
    );
    let turn = |bone: &str| turns.iter().find(|(b, _)| b == bone).unwrap().1;
    let q = glam::Quat::from_array(faceanim_anim::head_rotation(head));
    // The head ends where the pose says, its turn shared down the spine.
    assert!(degrees_between(turn("Head"), q) < 0.5, "{turns:?}");
    let chest = glam::Quat::from_rotation_y((0.2 * 30.0f32).to_radians());
    assert!(degrees_between(turn("Chest"), chest) < 0.5, "{turns:?}");
    let neck = chest * glam::Quat::IDENTITY.slerp(chest.inverse() * q, 0.5);
    assert!(degrees_between(turn("Neck"), neck) < 0.5, "{turns:?}");
    // Both eyes to the character's left and up, as far as eyeLook 1 turns them, as the head
    // turned.
    let [sideways, up] = faceanim_rig::bones::EYE_RANGE;
    let look = glam::Quat::from_array(faceanim_anim::head_rotation([sideways, up, 0.0]));
    for eye in ["LeftEye", "RightEye"] {
        assert!(
            degrees_between(turn(eye), q * look) < 0.5,
            "{eye}: {turns:?}"
        );
    }
    // The jaw opens about the character's left-right axis, chin down, by a share of the angle
    // its own jawOpen shape opens.
    let (axis, angle) = (q.inverse() * turn("Jaw")).to_axis_angle();
    let opened = angle.to_degrees() * axis.x.signum();
    assert!(
        axis.x.abs() > 0.99,
        "the jaw turned about {axis}: {turns:?}"
    );
    assert!((0.6..=24.0).contains(&opened), "the jaw opened {opened}°");
    eprintln!("Blender read the jaw opened {opened:.1}° at jawOpen 0.6");

    // The eyes turn once: by bone, their eyeLook shapes held still in the file.
    let bytes = std::fs::read(&out).unwrap();
    let imported = faceanim_rig::import::import_gltf(
        &bytes,
        "bones.glb",
        &faceanim_rig::import::NoExternalResources,
    )
    .unwrap();
    let source = imported.character.source().unwrap();
    let stored = source.animations()[0].sample(source.shapes());
    let names = imported.character.blendshape_names();
    for name in ["eyeLookOut_L", "eyeLookIn_R", "eyeLookUp_L", "eyeLookUp_R"] {
        let c = names.iter().position(|n| n == name).unwrap();
        assert!(
            stored.weights.iter().all(|row| row[c] == 0.0),
            "{name} moves beside the eye bones"
        );
    }
    // Opened again, the take has its head pose and its gaze back from the bones.
    assert_reopened(
        "bones.glb",
        &bytes,
        head,
        &[
            ("eyeLookOut_L", 1.0),
            ("eyeLookIn_R", 1.0),
            ("eyeLookUp_L", 1.0),
            ("eyeLookUp_R", 1.0),
            ("eyeLookIn_L", 0.0),
            ("eyeLookDown_R", 0.0),
            ("jawOpen", 0.6),
        ],
    );
}

/// The Live Link Face CSV at `path`: its header and rows (the values after the timecode and
/// the count).
fn live_link_csv(path: &Path) -> (Vec<String>, Vec<Vec<f32>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .skip(2)
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').skip(2).map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// A real person captured onto a body whose face has no blendshapes (the Blender avatar
/// exported without shape keys, as Mixamo and Ready Player Me bodies come without morph
/// targets): `track` turns its head, eyes and jaw bones by the take's head pose, gaze and
/// jawOpen — MediaPipe's own readings of the person — and Blender plays them so at every
/// sampled frame; the clip JSON it writes turns them the same when exported again. The capture
/// was refused ("no shape … answers to MediaPipe's channels"), and any clip put on the body.
#[test]
fn a_capture_turns_the_head_eyes_and_jaw_of_a_body_with_no_shapes() {
    let dir = output_dir("made-by-others-capture-bones");
    // Eight seconds of a person talking and turning his head (yaw −8° to 22°), cut by ffmpeg.
    let video = dir.join("talking.mp4");
    support::cut_footage(faceanim_testdata::producers::CAP13, 16, 8, &video);
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let (glb, session) = (dir.join("bare.glb"), dir.join("bare.session.json"));
    let clip = dir.join("bare.json");
    let [glb_path, clip_path, session_path] = [&glb, &clip, &session].map(|p| p.to_str().unwrap());
    let outputs = ["-o", glb_path, "-o", clip_path, "--session", session_path];
    let more = [&["--filter", "none"][..], &outputs].concat();
    let summary = support::track_summary(&video, &bare, &more);
    assert_eq!(summary["blendshapes"], 0, "{summary}");
    let bones = faceanim_rig::bones::Bone::ALL.map(faceanim_rig::bones::Bone::name);
    assert_eq!(summary["bones"], serde_json::json!(bones), "{summary}");
    assert_valid_gltf(&glb);
    let session = faceanim_take::Session::from_json(&std::fs::read(&session).unwrap()).unwrap();
    let heads = session.clip().head.unwrap();
    let arkit = session.arkit_clip().unwrap();
    let channel = |name: &str| arkit.column(name).unwrap();
    let jaw_open = channel("jawOpen");
    let fps = arkit.fps;
    let sampled: Vec<usize> = (0..arkit.frames.len()).step_by(8).collect();
    let times: Vec<f32> = sampled.iter().map(|&f| f as f32 / fps).collect();
    let played = blender_bone_turns_at(&glb, &times, &["Head", "LeftEye", "RightEye", "Jaw"]);
    let (mut yaws, mut opens) = (Vec::new(), Vec::new());
    for (&f, turns) in sampled.iter().zip(&played) {
        let turn = |bone: &str| turns.iter().find(|(b, _)| b == bone).unwrap().1;
        let row = &arkit.frames[f];
        // The head ends where the take's head pose says.
        let q = glam::Quat::from_array(faceanim_anim::head_rotation(heads[f]));
        let off = degrees_between(turn("Head"), q);
        assert!(
            off < 0.5,
            "frame {f}: the head is {off}° from the take's pose"
        );
        // Each eye looks where MediaPipe's eyeLook scores say, as the head turned.
        let value = |name: &str| arkit.column(name).map_or(0.0, |c| row[c]);
        let gaze = faceanim_rig::bones::gaze_from_arkit(value);
        for (eye, [yaw, pitch]) in ["LeftEye", "RightEye"].into_iter().zip(gaze) {
            let look = glam::Quat::from_array(faceanim_anim::head_rotation([yaw, pitch, 0.0]));
            let off = degrees_between(turn(eye), q * look);
            assert!(
                off < 0.5,
                "frame {f}: {eye} is {off}° from the gaze {yaw}°, {pitch}°"
            );
        }
        // The jaw opens about the character's left-right axis by jawOpen.
        let (axis, angle) = (q.inverse() * turn("Jaw")).to_axis_angle();
        let want = row[jaw_open] * faceanim_export::bones::DEFAULT_JAW_DEGREES;
        let opened = angle.to_degrees();
        assert!(
            (opened - want).abs() < 1.0,
            "frame {f}: Blender reads the jaw {opened}° open for jawOpen {}",
            row[jaw_open]
        );
        assert!(
            opened < 0.1 || axis.x.abs() > 0.99,
            "the jaw turned about {axis}"
        );
        yaws.push(heads[f][0]);
        opens.push(row[jaw_open]);
    }
    // The person moves: the bones are not held at rest.
    let span = |v: &[f32]| {
        v.iter().copied().fold(f32::MIN, f32::max) - v.iter().copied().fold(f32::MAX, f32::min)
    };
    assert!(span(&yaws) > 10.0, "the head's yaw spans {}°", span(&yaws));
    assert!(span(&opens) > 0.15, "jawOpen spans {}", span(&opens));

    // The clip JSON holds what the bones follow: put on the body again, it turns them the same.
    let again = dir.join("again.glb");
    export_with_clip(&bare, &again, &clip);
    let replayed = blender_bone_turns_at(&again, &times, &["Head", "LeftEye", "RightEye", "Jaw"]);
    for ((&f, first), second) in sampled.iter().zip(&played).zip(&replayed) {
        for ((bone, a), (_, b)) in first.iter().zip(second) {
            let off = degrees_between(*a, *b);
            assert!(off < 0.1, "frame {f}: {bone} replayed {off}° away");
        }
    }
    // The file opens again as a take (the studio's Capture tab, `faceanim studio bare.glb`): the
    // head pose, gaze and jawOpen its bones were turned by. So does the file written again by
    // Blender's own exporter (as after polishing it there), which loses faceanim's marks,
    // keys the face at Blender's 24 fps and writes every other bone's rest as keys too.
    let polished = dir.join("bare-blender.glb");
    support::blender_script(
        "blender_bare.py",
        &[glb.as_os_str(), polished.as_os_str()],
        "FACEANIM_BARE ",
    );
    // The take's value at `t` seconds, between its frames.
    let at = |series: &dyn Fn(usize) -> f32, t: f32| {
        let x = (t * fps).clamp(0.0, (arkit.frames.len() - 1) as f32);
        let (a, u) = (x.floor() as usize, x.fract());
        let b = (a + 1).min(arkit.frames.len() - 1);
        series(a) + (series(b) - series(a)) * u
    };
    for file in [&glb, &polished] {
        let name = file.file_name().unwrap().to_string_lossy();
        let reopened =
            faceanim_export::reopen::clip_of_file(&name, &std::fs::read(file).unwrap()).unwrap();
        let back = &reopened.clip;
        let seconds = back.duration_seconds() - arkit.duration_seconds();
        assert!(seconds.abs() < 0.05, "{name}: {}", reopened.what);
        let back_head = back.head.as_ref().unwrap();
        for k in (0..back.frames.len()).step_by(8) {
            let t = k as f32 / back.fps;
            let value = |clip: &faceanim_anim::Clip, f: usize, name: &str| {
                clip.column(name).map_or(0.0, |c| clip.frames[f][c])
            };
            let then = |name: &str| at(&|f| value(&arkit, f, name), t);
            let head: [f32; 3] = std::array::from_fn(|i| at(&|f| heads[f][i], t));
            let off = degrees_between(
                glam::Quat::from_array(faceanim_anim::head_rotation(back_head[k])),
                glam::Quat::from_array(faceanim_anim::head_rotation(head)),
            );
            assert!(off < 0.1, "{name} at {t} s: the head reopened {off}° away");
            let jaw = (value(back, k, "jawOpen") - then("jawOpen").clamp(0.0, 1.0)).abs();
            assert!(jaw < 0.01, "{name} at {t} s: jawOpen reopened {jaw} away");
            let was = faceanim_rig::bones::gaze_from_arkit(then);
            let now = faceanim_rig::bones::gaze_from_arkit(|c| value(back, k, c));
            for (a, b) in was.iter().flatten().zip(now.iter().flatten()) {
                assert!(
                    (a - b).abs() < 0.1,
                    "{name} at {t} s: gaze {was:?} reopened {now:?}"
                );
            }
        }
    }
    // A clip that turns none of its bones is refused, naming what would give it shapes.
    let smile = dir.join("smile.json");
    std::fs::write(
        &smile,
        r#"{"fps": 30, "blendshapes": ["mouthSmileLeft"], "frames": [[1.0]]}"#,
    )
    .unwrap();
    let refused = support::faceanim(&[
        "export",
        bare.to_str().unwrap(),
        "--clip",
        smile.to_str().unwrap(),
        "-o",
        dir.join("smile.glb").to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && said.contains("generate-shapes"),
        "{said}"
    );
    eprintln!(
        "{} frames played: head yaw spans {:.1}°, jawOpen {:.2}",
        sampled.len(),
        span(&yaws),
        span(&opens)
    );
}

/// A real person captured onto a VRoid-style avatar (Blender's jaw-and-vowels avatar: `Fcl_*`
/// keys and no ARKit names, its eyeballs on eye bones) keeps the gaze its eye bones show in the
/// clip JSON `track` writes: put on the avatar again (`export --clip`), the eyes and the jaw
/// turn as in the take's own GLB, whose Live Link Face CSV comes back the same, and the studio
/// shows the clip as it shows the take's session; put on the ICT head, the clip's gaze moves its
/// eyeLook shapes. Before, the clip JSON held the avatar's own weights alone: exported again,
/// the eyes stared ahead (they had turned up to 18°), Live Link Face's eyeLook curves were
/// zeros, and so were the ICT head's eyeLook shapes.
#[test]
fn a_vroid_takes_clip_json_keeps_the_gaze_its_eye_bones_show() {
    let dir = support::fresh_output_dir("made-by-others-clip-gaze");
    let video = dir.join("talking.mp4");
    support::cut_footage(faceanim_testdata::producers::CAP13, 16, 4, &video);
    // Its own copy: the retarget map capture makes is saved beside it.
    let avatar = dir.join("vroid.glb");
    std::fs::copy(
        faceanim_testdata::producers::blender_avatar_variant(Variant::JawAndVowels),
        &avatar,
    )
    .unwrap();
    let [glb, clip, csv, session] =
        ["take.glb", "take.json", "take.csv", "take.session.json"].map(|n| dir.join(n));
    let path = |p: &PathBuf| p.to_str().unwrap().to_owned();
    let outputs = [
        "--filter",
        "none",
        "-o",
        &path(&glb),
        "-o",
        &path(&clip),
        "-o",
        &path(&csv),
        "--session",
        &path(&session),
    ];
    let summary = support::track_summary(&video, &avatar, &outputs);
    assert_eq!(summary["estimator"], "retarget", "{summary}");
    let kept: Value = serde_json::from_slice(&std::fs::read(&clip).unwrap()).unwrap();
    let rows = kept["arkit"]
        .as_array()
        .expect("the clip keeps no ARKit values");
    assert_eq!(rows.len(), kept["frames"].as_array().unwrap().len());

    let again = dir.join("again.glb");
    export_with_clip(&avatar, &again, &clip);
    let fps = kept["fps"].as_f64().unwrap() as f32;
    let times: Vec<f32> = (0..rows.len()).step_by(5).map(|f| f as f32 / fps).collect();
    let bones = ["Head", "LeftEye", "RightEye", "Jaw"];
    let played = blender_bone_turns_at(&glb, &times, &bones);
    let replayed = blender_bone_turns_at(&again, &times, &bones);
    let mut widest: f32 = 0.0;
    for ((t, first), second) in times.iter().zip(&played).zip(&replayed) {
        for ((bone, a), (_, b)) in first.iter().zip(second) {
            let off = degrees_between(*a, *b);
            assert!(off < 0.1, "at {t} s: {bone} replayed {off}° away");
        }
        let head = first[0].1;
        for (_, eye) in &first[1..3] {
            widest = widest.max(degrees_between(*eye, head));
        }
    }
    // The eyes did look about: staring ahead would not pass.
    println!("the eyes turned up to {widest:.1}° from the head, replayed the same");
    assert!(
        widest > 3.0,
        "the eyes turned at most {widest}° in the take"
    );

    // Live Link Face from the clip JSON is the take's own.
    let csv_again = dir.join("again.csv");
    export_with_clip(&avatar, &csv_again, &clip);
    let (header, first) = live_link_csv(&csv);
    let (header_again, second) = live_link_csv(&csv_again);
    assert_eq!(header, header_again);
    for (f, (a, b)) in first.iter().zip(&second).enumerate() {
        for ((name, x), y) in header.iter().zip(a).zip(b) {
            assert!((x - y).abs() < 1e-4, "frame {f}: {name} {x} came back {y}");
        }
    }

    // Put on another character (the ICT head, whose eyes move by their eyeLook shapes), the
    // kept values move the shapes the avatar's names left out.
    let other = dir.join("ict.json");
    export_with_clip(Path::new(&support::ict()), &other, &clip);
    let other: Value = serde_json::from_slice(&std::fs::read(&other).unwrap()).unwrap();
    let column = |name: &str| {
        other["blendshapes"]
            .as_array()
            .unwrap()
            .iter()
            .position(|n| n == name)
            .unwrap()
    };
    let mut looked: f64 = 0.0;
    for way in ["In", "Out", "Up", "Down"] {
        for (side, half) in [("Left", "L"), ("Right", "R")] {
            let shape = column(&format!("eyeLook{way}_{half}"));
            let channel = faceanim_rig::names::Channel::named(&format!("eyeLook{way}{side}"))
                .unwrap()
                .index();
            for (f, (row, made_of)) in other["frames"]
                .as_array()
                .unwrap()
                .iter()
                .zip(rows)
                .enumerate()
            {
                let (got, want) = (
                    row[shape].as_f64().unwrap(),
                    made_of[channel].as_f64().unwrap(),
                );
                assert!(
                    (got - want).abs() < 1e-4,
                    "frame {f}: eyeLook{way}_{half} {got}, the take's {want}"
                );
                looked = looked.max(got);
            }
        }
    }
    println!("the ICT head's eyeLook shapes reached {looked:.2}, as the take's values");
    assert!(
        looked > 0.1,
        "the ICT head's eyes looked at most {looked} any way"
    );

    // The studio opens the clip as it opens the take's session: the same joints turn.
    let studio = start_on(Some(&avatar), &dir.join("vroid.project.json"), &[]);
    let shown = |file: &Path| -> Vec<Vec<Vec<f32>>> {
        let (status, state) = support::open_path(studio.port, file);
        assert_eq!(status, 200, "{state}");
        let state: Value = serde_json::from_str(&state).unwrap();
        state["take"]["bones"]
            .as_array()
            .unwrap_or_else(|| panic!("no bones in the view: {state}"))
            .iter()
            .map(|joints| {
                joints
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(support::f32s)
                    .collect()
            })
            .collect()
    };
    let (from_clip, from_session) = (shown(&clip), shown(&session));
    drop(studio);
    assert_eq!(from_clip.len(), from_session.len());
    for (f, (a, b)) in from_clip.iter().zip(&from_session).enumerate() {
        for (j, (x, y)) in a.iter().zip(b).enumerate() {
            let off = degrees_between(glam::Quat::from_slice(x), glam::Quat::from_slice(y));
            assert!(
                off < 0.1,
                "frame {f}: joint {j} of the clip's view is {off}° from the session's"
            );
        }
    }
}

/// A face keyed on its bones by hand in Blender (`tools/blender_keyed_bones.py`: the jaw of
/// the body with no shape keys opened 12° and shut again over a second, Bezier curves, written
/// by Blender's exporter with every other bone's rest as keys) opens as a take whose jawOpen is
/// the jaw's angle over its 20° range at every frame Blender evaluates; a walk keyed the same
/// way (the hips moving, a leg swinging, the head turning) is no take of the face. Before, any
/// animation of bones alone that faceanim had not written was passed over.
#[test]
fn a_face_keyed_on_its_bones_in_blender_opens_as_a_take_and_a_walk_does_not() {
    let dir = output_dir("made-by-others-keyed-bones");
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let keyed = |kind: &str| {
        let out = dir.join(format!("{kind}.glb"));
        let arguments = [bare.as_os_str(), out.as_os_str(), kind.as_ref()];
        let report = support::blender_script(
            "blender_keyed_bones.py",
            &arguments,
            "FACEANIM_KEYED_BONES ",
        );
        let opened = faceanim_export::reopen::clip_of_file(
            &format!("{kind}.glb"),
            &std::fs::read(&out).unwrap(),
        );
        (report, opened)
    };
    let (report, opened) = keyed("jaw");
    let opened = opened.unwrap();
    let clip = &opened.clip;
    assert_eq!(clip.fps, 24.0, "{}", opened.what);
    let jaw = clip.column("jawOpen").expect("jawOpen");
    let degrees = f64::from(faceanim_export::bones::DEFAULT_JAW_DEGREES);
    let played = support::f32s(&report["jaw"]);
    assert_eq!(clip.frames.len(), played.len(), "{}", opened.what);
    for (k, (row, &angle)) in clip.frames.iter().zip(&played).enumerate() {
        let (read, angle) = (f64::from(row[jaw]) * degrees, f64::from(angle));
        assert!(
            (read - angle).abs() < 0.05,
            "frame {k}: the jaw opened {read:.3}°, Blender turned it {angle:.3}°"
        );
    }
    let (_, walk) = keyed("walk");
    let refused = walk.map(|w| w.what).unwrap_err().to_string();
    assert!(
        refused.contains("walk.glb: it has no animation"),
        "{refused}"
    );
}

/// The mouth opens once, by the bone or by the shape. Blender's avatar with its chin skinned to
/// the jaw bone and its jawOpen key a corrective that moves a tenth as far (as Character
/// Creator's jaw opens by its bone): a clip opening the jaw turns the bone as far as a jaw
/// with no shape to measure (Blender plays it so). Before, the bone turned as far as the
/// corrective turns the chin: 1°, a mouth that hardly opened. On the avatar whose chin the
/// shape opens (not skinned to the bone), the bone turns as far as the shape turns the chin,
/// so what hangs on it goes with the chin. On one whose chin is on the bone while its vowel
/// keys open it (no jawOpen key), the bone stays: before, it turned 20° beside `Fcl_MTH_A`'s
/// opening, and the mouth opened twice.
#[test]
fn the_mouth_opens_once_by_the_jaw_bone_or_by_its_shapes() {
    let dir = output_dir("made-by-others-jaw-skinned");
    let clip = dir.join("open.json");
    let opening =
        faceanim_anim::Clip::of_weights(10.0, &["jawOpen"], vec![vec![0.0], vec![0.5], vec![1.0]]);
    std::fs::write(&clip, opening.to_json()).unwrap();
    let turned = |avatar: &Path, name: &str| -> [f32; 2] {
        let out = dir.join(name);
        export_with_clip(avatar, &out, &clip);
        let at = blender_bone_turns_at(&out, &[0.1, 0.2], &["Jaw"]);
        [0, 1].map(|k| degrees_between(at[k][0].1, glam::Quat::IDENTITY))
    };
    let skinned = faceanim_testdata::producers::blender_avatar_variant(Variant::JawSkinned);
    let [half, full] = turned(&skinned, "skinned.glb");
    let want = faceanim_export::bones::DEFAULT_JAW_DEGREES;
    println!("the skinned jaw turns {half:.2}° and {full:.2}°");
    assert!(
        (full - want).abs() < 0.1,
        "the jaw turned {full}°, for {want}°"
    );
    assert!((half - want / 2.0).abs() < 0.1, "half open: {half}°");
    let vowels = faceanim_testdata::producers::blender_avatar_variant(Variant::JawAndVowels);
    let [_, beside_vowels] = turned(&vowels, "vowels.glb");
    println!("the jaw under a chin its vowel opens turns {beside_vowels:.2}°");
    assert!(
        beside_vowels < 0.1,
        "the jaw turned {beside_vowels}° beside Fcl_MTH_A"
    );
    let [_, by_shape] = turned(
        &faceanim_testdata::producers::blender_avatar_path(),
        "plain.glb",
    );
    println!("the jaw under a chin its shape opens turns {by_shape:.2}°");
    assert!(
        by_shape > 2.0 && (by_shape - want).abs() > 1.0,
        "the jaw under a chin its shape opens turned {by_shape}°"
    );
}

/// A rig whose names say nothing opens its mouth once too: its jaw bone's turn is measured on
/// the shapes its retarget map opens the mouth with. Blender's jaw-and-vowels avatar with its
/// targets renamed `shape_N` (no name says `Fcl_MTH_A` any more): the map made on export opens
/// the chin on the jaw bone by its shapes, and the bone stays. The jaw-skinned avatar renamed
/// the same way, whose shapes only shape the lips around the chin, opens by the bone, although
/// none of its shapes takes the clip. `faceanim info` and the studio's view say the same turn.
/// Before, the bone opened 20° on the first, whatever the map's shapes did (twice), and the
/// clip was refused on the second.
#[test]
fn a_rig_whose_names_say_nothing_opens_its_mouth_once_through_its_map() {
    let dir = support::fresh_output_dir("made-by-others-jaw-mapped");
    let clip = dir.join("open.json");
    let opening = faceanim_anim::Clip::of_weights(10.0, &["jawOpen"], vec![vec![0.0], vec![1.0]]);
    std::fs::write(&clip, opening.to_json()).unwrap();
    // The jaw bone's turn at jawOpen 1, and the largest of the renamed shapes' weights there.
    let turned = |avatar: &Path, name: &str| -> (f32, f64) {
        let renamed = dir.join(format!("{name}.glb"));
        support::rename_targets(avatar, &renamed);
        let out = dir.join(format!("{name}-open.glb"));
        let said = support::export_with_clip_and(&renamed, &out, &clip, &[]);
        assert!(said.contains("making the retarget map"), "{said}");
        let at = blender_bone_turns_at(&out, &[0.1], &["Jaw"]);
        let weights = dir.join(format!("{name}-open.json"));
        export_with_clip(&renamed, &weights, &clip);
        let weights: Value = serde_json::from_slice(&std::fs::read(&weights).unwrap()).unwrap();
        let widest = weights["frames"][1]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_f64().unwrap())
            .fold(0.0, f64::max);
        let turn = degrees_between(at[0][0].1, glam::Quat::IDENTITY);
        // `faceanim info` says the same, reading the map beside the character.
        let said = info(&renamed)["file"]["jaw_degrees"].as_f64().unwrap();
        assert!(
            (said - f64::from(turn)).abs() < 0.1,
            "{name}: info says the jaw turns {said}°, the export turned it {turn}°"
        );
        // So does the studio's view (its skeleton measured through the same map), which opens
        // the clip on the bones where none of the shapes takes it.
        let studio = start_on(
            Some(&renamed),
            &dir.join(format!("{name}.project.json")),
            &[],
        );
        let (status, state) = support::open_path(studio.port, &clip);
        drop(studio);
        assert_eq!(status, 200, "{name}: {state}");
        let state: Value = serde_json::from_str(&state).unwrap();
        let shown = state["take"]["bones"][1]
            .as_array()
            .unwrap_or_else(|| panic!("{name}: no bones in the view: {state}"))
            .iter()
            .map(|q| {
                degrees_between(
                    glam::Quat::from_slice(&support::f32s(q)),
                    glam::Quat::IDENTITY,
                )
            })
            .fold(0.0, f32::max);
        assert!(
            (shown - turn).abs() < 0.1,
            "{name}: the studio's view turns the jaw {shown}°, the export {turn}°"
        );
        (turn, widest)
    };
    let variant = faceanim_testdata::producers::blender_avatar_variant;
    let (by_shapes, widest) = turned(&variant(Variant::JawAndVowels), "vowels");
    println!("renamed jaw-and-vowels: the jaw turns {by_shapes:.2}°, a shape at {widest:.2}");
    assert!(
        widest > 0.3,
        "the map opens the renamed vowels' mouth with none of its shapes ({widest})"
    );
    assert!(
        by_shapes < 0.1,
        "the jaw turned {by_shapes}° beside the shapes the map opens the chin with"
    );
    // The plain avatar renamed: its chin opens by its shape, the teeth hang on the bone, which
    // turns as far as the chin (as it does by name).
    let (with_teeth, _) = turned(
        &faceanim_testdata::producers::blender_avatar_path(),
        "plain",
    );
    println!("renamed plain avatar: the jaw turns {with_teeth:.2}°");
    assert!(
        with_teeth > 2.0 && (with_teeth - 20.0).abs() > 1.0,
        "the jaw under a chin the map's shapes open turned {with_teeth}°"
    );
    let (by_bone, _) = turned(&variant(Variant::JawSkinned), "skinned");
    println!("renamed jaw-skinned: the jaw turns {by_bone:.2}°");
    let want = faceanim_export::bones::DEFAULT_JAW_DEGREES;
    assert!(
        (by_bone - want).abs() < 0.1,
        "the jaw turned {by_bone}°, for {want}°"
    );
}

/// The eyes look once, by the bones or by the shapes, and never not at all. On Blender's avatar
/// the eyeballs hang on the eye bones: a clip's gaze turns them, and the eyeLook shapes hold
/// still. On the same avatar with its eyeballs skinned to the head (the eye bones carry
/// nothing), the gaze stays on the shapes and no eye bone is keyed. Before, the bones that
/// carried nothing were turned and the shapes held still: the eyes never moved.
#[test]
fn eye_bones_that_carry_nothing_leave_the_gaze_on_the_shapes() {
    let dir = output_dir("made-by-others-eyes-on-head");
    let clip = dir.join("look.json");
    let looking = faceanim_anim::Clip::of_weights(
        10.0,
        &["eyeLookInLeft", "eyeLookOutRight"],
        vec![vec![0.0, 0.0], vec![1.0, 1.0]],
    );
    std::fs::write(&clip, looking.to_json()).unwrap();
    // The last frame's eyeLookIn_L shape, and whether the LeftEye bone is keyed.
    let looked = |avatar: &Path, name: &str| -> (f32, bool) {
        let out = dir.join(name);
        export_with_clip(avatar, &out, &clip);
        let bytes = std::fs::read(&out).unwrap();
        // The shapes' own keys, as the file holds them (a reopened clip would add the gaze the
        // bones turn to them).
        let imported = faceanim_rig::import::import_gltf(
            &bytes,
            name,
            &faceanim_rig::import::NoExternalResources,
        )
        .unwrap();
        let character = &imported.character;
        let take = character.source().unwrap().take().unwrap();
        let shape = character
            .blendshape_names()
            .iter()
            .position(|n| n == "eyeLookIn_L")
            .expect("eyeLookIn_L");
        let document = faceanim_testdata::glb::json(&bytes);
        let eye = faceanim_testdata::glb::names(&document, "nodes")
            .iter()
            .position(|n| n == "LeftEye")
            .expect("a LeftEye node");
        let keyed = document["animations"]
            .as_array()
            .into_iter()
            .flatten()
            .flat_map(|a| a["channels"].as_array().unwrap())
            .any(|c| c["target"]["node"] == eye);
        (take.animation.weights.last().unwrap()[shape], keyed)
    };
    let on_bones = faceanim_testdata::producers::blender_avatar_path();
    let (shape, keyed) = looked(&on_bones, "on-bones.glb");
    assert!(
        keyed && shape < 0.01,
        "eyes on their bones: shape {shape}, bone keyed {keyed}"
    );
    let on_head = faceanim_testdata::producers::blender_avatar_variant(Variant::EyesOnHead);
    let (shape, keyed) = looked(&on_head, "on-head.glb");
    assert!(
        !keyed && shape > 0.99,
        "eyes on the head: shape {shape}, bone keyed {keyed}"
    );
    // `faceanim info` says so.
    let info = faceanim_ok(&["info", on_head.to_str().unwrap(), "--json"]);
    let info: Value = serde_json::from_str(&info).unwrap();
    assert_eq!(
        info["file"]["still_bones"]["left_eye"], "LeftEye",
        "{}",
        info["file"]
    );
    assert!(
        info["file"]["bones"]["left_eye"].is_null(),
        "{}",
        info["file"]
    );
}

/// Lip sync reaches what a character has. Blender's own export of its avatar without shape
/// keys has a jaw bone: the line opens it (Blender reads the jaw turned as far as the line's
/// jawOpen says, about the left-right axis, and shut before the line starts). The avatar made a
/// VRM, whose lip sync goes through its vowels while its ARKit-named shapes stay at rest, gives
/// Live Link Face the line's ARKit curves, not zeros. A head with neither shapes nor a jaw bone
/// is sent to generate-shapes.
#[test]
fn lip_sync_opens_a_jaw_bone_and_live_link_face_hears_any_avatar() {
    let dir = output_dir("made-by-others-lipsync-bones");
    let speech = dir.join("line.wav");
    support::flite(
        "slt",
        "Bob and Mary moved the heavy boxes up the narrow path.",
        &speech,
    );
    // `faceanim lipsync` of the line on `character`, writing `outputs`.
    let lipsync = |character: &Path, outputs: &[&Path], more: &[&str]| {
        let mut args = vec!["lipsync", speech.to_str().unwrap(), "--character"];
        args.push(character.to_str().unwrap());
        for out in outputs {
            args.extend(["-o", out.to_str().unwrap()]);
        }
        args.extend(more);
        support::faceanim(&args)
    };
    let bare = faceanim_testdata::producers::blender_bare_avatar_path();
    let (glb, csv) = (dir.join("bare.glb"), dir.join("bare.csv"));
    let out = lipsync(&bare, &[&glb, &csv], &["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["route"], "jaw_bone", "{summary}");
    assert_valid_gltf(&glb);
    let (header, rows) = live_link_csv(&csv);
    let jaw_column = header.iter().position(|h| h == "JawOpen").unwrap();
    let (widest, jaw) = rows
        .iter()
        .map(|r| r[jaw_column])
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(jaw > 0.3, "the line opens the jaw at most {jaw}");
    assert!(rows[0][jaw_column] < 0.02, "{:?}", rows[0]);
    let fps = summary["fps"].as_f64().unwrap() as f32;
    for (seconds, open) in [(0.0, 0.0), (widest as f32 / fps, jaw)] {
        let turns = blender_bone_turns(&glb, seconds, &["Jaw"]);
        let (axis, angle) = turns[0].1.to_axis_angle();
        let want = open * faceanim_export::bones::DEFAULT_JAW_DEGREES;
        let opened = angle.to_degrees();
        assert!(
            (opened - want).abs() < 1.0,
            "at {seconds} s Blender reads the jaw {opened}° open for jawOpen {open}"
        );
        assert!(
            open == 0.0 || axis.x.abs() > 0.99,
            "the jaw turned about {axis}"
        );
    }

    // The VRM: its vowels move, its ARKit-named shapes do not; Live Link Face hears the line.
    let avatar = dir.join("avatar.vrm");
    std::fs::write(
        &avatar,
        complete_vrm(&with_vrm(blender_avatar(), VrmKind::V1)),
    )
    .unwrap();
    let csv = dir.join("avatar.csv");
    let out = lipsync(&avatar, &[&csv], &[]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{said}");
    assert!(
        said.contains("ARKit-named blendshapes stay at rest in this take"),
        "{said}"
    );
    let (header, rows) = live_link_csv(&csv);
    for curve in ["JawOpen", "MouthPressLeft"] {
        let at = header.iter().position(|h| h == curve).unwrap();
        let peak = rows.iter().map(|r| r[at]).fold(0.0, f32::max);
        assert!(peak > 0.3, "{curve} peaks at {peak}");
    }

    // A head with neither: told what makes it shapes.
    let mut parts = faceanim_testdata::ict().to_parts();
    parts.blendshapes.clear();
    parts.normal_deltas = None;
    let head = dir.join("head.glb");
    let character = faceanim_rig::Character::new(parts).unwrap();
    std::fs::write(&head, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    let out = lipsync(&head, &[&dir.join("head.json")], &[]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("faceanim generate-shapes"), "{said}");
    assert!(!dir.join("head.json").exists());
}
