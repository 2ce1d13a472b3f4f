//! Refitting (paper 004 §3): a bicubic B-spline surface fitted by least
//! squares to faired points at given parameters (for a patch's samples,
//! its domain coordinates mapped from [−1, 1]² to [0, 1]²: the surface
//! spans the domain's square and the patch is its n-gon part).
//!
//! Minimises Σ |S(u_k, v_k) − p_k|² + λ Σ |Δ²P|² over the control points,
//! the second term the squared second differences of the control net in u,
//! v and the mixed direction, with λ = `smoothing` × the mean diagonal of
//! the data term: it fixes the control points no sample constrains (outside
//! the n-gon) and keeps the net fair. The normal equations are solved by
//! sparse Cholesky (faer). The net starts at 4 × 4 and doubles its spans
//! until the largest distance from a point to its surface point is within
//! `tolerance` ([`FairingError::RefitTolerance`] past `max_ctrl`).

use glam::{DVec2, DVec3};

use super::error::FairingError;
use super::sparse::solve_spd;
use crate::bspline::{BSplineSurface, BasisDerivs, KnotVector, basis_derivs_into};

/// How to refit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefitOptions {
    /// The largest allowed distance from a point to its surface point.
    pub tolerance: f64,
    /// The most control points per direction.
    pub max_ctrl: usize,
    /// The fairness weight relative to the data term.
    pub smoothing: f64,
}

impl Default for RefitOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-4,
            max_ctrl: 67,
            smoothing: 1e-7,
        }
    }
}

/// A refitted surface and how well it fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Refit {
    /// The surface (bicubic, clamped uniform knots over [0, 1]²).
    pub surface: BSplineSurface,
    /// The largest distance |S(u_k, v_k) − p_k|.
    pub max_deviation: f64,
    /// The RMS distance.
    pub rms_deviation: f64,
}

/// Fits `points` at parameters `params` (in [0, 1]²).
pub fn refit(
    points: &[DVec3],
    params: &[DVec2],
    options: &RefitOptions,
) -> Result<Refit, FairingError> {
    if points.len() != params.len() || points.len() < 16 {
        return Err(FairingError::BadValue(format!(
            "{} points and {} parameters (need equal, at least 16)",
            points.len(),
            params.len()
        )));
    }
    if params
        .iter()
        .any(|p| !p.is_finite() || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0)
        || points.iter().any(|p| !p.is_finite())
    {
        return Err(FairingError::BadValue(
            "parameters must be in [0, 1]², points finite".into(),
        ));
    }
    if !(options.tolerance > 0.0 && options.smoothing >= 0.0) {
        return Err(FairingError::BadValue(
            "tolerance > 0, smoothing ≥ 0".into(),
        ));
    }
    let mut n = 4;
    loop {
        let fit = fit_once(points, params, n, options.smoothing)?;
        if fit.max_deviation <= options.tolerance {
            return Ok(fit);
        }
        let next = 2 * n - 3;
        if next > options.max_ctrl {
            return Err(FairingError::RefitTolerance {
                deviation: fit.max_deviation,
                tolerance: options.tolerance,
                nu: n,
                nv: n,
            });
        }
        n = next;
    }
}

fn fit_once(
    points: &[DVec3],
    params: &[DVec2],
    n: usize,
    smoothing: f64,
) -> Result<Refit, FairingError> {
    let kv =
        KnotVector::clamped_uniform(3, n).map_err(|e| FairingError::BadValue(e.to_string()))?;
    let dim = n * n;
    let mut dense_rows: Vec<(usize, usize, f64)> = Vec::new();
    let mut rhs = vec![vec![0.0; dim]; 3];
    let (mut bu, mut bv) = (BasisDerivs::default(), BasisDerivs::default());
    let mut diag = vec![0.0; dim];
    let mut idx = [0usize; 16];
    let mut w = [0.0; 16];
    for (p, uv) in points.iter().zip(params) {
        basis_derivs_into(&kv, uv.x, 0, &mut bu);
        basis_derivs_into(&kv, uv.y, 0, &mut bv);
        for a in 0..4 {
            for b in 0..4 {
                idx[a * 4 + b] = (bu.first + a) * n + bv.first + b;
                w[a * 4 + b] = bu.get(0, a) * bv.get(0, b);
            }
        }
        for r in 0..16 {
            rhs[0][idx[r]] += w[r] * p.x;
            rhs[1][idx[r]] += w[r] * p.y;
            rhs[2][idx[r]] += w[r] * p.z;
            diag[idx[r]] += w[r] * w[r];
            for c in 0..16 {
                if idx[c] <= idx[r] {
                    dense_rows.push((idx[r], idx[c], w[r] * w[c]));
                }
            }
        }
    }
    let mean_diag = diag.iter().sum::<f64>() / dim as f64;
    let lambda = smoothing * mean_diag.max(1e-300);
    // Second differences of the net: along u, along v, mixed.
    let at = |i: usize, j: usize| i * n + j;
    let mut stencils: Vec<Vec<(usize, f64)>> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            if i + 2 < n {
                stencils.push(vec![
                    (at(i, j), 1.0),
                    (at(i + 1, j), -2.0),
                    (at(i + 2, j), 1.0),
                ]);
            }
            if j + 2 < n {
                stencils.push(vec![
                    (at(i, j), 1.0),
                    (at(i, j + 1), -2.0),
                    (at(i, j + 2), 1.0),
                ]);
            }
            if i + 1 < n && j + 1 < n {
                let s = std::f64::consts::SQRT_2;
                stencils.push(vec![
                    (at(i, j), s),
                    (at(i + 1, j), -s),
                    (at(i, j + 1), -s),
                    (at(i + 1, j + 1), s),
                ]);
            }
        }
    }
    for st in &stencils {
        for &(r, wr) in st {
            for &(c, wc) in st {
                if c <= r {
                    dense_rows.push((r, c, lambda * wr * wc));
                }
            }
        }
    }
    // A tiny ridge keeps the system definite when smoothing is 0.
    for k in 0..dim {
        dense_rows.push((k, k, 1e-14 * mean_diag));
    }
    let x = solve_spd(dim, &dense_rows, &rhs)?;
    let ctrl: Vec<DVec3> = (0..dim)
        .map(|k| DVec3::new(x[0][k], x[1][k], x[2][k]))
        .collect();
    let surface = BSplineSurface::new(kv.clone(), kv, ctrl)
        .map_err(|e| FairingError::BadValue(e.to_string()))?;
    let (mut max, mut sum) = (0.0f64, 0.0);
    for (p, uv) in points.iter().zip(params) {
        let d = (surface.point(uv.x, uv.y) - *p).length();
        max = max.max(d);
        sum += d * d;
    }
    Ok(Refit {
        surface,
        max_deviation: max,
        rms_deviation: (sum / points.len() as f64).sqrt(),
    })
}
