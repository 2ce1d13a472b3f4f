//! A change of the pinned set (region and edge icons pin control points:
//! added, removed, switched) is held over the factor of the old set without
//! a refactor (`solve::pin_update`), the refactor deferred to
//! `Solver::settle_pins` (called by a solve that moves the shape, a grab,
//! or a host when idle). Every answer — full solves and drag frames with a
//! load pulling, before and after the deferred refactor — is checked
//! against a fresh solver on the same problem and against a dense KKT
//! solve independent of the solver.

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, ScalarRow, Solver};

mod kkt_support;
use kkt_support::{dense_answer, max_gap};

/// Large enough for a supernodal factor (the update needs one).
const N: usize = 30;

fn plate(n: usize) -> BSplineSurface {
    let mut s = BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap();
    for p in s.points_mut() {
        p.z = 0.1 * (3.0 * p.x).sin() * (2.0 * p.y).cos();
    }
    s
}

fn material(scale: f64) -> SurfaceMaterial {
    SurfaceMaterial {
        alpha11: 0.1 * scale,
        alpha12: 0.0,
        alpha22: 0.1 * scale,
        beta11: scale,
        beta12: scale,
        beta22: scale,
        rest: 1e-3,
    }
}

/// Pins every control point of `points` where it is, lifted by `lift`
/// (a region or edge icon's equations).
fn pins(s: &BSplineSurface, key: u64, points: &[usize], lift: DVec3) -> Group {
    Group {
        key,
        equations: points
            .iter()
            .map(|&i| Equation::Vector {
                row: ScalarRow {
                    indices: vec![i],
                    weights: vec![1.0],
                },
                target: s.points()[i] + lift,
            })
            .collect(),
        loads: vec![],
    }
}

/// The control points of the block [i0, i0 + w) × [j0, j0 + h).
fn block(i0: usize, j0: usize, w: usize, h: usize) -> Vec<usize> {
    (i0..i0 + w)
        .flat_map(|i| (j0..j0 + h).map(move |j| i * N + j))
        .collect()
}

/// The two outer rows along u = 0 (an edge clamp).
fn clamp_rows() -> Vec<usize> {
    (0..2)
        .flat_map(|i| (0..N).map(move |j| i * N + j))
        .collect()
}

