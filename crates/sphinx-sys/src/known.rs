//! The pronouncing dictionary cut to the words the language model finds likeliest.
//!
//! A word search can only find words that are in both: US English's dictionary has 134,723
//! entries, its language model 72,547 words. Lip sync wants the words' phones, not the words:
//! a rare word the search cannot name is heard as common words that sound alike. So the
//! dictionary keeps the language model's [`KEPT_WORDS`] likeliest words (by their unigram
//! probability), which makes the search tree a third of the size and a line's whole command
//! about a third faster, at the same agreement on the voices it was chosen on.
//!
//! The cut dictionary is made once per pair of model files (told apart by their contents) and
//! kept in the user's cache folder. Where the unigrams cannot be read every word of the model is
//! kept; where nothing can be read or kept the whole dictionary is used.

use std::collections::HashSet;
use std::hash::{Hash as _, Hasher as _};
use std::io::{Read as _, Seek as _, SeekFrom};
use std::path::{Path, PathBuf};

/// The first bytes of a language model in sphinxbase's binary trie format (`.lm.bin`).
const TRIE_HEADER: &[u8] = b"Trie Language Model";

/// How many of the language model's words the dictionary keeps, likeliest first. Chosen on
/// the tuning voices (flite slt, rms, awb; eSpeak NG en-us+m3, audio alone): the smallest of
/// 5,000, 10,000, 15,000, 20,000 and 30,000 whose mean agreement and mean share of P, B, M
/// closed stay within 0.01 of all 72,547 words'.
pub(crate) const KEPT_WORDS: usize = 20_000;

/// The quantisation tables a trie model of `order` stores before its unigrams: 16-bit
/// probabilities and back-offs for each middle order, probabilities for the longest.
fn quantised_values(order: usize) -> usize {
    (order - 2) * ((1 << 16) + (1 << 16)) + (1 << 16)
}

/// The dictionary a word search over `language_model` reads: `dictionary` cut to the model's
/// words (cached), or `dictionary` itself when the model is not a binary trie or the cut
/// cannot be made or kept.
pub(crate) fn dictionary_for(language_model: &Path, dictionary: &Path) -> PathBuf {
    cache_folder()
        .and_then(|folder| cut(&folder, language_model, dictionary))
        .unwrap_or_else(|| dictionary.to_owned())
}

