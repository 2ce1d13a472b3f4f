//! Degree elevation of curves, surfaces and volumes.
//!
//! A degree-p spline with a knot of multiplicity m is C^{p−m} there; the
//! same function in degree p+1 needs that knot with multiplicity m+1. The
//! elevated space contains the old one, so the elevated control points are
//! the unique interpolant of the old curve at the Greville abscissae of the
//! new space (always well posed: Schoenberg–Whitney holds at Greville
//! sites). One dense LU (faer) of the collocation matrix serves every line
//! of a surface or volume. The result equals the old spline to rounding
//! (tests compare at 1e-12).

use faer::Mat;
use faer::prelude::Solve;
use glam::DVec3;

use super::refine::{distinct_knots, map_surface_lines};
use super::{BSplineVolume, BodyError, Dir};
use crate::bspline::{BSplineCurve, BSplineSurface, KnotVector, basis_derivs, greville};

/// The knot vector of degree p + `times` holding the same spline space
/// (every distinct knot's multiplicity raised by `times`).
pub fn elevated_knots(kv: &KnotVector, times: usize) -> KnotVector {
    let mut knots = Vec::new();
    for (v, m) in distinct_knots(kv) {
        knots.extend(std::iter::repeat_n(v, m + times));
    }
    KnotVector::new(kv.degree() + times, knots).expect("raising all multiplicities stays valid")
}

/// A precomputed elevation from one knot vector to its elevated space.
pub struct Elevation {
    from: KnotVector,
    to: KnotVector,
    sites: Vec<f64>,
    lu: faer::linalg::solvers::PartialPivLu<f64>,
}

impl Elevation {
    /// Prepares elevation of splines on `kv` by `times` degrees.
    pub fn new(kv: &KnotVector, times: usize) -> Result<Self, BodyError> {
        let to = elevated_knots(kv, times);
        let sites = greville(&to);
        let n = to.num_ctrl();
        let mut a = Mat::<f64>::zeros(n, n);
        for (r, &t) in sites.iter().enumerate() {
            let b = basis_derivs(&to, t, 0);
            for (c, &v) in b.row(0).iter().enumerate() {
                a[(r, b.first + c)] = v;
            }
        }
        let lu = a.partial_piv_lu();
        Ok(Self {
            from: kv.clone(),
            to,
            sites,
            lu,
        })
    }

    /// The elevated knot vector.
    pub fn knots(&self) -> &KnotVector {
        &self.to
    }

    /// The curve `c` (on this elevation's source knots) in the elevated space.
    pub fn apply(&self, c: &BSplineCurve) -> Result<BSplineCurve, BodyError> {
        if c.knots() != &self.from {
            return Err(BodyError::Mismatch(
                "curve is not on the elevation's knots".into(),
            ));
        }
        let n = self.sites.len();
        let rhs = Mat::<f64>::from_fn(n, 3, |r, d| c.point(self.sites[r])[d]);
        let x = self.lu.solve(&rhs);
        let pts: Vec<DVec3> = (0..n)
            .map(|r| DVec3::new(x[(r, 0)], x[(r, 1)], x[(r, 2)]))
            .collect();
        if pts.iter().any(|p| !p.is_finite()) {
            return Err(BodyError::Singular("degree elevation".into()));
        }
        Ok(BSplineCurve::new(self.to.clone(), pts)?)
    }
}

/// The curve `c` with its degree raised by `times` (the same curve).
pub fn elevate_curve(c: &BSplineCurve, times: usize) -> Result<BSplineCurve, BodyError> {
    if times == 0 {
        return Ok(c.clone());
    }
    Elevation::new(c.knots(), times)?.apply(c)
}

/// The surface `s` with its degrees raised by `tu` in u and `tv` in v.
pub fn elevate_surface(
    s: &BSplineSurface,
    tu: usize,
    tv: usize,
) -> Result<BSplineSurface, BodyError> {
    let mut s = s.clone();
    if tu > 0 {
        let e = Elevation::new(s.u_knots(), tu)?;
        s = map_surface_lines(&s, true, |c| e.apply(c))?;
    }
    if tv > 0 {
        let e = Elevation::new(s.v_knots(), tv)?;
        s = map_surface_lines(&s, false, |c| e.apply(c))?;
    }
    Ok(s)
}

impl BSplineVolume {
    /// The same volume with its degree in `dir` raised by `times`.
    pub fn elevate(&self, dir: Dir, times: usize) -> Result<BSplineVolume, BodyError> {
        if times == 0 {
            return Ok(self.clone());
        }
        let e = Elevation::new(self.knots(dir), times)?;
        self.map_lines(dir, |c| e.apply(c))
    }
}
