//! The spring of one load drag (paper 003), on the kernel's spring model
//! ([`vsculpt_kernel::spring::Spring`]): a hand displacement Δx becomes the force
//! f = k Δx with k = κ S (S the surface area); after each solve the icon's actual
//! displacement Δy, reported by the server (`icon_feedback`), adapts κ until
//! 0.8 ≤ Δy/Δx ≤ 1.2.
//!
//! The protocol carries a load drag as the point the load icon is pulled to; the
//! server applies its spring with the initial stiffness k0 = κ0 S to that point, so
//! the bridge sends `origin + f / k0` ([`DragSpring::pull_point`]) and the adapted
//! stiffness reaches the solver unchanged.

use glam::DVec3;
use vsculpt_kernel::spring::{Adaptation, BAND, Spring};

/// Initial coefficient κ0.
pub const KAPPA0: f64 = 1.0;
/// Lower end of the accepted ratio Δy/Δx.
pub const RATIO_MIN: f64 = BAND.0;
/// Upper end of the accepted ratio Δy/Δx.
pub const RATIO_MAX: f64 = BAND.1;

/// The adaptive spring of one drag.
#[derive(Clone, Debug, PartialEq)]
pub struct DragSpring {
    spring: Spring,
    k0: f64,
}

impl DragSpring {
    /// A spring for a surface of area `area` (k0 = κ0 S); an invalid area counts as 1.
    pub fn new(area: f64) -> Self {
        let area = if area.is_finite() && area > 0.0 {
            area
        } else {
            1.0
        };
        let spring = Spring::new(KAPPA0, area)
            .or_else(|_| Spring::new(KAPPA0, 1.0))
            .unwrap_or_else(|_| unreachable_spring());
        Self {
            k0: spring.stiffness(),
            spring,
        }
    }

    /// Current stiffness k = κ S.
    pub fn stiffness(&self) -> f64 {
        self.spring.stiffness()
    }

    /// The initial stiffness k0 = κ0 S.
    pub fn initial_stiffness(&self) -> f64 {
        self.k0
    }

    /// Current κ.
    pub fn kappa(&self) -> f64 {
        self.spring.kappa()
    }

    /// The force for displacement `dx`.
    pub fn force(&self, dx: DVec3) -> DVec3 {
        self.spring.force(dx)
    }

    /// The force for `dx` as the point a load icon at `origin` is pulled to:
    /// `origin + f / k0`, which the server's k0-spring turns back into f.
    pub fn pull_point(&self, origin: DVec3, dx: DVec3) -> DVec3 {
        origin + self.force(dx) / self.k0
    }

    /// Adapts κ from the icon's displacement `dy` under the drag `dx`: the ratio is
    /// the component of Δy along Δx over |Δx| (a pull that moved the icon backwards
    /// counts as no motion).
    pub fn observe(&mut self, dx: DVec3, dy: DVec3) -> Adaptation {
        let len = dx.length();
        if !(len.is_finite() && dy.is_finite()) || len < 1e-9 {
            return Adaptation::NoMeasure;
        }
        let along = (dy.dot(dx) / len).max(0.0);
        self.spring.adapt(len, along)
    }
}

/// κ0 = 1 on a unit size is always a valid spring; this is never reached.
fn unreachable_spring() -> Spring {
    match Spring::new(1.0, 1.0) {
        Ok(s) => s,
        Err(e) => panic!("the kernel rejects κ = 1 on S = 1: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear "surface": the icon moves by c · f for a force f.
    fn settle(c: f64) -> (DragSpring, f64) {
        let mut s = DragSpring::new(2.0);
        let dx = DVec3::new(0.0, 0.0, 0.1);
        let mut ratio = 0.0;
        for _ in 0..60 {
            let dy = s.force(dx) * c;
            ratio = dy.z / dx.z;
            s.observe(dx, dy);
        }
        (s, ratio)
    }

    #[test]
    fn adapts_into_the_band_for_stiff_and_soft_surfaces() {
        for c in [1e-3, 0.1, 0.5, 3.0, 400.0] {
            let (s, ratio) = settle(c);
            assert!(
                (RATIO_MIN..=RATIO_MAX).contains(&ratio),
                "c = {c}: ratio {ratio}"
            );
            assert!(s.kappa() > 0.0);
        }
    }

    #[test]
    fn k0_is_kappa_times_area_and_pull_point_encodes_the_force() {
        let s = DragSpring::new(3.0);
        assert_eq!(s.stiffness(), 3.0 * KAPPA0);
        assert_eq!(s.initial_stiffness(), 3.0 * KAPPA0);
        assert_eq!(s.force(DVec3::X), DVec3::X * 3.0);
        // at κ0 the pulled-to point is the hand displacement itself
        assert_eq!(
            s.pull_point(DVec3::ONE, DVec3::X),
            DVec3::new(2.0, 1.0, 1.0)
        );
    }

    #[test]
    fn tiny_backward_or_bad_observations() {
        let mut s = DragSpring::new(3.0);
        assert_eq!(s.observe(DVec3::ZERO, DVec3::X), Adaptation::NoMeasure);
        assert_eq!(
            s.observe(DVec3::X, DVec3::splat(f64::NAN)),
            Adaptation::NoMeasure
        );
        assert_eq!(s.kappa(), KAPPA0);
        // pulled one way, moved the other: too weak, κ goes up
        assert_eq!(s.observe(DVec3::X, -DVec3::X), Adaptation::Raised);
        assert!(s.kappa() > KAPPA0);
        assert_eq!(DragSpring::new(f64::NAN).stiffness(), KAPPA0);
    }
}
