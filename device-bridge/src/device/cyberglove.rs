//! CyberGlove (Immersion / CyberGlove Systems) over RS-232: the record decoder
//! and the command script.
//!
//! Wire format (as summarised in `shared/reference/device-formats.md` §4.1 from
//! OrebroUniversity/cyberglove `serial_glove.c`, TAMS-Group/cybergloveplus
//! `cybergloveraw.cpp` and asr-ros/asr_cyberglove_lib `gloveDevice.cc`): 115200 8N1.
//! A poll is the single byte `G`; the reply, and every streamed record after `S`,
//! is `'G'`, then one byte per sensor (18 or 22 sensors, each in 1..=255 — a zero
//! byte never occurs inside a record), then a 5-byte timestamp if `D` is on, a
//! status byte if `U` is on, optional error pairs `'e','s'` (sample error) or
//! `'e','g'` (glove unplugged), then a terminating `0x00`.
//!
//! Resynchronisation: a candidate record starts at a `'G'`; it is accepted only when
//! every sensor byte is non-zero and the terminator sits exactly where the settings
//! say. Otherwise the candidate's first byte is dropped and scanning resumes, so a
//! sensor value that happens to equal `'G'` can never start a wrong record that
//! survives the checks.

use super::driver::{Check, DecodeStats, Decoder, Script, Step};
use super::sample::{GloveValues, Reading, Sample, SourceId, Timestamp};
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// How a CyberGlove is set up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CyberGloveSettings {
    /// Number of joint sensors: 18 or 22.
    pub sensors: u8,
    /// Records carry the 5-byte timestamp (`D` on).
    pub timestamp: bool,
    /// Records carry the status byte (`U` on).
    pub status_byte: bool,
    /// Stream records (`S`) rather than poll with `G`.
    pub stream: bool,
}

impl Default for CyberGloveSettings {
    fn default() -> Self {
        Self {
            sensors: 22,
            timestamp: false,
            status_byte: false,
            stream: false,
        }
    }
}

impl CyberGloveSettings {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), String> {
        if self.sensors != 18 && self.sensors != 22 {
            return Err(format!("sensors must be 18 or 22, got {}", self.sensors));
        }
        Ok(())
    }

    /// Bytes between the sensors and the error pairs.
    fn extras(&self) -> usize {
        5 * usize::from(self.timestamp) + usize::from(self.status_byte)
    }
}

/// Encodes a record (for simulators and tests). Sensor values of 0 are sent as 1,
/// as the glove never sends 0.
pub fn encode_record(settings: &CyberGloveSettings, values: &[u8], error: Option<u8>) -> Vec<u8> {
    let mut r = vec![b'G'];
    r.extend(values.iter().map(|&v| v.max(1)));
    if settings.timestamp {
        r.extend_from_slice(&[0, 0, 0, 0, 0]);
    }
    if settings.status_byte {
        r.push(0);
    }
    if let Some(e) = error {
        r.extend_from_slice(&[b'e', e]);
    }
    r.push(0);
    r
}

/// Outcome of trying to parse a record at the start of the buffer.
enum Attempt {
    /// Need more bytes.
    More,
    /// Not a record at this position.
    Invalid,
    /// A record of this many bytes; `None` when the glove flagged it as bad.
    Done(usize, Option<Reading>),
}

/// The CyberGlove record decoder.
pub struct CyberGloveDecoder {
    settings: CyberGloveSettings,
    source: SourceId,
    buf: Vec<u8>,
    started: Timestamp,
    stats: DecodeStats,
    unplugged: bool,
}

/// Error pairs tolerated in one record before it is called invalid.
const MAX_ERROR_PAIRS: usize = 2;

impl CyberGloveDecoder {
    /// A decoder for a glove set up as `settings`.
    pub fn new(source: SourceId, settings: CyberGloveSettings) -> Self {
        Self {
            settings,
            source,
            buf: Vec::with_capacity(64),
            started: Timestamp(0),
            stats: DecodeStats::default(),
            unplugged: false,
        }
    }

    /// True after the last record said the glove is unplugged from its box (`'e','g'`).
    pub fn glove_unplugged(&self) -> bool {
        self.unplugged
    }

    fn attempt(&mut self) -> Attempt {
        let b = &self.buf;
        let n = usize::from(self.settings.sensors);
        let fixed = 1 + n + self.settings.extras();
        let sensor_end = (1 + n).min(b.len());
        if b[1..sensor_end].contains(&0) {
            return Attempt::Invalid;
        }
        if b.len() < fixed + 1 {
            return Attempt::More;
        }
        let mut i = fixed;
        let mut bad = false;
        let mut unplugged = false;
        for _ in 0..=MAX_ERROR_PAIRS {
            match b.get(i) {
                None => return Attempt::More,
                Some(0) => {
                    self.unplugged = unplugged;
                    let reading = if bad {
                        None
                    } else {
                        GloveValues::new(&b[1..1 + n]).map(Reading::Glove)
                    };
                    return Attempt::Done(i + 1, reading);
                }
                Some(b'e') => match b.get(i + 1) {
                    None => return Attempt::More,
                    Some(b's') => {
                        bad = true;
                        i += 2;
                    }
                    Some(b'g') => {
                        bad = true;
                        unplugged = true;
                        i += 2;
                    }
                    Some(_) => return Attempt::Invalid,
                },
                Some(_) => return Attempt::Invalid,
            }
        }
        Attempt::Invalid
    }
}

