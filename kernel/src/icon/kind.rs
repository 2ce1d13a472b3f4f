//! What an icon is: where it sits (its [`Anchor`]) and what it does (its [`Role`]).

use crate::bspline::BSplineCurve;

/// Where an icon sits on the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Anchor {
    /// A point at (u, v).
    Point {
        /// Parameter u.
        u: f64,
        /// Parameter v.
        v: f64,
    },
    /// A curve in the (u,v) domain: a B-spline whose control points are
    /// (u, v, 0).
    Curve(BSplineCurve),
    /// A parameter rectangle picked by two corners.
    Region {
        /// One corner.
        u0: f64,
        /// One corner.
        v0: f64,
        /// The opposite corner.
        u1: f64,
        /// The opposite corner.
        v1: f64,
        /// `true`: the deformation is asked inside — the region's patch is
        /// moved (constraint) or pushed (load) and the outside follows.
        /// `false`: asked outside — a constraint holds the region as it is
        /// while the rest deforms; a load acts on the rest of the surface.
        inside: bool,
    },
}

/// Which derivative a derivative constraint fixes (paper 003's labels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Derivative {
    /// w_u.
    R,
    /// w_v.
    V,
    /// w_uu.
    R2,
    /// w_vv.
    V2,
    /// w_uv.
    RV,
}

impl Derivative {
    /// The orders (du, dv) of the derivative.
    pub fn orders(self) -> (usize, usize) {
        match self {
            Derivative::R => (1, 0),
            Derivative::V => (0, 1),
            Derivative::R2 => (2, 0),
            Derivative::V2 => (0, 2),
            Derivative::RV => (1, 1),
        }
    }
}

/// What an icon does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// A load: pulled by a spring, it pushes the surface.
    Load,
    /// Position constraint: the surface passes through the target.
    Position,
    /// Derivative constraint: a derivative of the surface equals the target vector.
    Derivative(Derivative),
    /// Normal constraint: N·w_u = N·w_v = 0 with N the target direction.
    Normal,
}

impl Role {
    /// Whether this is a constraint (anything but a load).
    pub fn is_constraint(self) -> bool {
        self != Role::Load
    }
}
