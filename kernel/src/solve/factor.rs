//! Sparse Cholesky factorisation of the stiffness (faer 0.24, AMD ordering,
//! sequential: on two cores faer's threads only slow the solve down, see
//! shared/reference/solver.md). The symbolic analysis is done once per
//! sparsity pattern; a material change is a numeric refactorisation into a
//! spare buffer (so a failed one leaves the previous factor intact). The
//! low-level API is used so that the factor's values and the scratch of the
//! factorisation and of the solves are allocated once and reused.
//!
//! [`Factor::forward_gram`] answers aᵀK⁻¹b for sparse a, b without a full
//! solve: with K = Pᵀ L Lᵀ P it is (L⁻¹Pa)·(L⁻¹Pb), and the forward solve of a
//! sparse right-hand side ([`Factor::forward_sparse`]) only visits the
//! supernodes on the paths from its nonzeros to the root of the elimination
//! tree. [`Factor::backward_in_place`] finishes such solves later with the
//! backward half alone (one pass over L for every column at once).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::mat::MatMut;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, Par, Side};

use super::SolveError;
use crate::energy::Stiffness;

/// A forward half y = L⁻¹Pa of a sparse vector a (see
/// [`Factor::forward_sparse`]).
#[derive(Clone, Debug)]
pub struct Forward {
    /// y, in the factor's (permuted) order: zero outside `reach`.
    values: Vec<f64>,
    /// The supernodes the forward solve visited, in increasing order.
    reach: Vec<usize>,
}

impl Forward {
    /// y in the factor's (permuted) order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// y, owned.
    pub fn into_values(self) -> Vec<f64> {
        self.values
    }
}

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
    /// The supernodal elimination tree, when the factor is supernodal.
    tree: Option<SupernodeTree>,
}

/// Per column of L its supernode, and per supernode its parent in the
/// elimination tree (`usize::MAX` at a root): the reach of a sparse
/// right-hand side is the union of the paths from its supernodes up.
struct SupernodeTree {
    of_column: Vec<usize>,
    parent: Vec<usize>,
}

