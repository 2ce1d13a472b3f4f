//! The inverse transformation of the DSM (paper §3.1, eqs. 8–11): from a
//! passing-points net over a plane-based primitive's reference plane, the reducing
//! factors a_dk and strengths D_dk of point charges under the interior nodes, so
//! that the equal density surface h(u, v) passes through every interior node.
//!
//! * eq. (8): a_dk = |ln(h_k / h_mk) · exp(a_i (h_k − h_mk)) / r_mk²| + a_min;
//! * eqs. (9)–(11): Σ_k C_jk X_k = D_e with C_jk = exp(−a_dk ρ_jk² − a_i h_j), X_k = D_dk.
//!
//! Choices the paper leaves open, made here:
//! * "Surrounding" nodes: the ring of 8 neighbours on a regular net; the 8 nearest
//!   nodes on a scattered net. h_mk is their mean height, r_mk their mean distance
//!   in the (u, v) plane; log is natural.
//! * Peripheral nodes (the rim of a regular net, the convex hull of a scattered one)
//!   carry no charge, so the surface passes through the interior nodes only.
//! * With a uniform base density D₀ (default 0) the right-hand side becomes
//!   D_e − D₀ e^{−a_i h_j}. Each row j is scaled by e^{a_i h_j} before solving
//!   (the same solution; the reported condition is of the scaled system).
//! * a_min defaults to 1/r̄², r̄ the mean neighbour distance of the net.
//! * Bad nets are refused: h ≤ 0 (eq. 8 takes ln h), nodes closer than 1e-9 of the
//!   net's size in (u, v), no interior node, a singular system (1-norm condition
//!   estimate above 1e14). Eq. (8) is a heuristic: between nodes the surface may
//!   leave the nodes' height range or drop below the reference plane (a hole in the
//!   solid). That is reported ([`InverseReport::min_height`], `below_plane`), not refused.

use super::distribution::{Charge, Distribution};
use super::error::{DsmError, finite, positive};
use super::surface::EqualDensitySurface;
use faer::Mat;
use faer::prelude::Solve;
use glam::{DVec2, DVec3};

/// A passing-points net: nodes (u, v, h) over a reference plane.
#[derive(Clone, Debug, PartialEq)]
pub struct PassingPointsNet {
    nodes: Vec<DVec3>,
    peripheral: Vec<bool>,
    neighbours: Vec<Vec<usize>>,
}

/// Parameters of the inverse transformation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseOptions {
    /// Reducing factor a_i of the plane-based primitive.
    pub reducing: f64,
    /// a_min of eq. (8).
    pub a_min: f64,
    /// D_e.
    pub de: f64,
    /// Uniform base density D₀ of the distribution.
    pub base: f64,
    /// Culling threshold of the charges (relative to D_e).
    pub tau: f64,
}

/// What the inverse transformation found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseReport {
    /// Number of point charges (interior nodes).
    pub charges: usize,
    /// 1-norm condition estimate (Hager) of the row-scaled system.
    pub condition: f64,
    /// max |h(u_j, v_j) − h_j| over the charged nodes.
    pub max_residual: f64,
    /// Smallest h sampled on a grid of twice the node density (per side) over the net's (u, v) box
    /// (−∞ where D ≤ 0).
    pub min_height: f64,
    /// Largest h sampled there.
    pub max_height: f64,
    /// Whether the surface drops to or below the reference plane inside the net's box.
    pub below_plane: bool,
}

