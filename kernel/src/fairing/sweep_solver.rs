//! The linear solve of one global fairing sweep ([`super::implicit`]).
//!
//! A sweep's equations for the interior points q (3 unknowns each, rows
//! 3k..3k+3 = the point's frame x, y, z) are
//! R_k (q_k − Σ_j W_kj q_j) = r_k with the 1-ring weights W_kj = 1/m_k in
//! the two tangential rows and the goal-constrained fit's weights in the
//! normal row. Without that last difference the matrix would be
//! R (L ⊗ I₃), L = D⁻¹K the uniform graph Laplacian of the interior
//! (D the ring sizes, K = D − adjacency, symmetric positive definite and the
//! same in every sweep), whose inverse is (K⁻¹D ⊗ I₃) Rᵀ: one sparse
//! Cholesky factorisation for the whole fairing, three triangular solves
//! per application. That is the preconditioner of a BiCGSTAB solve (faer's
//! matrix-free solver, right-preconditioned so the residual it measures is
//! the true one) warm-started from the current positions, which late
//! sweeps almost satisfy. The solve stops at a residual far below what the
//! convergence test can see; if it does not get there the sweep falls
//! back to a sparse LU (the symbolic factorisation kept across sweeps).
//! Either way the sweep's solution is the same to round-off, so the
//! sweeps and their fixed point are those of the direct solve.

use faer::Side;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::bicgstab::{BicgParams, bicgstab, bicgstab_scratch};
use faer::matrix_free::{IdentityPrecond, InitialGuessStatus, LinOp, Precond};
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLu};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat, Triplet};
use faer::{Mat, MatMut, MatRef, Par};
use glam::DVec3;

use super::error::FairingError;

/// How a sweep is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepSolve {
    /// Preconditioned BiCGSTAB, LU when it does not converge.
    Iterative,
    /// Sparse LU every sweep (symbolic factorisation kept).
    Direct,
}

/// (K⁻¹ D ⊗ I₃) Rᵀ: the inverse of the sweep matrix without the normal
/// rows' non-uniform weights.
#[derive(Debug)]
struct LaplacePrecond<'a> {
    llt: &'a Llt<usize, f64>,
    degree: &'a [f64],
    frames: &'a [[DVec3; 3]],
}

impl LaplacePrecond<'_> {
    fn dim(&self) -> usize {
        3 * self.degree.len()
    }
}

impl LinOp<f64> for LaplacePrecond<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.dim()
    }

    fn ncols(&self) -> usize {
        self.dim()
    }

    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _: &mut MemStack) {
        let n = self.degree.len();
        let mut u = Mat::<f64>::zeros(n, 3);
        for col in 0..rhs.ncols() {
            for (k, ([x, y, z], m)) in self.frames.iter().zip(self.degree).enumerate() {
                let v = (*x * rhs[(3 * k, col)]
                    + *y * rhs[(3 * k + 1, col)]
                    + *z * rhs[(3 * k + 2, col)])
                    * *m;
                u[(k, 0)] = v.x;
                u[(k, 1)] = v.y;
                u[(k, 2)] = v.z;
            }
            self.llt.solve_in_place(u.as_mut());
            for k in 0..n {
                for c in 0..3 {
                    out[(3 * k + c, col)] = u[(k, c)];
                }
            }
        }
    }

    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

impl Precond<f64> for LaplacePrecond<'_> {}

/// The solver of a fairing's sweeps: the equations' pattern and the
/// factorisations that outlive a sweep.
pub struct SweepSolver {
    solve: SweepSolve,
    dim: usize,
    /// Row and column of every value a sweep pushes, in push order (the
    /// first sweep's; later sweeps push the same sequence).
    pairs: Vec<Pair<usize, usize>>,
    pattern: Option<(SymbolicSparseColMat<usize>, Argsort<usize>)>,
    symbolic_lu: Option<SymbolicLu<usize>>,
    laplace: Option<Llt<usize, f64>>,
    degree: Vec<f64>,
    /// BiCGSTAB iterations per sweep (0: solved by LU).
    pub iterations: Vec<usize>,
}

