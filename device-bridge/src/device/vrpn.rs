//! A VRPN tracker client in TCP-only mode: the cookie exchange, the framed message
//! decoder, sender/type descriptions and `vrpn_Tracker Pos_Quat` payloads.
//!
//! Wire format (checked against VRPN `vrpn_Connection.C` — `write_vrpn_cookie`,
//! `marshall_message`, `getOneTCPMessage`, `pack_sender_description` — and
//! `vrpn_Tracker.C` `encode_to`, HEAD 893c749; see also `shared/reference/device-formats.md` §1):
//! * each side sends a 24-byte cookie: `"vrpn: ver. 07.38"`, two spaces, an ASCII
//!   log-mode digit, NUL padding; a peer is accepted when its first 14 bytes are
//!   `"vrpn: ver. 07."`;
//! * every message has a 24-byte big-endian header — total length (24 + unpadded
//!   payload), seconds, microseconds, sender id, type id, sequence — and a payload
//!   zero-padded to a multiple of 8;
//! * type −1 (sender description) and −2 (type description) carry the described id
//!   in the sender field and a payload of BE `u32` (name length + 1), the name and a NUL;
//! * `vrpn_Tracker Pos_Quat` payloads are exactly 64 bytes: `i32` sensor, `i32`
//!   filler, 3 × `f64` position (metres), 4 × `f64` quaternion (x, y, z, w), all BE.
//!
//! VRPN over UDP (`vrpn_Connection.C`: `finish_new_connection_setup`,
//! `pack_udp_description`, `handle_UDP_message`, `getOneUDPMessage`,
//! `pack_message`): unless the connection is TCP-only, the client opens a UDP
//! port and tells the server over TCP with a message of type −3 whose *sender*
//! field is the port and whose payload is the client's IP address as a
//! NUL-terminated string ([`udp_description`]); the server then sends every
//! message of its "low latency" class — tracker reports among them — as UDP
//! datagrams to that port, one or more messages per datagram, each framed exactly
//! as on TCP (24-byte header, payload padded to 8). The header's sixth word is
//! the sender's per-channel sequence number (`d_udpSequenceNumber`, one per
//! message). A datagram is lossy: it may be lost, duplicated or arrive out of
//! order. [`VrpnDecoder`]'s [`Decoder::feed_datagram`] keeps a message only when
//! its sequence number is newer than the last kept (or, from a server that
//! leaves it 0, its time is later), so a late or repeated datagram never moves a
//! hand back; a malformed datagram is dropped whole and never breaks the TCP
//! stream.

use super::driver::{DecodeStats, Decoder, Script, Step};
use super::sample::{QUAT_NORM_TOLERANCE, Reading, Sample, SourceId, Timestamp, is_unit_quat};
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::time::Duration;

/// Length of the cookie each side sends.
pub const COOKIE_LEN: usize = 24;
/// The part of the magic string a peer must match.
pub const MAGIC_PREFIX: &[u8] = b"vrpn: ver. 07.";
/// Length of a message header.
pub const HEADER_LEN: usize = 24;
/// Largest message accepted (VRPN's TCP buffer size).
pub const MAX_MESSAGE: usize = 64000;
/// Type id of a sender description.
pub const SENDER_DESCRIPTION: i32 = -1;
/// Type id of a type description.
pub const TYPE_DESCRIPTION: i32 = -2;
/// Type id of a UDP description (`vrpn_CONNECTION_UDP_DESCRIPTION`).
pub const UDP_DESCRIPTION: i32 = -3;
/// Name of the tracker pose message type.
pub const POS_QUAT: &str = "vrpn_Tracker Pos_Quat";
/// Payload length of a Pos_Quat message.
pub const POS_QUAT_LEN: usize = 64;
/// Longest name VRPN allows (`vrpn_CNAME`).
const MAX_NAME: usize = 100;

/// Which VRPN device to read, and how.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VrpnSettings {
    /// The sender name on the server, e.g. `Tracker0`.
    pub device: String,
    /// Ask the server for its low-latency messages (tracker reports) over UDP, as
    /// VRPN's own clients do; `false`, or an address `…@tcp://host:port`, keeps
    /// everything on the TCP connection.
    pub udp: bool,
}

impl Default for VrpnSettings {
    fn default() -> Self {
        Self {
            device: "Tracker0".into(),
            udp: true,
        }
    }
}

