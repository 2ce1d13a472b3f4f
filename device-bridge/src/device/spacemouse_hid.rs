//! 3Dconnexion SpaceNavigator / SpaceMouse family over USB HID: the model table
//! (vendor/product allow-list), the input-report decoder and per-model axis mapping.
//!
//! Report formats (checked against VRPN `vrpn_3DConnexion.C` `decodePacket` and the
//! SpaceMouse Pro Wireless variant, HEAD 893c749; FreeSpacenav/spacenavd `src/dev.c`
//! `usbdb` and `devid_blacklist`, HEAD bac572a; see `shared/reference/device-formats.md` §2).
//! hidapi returns the report id as byte 0; axis values are signed 16-bit little-endian.
//! * report 1, 7 bytes: translation x, y, z (older / wired models);
//! * report 2, 7 bytes: rotation rx, ry, rz (alternates with report 1);
//! * report 1, 13 bytes: all six axes x, y, z, rx, ry, rz (wireless and newer models);
//! * report 3: button bitfield from byte 1, LSB first (button n = byte 1 + n/8, bit n%8);
//! * report 0x17: battery level — ignored;
//! * output report `[0x04, on]` drives the LED (not used).
//!
//! Values are roughly ±350 at full deflection. spacenavd marks almost every USB model "swap y-z, invert y-z"
//! (and adds both flags to unknown 3Dconnexion models); the table below carries the
//! same per-model flags, which give spacenavd's axes (x right, y up, z away from the
//! user); [`super::spacenavd::to_bridge_frame`] then makes them the bridge's
//! right-handed frame (z towards the user), as libspnav does, and the device's
//! calibration (full scale, dead zone, scale and sign per axis) follows
//! ([`super::mouse_axes`]).

use super::driver::{DecodeStats, Decoder, Script};
use super::mouse_axes::{DEFAULT_DEADZONE, MouseAxes};
use super::sample::{Reading, Sample, SourceId, Timestamp};
use serde::{Deserialize, Serialize};

/// Logitech-era 3Dconnexion vendor id.
pub const VENDOR_LOGITECH: u16 = 0x046d;
/// 3Dconnexion vendor id.
pub const VENDOR_3DCONNEXION: u16 = 0x256f;

/// A known 3D-mouse model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model {
    /// USB vendor id.
    pub vendor: u16,
    /// USB product id.
    pub product: u16,
    /// Marketing name.
    pub name: &'static str,
    /// Raw axes need "swap y-z, invert y-z" (spacenavd's DF_SWAPYZ | DF_INVYZ).
    pub swap_invert_yz: bool,
}

const fn m(vendor: u16, product: u16, name: &'static str, swap_invert_yz: bool) -> Model {
    Model {
        vendor,
        product,
        name,
        swap_invert_yz,
    }
}

/// Known models (spacenavd `usbdb`, VRPN `vrpn_3DConnexion.C`).
pub const MODELS: &[Model] = &[
    m(VENDOR_LOGITECH, 0xc603, "SpaceMouse Plus XT", false),
    m(VENDOR_LOGITECH, 0xc605, "CadMan", true),
    m(VENDOR_LOGITECH, 0xc606, "SpaceMouse Classic", false),
    m(VENDOR_LOGITECH, 0xc621, "SpaceBall 5000", true),
    m(VENDOR_LOGITECH, 0xc623, "SpaceTraveler", true),
    m(VENDOR_LOGITECH, 0xc625, "SpacePilot", true),
    m(VENDOR_LOGITECH, 0xc626, "SpaceNavigator", true),
    m(VENDOR_LOGITECH, 0xc627, "SpaceExplorer", true),
    m(
        VENDOR_LOGITECH,
        0xc628,
        "SpaceNavigator for Notebooks",
        true,
    ),
    m(VENDOR_LOGITECH, 0xc629, "SpacePilot Pro", true),
    m(VENDOR_LOGITECH, 0xc62b, "SpaceMouse Pro", true),
    m(
        VENDOR_3DCONNEXION,
        0xc62e,
        "SpaceMouse Wireless (cable)",
        true,
    ),
    m(
        VENDOR_3DCONNEXION,
        0xc62f,
        "SpaceMouse Wireless (receiver)",
        true,
    ),
    m(
        VENDOR_3DCONNEXION,
        0xc631,
        "SpaceMouse Pro Wireless (cable)",
        true,
    ),
    m(
        VENDOR_3DCONNEXION,
        0xc632,
        "SpaceMouse Pro Wireless (receiver)",
        true,
    ),
    m(VENDOR_3DCONNEXION, 0xc633, "SpaceMouse Enterprise", true),
    m(VENDOR_3DCONNEXION, 0xc635, "SpaceMouse Compact", true),
    m(VENDOR_3DCONNEXION, 0xc636, "SpaceMouse Module", true),
    m(
        VENDOR_3DCONNEXION,
        0xc638,
        "SpaceMouse Pro Wireless BT (cable)",
        true,
    ),
    m(
        VENDOR_3DCONNEXION,
        0xc63a,
        "SpaceMouse Wireless BT (cable)",
        true,
    ),
    m(
        VENDOR_3DCONNEXION,
        0xc652,
        "3Dconnexion Universal Receiver",
        true,
    ),
];