impl Decoder for CyberGloveDecoder {
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        for &byte in chunk {
            if self.buf.is_empty() {
                if byte == b'G' {
                    self.buf.push(byte);
                    self.started = at;
                } else {
                    self.stats.discarded_bytes += 1;
                }
                continue;
            }
            self.buf.push(byte);
            // Re-examine the buffer until it needs more bytes.
            loop {
                if self.buf.is_empty() {
                    break;
                }
                match self.attempt() {
                    Attempt::More => break,
                    Attempt::Done(len, reading) => {
                        match reading {
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
                        self.buf.drain(..len);
                        self.skip_to_header();
                    }
                    Attempt::Invalid => {
                        self.buf.remove(0);
                        self.stats.discarded_bytes += 1;
                        self.skip_to_header();
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
        self.unplugged = false;
    }

    fn fatal(&self) -> Option<String> {
        self.unplugged.then(|| {
            "the glove is not plugged into its box (the CyberGlove answers 'e','g'): \
             connect the glove's cable to the CyberGlove box"
                .to_owned()
        })
    }
}

impl CyberGloveDecoder {
    fn skip_to_header(&mut self) {
        let skip = self
            .buf
            .iter()
            .position(|&c| c == b'G')
            .unwrap_or(self.buf.len());
        self.stats.discarded_bytes += skip as u64;
        self.buf.drain(..skip);
    }
}

/// The command script: first `?S` (total sensors; the glove answers `?`, `S`, the
/// count, NUL) checks that the glove has the configured number of sensors; then
/// polling with `G` (the documented request) or streaming with `S`. Streaming is
/// stopped with Ctrl-C (0x03), the manual's "^C"; the asr library sends the two
/// characters `^c` instead, so polling is the default.
pub fn script(s: &CyberGloveSettings, settle: Duration) -> Script {
    let mut open = vec![
        Step::Send(vec![0x03]),
        Step::Drain(settle),
        Step::Send(b"?S".to_vec()),
        Step::Expect {
            len: 4,
            timeout: Duration::from_millis(500).max(settle),
            check: Check::Equals(vec![b'?', b'S', s.sensors, 0]),
        },
    ];
    if s.stream {
        open.push(Step::Send(vec![b'S']));
    }
    Script {
        open,
        poll: (!s.stream).then(|| vec![b'G']),
        close: if s.stream { vec![0x03] } else { Vec::new() },
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(out: &[Sample]) -> Vec<Vec<u8>> {
        out.iter()
            .map(|s| match s.reading {
                Reading::Glove(g) => g.as_slice().to_vec(),
                _ => panic!(),
            })
            .collect()
    }

    #[test]
    fn reply_layout_22_and_18_sensors() {
        for sensors in [22u8, 18] {
            let s = CyberGloveSettings {
                sensors,
                ..Default::default()
            };
            let v: Vec<u8> = (1..=sensors).map(|i| i * 10).collect();
            let r = encode_record(&s, &v, None);
            assert_eq!(r.len(), usize::from(sensors) + 2);
            assert_eq!(r[0], b'G');
            assert_eq!(*r.last().unwrap(), 0);
            let mut d = CyberGloveDecoder::new(SourceId(0), s);
            let mut out = Vec::new();
            d.feed(&r, Timestamp(0), &mut out);
            assert_eq!(values(&out), vec![v]);
        }
    }

    #[test]
    fn timestamp_status_and_error_pairs() {
        let s = CyberGloveSettings {
            timestamp: true,
            status_byte: true,
            ..Default::default()
        };
        let v = vec![71u8; 22]; // every sensor equals 'G'
        let good = encode_record(&s, &v, None);
        assert_eq!(good.len(), 1 + 22 + 5 + 1 + 1);
        let sample_err = encode_record(&s, &v, Some(b's'));
        let unplugged = encode_record(&s, &v, Some(b'g'));
        let mut stream = sample_err.clone();
        stream.extend_from_slice(&good);
        stream.extend_from_slice(&unplugged);
        let mut d = CyberGloveDecoder::new(SourceId(0), s);
        let mut out = Vec::new();
        d.feed(&stream, Timestamp(0), &mut out);
        assert_eq!(values(&out), vec![v]);
        assert_eq!(d.stats().rejected_records, 2);
        assert!(d.glove_unplugged());
    }

    #[test]
    fn garbage_short_overlong_are_skipped_in_any_split() {
        let s = CyberGloveSettings::default();
        let v: Vec<u8> = (0..22).map(|i| 100 + i).collect();
        let good = encode_record(&s, &v, None);
        let mut stream = b"\x01\x02G\x05".to_vec(); // garbage including a 'G'
        stream.extend_from_slice(&good[..10]); // truncated record
        stream.push(0); // ... ended early
        stream.extend_from_slice(&good);
        let mut long = good.clone();
        long.insert(20, 9); // overlong record: terminator misplaced
        stream.extend_from_slice(&long);
        stream.extend_from_slice(&good);
        for chunk in [1usize, 2, 7, 1000] {
            let mut d = CyberGloveDecoder::new(SourceId(0), s.clone());
            let mut out = Vec::new();
            for c in stream.chunks(chunk) {
                d.feed(c, Timestamp(0), &mut out);
            }
            assert_eq!(values(&out), vec![v.clone(), v.clone()], "chunk {chunk}");
        }
    }

    #[test]
    fn script_polls_with_g() {
        let sc = script(&CyberGloveSettings::default(), Duration::ZERO);
        assert_eq!(sc.poll, Some(vec![b'G']));
        let st = script(
            &CyberGloveSettings {
                stream: true,
                ..Default::default()
            },
            Duration::ZERO,
        );
        assert!(st.open.contains(&Step::Send(vec![b'S'])));
        assert_eq!(st.poll, None);
    }
}
