//! The validated blendshape character: neutral mesh, sparse blendshapes, materials, and the
//! structures derived from them once (bounds, edge graph; the symmetry when first asked for).
//!
//! A [`Character`] only exists validated: [`Character::new`] checks every index, count and value
//! and derives the rest, so the sketch engine, the capture adapter and the exporters never
//! re-check.

use std::sync::Arc;

use glam::Vec3;

use crate::blendshape::{Blendshape, BlendshapeId};
use crate::bounds::Aabb;
use crate::graph::EdgeGraph;
use crate::names;
use crate::normals::{self, NormalDeltas};
use crate::runs::{EvaluationRuns, Runs};
use crate::symmetry::Symmetry;

/// Index of a material within its [`Character`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MaterialId(pub u32);

/// Encoded image bytes (PNG, JPEG, WebP or KTX2) kept as they came, for rendering and re-export.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// `image/png`, `image/jpeg`, `image/webp` or `image/ktx2`.
    pub mime_type: String,
    /// The encoded file.
    pub bytes: Arc<[u8]>,
}

/// How a part of the mesh looks: the glTF metallic-roughness subset animators' tools agree on.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The material's name (may be empty).
    pub name: String,
    /// Linear RGBA multiplier of the base colour.
    pub base_color: [f32; 4],
    /// Optional base-colour texture, sampled with the mesh's UVs.
    pub base_color_texture: Option<Texture>,
    /// 0 = dielectric, 1 = metal.
    pub metallic: f32,
    /// 0 = mirror, 1 = fully rough.
    pub roughness: f32,
    /// Render back faces too.
    pub double_sided: bool,
    /// How the base colour's alpha is used (glTF's `alphaMode`): lashes, brows and hair cards
    /// are cut out by their texture's alpha.
    pub alpha: AlphaMode,
}

/// How a material's alpha is used, as glTF's `alphaMode` says.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Cut out: drawn where alpha is at least `cutoff`, not at all elsewhere.
    Mask {
        /// The alpha below which nothing is drawn (glTF's `alphaCutoff`, 0.5 by default).
        cutoff: f32,
    },
    /// Blended over what is behind.
    Blend,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: [1.0, 1.0, 1.0, 1.0],
            base_color_texture: None,
            metallic: 0.0,
            roughness: 0.7,
            double_sided: false,
            alpha: AlphaMode::Opaque,
        }
    }
}

/// A run of triangles drawn with one material (one glTF primitive on export).
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// The part's name (the glTF mesh name it came from, or the OBJ group).
    pub name: String,
    /// Its material.
    pub material: MaterialId,
    /// Its triangles, as a range of [`Character::triangles`].
    pub triangles: std::ops::Range<usize>,
}

/// A character whose bounds are at least this many times its face region's diagonal is
/// framed on a head-sized box around its face instead of on its whole bounds.
const FULL_BODY_RATIO: f32 = 1.6;
/// How far the head box reaches beyond the face region on each side, as a fraction of the
/// face region's diagonal (on a scanned head the face region spans about 0.83 of the head's
/// diagonal; this margin gives the head's size back).
const HEAD_MARGIN: f32 = 0.06;

/// The face region and the head box (see [`Character::face_bounds`] and
/// [`Character::head_bounds`]).
fn face_and_head(positions: &[Vec3], blendshapes: &[Blendshape], whole: &Aabb) -> (Aabb, Aabb) {
    let mut moved = vec![0.0f32; positions.len()];
    for shape in blendshapes {
        for (i, d) in shape.moves() {
            if let Some(m) = moved.get_mut(i as usize) {
                *m = m.max(d.length());
            }
        }
    }
    let largest = moved.iter().copied().fold(0.0f32, f32::max);
    if largest <= 0.0 {
        return (*whole, *whole);
    }
    let face_points: Vec<Vec3> = positions
        .iter()
        .zip(&moved)
        .filter(|&(_, &m)| m > 0.02 * largest)
        .map(|(p, _)| *p)
        .collect();
    let face = Aabb::around(&face_points);
    let face_size = face.diagonal();
    if face_size <= 0.0 || whole.diagonal() < FULL_BODY_RATIO * face_size {
        return (face, *whole);
    }
    let margin = Vec3::splat(HEAD_MARGIN * face_size);
    let head = Aabb {
        min: (face.min - margin).max(whole.min),
        max: (face.max + margin).min(whole.max),
    };
    (face, head)
}

