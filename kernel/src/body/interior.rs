//! Interior modelling (paper 002 §2.3–2.4, figures 4 and 6): moving lattice
//! points so that the outer shape stays while the interior distribution
//! changes, the measure of that distribution, and checked edits.
//!
//! * **Interior distribution** ("density", which the paper never defines):
//!   det J(u, v, w), the local volume of material per unit parameter
//!   volume. A uniform lattice has it constant; pulling edge points
//!   together concentrates parameter lines (the "density") there.
//!   [`det_grid`] samples it on a grid, [`det_on_plane`] on an
//!   isoparametric cutting plane (for display as colour), [`volume`]
//!   integrates it (the solid's volume, exact by Gauss quadrature).
//! * **Shape-preserving moves** ([`move_keeping_shape`]): an inner lattice
//!   point moves freely; a point on the boundary may move only inside its
//!   boundary: within a flat face (all its control points on one plane), or
//!   along a straight edge where two flat faces meet; corners never move.
//!   Then every boundary face stays in its plane with the same boundary
//!   curve, and as the edit is refused unless det J > 0 everywhere, the face
//!   is not folded, so its image — and the outer shape — is unchanged. A
//!   move on a curved face would change the shape and is refused.
//! * **Checked edits** ([`edit`]): any set of moves, applied only if the
//!   result passes [`check_injective`]; a fold is refused with the (u, v, w)
//!   where det J ≤ 0, and nothing changes.

use glam::DVec3;

use super::injective::{InjectivityReport, check_injective};
use super::{BSplineVolume, BodyError, Dir, Face, VolumeScratch};
use crate::quadrature::GaussLegendre;

/// det J at an `n × n × n` grid of parameters (corners included), k fastest.
pub fn det_grid(vol: &BSplineVolume, n: usize) -> Vec<f64> {
    let n = n.max(2);
    let dom = vol.domain();
    let mut s = VolumeScratch::default();
    let mut out = Vec::with_capacity(n * n * n);
    let t = |d: usize, a: usize| dom[d].0 + (dom[d].1 - dom[d].0) * a as f64 / (n - 1) as f64;
    for a in 0..n {
        for b in 0..n {
            for c in 0..n {
                out.push(vol.eval(&mut s, [t(0, a), t(1, b), t(2, c)], 1).det());
            }
        }
    }
    out
}

/// Points and det J on the isoparametric cutting plane `dir` = `t`, on an
/// `n × n` grid of the two other parameters (in increasing direction order,
/// second fastest): what a client colours to show the interior.
pub fn det_on_plane(vol: &BSplineVolume, dir: Dir, t: f64, n: usize) -> Vec<(DVec3, f64)> {
    let n = n.max(2);
    let dom = vol.domain();
    let (d1, d2) = dir.others();
    let mut s = VolumeScratch::default();
    let mut out = Vec::with_capacity(n * n);
    for a in 0..n {
        for b in 0..n {
            let mut p = [0.0; 3];
            p[dir.index()] = t;
            let (x1, y1) = dom[d1.index()];
            let (x2, y2) = dom[d2.index()];
            p[d1.index()] = x1 + (y1 - x1) * a as f64 / (n - 1) as f64;
            p[d2.index()] = x2 + (y2 - x2) * b as f64 / (n - 1) as f64;
            let d = vol.eval(&mut s, p, 1);
            out.push((d.p, d.det()));
        }
    }
    out
}

/// ∫ det J du dv dw over the domain: the solid's volume when det J > 0.
/// Gauss–Legendre per knot-span cell with enough points to be exact for
/// det J's degree (3p − 1 per direction).
pub fn volume(vol: &BSplineVolume) -> f64 {
    let deg = vol.degrees();
    let rules = deg.map(|p| GaussLegendre::exact_for(3 * p - 1));
    let spans = Dir::ALL.map(|d| vol.knots(d).spans());
    let mut s = VolumeScratch::default();
    let mut total = 0.0;
    for &(_, a0, a1) in &spans[0] {
        for &(_, b0, b1) in &spans[1] {
            for &(_, c0, c1) in &spans[2] {
                for (x, wx) in rules[0].on(a0, a1) {
                    for (y, wy) in rules[1].on(b0, b1) {
                        for (z, wz) in rules[2].on(c0, c1) {
                            total += wx * wy * wz * vol.eval(&mut s, [x, y, z], 1).det();
                        }
                    }
                }
            }
        }
    }
    total
}

