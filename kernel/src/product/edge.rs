//! The four boundary edges of a tensor-product surface and the control
//! points that make them: the edge row itself and the first row inside,
//! which (knots being clamped) alone fixes the cross-edge derivative.

use crate::bspline::{BSplineSurface, KnotVector};

/// A boundary edge of a surface part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Edge {
    /// u = u_min (runs along v).
    UMin,
    /// u = u_max (runs along v).
    UMax,
    /// v = v_min (runs along u).
    VMin,
    /// v = v_max (runs along u).
    VMax,
}

/// The control points of one edge, in the edge's own parameter order.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EdgeRows {
    /// Indices of the edge's control points (on the boundary).
    pub on: Vec<usize>,
    /// Indices of the first row inside, paired with `on`.
    pub inside: Vec<usize>,
}

impl Edge {
    /// The knot vector the edge runs along.
    pub fn knots(self, s: &BSplineSurface) -> &KnotVector {
        match self {
            Edge::UMin | Edge::UMax => s.v_knots(),
            Edge::VMin | Edge::VMax => s.u_knots(),
        }
    }

    /// The edge's point at its own parameter `t` (a parameter of
    /// [`Self::knots`]).
    pub fn point(self, s: &BSplineSurface, t: f64) -> glam::DVec3 {
        let ((u0, u1), (v0, v1)) = s.domain();
        match self {
            Edge::UMin => s.point(u0, t),
            Edge::UMax => s.point(u1, t),
            Edge::VMin => s.point(t, v0),
            Edge::VMax => s.point(t, v1),
        }
    }

    /// The surface's unit normal at the edge's parameter `t`.
    pub fn normal(self, s: &BSplineSurface, t: f64) -> glam::DVec3 {
        let ((u0, u1), (v0, v1)) = s.domain();
        match self {
            Edge::UMin => s.normal(u0, t),
            Edge::UMax => s.normal(u1, t),
            Edge::VMin => s.normal(t, v0),
            Edge::VMax => s.normal(t, v1),
        }
    }

    pub(crate) fn rows(self, s: &BSplineSurface) -> EdgeRows {
        let (nu, nv) = (s.nu(), s.nv());
        let (on, inside): (Vec<usize>, Vec<usize>) = match self {
            Edge::UMin => (0..nv).map(|j| (s.index(0, j), s.index(1, j))).unzip(),
            Edge::UMax => (0..nv)
                .map(|j| (s.index(nu - 1, j), s.index(nu - 2, j)))
                .unzip(),
            Edge::VMin => (0..nu).map(|i| (s.index(i, 0), s.index(i, 1))).unzip(),
            Edge::VMax => (0..nu)
                .map(|i| (s.index(i, nv - 1), s.index(i, nv - 2)))
                .unzip(),
        };
        EdgeRows { on, inside }
    }
}
