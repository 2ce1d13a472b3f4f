//! The first grab after the equations changed (an icon added or removed, a
//! load released and grabbed again, a contradictory icon, a new pin): the
//! drag response is computed again, from the x input alone when the
//! problem is symmetric (one-term equations alike on x, y and z: the
//! response is ρ ⊗ I). Every frame is checked against a fresh solver on
//! the same problem and, for vector equations, against a dense KKT solve
//! independent of the solver; a symmetric response must cost one
//! right-hand side per refinement step (three before).

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{
    Equation, Group, Load, Problem, ScalarRow, SolveReport, SolveWarning, Solver,
};

mod kkt_support;
use kkt_support::{dense_answer, max_gap};

/// Large enough for a supernodal factor: new columns are left pending.
const N: usize = 30;

fn plate(n: usize) -> BSplineSurface {
    let mut s = BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap();
    // A curved reference: the answers do not start from a flat sheet.
    for p in s.points_mut() {
        p.z = 0.1 * (3.0 * p.x).sin() * (2.0 * p.y).cos();
    }
    s
}

fn stiff_material() -> SurfaceMaterial {
    SurfaceMaterial {
        alpha11: 0.1,
        alpha12: 0.0,
        alpha22: 0.1,
        beta11: 1.0,
        beta12: 1.0,
        beta22: 1.0,
        rest: 1e-3,
    }
}

fn point(s: &BSplineSurface, key: u64, u: f64, v: f64, lift: DVec3) -> Group {
    Group {
        key,
        equations: vec![Equation::Vector {
            row: surface_row(s, u, v, 0, 0),
            target: s.point(u, v) + lift,
        }],
        loads: vec![],
    }
}

fn load(s: &BSplineSurface, key: u64, u: f64, v: f64) -> Group {
    Group {
        key,
        equations: vec![],
        loads: vec![Load {
            row: surface_row(s, u, v, 0, 0),
            force: DVec3::new(0.0, 0.1, 0.3),
            drag_gain: 2.0,
        }],
    }
}

/// A normal constraint: N · w_u = N · w_v = 0 at (u, v) (coupled rows).
fn normal(s: &BSplineSurface, key: u64, u: f64, v: f64, n: DVec3) -> Group {
    Group {
        key,
        equations: [(1, 0), (0, 1)]
            .into_iter()
            .map(|(du, dv)| Equation::Projected {
                row: surface_row(s, u, v, du, dv),
                direction: n,
                target: 0.0,
            })
            .collect(),
        loads: vec![],
    }
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

const FRAMES: [DVec3; 3] = [
    DVec3::new(0.0, 0.0, 0.2),
    DVec3::new(0.13, -0.07, 0.05),
    DVec3::new(-0.3, 0.21, -0.4),
];

/// Drag frames of group `key` from `solver` against a fresh solver on the
/// same problem (from scratch: its own base and response) and, when
/// `dense` is given, the dense KKT answer: equal to 1e-9, every equation
/// held to 1e-9. The response fields (uniform case) equal to 1e-9.
fn frames_match(
    solver: &mut Solver,
    problem: &Problem,
    p: &[DVec3],
    key: u64,
    dense: Option<&Stiffness>,
) -> SolveReport {
    let mut fresh = Solver::new(solver.stiffness().clone()).unwrap();
    fresh.set_problem(problem.clone()).unwrap();
    let mut out = vec![DVec3::ZERO; p.len()];
    let mut want = vec![DVec3::ZERO; p.len()];
    let mut last = SolveReport::default();
    for t in FRAMES {
        let report = solver.drag(key, t, p, &mut out).unwrap();
        let fresh_report = fresh.drag(key, t, p, &mut want).unwrap();
        assert_eq!(report.rank_deficiency, fresh_report.rank_deficiency);
        assert_eq!(report.warning.is_some(), fresh_report.warning.is_some());
        let gap = max_gap(&out, &want);
        assert!(gap < 1e-9, "frame {t} off the fresh solver by {gap:e}");
        if report.warning.is_none() {
            assert!(
                report.constraint_residual < 1e-9,
                "frame {t}: an equation off by {:e}",
                report.constraint_residual
            );
        }
        if let Some(k) = dense {
            let exact = dense_answer(k, p, problem, Some((key, t)));
            let gap = max_gap(&out, &exact);
            assert!(gap < 1e-9, "frame {t} off the dense KKT answer by {gap:e}");
        }
        last = report;
    }
    if let (Some((_, r)), Some((_, q))) = (solver.drag_basis(), fresh.drag_basis()) {
        let scale = max_abs(q).max(1.0);
        let gap = r
            .iter()
            .zip(q)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(gap < 1e-9 * scale, "response off the fresh one by {gap:e}");
    }
    last
}

struct Scene {
    s: BSplineSurface,
    k: Stiffness,
    p: Vec<DVec3>,
    groups: Vec<Group>,
    solver: Solver,
}

/// Four corner constraints and a dragged load (key 10), the response
/// computed by a first drag.
fn scene(material: &SurfaceMaterial) -> Scene {
    let s = plate(N);
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), material).unwrap();
    let p = s.points().to_vec();
    let mut groups: Vec<Group> = [(0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)]
        .iter()
        .enumerate()
        .map(|(i, &(u, v))| point(&s, i as u64 + 1, u, v, DVec3::ZERO))
        .collect();
    groups.push(load(&s, 10, 0.5, 0.45));
    let mut solver = Solver::new(k.clone()).unwrap();
    solver
        .set_problem(Problem {
            groups: groups.clone(),
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; p.len()];
    solver.drag(10, FRAMES[0], &p, &mut out).unwrap();
    assert_eq!(solver.response_counts().computed, 1);
    Scene {
        s,
        k,
        p,
        groups,
        solver,
    }
}

