//! The iterative scheme with each sweep solved globally: the same
//! equations as [`super::iterate::fair`] — every interior point on the
//! normal line through its pseudo-centroid (two tangential equations) at
//! the height of its 1-ring's goal-constrained quadric (one normal
//! equation) — but with the frames, the fits' weights and the tangential
//! coordinates frozen at the current positions, the equations are linear
//! in the new positions and are solved for all points at once (sparse LU,
//! faer). The frames are then refitted and the solve repeated until no
//! point moves more than the threshold. A local sweep only spreads a
//! correction one ring per pass, so it needs O(n) sweeps on an n × n
//! mesh; the global solve needs a handful. Same fixed point, same
//! options, progress, cancellation and untouched boundary.
//!
//! The normal equation: the constrained fit's height at the centroid is
//! linear in the neighbours' heights, f = Σ_j α_j z_j + β (α, β from one
//! 7 × 7 KKT solve with the unit vector e_f), so
//! n·q_i − Σ_j (α_j + (1 − Σα)/m) n·q_j = β.
//!
//! The equations' sparsity pattern (the 1-rings) never changes, so the
//! pattern and the order of the entries in it are computed in the first
//! sweep and every later sweep only refills the values; the solve is a
//! Laplacian-preconditioned BiCGSTAB warm-started from the current points
//! ([`super::sweep_solver`]), or a sparse LU with its symbolic
//! factorisation kept ([`SweepSolve::Direct`]).
//!
//! The sweeps are stepped by Anderson acceleration by default
//! ([`super::anderson`]): same fixed point, fewer sweeps; plain steps
//! (x ← x + ω f) with [`Acceleration::Plain`].

use glam::DVec3;

use super::anderson::{Acceleration, Anderson};
use super::error::FairingError;
use super::iterate::{Control, FairingOptions, FairingReport, Progress};
use super::local_axes::{LocalAxes, fit_axes, pseudo_centroid};
use super::mesh::PointMesh;
use super::quadric::{Measure, measure_goal_weights};
use super::sweep_solver::{SweepSolve, SweepSolver};

/// Fairs `mesh` toward `goals` (one per point, in `options.measure`: mean
/// or Gaussian curvature) by global sweeps (each solved iteratively, see [`super::sweep_solver`]).
pub fn fair_implicit(
    mesh: &mut PointMesh,
    goals: &[f64],
    options: &FairingOptions,
    progress: impl FnMut(&Progress) -> Control,
) -> Result<FairingReport, FairingError> {
    fair_implicit_with(mesh, goals, options, SweepSolve::Iterative, progress)
}

/// [`fair_implicit`] with the sweeps' linear solves made by `solve`
/// (the same sweeps to round-off either way).
pub fn fair_implicit_with(
    mesh: &mut PointMesh,
    goals: &[f64],
    options: &FairingOptions,
    solve: SweepSolve,
    progress: impl FnMut(&Progress) -> Control,
) -> Result<FairingReport, FairingError> {
    fair_sweeps(
        mesh,
        goals,
        options,
        solve,
        Acceleration::default(),
        progress,
    )
}

