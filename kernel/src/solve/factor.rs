//! Sparse Cholesky factorisation of the stiffness (faer 0.24, AMD ordering,
//! sequential: on two cores faer's threads only slow the solve down, see
//! shared/reference/solver.md). The symbolic analysis is done once per
//! sparsity pattern; a material change is a numeric refactorisation into a
//! spare buffer (so a failed one leaves the previous factor intact). The
//! low-level API is used so that the factor's values and the scratch of the
//! factorisation and of the solves are allocated once and reused.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::mat::MatMut;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, Par, Side};

use super::SolveError;
use crate::energy::Stiffness;

/// K = L Lᵀ, ready for batched solves.
pub struct Factor {
    stiffness: Stiffness,
    symbolic: SymbolicCholesky<usize>,
    /// The values of L.
    l_vals: Vec<f64>,
    /// Where the next numeric refactorisation is written (swapped with
    /// `l_vals` on success).
    spare: Vec<f64>,
    factor_mem: MemBuffer,
    solve_mem: MemBuffer,
    /// How many right-hand sides `solve_mem` is sized for.
    solve_cols: usize,
    /// Right-hand sides solved so far.
    solved: u64,
}

impl std::fmt::Debug for Factor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Factor")
            .field("dim", &self.dim())
            .field("nnz_l", &self.l_vals.len())
            .field("solve_cols", &self.solve_cols)
            .finish_non_exhaustive()
    }
}

/// Right-hand sides the solve scratch is sized for up front (x, y, z).
const INITIAL_SOLVE_COLS: usize = 3;

impl Factor {
    /// Symbolic and numeric factorisation of `stiffness`.
    pub fn new(stiffness: Stiffness) -> Result<Self, SolveError> {
        faer::set_global_parallelism(Par::Seq);
        let symbolic = factorize_symbolic_cholesky(
            stiffness.lower().symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| SolveError::Factor(format!("symbolic analysis: {e:?}")))?;
        let factor_mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        )
        .map_err(|e| SolveError::Factor(format!("factor scratch: {e:?}")))?;
        let solve_mem = MemBuffer::try_new(
            symbolic.solve_in_place_scratch::<f64>(INITIAL_SOLVE_COLS, Par::Seq),
        )
        .map_err(|e| SolveError::Factor(format!("solve scratch: {e:?}")))?;
        let len = symbolic.len_val();
        let mut this = Self {
            stiffness,
            symbolic,
            l_vals: vec![0.0; len],
            spare: vec![0.0; len],
            factor_mem,
            solve_mem,
            solve_cols: INITIAL_SOLVE_COLS,
            solved: 0,
        };
        this.numeric(None)?;
        Ok(this)
    }

    /// Numeric factorisation of `stiffness` (or of the current one) into
    /// `spare`; on success it becomes the factor.
    fn numeric(&mut self, stiffness: Option<&Stiffness>) -> Result<(), SolveError> {
        let a = stiffness.unwrap_or(&self.stiffness).lower().as_ref();
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.spare,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.factor_mem),
                Default::default(),
            )
            .map_err(|e| SolveError::Factor(format!("not positive definite: {e:?}")))?;
        std::mem::swap(&mut self.l_vals, &mut self.spare);
        Ok(())
    }

    /// Refactors for new values; only the numeric phase when the sparsity
    /// pattern is unchanged. On error the previous factor stays.
    pub fn refactor(&mut self, stiffness: Stiffness) -> Result<(), SolveError> {
        if !self.stiffness.same_pattern(&stiffness) {
            *self = Self::new(stiffness)?;
            return Ok(());
        }
        self.numeric(Some(&stiffness))?;
        self.stiffness = stiffness;
        Ok(())
    }

    /// The factored matrix.
    pub fn stiffness(&self) -> &Stiffness {
        &self.stiffness
    }

    /// Right-hand sides solved so far.
    pub fn columns_solved(&self) -> u64 {
        self.solved
    }

    /// The number of unknowns.
    pub fn dim(&self) -> usize {
        self.stiffness.dim()
    }

    /// Overwrites every column of `rhs` (dim × k) with K⁻¹ times it. The
    /// scratch grows (once) when k exceeds every earlier batch.
    pub fn solve_in_place(&mut self, rhs: MatMut<'_, f64>) {
        let k = rhs.ncols();
        self.solved += k as u64;
        if k > self.solve_cols {
            self.solve_mem =
                MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq));
            self.solve_cols = k;
        }
        LltRef::<usize, f64>::new(&self.symbolic, &self.l_vals).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
    }
}
