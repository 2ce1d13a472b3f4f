//! A change of the pinned set answered with the factor of the old one.
//!
//! The factor is of Ã = K̃ with the control points P₀ eliminated (see
//! [`Stiffness::with_pinned`]: their rows and columns keep only the
//! diagonal). The problem now pins P₁: the points N = P₁ \ P₀ are newly
//! pinned (free in Ã) and F = P₀ \ P₁ newly freed (eliminated in Ã). For a
//! right-hand side b that is zero on P₁, x = A₁⁻¹b (zero on P₁) solves
//!
//! ```text
//! [ A₀    K̃₀F  E_N ] [x₀ ]   [b₀]
//! [ K̃F₀   K̃FF  0   ] [x_F] = [b_F]      (A₀ = Ã over its free points)
//! [ E_Nᵀ  0    0   ] [μ  ]   [0 ]
//! ```
//!
//! With V = [K̃₀F, E_N] (per freed point the coupling column the factor
//! dropped, per newly pinned point a unit vector: one column per point, x,
//! y and z share K) and eliminating x₀ = Ã⁻¹(b₀ − V ξ):
//!
//! ```text
//! R ξ = [b_F; 0] − Vᵀ Ã⁻¹ b₀,    R = [[K̃FF, 0], [0, 0]] − Vᵀ Ã⁻¹ V,    ξ = (x_F, μ)
//! ```
//!
//! Every product with Ã⁻¹ here is a pair of forward halves: with
//! Ã = Pᵀ L Lᵀ P, Vᵀ Ã⁻¹ b₀ = (L⁻¹PV)ᵀ (L⁻¹P b₀), so a solve is the forward
//! half of b₀, |V| dot products and a |V| × |V| product with R⁻¹, the
//! forward half corrected by −(L⁻¹PV) ξ, and the backward half. Building
//! the update costs the forward halves of V (only the elimination-tree
//! paths of their non-zeros, [`Factor::forward_sparse`]), their Gram matrix
//! and a dense LU of R — no numeric refactorisation. The solver uses it for
//! S over the new pinned set: aᵀA₁⁻¹b = a₀ᵀÃ⁻¹b₀ + αₐᵀ R⁻¹ α_b with
//! α = [a_F; 0] − Vᵀ Ã⁻¹ a₀, from the columns it kept over the old factor
//! (dot products) or forward halves. Solves through the update (the unit
//! test below) need refinement against K with P₁, since R's conditioning
//! costs digits; measured on the paper scene, the first grab after a pin
//! change cost more that way than refactoring first, so the solver settles
//! (refactors) before any solve that moves the shape.
//!
//! [`Stiffness::with_pinned`]: crate::energy::Stiffness::with_pinned

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::factor::{Factor, Forward};
use crate::energy::Stiffness;

/// A sparse vector in the original order: indices and values.
type Sparse = (Vec<usize>, Vec<f64>);

/// The pinned set P₁ answered through the factor of P₀ (see the module doc).
#[derive(Debug)]
pub(crate) struct PinUpdate {
    /// F: free now, eliminated in the factor, ascending.
    freed: Vec<usize>,
    /// N: pinned now, free in the factor, ascending.
    newly: Vec<usize>,
    /// Per point: its place in `freed`, or `usize::MAX`.
    freed_at: Vec<usize>,
    /// V's columns (F's couplings, then N's unit vectors), sparse.
    columns: Vec<Sparse>,
    /// Their forward halves L⁻¹PV.
    forward: Vec<Forward>,
    /// R⁻¹, row-major (|V| × |V|).
    r_inv: Vec<f64>,
}

/// Largest |V| (freed plus newly pinned points) answered without a
/// refactor. Beyond it the forward halves cost more than the numeric
/// refactorisation they replace: measured at 81 × 159, 100 unit columns
/// 8–15 ms (loaded) against a refactor of ~45 ms; on the 128 × 128 plate the
/// 248 boundary points of an edge clamp cost 117–138 ms of forward halves
/// (boundary points have long elimination-tree paths) against ~60 ms.
pub(crate) const MAX_UPDATED_POINTS: usize = 160;

/// Bound on R's (equilibrated) condition number for an update, so that the
/// Gram entries of S built through it lose at most ~6 digits (the solver's
/// refinement recovers them). Beyond it the caller refactors: a region
/// next to nothing pinned, with a tiny `rest`, makes R as ill-conditioned
/// as K's soft modes.
const MAX_CONDITION: f64 = 1e6;

