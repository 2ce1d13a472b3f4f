//! B-spline basis functions and their derivatives (Piegl & Tiller, *The NURBS
//! Book*, algorithms A2.2 and A2.3).
//!
//! At a parameter t only p+1 basis functions are non-zero: N_{s−p} … N_s for
//! the span s holding t. [`BasisDerivs`] holds their values and derivatives up
//! to a chosen order; [`basis_derivs_into`] refills one without allocating,
//! for hot loops (tessellation, quadrature, constraint rows).

use super::KnotVector;

/// Values and derivatives up to order `order` of the `degree + 1` basis
/// functions that are non-zero at a parameter.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BasisDerivs {
    /// Index of the first non-zero basis function, N_{first}.
    pub first: usize,
    degree: usize,
    order: usize,
    /// Row-major (order+1) × (degree+1): values[d * (p+1) + k] = N^{(d)}_{first+k}.
    values: Vec<f64>,
    // Scratch for the triangular table and the derivative recursion.
    ndu: Vec<f64>,
    left: Vec<f64>,
    right: Vec<f64>,
    a: Vec<f64>,
}

impl BasisDerivs {
    /// The d-th derivative of N_{first+k}; zero for d above the degree.
    pub fn get(&self, d: usize, k: usize) -> f64 {
        self.values[d * (self.degree + 1) + k]
    }

    /// The d-th derivatives of the degree+1 non-zero functions.
    pub fn row(&self, d: usize) -> &[f64] {
        let w = self.degree + 1;
        &self.values[d * w..(d + 1) * w]
    }

    /// The degree of the basis.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The highest derivative order held.
    pub fn order(&self) -> usize {
        self.order
    }
}

/// The non-zero basis functions of `kv` at `t` and their derivatives up to
/// order `n`. `t` is clamped into the domain (see [`KnotVector::find_span`]).
pub fn basis_derivs(kv: &KnotVector, t: f64, n: usize) -> BasisDerivs {
    let mut out = BasisDerivs::default();
    basis_derivs_into(kv, t, n, &mut out);
    out
}

