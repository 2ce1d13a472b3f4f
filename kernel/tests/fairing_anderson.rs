//! Anderson-accelerated global sweeps against plain ones: on perturbed
//! octants of the unit sphere (the paper's example, and a finer one) both
//! converge, to the same points (the same fixed point, to within what the
//! convergence threshold leaves), the accelerated run in fewer sweeps; the
//! boundary is untouched; the last sweep's plain residual is under the
//! threshold; and a relaxed run (ω = 0.7, which takes damped plain steps
//! as asked, unaccelerated) ends at that fixed point too.

use vsculpt_kernel::fairing::{Acceleration, FairingOptions, FairingReport, PointMesh};

mod fairing_support;
use fairing_support::{octant, perturb, sweep};

fn run(
    start: &PointMesh,
    acceleration: Acceleration,
    relaxation: f64,
) -> (PointMesh, FairingReport) {
    let options = FairingOptions {
        relaxation,
        ..FairingOptions::default()
    };
    sweep(start, &vec![1.0; start.len()], &options, acceleration)
}

fn apart(a: &PointMesh, b: &PointMesh) -> f64 {
    a.points
        .iter()
        .zip(&b.points)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

#[test]
fn accelerated_sweeps_reach_the_plain_fixed_point_in_fewer_sweeps() {
    for (m, amount, seed) in [(24, 0.03, 5), (60, 0.01, 9)] {
        let mut start = octant(m);
        perturb(&mut start, amount, seed);
        let (plain, rp) = run(&start, Acceleration::Plain, 1.0);
        let (fast, ra) = run(&start, Acceleration::Anderson(5), 1.0);
        let (relaxed, rr) = run(&start, Acceleration::Anderson(5), 0.7);
        let d = apart(&plain, &fast);
        let dr = apart(&plain, &relaxed);
        println!(
            "m = {m}: plain {} sweeps, Anderson {} sweeps (relaxed 0.7: {}), ends {d:.2e} apart (relaxed {dr:.2e})",
            rp.iterations, ra.iterations, rr.iterations
        );
        assert!(rp.converged && ra.converged && rr.converged);
        assert!(
            ra.iterations * 4 <= rp.iterations * 3,
            "m = {m}: {} accelerated sweeps against {} plain",
            ra.iterations,
            rp.iterations
        );
        // Both stop within 1e-10 (of a size ≈ 1.4) of the fixed point's
        // residual; the points agree far below the perturbation (1e-2).
        assert!(d < 1e-8, "m = {m}: {d:.2e} apart");
        assert!(dr < 1e-8, "m = {m}: relaxed run {dr:.2e} apart");
        let (relaxed_plain, _) = run(&start, Acceleration::Plain, 0.7);
        assert_eq!(
            relaxed.points, relaxed_plain.points,
            "a relaxed run was accelerated"
        );
        // The size (bounding-box diagonal) is √3 plus the perturbation.
        assert!(*ra.history.last().unwrap() <= 1e-10 * 1.8);
        for i in 0..start.len() {
            if start.boundary[i] {
                assert_eq!(fast.points[i], start.points[i]);
                assert_eq!(relaxed.points[i], start.points[i]);
            }
        }
    }
}
