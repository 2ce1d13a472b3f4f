//! Curvature and tessellation against analytic surfaces: B-spline surfaces
//! interpolated through a sphere, a cylinder and the saddle z = xy; knot
//! insertion and sub-patches against the original shape; interpolation
//! against its data; bad input refused.

use glam::DVec3;
use vsculpt_kernel::analysis::{
    Tessellation, Tessellator, curve_curvature, samples_for, surface_curvature, tessellate,
    tessellate_curve,
};
use vsculpt_kernel::bspline::{
    BSplineCurve, BSplineSurface, GeometryError, KnotVector, interpolate_curve, interpolate_surface,
};

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

/// Centripetal parameters computed here, independently of the kernel.
fn chord_params(pts: &[DVec3]) -> Vec<f64> {
    let d: Vec<f64> = pts
        .windows(2)
        .map(|w| (w[1] - w[0]).length().sqrt())
        .collect();
    let total: f64 = d.iter().sum();
    let mut t = vec![0.0];
    let mut acc = 0.0;
    for x in d {
        acc += x;
        t.push(acc / total);
    }
    t
}

/// A bicubic surface with non-uniform knots and a wavy control net.
fn wavy() -> BSplineSurface {
    let u = KnotVector::new(3, vec![0., 0., 0., 0., 0.25, 0.4, 0.7, 1., 1., 1., 1.]).unwrap();
    let v = KnotVector::clamped_uniform(3, 6).unwrap();
    let pts = (0..42)
        .map(|k| {
            let (x, y) = ((k / 6) as f64, (k % 6) as f64);
            DVec3::new(x + 0.1 * y, y, (0.7 * x).sin() * (0.9 * y).cos())
        })
        .collect();
    BSplineSurface::new(u, v, pts).unwrap()
}

fn max_gap(a: &BSplineSurface, b: &BSplineSurface) -> f64 {
    let mut gap = 0.0f64;
    for i in 0..=60 {
        for j in 0..=60 {
            let (u, v) = (i as f64 / 60.0, j as f64 / 60.0);
            gap = gap.max((a.point(u, v) - b.point(u, v)).length());
        }
    }
    gap
}

#[test]
fn knot_insertion_leaves_curves_and_surfaces_unchanged() {
    let s = wavy();
    let mut r = s.clone();
    for (t, along_u) in [
        (0.1, true),
        (0.4, true),
        (0.4, true),
        (0.33, false),
        (0.9, false),
    ] {
        r = if along_u {
            r.insert_knot_u(t).unwrap()
        } else {
            r.insert_knot_v(t).unwrap()
        };
    }
    assert_eq!((r.nu(), r.nv()), (s.nu() + 3, s.nv() + 2));
    assert!(max_gap(&s, &r) < 1e-12);
    let f = s.refine_uniform().unwrap();
    // Spans: 4 along u, 3 along v — each halved.
    assert_eq!((f.nu(), f.nv()), (s.nu() + 4, s.nv() + 3));
    assert!(max_gap(&s, &f) < 1e-12);
    // Derivatives are unchanged too (same function).
    let (a, b) = (s.derivs(0.37, 0.61), f.derivs(0.37, 0.61));
    assert!((a.uu - b.uu).length() < 1e-9 && (a.uv - b.uv).length() < 1e-9);

    let c = BSplineCurve::new(s.u_knots().clone(), s.points()[..7].to_vec()).unwrap();
    let mut c2 = c.clone();
    for t in [0.05, 0.5, 0.5, 0.99] {
        c2 = c2.insert_knot(t).unwrap();
    }
    assert_eq!(c2.points().len(), c.points().len() + 4);
    for k in 0..=500 {
        let t = k as f64 / 500.0;
        assert!((c.point(t) - c2.point(t)).length() < 1e-12, "t = {t}");
    }
}

#[test]
fn sub_patch_matches_the_surface() {
    let s = wavy();
    // A rectangle whose edges fall on an existing knot (0.4) and between knots.
    for (u0, u1, v0, v1) in [
        (0.4, 0.85, 0.1, 0.6),
        (0.0, 0.3, 0.5, 1.0),
        (0.0, 1.0, 0.0, 1.0),
    ] {
        let p = s.sub_patch(u0, u1, v0, v1).unwrap();
        let ((pu0, pu1), (pv0, pv1)) = p.domain();
        for i in 0..=25 {
            for j in 0..=25 {
                let (a, b) = (i as f64 / 25.0, j as f64 / 25.0);
                let q = p.point(pu0 + (pu1 - pu0) * a, pv0 + (pv1 - pv0) * b);
                let w = s.point(u0 + (u1 - u0) * a, v0 + (v1 - v0) * b);
                assert!((q - w).length() < 1e-11, "({a},{b}) in {u0},{u1},{v0},{v1}");
            }
        }
    }
}

