//! Knot insertion (Boehm's algorithm, Piegl & Tiller A5.1): adds a knot,
//! and a control point, without changing the shape — how a user adds detail
//! where the surface must bend more. Also the exact sub-patch of a surface
//! over a parameter rectangle (knots inserted to full multiplicity).

use glam::DVec3;

use super::{BSplineCurve, BSplineSurface, GeometryError, KnotVector};

/// Inserts `t` once into a knot vector and its control polygon (one
/// "line" of control points per call, all sharing the knot vector).
fn insert(
    kv: &KnotVector,
    t: f64,
    lines: &[Vec<DVec3>],
) -> Result<(KnotVector, Vec<Vec<DVec3>>), GeometryError> {
    let (a, b) = kv.domain();
    if !t.is_finite() || t <= a || t >= b {
        return Err(GeometryError::OutOfDomain {
            value: t,
            start: a,
            end: b,
        });
    }
    let p = kv.degree();
    let u = kv.knots();
    let mult = u.iter().filter(|&&x| x == t).count();
    if mult >= p {
        return Err(GeometryError::InteriorMultiplicity {
            value: t,
            multiplicity: mult + 1,
            degree: p,
        });
    }
    let k = kv.find_span(t);
    let mut knots = u.to_vec();
    knots.insert(k + 1, t);
    let new_kv = KnotVector::new(p, knots)?;
    let out = lines
        .iter()
        .map(|pts| {
            let mut q = Vec::with_capacity(pts.len() + 1);
            for i in 0..=pts.len() {
                if i + p <= k {
                    q.push(pts[i]);
                } else if i > k {
                    q.push(pts[i - 1]);
                } else {
                    let alpha = (t - u[i]) / (u[i + p] - u[i]);
                    q.push(pts[i] * alpha + pts[i - 1] * (1.0 - alpha));
                }
            }
            q
        })
        .collect();
    Ok((new_kv, out))
}

impl BSplineCurve {
    /// The same curve with the knot `t` inserted once.
    pub fn insert_knot(&self, t: f64) -> Result<BSplineCurve, GeometryError> {
        let (kv, mut lines) = insert(self.knots(), t, &[self.points().to_vec()])?;
        BSplineCurve::new(kv, lines.remove(0))
    }
}

impl BSplineSurface {
    /// The same surface with the knot `t` inserted once along u.
    pub fn insert_knot_u(&self, t: f64) -> Result<BSplineSurface, GeometryError> {
        let (nu, nv) = (self.nu(), self.nv());
        let columns: Vec<Vec<DVec3>> = (0..nv)
            .map(|j| (0..nu).map(|i| self.points()[i * nv + j]).collect())
            .collect();
        let (ku, cols) = insert(self.u_knots(), t, &columns)?;
        let mut pts = Vec::with_capacity((nu + 1) * nv);
        for i in 0..=nu {
            for col in &cols {
                pts.push(col[i]);
            }
        }
        BSplineSurface::new(ku, self.v_knots().clone(), pts)
    }

    /// The same surface with the knot `t` inserted once along v.
    pub fn insert_knot_v(&self, t: f64) -> Result<BSplineSurface, GeometryError> {
        let nv = self.nv();
        let rows: Vec<Vec<DVec3>> = self.points().chunks(nv).map(|r| r.to_vec()).collect();
        let (kv, rows) = insert(self.v_knots(), t, &rows)?;
        BSplineSurface::new(
            self.u_knots().clone(),
            kv,
            rows.into_iter().flatten().collect(),
        )
    }

    /// The same surface with every non-empty knot span halved in u and v.
    pub fn refine_uniform(&self) -> Result<BSplineSurface, GeometryError> {
        let mut s = self.clone();
        for (_, a, b) in self.u_knots().spans() {
            s = s.insert_knot_u(0.5 * (a + b))?;
        }
        for (_, a, b) in self.v_knots().spans() {
            s = s.insert_knot_v(0.5 * (a + b))?;
        }
        Ok(s)
    }

