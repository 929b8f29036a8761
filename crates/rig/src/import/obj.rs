//! OBJ sets: a neutral OBJ plus one OBJ per blendshape with the same vertices in the same order
//! (the ICT-FaceKit layout). Faces, UVs and `usemtl` groups come from the neutral file; the
//! blendshape files only contribute their `v` lines.
//!
//! The first vertices of the character are the OBJ's `v` lines in order (so vertex numbers match
//! the files); a vertex used with several UVs (a seam) gets extra copies appended after them.

use std::collections::HashMap;

use glam::Vec3;

use super::types::{
    ImportError, ImportErrorKind, Imported, MAX_BLENDSHAPES, MAX_TRIANGLES, MAX_VERTICES,
};
use crate::blendshape::{Blendshape, SPARSE_DELTA_THRESHOLD};
use crate::bounds::Aabb;
use crate::character::{Character, CharacterParts, Material, MaterialId, Part};

/// One OBJ file's name (for messages and the blendshape name) and text.
#[derive(Debug, Clone, Copy)]
pub struct ObjSource<'a> {
    /// File name; a blendshape is named after its file stem.
    pub name: &'a str,
    /// The file's contents.
    pub text: &'a str,
}

/// Imports a neutral OBJ and its blendshape OBJs (none: a head to make shapes for, with a
/// warning saying how). `character_name` names the result.
///
/// # Errors
/// An [`ImportError`] naming the offending file (and line, for syntax errors).
pub fn import_obj_set(
    character_name: &str,
    neutral: ObjSource<'_>,
    shapes: &[ObjSource<'_>],
) -> Result<Imported, ImportError> {
    let err = |source: &str, kind| ImportError {
        source_name: source.to_owned(),
        kind,
    };
    if shapes.len() > MAX_BLENDSHAPES {
        return Err(err(
            neutral.name,
            ImportErrorKind::TooLarge(format!(
                "{} blendshape files (at most {MAX_BLENDSHAPES})",
                shapes.len()
            )),
        ));
    }
    let mesh = parse(neutral, true).map_err(|k| err(neutral.name, k))?;
    if mesh.faces.is_empty() {
        return Err(err(neutral.name, ImportErrorKind::NoMeshes));
    }

    // Vertex layout: OBJ vertices first, then one copy per extra (v, vt) combination.
    let n = mesh.positions.len();
    let mut origin: Vec<u32> = (0..n as u32).collect();
    let mut uv_of: Vec<Option<u32>> = vec![None; n];
    let mut extra: HashMap<(u32, u32), u32> = HashMap::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut parts: Vec<Part> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_ids: HashMap<String, MaterialId> = HashMap::new();
    for face in &mesh.faces {
        let mut corner = |(v, vt): (u32, Option<u32>)| -> u32 {
            match (vt, uv_of[v as usize]) {
                (None, _) => v,
                (Some(t), None) => {
                    uv_of[v as usize] = Some(t);
                    v
                }
                (Some(t), Some(existing)) if existing == t => v,
                (Some(t), Some(_)) => *extra.entry((v, t)).or_insert_with(|| {
                    origin.push(v);
                    uv_of.push(Some(t));
                    (origin.len() - 1) as u32
                }),
            }
        };
        let corners: Vec<u32> = face.corners.iter().map(|&c| corner(c)).collect();
        let material = *material_ids
            .entry(face.material.clone())
            .or_insert_with(|| {
                materials.push(Material {
                    name: face.material.clone(),
                    ..Material::default()
                });
                MaterialId((materials.len() - 1) as u32)
            });
        if parts.last().is_none_or(|p| p.material != material) {
            parts.push(Part {
                name: face.material.clone(),
                material,
                triangles: triangles.len()..triangles.len(),
            });
        }
        for k in 1..corners.len() - 1 {
            let tri = [corners[0], corners[k], corners[k + 1]];
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                triangles.push(tri);
            }
        }
        if let Some(part) = parts.last_mut() {
            part.triangles.end = triangles.len();
        }
        if triangles.len() > MAX_TRIANGLES {
            return Err(err(
                neutral.name,
                ImportErrorKind::TooLarge(format!("more than {MAX_TRIANGLES} triangles")),
            ));
        }
    }
    if origin.len() > MAX_VERTICES {
        return Err(err(
            neutral.name,
            ImportErrorKind::TooLarge(format!("more than {MAX_VERTICES} vertices")),
        ));
    }
    let positions: Vec<Vec3> = origin.iter().map(|&o| mesh.positions[o as usize]).collect();
    let uvs = (!mesh.uvs.is_empty()).then(|| {
        uv_of
            .iter()
            .map(|t| {
                t.and_then(|t| mesh.uvs.get(t as usize).copied())
                    .unwrap_or([0.0, 0.0])
            })
            .collect()
    });
    let colors = (!mesh.colors.is_empty()).then(|| {
        origin
            .iter()
            .map(|&o| {
                mesh.colors
                    .get(o as usize)
                    .copied()
                    .unwrap_or([1.0, 1.0, 1.0, 1.0])
            })
            .collect()
    });

    let threshold = SPARSE_DELTA_THRESHOLD * Aabb::around(&positions).diagonal();
    let mut blendshapes = Vec::with_capacity(shapes.len());
    let mut dense = vec![Vec3::ZERO; positions.len()];
    for shape in shapes {
        let parsed = parse(*shape, false).map_err(|k| err(shape.name, k))?;
        if parsed.positions.len() != n {
            return Err(err(
                shape.name,
                ImportErrorKind::CountMismatch(format!(
                    "it has {} vertices but the neutral '{}' has {n}",
                    parsed.positions.len(),
                    neutral.name
                )),
            ));
        }
        for (slot, &o) in dense.iter_mut().zip(&origin) {
            *slot = parsed.positions[o as usize] - mesh.positions[o as usize];
        }
        let name = std::path::Path::new(shape.name).file_stem().map_or_else(
            || shape.name.to_owned(),
            |s| s.to_string_lossy().into_owned(),
        );
        blendshapes.push(Blendshape::from_dense(name, &dense, threshold));
    }

    let character = Character::new(CharacterParts {
        name: character_name.to_owned(),
        positions,
        normals: None,
        uvs,
        colors,
        triangles,
        materials,
        parts,
        blendshapes,
        normal_deltas: None,
    })
    .map_err(|e| err(neutral.name, e.into()))?;
    let warnings = if shapes.is_empty() {
        vec![
            "no blendshapes: make ARKit's 52 on this head with `faceanim generate-shapes` (or \
             give the folder holding the neutral OBJ and one OBJ per blendshape)"
                .to_owned(),
        ]
    } else {
        Vec::new()
    };
    Ok(Imported {
        character,
        warnings,
    })
}