/// As [`basis_derivs`], refilling `out`; allocates only when `out` is smaller
/// than needed, so a reused `out` makes this allocation-free.
pub fn basis_derivs_into(kv: &KnotVector, t: f64, n: usize, out: &mut BasisDerivs) {
    let p = kv.degree();
    let (a0, b0) = kv.domain();
    let t = if t.is_nan() { a0 } else { t.clamp(a0, b0) };
    let span = kv.find_span(t);
    let u = kv.knots();
    let w = p + 1;
    out.first = span - p;
    out.degree = p;
    out.order = n;
    out.values.clear();
    out.values.resize((n + 1) * w, 0.0);
    out.ndu.clear();
    out.ndu.resize(w * w, 0.0);
    out.left.clear();
    out.left.resize(w, 0.0);
    out.right.clear();
    out.right.resize(w, 0.0);
    out.a.clear();
    out.a.resize(2 * w, 0.0);

    // ndu[j][r] (row j, column r) stored at j * w + r. Upper triangle: basis
    // values; lower triangle: knot differences (A2.3).
    let ndu = &mut out.ndu;
    ndu[0] = 1.0;
    for j in 1..=p {
        out.left[j] = t - u[span + 1 - j];
        out.right[j] = u[span + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j * w + r] = out.right[r + 1] + out.left[j - r];
            let temp = ndu[r * w + (j - 1)] / ndu[j * w + r];
            ndu[r * w + j] = saved + out.right[r + 1] * temp;
            saved = out.left[j - r] * temp;
        }
        ndu[j * w + j] = saved;
    }
    for j in 0..=p {
        out.values[j] = ndu[j * w + p];
    }
    let nd = n.min(p);
    if nd == 0 {
        return;
    }
    // a[s][j] as two rows of length w.
    for r in 0..=p {
        let (mut s1, mut s2) = (0usize, 1usize);
        out.a.iter_mut().for_each(|x| *x = 0.0);
        out.a[0] = 1.0;
        for k in 1..=nd {
            let mut d = 0.0;
            let rk = r as isize - k as isize;
            let pk = p - k;
            if r >= k {
                out.a[s2 * w] = out.a[s1 * w] / ndu[(pk + 1) * w + (r - k)];
                d = out.a[s2 * w] * ndu[(r - k) * w + pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r as isize - 1 <= pk as isize {
                k - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                out.a[s2 * w + j] =
                    (out.a[s1 * w + j] - out.a[s1 * w + j - 1]) / ndu[(pk + 1) * w + idx];
                d += out.a[s2 * w + j] * ndu[idx * w + pk];
            }
            if r <= pk {
                out.a[s2 * w + k] = -out.a[s1 * w + k - 1] / ndu[(pk + 1) * w + r];
                d += out.a[s2 * w + k] * ndu[r * w + pk];
            }
            out.values[k * w + r] = d;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut factor = p as f64;
    for k in 1..=nd {
        for j in 0..=p {
            out.values[k * w + j] *= factor;
        }
        factor *= (p - k) as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kv() -> KnotVector {
        KnotVector::new(3, vec![0., 0., 0., 0., 0.2, 0.5, 0.5, 0.8, 1., 1., 1., 1.]).unwrap()
    }

    #[test]
    fn partition_of_unity_and_nonnegativity() {
        let kv = kv();
        for i in 0..=200 {
            let t = i as f64 / 200.0;
            let b = basis_derivs(&kv, t, 2);
            let sum: f64 = b.row(0).iter().sum();
            assert!((sum - 1.0).abs() < 1e-14, "t={t} sum={sum}");
            assert!(b.row(0).iter().all(|&v| v >= -1e-15));
            // Derivatives of a partition of unity sum to zero.
            assert!(b.row(1).iter().sum::<f64>().abs() < 1e-10);
            assert!(b.row(2).iter().sum::<f64>().abs() < 1e-8);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let kv = kv();
        let h = 1e-6;
        for &t in &[0.1, 0.3, 0.45, 0.6, 0.9] {
            let b = basis_derivs(&kv, t, 2);
            let bp = basis_derivs(&kv, t + h, 1);
            let bm = basis_derivs(&kv, t - h, 1);
            assert_eq!(bp.first, b.first);
            assert_eq!(bm.first, b.first);
            for k in 0..4 {
                let d1 = (bp.get(0, k) - bm.get(0, k)) / (2.0 * h);
                let d2 = (bp.get(1, k) - bm.get(1, k)) / (2.0 * h);
                assert!((d1 - b.get(1, k)).abs() < 1e-6, "t={t} k={k}");
                assert!(
                    (d2 - b.get(2, k)).abs() < 1e-4 * (1.0 + b.get(2, k).abs()),
                    "t={t} k={k}"
                );
            }
        }
    }

    #[test]
    fn known_quadratic_values() {
        // Piegl & Tiller Ex. 2.3: U = {0,0,0,1,2,3,4,4,5,5,5}, p = 2, u = 5/2:
        // N_{2,2} = 1/8, N_{3,2} = 6/8, N_{4,2} = 1/8.
        let kv = KnotVector::new(2, vec![0., 0., 0., 1., 2., 3., 4., 4., 5., 5., 5.]).unwrap();
        let b = basis_derivs(&kv, 2.5, 1);
        assert_eq!(b.first, 2);
        assert!((b.get(0, 0) - 0.125).abs() < 1e-15);
        assert!((b.get(0, 1) - 0.75).abs() < 1e-15);
        assert!((b.get(0, 2) - 0.125).abs() < 1e-15);
        // Derivatives: N'_{2,2} = -(5/2 - 2) = -1/2, N'_{3,2} = 0, N'_{4,2} = 1/2.
        assert!((b.get(1, 0) + 0.5).abs() < 1e-14);
        assert!(b.get(1, 1).abs() < 1e-14);
        assert!((b.get(1, 2) - 0.5).abs() < 1e-14);
    }

    #[test]
    fn derivative_above_degree_is_zero_and_reuse_is_consistent() {
        let kv = KnotVector::clamped_uniform(1, 4).unwrap();
        let b = basis_derivs(&kv, 0.4, 3);
        assert_eq!(b.row(2), &[0.0, 0.0]);
        let mut reused = basis_derivs(&kv, 0.9, 3);
        basis_derivs_into(&kv, 0.4, 3, &mut reused);
        assert_eq!(reused, b);
    }
}
