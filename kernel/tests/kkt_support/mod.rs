//! What the solver tests share: the KKT system of one coordinate solved
//! densely (LU with partial pivoting), an answer independent of the
//! solver's Schur complement, pinned-point elimination and refinement.

#![allow(dead_code)]

use glam::DVec3;
use vsculpt_kernel::energy::Stiffness;
use vsculpt_kernel::solve::{Equation, Problem};

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

/// The exact answer of `problem` from the reference `p` (group `dragged`'s
/// targets shifted by t, its loads' forces by t · gain), by a dense KKT
/// solve per coordinate.
pub fn dense_answer(
    k: &Stiffness,
    p: &[DVec3],
    problem: &Problem,
    dragged: Option<(u64, DVec3)>,
) -> Vec<DVec3> {
    let mut out = p.to_vec();
    for c in 0..3 {
        let rows: Vec<(Vec<usize>, Vec<f64>, f64)> = problem
            .groups
            .iter()
            .flat_map(|g| {
                let shift = match dragged {
                    Some((key, t)) if key == g.key => t,
                    _ => DVec3::ZERO,
                };
                g.equations.iter().map(move |eq| (eq, shift))
            })
            .map(|(eq, shift)| match eq {
                Equation::Vector { row, target } => (
                    row.indices.clone(),
                    row.weights.clone(),
                    target[c] + shift[c] - row.apply(p)[c],
                ),
                Equation::Projected { .. } => unreachable!(),
            })
            .collect();
        let mut b = vec![0.0; p.len()];
        for g in &problem.groups {
            for l in &g.loads {
                let force = match dragged {
                    Some((key, t)) if key == g.key => l.force + t * l.drag_gain,
                    _ => l.force,
                };
                for (&i, &w) in l.row.indices.iter().zip(&l.row.weights) {
                    b[i] += w * force[c];
                }
            }
        }
        for (o, d) in out.iter_mut().zip(dense_kkt(k, &rows, &b)) {
            o[c] += d;
        }
    }
    out
}

/// The largest coordinate difference between two shapes.
pub fn max_gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f64::max)
}