impl SweepSolver {
    /// A solver for `interior` points whose 1-rings (interior neighbours
    /// as interior indices) are `rings` and whose ring sizes (boundary
    /// neighbours included) are `degree`. Without a Cholesky factorisation
    /// of the interior Laplacian (points cut off from the boundary) every
    /// sweep is solved by LU.
    pub fn new(
        solve: SweepSolve,
        rings: &[Vec<usize>],
        degree: Vec<f64>,
    ) -> Result<Self, FairingError> {
        let n = rings.len();
        let laplace = if solve == SweepSolve::Iterative {
            let mut trip = Vec::new();
            for (k, ring) in rings.iter().enumerate() {
                trip.push(Triplet::new(k, k, degree[k]));
                for &j in ring {
                    if j < k {
                        trip.push(Triplet::new(k, j, -1.0));
                    }
                }
            }
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
                .map_err(|e| FairingError::Solve(format!("{e:?}")))?;
            // Not positive definite (interior points cut off from the
            // boundary): no preconditioner, every sweep by LU.
            a.sp_cholesky(Side::Lower).ok()
        } else {
            None
        };
        Ok(Self {
            solve,
            dim: 3 * n,
            pairs: Vec::new(),
            pattern: None,
            symbolic_lu: None,
            laplace,
            degree,
            iterations: Vec::new(),
        })
    }

    /// Whether the next sweep must report its entries' rows and columns.
    pub fn needs_pattern(&self) -> bool {
        self.pattern.is_none()
    }

    /// Records an entry's position (first sweep only).
    pub fn push_pair(&mut self, row: usize, col: usize) {
        self.pairs.push(Pair::new(row, col));
    }

    /// Solves the sweep whose values (in push order) are `values` and
    /// right-hand side `rhs`, frames `frames` (x, y, z per interior point),
    /// starting from `guess`; the solution is written to `guess`.
    pub fn solve(
        &mut self,
        values: &[f64],
        rhs: &Mat<f64>,
        frames: &[[DVec3; 3]],
        guess: &mut Mat<f64>,
    ) -> Result<(), FairingError> {
        let err = |e: &dyn std::fmt::Debug| FairingError::Solve(format!("{e:?}"));
        if self.pattern.is_none() {
            let p = SymbolicSparseColMat::try_new_from_indices(self.dim, self.dim, &self.pairs)
                .map_err(|e| err(&e))?;
            self.pattern = Some(p);
            self.pairs = Vec::new();
        }
        let (sym, order) = self.pattern.as_ref().expect("pattern built above");
        let a = SparseColMat::new_from_argsort(sym.clone(), order, values).map_err(|e| err(&e))?;
        if let (SweepSolve::Iterative, Some(llt)) = (self.solve, &self.laplace) {
            let pre = LaplacePrecond {
                llt,
                degree: &self.degree,
                frames,
            };
            let left = IdentityPrecond { dim: self.dim };
            let mat = a.as_ref();
            let params = BicgParams::<f64> {
                initial_guess: InitialGuessStatus::MaybeNonZero,
                abs_tolerance: 0.0,
                rel_tolerance: 1e-13,
                max_iters: 200,
                ..Default::default()
            };
            let mut x = guess.clone();
            let mut buf = MemBuffer::new(bicgstab_scratch(&left, &pre, mat, 1, Par::Seq));
            let r = bicgstab(
                x.as_mut(),
                &left,
                &pre,
                mat,
                rhs.as_ref(),
                params,
                |_| {},
                Par::Seq,
                MemStack::new(&mut buf),
            );
            if let Ok(info) = r
                && x.col(0).iter().all(|v| v.is_finite())
            {
                self.iterations.push(info.iter_count);
                *guess = x;
                return Ok(());
            }
        }
        if self.symbolic_lu.is_none() {
            self.symbolic_lu = Some(SymbolicLu::try_new(sym.as_ref()).map_err(|e| err(&e))?);
        }
        let lu = Lu::try_new_with_symbolic(
            self.symbolic_lu.clone().expect("symbolic LU built above"),
            a.as_ref(),
        )
        .map_err(|e| err(&e))?;
        *guess = lu.solve(rhs);
        self.iterations.push(0);
        Ok(())
    }
}
