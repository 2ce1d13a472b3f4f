//! One-dimensional Gram matrices of B-spline basis functions and their
//! derivatives, G_ab[i][k] = ∫ N_i^(a)(t) N_k^(b)(t) dt for a, b ∈ {0, 1, 2},
//! exact: Gauss–Legendre with degree+1 nodes per knot span integrates the
//! degree-2p polynomial products exactly.
//!
//! The surface stiffness is a sum of tensor products of these.

use crate::bspline::{BasisDerivs, KnotVector, basis_derivs_into};
use crate::quadrature::GaussLegendre;

/// The nine Gram matrices of one knot vector, dense n × n (n is at most a few
/// hundred control points per direction; entries vanish for |i − k| > p).
#[derive(Clone, Debug, PartialEq)]
pub struct Gram {
    n: usize,
    degree: usize,
    /// g[a * 3 + b] is G_ab, row-major n × n.
    g: Vec<Vec<f64>>,
}

impl Gram {
    /// The Gram matrices of `kv`.
    pub fn new(kv: &KnotVector) -> Self {
        let n = kv.num_ctrl();
        let p = kv.degree();
        let rule = GaussLegendre::new(p + 1);
        let mut g = vec![vec![0.0; n * n]; 9];
        let mut b = BasisDerivs::default();
        for (_, a0, a1) in kv.spans() {
            for (t, w) in rule.on(a0, a1) {
                basis_derivs_into(kv, t, 2, &mut b);
                for a in 0..3 {
                    for c in 0..3 {
                        let m = &mut g[a * 3 + c];
                        for i in 0..=p {
                            let ni = b.get(a, i) * w;
                            if ni == 0.0 {
                                continue;
                            }
                            let row = (b.first + i) * n + b.first;
                            for k in 0..=p {
                                m[row + k] += ni * b.get(c, k);
                            }
                        }
                    }
                }
            }
        }
        Self { n, degree: p, g }
    }

    /// Number of basis functions.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a knot vector has at least degree+1 functions.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The degree of the basis.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// ∫ N_i^(a) N_k^(b).
    pub fn get(&self, a: usize, b: usize, i: usize, k: usize) -> f64 {
        self.g[a * 3 + b][i * self.n + k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gram_identities() {
        let kv = KnotVector::new(3, vec![0., 0., 0., 0., 0.3, 0.5, 1., 1., 1., 1.]).unwrap();
        let g = Gram::new(&kv);
        let n = g.len();
        // Σ_k N_k = 1, so Σ_ik G00 = ∫1 = 1 and Σ_k G_a0[i][k] = ∫ N_i^(a).
        let total: f64 = (0..n)
            .flat_map(|i| (0..n).map(move |k| (i, k)))
            .map(|(i, k)| g.get(0, 0, i, k))
            .sum();
        assert!((total - 1.0).abs() < 1e-14);
        // Σ_k N_k' = 0, so every row of G01 sums to zero.
        for i in 0..n {
            let s: f64 = (0..n).map(|k| g.get(0, 1, i, k)).sum();
            assert!(s.abs() < 1e-12);
        }
        // Symmetry of G_ab and G_ba transposed.
        for i in 0..n {
            for k in 0..n {
                assert!((g.get(1, 0, i, k) - g.get(0, 1, k, i)).abs() < 1e-14);
                assert!((g.get(2, 2, i, k) - g.get(2, 2, k, i)).abs() < 1e-10);
            }
        }
        // ∫ N_0 = (u_{p+1} − u_0)/(p+1) = 0.3/4.
        let int0: f64 = (0..n).map(|k| g.get(0, 0, 0, k)).sum();
        assert!((int0 - 0.075).abs() < 1e-14);
    }
}
