//! Fairness measures over a point mesh (paper 004 §4): curvature at every
//! point by a local quadric fit, its variation (the RMS over the 1-ring of
//! the measure's difference quotient |μ_j − μ_i| / |p_j − p_i|), and a
//! summary against per-point goals.

use glam::DVec3;

use super::error::FairingError;
use super::local_axes::fit_axes;
use super::mesh::PointMesh;
use super::quadric::{Curvatures, Measure, curvatures};

/// Which neighbours a curvature estimate uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Neighbourhood {
    /// The points sharing an edge.
    Ring1,
    /// The points within two edges, fitted with the cubic terms too (the
    /// default: chosen by measurement, `tests/fairing_curvature.rs`).
    Ring2,
}

/// Curvatures at every point (normals oriented like the mesh's triangles).
/// A point whose 1-ring has fewer than 5 points uses its 2-ring.
pub fn estimate(mesh: &PointMesh, hood: Neighbourhood) -> Result<Vec<Curvatures>, FairingError> {
    let tri_normals = mesh.triangle_normals();
    (0..mesh.len())
        .map(|i| {
            // A point with too small a 1-ring (a corner) uses its 2-ring.
            let ring = match hood {
                Neighbourhood::Ring1 if mesh.ring1(i).len() >= 5 => mesh.ring1(i),
                _ => mesh.ring2(i),
            };
            let pts = ring.iter().map(|&j| mesh.points[j as usize]);
            let axes = fit_axes(
                mesh.points[i],
                pts.clone().chain(std::iter::once(mesh.points[i])),
                tri_normals[i],
            );
            curvatures(&axes, pts, hood == Neighbourhood::Ring2).ok_or(
                FairingError::TooFewNeighbours {
                    point: i,
                    neighbours: ring.len(),
                    needed: 5,
                },
            )
        })
        .collect()
}

/// The variation of `values` at every point: RMS over its 1-ring of
/// (μ_j − μ_i) / |p_j − p_i|.
pub fn variation(mesh: &PointMesh, values: &[f64]) -> Vec<f64> {
    (0..mesh.len())
        .map(|i| {
            let ring = mesh.ring1(i);
            let s: f64 = ring
                .iter()
                .map(|&j| {
                    let j = j as usize;
                    let d = (mesh.points[j] - mesh.points[i]).length().max(1e-300);
                    ((values[j] - values[i]) / d).powi(2)
                })
                .sum();
            (s / ring.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// How fair a mesh is against its goals (interior points only).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Fairness {
    /// max |μ_i − goal_i|.
    pub max_error: f64,
    /// RMS of μ_i − goal_i.
    pub rms_error: f64,
    /// Largest variation of μ.
    pub max_variation: f64,
    /// RMS variation of μ.
    pub rms_variation: f64,
}

/// The fairness of `mesh` in `measure` against `goals` (one per point).
pub fn fairness(
    mesh: &PointMesh,
    measure: Measure,
    goals: &[f64],
    hood: Neighbourhood,
) -> Result<Fairness, FairingError> {
    let c = estimate(mesh, hood)?;
    let mu: Vec<f64> = c.iter().map(|k| k.get(measure)).collect();
    let var = variation(mesh, &mu);
    let mut out = Fairness::default();
    let mut n = 0usize;
    let (mut se, mut sv) = (0.0, 0.0);
    for i in 0..mesh.len() {
        if mesh.boundary[i] {
            continue;
        }
        let e = (mu[i] - goals[i]).abs();
        out.max_error = out.max_error.max(e);
        out.max_variation = out.max_variation.max(var[i]);
        se += e * e;
        sv += var[i] * var[i];
        n += 1;
    }
    out.rms_error = (se / n.max(1) as f64).sqrt();
    out.rms_variation = (sv / n.max(1) as f64).sqrt();
    Ok(out)
}

/// The unit normals of the curvature fits.
pub fn normals(c: &[Curvatures]) -> Vec<DVec3> {
    c.iter().map(|k| k.normal).collect()
}
