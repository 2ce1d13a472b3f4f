//! The surface connecting function s(u, v) of eq. (13): h = s(u, v)/a · (ln D − ln D_e).
//! It acts as a reducing factor a/s(u, v) that varies over the reference plane —
//! read as the paper's "non-uniform reducing factor surface" (Fig. 9).
//!
//! Choice (the paper gives no formula): s = P_u(u) · P_v(v), each P a piecewise
//! profile through knots (t_i, y_i), joined by the quintic smoothstep
//! 6x⁵ − 15x⁴ + 10x³, so P is C² with zero first and second derivative at every
//! knot. A profile falling to 0 at the domain's edge connects h to the reference
//! plane with continuous slope and curvature (h, h', h'' → 0); a profile moving
//! between two levels blends two surfaces or bridges primitives.

use super::error::{DsmError, finite};
use super::interval::Interval;
use super::jet::Jet2;
use glam::{DMat2, DVec2};

/// A 1-D C² profile through knots, constant outside them.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    knots: Vec<(f64, f64)>,
}

fn smooth(x: f64) -> (f64, f64, f64) {
    let x2 = x * x;
    (
        x2 * x * (10.0 + x * (-15.0 + 6.0 * x)),
        30.0 * x2 * (1.0 - x) * (1.0 - x),
        60.0 * x * (1.0 - x) * (1.0 - 2.0 * x),
    )
}

impl Profile {
    /// A profile through `knots` (t strictly increasing, all values finite, ≥ 1 knot).
    pub fn new(knots: Vec<(f64, f64)>) -> Result<Self, DsmError> {
        if knots.is_empty() {
            return Err(DsmError::BadParameter {
                name: "profile knots",
                value: 0.0,
                why: "need at least one knot",
            });
        }
        for w in knots.windows(2) {
            if w[1].0.partial_cmp(&w[0].0) != Some(std::cmp::Ordering::Greater) {
                return Err(DsmError::BadParameter {
                    name: "profile knot t",
                    value: w[1].0,
                    why: "must increase strictly",
                });
            }
        }
        for k in &knots {
            finite("profile knot t", k.0)?;
            finite("profile knot value", k.1)?;
        }
        Ok(Self { knots })
    }

    /// The constant profile 1.
    pub fn one() -> Self {
        Self {
            knots: vec![(0.0, 1.0)],
        }
    }

    /// 0 at `lo`, rising to 1 at `lo + width`, 1 until `hi − width`, 0 at `hi`.
    pub fn plateau(lo: f64, hi: f64, width: f64) -> Result<Self, DsmError> {
        if !(width > 0.0 && lo + 2.0 * width <= hi) {
            return Err(DsmError::BadParameter {
                name: "ramp width",
                value: width,
                why: "must be > 0 and fit twice in the domain",
            });
        }
        Self::new(vec![
            (lo, 0.0),
            (lo + width, 1.0),
            (hi - width, 1.0),
            (hi, 0.0),
        ])
    }

    /// (P, P', P'') at t.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let k = &self.knots;
        if t <= k[0].0 {
            return (k[0].1, 0.0, 0.0);
        }
        let last = k[k.len() - 1];
        if t >= last.0 {
            return (last.1, 0.0, 0.0);
        }
        let i = k.partition_point(|x| x.0 <= t) - 1;
        let (t0, y0) = k[i];
        let (t1, y1) = k[i + 1];
        let w = t1 - t0;
        let (s, s1, s2) = smooth((t - t0) / w);
        let dy = y1 - y0;
        (y0 + dy * s, dy * s1 / w, dy * s2 / (w * w))
    }

    /// Bounds of P over [a, b] (exact: P is monotone between knots).
    pub fn bound(&self, a: f64, b: f64) -> Interval {
        let (pa, _, _) = self.eval(a);
        let (pb, _, _) = self.eval(b);
        let mut lo = pa.min(pb);
        let mut hi = pa.max(pb);
        for &(t, y) in &self.knots {
            if t > a && t < b {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        Interval::new(lo, hi)
    }

    /// The largest value.
    pub fn max(&self) -> f64 {
        self.knots
            .iter()
            .map(|k| k.1)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// s(u, v) = P_u(u) · P_v(v).
#[derive(Clone, Debug, PartialEq)]
pub struct Connecting {
    /// Profile along u.
    pub u: Profile,
    /// Profile along v.
    pub v: Profile,
}

impl Connecting {
    /// s with the given profiles; every knot value must be in [0, 1] (s is a
    /// fraction of the reducing length 1/a).
    pub fn new(u: Profile, v: Profile) -> Result<Self, DsmError> {
        for k in u.knots.iter().chain(&v.knots) {
            if !(0.0..=1.0).contains(&k.1) {
                return Err(DsmError::BadParameter {
                    name: "connecting value",
                    value: k.1,
                    why: "must be in [0, 1]",
                });
            }
        }
        Ok(Self { u, v })
    }

    /// Connection to the reference plane over the rectangle [lo, hi] with a ramp
    /// of `width` along every edge.
    pub fn to_plane(lo: DVec2, hi: DVec2, width: f64) -> Result<Self, DsmError> {
        Self::new(
            Profile::plateau(lo.x, hi.x, width)?,
            Profile::plateau(lo.y, hi.y, width)?,
        )
    }

    /// s with first and second derivatives.
    pub fn jet(&self, p: DVec2) -> Jet2 {
        let (a, a1, a2) = self.u.eval(p.x);
        let (b, b1, b2) = self.v.eval(p.y);
        Jet2 {
            value: a * b,
            grad: DVec2::new(a1 * b, a * b1),
            hess: DMat2::from_cols(DVec2::new(a2 * b, a1 * b1), DVec2::new(a1 * b1, a * b2)),
        }
    }

    /// s at a point.
    pub fn value(&self, p: DVec2) -> f64 {
        self.u.eval(p.x).0 * self.v.eval(p.y).0
    }

    /// Bounds of s over the square of half side r about p.
    pub fn bound(&self, p: DVec2, r: f64) -> Interval {
        let a = self.u.bound(p.x - r, p.x + r);
        let b = self.v.bound(p.y - r, p.y + r);
        a.mul_nonneg(b)
    }
}
