//! A binding: a curve part that a surface part follows — paper 003's curve
//! icon "edited by editing the curve". The surface holds, along one of its
//! parameter lines (u = u0 or v = v0), the curve part's shape; editing or
//! dragging the curve part re-solves the surface so it follows.
//!
//! The line and the curve must carry the same spline space (the curve's
//! degree, control-point count and knots equal the surface's in the line's
//! direction, up to reversal and an affine reparameterisation). The
//! surface's line is then itself a B-spline curve on those knots whose
//! control points are Σ_i N_i(u0) P_ij, and the binding holds them equal to
//! the curve's control points: one vector equation per control point, an
//! identity along the whole curve (not a match at samples).
//!
//! Binding solves the surface's group (the surface moves by the least
//! energy that puts the line on the curve) and keeps that shape as its new
//! reference. The binding acts as a curve-constraint icon held by the
//! product; it is not listed among the surface's own icons. It is one-way:
//! the curve is sculpted alone and the surface follows.
//! [`iso_curve`] gives the curve of a line as it is now, for a new curve
//! part that starts exactly on the surface.

use glam::DVec3;

use super::compat::check_same_space;
use super::join::sparse_row;
use super::{PartId, ProductError};
use crate::bspline::{BSplineCurve, BSplineSurface, KnotVector, basis_derivs};
use crate::solve::Equation;

/// A binding's key in its product.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BindingId(pub u64);

/// A parameter line of a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IsoLine {
    /// u = the value, running along v.
    U(f64),
    /// v = the value, running along u.
    V(f64),
}

impl IsoLine {
    /// The knot vector the line runs along.
    pub fn knots(self, s: &BSplineSurface) -> &KnotVector {
        match self {
            IsoLine::U(_) => s.v_knots(),
            IsoLine::V(_) => s.u_knots(),
        }
    }

    /// The surface point on the line at its own parameter `t`.
    pub fn point(self, s: &BSplineSurface, t: f64) -> DVec3 {
        match self {
            IsoLine::U(u) => s.point(u, t),
            IsoLine::V(v) => s.point(t, v),
        }
    }

    fn check(self, s: &BSplineSurface) -> Result<(), String> {
        let ((u0, u1), (v0, v1)) = s.domain();
        let (x, (lo, hi), name) = match self {
            IsoLine::U(u) => (u, (u0, u1), "u"),
            IsoLine::V(v) => (v, (v0, v1), "v"),
        };
        if !(x.is_finite() && x >= lo && x <= hi) {
            return Err(format!("line {name} = {x} is outside [{lo}, {hi}]"));
        }
        Ok(())
    }

    /// For each control point of the line's curve, the surface's control
    /// points and weights it combines.
    fn combinations(self, s: &BSplineSurface) -> Vec<Vec<(usize, f64)>> {
        let (kv, x, n) = match self {
            IsoLine::U(u) => (s.u_knots(), u, s.nv()),
            IsoLine::V(v) => (s.v_knots(), v, s.nu()),
        };
        let b = basis_derivs(kv, x, 0);
        (0..n)
            .map(|j| {
                (0..=kv.degree())
                    .map(|a| {
                        let i = b.first + a;
                        let idx = match self {
                            IsoLine::U(_) => s.index(i, j),
                            IsoLine::V(_) => s.index(j, i),
                        };
                        (idx, b.get(0, a))
                    })
                    .collect()
            })
            .collect()
    }
}

/// The surface's parameter line `line` as it is now: a B-spline curve on
/// the line's knots (exact, not fitted). A line outside the surface's
/// domain is [`ProductError::Incompatible`].
pub fn iso_curve(s: &BSplineSurface, line: IsoLine) -> Result<BSplineCurve, ProductError> {
    line.check(s).map_err(ProductError::Incompatible)?;
    let p = s.points();
    let points: Vec<DVec3> = line
        .combinations(s)
        .iter()
        .map(|c| c.iter().map(|&(i, w)| p[i] * w).sum())
        .collect();
    BSplineCurve::new(line.knots(s).clone(), points)
        .map_err(|e| ProductError::Incompatible(e.to_string()))
}

/// What to bind: curve part `curve` held along `line` of surface part `surface`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BindingSpec {
    /// The curve part (it drives).
    pub curve: PartId,
    /// The surface part (it follows).
    pub surface: PartId,
    /// The surface's parameter line that holds the curve.
    pub line: IsoLine,
    /// Whether the curve runs against the line's parameter.
    pub reversed: bool,
}

/// A binding as the product holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Binding {
    /// What was bound.
    pub spec: BindingSpec,
}

impl Binding {
    /// Checks that the curve fits the line.
    pub(crate) fn new(
        spec: BindingSpec,
        curve: &BSplineCurve,
        surface: &BSplineSurface,
    ) -> Result<Self, String> {
        spec.line.check(surface)?;
        check_same_space(
            spec.line.knots(surface),
            curve.knots(),
            spec.reversed,
            &format!(
                "line {:?} of part {} and curve part {}",
                spec.line, spec.surface.0, spec.curve.0
            ),
        )?;
        Ok(Self { spec })
    }

    /// The binding's equations over the group's unknowns (the surface's
    /// control points starting at `offset`), with the curve's current
    /// control points as targets.
    pub(crate) fn equations(
        &self,
        curve: &BSplineCurve,
        surface: &BSplineSurface,
        offset: usize,
    ) -> Vec<Equation> {
        let cp = curve.points();
        let n = cp.len();
        self.spec
            .line
            .combinations(surface)
            .iter()
            .enumerate()
            .filter_map(|(j, c)| {
                let terms: Vec<(usize, f64)> = c.iter().map(|&(i, w)| (i + offset, w)).collect();
                let target = cp[if self.spec.reversed { n - 1 - j } else { j }];
                sparse_row(&terms).map(|row| Equation::Vector { row, target })
            })
            .collect()
    }
}
