//! Ascension Flock of Birds over RS-232: the record decoder, the word packing
//! and the command script.
//!
//! Wire format (checked against VRPN `vrpn_Flock.C` `get_report` and `reset`, HEAD 893c749,
//! and the Atamai "Flock of Birds C Interface Library" `flock.h`/`flock.c` as summarised in
//! `shared/reference/device-formats.md` §3.1):
//! * a record is `2 × words` bytes, plus one button byte in button mode, plus one
//!   FBB address byte in group mode; POSITION/ANGLES has 6 words, POSITION/QUATERNION 7;
//! * only the first byte of a record has bit 7 set (the *phasing bit*); the decoder
//!   resynchronises by scanning for it;
//! * each 16-bit word is sent LS byte first as two 7-bit bytes:
//!   `word = ((b0 & 0x7F) << 2) | ((b1 & 0x7F) << 9)` read as `i16` (14 significant bits);
//! * position `inches = word × full_scale / 32768` (36" standard, 72", 144" with the
//!   extended-range transmitter); angles `degrees = word × 180 / 32768` in the order
//!   azimuth (Z), elevation (Y), roll (X); quaternion elements `word / 32768` in the
//!   order w, x, y, z;
//! * in group mode the trailing byte is the bird's FBB address; VRPN maps it to a
//!   sensor number as `address − 1 − (1 if an ERT is unit 1)`.
//!
//! Commands: `B` point (also stops streaming), `@` stream, `Y` POS/ANGLES, `]` POS/QUAT,
//! `P 35 1` group mode, `0xF0 + addr` routes the next command to one bird, `L h s` sets
//! the hemisphere, `O 36` examines the flock status (14 bytes, bit 7 = accessible),
//! `G` sleep.

use super::driver::{Check, DecodeStats, Decoder, Script, Step};
use super::sample::{QUAT_NORM_TOLERANCE, Reading, Sample, SourceId, Timestamp, is_unit_quat};
use glam::{DQuat, DVec3, EulerRot};
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// Metres per inch.
pub const METRES_PER_INCH: f64 = 0.0254;

/// Record formats the bridge reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FlockFormat {
    /// POSITION/ANGLES (`Y`): x, y, z, azimuth, elevation, roll — 6 words.
    PosAngles,
    /// POSITION/QUATERNION (`]`): x, y, z, w, qx, qy, qz — 7 words.
    #[default]
    PosQuat,
}

impl FlockFormat {
    /// Data words per record.
    pub fn words(self) -> usize {
        match self {
            FlockFormat::PosAngles => 6,
            FlockFormat::PosQuat => 7,
        }
    }

    /// The command byte selecting this format.
    pub fn command(self) -> u8 {
        match self {
            FlockFormat::PosAngles => b'Y',
            FlockFormat::PosQuat => b']',
        }
    }
}

/// Which hemisphere the sensors operate in (`L` command).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Hemisphere {
    /// +X (forward), the power-on default.
    #[default]
    Forward,
    /// −X.
    Aft,
    /// +Y.
    Right,
    /// −Y.
    Left,
    /// +Z.
    Lower,
    /// −Z.
    Upper,
}

impl Hemisphere {
    /// The two data bytes of the `L` command (VRPN `vrpn_Flock.C` `reset`).
    pub fn bytes(self) -> [u8; 2] {
        match self {
            Hemisphere::Forward => [0x00, 0x00],
            Hemisphere::Aft => [0x00, 0x01],
            Hemisphere::Right => [0x06, 0x00],
            Hemisphere::Left => [0x06, 0x01],
            Hemisphere::Lower => [0x0c, 0x00],
            Hemisphere::Upper => [0x0c, 0x01],
        }
    }
}

/// How a flock is set up and what its records look like.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlockSettings {
    /// Record format.
    pub format: FlockFormat,
    /// Number of birds (receivers) to read.
    pub birds: u8,
    /// Group mode (records carry the bird's address byte); needed for more than one bird.
    pub group_mode: bool,
    /// An extended-range transmitter is unit 1 (shifts addresses, 144" full scale).
    pub ert: bool,
    /// Position full scale in inches (36, 72 or 144).
    pub full_scale_inches: f64,
    /// Records carry a button byte (button mode `M`).
    pub button_mode: bool,
    /// Stream (`@`) rather than poll with `B` each cycle.
    pub stream: bool,
    /// Hemisphere.
    pub hemisphere: Hemisphere,
    /// Conjugate every orientation (VRPN's `invert_quaternion` option, for a
    /// transmitter mounted above the user).
    pub invert_orientation: bool,
}

