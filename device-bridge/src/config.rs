//! The bridge's TOML configuration: devices (ports, baud rates, family settings),
//! the tracker-to-scene calibration, the server link, which sensors make up which
//! hand, and the 3D-mouse menu. [`Config::load`] parses and validates; [`build_driver`]
//! turns one device entry into a ready [`Driver`].
//!
//! ```toml
//! [server]
//! url = "ws://127.0.0.1:7878/ws?design=1&token=…"   # the server's "device:" line
//!
//! [calibration]
//! translation = [0.0, -1.0, 0.5]   # metres, added last
//! rotation = [0.0, 0.0, 0.0, 1.0]  # quaternion x, y, z, w
//! scale = 1.0                      # applied to tracker positions first
//!
//! [[device]]
//! name = "tracker"
//! kind = "flock"
//! port = "/dev/ttyUSB0"
//! baud = 115200
//! flock = { format = "pos_quat", birds = 1 }
//!
//! [[device]]
//! name = "glove"
//! kind = "cyberglove"
//! port = "/dev/ttyUSB1"
//!
//! [[hand]]
//! name = "right"
//! tracker = "tracker"
//! sensor = 0
//! glove = "glove"
//! ```

use crate::device::SourceId;
use crate::device::cyberglove::{self, CyberGloveDecoder, CyberGloveSettings};
use crate::device::driver::{Decoder, Driver, Script, Transport};
use crate::device::fastrak::{self, FastrakDecoder, FastrakSettings};
use crate::device::flock::{self, FlockDecoder, FlockSettings};
use crate::device::spacemouse_hid::{self, SpaceMouseDecoder, SpaceMouseSettings};
use crate::device::spacenavd::{self, SpacenavdDecoder, SpacenavdSettings};
use crate::device::transport::{
    HidSelector, HidTransport, SerialTransport, TcpTransport, UnixTransport,
};
use crate::device::vrpn::{self, VrpnDecoder, VrpnSettings};
use crate::device::vrpn_link::VrpnUdpTransport;
use crate::gate::GateSettings;
use crate::hand::GloveCalibration;
use crate::interaction::MenuAction;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;
use thiserror::Error;

/// A configuration that cannot be used.
#[derive(Debug, Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The TOML is malformed or has unknown keys.
    #[error("invalid configuration: {0}")]
    Parse(String),
    /// Values that parse but do not make sense.
    #[error("invalid configuration: {0}")]
    Invalid(String),
}

/// Device families.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviceKind {
    /// Ascension Flock of Birds (serial).
    Flock,
    /// Polhemus Fastrak (serial).
    Fastrak,
    /// CyberGlove (serial).
    Cyberglove,
    /// 3Dconnexion mouse over USB HID.
    SpacemouseHid,
    /// 3D mouse through spacenavd.
    Spacenavd,
    /// Any tracker served by a VRPN server.
    Vrpn,
}

impl DeviceKind {
    /// True for the RS-232 families.
    pub fn is_serial(self) -> bool {
        matches!(
            self,
            DeviceKind::Flock | DeviceKind::Fastrak | DeviceKind::Cyberglove
        )
    }

    /// The kind's name as written in the configuration.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Flock => "flock",
            DeviceKind::Fastrak => "fastrak",
            DeviceKind::Cyberglove => "cyberglove",
            DeviceKind::SpacemouseHid => "spacemouse_hid",
            DeviceKind::Spacenavd => "spacenavd",
            DeviceKind::Vrpn => "vrpn",
        }
    }
}

/// Baud rate of a serial device without `baud`.
pub const DEFAULT_BAUD: u32 = 115_200;

/// The rates a serial tracker or glove can be set to (the Flock's DIP switches
/// give 2400–115200; Fastrak and CyberGlove use 9600–115200).
pub const STANDARD_BAUDS: [u32; 9] = [
    1200, 2400, 4800, 9600, 19_200, 38_400, 57_600, 115_200, 230_400,
];

