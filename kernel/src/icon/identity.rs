//! A curve constraint as a polynomial identity: c(t) = w(u(t), v(t)) for
//! every t, not at samples (paper 003).
//!
//! On each piece of the curve (its own knot spans, cut where u(t) or v(t)
//! crosses a knot line of the surface) w∘c is one polynomial of degree
//! q·(p_u + p_v) (q the curve's degree, p the surface's), so holding it at
//! that many points plus one per piece (`sampling::collocation`) holds it
//! on the whole piece. Those collocation equations A P = shape are
//! dependent (neighbouring pieces share control points), so only an
//! independent subset is kept: the rows a column-pivoted QR of Aᵀ picks
//! before its pivot falls below [`DEPENDENT`] of the first. Every other
//! collocation row is a combination of the kept ones (to that tolerance),
//! and the held values come from one surface, so holding the kept samples
//! holds them all. The kept rows are ordinary point rows (4 × 4 control
//! points), so the solver can treat them like any point constraint.

use faer::Mat;

use super::surface_row;
use crate::bspline::BSplineSurface;

/// Relative pivot of the QR below which a collocation row counts as
/// dependent on the ones kept. Exact dependencies come out at 1e-12 and
/// below, but the pivots of a curved curve decay smoothly down to ~1e-10
/// (control points the curve barely touches): keeping rows below 1e-6 made
/// S singular to working precision (rows dropped, the solve off by 3e-9 of
/// the shape when a curve was created mid-drag). A row dropped here moves
/// the curve by at most this fraction of the motion of its control points;
/// measured at 10× the sample density, ≤ 1e-7 of the shape's size
/// (`tests/held_everywhere.rs`).
const DEPENDENT: f64 = 1e-6;

/// The independent subset of the collocation `samples` on `surface`, in
/// their original order.
pub fn independent_samples(samples: &[(f64, f64)], surface: &BSplineSurface) -> Vec<(f64, f64)> {
    let rows: Vec<_> = samples
        .iter()
        .map(|&(u, v)| surface_row(surface, u, v, 0, 0))
        .collect();
    let mut touched: Vec<usize> = rows
        .iter()
        .flat_map(|r| r.indices.iter().copied())
        .collect();
    touched.sort_unstable();
    touched.dedup();
    // Aᵀ: one column per sample.
    let mut at = Mat::<f64>::zeros(touched.len(), rows.len());
    for (s, r) in rows.iter().enumerate() {
        for (&i, &w) in r.indices.iter().zip(&r.weights) {
            if let Ok(c) = touched.binary_search(&i) {
                at[(c, s)] += w;
            }
        }
    }
    let qr = at.col_piv_qr();
    let r = qr.thin_R();
    let k = r.nrows().min(r.ncols());
    let first = if k > 0 { r[(0, 0)].abs() } else { 0.0 };
    let rank = (0..k)
        .take_while(|&d| r[(d, d)].abs() > DEPENDENT * first)
        .count();
    let (fwd, _) = qr.P().arrays();
    let mut kept: Vec<usize> = fwd[..rank].to_vec();
    kept.sort_unstable();
    kept.into_iter().map(|s| samples[s]).collect()
}
