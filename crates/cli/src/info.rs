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
    size: f32,
    symmetry_plane: Option<PlaneReport>,
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

#[derive(Debug, Serialize)]
struct PlaneReport {
    axis: &'static str,
    offset: f32,
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
            bbox: BboxReport {
                min: character.bounds().min.to_array(),
                max: character.bounds().max.to_array(),
            },
            size: character.size(),
            symmetry_plane: symmetry.plane().map(|p| PlaneReport {
                axis: match p.axis {
                    faceanim_rig::symmetry::Axis::X => "x",
                    faceanim_rig::symmetry::Axis::Y => "y",
                    faceanim_rig::symmetry::Axis::Z => "z",
                },
                offset: p.offset,
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
        match &self.symmetry_plane {
            Some(p) => {
                let _ = writeln!(
                    out,
                    "  symmetry     {} = {:.5} ({:.0}% of vertices mirrored)",
                    p.axis,
                    p.offset,
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
