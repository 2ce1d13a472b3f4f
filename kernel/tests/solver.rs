//! The energy and the constrained solver against analytic truth.

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector, greville};
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, SolveError, Solver};

mod kkt_support;
use kkt_support::dense_kkt;

fn material(alpha: f64, beta: f64, rest: f64) -> SurfaceMaterial {
    SurfaceMaterial {
        alpha11: alpha,
        alpha12: 0.0,
        alpha22: alpha,
        beta11: beta,
        beta12: beta,
        beta22: beta,
        rest,
    }
}

#[test]
fn energy_of_polynomial_fields_is_exact() {
    let kv = KnotVector::new(3, vec![0., 0., 0., 0., 0.2, 0.45, 0.7, 1., 1., 1., 1.]).unwrap();
    let m = SurfaceMaterial {
        alpha11: 0.3,
        alpha12: 0.1,
        alpha22: 0.7,
        beta11: 1.3,
        beta12: 0.9,
        beta22: 2.1,
        rest: 0.01,
    };
    let k = Stiffness::surface(&kv, &kv, &m).unwrap();
    let n = kv.num_ctrl();
    let g = greville(&kv);
    let kn = kv.knots();
    // Marsden: control values of t² for a cubic are symmetric products of its interior knots.
    let sq: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b, c) = (kn[i + 1], kn[i + 2], kn[i + 3]);
            (a * b + a * c + b * c) / 3.0
        })
        .collect();
    let field = |f: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
        (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| f(i, j))
            .collect()
    };
    // Constant 1: only the rest term, ∫∫1 = 1.
    let one = field(&|_, _| 1.0);
    // Round-off of the cancelling α and β terms is ~1e-12 here.
    assert!((k.energy(&one) - m.rest).abs() < 1e-10);
    // w = u: α11 ∫∫1 + rest ∫∫u² = α11 + rest/3; bending vanishes.
    let u = field(&|i, _| g[i]);
    assert!((k.energy(&u) - (m.alpha11 + m.rest / 3.0)).abs() < 1e-10);
    // w = u + v: α11 + 2α12 + α22 + rest ∫∫(u+v)² = … + rest·7/6.
    let uv = field(&|i, j| g[i] + g[j]);
    let want = m.alpha11 + 2.0 * m.alpha12 + m.alpha22 + m.rest * 7.0 / 6.0;
    assert!((k.energy(&uv) - want).abs() < 1e-10);
    // w = u²: α11 ∫4u² + β11 ∫4 + rest ∫u⁴ = 4α11/3 + 4β11 + rest/5.
    let u2 = field(&|i, _| sq[i]);
    assert!((k.energy(&u2) - (4.0 * m.alpha11 / 3.0 + 4.0 * m.beta11 + m.rest / 5.0)).abs() < 1e-9);
    // w = u·v: w_u = v, w_v = u, w_uv = 1: α11/3 + 2α12/4 + α22/3 + 2β12 + rest/9.
    let prod = field(&|i, j| g[i] * g[j]);
    let want = m.alpha11 / 3.0 + m.alpha12 / 2.0 + m.alpha22 / 3.0 + 2.0 * m.beta12 + m.rest / 9.0;
    assert!((k.energy(&prod) - want).abs() < 1e-9);
}

fn plate(n: usize) -> BSplineSurface {
    BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap()
}

fn solver_for(s: &BSplineSurface, m: &SurfaceMaterial) -> Solver {
    Solver::new(Stiffness::surface(s.u_knots(), s.v_knots(), m).unwrap()).unwrap()
}

fn position(s: &BSplineSurface, key: u64, u: f64, v: f64, target: DVec3) -> Group {
    Group {
        key,
        equations: vec![Equation::Vector {
            row: surface_row(s, u, v, 0, 0),
            target,
        }],
        loads: vec![],
    }
}

/// The largest distance between corresponding points.
fn max_gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

