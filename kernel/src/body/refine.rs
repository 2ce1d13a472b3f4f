//! Knot insertion, knot-vector merging and splitting for curves, surfaces
//! and volumes, line by line: every line of control points along one
//! direction is a [`BSplineCurve`] refined by the `bspline` layer's Boehm
//! insertion ([`BSplineCurve::insert_knot`]), so the shape never changes.

use glam::DVec3;

use super::{BSplineVolume, BodyError, Dir};
use crate::bspline::{BSplineCurve, BSplineSurface, GeometryError, KnotVector};

/// The distinct knots of `kv` with their multiplicities, in order.
pub fn distinct_knots(kv: &KnotVector) -> Vec<(f64, usize)> {
    let mut out: Vec<(f64, usize)> = Vec::new();
    for &k in kv.knots() {
        match out.last_mut() {
            Some((v, m)) if *v == k => *m += 1,
            _ => out.push((k, 1)),
        }
    }
    out
}

/// `kv` with its knots mapped affinely onto [0, 1] (same degree and
/// multiplicities). The end knots are set to exactly 0 and 1.
pub fn normalized(kv: &KnotVector) -> KnotVector {
    let (a, b) = kv.domain();
    let knots = kv
        .knots()
        .iter()
        .map(|&k| {
            if k == a {
                0.0
            } else if k == b {
                1.0
            } else {
                (k - a) / (b - a)
            }
        })
        .collect();
    KnotVector::new(kv.degree(), knots).expect("an affine image of a valid knot vector")
}

/// The smallest knot vector of degree `degree` containing both `a` and `b`
/// (same domain): every distinct knot with the larger multiplicity.
pub fn merge(a: &KnotVector, b: &KnotVector) -> Result<KnotVector, BodyError> {
    if a.degree() != b.degree() || a.domain() != b.domain() {
        return Err(BodyError::Mismatch(format!(
            "knot vectors of degree {} on {:?} and degree {} on {:?}",
            a.degree(),
            a.domain(),
            b.degree(),
            b.domain()
        )));
    }
    let (da, db) = (distinct_knots(a), distinct_knots(b));
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < da.len() || j < db.len() {
        let (v, m) = if j >= db.len() || (i < da.len() && da[i].0 < db[j].0) {
            i += 1;
            da[i - 1]
        } else if i >= da.len() || db[j].0 < da[i].0 {
            j += 1;
            db[j - 1]
        } else {
            i += 1;
            j += 1;
            (da[i - 1].0, da[i - 1].1.max(db[j - 1].1))
        };
        out.extend(std::iter::repeat_n(v, m));
    }
    Ok(KnotVector::new(a.degree(), out)?)
}

/// The knots of `target` missing from `kv` (with multiplicity), in order;
/// an error if `kv` has a knot `target` lacks or the degrees differ.
fn missing(kv: &KnotVector, target: &KnotVector) -> Result<Vec<f64>, BodyError> {
    if kv.degree() != target.degree() || kv.domain() != target.domain() {
        return Err(BodyError::Mismatch(
            "refinement target has another degree or domain".into(),
        ));
    }
    let have = distinct_knots(kv);
    let want = distinct_knots(target);
    let mut out = Vec::new();
    for &(v, m) in &want {
        let h = have.iter().find(|x| x.0 == v).map_or(0, |x| x.1);
        if h > m {
            return Err(BodyError::Mismatch(format!(
                "knot {v} has multiplicity {h}, the target only {m}"
            )));
        }
        out.extend(std::iter::repeat_n(v, m - h));
    }
    if have.iter().any(|&(v, _)| !want.iter().any(|x| x.0 == v)) {
        return Err(BodyError::Mismatch(
            "the target lacks a knot of the source".into(),
        ));
    }
    Ok(out)
}

/// The same curve expressed on `target`, a refinement of its knot vector
/// (same degree and domain, every knot of the curve present at least as
/// often).
pub fn refine_curve(c: &BSplineCurve, target: &KnotVector) -> Result<BSplineCurve, BodyError> {
    let mut out = c.clone();
    for t in missing(c.knots(), target)? {
        out = out.insert_knot(t)?;
    }
    Ok(out)
}

