//! `faceanim info`: what a character contains, as text for people or JSON for scripts.

use std::path::PathBuf;

use clap::Args;
use faceanim_rig::Character;
use serde::Serialize;

/// The JSON form of `faceanim info --json` (a stable format: scripts rely on its field names).
#[derive(Debug, Serialize)]
pub struct Report {
    vertices: usize,
    triangles: usize,
    blendshapes: Vec<BlendshapeReport>,
    pairs: Vec<[String; 2]>,
    arkit: Vec<String>,
    /// ARKit channels that drive none of the blendshapes by name.
    undriven_channels: Vec<&'static str>,
    bbox: BboxReport,
    /// Where the blendshapes move vertices.
    face: BboxReport,
    /// The head box that framing and default distances use (the whole box for a bare head).
    head: BboxReport,
    #[serde(skip)]
    full_body: bool,
    size: f32,
    symmetry_plane: Option<PlaneReport>,
    /// The user's file, when the character came from glTF: what an export keeps.
    file: Option<FileReport>,
}

#[derive(Debug, Serialize)]
struct FileReport {
    nodes: usize,
    meshes: usize,
    skins: usize,
    materials: usize,
    textures: usize,
    vrm: bool,
    /// The file's animations (a take or sketch faceanim exported, or the file's own).
    animations: Vec<AnimationReport>,
    /// The bones exports turn (head pose, gaze, jaw), by name: `head`, `neck`, `upper_spine`,
    /// `left_eye`, `right_eye`, `jaw`.
    bones: std::collections::BTreeMap<&'static str, String>,
    /// Face bones the file has that exports leave still: eye bones that carry no vertex (the
    /// eyeballs skinned to the head) or that a VRM's lookAt leaves to expressions; the gaze
    /// moves shapes instead.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    still_bones: std::collections::BTreeMap<&'static str, String>,
    /// How far exports turn the jaw bone at `jawOpen` 1, in degrees: as far as the shape that
    /// opens the mouth turns the chin, 20 where the chin is on the bone and the shape only
    /// shapes the lips, 0 where the shapes open a chin on the bone on their own (measured on
    /// its retarget map's shapes where no name says which open the mouth).
    #[serde(skip_serializing_if = "Option::is_none")]
    jaw_degrees: Option<f32>,
    /// The blendshapes `faceanim generate-shapes` made, as the file records them.
    #[serde(skip_serializing_if = "Option::is_none")]
    generated: Option<GeneratedReport>,
}

#[derive(Debug, Serialize)]
struct AnimationReport {
    name: String,
    /// Its channels: morph weights and bone rotations.
    channels: usize,
    /// Its length in seconds (the latest key time its samplers declare).
    seconds: f64,
    /// For a sketch faceanim exported: how many strokes it keeps (it opens as them).
    #[serde(skip_serializing_if = "Option::is_none")]
    strokes: Option<usize>,
}

impl AnimationReport {
    fn all_of(doc: &serde_json::Value) -> Vec<AnimationReport> {
        use serde_json::Value;
        let accessors = doc.get("accessors").and_then(Value::as_array);
        let end_of = |sampler: &Value| {
            let accessor = sampler.get("input").and_then(Value::as_u64)?;
            accessors?
                .get(usize::try_from(accessor).ok()?)?
                .pointer("/max/0")?
                .as_f64()
        };
        doc.get("animations")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
            .map(|(k, a)| AnimationReport {
                name: a
                    .get("name")
                    .and_then(Value::as_str)
                    .map_or_else(|| format!("animation {k}"), str::to_owned),
                channels: a
                    .get("channels")
                    .and_then(Value::as_array)
                    .map_or(0, Vec::len),
                seconds: a
                    .get("samplers")
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                    .filter_map(end_of)
                    .fold(0.0, f64::max),
                strokes: a
                    .pointer(&format!(
                        "/extras/{}/{}/strokes",
                        faceanim_rig::file_animation::EXTRAS_KEY,
                        faceanim_rig::file_animation::STROKES_KEY
                    ))
                    .and_then(Value::as_array)
                    .map(Vec::len),
            })
            .collect()
    }
}

#[derive(Debug, Serialize)]
struct GeneratedReport {
    shapes: Vec<String>,
    template: String,
}

