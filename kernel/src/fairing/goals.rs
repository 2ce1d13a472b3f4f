//! Goal values of the fairness measure per point (paper 004 §8): given
//! directly (one per point, or one for all), or interpolated from the
//! boundary — the measure is estimated at the boundary points and spread
//! over the interior as the discrete harmonic function with those values
//! (each interior value the mean of its 1-ring), solved by sparse Cholesky.

use super::error::FairingError;
use super::measures::{Neighbourhood, estimate};
use super::mesh::PointMesh;
use super::quadric::Measure;
use super::sparse::solve_spd;

/// Where the goals come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Goals {
    /// The same value everywhere.
    Constant(f64),
    /// One value per point.
    PerPoint(Vec<f64>),
    /// Harmonic interpolation of the boundary's measured values.
    FromBoundary,
}

/// One goal per point.
pub fn resolve(
    mesh: &PointMesh,
    measure: Measure,
    goals: &Goals,
) -> Result<Vec<f64>, FairingError> {
    match goals {
        Goals::Constant(g) if g.is_finite() => Ok(vec![*g; mesh.len()]),
        Goals::Constant(g) => Err(FairingError::BadValue(format!("goal {g}"))),
        Goals::PerPoint(v) => {
            if v.len() != mesh.len() || v.iter().any(|x| !x.is_finite()) {
                return Err(FairingError::BadValue(format!(
                    "{} goals for {} points (all finite)",
                    v.len(),
                    mesh.len()
                )));
            }
            Ok(v.clone())
        }
        Goals::FromBoundary => interpolate_from_boundary(mesh, measure),
    }
}

/// The boundary's measured values interpolated harmonically inside.
pub fn interpolate_from_boundary(
    mesh: &PointMesh,
    measure: Measure,
) -> Result<Vec<f64>, FairingError> {
    let c = estimate(mesh, Neighbourhood::Ring2)?;
    let mut out: Vec<f64> = c.iter().map(|k| k.get(measure)).collect();
    harmonic_fill(mesh, &mut out)?;
    Ok(out)
}

/// Replaces the interior entries of `values` by the harmonic interpolation
/// of the boundary entries.
pub fn harmonic_fill(mesh: &PointMesh, values: &mut [f64]) -> Result<(), FairingError> {
    let interior: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.boundary[i]).collect();
    let mut index = vec![usize::MAX; mesh.len()];
    for (k, &i) in interior.iter().enumerate() {
        index[i] = k;
    }
    let mut lower = Vec::new();
    let mut rhs = vec![0.0; interior.len()];
    for (k, &i) in interior.iter().enumerate() {
        let ring = mesh.ring1(i);
        lower.push((k, k, ring.len() as f64));
        for &j in ring {
            let j = j as usize;
            if mesh.boundary[j] {
                rhs[k] += values[j];
            } else if index[j] < k {
                lower.push((k, index[j], -1.0));
            }
        }
    }
    let x = solve_spd(interior.len(), &lower, &[rhs])?;
    for (k, &i) in interior.iter().enumerate() {
        values[i] = x[0][k];
    }
    Ok(())
}
