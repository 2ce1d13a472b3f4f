//! A curve constraint as a polynomial identity: c(t) = w(u(t), v(t)) for
//! every t, not at samples (paper 003).
//!
//! On each piece of the curve (its own knot spans, cut where u(t) or v(t)
//! crosses a knot line of the surface) w∘c is one polynomial of degree
//! q·(p_u + p_v) (q the curve's degree, p the surface's), so holding it at
//! that many points plus one per piece (`sampling::collocation`) holds it
//! on the whole piece: the identity is A P = shape, A the collocation rows.
//! Those rows are dependent (neighbouring pieces share control points), and
//! the curve's handle is always the first point row (see [`curve_identity`]),
//! and a column-pivoted QR of the rest of Aᵀ (the handle's direction taken
//! out), Aᵀ = Q R Πᵀ, splits their span in two:
//!
//! * the samples it picks first, while its pivot stays above [`POINT`] of
//!   the first: kept as ordinary point rows (4 × 4 control points, sum 1),
//!   which the solver can fold into its factor like any point constraint,
//!   and which are well conditioned among themselves;
//! * the rest of A's row space, down to [`EXACT`]: the further columns of Q,
//!   orthonormal and orthogonal to the point rows — directions of control
//!   points the curve barely touches (a basis function near the end of its
//!   support). Each is made translation-free (minus its sum times one point
//!   row) and held at its captured value as three scalar equations
//!   (`Equation::Projected` per coordinate), so a drag that translates the
//!   held shape leaves them as they are.
//!
//! Why two thresholds. Before, every direction down to a pivot of 1e-6
//! was a point row and the rest of the span was left free. Point rows that
//! nearly depend on each other make S = C K⁻¹ Cᵀ singular to working
//! precision: on 20 × 15 the solver dropped 3 directions and missed the
//! equations by 2.8e-9, the curve off by 5e-9 of the shape between
//! samples; on 81 × 159 by 5e-8. Cut at 1e-3, the point rows are well
//! conditioned (nothing dropped, equations met to 1e-14) and the rest of
//! the span is held by orthonormal rows, as well conditioned. A QR column
//! of pivot ρ is accurate to about ε/ρ in direction (ε the unit
//! round-off), so a direction below [`EXACT`] is left out: what it leaves
//! free moves the curve by less than 1e-9 of its control points' motion,
//! while holding it would hold a 1e-7 tilt of it.

use faer::Mat;

use super::surface_row;
use crate::bspline::BSplineSurface;
use crate::solve::ScalarRow;

/// Relative QR pivot down to which collocation samples are kept as point
/// rows. At 1e-6 they made S singular to working precision (3 directions
/// dropped under a pulling load on 20 × 15); at 1e-3 none is dropped and
/// the held curve is the same (the rest of the span is held by the
/// translation-free rows), on 20 × 15 and 81 × 159 alike.
const POINT: f64 = 1e-3;

/// Relative QR pivot down to which the rest of the row space is held (as
/// translation-free rows, see the module doc).
const EXACT: f64 = 1e-9;

/// A curve's identity on a surface: the point rows' samples and the
/// translation-free rows that complete their span to the collocation rows'.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Identity {
    /// The collocation samples kept as point rows, in their original order.
    pub samples: Vec<(f64, f64)>,
    /// Rows over the control points whose weights sum to zero, orthogonal
    /// to the point rows' span (up to one point row each): the identity's
    /// remaining directions.
    pub rows: Vec<ScalarRow>,
}

/// The identity held by the collocation `samples` on `surface`, with
/// `handle` (the curve's handle, [`super::Anchor::handle_uv`]) always its
/// first point row.
///
/// Why the handle is a row of its own: a curve constraint's targets are
/// its captured shape translated by `target − handle`, and a design rebuilt
/// from its document measures that handle again on the current surface.
/// Held only through the identity, the handle would follow the held shape
/// to [`EXACT`] of its motion, so a rebuild after a pull found the curve
/// "moved" by ~5e-9 and the solve translated it back, which a point
/// constraint 0.8 mm from the curve turned into a 1.4e-5 mm bend of the
/// whole 20 × 15 plate. As a point row the handle is held to round-off, so
/// a rebuild finds every target where it is and moves nothing
/// (`server/tests/icon_creation.rs`).
pub fn curve_identity(
    samples: &[(f64, f64)],
    handle: (f64, f64),
    surface: &BSplineSurface,
) -> Identity {
    let handle_row = surface_row(surface, handle.0, handle.1, 0, 0);
    let rows: Vec<_> = samples
        .iter()
        .map(|&(u, v)| surface_row(surface, u, v, 0, 0))
        .collect();
    let mut touched: Vec<usize> = rows
        .iter()
        .chain(std::iter::once(&handle_row))
        .flat_map(|r| r.indices.iter().copied())
        .collect();
    touched.sort_unstable();
    touched.dedup();
    let column = |r: &ScalarRow| {
        let mut c = vec![0.0; touched.len()];
        for (&i, &w) in r.indices.iter().zip(&r.weights) {
            if let Ok(k) = touched.binary_search(&i) {
                c[k] += w;
            }
        }
        c
    };
    let h = column(&handle_row);
    let h_norm = h.iter().map(|x| x * x).sum::<f64>().sqrt();
    // Aᵀ: one column per sample, the handle's direction taken out (it is
    // the first point row whatever the pivoting picks).
    let mut at = Mat::<f64>::zeros(touched.len(), rows.len());
    for (s, r) in rows.iter().enumerate() {
        let c = column(r);
        let along: f64 = c.iter().zip(&h).map(|(a, b)| a * b).sum::<f64>() / (h_norm * h_norm);
        for (k, (x, hk)) in c.iter().zip(&h).enumerate() {
            at[(k, s)] = x - along * hk;
        }
    }
    let qr = at.col_piv_qr();
    let r = qr.thin_R();
    let k = r.nrows().min(r.ncols());
    let first = h_norm.max(if k > 0 { r[(0, 0)].abs() } else { 0.0 });
    let rank = |tol: f64| {
        (0..k)
            .take_while(|&d| r[(d, d)].abs() > tol * first)
            .count()
    };
    let (points, exact) = (rank(POINT), rank(EXACT));
    let (fwd, _) = qr.P().arrays();
    let mut kept: Vec<usize> = fwd[..points].to_vec();
    kept.sort_unstable();
    let mut extra = Vec::new();
    if exact > points {
        let q = qr.compute_thin_Q();
        // The handle's point row (weights sum to 1) takes each direction's
        // sum off.
        for j in points..exact {
            let sum: f64 = (0..touched.len()).map(|c| q[(c, j)]).sum();
            let mut row = ScalarRow::default();
            for (c, &index) in touched.iter().enumerate() {
                let w = q[(c, j)] - sum * h[c];
                if w != 0.0 {
                    row.indices.push(index);
                    row.weights.push(w);
                }
            }
            extra.push(row);
        }
    }
    Identity {
        samples: std::iter::once(handle)
            .chain(kept.into_iter().map(|s| samples[s]))
            .collect(),
        rows: extra,
    }
}