impl PinUpdate {
    /// The update from the factor's pinned set `factored` (P₀) to `pinned`
    /// (P₁) over `matrix` (K̃, the matrix the factor eliminated P₀ from).
    /// `None` when the factor is not supernodal, the change is larger than
    /// [`MAX_UPDATED_POINTS`], or R is singular: the caller refactors.
    pub(crate) fn new(
        factor: &Factor,
        matrix: &Stiffness,
        factored: &[bool],
        pinned: &[bool],
    ) -> Option<Self> {
        let n = factor.dim();
        if !factor.is_supernodal() || factored.len() != n || pinned.len() != n {
            return None;
        }
        let freed: Vec<usize> = (0..n).filter(|&i| factored[i] && !pinned[i]).collect();
        let newly: Vec<usize> = (0..n).filter(|&i| !factored[i] && pinned[i]).collect();
        let (nf, k) = (freed.len(), freed.len() + newly.len());
        if k == 0 || k > MAX_UPDATED_POINTS {
            return None;
        }
        let mut freed_at = vec![usize::MAX; n];
        for (j, &i) in freed.iter().enumerate() {
            freed_at[i] = j;
        }
        // One pass over the lower triangle: each freed point's column over
        // the factor's free points, and K̃FF.
        let mut columns: Vec<Sparse> = vec![(Vec::new(), Vec::new()); nf];
        let mut kff = vec![0.0; nf * nf];
        let lower = matrix.lower();
        let sym = lower.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), lower.val());
        for c in 0..n {
            for e in cp[c]..cp[c + 1] {
                let (r, v) = (ri[e], val[e]);
                let (fc, fr) = (freed_at[c], freed_at[r]);
                if fc != usize::MAX {
                    if fr != usize::MAX {
                        kff[fr * nf + fc] = v;
                        kff[fc * nf + fr] = v;
                    } else if !factored[r] {
                        columns[fc].0.push(r);
                        columns[fc].1.push(v);
                    }
                }
                if fr != usize::MAX && r != c && fc == usize::MAX && !factored[c] {
                    columns[fr].0.push(c);
                    columns[fr].1.push(v);
                }
            }
        }
        columns.extend(newly.iter().map(|&i| (vec![i], vec![1.0])));
        let refs: Vec<(&[usize], &[f64])> = columns
            .iter()
            .map(|(i, w)| (i.as_slice(), w.as_slice()))
            .collect();
        let forward = factor.forward_sparse(&refs)?;
        let gram = factor.gram_of(&forward);
        let r = Mat::<f64>::from_fn(k, k, |a, b| {
            let block = if a < nf && b < nf {
                kff[a * nf + b]
            } else {
                0.0
            };
            block - gram[a * k + b]
        });
        // Equilibrated (R̂ = D R D, D = |diag R|^-½: K̃FF and S_N have
        // different units), inverted, and refused when its condition bound
        // ‖R̂‖∞‖R̂⁻¹‖∞ exceeds [`MAX_CONDITION`].
        let d: Vec<f64> = (0..k).map(|a| 1.0 / r[(a, a)].abs().sqrt()).collect();
        if d.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let scaled = Mat::<f64>::from_fn(k, k, |a, b| r[(a, b)] * d[a] * d[b]);
        let inverse = scaled
            .full_piv_lu()
            .solve(Mat::<f64>::identity(k, k).as_ref());
        let norm = |m: &Mat<f64>| {
            (0..k)
                .map(|a| (0..k).map(|b| m[(a, b)].abs()).sum::<f64>())
                .fold(0.0f64, f64::max)
        };
        let bound = norm(&scaled) * norm(&inverse);
        if !(bound.is_finite() && bound < MAX_CONDITION) {
            return None;
        }
        let r_inv: Vec<f64> = (0..k)
            .flat_map(|a| (0..k).map(move |b| (a, b)))
            .map(|(a, b)| 0.5 * (inverse[(a, b)] + inverse[(b, a)]) * d[a] * d[b])
            .collect();
        Some(Self {
            freed,
            newly,
            freed_at,
            columns,
            forward,
            r_inv,
        })
    }

    /// Whether any of `indices` is newly pinned.
    pub(crate) fn touches_newly(&self, indices: &[usize]) -> bool {
        indices.iter().any(|i| self.newly.binary_search(i).is_ok())
    }

    /// Splits a sparse right-hand side (zero on P₁) into b₀ (over the
    /// factor's free points) and b_F (per freed point).
    pub(crate) fn split_sparse(&self, indices: &[usize], weights: &[f64]) -> (Sparse, Vec<f64>) {
        let mut b_f = vec![0.0; self.freed.len()];
        let mut rest: Sparse = (Vec::new(), Vec::new());
        for (&i, &w) in indices.iter().zip(weights) {
            match self.freed_at[i] {
                usize::MAX => {
                    rest.0.push(i);
                    rest.1.push(w);
                }
                j => b_f[j] += w,
            }
        }
        (rest, b_f)
    }

    #[cfg(test)]
    /// Takes b_F out of a dense right-hand side (original order): returns
    /// it and zeroes those entries.
    pub(crate) fn split_dense(&self, b: &mut [f64]) -> Vec<f64> {
        self.freed
            .iter()
            .map(|&i| std::mem::take(&mut b[i]))
            .collect()
    }

    /// ξ = R⁻¹ α.
    pub(crate) fn xi(&self, alpha: &[f64]) -> Vec<f64> {
        let k = alpha.len();
        (0..k)
            .map(|a| {
                self.r_inv[a * k..(a + 1) * k]
                    .iter()
                    .zip(alpha)
                    .map(|(r, x)| r * x)
                    .sum()
            })
            .collect()
    }

    /// α = [b_F; 0] − Vᵀ Ã⁻¹ b₀ from the forward half f = L⁻¹P b₀, with
    /// `dot` the product of one of V's forward halves with f.
    fn alpha_by(&self, b_f: &[f64], dot: impl Fn(&Forward) -> f64) -> Vec<f64> {
        self.forward
            .iter()
            .enumerate()
            .map(|(v, fv)| b_f.get(v).copied().unwrap_or(0.0) - dot(fv))
            .collect()
    }

    /// α from the forward half f = L⁻¹P b₀ (see [`Self::alpha_by`]).
    pub(crate) fn alpha_of_forward(&self, f: &Forward, b_f: &[f64]) -> Vec<f64> {
        self.alpha_by(b_f, |fv| fv.dot(f))
    }

    /// α = [b_F; 0] − Vᵀ z₀ from the full solve z₀ = Ã⁻¹ b₀ (original
    /// order).
    pub(crate) fn alpha_of_column(&self, z0: &[f64], b_f: &[f64]) -> Vec<f64> {
        self.columns
            .iter()
            .enumerate()
            .map(|(v, (idx, w))| {
                let vz: f64 = idx.iter().zip(w).map(|(&i, &x)| x * z0[i]).sum();
                b_f.get(v).copied().unwrap_or(0.0) - vz
            })
            .collect()
    }

    #[cfg(test)]
    /// f −= (L⁻¹PV) ξ: the forward half of b₀ − V ξ.
    pub(crate) fn subtract(&self, xi: &[f64], f: &mut [f64]) {
        for (fv, &x) in self.forward.iter().zip(xi) {
            if x != 0.0 {
                fv.axpy(-x, f);
            }
        }
    }

    #[cfg(test)]
    /// Corrects the forward half f = L⁻¹P b₀ in place into that of
    /// b₀ − V ξ; returns x_F (the freed points' values, ξ's first part).
    pub(crate) fn correct(&self, f: &mut [f64], b_f: &[f64]) -> Vec<f64> {
        let xi = self.xi(&self.alpha_by(b_f, |fv| fv.dot_dense(f)));
        self.subtract(&xi, f);
        xi[..self.freed.len()].to_vec()
    }

    #[cfg(test)]
    /// Finishes a solve (original order, `get`/`set` on one column): the
    /// freed points take x_F, the newly pinned ones are exactly zero.
    pub(crate) fn finish(&self, x_f: &[f64], mut set: impl FnMut(usize, f64)) {
        for (&i, &v) in self.freed.iter().zip(x_f) {
            set(i, v);
        }
        for &i in &self.newly {
            set(i, 0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::BSplineSurface;
    use crate::energy::SurfaceMaterial;

    /// A dense solve through the update equals a fresh factor's of the new
    /// pinned set, for points newly pinned and freed at once.
    #[test]
    fn an_updated_solve_is_the_new_factors() {
        let n = 30;
        let s = BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap();
        let k = Stiffness::surface(s.u_knots(), s.v_knots(), &SurfaceMaterial::default()).unwrap();
        let dim = k.dim();
        let old: Vec<bool> = (0..dim).map(|c| c / n < 2).collect();
        let new: Vec<bool> = (0..dim)
            .map(|c| {
                let (i, j) = (c / n, c % n);
                (i == 0 && j > 10) || ((12..18).contains(&i) && (14..19).contains(&j))
            })
            .collect();
        let mut factor = Factor::new(k.with_pinned(&old)).unwrap();
        let mut fresh = Factor::new(k.with_pinned(&new)).unwrap();
        let update = PinUpdate::new(&factor, &k, &old, &new).unwrap();
        let b: Vec<f64> = (0..dim)
            .map(|i| {
                if new[i] {
                    0.0
                } else {
                    ((i * 37) % 11) as f64 - 5.0
                }
            })
            .collect();
        let mut want = Mat::<f64>::from_fn(dim, 1, |i, _| b[i]);
        fresh.solve_in_place(want.as_mut());
        let mut got = Mat::<f64>::from_fn(dim, 1, |i, _| b[i]);
        let b_f = update.split_dense(got.col_as_slice_mut(0));
        assert!(factor.forward_in_place(got.as_mut()));
        let x_f = update.correct(got.col_as_slice_mut(0), &b_f);
        assert!(factor.backward_in_place(got.as_mut()));
        update.finish(&x_f, |i, v| got[(i, 0)] = v);
        let scale = (0..dim).fold(0.0f64, |m, i| m.max(want[(i, 0)].abs()));
        for i in 0..dim {
            assert!(
                (got[(i, 0)] - want[(i, 0)]).abs() <= 1e-8 * scale,
                "{i}: {} vs {} (pinned old {} new {})",
                got[(i, 0)],
                want[(i, 0)],
                old[i],
                new[i]
            );
        }
    }
}
