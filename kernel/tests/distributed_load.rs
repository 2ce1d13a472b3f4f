//! Distributed loads (issue 15, item 2): a region or curve load is the
//! consistent load ∫ N_i f, its total force scales with the region's area,
//! and a uniform load on a square plate converges to Kirchhoff plate theory.
//!
//! Independent truths:
//! * B-splines reproduce linear functions with control points at the
//!   Greville abscissae (Σ N_i(u) ξ_i = u), so with P_ij = (ξ_i, η_j, ξ_i η_j)
//!   the row applied to P is ∫_Ω (u, v, uv), known in closed form;
//! * the plate: with α = 0 the energy β ∫ |w_uu|² + 2|w_uv|² + |w_vv|² − 2wf
//!   has the Euler–Lagrange equation β Δ²w = f, Kirchhoff's D Δ²w = q with
//!   D = β, q = f (Poisson's ratio 0: the twist term; the deflection of a
//!   simply supported or clamped plate does not depend on it). Simply
//!   supported: Navier's double series, summed here. Clamped: the tabulated
//!   coefficients of S. Timoshenko and S. Woinowsky-Krieger, *Theory of
//!   Plates and Shells*, 2nd ed., McGraw-Hill 1959 (square plate, ν-free
//!   deflections at the centre): uniform load w = 0.00126 q a⁴/D (SS
//!   0.00406), central point load w = 0.00560 P a²/D (SS 0.01160);
//! * the same discrete system (the kernel's K, the pinned control points
//!   eliminated, the load vector) solved by a dense Cholesky here.

use faer::Mat;
use faer::linalg::solvers::Solve;
use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector, greville};
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::{Anchor, load_row, surface_row};
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, ScalarRow, Solver};

/// A bicubic surface over [0,1]² whose control points are (ξ_i, η_j, ξ_i η_j).
fn greville_surface(nu: usize, nv: usize) -> BSplineSurface {
    let ku = KnotVector::clamped_uniform(3, nu).unwrap();
    let kv = KnotVector::clamped_uniform(3, nv).unwrap();
    let (gu, gv) = (greville(&ku), greville(&kv));
    let mut pts = Vec::new();
    for &x in &gu {
        for &y in &gv {
            pts.push(DVec3::new(x, y, x * y));
        }
    }
    BSplineSurface::new(ku, kv, pts).unwrap()
}

/// ∫ over [a0,a1]×[b0,b1] of (u, v, uv).
fn moments(a0: f64, a1: f64, b0: f64, b1: f64) -> DVec3 {
    let (la, lb) = (a1 - a0, b1 - b0);
    let (mu, mv) = (0.5 * (a1 * a1 - a0 * a0), 0.5 * (b1 * b1 - b0 * b0));
    DVec3::new(mu * lb, mv * la, mu * mv)
}

fn total(row: &ScalarRow) -> f64 {
    row.weights.iter().sum()
}

#[test]
fn a_region_load_integrates_exactly_and_scales_with_area() {
    for (nu, nv) in [(7, 5), (20, 15), (38, 32)] {
        let s = greville_surface(nu, nv);
        let (a0, a1, b0, b1) = (0.137, 0.391, 0.52, 0.83);
        let inside = load_row(
            &Anchor::Region {
                u0: a1,
                v0: b0,
                u1: a0,
                v1: b1,
                inside: true,
            },
            &s,
        );
        let area = (a1 - a0) * (b1 - b0);
        assert!((total(&inside) - area).abs() < 1e-14, "{nu}x{nv}");
        let got = inside.apply(s.points());
        let want = moments(a0, a1, b0, b1);
        assert!((got - want).length() < 1e-14, "{nu}x{nv}: {got} vs {want}");
        // The outside: the whole domain minus the rectangle.
        let outside = load_row(
            &Anchor::Region {
                u0: a0,
                v0: b0,
                u1: a1,
                v1: b1,
                inside: false,
            },
            &s,
        );
        assert!(
            (total(&outside) - (1.0 - area)).abs() < 1e-13,
            "{}",
            total(&outside) - (1.0 - area)
        );
        let want = moments(0.0, 1.0, 0.0, 1.0) - moments(a0, a1, b0, b1);
        assert!((outside.apply(s.points()) - want).length() < 1e-13);
        // A region 16× larger (4× each side) carries 16× the force.
        let small = load_row(
            &Anchor::Region {
                u0: 0.4,
                v0: 0.4,
                u1: 0.45,
                v1: 0.45,
                inside: true,
            },
            &s,
        );
        let large = load_row(
            &Anchor::Region {
                u0: 0.3,
                v0: 0.3,
                u1: 0.5,
                v1: 0.5,
                inside: true,
            },
            &s,
        );
        assert!((total(&large) / total(&small) - 16.0).abs() < 1e-10);
    }
}