impl Scene {
    /// Takes `groups` and solves (the drag base is then cached: a frame
    /// after it costs only the response).
    fn set(&mut self, groups: Vec<Group>) -> Problem {
        self.groups = groups;
        let problem = Problem {
            groups: self.groups.clone(),
        };
        self.solver.set_problem(problem.clone()).unwrap();
        let mut out = vec![DVec3::ZERO; self.p.len()];
        self.solver.solve(&self.p, &mut out).unwrap();
        problem
    }

    /// The next drag frames compute the response again, exactly; when it
    /// is symmetric (uniform), from one input: the frame solves the
    /// `pending` new columns (unless a solve already did), the one combined
    /// right-hand side of the x input, and at most one right-hand side per
    /// refinement step (three inputs would take three of each).
    fn expect_response(&mut self, problem: &Problem, key: u64, pending: u64) {
        let counts = self.solver.response_counts();
        let columns = self.solver.columns_solved();
        let mut out = vec![DVec3::ZERO; self.p.len()];
        self.solver.drag(key, FRAMES[1], &self.p, &mut out).unwrap();
        let now = self.solver.response_counts();
        assert_eq!(now.computed, counts.computed + 1, "not recomputed");
        assert!(self.solver.drag_basis().is_some(), "not uniform");
        let steps = now.refinement_steps - counts.refinement_steps;
        let solved = self.solver.columns_solved() - columns;
        assert!(
            (1..=pending + 1 + steps).contains(&solved),
            "{solved} columns for {pending} pending, one input and {steps} steps"
        );
        frames_match(&mut self.solver, problem, &self.p, key, Some(&self.k));
    }
}

#[test]
fn an_added_constraint_gives_an_exact_response_from_one_input() {
    let mut sc = scene(&stiff_material());
    let mut groups = sc.groups.clone();
    groups.push(point(&sc.s, 20, 0.3, 0.6, DVec3::new(0.0, 0.02, 0.1)));
    let problem = sc.set(groups);
    // The new row's column was left pending by the change; the frame
    // solves it (one column) and nothing else.
    sc.expect_response(&problem, 10, 1);
    // And a second one, where the surface is.
    let mut groups = sc.groups.clone();
    groups.push(point(&sc.s, 21, 0.62, 0.35, DVec3::ZERO));
    let problem = sc.set(groups);
    sc.expect_response(&problem, 10, 1);
}

#[test]
fn a_removed_constraint_gives_an_exact_response() {
    let mut sc = scene(&stiff_material());
    let groups: Vec<Group> = sc.groups.iter().filter(|g| g.key != 2).cloned().collect();
    let problem = sc.set(groups);
    sc.expect_response(&problem, 10, 0);
    // Removed and added at once (an icon moved): both in one step.
    let mut groups: Vec<Group> = sc.groups.iter().filter(|g| g.key != 3).cloned().collect();
    groups.push(point(&sc.s, 3, 0.15, 0.8, DVec3::new(0.05, 0.0, -0.1)));
    let problem = sc.set(groups);
    sc.expect_response(&problem, 10, 1);
}

/// The grab after an icon was added, as `Design` does it: the released
/// load's group leaves the problem, an icon comes, the load's group comes
/// back; a previously added icon was removed in between.
#[test]
fn a_release_an_edit_and_a_grab_give_an_exact_response() {
    let mut sc = scene(&stiff_material());
    let load_group = sc.groups.iter().find(|g| g.key == 10).unwrap().clone();
    let mut extra = 30;
    for (u, v) in [(0.35, 0.55), (0.7, 0.6), (0.45, 0.3)] {
        // Release: the load leaves; the previous extra icon is removed.
        let mut groups: Vec<Group> = sc
            .groups
            .iter()
            .filter(|g| g.key != 10 && g.key != extra)
            .cloned()
            .collect();
        sc.set(groups.clone());
        extra += 1;
        groups.push(point(&sc.s, extra, u, v, DVec3::ZERO));
        sc.set(groups.clone());
        groups.push(load_group.clone());
        let problem = sc.set(groups);
        sc.expect_response(&problem, 10, 1);
    }
}

