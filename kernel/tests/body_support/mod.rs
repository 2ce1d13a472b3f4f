//! What the Coons-body tests share: a small deterministic random generator
//! (xorshift64), independent of the code under test, so each test's random
//! parameters and lattice moves are the same on every run.

#![allow(dead_code)]

use glam::DVec3;

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
