//! The acoustic model's Gaussians as its files hold them, and the speaker adaptation a decoder
//! can be given ([`Transform`]): the two ends of adapting the model to a voice, which the
//! speech crate estimates between them. This module owns the formats of the files read
//! (`mdef`, `means`, `variances`, `feat.params`) and written (an MLLR transform).
use std::path::{Path, PathBuf};

/// Why a model could not be read for adaptation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file is not what the model's format says it must be.
    #[error("{path}: {what}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// A model that is not phonetically tied (one codebook per phone), or whose features are
    /// not cepstra with their deltas and accelerations: adapted by no rule here.
    #[error("{0}: not a phonetically tied model over 1s_c_d_dd features")]
    Unsupported(PathBuf),
}

/// The Gaussians of a phonetically tied model (`-model ptm`): one codebook for each
/// context-independent phone, the same number of Gaussians in each, over features split in
/// streams (cepstra, their deltas, their accelerations).
#[derive(Debug, Clone, PartialEq)]
pub struct Codebooks {
    /// The phones, in the order of their codebooks (`SIL`, `AA`, `+NSN+`, …).
    pub phones: Vec<String>,
    /// Each stream's length.
    pub streams: Vec<usize>,
    /// Gaussians per codebook and stream.
    pub density: usize,
    /// Means, codebook by codebook, stream by stream, Gaussian by Gaussian.
    pub means: Vec<f32>,
    /// Variances, laid out as [`Codebooks::means`] (floored as the decoder floors them).
    pub variances: Vec<f32>,
}

/// The least variance, as the decoder floors them (`-varfloor`'s default).
const VARIANCE_FLOOR: f32 = 1e-4;

impl Codebooks {
    /// Reads the codebooks of the model in folder `acoustic`.
    ///
    /// # Errors
    /// [`ModelError`] naming the file that is missing, damaged, or not of a phonetically tied
    /// model.
    pub fn read(acoustic: &Path) -> Result<Codebooks, ModelError> {
        let params_path = acoustic.join("feat.params");
        let params = std::fs::read_to_string(&params_path).map_err(|source| ModelError::Read {
            path: params_path.clone(),
            source,
        })?;
        let setting = |name: &str| {
            params.lines().find_map(|l| {
                let mut words = l.split_whitespace();
                (words.next() == Some(name)).then(|| words.next().unwrap_or("").to_owned())
            })
        };
        if setting("-model").as_deref() != Some("ptm")
            || setting("-feat").as_deref() != Some("1s_c_d_dd")
        {
            return Err(ModelError::Unsupported(acoustic.to_path_buf()));
        }
        let phones = ci_phones(&acoustic.join("mdef"))?;
        let (shape, means) = gaussians(&acoustic.join("means"))?;
        let (shape_v, mut variances) = gaussians(&acoustic.join("variances"))?;
        let path = acoustic.join("variances");
        if shape != shape_v {
            return Err(ModelError::Format {
                path,
                what: "its shape is not the means'".into(),
            });
        }
        if shape.codebooks != phones.len() {
            return Err(ModelError::Unsupported(acoustic.to_path_buf()));
        }
        for v in &mut variances {
            *v = v.max(VARIANCE_FLOOR);
        }
        Ok(Codebooks {
            phones,
            streams: shape.streams,
            density: shape.density,
            means,
            variances,
        })
    }

    /// The codebook of `phone`, if it has one.
    #[must_use]
    pub fn codebook(&self, phone: &str) -> Option<usize> {
        self.phones.iter().position(|p| p == phone)
    }

    /// Where codebook `codebook`'s stream `stream` starts in [`Codebooks::means`].
    #[must_use]
    pub fn offset(&self, codebook: usize, stream: usize) -> usize {
        let width: usize = self.streams.iter().sum();
        let before: usize = self.streams[..stream].iter().sum();
        self.density * (codebook * width + before)
    }
}

/// A Gaussian file's shape.
#[derive(Debug, PartialEq)]
struct Shape {
    codebooks: usize,
    streams: Vec<usize>,
    density: usize,
}

fn format(path: &Path, what: &str) -> ModelError {
    ModelError::Format {
        path: path.to_path_buf(),
        what: what.to_owned(),
    }
}

fn read(path: &Path) -> Result<Vec<u8>, ModelError> {
    std::fs::read(path).map_err(|source| ModelError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Little- or big-endian 32-bit words, as the file's byte-order mark says.
struct Words<'a> {
    bytes: &'a [u8],
    at: usize,
    swapped: bool,
}

impl Words<'_> {
    fn next(&mut self) -> Option<[u8; 4]> {
        let word: [u8; 4] = self.bytes.get(self.at..self.at + 4)?.try_into().ok()?;
        self.at += 4;
        Some(if self.swapped {
            [word[3], word[2], word[1], word[0]]
        } else {
            word
        })
    }

    fn count(&mut self) -> Option<usize> {
        usize::try_from(i32::from_le_bytes(self.next()?)).ok()
    }
}

