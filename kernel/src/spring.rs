//! The spring model of paper 003: a drag of Δx becomes a load f = k·Δx, with
//! Δx the displacement from the point where the spring is attached on the
//! surface to the hand (so the load pulls the surface toward the hand). The
//! stiffness starts at k0 = κ·S, S the surface area (or curve length), and κ
//! is adapted from the icon's actual displacement Δy until
//! 0.8 ≤ Δy/Δx ≤ 1.2.
//!
//! Update rule. The load is applied as a force (paper 003), so a linear
//! surface of compliance c at the icon moves Δy = c·k·Δx: the ratio
//! r = Δy/Δx is proportional to κ. Outside the band the rule scales κ by
//! 1/r (aiming at r = 1), clamped to [1.25, 100] when raising and
//! [0.01, 0.8] when lowering. Every step outside the band moves κ by at
//! least a factor 1.25 or 0.8 within [κ_min, κ_max], so the adaptation ends —
//! inside the band or at a bound (then reported); on a linear surface it
//! ends after one step.

use glam::DVec3;
use thiserror::Error;

/// The band the ratio Δy/Δx is kept in.
pub const BAND: (f64, f64) = (0.8, 1.2);

/// A spring parameter is invalid.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("spring: {0}")]
pub struct SpringError(pub String);

/// What one adaptation step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Adaptation {
    /// The ratio is inside the band; κ unchanged.
    InBand,
    /// κ was raised (the spring was too weak).
    Raised,
    /// κ was lowered (the spring was too strong).
    Lowered,
    /// κ is at its bound and the ratio is still outside the band.
    AtLimit,
    /// Δx was too small to measure a ratio; κ unchanged.
    NoMeasure,
}

/// The adaptive spring.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    kappa: f64,
    size: f64,
}

impl Spring {
    /// Smallest κ.
    pub const KAPPA_MIN: f64 = 1e-6;
    /// Largest κ.
    pub const KAPPA_MAX: f64 = 1e9;

    /// A spring with coefficient `kappa` on a shape of size `size` (area or
    /// length); both finite and > 0.
    pub fn new(kappa: f64, size: f64) -> Result<Self, SpringError> {
        if !(kappa.is_finite() && (Self::KAPPA_MIN..=Self::KAPPA_MAX).contains(&kappa)) {
            return Err(SpringError(format!(
                "κ = {kappa} outside [{}, {}]",
                Self::KAPPA_MIN,
                Self::KAPPA_MAX
            )));
        }
        if !(size.is_finite() && size > 0.0) {
            return Err(SpringError(format!("size {size} must be finite and > 0")));
        }
        Ok(Self { kappa, size })
    }

    /// The coefficient κ.
    pub fn kappa(&self) -> f64 {
        self.kappa
    }

    /// The size S the stiffness scales with.
    pub fn size(&self) -> f64 {
        self.size
    }

    /// Updates S (after the shape changed); ignored unless finite and > 0.
    pub fn set_size(&mut self, size: f64) {
        if size.is_finite() && size > 0.0 {
            self.size = size;
        }
    }

    /// The stiffness k = κ·S.
    pub fn stiffness(&self) -> f64 {
        self.kappa * self.size
    }

    /// The load for a displacement `dx` from the attachment to the hand.
    pub fn force(&self, dx: DVec3) -> DVec3 {
        dx * self.stiffness()
    }

    /// One adaptation step from the pull length `dx` and the icon's actual
    /// displacement `dy` (both ≥ 0).
    pub fn adapt(&mut self, dx: f64, dy: f64) -> Adaptation {
        if !(dx.is_finite() && dy.is_finite()) || dx < 1e-12 {
            return Adaptation::NoMeasure;
        }
        let r = dy / dx;
        let factor = if r < BAND.0 {
            (1.0 / r.max(1e-9)).clamp(1.25, 100.0)
        } else if r > BAND.1 {
            (1.0 / r).clamp(0.01, 0.8)
        } else {
            return Adaptation::InBand;
        };
        let next = (self.kappa * factor).clamp(Self::KAPPA_MIN, Self::KAPPA_MAX);
        if next == self.kappa {
            return Adaptation::AtLimit;
        }
        self.kappa = next;
        if factor > 1.0 {
            Adaptation::Raised
        } else {
            Adaptation::Lowered
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear "surface" of compliance c under the force k·Δx: Δy = c·k·Δx.
    fn run(c: f64, kappa: f64) -> (Spring, usize) {
        let mut s = Spring::new(kappa, 2.0).unwrap();
        for steps in 0..100 {
            let dy = s.stiffness() * c;
            match s.adapt(1.0, dy) {
                Adaptation::InBand => return (s, steps),
                Adaptation::AtLimit => panic!("hit a bound"),
                _ => {}
            }
        }
        panic!("did not end");
    }

    #[test]
    fn adaptation_ends_in_band_for_soft_and_stiff_models() {
        for c in [1e-4, 1e-2, 1.0, 10.0] {
            for kappa in [1e-3, 1.0, 1e4] {
                let (s, steps) = run(c, kappa);
                let r = s.stiffness() * c;
                assert!((BAND.0..=BAND.1).contains(&r), "c={c} κ={kappa}: r={r}");
                assert!(steps <= 4, "c={c} κ={kappa}: {steps} steps");
            }
        }
    }

    #[test]
    fn too_strong_is_lowered_and_bad_input_is_ignored() {
        let mut s = Spring::new(10.0, 1.0).unwrap();
        assert_eq!(s.adapt(1.0, 2.0), Adaptation::Lowered);
        assert!(s.kappa() < 10.0);
        let k = s.kappa();
        assert_eq!(s.adapt(0.0, 1.0), Adaptation::NoMeasure);
        assert_eq!(s.adapt(f64::NAN, 1.0), Adaptation::NoMeasure);
        assert_eq!(s.kappa(), k);
        assert!(Spring::new(f64::NAN, 1.0).is_err());
        assert!(Spring::new(1.0, -1.0).is_err());
        assert_eq!(s.force(DVec3::X), DVec3::X * s.stiffness());
    }
}
