//! The exact Galerkin stiffness of the thin-plate deformation energy.
//!
//! For a surface w(u,v) = Σ N_i(u) M_j(v) P_ij the energy of a displacement
//! field x (one coordinate; x, y and z share the matrix) is the quadratic
//! form xᵀ K x with
//!
//! ```text
//! K = α11 G11⊗H00 + α12 (G10⊗H01 + G01⊗H10) + α22 G00⊗H11
//!   + β11 G22⊗H00 + 2β12 G11⊗H11 + β22 G00⊗H22 + rest G00⊗H00
//! ```
//!
//! where G_ab, H_ab are the 1-D Gram matrices ([`super::gram::Gram`]) in u
//! and v and `A⊗B` at ((i,j),(k,l)) is A[i][k]·B[j][l]. For a curve,
//! K = α G11 + β G22 + rest G00. The matrix is stored as its lower triangle
//! in compressed columns, which is what the sparse Cholesky reads.

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use thiserror::Error;

use super::gram::Gram;
use super::material::{CurveMaterial, MaterialError, SurfaceMaterial};
use crate::bspline::KnotVector;

/// The stiffness could not be built.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum StiffnessError {
    /// The material is invalid.
    #[error(transparent)]
    Material(#[from] MaterialError),
    /// The sparse matrix could not be allocated.
    #[error("stiffness matrix: {0}")]
    Build(String),
}

/// A symmetric positive definite stiffness matrix (lower triangle stored),
/// independent of the shape model that produced it.
#[derive(Clone, Debug)]
pub struct Stiffness {
    lower: SparseColMat<usize, f64>,
}

impl Stiffness {
    /// The stiffness of a tensor-product surface with knots `u`, `v` and `m`.
    pub fn surface(
        u: &KnotVector,
        v: &KnotVector,
        m: &SurfaceMaterial,
    ) -> Result<Self, StiffnessError> {
        m.validate()?;
        let gu = Gram::new(u);
        let gv = Gram::new(v);
        let (nu, nv) = (gu.len(), gv.len());
        let (pu, pv) = (gu.degree(), gv.degree());
        let n = nu * nv;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut rows = Vec::with_capacity(n * (pu + 1) * (2 * pv + 1));
        let mut vals = Vec::with_capacity(rows.capacity());
        col_ptr.push(0);
        let entry = |i: usize, j: usize, k: usize, l: usize| -> f64 {
            let g = |a, b| gu.get(a, b, i, k);
            let h = |a, b| gv.get(a, b, j, l);
            m.alpha11 * g(1, 1) * h(0, 0)
                + m.alpha12 * (g(1, 0) * h(0, 1) + g(0, 1) * h(1, 0))
                + m.alpha22 * g(0, 0) * h(1, 1)
                + m.beta11 * g(2, 2) * h(0, 0)
                + 2.0 * m.beta12 * g(1, 1) * h(1, 1)
                + m.beta22 * g(0, 0) * h(2, 2)
                + m.rest * g(0, 0) * h(0, 0)
        };
        for k in 0..nu {
            for l in 0..nv {
                for i in k..(k + pu + 1).min(nu) {
                    let j0 = if i == k { l } else { l.saturating_sub(pv) };
                    for j in j0..(l + pv + 1).min(nv) {
                        rows.push(i * nv + j);
                        vals.push(entry(i, j, k, l));
                    }
                }
                col_ptr.push(rows.len());
            }
        }
        Self::from_csc(n, col_ptr, rows, vals)
    }

    /// The stiffness of a curve with knots `kv` and material `m`.
    pub fn curve(kv: &KnotVector, m: &CurveMaterial) -> Result<Self, StiffnessError> {
        m.validate()?;
        let g = Gram::new(kv);
        let (n, p) = (g.len(), g.degree());
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        let mut vals = Vec::new();
        for k in 0..n {
            for i in k..(k + p + 1).min(n) {
                rows.push(i);
                vals.push(
                    m.alpha * g.get(1, 1, i, k)
                        + m.beta * g.get(2, 2, i, k)
                        + m.rest * g.get(0, 0, i, k),
                );
            }
            col_ptr.push(rows.len());
        }
        Self::from_csc(n, col_ptr, rows, vals)
    }

