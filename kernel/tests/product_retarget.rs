//! `Solver::retarget` (new targets and forces, same rows: what a moving
//! bound curve asks of its surface's group) answers as a fresh solver given
//! the same problem, and hands any other change to `set_problem`.

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, Solver};

fn problem(s: &BSplineSurface, lift: f64, force: f64, extra: bool) -> Problem {
    let mut groups = vec![Group {
        key: 1,
        equations: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.3)]
            .iter()
            .map(|&(u, v)| Equation::Vector {
                row: surface_row(s, u, v, 0, 0),
                target: s.point(u, v) + DVec3::Z * lift * u * v,
            })
            .chain([Equation::Projected {
                row: surface_row(s, 0.3, 0.6, 1, 0),
                direction: DVec3::new(0.0, 0.0, 1.0),
                target: 0.2 * lift,
            }])
            .collect(),
        loads: Vec::new(),
    }];
    groups.push(Group {
        key: 2,
        equations: Vec::new(),
        loads: vec![Load {
            row: surface_row(s, 0.7, 0.4, 0, 0),
            force: DVec3::new(0.0, force, force),
            drag_gain: 1.0,
        }],
    });
    if extra {
        groups.push(Group {
            key: 3,
            equations: vec![Equation::Vector {
                row: surface_row(s, 0.2, 0.8, 0, 0),
                target: s.point(0.2, 0.8),
            }],
            loads: Vec::new(),
        });
    }
    Problem { groups }
}

fn fresh(s: &BSplineSurface, p: Problem) -> Vec<DVec3> {
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), &SurfaceMaterial::default()).unwrap();
    let mut solver = Solver::new(k).unwrap();
    solver.set_problem(p).unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    solver.solve(s.points(), &mut out).unwrap();
    out
}

fn gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

#[test]
fn retargeting_answers_as_a_fresh_solver_and_keeps_its_columns() {
    let s = BSplineSurface::plane(2.0, 1.0, 9, 7, 3).unwrap();
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), &SurfaceMaterial::default()).unwrap();
    let mut solver = Solver::new(k).unwrap();
    solver.set_problem(problem(&s, 0.1, 0.0, false)).unwrap();
    let mut out = vec![DVec3::ZERO; s.points().len()];
    solver.solve(s.points(), &mut out).unwrap();
    for (k, (lift, force)) in [(0.3, 0.0), (-0.2, 0.5), (0.05, -1.0)]
        .into_iter()
        .enumerate()
    {
        let columns = solver.columns_solved();
        solver.retarget(problem(&s, lift, force, false)).unwrap();
        // Only targets and forces changed: no new column was solved for.
        assert_eq!(solver.columns_solved(), columns, "step {k}");
        solver.solve(s.points(), &mut out).unwrap();
        let want = fresh(&s, problem(&s, lift, force, false));
        let g = gap(&out, &want);
        assert!(g < 1e-10, "step {k}: {g:e}");
        // The answer moved with the targets.
        assert!(gap(&out, s.points()) > 1e-3);
    }
    // Another structure (one more group) goes through set_problem.
    solver.retarget(problem(&s, 0.1, 0.2, true)).unwrap();
    solver.solve(s.points(), &mut out).unwrap();
    let g = gap(&out, &fresh(&s, problem(&s, 0.1, 0.2, true)));
    assert!(g < 1e-10, "{g:e}");
    // Bad input is refused and changes nothing.
    let mut bad = problem(&s, 0.1, 0.2, true);
    if let Equation::Vector { target, .. } = &mut bad.groups[0].equations[0] {
        target.x = f64::NAN;
    }
    assert!(solver.retarget(bad).is_err());
    solver.solve(s.points(), &mut out).unwrap();
    assert!(gap(&out, &fresh(&s, problem(&s, 0.1, 0.2, true))) < 1e-10);
}