/// A dragged constraint (its targets shift) with coupled normal rows in
/// the problem: the response is coupled across coordinates (three inputs).
/// Compared with a fresh solver (the dense check takes vector equations
/// only).
#[test]
fn a_coupled_response_of_a_dragged_constraint_is_exact() {
    let mut sc = scene(&stiff_material());
    let mut groups = sc.groups.clone();
    groups.push(normal(
        &sc.s,
        40,
        0.4,
        0.5,
        DVec3::new(0.2, 0.1, 1.0).normalize(),
    ));
    sc.set(groups);
    let mut out = vec![DVec3::ZERO; sc.p.len()];
    sc.solver.drag(1, FRAMES[0], &sc.p, &mut out).unwrap();
    assert!(sc.solver.drag_basis().is_none(), "the response is coupled");
    for (key, u, v) in [(41, 0.6, 0.7), (42, 0.25, 0.4)] {
        let mut groups = sc.groups.clone();
        groups.push(point(&sc.s, key, u, v, DVec3::new(0.0, 0.0, 0.05)));
        groups.push(normal(&sc.s, key + 10, u + 0.1, v - 0.2, DVec3::Z));
        let problem = sc.set(groups);
        frames_match(&mut sc.solver, &problem, &sc.p, 1, None);
        assert!(sc.solver.drag_basis().is_none(), "the response is coupled");
    }
    // Without the normal rows the problem is symmetric again: uniform.
    let groups: Vec<Group> = sc
        .groups
        .iter()
        .filter(|g| g.key != 40 && !(50..60).contains(&g.key))
        .cloned()
        .collect();
    let problem = sc.set(groups);
    frames_match(&mut sc.solver, &problem, &sc.p, 1, Some(&sc.k));
    assert!(sc.solver.drag_basis().is_some(), "the response is uniform");
}

/// The default material (rest 1e-4: the response leans on cancelling
/// columns): still exact.
#[test]
fn the_response_is_exact_with_the_default_material() {
    let mut sc = scene(&SurfaceMaterial::default());
    for (key, u, v) in [(50, 0.3, 0.65), (51, 0.72, 0.3)] {
        let mut groups = sc.groups.clone();
        groups.push(point(&sc.s, key, u, v, DVec3::new(0.0, 0.0, 0.05)));
        let problem = sc.set(groups);
        frames_match(&mut sc.solver, &problem, &sc.p, 10, Some(&sc.k));
    }
    let groups: Vec<Group> = sc.groups.iter().filter(|g| g.key != 50).cloned().collect();
    let problem = sc.set(groups);
    frames_match(&mut sc.solver, &problem, &sc.p, 10, Some(&sc.k));
}

/// A contradictory constraint (the same point held elsewhere: least
/// squares and a warning), its removal, and a new pin (a refactor): the
/// answers stay those of a fresh solver (and the dense solve where exact).
#[test]
fn contradictions_and_pins_give_the_fresh_answers() {
    let mut sc = scene(&stiff_material());
    let mut groups = sc.groups.clone();
    groups.push(point(&sc.s, 60, 0.1, 0.1, DVec3::new(0.0, 0.0, 0.2)));
    let problem = sc.set(groups);
    let computed = sc.solver.response_counts().computed;
    let report = frames_match(&mut sc.solver, &problem, &sc.p, 10, None);
    assert!(
        matches!(
            report.warning,
            Some(SolveWarning::Dependent { dropped: 3, .. })
        ),
        "{report:?}"
    );
    assert_eq!(sc.solver.response_counts().computed, computed + 1);
    let groups: Vec<Group> = sc.groups.iter().filter(|g| g.key != 60).cloned().collect();
    let problem = sc.set(groups);
    let computed = sc.solver.response_counts().computed;
    frames_match(&mut sc.solver, &problem, &sc.p, 10, Some(&sc.k));
    assert_eq!(sc.solver.response_counts().computed, computed + 1);
    // A pin: a vector equation on one control point (eliminated from the
    // unknowns, a refactor).
    let mut groups = sc.groups.clone();
    let corner = sc.s.points()[N * 7 + 12];
    groups.push(Group {
        key: 61,
        equations: vec![Equation::Vector {
            row: ScalarRow {
                indices: vec![N * 7 + 12],
                weights: vec![1.0],
            },
            target: corner + DVec3::new(0.0, 0.0, 0.03),
        }],
        loads: vec![],
    });
    let problem = sc.set(groups);
    let computed = sc.solver.response_counts().computed;
    frames_match(&mut sc.solver, &problem, &sc.p, 10, Some(&sc.k));
    assert_eq!(sc.solver.response_counts().computed, computed + 1);
}
