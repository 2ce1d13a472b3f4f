//! Sparse Cholesky factorisation of the stiffness (faer 0.24, AMD ordering,
//! sequential: on two cores faer's threads only slow the solve down, see
//! shared/reference/solver.md). The symbolic analysis is done once per
//! sparsity pattern; a material change is a numeric refactorisation.

use faer::Side;
use faer::mat::MatMut;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};

use super::SolveError;
use crate::energy::Stiffness;

/// K = L Lᵀ, ready for batched solves.
#[derive(Debug)]
pub struct Factor {
    stiffness: Stiffness,
    symbolic: SymbolicLlt<usize>,
    llt: Llt<usize, f64>,
}

impl Factor {
    /// Symbolic and numeric factorisation of `stiffness`.
    pub fn new(stiffness: Stiffness) -> Result<Self, SolveError> {
        faer::set_global_parallelism(faer::Par::Seq);
        let lower = stiffness.lower();
        let symbolic = SymbolicLlt::try_new(lower.symbolic(), Side::Lower)
            .map_err(|e| SolveError::Factor(format!("symbolic analysis: {e:?}")))?;
        let llt = Llt::try_new_with_symbolic(symbolic.clone(), lower.as_ref(), Side::Lower)
            .map_err(|e| SolveError::Factor(format!("not positive definite: {e:?}")))?;
        Ok(Self {
            stiffness,
            symbolic,
            llt,
        })
    }

    /// Refactors for new values; only the numeric phase when the sparsity
    /// pattern is unchanged. On error the previous factor stays.
    pub fn refactor(&mut self, stiffness: Stiffness) -> Result<(), SolveError> {
        if !self.stiffness.same_pattern(&stiffness) {
            *self = Self::new(stiffness)?;
            return Ok(());
        }
        let llt = Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            stiffness.lower().as_ref(),
            Side::Lower,
        )
        .map_err(|e| SolveError::Factor(format!("not positive definite: {e:?}")))?;
        self.llt = llt;
        self.stiffness = stiffness;
        Ok(())
    }

    /// The factored matrix.
    pub fn stiffness(&self) -> &Stiffness {
        &self.stiffness
    }

    /// The number of unknowns.
    pub fn dim(&self) -> usize {
        self.stiffness.dim()
    }

    /// Overwrites every column of `rhs` (dim × k) with K⁻¹ times it.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.llt.solve_in_place(rhs);
    }
}