/// Everything needed to build a [`Character`]; [`Character::new`] validates it.
#[derive(Debug, Clone, Default)]
pub struct CharacterParts {
    /// Display name.
    pub name: String,
    /// Neutral vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals; computed from the triangles when `None`.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Per-vertex linear RGBA colours.
    pub colors: Option<Vec<[f32; 4]>>,
    /// Triangles, counter-clockwise when seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Materials referenced by `parts`.
    pub materials: Vec<Material>,
    /// Material runs over `triangles`; one default part covering all when empty.
    pub parts: Vec<Part>,
    /// Blendshapes (names need not be unique; duplicates get `.001` suffixes).
    pub blendshapes: Vec<Blendshape>,
    /// Normal deltas per blendshape, when the source file carried them; computed otherwise.
    pub normal_deltas: Option<Vec<NormalDeltas>>,
}

/// Why a set of [`CharacterParts`] is not a valid character.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// No vertices at all.
    #[error("the mesh has no vertices")]
    NoVertices,
    /// No triangles at all.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// A per-vertex attribute has the wrong length.
    #[error("{attribute} has {found} entries but there are {expected} vertices")]
    AttributeCount {
        /// Which attribute.
        attribute: &'static str,
        /// Its length.
        found: usize,
        /// The vertex count.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what} [{index}] is not a finite number")]
    NonFinite {
        /// Which array.
        what: String,
        /// Where in it.
        index: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {vertex}, but there are only {vertices} vertices"
    )]
    VertexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The bad index.
        vertex: u32,
        /// The vertex count.
        vertices: usize,
    },
    /// A blendshape's sparse data is inconsistent.
    #[error("blendshape '{name}': {problem}")]
    BadBlendshape {
        /// The blendshape.
        name: String,
        /// What is wrong.
        problem: String,
    },
    /// A part refers to a missing material or runs past the triangles.
    #[error("part '{name}': {problem}")]
    BadPart {
        /// The part.
        name: String,
        /// What is wrong.
        problem: String,
    },
}

/// A validated blendshape character. See the module docs.
#[derive(Debug, Clone)]
pub struct Character {
    name: String,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<[f32; 2]>>,
    colors: Option<Vec<[f32; 4]>>,
    triangles: Vec<[u32; 3]>,
    materials: Vec<Material>,
    parts: Vec<Part>,
    blendshapes: Vec<Blendshape>,
    normal_deltas: Vec<NormalDeltas>,
    bounds: Aabb,
    face: Aabb,
    head: Aabb,
    source: Option<crate::source::SharedSource>,
    graph: EdgeGraph,
    /// Found when first asked for (sketching and mirroring need it; lip sync, capture and
    /// export do not).
    symmetry: std::sync::OnceLock<Symmetry>,
    runs: EvaluationRuns,
}