#[derive(Debug, Serialize)]
struct BlendshapeReport {
    name: String,
    moved: usize,
    max_displacement: f32,
    /// What its name means in ARKit's channels, and whether capture by name drives it.
    #[serde(skip_serializing_if = "Option::is_none")]
    arkit: Option<NameReport>,
}

/// One blendshape's reading in faceanim's name table (`faceanim_rig::names`).
#[derive(Debug, Serialize)]
struct NameReport {
    /// How: `channel`, `split` (one side of a channel ARKit does not split), `merge` (the mean
    /// of a left/right pair), `expression` (a viseme or VRM's `surprised`).
    kind: NameKind,
    /// The ARKit channels it reads.
    channels: Vec<&'static str>,
    /// In words, as `faceanim info` prints it.
    meaning: String,
    /// Whether capture by name drives it.
    driven: bool,
    /// Why not, when it is not.
    #[serde(skip_serializing_if = "Option::is_none")]
    because: Option<String>,
}

#[derive(Debug, Clone, Copy, Serialize)]
#[serde(rename_all = "snake_case")]
enum NameKind {
    Channel,
    Split,
    Merge,
    Expression,
}

#[derive(Debug, Serialize)]
struct BboxReport {
    min: [f32; 3],
    max: [f32; 3],
}

impl BboxReport {
    fn of(b: faceanim_rig::Aabb) -> BboxReport {
        BboxReport {
            min: b.min.to_array(),
            max: b.max.to_array(),
        }
    }

    /// `[x, y, z] .. [x, y, z]`, to four decimals.
    fn text(&self) -> String {
        let [a, b, c] = self.min;
        let [d, e, f] = self.max;
        format!("[{a:.4}, {b:.4}, {c:.4}] .. [{d:.4}, {e:.4}, {f:.4}]")
    }
}

#[derive(Debug, Serialize)]
struct PlaneReport {
    /// The coordinate axis nearest the plane's normal.
    axis: &'static str,
    /// The unit normal (towards the character's left) and the offset along it.
    normal: [f32; 3],
    offset: f32,
    /// How far the normal leans from `axis`.
    tilt_degrees: f32,
    mirrored_vertices: f32,
}

fn name_report(entry: faceanim_rig::name_map::Entry, character: &Character) -> NameReport {
    use faceanim_rig::name_map::Use;
    use faceanim_rig::names::Drive;
    let name_of = |i: usize| {
        character
            .blendshapes()
            .get(i)
            .map_or_else(String::new, |b| b.name().to_owned())
    };
    NameReport {
        kind: match entry.drive {
            Drive::Channel(_) => NameKind::Channel,
            Drive::Split(..) => NameKind::Split,
            Drive::Merge(..) => NameKind::Merge,
            Drive::Expression(_) => NameKind::Expression,
        },
        channels: entry.drive.channels().iter().map(|c| c.name()).collect(),
        meaning: entry.drive.describe(),
        driven: entry.used == Use::Driven,
        because: match entry.used {
            Use::Driven => None,
            Use::Duplicate(first) => Some(format!("{} is the same channel", name_of(first))),
            Use::Covered => Some("its channels drive other blendshapes directly".to_owned()),
            Use::TargetsDriven => Some("the morph targets it binds are driven by name".to_owned()),
            Use::NoReading => {
                Some("no reading from a face's channels (lip sync drives it)".to_owned())
            }
            _ => Some("not driven".to_owned()),
        },
    }
}

