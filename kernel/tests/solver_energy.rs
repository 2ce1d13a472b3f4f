//! The curve energy against analytic integrals, material validation at the
//! boundary, and the solver on a deformable curve.

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector, greville};
use vsculpt_kernel::energy::{CurveMaterial, Stiffness, StiffnessError, SurfaceMaterial};
use vsculpt_kernel::icon::curve_row;
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, Solver};

fn knots() -> KnotVector {
    KnotVector::new(
        3,
        vec![0., 0., 0., 0., 0.15, 0.4, 0.55, 0.8, 1., 1., 1., 1.],
    )
    .unwrap()
}

#[test]
fn curve_energy_of_polynomial_fields_is_exact() {
    let kv = knots();
    let m = CurveMaterial {
        alpha: 0.7,
        beta: 1.9,
        rest: 0.03,
    };
    let k = Stiffness::curve(&kv, &m).unwrap();
    let n = kv.num_ctrl();
    assert_eq!(k.dim(), n);
    let g = greville(&kv);
    let kn = kv.knots();
    // Marsden: the control values of t² for a cubic are the symmetric
    // products of its three interior knots.
    let sq: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b, c) = (kn[i + 1], kn[i + 2], kn[i + 3]);
            (a * b + a * c + b * c) / 3.0
        })
        .collect();
    // w = 1: stretch and bend vanish, rest ∫1 = rest.
    let e1 = k.energy(&vec![1.0; n]);
    assert!((e1 - m.rest).abs() < 1e-10, "{e1}");
    // w = t: α ∫1 + rest ∫t²; bending vanishes on affine fields.
    assert!((k.energy(&g) - (m.alpha + m.rest / 3.0)).abs() < 1e-10);
    // w = t²: α ∫4t² + β ∫4 + rest ∫t⁴.
    let want = 4.0 * m.alpha / 3.0 + 4.0 * m.beta + m.rest / 5.0;
    assert!((k.energy(&sq) - want).abs() < 1e-10);
    // The stored lower triangle is read as a symmetric matrix: xᵀKy = yᵀKx.
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
    let y: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).cos()).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
    assert!((dot(&k.mul(&x), &y) - dot(&x, &k.mul(&y))).abs() < 1e-10);
}

#[test]
fn the_three_coordinate_product_equals_three_scalar_products() {
    let s = Stiffness::surface(
        &KnotVector::clamped_uniform(3, 9).unwrap(),
        &KnotVector::clamped_uniform(2, 7).unwrap(),
        &SurfaceMaterial::default(),
    )
    .unwrap();
    let n = s.dim();
    let p: Vec<DVec3> = (0..n)
        .map(|i| {
            let t = i as f64;
            DVec3::new((0.7 * t).sin(), (1.3 * t).cos(), 0.1 * t)
        })
        .collect();
    let mut y = vec![DVec3::splat(f64::NAN); n];
    s.mul_points(&p, &mut y);
    for k in 0..3 {
        let x: Vec<f64> = p.iter().map(|v| v[k]).collect();
        for (a, b) in s.mul(&x).iter().zip(&y) {
            assert!(
                (a - b[k]).abs() <= 1e-12 * a.abs().max(1.0),
                "{a} vs {}",
                b[k]
            );
        }
    }
}

#[test]
fn bad_materials_are_refused() {
    let kv = knots();
    let good = SurfaceMaterial::default();
    assert!(good.validate().is_ok());
    for bad in [
        SurfaceMaterial {
            beta11: f64::NAN,
            ..good
        },
        SurfaceMaterial {
            alpha22: -1.0,
            ..good
        },
        SurfaceMaterial { rest: 0.0, ..good },
        SurfaceMaterial {
            rest: f64::INFINITY,
            ..good
        },
        SurfaceMaterial {
            alpha12: 1.0,
            ..good
        },
    ] {
        assert!(matches!(
            Stiffness::surface(&kv, &kv, &bad),
            Err(StiffnessError::Material(_))
        ));
    }
    let curve = CurveMaterial::default();
    assert!(curve.validate().is_ok());
    for bad in [
        CurveMaterial {
            alpha: -0.1,
            ..curve
        },
        CurveMaterial {
            beta: f64::NAN,
            ..curve
        },
        CurveMaterial {
            rest: -1e-3,
            ..curve
        },
    ] {
        assert!(Stiffness::curve(&kv, &bad).is_err());
    }
}