/// The model for (vendor, product), if known.
pub fn model(vendor: u16, product: u16) -> Option<&'static Model> {
    MODELS
        .iter()
        .find(|m| m.vendor == vendor && m.product == product)
}

/// How a HID 3D mouse is chosen and scaled (the calibration of [`super::mouse_axes`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpaceMouseSettings {
    /// Open this hidraw path instead of searching the allow-list.
    pub path: Option<String>,
    /// Extra (vendor, product) ids to accept, for models newer than the table.
    pub extra_ids: Vec<[u16; 2]>,
    /// Raw axis value that maps to 1.0.
    pub full_scale: f64,
    /// Dead zone per axis x, y, z, rx, ry, rz (bridge frame), a fraction of full scale.
    pub deadzone: [f64; 6],
    /// Gain per axis x, y, z, rx, ry, rz (bridge frame).
    pub axis_scale: [f64; 6],
    /// Sign (1 or −1) per axis x, y, z, rx, ry, rz (bridge frame, after the model mapping).
    pub axis_signs: [f64; 6],
}

impl Default for SpaceMouseSettings {
    fn default() -> Self {
        Self {
            path: None,
            extra_ids: Vec::new(),
            full_scale: 350.0,
            deadzone: [DEFAULT_DEADZONE; 6],
            axis_scale: [1.0; 6],
            axis_signs: [1.0; 6],
        }
    }
}

