//! `faceanim info`: what a character contains, as text for people or JSON for scripts.

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
}

#[derive(Debug, Serialize)]
struct BlendshapeReport {
    name: String,
    moved: usize,
    max_displacement: f32,
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

impl Report {
    /// Gathers the report for `character`.
    pub fn of(character: &Character) -> Report {
        let names =
            |id: faceanim_rig::BlendshapeId| character.blendshapes()[id.index()].name().to_owned();
        let symmetry = character.symmetry();
        Report {
            vertices: character.vertex_count(),
            triangles: character.triangles().len(),
            blendshapes: character
                .blendshapes()
                .iter()
                .map(|b| BlendshapeReport {
                    name: b.name().to_owned(),
                    moved: b.moved(),
                    max_displacement: b.max_displacement(),
                })
                .collect(),
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
            "  bounding box [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}] (size {:.4})",
            self.bbox.min[0],
            self.bbox.min[1],
            self.bbox.min[2],
            self.bbox.max[0],
            self.bbox.max[1],
            self.bbox.max[2],
            self.size
        );
        if self.full_body {
            let _ = writeln!(
                out,
                "  head         [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}] (framing and default distances)",
                self.head.min[0],
                self.head.min[1],
                self.head.min[2],
                self.head.max[0],
                self.head.max[1],
                self.head.max[2],
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
        let _ = writeln!(out, "  ARKit names  {} of 52 recognised", self.arkit.len());
        let _ = writeln!(out, "  blendshapes  {}", self.blendshapes.len());
        let width = self
            .blendshapes
            .iter()
            .map(|b| b.name.len())
            .max()
            .unwrap_or(0);
        for b in &self.blendshapes {
            let _ = writeln!(
                out,
                "    {:width$}  {:>6} vertices moved, up to {:.5}",
                b.name, b.moved, b.max_displacement
            );
        }
        let _ = writeln!(out, "  symmetric pairs  {}", self.pairs.len());
        for [l, r] in &self.pairs {
            let _ = writeln!(out, "    {l} <-> {r}");
        }
        out
    }
}