/// Applies `moves` (storage index, new position) to a copy of `vol` and
/// returns it if it is injective (det J > 0 proved); otherwise
/// [`BodyError::Folds`] with where, and `vol` is untouched.
pub fn edit(
    vol: &BSplineVolume,
    moves: &[(usize, DVec3)],
) -> Result<(BSplineVolume, InjectivityReport), BodyError> {
    let mut out = vol.clone();
    for &(i, p) in moves {
        out.set_point(i, p)?;
    }
    let report = check_injective(&out)?;
    Ok((out, report))
}

/// The plane (point, unit normal) of face `face` if all its control points
/// lie on one plane within `tol`.
fn face_plane(vol: &BSplineVolume, face: Face, tol: f64) -> Option<(DVec3, DVec3)> {
    let idx = vol.face_indices(face);
    let pts: Vec<DVec3> = idx.iter().map(|&i| vol.points()[i]).collect();
    let o = pts[0];
    // The normal from the widest triangle through o.
    let far = pts
        .iter()
        .copied()
        .max_by(|a, b| (*a - o).length().total_cmp(&(*b - o).length()))?;
    let e1 = far - o;
    let n = pts
        .iter()
        .map(|p| e1.cross(*p - o))
        .max_by(|a, b| a.length().total_cmp(&b.length()))?;
    if n.length() == 0.0 {
        return None;
    }
    let n = n.normalize();
    pts.iter()
        .all(|p| (*p - o).dot(n).abs() <= tol)
        .then_some((o, n))
}

/// Moves lattice point `index` as close to `target` as it can go without
/// changing the outer shape (see the module doc): inner points go to
/// `target`; boundary points are projected onto their flat face or straight
/// edge. Refused if the point is a corner, if a face it lies on is not flat
/// (within 1e-9 of the lattice size), or if the result folds. Returns the new
/// volume and where the point went.
pub fn move_keeping_shape(
    vol: &BSplineVolume,
    index: usize,
    target: DVec3,
) -> Result<(BSplineVolume, DVec3), BodyError> {
    if index >= vol.points().len() {
        return Err(BodyError::BadIndex {
            index,
            count: vol.points().len(),
        });
    }
    if !target.is_finite() {
        return Err(BodyError::NonFinite("target".into()));
    }
    let c = vol.counts();
    let ijk = vol.ijk(index);
    let faces: Vec<Face> = Face::ALL
        .into_iter()
        .filter(|f| {
            let d = f.dir.index();
            ijk[d] == if f.end { c[d] - 1 } else { 0 }
        })
        .collect();
    let (lo, hi) = vol
        .points()
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    let tol = 1e-9 * (hi - lo).length();
    let p0 = vol.points()[index];
    let new = match faces.len() {
        0 => target,
        1 => {
            let (_, n) = face_plane(vol, faces[0], tol).ok_or_else(|| {
                BodyError::Mismatch(
                    "the point's face is curved: moving it changes the shape".into(),
                )
            })?;
            target - n * (target - p0).dot(n)
        }
        2 => {
            let (_, n1) = face_plane(vol, faces[0], tol).ok_or_else(|| {
                BodyError::Mismatch(
                    "the point's face is curved: moving it changes the shape".into(),
                )
            })?;
            let (_, n2) = face_plane(vol, faces[1], tol).ok_or_else(|| {
                BodyError::Mismatch(
                    "the point's face is curved: moving it changes the shape".into(),
                )
            })?;
            let line = n1.cross(n2);
            if line.length() < 1e-12 {
                return Err(BodyError::Mismatch(
                    "the faces at this edge are parallel".into(),
                ));
            }
            let l = line.normalize();
            p0 + l * (target - p0).dot(l)
        }
        _ => {
            return Err(BodyError::Mismatch(
                "a corner cannot move without changing the shape".into(),
            ));
        }
    };
    let (out, _) = edit(vol, &[(index, new)])?;
    Ok((out, new))
}