struct Face {
    corners: Vec<(u32, Option<u32>)>,
    material: String,
}

#[derive(Default)]
struct ObjMesh {
    positions: Vec<Vec3>,
    colors: Vec<[f32; 4]>,
    uvs: Vec<[f32; 2]>,
    faces: Vec<Face>,
}

/// Parses `v` (with optional vertex colours), and with `full` also `vt`, `f` and `usemtl`.
fn parse(source: ObjSource<'_>, full: bool) -> Result<ObjMesh, ImportErrorKind> {
    let mut mesh = ObjMesh::default();
    let mut material = String::from("default");
    let mut saw_anything = false;
    for (number, line) in source.text.lines().enumerate() {
        let fail = |problem: String| ImportErrorKind::Obj {
            file: source.name.to_owned(),
            line: number + 1,
            problem,
        };
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        saw_anything = true;
        match keyword {
            "v" => {
                let values: Vec<f32> = words
                    .map(|w| parse_number(w).map_err(&fail))
                    .collect::<Result<_, _>>()?;
                if values.len() < 3 {
                    return Err(fail(format!(
                        "a vertex needs 3 coordinates, found {}",
                        values.len()
                    )));
                }
                let p = Vec3::new(values[0], values[1], values[2]);
                if mesh.positions.len() >= MAX_VERTICES {
                    return Err(ImportErrorKind::TooLarge(format!(
                        "more than {MAX_VERTICES} vertices"
                    )));
                }
                mesh.positions.push(p);
                if values.len() >= 6 {
                    mesh.colors.push([values[3], values[4], values[5], 1.0]);
                }
            }
            "vt" if full => {
                let values: Vec<f32> = words
                    .map(|w| parse_number(w).map_err(&fail))
                    .collect::<Result<_, _>>()?;
                if values.is_empty() {
                    return Err(fail("a texture coordinate needs at least 1 value".into()));
                }
                mesh.uvs
                    .push([values[0], values.get(1).copied().unwrap_or(0.0)]);
            }
            "f" if full => {
                let mut corners = Vec::new();
                for word in words {
                    let mut fields = word.split('/');
                    let v = resolve(fields.next().unwrap_or(""), mesh.positions.len(), "vertex")
                        .map_err(&fail)?;
                    let vt = match fields.next() {
                        Some(t) if !t.is_empty() => {
                            Some(resolve(t, mesh.uvs.len(), "texture coordinate").map_err(&fail)?)
                        }
                        _ => None,
                    };
                    corners.push((v, vt));
                }
                if corners.len() < 3 {
                    return Err(fail(format!(
                        "a face needs at least 3 corners, found {}",
                        corners.len()
                    )));
                }
                mesh.faces.push(Face {
                    corners,
                    material: material.clone(),
                });
            }
            "usemtl" if full => material = words.next().unwrap_or("default").to_owned(),
            _ => {}
        }
    }
    if !saw_anything || mesh.positions.is_empty() {
        return Err(ImportErrorKind::NotObj(
            "it has no vertices (no 'v' lines)".into(),
        ));
    }
    Ok(mesh)
}