/// The standard rate a mistyped `baud` most likely meant: one whose digits begin
/// with the typed ones (11520 → 115200), else the nearest by ratio.
pub fn nearest_baud(b: u32) -> u32 {
    let typed = b.to_string();
    if let Some(s) = STANDARD_BAUDS
        .iter()
        .find(|s| s.to_string().starts_with(&typed) || typed.starts_with(&s.to_string()))
    {
        return *s;
    }
    let ratio = |s: u32| (f64::from(s) / f64::from(b.max(1))).ln().abs();
    STANDARD_BAUDS
        .iter()
        .copied()
        .min_by(|a, c| ratio(*a).total_cmp(&ratio(*c)))
        .unwrap_or(DEFAULT_BAUD)
}

impl DeviceConfig {
    /// For a serial device, what to say when its line yields bytes but no valid
    /// record: the configured rate and the others the device may be set to.
    pub fn line_hint(&self) -> Option<String> {
        if !self.kind.is_serial() {
            return None;
        }
        let baud = self.baud.unwrap_or(DEFAULT_BAUD);
        let others: Vec<String> = STANDARD_BAUDS
            .iter()
            .filter(|b| **b != baud && (9600..=115_200).contains(*b))
            .map(u32::to_string)
            .collect();
        let format = match self.kind {
            DeviceKind::Flock => format!(
                ", or the record format ({:?}, {} birds, group mode {})",
                self.flock.format, self.flock.birds, self.flock.group_mode
            ),
            DeviceKind::Cyberglove => format!(
                ", or the sensor count ({}) and record options",
                self.cyberglove.sensors
            ),
            _ => String::new(),
        };
        Some(format!(
            "wrong baud rate? configured {baud}; the device may be set to {}{format}",
            others.join(", ")
        ))
    }
}

fn default_settle_ms() -> u64 {
    50
}

/// A CyberGlove samples at up to about 150 records a second and a Flock streams at
/// about 100–144; 100 polls a second follow a hand without flooding the line.
fn default_poll_hz() -> f64 {
    100.0
}

/// One device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceConfig {
    /// Unique name, used by hands and the menu.
    pub name: String,
    /// Family.
    pub kind: DeviceKind,
    /// Serial port path (serial families).
    #[serde(default)]
    pub port: Option<String>,
    /// Baud rate (serial families; default 115200, 9600–115200 typical).
    #[serde(default)]
    pub baud: Option<u32>,
    /// `host:port` of the VRPN server (default port 3883).
    #[serde(default)]
    pub address: Option<String>,
    /// Wait after stopping a serial device before configuring it, in ms.
    #[serde(default = "default_settle_ms")]
    pub settle_ms: u64,
    /// Polls a second at most, for a device set to be polled rather than stream
    /// (a CyberGlove by default; a Flock or Fastrak with `stream = false`).
    #[serde(default = "default_poll_hz")]
    pub poll_hz: f64,
    /// Flock of Birds settings.
    #[serde(default)]
    pub flock: FlockSettings,
    /// Fastrak settings.
    #[serde(default)]
    pub fastrak: FastrakSettings,
    /// CyberGlove settings.
    #[serde(default)]
    pub cyberglove: CyberGloveSettings,
    /// HID 3D-mouse settings.
    #[serde(default)]
    pub spacemouse: SpaceMouseSettings,
    /// spacenavd settings.
    #[serde(default)]
    pub spacenavd: SpacenavdSettings,
    /// VRPN settings.
    #[serde(default)]
    pub vrpn: VrpnSettings,
    /// Plausibility gate of a tracker's poses ([`crate::gate`]).
    #[serde(default)]
    pub gate: GateSettings,
}

impl DeviceConfig {
    /// A device entry with every family setting at its default.
    pub fn new(name: impl Into<String>, kind: DeviceKind) -> Self {
        Self {
            name: name.into(),
            kind,
            port: None,
            baud: None,
            address: None,
            settle_ms: default_settle_ms(),
            poll_hz: default_poll_hz(),
            flock: FlockSettings::default(),
            fastrak: FastrakSettings::default(),
            cyberglove: CyberGloveSettings::default(),
            spacemouse: SpaceMouseSettings::default(),
            spacenavd: SpacenavdSettings::default(),
            vrpn: VrpnSettings::default(),
            gate: GateSettings::default(),
        }
    }

