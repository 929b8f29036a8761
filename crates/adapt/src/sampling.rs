//! Random weight vectors for the training set, drawn in the seed's groups (every shape at a
//! random weight, or one, two or three shapes active), with mutually exclusive pairs never
//! active together, and how those pairs are found.
//!
//! A pair is exclusive when the two shapes move the same vertices in opposite directions
//! (jawLeft/jawRight, smile/frown, blink/wide): people do not do both at once, and a render of
//! both is a face the capture pipeline has never seen. Opposites are found from the geometry,
//! so a rig whose names say nothing gets the same rules, and from ARKit names when the names
//! allow; users add their own.

use faceanim_rig::{BlendshapeId, Character};
use rand::Rng as _;
use rand::seq::IndexedRandom as _;
use serde::{Deserialize, Serialize};

/// Two shapes are opposites when the cosine between their whole displacement fields is below
/// minus this. On ICT-FaceKit: eyeLookIn/eyeLookOut, jawLeft/jawRight and eyeLookUp/eyeLookDown
/// are at −0.93 to −0.97, eyeBlink/eyeWide and mouthLeft/mouthRight at −0.80,
/// mouthLowerDown/mouthPress at −0.71; pairs that only share some vertices (jawOpen and
/// mouthClose, −0.44) stay above it. Smile/frown is not opposite in geometry (above −0.3):
/// the name rules catch it where names allow.
pub const OPPOSITE_COSINE: f32 = 0.7;

/// Exclusive pairs of ARKit's names (without side; both sides are added).
const ARKIT_EXCLUSIVE: [(&str, &str); 8] = [
    ("jawLeft", "jawRight"),
    ("mouthLeft", "mouthRight"),
    ("mouthSmile", "mouthFrown"),
    ("eyeBlink", "eyeWide"),
    ("eyeLookIn", "eyeLookOut"),
    ("eyeLookUp", "eyeLookDown"),
    ("browDown", "browOuterUp"),
    ("browDown", "browInnerUp"),
];

/// Why two shapes are never active together.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExclusionReason {
    /// Their displacements point in opposite directions.
    Opposite,
    /// Their ARKit names say so (jawLeft/jawRight, smile/frown, …).
    ArkitNames,
    /// The user said so.
    User,
}

/// Two shapes never active together in a training sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExclusivePair {
    /// One shape's index.
    pub a: usize,
    /// The other's (greater than `a`).
    pub b: usize,
    /// How the pair was found.
    pub reason: ExclusionReason,
}

/// A user's exclusion rule named a shape the character does not have.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("exclusive pair {a}/{b}: the character has no blendshape named '{missing}'")]
pub struct UnknownShape {
    /// First name of the rule.
    pub a: String,
    /// Second name of the rule.
    pub b: String,
    /// The name not found.
    pub missing: String,
}

/// The cosine between two sparse displacement fields (0 when either is empty).
fn displacement_cosine(character: &Character, i: usize, j: usize) -> f32 {
    let (a, b) = (&character.blendshapes()[i], &character.blendshapes()[j]);
    let norm = |s: &faceanim_rig::Blendshape| {
        s.deltas()
            .iter()
            .map(|d| f64::from(d.length_squared()))
            .sum::<f64>()
    };
    let (na, nb) = (norm(a), norm(b));
    if na <= 0.0 || nb <= 0.0 {
        return 0.0;
    }
    // Both index lists are strictly increasing: merge them.
    let (ia, ib) = (a.indices(), b.indices());
    let (mut p, mut q, mut dot) = (0, 0, 0.0f64);
    while p < ia.len() && q < ib.len() {
        match ia[p].cmp(&ib[q]) {
            std::cmp::Ordering::Less => p += 1,
            std::cmp::Ordering::Greater => q += 1,
            std::cmp::Ordering::Equal => {
                dot += f64::from(a.deltas()[p].dot(b.deltas()[q]));
                p += 1;
                q += 1;
            }
        }
    }
    (dot / (na * nb).sqrt()) as f32
}