fn parse_number(word: &str) -> Result<f32, String> {
    let value: f32 = word
        .parse()
        .map_err(|_| format!("'{word}' is not a number"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("'{word}' is not a finite number"))
    }
}

/// Resolves a 1-based (or negative, relative) OBJ index against `count` items so far.
fn resolve(word: &str, count: usize, what: &str) -> Result<u32, String> {
    let index: i64 = word
        .parse()
        .map_err(|_| format!("'{word}' is not a {what} index"))?;
    let resolved = if index > 0 {
        index - 1
    } else {
        count as i64 + index
    };
    if index == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(format!(
            "{what} index {index} is out of range (there are {count} so far)"
        ));
    }
    Ok(resolved as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";

    #[test]
    fn quad_with_one_shape() {
        let shape = "v 0 0 0\nv 1 0 0\nv 1 1 0.5\nv 0 1 0\n";
        let imported = import_obj_set(
            "quad",
            ObjSource {
                name: "neutral.obj",
                text: QUAD,
            },
            &[ObjSource {
                name: "lift.obj",
                text: shape,
            }],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let c = imported.character;
        assert_eq!(c.vertex_count(), 4);
        assert_eq!(c.triangles().len(), 2);
        assert_eq!(c.blendshapes()[0].name(), "lift");
        assert_eq!(c.blendshapes()[0].indices(), &[2]);
        assert_eq!(c.uvs().map(|u| u[2]), Some([1.0, 1.0]));
    }

    /// The error message of importing `neutral` with one blendshape file `shape`.
    fn error_of(neutral: (&str, &str), shape: (&str, &str)) -> Option<String> {
        import_obj_set(
            "x",
            ObjSource {
                name: neutral.0,
                text: neutral.1,
            },
            &[ObjSource {
                name: shape.0,
                text: shape.1,
            }],
        )
        .err()
        .map(|e| e.to_string())
    }

    #[test]
    fn errors_name_file_and_line() {
        assert_eq!(
            error_of(("neutral.obj", QUAD), ("s.obj", "v 0 0 0\nv 1 0\n")).as_deref(),
            Some("s.obj: line 2: a vertex needs 3 coordinates, found 2")
        );
        assert_eq!(
            error_of(("n.obj", "v 0 0 0\nf 1 2 3\n"), ("s.obj", "v 0 0 0\n")).as_deref(),
            Some("n.obj: line 2: vertex index 2 is out of range (there are 1 so far)")
        );
        assert_eq!(
            error_of(("n.obj", QUAD), ("s.obj", "v 0 0 0\n")).as_deref(),
            Some("s.obj: counts disagree: it has 1 vertices but the neutral 'n.obj' has 4")
        );
    }
}