    /// True for the tracker families (their poses pass the [`crate::gate`]).
    pub fn is_tracker(&self) -> bool {
        matches!(
            self.kind,
            DeviceKind::Flock | DeviceKind::Fastrak | DeviceKind::Vrpn
        )
    }

    /// The shortest time between two records of this device, in seconds: the time
    /// its serial line needs to carry one record (8N1: ten bit times a byte);
    /// 0 for network devices.
    pub fn record_interval(&self) -> f64 {
        let bytes = match self.kind {
            DeviceKind::Flock => self.flock.record_len(),
            DeviceKind::Fastrak => fastrak::RECORD_LEN,
            DeviceKind::Cyberglove => usize::from(self.cyberglove.sensors) + 2,
            _ => return 0.0,
        };
        let baud = f64::from(self.baud.unwrap_or(DEFAULT_BAUD));
        bytes as f64 * 10.0 / baud
    }

    fn validate(&self) -> Result<(), String> {
        let ctx = |e: String| format!("device {:?}: {e}", self.name);
        if self.kind.is_serial() && self.port.is_none() {
            return Err(ctx("a serial device needs `port`".into()));
        }
        if let Some(b) = self.baud
            && !STANDARD_BAUDS.contains(&b)
        {
            return Err(ctx(format!(
                "baud {b} is not a standard rate; did you mean {}? (standard: {})",
                nearest_baud(b),
                STANDARD_BAUDS.map(|b| b.to_string()).join(", ")
            )));
        }
        if self.is_tracker() {
            self.gate.validate().map_err(ctx)?;
        }
        if !(self.poll_hz.is_finite() && (1.0..=1000.0).contains(&self.poll_hz)) {
            return Err(ctx(format!(
                "poll_hz must be 1..=1000, got {}",
                self.poll_hz
            )));
        }
        match self.kind {
            DeviceKind::Flock => self.flock.validate(),
            DeviceKind::Fastrak => self.fastrak.validate(),
            DeviceKind::Cyberglove => self.cyberglove.validate(),
            DeviceKind::SpacemouseHid => self.spacemouse.validate(),
            DeviceKind::Spacenavd => self.spacenavd.validate(),
            DeviceKind::Vrpn => self.vrpn_target().map(|_| ()),
        }
        .map_err(ctx)
    }

    /// True when this VRPN entry asks for the server's UDP channel: `vrpn.udp`
    /// and an address that is not TCP-only (`…@tcp://…` or `…@tcp:…`, as VRPN
    /// reads them).
    pub fn vrpn_udp(&self) -> bool {
        let a = self.address.as_deref().unwrap_or_default().trim();
        let rest = a.split_once('@').map_or(a, |(_, r)| r);
        self.vrpn.udp && !rest.starts_with("tcp:")
    }

    /// The VRPN address with the default port added when missing (`host:port`).
    pub fn vrpn_address(&self) -> Option<String> {
        self.vrpn_target().ok().map(|t| t.1)
    }

    /// The VRPN device name and `host:port` this entry reads, from `address` in any
    /// of the forms VRPN users write (`vrpn.cfg`, `vrpn_print_devices`):
    /// `host`, `host:port`, `Device@host`, `Device@host:port`, `Device@tcp://host:port`,
    /// `Device@tcp:host[:port]`, `Device@x-vrpn://host[:port]` — a device named in the address wins over
    /// `vrpn.device`; the port defaults to 3883.
    pub fn vrpn_target(&self) -> Result<(String, String), String> {
        let a = self
            .address
            .as_deref()
            .map(str::trim)
            .filter(|a| !a.is_empty())
            .ok_or("a VRPN device needs `address` (Tracker0@host[:port] or host[:port])")?;
        let (device, rest) = match a.split_once('@') {
            Some((d, r)) if !d.is_empty() => (d.to_owned(), r),
            Some(_) => return Err(format!("VRPN address {a:?}: no device name before '@'")),
            None => (self.vrpn.device.clone(), a),
        };
        let host_port = ["tcp://", "tcp:", "x-vrpn://", "x-vrpn:"]
            .iter()
            .find_map(|p| rest.strip_prefix(p))
            .unwrap_or(rest);
        if host_port.contains("://") {
            return Err(format!(
                "VRPN address {a:?}: the bridge speaks VRPN over TCP + UDP (`Device@host[:port]`, \
                 `x-vrpn://`) or TCP only (`Device@tcp://host:port`); no other scheme"
            ));
        }
        let (host, port) = match host_port.strip_prefix('[') {
            // an IPv6 literal: [::1] or [::1]:3883
            Some(v6) => {
                let (h, after) = v6
                    .split_once(']')
                    .ok_or_else(|| format!("VRPN address {a:?}: unclosed '['"))?;
                (format!("[{h}]"), after.strip_prefix(':'))
            }
            None => match host_port.rsplit_once(':') {
                Some((h, p)) => (h.to_owned(), Some(p)),
                None => (host_port.to_owned(), None),
            },
        };
        if host.is_empty() || host == "[]" {
            return Err(format!("VRPN address {a:?}: no host"));
        }
        let port = match port {
            Some(p) => p
                .parse::<u16>()
                .map_err(|_| format!("VRPN address {a:?}: bad port {p:?}"))?,
            None => 3883,
        };
        let addr = format!("{host}:{port}");
        Ok((device, addr))
    }
}

