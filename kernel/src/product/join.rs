//! A join: two surface parts held together along an edge, by linear
//! constraints between their control points, solved jointly.
//!
//! The edges must carry the same spline space (same degree, number of
//! control points and knots up to reversal and an affine
//! reparameterisation, see `compat.rs`), so each condition below is a
//! polynomial identity along the whole seam, not a match at samples.
//! Pair the edge control points E^a_i, E^b_i (b's reversed if asked) and
//! the first rows inside, I^a_i and I^b_i:
//!
//! * **G0** (position): E^a_i = E^b_i. The two edge curves are the same
//!   B-spline, so the seam is closed everywhere.
//! * **G1** (tangent plane): G0 and, for every i,
//!   E_i − I^a_i = ρ (I^b_i − E_i), i.e. I^a_i, E_i, I^b_i collinear with a
//!   fixed ratio ρ > 0. Clamped knots make the cross-edge derivative of each
//!   side a fixed positive multiple of Σ (E_i − I_i) M_i(t), so the two
//!   cross derivatives are positive multiples of each other at every point
//!   of the seam: with the common edge tangent, the tangent planes agree
//!   identically (and the normals, when the parts are oriented alike, e.g.
//!   a's `UMax` to b's `UMin`).
//!
//! Limits of the G1 choice: it is *constant-ratio* G1 (C1 after an affine
//! reparameterisation), a sufficient condition — G1 with a ratio varying
//! along the seam (or a twist) is not reachable; the ratio is fixed when
//! the join is made (measured from the current shapes unless given); where
//! a cross-edge row is degenerate (I_i = E_i) the surface has no tangent
//! plane to match and the rows hold trivially there.
//!
//! Joining solves the group: the two parts move by the least energy (from
//! their reference shapes, under their icons) that makes the edges meet,
//! and that shape is kept as their new reference (as a released load's is).

use glam::DVec3;

use super::compat::check_same_space;
use super::{Edge, PartId};
use crate::bspline::BSplineSurface;
use crate::solve::{Equation, ScalarRow};

/// A join's key in its product.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct JoinId(pub u64);

/// How smoothly two joined surfaces meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Continuity {
    /// Position: the edges coincide.
    G0,
    /// Tangent plane: the edges coincide and the surfaces share a tangent
    /// plane all along them (constant-ratio G1, see the module doc).
    G1,
}

/// What to join: an edge of part `a` to an edge of part `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JoinSpec {
    /// The first part.
    pub a: PartId,
    /// Its edge.
    pub edge_a: Edge,
    /// The second part (may be `a` itself, with another edge).
    pub b: PartId,
    /// Its edge.
    pub edge_b: Edge,
    /// Whether `b`'s edge runs the other way (its first control point
    /// meets `a`'s last).
    pub reversed: bool,
    /// G0 or G1.
    pub continuity: Continuity,
    /// G1's ratio ρ = |E − I^a| / |I^b − E|; `None` measures it from the
    /// current shapes when the join is made (ignored for G0). Give the
    /// stored [`Join::ratio`] to rebuild a product exactly.
    pub ratio: Option<f64>,
}

/// A join as the product holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Join {
    /// What was joined, with `ratio` the one in force (`Some` for G1,
    /// `None` for G0).
    pub spec: JoinSpec,
    /// The G1 ratio in force (1 for G0).
    pub ratio: f64,
}