/// Our cookie (log mode 0).
pub fn cookie() -> [u8; COOKIE_LEN] {
    let mut c = [0u8; COOKIE_LEN];
    c[..16].copy_from_slice(b"vrpn: ver. 07.38");
    c[16] = b' ';
    c[17] = b' ';
    c[18] = b'0';
    c
}

/// Rounds up to VRPN's 8-byte alignment.
pub fn padded(len: usize) -> usize {
    len.div_ceil(8) * 8
}

/// Encodes one message (for the fake server and tests).
pub fn encode_message(sec: u32, usec: u32, sender: i32, kind: i32, payload: &[u8]) -> Vec<u8> {
    let mut m = Vec::with_capacity(HEADER_LEN + padded(payload.len()));
    m.extend_from_slice(&((HEADER_LEN + payload.len()) as u32).to_be_bytes());
    m.extend_from_slice(&sec.to_be_bytes());
    m.extend_from_slice(&usec.to_be_bytes());
    m.extend_from_slice(&sender.to_be_bytes());
    m.extend_from_slice(&kind.to_be_bytes());
    m.extend_from_slice(&0u32.to_be_bytes());
    m.extend_from_slice(payload);
    m.resize(HEADER_LEN + padded(payload.len()), 0);
    m
}

/// Encodes a sender (`kind` = −1) or type (−2) description of `id` = `name`.
pub fn encode_description(kind: i32, id: i32, name: &str) -> Vec<u8> {
    let mut p = Vec::with_capacity(name.len() + 5);
    p.extend_from_slice(&((name.len() + 1) as u32).to_be_bytes());
    p.extend_from_slice(name.as_bytes());
    p.push(0);
    encode_message(0, 0, id, kind, &p)
}

/// The client's UDP description: "send your low-latency messages to `ip`:`port`".
pub fn udp_description(port: u16, ip: &str) -> Vec<u8> {
    let mut p = ip.as_bytes().to_vec();
    p.push(0);
    encode_message(0, 0, i32::from(port), UDP_DESCRIPTION, &p)
}

/// Encodes a Pos_Quat payload; `xyzw` in VRPN order.
pub fn encode_pos_quat(sensor: i32, pos: [f64; 3], xyzw: [f64; 4]) -> Vec<u8> {
    let mut p = Vec::with_capacity(POS_QUAT_LEN);
    p.extend_from_slice(&sensor.to_be_bytes());
    p.extend_from_slice(&sensor.to_be_bytes());
    for v in pos.iter().chain(xyzw.iter()) {
        p.extend_from_slice(&v.to_be_bytes());
    }
    p
}

fn be_u32(b: &[u8]) -> u32 {
    u32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

fn be_i32(b: &[u8]) -> i32 {
    i32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

fn be_f64(b: &[u8]) -> f64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[..8]);
    f64::from_be_bytes(a)
}

/// Parses a description payload into its name.
fn description_name(payload: &[u8]) -> Option<String> {
    if payload.len() < 5 {
        return None;
    }
    let n = be_u32(payload) as usize;
    if n == 0 || n > MAX_NAME || payload.len() < 4 + n || payload[4 + n - 1] != 0 {
        return None;
    }
    std::str::from_utf8(&payload[4..4 + n - 1])
        .ok()
        .map(str::to_owned)
}

/// Decodes a Pos_Quat payload into a validated pose.
pub fn decode_pos_quat(p: &[u8]) -> Option<Reading> {
    if p.len() != POS_QUAT_LEN {
        return None;
    }
    let sensor = u16::try_from(be_i32(p)).ok()?;
    let f = |i: usize| be_f64(&p[8 + 8 * i..]);
    let position = DVec3::new(f(0), f(1), f(2));
    let q = DQuat::from_xyzw(f(3), f(4), f(5), f(6));
    if !position.is_finite() || !is_unit_quat(q, QUAT_NORM_TOLERANCE) {
        return None;
    }
    Some(Reading::Pose {
        sensor,
        position,
        orientation: q.normalize(),
    })
}

