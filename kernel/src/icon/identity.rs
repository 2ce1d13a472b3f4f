//! A curve constraint as a polynomial identity: c(t) = w(u(t), v(t)) for
//! every t, not at samples (paper 003).
//!
//! On each piece of the curve (its own knot spans, cut where u(t) or v(t)
//! crosses a knot line of the surface) w∘c is one polynomial of degree
//! q·(p_u + p_v) (q the curve's degree, p the surface's), so holding it at
//! that many points plus one per piece ([`super::samples`]) holds it on the
//! whole piece. Those collocation equations A P = shape are dependent
//! (neighbouring pieces share the same control points), so they are
//! replaced by an orthonormal basis of A's row space: with A = U Σ Vᵀ
//! over the control points the curve touches, the rows are the columns of
//! V whose singular value is above 1e-13 of the largest (the rest are exact
//! dependencies, at round-off). A constraint captures the rows' values on
//! the control points themselves (Vᵀ P), so no sample value is divided by
//! a small singular value. The same equations, none redundant, none
//! dropped: independent by construction and well scaled for the solver.

use faer::Mat;
use glam::DVec3;

use super::surface_row;
use crate::bspline::BSplineSurface;
use crate::solve::ScalarRow;

/// Relative singular value of A below which a direction is a dependency
/// (exact dependencies come out at ~1e-16; a direction this weak moves the
/// curve by at most 1e-13 of the motion along it).
const DEPENDENT: f64 = 1e-13;

/// The independent equations equivalent to holding a curve at its
/// collocation samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Identity {
    /// One row per independent direction (orthonormal over the control points).
    pub rows: Vec<ScalarRow>,
    /// Per row, the sum of its weights: a translation by s moves the row's
    /// value by s times it.
    pub sums: Vec<f64>,
}

impl Identity {
    /// The rows' values on `points` (what a constraint captures: the
    /// targets are these, no sample values in between to amplify).
    pub fn capture(&self, points: &[DVec3]) -> Vec<DVec3> {
        self.rows.iter().map(|r| r.apply(points)).collect()
    }

    /// The targets of the rows for the captured values translated by `shift`.
    pub fn targets(&self, held: &[DVec3], shift: DVec3) -> Vec<DVec3> {
        held.iter()
            .zip(&self.sums)
            .map(|(h, s)| *h + shift * *s)
            .collect()
    }
}

/// The identity of the curve sampled at `samples` on `surface`: an
/// orthonormal basis of the row space of the collocation matrix A (its
/// right singular vectors above [`DEPENDENT`]).
pub fn identity(samples: &[(f64, f64)], surface: &BSplineSurface) -> Identity {
    let rows: Vec<ScalarRow> = samples
        .iter()
        .map(|&(u, v)| surface_row(surface, u, v, 0, 0))
        .collect();
    let mut touched: Vec<usize> = rows
        .iter()
        .flat_map(|r| r.indices.iter().copied())
        .collect();
    touched.sort_unstable();
    touched.dedup();
    let t = touched.len();
    let mut a = Mat::<f64>::zeros(rows.len(), t);
    for (s, r) in rows.iter().enumerate() {
        for (&i, &w) in r.indices.iter().zip(&r.weights) {
            if let Ok(c) = touched.binary_search(&i) {
                a[(s, c)] += w;
            }
        }
    }
    let Ok(svd) = a.thin_svd() else {
        return Identity::default();
    };
    let (v, sigma) = (svd.V(), svd.S());
    let k = sigma.dim();
    let max = (0..k).map(|i| sigma[i]).fold(0.0f64, f64::max);
    let mut out = Identity::default();
    for d in (0..k).filter(|&d| sigma[d] > DEPENDENT * max) {
        let mut row = ScalarRow::default();
        for (c, &i) in touched.iter().enumerate() {
            if v[(c, d)] != 0.0 {
                row.indices.push(i);
                row.weights.push(v[(c, d)]);
            }
        }
        out.sums.push(row.weights.iter().sum());
        out.rows.push(row);
    }
    out
}