impl SupernodeTree {
    fn new(symbolic: &SymbolicCholesky<usize>) -> Option<Self> {
        let SymbolicCholeskyRaw::Supernodal(sym) = symbolic.raw() else {
            return None;
        };
        let count = sym.n_supernodes();
        let mut of_column = vec![0; sym.nrows()];
        for (s, (&b, &e)) in sym
            .supernode_begin()
            .iter()
            .zip(sym.supernode_end())
            .enumerate()
        {
            of_column[b..e].fill(s);
        }
        let ptr = sym.col_ptr_for_row_idx();
        let parent = (0..count)
            .map(|s| {
                sym.row_idx()[ptr[s]..ptr[s + 1]]
                    .iter()
                    .min()
                    .map_or(usize::MAX, |&r| of_column[r])
            })
            .collect();
        Some(Self { of_column, parent })
    }
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
        let tree = SupernodeTree::new(&symbolic);
        let mut this = Self {
            tree,
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
            .map_err(|e| {
                SolveError::Factor(format!(
                    "the stiffness is not positive definite to working precision ({e:?}): \
                     `rest` is too small against α and β for this many control points"
                ))
            })?;
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

    /// The forward halves y = L⁻¹Pa of sparse vectors a (`(indices,
    /// weights)`, indices below [`Self::dim`]): each a dense vector in the
    /// factor's (permuted) order, zero outside its reach — the supernodes on
    /// the elimination-tree paths from a's non-zeros to the root, the only
    /// ones the forward solve visits — with that reach. `None` when the
    /// factor is not supernodal (small problems).
    pub fn forward_sparse(&self, columns: &[(&[usize], &[f64])]) -> Option<Vec<Forward>> {
        let tree = self.tree.as_ref()?;
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return None;
        };
        let n = self.dim();
        let inv = self.symbolic.perm().map(|p| p.arrays().1);
        let begin = sym.supernode_begin();
        let end = sym.supernode_end();
        let row_ptr = sym.col_ptr_for_row_idx();
        let val_ptr = sym.col_ptr_for_val();
        let rows = sym.row_idx();
        let mut marked = vec![false; tree.parent.len()];
        // The updates a supernode sends to the rows below its diagonal
        // block, summed over its columns before they are scattered: one
        // contiguous multiply-add per column instead of a scatter.
        let mut below: Vec<f64> = Vec::new();
        let mut solved: Vec<Forward> = Vec::with_capacity(columns.len());
        for (indices, weights) in columns {
            let mut x = vec![0.0; n];
            let mut reach: Vec<usize> = Vec::new();
            for (&i, &w) in indices.iter().zip(*weights) {
                let p = inv.map_or(i, |inv| inv[i]);
                x[p] += w;
                let mut s = tree.of_column[p];
                while s != usize::MAX && !marked[s] {
                    marked[s] = true;
                    reach.push(s);
                    s = tree.parent[s];
                }
            }
            // A parent comes after its children: increasing order is a
            // topological order of the tree.
            reach.sort_unstable();
            for &s in &reach {
                marked[s] = false;
                let (b, size) = (begin[s], end[s] - begin[s]);
                let pattern = &rows[row_ptr[s]..row_ptr[s + 1]];
                let height = size + pattern.len();
                let l = &self.l_vals[val_ptr[s]..val_ptr[s + 1]];
                below.clear();
                below.resize(pattern.len(), 0.0);
                let mut sends = false;
                let block = &mut x[b..b + size];
                for j in 0..size {
                    let col = &l[j * height..(j + 1) * height];
                    let xj = block[j] / col[j];
                    block[j] = xj;
                    if xj == 0.0 {
                        continue;
                    }
                    sends = true;
                    for (xi, &c) in block[j + 1..].iter_mut().zip(&col[j + 1..size]) {
                        *xi -= c * xj;
                    }
                    for (t, &v) in below.iter_mut().zip(&col[size..]) {
                        *t += v * xj;
                    }
                }
                if sends {
                    for (&r, &t) in pattern.iter().zip(&below) {
                        x[r] -= t;
                    }
                }
            }
            solved.push(Forward { values: x, reach });
        }
        Some(solved)
    }

    /// The Gram matrix aᵢᵀ K⁻¹ aⱼ (row-major, k × k) of k sparse vectors
    /// (`(indices, weights)`, indices below [`Self::dim`]), by forward
    /// solves that visit only the elimination-tree paths of their nonzeros:
    /// a fraction of one full solve each. `None` when the factor is not
    /// supernodal (small problems: the caller solves in full).
    pub fn forward_gram(&self, columns: &[(&[usize], &[f64])]) -> Option<Vec<f64>> {
        Some(self.gram_of(&self.forward_sparse(columns)?))
    }

