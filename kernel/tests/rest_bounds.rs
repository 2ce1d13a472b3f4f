//! The residual tolerance does not grow with the loads' pull (issue 15,
//! item 1): for every `rest` the validator accepts, an answer is either
//! `Ok` with every equation met to 1e-9 of the shape's size, or a clear
//! factorisation error when `rest` is too small against α, β for the grid
//! to be factored at all. Here the loads alone would move the shape 1e4 to
//! 1e13 times its constrained size (K⁻¹b from an unconstrained solve), which
//! the old tolerance (scaled by that pull) accepted answers against.

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector, greville};
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{
    Equation, Group, Load, Problem, RESIDUAL_TOLERANCE, SolveError, Solver,
};

fn extent(p: &[DVec3]) -> f64 {
    p.iter().fold(0.0f64, |a, q| a.max(q.abs().max_element()))
}

/// The held equations of case `case`: two dense curves, one point, or a
/// dense 21 × 21 patch of points (dependent: more equations than the
/// control points under them).
fn held(case: usize, s: &BSplineSurface, pts: &[DVec3]) -> Vec<Equation> {
    let at = |u: f64, v: f64| {
        let row = surface_row(s, u, v, 0, 0);
        let target = row.apply(pts);
        Equation::Vector { row, target }
    };
    match case {
        0 => (0..=40)
            .flat_map(|i| [0.1, 0.9].map(|v| at(i as f64 / 40.0, v)))
            .collect(),
        1 => vec![at(0.2, 0.3)],
        _ => (0..=20)
            .flat_map(|i| (0..=20).map(move |j| (i, j)))
            .map(|(i, j)| at(0.05 + 0.01 * i as f64, 0.7 + 0.0125 * j as f64))
            .collect(),
    }
}

#[test]
fn every_accepted_rest_meets_the_equations_to_the_shape_or_fails_to_factor() {
    let d = SurfaceMaterial::default();
    let (mut answered, mut refused, mut largest_pull) = (0, 0, 0.0f64);
    for n in [18usize, 40] {
        let kv = KnotVector::clamped_uniform(3, n).unwrap();
        let g = greville(&kv);
        let pts: Vec<DVec3> = g
            .iter()
            .flat_map(|&x| g.iter().map(move |&y| DVec3::new(x, y, 0.0)))
            .collect();
        let s = BSplineSurface::new(kv.clone(), kv.clone(), pts.clone()).unwrap();
        let load = Group {
            key: 2,
            equations: vec![],
            loads: vec![Load {
                row: surface_row(&s, 0.5, 0.5, 0, 0),
                force: DVec3::new(0.2, -0.1, 1.0),
                drag_gain: 1.0,
            }],
        };
        for rest in [1e-4, 1e-8, 1e-12] {
            for scale in [0.01, 100.0] {
                let material = SurfaceMaterial {
                    rest,
                    alpha11: d.alpha11 * scale,
                    alpha22: d.alpha22 * scale,
                    beta11: d.beta11 * scale,
                    beta12: d.beta12 * scale,
                    beta22: d.beta22 * scale,
                    ..d
                };
                material.validate().unwrap();
                let k = Stiffness::surface(&kv, &kv, &material).unwrap();
                let mut solver = match Solver::new(k) {
                    Ok(solver) => solver,
                    Err(e) => {
                        assert!(
                            matches!(&e, SolveError::Factor(m) if m.contains("rest")),
                            "{e}"
                        );
                        refused += 1;
                        continue;
                    }
                };
                // The loads' pull alone: no equation.
                solver
                    .set_problem(Problem {
                        groups: vec![load.clone()],
                    })
                    .unwrap();
                let mut free = pts.clone();
                solver.solve(&pts, &mut free).unwrap();
                for case in 0..3 {
                    let equations = held(case, &s, &pts);
                    let targets = equations.iter().fold(0.0f64, |m, e| match e {
                        Equation::Vector { target, .. } => m.max(target.abs().max_element()),
                        _ => m,
                    });
                    solver
                        .set_problem(Problem {
                            groups: vec![
                                Group {
                                    key: 1,
                                    equations,
                                    loads: vec![],
                                },
                                load.clone(),
                            ],
                        })
                        .unwrap();
                    let mut out = pts.clone();
                    let full = solver.solve(&pts, &mut out).unwrap();
                    let scale = extent(&out).max(targets);
                    largest_pull = largest_pull.max(extent(&free) / scale);
                    let mut dragged = pts.clone();
                    let frame = solver
                        .drag(2, DVec3::new(0.3, 0.2, 1.0), &pts, &mut dragged)
                        .unwrap();
                    let drag_scale = extent(&dragged).max(targets);
                    for (report, size) in [(full, scale), (frame, drag_scale)] {
                        assert!(
                            report.constraint_residual <= RESIDUAL_TOLERANCE * size,
                            "n {n} rest {rest:e} x{scale} case {case}: residual {:e} of size {size}",
                            report.constraint_residual
                        );
                        assert_eq!(report.warning, None, "consistent equations are met");
                    }
                    answered += 1;
                }
            }
        }
    }
    // Both paths were taken, and the loads pulled far harder than the
    // shape's size somewhere (else the old tolerance would be the same).
    assert!(
        answered >= 18 && refused >= 2,
        "{answered} answered, {refused} refused"
    );
    eprintln!("{answered} answered, {refused} refused, largest pull {largest_pull:e}");
    assert!(largest_pull > 1e6, "largest pull {largest_pull:e}");
}
