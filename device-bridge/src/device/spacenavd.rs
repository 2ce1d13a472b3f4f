//! 3D mice through the spacenavd daemon: its AF_UNIX client protocol (v0).
//!
//! Wire format (checked against FreeSpacenav/spacenavd `src/proto_unix.c` `send_uevent`
//! and `src/proto.h`, HEAD bac572a): the daemon listens on a stream socket
//! (`/var/run/spnav.sock`; libspnav also honours `$SPNAV_SOCKET`). A v0 client connects
//! and reads; nothing needs to be sent. Every event is 32 bytes: eight `i32` in the
//! host's byte order.
//! * motion `[0, x, y, z, rx, ry, rz, period_ms]` — values already scaled by the
//!   client's sensitivity and mapped to spacenavd's axes (about ±350 full scale):
//!   x right, y up, z *away* from the user (pushing the cap forward is +z), a
//!   left-handed frame; rx, ry, rz are the twists about those axes (spacenavd's
//!   `process_input` in `src/event.c` fills `motion.data[0..6]` in that order from
//!   the mapped device axes 0–5). libspnav's own `spnav_posrot_moveobj`
//!   (`src/spnav.c`) turns it into a right-handed object motion by negating z and
//!   rz, and so does [`to_bridge_frame`]; the per-device calibration (dead zone,
//!   scale, sign per axis) follows ([`super::mouse_axes`]);
//! * button `[1 (press) | 2 (release), button, press, 0…]`;
//! * v1 only: 3 device, 4 config, 5 raw axis, 6 raw button (ignored here).
//!
//! The stream has no sync marker; an event type outside 0..=6 means the stream is
//! out of step, so the link is reopened.

use super::driver::{DecodeStats, Decoder, Script};
use super::mouse_axes::{DEFAULT_DEADZONE, MouseAxes};
use super::sample::{Reading, Sample, SourceId, Timestamp};
use serde::{Deserialize, Serialize};

/// Default socket path.
pub const DEFAULT_SOCKET: &str = "/var/run/spnav.sock";
/// Bytes per event.
pub const EVENT_LEN: usize = 32;
/// Largest axis magnitude believed (raw ±350 times any sane sensitivity); larger
/// values only come from a stream that is out of step.
const MAX_AXIS: u32 = 1 << 16;

/// How spacenavd events are scaled: the calibration of [`super::mouse_axes`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpacenavdSettings {
    /// Socket path (`$SPNAV_SOCKET` overrides the default when unset here).
    pub socket: Option<String>,
    /// Axis value that maps to 1.0.
    pub full_scale: f64,
    /// Dead zone per axis x, y, z, rx, ry, rz (bridge frame), a fraction of full scale.
    pub deadzone: [f64; 6],
    /// Gain per axis x, y, z, rx, ry, rz (bridge frame).
    pub axis_scale: [f64; 6],
    /// Sign (1 or −1) per axis x, y, z, rx, ry, rz (bridge frame).
    pub axis_signs: [f64; 6],
}

impl Default for SpacenavdSettings {
    fn default() -> Self {
        Self {
            socket: None,
            full_scale: 350.0,
            deadzone: [DEFAULT_DEADZONE; 6],
            axis_scale: [1.0; 6],
            axis_signs: [1.0; 6],
        }
    }
}

impl SpacenavdSettings {
    /// The socket to connect to: the configured path, else `$SPNAV_SOCKET`, else the default.
    pub fn socket_path(&self) -> String {
        self.socket
            .clone()
            .or_else(|| std::env::var("SPNAV_SOCKET").ok())
            .unwrap_or_else(|| DEFAULT_SOCKET.to_owned())
    }

    /// The axis calibration.
    pub fn axes(&self) -> MouseAxes {
        MouseAxes {
            full_scale: self.full_scale,
            deadzone: self.deadzone,
            axis_scale: self.axis_scale,
            axis_signs: self.axis_signs,
        }
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<(), String> {
        self.axes().validate()
    }
}

pub use super::mouse_axes::to_bridge_frame;

/// Encodes an event in host byte order (for the fake daemon and tests).
pub fn encode_event(words: [i32; 8]) -> [u8; EVENT_LEN] {
    let mut b = [0u8; EVENT_LEN];
    for (i, w) in words.iter().enumerate() {
        b[4 * i..4 * i + 4].copy_from_slice(&w.to_ne_bytes());
    }
    b
}

/// The spacenavd event decoder.
pub struct SpacenavdDecoder {
    axes: MouseAxes,
    source: SourceId,
    buf: [u8; EVENT_LEN],
    len: usize,
    stats: DecodeStats,
    fatal: Option<String>,
}

impl SpacenavdDecoder {
    /// A decoder scaling motion by `settings`.
    pub fn new(source: SourceId, settings: SpacenavdSettings) -> Self {
        Self {
            axes: settings.axes(),
            source,
            buf: [0; EVENT_LEN],
            len: 0,
            stats: DecodeStats::default(),
            fatal: None,
        }
    }

