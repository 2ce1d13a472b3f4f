//! The density distribution surface D(u, v) of a plane-based primitive (eq. 1's
//! D_ik): a uniform base density plus point charges on the reference plane, each
//! X_k exp(−a_dk ((u − u_k)² + (v − v_k)²)) — the in-plane Gaussian of eq. (11).
//!
//! Culling: a charge is considered 0 where it is below `tau`·D_e (its influence
//! disk of radius sqrt(ln(|X_k| / (τ D_e)) / a_dk)); charges are bucketed on a
//! uniform (u, v) grid so a point visits only the charges whose disks cover it. The
//! error this puts into D is below n_cut·τ·D_e, n_cut the number of culled charges.

use super::error::{DsmError, finite, positive};
use super::interval::Interval;
use super::jet::Jet2;
use glam::{DMat2, DVec2};

/// One point charge on the reference plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Charge {
    /// Position (u_k, v_k) on the reference plane.
    pub at: DVec2,
    /// Strength X_k = D_dk (any sign).
    pub strength: f64,
    /// In-plane reducing factor a_dk (> 0).
    pub reducing: f64,
}

/// D(u, v): a uniform base plus culled Gaussian point charges.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    base: f64,
    charges: Vec<Charge>,
    radii: Vec<f64>,
    // Bucket grid over the charges' influence disks.
    origin: DVec2,
    cell: f64,
    dims: (usize, usize),
    buckets: Vec<Vec<u32>>,
}

impl Distribution {
    /// A uniform distribution D(u, v) = base.
    pub fn uniform(base: f64) -> Result<Self, DsmError> {
        Self::new(base, Vec::new(), 1.0, 1e-15)
    }

