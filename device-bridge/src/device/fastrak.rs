//! Polhemus Fastrak (and InterSense IS-900 in Fastrak mode) over RS-232: the binary
//! record decoder and the command script.
//!
//! Wire format (checked against VRPN `vrpn_Tracker_Fastrak.C` `reset`, `report_length`
//! and `get_report`, HEAD 893c749, and Vrui `PolhemusFastrak.cpp` as summarised in
//! `shared/reference/device-formats.md` §3.2): with the output list `O<st>,2,11,0`
//! (position, quaternion, space) and binary mode (`f`), each record is 32 bytes:
//! `'0'`, the station as an ASCII digit `'1'..'4'`, a status byte (`' '` or a letter
//! `'A'..'F'` for warnings), three little-endian `f32` positions, four little-endian
//! `f32` quaternion elements in the order w, x, y, z, and a trailing `' '`.
//! Positions are in inches after `U` (centimetres after `u`, from the manual; not
//! confirmed in code). Resynchronisation looks for `'0'` followed by a valid station.
//!
//! Commands: `c` stop continuous, `C` continuous, `P` one record, `f` binary,
//! `O<st>,<items>\r` output list, `U`/`u` inches/centimetres.

use super::driver::{DecodeStats, Decoder, Script, Step};
use super::flock::METRES_PER_INCH;
use super::sample::{QUAT_NORM_TOLERANCE, Reading, Sample, SourceId, Timestamp, is_unit_quat};
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// Bytes in one binary record with the output list 2,11,0.
pub const RECORD_LEN: usize = 32;

/// Largest position magnitude accepted, in device units (the Fastrak's range is a
/// few feet; anything beyond this is a corrupt record).
const MAX_POSITION: f32 = 1000.0;

/// Position units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FastrakUnits {
    /// Inches (`U`).
    #[default]
    Inches,
    /// Centimetres (`u`).
    Centimetres,
}

impl FastrakUnits {
    /// Metres per device unit.
    pub fn metres(self) -> f64 {
        match self {
            FastrakUnits::Inches => METRES_PER_INCH,
            FastrakUnits::Centimetres => 0.01,
        }
    }

    /// The command byte selecting the units.
    pub fn command(self) -> u8 {
        match self {
            FastrakUnits::Inches => b'U',
            FastrakUnits::Centimetres => b'u',
        }
    }
}

/// How a Fastrak is set up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FastrakSettings {
    /// Number of stations (receivers) in use, 1..=4; stations are numbered from 1.
    pub stations: u8,
    /// Position units.
    pub units: FastrakUnits,
    /// Continuous output (`C`) rather than polling with `P`.
    pub stream: bool,
}

impl Default for FastrakSettings {
    fn default() -> Self {
        Self {
            stations: 1,
            units: FastrakUnits::Inches,
            stream: true,
        }
    }
}

impl FastrakSettings {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=4).contains(&self.stations) {
            return Err(format!("stations must be 1..=4, got {}", self.stations));
        }
        Ok(())
    }
}