    fn event(&mut self, at: Timestamp, out: &mut Vec<Sample>) {
        let w: Vec<i32> = (0..8)
            .map(|i| {
                i32::from_ne_bytes([
                    self.buf[4 * i],
                    self.buf[4 * i + 1],
                    self.buf[4 * i + 2],
                    self.buf[4 * i + 3],
                ])
            })
            .collect();
        let reading = match w[0] {
            0 if w[1..7].iter().any(|v| v.unsigned_abs() > MAX_AXIS) => {
                self.fatal = Some("spacenavd motion value out of range; stream out of step".into());
                self.stats.rejected_records += 1;
                return;
            }
            0 => {
                let v = |i: usize| f64::from(w[i + 1]);
                let (translation, rotation) = self.axes.apply([v(0), v(1), v(2), v(3), v(4), v(5)]);
                Reading::Motion {
                    translation,
                    rotation,
                }
            }
            1 | 2 => match u16::try_from(w[1]) {
                Ok(button) => Reading::Button {
                    button,
                    pressed: w[0] == 1,
                },
                Err(_) => {
                    self.stats.rejected_records += 1;
                    return;
                }
            },
            3..=6 => return,
            t => {
                self.fatal = Some(format!(
                    "spacenavd event type {t} out of range; stream out of step"
                ));
                self.stats.rejected_records += 1;
                return;
            }
        };
        self.stats.records += 1;
        out.push(Sample {
            source: self.source,
            time: at,
            reading,
        });
    }
}

impl Decoder for SpacenavdDecoder {
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        for &b in chunk {
            if self.fatal.is_some() {
                self.stats.discarded_bytes += 1;
                continue;
            }
            self.buf[self.len] = b;
            self.len += 1;
            if self.len == EVENT_LEN {
                self.len = 0;
                self.event(at, out);
            }
        }
    }

    fn stats(&self) -> DecodeStats {
        self.stats
    }

    fn reset(&mut self) {
        self.len = 0;
        self.fatal = None;
    }

    fn fatal(&self) -> Option<String> {
        self.fatal.clone()
    }
}

/// Protocol v0 needs no commands.
pub fn script() -> Script {
    Script::default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// No dead zone: these tests are about the wire format.
    fn plain() -> SpacenavdSettings {
        SpacenavdSettings {
            deadzone: [0.0; 6],
            ..Default::default()
        }
    }

    #[test]
    fn motion_and_buttons() {
        let mut s = encode_event([0, 350, -175, 0, 700, 0, -35, 8]).to_vec();
        s.extend(encode_event([1, 3, 1, 0, 0, 0, 0, 0]));
        s.extend(encode_event([2, 3, 0, 0, 0, 0, 0, 0]));
        s.extend(encode_event([3, 0, 1, 6, 0x256f, 0xc635, 0, 0])); // v1 device event: ignored
        let mut d = SpacenavdDecoder::new(SourceId(0), plain());
        let mut out = Vec::new();
        for c in s.chunks(5) {
            d.feed(c, Timestamp(0), &mut out);
        }
        assert_eq!(out.len(), 3);
        assert_eq!(
            out[0].reading,
            Reading::Motion {
                translation: DVec3::new(1.0, -0.5, 0.0),
                rotation: DVec3::new(1.0, 0.0, 0.1)
            }
        );
        assert_eq!(
            out[1].reading,
            Reading::Button {
                button: 3,
                pressed: true
            }
        );
        assert_eq!(
            out[2].reading,
            Reading::Button {
                button: 3,
                pressed: false
            }
        );
    }

    /// spacenavd's convention: the cap pushed away from the user is +z, twisted
    /// clockwise seen from above is +rz (left-handed); in the bridge's right-handed
    /// frame that is −z, −rz, as libspnav's `spnav_posrot_moveobj` computes
    /// (`pos[2] -= ev->z`, axis z = `-ev->rz`).
    #[test]
    fn pushing_the_cap_away_is_minus_z() {
        let mut d = SpacenavdDecoder::new(SourceId(0), plain());
        let mut out = Vec::new();
        let ev: Vec<u8> = [0i32, 0, 0, 350, 0, 0, 175, 16]
            .iter()
            .flat_map(|w| w.to_ne_bytes())
            .collect();
        d.feed(&ev, Timestamp(0), &mut out);
        assert_eq!(
            out[0].reading,
            Reading::Motion {
                translation: DVec3::new(0.0, 0.0, -1.0),
                rotation: DVec3::new(0.0, 0.0, -0.5)
            }
        );
    }

    #[test]
    fn out_of_step_stream_is_fatal() {
        let mut s = vec![0u8; 3];
        s.extend(encode_event([0, 1, 2, 3, 4, 5, 6, 7]));
        let mut d = SpacenavdDecoder::new(SourceId(0), plain());
        let mut out = Vec::new();
        d.feed(&s, Timestamp(0), &mut out);
        // the shifted frame reads motion values of 1 << 24: never a motion
        assert!(out.is_empty());
        assert!(d.fatal().is_some());
        d.reset();
        assert!(d.fatal().is_none());
    }
}
