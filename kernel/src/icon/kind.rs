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

impl Anchor {
    /// The (u,v) of the anchor's handle: the point itself, a curve's middle
    /// control point (`points[len / 2]`, its (u,v) in x and y), a region's
    /// centre. This is the point clients show and drag (the server's
    /// `AnchorDoc::centre`), so an icon's target is the surface point or
    /// derivative *at the handle*: a new icon whose target is the surface's
    /// value there asks for no change.
    pub fn handle_uv(&self) -> (f64, f64) {
        match self {
            Anchor::Point { u, v } => (*u, *v),
            Anchor::Curve(c) => {
                // On the curve (its mid-parameter point), so a curve constraint
                // holds its own handle and a rebuild measures no offset.
                let (a, b) = c.domain();
                let p = c.point(0.5 * (a + b));
                (p.x, p.y)
            }
            Anchor::Region { u0, v0, u1, v1, .. } => (0.5 * (u0 + u1), 0.5 * (v0 + v1)),
        }
    }
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
