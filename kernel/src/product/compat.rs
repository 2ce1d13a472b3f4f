//! When two B-spline parameter lines can be held equal as a polynomial
//! identity: the same degree and the same knots after mapping each domain
//! affinely onto [0, 1] (and, reversed, t ↦ 1 − t). Then both are
//! combinations of the same basis functions and equal control points mean
//! equal curves at every parameter, not only at samples.

use crate::bspline::KnotVector;

/// Relative tolerance on normalised knots.
const KNOT_TOLERANCE: f64 = 1e-12;

/// `Ok` when `a` and `b` (reversed if `reversed`) span the same spline
/// space up to an affine map of the parameter; otherwise what differs.
pub(crate) fn check_same_space(
    a: &KnotVector,
    b: &KnotVector,
    reversed: bool,
    what: &str,
) -> Result<(), String> {
    if a.degree() != b.degree() {
        return Err(format!(
            "{what}: degree {} against {}",
            a.degree(),
            b.degree()
        ));
    }
    if a.num_ctrl() != b.num_ctrl() {
        return Err(format!(
            "{what}: {} control points against {}",
            a.num_ctrl(),
            b.num_ctrl()
        ));
    }
    let norm = |k: &KnotVector| -> Vec<f64> {
        let (t0, t1) = k.domain();
        k.knots().iter().map(|&t| (t - t0) / (t1 - t0)).collect()
    };
    let na = norm(a);
    let mut nb = norm(b);
    if reversed {
        nb = nb.iter().rev().map(|t| 1.0 - t).collect();
    }
    if let Some(i) = (0..na.len()).find(|&i| (na[i] - nb[i]).abs() > KNOT_TOLERANCE) {
        return Err(format!(
            "{what}: knot {i} at {} against {} (normalised to [0, 1]{})",
            na[i],
            nb[i],
            if reversed { ", reversed" } else { "" }
        ));
    }
    Ok(())
}

/// The parameter of `b` that corresponds to `t` on `a` (same normalised
/// position, or mirrored when `reversed`).
pub fn map_parameter(a: &KnotVector, b: &KnotVector, reversed: bool, t: f64) -> f64 {
    let (a0, a1) = a.domain();
    let (b0, b1) = b.domain();
    let mut s = (t - a0) / (a1 - a0);
    if reversed {
        s = 1.0 - s;
    }
    b0 + s * (b1 - b0)
}
