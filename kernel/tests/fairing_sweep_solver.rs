//! The global sweeps' iterative solve (Laplacian-preconditioned BiCGSTAB,
//! warm-started) against the direct one (sparse LU of the same frozen
//! equations): on perturbed octants of the unit sphere of two sizes the two
//! make the same number of sweeps, the same largest move in every sweep
//! (to round-off) and end at the same points, with the boundary untouched.

use vsculpt_kernel::fairing::{Control, FairingOptions, SweepSolve, fair_implicit_with};

mod fairing_support;
use fairing_support::{octant, perturb};

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
