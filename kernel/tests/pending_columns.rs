//! New constraint rows whose columns of Z are left pending (a supernodal
//! factor: the 81 × 159 paper scene and anything large): their block of
//! S comes from sparse forward solves, the full column is solved only when
//! the shape moves. Checked against full solves and a dense KKT solve.

use glam::DVec3;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Factor, Group, Load, Problem, ScalarRow, Solver};

mod kkt_support;
use kkt_support::{dense_answer, max_gap};

/// `x` solves K x = a to round-off: componentwise against |K||x| + |a|.
fn assert_solves(k: &Stiffness, x: &[f64], a: &[f64], column: usize) {
    let n = k.dim();
    let xs: Vec<DVec3> = x.iter().map(|&v| DVec3::new(v, 0.0, 0.0)).collect();
    let mut kx = vec![DVec3::ZERO; n];
    let mut bound = vec![DVec3::ZERO; n];
    k.mul_points_with_bound(&xs, &mut kx, &mut bound);
    for i in 0..n {
        let r = (kx[i].x - a[i]).abs();
        assert!(
            r <= 1e-12 * (bound[i].x + a[i].abs()),
            "column {column}, point {i}: residual {r:e} against {:e}",
            bound[i].x
        );
    }
}

/// Large enough for a supernodal factor (checked below).
const N: usize = 30;

fn plate(n: usize) -> BSplineSurface {
    BSplineSurface::plane(1.0, 1.0, n, n, 3).unwrap()
}

fn stiffness(s: &BSplineSurface) -> Stiffness {
    let m = SurfaceMaterial {
        alpha11: 0.1,
        alpha12: 0.0,
        alpha22: 0.1,
        beta11: 1.0,
        beta12: 1.0,
        beta22: 1.0,
        rest: 1e-3,
    };
    Stiffness::surface(s.u_knots(), s.v_knots(), &m).unwrap()
}

fn pin(s: &BSplineSurface, key: u64, u: f64, v: f64, target: DVec3) -> Group {
    Group {
        key,
        equations: vec![Equation::Vector {
            row: surface_row(s, u, v, 0, 0),
            target,
        }],
        loads: vec![],
    }
}

#[test]
fn forward_gram_equals_the_gram_of_full_solves() {
    let s = plate(N);
    let k = stiffness(&s);
    let rows: Vec<ScalarRow> = vec![
        surface_row(&s, 0.3, 0.6, 0, 0),
        surface_row(&s, 0.31, 0.62, 0, 0),
        surface_row(&s, 0.8, 0.15, 1, 0),
        surface_row(&s, 0.5, 0.5, 0, 1),
    ];
    let factor = Factor::new(k.clone()).unwrap();
    let columns: Vec<(&[usize], &[f64])> = rows
        .iter()
        .map(|r| (r.indices.as_slice(), r.weights.as_slice()))
        .collect();
    let gram = factor
        .forward_gram(&columns)
        .expect("the factor of a 30 × 30 plate is supernodal");
    // Independent: full solves z_j = K⁻¹ a_j, then a_i · z_j.
    let mut factor = factor;
    let n = k.dim();
    let mut z = faer::Mat::<f64>::zeros(n, rows.len());
    for (j, r) in rows.iter().enumerate() {
        for (&i, &w) in r.indices.iter().zip(&r.weights) {
            z[(i, j)] += w;
        }
    }
    factor.solve_in_place(z.as_mut());
    let k_rows = rows.len();
    let want = |a: usize, b: usize| -> f64 {
        let r = &rows[a];
        r.indices
            .iter()
            .zip(&r.weights)
            .map(|(&i, &w)| w * z[(i, b)])
            .sum()
    };
    let scale = (0..k_rows).map(|a| want(a, a).abs()).fold(0.0, f64::max);
    for a in 0..k_rows {
        for b in 0..k_rows {
            let got = gram[a * k_rows + b];
            assert!(
                (got - want(a, b)).abs() <= 1e-12 * scale,
                "({a}, {b}): {got} vs {}",
                want(a, b)
            );
        }
    }
    // A small factor is simplicial: no forward Gram (the solver then solves
    // new columns in full, as before).
    let small = plate(6);
    assert!(
        Factor::new(stiffness(&small))
            .unwrap()
            .forward_gram(&columns[..0])
            .is_none()
    );
}