#[test]
fn a_curve_holds_its_constraint_and_follows_its_load() {
    let kv = knots();
    let n = kv.num_ctrl();
    let points: Vec<DVec3> = greville(&kv)
        .iter()
        .map(|&t| DVec3::new(t, 0.0, 0.0))
        .collect();
    let curve = BSplineCurve::new(kv.clone(), points).unwrap();
    let mut solver =
        Solver::new(Stiffness::curve(&kv, &CurveMaterial::default()).unwrap()).unwrap();
    let pin = |t: f64, target: DVec3| Equation::Vector {
        row: curve_row(&curve, t, 0),
        target,
    };
    let target = DVec3::new(0.3, 0.2, -0.1);
    solver
        .set_problem(Problem {
            groups: vec![
                Group {
                    key: 1,
                    equations: vec![pin(0.0, DVec3::ZERO), pin(0.3, target), pin(1.0, DVec3::X)],
                    loads: vec![],
                },
                Group {
                    key: 2,
                    equations: vec![],
                    loads: vec![Load {
                        row: curve_row(&curve, 0.7, 0),
                        force: DVec3::new(0.0, 0.0, 0.5),
                        drag_gain: 1.0,
                    }],
                },
            ],
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; n];
    let report = solver.solve(curve.points(), &mut out).unwrap();
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    assert_eq!(report.rank_deficiency, 0);
    let solved = BSplineCurve::new(kv, out).unwrap();
    assert!((solved.point(0.3) - target).length() < 1e-9);
    assert!(solved.point(0.0).length() < 1e-9);
    // More force along +z (the drag input adds to the load) lifts the curve
    // where the load acts, and only in z; the pins still hold.
    let mut dragged = vec![DVec3::ZERO; n];
    let report = solver
        .drag(2, DVec3::Z, curve.points(), &mut dragged)
        .unwrap();
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    let lifted = BSplineCurve::new(solved.knots().clone(), dragged).unwrap();
    let rise = lifted.point(0.7) - solved.point(0.7);
    assert!(rise.z > 1e-4, "{rise}");
    assert!(rise.x.abs() < 1e-12 && rise.y.abs() < 1e-12, "{rise}");
    assert!((lifted.point(0.3) - target).length() < 1e-9);
}

#[test]
fn a_numeric_refactor_equals_a_fresh_factor() {
    let kv = knots();
    let soft = CurveMaterial::default();
    let stiff = CurveMaterial { beta: 5.0, ..soft };
    let points: Vec<DVec3> = greville(&kv)
        .iter()
        .map(|&t| DVec3::new(t, 0.0, 0.0))
        .collect();
    let curve = BSplineCurve::new(kv.clone(), points).unwrap();
    let problem = Problem {
        groups: vec![Group {
            key: 1,
            equations: vec![Equation::Vector {
                row: curve_row(&curve, 0.5, 0),
                target: DVec3::new(0.5, 0.3, 0.0),
            }],
            loads: vec![Load {
                row: curve_row(&curve, 0.2, 0),
                force: DVec3::new(0.0, 0.0, 1.0),
                drag_gain: 0.0,
            }],
        }],
    };
    let solve = |solver: &mut Solver| {
        let mut out = vec![DVec3::ZERO; curve.points().len()];
        solver.solve(curve.points(), &mut out).unwrap();
        out
    };
    let mut refactored = Solver::new(Stiffness::curve(&kv, &soft).unwrap()).unwrap();
    refactored.set_problem(problem.clone()).unwrap();
    let before = solve(&mut refactored);
    refactored
        .refactor(Stiffness::curve(&kv, &stiff).unwrap())
        .unwrap();
    let mut fresh = Solver::new(Stiffness::curve(&kv, &stiff).unwrap()).unwrap();
    fresh.set_problem(problem).unwrap();
    let (a, b) = (solve(&mut refactored), solve(&mut fresh));
    let diff = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
    assert!(diff < 1e-12, "{diff}");
    // The material matters: the stiffer curve bends differently.
    let moved = a
        .iter()
        .zip(&before)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
    assert!(moved > 1e-6, "{moved}");
}
