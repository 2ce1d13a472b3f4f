//! A hand: a tracker sensor and a data glove fused into a scene pose and a
//! gesture. Glove bytes are calibrated to per-joint flexion (0 = the open hand,
//! 1 = the closed fist, i.e. about 0° and 90° of joint flexion); gestures — grab
//! (hand closes), release (hand opens), point (index out, other fingers curled) —
//! switch with hysteresis so that a hand held near a threshold does not chatter.
//!
//! Sensor order (TAMS-Group/cybergloveplus `cybergloveraw.cpp`, via
//! `shared/reference/device-formats.md` §4.1): the 22-sensor glove reports thumb
//! rotation, thumb MPJ, thumb IJ, thumb abduction; index MPJ, PIJ, DIJ; middle MPJ,
//! PIJ, DIJ, middle–index abduction; ring MPJ, PIJ, DIJ, ring–middle abduction;
//! pinkie MPJ, PIJ, DIJ, pinkie–ring abduction; palm arch; wrist pitch; wrist yaw.
//! The 18-sensor glove has the same order without the four DIJ sensors.

use crate::config::Calibration;
use crate::device::{GloveValues, Timestamp};
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// Joint flexion, in degrees, that calibration value 1.0 stands for.
pub const FULL_FLEXION_DEG: f64 = 90.0;

/// Finger joints the gestures look at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Joint {
    /// Index metacarpophalangeal.
    IndexMpj,
    /// Index proximal interphalangeal.
    IndexPij,
    /// Middle MPJ.
    MiddleMpj,
    /// Middle PIJ.
    MiddlePij,
    /// Ring MPJ.
    RingMpj,
    /// Ring PIJ.
    RingPij,
    /// Pinkie MPJ.
    PinkieMpj,
    /// Pinkie PIJ.
    PinkiePij,
}

impl Joint {
    /// Sensor index of the joint on a glove with `sensors` sensors (18 or 22).
    pub fn index(self, sensors: usize) -> usize {
        let full = sensors >= 22;
        match (self, full) {
            (Joint::IndexMpj, _) => 4,
            (Joint::IndexPij, _) => 5,
            (Joint::MiddleMpj, true) => 7,
            (Joint::MiddlePij, true) => 8,
            (Joint::RingMpj, true) => 11,
            (Joint::RingPij, true) => 12,
            (Joint::PinkieMpj, true) => 15,
            (Joint::PinkiePij, true) => 16,
            (Joint::MiddleMpj, false) => 6,
            (Joint::MiddlePij, false) => 7,
            (Joint::RingMpj, false) => 9,
            (Joint::RingPij, false) => 10,
            (Joint::PinkieMpj, false) => 12,
            (Joint::PinkiePij, false) => 13,
        }
    }
}

/// Per-sensor raw values of the open hand and of the closed fist.
///
/// A single value applies to every sensor; otherwise there must be one per sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GloveCalibration {
    /// Raw values with the hand flat and open.
    pub open: Vec<u8>,
    /// Raw values with the hand in a fist.
    pub closed: Vec<u8>,
}

impl Default for GloveCalibration {
    fn default() -> Self {
        Self {
            open: vec![40],
            closed: vec![200],
        }
    }
}

impl GloveCalibration {
    /// Checks the calibration.
    pub fn validate(&self) -> Result<(), String> {
        if self.open.is_empty() || self.open.len() != self.closed.len() {
            return Err("glove calibration needs as many open as closed values".into());
        }
        if self.open.iter().zip(&self.closed).any(|(o, c)| o == c) {
            return Err("glove calibration: open and closed values must differ".into());
        }
        Ok(())
    }

    fn range(&self, i: usize) -> Option<(f64, f64)> {
        let pick = |v: &[u8]| match v.len() {
            1 => Some(v[0]),
            _ => v.get(i).copied(),
        };
        Some((f64::from(pick(&self.open)?), f64::from(pick(&self.closed)?)))
    }

    /// Flexion of sensor `i` in [0, 1] (clamped); `None` when uncalibrated.
    pub fn flexion(&self, values: &GloveValues, i: usize) -> Option<f64> {
        let raw = f64::from(*values.as_slice().get(i)?);
        let (o, c) = self.range(i)?;
        if o == c {
            return None;
        }
        Some(((raw - o) / (c - o)).clamp(0.0, 1.0))
    }

    /// Flexion angle of sensor `i` in degrees.
    pub fn angle_deg(&self, values: &GloveValues, i: usize) -> Option<f64> {
        self.flexion(values, i).map(|f| f * FULL_FLEXION_DEG)
    }
}

/// What the hand is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Gesture {
    /// Open (or relaxed) hand.
    #[default]
    Open,
    /// Closed hand: grabbing.
    Grab,
    /// Index out, other fingers curled.
    Point,
}

