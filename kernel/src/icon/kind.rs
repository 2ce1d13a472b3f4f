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
        /// `false`: asked outside — a constraint holds everything *outside*
        /// the rectangle where it is while the region deforms; a load acts on
        /// the rest of the surface.
        ///
        /// A region constraint holds its whole set exactly (not at samples):
        /// w = w_held on an open set is equivalent to fixing every control
        /// point whose support meets it, so it pins those points. Outside,
        /// only control points whose support lies inside the rectangle stay
        /// free: a rectangle narrower than degree + 1 knot spans leaves
        /// nothing free.
        inside: bool,
    },
    /// A boundary edge of the surface, held in one icon: its control row
    /// pinned ("simply supported": the edge curve held in position), and
    /// with `clamped` also the next row (the edge and the surface's
    /// cross-boundary derivative held: position and tangent plane). Exact
    /// for clamped knot vectors (every surface of this kernel).
    Edge {
        /// Which edge.
        edge: Edge,
        /// Hold the tangent plane too.
        clamped: bool,
    },
}

/// A boundary edge of the parameter domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Edge {
    /// u = u_min.
    UMin,
    /// u = u_max.
    UMax,
    /// v = v_min.
    VMin,
    /// v = v_max.
    VMax,
}

impl Edge {
    /// The edge's two ends in the unit parameter square.
    pub fn ends(self) -> ((f64, f64), (f64, f64)) {
        match self {
            Edge::UMin => ((0.0, 0.0), (0.0, 1.0)),
            Edge::UMax => ((1.0, 0.0), (1.0, 1.0)),
            Edge::VMin => ((0.0, 0.0), (1.0, 0.0)),
            Edge::VMax => ((0.0, 1.0), (1.0, 1.0)),
        }
    }

    /// The edge as a straight (u, v) curve (a load along it integrates
    /// along this).
    pub fn curve(self) -> BSplineCurve {
        let ((a, b), (c, d)) = self.ends();
        BSplineCurve::new(
            crate::bspline::KnotVector::clamped_uniform(1, 2)
                .expect("two control points of degree 1 make a knot vector"),
            vec![glam::DVec3::new(a, b, 0.0), glam::DVec3::new(c, d, 0.0)],
        )
        .expect("a straight edge is a valid curve")
    }
}

impl Anchor {
    /// The (u,v) of the anchor's handle: the point itself, a curve's middle
    /// control point (`points[len / 2]`, its (u,v) in x and y), a region's
    /// centre. This is the point clients show and drag (the server's
    /// `AnchorDoc::centre`), so an icon's target is the surface point or
    /// derivative *at the handle*: a new icon whose target is the surface's
    /// value there asks for no change.
    ///
    /// An edge's handle is its middle. Edge anchors need the unit parameter
    /// domain [0, 1]² (every surface the kernel builds; [`super::samples`]
    /// refuses others), so the handle needs no surface.
    pub fn handle_uv(&self) -> (f64, f64) {
        let ((a0, a1), (b0, b1)) = ((0.0, 1.0), (0.0, 1.0));
        match self {
            Anchor::Edge { edge, .. } => match edge {
                Edge::UMin => (a0, 0.5 * (b0 + b1)),
                Edge::UMax => (a1, 0.5 * (b0 + b1)),
                Edge::VMin => (0.5 * (a0 + a1), b0),
                Edge::VMax => (0.5 * (a0 + a1), b1),
            },
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