/// A solve split in halves: the forward halves of sparse rows (on their
/// elimination-tree reach) or of dense right-hand sides, finished together
/// by one backward pass, equal full solves of the same right-hand sides.
#[test]
fn forward_and_backward_halves_equal_full_solves() {
    let s = plate(N);
    let k = stiffness(&s);
    let n = k.dim();
    let rows: Vec<ScalarRow> = vec![
        surface_row(&s, 0.3, 0.6, 0, 0),
        surface_row(&s, 0.8, 0.15, 1, 0),
        surface_row(&s, 0.05, 0.95, 0, 2),
    ];
    let mut factor = Factor::new(k.clone()).unwrap();
    // Independent: full solves of the scattered rows, and of a dense
    // right-hand side (every point loaded).
    let dense: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
    let mut want = faer::Mat::<f64>::zeros(n, rows.len() + 1);
    for (j, r) in rows.iter().enumerate() {
        for (&i, &w) in r.indices.iter().zip(&r.weights) {
            want[(i, j)] += w;
        }
    }
    for (i, &v) in dense.iter().enumerate() {
        want[(i, rows.len())] = v;
    }
    let mut x = want.clone();
    factor.solve_in_place(want.as_mut());
    let columns: Vec<(&[usize], &[f64])> = rows
        .iter()
        .map(|r| (r.indices.as_slice(), r.weights.as_slice()))
        .collect();
    let halves = factor
        .forward_sparse(&columns)
        .expect("the factor of a 30 × 30 plate is supernodal");
    for (j, h) in halves.iter().enumerate() {
        x.col_mut(j)
            .copy_from(faer::ColRef::from_slice(&h.to_dense()));
    }
    let last = rows.len();
    assert!(factor.forward_in_place(x.as_mut().subcols_mut(last, 1)));
    let before = factor.columns_solved();
    assert!(factor.backward_in_place(x.as_mut()));
    assert_eq!(factor.columns_solved() - before, rows.len() as u64 + 1);
    // Each finished column solves K x = a to round-off (componentwise
    // against |K||x|), and agrees with the full solve as far as K's
    // conditioning lets two backward-stable solves agree.
    for j in 0..=last {
        let mut a = vec![0.0; n];
        if j < last {
            for (&i, &w) in rows[j].indices.iter().zip(&rows[j].weights) {
                a[i] += w;
            }
        } else {
            a.copy_from_slice(&dense);
        }
        assert_solves(&k, x.col_as_slice(j), &a, j);
        let scale = (0..n).fold(0.0f64, |m, i| m.max(want[(i, j)].abs()));
        for i in 0..n {
            assert!(
                (x[(i, j)] - want[(i, j)]).abs() <= 1e-6 * scale,
                "column {j}, point {i}: {} vs {}",
                x[(i, j)],
                want[(i, j)]
            );
        }
    }
    // A small factor is simplicial: no halves (the solver solves in full).
    let mut small = Factor::new(stiffness(&plate(6))).unwrap();
    assert!(small.forward_sparse(&columns[..0]).is_none());
    let mut y = faer::Mat::<f64>::zeros(small.dim(), 1);
    assert!(!small.forward_in_place(y.as_mut()));
    assert!(!small.backward_in_place(y.as_mut()));
}

