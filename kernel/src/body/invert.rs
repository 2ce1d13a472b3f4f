//! Point inversion x → (u, v, w) of a B-spline volume.
//!
//! Robust start: the volume is sampled on a seed grid (the knots plus
//! `SEEDS_PER_SPAN − 1` points inside every knot span, per direction) and
//! the nearest sample starts the iteration. Newton's step solves
//! J δ = x − x(u, v, w); the new parameters are clamped into the domain and
//! the step is halved (at most 30 times) until the distance to `x`
//! decreases. When the Jacobian is singular a gradient step Jᵀr is taken.
//! A point outside the body ends at the nearest boundary parameter it can
//! reach; [`Inversion::distance`] tells how far off it is. An [`Inverter`]
//! keeps the seed grid for many queries on one volume.

use glam::DVec3;

use super::{BSplineVolume, BodyError, VolumeScratch};

/// Seed samples per knot span in each direction.
pub const SEEDS_PER_SPAN: usize = 3;

/// The result of inverting one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inversion {
    /// The parameters found (inside the domain).
    pub uvw: [f64; 3],
    /// x(u, v, w) there.
    pub point: DVec3,
    /// |x(u, v, w) − target|: ≈ 0 for a point inside the body.
    pub distance: f64,
    /// Newton iterations taken.
    pub iterations: usize,
}

/// A volume with its seed grid, ready for many inversions.
pub struct Inverter<'a> {
    volume: &'a BSplineVolume,
    seeds: Vec<([f64; 3], DVec3)>,
    size: f64,
}

fn seed_params(kv: &crate::bspline::KnotVector) -> Vec<f64> {
    let mut out = Vec::new();
    for (_, a, b) in kv.spans() {
        for s in 0..SEEDS_PER_SPAN {
            out.push(a + (b - a) * s as f64 / SEEDS_PER_SPAN as f64);
        }
    }
    out.push(kv.domain().1);
    out
}

impl<'a> Inverter<'a> {
    /// Samples the seed grid of `volume`.
    pub fn new(volume: &'a BSplineVolume) -> Self {
        let [su, sv, sw] = [
            seed_params(volume.knots(super::Dir::U)),
            seed_params(volume.knots(super::Dir::V)),
            seed_params(volume.knots(super::Dir::W)),
        ];
        let mut scratch = VolumeScratch::default();
        let mut seeds = Vec::with_capacity(su.len() * sv.len() * sw.len());
        for &u in &su {
            for &v in &sv {
                for &w in &sw {
                    seeds.push(([u, v, w], volume.eval(&mut scratch, [u, v, w], 0).p));
                }
            }
        }
        let (lo, hi) = volume
            .points()
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        Self {
            volume,
            seeds,
            size: (hi - lo).length().max(f64::MIN_POSITIVE),
        }
    }

    /// The parameters of `x`: iterates until the distance is below
    /// `tolerance` (absolute, model units) or the step stalls (≤ 1e-15 of
    /// the domain), at most 100 iterations.
    pub fn invert(&self, x: DVec3, tolerance: f64) -> Result<Inversion, BodyError> {
        if !x.is_finite() {
            return Err(BodyError::NonFinite("point to invert".into()));
        }
        let start = self
            .seeds
            .iter()
            .min_by(|a, b| {
                (a.1 - x)
                    .length_squared()
                    .total_cmp(&(b.1 - x).length_squared())
            })
            .map(|s| s.0)
            .expect("a seed grid is never empty");
        Ok(self.newton(x, start, tolerance))
    }

    fn newton(&self, x: DVec3, start: [f64; 3], tolerance: f64) -> Inversion {
        let vol = self.volume;
        let dom = vol.domain();
        let clamp = |t: [f64; 3]| {
            [
                t[0].clamp(dom[0].0, dom[0].1),
                t[1].clamp(dom[1].0, dom[1].1),
                t[2].clamp(dom[2].0, dom[2].1),
            ]
        };
        let extent = (0..3).map(|d| dom[d].1 - dom[d].0).fold(0.0, f64::max);
        let mut scratch = VolumeScratch::default();
        let mut t = start;
        let mut d = vol.eval(&mut scratch, t, 1);
        let mut r = x - d.p;
        let mut it = 0;
        while it < 100 && r.length() > tolerance {
            it += 1;
            let j = d.jacobian();
            let det = j.determinant();
            let step = if det.abs() > 1e-14 * (d.d[0].length() * d.d[1].length() * d.d[2].length())
            {
                j.inverse() * r
            } else {
                // Gradient of ½|r|²: −Jᵀ r; scaled to a parameter-sized step.
                let g = j.transpose() * r;
                let gl = g.length();
                if gl == 0.0 {
                    break;
                }
                g * (r.length() / (gl * self.size.max(1e-300))).min(extent)
            };
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                let cand = clamp([
                    t[0] + lambda * step.x,
                    t[1] + lambda * step.y,
                    t[2] + lambda * step.z,
                ]);
                let dc = vol.eval(&mut scratch, cand, 1);
                let rc = x - dc.p;
                if rc.length() < r.length() {
                    let moved = (0..3).map(|k| (cand[k] - t[k]).abs()).fold(0.0, f64::max);
                    t = cand;
                    d = dc;
                    r = rc;
                    accepted = moved > 1e-15 * extent;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                break;
            }
        }
        Inversion {
            uvw: t,
            point: d.p,
            distance: r.length(),
            iterations: it,
        }
    }
}

impl BSplineVolume {
    /// The parameters (u, v, w) of `x` (see [`Inverter::invert`]); builds a
    /// seed grid, so use an [`Inverter`] for many points.
    pub fn invert(&self, x: DVec3, tolerance: f64) -> Result<Inversion, BodyError> {
        Inverter::new(self).invert(x, tolerance)
    }
}