#[test]
fn interpolation_passes_through_its_data() {
    // Curve: a helix-like space curve with uneven spacing.
    let pts: Vec<DVec3> = (0..12)
        .map(|k| {
            let t = (k as f64).powf(1.3);
            DVec3::new(t.cos(), t.sin(), 0.3 * t)
        })
        .collect();
    for degree in [1, 2, 3, 5] {
        let c = interpolate_curve(&pts, degree).unwrap();
        for (p, t) in pts.iter().zip(chord_params(&pts)) {
            assert!((c.point(t) - *p).length() < 1e-10, "degree {degree}");
        }
    }
    // Surface: z = g(x) + h(y) on an uneven grid keeps every column's (and
    // every row's) chords equal, so the averaged parameters are known here.
    let xs: Vec<f64> = (0..8).map(|i| (i as f64).powf(1.2)).collect();
    let ys: Vec<f64> = (0..7)
        .map(|j| 0.5 * j as f64 + 0.05 * (j * j) as f64)
        .collect();
    let g = |x: f64| 0.4 * (0.8 * x).sin();
    let h = |y: f64| 0.3 * (1.1 * y).cos();
    let grid: Vec<DVec3> = xs
        .iter()
        .flat_map(|&x| ys.iter().map(move |&y| DVec3::new(x, y, g(x) + h(y))))
        .collect();
    let s = interpolate_surface(&grid, xs.len(), ys.len(), 3, 3).unwrap();
    let us = chord_params(
        &xs.iter()
            .map(|&x| DVec3::new(x, 0.0, g(x)))
            .collect::<Vec<_>>(),
    );
    let vs = chord_params(
        &ys.iter()
            .map(|&y| DVec3::new(0.0, y, h(y)))
            .collect::<Vec<_>>(),
    );
    for (i, &u) in us.iter().enumerate() {
        for (j, &v) in vs.iter().enumerate() {
            let d = (s.point(u, v) - grid[i * ys.len() + j]).length();
            assert!(d < 1e-10, "({i},{j}) off by {d}");
        }
    }
}

#[test]
fn curve_curvature_of_a_fitted_circle() {
    let r = 2.5;
    // 81 samples over 270°: the cubic fit's curvature error is O(h²) ≈ 1e-4
    // relative inside; 41 samples gave 1.2e-3.
    let pts: Vec<DVec3> = (0..81)
        .map(|k| {
            let a = 1.5 * std::f64::consts::PI * k as f64 / 80.0;
            DVec3::new(r * a.cos(), r * a.sin(), 1.0)
        })
        .collect();
    let c = interpolate_curve(&pts, 3).unwrap();
    let comb = tessellate_curve(&c, 101);
    assert_eq!(comb.points.len(), 101);
    // Away from the free ends (where the fit's end conditions dominate).
    for k in 10..=90 {
        let p = comb.points[k];
        assert!(
            (comb.curvature[k] - 1.0 / r).abs() < 1e-3 / r,
            "{}",
            comb.curvature[k]
        );
        let to_centre = (DVec3::new(0.0, 0.0, 1.0) - p).normalize();
        assert!((comb.normals[k] - to_centre).length() < 1e-3);
    }
    // A straight line: κ = 0, no normal; a stalled curve is degenerate.
    let line = interpolate_curve(&[DVec3::ZERO, DVec3::X, DVec3::X * 2.0], 2).unwrap();
    let (k, n) = curve_curvature(&line.derivs(0.3)).unwrap();
    assert!(k.abs() < 1e-12 && n == DVec3::ZERO);
    let stalled = BSplineCurve::new(
        KnotVector::clamped_uniform(1, 2).unwrap(),
        vec![DVec3::ONE, DVec3::ONE],
    )
    .unwrap();
    assert!(curve_curvature(&stalled.derivs(0.5)).is_err());
}

#[test]
fn a_degenerate_corner_gets_finite_values() {
    // Collapse the first row of control points: w_v = 0 along u = 0.
    let mut s = wavy();
    let nv = s.nv();
    let apex = s.points()[0];
    for q in &mut s.points_mut()[..nv] {
        *q = apex;
    }
    assert!(surface_curvature(&s.derivs(0.0, 0.5)).is_err());
    let t = tessellate(&s, 9, 9);
    for k in 0..t.positions.len() {
        assert!(t.normals[k].iter().all(|x| x.is_finite()));
        assert!(t.mean[k].is_finite() && t.gauss[k].is_finite());
    }
    assert_eq!((t.mean[4], t.gauss[4]), (0.0, 0.0));
}

#[test]
fn bad_input_is_refused() {
    let s = wavy();
    let domain = |e| matches!(e, GeometryError::OutOfDomain { .. });
    assert!(domain(s.insert_knot_u(f64::NAN).unwrap_err()));
    assert!(domain(s.insert_knot_v(-0.1).unwrap_err()));
    assert!(domain(s.insert_knot_u(1.0).unwrap_err()));
    assert!(domain(s.insert_knot_v(f64::INFINITY).unwrap_err()));
    // 0.4 is already a knot once; a cubic takes it at most 3 times.
    let twice = s.insert_knot_u(0.4).unwrap().insert_knot_u(0.4).unwrap();
    assert!(matches!(
        twice.insert_knot_u(0.4),
        Err(GeometryError::InteriorMultiplicity { .. })
    ));
    assert!(s.sub_patch(0.5, 0.2, 0.0, 1.0).is_err());
    assert!(s.sub_patch(0.2, 0.2, 0.0, 1.0).is_err());
    assert!(s.sub_patch(0.0, 1.2, 0.0, 1.0).is_err());
    assert!(s.sub_patch(0.0, 0.5, f64::NAN, 1.0).is_err());

    let pts: Vec<DVec3> = (0..6).map(|k| DVec3::new(k as f64, 0.0, 0.0)).collect();
    assert!(matches!(
        interpolate_curve(&[DVec3::Y; 6], 3),
        Err(GeometryError::Singular(_))
    ));
    let mut dup = pts.clone();
    dup[3] = dup[2];
    assert!(matches!(
        interpolate_curve(&dup, 3),
        Err(GeometryError::Singular(_))
    ));
    let mut nan = pts.clone();
    nan[1].y = f64::NAN;
    assert!(interpolate_curve(&nan, 3).is_err());
    assert!(interpolate_curve(&pts[..3], 3).is_err());
    assert!(interpolate_curve(&pts, 0).is_err());
    assert!(interpolate_surface(&pts, 2, 2, 1, 1).is_err());
    let flat = vec![DVec3::ZERO; 16];
    assert!(matches!(
        interpolate_surface(&flat, 4, 4, 3, 3),
        Err(GeometryError::Singular(_))
    ));
}
