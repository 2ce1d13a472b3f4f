//! What the fairing tests share: the paper's test mesh — an octant of the
//! unit sphere as a triangulated lattice —, a seeded perturbation of its
//! interior (an LCG independent of the code under test), and a run of
//! global sweeps to convergence.

#![allow(dead_code)]

use glam::DVec3;
use vsculpt_kernel::fairing::{
    Acceleration, Control, FairingOptions, FairingReport, PointMesh, SweepSolve, fair_sweeps,
};

/// `start` faired towards `goals` by global sweeps (iterative solves) with
/// `acceleration` until `options` says it has converged: the faired mesh
/// and the report.
pub fn sweep(
    start: &PointMesh,
    goals: &[f64],
    options: &FairingOptions,
    acceleration: Acceleration,
) -> (PointMesh, FairingReport) {
    let mut mesh = start.clone();
    let report = fair_sweeps(
        &mut mesh,
        goals,
        options,
        SweepSolve::Iterative,
        acceleration,
        |_| Control::Continue,
    )
    .unwrap();
    (mesh, report)
}

/// A 64-bit linear congruential generator (Knuth's MMIX constants).
pub struct Lcg(pub u64);
impl Lcg {
    /// The next number in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
}

/// The octant lattice: point (i, j, k)/|(i, j, k)|, i + j + k = m.
#[allow(clippy::needless_range_loop)] // lattice indices (i, j)
pub fn octant(m: usize) -> PointMesh {
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

/// Moves every interior point by up to ±`amount` per coordinate.
pub fn perturb(mesh: &mut PointMesh, amount: f64, seed: u64) {
    let mut rng = Lcg(seed);
    for i in 0..mesh.len() {
        if !mesh.boundary[i] {
            let d = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 2.0 * amount;
            mesh.points[i] += d;
        }
    }
}
