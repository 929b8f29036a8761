//! Linear least squares over mesh vertices, three coordinates at once: the normal equations
//! `AᵀA x = Aᵀb` gathered row by row and solved by faer's sparse Cholesky factorisation.

use faer::linalg::solvers::Solve as _;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};

use crate::FitError;

/// Normal equations of a least-squares problem in `n` unknown points.
pub(crate) struct Normal {
    n: usize,
    entries: Vec<Triplet<usize, usize, f64>>,
    rhs: Vec<[f64; 3]>,
}

impl Normal {
    pub(crate) fn new(n: usize) -> Normal {
        Normal {
            n,
            entries: Vec::with_capacity(16 * n),
            rhs: vec![[0.0; 3]; n],
        }
    }

    /// Adds the residual `weight · |Σ cₖ x_{iₖ} − target|²`.
    pub(crate) fn row(&mut self, terms: &[(usize, f64)], target: [f64; 3], weight: f64) {
        for &(i, ci) in terms {
            for &(j, cj) in terms {
                self.entries.push(Triplet::new(i, j, weight * ci * cj));
            }
            for (r, t) in self.rhs[i].iter_mut().zip(target) {
                *r += weight * ci * t;
            }
        }
    }

    /// Adds `weight · |x_j − x_i − target|²`: an edge that should be `target` long.
    pub(crate) fn edge(&mut self, i: usize, j: usize, target: [f64; 3], weight: f64) {
        self.row(&[(j, 1.0), (i, -1.0)], target, weight);
    }

    /// The factorised matrix, and the right-hand side gathered so far.
    pub(crate) fn factor(self) -> Result<(Factor, Vec<[f64; 3]>), FitError> {
        self.factor_alike(&mut None)
    }

    /// As [`Normal::factor`], with `analysis` the symbolic factorisation (the ordering and
    /// the pattern) of matrices gathered with the same rows and other weights: made on the
    /// first call, reused on the next.
    pub(crate) fn factor_alike(
        self,
        analysis: &mut Option<SymbolicLlt<usize>>,
    ) -> Result<(Factor, Vec<[f64; 3]>), FitError> {
        let failed = |e: &dyn std::fmt::Debug| FitError::Solve(format!("{e:?}"));
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(self.n, self.n, &self.entries)
                .map_err(|e| failed(&e))?;
        let symbolic = match analysis {
            Some(symbolic) => symbolic.clone(),
            None => {
                let symbolic =
                    SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).map_err(|e| failed(&e))?;
                analysis.insert(symbolic).clone()
            }
        };
        let llt = Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower)
            .map_err(|e| failed(&e))?;
        Ok((Factor { n: self.n, llt }, self.rhs))
    }

    /// Solves for the points, `analysis` as in [`Normal::factor_alike`].
    pub(crate) fn solve(
        self,
        analysis: &mut Option<SymbolicLlt<usize>>,
    ) -> Result<Vec<[f64; 3]>, FitError> {
        let (factor, rhs) = self.factor_alike(analysis)?;
        Ok(factor.solve(&[rhs]).swap_remove(0))
    }
}

/// A factorised normal matrix, for right-hand sides that share it.
pub(crate) struct Factor {
    n: usize,
    llt: Llt<usize, f64>,
}

impl Factor {
    /// Solves for each right-hand side (three columns each) in one pass.
    pub(crate) fn solve(&self, rhs: &[Vec<[f64; 3]>]) -> Vec<Vec<[f64; 3]>> {
        let mut b = Mat::<f64>::zeros(self.n, 3 * rhs.len());
        for (k, side) in rhs.iter().enumerate() {
            for (i, r) in side.iter().enumerate() {
                for (c, v) in r.iter().enumerate() {
                    b[(i, 3 * k + c)] = *v;
                }
            }
        }
        self.llt.solve_in_place(b.as_mut());
        (0..rhs.len())
            .map(|k| {
                (0..self.n)
                    .map(|i| [b[(i, 3 * k)], b[(i, 3 * k + 1)], b[(i, 3 * k + 2)]])
                    .collect()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chain_pinned_at_one_end_takes_its_edges() {
        // Three points; the first held at the origin, each edge one unit along x.
        let mut normal = Normal::new(3);
        normal.row(&[(0, 1.0)], [0.0; 3], 1.0);
        normal.edge(0, 1, [1.0, 0.0, 0.0], 1.0);
        normal.edge(1, 2, [1.0, 0.0, 0.0], 1.0);
        let mut analysis = None;
        let x = normal.solve(&mut analysis).unwrap();
        for (i, p) in x.iter().enumerate() {
            assert!((p[0] - i as f64).abs() < 1e-9 && p[1].abs() < 1e-9, "{x:?}");
        }
        // The same rows with other weights, solved with the first one's analysis.
        let mut normal = Normal::new(3);
        normal.row(&[(0, 1.0)], [0.0; 3], 5.0);
        normal.edge(0, 1, [2.0, 0.0, 0.0], 3.0);
        normal.edge(1, 2, [2.0, 0.0, 0.0], 0.5);
        let x = normal.solve(&mut analysis).unwrap();
        for (i, p) in x.iter().enumerate() {
            assert!(
                (p[0] - 2.0 * i as f64).abs() < 1e-9 && p[1].abs() < 1e-9,
                "{x:?}"
            );
        }
    }
}