/// Tracker-to-scene calibration: `scene = translation + rotation · (scale · tracker)`,
/// orientations `rotation · q`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Calibration {
    /// Added last, in scene units.
    pub translation: [f64; 3],
    /// Unit quaternion x, y, z, w.
    pub rotation: [f64; 4],
    /// Scene units per tracker metre.
    pub scale: f64,
}

impl Default for Calibration {
    fn default() -> Self {
        Self {
            translation: [0.0; 3],
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: 1.0,
        }
    }
}

impl Calibration {
    /// The rotation as a quaternion.
    pub fn quat(&self) -> DQuat {
        DQuat::from_array(self.rotation).normalize()
    }

    /// Maps a tracker position (metres) to the scene.
    pub fn position(&self, p: DVec3) -> DVec3 {
        DVec3::from_array(self.translation) + self.quat() * (self.scale * p)
    }

    /// Maps a tracker orientation to the scene.
    pub fn orientation(&self, q: DQuat) -> DQuat {
        (self.quat() * q).normalize()
    }

    /// Maps a displacement (no translation).
    pub fn displacement(&self, d: DVec3) -> DVec3 {
        self.quat() * (self.scale * d)
    }

    fn validate(&self) -> Result<(), String> {
        let q = DQuat::from_array(self.rotation);
        if !(q.is_finite() && q.length() > 1e-9) {
            return Err("calibration.rotation must be a non-zero finite quaternion".into());
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err("calibration.scale must be positive".into());
        }
        if self.translation.iter().any(|v| !v.is_finite()) {
            return Err("calibration.translation must be finite".into());
        }
        Ok(())
    }
}

fn default_reach() -> f64 {
    0.05
}

/// A hand: a tracker sensor plus, optionally, a glove.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandConfig {
    /// Name (for logs).
    pub name: String,
    /// Name of the tracker device.
    pub tracker: String,
    /// Sensor index on that tracker.
    #[serde(default)]
    pub sensor: u16,
    /// Name of the glove device (a hand without a glove only points).
    #[serde(default)]
    pub glove: Option<String>,
    /// Grab radius in scene units: the nearest icon within it is taken.
    #[serde(default = "default_reach")]
    pub reach: f64,
    /// Glove calibration (raw values of the open and the closed hand).
    #[serde(default)]
    pub calibration: GloveCalibration,
}

/// The link to the server.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct ServerConfig {
    /// The device URL the server prints (`ws://host:port/ws?design=N&token=…`).
    pub url: String,
    /// The device token, when not in the URL.
    pub token: Option<String>,
    /// The design, when not in the URL.
    pub design: Option<u64>,
}

/// Which device drives the 3D menu and what its buttons do.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MenuConfig {
    /// Name of the 3D-mouse device (HID or spacenavd); `None` = the first one configured.
    pub device: Option<String>,
    /// Button number → action.
    pub buttons: BTreeMap<u16, MenuAction>,
    /// Scene units per second at full deflection when moving the selected icon.
    pub speed: f64,
    /// Radians per second at full twist when turning the selected normal or
    /// tangent icon's direction (the dead zones are the device's, `deadzone`).
    pub rotation_speed: f64,
}

