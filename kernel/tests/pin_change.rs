//! A change of the pinned set (region and edge icons pin control points:
//! added, removed, switched) is answered through the factor of the old set
//! without a refactor (`solve::pin_update`). Every answer — full solves and
//! drag frames with a load pulling — is checked against a fresh solver on
//! the same problem and against a dense KKT solve independent of the
//! solver; the same after the deferred refactor is installed.

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Group, Load, Problem, ScalarRow, Solver};

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

/// The KKT system [K Cᵀ; C 0] [δ; λ] = [b; d − C P_ref] of one coordinate,
/// solved densely (LU with partial pivoting), independent of the solver.
fn dense_kkt(k: &Stiffness, rows: &[(Vec<usize>, Vec<f64>, f64)], b: &[f64]) -> Vec<f64> {
    use faer::linalg::solvers::Solve;
    let n = k.dim();
    let m = rows.len();
    let mut a = faer::Mat::<f64>::zeros(n + m, n + m);
    let lower = k.lower();
    let (cp, ri, v) = (
        lower.symbolic().col_ptr(),
        lower.symbolic().row_idx(),
        lower.val(),
    );
    for c in 0..n {
        for e in cp[c]..cp[c + 1] {
            a[(ri[e], c)] = v[e];
            a[(c, ri[e])] = v[e];
        }
    }
    let mut rhs = faer::Mat::<f64>::zeros(n + m, 1);
    for (i, x) in b.iter().enumerate() {
        rhs[(i, 0)] = *x;
    }
    for (e, (idx, w, target)) in rows.iter().enumerate() {
        for (&i, &wi) in idx.iter().zip(w) {
            a[(n + e, i)] = wi;
            a[(i, n + e)] = wi;
        }
        rhs[(n + e, 0)] = *target;
    }
    let x = a.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| x[(i, 0)]).collect()
}

/// The exact answer of `problem` from the reference `p` (group `dragged`'s
/// targets shifted by t, its loads' forces by t · gain), by a dense KKT
/// solve per coordinate.
fn dense_answer(
    k: &Stiffness,
    p: &[DVec3],
    problem: &Problem,
    dragged: Option<(u64, DVec3)>,
) -> Vec<DVec3> {
    let mut out = p.to_vec();
    for c in 0..3 {
        let rows: Vec<(Vec<usize>, Vec<f64>, f64)> = problem
            .groups
            .iter()
            .flat_map(|g| {
                let shift = match dragged {
                    Some((key, t)) if key == g.key => t,
                    _ => DVec3::ZERO,
                };
                g.equations.iter().map(move |eq| (eq, shift))
            })
            .map(|(eq, shift)| match eq {
                Equation::Vector { row, target } => (
                    row.indices.clone(),
                    row.weights.clone(),
                    target[c] + shift[c] - row.apply(p)[c],
                ),
                Equation::Projected { .. } => unreachable!(),
            })
            .collect();
        let mut b = vec![0.0; p.len()];
        for g in &problem.groups {
            for l in &g.loads {
                let force = match dragged {
                    Some((key, t)) if key == g.key => l.force + t * l.drag_gain,
                    _ => l.force,
                };
                for (&i, &w) in l.row.indices.iter().zip(&l.row.weights) {
                    b[i] += w * force[c];
                }
            }
        }
        for (o, d) in out.iter_mut().zip(dense_kkt(k, &rows, &b)) {
            o[c] += d;
        }
    }
    out
}

fn max_gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f64::max)
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
        let base = vec![
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
