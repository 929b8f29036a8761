//! VRM avatars (`.vrm`, a GLB with a VRM extension): their expressions.
//!
//! A VRM expression ("blink", "aa", "happy", or a custom one) is a named set of morph-target
//! bindings with weights. faceanim makes each one a blendshape of the character beside the raw
//! morph targets, so a stroke or a capture can pick "blink" as it would pick `Fcl_EYE_Close`.
//!
//! - VRM 0.x: `extensions.VRM.blendShapeMaster.blendShapeGroups[]`, each with `name`,
//!   `presetName` and `binds[]` of `{mesh, index, weight}`, weights 0–100; the model faces −Z.
//! - VRM 1.0: `extensions.VRMC_vrm.expressions.{preset,custom}.NAME.morphTargetBinds[]` of
//!   `{node, index, weight}`, weights 0–1; the model faces +Z.
//!
//! Presets keep VRM 1.0's names in both versions (0.x `a` is `aa`, `joy` is `happy`,
//! `blink_l` is `blinkLeft`, …), so the same avatar made for either version has the same
//! blendshape names.

use crate::names::VRM_PRESET_NAMES;
use serde_json::Value;

/// Which VRM specification the file follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Version {
    /// VRM 0.x: faces −Z, weights 0–100.
    V0,
    /// VRM 1.0: faces +Z, weights 0–1.
    V1,
}

/// One morph target of one mesh, with its weight in the expression (0–1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bind {
    pub mesh: usize,
    pub target: usize,
    pub weight: f32,
}

/// A named expression.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Expression {
    pub name: String,
    /// Named as one of VRM 1.0's presets (a custom expression may not be).
    pub preset: bool,
    pub binds: Vec<Bind>,
}

impl Expression {
    /// `name` binding `binds`, a preset where VRM 1.0 names one so.
    fn new(name: String, binds: Vec<Bind>) -> Expression {
        Expression {
            preset: is_preset(&name),
            name,
            binds,
        }
    }
}

/// What faceanim reads of a VRM file.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Vrm {
    pub version: Version,
    pub expressions: Vec<Expression>,
}

/// Whether `name` is one of VRM 1.0's preset expressions (which a custom one may not be named).
fn is_preset(name: &str) -> bool {
    VRM_PRESET_NAMES.iter().any(|(_, v1)| *v1 == name)
}

/// Reads the VRM extension of a glTF JSON, if there is one.
pub(crate) fn read(value: &Value, warnings: &mut Vec<String>) -> Option<Vrm> {
    let extensions = value.get("extensions");
    if let Some(v1) = extensions.and_then(|e| e.get("VRMC_vrm")) {
        return Some(read_v1(value, v1, warnings));
    }
    if let Some(v0) = extensions.and_then(|e| e.get("VRM")) {
        return Some(read_v0(value, v0, warnings));
    }
    None
}

fn mesh_target_count(value: &Value, mesh: usize) -> Option<usize> {
    let primitive = value.pointer(&format!("/meshes/{mesh}/primitives/0"))?;
    Some(
        primitive
            .get("targets")
            .and_then(Value::as_array)
            .map_or(0, Vec::len),
    )
}

/// Checks a binding against the file's meshes; a wrong one is a warning, not an error, since
/// the raw morph targets still import.
fn checked_bind(
    value: &Value,
    bind: &Value,
    mesh: Option<usize>,
    scale: f64,
    at: &str,
    warnings: &mut Vec<String>,
) -> Option<Bind> {
    let target = as_index(bind.get("index"));
    let weight = bind.get("weight").and_then(Value::as_f64);
    let (Some(mesh), Some(target)) = (mesh, target) else {
        warnings.push(format!(
            "{at}: a binding without its mesh and index was skipped"
        ));
        return None;
    };
    let count = mesh_target_count(value, mesh);
    if count.is_none_or(|c| target >= c) {
        warnings.push(format!(
            "{at}: binds morph target {target} of mesh {mesh}, which does not exist; skipped"
        ));
        return None;
    }
    let weight = (weight.unwrap_or(scale) / scale) as f32;
    (weight.is_finite() && weight != 0.0).then_some(Bind {
        mesh,
        target,
        weight,
    })
}

/// The items of the array `key` of `value` (none where it is missing or no array), numbered.
fn items<'a>(value: &'a Value, key: &str) -> impl Iterator<Item = (usize, &'a Value)> {
    value
        .get(key)
        .and_then(Value::as_array)
        .map_or(&[][..], Vec::as_slice)
        .iter()
        .enumerate()
}

fn as_index(v: Option<&Value>) -> Option<usize> {
    v.and_then(Value::as_u64)
        .and_then(|n| usize::try_from(n).ok())
}

fn read_v0(value: &Value, vrm: &Value, warnings: &mut Vec<String>) -> Vrm {
    let groups = vrm
        .pointer("/blendShapeMaster/blendShapeGroups")
        .and_then(Value::as_array)
        .map_or(&[][..], Vec::as_slice);
    let mut expressions = Vec::new();
    for (g, group) in groups.iter().enumerate() {
        let at = format!("extensions.VRM.blendShapeMaster.blendShapeGroups[{g}]");
        let preset = group
            .get("presetName")
            .and_then(Value::as_str)
            .unwrap_or("unknown");
        let name = VRM_PRESET_NAMES
            .iter()
            .find(|(v0, _)| v0.eq_ignore_ascii_case(preset))
            .map(|(_, v1)| (*v1).to_owned())
            .or_else(|| group.get("name").and_then(Value::as_str).map(str::to_owned))
            .unwrap_or_else(|| format!("expression_{g}"));
        let binds: Vec<Bind> = items(group, "binds")
            .filter_map(|(b, bind)| {
                let at = format!("{at}.binds[{b}]");
                checked_bind(
                    value,
                    bind,
                    as_index(bind.get("mesh")),
                    100.0,
                    &at,
                    warnings,
                )
            })
            .collect();
        expressions.push(Expression::new(name, binds));
    }
    Vrm {
        version: Version::V0,
        expressions,
    }
}

fn read_v1(value: &Value, vrm: &Value, warnings: &mut Vec<String>) -> Vrm {
    let mut expressions = Vec::new();
    for kind in ["preset", "custom"] {
        let Some(map) = vrm
            .pointer(&format!("/expressions/{kind}"))
            .and_then(Value::as_object)
        else {
            continue;
        };
        for (name, expression) in map {
            let at = format!("extensions.VRMC_vrm.expressions.{kind}.{name}");
            let binds = items(expression, "morphTargetBinds")
                .filter_map(|(b, bind)| {
                    let node = as_index(bind.get("node"));
                    let mesh =
                        node.and_then(|n| as_index(value.pointer(&format!("/nodes/{n}/mesh"))));
                    if node.is_some() && mesh.is_none() {
                        warnings.push(format!(
                            "{at}.morphTargetBinds[{b}]: node {} has no mesh; skipped",
                            node.unwrap_or_default()
                        ));
                        return None;
                    }
                    let at = format!("{at}.morphTargetBinds[{b}]");
                    checked_bind(value, bind, mesh, 1.0, &at, warnings)
                })
                .collect();
            expressions.push(Expression::new(name.clone(), binds));
        }
    }
    Vrm {
        version: Version::V1,
        expressions,
    }
}
