//! Byte streams written from the vendors' manuals and the reference sources, not
//! from the bridge's own encoders (shared/reference/device-formats.md cites them):
//! Flock of Birds records (Ascension manual: LS byte first, 7 data bits a byte, the
//! phasing bit 0x80 on a record's first byte only, 14-bit words), Fastrak binary
//! records (`O1,2,11,0` + `f`: '0', station, status, IEEE-754 little-endian
//! floats, a space), CyberGlove `G` replies, spacenavd's 32-byte events, plus line
//! faults: single bit flips, truncations, lost phasing bits, and a UART receiving
//! at the wrong baud rate.

#![allow(dead_code)]

/// Inches per metre.
pub const INCH: f64 = 0.0254;

/// A deterministic pseudo-random sequence (xorshift64*), so failures reproduce.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A Flock word on the wire: the LS byte carries word bits 2..8 in its bits 0..6,
/// the MS byte bits 9..15 (the manual's "shift left twice" reconstruction).
fn flock_word(value: f64, first: bool) -> [u8; 2] {
    let w = value.round().clamp(-32768.0, 32767.0) as i16 as u16;
    let lsb = ((w >> 2) & 0x7f) as u8 | if first { 0x80 } else { 0 };
    let msb = ((w >> 9) & 0x7f) as u8;
    [lsb, msb]
}

/// A POSITION/QUATERNION record (`]`): x, y, z at 36" full scale, then the
/// quaternion w, x, y, z scaled by 32768.
pub fn flock_pos_quat(p_m: [f64; 3], wxyz: [f64; 4]) -> Vec<u8> {
    let mut out = Vec::with_capacity(14);
    let per_inch = 32768.0 / 36.0;
    for (i, v) in p_m.iter().enumerate() {
        out.extend(flock_word(v / INCH * per_inch, i == 0));
    }
    for q in wxyz {
        out.extend(flock_word(q * 32768.0, false));
    }
    out
}

/// A POSITION/ANGLES record (`Y`): x, y, z, then azimuth (about z), elevation
/// (about y), roll (about x) in degrees, 180° = 32768.
pub fn flock_pos_angles(p_m: [f64; 3], zyx_deg: [f64; 3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(12);
    let per_inch = 32768.0 / 36.0;
    for (i, v) in p_m.iter().enumerate() {
        out.extend(flock_word(v / INCH * per_inch, i == 0));
    }
    for a in zyx_deg {
        out.extend(flock_word(a * 32768.0 / 180.0, false));
    }
    out
}

/// A Fastrak binary record of station 1, position in inches.
pub fn fastrak(p_m: [f64; 3], wxyz: [f64; 4]) -> Vec<u8> {
    let mut out = vec![b'0', b'1', b' '];
    for v in p_m {
        out.extend(((v / INCH) as f32).to_le_bytes());
    }
    for q in wxyz {
        out.extend((q as f32).to_le_bytes());
    }
    out.push(b' ');
    out
}

/// A 22-sensor CyberGlove reply to `G`: raw sensor bytes (never 0), NUL-terminated.
pub fn glove(value: u8) -> Vec<u8> {
    let mut out = vec![b'G'];
    out.extend(std::iter::repeat_n(value.max(1), 22));
    out.push(0);
    out
}

/// The raw glove value of a closed hand and of an open one for the bridge's
/// default calibration (open 40, closed 200).
pub const GLOVE_CLOSED: u8 = 220;
/// See [`GLOVE_CLOSED`].
pub const GLOVE_OPEN: u8 = 30;

/// A spacenavd event: eight native-endian i32.
pub fn spnav(words: [i32; 8]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_ne_bytes()).collect()
}

/// Flips bit `bit` (0..8) of byte `byte` of `record`.
pub fn flip(record: &[u8], byte: usize, bit: u32) -> Vec<u8> {
    let mut r = record.to_vec();
    r[byte] ^= 1 << bit;
    r
}

