//! A solve is exact or says why not (issue 15, item 3): redundant equations
//! are answered exactly, contradictory ones get the least-squares answer
//! and a typed warning, and a residual above tolerance on independent
//! equations is an error, never `Ok`.

use glam::DVec3;
use vsculpt_kernel::bspline::{KnotVector, greville};
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{
    Equation, Group, Load, Problem, RESIDUAL_TOLERANCE, ScalarRow, SolveError, SolveWarning, Solver,
};

/// A flat unit square of `n × n` bicubic control points, its solver and the
/// row of w at (0.4, 0.6).
fn plane(n: usize, material: &SurfaceMaterial) -> (Vec<DVec3>, Solver, ScalarRow) {
    let kv = KnotVector::clamped_uniform(3, n).unwrap();
    let g = greville(&kv);
    let pts: Vec<DVec3> = g
        .iter()
        .flat_map(|&x| g.iter().map(move |&y| DVec3::new(x, y, 0.0)))
        .collect();
    let s =
        vsculpt_kernel::bspline::BSplineSurface::new(kv.clone(), kv.clone(), pts.clone()).unwrap();
    let row = surface_row(&s, 0.4, 0.6, 0, 0);
    let solver = Solver::new(Stiffness::surface(&kv, &kv, material).unwrap()).unwrap();
    (pts, solver, row)
}

fn at(row: &ScalarRow, target: DVec3) -> Equation {
    Equation::Vector {
        row: row.clone(),
        target,
    }
}

#[test]
fn redundant_equations_are_met_and_contradictory_ones_warned() {
    let (pts, mut solver, row) = plane(10, &SurfaceMaterial::default());
    let here = row.apply(&pts);
    let up = here + DVec3::Z * 0.1;
    // The same point held twice at the same place: redundant, met exactly.
    solver
        .set_problem(Problem {
            groups: vec![
                Group {
                    key: 1,
                    equations: vec![at(&row, up)],
                    loads: vec![],
                },
                Group {
                    key: 2,
                    equations: vec![at(&row, up)],
                    loads: vec![],
                },
            ],
        })
        .unwrap();
    let mut out = pts.clone();
    let r = solver.solve(&pts, &mut out).unwrap();
    assert_eq!(r.rank_deficiency, 3, "{r:?}");
    assert!(r.constraint_residual < 1e-12, "{r:?}");
    assert_eq!(r.warning, None);
    assert!((row.apply(&out) - up).length() < 1e-12);
    // Held at two places: the least-squares answer is the middle, the
    // residual half the gap, and the report says so.
    let down = here - DVec3::Z * 0.1;
    solver
        .set_problem(Problem {
            groups: vec![
                Group {
                    key: 1,
                    equations: vec![at(&row, up)],
                    loads: vec![],
                },
                Group {
                    key: 2,
                    equations: vec![at(&row, down)],
                    loads: vec![],
                },
            ],
        })
        .unwrap();
    let r = solver.solve(&pts, &mut out).unwrap();
    assert!((r.constraint_residual - 0.1).abs() < 1e-12, "{r:?}");
    assert!((row.apply(&out) - here).length() < 1e-12);
    match r.warning {
        Some(SolveWarning::Dependent { dropped, residual }) => {
            assert_eq!(dropped, 3);
            assert_eq!(residual, r.constraint_residual);
        }
        other => panic!("no warning: {other:?}"),
    }
}

#[test]
fn independent_equations_are_met_to_tolerance_or_refused() {
    // A plate with its two outer rings pinned under a uniform pull, on grids
    // up to where the Schur complement loses digits: every answer either
    // meets every pin to tolerance or is an Inexact error — never an `Ok`
    // that misses.
    for n in [11, 19, 35] {
        let (pts, mut solver, _) = plane(n, &SurfaceMaterial::default());
        let mut group = Group {
            key: 1,
            ..Group::default()
        };
        for i in 0..n {
            for j in 0..n {
                if i.min(j).min(n - 1 - i).min(n - 1 - j) < 2 {
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
            row: ScalarRow {
                indices: (0..n * n).collect(),
                weights: vec![1.0 / (n * n) as f64; n * n],
            },
            force: DVec3::Z * 1e3,
            drag_gain: 0.0,
        });
        solver
            .set_problem(Problem {
                groups: vec![group],
            })
            .unwrap();
        let mut out = pts.clone();
        match solver.solve(&pts, &mut out) {
            Ok(r) => {
                let size = out.iter().fold(1.0f64, |m, p| m.max(p.abs().max_element()));
                let worst = pts
                    .iter()
                    .zip(&out)
                    .enumerate()
                    .filter(|(c, _)| {
                        let (i, j) = (c / n, c % n);
                        i.min(j).min(n - 1 - i).min(n - 1 - j) < 2
                    })
                    .map(|(_, (a, b))| (*a - *b).length())
                    .fold(0.0, f64::max);
                // The report is honest: the pins are off by what it says
                // (measured here per coordinate, independently).
                let worst_coord = pts
                    .iter()
                    .zip(&out)
                    .enumerate()
                    .filter(|(c, _)| {
                        let (i, j) = (c / n, c % n);
                        i.min(j).min(n - 1 - i).min(n - 1 - j) < 2
                    })
                    .map(|(_, (a, b))| (*a - *b).abs().max_element())
                    .fold(0.0, f64::max);
                assert!((worst_coord - r.constraint_residual).abs() <= 1e-15 * size);
                assert!(worst <= 2.0 * worst_coord);
                // And an `Ok` with no warning is within tolerance of the
                // shape or of the pull it cancels (≤ 1e3 here).
                assert!(
                    r.warning.is_some() || worst_coord <= RESIDUAL_TOLERANCE * size.max(1e3),
                    "{n}: pins off by {worst_coord:e}, {r:?}"
                );
            }
            Err(SolveError::Inexact {
                residual,
                tolerance,
            }) => {
                assert!(residual > tolerance, "{n}");
            }
            Err(e) => panic!("{n}: {e}"),
        }
    }
}
