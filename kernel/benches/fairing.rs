//! Fairing a 10 011-point mesh to convergence: the octant of the unit
//! sphere at 140 segments per edge, interior perturbed by up to ±0.005,
//! mean-curvature goal 1, converged when a sweep moves no point more than
//! 1e-10 of the size. `global_sweeps`: [`fair_implicit`] (each sweep a
//! Laplacian-preconditioned BiCGSTAB solve of the frozen equations,
//! warm-started, the sweeps stepped by Anderson acceleration);
//! `global_sweeps_plain`: the same without acceleration (plain steps, the
//! previous implementation); `global_sweeps_lu`: the sweeps each solved by a
//! sparse LU (symbolic factorisation kept); baseline `laplacian`: uniform
//! Laplacian smoothing solved to its fixed point (one sparse Cholesky),
//! the straightforward smoother that does not keep the curvature. The
//! local (Gauss–Seidel) sweeps of [`fair`] need O(n) sweeps here and are
//! measured on the paper's 325-point octant instead (`local_sweeps_325`).
//! Target: ≤ 1 s.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use vsculpt_kernel::fairing::{
    Acceleration, Control, FairingOptions, PointMesh, SweepSolve, fair, fair_implicit,
    fair_implicit_with, fair_sweeps, laplacian_implicit,
};

#[allow(clippy::needless_range_loop)] // lattice indices (i, j)
fn octant(m: usize, amount: f64) -> PointMesh {
    let mut index = vec![vec![0u32; m + 1]; m + 1];
    let mut points = Vec::new();
    let mut boundary = Vec::new();
    let mut state = 11u64;
    for i in 0..=m {
        for j in 0..=m - i {
            let k = m - i - j;
            index[i][j] = points.len() as u32;
            let mut p = DVec3::new(i as f64, j as f64, k as f64).normalize();
            let edge = i == 0 || j == 0 || k == 0;
            if !edge {
                let mut r = || {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
                };
                p += DVec3::new(r(), r(), r()) * 2.0 * amount;
            }
            points.push(p);
            boundary.push(edge);
        }
    }
    let mut tris = Vec::new();
    for i in 0..m {
        for j in 0..m - i {
            tris.push([index[i][j], index[i + 1][j], index[i][j + 1]]);
            if i + j + 1 < m {
                tris.push([index[i + 1][j], index[i + 1][j + 1], index[i][j + 1]]);
            }
        }
    }
    PointMesh::new(points, tris, boundary).unwrap()
}

fn bench(c: &mut Criterion) {
    let big = octant(140, 0.005);
    let goals = vec![1.0; big.len()];
    let mut results = Vec::new();
    for (solve, acceleration) in [
        (SweepSolve::Iterative, Acceleration::default()),
        (SweepSolve::Direct, Acceleration::default()),
        (SweepSolve::Iterative, Acceleration::Plain),
    ] {
        let mut probe = big.clone();
        let r = fair_sweeps(
            &mut probe,
            &goals,
            &FairingOptions::default(),
            solve,
            acceleration,
            |_| Control::Continue,
        )
        .unwrap();
        let dist = probe
            .points
            .iter()
            .map(|p| (p.length() - 1.0).abs())
            .fold(0.0, f64::max);
        println!(
            "{} points, {solve:?}, {acceleration:?}: {} global sweeps, converged {}, distance to sphere {dist:.2e}",
            big.len(),
            r.iterations,
            r.converged
        );
        results.push(probe);
    }
    let apart = results[0]
        .points
        .iter()
        .zip(&results[1].points)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    println!("iterative and direct sweeps end {apart:.2e} apart");
    let plain_apart = results[0]
        .points
        .iter()
        .zip(&results[2].points)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    println!("accelerated and plain sweeps end {plain_apart:.2e} apart");
    let mut g = c.benchmark_group("fairing_10k");
    g.sample_size(10);
    g.bench_function("global_sweeps", |b| {
        b.iter(|| {
            let mut m = big.clone();
            fair_implicit(&mut m, &goals, &FairingOptions::default(), |_| {
                Control::Continue
            })
            .unwrap()
        })
    });
    g.bench_function("global_sweeps_plain", |b| {
        b.iter(|| {
            let mut m = big.clone();
            fair_sweeps(
                &mut m,
                &goals,
                &FairingOptions::default(),
                SweepSolve::Iterative,
                Acceleration::Plain,
                |_| Control::Continue,
            )
            .unwrap()
        })
    });
    g.bench_function("global_sweeps_lu", |b| {
        b.iter(|| {
            let mut m = big.clone();
            fair_implicit_with(
                &mut m,
                &goals,
                &FairingOptions::default(),
                SweepSolve::Direct,
                |_| Control::Continue,
            )
            .unwrap()
        })
    });
    g.bench_function("laplacian", |b| {
        b.iter(|| {
            let mut m = big.clone();
            laplacian_implicit(&mut m).unwrap();
            m.points[100]
        })
    });
    g.finish();
    let small = octant(24, 0.03);
    let goals = vec![1.0; small.len()];
    let mut g = c.benchmark_group("fairing_325");
    g.sample_size(10);
    g.bench_function("local_sweeps_325", |b| {
        b.iter(|| {
            let mut m = small.clone();
            fair(&mut m, &goals, &FairingOptions::default(), |_| {
                Control::Continue
            })
            .unwrap()
        })
    });
    g.bench_function("global_sweeps_325", |b| {
        b.iter(|| {
            let mut m = small.clone();
            fair_implicit(&mut m, &goals, &FairingOptions::default(), |_| {
                Control::Continue
            })
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