/// The VRPN stream decoder: cookie, then framed messages.
pub struct VrpnDecoder {
    device: String,
    source: SourceId,
    buf: Vec<u8>,
    cookie_ok: bool,
    checked_name: bool,
    senders: HashMap<i32, String>,
    types: HashMap<i32, String>,
    /// Sequence number and time (s, µs) of the last UDP message kept.
    udp_last: Option<(u32, u32, u32)>,
    stats: DecodeStats,
    fatal: Option<String>,
}

impl VrpnDecoder {
    /// A decoder reading the poses of sender `settings.device`.
    pub fn new(source: SourceId, settings: VrpnSettings) -> Self {
        Self {
            device: settings.device,
            source,
            buf: Vec::with_capacity(4096),
            cookie_ok: false,
            checked_name: false,
            senders: HashMap::new(),
            types: HashMap::new(),
            udp_last: None,
            stats: DecodeStats::default(),
            fatal: None,
        }
    }

    /// True when a UDP message (`seq`, `sec`, `usec`) comes after the last one kept.
    fn udp_is_newer(&self, seq: u32, sec: u32, usec: u32) -> bool {
        match self.udp_last {
            None => true,
            Some((s, ts, tu)) => {
                // Sequence numbers wrap: newer means ahead by less than half the range.
                let ahead = seq.wrapping_sub(s) as i32;
                ahead > 0 || (ahead == 0 && (sec, usec) > (ts, tu))
            }
        }
    }

    /// Sender names announced so far (for `--list`).
    pub fn senders(&self) -> impl Iterator<Item = &str> {
        self.senders.values().map(String::as_str)
    }

    fn handle(
        &mut self,
        sender: i32,
        kind: i32,
        payload: &[u8],
        at: Timestamp,
        out: &mut Vec<Sample>,
    ) {
        self.stats.messages += 1;
        if kind >= 0 && !self.checked_name {
            // The server describes every sender before its first data message.
            self.checked_name = true;
            if !self.senders.values().any(|s| *s == self.device) {
                let mut served: Vec<&str> = self.senders.values().map(String::as_str).collect();
                served.sort_unstable();
                self.fatal = Some(format!(
                    "the VRPN server serves no device {:?}; it serves: {}",
                    self.device,
                    if served.is_empty() {
                        "nothing".to_owned()
                    } else {
                        served.join(", ")
                    }
                ));
                return;
            }
        }
        match kind {
            SENDER_DESCRIPTION | TYPE_DESCRIPTION => match description_name(payload) {
                Some(name) => {
                    let map = if kind == SENDER_DESCRIPTION {
                        &mut self.senders
                    } else {
                        &mut self.types
                    };
                    map.insert(sender, name);
                }
                None => self.stats.rejected_records += 1,
            },
            k if k < 0 => {} // UDP / log descriptions and other system messages
            k => {
                let is_pose = self.types.get(&k).is_some_and(|t| t == POS_QUAT);
                let ours = self.senders.get(&sender).is_some_and(|s| *s == self.device);
                if is_pose && ours {
                    match decode_pos_quat(payload) {
                        Some(reading) => {
                            self.stats.records += 1;
                            out.push(Sample {
                                source: self.source,
                                time: at,
                                reading,
                            });
                        }
                        None => self.stats.rejected_records += 1,
                    }
                }
            }
        }
    }
}