/// The character's exclusive pairs: opposites by geometry, ARKit name rules, and `user` rules
/// (pairs of blendshape names).
///
/// # Errors
/// [`UnknownShape`] when a user rule names a shape the character lacks.
pub fn exclusive_pairs(
    character: &Character,
    user: &[(String, String)],
) -> Result<Vec<ExclusivePair>, UnknownShape> {
    let count = character.blendshapes().len();
    let mut pairs: Vec<ExclusivePair> = Vec::new();
    let add = |a: usize, b: usize, reason: ExclusionReason, pairs: &mut Vec<ExclusivePair>| {
        let (a, b) = (a.min(b), a.max(b));
        if a != b && !pairs.iter().any(|p| p.a == a && p.b == b) {
            pairs.push(ExclusivePair { a, b, reason });
        }
    };
    for i in 0..count {
        for j in i + 1..count {
            if displacement_cosine(character, i, j) < -OPPOSITE_COSINE {
                add(i, j, ExclusionReason::Opposite, &mut pairs);
            }
        }
    }
    let arkit: Vec<Option<&'static str>> = character
        .blendshapes()
        .iter()
        .map(|s| faceanim_rig::names::arkit_name(s.name()))
        .collect();
    for (stem_a, stem_b) in ARKIT_EXCLUSIVE {
        for side in ["", "Left", "Right"] {
            let (name_a, name_b) = (format!("{stem_a}{side}"), format!("{stem_b}{side}"));
            let find = |name: &str| arkit.iter().position(|n| *n == Some(name));
            if let (Some(i), Some(j)) = (find(&name_a), find(&name_b)) {
                add(i, j, ExclusionReason::ArkitNames, &mut pairs);
            }
        }
    }
    for (a, b) in user {
        let find = |name: &str| {
            character
                .find_blendshape(name)
                .map(BlendshapeId::index)
                .ok_or_else(|| UnknownShape {
                    a: a.clone(),
                    b: b.clone(),
                    missing: name.to_owned(),
                })
        };
        add(find(a)?, find(b)?, ExclusionReason::User, &mut pairs);
    }
    pairs.sort_by_key(|p| (p.a, p.b));
    Ok(pairs)
}

/// The seed's groups of random weight vectors, drawn in equal shares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Group {
    /// Every shape at a uniform random weight (then one of each exclusive pair zeroed).
    Uniform,
    /// One shape active.
    One,
    /// Two shapes active.
    Two,
    /// Three shapes active.
    Three,
}

impl Group {
    /// All groups, in the order they are drawn.
    pub const ALL: [Group; 4] = [Group::Uniform, Group::One, Group::Two, Group::Three];
}

impl Group {
    /// The name used in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Group::Uniform => "uniform",
            Group::One => "one",
            Group::Two => "two",
            Group::Three => "three",
        }
    }

    /// The group a weight vector looks like it was drawn from, by how many shapes are active:
    /// at most one, two, three, or more (the dense group, every shape at a random weight).
    /// Works for any truth (a held-out still's), not only the sampler's draws.
    #[must_use]
    pub fn of(weights: &[f32]) -> Group {
        match weights.iter().filter(|w| **w > 0.0).count() {
            0 | 1 => Group::One,
            2 => Group::Two,
            3 => Group::Three,
            _ => Group::Uniform,
        }
    }
}

/// The error over one group's samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GroupError {
    /// Which group.
    pub group: Group,
    /// Samples in it.
    pub samples: usize,
    /// Mean absolute error over its samples and every shape.
    pub mae: f32,
}

/// The mean absolute error per [`Group`] of (truth, prediction) pairs, in [`Group::ALL`]'s
/// order; groups with no sample are left out. The seed's dense group has a floor of its own
/// (many shapes at once, some hiding others): its error is reported apart from the sparse
/// groups', where the adapter should be near exact.
pub fn errors_by_group<'a>(
    pairs: impl IntoIterator<Item = (&'a [f32], &'a [f32])>,
) -> Vec<GroupError> {
    let mut sums = [(0.0f64, 0usize, 0usize); 4];
    for (truth, predicted) in pairs {
        let slot = Group::ALL
            .iter()
            .position(|g| *g == Group::of(truth))
            .unwrap_or(0);
        let (sum, cells, samples) = &mut sums[slot];
        for (t, p) in truth.iter().zip(predicted) {
            *sum += f64::from((t - p).abs());
            *cells += 1;
        }
        *samples += 1;
    }
    Group::ALL
        .iter()
        .zip(sums)
        .filter(|(_, (_, _, samples))| *samples > 0)
        .map(|(&group, (sum, cells, samples))| GroupError {
            group,
            samples,
            mae: (sum / cells.max(1) as f64) as f32,
        })
        .collect()
}