/// Encodes one binary record (for simulators and tests). `position` in device units.
pub fn encode_record(
    station: u8,
    status: u8,
    position: [f32; 3],
    wxyz: [f32; 4],
) -> [u8; RECORD_LEN] {
    let mut r = [0u8; RECORD_LEN];
    r[0] = b'0';
    r[1] = b'0' + station;
    r[2] = status;
    for (i, v) in position.iter().chain(wxyz.iter()).enumerate() {
        r[3 + 4 * i..7 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    r[31] = b' ';
    r
}

/// The Fastrak binary record decoder.
pub struct FastrakDecoder {
    settings: FastrakSettings,
    source: SourceId,
    buf: Vec<u8>,
    started: Timestamp,
    stats: DecodeStats,
}

impl FastrakDecoder {
    /// A decoder for a Fastrak set up as `settings`.
    pub fn new(source: SourceId, settings: FastrakSettings) -> Self {
        Self {
            settings,
            source,
            buf: Vec::with_capacity(2 * RECORD_LEN),
            started: Timestamp(0),
            stats: DecodeStats::default(),
        }
    }

    fn station_ok(&self, b: u8) -> bool {
        (b'1'..b'1' + self.settings.stations).contains(&b)
    }

    fn decode(&self, r: &[u8]) -> Option<Reading> {
        if r[0] != b'0' || !self.station_ok(r[1]) {
            return None;
        }
        if r[2] != b' ' && !r[2].is_ascii_alphabetic() {
            return None;
        }
        if r[RECORD_LEN - 1] != b' ' {
            return None;
        }
        let f =
            |i: usize| f32::from_le_bytes([r[3 + 4 * i], r[4 + 4 * i], r[5 + 4 * i], r[6 + 4 * i]]);
        let p = [f(0), f(1), f(2)];
        if p.iter().any(|v| !v.is_finite() || v.abs() > MAX_POSITION) {
            return None;
        }
        let q = DQuat::from_xyzw(
            f64::from(f(4)),
            f64::from(f(5)),
            f64::from(f(6)),
            f64::from(f(3)),
        );
        if !is_unit_quat(q, QUAT_NORM_TOLERANCE) {
            return None;
        }
        let m = self.settings.units.metres();
        Some(Reading::Pose {
            sensor: u16::from(r[1] - b'1'),
            position: DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * m,
            orientation: q.normalize(),
        })
    }
}

impl Decoder for FastrakDecoder {
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        for &b in chunk {
            match self.buf.len() {
                0 => {
                    if b == b'0' {
                        self.buf.push(b);
                        self.started = at;
                    } else {
                        self.stats.discarded_bytes += 1;
                    }
                    continue;
                }
                1 if !self.station_ok(b) => {
                    // Not a record start: drop the '0' and look at this byte afresh.
                    self.stats.discarded_bytes += 1;
                    self.buf.clear();
                    if b == b'0' {
                        self.buf.push(b);
                        self.started = at;
                    } else {
                        self.stats.discarded_bytes += 1;
                    }
                    continue;
                }
                _ => self.buf.push(b),
            }
            if self.buf.len() == RECORD_LEN {
                match self.decode(&self.buf) {
                    Some(reading) => {
                        self.stats.records += 1;
                        out.push(Sample {
                            source: self.source,
                            time: self.started,
                            reading,
                        });
                        self.buf.clear();
                    }
                    None => {
                        // Bad record: drop its first byte and rescan the rest.
                        self.stats.rejected_records += 1;
                        let rest: Vec<u8> = self.buf.drain(1..).collect();
                        self.buf.clear();
                        self.stats.discarded_bytes += 1;
                        let mut sub = Vec::new();
                        let start = rest.iter().position(|&c| c == b'0');
                        if let Some(s) = start {
                            self.stats.discarded_bytes += s as u64;
                            self.feed(&rest[s..], at, &mut sub);
                        } else {
                            self.stats.discarded_bytes += rest.len() as u64;
                        }
                        out.extend(sub);
                    }
                }
            }
        }
    }

    fn stats(&self) -> DecodeStats {
        self.stats
    }

    fn reset(&mut self) {
        self.buf.clear();
    }
}

/// The command script (after VRPN `vrpn_Tracker_Fastrak.C` `reset`, without the
/// Ctrl-Y hardware reset and its 10–20 s wait).
pub fn script(s: &FastrakSettings, settle: Duration) -> Script {
    let mut open = vec![Step::Send(vec![b'c']), Step::Drain(settle)];
    for st in 1..=s.stations {
        open.push(Step::Send(format!("O{st},2,11,0\r").into_bytes()));
    }
    open.push(Step::Send(vec![s.units.command(), b'f']));
    if s.stream {
        open.push(Step::Send(vec![b'C']));
    }
    Script {
        open,
        poll: (!s.stream).then(|| vec![b'P']),
        close: vec![b'c'],
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode_all(d: &mut FastrakDecoder, bytes: &[u8]) -> Vec<Sample> {
        let mut out = Vec::new();
        d.feed(bytes, Timestamp(5), &mut out);
        out
    }

    #[test]
    fn byte_layout_is_as_published() {
        let r = encode_record(2, b' ', [1.0, -2.5, 3.0], [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(&r[..3], b"02 ");
        assert_eq!(&r[3..7], &[0x00, 0x00, 0x80, 0x3f]); // 1.0f32 little-endian
        assert_eq!(&r[7..11], &[0x00, 0x00, 0x20, 0xc0]); // -2.5f32
        assert_eq!(&r[15..19], &[0x00, 0x00, 0x80, 0x3f]); // w = 1
        assert_eq!(r[31], b' ');
        let mut d = FastrakDecoder::new(
            SourceId(1),
            FastrakSettings {
                stations: 2,
                ..Default::default()
            },
        );
        let out = decode_all(&mut d, &r);
        assert_eq!(out.len(), 1);
        match out[0].reading {
            Reading::Pose {
                sensor,
                position,
                orientation,
            } => {
                assert_eq!(sensor, 1);
                assert!((position - DVec3::new(1.0, -2.5, 3.0) * 0.0254).length() < 1e-9);
                assert_eq!(orientation, DQuat::IDENTITY);
            }
            _ => panic!(),
        }
    }

    #[test]
    fn centimetres_and_quaternion_order() {
        let h = std::f32::consts::FRAC_1_SQRT_2;
        // 90° about z: w = x? no: w = cos45, z = sin45
        let r = encode_record(1, b'A', [10.0, 0.0, 0.0], [h, 0.0, 0.0, h]);
        let s = FastrakSettings {
            units: FastrakUnits::Centimetres,
            ..Default::default()
        };
        let out = decode_all(&mut FastrakDecoder::new(SourceId(0), s), &r);
        match out[0].reading {
            Reading::Pose {
                position,
                orientation,
                ..
            } => {
                assert!((position.x - 0.1).abs() < 1e-7);
                assert!((orientation * DVec3::X - DVec3::Y).length() < 1e-6);
            }
            _ => panic!(),
        }
    }

    #[test]
    fn garbage_short_overlong_and_bad_values_are_skipped() {
        let good = encode_record(1, b' ', [1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0]);
        let mut nan = encode_record(1, b' ', [f32::NAN, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0]);
        nan[0] = b'0';
        let bad_quat = encode_record(1, b' ', [1.0, 2.0, 3.0], [0.5, 0.0, 0.0, 0.0]);
        let mut stream = b"xx0A09".to_vec(); // garbage, '0' then invalid station
        stream.extend_from_slice(&good[..20]); // short record
        stream.extend_from_slice(&good);
        stream.extend_from_slice(b"\r\n"); // overlong tail
        stream.extend_from_slice(&nan);
        stream.extend_from_slice(&bad_quat);
        stream.extend_from_slice(&good);
        let mut d = FastrakDecoder::new(SourceId(0), FastrakSettings::default());
        let out = decode_all(&mut d, &stream);
        assert_eq!(out.len(), 2, "{:?}", d.stats());
        let mut split = FastrakDecoder::new(SourceId(0), FastrakSettings::default());
        let mut out2 = Vec::new();
        for c in stream.chunks(3) {
            split.feed(c, Timestamp(5), &mut out2);
        }
        assert_eq!(out, out2);
        for s in &out {
            match s.reading {
                Reading::Pose { position, .. } => {
                    assert!((position - DVec3::new(1.0, 2.0, 3.0) * 0.0254).length() < 1e-9)
                }
                _ => panic!(),
            }
        }
        assert!(d.stats().rejected_records >= 2);
    }

    #[test]
    fn script_sets_output_list_binary_and_continuous() {
        let sc = script(
            &FastrakSettings {
                stations: 2,
                ..Default::default()
            },
            Duration::ZERO,
        );
        assert_eq!(sc.open[0], Step::Send(b"c".to_vec()));
        assert_eq!(sc.open[2], Step::Send(b"O1,2,11,0\r".to_vec()));
        assert_eq!(sc.open[3], Step::Send(b"O2,2,11,0\r".to_vec()));
        assert_eq!(sc.open[4], Step::Send(b"Uf".to_vec()));
        assert_eq!(sc.open[5], Step::Send(b"C".to_vec()));
        assert!(sc.poll.is_none());
    }
}