    /// The Gram matrix aᵢᵀ K⁻¹ aⱼ (row-major, k × k) of the sparse vectors
    /// whose forward halves are `forward` ([`Self::forward_sparse`]): with
    /// K = Pᵀ L Lᵀ P it is (L⁻¹Paᵢ)·(L⁻¹Paⱼ).
    pub fn gram_of(&self, forward: &[Forward]) -> Vec<f64> {
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            // Forward halves come only from a supernodal factor.
            return vec![0.0; forward.len() * forward.len()];
        };
        let begin = sym.supernode_begin();
        let end = sym.supernode_end();
        let k = forward.len();
        let mut gram = vec![0.0; k * k];
        for a in 0..k {
            for b in a..k {
                // y_b is zero outside its reach.
                let (xa, xb) = (&forward[a].values, &forward[b].values);
                let v: f64 = forward[b]
                    .reach
                    .iter()
                    .flat_map(|&s| begin[s]..end[s])
                    .map(|i| xa[i] * xb[i])
                    .sum();
                gram[a * k + b] = v;
                gram[b * k + a] = v;
            }
        }
        gram
    }

    /// The index ranges (factor order) of the supernodes a forward half
    /// reached: it is zero outside them.
    fn reach_ranges<'a>(
        &'a self,
        f: &'a Forward,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
        let sym = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sym) => Some(sym),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
        f.reach.iter().filter_map(move |&s| {
            let sym = sym?;
            Some(sym.supernode_begin()[s]..sym.supernode_end()[s])
        })
    }

    /// f · x over f's reach (x a dense vector in the factor's order).
    pub fn dot_on_reach(&self, f: &Forward, x: &[f64]) -> f64 {
        self.reach_ranges(f)
            .map(|r| {
                f.values[r.clone()]
                    .iter()
                    .zip(&x[r])
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
            })
            .sum()
    }

    /// y += alpha · f over f's reach (y a dense vector in the factor's
    /// order).
    pub fn axpy_on_reach(&self, alpha: f64, f: &Forward, y: &mut [f64]) {
        for r in self.reach_ranges(f) {
            for (yi, &fi) in y[r.clone()].iter_mut().zip(&f.values[r]) {
                *yi += alpha * fi;
            }
        }
    }

    /// Whether the factor is supernodal: only then are forward and
    /// backward halves ([`Self::forward_sparse`], [`Self::forward_in_place`],
    /// [`Self::backward_in_place`]) available.
    pub fn is_supernodal(&self) -> bool {
        self.tree.is_some()
    }

    /// The forward halves of dense right-hand sides: every column a of `x`
    /// (dim × k, original order) becomes y = L⁻¹Pa in the factor's order,
    /// to be finished by [`Self::backward_in_place`] (with other columns:
    /// one backward pass for all). Returns `false` (and leaves `x`) when the
    /// factor is not supernodal.
    pub fn forward_in_place(&mut self, mut x: MatMut<'_, f64>) -> bool {
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return false;
        };
        let k = x.ncols();
        if k > self.solve_cols {
            self.solve_mem =
                MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq));
            self.solve_cols = k;
        }
        if let Some(perm) = self.symbolic.perm() {
            let inv = perm.arrays().1;
            let mut column = vec![0.0; self.dim()];
            for j in 0..k {
                for (i, &p) in inv.iter().enumerate() {
                    column[p] = x[(i, j)];
                }
                for (i, &c) in column.iter().enumerate() {
                    x[(i, j)] = c;
                }
            }
        }
        SupernodalLltRef::<usize, f64>::new(sym, &self.l_vals).l_solve_with_conj(
            Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
        true
    }

    /// Finishes solves begun by [`Self::forward_sparse`]: every column of
    /// `x` (dim × k), a forward half y = L⁻¹Pa in the factor's order,
    /// becomes K⁻¹a = Pᵀ L⁻ᵀ y in the original order — the backward half
    /// only, one pass over L for all k columns. Returns `false` (and leaves
    /// `x`) when the factor is not supernodal.
    pub fn backward_in_place(&mut self, mut x: MatMut<'_, f64>) -> bool {
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return false;
        };
        let k = x.ncols();
        self.solved += k as u64;
        if k > self.solve_cols {
            self.solve_mem =
                MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq));
            self.solve_cols = k;
        }
        SupernodalLltRef::<usize, f64>::new(sym, &self.l_vals).l_transpose_solve_with_conj(
            Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
        if let Some(perm) = self.symbolic.perm() {
            let inv = perm.arrays().1;
            let mut column = vec![0.0; self.dim()];
            for j in 0..k {
                for (c, &p) in column.iter_mut().zip(inv) {
                    *c = x[(p, j)];
                }
                for (i, &c) in column.iter().enumerate() {
                    x[(i, j)] = c;
                }
            }
        }
        true
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