/// Thresholds on flexion (0 open, 1 closed) with hysteresis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GestureThresholds {
    /// Flexion at or above which the index and (on average) the other fingers count
    /// as closed: the hand grabs.
    pub close: f64,
    /// Mean finger flexion at or below which a closed hand opens.
    pub open: f64,
    /// Index flexion at or below which the index counts as out (pointing).
    pub index_out: f64,
    /// Index flexion at or above which a pointing index counts as back in.
    pub index_in: f64,
    /// Flexion of the other fingers needed for pointing.
    pub curled: f64,
}

impl Default for GestureThresholds {
    fn default() -> Self {
        Self {
            close: 0.7,
            open: 0.4,
            index_out: 0.25,
            index_in: 0.45,
            curled: 0.6,
        }
    }
}

/// The gesture state machine of one glove.
#[derive(Clone, Debug)]
pub struct GestureDetector {
    calibration: GloveCalibration,
    thresholds: GestureThresholds,
    state: Gesture,
}

impl GestureDetector {
    /// A detector starting with an open hand.
    pub fn new(calibration: GloveCalibration, thresholds: GestureThresholds) -> Self {
        Self {
            calibration,
            thresholds,
            state: Gesture::Open,
        }
    }

    /// The current gesture.
    pub fn gesture(&self) -> Gesture {
        self.state
    }

    /// The calibration in use.
    pub fn calibration(&self) -> &GloveCalibration {
        &self.calibration
    }

    fn mean(&self, v: &GloveValues, joints: &[Joint]) -> Option<f64> {
        let mut s = 0.0;
        for j in joints {
            s += self.calibration.flexion(v, j.index(v.len()))?;
        }
        Some(s / joints.len() as f64)
    }

    /// Feeds one glove reading; returns the new gesture when it changed.
    pub fn update(&mut self, v: &GloveValues) -> Option<Gesture> {
        use Joint::*;
        let index = self.mean(v, &[IndexMpj, IndexPij])?;
        let others = self.mean(
            v,
            &[MiddleMpj, MiddlePij, RingMpj, RingPij, PinkieMpj, PinkiePij],
        )?;
        let all = (2.0 * index + 6.0 * others) / 8.0;
        let t = self.thresholds;
        let closed = index.min(others) >= t.close;
        let pointing = index <= t.index_out && others >= t.curled;
        let next = match self.state {
            Gesture::Open if closed => Gesture::Grab,
            Gesture::Open if pointing => Gesture::Point,
            Gesture::Open => Gesture::Open,
            Gesture::Grab if all <= t.open => Gesture::Open,
            Gesture::Grab if pointing => Gesture::Point,
            Gesture::Grab => Gesture::Grab,
            Gesture::Point if closed => Gesture::Grab,
            Gesture::Point
                if index >= t.index_in || others < t.curled - (t.index_in - t.index_out) =>
            {
                Gesture::Open
            }
            Gesture::Point => Gesture::Point,
        };
        (next != self.state).then(|| {
            self.state = next;
            next
        })
    }
}

/// A hand pose in scene coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandPose {
    /// Position in scene units.
    pub position: DVec3,
    /// Orientation.
    pub orientation: DQuat,
    /// When the tracker record arrived.
    pub time: Timestamp,
}

/// A hand: the latest calibrated pose plus the gesture.
#[derive(Clone, Debug)]
pub struct Hand {
    calibration: Calibration,
    gestures: GestureDetector,
    pose: Option<HandPose>,
    glove: Option<GloveValues>,
}

impl Hand {
    /// A hand mapping tracker poses through `calibration`.
    pub fn new(calibration: Calibration, glove: GloveCalibration) -> Self {
        Self {
            calibration,
            gestures: GestureDetector::new(glove, GestureThresholds::default()),
            pose: None,
            glove: None,
        }
    }

    /// Takes a tracker pose (metres, tracker frame); returns the scene pose.
    pub fn update_pose(
        &mut self,
        position: DVec3,
        orientation: DQuat,
        time: Timestamp,
    ) -> HandPose {
        let p = HandPose {
            position: self.calibration.position(position),
            orientation: self.calibration.orientation(orientation),
            time,
        };
        self.pose = Some(p);
        p
    }

    /// Takes a glove reading; returns the new gesture when it changed.
    pub fn update_glove(&mut self, values: &GloveValues) -> Option<Gesture> {
        self.glove = Some(*values);
        self.gestures.update(values)
    }

    /// Flexion of every glove sensor in radians (empty before the first glove reading).
    pub fn flexion_rad(&self) -> Vec<f64> {
        let Some(v) = &self.glove else {
            return Vec::new();
        };
        (0..v.len())
            .map(|i| {
                self.gestures
                    .calibration()
                    .angle_deg(v, i)
                    .unwrap_or(0.0)
                    .to_radians()
            })
            .collect()
    }

