//! Sparse symmetric positive definite solves (faer's sparse Cholesky), for
//! the harmonic goal interpolation and the least-squares refit.

use faer::Side;
use faer::prelude::Solve;
use faer::sparse::{SparseColMat, Triplet};

use super::error::FairingError;

/// Solves A X = B for the SPD `n × n` matrix A given by its lower-triangle
/// entries (row ≥ col; duplicates are summed) and the right-hand sides `rhs`
/// (each of length n).
pub fn solve_spd(
    n: usize,
    lower: &[(usize, usize, f64)],
    rhs: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, FairingError> {
    let trip: Vec<Triplet<usize, usize, f64>> = lower
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
        .map_err(|e| FairingError::Solve(format!("{e:?}")))?;
    let llt = a
        .sp_cholesky(Side::Lower)
        .map_err(|e| FairingError::Solve(format!("{e:?}")))?;
    let mut b = faer::Mat::<f64>::zeros(n, rhs.len());
    for (j, col) in rhs.iter().enumerate() {
        for (i, v) in col.iter().enumerate() {
            b[(i, j)] = *v;
        }
    }
    let x = llt.solve(&b);
    Ok((0..rhs.len())
        .map(|j| (0..n).map(|i| x[(i, j)]).collect())
        .collect())
}