#[test]
fn a_curve_load_integrates_along_the_curve() {
    let s = greville_surface(20, 15);
    // A straight segment: ∫ (u, v) ds = L · midpoint, total = L.
    let (a, b) = (DVec3::new(0.1, 0.2, 0.0), DVec3::new(0.85, 0.7, 0.0));
    let line = BSplineCurve::new(KnotVector::clamped_uniform(1, 2).unwrap(), vec![a, b]).unwrap();
    let row = load_row(&Anchor::Curve(line), &s);
    let len = (b - a).length();
    assert!(
        (total(&row) - len).abs() < 1e-12,
        "{} vs {len}",
        total(&row)
    );
    let got = row.apply(s.points());
    let mid = 0.5 * (a + b);
    let want = DVec3::new(len * mid.x, len * mid.y, 0.0);
    assert!((got.truncate() - want.truncate()).length() < 1e-12);
    // A cubic: the total is its (u,v) length, by a fine polyline.
    let pts = vec![
        DVec3::new(0.1, 0.1, 0.0),
        DVec3::new(0.3, 0.9, 0.0),
        DVec3::new(0.7, 0.05, 0.0),
        DVec3::new(0.9, 0.8, 0.0),
    ];
    let c = BSplineCurve::new(KnotVector::clamped_uniform(3, 4).unwrap(), pts).unwrap();
    let n = 200_000;
    let length: f64 = (0..n)
        .map(|k| {
            let p = c.point(k as f64 / n as f64);
            let q = c.point((k + 1) as f64 / n as f64);
            (q - p).truncate().length()
        })
        .sum();
    let row = load_row(&Anchor::Curve(c), &s);
    assert!(
        (total(&row) - length).abs() < 1e-8 * length,
        "{} vs {length}",
        total(&row)
    );
}

