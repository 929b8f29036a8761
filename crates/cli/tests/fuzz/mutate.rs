//! Mutations of well-formed inputs, as a careless tool or an attacker makes them: bytes
//! flipped, cut, repeated or inserted; JSON values replaced by extremes (1e39, 2^63, NaN's
//! spellings, huge strings, deep nesting). Seeded, so a failure is the same on every run.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

pub struct Mutator(ChaCha8Rng);

/// Values a field may be replaced with: out of range, of the wrong type, or huge.
fn extremes(rng: &mut ChaCha8Rng) -> Value {
    match rng.random_range(0..16) {
        0 => serde_json::json!(1e39),
        1 => serde_json::json!(-1e39),
        2 => serde_json::json!(1e12),
        3 => serde_json::json!(9_223_372_036_854_775_808_u64),
        4 => serde_json::json!(u64::MAX),
        5 => serde_json::json!(-1),
        6 => serde_json::json!(0),
        7 => serde_json::json!(1e-45),
        8 => Value::String("x".repeat(rng.random_range(1..200_000))),
        9 => Value::Null,
        10 => Value::Bool(true),
        11 => serde_json::json!([]),
        12 => serde_json::json!({}),
        13 => serde_json::json!(2.5),
        14 => Value::String("\u{1b}[2J\u{0}é✓".into()),
        _ => serde_json::json!(1_000_000_000),
    }
}

impl Mutator {
    pub fn new(seed: u64) -> Mutator {
        Mutator(ChaCha8Rng::seed_from_u64(seed))
    }

    /// 1 to 4 byte-level changes of `seed`.
    pub fn bytes(&mut self, seed: &[u8]) -> Vec<u8> {
        let mut out = seed.to_vec();
        for _ in 0..self.0.random_range(1..=4) {
            let len = out.len().max(1);
            let at = self.0.random_range(0..len);
            let last = out.len().saturating_sub(1);
            match self.0.random_range(0..8) {
                0 if !out.is_empty() => out[at.min(last)] ^= 1 << self.0.random_range(0..8),
                1 if !out.is_empty() => {
                    out[at.min(last)] = [0, 0xff, 0x7f, 0x80][self.0.random_range(0..4)];
                }
                2 => out.truncate(at),
                3 => {
                    let count = self.0.random_range(1..64);
                    let noise: Vec<u8> = (0..count).map(|_| self.0.random()).collect();
                    out.splice(at.min(out.len())..at.min(out.len()), noise);
                }
                4 if out.len() > 1 => {
                    let end = (at + self.0.random_range(1..256)).min(out.len());
                    out.drain(at.min(end)..end);
                }
                5 if !out.is_empty() => {
                    let end = (at + self.0.random_range(1..512)).min(out.len());
                    let piece = out[at.min(end)..end].to_vec();
                    out.splice(at.min(out.len())..at.min(out.len()), piece);
                }
                6 if out.len() >= 4 => {
                    // A length or count field set to a huge or tiny number.
                    let word = [u32::MAX, 0, 1, 0x7fff_ffff][self.0.random_range(0..4)];
                    let at = at.min(out.len() - 4);
                    out[at..at + 4].copy_from_slice(&word.to_le_bytes());
                }
                _ => {}
            }
        }
        out
    }

    /// `seed` with 1 to 3 of its values (anywhere in the tree) replaced by extremes, and now
    /// and then a byte-level change of the text too.
    pub fn json(&mut self, seed: &Value) -> Vec<u8> {
        let mut value = seed.clone();
        for _ in 0..self.0.random_range(1..=3) {
            let mut paths = Vec::new();
            collect_paths(&value, String::new(), &mut paths);
            if paths.is_empty() {
                break;
            }
            let path = paths[self.0.random_range(0..paths.len())].clone();
            let replacement = if self.0.random_range(0..20) == 0 {
                nested(self.0.random_range(100..300))
            } else {
                extremes(&mut self.0)
            };
            if let Some(slot) = value.pointer_mut(&path) {
                *slot = replacement;
            }
        }
        let text = serde_json::to_vec(&value).unwrap_or_default();
        if self.0.random_range(0..5) == 0 {
            self.bytes(&text)
        } else {
            text
        }
    }

    /// Text of `words` random words (letters, digits, punctuation, other scripts).
    pub fn text(&mut self, words: usize) -> String {
        const PIECES: [&str; 12] = [
            "the",
            "bed",
            "mama",
            "42",
            "don't",
            "—",
            "日本語",
            "¿qué?",
            "\u{0}",
            "\n",
            "x'",
            "'",
        ];
        (0..words)
            .map(|_| PIECES[self.0.random_range(0..PIECES.len())])
            .collect::<Vec<_>>()
            .join(" ")
    }
}

fn nested(depth: usize) -> Value {
    let mut v = serde_json::json!(1);
    for _ in 0..depth {
        v = Value::Array(vec![v]);
    }
    v
}

/// Every JSON pointer in `value` (a long array contributes a few of its items).
fn collect_paths(value: &Value, at: String, out: &mut Vec<String>) {
    out.push(at.clone());
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                collect_paths(
                    v,
                    format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")),
                    out,
                );
            }
        }
        Value::Array(items) => {
            let picks = [0, 1, items.len() / 2, items.len().saturating_sub(1)];
            let mut seen = Vec::new();
            for &k in &picks {
                if k < items.len() && !seen.contains(&k) {
                    seen.push(k);
                    collect_paths(&items[k], format!("{at}/{k}"), out);
                }
            }
        }
        _ => {}
    }
}