/// New pins where the surface is cost no full solve; the pending columns
/// are solved when a drag needs them; a pending column dropped before it
/// was solved is not kept as a retired column (re-adding its row and moving
/// the shape must not read an empty column), and every answer equals the
/// dense KKT solution.
#[test]
fn pending_columns_are_solved_when_the_shape_moves_and_answers_stay_exact() {
    let s = plate(N);
    let k = stiffness(&s);
    let p = s.points().to_vec();
    let mut groups: Vec<Group> = [(0.05, 0.05), (0.95, 0.05), (0.05, 0.95), (0.95, 0.95)]
        .iter()
        .enumerate()
        .map(|(i, &(u, v))| pin(&s, i as u64 + 1, u, v, s.point(u, v)))
        .collect();
    groups.push(Group {
        key: 10,
        equations: vec![],
        loads: vec![Load {
            row: surface_row(&s, 0.5, 0.45, 0, 0),
            force: DVec3::new(0.0, 0.0, 0.5),
            drag_gain: 2.0,
        }],
    });
    let mut solver = Solver::new(k.clone()).unwrap();
    solver
        .set_problem(Problem {
            groups: groups.clone(),
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; p.len()];
    solver.solve(&p, &mut out).unwrap();
    let problem = Problem {
        groups: groups.clone(),
    };
    assert!(max_gap(&out, &dense_answer(&k, &p, &problem, None)) < 1e-9);
    let solved = {
        let mut t = s.clone();
        t.set_points(out.clone()).unwrap();
        t
    };
    // Two pins where the solved surface is: no column solved, the shape
    // kept exactly.
    let before = solver.columns_solved();
    let shape = out.clone();
    for (key, (u, v)) in [(20u64, (0.3, 0.6)), (21, (0.62, 0.35))] {
        groups.push(pin(&s, key, u, v, solved.point(u, v)));
        solver
            .set_problem(Problem {
                groups: groups.clone(),
            })
            .unwrap();
        solver.solve(&p, &mut out).unwrap();
    }
    assert_eq!(solver.columns_solved(), before, "the new columns wait");
    assert_eq!(out, shape);
    // A drag frame needs them: solved (one batch), and the frame is the
    // dense KKT answer, the new pins held.
    let t = DVec3::new(0.1, -0.2, 0.7);
    solver.drag(10, t, &p, &mut out).unwrap();
    assert!(solver.columns_solved() > before);
    let problem = Problem {
        groups: groups.clone(),
    };
    let want = dense_answer(&k, &p, &problem, Some((10, t)));
    let gap = max_gap(&out, &want);
    assert!(gap < 1e-9, "drag frame off the dense answer by {gap:e}");
    let mut dragged = s.clone();
    dragged.set_points(out.clone()).unwrap();
    for (u, v) in [(0.3, 0.6), (0.62, 0.35)] {
        let held = (dragged.point(u, v) - solved.point(u, v))
            .abs()
            .max_element();
        assert!(held < 1e-9, "pin at ({u}, {v}) moved by {held:e}");
    }
    // A pin added and dropped before anything solved its column, then
    // added again with a lifted target: the shape moves, exactly.
    let extra = pin(&s, 30, 0.4, 0.2, solved.point(0.4, 0.2));
    let mut with_extra = groups.clone();
    with_extra.push(extra.clone());
    solver
        .set_problem(Problem {
            groups: with_extra.clone(),
        })
        .unwrap();
    solver
        .set_problem(Problem {
            groups: groups.clone(),
        })
        .unwrap();
    let mut lifted = groups.clone();
    lifted.push(pin(
        &s,
        30,
        0.4,
        0.2,
        solved.point(0.4, 0.2) + DVec3::new(0.0, 0.05, 0.2),
    ));
    let problem = Problem { groups: lifted };
    solver.set_problem(problem.clone()).unwrap();
    let report = solver.solve(&p, &mut out).unwrap();
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    let gap = max_gap(&out, &dense_answer(&k, &p, &problem, None));
    assert!(gap < 1e-9, "moving solve off the dense answer by {gap:e}");
}

/// A combination of many rows (as a drag response's first answer is
/// solved: the constraint and load rows weighted by their multipliers and
/// forces) solved by its sparse forward half — only the elimination-tree
/// reach of its non-zeros — and the backward pass: a solution of K x = a
/// to round-off, the same as a full solve of the dense right-hand side.
#[test]
fn a_combined_sparse_right_hand_side_solves_like_a_dense_one() {
    let s = plate(N);
    let k = stiffness(&s);
    let n = k.dim();
    let mut a = vec![0.0; n];
    for (m, (u, v)) in [
        (0.1, 0.1),
        (0.9, 0.15),
        (0.3, 0.6),
        (0.55, 0.45),
        (0.8, 0.85),
    ]
    .into_iter()
    .enumerate()
    {
        let row = surface_row(&s, u, v, 0, 0);
        let weight = [0.7, -1.3, 2.1, -0.4, 1.9][m];
        for (&i, &w) in row.indices.iter().zip(&row.weights) {
            a[i] += weight * w;
        }
    }
    let (indices, weights): (Vec<usize>, Vec<f64>) = a
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(i, v)| (i, *v))
        .unzip();
    let mut factor = Factor::new(k.clone()).unwrap();
    let mut want = faer::Mat::<f64>::from_fn(n, 1, |i, _| a[i]);
    factor.solve_in_place(want.as_mut());
    let half = factor
        .forward_sparse(&[(indices.as_slice(), weights.as_slice())])
        .expect("supernodal")
        .pop()
        .unwrap();
    let half = half.to_dense();
    let mut x = faer::Mat::<f64>::from_fn(n, 1, |i, _| half[i]);
    assert!(factor.backward_in_place(x.as_mut()));
    assert_solves(&k, x.col_as_slice(0), &a, 0);
    let scale = (0..n).fold(0.0f64, |m, i| m.max(want[(i, 0)].abs()));
    for i in 0..n {
        assert!((x[(i, 0)] - want[(i, 0)]).abs() <= 1e-6 * scale);
    }
}