    /// A base density plus charges, culled below `tau`·`de` (τ in (0, 1)).
    pub fn new(base: f64, charges: Vec<Charge>, de: f64, tau: f64) -> Result<Self, DsmError> {
        finite("base density", base)?;
        positive("D_e", de)?;
        if !(tau > 0.0 && tau < 1.0) {
            return Err(DsmError::BadParameter {
                name: "tau",
                value: tau,
                why: "must be in (0, 1)",
            });
        }
        for c in &charges {
            finite("charge strength", c.strength)?;
            finite("charge u", c.at.x)?;
            finite("charge v", c.at.y)?;
            positive("charge reducing factor", c.reducing)?;
        }
        let radii: Vec<f64> = charges
            .iter()
            .map(|c| {
                let l = (c.strength.abs() / (tau * de)).ln();
                if l > 0.0 {
                    (l / c.reducing).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        let mut rmax: f64 = 0.0;
        for (c, &r) in charges.iter().zip(&radii) {
            lo = lo.min(c.at - r);
            hi = hi.max(c.at + r);
            rmax = rmax.max(r);
        }
        let (origin, cell, dims, buckets) = if charges.is_empty() || rmax == 0.0 {
            (DVec2::ZERO, 1.0, (0, 0), Vec::new())
        } else {
            let ext = hi - lo;
            // About one bucket per influence radius, at most 256 per side.
            let cell = rmax.max(ext.max_element() / 256.0);
            let nx = ((ext.x / cell).ceil() as usize).max(1);
            let ny = ((ext.y / cell).ceil() as usize).max(1);
            let mut buckets = vec![Vec::new(); nx * ny];
            for (k, (c, &r)) in charges.iter().zip(&radii).enumerate() {
                if r == 0.0 {
                    continue;
                }
                let i0 = (((c.at.x - r - lo.x) / cell).floor().max(0.0) as usize).min(nx - 1);
                let i1 = (((c.at.x + r - lo.x) / cell).floor().max(0.0) as usize).min(nx - 1);
                let j0 = (((c.at.y - r - lo.y) / cell).floor().max(0.0) as usize).min(ny - 1);
                let j1 = (((c.at.y + r - lo.y) / cell).floor().max(0.0) as usize).min(ny - 1);
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        buckets[j * nx + i].push(k as u32);
                    }
                }
            }
            (lo, cell, (nx, ny), buckets)
        };
        Ok(Self {
            base,
            charges,
            radii,
            origin,
            cell,
            dims,
            buckets,
        })
    }

    /// The uniform base density.
    pub fn base(&self) -> f64 {
        self.base
    }

    /// The charges.
    pub fn charges(&self) -> &[Charge] {
        &self.charges
    }

    fn bucket(&self, p: DVec2) -> &[u32] {
        if self.dims.0 == 0 {
            return &[];
        }
        let f = (p - self.origin) / self.cell;
        if f.x < 0.0 || f.y < 0.0 {
            return &[];
        }
        let (i, j) = (f.x as usize, f.y as usize);
        if i >= self.dims.0 || j >= self.dims.1 {
            return &[];
        }
        &self.buckets[j * self.dims.0 + i]
    }

    /// D(u, v) (culled).
    pub fn value(&self, p: DVec2) -> f64 {
        let mut d = self.base;
        for &k in self.bucket(p) {
            let c = &self.charges[k as usize];
            let r2 = (p - c.at).length_squared();
            if r2 <= self.radii[k as usize].powi(2) {
                d += c.strength * (-c.reducing * r2).exp();
            }
        }
        d
    }

    /// D(u, v) with exact (unculled) summation over every charge.
    pub fn value_exact(&self, p: DVec2) -> f64 {
        self.base
            + self
                .charges
                .iter()
                .map(|c| c.strength * (-c.reducing * (p - c.at).length_squared()).exp())
                .sum::<f64>()
    }

    /// D with first and second derivatives (culled).
    pub fn jet(&self, p: DVec2) -> Jet2 {
        let mut j = Jet2::constant(self.base);
        for &k in self.bucket(p) {
            let c = &self.charges[k as usize];
            let d = p - c.at;
            let r2 = d.length_squared();
            if r2 <= self.radii[k as usize].powi(2) {
                let a = c.reducing;
                let t = c.strength * (-a * r2).exp();
                j.value += t;
                j.grad += d * (-2.0 * a * t);
                j.hess += (DMat2::from_cols(d * d.x, d * d.y) * (4.0 * a * a)
                    - DMat2::IDENTITY * (2.0 * a))
                    * t;
            }
        }
        j
    }

    /// D with first and second derivatives at every node of the regular
    /// (nu + 1) × (nv + 1) grid over [lo, hi], row by row (index j·(nu + 1) + i),
    /// culled exactly as [`Self::jet`]. Each charge's Gaussian is separable,
    /// e^{−a(Δu² + Δv²)} = e^{−aΔu²} e^{−aΔv²}, so a charge costs nu + nv + 2
    /// exponentials instead of one per node it reaches.
    pub fn jets_on_grid(&self, lo: DVec2, hi: DVec2, nu: usize, nv: usize) -> Vec<Jet2> {
        let mut out = vec![Jet2::constant(self.base); (nu + 1) * (nv + 1)];
        let us: Vec<f64> = (0..=nu)
            .map(|i| lo.x + (hi.x - lo.x) * (i as f64 / nu.max(1) as f64))
            .collect();
        let vs: Vec<f64> = (0..=nv)
            .map(|j| lo.y + (hi.y - lo.y) * (j as f64 / nv.max(1) as f64))
            .collect();
        let mut eu: Vec<f64> = vec![0.0; nu + 1];
        for (c, &r) in self.charges.iter().zip(&self.radii) {
            if r == 0.0 {
                continue;
            }
            let r2 = r * r;
            let a = c.reducing;
            // Columns and rows the influence disk can reach.
            let i0 = us.partition_point(|&u| u < c.at.x - r);
            let i1 = us.partition_point(|&u| u <= c.at.x + r);
            let j0 = vs.partition_point(|&v| v < c.at.y - r);
            let j1 = vs.partition_point(|&v| v <= c.at.y + r);
            if i0 >= i1 || j0 >= j1 {
                continue;
            }
            for i in i0..i1 {
                let du = us[i] - c.at.x;
                eu[i] = (-a * du * du).exp();
            }
            for (j, &v) in vs.iter().enumerate().take(j1).skip(j0) {
                let dv = v - c.at.y;
                let ev = c.strength * (-a * dv * dv).exp();
                let row = j * (nu + 1);
                for i in i0..i1 {
                    let du = us[i] - c.at.x;
                    if du * du + dv * dv > r2 {
                        continue;
                    }
                    let t = ev * eu[i];
                    let o = &mut out[row + i];
                    o.value += t;
                    o.grad.x -= 2.0 * a * du * t;
                    o.grad.y -= 2.0 * a * dv * t;
                    let q = 4.0 * a * a * t;
                    let huv = q * du * dv;
                    o.hess.x_axis.x += q * du * du - 2.0 * a * t;
                    o.hess.x_axis.y += huv;
                    o.hess.y_axis.x += huv;
                    o.hess.y_axis.y += q * dv * dv - 2.0 * a * t;
                }
            }
        }
        out
    }

    /// Bounds of D over the disk of radius `r` about `p`.
    pub fn bound(&self, p: DVec2, r: f64) -> Interval {
        let mut out = Interval::point(self.base);
        // Visit every bucket the disk touches (charges may repeat: skip by index set).
        if self.dims.0 == 0 {
            return out;
        }
        let lo = ((p - r - self.origin) / self.cell).floor();
        let hi = ((p + r - self.origin) / self.cell).floor();
        let (nx, ny) = (self.dims.0 as i64, self.dims.1 as i64);
        let i0 = (lo.x as i64).max(0);
        let i1 = (hi.x as i64).min(nx - 1);
        let j0 = (lo.y as i64).max(0);
        let j1 = (hi.y as i64).min(ny - 1);
        let mut seen: Vec<u32> = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                for &k in &self.buckets[(j * nx + i) as usize] {
                    seen.push(k);
                }
            }
        }
        seen.sort_unstable();
        seen.dedup();
        for k in seen {
            let c = &self.charges[k as usize];
            let dist = (p - c.at).length();
            let dmin = (dist - r).max(0.0);
            let dmax = dist + r;
            let rk = self.radii[k as usize];
            if dmin > rk {
                continue;
            }
            let e = Interval::new(
                (-c.reducing * dmax * dmax).exp(),
                (-c.reducing * dmin * dmin).exp(),
            );
            let mut t = Interval::point(c.strength).mul_nonneg(e);
            if dmax > rk {
                t = t.with_zero();
            }
            out = out.plus(t);
        }
        out
    }

    /// An upper bound of |D| anywhere.
    pub fn max_abs(&self) -> f64 {
        self.base.abs() + self.charges.iter().map(|c| c.strength.abs()).sum::<f64>()
    }
}