impl PassingPointsNet {
    /// A regular nu × nv net (nu, nv ≥ 3) at origin + (i·du, j·dv), heights row by row
    /// (index j·nu + i).
    pub fn regular(
        origin: DVec2,
        spacing: DVec2,
        nu: usize,
        nv: usize,
        heights: &[f64],
    ) -> Result<Self, DsmError> {
        if nu < 3 || nv < 3 {
            return Err(DsmError::DegenerateNet(
                "a regular net needs at least 3 × 3 nodes",
            ));
        }
        if heights.len() != nu * nv {
            return Err(DsmError::DegenerateNet("heights must have nu × nv entries"));
        }
        positive("net spacing u", spacing.x)?;
        positive("net spacing v", spacing.y)?;
        finite("net origin u", origin.x)?;
        finite("net origin v", origin.y)?;
        let mut nodes = Vec::with_capacity(nu * nv);
        let mut peripheral = Vec::with_capacity(nu * nv);
        let mut neighbours = Vec::with_capacity(nu * nv);
        for j in 0..nv {
            for i in 0..nu {
                let p = origin + spacing * DVec2::new(i as f64, j as f64);
                nodes.push(DVec3::new(p.x, p.y, heights[j * nu + i]));
                peripheral.push(i == 0 || j == 0 || i == nu - 1 || j == nv - 1);
                let mut n = Vec::with_capacity(8);
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (a, b) = (i as i64 + di, j as i64 + dj);
                        if (di, dj) != (0, 0) && a >= 0 && b >= 0 && a < nu as i64 && b < nv as i64
                        {
                            n.push(b as usize * nu + a as usize);
                        }
                    }
                }
                neighbours.push(n);
            }
        }
        let net = Self {
            nodes,
            peripheral,
            neighbours,
        };
        net.validate()?;
        Ok(net)
    }

    /// A scattered net: peripheral nodes are those on the convex hull of the (u, v)
    /// positions; each node's surrounding nodes are its 8 nearest.
    pub fn scattered(nodes: Vec<DVec3>) -> Result<Self, DsmError> {
        if nodes.len() < 4 {
            return Err(DsmError::DegenerateNet(
                "a scattered net needs at least 4 nodes",
            ));
        }
        let mut net = Self {
            peripheral: vec![false; nodes.len()],
            neighbours: Vec::new(),
            nodes,
        };
        net.validate()?;
        let size = net.size();
        let uv: Vec<DVec2> = net.nodes.iter().map(|n| DVec2::new(n.x, n.y)).collect();
        // Convex hull (Andrew's monotone chain), then every node within 1e-12·size of
        // a hull edge is peripheral.
        let mut idx: Vec<usize> = (0..uv.len()).collect();
        idx.sort_by(|&a, &b| {
            uv[a]
                .x
                .total_cmp(&uv[b].x)
                .then(uv[a].y.total_cmp(&uv[b].y))
        });
        let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
        let mut hull: Vec<usize> = Vec::new();
        for pass in 0..2 {
            let start = hull.len();
            let order: Vec<usize> = if pass == 0 {
                idx.clone()
            } else {
                idx.iter().rev().copied().collect()
            };
            for &i in &order {
                while hull.len() >= start + 2
                    && cross(uv[hull[hull.len() - 2]], uv[hull[hull.len() - 1]], uv[i]) <= 0.0
                {
                    hull.pop();
                }
                hull.push(i);
            }
            hull.pop();
        }
        if hull.len() < 3 {
            return Err(DsmError::DegenerateNet("the nodes are collinear"));
        }
        for (i, p) in uv.iter().enumerate() {
            for e in 0..hull.len() {
                let (a, b) = (uv[hull[e]], uv[hull[(e + 1) % hull.len()]]);
                let ab = b - a;
                let t = ((*p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                if (a + ab * t - *p).length() <= 1e-12 * size {
                    net.peripheral[i] = true;
                }
            }
        }
        let k = 8.min(uv.len() - 1);
        net.neighbours = (0..uv.len())
            .map(|i| {
                let mut d: Vec<(f64, usize)> = (0..uv.len())
                    .filter(|&j| j != i)
                    .map(|j| ((uv[j] - uv[i]).length_squared(), j))
                    .collect();
                d.sort_by(|a, b| a.0.total_cmp(&b.0));
                d.iter().take(k).map(|x| x.1).collect()
            })
            .collect();
        Ok(net)
    }

    fn validate(&self) -> Result<(), DsmError> {
        for (i, n) in self.nodes.iter().enumerate() {
            finite("node u", n.x)?;
            finite("node v", n.y)?;
            if !(n.z.is_finite() && n.z > 0.0) {
                return Err(DsmError::NonPositiveHeight {
                    node: i,
                    height: n.z,
                });
            }
        }
        let size = self.size();
        for a in 0..self.nodes.len() {
            for b in a + 1..self.nodes.len() {
                let d = (self.nodes[a].truncate() - self.nodes[b].truncate()).length();
                if d <= 1e-9 * size {
                    return Err(DsmError::CoincidentNodes { a, b, distance: d });
                }
            }
        }
        Ok(())
    }

    /// The nodes (u, v, h).
    pub fn nodes(&self) -> &[DVec3] {
        &self.nodes
    }

    /// The surrounding nodes of node i (eq. 8's h_mk and r_mk are over them).
    pub fn neighbours(&self, i: usize) -> &[usize] {
        &self.neighbours[i]
    }

    /// Whether node i is peripheral (carries no charge).
    pub fn is_peripheral(&self, i: usize) -> bool {
        self.peripheral[i]
    }

    /// The net's size: the diagonal of its (u, v, h) bounding box.
    pub fn size(&self) -> f64 {
        let lo = self
            .nodes
            .iter()
            .fold(DVec3::splat(f64::INFINITY), |a, b| a.min(*b));
        let hi = self
            .nodes
            .iter()
            .fold(DVec3::splat(f64::NEG_INFINITY), |a, b| a.max(*b));
        (hi - lo).length()
    }

    /// The (u, v) bounding box (lo, hi).
    pub fn uv_box(&self) -> (DVec2, DVec2) {
        let lo = self
            .nodes
            .iter()
            .fold(DVec2::splat(f64::INFINITY), |a, b| a.min(b.truncate()));
        let hi = self
            .nodes
            .iter()
            .fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(b.truncate()));
        (lo, hi)
    }

    /// Moves node i to height h (a drag); on error nothing changes.
    pub fn set_height(&mut self, i: usize, h: f64) -> Result<(), DsmError> {
        if i >= self.nodes.len() {
            return Err(DsmError::DegenerateNet("no such node"));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(DsmError::NonPositiveHeight { node: i, height: h });
        }
        self.nodes[i].z = h;
        Ok(())
    }

    /// The mean (u, v) distance between a node and its surrounding nodes, over the net.
    pub fn mean_spacing(&self) -> f64 {
        let mut s = 0.0;
        let mut n = 0usize;
        for (i, nb) in self.neighbours.iter().enumerate() {
            for &j in nb {
                s += (self.nodes[i].truncate() - self.nodes[j].truncate()).length();
                n += 1;
            }
        }
        s / n as f64
    }
}