impl Default for FlockSettings {
    fn default() -> Self {
        Self {
            format: FlockFormat::PosQuat,
            birds: 1,
            group_mode: false,
            ert: false,
            full_scale_inches: 36.0,
            button_mode: false,
            stream: true,
            hemisphere: Hemisphere::Forward,
            invert_orientation: false,
        }
    }
}

impl FlockSettings {
    /// Bytes per record.
    pub fn record_len(&self) -> usize {
        2 * self.format.words() + usize::from(self.button_mode) + usize::from(self.group_mode)
    }

    /// FBB address of bird `i` (0-based): the transmitter (or ERT) is unit 1.
    pub fn address(&self, i: u8) -> u8 {
        i + 1 + u8::from(self.ert)
    }

    /// Checks the settings; `Err` names the problem.
    pub fn validate(&self) -> Result<(), String> {
        if self.birds == 0 || self.birds > 13 {
            return Err(format!("birds must be 1..=13, got {}", self.birds));
        }
        if self.birds > 1 && !self.group_mode {
            return Err("more than one bird needs group_mode = true".into());
        }
        if ![36.0, 72.0, 144.0].contains(&self.full_scale_inches) {
            return Err(format!(
                "full_scale_inches must be 36, 72 or 144, got {}",
                self.full_scale_inches
            ));
        }
        Ok(())
    }
}

/// Unpacks one 7-bit-packed word (LS byte first, phasing bit ignored).
pub fn unpack_word(b0: u8, b1: u8) -> i16 {
    ((((b0 & 0x7F) as u16) << 2) | (((b1 & 0x7F) as u16) << 9)) as i16
}

/// Packs a word for the wire (the two low bits are lost); `first` sets the phasing bit.
pub fn pack_word(w: i16, first: bool) -> [u8; 2] {
    let u = w as u16;
    let b0 = ((u >> 2) & 0x7F) as u8 | if first { 0x80 } else { 0 };
    let b1 = ((u >> 9) & 0x7F) as u8;
    [b0, b1]
}

/// Encodes one record of raw words (for simulators and tests).
pub fn encode_record(words: &[i16], button: Option<u8>, address: Option<u8>) -> Vec<u8> {
    let mut out = Vec::with_capacity(words.len() * 2 + 2);
    for (i, w) in words.iter().enumerate() {
        out.extend_from_slice(&pack_word(*w, i == 0));
    }
    if let Some(b) = button {
        out.push(b & 0x7F);
    }
    if let Some(a) = address {
        out.push(a & 0x7F);
    }
    out
}

/// Words of a pose as the Flock would send them (for simulators and tests).
///
/// `position` in metres, `orientation` a unit quaternion.
pub fn pose_words(settings: &FlockSettings, position: DVec3, orientation: DQuat) -> Vec<i16> {
    let per_inch = 32768.0 / settings.full_scale_inches;
    let to_word = |v: f64| (v.clamp(-32768.0, 32767.0)).round() as i16;
    let mut w: Vec<i16> = (0..3)
        .map(|i| to_word(position[i] / METRES_PER_INCH * per_inch))
        .collect();
    match settings.format {
        FlockFormat::PosQuat => {
            let q = if settings.invert_orientation {
                orientation.conjugate()
            } else {
                orientation
            };
            for v in [q.w, q.x, q.y, q.z] {
                w.push(to_word(v * 32768.0));
            }
        }
        FlockFormat::PosAngles => {
            let q = if settings.invert_orientation {
                orientation.conjugate()
            } else {
                orientation
            };
            let (az, el, roll) = q.to_euler(EulerRot::ZYX);
            for a in [az, el, roll] {
                w.push(to_word(a.to_degrees() * 32768.0 / 180.0));
            }
        }
    }
    w
}

/// Longest record (POS/MATRIX-class words + button + address), for the buffer.
const MAX_RECORD: usize = 32;

/// The Flock of Birds record decoder.
pub struct FlockDecoder {
    settings: FlockSettings,
    source: SourceId,
    buf: [u8; MAX_RECORD],
    len: usize,
    started: Timestamp,
    stats: DecodeStats,
}