impl Default for MenuConfig {
    fn default() -> Self {
        Self {
            device: None,
            buttons: BTreeMap::from([
                (0, MenuAction::NextEntry),
                (1, MenuAction::ApplyEntry),
                (2, MenuAction::SelectNextIcon),
                (3, MenuAction::PreviousEntry),
            ]),
            speed: 0.2,
            rotation_speed: 1.0,
        }
    }
}

/// How often continuous commands may leave for the server.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RatesConfig {
    /// Drags per second per held icon at most (latest wins; the last drag before a
    /// release is always sent). A 1 kHz tracker thus costs the server 120 solves a
    /// second, not 1000. Streaming serial trackers are also read at this rate, in
    /// bulk (every record that arrived, decoded at once).
    pub drag_hz: f64,
}

impl Default for RatesConfig {
    fn default() -> Self {
        Self { drag_hz: 120.0 }
    }
}

impl RatesConfig {
    /// Minimum time between two drags of one icon, in µs (by sample time).
    pub fn drag_period_us(&self) -> u64 {
        (1e6 / self.drag_hz).round() as u64
    }

    fn validate(&self) -> Result<(), String> {
        if !(self.drag_hz.is_finite() && self.drag_hz >= 1.0) {
            return Err(format!(
                "rates.drag_hz must be at least 1, got {}",
                self.drag_hz
            ));
        }
        Ok(())
    }
}

/// The whole configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// The server link.
    pub server: ServerConfig,
    /// Tracker-to-scene calibration.
    pub calibration: Calibration,
    /// Devices, in order; a device's [`SourceId`] is its index here.
    #[serde(rename = "device")]
    pub devices: Vec<DeviceConfig>,
    /// Hands.
    #[serde(rename = "hand")]
    pub hands: Vec<HandConfig>,
    /// The 3D menu.
    pub menu: MenuConfig,
    /// Send rates.
    pub rates: RatesConfig,
}

impl Config {
    /// Reads and validates a TOML file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text)
    }

    /// Parses and validates TOML text.
    pub fn parse(text: &str) -> Result<Self, ConfigError> {
        let c: Config = toml::from_str(text).map_err(|e| ConfigError::Parse(e.to_string()))?;
        c.validate().map_err(ConfigError::Invalid)?;
        Ok(c)
    }

    /// The configuration as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// Checks cross-references and ranges.
    pub fn validate(&self) -> Result<(), String> {
        self.calibration.validate()?;
        self.rates.validate()?;
        if self.devices.len() > usize::from(u16::MAX) {
            return Err("too many devices".into());
        }
        for (i, d) in self.devices.iter().enumerate() {
            d.validate()?;
            if self.devices[..i].iter().any(|e| e.name == d.name) {
                return Err(format!("device name {:?} used twice", d.name));
            }
        }
        for h in &self.hands {
            let t = self
                .device(&h.tracker)
                .ok_or_else(|| format!("hand {:?}: no device {:?}", h.name, h.tracker))?;
            if !matches!(
                t.1.kind,
                DeviceKind::Flock | DeviceKind::Fastrak | DeviceKind::Vrpn
            ) {
                return Err(format!(
                    "hand {:?}: {:?} is not a tracker",
                    h.name, h.tracker
                ));
            }
            if let Some(g) = &h.glove {
                let g = self
                    .device(g)
                    .ok_or_else(|| format!("hand {:?}: no device {g:?}", h.name))?;
                if g.1.kind != DeviceKind::Cyberglove {
                    return Err(format!("hand {:?}: {:?} is not a glove", h.name, g.1.name));
                }
            }
            if !(h.reach.is_finite() && h.reach > 0.0) {
                return Err(format!("hand {:?}: reach must be positive", h.name));
            }
            h.calibration
                .validate()
                .map_err(|e| format!("hand {:?}: {e}", h.name))?;
        }
        if let Some(m) = &self.menu.device {
            let d = self
                .device(m)
                .ok_or_else(|| format!("menu: no device {m:?}"))?;
            if !matches!(d.1.kind, DeviceKind::SpacemouseHid | DeviceKind::Spacenavd) {
                return Err(format!("menu: {m:?} is not a 3D mouse"));
            }
        }
        if !(self.menu.speed.is_finite() && self.menu.speed >= 0.0) {
            return Err("menu.speed must be non-negative".into());
        }
        if !(self.menu.rotation_speed.is_finite() && self.menu.rotation_speed >= 0.0) {
            return Err("menu.rotation_speed must be non-negative".into());
        }
        Ok(())
    }

    /// The device named `name` with its [`SourceId`].
    pub fn device(&self, name: &str) -> Option<(SourceId, &DeviceConfig)> {
        self.devices
            .iter()
            .enumerate()
            .find(|(_, d)| d.name == name)
            .map(|(i, d)| (SourceId(i as u16), d))
    }

    /// The 3D-mouse device driving the menu.
    pub fn menu_device(&self) -> Option<SourceId> {
        match &self.menu.device {
            Some(n) => self.device(n).map(|d| d.0),
            None => self
                .devices
                .iter()
                .position(|d| matches!(d.kind, DeviceKind::SpacemouseHid | DeviceKind::Spacenavd))
                .map(|i| SourceId(i as u16)),
        }
    }
}