impl InverseOptions {
    /// Defaults for a net: D_e = 1, D₀ = 0, a_min = 1/r̄², τ = 1e-15.
    pub fn for_net(net: &PassingPointsNet, reducing: f64) -> Self {
        Self {
            reducing,
            a_min: 1.0 / net.mean_spacing().powi(2),
            de: 1.0,
            base: 0.0,
            tau: 1e-15,
        }
    }
}

/// Eq. (8)'s reducing factor of node k.
pub fn reducing_factor(net: &PassingPointsNet, k: usize, a_i: f64, a_min: f64) -> f64 {
    let n = &net.nodes;
    let nb = &net.neighbours[k];
    let hm = nb.iter().map(|&j| n[j].z).sum::<f64>() / nb.len() as f64;
    let rm = nb
        .iter()
        .map(|&j| (n[j].truncate() - n[k].truncate()).length())
        .sum::<f64>()
        / nb.len() as f64;
    let hk = n[k].z;
    ((hk / hm).ln() * (a_i * (hk - hm)).exp() / (rm * rm)).abs() + a_min
}

/// Solves eqs. (8)–(11) for the net; returns h(u, v) and a report.
pub fn inverse_transform(
    net: &PassingPointsNet,
    opts: &InverseOptions,
) -> Result<(EqualDensitySurface, InverseReport), DsmError> {
    positive("reducing factor a_i", opts.reducing)?;
    positive("a_min", opts.a_min)?;
    positive("D_e", opts.de)?;
    finite("base density", opts.base)?;
    let interior: Vec<usize> = (0..net.nodes.len())
        .filter(|&i| !net.peripheral[i])
        .collect();
    if interior.is_empty() {
        return Err(DsmError::DegenerateNet(
            "no interior node to carry a charge",
        ));
    }
    let n = interior.len();
    let a_i = opts.reducing;
    let ad: Vec<f64> = interior
        .iter()
        .map(|&k| reducing_factor(net, k, a_i, opts.a_min))
        .collect();
    // Row-scaled eq. (9): Σ_k exp(−a_dk ρ_jk²) X_k = D_e e^{a_i h_j} − D₀.
    let c = Mat::<f64>::from_fn(n, n, |j, k| {
        let (pj, pk) = (net.nodes[interior[j]], net.nodes[interior[k]]);
        (-ad[k] * (pj.truncate() - pk.truncate()).length_squared()).exp()
    });
    let rhs = Mat::<f64>::from_fn(n, 1, |j, _| {
        opts.de * (a_i * net.nodes[interior[j]].z).exp() - opts.base
    });
    let lu = c.partial_piv_lu();
    let x = lu.solve(&rhs);
    let condition = condition_1(&c, &lu);
    if !(condition.is_finite() && condition < 1e14) || (0..n).any(|k| !x[(k, 0)].is_finite()) {
        return Err(DsmError::Singular { condition });
    }
    let charges: Vec<Charge> = (0..n)
        .map(|k| Charge {
            at: net.nodes[interior[k]].truncate(),
            strength: x[(k, 0)],
            reducing: ad[k],
        })
        .collect();
    let distribution = Distribution::new(opts.base, charges, opts.de, opts.tau)?;
    let surface = EqualDensitySurface {
        distribution,
        reducing: a_i,
        de: opts.de,
        connect: None,
    };
    let mut max_residual: f64 = 0.0;
    for &j in &interior {
        let h = surface
            .height(net.nodes[j].truncate())
            .unwrap_or(f64::NEG_INFINITY);
        max_residual = max_residual.max((h - net.nodes[j].z).abs());
    }
    // Sample between the nodes.
    let (lo, hi) = net.uv_box();
    let m = (2.0 * (net.nodes.len() as f64).sqrt()).ceil() as usize;
    let (mut hmin, mut hmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for h in surface.jets_on_grid(lo, hi, m, m) {
        let h = h.map_or(f64::NEG_INFINITY, |j| j.value);
        hmin = hmin.min(h);
        hmax = hmax.max(h);
    }
    let report = InverseReport {
        charges: n,
        condition,
        max_residual,
        min_height: hmin,
        max_height: hmax,
        below_plane: hmin <= 0.0,
    };
    Ok((surface, report))
}

/// Hager's estimate of cond₁(C) = ‖C‖₁ ‖C⁻¹‖₁ from its LU factors.
fn condition_1(c: &Mat<f64>, lu: &faer::linalg::solvers::PartialPivLu<f64>) -> f64 {
    let n = c.nrows();
    let norm = (0..n)
        .map(|k| (0..n).map(|j| c[(j, k)].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut x = Mat::<f64>::from_fn(n, 1, |_, _| 1.0 / n as f64);
    let mut est = 0.0;
    for _ in 0..5 {
        let y = lu.solve(&x);
        est = (0..n).map(|i| y[(i, 0)].abs()).sum::<f64>();
        let xi = Mat::<f64>::from_fn(n, 1, |i, _| if y[(i, 0)] >= 0.0 { 1.0 } else { -1.0 });
        let z = lu.solve_transpose(&xi);
        let (jmax, zmax) = (0..n)
            .map(|i| (i, z[(i, 0)].abs()))
            .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        let ztx: f64 = (0..n).map(|i| z[(i, 0)] * x[(i, 0)]).sum();
        if zmax <= ztx {
            break;
        }
        x = Mat::<f64>::from_fn(n, 1, |i, _| if i == jmax { 1.0 } else { 0.0 });
    }
    if est.is_finite() {
        norm * est
    } else {
        f64::INFINITY
    }
}
