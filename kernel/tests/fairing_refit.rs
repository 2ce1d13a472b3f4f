//! Refitting a B-spline surface to faired points: within the stated
//! tolerance at every point (checked by evaluating the returned surface,
//! not by trusting its report), for a 3-sided and a 5-sided patch's
//! samples; a tolerance the net cannot reach is a clear error.

use glam::{DVec2, DVec3};
use vsculpt_kernel::fairing::{
    Control, FairingError, FairingOptions, PointMesh, RefitOptions, fair, refit,
};
use vsculpt_kernel::network::demo::bottle;
use vsculpt_kernel::network::{DomainMesh, Patch};

fn params(patch: &Patch, m: usize) -> Vec<DVec2> {
    DomainMesh::new(patch.domain(), m)
        .points
        .iter()
        .map(|p| (*p + DVec2::ONE) * 0.5)
        .collect()
}

fn check(points: &[DVec3], uv: &[DVec2], tol: f64) -> f64 {
    let fit = refit(
        points,
        uv,
        &RefitOptions {
            tolerance: tol,
            ..RefitOptions::default()
        },
    )
    .unwrap();
    let worst = points
        .iter()
        .zip(uv)
        .map(|(p, q)| (fit.surface.point(q.x, q.y) - *p).length())
        .fold(0.0, f64::max);
    println!(
        "refit: {} × {} control points, max deviation {worst:.2e} (reported {:.2e}), rms {:.2e}",
        fit.surface.nu(),
        fit.surface.nv(),
        fit.max_deviation,
        fit.rms_deviation
    );
    assert!(worst <= tol, "{worst} > {tol}");
    assert!((worst - fit.max_deviation).abs() < 1e-12);
    worst
}

#[test]
fn faired_bottle_faces_refit_within_tolerance() {
    let net = bottle().unwrap();
    for (f, face) in net.faces().iter().enumerate() {
        let patch = net.patch(f).unwrap();
        let m = 12;
        let mut mesh = PointMesh::from_patch(&patch, m).unwrap();
        // Fair toward the mean curvature the boundary suggests.
        let goals = vsculpt_kernel::fairing::resolve(
            &mesh,
            vsculpt_kernel::fairing::Measure::Mean,
            &vsculpt_kernel::fairing::Goals::FromBoundary,
        )
        .unwrap();
        let report = fair(&mut mesh, &goals, &FairingOptions::default(), |_| {
            Control::Continue
        })
        .unwrap();
        println!(
            "bottle face {f} ({} sides): faired in {} sweeps",
            face.sides.len(),
            report.iterations
        );
        check(&mesh.points, &params(&patch, m), 1e-3);
    }
}

#[test]
fn unreachable_tolerance_is_an_error() {
    let net = bottle().unwrap();
    let patch = net.patch(0).unwrap();
    let mesh = PointMesh::from_patch(&patch, 10).unwrap();
    let err = refit(
        &mesh.points,
        &params(&patch, 10),
        &RefitOptions {
            tolerance: 1e-13,
            max_ctrl: 10,
            ..RefitOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, FairingError::RefitTolerance { .. }), "{err}");
    // Bad input.
    assert!(
        refit(
            &mesh.points[..3],
            &params(&patch, 10)[..3],
            &RefitOptions::default()
        )
        .is_err()
    );
    let mut uv = params(&patch, 10);
    uv[0].x = 1.5;
    assert!(refit(&mesh.points, &uv, &RefitOptions::default()).is_err());
}

#[test]
fn a_tensor_product_surface_is_refitted_exactly() {
    // Points on a bicubic polynomial surface are reproduced by the first,
    // 4 × 4, fit when there is no smoothing term.
    let f = |u: f64, v: f64| DVec3::new(u, v, u * u * v - 0.5 * v * v * v + u * v);
    let mut pts = Vec::new();
    let mut uv = Vec::new();
    for i in 0..=20 {
        for j in 0..=20 {
            let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
            pts.push(f(u, v));
            uv.push(DVec2::new(u, v));
        }
    }
    let fit = refit(
        &pts,
        &uv,
        &RefitOptions {
            tolerance: 1e-12,
            smoothing: 0.0,
            ..RefitOptions::default()
        },
    )
    .unwrap();
    assert_eq!((fit.surface.nu(), fit.surface.nv()), (4, 4));
    let worst = pts
        .iter()
        .zip(&uv)
        .map(|(p, q)| (fit.surface.point(q.x, q.y) - *p).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-12, "{worst}");
}