/// Draws weight vectors for one character.
#[derive(Debug, Clone)]
pub struct WeightSampler {
    count: usize,
    /// For each shape, the shapes it excludes.
    excludes: Vec<Vec<usize>>,
}

impl WeightSampler {
    /// A sampler for `count` shapes with these exclusive pairs.
    #[must_use]
    pub fn new(count: usize, pairs: &[ExclusivePair]) -> WeightSampler {
        let mut excludes = vec![Vec::new(); count];
        for p in pairs {
            let (a, b) = (p.a, p.b);
            if a < count && b < count {
                excludes[a].push(b);
                excludes[b].push(a);
            }
        }
        WeightSampler { count, excludes }
    }

    /// One weight vector of `group`. Active weights are uniform in (0, 1].
    pub fn sample(&self, group: Group, rng: &mut impl rand::Rng) -> Vec<f32> {
        let mut weights = vec![0.0f32; self.count];
        if self.count == 0 {
            return weights;
        }
        let active = |rng: &mut dyn rand::RngCore| 1.0 - rng.random::<f32>();
        match group {
            Group::Uniform => {
                for w in &mut weights {
                    *w = active(rng);
                }
                // Zero one side of every exclusive pair, visiting shapes in a random order so
                // neither side is favoured.
                let mut order: Vec<usize> = (0..self.count).collect();
                for k in (1..order.len()).rev() {
                    order.swap(k, rng.random_range(0..=k));
                }
                for &i in &order {
                    if weights[i] > 0.0 {
                        for &j in &self.excludes[i] {
                            weights[j] = 0.0;
                        }
                    }
                }
            }
            Group::One | Group::Two | Group::Three => {
                let wanted = match group {
                    Group::One => 1,
                    Group::Two => 2,
                    _ => 3,
                };
                let mut chosen: Vec<usize> = Vec::with_capacity(wanted);
                while chosen.len() < wanted.min(self.count) {
                    let allowed: Vec<usize> = (0..self.count)
                        .filter(|i| {
                            !chosen.contains(i)
                                && !chosen.iter().any(|c| self.excludes[*c].contains(i))
                        })
                        .collect();
                    let Some(&pick) = allowed.choose(rng) else {
                        break;
                    };
                    chosen.push(pick);
                }
                for i in chosen {
                    weights[i] = active(rng);
                }
            }
        }
        weights
    }

    /// `n` vectors, groups in turn (uniform, one, two, three, uniform, …), from `seed`.
    #[must_use]
    pub fn draw(&self, n: usize, seed: u64) -> Vec<Vec<f32>> {
        use rand::SeedableRng as _;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|k| self.sample(Group::ALL[k % Group::ALL.len()], &mut rng))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(a: usize, b: usize) -> ExclusivePair {
        ExclusivePair {
            a,
            b,
            reason: ExclusionReason::User,
        }
    }

    #[test]
    fn exclusive_shapes_are_never_both_active() {
        let sampler = WeightSampler::new(6, &[pair(0, 1), pair(2, 3)]);
        let draws = sampler.draw(4000, 7);
        for w in &draws {
            assert!(w[0] == 0.0 || w[1] == 0.0, "{w:?}");
            assert!(w[2] == 0.0 || w[3] == 0.0, "{w:?}");
            assert!(w.iter().all(|x| (0.0..=1.0).contains(x)));
        }
        // The one-active group has exactly one non-zero weight; the others two and three.
        for (k, w) in draws.iter().enumerate() {
            let active = w.iter().filter(|x| **x > 0.0).count();
            match k % 4 {
                1 => assert_eq!(active, 1),
                2 => assert_eq!(active, 2),
                3 => assert_eq!(active, 3),
                _ => assert!(active >= 4, "uniform keeps the shapes of no pair: {w:?}"),
            }
        }
        // Both sides of a pair get their turn.
        assert!(draws.iter().any(|w| w[0] > 0.0) && draws.iter().any(|w| w[1] > 0.0));
    }

    #[test]
    fn the_same_seed_gives_the_same_vectors() {
        let sampler = WeightSampler::new(10, &[]);
        assert_eq!(sampler.draw(50, 3), sampler.draw(50, 3));
        assert_ne!(sampler.draw(50, 3), sampler.draw(50, 4));
    }
}
