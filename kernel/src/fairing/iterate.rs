//! The iterative scheme (paper 004 §8): only interior points move. A sweep
//! visits them in order (Gauss–Seidel: each uses its neighbours' newest
//! positions) and for each
//!
//! 1. fits local axes to the point and its 1-ring (the normal kept on the
//!    side of the previous one);
//! 2. takes the pseudo-centroid c of the 1-ring (so points do not bunch);
//! 3. fits the 1-ring, in axes at c, by the quadric whose measure at c is
//!    the point's goal ([`goal_height`]);
//! 4. moves the point by ω·(c + f·z − p), f the quadric's height at c.
//!
//! Goals are in mean curvature (the paper's example) or Gaussian
//! curvature: the fit is then the mean-curvature fit whose H meets K with
//! the fit's own anisotropy, to round-off ([`super::gaussian_goal`]; a
//! single linearisation per pass, tried first, left the fixed point off
//! the goal: RMS error 0.19 on the octant, K = 1), after umbilic warm-up
//! sweeps. Principal-curvature goals are refused.
//!
//! The run converges when a sweep moves no point by more than `tolerance`
//! times the mesh's size (bounding-box diagonal); every sweep is reported
//! to a progress callback, which may cancel (the mesh is then restored).
//! Boundary points are never written.

use glam::DVec3;

use super::error::FairingError;
use super::local_axes::{LocalAxes, fit_axes, pseudo_centroid};
use super::mesh::PointMesh;
use super::quadric::{Measure, goal_height, measure_goal_weights};

/// How to fair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FairingOptions {
    /// The measure the goals are in ([`Measure::Mean`] or
    /// [`Measure::Gaussian`]).
    pub measure: Measure,
    /// Relaxation ω in (0, 2): 1 moves each point to its target.
    pub relaxation: f64,
    /// Convergence: the largest move of a sweep, relative to the size.
    pub tolerance: f64,
    /// Sweeps at most.
    pub max_iterations: usize,
}

impl Default for FairingOptions {
    fn default() -> Self {
        Self {
            measure: Measure::Mean,
            relaxation: 1.0,
            tolerance: 1e-10,
            max_iterations: 20_000,
        }
    }
}

/// A sweep's report to the progress callback.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Sweeps done.
    pub iteration: usize,
    /// The largest move of the last sweep (model units).
    pub max_move: f64,
    /// The move below which the run has converged (model units).
    pub threshold: f64,
}

/// What the callback wants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// Stop and restore the mesh.
    Cancel,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct FairingReport {
    /// Sweeps done.
    pub iterations: usize,
    /// Whether the last sweep moved less than the threshold.
    pub converged: bool,
    /// The largest move of each sweep.
    pub history: Vec<f64>,
}

