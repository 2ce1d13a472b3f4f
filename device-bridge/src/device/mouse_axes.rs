//! A 3D mouse's six axes, from the values of its wire format to the bridge's
//! frame, through the per-device calibration (`full_scale`, `deadzone`,
//! `axis_scale`, `axis_signs` in the device's `spacemouse = {…}` or
//! `spacenavd = {…}` settings).
//!
//! The order of operations, for both the HID reports and spacenavd's events:
//! 1. the six values in spacenavd's axis order and frame: x right, y up, z away
//!    from the user; rx, ry, rz the twists about those axes, each positive by the
//!    right-hand rule of that (left-handed) frame — the HID decoder first applies
//!    spacenavd's per-model "swap y-z, invert y-z" (FreeSpacenav `src/dev.c`
//!    `read_device`: device axes 1↔2 and 4↔5 swapped, then 1, 2, 4, 5 negated);
//!    spacenavd's own events already come so;
//! 2. to the bridge's right-handed frame (x right, y up, z towards the user) by
//!    negating z and rz, as libspnav's `spnav_posrot_moveobj` does
//!    ([`to_bridge_frame`]);
//! 3. divided by `full_scale` (the value at full deflection, about 350 for every
//!    3Dconnexion model and spacenavd at sensitivity 1) and clamped to [-1, 1];
//! 4. a dead zone per bridge axis (a fraction of full scale): below it the axis
//!    reads 0; above it the value ramps from 0, so full deflection still reads 1
//!    and the response has no step (spacenavd's `dead-zoneN` only cuts, in raw
//!    units, before its own mapping);
//! 5. times `axis_scale` and `axis_signs` per axis (like spacenavd's per-axis
//!    sensitivity and `invert-trans` / `invert-rot`).
//!
//! A value exactly 0 on all six axes means the cap is at rest.

use glam::DVec3;

/// Default dead zone, a fraction of full scale per axis (≈ 17 of ±350 counts: a
/// cap at rest reads a few counts of drift, a deliberate push hundreds).
pub const DEFAULT_DEADZONE: f64 = 0.05;

/// spacenavd's axes (x right, y up, z away from the user) to the bridge's
/// right-handed frame (x right, y up, z towards the user), as libspnav's
/// `spnav_posrot_moveobj` does: translation `(x, y, −z)`, rotation `(rx, ry, −rz)`.
pub fn to_bridge_frame(translation: DVec3, rotation: DVec3) -> (DVec3, DVec3) {
    (
        DVec3::new(translation.x, translation.y, -translation.z),
        DVec3::new(rotation.x, rotation.y, -rotation.z),
    )
}

/// The calibration of one 3D mouse's axes (a view of its device settings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MouseAxes {
    /// Value that maps to 1.0 (full deflection).
    pub full_scale: f64,
    /// Dead zone per bridge axis x, y, z, rx, ry, rz, a fraction of full scale in [0, 1).
    pub deadzone: [f64; 6],
    /// Gain per bridge axis (≥ 0).
    pub axis_scale: [f64; 6],
    /// Sign per bridge axis (1 or −1).
    pub axis_signs: [f64; 6],
}

impl MouseAxes {
    /// Checks the calibration; the error names the setting.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.full_scale.is_finite() && self.full_scale > 0.0) {
            return Err(format!(
                "full_scale must be positive, got {}",
                self.full_scale
            ));
        }
        if let Some(d) = self.deadzone.iter().find(|d| !(0.0..1.0).contains(*d)) {
            return Err(format!(
                "deadzone values are fractions of full scale in [0, 1), got {d}"
            ));
        }
        if let Some(s) = self
            .axis_scale
            .iter()
            .find(|s| !(s.is_finite() && **s >= 0.0))
        {
            return Err(format!("axis_scale values must be finite and ≥ 0, got {s}"));
        }
        if let Some(s) = self.axis_signs.iter().find(|s| **s != 1.0 && **s != -1.0) {
            return Err(format!("axis_signs values must be 1 or -1, got {s}"));
        }
        Ok(())
    }

    /// Maps six values in spacenavd's order and frame (step 1 above) to the
    /// bridge's translation and rotation (steps 2–5).
    pub fn apply(&self, spnav: [f64; 6]) -> (DVec3, DVec3) {
        let (t, r) = to_bridge_frame(
            DVec3::new(spnav[0], spnav[1], spnav[2]),
            DVec3::new(spnav[3], spnav[4], spnav[5]),
        );
        let mut v = [t.x, t.y, t.z, r.x, r.y, r.z];
        for (i, x) in v.iter_mut().enumerate() {
            let u = (*x / self.full_scale).clamp(-1.0, 1.0);
            let dz = self.deadzone[i];
            let ramped = if u.abs() <= dz {
                0.0
            } else {
                u.signum() * (u.abs() - dz) / (1.0 - dz)
            };
            // `+ 0.0` turns a −0 into 0, so "at rest" is one value.
            *x = ramped * self.axis_scale[i] * self.axis_signs[i] + 0.0;
        }
        (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain() -> MouseAxes {
        MouseAxes {
            full_scale: 350.0,
            deadzone: [0.0; 6],
            axis_scale: [1.0; 6],
            axis_signs: [1.0; 6],
        }
    }

    #[test]
    fn frame_change_negates_z_and_rz_only() {
        let (t, r) = plain().apply([35.0, 70.0, 105.0, 140.0, 175.0, 210.0]);
        assert_eq!(t, DVec3::new(0.1, 0.2, -0.3));
        assert_eq!(r, DVec3::new(0.4, 0.5, -0.6));
    }

    #[test]
    fn dead_zone_cuts_then_ramps_without_a_step() {
        let a = MouseAxes {
            deadzone: [0.1; 6],
            ..plain()
        };
        // 0.1 of full scale and below read 0
        assert_eq!(a.apply([35.0, -20.0, 0.0, 0.0, 0.0, 0.0]).0, DVec3::ZERO);
        // just above it the value is small, not 0.1
        let (t, _) = a.apply([35.35, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert!((t.x - 0.001 / 0.9).abs() < 1e-12, "{t}");
        // full deflection still reads 1 (and beyond it is clamped)
        let (t, r) = a.apply([350.0, -700.0, 0.0, 0.0, 0.0, 350.0]);
        assert_eq!(t, DVec3::new(1.0, -1.0, 0.0));
        assert_eq!(r, DVec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn scale_and_sign_per_axis_after_the_frame_change() {
        let a = MouseAxes {
            axis_scale: [2.0, 1.0, 1.0, 0.0, 1.0, 0.5],
            axis_signs: [1.0, -1.0, 1.0, 1.0, 1.0, -1.0],
            ..plain()
        };
        let (t, r) = a.apply([175.0, 175.0, 175.0, 175.0, 175.0, 175.0]);
        assert_eq!(t, DVec3::new(1.0, -0.5, -0.5));
        // rx switched off; rz: −0.5 (frame) × 0.5 × −1
        assert_eq!(r, DVec3::new(0.0, 0.5, 0.25));
    }

    #[test]
    fn validation_names_the_setting() {
        let bad = |f: fn(&mut MouseAxes)| {
            let mut a = plain();
            f(&mut a);
            a.validate().unwrap_err()
        };
        assert!(bad(|a| a.full_scale = 0.0).contains("full_scale"));
        assert!(bad(|a| a.deadzone[4] = 1.0).contains("deadzone"));
        assert!(bad(|a| a.axis_scale[0] = f64::NAN).contains("axis_scale"));
        assert!(bad(|a| a.axis_signs[2] = 0.5).contains("axis_signs"));
        assert!(plain().validate().is_ok());
    }
}
