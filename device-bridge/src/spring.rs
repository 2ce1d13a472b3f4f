//! The spring of one load drag (paper 003): a hand displacement Δx becomes the
//! force f = k Δx with k = κ S (S the surface area); after each solve the icon's
//! actual displacement Δy is compared with Δx and κ is corrected until
//! 0.8 ≤ Δy/Δx ≤ 1.2.

/// Initial coefficient κ.
pub const KAPPA0: f64 = 1.0;
/// Lower end of the accepted ratio Δy/Δx.
pub const RATIO_MIN: f64 = 0.8;
/// Upper end of the accepted ratio Δy/Δx.
pub const RATIO_MAX: f64 = 1.2;
/// Largest factor κ changes by in one observation (keeps the loop stable).
const MAX_STEP: f64 = 2.0;
/// Drags shorter than this (scene units) say nothing about the stiffness.
const MIN_DRAG: f64 = 1e-6;

use glam::DVec3;

/// The adaptive spring of one drag.
#[derive(Clone, Debug, PartialEq)]
pub struct DragSpring {
    kappa: f64,
    area: f64,
}

impl DragSpring {
    /// A spring for a surface of area `area` (k0 = κ0 S).
    pub fn new(area: f64) -> Self {
        Self {
            kappa: KAPPA0,
            area: if area.is_finite() && area > 0.0 {
                area
            } else {
                1.0
            },
        }
    }

    /// Current stiffness k = κ S.
    pub fn stiffness(&self) -> f64 {
        self.kappa * self.area
    }

    /// Current κ.
    pub fn kappa(&self) -> f64 {
        self.kappa
    }

    /// The force for displacement `dx`.
    pub fn force(&self, dx: DVec3) -> DVec3 {
        dx * self.stiffness()
    }

    /// The initial stiffness k0 = κ0 S.
    pub fn initial_stiffness(&self) -> f64 {
        KAPPA0 * self.area
    }

    /// The force for `dx` expressed as the point a load icon at `origin` is pulled
    /// to: the server applies the spring with its initial stiffness k0 = κ0 S to the
    /// pulled-to point (`move`/`drag` of a load icon, protocol `Role::Load`), so the
    /// point `origin + f / k0` yields exactly the force f = k Δx of the adapted spring.
    pub fn pull_point(&self, origin: DVec3, dx: DVec3) -> DVec3 {
        origin + self.force(dx) / self.initial_stiffness()
    }

    /// Adapts κ from the icon's displacement `dy` under the drag `dx`. The ratio is
    /// the component of Δy along Δx over |Δx|; outside [0.8, 1.2] κ is scaled by
    /// 1/ratio (exact when the response is linear), by at most a factor 2 per step.
    pub fn observe(&mut self, dx: DVec3, dy: DVec3) {
        let len2 = dx.length_squared();
        if !(len2.is_finite() && dy.is_finite()) || len2 < MIN_DRAG * MIN_DRAG {
            return;
        }
        let ratio = dy.dot(dx) / len2;
        if (RATIO_MIN..=RATIO_MAX).contains(&ratio) {
            return;
        }
        let factor = if ratio <= 0.0 {
            MAX_STEP
        } else {
            (1.0 / ratio).clamp(1.0 / MAX_STEP, MAX_STEP)
        };
        self.kappa *= factor;
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
        for _ in 0..50 {
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
    fn k0_is_kappa_times_area_and_tiny_or_bad_drags_change_nothing() {
        let mut s = DragSpring::new(3.0);
        assert_eq!(s.stiffness(), 3.0 * KAPPA0);
        assert_eq!(s.force(DVec3::X), DVec3::X * 3.0);
        s.observe(DVec3::ZERO, DVec3::X);
        s.observe(DVec3::X, DVec3::splat(f64::NAN));
        assert_eq!(s.kappa(), KAPPA0);
        assert_eq!(DragSpring::new(f64::NAN).stiffness(), KAPPA0);
    }
}
