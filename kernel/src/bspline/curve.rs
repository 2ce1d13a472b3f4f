//! Non-rational B-spline curves in 3D: evaluation with first and second
//! derivatives, length. A curve in a surface's (u,v) domain is a
//! `BSplineCurve` whose points have z = 0 (x = u, y = v).

use glam::DVec3;

use super::{BasisDerivs, GeometryError, KnotVector, basis_derivs_into};
use crate::quadrature::GaussLegendre;

/// A point of a curve with its first and second derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurveDerivs {
    /// c(t).
    pub p: DVec3,
    /// c'(t).
    pub d1: DVec3,
    /// c''(t).
    pub d2: DVec3,
}

/// A clamped B-spline curve: a knot vector and its control points.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineCurve {
    knots: KnotVector,
    points: Vec<DVec3>,
}

impl BSplineCurve {
    /// A curve from its knots and `knots.num_ctrl()` finite control points.
    pub fn new(knots: KnotVector, points: Vec<DVec3>) -> Result<Self, GeometryError> {
        if points.len() != knots.num_ctrl() {
            return Err(GeometryError::GridSize {
                expected: knots.num_ctrl(),
                got: points.len(),
            });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::NonFinitePoint { index });
        }
        Ok(Self { knots, points })
    }

    /// The knot vector.
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.knots.degree()
    }

    /// The control points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The control points, to edit in place (keep them finite).
    pub fn points_mut(&mut self) -> &mut [DVec3] {
        &mut self.points
    }

    /// The parameter domain.
    pub fn domain(&self) -> (f64, f64) {
        self.knots.domain()
    }

    /// c(t); t is clamped into the domain.
    pub fn point(&self, t: f64) -> DVec3 {
        self.derivs_order(t, 0).p
    }

    /// c(t), c'(t), c''(t); t is clamped into the domain.
    pub fn derivs(&self, t: f64) -> CurveDerivs {
        self.derivs_order(t, 2)
    }

    fn derivs_order(&self, t: f64, n: usize) -> CurveDerivs {
        let mut b = BasisDerivs::default();
        basis_derivs_into(&self.knots, t, n, &mut b);
        let mut out = CurveDerivs::default();
        for k in 0..=self.degree() {
            let p = self.points[b.first + k];
            out.p += p * b.get(0, k);
            if n >= 1 {
                out.d1 += p * b.get(1, k);
            }
            if n >= 2 {
                out.d2 += p * b.get(2, k);
            }
        }
        out
    }

    /// Arc length ∫|c'(t)| dt by Gauss–Legendre quadrature on every span.
    pub fn length(&self) -> f64 {
        let rule = GaussLegendre::new(self.degree() + 4);
        let mut b = BasisDerivs::default();
        let mut total = 0.0;
        for (_, a, e) in self.knots.spans() {
            for (t, w) in rule.on(a, e) {
                basis_derivs_into(&self.knots, t, 1, &mut b);
                let d1: DVec3 = (0..=self.degree())
                    .map(|k| self.points[b.first + k] * b.get(1, k))
                    .sum();
                total += w * d1.length();
            }
        }
        total
    }

    /// Moves every control point by `offset`.
    pub fn translate(&mut self, offset: DVec3) {
        self.points.iter_mut().for_each(|p| *p += offset);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> BSplineCurve {
        let kv = KnotVector::new(3, vec![0., 0., 0., 0., 0.3, 0.7, 1., 1., 1., 1.]).unwrap();
        let pts = vec![
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 2., 0.),
            DVec3::new(2., -1., 1.),
            DVec3::new(3., 1., 0.5),
            DVec3::new(4., 0., 2.),
            DVec3::new(5., 1., 0.),
        ];
        BSplineCurve::new(kv, pts).unwrap()
    }

    #[test]
    fn clamped_curve_interpolates_its_ends() {
        let c = curve();
        assert!((c.point(0.0) - c.points()[0]).length() < 1e-15);
        assert!((c.point(1.0) - c.points()[5]).length() < 1e-15);
        // End tangent is p/(u_{p+1}-u_1)·(P1−P0).
        let d = c.derivs(0.0);
        assert!((d.d1 - (c.points()[1] - c.points()[0]) * (3.0 / 0.3)).length() < 1e-12);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let c = curve();
        let h = 1e-6;
        for &t in &[0.1, 0.35, 0.5, 0.8] {
            let d = c.derivs(t);
            let fd1 = (c.point(t + h) - c.point(t - h)) / (2.0 * h);
            let fd2 = (c.derivs(t + h).d1 - c.derivs(t - h).d1) / (2.0 * h);
            assert!((fd1 - d.d1).length() < 1e-6 * (1.0 + d.d1.length()));
            assert!((fd2 - d.d2).length() < 1e-5 * (1.0 + d.d2.length()));
        }
    }

    #[test]
    fn length_of_a_straight_line() {
        let kv = KnotVector::clamped_uniform(3, 5).unwrap();
        let pts = (0..5)
            .map(|i| DVec3::new(i as f64, 2.0 * i as f64, 0.0))
            .collect();
        let c = BSplineCurve::new(kv, pts).unwrap();
        assert!((c.length() - 20f64.sqrt() * 2.0).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_rejected() {
        let kv = KnotVector::clamped_uniform(2, 4).unwrap();
        assert!(BSplineCurve::new(kv.clone(), vec![DVec3::ZERO; 3]).is_err());
        let mut pts = vec![DVec3::ZERO; 4];
        pts[2].y = f64::INFINITY;
        assert_eq!(
            BSplineCurve::new(kv, pts),
            Err(GeometryError::NonFinitePoint { index: 2 })
        );
    }
}
