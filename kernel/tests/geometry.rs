//! Curvature and tessellation against analytic surfaces: B-spline surfaces
//! interpolated through a sphere, a cylinder and the saddle z = xy.

use glam::DVec3;
use vsculpt_kernel::analysis::{
    Tessellation, Tessellator, samples_for, surface_curvature, tessellate,
};
use vsculpt_kernel::bspline::{BSplineSurface, interpolate_surface};

fn fit(m: usize, f: impl Fn(f64, f64) -> DVec3) -> BSplineSurface {
    let pts: Vec<DVec3> = (0..m * m)
        .map(|k| {
            f(
                (k / m) as f64 / (m - 1) as f64,
                (k % m) as f64 / (m - 1) as f64,
            )
        })
        .collect();
    interpolate_surface(&pts, m, m, 3, 3).unwrap()
}

/// Max over interior sample points of |computed − expected| for (H, K, κ1, κ2).
fn curvature_error(s: &BSplineSurface, want: (f64, f64, f64, f64)) -> f64 {
    let mut err = 0.0f64;
    for i in 2..=8 {
        for j in 2..=8 {
            let c = surface_curvature(&s.derivs(i as f64 / 10.0, j as f64 / 10.0)).unwrap();
            for (got, w) in [
                (c.mean, want.0),
                (c.gauss, want.1),
                (c.k1, want.2),
                (c.k2, want.3),
            ] {
                err = err.max((got - w).abs());
            }
        }
    }
    err
}

#[test]
fn sphere_has_h_minus_one_over_r_with_outward_normal() {
    let r = 2.0;
    let sphere = |a: f64, b: f64| {
        let (th, ph) = (0.6 + 0.8 * a, -0.4 + 0.8 * b);
        DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * r
    };
    // w_u × w_v points outward here, so the sphere bends away from n: H = −1/r.
    let want = (-1.0 / r, 1.0 / (r * r), -1.0 / r, -1.0 / r);
    let coarse = curvature_error(&fit(9, sphere), want);
    let fine = curvature_error(&fit(17, sphere), want);
    assert!(fine < 1e-3, "fine {fine}");
    assert!(fine < coarse / 4.0, "converges: {coarse} → {fine}");
    let s = fit(17, sphere);
    let c = surface_curvature(&s.derivs(0.5, 0.5)).unwrap();
    let p = s.point(0.5, 0.5);
    assert!((c.normal - p.normalize()).length() < 1e-3, "outward normal");
}

#[test]
fn cylinder_has_k_zero_and_h_half_over_r() {
    let r = 1.5;
    let cyl = |a: f64, b: f64| {
        let ph = -0.7 + 1.4 * b;
        DVec3::new(r * ph.cos(), r * ph.sin(), 3.0 * a)
    };
    // n = w_u × w_v points to the axis: the cylinder bends toward it.
    let want = (0.5 / r, 0.0, 1.0 / r, 0.0);
    let coarse = curvature_error(&fit(9, cyl), want);
    let fine = curvature_error(&fit(17, cyl), want);
    assert!(fine < 1e-3, "fine {fine}");
    assert!(fine < coarse / 4.0, "{coarse} → {fine}");
    // κ1's direction runs around the cylinder, κ2's along the axis.
    let c = surface_curvature(&fit(17, cyl).derivs(0.5, 0.5)).unwrap();
    assert!(c.dir2.cross(DVec3::Z).length() < 1e-3, "{:?}", c.dir2);
    assert!(c.dir1.z.abs() < 1e-3);
}

#[test]
fn saddle_xy_has_k_minus_one_at_the_origin() {
    // z = xy is a bicubic-representable surface: interpolation reproduces it
    // up to the parametrisation; at the origin K = −1, H = 0, κ = ±1.
    let saddle = |a: f64, b: f64| {
        let (x, y) = (a - 0.5, b - 0.5);
        DVec3::new(x, y, x * y)
    };
    let s = fit(9, saddle);
    let c = surface_curvature(&s.derivs(0.5, 0.5)).unwrap();
    assert!((s.point(0.5, 0.5)).length() < 1e-12);
    assert!((c.gauss + 1.0).abs() < 1e-9, "{}", c.gauss);
    assert!(c.mean.abs() < 1e-9);
    assert!((c.k1 - 1.0).abs() < 1e-9 && (c.k2 + 1.0).abs() < 1e-9);
    // Principal directions are the diagonals.
    let diag = DVec3::new(1.0, 1.0, 0.0).normalize();
    assert!(c.dir1.dot(diag).abs() > 1.0 - 1e-9 || c.dir2.dot(diag).abs() > 1.0 - 1e-9);
}

#[test]
fn a_plane_is_degenerate_nowhere_and_flat() {
    let s = BSplineSurface::plane(2.0, 1.0, 6, 5, 3).unwrap();
    let t = tessellate(&s, 11, 7);
    assert!(t.mean.iter().chain(&t.gauss).all(|&k| k == 0.0));
    assert!(t.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
}

#[test]
fn tessellation_agrees_with_direct_evaluation() {
    let s = fit(9, |a, b| {
        DVec3::new(a * 3.0, b * 2.0, (3.0 * a).sin() * (2.0 * b).cos() * 0.5)
    });
    let (su, sv) = samples_for(&s, 2000);
    let t = tessellate(&s, su, sv);
    assert!(
        (t.triangles() as f64 - 2000.0).abs() < 200.0,
        "{}",
        t.triangles()
    );
    assert_eq!(t.positions.len(), su * sv);
    assert!(t.indices.iter().all(|&i| (i as usize) < su * sv));
    for idx in [0, 17, su * sv / 2, su * sv - 1] {
        let [u, v] = t.uvs[idx];
        let (u, v) = (u as f64, v as f64);
        let p = s.point(u, v);
        let c = surface_curvature(&s.derivs(u, v)).unwrap();
        let q = t.positions[idx];
        assert!((DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) - p).length() < 1e-5);
        let n = t.normals[idx];
        assert!((DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) - c.normal).length() < 1e-5);
        assert!((t.mean[idx] as f64 - c.mean).abs() < 1e-4 * (1.0 + c.mean.abs()));
        assert!((t.gauss[idx] as f64 - c.gauss).abs() < 1e-4 * (1.0 + c.gauss.abs()));
    }
    // Triangles face along the normal (counter-clockwise seen from n).
    let p = |i: u32| {
        let q = t.positions[i as usize];
        DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64)
    };
    let tri = &t.indices[0..3];
    let face = (p(tri[1]) - p(tri[0])).cross(p(tri[2]) - p(tri[0]));
    let n = t.normals[tri[0] as usize];
    assert!(face.dot(DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64)) > 0.0);
    // Refilling after a change reuses the tables and sees the new shape.
    let mut tess = Tessellator::new(&s, su, sv);
    let mut out = Tessellation::default();
    let mut moved = s.clone();
    for q in moved.points_mut() {
        q.z += 1.0;
    }
    tess.fill(&moved, &mut out);
    assert!((out.positions[5][2] - t.positions[5][2] - 1.0).abs() < 1e-5);
}
