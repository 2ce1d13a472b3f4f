//! What the solver tests share: the KKT system of one coordinate solved
//! densely (LU with partial pivoting), an answer independent of the
//! solver's Schur complement, pinned-point elimination and refinement.

#![allow(dead_code)]

use vsculpt_kernel::energy::Stiffness;

/// The KKT system [K Cᵀ; C 0] [δ; λ] = [b; d − C P_ref] of one coordinate,
/// solved densely (LU with partial pivoting), independent of the solver.
/// `rows` are C's rows as (indices, weights, right-hand side).
pub fn dense_kkt(k: &Stiffness, rows: &[(Vec<usize>, Vec<f64>, f64)], b: &[f64]) -> Vec<f64> {
    use faer::linalg::solvers::Solve;
    let n = k.dim();
    let m = rows.len();
    let mut a = faer::Mat::<f64>::zeros(n + m, n + m);
    let lower = k.lower();
    let (cp, ri, v) = (
        lower.symbolic().col_ptr(),
        lower.symbolic().row_idx(),
        lower.val(),
    );
    for c in 0..n {
        for e in cp[c]..cp[c + 1] {
            a[(ri[e], c)] = v[e];
            a[(c, ri[e])] = v[e];
        }
    }
    let mut rhs = faer::Mat::<f64>::zeros(n + m, 1);
    for (i, x) in b.iter().enumerate() {
        rhs[(i, 0)] = *x;
    }
    for (e, (idx, w, target)) in rows.iter().enumerate() {
        for (&i, &wi) in idx.iter().zip(w) {
            a[(n + e, i)] = wi;
            a[(i, n + e)] = wi;
        }
        rhs[(n + e, 0)] = *target;
    }
    let x = a.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| x[(i, 0)]).collect()
}