/// The decoder for a device entry (also used by replay).
pub fn build_decoder(source: SourceId, d: &DeviceConfig) -> Box<dyn Decoder> {
    match d.kind {
        DeviceKind::Flock => Box::new(FlockDecoder::new(source, d.flock.clone())),
        DeviceKind::Fastrak => Box::new(FastrakDecoder::new(source, d.fastrak.clone())),
        DeviceKind::Cyberglove => Box::new(CyberGloveDecoder::new(source, d.cyberglove.clone())),
        DeviceKind::SpacemouseHid => Box::new(SpaceMouseDecoder::new(source, d.spacemouse.clone())),
        DeviceKind::Spacenavd => Box::new(SpacenavdDecoder::new(source, d.spacenavd.clone())),
        DeviceKind::Vrpn => {
            let mut v = d.vrpn.clone();
            if let Ok((device, _)) = d.vrpn_target() {
                v.device = device;
            }
            Box::new(VrpnDecoder::new(source, v))
        }
    }
}

fn build_script(d: &DeviceConfig) -> Script {
    let settle = Duration::from_millis(d.settle_ms);
    let mut script = match d.kind {
        DeviceKind::Flock => flock::script(&d.flock, settle),
        DeviceKind::Fastrak => fastrak::script(&d.fastrak, settle),
        DeviceKind::Cyberglove => cyberglove::script(&d.cyberglove, settle),
        DeviceKind::SpacemouseHid => spacemouse_hid::script(),
        DeviceKind::Spacenavd => spacenavd::script(),
        DeviceKind::Vrpn => vrpn::script(
            &d.vrpn_target().map(|t| t.0).unwrap_or_default(),
            d.vrpn_udp(),
        ),
    };
    if script.poll_interval.is_zero() {
        script.poll_interval = Duration::from_secs_f64(1.0 / d.poll_hz);
    }
    script
}

fn build_transport(d: &DeviceConfig) -> Box<dyn Transport> {
    let port = d.port.clone().unwrap_or_default();
    let baud = d.baud.unwrap_or(DEFAULT_BAUD);
    match d.kind {
        DeviceKind::Flock | DeviceKind::Fastrak | DeviceKind::Cyberglove => {
            Box::new(SerialTransport::new(port, baud))
        }
        DeviceKind::SpacemouseHid => Box::new(HidTransport::new(match &d.spacemouse.path {
            Some(p) => HidSelector::Path(p.clone()),
            None => HidSelector::AnyOf(d.spacemouse.allow_list()),
        })),
        DeviceKind::Spacenavd => Box::new(UnixTransport::new(d.spacenavd.socket_path())),
        DeviceKind::Vrpn if d.vrpn_udp() => {
            Box::new(VrpnUdpTransport::new(d.vrpn_address().unwrap_or_default()))
        }
        DeviceKind::Vrpn => Box::new(TcpTransport::new(d.vrpn_address().unwrap_or_default())),
    }
}

