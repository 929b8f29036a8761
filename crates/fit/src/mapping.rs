//! The retarget map by geometry: which of a character's own shapes make each ARKit channel
//! its names do not give.
//!
//! The template head is registered onto the character's face as [`crate::generate`] does, and
//! each channel's template shape is moved onto the character's vertices (deformation
//! transfer): `D_c`, what the channel looks like on this face. The character's shapes that no
//! name claims (`B_k`) are then compared with those displacements in a least squares weighted
//! by face region — lids, gaze, brows, cheeks, nose, jaw, mouth and the rest each count alike,
//! so that a small region (a lid) weighs as much as a large one (the jaw) — giving the Gram
//! matrix `G = BᵀWB` and the products `H = BᵀWD` of the per-frame solve
//! ([`faceanim_retarget::Solve`]), and each channel's own row.

use std::collections::{BTreeMap, BTreeSet};

use faceanim_retarget::{Fitted, Mode, RetargetMap, RowSource, Solve, channel_index};
use faceanim_rig::Character;
use faceanim_track::FaceModels;
use glam::Vec3;

use crate::{FaceLandmarks, FacePoints, FitError, OnUser, channel_deltas};

/// The price of a shape in the solve, per unit of its size (see [`Solve`]).
pub const SPARSITY: f32 = 0.04;
/// A shape taking less than this of a channel is left out of the channel's row.
const ROW_FLOOR: f32 = 0.05;
/// A channel whose displacement the free shapes reproduce less than this share of is not
/// reached by geometry (its row stays empty and the solve leaves it out): the character has
/// nothing like it.
pub const MIN_EXPLAINED: f32 = 0.7;
/// A shape may answer to a channel when at least this share of its (region-weighted) motion
/// is in the channel's region.
const REGION_SHARE: f64 = 0.2;
/// A channel (or shape) with more than this share of its motion on one side of the face is
/// one-sided.
const ONE_SIDED: f64 = 0.75;
/// A channel whose one shape explains at least this share of it is driven by its row.
const DIRECT_EXPLAINED: f32 = 0.85;
/// Shapes leave a channel's row while the row still explains within this share of the
/// channel's displacement of the best its shapes gave ([`pruned_row`]): less is the template's
/// shape not quite landing on this face, not the face. Chosen on ICT's identity `id3` (shapes
/// one per channel, names replaced), whose rows took such extras for 0.06–0.4 % (its jaw 0.15
/// of the lower lip's roll for 0.06 %), and on the Blender avatar, where a second mouth shape
/// adds 0.8–1 % of the jaw and keeps the mouth corners from dropping as it opens. On `id48`
/// the jaw took 0.31 of one side's lower lip for 0.2 %, so that lip followed a person's jaw
/// (r 0.77 with its own channel; now 0.99).
const MIN_GAIN: f32 = 0.005;

/// The face regions that count alike in the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Region {
    Lids,
    Gaze,
    Brows,
    Cheeks,
    Nose,
    Jaw,
    Mouth,
    /// Everything no channel moves (the rest of the head, a body): counts half, so that a
    /// shape moving it where no channel does pays for it.
    Rest,
}

impl Region {
    fn of_channel(name: &str) -> Region {
        use faceanim_rig::names::Region as Face;
        match faceanim_rig::names::region(name) {
            Face::Gaze => Region::Gaze,
            Face::Lids => Region::Lids,
            Face::Brows => Region::Brows,
            Face::Cheeks => Region::Cheeks,
            Face::Nose => Region::Nose,
            Face::Jaw => Region::Jaw,
            Face::Mouth | Face::Tongue => Region::Mouth,
        }
    }
}

