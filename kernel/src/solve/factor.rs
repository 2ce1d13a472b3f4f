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
//! tree, and keeps y on that reach only ([`Forward`]); the Gram matrix of
//! many such halves is summed supernode by supernode ([`Factor::gram_of`]).
//! [`Factor::backward_in_place`] finishes such solves later with the
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
/// [`Factor::forward_sparse`]), kept on its reach only: y is zero outside
/// the supernodes the forward solve visited, so a curve's hundreds of rows
/// cost their reaches, not a dense vector each.
#[derive(Clone, Debug)]
pub struct Forward {
    /// y over `spans`, concatenated in their order.
    values: Vec<f64>,
    /// The supernodes the forward solve visited, in increasing order.
    reach: Vec<usize>,
    /// Per supernode of `reach`: its index range in the factor's
    /// (permuted) order.
    spans: Vec<std::ops::Range<usize>>,
    /// The factor's dimension.
    dim: usize,
}

impl Forward {
    /// y as a dense vector in the factor's (permuted) order.
    pub fn to_dense(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.dim];
        self.scatter(&mut out);
        out
    }

    /// Per reach supernode, its values and its range in the factor's order.
    fn segments(&self) -> impl Iterator<Item = (std::ops::Range<usize>, &[f64])> + '_ {
        let mut at = 0;
        self.spans.iter().map(move |r| {
            let seg = &self.values[at..at + r.len()];
            at += r.len();
            (r.clone(), seg)
        })
    }

    /// Writes y into `out` (a dense vector in the factor's order) on its
    /// reach; the rest of `out` is left as it is.
    pub fn scatter(&self, out: &mut [f64]) {
        for (r, seg) in self.segments() {
            out[r].copy_from_slice(seg);
        }
    }

    /// y · x (x a dense vector in the factor's order).
    pub fn dot_dense(&self, x: &[f64]) -> f64 {
        self.segments()
            .map(|(r, seg)| seg.iter().zip(&x[r]).map(|(a, b)| a * b).sum::<f64>())
            .sum()
    }

    /// y · z of two forward halves: the supernodes both reached.
    pub fn dot(&self, other: &Forward) -> f64 {
        let (mut a, mut b) = (self.segments().peekable(), other.segments().peekable());
        let mut sum = 0.0;
        while let (Some((ra, sa)), Some((rb, sb))) = (a.peek(), b.peek()) {
            match ra.start.cmp(&rb.start) {
                std::cmp::Ordering::Less => {
                    a.next();
                }
                std::cmp::Ordering::Greater => {
                    b.next();
                }
                std::cmp::Ordering::Equal => {
                    sum += sa.iter().zip(sb.iter()).map(|(x, y)| x * y).sum::<f64>();
                    a.next();
                    b.next();
                }
            }
        }
        sum
    }

    /// out += alpha · y (out a dense vector in the factor's order).
    pub fn axpy(&self, alpha: f64, out: &mut [f64]) {
        for (r, seg) in self.segments() {
            for (o, &v) in out[r].iter_mut().zip(seg) {
                *o += alpha * v;
            }
        }
    }

    /// How many values y keeps (the size of its reach).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether y's reach is empty (a zero right-hand side).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
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
    /// The reach of the factor-order indices `points`: the supernodes on
    /// their paths to the root, in increasing order (a topological order:
    /// a parent comes after its children). `marked` (one flag per
    /// supernode, all clear) is left clear.
    fn reach(&self, points: impl Iterator<Item = usize>, marked: &mut [bool]) -> Vec<usize> {
        let mut reach: Vec<usize> = Vec::new();
        for p in points {
            let mut s = self.of_column[p];
            while s != usize::MAX && !marked[s] {
                marked[s] = true;
                reach.push(s);
                s = self.parent[s];
            }
        }
        reach.sort_unstable();
        for &s in &reach {
            marked[s] = false;
        }
        reach
    }

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
    /// weights)`, indices below [`Self::dim`]), each kept on its reach —
    /// the supernodes on the elimination-tree paths from a's non-zeros to
    /// the root, the only ones the forward solve visits (one dense
    /// workspace serves every column and is cleared on the reach only).
    /// `None` when the factor is not supernodal (small problems).
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
        let mut x = vec![0.0; n];
        let mut solved: Vec<Forward> = Vec::with_capacity(columns.len());
        let at = |i: usize| inv.map_or(i, |inv| inv[i]);
        for (indices, weights) in columns {
            for (&i, &w) in indices.iter().zip(*weights) {
                x[at(i)] += w;
            }
            let reach = tree.reach(indices.iter().map(|&i| at(i)), &mut marked);
            for &s in &reach {
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
            let spans: Vec<std::ops::Range<usize>> =
                reach.iter().map(|&s| begin[s]..end[s]).collect();
            let mut values = Vec::with_capacity(spans.iter().map(|r| r.len()).sum());
            for r in &spans {
                values.extend_from_slice(&x[r.clone()]);
                x[r.clone()].fill(0.0);
            }
            solved.push(Forward {
                values,
                reach,
                spans,
                dim: n,
            });
        }
        Some(solved)
    }

    /// [`Self::forward_sparse`] and [`Self::gram_of`] of many columns at
    /// once, as dense blocks: per supernode s of the union of their reaches,
    /// the columns J_s that reach it share one block X_s (its rows × J_s),
    /// solved by one triangular solve with the diagonal block of L, sent to
    /// the ancestors by one product with the block below it, and added to
    /// the Gram matrix as X_sᵀX_s. The same numbers as column by column
    /// (each column still visits its own reach only), but as matrix
    /// products: a curve's hundreds of rows share the separators near the
    /// root. `None` when the factor is not supernodal.
    pub fn forward_batch(
        &self,
        columns: &[(&[usize], &[f64])],
    ) -> Option<(Vec<Forward>, Vec<f64>)> {
        use faer::linalg::matmul::matmul;
        use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
        let tree = self.tree.as_ref()?;
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return None;
        };
        let inv = self.symbolic.perm().map(|p| p.arrays().1);
        let begin = sym.supernode_begin();
        let end = sym.supernode_end();
        let row_ptr = sym.col_ptr_for_row_idx();
        let val_ptr = sym.col_ptr_for_val();
        let rows = sym.row_idx();
        let supernodes = tree.parent.len();
        let k = columns.len();
        // Reaches, and per supernode the columns that reach it (ascending).
        let mut marked = vec![false; supernodes];
        let mut reaches: Vec<Vec<usize>> = Vec::with_capacity(k);
        let mut meets: Vec<Vec<usize>> = vec![Vec::new(); supernodes];
        for (j, (indices, _)) in columns.iter().enumerate() {
            let reach = tree.reach(
                indices.iter().map(|&i| inv.map_or(i, |inv| inv[i])),
                &mut marked,
            );
            for &s in &reach {
                meets[s].push(j);
            }
            reaches.push(reach);
        }
        // One flat buffer: X_s (column-major, its rows × |J_s|) at offset[s].
        let mut offset = vec![0usize; supernodes + 1];
        for s in 0..supernodes {
            offset[s + 1] = offset[s] + (end[s] - begin[s]) * meets[s].len();
        }
        let mut xs = vec![0.0; offset[supernodes]];
        for (j, (indices, weights)) in columns.iter().enumerate() {
            for (&i, &w) in indices.iter().zip(*weights) {
                let p = inv.map_or(i, |inv| inv[i]);
                let s = tree.of_column[p];
                let at = meets[s].binary_search(&j).unwrap_or(0);
                xs[offset[s] + at * (end[s] - begin[s]) + p - begin[s]] += w;
            }
        }
        let mut gram = vec![0.0; k * k];
        let mut map: Vec<usize> = Vec::new();
        for s in 0..supernodes {
            let c = meets[s].len();
            if c == 0 {
                continue;
            }
            let size = end[s] - begin[s];
            let pattern = &rows[row_ptr[s]..row_ptr[s + 1]];
            let height = size + pattern.len();
            let l = faer::MatRef::from_column_major_slice(
                &self.l_vals[val_ptr[s]..val_ptr[s + 1]],
                height,
                size,
            );
            let (head, tail) = xs.split_at_mut(offset[s + 1]);
            let mut x = faer::MatMut::from_column_major_slice_mut(&mut head[offset[s]..], size, c);
            solve_lower_triangular_in_place(l.submatrix(0, 0, size, size), x.as_mut(), Par::Seq);
            let x = x.as_ref();
            let mut g = faer::Mat::<f64>::zeros(c, c);
            matmul(
                g.as_mut(),
                faer::Accum::Replace,
                x.transpose(),
                x,
                1.0,
                Par::Seq,
            );
            for (a, &ja) in meets[s].iter().enumerate() {
                for (bb, &jb) in meets[s].iter().enumerate() {
                    gram[ja * k + jb] += g[(a, bb)];
                }
            }
            if pattern.is_empty() {
                continue;
            }
            let mut update = faer::Mat::<f64>::zeros(pattern.len(), c);
            matmul(
                update.as_mut(),
                faer::Accum::Replace,
                l.submatrix(size, 0, pattern.len(), size),
                x,
                1.0,
                Par::Seq,
            );
            let mut current = usize::MAX;
            for (q, &r) in pattern.iter().enumerate() {
                let t = tree.of_column[r];
                if t != current {
                    // J_s ⊆ J_t (a reach is closed towards the root):
                    // where each of J_s sits in J_t.
                    current = t;
                    map.clear();
                    let mut at = 0;
                    for &j in &meets[s] {
                        while meets[t][at] != j {
                            at += 1;
                        }
                        map.push(at);
                    }
                }
                let size_t = end[t] - begin[t];
                let base = offset[t] - offset[s + 1] + r - begin[t];
                for (a, &at) in map.iter().enumerate() {
                    tail[base + at * size_t] -= update[(q, a)];
                }
            }
        }
        // Symmetric to the last bit.
        for a in 0..k {
            for bb in a + 1..k {
                let v = 0.5 * (gram[a * k + bb] + gram[bb * k + a]);
                gram[a * k + bb] = v;
                gram[bb * k + a] = v;
            }
        }
        let forward = reaches
            .into_iter()
            .enumerate()
            .map(|(j, reach)| {
                let spans: Vec<std::ops::Range<usize>> =
                    reach.iter().map(|&s| begin[s]..end[s]).collect();
                let mut values = Vec::with_capacity(spans.iter().map(|r| r.len()).sum());
                for &s in &reach {
                    let size = end[s] - begin[s];
                    let at = meets[s].binary_search(&j).unwrap_or(0);
                    let o = offset[s] + at * size;
                    values.extend_from_slice(&xs[o..o + size]);
                }
                Forward {
                    values,
                    reach,
                    spans,
                    dim: self.dim(),
                }
            })
            .collect();
        Some((forward, gram))
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
    /// K = Pᵀ L Lᵀ P it is (L⁻¹Paᵢ)·(L⁻¹Paⱼ). Summed supernode by
    /// supernode: the halves that reached a supernode give a dense block B
    /// (its rows × those halves) and add BᵀB to their entries — a supernode
    /// near the leaves meets few halves, the separators near the root meet
    /// them all, as one matrix product.
    pub fn gram_of(&self, forward: &[Forward]) -> Vec<f64> {
        let k = forward.len();
        let mut gram = vec![0.0; k * k];
        let supernodes = self.tree.as_ref().map_or(0, |t| t.parent.len());
        // Per supernode: the halves that reached it and where its values
        // start in each.
        let mut meets: Vec<Vec<(usize, usize)>> = vec![Vec::new(); supernodes];
        for (j, f) in forward.iter().enumerate() {
            let mut at = 0;
            for (&s, r) in f.reach.iter().zip(&f.spans) {
                meets[s].push((j, at));
                at += r.len();
            }
        }
        let mut block: Vec<f64> = Vec::new();
        for (s, met) in meets.iter().enumerate() {
            let Some(size) = met.first().map(|&(j, _)| {
                let f = &forward[j];
                f.spans[f.reach.binary_search(&s).unwrap_or(0)].len()
            }) else {
                continue;
            };
            let c = met.len();
            if c * size < 64 {
                for (x, &(a, oa)) in met.iter().enumerate() {
                    let ya = &forward[a].values[oa..oa + size];
                    for &(b, ob) in &met[x..] {
                        let yb = &forward[b].values[ob..ob + size];
                        let v: f64 = ya.iter().zip(yb).map(|(p, q)| p * q).sum();
                        gram[a * k + b] += v;
                        if a != b {
                            gram[b * k + a] += v;
                        }
                    }
                }
                continue;
            }
            block.clear();
            for &(j, o) in met {
                block.extend_from_slice(&forward[j].values[o..o + size]);
            }
            let b = faer::MatRef::from_column_major_slice(&block, size, c);
            let product = b.transpose() * b;
            for (x, &(a, _)) in met.iter().enumerate() {
                for (y, &(bb, _)) in met.iter().enumerate() {
                    gram[a * k + bb] += product[(x, y)];
                }
            }
        }
        // Symmetric to the last bit.
        for a in 0..k {
            for b in a + 1..k {
                let v = 0.5 * (gram[a * k + b] + gram[b * k + a]);
                gram[a * k + b] = v;
                gram[b * k + a] = v;
            }
        }
        gram
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