/// `dictionary` cut to `language_model`'s words, kept in `folder` (made there when missing).
fn cut(folder: &Path, language_model: &Path, dictionary: &Path) -> Option<PathBuf> {
    let mut key = std::collections::hash_map::DefaultHasher::new();
    for file in [language_model, dictionary] {
        fingerprint(file, &mut key)?;
    }
    let stem = dictionary.file_stem()?.to_string_lossy();
    let path = folder.join(format!("{stem}-{:016x}-{KEPT_WORDS}.dict", key.finish()));
    if path.is_file() {
        return Some(path);
    }
    let known = likeliest(language_model, KEPT_WORDS)?;
    let text = std::fs::read(dictionary).ok()?;
    let mut kept = Vec::with_capacity(text.len() / 2);
    for line in text.split_inclusive(|&b| b == b'\n') {
        let word = line.split(|&b| b == b' ' || b == b'\t').next()?;
        // Alternative pronunciations are `word(2)`.
        let word = word.split(|&b| b == b'(').next()?;
        if known.contains(word) {
            kept.extend_from_slice(line);
        }
    }
    if kept.is_empty() {
        return None;
    }
    std::fs::create_dir_all(folder).ok()?;
    // Written whole under a name of its own (this process's, this call's), then renamed: a
    // reader never sees half a file.
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let partial = folder.join(format!(
        ".{}.{}-{}.partial",
        path.file_name()?.to_string_lossy(),
        std::process::id(),
        CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    match std::fs::write(&partial, &kept).and_then(|()| std::fs::rename(&partial, &path)) {
        Ok(()) => Some(path),
        Err(_) => {
            let _ = std::fs::remove_file(&partial);
            None
        }
    }
}

/// Bytes read from each of three places of a file (its start, middle and end) to tell it from
/// another.
const SAMPLED: usize = 1 << 16;

/// Hashes what tells `file` from another into `key`: its length and [`SAMPLED`] bytes from its
/// start, middle and end. Not its path or time: the same model built into another folder (a
/// second checkout, a reinstall) is the same model and finds the cut made for it, where a
/// key by path and time left one more file in the cache for each. A model changed in place
/// with its length and those bytes kept would be missed; models are not edited so.
fn fingerprint(file: &Path, key: &mut impl std::hash::Hasher) -> Option<()> {
    let mut file = std::fs::File::open(file).ok()?;
    let len = file.metadata().ok()?.len();
    len.hash(key);
    let mut buffer = vec![0u8; SAMPLED];
    for at in [0, len / 2, len.saturating_sub(SAMPLED as u64)] {
        file.seek(SeekFrom::Start(at)).ok()?;
        let mut read = 0;
        loop {
            match file.read(&mut buffer[read..]) {
                Ok(0) => break,
                Ok(n) => read += n,
                Err(_) => return None,
            }
        }
        buffer[..read].hash(key);
    }
    Some(())
}

/// Where faceanim keeps what it can make again: `$XDG_CACHE_HOME/faceanim`,
/// `~/.cache/faceanim`, `%LOCALAPPDATA%\faceanim`.
fn cache_folder() -> Option<PathBuf> {
    let var = |name: &str| {
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("XDG_CACHE_HOME")
        .or_else(|| var("HOME").map(|home| home.join(".cache")))
        .or_else(|| var("LOCALAPPDATA"))
        .map(|base| base.join("faceanim"))
}

/// The `keep` likeliest words of a binary trie language model by their unigram probability,
/// or all its words when its unigrams cannot be read.
fn likeliest(language_model: &Path, keep: usize) -> Option<HashSet<Vec<u8>>> {
    let mut file = std::fs::File::open(language_model).ok()?;
    let words = vocabulary(&mut file)?;
    let Some(probabilities) = unigrams(&mut file, words.len()) else {
        return Some(words.into_iter().collect());
    };
    let mut ranked: Vec<(f32, Vec<u8>)> = probabilities.into_iter().zip(words).collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    Some(
        ranked
            .into_iter()
            .take(keep)
            .map(|(_, word)| word)
            .collect(),
    )
}

/// The log probability of each of a trie model's `count` unigrams, in the order of its
/// words: after the header (the order, the n-gram counts) and the quantisation tables, each
/// unigram is a probability, a back-off and the index of its first bigram. `None` where the
/// header does not say `count` unigrams or a probability is not a log probability.
fn unigrams(file: &mut std::fs::File, count: usize) -> Option<Vec<f32>> {
    file.seek(SeekFrom::Start(TRIE_HEADER.len() as u64)).ok()?;
    let mut order = [0u8];
    file.read_exact(&mut order).ok()?;
    let order = usize::from(order[0]);
    // sphinxbase reads up to five orders; a unigram model has no quantisation tables.
    if !(2..=5).contains(&order) {
        return None;
    }
    let mut counts = vec![0u8; 4 * order];
    file.read_exact(&mut counts).ok()?;
    if u32::from_le_bytes(counts[..4].try_into().ok()?) as usize != count {
        return None;
    }
    // A 4-byte word before the tables, which sphinxbase skips.
    file.seek(SeekFrom::Current(4 + 4 * quantised_values(order) as i64))
        .ok()?;
    let mut bytes = vec![0u8; 12 * count];
    file.read_exact(&mut bytes).ok()?;
    let probabilities: Vec<f32> = bytes
        .chunks_exact(12)
        .map(|unigram| f32::from_le_bytes([unigram[0], unigram[1], unigram[2], unigram[3]]))
        .collect();
    probabilities
        .iter()
        .all(|p| p.is_finite() && *p <= 0.0)
        .then_some(probabilities)
}

/// The words of a binary trie language model, in the order of their unigrams: their count
/// from the header, and the words themselves, NUL-terminated at the end of the file after
/// their total length.
fn vocabulary(file: &mut std::fs::File) -> Option<Vec<Vec<u8>>> {
    let mut head = [0u8; TRIE_HEADER.len() + 1 + 4];
    file.read_exact(&mut head).ok()?;
    if !head.starts_with(TRIE_HEADER) || head[TRIE_HEADER.len()] == 0 {
        return None;
    }
    let count_at = TRIE_HEADER.len() + 1;
    let words = u32::from_le_bytes(head[count_at..count_at + 4].try_into().ok()?) as usize;
    let length = file.metadata().ok()?.len();
    // Words of up to 64 bytes on average: far more than any language has.
    let tail = length.min(words as u64 * 64 + 4);
    file.seek(SeekFrom::Start(length - tail)).ok()?;
    let mut bytes = Vec::with_capacity(tail as usize);
    file.read_to_end(&mut bytes).ok()?;
    read_tail(&bytes, words)
}

/// The last `count` NUL-terminated words of `bytes`, in their order, when the four bytes
/// before them hold their total length (the format's own check that they were found).
fn read_tail(bytes: &[u8], count: usize) -> Option<Vec<Vec<u8>>> {
    if count == 0 || bytes.last() != Some(&0) {
        return None;
    }
    let mut known = Vec::with_capacity(count);
    let mut end = bytes.len() - 1;
    for _ in 0..count {
        let start = bytes[..end]
            .iter()
            .rposition(|&b| b == 0)
            .map_or(0, |p| p + 1);
        known.push(bytes[start..end].to_vec());
        end = start.checked_sub(1)?;
    }
    known.reverse();
    let first = end + 1;
    let stored = u32::from_le_bytes(bytes.get(first.checked_sub(4)?..first)?.try_into().ok()?);
    (stored as usize == bytes.len() - first).then_some(known)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trie model's tail as sphinxbase writes it: the length, then the words.
    fn tail(prefix: &[u8], words: &[&str]) -> Vec<u8> {
        let text: Vec<u8> = words.iter().flat_map(|w| w.bytes().chain([0])).collect();
        let mut out = prefix.to_vec();
        out.extend(u32::try_from(text.len()).unwrap_or(0).to_le_bytes());
        out.extend(text);
        out
    }

    #[test]
    fn the_words_at_the_end_are_found_and_checked_by_their_length() {
        let bytes = tail(
            b"trie data \0 with nuls\0",
            &["<s>", "a", "hello", "world's"],
        );
        let known = read_tail(&bytes, 4).unwrap();
        assert_eq!(known, [&b"<s>"[..], b"a", b"hello", b"world's"]);
        // A wrong count does not match the stored length: nothing is guessed.
        assert!(read_tail(&bytes, 3).is_none());
        assert!(read_tail(&bytes, 5).is_none());
        assert!(read_tail(b"no nul at the end", 1).is_none());
    }

    /// A bigram trie model as sphinxbase lays it out, with these unigrams, up to the bigrams
    /// (which are not read), then its words.
    fn model(words: &[(&str, f32)]) -> Vec<u8> {
        let mut out = TRIE_HEADER.to_vec();
        out.push(2);
        let count = u32::try_from(words.len()).unwrap_or(0);
        out.extend(count.to_le_bytes());
        out.extend(7u32.to_le_bytes());
        out.extend([0u8; 4]);
        out.extend(std::iter::repeat_n(0u8, 4 * quantised_values(2)));
        for (i, (_, p)) in words.iter().chain([&("", 0.0)]).enumerate() {
            out.extend(p.to_le_bytes());
            out.extend((-0.5f32).to_le_bytes());
            out.extend(u32::try_from(i).unwrap_or(0).to_le_bytes());
        }
        out.extend(b"bigrams \0 and trigrams\0");
        let names: Vec<&str> = words.iter().map(|(w, _)| *w).collect();
        tail(&out, &names)
    }

    fn likeliest_of(bytes: &[u8], keep: usize) -> Option<HashSet<Vec<u8>>> {
        let path = std::env::temp_dir().join(format!(
            "faceanim-known-model-{}-{keep}-{}.lm.bin",
            std::process::id(),
            bytes.len()
        ));
        std::fs::write(&path, bytes).ok()?;
        let known = likeliest(&path, keep);
        let _ = std::fs::remove_file(&path);
        known
    }

    #[test]
    fn the_likeliest_words_are_kept_or_all_when_the_unigrams_are_unreadable() {
        let words = [
            ("<s>", -99.0),
            ("the", -1.2),
            ("zyuganov", -6.5),
            ("birch", -5.0),
        ];
        let set = |w: &[&str]| {
            w.iter()
                .map(|w| w.as_bytes().to_vec())
                .collect::<HashSet<_>>()
        };
        assert_eq!(
            likeliest_of(&model(&words), 2),
            Some(set(&["the", "birch"]))
        );
        assert_eq!(
            likeliest_of(&model(&words), 9),
            Some(set(&["<s>", "the", "zyuganov", "birch"]))
        );
        // A probability above one is no log probability: every word is kept, none guessed.
        let odd = [
            ("<s>", -99.0),
            ("the", 1.2),
            ("zyuganov", -6.5),
            ("birch", -5.0),
        ];
        assert_eq!(likeliest_of(&model(&odd), 2).map(|k| k.len()), Some(4));
        // Cut short before the unigrams end: the same.
        let mut short = model(&words);
        short.truncate(TRIE_HEADER.len() + 1 + 8 + 4 + 4 * quantised_values(2) + 20);
        short.extend(tail(&[], &["<s>", "the", "zyuganov", "birch"]));
        assert_eq!(likeliest_of(&short, 2).map(|k| k.len()), Some(4));
    }

    #[test]
    fn a_cut_is_found_again_by_its_models_contents_wherever_they_lie() {
        let root =
            std::env::temp_dir().join(format!("faceanim-known-copies-{}", std::process::id()));
        let cache = root.join("cache");
        let words = [("<s>", -99.0), ("the", -1.2), ("birch", -5.0)];
        let dictionary = b"the DH AH0\nthe(2) DH IY0\nbirch B ER1 CH\nplanks P L AE1 NG K S\n";
        let place = |folder: &str, dictionary: &[u8]| {
            let folder = root.join(folder);
            std::fs::create_dir_all(&folder).unwrap();
            let (lm, dict) = (folder.join("m.lm.bin"), folder.join("m.dict"));
            std::fs::write(&lm, model(&words)).unwrap();
            std::fs::write(&dict, dictionary).unwrap();
            cut(&cache, &lm, &dict).unwrap()
        };
        let first = place("checkout-1", dictionary);
        assert_eq!(
            std::fs::read(&first).unwrap(),
            b"the DH AH0\nthe(2) DH IY0\nbirch B ER1 CH\n",
            "the model's words, not the others"
        );
        // The same files in another folder, written at another time: the same cut.
        assert_eq!(place("checkout-2", dictionary), first);
        // Another dictionary: a cut of its own.
        let mut changed = dictionary.to_vec();
        changed.extend_from_slice(b"birch(2) B IH1 R CH\n");
        assert_ne!(place("checkout-3", &changed), first);
        assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 2);
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn us_english_is_cut_to_its_language_models_likeliest_words() {
        let (lm, dict) = (
            Path::new(crate::EN_US.language_model),
            Path::new(crate::EN_US.dictionary),
        );
        let Some(known) = likeliest(lm, KEPT_WORDS) else {
            eprintln!(
                "{} is missing: apt-get install pocketsphinx-en-us",
                lm.display()
            );
            return;
        };
        assert_eq!(known.len(), KEPT_WORDS);
        for word in ["the", "</s>", "mama", "made", "bed", "canoe", "smooth"] {
            assert!(known.contains(word.as_bytes()), "{word}");
        }
        // Rare words are heard as common ones that sound alike.
        for word in ["birch", "planks", "zyuganov"] {
            assert!(!known.contains(word.as_bytes()), "{word}");
        }
        let cache = std::env::temp_dir().join(format!("faceanim-known-{}", std::process::id()));
        let made = cut(&cache, lm, dict).unwrap();
        assert_eq!(
            cut(&cache, lm, dict),
            Some(made.clone()),
            "made once, then found"
        );
        assert!(made.starts_with(&cache), "{}", made.display());
        let kept = std::fs::read(&made).unwrap();
        let kept: HashSet<&[u8]> = kept.split(|&b| b == b'\n').collect();
        let all = std::fs::read(dict).unwrap();
        let all: Vec<&[u8]> = all
            .split(|&b| b == b'\n')
            .filter(|l| !l.is_empty())
            .collect();
        assert!(
            kept.len() * 5 < all.len(),
            "{} of {}",
            kept.len(),
            all.len()
        );
        // Every entry kept is a kept word, alternatives included; none kept is lost.
        for line in all {
            let word = line.split(|&b| b == b' ' || b == b'(').next().unwrap();
            assert_eq!(
                kept.contains(line),
                known.contains(word),
                "{}",
                String::from_utf8_lossy(line)
            );
        }
        let _ = std::fs::remove_dir_all(&cache);
    }
}