impl Decoder for VrpnDecoder {
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        if self.fatal.is_some() {
            self.stats.discarded_bytes += chunk.len() as u64;
            return;
        }
        self.buf.extend_from_slice(chunk);
        let mut pos = 0;
        if !self.cookie_ok {
            if self.buf.len() < COOKIE_LEN {
                return;
            }
            if !self.buf.starts_with(MAGIC_PREFIX) {
                self.fatal = Some("peer is not a VRPN 07.xx server".into());
                self.stats.discarded_bytes += self.buf.len() as u64;
                self.buf.clear();
                return;
            }
            self.cookie_ok = true;
            pos = COOKIE_LEN;
        }
        while self.buf.len() - pos >= HEADER_LEN {
            let h = &self.buf[pos..pos + HEADER_LEN];
            let len = be_u32(h) as usize;
            if !(HEADER_LEN..=MAX_MESSAGE).contains(&len) {
                // A TCP stream has no resync marker: the link must be reopened.
                self.fatal = Some(format!("corrupt VRPN message length {len}"));
                self.stats.discarded_bytes += (self.buf.len() - pos) as u64;
                self.buf.clear();
                return;
            }
            let total = HEADER_LEN + padded(len - HEADER_LEN);
            if self.buf.len() - pos < total {
                break;
            }
            let sender = be_i32(&h[12..]);
            let kind = be_i32(&h[16..]);
            let payload = self.buf[pos + HEADER_LEN..pos + len].to_vec();
            self.handle(sender, kind, &payload, at, out);
            pos += total;
            if self.fatal.is_some() {
                self.buf.clear();
                return;
            }
        }
        self.buf.drain(..pos);
    }

    fn stats(&self) -> DecodeStats {
        self.stats
    }

    fn reset(&mut self) {
        self.buf.clear();
        self.cookie_ok = false;
        self.checked_name = false;
        self.senders.clear();
        self.types.clear();
        self.udp_last = None;
        self.fatal = None;
    }

    fn feed_datagram(&mut self, datagram: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        if self.fatal.is_some() {
            return;
        }
        // Check the whole datagram's framing first: a malformed one is dropped whole.
        let mut messages = Vec::new();
        let mut pos = 0;
        while pos < datagram.len() {
            let rest = &datagram[pos..];
            let len = if rest.len() >= HEADER_LEN {
                be_u32(rest) as usize
            } else {
                0
            };
            let total = HEADER_LEN + padded(len.saturating_sub(HEADER_LEN));
            if !(HEADER_LEN..=MAX_MESSAGE).contains(&len) || rest.len() < total {
                self.stats.rejected_records += 1;
                self.stats.discarded_bytes += datagram.len() as u64;
                return;
            }
            messages.push((pos, len));
            pos += total;
        }
        for (pos, len) in messages {
            let h = &datagram[pos..pos + HEADER_LEN];
            let (sec, usec) = (be_u32(&h[4..]), be_u32(&h[8..]));
            let (sender, kind, seq) = (be_i32(&h[12..]), be_i32(&h[16..]), be_u32(&h[20..]));
            // Descriptions travel reliably over TCP; a data message whose sender or
            // type is not described yet cannot be read (and must not be mistaken for
            // "the server serves no such device").
            let described = self.senders.contains_key(&sender) && self.types.contains_key(&kind);
            if kind < 0 || !described || !self.udp_is_newer(seq, sec, usec) {
                self.stats.stale += 1;
                continue;
            }
            self.udp_last = Some((seq, sec, usec));
            self.handle(
                sender,
                kind,
                &datagram[pos + HEADER_LEN..pos + len],
                at,
                out,
            );
        }
    }

    fn fatal(&self) -> Option<String> {
        self.fatal.clone()
    }
}

/// Name of VRPN's liveness request type (`vrpn_BaseClass.C`).
pub const PING: &str = "vrpn_Base ping_message";
/// How often the bridge pings (VRPN's own clients ping once a second; the bridge
/// must notice a hung server within one).
pub const PING_INTERVAL: Duration = Duration::from_millis(200);

/// Our ping to `device`: the sender and type descriptions VRPN sends for every
/// local sender and type before their first use (`pack_sender_description`,
/// `pack_type_description`), then an empty `ping_message` from sender 0, type 0.
/// The server's `vrpn_BaseClass` of `device` answers with a `pong_message`.
pub fn ping(device: &str) -> Vec<u8> {
    let mut m = encode_description(SENDER_DESCRIPTION, 0, device);
    m.extend(encode_description(TYPE_DESCRIPTION, 0, PING));
    m.extend(encode_message(0, 0, 0, 0, &[]));
    m
}

