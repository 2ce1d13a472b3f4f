//! The explicit equal density surface of a plane-based primitive (eq. 12):
//! h(u, v) = (ln D(u, v) − ln D_e) / a, or with the connecting function of eq. (13)
//! h(u, v) = s(u, v)/a · (ln D(u, v) − ln D_e), with analytic first and second
//! derivatives and the mean and Gaussian ("total") curvature of the graph
//! (u, v, h(u, v)).
//!
//! Conventions: curvatures are taken with respect to the upward unit normal
//! n = (−h_u, −h_v, 1)/W, W = √(1 + h_u² + h_v²); H = (k₁ + k₂)/2 (so a cap bulging
//! up has H < 0), K = k₁ k₂. Where D ≤ 0 there is no surface (h undefined); where
//! h < 0 the lens |r| ≤ h is empty — the solid has a hole there.

use super::connect::Connecting;
use super::density::{DensityPrimitive, Sheet};
use super::distribution::Distribution;
use super::error::DsmError;
use super::jet::Jet2;
use super::mesh::Mesh;
use super::placement::Placement;
use glam::{DVec2, DVec3};

/// h(u, v) of a plane-based primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct EqualDensitySurface {
    /// D(u, v).
    pub distribution: Distribution,
    /// The primitive's reducing factor a_i.
    pub reducing: f64,
    /// D_e.
    pub de: f64,
    /// s(u, v), if any.
    pub connect: Option<Connecting>,
}

/// Curvature of h at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// Mean curvature (k₁ + k₂)/2 w.r.t. the upward normal.
    pub mean: f64,
    /// Gaussian curvature k₁ k₂.
    pub gaussian: f64,
    /// Upward unit normal.
    pub normal: DVec3,
}

impl EqualDensitySurface {
    /// h(u, v) (None where D ≤ 0).
    pub fn height(&self, p: DVec2) -> Option<f64> {
        let d = self.distribution.value(p);
        if d <= 0.0 {
            return None;
        }
        let s = self.connect.as_ref().map_or(1.0, |c| c.value(p));
        Some(s * (d.ln() - self.de.ln()) / self.reducing)
    }

    /// h with first and second derivatives (None where D ≤ 0).
    pub fn jet(&self, p: DVec2) -> Option<Jet2> {
        let d = self.distribution.jet(p);
        if d.value <= 0.0 {
            return None;
        }
        let mut l = d.ln();
        l.value -= self.de.ln();
        let l = match &self.connect {
            Some(c) => c.jet(p).times(l),
            None => l,
        };
        Some(l.scale(1.0 / self.reducing))
    }

    /// h with derivatives at every node of the regular (nu + 1) × (nv + 1) grid over
    /// [lo, hi], row by row (None where D ≤ 0): the same values as [`Self::jet`] at
    /// each node, with D from [`Distribution::jets_on_grid`].
    pub fn jets_on_grid(&self, lo: DVec2, hi: DVec2, nu: usize, nv: usize) -> Vec<Option<Jet2>> {
        let ds = self.distribution.jets_on_grid(lo, hi, nu, nv);
        let lnde = self.de.ln();
        ds.into_iter()
            .enumerate()
            .map(|(k, d)| {
                if d.value <= 0.0 {
                    return None;
                }
                let mut l = d.ln();
                l.value -= lnde;
                let l = match &self.connect {
                    Some(c) => {
                        let (i, j) = (k % (nu + 1), k / (nu + 1));
                        let p = lo
                            + (hi - lo)
                                * DVec2::new(
                                    i as f64 / nu.max(1) as f64,
                                    j as f64 / nv.max(1) as f64,
                                );
                        c.jet(p).times(l)
                    }
                    None => l,
                };
                Some(l.scale(1.0 / self.reducing))
            })
            .collect()
    }

    /// Mean and Gaussian curvature and the normal at (u, v).
    pub fn curvature(&self, p: DVec2) -> Option<Curvature> {
        let j = self.jet(p)?;
        Some(graph_curvature(j))
    }

    /// The plane-based primitive whose equal density surface this is, on the
    /// rectangle [lo, hi] of the reference plane z = 0 of `placement`.
    pub fn primitive(
        &self,
        lo: DVec2,
        hi: DVec2,
        placement: Placement,
    ) -> Result<DensityPrimitive, DsmError> {
        let sheet = Sheet {
            distribution: self.distribution.clone(),
            lo,
            hi,
            connect: self.connect.clone(),
        };
        DensityPrimitive::plane(sheet, placement, self.reducing)
    }

    /// A (nu + 1) × (nv + 1) vertex height-field mesh of the surface over [lo, hi]
    /// (h clamped at 0 where the surface is missing), with analytic normals.
    pub fn mesh(&self, lo: DVec2, hi: DVec2, nu: usize, nv: usize) -> Result<Mesh, DsmError> {
        if nu == 0 || nv == 0 || nu > 4096 || nv > 4096 {
            return Err(DsmError::BadMeshRequest("grid must be 1..=4096 per side"));
        }
        let jets = self.jets_on_grid(lo, hi, nu, nv);
        let mut m = Mesh::default();
        m.positions.reserve(jets.len());
        m.normals.reserve(jets.len());
        for j in 0..=nv {
            for i in 0..=nu {
                let p = lo + (hi - lo) * DVec2::new(i as f64 / nu as f64, j as f64 / nv as f64);
                match jets[j * (nu + 1) + i] {
                    Some(h) if h.value > 0.0 => {
                        m.positions.push(DVec3::new(p.x, p.y, h.value));
                        m.normals
                            .push(DVec3::new(-h.grad.x, -h.grad.y, 1.0).normalize());
                    }
                    _ => {
                        m.positions.push(DVec3::new(p.x, p.y, 0.0));
                        m.normals.push(DVec3::Z);
                    }
                }
            }
        }
        let w = (nu + 1) as u32;
        for j in 0..nv as u32 {
            for i in 0..nu as u32 {
                let a = j * w + i;
                m.triangles.push([a, a + 1, a + w + 1]);
                m.triangles.push([a, a + w + 1, a + w]);
            }
        }
        Ok(m)
    }
}

/// Mean and Gaussian curvature of the graph z = h(u, v) from h's jet.
pub fn graph_curvature(j: Jet2) -> Curvature {
    let (hu, hv) = (j.grad.x, j.grad.y);
    let (huu, huv, hvv) = (j.hess.x_axis.x, j.hess.y_axis.x, j.hess.y_axis.y);
    let w2 = 1.0 + hu * hu + hv * hv;
    let w = w2.sqrt();
    Curvature {
        mean: ((1.0 + hv * hv) * huu - 2.0 * hu * hv * huv + (1.0 + hu * hu) * hvv)
            / (2.0 * w2 * w),
        gaussian: (huu * hvv - huv * huv) / (w2 * w2),
        normal: DVec3::new(-hu, -hv, 1.0) / w,
    }
}
