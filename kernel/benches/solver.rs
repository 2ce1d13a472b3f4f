//! The solver alone (no icons, no re-placement) on the paper's five surfaces
//! (paper 003, Table 2: 20×15 … 81×159 bicubic control points, clamped
//! uniform knots), each with 4 point position constraints, 1 curve
//! constraint (20 `Vector` equations sampled along a curve in (u,v)) and one
//! dragged point load. Measures:
//!
//! * `assemble` — the exact Galerkin stiffness;
//! * `drag_frame` — one `Solver::drag` of the load (the response is cached);
//! * `constraint_change` — `set_problem` with one more position equation
//!   (a new row each iteration, so its column is really solved);
//! * `refactor` — a numeric refactorisation for new material values, with
//!   every column of the problem solved again;
//! * `full_solve` — `Solver::solve` with the problem's targets and loads
//!   (alternating two reference shapes, so each is a real, refined solve);
//! * `sparse_solve_1` / `_3` / `_9` — one K⁻¹ solve with 1, 3 or 9
//!   right-hand sides: the floor under a constraint change (its new columns)
//!   and a refinement step (x, y, z). The solve streams L once per direction
//!   and is memory-bound: 9 columns cost far less than 3 solves of 3.
//!
//! Run: `cargo bench -p vsculpt-kernel --bench solver`.

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;
use std::time::Duration;
use vsculpt_kernel::bspline::BSplineSurface;
use vsculpt_kernel::energy::{Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::surface_row;
use vsculpt_kernel::solve::{Equation, Factor, Group, Load, Problem, Solver};

/// (nu, nv) of paper 003's Table 2.
const GRIDS: [(usize, usize); 5] = [(20, 15), (38, 32), (42, 40), (91, 54), (81, 159)];

/// The group key of the dragged load.
const LOAD: u64 = 100;

fn surface(nu: usize, nv: usize) -> BSplineSurface {
    BSplineSurface::plane(nu as f64 / 10.0, nv as f64 / 10.0, nu, nv, 3).expect("plane")
}

fn position(s: &BSplineSurface, key: u64, u: f64, v: f64, lift: f64) -> Group {
    Group {
        key,
        equations: vec![Equation::Vector {
            row: surface_row(s, u, v, 0, 0),
            target: s.point(u, v) + DVec3::Z * lift,
        }],
        loads: vec![],
    }
}

/// 4 point constraints, a 20-sample curve constraint and a point load.
fn problem(s: &BSplineSurface) -> Problem {
    let mut groups: Vec<Group> = [(0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)]
        .iter()
        .enumerate()
        .map(|(k, &(u, v))| position(s, k as u64 + 1, u, v, 0.05 * k as f64))
        .collect();
    let curve = (0..20)
        .map(|k| {
            let t = k as f64 / 19.0;
            let (u, v) = (0.25 + 0.5 * t, 0.3 + 0.3 * t * t);
            Equation::Vector {
                row: surface_row(s, u, v, 0, 0),
                target: s.point(u, v),
            }
        })
        .collect();
    groups.push(Group {
        key: 10,
        equations: curve,
        loads: vec![],
    });
    groups.push(Group {
        key: LOAD,
        equations: vec![],
        loads: vec![Load {
            row: surface_row(s, 0.5, 0.75, 0, 0),
            force: DVec3::ZERO,
            drag_gain: 1.0,
        }],
    });
    Problem { groups }
}

fn stiffness(s: &BSplineSurface, m: &SurfaceMaterial) -> Stiffness {
    Stiffness::surface(s.u_knots(), s.v_knots(), m).expect("stiffness")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("solver");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let material = SurfaceMaterial::default();
    let stiffer = SurfaceMaterial {
        beta11: 2.0,
        ..material
    };
    for &(nu, nv) in &GRIDS {
        let label = format!("{nu}x{nv}");
        let s = surface(nu, nv);
        let base = problem(&s);
        let mut solver = Solver::new(stiffness(&s, &material)).expect("factor");
        solver.set_problem(base.clone()).expect("problem");
        let mut out = vec![DVec3::ZERO; s.points().len()];

        group.bench_function(BenchmarkId::new("assemble", &label), |b| {
            b.iter(|| black_box(stiffness(&s, &material)))
        });

        solver.solve(s.points(), &mut out).expect("solve");
        let mut frame = 0u64;
        group.bench_function(BenchmarkId::new("drag_frame", &label), |b| {
            b.iter(|| {
                frame += 1;
                let t = DVec3::new(0.0, 0.0, 1e-3 * (frame % 100) as f64);
                black_box(solver.drag(LOAD, t, s.points(), &mut out).expect("drag"))
            })
        });

        let mut change = 0u64;
        group.bench_function(BenchmarkId::new("constraint_change", &label), |b| {
            b.iter(|| {
                change += 1;
                // A different parameter every time: its row is not cached.
                let u = 0.2 + 0.6 * ((change as f64 * 0.618_033_988_75) % 1.0);
                let mut p = base.clone();
                p.groups.push(position(&s, 50, u, 0.45, 0.1));
                solver.set_problem(p).expect("problem");
            })
        });

        let values = [stiffness(&s, &stiffer), stiffness(&s, &material)];
        let mut which = 0usize;
        group.bench_function(BenchmarkId::new("refactor", &label), |b| {
            b.iter_batched(
                || {
                    which ^= 1;
                    values[which].clone()
                },
                |k| solver.refactor(k).expect("refactor"),
                BatchSize::LargeInput,
            )
        });

        solver.set_problem(base.clone()).expect("problem");
        // Two reference shapes in turn, so every iteration is a real solve
        // (a repeated solve of an unchanged problem is answered at once).
        let shifted: Vec<DVec3> = s.points().iter().map(|p| *p + DVec3::Z * 1e-3).collect();
        let references = [s.points().to_vec(), shifted];
        let mut turn = 0usize;
        group.bench_function(BenchmarkId::new("full_solve", &label), |b| {
            b.iter(|| {
                turn ^= 1;
                black_box(solver.solve(&references[turn], &mut out).expect("solve"))
            })
        });

        // Fresh right-hand sides every iteration (repeated K⁻¹ would overflow).
        let mut factor = Factor::new(stiffness(&s, &material)).expect("factor");
        let n = factor.dim();
        for k in [1usize, 3, 9] {
            let rhs = faer::Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j) % 11) as f64);
            group.bench_function(BenchmarkId::new(format!("sparse_solve_{k}"), &label), |b| {
                b.iter_batched_ref(
                    || rhs.clone(),
                    |x| factor.solve_in_place(x.as_mut()),
                    BatchSize::SmallInput,
                )
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
