//! The paper's examples as kernel constructors: the cube, the spool made
//! from it (figure 7), the cube-to-spool metamorphosis (figure 10) and a
//! five-body chair (figure 9). The paper gives no numbers; these are ours.
//!
//! * **Cube**: [−1, 1]³, tricubic, 5 × 5 × 7 control points at the Greville
//!   abscissae (so x(u, v, w) is the affine map onto the cube).
//! * **Spool**: the cube's lattice with every layer k (along w, i.e. z)
//!   rounded — a square layer point (x, y) goes to the disc point
//!   r_k (x √(1 − y²/2), y √(1 − x²/2)) — with radii r = (1.5, 1.5, 0.7,
//!   0.7, 0.7, 1.5, 1.5): the two outer layers at each end are the flanges
//!   (their distance is the flange thickness, §3 "top and bottom points also
//!   define the thickness"), the middle ones the waist. Only the six faces
//!   are taken from that lattice; the spool is the Coons body 2 of those
//!   faces, so its interior follows the Boolean sum.
//! * **Chair**: a cantilever strip (foot, leg, seat front, seat rear,
//!   backrest) of five tricubic bodies cut from one B-spline volume, so
//!   they share faces; the knot multiplicities at the cuts make the joints
//!   C1, C0 (a sharp edge at the seat's front: a triple knot), C2 and C1.

use glam::{DVec2, DVec3};

use super::lattice::BodyLattice;
use super::morph::{Morph, Path};
use super::{BSplineVolume, Body2, BodyError, Dir};

/// The flange and waist radii per layer of the spool (7 layers along w).
pub const SPOOL_RADII: [f64; 7] = [1.5, 1.5, 0.7, 0.7, 0.7, 1.5, 1.5];

/// The cube [−1, 1]³ as a tricubic volume with 5 × 5 × 7 control points.
pub fn cube() -> BSplineVolume {
    BSplineVolume::affine(
        DVec3::splat(-1.0),
        [DVec3::X * 2.0, DVec3::Y * 2.0, DVec3::Z * 2.0],
        [3, 3, 3],
        [5, 5, 7],
    )
    .expect("valid sizes")
}

/// The square-to-disc map of the spool (Fong's elliptical grid mapping).
fn to_disc(p: DVec2) -> DVec2 {
    DVec2::new(
        p.x * (1.0 - 0.5 * p.y * p.y).sqrt(),
        p.y * (1.0 - 0.5 * p.x * p.x).sqrt(),
    )
}

/// The spool of figure 7 as a Coons body 2 (see the module doc).
pub fn spool_body() -> Result<Body2, BodyError> {
    let mut lattice = cube();
    let pts: Vec<DVec3> = (0..lattice.points().len())
        .map(|idx| {
            let p = lattice.points()[idx];
            let k = lattice.ijk(idx)[2];
            let d = to_disc(DVec2::new(p.x, p.y)) * SPOOL_RADII[k];
            DVec3::new(d.x, d.y, p.z)
        })
        .collect();
    lattice.set_points(pts)?;
    Body2::from_volume_faces(&lattice)
}

/// The spool of figure 7 as a B-spline volume (the exact conversion of
/// [`spool_body`]).
pub fn spool() -> Result<BSplineVolume, BodyError> {
    spool_body()?.to_volume()
}

/// The metamorphosis of figure 10, cube to spool, with the eased path.
pub fn cube_to_spool() -> Result<Morph, BodyError> {
    Morph::new(&cube(), &spool()?, Path::Eased)
}

/// The chair's strip along u (global parameter 0 … 5): knots of the cubic
/// with, at the four cuts between its bodies, multiplicity 2 (1: the floor
/// bend, C1), 3 (2: the seat's front edge, a sharp edge, C0), 1 (3: the
/// middle of the seat, C2) and 2 (4: seat to back, C1); one more simple
/// knot inside each body.
pub const CHAIR_U_KNOTS: [f64; 21] = [
    0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.5, 3.0, 3.5, 4.0, 4.0, 4.5, 5.0, 5.0,
    5.0, 5.0,
];
/// Where the strip is cut into the chair's five bodies.
pub const CHAIR_CUTS: [f64; 4] = [1.0, 2.0, 3.0, 4.0];
/// The parametric continuity of each joint of [`chair`] (joint k between
/// bodies k and k + 1): p − multiplicity of the knot at the cut.
pub const CHAIR_CONTINUITY: [usize; 4] = [1, 0, 2, 1];
/// The strip's thickness (m).
pub const CHAIR_THICKNESS: f64 = 0.04;
/// The strip's width along y (m).
pub const CHAIR_WIDTH: f64 = 0.5;

