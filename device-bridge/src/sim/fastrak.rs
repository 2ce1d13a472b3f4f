//! A simulated Polhemus Fastrak answering as the real one does: `c`/`C` continuous
//! off/on, `P` one record per station, `f`/`F` binary/ASCII, `U`/`u` inches/cm,
//! `S` status (a 55-byte line starting `'2'` and ending in LF, which VRPN checks),
//! `O<st>,…\r` and other line commands accepted.

use super::pty::SerialDevice;
use crate::device::fastrak::{FastrakUnits, encode_record};
use glam::{DQuat, DVec3};
use std::time::Duration;

/// The simulated Fastrak's state.
pub struct FastrakSim {
    /// Per station: position (metres) and orientation.
    pub poses: Vec<(DVec3, DQuat)>,
    /// Continuous output on.
    pub continuous: bool,
    /// Binary output on.
    pub binary: bool,
    /// Position units.
    pub units: FastrakUnits,
    /// Status byte to put in records (`' '` or `'A'..'F'`).
    pub status: u8,
    line: Option<Vec<u8>>,
    period: Duration,
}

impl FastrakSim {
    /// A Fastrak with `stations` receivers streaming every `period` when continuous.
    pub fn new(stations: usize, period: Duration) -> Self {
        Self {
            poses: vec![(DVec3::ZERO, DQuat::IDENTITY); stations],
            continuous: false,
            binary: false,
            units: FastrakUnits::Inches,
            status: b' ',
            line: None,
            period,
        }
    }

    fn records(&self, out: &mut Vec<u8>) {
        if !self.binary {
            return;
        }
        let m = self.units.metres();
        for (i, (p, q)) in self.poses.iter().enumerate() {
            let pos = [(p.x / m) as f32, (p.y / m) as f32, (p.z / m) as f32];
            out.extend_from_slice(&encode_record(
                i as u8 + 1,
                self.status,
                pos,
                [q.w as f32, q.x as f32, q.y as f32, q.z as f32],
            ));
        }
    }
}

impl SerialDevice for FastrakSim {
    fn on_input(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        for &b in bytes {
            if let Some(line) = &mut self.line {
                if b == b'\r' {
                    self.line = None;
                } else {
                    line.push(b);
                }
                continue;
            }
            match b {
                b'c' => self.continuous = false,
                b'C' => self.continuous = true,
                b'P' => self.records(out),
                b'f' => self.binary = true,
                b'F' => self.binary = false,
                b'U' => self.units = FastrakUnits::Inches,
                b'u' => self.units = FastrakUnits::Centimetres,
                b'S' => {
                    let mut s = b"21S  0x0000 3.0 Polhemus Fastrak simulated".to_vec();
                    s.resize(53, b' ');
                    s.extend_from_slice(b"\r\n");
                    out.extend_from_slice(&s);
                }
                b'O' | b'H' | b'l' | b'e' | b'M' => self.line = Some(vec![b]),
                _ => {}
            }
        }
    }

    fn on_tick(&mut self, out: &mut Vec<u8>) {
        if self.continuous {
            self.records(out);
        }
    }

    fn tick(&self) -> Duration {
        self.period
    }
}