impl Join {
    /// Checks that the edges can be joined and fixes the ratio.
    pub(crate) fn new(
        spec: JoinSpec,
        a: &BSplineSurface,
        b: &BSplineSurface,
    ) -> Result<Self, String> {
        if spec.a == spec.b && spec.edge_a == spec.edge_b {
            return Err("an edge cannot be joined to itself".into());
        }
        check_same_space(
            spec.edge_a.knots(a),
            spec.edge_b.knots(b),
            spec.reversed,
            &format!(
                "edge {:?} of part {} and edge {:?} of part {}",
                spec.edge_a, spec.a.0, spec.edge_b, spec.b.0
            ),
        )?;
        let ratio = match (spec.continuity, spec.ratio) {
            (Continuity::G0, _) => 1.0,
            (Continuity::G1, Some(r)) => r,
            (Continuity::G1, None) => {
                let (ra, rb) = (spec.edge_a.rows(a), spec.edge_b.rows(b));
                let pa = a.points();
                let pb = b.points();
                let side_a: f64 = ra
                    .on
                    .iter()
                    .zip(&ra.inside)
                    .map(|(&e, &i)| (pa[e] - pa[i]).length())
                    .sum();
                let side_b: f64 = rb
                    .on
                    .iter()
                    .zip(&rb.inside)
                    .map(|(&e, &i)| (pb[i] - pb[e]).length())
                    .sum();
                side_a / side_b
            }
        };
        if !(ratio.is_finite() && ratio > 0.0) {
            return Err(format!(
                "G1 ratio {ratio} (a degenerate cross-edge row of control points)"
            ));
        }
        let ratio_in_spec = (spec.continuity == Continuity::G1).then_some(ratio);
        Ok(Self {
            spec: JoinSpec {
                ratio: ratio_in_spec,
                ..spec
            },
            ratio,
        })
    }

    /// The join's scalar equations over the group's unknowns, part `a`'s
    /// control points starting at `off_a` and `b`'s at `off_b`.
    pub(crate) fn equations(
        &self,
        a: &BSplineSurface,
        off_a: usize,
        b: &BSplineSurface,
        off_b: usize,
    ) -> Vec<Equation> {
        let ra = self.spec.edge_a.rows(a);
        let rb = self.spec.edge_b.rows(b);
        let n = ra.on.len();
        let pair = |i: usize| if self.spec.reversed { n - 1 - i } else { i };
        let mut eqs = Vec::new();
        for i in 0..n {
            let (ea, eb) = (ra.on[i] + off_a, rb.on[pair(i)] + off_b);
            if let Some(row) = sparse_row(&[(ea, 1.0), (eb, -1.0)]) {
                eqs.push(Equation::Vector {
                    row,
                    target: DVec3::ZERO,
                });
            }
        }
        if self.spec.continuity == Continuity::G1 {
            let r = self.ratio;
            for i in 0..n {
                let (ea, ia) = (ra.on[i] + off_a, ra.inside[i] + off_a);
                let (eb, ib) = (rb.on[pair(i)] + off_b, rb.inside[pair(i)] + off_b);
                // E − I^a = ρ (I^b − E), with E = E^a on the left and E^b on
                // the right (equal by G0): E^a + ρ E^b − I^a − ρ I^b = 0.
                if let Some(row) = sparse_row(&[(ea, 1.0), (eb, r), (ia, -1.0), (ib, -r)]) {
                    eqs.push(Equation::Vector {
                        row,
                        target: DVec3::ZERO,
                    });
                }
            }
        }
        eqs
    }
}

/// A row from (index, weight) pairs, repeated indices summed, zeros
/// dropped; `None` when nothing is left (a trivially true equation, e.g. a
/// part's corner joined to itself).
pub(crate) fn sparse_row(terms: &[(usize, f64)]) -> Option<ScalarRow> {
    let mut sorted = terms.to_vec();
    sorted.sort_by_key(|t| t.0);
    let mut row = ScalarRow::default();
    for (i, w) in sorted {
        if row.indices.last() == Some(&i) {
            if let Some(last) = row.weights.last_mut() {
                *last += w;
            }
        } else {
            row.indices.push(i);
            row.weights.push(w);
        }
    }
    let keep: Vec<bool> = row.weights.iter().map(|w| *w != 0.0).collect();
    let mut k = keep.iter();
    row.indices.retain(|_| *k.next().unwrap_or(&false));
    row.weights.retain(|w| *w != 0.0);
    (!row.indices.is_empty()).then_some(row)
}
