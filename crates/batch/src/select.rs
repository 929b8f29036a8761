//! Which rows a worker runs: all of them, one by its index, or a shard.
//!
//! Array-job engines give each worker its index in a variable: Kubernetes' Indexed Jobs
//! `JOB_COMPLETION_INDEX`, AWS Batch `AWS_BATCH_JOB_ARRAY_INDEX`, Slurm `SLURM_ARRAY_TASK_ID`
//! (submit with `--array=0-N` so that it counts from 0, as the others do).

use crate::BatchError;

/// The variables that give a worker its row, in the order they are looked at.
pub const INDEX_VARIABLES: [&str; 3] = [
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "SLURM_ARRAY_TASK_ID",
];

/// The rows to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Selection {
    /// Every row.
    All,
    /// The row at this index (0-based, among the manifest's rows).
    Index(usize),
    /// The rows whose index is `part` modulo `of`.
    Shard {
        /// Which share (0-based).
        part: usize,
        /// Of how many.
        of: usize,
    },
}

impl Selection {
    /// The selection asked for: `--index`, else `--shard` (`i/n`), else the first index
    /// variable set (`var` reads one), else every row.
    ///
    /// # Errors
    /// [`BatchError::Selection`] for a shard or a variable that is not a number.
    pub fn choose(
        index: Option<usize>,
        shard: Option<&str>,
        var: impl Fn(&str) -> Option<String>,
    ) -> Result<Selection, BatchError> {
        if let Some(index) = index {
            return Ok(Selection::Index(index));
        }
        if let Some(shard) = shard {
            return Selection::shard(shard);
        }
        for name in INDEX_VARIABLES {
            if let Some(value) = var(name).filter(|v| !v.trim().is_empty()) {
                let index = value.trim().parse().map_err(|_| {
                    BatchError::Selection(format!("{name}={value} is not a row index"))
                })?;
                return Ok(Selection::Index(index));
            }
        }
        Ok(Selection::All)
    }

    /// `i/n`: the `i`th of `n` shares (0-based).
    ///
    /// # Errors
    /// [`BatchError::Selection`] when it is not two numbers with `i < n`.
    pub fn shard(text: &str) -> Result<Selection, BatchError> {
        let bad = || {
            BatchError::Selection(format!(
                "--shard {text}: give I/N, the Ith of N shares counting from 0 (0/4 … 3/4)"
            ))
        };
        let (part, of) = text.split_once('/').ok_or_else(bad)?;
        let part: usize = part.trim().parse().map_err(|_| bad())?;
        let of: usize = of.trim().parse().map_err(|_| bad())?;
        if of == 0 || part >= of {
            return Err(bad());
        }
        Ok(Selection::Shard { part, of })
    }

    /// Whether the row at `index` is selected.
    #[must_use]
    pub fn contains(self, index: usize) -> bool {
        match self {
            Selection::All => true,
            Selection::Index(i) => i == index,
            Selection::Shard { part, of } => index % of == part,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flag_wins_over_the_variables_and_the_first_variable_over_the_others() {
        let vars = |name: &str| match name {
            "JOB_COMPLETION_INDEX" => Some("7".to_owned()),
            "SLURM_ARRAY_TASK_ID" => Some("3".to_owned()),
            _ => None,
        };
        assert_eq!(
            Selection::choose(Some(2), None, vars).unwrap(),
            Selection::Index(2)
        );
        assert_eq!(
            Selection::choose(None, None, vars).unwrap(),
            Selection::Index(7)
        );
        assert_eq!(
            Selection::choose(None, Some("1/4"), vars).unwrap(),
            Selection::Shard { part: 1, of: 4 }
        );
        assert_eq!(
            Selection::choose(None, None, |_| None).unwrap(),
            Selection::All
        );
        let error = Selection::choose(None, None, |n: &str| {
            (n == "AWS_BATCH_JOB_ARRAY_INDEX").then(|| "x".to_owned())
        })
        .unwrap_err();
        assert!(error.to_string().contains("AWS_BATCH_JOB_ARRAY_INDEX=x"));
    }

    #[test]
    fn shards_cover_every_row_once() {
        for text in ["4/4", "1/0", "a/2", "3"] {
            assert!(Selection::shard(text).is_err(), "{text}");
        }
        let shards: Vec<_> = (0..3)
            .map(|i| Selection::shard(&format!("{i}/3")).unwrap())
            .collect();
        for index in 0..100 {
            assert_eq!(shards.iter().filter(|s| s.contains(index)).count(), 1);
        }
    }
}