impl Character {
    /// Validates `parts` and derives normals (when missing), normal deltas, bounds and the edge
    /// graph; the symmetry (plane, mirrored vertices, left/right blendshape pairs) is found
    /// when first asked for.
    ///
    /// # Errors
    /// Any inconsistency, as a [`ModelError`] naming the attribute, index or blendshape.
    pub fn new(parts: CharacterParts) -> Result<Character, ModelError> {
        let CharacterParts {
            name,
            positions,
            normals,
            uvs,
            colors,
            triangles,
            mut materials,
            parts,
            blendshapes,
            normal_deltas,
        } = parts;
        let vertex_count = positions.len();
        if vertex_count == 0 {
            return Err(ModelError::NoVertices);
        }
        if triangles.is_empty() {
            return Err(ModelError::NoTriangles);
        }
        check_finite_vec3("positions", &positions)?;
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                if v as usize >= vertex_count {
                    return Err(ModelError::VertexOutOfRange {
                        triangle: t,
                        vertex: v,
                        vertices: vertex_count,
                    });
                }
            }
        }
        check_count("normals", normals.as_ref().map(Vec::len), vertex_count)?;
        check_count("uvs", uvs.as_ref().map(Vec::len), vertex_count)?;
        check_count("colors", colors.as_ref().map(Vec::len), vertex_count)?;
        if let Some(normals) = &normals {
            check_finite_vec3("normals", normals)?;
        }
        if let Some(uvs) = &uvs
            && let Some(index) = uvs.iter().position(|uv| !uv.iter().all(|c| c.is_finite()))
        {
            return Err(ModelError::NonFinite {
                what: "uvs".into(),
                index,
            });
        }
        if let Some(colors) = &colors
            && let Some(index) = colors.iter().position(|c| !c.iter().all(|x| x.is_finite()))
        {
            return Err(ModelError::NonFinite {
                what: "colors".into(),
                index,
            });
        }

        let blendshapes = unique_names(blendshapes);
        for shape in &blendshapes {
            check_blendshape(shape, vertex_count)?;
        }

        if materials.is_empty() {
            materials.push(Material::default());
        }
        let parts = if parts.is_empty() {
            vec![Part {
                name: name.clone(),
                material: MaterialId(0),
                triangles: 0..triangles.len(),
            }]
        } else {
            parts
        };
        for part in &parts {
            if part.material.0 as usize >= materials.len() {
                return Err(ModelError::BadPart {
                    name: part.name.clone(),
                    problem: format!(
                        "material {} does not exist ({} materials)",
                        part.material.0,
                        materials.len()
                    ),
                });
            }
            if part.triangles.start > part.triangles.end || part.triangles.end > triangles.len() {
                return Err(ModelError::BadPart {
                    name: part.name.clone(),
                    problem: format!(
                        "triangles {:?} run past the {} triangles",
                        part.triangles,
                        triangles.len()
                    ),
                });
            }
        }

        let bounds = Aabb::around(&positions);
        let graph = EdgeGraph::build(&positions, &triangles);
        let normals = match normals {
            Some(n) => n,
            None => normals::vertex_normals(&positions, &triangles, &graph),
        };
        let normal_deltas = match normal_deltas {
            Some(given) if given.len() == blendshapes.len() => {
                for (shape, deltas) in blendshapes.iter().zip(&given) {
                    deltas
                        .check(vertex_count)
                        .map_err(|problem| ModelError::BadBlendshape {
                            name: shape.name().to_owned(),
                            problem,
                        })?;
                }
                given
            }
            _ => normals::blendshape_normal_deltas(&positions, &triangles, &graph, &blendshapes),
        };
        let (face, head) = face_and_head(&positions, &blendshapes, &bounds);
        let runs = EvaluationRuns {
            positions: blendshapes
                .iter()
                .map(|b| Runs::of(b.indices(), b.deltas()))
                .collect(),
            normals: normal_deltas
                .iter()
                .map(|n| Runs::of(&n.indices, &n.deltas))
                .collect(),
        };

        Ok(Character {
            name,
            positions,
            normals,
            uvs,
            colors,
            triangles,
            materials,
            parts,
            blendshapes,
            normal_deltas,
            bounds,
            face,
            head,
            source: None,
            graph,
            symmetry: std::sync::OnceLock::new(),
            runs,
        })
    }

    /// Display name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Neutral positions.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Neutral per-vertex normals (unit length).
    #[must_use]
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// Texture coordinates, if the source had them.
    #[must_use]
    pub fn uvs(&self) -> Option<&[[f32; 2]]> {
        self.uvs.as_deref()
    }

    /// Linear RGBA vertex colours, if the source had them.
    #[must_use]
    pub fn colors(&self) -> Option<&[[f32; 4]]> {
        self.colors.as_deref()
    }

    /// Triangles (indices into the vertices).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Materials (at least one).
    #[must_use]
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Material runs over the triangles (at least one).
    #[must_use]
    pub fn parts(&self) -> &[Part] {
        &self.parts
    }

    /// The blendshapes, in file order.
    #[must_use]
    pub fn blendshapes(&self) -> &[Blendshape] {
        &self.blendshapes
    }

    /// The blendshapes' names, in file order.
    #[must_use]
    pub fn blendshape_names(&self) -> Vec<String> {
        self.blendshapes
            .iter()
            .map(|b| b.name().to_owned())
            .collect()
    }

    /// The blendshape `id`.
    #[must_use]
    pub fn blendshape(&self, id: BlendshapeId) -> Option<&Blendshape> {
        self.blendshapes.get(id.index())
    }

    /// Iterates over blendshape ids in order.
    pub fn blendshape_ids(&self) -> impl ExactSizeIterator<Item = BlendshapeId> + use<> {
        (0..self.blendshapes.len() as u32).map(BlendshapeId)
    }

    /// The blendshape called exactly `name`, or else the one whose name means the same ARKit
    /// shape (`eyeBlink_L` finds `eyeBlinkLeft`).
    #[must_use]
    pub fn find_blendshape(&self, name: &str) -> Option<BlendshapeId> {
        if let Some(i) = self.blendshapes.iter().position(|b| b.name() == name) {
            return Some(BlendshapeId(i as u32));
        }
        let wanted = names::arkit_name(name)?;
        self.blendshapes
            .iter()
            .position(|b| names::arkit_name(b.name()) == Some(wanted))
            .map(|i| BlendshapeId(i as u32))
    }

    /// Normal deltas of each blendshape, parallel to [`Character::blendshapes`].
    #[must_use]
    pub fn normal_deltas(&self) -> &[NormalDeltas] {
        &self.normal_deltas
    }

    /// Bounding box of the neutral mesh.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The face region: the box around the vertices the blendshapes move (by more than 2 % of
    /// the largest motion of any vertex), eyes, teeth and tongue included.
    #[must_use]
    pub fn face_bounds(&self) -> Aabb {
        self.face
    }

    /// The head: the box that framing (the studio's camera, renders, the adapter's training
    /// pictures) and default distances are measured on. For a bare head it is the whole
    /// [`Character::bounds`]; for a character much larger than its face (a full-body avatar) it
    /// is a head-sized box around the face region.
    #[must_use]
    pub fn head_bounds(&self) -> Aabb {
        self.head
    }

    /// The user's glTF file this character was imported from, kept so that exports can be
    /// that file with the animation added; `None` for OBJ sets and characters made in code.
    #[must_use]
    pub fn source(&self) -> Option<&crate::source::GltfSource> {
        self.source.as_deref()
    }

    /// This character with `record` noted in its file (see
    /// [`crate::source::GeneratedShapes`]), added to what the file noted already; a character
    /// made in code or from OBJ files has no file to note it in and comes back as it was.
    #[must_use]
    pub fn with_generated_shapes(&self, record: &crate::source::GeneratedShapes) -> Character {
        let Some(source) = self.source() else {
            return self.clone();
        };
        let mut all = source.generated_shapes().unwrap_or_default();
        for name in &record.shapes {
            if !all.shapes.contains(name) {
                all.shapes.push(name.clone());
            }
        }
        all.template = if all.template.is_empty() || all.template == record.template {
            record.template.clone()
        } else {
            format!("{}, {}", all.template, record.template)
        };
        let mut source = source.clone();
        let asset = &mut source.document["asset"];
        if !asset.is_object() {
            *asset = serde_json::json!({ "version": "2.0" });
        }
        if !asset["extras"].is_object() {
            asset["extras"] = serde_json::json!({});
        }
        if !asset["extras"]["faceanim"].is_object() {
            asset["extras"]["faceanim"] = serde_json::json!({});
        }
        asset["extras"]["faceanim"]["generated"] =
            serde_json::json!({ "shapes": all.shapes, "template": all.template });
        self.clone().with_source(source)
    }

    /// This character with the file it came from (the importer's job).
    #[must_use]
    pub(crate) fn with_source(mut self, source: crate::source::GltfSource) -> Character {
        self.source = Some(std::sync::Arc::new(source));
        self
    }

    /// The character's size `D`, that default distances scale with: the diagonal of
    /// [`Character::head_bounds`] (so a full-body avatar gets the same stroke radii as its
    /// head alone would).
    #[must_use]
    pub fn size(&self) -> f32 {
        self.head.diagonal()
    }

    /// Vertex adjacency, with coincident vertices (UV seams) joined.
    #[must_use]
    pub fn graph(&self) -> &EdgeGraph {
        &self.graph
    }

    pub(crate) fn evaluation_runs(&self) -> &EvaluationRuns {
        &self.runs
    }

    /// Symmetry plane, mirrored vertices and left/right blendshape pairs.
    #[must_use]
    pub fn symmetry(&self) -> &Symmetry {
        self.symmetry
            .get_or_init(|| Symmetry::detect(&self.positions, &self.head, &self.blendshapes))
    }

    /// For each blendshape that is a VRM expression, the blendshapes whose morph targets it
    /// binds (empty for the file's own targets and for characters not read from a file).
    #[must_use]
    pub fn expression_parts(&self) -> Vec<Vec<usize>> {
        let Some(source) = self.source() else {
            return vec![Vec::new(); self.blendshapes.len()];
        };
        let mut owner: std::collections::HashMap<(u32, u32), usize> =
            std::collections::HashMap::new();
        for (slot, bindings) in source.shapes().iter().enumerate() {
            for b in bindings {
                owner.entry((b.mesh, b.target)).or_insert(slot);
            }
        }
        (0..self.blendshapes.len())
            .map(|slot| {
                let mut parts: Vec<usize> = source
                    .shapes()
                    .get(slot)
                    .into_iter()
                    .flatten()
                    .filter_map(|b| owner.get(&(b.mesh, b.target)).copied())
                    .filter(|&p| p != slot)
                    .collect();
                parts.sort_unstable();
                parts.dedup();
                parts
            })
            .collect()
    }

    /// Which blendshapes ARKit's channels drive by name (see [`crate::name_map`]).
    #[must_use]
    pub fn name_map(&self) -> crate::name_map::NameMap {
        let names: Vec<String> = self
            .blendshapes
            .iter()
            .map(|b| b.name().to_owned())
            .collect();
        crate::name_map::NameMap::from_names(&names, &self.expression_parts())
    }

    /// The blendshapes whose names are ARKit names, with the canonical name each one spells.
    #[must_use]
    pub fn arkit_coverage(&self) -> Vec<(BlendshapeId, &'static str)> {
        self.blendshape_ids()
            .filter_map(|id| {
                names::arkit_name(self.blendshapes[id.index()].name()).map(|n| (id, n))
            })
            .collect()
    }

    /// This character with `extra` blendshapes appended (for example the corrective targets an
    /// animation export bakes). Existing ids, symmetry pairs and derived data are kept; only
    /// the new blendshapes are checked and get normal deltas.
    ///
    /// # Errors
    /// A [`ModelError`] naming the first bad extra blendshape.
    pub fn with_extra_blendshapes(&self, extra: Vec<Blendshape>) -> Result<Character, ModelError> {
        for shape in &extra {
            check_blendshape(shape, self.vertex_count())?;
        }
        // The pairs are this character's: found now, before the extra shapes join.
        let _ = self.symmetry();
        let mut out = self.clone();
        let normal_deltas = normals::blendshape_normal_deltas(
            &self.positions,
            &self.triangles,
            &self.graph,
            &extra,
        );
        for (shape, normals) in extra.iter().zip(&normal_deltas) {
            out.runs
                .positions
                .push(Runs::of(shape.indices(), shape.deltas()));
            out.runs
                .normals
                .push(Runs::of(&normals.indices, &normals.deltas));
        }
        let mut all = std::mem::take(&mut out.blendshapes);
        all.extend(extra);
        out.blendshapes = unique_names(all);
        out.normal_deltas.extend(normal_deltas);
        Ok(out)
    }

    /// The parts needed to rebuild this character with changes (for example extra blendshapes).
    #[must_use]
    pub fn to_parts(&self) -> CharacterParts {
        CharacterParts {
            name: self.name.clone(),
            positions: self.positions.clone(),
            normals: Some(self.normals.clone()),
            uvs: self.uvs.clone(),
            colors: self.colors.clone(),
            triangles: self.triangles.clone(),
            materials: self.materials.clone(),
            parts: self.parts.clone(),
            blendshapes: self.blendshapes.clone(),
            normal_deltas: Some(self.normal_deltas.clone()),
        }
    }
}

