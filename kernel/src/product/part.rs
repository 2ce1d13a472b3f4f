//! A part of a product: one shape of one kind, keyed by a [`PartId`].
//!
//! Each kind is one variant of [`Part`] holding that kind's own sculptable
//! value (its shape, icons, material and solver). A new shape model (an
//! implicit solid, a B-spline solid, an n-sided patch network) is one new
//! variant here and one new arm in the few `match`es of this module.

use glam::DVec3;

use crate::curve_design::{CurveDesign, CurveDesignSnapshot};
use crate::design::{Design, DesignError, DesignSnapshot};

/// A part's key in its product. The product never reuses an id it handed
/// out; ids given to [`super::Product::insert_part`] are the caller's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PartId(pub u64);

/// What kind of shape a part is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PartKind {
    /// A deformable B-spline surface (paper 003).
    Surface,
    /// A deformable B-spline curve (paper 003, eq. 1).
    Curve,
}

/// One part: a sculptable shape of one kind.
// Parts live in the product's map, one each: the variants' size difference
// costs nothing, and a box would add an indirection to every drag frame.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Part {
    /// A surface part.
    Surface(Design),
    /// A curve part.
    Curve(CurveDesign),
}

/// A part as a value (undo, redo, store): its kind's snapshot.
#[derive(Clone, Debug, PartialEq)]
pub enum PartSnapshot {
    /// A surface part's value.
    Surface(DesignSnapshot),
    /// A curve part's value.
    Curve(CurveDesignSnapshot),
}

impl PartSnapshot {
    /// Its kind.
    pub fn kind(&self) -> PartKind {
        match self {
            PartSnapshot::Surface(_) => PartKind::Surface,
            PartSnapshot::Curve(_) => PartKind::Curve,
        }
    }
}

impl Part {
    /// The part as a value.
    pub fn snapshot(&self) -> PartSnapshot {
        match self {
            Part::Surface(d) => PartSnapshot::Surface(d.snapshot()),
            Part::Curve(c) => PartSnapshot::Curve(c.snapshot()),
        }
    }

    /// A part from its value.
    pub fn from_snapshot(s: &PartSnapshot) -> Result<Self, DesignError> {
        Ok(match s {
            PartSnapshot::Surface(d) => Part::Surface(Design::from_snapshot(d)?),
            PartSnapshot::Curve(c) => Part::Curve(CurveDesign::from_snapshot(c)?),
        })
    }

    /// Replaces the part's value by `s` (of the same kind), keeping its
    /// factorisation when knots and material are unchanged. Nothing is
    /// solved. On error nothing changes.
    pub(crate) fn restore(&mut self, s: &PartSnapshot) -> Result<(), DesignError> {
        match (self, s) {
            (Part::Surface(d), PartSnapshot::Surface(v)) => d.restore(v),
            (Part::Curve(c), PartSnapshot::Curve(v)) => c.restore(v),
            _ => Err(DesignError::Unsupported(
                "a snapshot of another kind of part".into(),
            )),
        }
    }

    /// Its kind.
    pub fn kind(&self) -> PartKind {
        match self {
            Part::Surface(_) => PartKind::Surface,
            Part::Curve(_) => PartKind::Curve,
        }
    }

    /// The surface design, if it is a surface part.
    pub fn as_surface(&self) -> Option<&Design> {
        match self {
            Part::Surface(d) => Some(d),
            _ => None,
        }
    }

    /// The curve design, if it is a curve part.
    pub fn as_curve(&self) -> Option<&CurveDesign> {
        match self {
            Part::Curve(c) => Some(c),
            _ => None,
        }
    }

    pub(crate) fn as_surface_mut(&mut self) -> Option<&mut Design> {
        match self {
            Part::Surface(d) => Some(d),
            _ => None,
        }
    }

    pub(crate) fn as_curve_mut(&mut self) -> Option<&mut CurveDesign> {
        match self {
            Part::Curve(c) => Some(c),
            _ => None,
        }
    }

    /// Its current control points (row-major for a surface, as
    /// [`crate::bspline::BSplineSurface::points`]).
    pub fn control_points(&self) -> &[DVec3] {
        match self {
            Part::Surface(d) => d.surface().points(),
            Part::Curve(c) => c.curve().points(),
        }
    }
}
