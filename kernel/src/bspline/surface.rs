//! Non-rational tensor-product B-spline surfaces: evaluation with all
//! derivatives up to second order, unit normal, area.
//!
//! Control points are stored row-major: `index(i, j) = i * nv + j`, i along u
//! (0..nu), j along v (0..nv).

use glam::DVec3;

use super::{BasisDerivs, GeometryError, KnotVector, basis_derivs_into};
use crate::quadrature::GaussLegendre;

/// A surface point with its derivatives up to second order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceDerivs {
    /// w(u,v).
    pub p: DVec3,
    /// ∂w/∂u.
    pub u: DVec3,
    /// ∂w/∂v.
    pub v: DVec3,
    /// ∂²w/∂u².
    pub uu: DVec3,
    /// ∂²w/∂u∂v.
    pub uv: DVec3,
    /// ∂²w/∂v².
    pub vv: DVec3,
}

/// A clamped tensor-product B-spline surface.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineSurface {
    u: KnotVector,
    v: KnotVector,
    points: Vec<DVec3>,
}

impl BSplineSurface {
    /// A surface from its knot vectors and `nu * nv` finite control points
    /// (row-major, i along u).
    pub fn new(u: KnotVector, v: KnotVector, points: Vec<DVec3>) -> Result<Self, GeometryError> {
        let expected = u.num_ctrl() * v.num_ctrl();
        if points.len() != expected {
            return Err(GeometryError::GridSize {
                expected,
                got: points.len(),
            });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::NonFinitePoint { index });
        }
        Ok(Self { u, v, points })
    }

    /// A flat plate z = 0 over [0, size_x] × [0, size_y] with `nu × nv`
    /// control points of the given degree in both directions, clamped uniform
    /// knots, control points at the Greville abscissae (so the parametrisation
    /// is linear: w(u,v) = (size_x·u, size_y·v, 0)).
    pub fn plane(
        size_x: f64,
        size_y: f64,
        nu: usize,
        nv: usize,
        degree: usize,
    ) -> Result<Self, GeometryError> {
        if !(size_x.is_finite() && size_y.is_finite() && size_x > 0.0 && size_y > 0.0) {
            return Err(GeometryError::InvalidSize(format!(
                "plate {size_x} × {size_y}"
            )));
        }
        let u = KnotVector::clamped_uniform(degree, nu)?;
        let v = KnotVector::clamped_uniform(degree, nv)?;
        let gu = greville(&u);
        let gv = greville(&v);
        let mut points = Vec::with_capacity(nu * nv);
        for &a in &gu {
            for &b in &gv {
                points.push(DVec3::new(size_x * a, size_y * b, 0.0));
            }
        }
        Self::new(u, v, points)
    }

    /// Control points along u.
    pub fn nu(&self) -> usize {
        self.u.num_ctrl()
    }

    /// Control points along v.
    pub fn nv(&self) -> usize {
        self.v.num_ctrl()
    }

    /// The storage index of control point (i, j).
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.nv() + j
    }

    /// The knot vector in u.
    pub fn u_knots(&self) -> &KnotVector {
        &self.u
    }

    /// The knot vector in v.
    pub fn v_knots(&self) -> &KnotVector {
        &self.v
    }

    /// The control points, row-major.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The control points, to edit in place (keep them finite).
    pub fn points_mut(&mut self) -> &mut [DVec3] {
        &mut self.points
    }

    /// The control point vector, for crate-internal buffer swaps that keep
    /// its length (and finiteness).
    pub(crate) fn points_mut_vec(&mut self) -> &mut Vec<DVec3> {
        &mut self.points
    }

    /// Replaces every control point; the count must match and all must be finite.
    pub fn set_points(&mut self, points: Vec<DVec3>) -> Result<(), GeometryError> {
        if points.len() != self.points.len() {
            return Err(GeometryError::GridSize {
                expected: self.points.len(),
                got: points.len(),
            });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::NonFinitePoint { index });
        }
        self.points = points;
        Ok(())
    }

    /// The parameter domain ((u0, u1), (v0, v1)).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (self.u.domain(), self.v.domain())
    }

    /// Whether (u, v) is finite and inside the domain.
    pub fn contains(&self, u: f64, v: f64) -> bool {
        self.u.contains(u) && self.v.contains(v)
    }

    /// w(u, v); parameters are clamped into the domain.
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.derivs_order(u, v, 0).p
    }

    /// w and all its derivatives up to second order at (u, v); parameters
    /// are clamped into the domain.
    pub fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
        self.derivs_order(u, v, 2)
    }

    /// The unit normal n = w_u × w_v / |w_u × w_v|. Where the surface is
    /// degenerate (|w_u × w_v| below 1e-14 of |w_u||w_v|), the normal of a
    /// nearby interior point is used instead, and +z as the last resort.
    pub fn normal(&self, u: f64, v: f64) -> DVec3 {
        let d = self.derivs_order(u, v, 1);
        let n = d.u.cross(d.v);
        let scale = d.u.length() * d.v.length();
        if n.length() > 1e-14 * scale && scale > 0.0 {
            return n / n.length();
        }
        let ((u0, u1), (v0, v1)) = self.domain();
        let (cu, cv) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
        let d = self.derivs_order(u + 1e-6 * (cu - u), v + 1e-6 * (cv - v), 1);
        let n = d.u.cross(d.v);
        if n.length() > 0.0 && n.is_finite() {
            n.normalize()
        } else {
            DVec3::Z
        }
    }

    fn derivs_order(&self, u: f64, v: f64, n: usize) -> SurfaceDerivs {
        let mut bu = BasisDerivs::default();
        let mut bv = BasisDerivs::default();
        basis_derivs_into(&self.u, u, n, &mut bu);
        basis_derivs_into(&self.v, v, n, &mut bv);
        self.combine(&bu, &bv, n)
    }

    /// Sums control points against precomputed basis values in u and v
    /// (derivatives up to `n` ≤ 2, as held by `bu` and `bv`).
    pub fn combine(&self, bu: &BasisDerivs, bv: &BasisDerivs, n: usize) -> SurfaceDerivs {
        let pu = self.u.degree();
        let pv = self.v.degree();
        let nv = self.nv();
        let mut out = SurfaceDerivs::default();
        for a in 0..=pu {
            let row = (bu.first + a) * nv + bv.first;
            // Contract v first: c_d = Σ_b M^{(d)}_b P_{a,b}.
            let (mut c0, mut c1, mut c2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
            for b in 0..=pv {
                let p = self.points[row + b];
                c0 += p * bv.get(0, b);
                if n >= 1 {
                    c1 += p * bv.get(1, b);
                }
                if n >= 2 {
                    c2 += p * bv.get(2, b);
                }
            }
            let n0 = bu.get(0, a);
            out.p += c0 * n0;
            if n >= 1 {
                let n1 = bu.get(1, a);
                out.u += c0 * n1;
                out.v += c1 * n0;
                if n >= 2 {
                    out.uu += c0 * bu.get(2, a);
                    out.uv += c1 * n1;
                    out.vv += c2 * n0;
                }
            }
        }
        out
    }

    /// Surface area ∫∫|w_u × w_v| du dv by Gauss–Legendre quadrature on every
    /// knot-span rectangle.
    pub fn area(&self) -> f64 {
        let ru = GaussLegendre::new(self.u.degree() + 4);
        let rv = GaussLegendre::new(self.v.degree() + 4);
        let mut bu = BasisDerivs::default();
        let mut bv = BasisDerivs::default();
        let vspans = self.v.spans();
        let mut total = 0.0;
        for (_, ua, ub) in self.u.spans() {
            for (u, wu) in ru.on(ua, ub) {
                basis_derivs_into(&self.u, u, 1, &mut bu);
                for &(_, va, vb) in &vspans {
                    for (v, wv) in rv.on(va, vb) {
                        basis_derivs_into(&self.v, v, 1, &mut bv);
                        let d = self.combine(&bu, &bv, 1);
                        total += wu * wv * d.u.cross(d.v).length();
                    }
                }
            }
        }
        total
    }
}