/// A solver that saw nothing but `problem`: its full solve of the plate
/// `s` (or, with `drag`, its frame of that group's drag).
fn fresh(
    s: &BSplineSurface,
    m: &SurfaceMaterial,
    problem: Problem,
    drag: Option<(u64, DVec3)>,
) -> Vec<DVec3> {
    let mut solver = solver_for(s, m);
    solver.set_problem(problem).unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    match drag {
        Some((key, t)) => solver.drag(key, t, s.points(), &mut out).unwrap(),
        None => solver.solve(s.points(), &mut out).unwrap(),
    };
    out
}

#[test]
fn constraints_hold_and_redundancy_is_harmless() {
    let s = plate(12);
    let mut solver = solver_for(&s, &material(0.1, 1.0, 1e-3));
    let t1 = DVec3::new(0.3, 0.4, 0.25);
    let mut dup = position(&s, 2, 0.3, 0.4, t1);
    dup.equations.push(dup.equations[0].clone());
    let deriv = Group {
        key: 3,
        equations: vec![Equation::Vector {
            row: surface_row(&s, 0.7, 0.2, 1, 0),
            target: DVec3::new(1.0, 0.0, 0.5),
        }],
        loads: vec![],
    };
    let normal = DVec3::new(0.2, -0.1, 1.0).normalize();
    let norm = Group {
        key: 4,
        equations: vec![
            Equation::Projected {
                row: surface_row(&s, 0.6, 0.7, 1, 0),
                direction: normal,
                target: 0.0,
            },
            Equation::Projected {
                row: surface_row(&s, 0.6, 0.7, 0, 1),
                direction: normal,
                target: 0.0,
            },
        ],
        loads: vec![],
    };
    solver
        .set_problem(Problem {
            groups: vec![position(&s, 1, 0.3, 0.4, t1), dup, deriv, norm],
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    let report = solver.solve(s.points(), &mut out).unwrap();
    assert!(
        report.rank_deficiency >= 6,
        "duplicates are redundant: {report:?}"
    );
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    let mut solved = s.clone();
    solved.set_points(out).unwrap();
    assert!((solved.point(0.3, 0.4) - t1).length() < 1e-9);
    assert!((solved.derivs(0.7, 0.2).u - DVec3::new(1.0, 0.0, 0.5)).length() < 1e-9);
    let d = solved.derivs(0.6, 0.7);
    assert!(d.u.dot(normal).abs() < 1e-9 && d.v.dot(normal).abs() < 1e-9);
    // The surface's normal there is ±normal.
    assert!(solved.normal(0.6, 0.7).dot(normal).abs() > 1.0 - 1e-9);
}

#[test]
fn contradictory_constraints_give_a_finite_least_squares_answer() {
    let s = plate(8);
    let mut solver = solver_for(&s, &material(0.1, 1.0, 1e-3));
    let a = DVec3::new(0.5, 0.5, 1.0);
    let b = DVec3::new(0.5, 0.5, -1.0);
    solver
        .set_problem(Problem {
            groups: vec![position(&s, 1, 0.5, 0.5, a), position(&s, 2, 0.5, 0.5, b)],
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    let report = solver.solve(s.points(), &mut out).unwrap();
    assert!(out.iter().all(|p| p.is_finite()));
    assert!(report.rank_deficiency >= 1);
    assert!(
        (report.constraint_residual - 1.0).abs() < 1e-6,
        "halfway: {report:?}"
    );
    let mut solved = s.clone();
    solved.set_points(out).unwrap();
    assert!(solved.point(0.5, 0.5).z.abs() < 1e-6);
}

#[test]
fn drag_frames_equal_full_solves() {
    let s = plate(15);
    let mut solver = solver_for(&s, &material(0.05, 1.0, 1e-3));
    let normal = DVec3::new(0.0, 0.3, 1.0).normalize();
    let groups = |shift: DVec3, gain: f64| {
        vec![
            position(&s, 1, 0.1, 0.1, DVec3::new(0.1, 0.1, 0.0)),
            position(&s, 2, 0.9, 0.8, DVec3::new(0.9, 0.8, 0.1) + shift),
            Group {
                key: 3,
                equations: vec![
                    Equation::Projected {
                        row: surface_row(&s, 0.3, 0.7, 1, 0),
                        direction: normal,
                        target: 0.0,
                    },
                    Equation::Projected {
                        row: surface_row(&s, 0.3, 0.7, 0, 1),
                        direction: normal,
                        target: 0.0,
                    },
                ],
                loads: vec![],
            },
            Group {
                key: 4,
                equations: vec![],
                loads: vec![Load {
                    row: surface_row(&s, 0.5, 0.5, 0, 0),
                    force: DVec3::new(0.0, 0.0, 2.0) + shift * gain,
                    drag_gain: gain,
                }],
            },
        ]
    };
    solver
        .set_problem(Problem {
            groups: groups(DVec3::ZERO, 3.0),
        })
        .unwrap();
    let n = s.points().len();
    let (mut fast, mut full) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let t = DVec3::new(0.05, -0.02, 0.3);
    // Group 2 (constraint) then group 4 (load), each against a fresh full solve.
    for key in [2u64, 4, 2] {
        solver.drag(key, t, s.points(), &mut fast).unwrap();
        let mut reference = solver_for(&s, &material(0.05, 1.0, 1e-3));
        let mut g = groups(DVec3::ZERO, 3.0);
        let shifted = groups(t, 3.0);
        let idx = g.iter().position(|x| x.key == key).unwrap();
        g[idx] = shifted[idx].clone();
        reference.set_problem(Problem { groups: g }).unwrap();
        reference.solve(s.points(), &mut full).unwrap();
        let err = fast
            .iter()
            .zip(&full)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        assert!(err < 1e-9, "key {key}: {err}");
    }
    // The drag moved something: a load of more force moves the surface more.
    let mut base = vec![DVec3::ZERO; n];
    solver.solve(s.points(), &mut base).unwrap();
    let moved = fast
        .iter()
        .zip(&base)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(moved > 1e-3);
}

#[test]
fn bad_input_is_refused_and_changes_nothing() {
    let s = plate(6);
    let mut solver = solver_for(&s, &material(0.1, 1.0, 1e-3));
    let good = Problem {
        groups: vec![position(&s, 1, 0.5, 0.5, DVec3::new(0.5, 0.5, 0.2))],
    };
    solver.set_problem(good.clone()).unwrap();
    let bad = Problem {
        groups: vec![position(&s, 1, 0.5, 0.5, DVec3::new(f64::NAN, 0.5, 0.2))],
    };
    assert!(matches!(
        solver.set_problem(bad),
        Err(SolveError::NotFinite(_))
    ));
    let mut far = position(&s, 1, 0.5, 0.5, DVec3::ZERO);
    if let Equation::Vector { row, .. } = &mut far.equations[0] {
        row.indices[0] = 10_000;
    }
    assert!(matches!(
        solver.set_problem(Problem { groups: vec![far] }),
        Err(SolveError::IndexOutOfRange { .. })
    ));
    assert_eq!(solver.problem(), &good);
    let mut out = vec![DVec3::ZERO; 36];
    assert!(matches!(
        solver.drag(99, DVec3::X, s.points(), &mut out),
        Err(SolveError::UnknownGroup(99))
    ));
    assert!(
        solver
            .drag(1, DVec3::splat(f64::INFINITY), s.points(), &mut out)
            .is_err()
    );
    assert!(solver.solve(&s.points()[..5], &mut out).is_err());
    solver.solve(s.points(), &mut out).unwrap();
    let mut solved = s.clone();
    solved.set_points(out).unwrap();
    assert!((solved.point(0.5, 0.5) - DVec3::new(0.5, 0.5, 0.2)).length() < 1e-9);
}

/// Central deflection of a clamped unit plate, D = 1, P = 1, with `spans`
/// cubic spans per side.
fn clamped_plate_deflection(spans: usize, load: f64) -> (f64, BSplineSurface) {
    let n = spans + 3;
    let s = plate(n);
    // α = 0, β = 1: E = ∫∫(w_uu² + 2w_uv² + w_vv²) − 2 w·f. For a clamped plate
    // ∫∫(w_uu² + 2w_uv² + w_vv²) = ∫∫(Δw)², so E/2 = ½∫∫(Δw)² − P·w(c): the
    // Kirchhoff plate energy with D = β = 1. The mass term rest·∫∫w² stiffens
    // it by about rest/λ_min, λ_min ≈ 1300 the lowest eigenvalue of the clamped
    // plate: 1e-3 biases w by under 1e-6 relative. (Much smaller values make
    // K⁻¹b huge in the constant mode and lose digits in δ0 − Yλ.)
    let mut solver = solver_for(&s, &material(0.0, 1.0, 1e-3));
    let mut eqs = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let ring = i < 2 || j < 2 || i >= n - 2 || j >= n - 2;
            if ring {
                // Fixing the two outer rows of control points in z gives w = 0 and ∂w/∂n = 0 on the edge.
                let row = vsculpt_kernel::solve::ScalarRow {
                    indices: vec![s.index(i, j)],
                    weights: vec![1.0],
                };
                eqs.push(Equation::Projected {
                    row,
                    direction: DVec3::Z,
                    target: 0.0,
                });
            }
        }
    }
    let groups = vec![
        Group {
            key: 1,
            equations: eqs,
            loads: vec![],
        },
        Group {
            key: 2,
            equations: vec![],
            loads: vec![Load {
                row: surface_row(&s, 0.5, 0.5, 0, 0),
                force: DVec3::new(0.0, 0.0, load),
                drag_gain: 0.0,
            }],
        },
    ];
    solver.set_problem(Problem { groups }).unwrap();
    let mut out = vec![DVec3::ZERO; n * n];
    solver.solve(s.points(), &mut out).unwrap();
    let mut solved = s.clone();
    solved.set_points(out).unwrap();
    (solved.point(0.5, 0.5).z, solved)
}

#[test]
fn clamped_plate_under_central_load_converges_to_kirchhoff() {
    // Timoshenko & Woinowsky-Krieger, Theory of Plates and Shells (2nd ed.,
    // 1959), §44, Table 35: clamped square plate, central load P:
    // w_max = 0.00560 · P a² / D.
    // Cross-check: Roark's Formulas (all edges fixed, central load, a/b = 1)
    // give y = 0.0611 W b²/(E t³); with D = E t³/(12(1 − ν²)), ν = 0.3, that
    // is 0.0611/10.92 = 0.00560 P a²/D.
    let exact = 0.00560;
    let mut errors = Vec::new();
    let mut deflections = Vec::new();
    for spans in [8, 16, 32, 64] {
        let (w, _) = clamped_plate_deflection(spans, 1.0);
        deflections.push(w);
        errors.push(((w - exact) / exact).abs());
        println!(
            "{spans} spans: w = {w:.6}, relative error {:.4}",
            errors.last().unwrap()
        );
    }
    assert!(errors[3] < 0.02, "{errors:?}");
    assert!(errors[3] < errors[0]);
    // Converging: each refinement changes the deflection less than the one
    // before (the table's three digits cannot resolve the last levels).
    let steps: Vec<f64> = deflections
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .collect();
    assert!(
        steps[2] < steps[1] && steps[1] < steps[0],
        "{deflections:?}"
    );
    // Linear in the load, and symmetric under the square's symmetries.
    let (w1, s) = clamped_plate_deflection(16, 1.0);
    let (w3, _) = clamped_plate_deflection(16, 3.0);
    assert!((w3 - 3.0 * w1).abs() < 1e-9 * w3.abs());
    for &(u, v) in &[(0.3, 0.4), (0.2, 0.65), (0.45, 0.1)] {
        let z = s.point(u, v).z;
        for (a, b) in [(1.0 - u, v), (u, 1.0 - v), (v, u), (1.0 - v, 1.0 - u)] {
            assert!(
                (s.point(a, b).z - z).abs() < 1e-10,
                "({u},{v}) vs ({a},{b})"
            );
        }
    }
}

#[test]
fn a_constraint_switched_off_and_on_reuses_its_column() {
    let s = plate(14);
    let m = material(0.1, 1.0, 1e-3);
    let pins = |with_switch: bool| Problem {
        groups: [
            Some(position(&s, 1, 0.1, 0.1, s.point(0.1, 0.1))),
            Some(position(&s, 2, 0.9, 0.9, s.point(0.9, 0.9))),
            Some(position(
                &s,
                3,
                0.5,
                0.5,
                s.point(0.5, 0.5) + DVec3::Z * 0.2,
            )),
            with_switch.then(|| position(&s, 4, 0.3, 0.7, s.point(0.3, 0.7) - DVec3::Z * 0.1)),
        ]
        .into_iter()
        .flatten()
        .collect(),
    };
    let mut solver = solver_for(&s, &m);
    let mut out = vec![DVec3::ZERO; s.points().len()];
    solver.set_problem(pins(true)).unwrap();
    let first = solver.columns_solved();
    assert_eq!(first, 4, "one column per new row, solved in one batch");
    solver.solve(s.points(), &mut out).unwrap();
    let with = out.clone();
    // Off, then on again: no new column either way.
    let solved = solver.columns_solved();
    solver.set_problem(pins(false)).unwrap();
    assert_eq!(
        solver.columns_solved(),
        solved,
        "dropping a row solves nothing"
    );
    solver.solve(s.points(), &mut out).unwrap();
    assert!(
        (out[s.index(5, 9)] - with[s.index(5, 9)]).length() > 1e-3,
        "the switch matters"
    );
    let before = solver.columns_solved();
    solver.set_problem(pins(true)).unwrap();
    assert_eq!(
        solver.columns_solved(),
        before,
        "the retired column came back"
    );
    solver.solve(s.points(), &mut out).unwrap();
    // The same answer as a solver that never saw the switch.
    let gap = max_gap(&out, &fresh(&s, &m, pins(true), None));
    assert!(gap < 1e-12, "{gap}");
    // A new material invalidates every column: they are solved again.
    solver
        .refactor(Stiffness::surface(s.u_knots(), s.v_knots(), &material(0.2, 1.0, 1e-3)).unwrap())
        .unwrap();
    let after = solver.columns_solved();
    solver.set_problem(pins(false)).unwrap();
    solver.set_problem(pins(true)).unwrap();
    assert_eq!(
        solver.columns_solved(),
        after,
        "retired after the refactor, reused"
    );
    assert!(after >= before + 4, "the refactor solved the columns again");
}

#[test]
fn a_change_the_shape_already_satisfies_costs_no_solve_and_others_are_solved() {
    let s = plate(14);
    let m = material(0.1, 1.0, 1e-3);
    let base = vec![
        position(&s, 1, 0.1, 0.1, s.point(0.1, 0.1)),
        position(&s, 2, 0.9, 0.9, s.point(0.9, 0.9)),
        position(&s, 3, 0.5, 0.5, s.point(0.5, 0.5) + DVec3::Z * 0.2),
    ];
    let mut solver = solver_for(&s, &m);
    let mut out = vec![DVec3::ZERO; s.points().len()];
    solver
        .set_problem(Problem {
            groups: base.clone(),
        })
        .unwrap();
    solver.solve(s.points(), &mut out).unwrap();
    let solved = {
        let mut t = s.clone();
        t.set_points(out.clone()).unwrap();
        t
    };
    let fresh_solve = |groups: Vec<Group>| fresh(&s, &m, Problem { groups }, None);
    let gap = max_gap;
    // A pin where the solved surface already is: the shape is still the
    // answer; only the pin's column is solved, no full solve follows.
    let mut with_pin = base.clone();
    with_pin.push(position(&s, 4, 0.3, 0.7, solved.point(0.3, 0.7)));
    solver
        .set_problem(Problem {
            groups: with_pin.clone(),
        })
        .unwrap();
    let before = solver.columns_solved();
    let report = solver.solve(s.points(), &mut out).unwrap();
    assert_eq!(solver.columns_solved(), before, "no sparse solve");
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    assert!(gap(&out, &fresh_solve(with_pin.clone())) < 1e-10);
    // Put to sleep again: it pulled with λ ≈ 0, so nothing to solve either.
    solver
        .set_problem(Problem {
            groups: base.clone(),
        })
        .unwrap();
    let before = solver.columns_solved();
    solver.solve(s.points(), &mut out).unwrap();
    assert_eq!(solver.columns_solved(), before);
    assert!(gap(&out, &fresh_solve(base.clone())) < 1e-10);
    // A pin that asks for a new place is solved, and holds.
    let mut moved = base.clone();
    moved.push(position(
        &s,
        4,
        0.3,
        0.7,
        solved.point(0.3, 0.7) + DVec3::Z * 0.05,
    ));
    solver
        .set_problem(Problem {
            groups: moved.clone(),
        })
        .unwrap();
    let report = solver.solve(s.points(), &mut out).unwrap();
    assert!(report.constraint_residual < 1e-9);
    assert!(gap(&out, &fresh_solve(moved)) < 1e-10);
    // Dropping the lifted pin, which held the shape up, is solved too: the
    // plate comes down.
    let mut without = base[..2].to_vec();
    without.push(position(
        &s,
        4,
        0.3,
        0.7,
        solved.point(0.3, 0.7) + DVec3::Z * 0.05,
    ));
    solver
        .set_problem(Problem {
            groups: without.clone(),
        })
        .unwrap();
    solver.solve(s.points(), &mut out).unwrap();
    assert!(gap(&out, &fresh_solve(without)) < 1e-10);
    let mut down = s.clone();
    down.set_points(out.clone()).unwrap();
    assert!(down.point(0.5, 0.5).z < solved.point(0.5, 0.5).z - 0.05);
}

#[test]
fn solves_agree_with_a_dense_kkt_solve_in_every_coordinate() {
    let s = plate(12);
    let m = material(0.1, 1.0, 1e-3);
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), &m).unwrap();
    let mut solver = solver_for(&s, &m);
    // Pins, one lifted in z only (x and y barely take part), a derivative
    // constraint, and a load pulling in z.
    let mut groups: Vec<Group> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .iter()
        .enumerate()
        .map(|(i, &(u, v))| position(&s, i as u64 + 1, u, v, s.point(u, v)))
        .collect();
    groups.push(position(
        &s,
        5,
        0.5,
        0.5,
        s.point(0.5, 0.5) + DVec3::Z * 0.3,
    ));
    groups.push(Group {
        key: 6,
        equations: vec![Equation::Vector {
            row: surface_row(&s, 0.25, 0.7, 1, 0),
            target: s.derivs(0.25, 0.7).u + DVec3::new(0.1, 0.0, 0.4),
        }],
        loads: vec![],
    });
    let pull = DVec3::new(0.0, 0.0, -2.0);
    groups.push(Group {
        key: 7,
        equations: vec![],
        loads: vec![Load {
            row: surface_row(&s, 0.7, 0.3, 0, 0),
            force: pull,
            drag_gain: 1.0,
        }],
    });
    solver
        .set_problem(Problem {
            groups: groups.clone(),
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    solver.solve(s.points(), &mut out).unwrap();
    let load_row = surface_row(&s, 0.7, 0.3, 0, 0);
    for c in 0..3 {
        // Constraint rows: row · (P_ref + δ) = target ⇒ row · δ = target − row · P_ref.
        let rows: Vec<(Vec<usize>, Vec<f64>, f64)> = groups
            .iter()
            .flat_map(|g| g.equations.iter())
            .map(|eq| match eq {
                Equation::Vector { row, target } => (
                    row.indices.clone(),
                    row.weights.clone(),
                    target[c] - row.apply(s.points())[c],
                ),
                Equation::Projected { .. } => unreachable!(),
            })
            .collect();
        // Minimising δᵀKδ − 2δ·b: b = row ⊗ force.
        let mut b = vec![0.0; s.points().len()];
        for (&i, &w) in load_row.indices.iter().zip(&load_row.weights) {
            b[i] += w * pull[c];
        }
        let delta = dense_kkt(&k, &rows, &b);
        for (i, d) in delta.iter().enumerate() {
            let got = out[i][c] - s.points()[i][c];
            assert!(
                (got - d).abs() < 1e-9,
                "coordinate {c}, point {i}: {got} vs {d}"
            );
        }
    }
}

#[test]
fn a_grab_at_rest_solves_nothing_and_matches_a_fresh_solver() {
    let s = plate(14);
    let m = material(0.1, 1.0, 1e-3);
    let load_row = surface_row(&s, 0.6, 0.4, 0, 0);
    // Pins where the reference already is and a load that does not pull
    // yet: the reference itself is the answer (the state after a bake).
    let problem = |force: DVec3, lift: f64| Problem {
        groups: vec![
            position(&s, 1, 0.1, 0.1, s.point(0.1, 0.1)),
            position(&s, 2, 0.9, 0.2, s.point(0.9, 0.2) + DVec3::Z * lift),
            Group {
                key: 3,
                equations: vec![],
                loads: vec![Load {
                    row: load_row.clone(),
                    force,
                    drag_gain: 2.0,
                }],
            },
        ],
    };
    let n = s.points().len();
    let mut solver = solver_for(&s, &m);
    solver.set_problem(problem(DVec3::ZERO, 0.0)).unwrap();
    let mut out = vec![DVec3::ZERO; n];
    let after_columns = solver.columns_solved();
    solver.solve(s.points(), &mut out).unwrap();
    assert_eq!(out, s.points(), "at rest: δ = 0 exactly");
    assert_eq!(
        solver.columns_solved(),
        after_columns,
        "and no sparse solve"
    );
    // The first drag frame computes the response (one batched solve) …
    let t = DVec3::new(0.0, 0.1, 0.3);
    solver.drag(3, t, s.points(), &mut out).unwrap();
    let first = out.clone();
    // … a problem that differs only in targets and forces keeps it.
    solver.set_problem(problem(DVec3::ZERO, 0.0)).unwrap();
    let before = solver.columns_solved();
    solver.drag(3, t, s.points(), &mut out).unwrap();
    assert_eq!(solver.columns_solved(), before, "the response was kept");
    assert_eq!(out, first);
    // A changed target: the base is solved again, the response still kept,
    // and the frame equals a fresh solver's.
    solver.set_problem(problem(DVec3::ZERO, 0.05)).unwrap();
    solver.drag(3, t, s.points(), &mut out).unwrap();
    let gap = max_gap(
        &out,
        &fresh(&s, &m, problem(DVec3::ZERO, 0.05), Some((3, t))),
    );
    assert!(gap < 1e-10, "{gap}");
    // A different gain is another structure: the response is recomputed.
    let mut other = problem(DVec3::ZERO, 0.05);
    other.groups[2].loads[0].drag_gain = 3.0;
    solver.set_problem(other.clone()).unwrap();
    let before = solver.columns_solved();
    solver.drag(3, t, s.points(), &mut out).unwrap();
    assert!(solver.columns_solved() > before);
    let gap = max_gap(&out, &fresh(&s, &m, other, Some((3, t))));
    assert!(gap < 1e-10, "{gap}");
}