impl FlockDecoder {
    /// A decoder for records shaped by `settings`.
    pub fn new(source: SourceId, settings: FlockSettings) -> Self {
        Self {
            settings,
            source,
            buf: [0; MAX_RECORD],
            len: 0,
            started: Timestamp(0),
            stats: DecodeStats::default(),
        }
    }

    fn decode(&self) -> Option<Reading> {
        let s = &self.settings;
        let words = s.format.words();
        let rec = &self.buf[..s.record_len()];
        let w: Vec<i16> = (0..words)
            .map(|i| unpack_word(rec[2 * i], rec[2 * i + 1]))
            .collect();
        let sensor = if s.group_mode {
            let addr = rec[rec.len() - 1];
            let first = 1 + u8::from(s.ert);
            if addr < first || addr - first >= s.birds {
                return None;
            }
            u16::from(addr - first)
        } else {
            0
        };
        let inch = s.full_scale_inches / 32768.0;
        let position = DVec3::new(
            f64::from(w[0]) * inch,
            f64::from(w[1]) * inch,
            f64::from(w[2]) * inch,
        ) * METRES_PER_INCH;
        let orientation = match s.format {
            FlockFormat::PosQuat => {
                let k = 1.0 / 32768.0;
                let q = DQuat::from_xyzw(
                    f64::from(w[4]) * k,
                    f64::from(w[5]) * k,
                    f64::from(w[6]) * k,
                    f64::from(w[3]) * k,
                );
                if !is_unit_quat(q, QUAT_NORM_TOLERANCE) {
                    return None;
                }
                q.normalize()
            }
            FlockFormat::PosAngles => {
                let k = std::f64::consts::PI / 32768.0;
                DQuat::from_euler(
                    EulerRot::ZYX,
                    f64::from(w[3]) * k,
                    f64::from(w[4]) * k,
                    f64::from(w[5]) * k,
                )
            }
        };
        let orientation = if s.invert_orientation {
            orientation.conjugate()
        } else {
            orientation
        };
        Some(Reading::Pose {
            sensor,
            position,
            orientation,
        })
    }
}

impl Decoder for FlockDecoder {
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        let rec_len = self.settings.record_len();
        for &b in chunk {
            if b & 0x80 != 0 {
                // A phasing bit always starts a record; anything half-read is lost.
                self.stats.discarded_bytes += self.len as u64;
                self.buf[0] = b;
                self.len = 1;
                self.started = at;
            } else if self.len == 0 {
                self.stats.discarded_bytes += 1;
                continue;
            } else {
                self.buf[self.len] = b;
                self.len += 1;
            }
            if self.len == rec_len {
                self.len = 0;
                match self.decode() {
                    Some(reading) => {
                        self.stats.records += 1;
                        out.push(Sample {
                            source: self.source,
                            time: self.started,
                            reading,
                        });
                    }
                    None => self.stats.rejected_records += 1,
                }
            }
        }
    }

    fn stats(&self) -> DecodeStats {
        self.stats
    }

    fn reset(&mut self) {
        self.len = 0;
    }
}

