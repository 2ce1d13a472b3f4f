//! Fairing the bottle demo's faces as the server's fairing job does
//! (`server/src/design/fairing_job.rs`): each face of
//! `network::demo::bottle()` sampled at the server's resolution (12
//! segments per lattice side), goals in mean curvature interpolated from
//! the boundary, threshold 1e-10 of the size. Anderson-accelerated sweeps
//! must converge on every face, in no more sweeps than plain ones, to the
//! same fixed point (1e-9), leaving the boundary untouched.

use vsculpt_kernel::fairing::{
    Acceleration, FairingOptions, FairingReport, Goals, Measure, PointMesh, resolve,
};
use vsculpt_kernel::network::{PatchSampler, demo};

mod fairing_support;
use fairing_support::sweep;

/// The server's `MESH_RESOLUTION`.
const RESOLUTION: usize = 12;

fn faces(drag: f64) -> Vec<PointMesh> {
    let mut net = demo::bottle().unwrap();
    let mut ring = net.curves()[0].clone();
    ring.points_mut()[18] += glam::DVec3::new(drag, 0.0, 0.0);
    net.set_curve(0, ring).unwrap();
    net.patches()
        .iter()
        .map(|patch| {
            let mut sampler = PatchSampler::new(patch, RESOLUTION);
            let mut points = Vec::new();
            assert!(sampler.evaluate(patch, &mut points));
            let dm = sampler.mesh();
            PointMesh::new(points, dm.triangles.clone(), dm.boundary.clone()).unwrap()
        })
        .collect()
}

fn run(start: &PointMesh, acceleration: Acceleration) -> (PointMesh, FairingReport) {
    let goals = resolve(start, Measure::Mean, &Goals::FromBoundary).unwrap();
    let options = FairingOptions {
        max_iterations: 1000,
        ..FairingOptions::default()
    };
    sweep(start, &goals, &options, acceleration)
}

#[test]
fn anderson_fairs_every_bottle_face_in_no_more_sweeps_than_plain_to_the_same_points() {
    for drag in [0.0, 0.05, 0.1] {
        let faces = faces(drag);
        assert_eq!(faces.len(), 6);
        println!("bottom ring's control point 18 moved by {drag}:");
        for (f, start) in faces.iter().enumerate() {
            let (plain, rp) = run(start, Acceleration::Plain);
            let (fast, ra) = run(start, Acceleration::Anderson(5));
            let apart = plain
                .points
                .iter()
                .zip(&fast.points)
                .map(|(p, q)| (*p - *q).length())
                .fold(0.0, f64::max);
            println!(
                "face {f} ({} points): plain {} sweeps (converged {}), Anderson {} sweeps (converged {}), {apart:.2e} apart",
                start.len(),
                rp.iterations,
                rp.converged,
                ra.iterations,
                ra.converged
            );
            let show = |h: &[f64]| {
                h.iter()
                    .map(|m| format!("{m:.1e}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("  plain history: {}", show(&rp.history));
            println!("  Anderson history: {}", show(&ra.history));
            assert!(rp.converged, "face {f}: plain sweeps did not converge");
            assert!(ra.converged, "face {f}: Anderson sweeps did not converge");
            assert!(
                ra.iterations <= rp.iterations,
                "face {f}: {} accelerated sweeps against {} plain",
                ra.iterations,
                rp.iterations
            );
            assert!(apart < 1e-9, "face {f}: {apart:.2e} apart");
            for i in 0..start.len() {
                if start.boundary[i] {
                    assert_eq!(fast.points[i], start.points[i], "face {f}: boundary moved");
                }
            }
        }
    }
}