/// A ready driver for device entry `d` (not yet opened).
pub fn build_driver(source: SourceId, d: &DeviceConfig) -> Driver {
    let mut driver = Driver::new(
        d.name.clone(),
        source,
        build_transport(d),
        build_decoder(source, d),
        build_script(d),
    );
    if let Some(hint) = d.line_hint() {
        driver.set_garbage_hint(hint);
    }
    driver
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = r#"
[server]
url = "ws://127.0.0.1:7878/ws?design=1&token=abc"

[calibration]
translation = [0.0, -1.0, 0.5]
rotation = [0.0, 0.0, 0.7071067811865476, 0.7071067811865476]
scale = 2.0

[[device]]
name = "tracker"
kind = "flock"
port = "/dev/ttyUSB0"
baud = 38400
flock = { format = "pos_angles", birds = 2, group_mode = true }

[[device]]
name = "glove"
kind = "cyberglove"
port = "/dev/ttyUSB1"
cyberglove = { sensors = 18 }

[[device]]
name = "mouse"
kind = "spacemouse_hid"
spacemouse = { extra_ids = [[0x256f, 0xc6ff]] }

[[device]]
name = "studio"
kind = "vrpn"
address = "vrpnhost"
vrpn = { device = "Tracker1" }

[[hand]]
name = "right"
tracker = "tracker"
sensor = 1
glove = "glove"
reach = 0.1

[menu]
buttons = { 0 = "next_entry", 1 = "apply_entry" }
"#;

    #[test]
    fn parses_the_documented_shape() {
        let c = Config::parse(SAMPLE).unwrap();
        assert_eq!(c.devices.len(), 4);
        assert_eq!(c.devices[0].baud, Some(38400));
        assert_eq!(c.devices[0].flock.birds, 2);
        assert_eq!(c.devices[1].cyberglove.sensors, 18);
        assert_eq!(
            c.devices[3].vrpn_address().as_deref(),
            Some("vrpnhost:3883")
        );
        assert_eq!(c.hands[0].sensor, 1);
        assert_eq!(c.menu_device(), Some(SourceId(2)));
        assert!(
            c.devices[2]
                .spacemouse
                .allow_list()
                .contains(&(0x256f, 0xc6ff))
        );
        // calibration: scale 2, +90° about z, then translate
        let p = c.calibration.position(DVec3::X);
        assert!((p - DVec3::new(0.0, 1.0, 0.5)).length() < 1e-12);
        // round trip through TOML
        assert_eq!(Config::parse(&c.to_toml()).unwrap(), c);
    }

    #[test]
    fn the_shipped_example_is_valid() {
        let c = Config::parse(include_str!("../vsculpt-bridge.example.toml")).unwrap();
        assert_eq!(c.devices.len(), 3);
        assert_eq!(c.menu_device(), Some(SourceId(2)));
    }

    #[test]
    fn rejects_bad_configurations() {
        for (bad, why) in [
            (SAMPLE.replace("port = \"/dev/ttyUSB0\"\n", ""), "port"),
            (
                SAMPLE.replace("tracker = \"tracker\"", "tracker = \"nope\""),
                "no device",
            ),
            (
                SAMPLE.replace("glove = \"glove\"", "glove = \"mouse\""),
                "not a glove",
            ),
            (SAMPLE.replace("sensors = 18", "sensors = 20"), "sensors"),
            (SAMPLE.replace("scale = 2.0", "scale = -1.0"), "scale"),
            (
                SAMPLE.replace("birds = 2, ", "birds = 2, bogus = 1, "),
                "bogus",
            ),
            (SAMPLE.replace("baud = 38400", "baud = 7"), "baud"),
            (
                SAMPLE.replace("baud = 38400", "baud = 11520"),
                "baud 11520 is not a standard rate; did you mean 115200?",
            ),
            (
                SAMPLE.replace("baud = 38400", "baud = 3840"),
                "did you mean 38400?",
            ),
            (
                SAMPLE.replace("name = \"glove\"", "name = \"tracker\""),
                "twice",
            ),
        ] {
            let e = Config::parse(&bad).unwrap_err().to_string();
            assert!(e.contains(why), "{why}: {e}");
        }
    }
}
