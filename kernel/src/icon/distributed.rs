//! Distributed loads: the consistent load vector of a load spread over a
//! curve or a region (paper 003: f(u(t), v(t)) and f(u(s), v(t))).
//!
//! A uniform force density f over a set Ω of the parameter domain enters the
//! energy as −2∫_Ω w·f, so its load vector is b_ij = f · ∫_Ω N_i(u) M_j(v):
//! one [`ScalarRow`] c with c_ij = ∫_Ω N_i M_j, times the force density.
//! The row's weights sum to the measure of Ω (Σ N_i M_j = 1), so the total
//! force is f·|Ω| and grows with the region.
//!
//! * A rectangle [a0,a1]×[b0,b1] separates: c_ij = (∫N_i du)(∫M_j dv), each
//!   1-D integral by Gauss–Legendre with degree+1 nodes per knot span (exact
//!   for the degree-p pieces of N_i). The complement of a rectangle is the
//!   whole domain's row minus the rectangle's.
//! * A curve (u(t), v(t)) carries a line density: c_ij = ∫ N_i M_j |c′(t)| dt
//!   with |c′| the speed in (u,v). Each of the curve's knot spans is cut into
//!   pieces no longer than a quarter of the surface's knot spacing and
//!   integrated with 8 Gauss nodes per piece (the integrand is smooth inside
//!   a piece but for the C^(p−1) joins of N_i where the curve crosses a
//!   surface knot).
//!
//! Measures are in the parameter domain, as the energy is (kernel README,
//! "Units").

use super::Anchor;
use crate::bspline::{BSplineCurve, BSplineSurface, BasisDerivs, KnotVector, basis_derivs_into};
use crate::quadrature::GaussLegendre;
use crate::solve::ScalarRow;

/// ∫_a^b N_i(t) dt for every basis function of `kv` (a ≤ b inside the domain).
fn integrals(kv: &KnotVector, a: f64, b: f64) -> Vec<f64> {
    let mut out = vec![0.0; kv.num_ctrl()];
    let rule = GaussLegendre::new(kv.degree() + 1);
    let mut basis = BasisDerivs::default();
    for (_, s0, s1) in kv.spans() {
        let (lo, hi) = (s0.max(a), s1.min(b));
        if hi <= lo {
            continue;
        }
        for (t, w) in rule.on(lo, hi) {
            basis_derivs_into(kv, t, 0, &mut basis);
            for (k, n) in basis.row(0).iter().enumerate() {
                out[basis.first + k] += w * n;
            }
        }
    }
    out
}

/// The consistent-load row of a uniform unit density over `anchor` (see the
/// module doc); for a point anchor the row of w at the point (a
/// concentrated unit force).
pub fn load_row(anchor: &Anchor, surface: &BSplineSurface) -> ScalarRow {
    match anchor {
        Anchor::Point { u, v } => super::surface_row(surface, *u, *v, 0, 0),
        Anchor::Region {
            u0,
            v0,
            u1,
            v1,
            inside,
        } => {
            let (ku, kv) = (surface.u_knots(), surface.v_knots());
            let iu = integrals(ku, u0.min(*u1), u0.max(*u1));
            let iv = integrals(kv, v0.min(*v1), v0.max(*v1));
            let (whole_u, whole_v) = if *inside {
                (None, None)
            } else {
                let ((a0, a1), (b0, b1)) = surface.domain();
                (Some(integrals(ku, a0, a1)), Some(integrals(kv, b0, b1)))
            };
            let mut row = ScalarRow::default();
            for i in 0..surface.nu() {
                for j in 0..surface.nv() {
                    let rect = iu[i] * iv[j];
                    let c = match (&whole_u, &whole_v) {
                        (Some(tu), Some(tv)) => tu[i] * tv[j] - rect,
                        _ => rect,
                    };
                    if c != 0.0 {
                        row.indices.push(surface.index(i, j));
                        row.weights.push(c);
                    }
                }
            }
            row
        }
        Anchor::Curve(curve) => curve_row(curve, surface),
        Anchor::Edge { edge, .. } => curve_row(&edge.curve(), surface),
    }
}

/// ∫ N_i(u(t)) M_j(v(t)) |c′(t)| dt along a (u,v) curve.
fn curve_row(curve: &BSplineCurve, surface: &BSplineSurface) -> ScalarRow {
    let ((a0, a1), (b0, b1)) = surface.domain();
    let du = (a1 - a0) / surface.u_knots().spans().len().max(1) as f64;
    let dv = (b1 - b0) / surface.v_knots().spans().len().max(1) as f64;
    let rule = GaussLegendre::new(8);
    let mut dense = vec![0.0; surface.points().len()];
    let (mut bu, mut bv) = (BasisDerivs::default(), BasisDerivs::default());
    for (_, t0, t1) in curve.knots().spans() {
        // The span's extent in surface knot spans, from its control polygon
        // (which bounds the curve piece).
        let mut extent: f64 = 0.0;
        let steps = 16;
        let mut prev = curve.point(t0);
        for k in 1..=steps {
            let p = curve.point(t0 + (t1 - t0) * k as f64 / steps as f64);
            extent += ((p.x - prev.x) / du).abs().max(((p.y - prev.y) / dv).abs());
            prev = p;
        }
        let pieces = (4.0 * extent).ceil().max(1.0) as usize;
        for piece in 0..pieces {
            let lo = t0 + (t1 - t0) * piece as f64 / pieces as f64;
            let hi = t0 + (t1 - t0) * (piece + 1) as f64 / pieces as f64;
            for (t, w) in rule.on(lo, hi) {
                let d = curve.derivs(t);
                let speed = (d.d1.x * d.d1.x + d.d1.y * d.d1.y).sqrt();
                let (u, v) = (d.p.x.clamp(a0, a1), d.p.y.clamp(b0, b1));
                basis_derivs_into(surface.u_knots(), u, 0, &mut bu);
                basis_derivs_into(surface.v_knots(), v, 0, &mut bv);
                for (a, nu) in bu.row(0).iter().enumerate() {
                    for (b, nv) in bv.row(0).iter().enumerate() {
                        dense[surface.index(bu.first + a, bv.first + b)] += w * speed * nu * nv;
                    }
                }
            }
        }
    }
    let mut row = ScalarRow::default();
    for (i, c) in dense.into_iter().enumerate() {
        if c != 0.0 {
            row.indices.push(i);
            row.weights.push(c);
        }
    }
    row
}
