//! Fairing toward Gaussian-curvature goals, against surfaces that know the
//! answer: the paper's octant of the unit sphere (325 points), perturbed,
//! faired to K = 1 converges to the sphere; a quarter of a unit cylinder,
//! perturbed, faired to K = 0 converges to the cylinder (the convex
//! developable through its boundary). Both with the global sweeps and the
//! boundary untouched; the faired meshes' estimated K (2-ring cubic fits,
//! independent of the fairing's 1-ring quadrics) is the goal.

use glam::DVec3;
use vsculpt_kernel::fairing::{
    Control, FairingOptions, Goals, Measure, Neighbourhood, PointMesh, fair, fair_implicit,
    fairness, resolve,
};

mod fairing_support;
use fairing_support::{octant, perturb};

/// A quarter of the unit cylinder x² + y² = 1, θ ∈ [0, π/2], z ∈ [0, 1.5],
/// as an (m + 1) × (m + 1) lattice of right triangles, normals outward.
fn cylinder(m: usize) -> PointMesh {
    let mut points = Vec::new();
    let mut boundary = Vec::new();
    for i in 0..=m {
        for j in 0..=m {
            let theta = std::f64::consts::FRAC_PI_2 * i as f64 / m as f64;
            let z = 1.5 * j as f64 / m as f64;
            points.push(DVec3::new(theta.cos(), theta.sin(), z));
            boundary.push(i == 0 || j == 0 || i == m || j == m);
        }
    }
    let id = |i: usize, j: usize| (i * (m + 1) + j) as u32;
    let mut tris = Vec::new();
    for i in 0..m {
        for j in 0..m {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    PointMesh::new(points, tris, boundary).unwrap()
}

fn options() -> FairingOptions {
    FairingOptions {
        measure: Measure::Gaussian,
        max_iterations: 2000,
        ..FairingOptions::default()
    }
}

fn boundary_of(mesh: &PointMesh) -> Vec<DVec3> {
    (0..mesh.len())
        .filter(|&i| mesh.boundary[i])
        .map(|i| mesh.points[i])
        .collect()
}

#[test]
fn octant_faired_to_gaussian_curvature_one_is_the_sphere() {
    let mut mesh = octant(24);
    assert!(mesh.triangle_normal(100).dot(mesh.points[100]) > 0.9);
    perturb(&mut mesh, 0.03, 11);
    let start = mesh.clone();
    let dist = |m: &PointMesh| {
        m.points
            .iter()
            .map(|p| (p.length() - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let goals = resolve(&mesh, Measure::Gaussian, &Goals::Constant(1.0)).unwrap();
    let before = fairness(&mesh, Measure::Gaussian, &goals, Neighbourhood::Ring2).unwrap();
    let report = fair_implicit(&mut mesh, &goals, &options(), |_| Control::Continue).unwrap();
    let after = fairness(&mesh, Measure::Gaussian, &goals, Neighbourhood::Ring2).unwrap();
    let exact = fairness(&octant(24), Measure::Gaussian, &goals, Neighbourhood::Ring2).unwrap();
    println!(
        "octant 325 points, K = 1, global sweeps: distance to sphere {:.3e} → {:.3e}; K error max {:.3e} → {:.3e} (rms {:.3e}; the exact octant's own: max {:.3e}); {} sweeps, converged {}",
        dist(&start),
        dist(&mesh),
        before.max_error,
        after.max_error,
        after.rms_error,
        exact.max_error,
        report.iterations,
        report.converged
    );
    assert!(report.converged);
    assert!(dist(&mesh) < 2e-3, "{:.3e} from the sphere", dist(&mesh));
    assert!(after.max_error < 3e-2, "{after:?}");
    assert_eq!(boundary_of(&mesh), boundary_of(&start), "boundary moved");

    // The point-by-point sweeps reach the same surface.
    let mut local = start.clone();
    let r = fair(&mut local, &goals, &options(), |_| Control::Continue).unwrap();
    let apart = local
        .points
        .iter()
        .zip(&mesh.points)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
    println!(
        "  local sweeps: {} sweeps, converged {}, {apart:.2e} from the global run",
        r.iterations, r.converged
    );
    assert!(r.converged);
    assert!(apart < 1e-6, "{apart:.2e}");
}

#[test]
fn cylinder_patch_faired_to_gaussian_curvature_zero_is_the_cylinder() {
    let mut mesh = cylinder(16);
    assert!(mesh.triangle_normal(100).dot(DVec3::new(1.0, 1.0, 0.0)) > 0.0);
    perturb(&mut mesh, 0.02, 7);
    let start = mesh.clone();
    let dist = |m: &PointMesh| {
        m.points
            .iter()
            .map(|p| (p.truncate().length() - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let goals = vec![0.0; mesh.len()];
    let before = fairness(&mesh, Measure::Gaussian, &goals, Neighbourhood::Ring2).unwrap();
    let report = fair_implicit(&mut mesh, &goals, &options(), |_| Control::Continue).unwrap();
    let after = fairness(&mesh, Measure::Gaussian, &goals, Neighbourhood::Ring2).unwrap();
    println!(
        "cylinder quarter 17 × 17, K = 0: distance to cylinder {:.3e} → {:.3e}; K error max {:.3e} → {:.3e} (rms {:.3e}); {} sweeps, converged {}",
        dist(&start),
        dist(&mesh),
        before.max_error,
        after.max_error,
        after.rms_error,
        report.iterations,
        report.converged
    );
    assert!(report.converged);
    assert!(dist(&mesh) < 2e-3, "{:.3e} from the cylinder", dist(&mesh));
    assert!(after.max_error < 3e-2, "{after:?}");
    assert_eq!(boundary_of(&mesh), boundary_of(&start), "boundary moved");
}

#[test]
fn principal_curvature_goals_are_refused_and_change_nothing() {
    let mut mesh = octant(8);
    let before = mesh.clone();
    for measure in [Measure::MaxPrincipal, Measure::MinPrincipal] {
        let o = FairingOptions {
            measure,
            ..FairingOptions::default()
        };
        let goals = vec![1.0; mesh.len()];
        assert!(fair_implicit(&mut mesh, &goals, &o, |_| Control::Continue).is_err());
        assert!(fair(&mut mesh, &goals, &o, |_| Control::Continue).is_err());
    }
    assert_eq!(mesh, before);
}