fn point(s: &BSplineSurface, key: u64, u: f64, v: f64) -> Group {
    Group {
        key,
        equations: vec![Equation::Vector {
            row: surface_row(s, u, v, 0, 0),
            target: s.point(u, v),
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

/// The answers of `solver` to `problem` (a full solve and two drag frames
/// of the load `dragged`) equal a fresh solver's and the dense KKT
/// solve's to 1e-9 of the shape's size.
fn check(
    solver: &mut Solver,
    k: &Stiffness,
    p: &[DVec3],
    problem: &Problem,
    dragged: u64,
    what: &str,
) {
    let n = p.len();
    let mut fresh = Solver::new(k.clone()).unwrap();
    fresh.set_problem(problem.clone()).unwrap();
    // Its own factor of the pinned set, not an update over another.
    fresh.settle_pins().unwrap();
    assert!(!fresh.pins_pending());
    let (mut got, mut want) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let report = solver.solve(p, &mut got).unwrap();
    fresh.solve(p, &mut want).unwrap();
    let dense = dense_answer(k, p, problem, None);
    assert!(report.warning.is_none(), "{what}: {report:?}");
    eprintln!(
        "{what}: vs fresh {:e}, vs dense {:e}, fresh vs dense {:e}",
        max_gap(&got, &want),
        max_gap(&got, &dense),
        max_gap(&want, &dense)
    );
    assert!(
        max_gap(&got, &want) <= 1e-9,
        "{what}: solve vs fresh {:e}",
        max_gap(&got, &want)
    );
    assert!(
        max_gap(&got, &dense) <= 1e-9,
        "{what}: solve vs dense {:e}",
        max_gap(&got, &dense)
    );
    for t in [DVec3::new(0.0, 0.0, 0.05), DVec3::new(0.02, -0.01, 0.1)] {
        solver.drag(dragged, t, p, &mut got).unwrap();
        fresh.drag(dragged, t, p, &mut want).unwrap();
        let dense = dense_answer(k, p, problem, Some((dragged, t)));
        assert!(
            max_gap(&got, &want) <= 1e-9,
            "{what}: drag vs fresh {:e}",
            max_gap(&got, &want)
        );
        assert!(
            max_gap(&got, &dense) <= 1e-9,
            "{what}: drag vs dense {:e}",
            max_gap(&got, &dense)
        );
    }
}

#[test]
fn pins_added_removed_and_switched_answer_like_a_fresh_solver() {
    let s = plate(N);
    let p = s.points().to_vec();
    for scale in [1.0, 100.0] {
        let k = Stiffness::surface(s.u_knots(), s.v_knots(), &material(scale)).unwrap();
        let mut solver = Solver::new(k.clone()).unwrap();
        let base = [
            point(&s, 1, 0.2, 0.3),
            point(&s, 2, 0.7, 0.8),
            load(&s, 9, 0.5, 0.55),
        ];
        let region = pins(&s, 20, &block(12, 14, 6, 5), DVec3::new(0.0, 0.0, 0.02));
        let other = pins(&s, 21, &block(4, 20, 4, 4), DVec3::ZERO);
        let clamp = pins(&s, 22, &clamp_rows(), DVec3::ZERO);
        let with = |extra: &[&Group]| Problem {
            groups: base.iter().chain(extra.iter().copied()).cloned().collect(),
        };
        // The factor's pins: the clamp.
        let steps: Vec<(&str, Problem)> = vec![
            ("clamp", with(&[&clamp])),
            ("region added", with(&[&clamp, &region])),
            ("clamp removed", with(&[&region])),
            ("switched", with(&[&other])),
            ("both", with(&[&region, &other])),
            ("back to the factor's", with(&[&clamp])),
            ("none", with(&[])),
        ];
        for (what, problem) in steps {
            solver.set_problem(problem.clone()).unwrap();
            check(
                &mut solver,
                &k,
                &p,
                &problem,
                9,
                &format!("{what} (×{scale})"),
            );
        }
    }
}

/// A region that holds the shape where it is (no load pulling): the pin
/// change is held over the old factor, the solve proves the shape unchanged
/// without a refactor (still pending), the answer is the dense KKT's; the
/// deferred refactor then changes nothing; switching back to the base
/// problem goes back to the factor's own pins.
#[test]
fn a_region_that_holds_the_shape_costs_no_refactor_and_stays_exact() {
    let s = plate(N);
    let p = s.points().to_vec();
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), &material(1.0)).unwrap();
    let mut solver = Solver::new(k.clone()).unwrap();
    let clamp = pins(&s, 22, &clamp_rows(), DVec3::ZERO);
    let base = Problem {
        groups: vec![clamp, point(&s, 1, 0.2, 0.3), point(&s, 2, 0.7, 0.8)],
    };
    solver.set_problem(base.clone()).unwrap();
    let mut got = vec![DVec3::ZERO; p.len()];
    solver.solve(&p, &mut got).unwrap();
    for (what, region) in [
        ("region", pins(&s, 20, &block(12, 14, 6, 5), DVec3::ZERO)),
        (
            "clamp switched",
            pins(&s, 21, &block(4, 20, 4, 4), DVec3::ZERO),
        ),
    ] {
        let mut groups = base.groups.clone();
        if what == "clamp switched" {
            groups.remove(0);
        }
        groups.push(region);
        let problem = Problem { groups };
        solver.set_problem(problem.clone()).unwrap();
        assert!(solver.pins_pending(), "{what}: held over the old factor");
        let report = solver.solve(&p, &mut got).unwrap();
        assert!(solver.pins_pending(), "{what}: no refactor to prove it");
        let dense = dense_answer(&k, &p, &problem, None);
        assert!(report.constraint_residual <= 1e-12, "{what}: {report:?}");
        let gap = max_gap(&got, &dense);
        assert!(gap <= 1e-9, "{what}: {gap:e}");
        assert!(solver.settle_pins().unwrap(), "{what}: settled");
        let mut settled = vec![DVec3::ZERO; p.len()];
        solver.solve(&p, &mut settled).unwrap();
        let gap = max_gap(&settled, &dense);
        assert!(gap <= 1e-9, "{what}: settled {gap:e}");
        solver.set_problem(base.clone()).unwrap();
        solver.solve(&p, &mut got).unwrap();
    }
}

/// A random sequence of pin changes (region blocks and an edge clamp
/// switched on and off, some lifted, a point constraint and a load
/// pulling): every answer either meets the dense KKT solve to 1e-9 or is
/// an error — never a silent miss.
#[test]
fn a_random_sequence_of_pin_changes_never_misses_silently() {
    let s = plate(N);
    let p = s.points().to_vec();
    let k = Stiffness::surface(s.u_knots(), s.v_knots(), &material(1.0)).unwrap();
    let candidates = [
        pins(&s, 20, &block(12, 14, 6, 5), DVec3::new(0.0, 0.0, 0.02)),
        pins(&s, 21, &block(4, 20, 4, 4), DVec3::ZERO),
        pins(&s, 22, &clamp_rows(), DVec3::ZERO),
        pins(&s, 23, &block(20, 4, 3, 7), DVec3::new(0.01, 0.0, -0.01)),
        pins(&s, 24, &block(24, 24, 2, 2), DVec3::ZERO),
    ];
    let mut solver = Solver::new(k.clone()).unwrap();
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut on = [false; 5];
    let (mut exact, mut updated) = (0, 0);
    for step in 0..24 {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let flip = (seed % 5) as usize;
        on[flip] = !on[flip];
        if step == 12 {
            solver.settle_pins().unwrap();
        }
        let mut groups = vec![point(&s, 1, 0.7, 0.8), load(&s, 9, 0.5, 0.55)];
        groups.extend(
            candidates
                .iter()
                .zip(on)
                .filter(|(_, o)| *o)
                .map(|(g, _)| g.clone()),
        );
        let problem = Problem { groups };
        solver.set_problem(problem.clone()).unwrap();
        updated += usize::from(solver.pins_pending());
        let mut got = vec![DVec3::ZERO; p.len()];
        let t = DVec3::new(0.0, 0.01, 0.05);
        let answers = [
            solver.solve(&p, &mut got).map(|_| (got.clone(), None)),
            solver
                .drag(9, t, &p, &mut got)
                .map(|_| (got.clone(), Some((9, t)))),
        ];
        // An error is allowed (never silent); an Ok answer is exact.
        for (got, dragged) in answers.into_iter().flatten() {
            let dense = dense_answer(&k, &p, &problem, dragged);
            let gap = max_gap(&got, &dense);
            assert!(gap <= 1e-9, "step {step} {on:?}: {gap:e}");
            exact += 1;
        }
    }
    assert!(exact >= 40, "{exact} exact answers");
    assert!(updated > 0, "no change was held without a refactor");
}
