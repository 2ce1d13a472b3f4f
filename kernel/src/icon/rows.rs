//! The linear functionals icons are made of: the basis-function weights of
//! w(u,v) or one of its derivatives at a parameter point, as a [`ScalarRow`]
//! over the surface's (or curve's) control points.

use crate::bspline::{BSplineCurve, BSplineSurface, basis_derivs};
use crate::solve::ScalarRow;

/// The row of ∂^(du+dv) w / ∂u^du ∂v^dv at (u, v) (du, dv ≤ 2): applied to
/// the control points it gives that derivative of the surface.
pub fn surface_row(surface: &BSplineSurface, u: f64, v: f64, du: usize, dv: usize) -> ScalarRow {
    let bu = basis_derivs(surface.u_knots(), u, du);
    let bv = basis_derivs(surface.v_knots(), v, dv);
    let pu = surface.u_knots().degree();
    let pv = surface.v_knots().degree();
    let mut row = ScalarRow::default();
    for a in 0..=pu {
        let wa = bu.get(du, a);
        for b in 0..=pv {
            let w = wa * bv.get(dv, b);
            if w != 0.0 {
                row.indices.push(surface.index(bu.first + a, bv.first + b));
                row.weights.push(w);
            }
        }
    }
    row
}

/// The row of the d-th derivative of a curve at t (d ≤ 2).
pub fn curve_row(curve: &BSplineCurve, t: f64, d: usize) -> ScalarRow {
    let b = basis_derivs(curve.knots(), t, d);
    let mut row = ScalarRow::default();
    for k in 0..=curve.degree() {
        let w = b.get(d, k);
        if w != 0.0 {
            row.indices.push(b.first + k);
            row.weights.push(w);
        }
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::KnotVector;
    use glam::DVec3;

    #[test]
    fn rows_reproduce_evaluation() {
        let u = KnotVector::clamped_uniform(3, 6).unwrap();
        let v = KnotVector::clamped_uniform(2, 5).unwrap();
        let pts = (0..30)
            .map(|k| DVec3::new(k as f64, (k as f64).sqrt(), (k * k) as f64 * 0.01))
            .collect();
        let s = BSplineSurface::new(u, v, pts).unwrap();
        let d = s.derivs(0.3, 0.7);
        let pairs = [
            ((0, 0), d.p),
            ((1, 0), d.u),
            ((0, 1), d.v),
            ((2, 0), d.uu),
            ((1, 1), d.uv),
            ((0, 2), d.vv),
        ];
        for ((du, dv), want) in pairs {
            let got = surface_row(&s, 0.3, 0.7, du, dv).apply(s.points());
            assert!(
                (got - want).length() < 1e-10 * (1.0 + want.length()),
                "{du},{dv}"
            );
        }
        let c = BSplineCurve::new(
            KnotVector::clamped_uniform(3, 5).unwrap(),
            s.points()[..5].to_vec(),
        )
        .unwrap();
        let cd = c.derivs(0.4);
        assert!((curve_row(&c, 0.4, 1).apply(c.points()) - cd.d1).length() < 1e-10);
        assert!((curve_row(&c, 0.4, 2).apply(c.points()) - cd.d2).length() < 1e-9);
    }
}