    /// The block-diagonal stiffness of independent parts solved together
    /// (joined surfaces, [`crate::product`]): block `k`'s unknowns follow
    /// those of blocks `0..k`.
    pub fn block_diagonal(blocks: &[&Stiffness]) -> Result<Self, StiffnessError> {
        let n: usize = blocks.iter().map(|b| b.dim()).sum();
        let nnz: usize = blocks.iter().map(|b| b.lower.val().len()).sum();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut rows = Vec::with_capacity(nnz);
        let mut vals = Vec::with_capacity(nnz);
        col_ptr.push(0);
        let mut offset = 0;
        for b in blocks {
            let s = b.lower.symbolic();
            let (cp, ri, v) = (s.col_ptr(), s.row_idx(), b.lower.val());
            for c in 0..b.dim() {
                for e in cp[c]..cp[c + 1] {
                    rows.push(ri[e] + offset);
                    vals.push(v[e]);
                }
                col_ptr.push(rows.len());
            }
            offset += b.dim();
        }
        Self::from_csc(n, col_ptr, rows, vals)
    }

    fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        rows: Vec<usize>,
        vals: Vec<f64>,
    ) -> Result<Self, StiffnessError> {
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        Ok(Self {
            lower: SparseColMat::new(symbolic, vals),
        })
    }

    /// The number of unknowns per coordinate (control points).
    pub fn dim(&self) -> usize {
        self.lower.nrows()
    }

    /// The lower triangle, as the sparse Cholesky reads it.
    pub fn lower(&self) -> &SparseColMat<usize, f64> {
        &self.lower
    }

    /// Whether `other` has the same sparsity pattern (then a numeric
    /// refactorisation suffices).
    pub fn same_pattern(&self, other: &Stiffness) -> bool {
        self.lower.symbolic().col_ptr() == other.lower.symbolic().col_ptr()
            && self.lower.symbolic().row_idx() == other.lower.symbolic().row_idx()
    }

    /// The matrix with the unknowns where `pinned` is true eliminated: their
    /// rows and columns zeroed but for the diagonal, which is kept (so the
    /// scale of the matrix is kept). Solving with it and a right-hand side
    /// that is zero at the pinned unknowns solves K_ff x_f = b_f over the
    /// free ones and leaves the pinned ones zero. The sparsity pattern is
    /// unchanged, so refactoring for it is numeric only.
    ///
    /// # Panics
    /// If `pinned` is not [`Self::dim`] long.
    pub fn with_pinned(&self, pinned: &[bool]) -> Stiffness {
        assert_eq!(pinned.len(), self.dim(), "with_pinned: length");
        let mut out = self.clone();
        let n = self.dim();
        let cp = self.lower.symbolic().col_ptr().to_vec();
        let ri = self.lower.symbolic().row_idx().to_vec();
        let vals = out.lower.val_mut();
        for c in 0..n {
            for e in cp[c]..cp[c + 1] {
                let r = ri[e];
                if r != c && (pinned[r] || pinned[c]) {
                    vals[e] = 0.0;
                }
            }
        }
        out
    }

    /// Where entry (r, c), r ≥ c, is stored in the lower triangle.
    fn position(&self, r: usize, c: usize) -> Option<usize> {
        let sym = self.lower.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let (lo, hi) = (cp[c], cp[c + 1]);
        ri[lo..hi].binary_search(&r).ok().map(|k| lo + k)
    }

    /// K_ii.
    ///
    /// # Panics
    /// If `i` is out of range.
    pub fn diagonal(&self, i: usize) -> f64 {
        self.position(i, i).map_or(0.0, |e| self.lower.val()[e])
    }

    /// Whether every pair of `row`'s indices is an entry of the pattern, so
    /// that a a ᵀ can be added without changing it (e.g. the row of a
    /// surface point: its 4 × 4 control points lie in the stencil).
    pub fn holds(&self, row: &crate::solve::ScalarRow) -> bool {
        let n = self.dim();
        row.indices.iter().all(|&a| {
            row.indices
                .iter()
                .all(|&b| a < n && b < n && self.position(a.max(b), a.min(b)).is_some())
        })
    }

    /// K += ρ a aᵀ for the sparse vector a (`indices`, `weights`), whose
    /// pairs must lie in the pattern ([`Self::holds`]); pairs that do not
    /// are skipped.
    pub fn add_outer(&mut self, indices: &[usize], weights: &[f64], rho: f64) {
        for (x, (&a, &wa)) in indices.iter().zip(weights).enumerate() {
            for (&b, &wb) in indices.iter().zip(weights).skip(x) {
                if let Some(e) = self.position(a.max(b), a.min(b)) {
                    self.lower.val_mut()[e] += rho * wa * wb;
                }
            }
        }
    }

    /// y = K x for the full symmetric matrix.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let n = self.dim();
        let mut y = vec![0.0; n];
        let s = self.lower.symbolic();
        let (cp, ri, v) = (s.col_ptr(), s.row_idx(), self.lower.val());
        for c in 0..n {
            for e in cp[c]..cp[c + 1] {
                let r = ri[e];
                y[r] += v[e] * x[c];
                if r != c {
                    y[c] += v[e] * x[r];
                }
            }
        }
        y
    }

    /// Y = K X for the three coordinate fields at once (one pass over K, no
    /// allocation): `y[i] = Σ_j K[i][j] · x[j]`. `y` is overwritten.
    ///
    /// # Panics
    /// If `x` or `y` is not [`Self::dim`] long.
    pub fn mul_points(&self, x: &[glam::DVec3], y: &mut [glam::DVec3]) {
        let n = self.dim();
        assert!(x.len() == n && y.len() == n, "mul_points: length");
        y.fill(glam::DVec3::ZERO);
        let s = self.lower.symbolic();
        let (cp, ri, v) = (s.col_ptr(), s.row_idx(), self.lower.val());
        for c in 0..n {
            let xc = x[c];
            let mut acc = glam::DVec3::ZERO;
            for e in cp[c]..cp[c + 1] {
                let r = ri[e];
                y[r] += xc * v[e];
                if r != c {
                    acc += x[r] * v[e];
                }
            }
            y[c] += acc;
        }
    }

    /// [`Self::mul_points`] and, in the same pass, `y_abs[i] = Σ_j |K[i][j]| · |x[j]|`
    /// per coordinate: the size of the terms each product sums, which bounds
    /// its rounding (a residual below a few units of round-off of it is
    /// noise, see `Solver`'s refinement).
    ///
    /// # Panics
    /// If `x`, `y` or `y_abs` is not [`Self::dim`] long.
    pub fn mul_points_with_bound(
        &self,
        x: &[glam::DVec3],
        y: &mut [glam::DVec3],
        y_abs: &mut [glam::DVec3],
    ) {
        let n = self.dim();
        assert!(
            x.len() == n && y.len() == n && y_abs.len() == n,
            "mul_points_with_bound: length"
        );
        y.fill(glam::DVec3::ZERO);
        y_abs.fill(glam::DVec3::ZERO);
        let s = self.lower.symbolic();
        let (cp, ri, v) = (s.col_ptr(), s.row_idx(), self.lower.val());
        for c in 0..n {
            let xc = x[c];
            let xc_abs = xc.abs();
            let mut acc = glam::DVec3::ZERO;
            let mut acc_abs = glam::DVec3::ZERO;
            for e in cp[c]..cp[c + 1] {
                let r = ri[e];
                let a = v[e].abs();
                y[r] += xc * v[e];
                y_abs[r] += xc_abs * a;
                if r != c {
                    acc += x[r] * v[e];
                    acc_abs += x[r].abs() * a;
                }
            }
            y[c] += acc;
            y_abs[c] += acc_abs;
        }
    }

    /// The quadratic form xᵀ K x (the energy of one coordinate field).
    pub fn energy(&self, x: &[f64]) -> f64 {
        self.mul(x).iter().zip(x).map(|(a, b)| a * b).sum()
    }
}
