//! The global sweeps' iterative solve (Laplacian-preconditioned BiCGSTAB,
//! warm-started) against the direct one (sparse LU of the same frozen
//! equations): on perturbed octants of the unit sphere of two sizes the two
//! make the same number of sweeps, the same largest move in every sweep
//! (to round-off) and end at the same points, with the boundary untouched.

use glam::DVec3;
use vsculpt_kernel::fairing::{Control, FairingOptions, PointMesh, SweepSolve, fair_implicit_with};

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
}

/// The octant lattice: point (i, j, k)/|(i, j, k)|, i + j + k = m.
#[allow(clippy::needless_range_loop)] // lattice indices (i, j)
fn octant(m: usize) -> PointMesh {
    let mut index = vec![vec![0u32; m + 1]; m + 1];
    let mut points = Vec::new();
    let mut boundary = Vec::new();
    for i in 0..=m {
        for j in 0..=m - i {
            let k = m - i - j;
            index[i][j] = points.len() as u32;
            points.push(DVec3::new(i as f64, j as f64, k as f64).normalize());
            boundary.push(i == 0 || j == 0 || k == 0);
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

fn perturb(mesh: &mut PointMesh, amount: f64, seed: u64) {
    let mut rng = Lcg(seed);
    for i in 0..mesh.len() {
        if !mesh.boundary[i] {
            let d = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 2.0 * amount;
            mesh.points[i] += d;
        }
    }
}

#[test]
fn iterative_sweeps_equal_direct_sweeps_to_round_off() {
    for (m, amount, seed) in [(24, 0.03, 5), (60, 0.01, 9)] {
        let mut start = octant(m);
        perturb(&mut start, amount, seed);
        let goals = vec![1.0; start.len()];
        let run = |solve| {
            let mut mesh = start.clone();
            let r =
                fair_implicit_with(&mut mesh, &goals, &FairingOptions::default(), solve, |_| {
                    Control::Continue
                })
                .unwrap();
            (mesh, r)
        };
        let (it, ri) = run(SweepSolve::Iterative);
        let (lu, rl) = run(SweepSolve::Direct);
        assert!(ri.converged && rl.converged);
        assert_eq!(ri.iterations, rl.iterations, "m = {m}: sweeps");
        for (k, (a, b)) in ri.history.iter().zip(&rl.history).enumerate() {
            assert!(
                (a - b).abs() <= 1e-11 + 1e-9 * b,
                "m = {m}, sweep {k}: largest move {a:.3e} vs {b:.3e}"
            );
        }
        let apart = it
            .points
            .iter()
            .zip(&lu.points)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        println!("m = {m}: {} sweeps, ends {apart:.2e} apart", ri.iterations);
        assert!(apart < 1e-11, "m = {m}: {apart:.2e} apart");
        for i in 0..start.len() {
            if start.boundary[i] {
                assert_eq!(it.points[i], start.points[i]);
            }
        }
    }
}