    /// The latest scene pose.
    pub fn pose(&self) -> Option<HandPose> {
        self.pose
    }

    /// The current gesture.
    pub fn gesture(&self) -> Gesture {
        self.gestures.gesture()
    }
}

/// Raw glove values for a hand shape (for simulators and tests): `fingers` is the
/// flexion of index, and of the other fingers, in [0, 1], mapped through the default
/// calibration.
pub fn glove_shape(sensors: usize, index: f64, others: f64) -> Vec<u8> {
    let c = GloveCalibration::default();
    let raw = |f: f64| {
        (f64::from(c.open[0]) + f.clamp(0.0, 1.0) * f64::from(c.closed[0] - c.open[0])).round()
            as u8
    };
    let mut v = vec![raw(0.0); sensors];
    use Joint::*;
    for j in [IndexMpj, IndexPij] {
        v[j.index(sensors)] = raw(index);
    }
    for j in [MiddleMpj, MiddlePij, RingMpj, RingPij, PinkieMpj, PinkiePij] {
        v[j.index(sensors)] = raw(others);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn g(v: &[u8]) -> GloveValues {
        GloveValues::new(v).unwrap()
    }

    #[test]
    fn calibration_maps_to_flexion_angles() {
        let c = GloveCalibration {
            open: vec![50],
            closed: vec![150],
        };
        let v = g(&[50, 100, 150, 250, 10]);
        assert_eq!(c.angle_deg(&v, 0), Some(0.0));
        assert_eq!(c.angle_deg(&v, 1), Some(45.0));
        assert_eq!(c.angle_deg(&v, 2), Some(90.0));
        assert_eq!(c.flexion(&v, 3), Some(1.0)); // clamped
        assert_eq!(c.flexion(&v, 4), Some(0.0));
        assert_eq!(c.flexion(&v, 9), None);
        // per-sensor calibration, including a sensor whose value falls as it bends
        let c = GloveCalibration {
            open: vec![50, 200],
            closed: vec![150, 100],
        };
        let v = g(&[100, 150]);
        assert_eq!(c.flexion(&v, 0), Some(0.5));
        assert_eq!(c.flexion(&v, 1), Some(0.5));
        assert!(
            GloveCalibration {
                open: vec![1, 2],
                closed: vec![3]
            }
            .validate()
            .is_err()
        );
    }

    #[test]
    fn grab_release_point_with_hysteresis() {
        for sensors in [22, 18] {
            let mut d =
                GestureDetector::new(GloveCalibration::default(), GestureThresholds::default());
            let shape = |i: f64, o: f64| g(&glove_shape(sensors, i, o));
            assert_eq!(d.update(&shape(0.0, 0.0)), None);
            assert_eq!(d.update(&shape(0.9, 0.9)), Some(Gesture::Grab));
            // between the thresholds: stays closed
            assert_eq!(d.update(&shape(0.5, 0.5)), None);
            assert_eq!(d.gesture(), Gesture::Grab);
            assert_eq!(d.update(&shape(0.2, 0.2)), Some(Gesture::Open));
            // between the thresholds from open: stays open
            assert_eq!(d.update(&shape(0.6, 0.6)), None);
            assert_eq!(
                d.update(&shape(0.0, 0.9)),
                Some(Gesture::Point),
                "{sensors}"
            );
            assert_eq!(d.update(&shape(0.35, 0.9)), None); // index half in: still pointing
            assert_eq!(d.update(&shape(0.6, 0.9)), Some(Gesture::Open));
            // pointing then closing the index grabs; extending it while holding points
            assert_eq!(d.update(&shape(0.0, 0.9)), Some(Gesture::Point));
            assert_eq!(d.update(&shape(0.9, 0.9)), Some(Gesture::Grab));
            assert_eq!(d.update(&shape(0.1, 0.9)), Some(Gesture::Point));
        }
    }

    #[test]
    fn joint_indices_follow_the_published_order() {
        assert_eq!(Joint::MiddleMpj.index(22), 7);
        assert_eq!(Joint::PinkiePij.index(22), 16);
        assert_eq!(Joint::MiddleMpj.index(18), 6);
        assert_eq!(Joint::PinkiePij.index(18), 13);
    }

    #[test]
    fn hand_pose_goes_through_the_calibration() {
        let cal = Calibration {
            translation: [1.0, 0.0, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: 10.0,
        };
        let mut h = Hand::new(cal, GloveCalibration::default());
        let p = h.update_pose(DVec3::new(0.1, 0.2, 0.0), DQuat::IDENTITY, Timestamp(3));
        assert!((p.position - DVec3::new(2.0, 2.0, 0.0)).length() < 1e-12);
        assert_eq!(h.pose().unwrap().time, Timestamp(3));
    }
}
