//! Common spline spaces: bringing several curves or surfaces onto one degree
//! and one knot vector per parameter direction (normalise the domain to
//! [0, 1], elevate to the highest degree, merge the knots, insert the
//! missing ones). Every step is an exact change of basis, so the shapes
//! are unchanged; what it buys is control points that correspond one to one
//! — what a Boolean sum on control points and a grid-point correspondence
//! need.

use super::BodyError;
use super::elevate::{elevate_curve, elevate_surface};
use super::refine::{merge, normalized, refine_curve, refine_surface};
use crate::bspline::{BSplineCurve, BSplineSurface, KnotVector};

/// The common space of knot vectors `kvs` (each normalised to [0, 1]):
/// the highest degree and the merged knots after elevation.
pub fn common_knots(kvs: &[&KnotVector]) -> Result<KnotVector, BodyError> {
    let degree = kvs
        .iter()
        .map(|k| k.degree())
        .max()
        .ok_or_else(|| BodyError::Mismatch("no knot vectors".into()))?;
    let mut acc: Option<KnotVector> = None;
    for kv in kvs {
        let e = super::elevate::elevated_knots(&normalized(kv), degree - kv.degree());
        acc = Some(match acc {
            None => e,
            Some(a) => merge(&a, &e)?,
        });
    }
    Ok(acc.expect("at least one"))
}

/// A curve with its knots normalised to [0, 1] (same control points).
pub fn normalized_curve(c: &BSplineCurve) -> BSplineCurve {
    BSplineCurve::new(normalized(c.knots()), c.points().to_vec()).expect("same sizes")
}

/// A surface with its knots normalised to [0, 1]² (same control points).
pub fn normalized_surface(s: &BSplineSurface) -> BSplineSurface {
    BSplineSurface::new(
        normalized(s.u_knots()),
        normalized(s.v_knots()),
        s.points().to_vec(),
    )
    .expect("same sizes")
}

/// `c` (normalised) expressed exactly on `target`, a space containing it.
pub fn curve_to(c: &BSplineCurve, target: &KnotVector) -> Result<BSplineCurve, BodyError> {
    let c = normalized_curve(c);
    let up = target
        .degree()
        .checked_sub(c.degree())
        .ok_or_else(|| BodyError::Mismatch("target degree below the curve's".into()))?;
    refine_curve(&elevate_curve(&c, up)?, target)
}

/// `s` (normalised) expressed exactly on `tu` × `tv`, spaces containing it.
pub fn surface_to(
    s: &BSplineSurface,
    tu: &KnotVector,
    tv: &KnotVector,
) -> Result<BSplineSurface, BodyError> {
    let s = normalized_surface(s);
    let du = tu.degree().checked_sub(s.u_knots().degree());
    let dv = tv.degree().checked_sub(s.v_knots().degree());
    let (Some(du), Some(dv)) = (du, dv) else {
        return Err(BodyError::Mismatch(
            "target degree below the surface's".into(),
        ));
    };
    refine_surface(&elevate_surface(&s, du, dv)?, tu, tv)
}