/// A Sphinx-3 Gaussian parameter file (`s3` text header up to `endhdr`, a byte-order mark,
/// then codebooks, streams, densities, each stream's length, and every value as a float).
fn gaussians(path: &Path) -> Result<(Shape, Vec<f32>), ModelError> {
    const MARK: u32 = 0x1122_3344;
    let bytes = read(path)?;
    let end = bytes
        .windows(7)
        .position(|w| w == b"endhdr\n")
        .ok_or_else(|| format(path, "no header (endhdr)"))?
        + 7;
    let mark: [u8; 4] = bytes
        .get(end..end + 4)
        .and_then(|b| b.try_into().ok())
        .ok_or_else(|| format(path, "ends after its header"))?;
    let swapped = match u32::from_le_bytes(mark) {
        MARK => false,
        m if m.swap_bytes() == MARK => true,
        _ => return Err(format(path, "no byte-order mark after its header")),
    };
    let mut words = Words {
        bytes: &bytes,
        at: end + 4,
        swapped,
    };
    let damaged = || format(path, "damaged (its counts do not fit its length)");
    let codebooks = words.count().ok_or_else(damaged)?;
    let n_streams = words.count().ok_or_else(damaged)?;
    let density = words.count().ok_or_else(damaged)?;
    if n_streams == 0 || n_streams > 8 || density == 0 || codebooks == 0 {
        return Err(damaged());
    }
    let streams: Vec<usize> = (0..n_streams)
        .map(|_| words.count().filter(|n| (1..=256).contains(n)))
        .collect::<Option<_>>()
        .ok_or_else(damaged)?;
    let total = words.count().ok_or_else(damaged)?;
    if total != codebooks * density * streams.iter().sum::<usize>()
        || bytes.len() < words.at + 4 * total
    {
        return Err(damaged());
    }
    let values = (0..total)
        .map(|_| words.next().map(f32::from_le_bytes))
        .collect::<Option<Vec<f32>>>()
        .ok_or_else(damaged)?;
    Ok((
        Shape {
            codebooks,
            streams,
            density,
        },
        values,
    ))
}

/// The context-independent phones of a binary model definition (`BMDF`): after its format
/// description, ten counts (the first the number of phones), then the phones' names, each
/// ending in a NUL.
fn ci_phones(path: &Path) -> Result<Vec<String>, ModelError> {
    const END: &[u8] = b"END FILE FORMAT DESCRIPTION\n";
    let bytes = read(path)?;
    if !bytes.starts_with(b"BMDF") {
        return Err(format(path, "not a binary model definition (BMDF)"));
    }
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or_else(|| format(path, "no end to its format description"))?
        + END.len();
    // The description is padded to a 4-byte boundary.
    let start = end.div_ceil(4) * 4;
    let swapped = false;
    let mut words = Words {
        bytes: &bytes,
        at: start,
        swapped,
    };
    let damaged = || format(path, "damaged (its phones cannot be read)");
    let mut count = words.count().ok_or_else(damaged)?;
    if !(1..=1000).contains(&count) {
        // Written on a machine of the other byte order.
        words.at = start;
        words.swapped = true;
        count = words.count().ok_or_else(damaged)?;
    }
    if !(1..=1000).contains(&count) {
        return Err(damaged());
    }
    let names_at = start + 4 * 10;
    let names = bytes.get(names_at..).ok_or_else(damaged)?;
    let phones: Vec<String> = names
        .split(|b| *b == 0)
        .take(count)
        .map(|n| String::from_utf8_lossy(n).into_owned())
        .collect();
    if phones.len() != count || phones.iter().any(|p| p.is_empty()) {
        return Err(damaged());
    }
    Ok(phones)
}

/// A speaker adaptation of the model's means (maximum likelihood linear regression, one
/// class): each stream's means become `matrix · mean + bias`; the variances are kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Transform {
    /// Per stream, as [`Codebooks::streams`]: its matrix (rows) and bias.
    pub streams: Vec<(Vec<Vec<f32>>, Vec<f32>)>,
}

impl Transform {
    /// The transform as the decoder reads it (`-mllr`, `ps_mllr_read`): classes, streams,
    /// then per stream its length, its matrix row by row, its bias and its variances' scales.
    #[must_use]
    pub fn text(&self) -> String {
        use std::fmt::Write;
        let mut out = format!("1\n{}\n", self.streams.len());
        for (matrix, bias) in &self.streams {
            let _ = writeln!(out, "{}", bias.len());
            for row in matrix {
                let row: Vec<String> = row.iter().map(|v| format!("{v:.7}")).collect();
                let _ = writeln!(out, "{}", row.join(" "));
            }
            let b: Vec<String> = bias.iter().map(|v| format!("{v:.7}")).collect();
            let _ = writeln!(out, "{}", b.join(" "));
            let ones = vec!["1.0"; bias.len()];
            let _ = writeln!(out, "{}", ones.join(" "));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_transform_is_written_as_the_decoder_reads_it() {
        let t = Transform {
            streams: vec![(vec![vec![1.0, 0.5], vec![0.0, 2.0]], vec![0.25, -1.0])],
        };
        assert_eq!(
            t.text(),
            "1\n1\n2\n1.0000000 0.5000000\n0.0000000 2.0000000\n0.2500000 -1.0000000\n1.0 1.0\n"
        );
    }

    #[test]
    fn a_file_that_is_not_a_model_is_named() {
        let dir = std::env::temp_dir().join(format!("faceanim-model-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("feat.params"), "-model ptm\n-feat 1s_c_d_dd\n").unwrap();
        std::fs::write(dir.join("mdef"), "0.3\n42 n_base\n").unwrap();
        let e = Codebooks::read(&dir).unwrap_err().to_string();
        assert!(e.contains("mdef") && e.contains("BMDF"), "{e}");
        std::fs::write(dir.join("feat.params"), "-model cont\n-feat 1s_c_d_dd\n").unwrap();
        assert!(matches!(
            Codebooks::read(&dir),
            Err(ModelError::Unsupported(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