/// The global sweeps with their linear solves made by `solve` and their
/// steps taken by `acceleration` (every choice has the same fixed point;
/// the report's history is the plain residual's largest move per sweep).
/// Acceleration applies to undamped runs (relaxation 1, the default); a
/// run with another relaxation takes the damped plain steps it asks for.
pub fn fair_sweeps(
    mesh: &mut PointMesh,
    goals: &[f64],
    options: &FairingOptions,
    solve: SweepSolve,
    acceleration: Acceleration,
    mut progress: impl FnMut(&Progress) -> Control,
) -> Result<FairingReport, FairingError> {
    super::iterate::validate(mesh, goals, options)?;
    let threshold = options.tolerance * super::iterate::size(mesh);
    let interior: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.boundary[i]).collect();
    let mut index = vec![usize::MAX; mesh.len()];
    for (k, &i) in interior.iter().enumerate() {
        index[i] = k;
    }
    let original = mesh.points.clone();
    let mut normals = mesh.triangle_normals();
    let mut history = Vec::new();
    let mut converged = false;
    let dim = 3 * interior.len();
    let rings: Vec<Vec<usize>> = interior
        .iter()
        .map(|&i| {
            mesh.ring1(i)
                .iter()
                .filter(|&&j| !mesh.boundary[j as usize])
                .map(|&j| index[j as usize])
                .collect()
        })
        .collect();
    let degree = interior
        .iter()
        .map(|&i| mesh.ring1(i).len() as f64)
        .collect();
    let mut solver = SweepSolver::new(solve, &rings, degree)?;
    let mut values: Vec<f64> = Vec::new();
    let mut frames = vec![[DVec3::ZERO; 3]; interior.len()];
    let mut rhs = faer::Mat::<f64>::zeros(dim, 1);
    let mut x = faer::Mat::<f64>::zeros(dim, 1);
    let mut local = Vec::new();
    let mut alpha = Vec::new();
    // A relaxation other than 1 asks for damped plain steps (a slow run
    // on purpose): it is taken as asked.
    let mut stepper = Anderson::new(match acceleration {
        Acceleration::Anderson(m) if options.relaxation == 1.0 => m,
        _ => 0,
    });
    // Gaussian goals start with umbilic sweeps (`gaussian_goal`).
    let mut warm_up = options.measure == Measure::Gaussian;
    let warm_move = super::gaussian_goal::WARM_UP_MOVE * super::iterate::size(mesh);
    let mut current = vec![0.0; dim];
    let mut residual = vec![0.0; dim];
    for iteration in 1..=options.max_iterations {
        let first = solver.needs_pattern();
        values.clear();
        for (k, &i) in interior.iter().enumerate() {
            let ring = mesh.ring1(i);
            let m = ring.len() as f64;
            let pts = ring.iter().map(|&j| mesh.points[j as usize]);
            let axes = fit_axes(
                mesh.points[i],
                pts.clone().chain(std::iter::once(mesh.points[i])),
                normals[i],
            );
            normals[i] = axes.z;
            frames[k] = [axes.x, axes.y, axes.z];
            let c = pseudo_centroid(pts.clone());
            let at_c = LocalAxes { origin: c, ..axes };
            local.clear();
            local.extend(pts.map(|p| at_c.local(p)));
            let Some(beta) =
                measure_goal_weights(options.measure, &local, goals[i], warm_up, &mut alpha)
            else {
                let neighbours = ring.len();
                mesh.points = original;
                return Err(FairingError::TooFewNeighbours {
                    point: i,
                    neighbours,
                    needed: 4,
                });
            };
            let s: f64 = alpha.iter().sum();
            let rows = [(axes.x, 0.0), (axes.y, 0.0), (axes.z, beta)];
            for (a, (dir, b)) in rows.iter().enumerate() {
                let r = 3 * k + a;
                let mut value = *b;
                for c in 0..3 {
                    if first {
                        solver.push_pair(r, 3 * k + c);
                    }
                    values.push(dir[c]);
                }
                for (jj, &j) in ring.iter().enumerate() {
                    let j = j as usize;
                    let w = if a == 2 {
                        alpha[jj] + (1.0 - s) / m
                    } else {
                        1.0 / m
                    };
                    if mesh.boundary[j] {
                        value += w * dir.dot(mesh.points[j]);
                    } else {
                        for c in 0..3 {
                            if first {
                                solver.push_pair(r, 3 * index[j] + c);
                            }
                            values.push(-w * dir[c]);
                        }
                    }
                }
                rhs[(r, 0)] = value;
            }
            for c in 0..3 {
                x[(3 * k + c, 0)] = mesh.points[i][c];
            }
        }
        if let Err(e) = solver.solve(&values, &rhs, &frames, &mut x) {
            mesh.points = original;
            return Err(e);
        }
        let mut max_move = 0.0f64;
        for (k, &i) in interior.iter().enumerate() {
            let p = mesh.points[i];
            let q = DVec3::new(x[(3 * k, 0)], x[(3 * k + 1, 0)], x[(3 * k + 2, 0)]);
            max_move = max_move.max((q - p).length());
            for c in 0..3 {
                current[3 * k + c] = p[c];
                residual[3 * k + c] = q[c] - p[c];
            }
        }
        if (max_move <= threshold && !warm_up) || !max_move.is_finite() {
            // The last sweep (or a failed one): the plain step.
            Anderson::new(0).step(&mut current, &residual, options.relaxation);
        } else {
            stepper.step(&mut current, &residual, options.relaxation);
        }
        for (k, &i) in interior.iter().enumerate() {
            mesh.points[i] = DVec3::new(current[3 * k], current[3 * k + 1], current[3 * k + 2]);
        }
        history.push(max_move);
        if !max_move.is_finite() {
            mesh.points = original;
            return Err(FairingError::Solve(format!(
                "diverged at sweep {iteration}"
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
            // The warm-up is over: its history is of another map.
            warm_up = false;
            stepper = Anderson::new(stepper.depth());
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

/// The baseline: uniform Laplacian smoothing solved to its fixed point in
/// one sparse solve (each interior point the mean of its 1-ring).
pub fn laplacian_implicit(mesh: &mut PointMesh) -> Result<(), FairingError> {
    let interior: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.boundary[i]).collect();
    let mut index = vec![usize::MAX; mesh.len()];
    for (k, &i) in interior.iter().enumerate() {
        index[i] = k;
    }
    let n = interior.len();
    let mut lower = Vec::new();
    let mut rhs = vec![vec![0.0; n]; 3];
    for (k, &i) in interior.iter().enumerate() {
        let ring = mesh.ring1(i);
        lower.push((k, k, ring.len() as f64));
        for &j in ring {
            let j = j as usize;
            if mesh.boundary[j] {
                rhs[0][k] += mesh.points[j].x;
                rhs[1][k] += mesh.points[j].y;
                rhs[2][k] += mesh.points[j].z;
            } else if index[j] < k {
                lower.push((k, index[j], -1.0));
            }
        }
    }
    let x = super::sparse::solve_spd(n, &lower, &rhs)?;
    for (k, &i) in interior.iter().enumerate() {
        mesh.points[i] = DVec3::new(x[0][k], x[1][k], x[2][k]);
    }
    Ok(())
}