    /// The exact sub-surface over [u0, u1] × [v0, v1] (a rectangle inside
    /// the domain with u0 < u1, v0 < v1), with its own clamped knot vectors.
    pub fn sub_patch(
        &self,
        u0: f64,
        u1: f64,
        v0: f64,
        v1: f64,
    ) -> Result<BSplineSurface, GeometryError> {
        let ((a0, a1), (b0, b1)) = self.domain();
        for (t, lo, hi) in [(u0, a0, a1), (u1, a0, a1), (v0, b0, b1), (v1, b0, b1)] {
            if !t.is_finite() || t < lo || t > hi {
                return Err(GeometryError::OutOfDomain {
                    value: t,
                    start: lo,
                    end: hi,
                });
            }
        }
        if u1 <= u0 || v1 <= v0 {
            return Err(GeometryError::EmptyDomain);
        }
        let mut s = self.clone();
        for t in [u0, u1] {
            if t > a0 && t < a1 {
                let p = s.u_knots().degree();
                while s.u_knots().knots().iter().filter(|&&x| x == t).count() < p {
                    s = s.insert_knot_u(t)?;
                }
            }
        }
        for t in [v0, v1] {
            if t > b0 && t < b1 {
                let p = s.v_knots().degree();
                while s.v_knots().knots().iter().filter(|&&x| x == t).count() < p {
                    s = s.insert_knot_v(t)?;
                }
            }
        }
        // With lo at multiplicity p, the piece starts at the control point
        // just before lo's first occurrence (at the domain start: the first);
        // it has (interior knots strictly inside) + p + 1 control points.
        let cut = |kv: &KnotVector,
                   lo: f64,
                   hi: f64|
         -> Result<(KnotVector, usize, usize), GeometryError> {
            let p = kv.degree();
            let k = kv.knots();
            let first = k.iter().position(|&x| x == lo).unwrap_or(0);
            let start = if lo == k[0] {
                0
            } else {
                first.saturating_sub(1)
            };
            let interior: Vec<f64> = k.iter().copied().filter(|&x| x > lo && x < hi).collect();
            let count = interior.len() + p + 1;
            let mut knots = vec![lo; p + 1];
            knots.extend(interior);
            knots.extend(std::iter::repeat_n(hi, p + 1));
            Ok((KnotVector::new(p, knots)?, start, count))
        };
        let (ku, su, cu) = cut(s.u_knots(), u0, u1)?;
        let (kv, sv, cv) = cut(s.v_knots(), v0, v1)?;
        let nv = s.nv();
        let mut pts = Vec::with_capacity(cu * cv);
        for i in su..su + cu {
            for j in sv..sv + cv {
                pts.push(s.points()[i * nv + j]);
            }
        }
        BSplineSurface::new(ku, kv, pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy() -> BSplineSurface {
        let u = KnotVector::new(3, vec![0., 0., 0., 0., 0.4, 0.7, 1., 1., 1., 1.]).unwrap();
        let v = KnotVector::clamped_uniform(2, 5).unwrap();
        let pts = (0..30)
            .map(|k| {
                let (x, y) = ((k / 5) as f64, (k % 5) as f64);
                DVec3::new(x, y, (0.7 * x).sin() * (0.9 * y).cos())
            })
            .collect();
        BSplineSurface::new(u, v, pts).unwrap()
    }

    fn max_gap(a: &BSplineSurface, b: &BSplineSurface) -> f64 {
        let mut gap = 0.0f64;
        for i in 0..=30 {
            for j in 0..=30 {
                let (u, v) = (i as f64 / 30.0, j as f64 / 30.0);
                gap = gap.max((a.point(u, v) - b.point(u, v)).length());
            }
        }
        gap
    }

    #[test]
    fn insertion_keeps_the_shape() {
        let s = wavy();
        let r = s
            .insert_knot_u(0.55)
            .unwrap()
            .insert_knot_v(0.3)
            .unwrap()
            .insert_knot_u(0.4)
            .unwrap();
        assert_eq!((r.nu(), r.nv()), (s.nu() + 2, s.nv() + 1));
        assert!(max_gap(&s, &r) < 1e-12);
        let f = s.refine_uniform().unwrap();
        assert_eq!(f.nu(), s.nu() + 3);
        assert!(max_gap(&s, &f) < 1e-12);
        let c = BSplineCurve::new(s.u_knots().clone(), s.points()[..6].to_vec()).unwrap();
        let c2 = c.insert_knot(0.2).unwrap();
        for k in 0..=50 {
            let t = k as f64 / 50.0;
            assert!((c.point(t) - c2.point(t)).length() < 1e-12);
        }
    }

    #[test]
    fn sub_patch_is_exact() {
        let s = wavy();
        let p = s.sub_patch(0.2, 0.8, 0.1, 0.6).unwrap();
        for i in 0..=20 {
            for j in 0..=20 {
                let (a, b) = (i as f64 / 20.0, j as f64 / 20.0);
                let (u, v) = (0.2 + 0.6 * a, 0.1 + 0.5 * b);
                let (pu0, pu1) = p.u_knots().domain();
                let (pv0, pv1) = p.v_knots().domain();
                let q = p.point(pu0 + (pu1 - pu0) * a, pv0 + (pv1 - pv0) * b);
                assert!((q - s.point(u, v)).length() < 1e-11, "({u},{v})");
            }
        }
    }

    #[test]
    fn bad_insertions_are_refused() {
        let s = wavy();
        assert!(s.insert_knot_u(f64::NAN).is_err());
        assert!(s.insert_knot_u(1.0).is_err());
        assert!(
            s.insert_knot_u(0.4)
                .unwrap()
                .insert_knot_u(0.4)
                .unwrap()
                .insert_knot_u(0.4)
                .is_err()
        );
        assert!(s.sub_patch(0.5, 0.2, 0.0, 1.0).is_err());
    }
}
