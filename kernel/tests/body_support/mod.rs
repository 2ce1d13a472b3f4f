//! What the Coons-body tests (and the union bench) share: a small
//! deterministic random generator (xorshift64), independent of the code
//! under test, so each test's random parameters and lattice moves are the
//! same on every run; an axis-aligned box as a body.

#![allow(dead_code)]

use glam::DVec3;
use vsculpt_kernel::body::BSplineVolume;

/// An axis-aligned box [lo, hi] as a biquadratic-by-linear lattice (affine
/// lattices reproduce the box exactly at any degree).
pub fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> BSplineVolume {
    let e = [0, 1, 2].map(|a| hi[a] - lo[a]);
    BSplineVolume::affine(
        DVec3::from_array(lo),
        [DVec3::X * e[0], DVec3::Y * e[1], DVec3::Z * e[2]],
        [2, 2, 1],
        [4, 3, 3],
    )
    .unwrap()
}

/// xorshift64 (Marsaglia): seeded, reproducible, no dependency.
pub struct Rng(pub u64);

impl Rng {
    /// The next number in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A vector with coordinates in [−s/2, s/2).
    pub fn vec(&mut self, s: f64) -> DVec3 {
        DVec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * s
    }
}