/// `character`'s retarget map: by name, then by geometry from `templates` (the first that has
/// a channel gives it) for the channels its names leave out, if any of its shapes is free to
/// take them. Rows a user set in `previous` (a map of the same character) are kept. The face
/// is found by the face model, or taken from `points` where the user marked it.
///
/// # Errors
/// [`FitError`] when the face cannot be found or the template not placed.
pub fn retarget_map(
    character: &Character,
    templates: &[&Character],
    models: &FaceModels,
    previous: Option<&RetargetMap>,
    points: Option<&FacePoints>,
) -> Result<RetargetMap, FitError> {
    let names: Vec<String> = character.blendshape_names();
    let parts = character.expression_parts();
    let mut map = RetargetMap::by_name(character.name(), &names, &parts);
    if let Some(previous) = previous.filter(|p| p.blendshapes == names) {
        for (c, row) in previous.rows.iter().enumerate() {
            if row.from == RowSource::User {
                map.rows[c] = row.clone();
            }
        }
    }
    let wanted: Vec<usize> = (0..faceanim_retarget::CHANNELS)
        .filter(|&c| map.rows[c].from == RowSource::None)
        .collect();
    let free = RetargetMap::free_shapes(&names, &parts);
    if wanted.is_empty() || free.is_empty() {
        map.set_geometry(Vec::new(), None, Mode::Frame);
        return Ok(map);
    }
    let user_marks = FaceLandmarks::locate(character, models, points, templates)?;
    let on_user = OnUser::new(character)?;
    // Each channel's displacement on the character, from the first template that has it; and
    // every channel's, for the regions.
    let n = character.vertex_count();
    let mut displacement: Vec<Option<Vec<Vec3>>> = vec![None; faceanim_retarget::CHANNELS];
    let mut region_of = vec![(0.0f32, Region::Rest); n];
    let mut fit = None;
    for template in templates {
        let channels: Vec<(String, Vec<Vec3>)> = channel_deltas(template)
            .into_iter()
            .filter(|(name, _)| channel_index(name).is_some_and(|c| displacement[c].is_none()))
            .collect();
        if !channels
            .iter()
            .any(|(name, _)| channel_index(name).is_some_and(|c| wanted.contains(&c)))
        {
            continue;
        }
        let registered = on_user.register(&user_marks, template, models)?;
        let (channel_names, deltas): (Vec<String>, Vec<Vec<Vec3>>) = channels.into_iter().unzip();
        let moved = on_user.transfer(&registered, template, &deltas);
        for (name, dense) in channel_names.iter().zip(moved) {
            let region = Region::of_channel(name);
            for (slot, d) in region_of.iter_mut().zip(&dense) {
                let length = d.length();
                if length > slot.0 {
                    *slot = (length, region);
                }
            }
            if let Some(c) = channel_index(name) {
                displacement[c] = Some(dense);
            }
        }
        fit.get_or_insert_with(|| registered.report(template, Vec::new()));
    }
    // A vertex belongs to a region where a channel moves it by a thousandth of the head.
    let still = 1e-3 * on_user.size;
    let region: Vec<Region> = region_of
        .iter()
        .map(|(length, r)| if *length > still { *r } else { Region::Rest })
        .collect();
    let mut counts: BTreeMap<Region, usize> = BTreeMap::new();
    for r in &region {
        *counts.entry(*r).or_default() += 1;
    }
    let weight: Vec<f64> = region
        .iter()
        .map(|r| {
            let share = if *r == Region::Rest { 0.5 } else { 1.0 };
            share / counts[r] as f64
        })
        .collect();
    let channels: Vec<usize> = wanted
        .iter()
        .copied()
        .filter(|&c| displacement[c].is_some())
        .collect();
    // Regions the names already drive (a named blink's lids) are theirs: the solve keeps out.
    let named: Vec<Region> = map
        .rows
        .iter()
        .filter(|r| matches!(r.from, RowSource::ByName | RowSource::User) && !r.shapes.is_empty())
        .map(|r| Region::of_channel(&r.channel))
        .collect();
    let (rows, solve) = fit_shapes(
        character,
        &free,
        &channels,
        &displacement,
        &Weighting {
            weight: &weight,
            region: &region,
            named: &named,
        },
    );
    map.set_geometry(rows, solve, Mode::Frame);
    if let Some(fit) = fit {
        map.made.template = Some(fit.name);
        map.made.landmarks = Some(fit.landmarks[1]);
        map.made.residual = Some(fit.residual);
    }
    Ok(map)
}

/// How the fit weighs the character's vertices: each one's weight, its region, and the regions
/// its names already drive.
#[derive(Clone, Copy)]
struct Weighting<'a> {
    weight: &'a [f64],
    region: &'a [Region],
    named: &'a [Region],
}