fn check_count(
    attribute: &'static str,
    found: Option<usize>,
    expected: usize,
) -> Result<(), ModelError> {
    match found {
        Some(found) if found != expected => Err(ModelError::AttributeCount {
            attribute,
            found,
            expected,
        }),
        _ => Ok(()),
    }
}

fn check_finite_vec3(what: &str, values: &[Vec3]) -> Result<(), ModelError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ModelError::NonFinite {
            what: what.to_owned(),
            index,
        }),
        None => Ok(()),
    }
}

fn check_blendshape(shape: &Blendshape, vertex_count: usize) -> Result<(), ModelError> {
    let bad = |problem: String| ModelError::BadBlendshape {
        name: shape.name().to_owned(),
        problem,
    };
    if shape.indices().len() != shape.deltas().len() {
        return Err(bad(format!(
            "{} indices but {} deltas",
            shape.indices().len(),
            shape.deltas().len()
        )));
    }
    if let Some(w) = shape.indices().windows(2).position(|w| w[0] >= w[1]) {
        return Err(bad(format!(
            "vertex indices are not strictly increasing at entry {}",
            w + 1
        )));
    }
    if let Some(&last) = shape.indices().last()
        && last as usize >= vertex_count
    {
        return Err(bad(format!(
            "moves vertex {last}, but there are only {vertex_count} vertices"
        )));
    }
    if let Some(k) = shape.deltas().iter().position(|d| !d.is_finite()) {
        return Err(bad(format!(
            "delta of vertex {} is not a finite number",
            shape.indices()[k]
        )));
    }
    Ok(())
}

/// Gives repeated names Blender-style suffixes (`smile`, `smile.001`), so names stay keys.
fn unique_names(shapes: Vec<Blendshape>) -> Vec<Blendshape> {
    let mut seen = std::collections::HashSet::new();
    shapes
        .into_iter()
        .map(|shape| {
            if seen.insert(shape.name().to_owned()) {
                return shape;
            }
            let mut n = 1;
            let name = loop {
                let candidate = format!("{}.{n:03}", shape.name());
                if !seen.contains(&candidate) {
                    break candidate;
                }
                n += 1;
            };
            seen.insert(name.clone());
            shape.renamed(name)
        })
        .collect()
}