/// Rebuilds a surface after replacing every line along u (`along_u`) or v
/// by `f` of it; all results must share one knot vector.
pub fn map_surface_lines<F>(
    s: &BSplineSurface,
    along_u: bool,
    mut f: F,
) -> Result<BSplineSurface, BodyError>
where
    F: FnMut(&BSplineCurve) -> Result<BSplineCurve, BodyError>,
{
    let (nu, nv) = (s.nu(), s.nv());
    let (n_lines, kv) = if along_u {
        (nv, s.u_knots())
    } else {
        (nu, s.v_knots())
    };
    let mut lines = Vec::with_capacity(n_lines);
    for o in 0..n_lines {
        let pts: Vec<DVec3> = if along_u {
            (0..nu).map(|i| s.points()[s.index(i, o)]).collect()
        } else {
            (0..nv).map(|j| s.points()[s.index(o, j)]).collect()
        };
        lines.push(f(&BSplineCurve::new(kv.clone(), pts)?)?);
    }
    let new_kv = lines[0].knots().clone();
    if lines.iter().any(|l| l.knots() != &new_kv) {
        return Err(BodyError::Mismatch("lines got different knots".into()));
    }
    let n = new_kv.num_ctrl();
    if along_u {
        let mut pts = vec![DVec3::ZERO; n * nv];
        for (j, l) in lines.iter().enumerate() {
            for (i, &p) in l.points().iter().enumerate() {
                pts[i * nv + j] = p;
            }
        }
        Ok(BSplineSurface::new(new_kv, s.v_knots().clone(), pts)?)
    } else {
        let pts = lines.iter().flat_map(|l| l.points().to_vec()).collect();
        Ok(BSplineSurface::new(s.u_knots().clone(), new_kv, pts)?)
    }
}

/// The same surface expressed on the refined knot vectors `tu`, `tv`.
pub fn refine_surface(
    s: &BSplineSurface,
    tu: &KnotVector,
    tv: &KnotVector,
) -> Result<BSplineSurface, BodyError> {
    let s = map_surface_lines(s, true, |c| refine_curve(c, tu))?;
    map_surface_lines(&s, false, |c| refine_curve(c, tv))
}

impl BSplineVolume {
    /// The same volume with knot `t` inserted once in direction `dir`
    /// (strictly inside the domain, multiplicity staying ≤ degree).
    pub fn insert_knot(&self, dir: Dir, t: f64) -> Result<BSplineVolume, BodyError> {
        self.map_lines(dir, |c| Ok(c.insert_knot(t)?))
    }

    /// The same volume expressed on `target` in direction `dir`, a
    /// refinement of its knot vector there.
    pub fn refine(&self, dir: Dir, target: &KnotVector) -> Result<BSplineVolume, BodyError> {
        if missing(self.knots(dir), target)?.is_empty() {
            return Ok(self.clone());
        }
        self.map_lines(dir, |c| refine_curve(c, target))
    }

    /// The same volume with its knots in every direction mapped affinely to
    /// [0, 1] (a reparametrisation: the same solid, the same control points).
    pub fn normalized(&self) -> BSplineVolume {
        BSplineVolume::new(
            normalized(self.knots(Dir::U)),
            normalized(self.knots(Dir::V)),
            normalized(self.knots(Dir::W)),
            self.points().to_vec(),
        )
        .expect("same sizes")
    }

    /// The two exact pieces of the volume on either side of `t` in direction
    /// `dir` (strictly inside the domain), each keeping the global
    /// parameters (the first covers [start, t], the second [t, end]), so
    /// derivatives of the pieces compare directly across the cut.
    pub fn split(&self, dir: Dir, t: f64) -> Result<(BSplineVolume, BSplineVolume), BodyError> {
        let kv = self.knots(dir);
        let (a, b) = kv.domain();
        if !(t > a && t < b) {
            return Err(GeometryError::OutOfDomain {
                value: t,
                start: a,
                end: b,
            }
            .into());
        }
        let p = kv.degree();
        let have = kv.knots().iter().filter(|&&k| k == t).count();
        let mut full = self.clone();
        for _ in have..p {
            full = full.insert_knot(dir, t)?;
        }
        // Knots: ... t (×p) ...; the first piece's control points are those
        // up to index s - 1 where s is the position of the first t.
        let fk = full.knots(dir).knots().to_vec();
        let first_t = fk.iter().position(|&k| k == t).expect("inserted");
        let n_left = first_t; // control points of the left piece
        let mut left_knots: Vec<f64> = fk[..first_t + p].to_vec();
        left_knots.push(t);
        let mut right_knots = vec![t];
        right_knots.extend_from_slice(&fk[first_t..]);
        let left_kv = KnotVector::new(p, left_knots)?;
        let right_kv = KnotVector::new(p, right_knots)?;
        let c = full.counts();
        let take =
            |range: std::ops::Range<usize>, kvd: KnotVector| -> Result<BSplineVolume, BodyError> {
                let mut counts = c;
                counts[dir.index()] = range.len();
                let mut pts = Vec::with_capacity(counts[0] * counts[1] * counts[2]);
                for i in 0..c[0] {
                    for j in 0..c[1] {
                        for k in 0..c[2] {
                            let r = [i, j, k][dir.index()];
                            if range.contains(&r) {
                                pts.push(full.points()[full.index(i, j, k)]);
                            }
                        }
                    }
                }
                let mut knots = [
                    full.knots(Dir::U).clone(),
                    full.knots(Dir::V).clone(),
                    full.knots(Dir::W).clone(),
                ];
                knots[dir.index()] = kvd;
                let [ku, kv2, kw] = knots;
                Ok(BSplineVolume::new(ku, kv2, kw, pts)?)
            };
        let n = c[dir.index()];
        Ok((take(0..n_left, left_kv)?, take(n_left - 1..n, right_kv)?))
    }
}
