//! Typed device samples: what every driver yields once the raw bytes have
//! been parsed and validated at the edge.
//!
//! A [`Sample`] carries the [`SourceId`] of the configured device it came from,
//! the [`Timestamp`] at which its first byte arrived, and one [`Reading`]. Only
//! values that passed every check of their wire format become samples, so
//! nothing downstream ever sees a half-parsed or non-finite pose.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Microseconds on the bridge's monotonic clock (origin: first use in the process).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
pub struct Timestamp(pub u64);

fn origin() -> Instant {
    static ORIGIN: OnceLock<Instant> = OnceLock::new();
    *ORIGIN.get_or_init(Instant::now)
}

impl Timestamp {
    /// The current time on the bridge's monotonic clock.
    pub fn now() -> Self {
        Self::from_instant(Instant::now())
    }

    /// Converts an [`Instant`] to the bridge clock (instants before the origin map to 0).
    pub fn from_instant(at: Instant) -> Self {
        let d = at.saturating_duration_since(origin());
        Timestamp(u64::try_from(d.as_micros()).unwrap_or(u64::MAX))
    }

    /// The [`Instant`] this timestamp stands for.
    pub fn to_instant(self) -> Instant {
        origin() + Duration::from_micros(self.0)
    }

    /// Seconds since the clock origin.
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 * 1e-6
    }

    /// Time elapsed from `earlier` to `self` (zero if `earlier` is later).
    pub fn since(self, earlier: Timestamp) -> Duration {
        Duration::from_micros(self.0.saturating_sub(earlier.0))
    }
}

/// Index of a configured device (its position in the configuration's device list).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
pub struct SourceId(pub u16);

/// Most sensors a CyberGlove reports (the 22-sensor model).
pub const MAX_GLOVE_SENSORS: usize = 22;

/// Raw joint-sensor bytes of a data glove, in the device's sensor order.
///
/// Each value is in 1..=255 (0 never appears in a valid CyberGlove record).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GloveValues {
    count: u8,
    values: [u8; MAX_GLOVE_SENSORS],
}

impl GloveValues {
    /// Wraps `values` (at most [`MAX_GLOVE_SENSORS`]); `None` if there are too many.
    pub fn new(values: &[u8]) -> Option<Self> {
        if values.len() > MAX_GLOVE_SENSORS {
            return None;
        }
        let mut out = [0u8; MAX_GLOVE_SENSORS];
        out[..values.len()].copy_from_slice(values);
        Some(Self {
            count: values.len() as u8,
            values: out,
        })
    }

    /// The sensor values.
    pub fn as_slice(&self) -> &[u8] {
        &self.values[..self.count as usize]
    }

    /// Number of sensors.
    pub fn len(&self) -> usize {
        self.count as usize
    }

    /// True when there are no sensors.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// One validated reading of a device.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reading {
    /// A 6-DOF pose of one tracker sensor in the tracker's own frame:
    /// position in metres, orientation a unit quaternion.
    Pose {
        /// Sensor index on the device (0-based).
        sensor: u16,
        /// Position in metres.
        position: DVec3,
        /// Unit orientation.
        orientation: DQuat,
    },
    /// Raw glove joint sensors (calibrate with [`crate::hand`]).
    Glove(GloveValues),
    /// A 3D-mouse state: translation and rotation axes, each normalised to [-1, 1],
    /// already mapped to the bridge's frame (x right, y up, z towards the user).
    Motion {
        /// Push/pull of the cap.
        translation: DVec3,
        /// Twist/tilt of the cap.
        rotation: DVec3,
    },
    /// A button changed state.
    Button {
        /// Button number (0-based).
        button: u16,
        /// True when pressed.
        pressed: bool,
    },
}

/// A reading from one configured device, stamped with its arrival time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Which configured device.
    pub source: SourceId,
    /// When the first byte of the record arrived.
    pub time: Timestamp,
    /// The reading.
    pub reading: Reading,
}

/// True when `q` is a finite quaternion whose norm is within `tol` of 1.
pub fn is_unit_quat(q: DQuat, tol: f64) -> bool {
    q.is_finite() && (q.length() - 1.0).abs() <= tol
}

/// Tolerance on the norm of a device quaternion before it is rejected.
///
/// Devices with 14-bit words (Flock) give norms within about 1e-3 of 1; a
/// corrupted record is far off. 0.05 separates the two with margin.
pub const QUAT_NORM_TOLERANCE: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glove_values_bounds() {
        assert!(GloveValues::new(&[1; 23]).is_none());
        let g = GloveValues::new(&[5, 6, 7]).unwrap();
        assert_eq!(g.as_slice(), &[5, 6, 7]);
        assert_eq!(g.len(), 3);
        assert!(!g.is_empty());
    }

    #[test]
    fn timestamps_are_monotonic_and_convert() {
        let a = Timestamp::now();
        let b = Timestamp::now();
        assert!(b >= a);
        let i = a.to_instant();
        assert_eq!(Timestamp::from_instant(i), a);
        assert_eq!(Timestamp(10).since(Timestamp(20)), Duration::ZERO);
    }

    #[test]
    fn unit_quat_check() {
        assert!(is_unit_quat(DQuat::IDENTITY, 1e-9));
        assert!(!is_unit_quat(DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0), 0.05));
        assert!(!is_unit_quat(
            DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0),
            0.05
        ));
    }
}