/// Body indices of [`chair`], in the order of the strip.
pub mod chair_part {
    /// The foot on the floor, running forward from under the seat.
    pub const FOOT: usize = 0;
    /// The leg rising at the front.
    pub const LEG: usize = 1;
    /// Front half of the seat.
    pub const SEAT_FRONT: usize = 2;
    /// Rear half of the seat.
    pub const SEAT_REAR: usize = 3;
    /// The backrest.
    pub const BACK: usize = 4;
}

/// The chair's centre line in the (x, z) plane at strip parameter ξ ∈ [0, 5]
/// (a polyline through the floor bend at 1, the seat's front edge at 2 and
/// the seat's back at 4, with a dip of the seat and a lumbar bulge), and the
/// left normal of the polyline there (at the sharp corner ξ = 2 the miter,
/// whose projection on either side's normal is 1, so the thickness holds).
fn chair_line(xi: f64) -> (DVec2, DVec2) {
    let corners = [
        DVec2::new(0.85, 0.02),
        DVec2::new(0.10, 0.02),
        DVec2::new(0.10, 0.42),
        DVec2::new(0.85, 0.42),
        DVec2::new(1.00, 1.15),
    ];
    // Parameter at each corner.
    let at = [0.0, 1.0, 2.0, 4.0, 5.0];
    let seg = (0..4).find(|&s| xi <= at[s + 1]).unwrap_or(3);
    let f = (xi - at[seg]) / (at[seg + 1] - at[seg]);
    let mut p = corners[seg] + (corners[seg + 1] - corners[seg]) * f;
    let left = |s: usize| {
        let t = (corners[s + 1] - corners[s]).normalize();
        DVec2::new(-t.y, t.x)
    };
    let mut n = left(seg);
    if xi == 2.0 {
        let (a, b) = (left(1), left(2));
        n = (a + b) / (1.0 + a.dot(b));
    }
    if xi > 2.0 && xi < 4.0 {
        p.y -= 0.03 * (std::f64::consts::PI * (xi - 2.0) / 2.0).sin();
    }
    if xi > 4.0 {
        p.x += 0.03 * (std::f64::consts::PI * (xi - 4.0)).sin();
    }
    (p, n)
}

/// The chair's strip as one tricubic B-spline volume: u along the centre
/// line (knots [`CHAIR_U_KNOTS`]), v across the width, w through the
/// thickness (4 Bézier points each). Its control points are the centre line
/// at the Greville abscissae, offset along the left normal, so the
/// straight parts are reproduced exactly and the triple knot at ξ = 2 puts
/// a control point on the seat's front corner: the volume's edge there is
/// sharp (paper 002 §3, "multiple control points … sharp edges").
pub fn chair_strip() -> Result<BSplineVolume, BodyError> {
    use crate::bspline::{KnotVector, greville};
    let ku = KnotVector::new(3, CHAIR_U_KNOTS.to_vec())?;
    let kv = KnotVector::clamped_uniform(3, 4)?;
    let kw = KnotVector::clamped_uniform(3, 4)?;
    let (gu, gv, gw) = (greville(&ku), greville(&kv), greville(&kw));
    let mut pts = Vec::with_capacity(gu.len() * 16);
    for &xi in &gu {
        let (c, n) = chair_line(xi);
        for &s in &gv {
            for &t in &gw {
                let o = c + n * (CHAIR_THICKNESS * (t - 0.5));
                pts.push(DVec3::new(o.x, CHAIR_WIDTH * s, o.y));
            }
        }
    }
    Ok(BSplineVolume::new(ku, kv, kw, pts)?)
}

/// The five-body ergonomic chair of figure 9 (x: depth, front at 0.1;
/// y: width; z: up): a cantilever strip — foot, leg, seat front, seat rear,
/// backrest — cut from [`chair_strip`] at [`CHAIR_CUTS`] into Coons bodies
/// 2 that keep the strip's global parameters and share their faces. The
/// joints are C1, C0 (the seat's sharp front edge, a triple knot), C2 and
/// C1 ([`CHAIR_CONTINUITY`]).
pub fn chair() -> Result<BodyLattice, BodyError> {
    BodyLattice::split(&chair_strip()?, Dir::U, &CHAIR_CUTS)
}