/// The Greville abscissae of a knot vector: the average of p consecutive
/// interior knots, one per control point. A B-spline whose control values are
/// the Greville abscissae reproduces the identity function.
pub fn greville(kv: &KnotVector) -> Vec<f64> {
    let p = kv.degree();
    let k = kv.knots();
    (0..kv.num_ctrl())
        .map(|i| k[i + 1..=i + p].iter().sum::<f64>() / p as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy() -> BSplineSurface {
        let u = KnotVector::new(3, vec![0., 0., 0., 0., 0.4, 1., 1., 1., 1.]).unwrap();
        let v = KnotVector::clamped_uniform(2, 5).unwrap();
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let (x, y) = (i as f64, j as f64);
                pts.push(DVec3::new(
                    x,
                    y,
                    (0.7 * x).sin() * (0.9 * y).cos() + 0.1 * x * y,
                ));
            }
        }
        BSplineSurface::new(u, v, pts).unwrap()
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let s = wavy();
        let h = 1e-5;
        for &(u, v) in &[(0.1, 0.2), (0.5, 0.5), (0.8, 0.9), (0.35, 0.7)] {
            let d = s.derivs(u, v);
            let du = (s.point(u + h, v) - s.point(u - h, v)) / (2.0 * h);
            let dv = (s.point(u, v + h) - s.point(u, v - h)) / (2.0 * h);
            let duu = (s.derivs(u + h, v).u - s.derivs(u - h, v).u) / (2.0 * h);
            let duv = (s.derivs(u, v + h).u - s.derivs(u, v - h).u) / (2.0 * h);
            let dvv = (s.derivs(u, v + h).v - s.derivs(u, v - h).v) / (2.0 * h);
            for (fd, exact) in [(du, d.u), (dv, d.v), (duu, d.uu), (duv, d.uv), (dvv, d.vv)] {
                assert!(
                    (fd - exact).length() < 1e-5 * (1.0 + exact.length()),
                    "{fd} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn plane_is_linearly_parametrised_with_exact_area() {
        let s = BSplineSurface::plane(2.0, 3.0, 7, 5, 3).unwrap();
        for &(u, v) in &[(0.0, 0.0), (0.3, 0.6), (1.0, 1.0), (0.77, 0.12)] {
            assert!((s.point(u, v) - DVec3::new(2.0 * u, 3.0 * v, 0.0)).length() < 1e-14);
            assert!((s.normal(u, v) - DVec3::Z).length() < 1e-14);
        }
        assert!((s.area() - 6.0).abs() < 1e-12);
    }

    #[test]
    fn corners_interpolate_control_points() {
        let s = wavy();
        assert!((s.point(0.0, 0.0) - s.points()[0]).length() < 1e-15);
        assert!((s.point(1.0, 1.0) - s.points()[24]).length() < 1e-15);
        assert!((s.point(1.0, 0.0) - s.points()[s.index(4, 0)]).length() < 1e-15);
    }

    #[test]
    fn bad_input_is_rejected() {
        let u = KnotVector::clamped_uniform(3, 4).unwrap();
        assert!(BSplineSurface::new(u.clone(), u.clone(), vec![DVec3::ZERO; 15]).is_err());
        let mut pts = vec![DVec3::ZERO; 16];
        pts[3].x = f64::NAN;
        assert!(BSplineSurface::new(u.clone(), u.clone(), pts).is_err());
        assert!(BSplineSurface::plane(f64::NAN, 1.0, 4, 4, 3).is_err());
        let mut s = BSplineSurface::plane(1.0, 1.0, 4, 4, 3).unwrap();
        let before = s.clone();
        assert!(s.set_points(vec![DVec3::splat(f64::INFINITY); 16]).is_err());
        assert_eq!(s, before);
    }
}
