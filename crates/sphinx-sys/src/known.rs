//! The pronouncing dictionary cut to the words the language model knows.
//!
//! A word search can only find words that are in both: US English's dictionary has 134,723
//! entries, its language model 72,547 words. Loading the other 55,000 entries and their
//! cross-word triphones costs a short line about a tenth of its time and changes nothing it
//! finds. The cut dictionary is made once per pair of model files (by their sizes and times)
//! and kept in the user's cache folder; wherever it cannot be made, the whole dictionary is
//! used, so this only ever changes the speed.

use std::collections::HashSet;
use std::hash::{Hash as _, Hasher as _};
use std::io::{Read as _, Seek as _, SeekFrom};
use std::path::{Path, PathBuf};

/// The first bytes of a language model in sphinxbase's binary trie format (`.lm.bin`).
const TRIE_HEADER: &[u8] = b"Trie Language Model";

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
        let meta = std::fs::metadata(file).ok()?;
        file.hash(&mut key);
        meta.len().hash(&mut key);
        meta.modified().ok()?.hash(&mut key);
    }
    let stem = dictionary.file_stem()?.to_string_lossy();
    let path = folder.join(format!("{stem}-{:016x}.dict", key.finish()));
    if path.is_file() {
        return Some(path);
    }
    let known = vocabulary(language_model)?;
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

/// The words of a binary trie language model: its unigram count from the header, and the
/// words themselves, NUL-terminated at the end of the file after their total length.
fn vocabulary(language_model: &Path) -> Option<HashSet<Vec<u8>>> {
    let mut file = std::fs::File::open(language_model).ok()?;
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

/// The last `count` NUL-terminated words of `bytes`, when the four bytes before them hold
/// their total length (the format's own check that they were found).
fn read_tail(bytes: &[u8], count: usize) -> Option<HashSet<Vec<u8>>> {
    if count == 0 || bytes.last() != Some(&0) {
        return None;
    }
    let mut known = HashSet::with_capacity(count);
    let mut end = bytes.len() - 1;
    for _ in 0..count {
        let start = bytes[..end]
            .iter()
            .rposition(|&b| b == 0)
            .map_or(0, |p| p + 1);
        known.insert(bytes[start..end].to_vec());
        end = start.checked_sub(1)?;
    }
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
        assert_eq!(known.len(), 4);
        assert!(known.contains(b"world's".as_slice()) && known.contains(b"<s>".as_slice()));
        // A wrong count does not match the stored length: nothing is guessed.
        assert!(read_tail(&bytes, 3).is_none());
        assert!(read_tail(&bytes, 5).is_none());
        assert!(read_tail(b"no nul at the end", 1).is_none());
    }

    #[test]
    fn us_english_is_cut_to_its_language_model() {
        let (lm, dict) = (
            Path::new(crate::EN_US.language_model),
            Path::new(crate::EN_US.dictionary),
        );
        let Some(known) = vocabulary(lm) else {
            eprintln!(
                "{} is missing: apt-get install pocketsphinx-en-us",
                lm.display()
            );
            return;
        };
        assert!(known.len() > 50_000, "{}", known.len());
        assert!(known.contains(b"birch".as_slice()) && known.contains(b"</s>".as_slice()));
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
            kept.len() * 3 < all.len() * 2,
            "{} of {}",
            kept.len(),
            all.len()
        );
        // Every entry kept is a known word, alternatives included; none known is lost.
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