/// The free shapes against the channels' displacements: each channel's row (with the share
/// explained) and the per-frame solve over the channels they reach.
fn fit_shapes(
    character: &Character,
    free: &[usize],
    channels: &[usize],
    displacement: &[Option<Vec<Vec3>>],
    weighting: &Weighting<'_>,
) -> (Vec<Fitted>, Option<Solve>) {
    let Weighting {
        weight,
        region,
        named,
    } = *weighting;
    let shapes = character.blendshapes();
    // Dense deltas of the free shapes over the vertices any of them moves.
    let n = character.vertex_count();
    let mut dense: Vec<Vec<Vec3>> = Vec::with_capacity(free.len());
    for &k in free {
        let mut d = vec![Vec3::ZERO; n];
        for (i, delta) in shapes[k].moves() {
            d[i as usize] = delta;
        }
        dense.push(d);
    }
    let moved: Vec<usize> = (0..n)
        .filter(|&v| {
            dense.iter().any(|d| d[v] != Vec3::ZERO)
                || channels
                    .iter()
                    .any(|&c| displacement[c].as_ref().is_some_and(|d| d[v] != Vec3::ZERO))
        })
        .collect();
    let dot = |a: &[Vec3], b: &[Vec3]| -> f64 {
        moved
            .iter()
            .map(|&v| weight[v] * f64::from(a[v].dot(b[v])))
            .sum()
    };
    let k = free.len();
    let mut gram = vec![vec![0.0f64; k]; k];
    for i in 0..k {
        for j in i..k {
            let g = dot(&dense[i], &dense[j]);
            gram[i][j] = g;
            gram[j][i] = g;
        }
    }
    // Shapes that move nothing the fit weighs are left out.
    let largest = (0..k).map(|i| gram[i][i]).fold(0.0, f64::max);
    let kept: Vec<usize> = (0..k).filter(|&i| gram[i][i] > 1e-9 * largest).collect();
    if kept.is_empty() {
        let none = |&c: &usize| Fitted {
            channel: c,
            shapes: BTreeMap::new(),
            explained: 0.0,
            with_twin: false,
        };
        return (channels.iter().map(none).collect(), None);
    }
    let scale = kept.iter().map(|&i| gram[i][i]).sum::<f64>() / kept.len() as f64;
    // Which shapes may answer to which channel: those that move the channel's region (a
    // share of their weighted energy there), so that a nose sneer is never made of a squint
    // and a brow, nor a glance of a blink.
    let share_in = |i: usize, r: Region| -> f64 {
        let inside: f64 = moved
            .iter()
            .filter(|&&v| region[v] == r)
            .map(|&v| weight[v] * f64::from(dense[i][v].length_squared()))
            .sum();
        inside / gram[i][i].max(f64::MIN_POSITIVE)
    };
    // And on the channel's side: a channel that moves one side of the face (more than
    // [`ONE_SIDED`] of its motion there) takes no shape that moves only the other side.
    let positions = character.positions();
    let centre = {
        let face: Vec<f32> = moved
            .iter()
            .filter(|&&v| region[v] != Region::Rest)
            .map(|&v| positions[v].x)
            .collect();
        face.iter().sum::<f32>() / face.len().max(1) as f32
    };
    let right_share = |d: &[Vec3]| -> f64 {
        let (mut right, mut all) = (0.0, 0.0);
        for &v in &moved {
            let e = weight[v] * f64::from(d[v].length_squared());
            all += e;
            if positions[v].x > centre {
                right += e;
            }
        }
        right / all.max(f64::MIN_POSITIVE)
    };
    let shape_sides: Vec<f64> = kept.iter().map(|&i| right_share(&dense[i])).collect();
    // A shape and its mirror twin are judged alike, by the twin more of whose motion lies in the
    // region: registration places the template a little unevenly, and on the full-body ICT
    // avatar it put 0.215 of one wide eye's motion in the lids and 0.182 of the other's, so that
    // one eye had no shape for its channel.
    let symmetry = character.symmetry();
    let twin: Vec<Option<usize>> = kept
        .iter()
        .map(|&i| {
            let partner = symmetry.partner(faceanim_rig::BlendshapeId(free[i] as u32))?;
            kept.iter().position(|&j| free[j] == partner.index())
        })
        .collect();
    let region_share = |k: usize, r: Region| -> f64 {
        let own = share_in(kept[k], r);
        twin[k].map_or(own, |t| own.max(share_in(kept[t], r)))
    };
    let allowed: Vec<Vec<bool>> = channels
        .iter()
        .map(|&c| {
            let r = Region::of_channel(faceanim_rig::names::ARKIT_52[c]);
            let side = displacement[c].as_deref().map_or(0.5, right_share);
            (0..kept.len())
                .map(|k| {
                    let same_side = if side > ONE_SIDED {
                        shape_sides[k] >= 1.0 - ONE_SIDED
                    } else if side < 1.0 - ONE_SIDED {
                        shape_sides[k] <= ONE_SIDED
                    } else {
                        true
                    };
                    same_side && region_share(k, r) >= REGION_SHARE
                })
                .collect()
        })
        .collect();
    let projections: Vec<Vec<f64>> = kept
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            channels
                .iter()
                .enumerate()
                .map(|(col, &c)| {
                    if allowed[col][k] {
                        displacement[c].as_ref().map_or(0.0, |d| dot(&dense[i], d)) / scale
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let energy: Vec<f64> = channels
        .iter()
        .map(|&c| displacement[c].as_ref().map_or(0.0, |d| dot(d, d)) / scale)
        .collect();
    let mut solve = Solve {
        shapes: kept
            .iter()
            .map(|&i| shapes[free[i]].name().to_owned())
            .collect(),
        channels: channels
            .iter()
            .map(|&c| faceanim_rig::names::ARKIT_52[c].to_owned())
            .collect(),
        gram: kept
            .iter()
            .map(|&i| kept.iter().map(|&j| (gram[i][j] / scale) as f32).collect())
            .collect(),
        projections: projections
            .iter()
            .map(|row| row.iter().map(|v| *v as f32).collect())
            .collect(),
        sparsity: SPARSITY,
    };
    // Each channel alone: its row, and how much of it the shapes explain.
    let column = |col: usize| -> Vec<f64> { projections.iter().map(|row| row[col]).collect() };
    let mut rows = Vec::new();
    let mut reached = Vec::new();
    // The fits that fell short of MIN_EXPLAINED, each with the shapes its pruning kept.
    let mut short: Vec<Option<(Vec<f32>, Vec<bool>)>> = vec![None; channels.len()];
    for (col, &c) in channels.iter().enumerate() {
        let mut unit = vec![0.0; channels.len()];
        unit[col] = 1.0;
        let b = column(col);
        let (x, explained, kept_here) = pruned_row(&solve, &unit, allowed[col].clone(), |x| {
            explained_share(&solve.gram, &b, energy[col], x)
        });
        let shapes_of_row = if explained >= MIN_EXPLAINED {
            reached.push(col);
            leave_out_pull(&mut solve, &kept_here, col);
            row_of(&x, &solve.shapes, 1.0)
        } else {
            short[col] = Some((x, kept_here));
            BTreeMap::new()
        };
        rows.push(Fitted {
            channel: c,
            shapes: shapes_of_row,
            explained: (explained * 1000.0).round() / 1000.0,
            with_twin: false,
        });
    }
    // The channel on the other side of the face (`eyeBlinkRight` for `eyeBlinkLeft`), by its
    // column.
    let twin_column = |col: usize| {
        faceanim_rig::names::Channel::named(faceanim_rig::names::ARKIT_52[channels[col]])
            .and_then(faceanim_rig::names::Channel::twin)
            .and_then(|twin| channels.iter().position(|&c| c == twin.index()))
    };
    // A channel whose fit falls short while its twin's passes, and takes the mirror images of
    // its twin's shapes, is judged as its twin is, as the region gate judges mirror twins:
    // registration is never quite even. (An ICT head exported again by Blender, which flattens
    // its vertex colours, was registered so that its left blink explained 0.675 with its own
    // `eyeBlink_L` and its right 0.734 with `eyeBlink_R`: a person's left blink moved nothing.)
    for col in 0..channels.len() {
        let (Some((x, kept_here)), Some(t)) = (short[col].take(), twin_column(col)) else {
            continue;
        };
        if rows[t].shapes.is_empty() {
            continue;
        }
        let used: BTreeSet<usize> = (0..x.len()).filter(|&k| x[k] > 0.0).collect();
        let mirrored: Option<BTreeSet<usize>> = rows[t]
            .shapes
            .keys()
            .map(|name| {
                let k = solve.shapes.iter().position(|s| s == name)?;
                twin[k]
            })
            .collect();
        if used.is_empty() || mirrored.as_ref() != Some(&used) {
            continue;
        }
        reached.push(col);
        leave_out_pull(&mut solve, &kept_here, col);
        rows[col].shapes = row_of(&x, &solve.shapes, 1.0);
    }
    // A channel of one side that no shape of one side makes, with its twin that none makes
    // either, is made of the shapes that move both sides at once: VRoid's brows, wide eyes,
    // frowns and sneers are one shape for the two sides, which explains only half of either
    // side's channel. The two sides' displacements together are matched among the shapes both
    // may take, and each side's row is half of that match, as a name that merges a left and
    // right channel is driven by their mean: both sides raised move the shape fully, one side
    // half. (Without it, a VRoid avatar with its names scrambled kept its brows still when a
    // person lowered them, its eyes when they widened.)
    for col in 0..channels.len() {
        let Some(t) = twin_column(col).filter(|&t| t > col) else {
            continue;
        };
        if !rows[col].shapes.is_empty() || !rows[t].shapes.is_empty() {
            continue;
        }
        let (Some(one), Some(other)) = (&displacement[channels[col]], &displacement[channels[t]])
        else {
            continue;
        };
        let mut pair = vec![0.0; channels.len()];
        pair[col] = 1.0;
        pair[t] = 1.0;
        let both: Vec<bool> = allowed[col]
            .iter()
            .zip(&allowed[t])
            .map(|(a, b)| *a && *b)
            .collect();
        let b: Vec<f64> = projections.iter().map(|row| row[col] + row[t]).collect();
        let e = energy[col] + energy[t] + 2.0 * dot(one, other) / scale;
        let (x, explained, kept_here) = pruned_row(&solve, &pair, both, |x| {
            explained_share(&solve.gram, &b, e, x)
        });
        if explained < MIN_EXPLAINED {
            continue;
        }
        for side in [col, t] {
            leave_out_pull(&mut solve, &kept_here, side);
            rows[side].shapes = row_of(&x, &solve.shapes, 0.5);
            rows[side].explained = (explained * 1000.0).round() / 1000.0;
            rows[side].with_twin = true;
            reached.push(side);
        }
    }
    reached.sort_unstable();
    // A channel with a shape of its own (one shape makes it, and that shape makes no other
    // channel) is driven by its row, as a named one is; the solve matches, frame by frame,
    // the channels that share shapes or need several at once. (Measured on ICT's heads with
    // their names replaced, whose shapes are one per channel: solving those per frame trades
    // one shape for another as a person's channels combine, and follows the person less.)
    let own_shape = |col: usize| -> Option<String> {
        let shapes = &rows[col].shapes;
        let (name, w) = shapes.iter().max_by(|a, b| a.1.total_cmp(b.1))?;
        let rest: f32 = shapes.values().sum::<f32>() - w;
        (rows[col].explained >= DIRECT_EXPLAINED && *w >= 0.5 && rest < 0.15).then(|| name.clone())
    };
    let mut uses: BTreeMap<&str, usize> = BTreeMap::new();
    for &col in &reached {
        for name in rows[col].shapes.keys() {
            *uses.entry(name.as_str()).or_default() += 1;
        }
    }
    let direct: Vec<(usize, String)> = reached
        .iter()
        .filter_map(|&col| own_shape(col).map(|name| (col, name)))
        .filter(|(_, name)| uses.get(name.as_str()) == Some(&1))
        .collect();
    // Regions driven by a row of their own (named, set by the user, or a shape of its own) are
    // left to it: a shape that moves one of them (a whole-face emotion raising the brows) is
    // not in the solve, or opening the mouth would raise the brows too. A channel whose row
    // needs a shape so left out cannot be matched by the solve, so it is driven by its row as
    // well (its shapes and region then leave the solve too), rather than by nothing.
    let mut by_row: Vec<(usize, Vec<String>)> = direct
        .iter()
        .map(|(col, name)| (*col, vec![name.clone()]))
        .collect();
    let (solved, shapes_left) = loop {
        let owned: Vec<Region> =
            named
                .iter()
                .copied()
                .chain(by_row.iter().map(|(col, _)| {
                    Region::of_channel(faceanim_rig::names::ARKIT_52[channels[*col]])
                }))
                .collect();
        let shapes_left: Vec<usize> = (0..solve.shapes.len())
            .filter(|&k| {
                !by_row
                    .iter()
                    .any(|(_, names)| names.contains(&solve.shapes[k]))
            })
            .filter(|&k| !owned.iter().any(|&r| share_in(kept[k], r) >= REGION_SHARE))
            .collect();
        let solved: Vec<usize> = reached
            .iter()
            .copied()
            .filter(|col| !by_row.iter().any(|(d, _)| d == col))
            .collect();
        let stranded: Vec<(usize, Vec<String>)> = solved
            .iter()
            .filter(|&&col| {
                rows[col]
                    .shapes
                    .keys()
                    .any(|name| !shapes_left.iter().any(|&k| solve.shapes[k] == *name))
            })
            .map(|&col| (col, rows[col].shapes.keys().cloned().collect()))
            .collect();
        if stranded.is_empty() {
            break (solved, shapes_left);
        }
        by_row.extend(stranded);
    };
    let solve = (!solved.is_empty() && !shapes_left.is_empty()).then(|| Solve {
        shapes: shapes_left
            .iter()
            .map(|&k| solve.shapes[k].clone())
            .collect(),
        channels: solved
            .iter()
            .map(|&col| solve.channels[col].clone())
            .collect(),
        gram: shapes_left
            .iter()
            .map(|&i| shapes_left.iter().map(|&j| solve.gram[i][j]).collect())
            .collect(),
        projections: shapes_left
            .iter()
            .map(|&k| {
                solved
                    .iter()
                    .map(|&col| solve.projections[k][col])
                    .collect()
            })
            .collect(),
        sparsity: solve.sparsity,
    });
    (rows, solve)
}

/// A row's weights for channel values `values` among the shapes `allowed`, with few shapes:
/// shapes are left out, the one that moves least first (so that of two near twins the one the
/// fit leans on stays), while the row still explains within [`MIN_GAIN`] of the best share
/// (`share` measures the share weights explain) all of them gave. The losses add up: each
/// shape judged only against the row it was left out of let four shapes go from the jaw of
/// the Blender avatar optimised by glTF Transform (`optimize`: vertices merged, quantized),
/// each for under 0.5 % and together for 1.1 %, its mouth's second shape among them, and its
/// mouth corners then dropped as the jaw opened; judged against the best they keep that
/// shape as on the plain file (0.22 against 0.23), and no ICT identity's row changes. The
/// weights, their share, and the shapes left allowed.
fn pruned_row(
    solve: &Solve,
    values: &[f32],
    mut allowed: Vec<bool>,
    share: impl Fn(&[f32]) -> f32,
) -> (Vec<f32>, f32, Vec<bool>) {
    let mut x = solve.weights_among(values, &allowed);
    let mut explained = share(&x);
    // The best share any set of the shapes left gave so far: the losses add up against it.
    let mut best = explained;
    loop {
        let used: Vec<usize> = (0..x.len()).filter(|&k| x[k] > 0.0).collect();
        if used.len() < 2 {
            break;
        }
        let weakest = used
            .iter()
            .filter_map(|&k| {
                let mut without = allowed.clone();
                without[k] = false;
                let y = solve.weights_among(values, &without);
                let without_it = share(&y);
                let size = x[k] * solve.gram[k][k].sqrt();
                (best - without_it < MIN_GAIN).then_some((size, k, y, without_it))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let Some((_, k, y, without_it)) = weakest else {
            break;
        };
        allowed[k] = false;
        x = y;
        explained = without_it;
        best = best.max(explained);
    }
    (x, explained, allowed)
}

/// Channel `col` no longer pulls, in the per-frame solve, on the shapes its row left out
/// (`kept` false): a shape pruned from a row is out of the channel's solve as well.
fn leave_out_pull(solve: &mut Solve, kept: &[bool], col: usize) {
    for (projection, kept) in solve.projections.iter_mut().zip(kept) {
        if !kept {
            projection[col] = 0.0;
        }
    }
}

/// A row from weights `x` of the shapes `names`: those at [`ROW_FLOOR`] or more, times `scale`.
fn row_of(x: &[f32], names: &[String], scale: f32) -> BTreeMap<String, f32> {
    x.iter()
        .zip(names)
        .filter(|(w, _)| **w >= ROW_FLOOR)
        .map(|(w, name)| (name.clone(), (*w * scale * 1000.0).round() / 1000.0))
        .collect()
}

/// The share of a displacement (of region-weighted size `energy`, with products `b` with the
/// shapes) that weights `x` of the shapes reproduce: `1 − |Bx − D|² / |D|²`, from the Gram
/// matrix.
fn explained_share(gram: &[Vec<f32>], b: &[f64], energy: f64, x: &[f32]) -> f32 {
    if energy <= 0.0 {
        return 0.0;
    }
    let xgx: f64 = (0..x.len())
        .map(|i| {
            (0..x.len())
                .map(|j| f64::from(x[i]) * f64::from(gram[i][j]) * f64::from(x[j]))
                .sum::<f64>()
        })
        .sum();
    let xh: f64 = (0..x.len()).map(|i| f64::from(x[i]) * b[i]).sum();
    (1.0 - (xgx - 2.0 * xh + energy) / energy).clamp(0.0, 1.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The face's parts are `rig::names::region`'s (tested there); the fit takes the tongue
    /// with the mouth, whose shapes move it.
    #[test]
    fn the_tongue_is_fit_with_the_mouth() {
        assert_eq!(Region::of_channel("tongueOut"), Region::Mouth);
        assert_eq!(Region::of_channel("eyeLookUpRight"), Region::Gaze);
    }

    /// A face of `regions` (each a run of vertices, half on the left, half on the right) with
    /// `shapes` (name, dense deltas), and how the fit weighs it: each region alike.
    struct Face {
        character: Character,
        weight: Vec<f64>,
        region: Vec<Region>,
    }

    fn face(regions: &[(Region, usize)], shapes: &[(&str, Vec<Vec3>)]) -> Face {
        let region: Vec<Region> = regions
            .iter()
            .flat_map(|&(r, n)| std::iter::repeat_n(r, n))
            .collect();
        let n = region.len();
        // Vertices 2k (left) and 2k + 1 (right) mirror each other.
        let positions: Vec<Vec3> = (0..n)
            .map(|v| {
                Vec3::new(
                    if v % 2 == 0 { -1.0 } else { 1.0 },
                    (v / 2) as f32 * 0.1,
                    0.0,
                )
            })
            .collect();
        let triangles = (0..n as u32 - 2).map(|v| [v, v + 1, v + 2]).collect();
        let blendshapes = shapes
            .iter()
            .map(|(name, d)| faceanim_rig::Blendshape::from_dense(*name, d, 1e-6))
            .collect();
        let character = Character::new(faceanim_rig::CharacterParts {
            name: "face".into(),
            positions,
            triangles,
            blendshapes,
            ..faceanim_rig::CharacterParts::default()
        })
        .unwrap();
        let weight = region
            .iter()
            .map(|r| 1.0 / region.iter().filter(|q| *q == r).count() as f64)
            .collect();
        Face {
            character,
            weight,
            region,
        }
    }

    /// Dense deltas: `d` at the vertices of `range` that `side` keeps (`None`: both sides;
    /// `Some(true)`: the right, odd ones).
    fn moving(n: usize, range: std::ops::Range<usize>, side: Option<bool>, d: Vec3) -> Vec<Vec3> {
        (0..n)
            .map(|v| {
                let on_side = side.is_none_or(|right| (v % 2 == 1) == right);
                if range.contains(&v) && on_side {
                    d
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
    }

    fn fitted(face: &Face, wanted: &[(&str, Vec<Vec3>)]) -> (Vec<Fitted>, Option<Solve>) {
        let mut displacement = vec![None; faceanim_retarget::CHANNELS];
        let mut channels = Vec::new();
        for (name, d) in wanted {
            let c = channel_index(name).unwrap();
            displacement[c] = Some(d.clone());
            channels.push(c);
        }
        let free: Vec<usize> = (0..face.character.blendshapes().len()).collect();
        fit_shapes(
            &face.character,
            &free,
            &channels,
            &displacement,
            &Weighting {
                weight: &face.weight,
                region: &face.region,
                named: &[],
            },
        )
    }

    /// The template's jaw, moved onto this face, also drops the right half of the lower lip a
    /// little: the face's own jaw makes it but for that, and its lip shape would add 0.3 % of
    /// the channel. The jaw's row is its own shape alone (it was the jaw and 0.08 of the
    /// lip, so the lip's shape then moved with every jaw), and the jaw is driven by that row.
    #[test]
    fn a_shape_that_adds_almost_nothing_stays_out_of_a_row() {
        let regions = [(Region::Jaw, 20), (Region::Mouth, 10)];
        let n = 30;
        let down = Vec3::new(0.0, -1.0, 0.0);
        let jaw = moving(n, 0..20, None, down);
        let lip_right = moving(n, 14..30, Some(true), down);
        let lip_left = moving(n, 14..30, None, down)
            .iter()
            .zip(&lip_right)
            .map(|(a, b)| *a - *b)
            .collect::<Vec<_>>();
        let template_jaw: Vec<Vec3> = jaw
            .iter()
            .zip(&lip_right)
            .map(|(j, l)| *j + 0.07 * *l)
            .collect();
        let face = face(
            &regions,
            &[
                ("jaw", jaw),
                ("lip_r", lip_right.clone()),
                ("lip_l", lip_left.clone()),
            ],
        );
        let (rows, solve) = fitted(
            &face,
            &[
                ("jawOpen", template_jaw),
                ("mouthLowerDownRight", lip_right),
                ("mouthLowerDownLeft", lip_left),
            ],
        );
        let names = |row: &Fitted| row.shapes.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&rows[0]), ["jaw"], "{:?}", rows[0]);
        assert!(rows[0].explained > 0.99, "{:?}", rows[0]);
        assert_eq!(names(&rows[1]), ["lip_r"]);
        assert!(
            solve.is_none_or(|s| !s.channels.contains(&"jawOpen".to_owned())),
            "the jaw has a shape of its own"
        );
    }

    /// The template's jaw, on this face, also pushes three patches of the chin forward, which
    /// three of the face's shapes make: each adds 0.33 % of the channel, together 1 %. Judged
    /// one at a time against the row it is left out of, all three went; judged against the
    /// best row, only as many go as lose under [`MIN_GAIN`] together.
    #[test]
    fn small_losses_add_up_against_the_best_row() {
        let n = 40;
        let regions = [(Region::Jaw, n)];
        let jaw = moving(n, 0..n, None, Vec3::new(0.0, -1.0, 0.0));
        let patches: Vec<Vec<Vec3>> = (0..3)
            .map(|p| moving(n, 6 * p..6 * (p + 1), None, Vec3::Z))
            .collect();
        let template_jaw: Vec<Vec3> = (0..n)
            .map(|v| jaw[v] + 0.15 * patches.iter().map(|p| p[v]).sum::<Vec3>())
            .collect();
        let face = face(
            &regions,
            &[
                ("jaw", jaw),
                ("chin_a", patches[0].clone()),
                ("chin_b", patches[1].clone()),
                ("chin_c", patches[2].clone()),
            ],
        );
        let (rows, _) = fitted(&face, &[("jawOpen", template_jaw)]);
        let row = &rows[0];
        // All four shapes explain it fully; the jaw alone 99.0 %.
        assert!(row.explained >= 1.0 - MIN_GAIN, "{row:?}");
        assert_eq!(row.shapes.get("jaw"), Some(&1.0), "{row:?}");
        assert!(row.shapes.len() == 3, "two of the patches stay: {row:?}");
    }

    /// The brows' region is the lowered brow's (a shape of its own), so the inner brows' two
    /// shapes stay out of the solve that matches the mouth; the inner brows' channel is driven
    /// by its row, not dropped.
    #[test]
    fn a_channel_whose_shapes_the_solve_cannot_move_is_driven_by_its_row() {
        let regions = [(Region::Brows, 8), (Region::Mouth, 8)];
        let n = 16;
        let (up, forward) = (Vec3::Y, Vec3::Z);
        let lowered_left = moving(n, 0..8, Some(false), -up);
        let inner_left = moving(n, 0..4, Some(false), up);
        let inner_right = moving(n, 0..4, Some(true), up);
        let upper_lip = moving(n, 8..12, None, forward);
        let lower_lip = moving(n, 12..16, None, forward);
        let sum =
            |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(p, q)| *p + *q).collect::<Vec<_>>();
        let face = face(
            &regions,
            &[
                ("lowered_l", lowered_left.clone()),
                ("inner_l", inner_left.clone()),
                ("inner_r", inner_right.clone()),
                ("upper", upper_lip.clone()),
                ("lower", lower_lip.clone()),
            ],
        );
        let (rows, solve) = fitted(
            &face,
            &[
                ("browDownLeft", lowered_left),
                ("browInnerUp", sum(&inner_left, &inner_right)),
                ("mouthFunnel", sum(&upper_lip, &lower_lip)),
            ],
        );
        let solve = solve.expect("the mouth needs two shapes at once");
        assert_eq!(solve.channels, ["mouthFunnel"]);
        assert_eq!(solve.shapes, ["upper", "lower"]);
        let names: Vec<String> = face.character.blendshape_names();
        let mut map = RetargetMap::by_name("face", &names, &[]);
        map.set_geometry(rows, Some(solve), Mode::Frame);
        let mut values = [0.0; faceanim_retarget::CHANNELS];
        values[channel_index("browInnerUp").unwrap()] = 0.8;
        let weights = map.weights(&values);
        assert!(weights[1] > 0.7 && weights[2] > 0.7, "{weights:?}");
        assert!(weights[0] < 0.05 && weights[3] < 0.05, "{weights:?}");
    }

    /// Registration put one of the left lid's vertices in the brows' region, so less of the
    /// left wide eye's motion lies in the lids (0.185) than of the right's (0.243), across the
    /// region gate (0.2). The twins are judged alike: each eye has its shape.
    #[test]
    fn mirror_twins_pass_the_region_gate_together() {
        let mut regions = vec![(Region::Lids, 6), (Region::Brows, 1), (Region::Lids, 1)];
        regions.push((Region::Brows, 8));
        let n = 16;
        let lid = |right: bool| moving(n, 0..8, Some(right), Vec3::Y);
        let brow = |right: bool| moving(n, 8..16, Some(right), 2.0 * Vec3::Y);
        let wide = |right: bool| -> Vec<Vec3> {
            lid(right)
                .iter()
                .zip(brow(right))
                .map(|(a, b)| *a + b)
                .collect()
        };
        let face = face(&regions, &[("wide_l", wide(false)), ("wide_r", wide(true))]);
        assert!(
            face.character
                .symmetry()
                .partner(faceanim_rig::BlendshapeId(0))
                == Some(faceanim_rig::BlendshapeId(1)),
            "the two shapes mirror each other"
        );
        let (rows, _) = fitted(
            &face,
            &[("eyeWideLeft", wide(false)), ("eyeWideRight", wide(true))],
        );
        let names = |row: &Fitted| row.shapes.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&rows[0]), ["wide_l"], "{:?}", rows[0]);
        assert_eq!(names(&rows[1]), ["wide_r"], "{:?}", rows[1]);
    }

    /// Registration placed the template's right lid off the face's: the right blink's
    /// displacement is half sideways, and its own shape explains under [`MIN_EXPLAINED`] of it.
    /// Its twin passes with the mirror image of that shape: the two are judged alike, and each
    /// eye has its blink. A shape of the other side alone is not taken so.
    #[test]
    fn a_twin_that_falls_short_with_the_mirror_shapes_is_judged_as_its_twin() {
        let regions = [(Region::Lids, 8)];
        let n = 8;
        let lid = |right: bool| moving(n, 0..8, Some(right), Vec3::Y);
        let face = face(&regions, &[("shape_0", lid(false)), ("shape_1", lid(true))]);
        let off: Vec<Vec3> = lid(true)
            .iter()
            .zip(moving(n, 0..8, Some(true), 0.9 * Vec3::Z))
            .map(|(a, b)| *a + b)
            .collect();
        let (rows, _) = fitted(
            &face,
            &[("eyeBlinkLeft", lid(false)), ("eyeBlinkRight", off.clone())],
        );
        let names = |row: &Fitted| row.shapes.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&rows[0]), ["shape_0"], "{:?}", rows[0]);
        assert!(rows[1].explained < MIN_EXPLAINED, "{:?}", rows[1]);
        assert_eq!(names(&rows[1]), ["shape_1"], "{:?}", rows[1]);
        assert!(
            (rows[1].shapes["shape_1"] - 1.0).abs() < 0.05,
            "{:?}",
            rows[1]
        );
        // Alone, the same short fit is no row.
        let (rows, _) = fitted(&face, &[("eyeBlinkRight", off)]);
        assert!(rows[0].shapes.is_empty(), "{:?}", rows[0]);
    }

    /// The face lowers its brows with one shape for both sides, as VRoid's `Fcl_BRW_Angry`
    /// does (its shapes' names say nothing): it makes half of either side's channel, and neither alone reaches. Together they
    /// do: each side's row is the shape at half, so both sides lowered move it fully, one side
    /// half, and the solve answers one side as its row does. The twin channels of a mouth that
    /// has a shape for each side keep their own.
    #[test]
    fn twin_channels_share_a_shape_that_moves_both_sides() {
        let regions = [(Region::Brows, 8), (Region::Mouth, 8)];
        let n = 16;
        let down = -Vec3::Y;
        let lowered = |side| moving(n, 0..8, side, down);
        let frown = |side| moving(n, 8..16, side, down);
        let face = face(
            &regions,
            &[
                ("shape_0", lowered(None)),
                ("shape_1", frown(Some(false))),
                ("shape_2", frown(Some(true))),
                ("shape_3", moving(n, 8..16, None, Vec3::Y)),
            ],
        );
        let (rows, solve) = fitted(
            &face,
            &[
                ("browDownLeft", lowered(Some(false))),
                ("browDownRight", lowered(Some(true))),
                ("mouthFrownLeft", frown(Some(false))),
                ("mouthFrownRight", frown(Some(true))),
            ],
        );
        for row in &rows[..2] {
            assert_eq!(row.shapes.len(), 1, "{row:?}");
            assert!((row.shapes["shape_0"] - 0.5).abs() < 0.02, "{row:?}");
            assert!(row.explained > 0.99, "{row:?}");
            assert!(row.with_twin, "{row:?}");
        }
        let names = |row: &Fitted| row.shapes.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&rows[2]), ["shape_1"], "{:?}", rows[2]);
        assert_eq!(names(&rows[3]), ["shape_2"], "{:?}", rows[3]);
        assert!(!rows[2].with_twin && !rows[3].with_twin);
        let names: Vec<String> = face.character.blendshape_names();
        let mut map = RetargetMap::by_name("face", &names, &[]);
        map.set_geometry(rows, solve, Mode::Frame);
        let index = |name: &str| channel_index(name).unwrap();
        // Kept in the map's file: calibration shows the pair together, `info` says so.
        let map = RetargetMap::from_json(map.to_json().as_bytes(), &names).unwrap();
        assert_eq!(
            map.shares_with_twin(index("browDownLeft")),
            Some(index("browDownRight"))
        );
        assert_eq!(map.shares_with_twin(index("mouthFrownLeft")), None);
        let brows = |left: f32, right: f32| {
            let mut values = [0.0; faceanim_retarget::CHANNELS];
            values[channel_index("browDownLeft").unwrap()] = left;
            values[channel_index("browDownRight").unwrap()] = right;
            map.weights(&values)
        };
        let both = brows(0.8, 0.8);
        assert!((both[0] - 0.8).abs() < 0.05, "{both:?}");
        assert!(both[1..].iter().all(|w| *w < 0.05), "{both:?}");
        let one = brows(0.8, 0.0);
        assert!((one[0] - 0.4).abs() < 0.05, "{one:?}");
    }
}