impl SpaceMouseSettings {
    /// The ids to look for: the table plus `extra_ids`.
    pub fn allow_list(&self) -> Vec<(u16, u16)> {
        MODELS
            .iter()
            .map(|m| (m.vendor, m.product))
            .chain(self.extra_ids.iter().map(|[v, p]| (*v, *p)))
            .collect()
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

/// Report ids.
const REPORT_TRANSLATION: u8 = 1;
const REPORT_ROTATION: u8 = 2;
const REPORT_BUTTONS: u8 = 3;
const REPORT_BATTERY: u8 = 0x17;
/// Bytes of button bitfield tracked (Enterprise: 31 buttons).
const BUTTON_BYTES: usize = 4;

/// The HID report decoder. Each `feed` chunk is one report.
pub struct SpaceMouseDecoder {
    axes: MouseAxes,
    source: SourceId,
    swap_invert_yz: bool,
    raw: [i16; 6],
    buttons: [u8; BUTTON_BYTES],
    stats: DecodeStats,
}

fn le(b: &[u8], i: usize) -> i16 {
    i16::from_le_bytes([b[1 + 2 * i], b[2 + 2 * i]])
}

impl SpaceMouseDecoder {
    /// A decoder; the model mapping defaults to "swap and invert y-z", as spacenavd
    /// applies to every 3Dconnexion device it does not know.
    pub fn new(source: SourceId, settings: SpaceMouseSettings) -> Self {
        Self {
            axes: settings.axes(),
            source,
            swap_invert_yz: true,
            raw: [0; 6],
            buttons: [0; BUTTON_BYTES],
            stats: DecodeStats::default(),
        }
    }

    fn motion(&self) -> Reading {
        // Device axes in report order; spacenavd's model mapping (`read_device`:
        // swap 1↔2 and 4↔5, then negate 1, 2, 4, 5) gives its axes and frame.
        let mut v = self.raw.map(f64::from);
        if self.swap_invert_yz {
            for base in [1, 4] {
                let (y, z) = (v[base], v[base + 1]);
                v[base] = -z;
                v[base + 1] = -y;
            }
        }
        let (translation, rotation) = self.axes.apply(v);
        Reading::Motion {
            translation,
            rotation,
        }
    }

    fn push(&mut self, at: Timestamp, reading: Reading, out: &mut Vec<Sample>) {
        out.push(Sample {
            source: self.source,
            time: at,
            reading,
        });
    }
}

impl Decoder for SpaceMouseDecoder {
    fn feed(&mut self, report: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        let Some(&id) = report.first() else {
            return;
        };
        match (id, report.len()) {
            (REPORT_TRANSLATION, 7) => {
                for i in 0..3 {
                    self.raw[i] = le(report, i);
                }
            }
            (REPORT_TRANSLATION, 13) => {
                for i in 0..6 {
                    self.raw[i] = le(report, i);
                }
            }
            (REPORT_ROTATION, 7) => {
                for i in 0..3 {
                    self.raw[3 + i] = le(report, i);
                }
            }
            (REPORT_BUTTONS, 2..=33) => {
                let mut now = [0u8; BUTTON_BYTES];
                let n = (report.len() - 1).min(BUTTON_BYTES);
                now[..n].copy_from_slice(&report[1..1 + n]);
                self.stats.records += 1;
                let before = self.buttons;
                for (byte, (&new, &old)) in now.iter().zip(before.iter()).enumerate() {
                    let changed = new ^ old;
                    for bit in 0..8 {
                        if changed & (1 << bit) != 0 {
                            let pressed = new & (1 << bit) != 0;
                            let button = (byte * 8 + bit) as u16;
                            self.push(at, Reading::Button { button, pressed }, out);
                        }
                    }
                }
                self.buttons = now;
                return;
            }
            (REPORT_BATTERY, _) => return,
            _ => {
                self.stats.rejected_records += 1;
                return;
            }
        }
        self.stats.records += 1;
        let m = self.motion();
        self.push(at, m, out);
    }

    fn stats(&self) -> DecodeStats {
        self.stats
    }

    fn reset(&mut self) {
        self.raw = [0; 6];
        self.buttons = [0; BUTTON_BYTES];
    }

    fn set_identity(&mut self, (vendor, product): (u16, u16)) {
        self.swap_invert_yz = model(vendor, product).map_or(
            vendor == VENDOR_3DCONNEXION || vendor == VENDOR_LOGITECH,
            |m| m.swap_invert_yz,
        );
    }
}

/// HID needs no commands.
pub fn script() -> Script {
    Script::default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// No dead zone: these tests are about the report format.
    fn plain() -> SpaceMouseSettings {
        SpaceMouseSettings {
            deadzone: [0.0; 6],
            ..Default::default()
        }
    }

    fn run(d: &mut SpaceMouseDecoder, reports: &[&[u8]]) -> Vec<Reading> {
        let mut out = Vec::new();
        for r in reports {
            d.feed(r, Timestamp(0), &mut out);
        }
        out.into_iter().map(|s| s.reading).collect()
    }

    /// Frames captured from a SpaceMouse Compact (CloudCompare PR #2339).
    #[test]
    fn captured_compact_frames() {
        let mut d = SpaceMouseDecoder::new(SourceId(0), plain());
        d.set_identity((VENDOR_3DCONNEXION, 0xc635));
        let r = run(
            &mut d,
            &[
                &[0x02, 0x20, 0x00, 0x00, 0x00, 0x17, 0x00],
                &[0x01, 0x12, 0x00, 0x00, 0x00, 0xf8, 0x00],
            ],
        );
        assert_eq!(r.len(), 2);
        // rotation raw (32, 0, 23) → swap/invert: (32, -23, 0)/350
        assert_eq!(
            r[0],
            Reading::Motion {
                translation: DVec3::ZERO,
                rotation: DVec3::new(32.0, -23.0, -0.0) / 350.0
            }
        );
        // translation raw (18, 0, 248) → (18, -248, -0)/350; rotation kept
        assert_eq!(
            r[1],
            Reading::Motion {
                translation: DVec3::new(18.0, -248.0, -0.0) / 350.0,
                rotation: DVec3::new(32.0, -23.0, -0.0) / 350.0
            }
        );
    }

    #[test]
    fn combined_13_byte_report_and_clamping() {
        let mut d = SpaceMouseDecoder::new(SourceId(0), plain());
        d.set_identity((VENDOR_LOGITECH, 0xc603)); // no swap for the Plus XT
        let mut rep = vec![0x01];
        for v in [100i16, -200, 300, 1000, -1000, 0] {
            rep.extend_from_slice(&v.to_le_bytes());
        }
        let r = run(&mut d, &[&rep]);
        assert_eq!(
            r[0],
            Reading::Motion {
                translation: DVec3::new(100.0, -200.0, -300.0) / 350.0,
                rotation: DVec3::new(1.0, -1.0, 0.0)
            }
        );
    }

    #[test]
    fn buttons_battery_unknown_and_short_reports() {
        let mut d = SpaceMouseDecoder::new(SourceId(0), plain());
        let r = run(
            &mut d,
            &[
                &[0x03, 0x01, 0x00],             // button 0 down
                &[0x17, 0x64, 0x00],             // battery 100 %: ignored
                &[0x03, 0x03, 0x00],             // button 1 down
                &[0x03, 0x00, 0x00, 0x00, 0x01], // all up, SHIFT (byte 4 bit 0 = button 24) down
                &[0x01, 0x05, 0x00],             // truncated translation: rejected
                &[0x02; 9],                      // overlong rotation: rejected
                &[0x42, 0, 0],                   // unknown report id: rejected
                &[],
            ],
        );
        assert_eq!(
            r,
            vec![
                Reading::Button {
                    button: 0,
                    pressed: true
                },
                Reading::Button {
                    button: 1,
                    pressed: true
                },
                Reading::Button {
                    button: 0,
                    pressed: false
                },
                Reading::Button {
                    button: 1,
                    pressed: false
                },
                Reading::Button {
                    button: 24,
                    pressed: true
                },
            ]
        );
        assert_eq!(d.stats().rejected_records, 3);
    }

    #[test]
    fn allow_list_extends_and_excludes_cadmice() {
        let s = SpaceMouseSettings {
            extra_ids: vec![[0x256f, 0xc6ff]],
            ..Default::default()
        };
        let l = s.allow_list();
        assert!(l.contains(&(0x256f, 0xc6ff)));
        assert!(l.contains(&(0x046d, 0xc626)));
        assert!(!l.contains(&(0x256f, 0xc650))); // CadMouse is not a 6-DOF device
    }
}