/// The client's script for `device`: send our cookie (the server then sends its
/// cookie and descriptions) unless the transport does (with UDP, the transport
/// sends the cookie and its UDP description, [`super::vrpn_link`]), and ping
/// every [`PING_INTERVAL`] — every message back proves the server alive, so a hung
/// one is noticed by silence.
pub fn script(device: &str, udp: bool) -> Script {
    Script {
        open: if udp {
            Vec::new()
        } else {
            vec![Step::Send(cookie().to_vec())]
        },
        poll: Some(ping(device)),
        poll_interval: PING_INTERVAL,
        close: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(s: &str) -> Vec<u8> {
        let s: String = s.chars().filter(|c| c.is_ascii_hexdigit()).collect();
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    #[test]
    fn cookie_bytes_are_as_published() {
        assert_eq!(
            cookie().to_vec(),
            hex("76 72 70 6e 3a 20 76 65 72 2e 20 30 37 2e 33 38 20 20 30 00 00 00 00 00")
        );
    }

    /// The Pos_Quat test vector of device-formats.md §1.4 (type 5, sender 0, t = 1.5 s).
    #[test]
    fn pos_quat_test_vector() {
        let v = hex("00000058 00000001 0007a120 00000000 00000005 00000000 \
             00000000 00000000 3fb999999999999a 3fc999999999999a 3fd3333333333333 \
             0000000000000000 0000000000000000 0000000000000000 3ff0000000000000");
        assert_eq!(v.len(), 88);
        let built = encode_message(
            1,
            500_000,
            0,
            5,
            &encode_pos_quat(0, [0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 1.0]),
        );
        // our encoder writes the sensor into the filler as VRPN does; the vector has 0 there too
        assert_eq!(built, v);
        let mut d = VrpnDecoder::new(SourceId(2), VrpnSettings::default());
        let mut stream = cookie().to_vec();
        stream.extend(encode_description(SENDER_DESCRIPTION, 0, "Tracker0"));
        stream.extend(encode_description(TYPE_DESCRIPTION, 5, POS_QUAT));
        stream.extend(&v);
        let mut out = Vec::new();
        d.feed(&stream, Timestamp(9), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(
            out[0].reading,
            Reading::Pose {
                sensor: 0,
                position: DVec3::new(0.1, 0.2, 0.3),
                orientation: DQuat::IDENTITY
            }
        );
    }

    #[test]
    fn sender_description_is_40_bytes() {
        let m = encode_description(SENDER_DESCRIPTION, 0, "Tracker0");
        assert_eq!(m.len(), 40);
        assert_eq!(be_u32(&m), 24 + 13);
        assert_eq!(description_name(&m[24..37]).as_deref(), Some("Tracker0"));
    }

    #[test]
    fn other_senders_types_and_bad_payloads_are_ignored() {
        let mut s = cookie().to_vec();
        s.extend(encode_description(SENDER_DESCRIPTION, 0, "Tracker0"));
        s.extend(encode_description(SENDER_DESCRIPTION, 1, "Other"));
        s.extend(encode_description(TYPE_DESCRIPTION, 5, POS_QUAT));
        s.extend(encode_description(
            TYPE_DESCRIPTION,
            6,
            "vrpn_Tracker Velocity",
        ));
        let pq = encode_pos_quat(1, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]);
        s.extend(encode_message(0, 0, 1, 5, &pq)); // other sender
        s.extend(encode_message(0, 0, 0, 6, &[0u8; 72])); // velocity
        s.extend(encode_message(0, 0, 0, 5, &pq[..60])); // short payload
        s.extend(encode_message(
            0,
            0,
            0,
            5,
            &encode_pos_quat(1, [f64::NAN, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
        ));
        s.extend(encode_message(
            0,
            0,
            0,
            5,
            &encode_pos_quat(1, [0.0; 3], [0.0, 0.0, 0.0, 3.0]),
        ));
        s.extend(encode_message(0, 0, 0, -3, b"127.0.0.1\0")); // UDP description
        s.extend(encode_message(0, 0, 0, 5, &pq)); // the one good pose
        for chunk in [1usize, 5, 4096] {
            let mut d = VrpnDecoder::new(SourceId(0), VrpnSettings::default());
            let mut out = Vec::new();
            for c in s.chunks(chunk) {
                d.feed(c, Timestamp(0), &mut out);
            }
            assert_eq!(out.len(), 1, "chunk {chunk}");
            assert_eq!(d.stats().rejected_records, 3);
            assert!(d.fatal().is_none());
        }
    }

    #[test]
    fn wrong_cookie_and_corrupt_length_are_fatal() {
        let mut d = VrpnDecoder::new(SourceId(0), VrpnSettings::default());
        let mut out = Vec::new();
        d.feed(b"HTTP/1.1 400 Bad Request\r\n", Timestamp(0), &mut out);
        assert!(d.fatal().is_some());
        d.reset();
        let mut s = cookie().to_vec();
        s.extend_from_slice(&[0xff; 24]);
        d.feed(&s, Timestamp(0), &mut out);
        assert!(d.fatal().unwrap().contains("length"));
        assert!(out.is_empty());
    }
}