/// The command script for a flock (after VRPN `vrpn_Flock.C` `reset`, without its
/// multi-second hardware waits, which `settle` replaces).
pub fn script(s: &FlockSettings, settle: Duration) -> Script {
    let mut open = vec![Step::Send(vec![b'B']), Step::Drain(settle)];
    let units = usize::from(s.birds) + usize::from(s.ert);
    if s.group_mode {
        open.push(Step::Send(vec![b'P', 35, 1]));
    }
    for i in 0..s.birds {
        let mut cmd = Vec::new();
        if s.group_mode {
            cmd.push(0xF0 + s.address(i));
        }
        cmd.push(s.format.command());
        if s.group_mode {
            cmd.push(0xF0 + s.address(i));
        }
        cmd.push(b'L');
        cmd.extend_from_slice(&s.hemisphere.bytes());
        open.push(Step::Send(cmd));
    }
    if s.group_mode {
        open.push(Step::Send(vec![b'O', 36]));
        open.push(Step::Expect {
            len: 14,
            timeout: Duration::from_millis(500).max(settle),
            check: Check::HighBitSet(units.min(14)),
        });
    }
    if s.stream {
        open.push(Step::Send(vec![b'@']));
    }
    Script {
        open,
        poll: (!s.stream).then(|| vec![b'B']),
        close: vec![b'B', b'G'],
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed_all(d: &mut FlockDecoder, bytes: &[u8]) -> Vec<Sample> {
        let mut out = Vec::new();
        d.feed(bytes, Timestamp(1), &mut out);
        out
    }

    fn pose(s: &Sample) -> (u16, DVec3, DQuat) {
        match s.reading {
            Reading::Pose {
                sensor,
                position,
                orientation,
            } => (sensor, position, orientation),
            _ => panic!("not a pose"),
        }
    }

    /// The worked example of device-formats.md §3.1, recomputed by hand:
    /// 0x1120 → b0 = (0x1120 >> 2) & 0x7F = 0x48 | 0x80 = 0xC8, b1 = 0x1120 >> 9 = 0x08.
    #[test]
    fn published_test_vector() {
        let bytes = [
            0xc8, 0x08, 0x00, 0x70, 0x00, 0x00, 0x7f, 0x3f, 0, 0, 0, 0, 0, 0,
        ];
        assert_eq!(
            encode_record(&[0x1120, -8192, 0, 0x7FFC, 0, 0, 0], None, None),
            bytes
        );
        let mut d = FlockDecoder::new(SourceId(3), FlockSettings::default());
        let out = feed_all(&mut d, &bytes);
        assert_eq!(out.len(), 1);
        let (sensor, p, q) = pose(&out[0]);
        assert_eq!(sensor, 0);
        assert_eq!(out[0].source, SourceId(3));
        assert!((p.x - 4384.0 * 36.0 / 32768.0 * 0.0254).abs() < 1e-12);
        assert!((p.x / 0.0254 - 4.816).abs() < 1e-3);
        assert!((p.y / 0.0254 + 9.0).abs() < 1e-12);
        assert!(q.abs_diff_eq(DQuat::IDENTITY, 1e-3));
    }

    #[test]
    fn word_round_trip_keeps_14_bits() {
        for w in [-32768i16, -4, 0, 4, 0x1120, 32764, -8192] {
            let [b0, b1] = pack_word(w, true);
            assert_eq!(b0 & 0x80, 0x80);
            assert_eq!(b1 & 0x80, 0);
            assert_eq!(unpack_word(b0, b1), w);
        }
        // low two bits are not transmitted
        let [b0, b1] = pack_word(7, false);
        assert_eq!(unpack_word(b0, b1), 4);
    }

    #[test]
    fn pos_angles_decodes_euler_zyx() {
        let s = FlockSettings {
            format: FlockFormat::PosAngles,
            ..Default::default()
        };
        // azimuth 90° = 16384, elevation 0, roll 0, position (1", 2", -3")
        let per_inch = 32768.0 / 36.0;
        let words = [
            (per_inch * 1.0f64).round() as i16,
            (per_inch * 2.0f64).round() as i16,
            (per_inch * -3.0f64).round() as i16,
            16384,
            0,
            0,
        ];
        let bytes = encode_record(&words, None, None);
        assert_eq!(bytes.len(), 12);
        let mut d = FlockDecoder::new(SourceId(0), s);
        let out = feed_all(&mut d, &bytes);
        let (_, p, q) = pose(&out[0]);
        // 14 significant bits: one step is 4 × 36/32768 inch
        assert!((p - DVec3::new(1.0, 2.0, -3.0) * 0.0254).length() < 4.0 * 36.0 / 32768.0 * 0.0254);
        // +90° about Z maps x to y
        assert!((q * DVec3::X - DVec3::Y).length() < 1e-3);
    }

    #[test]
    fn group_mode_addresses_map_to_sensors() {
        let s = FlockSettings {
            birds: 2,
            group_mode: true,
            ..Default::default()
        };
        assert_eq!(s.record_len(), 15);
        // birds sit at FBB addresses 1 and 2 (VRPN: sensor = address - 1 - ERT)
        let mut bytes = encode_record(&[100, 0, 0, 0x7FFC, 0, 0, 0], None, Some(1));
        bytes.extend(encode_record(&[200, 0, 0, 0x7FFC, 0, 0, 0], None, Some(2)));
        // address 3 is not a configured bird: rejected
        bytes.extend(encode_record(&[300, 0, 0, 0x7FFC, 0, 0, 0], None, Some(3)));
        let mut d = FlockDecoder::new(SourceId(0), s);
        let out = feed_all(&mut d, &bytes);
        assert_eq!(out.len(), 2);
        assert_eq!(pose(&out[0]).0, 0);
        assert_eq!(pose(&out[1]).0, 1);
        assert_eq!(d.stats().rejected_records, 1);
    }

    #[test]
    fn ert_shifts_addresses_and_scale() {
        let s = FlockSettings {
            birds: 1,
            group_mode: true,
            ert: true,
            full_scale_inches: 144.0,
            ..Default::default()
        };
        let bytes = encode_record(&[16384, 0, 0, 0x7FFC, 0, 0, 0], None, Some(2));
        let mut d = FlockDecoder::new(SourceId(0), s);
        let out = feed_all(&mut d, &bytes);
        let (sensor, p, _) = pose(&out[0]);
        assert_eq!(sensor, 0);
        assert!((p.x - 72.0 * 0.0254).abs() < 1e-9);
    }

    #[test]
    fn garbage_truncation_and_split_feeds_resynchronise() {
        let good = encode_record(&[1000, 2000, -3000, 0x7FFC, 0, 0, 0], None, None);
        let mut stream = vec![0x01, 0x7f, 0x33]; // garbage without phasing bits
        stream.extend_from_slice(&good[..9]); // truncated record
        stream.extend_from_slice(&good); // full record: the phasing bit restarts the parse
        stream.extend_from_slice(&[0x05, 0x06]); // overlong tail
        stream.extend_from_slice(&good);
        let mut whole = FlockDecoder::new(SourceId(0), FlockSettings::default());
        let a = feed_all(&mut whole, &stream);
        let mut split = FlockDecoder::new(SourceId(0), FlockSettings::default());
        let mut b = Vec::new();
        for byte in &stream {
            split.feed(std::slice::from_ref(byte), Timestamp(1), &mut b);
        }
        assert_eq!(a.len(), 2);
        assert_eq!(a, b);
        for s in &a {
            let (_, p, _) = pose(s);
            assert!((p.x - 1000.0 * 36.0 / 32768.0 * 0.0254).abs() < 1e-12);
        }
        assert_eq!(whole.stats().discarded_bytes, 3 + 9 + 2);
    }

    #[test]
    fn non_unit_quaternion_is_never_a_pose() {
        // all quaternion words zero: norm 0
        let bytes = encode_record(&[0, 0, 0, 0, 0, 0, 0], None, None);
        let mut d = FlockDecoder::new(SourceId(0), FlockSettings::default());
        assert!(feed_all(&mut d, &bytes).is_empty());
        assert_eq!(d.stats().rejected_records, 1);
    }

    #[test]
    fn pose_words_round_trip() {
        for format in [FlockFormat::PosQuat, FlockFormat::PosAngles] {
            let s = FlockSettings {
                format,
                ..Default::default()
            };
            let q = DQuat::from_euler(EulerRot::ZYX, 0.3, -0.4, 1.1);
            let p = DVec3::new(0.2, -0.3, 0.1);
            let bytes = encode_record(&pose_words(&s, p, q), None, None);
            let mut d = FlockDecoder::new(SourceId(0), s);
            let out = feed_all(&mut d, &bytes);
            let (_, p2, q2) = pose(&out[0]);
            assert!((p2 - p).length() < 1e-4, "{format:?}");
            assert!(q2.dot(q).abs() > 1.0 - 1e-6, "{format:?}");
        }
    }

    #[test]
    fn script_matches_vrpn_reset_sequence() {
        let s = FlockSettings {
            birds: 2,
            group_mode: true,
            ..Default::default()
        };
        let sc = script(&s, Duration::from_millis(1));
        assert_eq!(sc.open[0], Step::Send(vec![b'B']));
        assert_eq!(sc.open[2], Step::Send(vec![b'P', 35, 1]));
        assert_eq!(sc.open[3], Step::Send(vec![0xF1, b']', 0xF1, b'L', 0, 0]));
        assert_eq!(sc.open.last(), Some(&Step::Send(vec![b'@'])));
        assert_eq!(sc.close, vec![b'B', b'G']);
        // O 36: bit 7 of each unit's status byte = accessible
        let check = Check::HighBitSet(3);
        assert!(
            check
                .verify(&[0xE0, 0xA0, 0xA0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])
                .is_ok()
        );
        assert!(
            check
                .verify(&[0xE0, 0xA0, 0x20, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0])
                .is_err()
        );
    }
}
