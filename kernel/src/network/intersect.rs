//! Curve–curve closest points: where two B-spline curves meet within a
//! tolerance. Candidates come from the closest points of their control
//! polylines' sampled chords (8 per knot span, at least 32 per curve); each is
//! refined by Gauss–Newton on ½|a(s) − b(t)|² with the parameters kept in
//! their domains (a clamped variable is held and the other re-solved), so
//! (chord pairs are first culled by the bounding boxes of runs of 8 chords)
//! end-to-end meetings (corners) are found as well as crossings.

use glam::DVec3;

use crate::bspline::{BSplineCurve, BasisDerivs, basis_derivs_into};

/// Where two curves come closest: parameters and distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    /// Parameter on the first curve.
    pub s: f64,
    /// Parameter on the second curve.
    pub t: f64,
    /// |a(s) − b(t)|.
    pub gap: f64,
    /// The midpoint of a(s) and b(t).
    pub point: DVec3,
}

/// c(t), c′(t) with a reused basis scratch.
fn eval(c: &BSplineCurve, t: f64, b: &mut BasisDerivs) -> (DVec3, DVec3) {
    basis_derivs_into(c.knots(), t, 1, b);
    let pts = c.points();
    let (mut p, mut d) = (DVec3::ZERO, DVec3::ZERO);
    for k in 0..=c.degree() {
        p += pts[b.first + k] * b.get(0, k);
        d += pts[b.first + k] * b.get(1, k);
    }
    (p, d)
}

/// Samples of a curve: parameters and points.
fn polyline(c: &BSplineCurve) -> (Vec<f64>, Vec<DVec3>) {
    let spans = c.knots().spans();
    let per = 8usize.max(32usize.div_ceil(spans.len().max(1)));
    let mut ts = Vec::with_capacity(spans.len() * per + 1);
    for (_, a, b) in &spans {
        for k in 0..per {
            ts.push(a + (b - a) * k as f64 / per as f64);
        }
    }
    ts.push(c.domain().1);
    let mut b = BasisDerivs::default();
    let ps = ts.iter().map(|&t| eval(c, t, &mut b).0).collect();
    (ts, ps)
}

/// Closest points of segments [p0, p1] and [q0, q1]: (fraction on p, on q, distance).
fn segment_closest(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64, f64) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (mut s, mut t);
    if a <= 1e-300 && e <= 1e-300 {
        return (0.0, 0.0, r.length());
    }
    if a <= 1e-300 {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= 1e-300 {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            s = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
        }
    }
    let d = (p0 + d1 * s) - (q0 + d2 * t);
    (s, t, d.length())
}

/// Refines a closest-point pair of `a` and `b` from (s, t).
pub fn refine(a: &BSplineCurve, b: &BSplineCurve, s: f64, t: f64) -> CurveHit {
    let (a0, a1) = a.domain();
    let (b0, b1) = b.domain();
    let (mut s, mut t) = (s.clamp(a0, a1), t.clamp(b0, b1));
    let mut sc = BasisDerivs::default();
    for _ in 0..64 {
        let (pa, da1) = eval(a, s, &mut sc);
        let (pb, db1) = eval(b, t, &mut sc);
        let r = pa - pb;
        let (m11, m12, m22) = (da1.dot(da1), -da1.dot(db1), db1.dot(db1));
        let (g1, g2) = (da1.dot(r), -db1.dot(r));
        let det = m11 * m22 - m12 * m12;
        let (mut ns, mut nt) = if det > 1e-12 * m11 * m22 {
            (
                s - (m22 * g1 - m12 * g2) / det,
                t - (m11 * g2 - m12 * g1) / det,
            )
        } else {
            (
                s - 0.5 * g1 / m11.max(1e-300),
                t - 0.5 * g2 / m22.max(1e-300),
            )
        };
        let (cs, ct) = (ns.clamp(a0, a1), nt.clamp(b0, b1));
        if cs != ns && ct == nt {
            // s held at its bound: t alone.
            ns = cs;
            let pa = eval(a, ns, &mut sc).0;
            let (pbt, dbt) = eval(b, t, &mut sc);
            nt = (t - dbt.dot(pbt - pa) / m22.max(1e-300)).clamp(b0, b1);
        } else if ct != nt && cs == ns {
            nt = ct;
            let pb = eval(b, nt, &mut sc).0;
            let (pas, das) = eval(a, s, &mut sc);
            ns = (s - das.dot(pas - pb) / m11.max(1e-300)).clamp(a0, a1);
        } else {
            ns = cs;
            nt = ct;
        }
        let step = (ns - s).abs() / (a1 - a0) + (nt - t).abs() / (b1 - b0);
        s = ns;
        t = nt;
        if step < 1e-15 {
            break;
        }
    }
    let (pa, pb) = (eval(a, s, &mut sc).0, eval(b, t, &mut sc).0);
    CurveHit {
        s,
        t,
        gap: (pa - pb).length(),
        point: (pa + pb) * 0.5,
    }
}