impl Report {
    /// Gathers the report for `character`, whose retarget `map` (when it has one) says which
    /// of its shapes open its mouth where no name does.
    pub fn of(character: &Character, retarget: Option<&faceanim_retarget::RetargetMap>) -> Report {
        let names =
            |id: faceanim_rig::BlendshapeId| character.blendshapes()[id.index()].name().to_owned();
        let symmetry = character.symmetry();
        let map = character.name_map();
        // The bones exports turn, as the view carries them.
        let view = faceanim_export::bones::ViewRig::of(character, retarget);
        Report {
            vertices: character.vertex_count(),
            triangles: character.triangles().len(),
            blendshapes: character
                .blendshapes()
                .iter()
                .zip(map.entries())
                .map(|(b, entry)| BlendshapeReport {
                    name: b.name().to_owned(),
                    moved: b.moved(),
                    max_displacement: b.max_displacement(),
                    arkit: entry.map(|e| name_report(e, character)),
                })
                .collect(),
            undriven_channels: map.undriven_channels().iter().map(|c| c.name()).collect(),
            pairs: symmetry
                .pairs()
                .iter()
                .map(|p| [names(p.left), names(p.right)])
                .collect(),
            arkit: character
                .arkit_coverage()
                .into_iter()
                .map(|(id, _)| names(id))
                .collect(),
            bbox: BboxReport::of(character.bounds()),
            face: BboxReport::of(character.face_bounds()),
            head: BboxReport::of(character.head_bounds()),
            full_body: character.head_bounds() != character.bounds(),
            size: character.size(),
            file: character.source().map(|s| FileReport {
                nodes: s.count("nodes"),
                meshes: s.count("meshes"),
                skins: s.count("skins"),
                materials: s.count("materials"),
                textures: s.count("textures"),
                vrm: s.is_vrm(),
                bones: bone_names(s, view.as_ref(), true),
                still_bones: bone_names(s, view.as_ref(), false),
                jaw_degrees: view
                    .as_ref()
                    .and_then(faceanim_export::bones::ViewRig::jaw_degrees),
                animations: AnimationReport::all_of(s.document()),
                generated: s.generated_shapes().map(|g| GeneratedReport {
                    shapes: g.shapes,
                    template: g.template,
                }),
            }),
            symmetry_plane: symmetry.plane().map(|p| PlaneReport {
                axis: match p.axis() {
                    faceanim_rig::symmetry::Axis::X => "x",
                    faceanim_rig::symmetry::Axis::Y => "y",
                    faceanim_rig::symmetry::Axis::Z => "z",
                },
                normal: p.normal.to_array(),
                offset: p.offset,
                tilt_degrees: p.tilt_degrees(),
                mirrored_vertices: symmetry.mirrored_fraction(),
            }),
        }
    }

    /// The human-readable form.
    pub fn text(&self, character: &Character) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let _ = writeln!(out, "{}", character.name());
        let _ = writeln!(out, "  vertices     {}", self.vertices);
        let _ = writeln!(out, "  triangles    {}", self.triangles);
        let _ = writeln!(
            out,
            "  bounding box {} (size {:.4})",
            self.bbox.text(),
            self.size
        );
        if self.full_body {
            let _ = writeln!(
                out,
                "  head         {} (framing and default distances)",
                self.head.text()
            );
        }
        if let Some(f) = &self.file {
            let _ = writeln!(
                out,
                "  file         {} nodes, {} meshes, {} skins, {} materials, {} textures{} (kept in exports)",
                f.nodes,
                f.meshes,
                f.skins,
                f.materials,
                f.textures,
                if f.vrm { ", VRM" } else { "" }
            );
            for a in &f.animations {
                let sketch = a
                    .strokes
                    .map(|n| format!(", a sketch of {n} stroke{}", if n == 1 { "" } else { "s" }))
                    .unwrap_or_default();
                let _ = writeln!(
                    out,
                    "  animation    {}: {:.2} s, {} channels{sketch}",
                    a.name, a.seconds, a.channels
                );
            }
            if !f.bones.is_empty() {
                let list: Vec<String> = f.bones.iter().map(|(k, v)| format!("{k} {v}")).collect();
                let _ = writeln!(
                    out,
                    "  bones        {} (exports turn them)",
                    list.join(", ")
                );
            }
            match f.jaw_degrees {
                Some(degrees) if degrees.abs() < 0.05 => {
                    let _ = writeln!(
                        out,
                        "  jaw          still at jawOpen: its shapes open the chin the bone carries"
                    );
                }
                Some(degrees) => {
                    let _ = writeln!(out, "  jaw          turns {degrees:.1}° at jawOpen 1");
                }
                None => {}
            }
            if !f.still_bones.is_empty() {
                let list: Vec<String> = f
                    .still_bones
                    .iter()
                    .map(|(k, v)| format!("{k} {v}"))
                    .collect();
                let _ = writeln!(
                    out,
                    "  still bones  {} (exports leave them still: the gaze moves shapes instead)",
                    list.join(", ")
                );
            }
            if let Some(g) = &f.generated {
                let _ = writeln!(
                    out,
                    "  generated    {} blendshapes made by faceanim generate-shapes (template: {})",
                    g.shapes.len(),
                    g.template
                );
            }
        }
        match &self.symmetry_plane {
            Some(p) => {
                let _ = writeln!(
                    out,
                    "  symmetry     {} = {:.5}, tilted {:.1}° ({:.0}% of vertices mirrored)",
                    p.axis,
                    p.offset,
                    p.tilt_degrees,
                    100.0 * p.mirrored_vertices
                );
            }
            None => {
                let _ = writeln!(out, "  symmetry     none found");
            }
        }
        let _ = writeln!(
            out,
            "  ARKit names  {} blendshapes spell an ARKit channel; {} of 52 channels drive a blendshape by name",
            self.arkit.len(),
            52 - self.undriven_channels.len()
        );
        let _ = writeln!(out, "  blendshapes  {}", self.blendshapes.len());
        let width = self
            .blendshapes
            .iter()
            .map(|b| b.name.len())
            .max()
            .unwrap_or(0);
        for b in &self.blendshapes {
            let by_name = match &b.arkit {
                Some(n) if n.driven => format!("  <- {}", n.meaning),
                Some(n) => format!(
                    "  ({}; not driven: {})",
                    n.meaning,
                    n.because.as_deref().unwrap_or("")
                ),
                None => String::new(),
            };
            let _ = writeln!(
                out,
                "    {:width$}  {:>6} vertices moved, up to {:.5}{by_name}",
                b.name, b.moved, b.max_displacement
            );
        }
        if self.undriven_channels.is_empty() {
            let _ = writeln!(out, "  ARKit channels: all 52 drive a blendshape by name");
        } else {
            let _ = writeln!(
                out,
                "  ARKit channels that drive nothing by name ({}): {}",
                self.undriven_channels.len(),
                self.undriven_channels.join(", ")
            );
        }
        let _ = writeln!(out, "  symmetric pairs  {}", self.pairs.len());
        for [l, r] in &self.pairs {
            let _ = writeln!(out, "    {l} <-> {r}");
        }
        out
    }
}
/// `faceanim info`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct InfoArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files (default: the built-in head).
    pub(crate) character: Option<PathBuf>,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub(crate) json: bool,
}