/// Fairs `mesh` toward `goals` (one per point; boundary entries unused).
pub fn fair(
    mesh: &mut PointMesh,
    goals: &[f64],
    options: &FairingOptions,
    mut progress: impl FnMut(&Progress) -> Control,
) -> Result<FairingReport, FairingError> {
    validate(mesh, goals, options)?;
    let threshold = options.tolerance * size(mesh);
    let original = mesh.points.clone();
    let mut normals = mesh.triangle_normals();
    let mut local = Vec::with_capacity(16);
    let mut alpha = Vec::with_capacity(16);
    let mut history = Vec::new();
    // Gaussian goals start with umbilic sweeps (`gaussian_goal`).
    let mut warm_up = options.measure == Measure::Gaussian;
    let warm_move = super::gaussian_goal::WARM_UP_MOVE * size(mesh);
    let mut converged = false;
    for iteration in 1..=options.max_iterations {
        let mut max_move = 0.0f64;
        for i in 0..mesh.len() {
            if mesh.boundary[i] {
                continue;
            }
            let ring = mesh.ring1(i);
            let pts = ring.iter().map(|&j| mesh.points[j as usize]);
            let axes = fit_axes(
                mesh.points[i],
                pts.clone().chain(std::iter::once(mesh.points[i])),
                normals[i],
            );
            normals[i] = axes.z;
            let c = pseudo_centroid(pts.clone());
            let at_c = LocalAxes { origin: c, ..axes };
            local.clear();
            local.extend(pts.map(|p| at_c.local(p)));
            let f = match options.measure {
                Measure::Mean => goal_height(&local, goals[i]),
                m => measure_goal_weights(m, &local, goals[i], warm_up, &mut alpha)
                    .map(|beta| beta + alpha.iter().zip(&local).map(|(a, q)| a * q.z).sum::<f64>()),
            };
            let Some(f) = f else {
                let neighbours = ring.len();
                mesh.points = original;
                return Err(FairingError::TooFewNeighbours {
                    point: i,
                    neighbours,
                    needed: 4,
                });
            };
            let target = c + axes.z * f;
            let step = (target - mesh.points[i]) * options.relaxation;
            max_move = max_move.max(step.length());
            mesh.points[i] += step;
        }
        history.push(max_move);
        if !max_move.is_finite() {
            mesh.points = original;
            return Err(FairingError::Solve(format!(
                "fairing diverged at sweep {iteration}"
            )));
        }
        let p = Progress {
            iteration,
            max_move,
            threshold,
        };
        if progress(&p) == Control::Cancel {
            mesh.points = original;
            return Err(FairingError::Cancelled {
                iterations: iteration,
            });
        }
        if warm_up && max_move <= warm_move {
            warm_up = false;
            continue;
        }
        if max_move <= threshold {
            converged = true;
            break;
        }
    }
    Ok(FairingReport {
        iterations: history.len(),
        converged,
        history,
    })
}

/// The baseline: uniform Laplacian smoothing (each interior point to the
/// mean of its 1-ring, Gauss–Seidel), to the same convergence rule.
pub fn laplacian_smooth(
    mesh: &mut PointMesh,
    tolerance: f64,
    max_iterations: usize,
) -> FairingReport {
    let (lo, hi) = mesh.points.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let threshold = tolerance * (hi - lo).length();
    let mut history = Vec::new();
    let mut converged = false;
    for _ in 0..max_iterations {
        let mut max_move = 0.0f64;
        for i in 0..mesh.len() {
            if mesh.boundary[i] {
                continue;
            }
            let c = pseudo_centroid(mesh.ring1(i).iter().map(|&j| mesh.points[j as usize]));
            max_move = max_move.max((c - mesh.points[i]).length());
            mesh.points[i] = c;
        }
        history.push(max_move);
        if max_move <= threshold {
            converged = true;
            break;
        }
    }
    FairingReport {
        iterations: history.len(),
        converged,
        history,
    }
}

/// Checks goals, options and neighbourhoods before a run.
pub(crate) fn validate(
    mesh: &PointMesh,
    goals: &[f64],
    options: &FairingOptions,
) -> Result<(), FairingError> {
    if goals.len() != mesh.len() || goals.iter().any(|g| !g.is_finite()) {
        return Err(FairingError::BadValue(format!(
            "{} goals for {} points (all finite)",
            goals.len(),
            mesh.len()
        )));
    }
    if !matches!(options.measure, Measure::Mean | Measure::Gaussian) {
        return Err(FairingError::BadValue(format!(
            "fairing goals must be in mean or Gaussian curvature, not {:?}",
            options.measure
        )));
    }
    if !(options.relaxation > 0.0 && options.relaxation < 2.0) {
        return Err(FairingError::BadValue(format!(
            "relaxation {}",
            options.relaxation
        )));
    }
    if !(options.tolerance > 0.0 && options.tolerance.is_finite()) {
        return Err(FairingError::BadValue(format!(
            "tolerance {}",
            options.tolerance
        )));
    }
    for i in 0..mesh.len() {
        if !mesh.boundary[i] && mesh.ring1(i).len() < 4 {
            return Err(FairingError::TooFewNeighbours {
                point: i,
                neighbours: mesh.ring1(i).len(),
                needed: 4,
            });
        }
    }
    Ok(())
}

/// The mesh's size: its bounding box's diagonal.
pub(crate) fn size(mesh: &PointMesh) -> f64 {
    let (lo, hi) = mesh.points.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    (hi - lo).length()
}