/// The centre deflection of a unit square plate (β = 1, α = 0) with `rings`
/// outer rings of control points pinned, under a uniform unit load
/// (`point` false) or a unit point load at the centre, on `spans` × `spans`
/// knot spans: the kernel's solver and a dense solve of the same system.
fn plate(spans: usize, rings: usize, point: bool) -> (f64, f64) {
    let n = spans + 3;
    let ku = KnotVector::clamped_uniform(3, n).unwrap();
    let (g, _) = (greville(&ku), ());
    let mut pts = Vec::new();
    for &x in &g {
        for &y in &g {
            pts.push(DVec3::new(x, y, 0.0));
        }
    }
    let s = BSplineSurface::new(ku.clone(), ku.clone(), pts.clone()).unwrap();
    let material = SurfaceMaterial {
        alpha11: 0.0,
        alpha12: 0.0,
        alpha22: 0.0,
        beta11: 1.0,
        beta12: 1.0,
        beta22: 1.0,
        rest: 1e-4,
    };
    let k = Stiffness::surface(&ku, &ku, &material).unwrap();
    let row = if point {
        load_row(&Anchor::Point { u: 0.5, v: 0.5 }, &s)
    } else {
        load_row(
            &Anchor::Region {
                u0: 0.0,
                v0: 0.0,
                u1: 1.0,
                v1: 1.0,
                inside: true,
            },
            &s,
        )
    };
    let pinned = |i: usize, j: usize| i.min(j).min(n - 1 - i).min(n - 1 - j) < rings;
    let mut group = Group {
        key: 1,
        ..Group::default()
    };
    for i in 0..n {
        for j in 0..n {
            if pinned(i, j) {
                group.equations.push(Equation::Vector {
                    row: ScalarRow {
                        indices: vec![i * n + j],
                        weights: vec![1.0],
                    },
                    target: pts[i * n + j],
                });
            }
        }
    }
    group.loads.push(Load {
        row: row.clone(),
        force: DVec3::Z,
        drag_gain: 0.0,
    });
    let mut solver = Solver::new(k.clone()).unwrap();
    solver
        .set_problem(Problem {
            groups: vec![group],
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; pts.len()];
    let report = solver.solve(&pts, &mut out).unwrap();
    assert!(report.constraint_residual < 1e-12, "{report:?}");
    let centre = surface_row(&s, 0.5, 0.5, 0, 0);
    let kernel = centre.apply(&out).z;
    // Dense: K_ff z_f = b_f over the free control points.
    let free: Vec<usize> = (0..n * n).filter(|&c| !pinned(c / n, c % n)).collect();
    let mut at = vec![usize::MAX; n * n];
    for (f, &c) in free.iter().enumerate() {
        at[c] = f;
    }
    let m = free.len();
    let mut kd = Mat::<f64>::zeros(m, m);
    for (f, &c) in free.iter().enumerate() {
        let mut e = vec![0.0; n * n];
        e[c] = 1.0;
        let col = k.mul(&e);
        for (r, v) in col.iter().enumerate() {
            if at[r] != usize::MAX {
                kd[(at[r], f)] = *v;
            }
        }
    }
    let mut b = Mat::<f64>::zeros(m, 1);
    for (&i, &w) in row.indices.iter().zip(&row.weights) {
        if at[i] != usize::MAX {
            b[(at[i], 0)] += w;
        }
    }
    let z = kd.llt(faer::Side::Lower).unwrap().solve(&b);
    let dense: f64 = centre
        .indices
        .iter()
        .zip(&centre.weights)
        .filter(|(i, _)| at[**i] != usize::MAX)
        .map(|(i, w)| w * z[(at[*i], 0)])
        .sum();
    (kernel, dense)
}

/// Navier's series for the centre of a simply supported unit square plate,
/// D = 1: uniform unit load, and unit point load at the centre.
fn navier() -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let (mut uniform, mut point) = (0.0, 0.0);
    for m in (1..4001).step_by(2) {
        for n in (1..4001).step_by(2) {
            let (m_, n_) = (m as f64, n as f64);
            let q = (m_ * m_ + n_ * n_).powi(2);
            let sign = if ((m + n) / 2 - 1) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            uniform += sign / (m_ * n_ * q);
            point += 1.0 / q;
        }
    }
    (16.0 / pi.powi(6) * uniform, 4.0 / pi.powi(4) * point)
}

#[test]
fn a_uniform_and_a_point_load_on_a_plate_converge_to_plate_theory() {
    let (ss_uniform, ss_point) = navier();
    // The series agree with the tables they are quoted from.
    assert!((ss_uniform - 0.00406).abs() < 5e-6, "{ss_uniform}");
    assert!((ss_point - 0.01160).abs() < 5e-6, "{ss_point}");
    let cases = [
        // (rings, point load, exact, tolerance at the finest grid)
        (1, false, ss_uniform, 1e-4),
        (1, true, ss_point, 2e-3),
        // The tables give 3 figures: 0.00126 is ±0.4 %.
        (2, false, 0.00126, 5e-3),
        (2, true, 0.00560, 5e-3),
    ];
    for (rings, point, exact, tol) in cases {
        let mut last = f64::INFINITY;
        for spans in [8, 16] {
            let (kernel, dense) = plate(spans, rings, point);
            assert!(
                (kernel - dense).abs() <= 1e-8 * dense.abs(),
                "rings {rings} point {point} spans {spans}: kernel {kernel} dense {dense}"
            );
            let error = (kernel - exact).abs() / exact;
            eprintln!(
                "rings {rings} point {point} spans {spans}: {kernel:.6e} (exact {exact:.5e}) rel {error:.2e}"
            );
            if rings == 1 {
                // Against the series: the error falls with refinement.
                assert!(
                    error < last,
                    "rings {rings} point {point} spans {spans}: {error}"
                );
            }
            last = error;
        }
        assert!(last < tol, "rings {rings} point {point}: {last}");
    }
}