/// `faceanim info`.
pub(crate) fn run(args: &InfoArgs) -> anyhow::Result<()> {
    let imported = crate::input::load_or_default(args.character.as_deref())?;
    let character = &imported.character;
    // Which of its shapes answer to each ARKit channel: its retarget map, when it has one.
    let map_path = crate::retarget::default_path(args.character.as_deref(), character);
    let map = crate::retarget::read_beside(&map_path, character)?;
    let report = Report::of(character, map.as_ref());
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        value["retarget"] = serde_json::json!({
            "path": map_path,
            "needed": faceanim_adapt::bridge::needs_map(character),
            "rows": map.as_ref().map(|m| &m.rows),
        });
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        out!("{}", report.text(character));
        match &map {
            Some(map) => out!(
                "retarget map ({}):\n{}",
                map_path.display(),
                crate::retarget::table(map)
            ),
            None if faceanim_adapt::bridge::needs_map(character) => outln!(
                "no retarget map yet: `faceanim retarget` makes one (capture makes it too) at {}",
                map_path.display()
            ),
            None => {}
        }
    }
    Ok(())
}

/// The face's bones of `source` that exports turn (`turned`: those of `view`, the character's
/// [`faceanim_export::bones::ViewRig`]), or that they leave still, by role, named as the file
/// names them (`node N` unnamed).
fn bone_names(
    source: &faceanim_rig::source::GltfSource,
    view: Option<&faceanim_export::bones::ViewRig>,
    turned: bool,
) -> std::collections::BTreeMap<&'static str, String> {
    let turns = |bone| view.is_some_and(|v| v.joints.iter().any(|j| j.bone == Some(bone)));
    let name = |n: usize| {
        source
            .document()
            .pointer(&format!("/nodes/{n}/name"))
            .and_then(serde_json::Value::as_str)
            .map_or_else(|| format!("node {n}"), str::to_owned)
    };
    source
        .bones()
        .found()
        .filter(|(bone, _)| turns(*bone) == turned)
        .map(|(bone, n)| (bone.name(), name(n)))
        .collect()
}