/// Segments per bounding box of the chunked search.
const CHUNK: usize = 8;

/// Bounding boxes of runs of `CHUNK` segments, with their longest segment.
fn chunks(ps: &[DVec3]) -> Vec<(DVec3, DVec3, f64)> {
    (0..(ps.len() - 1).div_ceil(CHUNK))
        .map(|c| {
            let run = &ps[c * CHUNK..((c + 1) * CHUNK + 1).min(ps.len())];
            let (lo, hi) = bbox(run);
            let longest = run
                .windows(2)
                .map(|w| (w[1] - w[0]).length())
                .fold(0.0, f64::max);
            (lo, hi, longest)
        })
        .collect()
}

fn bbox(ps: &[DVec3]) -> (DVec3, DVec3) {
    ps.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Every place where `a` and `b` come within `tol` of each other (one hit
/// per meeting; hits closer than 1e-7 of both domains are merged).
pub fn intersections(a: &BSplineCurve, b: &BSplineCurve, tol: f64) -> Vec<CurveHit> {
    hits(a, b, tol, false)
}

/// Where `a` comes within `tol` of itself away from the same point (its
/// parameters differ by more than 1e-3 of the domain and the chord between
/// them is longer than the curve's arc would allow for a mere touch).
pub fn self_intersections(a: &BSplineCurve, tol: f64) -> Vec<CurveHit> {
    hits(a, a, tol, true)
}

fn hits(a: &BSplineCurve, b: &BSplineCurve, tol: f64, same: bool) -> Vec<CurveHit> {
    let (ta, pa) = polyline(a);
    let (tb, pb) = polyline(b);
    let (lo_a, hi_a) = bbox(a.points());
    let (lo_b, hi_b) = bbox(b.points());
    let margin = DVec3::splat(tol);
    if !same
        && ((lo_a - hi_b - margin).cmpgt(DVec3::ZERO).any()
            || (lo_b - hi_a - margin).cmpgt(DVec3::ZERO).any())
    {
        return Vec::new();
    }
    let (wa, wb) = (a.domain().1 - a.domain().0, b.domain().1 - b.domain().0);
    let (ca, cb) = (chunks(&pa), chunks(&pb));
    let mut out: Vec<CurveHit> = Vec::new();
    for (ia, (la0, ha0, ma)) in ca.iter().enumerate() {
        for (ib, (lb0, hb0, mb)) in cb.iter().enumerate() {
            let margin = DVec3::splat(tol + 0.25 * (ma + mb));
            if (*la0 - *hb0 - margin).cmpgt(DVec3::ZERO).any()
                || (*lb0 - *ha0 - margin).cmpgt(DVec3::ZERO).any()
            {
                continue;
            }
            for i in ia * CHUNK..((ia + 1) * CHUNK).min(pa.len() - 1) {
                let la = (pa[i + 1] - pa[i]).length();
                for j in ib * CHUNK..((ib + 1) * CHUNK).min(pb.len() - 1) {
                    if same && j <= i + 2 {
                        continue;
                    }
                    let lb = (pb[j + 1] - pb[j]).length();
                    let (fs, ft, d) = segment_closest(pa[i], pa[i + 1], pb[j], pb[j + 1]);
                    if d > tol + 0.25 * (la + lb) {
                        continue;
                    }
                    let s0 = ta[i] + fs * (ta[i + 1] - ta[i]);
                    let t0 = tb[j] + ft * (tb[j + 1] - tb[j]);
                    let h = refine(a, b, s0, t0);
                    if h.gap > tol {
                        continue;
                    }
                    if same {
                        // A real self-crossing: the arc between the two parameters
                        // is much longer than the gap.
                        if (h.s - h.t).abs() < 1e-3 * wa {
                            continue;
                        }
                        let mid = a.point(0.5 * (h.s + h.t));
                        if (mid - h.point).length() <= 4.0 * tol {
                            continue;
                        }
                    }
                    if out
                        .iter()
                        .any(|o| (o.s - h.s).abs() <= 1e-7 * wa && (o.t - h.t).abs() <= 1e-7 * wb)
                    {
                        continue;
                    }
                    out.push(h);
                }
            }
        }
    }
    out
}