/// What a UART set to `rx_baud` reads from bytes sent 8N1 at `tx_baud` with the
/// line idle (mark) in between: it waits for a falling edge (start bit), samples
/// each data bit in the middle of its own (wrong) bit time, and drops a frame whose
/// stop bit reads as space (a framing error).
pub fn wrong_baud(bytes: &[u8], tx_baud: f64, rx_baud: f64) -> Vec<u8> {
    let tx_bit = 1.0 / tx_baud;
    let mut levels = Vec::with_capacity(bytes.len() * 10);
    for &b in bytes {
        levels.push(false);
        for i in 0..8 {
            levels.push(b >> i & 1 == 1);
        }
        levels.push(true);
    }
    let end = levels.len() as f64 * tx_bit;
    let line = |t: f64| -> bool {
        if t >= end || t < 0.0 {
            return true;
        }
        levels[(t / tx_bit) as usize]
    };
    let rx_bit = 1.0 / rx_baud;
    let step = tx_bit.min(rx_bit) / 8.0;
    let mut out = Vec::new();
    let mut t = 0.0;
    let mut prev = true;
    while t < end {
        let now = line(t);
        if prev && !now {
            // start bit: sample its middle, then the data bits and the stop bit
            if !line(t + rx_bit / 2.0) {
                let mut b = 0u8;
                for i in 0..8 {
                    if line(t + rx_bit * (1.5 + i as f64)) {
                        b |= 1 << i;
                    }
                }
                if line(t + rx_bit * 9.5) {
                    out.push(b);
                }
                t += rx_bit * 9.5;
                prev = line(t);
                continue;
            }
        }
        prev = now;
        t += step;
    }
    out
}

/// VRPN's 24-byte cookie (`vrpn_Connection.C` `write_vrpn_cookie`): the magic
/// `vrpn: ver. 07.38`, two spaces, the log-mode digit, NUL padding.
pub fn vrpn_cookie() -> Vec<u8> {
    let mut c = b"vrpn: ver. 07.38  0".to_vec();
    c.resize(24, 0);
    c
}

/// A VRPN message: a 24-byte big-endian header (length without padding, seconds,
/// microseconds, sender, type, sequence), the payload padded to 8 bytes.
pub fn vrpn_message(sender: i32, kind: i32, payload: &[u8]) -> Vec<u8> {
    let mut m = Vec::new();
    m.extend(((24 + payload.len()) as u32).to_be_bytes());
    m.extend(1u32.to_be_bytes());
    m.extend(500_000u32.to_be_bytes());
    m.extend(sender.to_be_bytes());
    m.extend(kind.to_be_bytes());
    m.extend(0u32.to_be_bytes());
    m.extend(payload);
    while m.len() % 8 != 0 {
        m.push(0);
    }
    m
}

/// A sender (−1) or type (−2) description: the id in the sender field, the payload
/// the name's length with its NUL as a BE u32, the name, the NUL.
pub fn vrpn_description(kind: i32, id: i32, name: &str) -> Vec<u8> {
    let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    p.extend(name.as_bytes());
    p.push(0);
    vrpn_message(id, kind, &p)
}

/// A `vrpn_Tracker Pos_Quat` payload: sensor, sensor again, position (m), quaternion
/// x, y, z, w, all big-endian.
pub fn vrpn_pos_quat(sensor: i32, pos: [f64; 3], xyzw: [f64; 4]) -> Vec<u8> {
    let mut p = sensor.to_be_bytes().to_vec();
    p.extend(sensor.to_be_bytes());
    for v in pos.iter().chain(&xyzw) {
        p.extend(v.to_be_bytes());
    }
    p
}

/// A VRPN message as the server marshals it for its UDP channel
/// (`vrpn_Endpoint::marshall_message`): the same header with its time and the
/// channel's sequence number in the sixth word, the payload padded to 8 bytes.
pub fn vrpn_udp_message(
    seq: u32,
    sec: u32,
    usec: u32,
    sender: i32,
    kind: i32,
    payload: &[u8],
) -> Vec<u8> {
    let mut m = Vec::new();
    m.extend(((24 + payload.len()) as u32).to_be_bytes());
    m.extend(sec.to_be_bytes());
    m.extend(usec.to_be_bytes());
    m.extend(sender.to_be_bytes());
    m.extend(kind.to_be_bytes());
    m.extend(seq.to_be_bytes());
    m.extend(payload);
    while m.len() % 8 != 0 {
        m.push(0);
    }
    m
}
