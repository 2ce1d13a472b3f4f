//! A simulated CyberGlove answering as the real one does: `G` → one record,
//! `S` → stream records, Ctrl-C (0x03) stops streaming, `?S` → total sensors
//! (`?S`, count, NUL), `?N` → enabled sensors.

use super::pty::SerialDevice;
use crate::device::cyberglove::{CyberGloveSettings, encode_record};
use std::time::Duration;

/// The simulated glove's state.
pub struct CyberGloveSim {
    /// Current raw sensor values (18 or 22 of them).
    pub values: Vec<u8>,
    /// Streaming.
    pub streaming: bool,
    /// Report the glove unplugged from its box (`'e','g'` in records).
    pub unplugged: bool,
    query: bool,
    period: Duration,
}

impl CyberGloveSim {
    /// A glove with `sensors` sensors, all at `value`, streaming every `period` on `S`.
    pub fn new(sensors: usize, value: u8, period: Duration) -> Self {
        Self {
            values: vec![value.max(1); sensors],
            streaming: false,
            unplugged: false,
            query: false,
            period,
        }
    }

    fn record(&self, out: &mut Vec<u8>) {
        let s = CyberGloveSettings {
            sensors: self.values.len() as u8,
            ..Default::default()
        };
        out.extend(encode_record(
            &s,
            &self.values,
            self.unplugged.then_some(b'g'),
        ));
    }
}

impl SerialDevice for CyberGloveSim {
    fn on_input(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        for &b in bytes {
            if self.query {
                self.query = false;
                match b {
                    b'S' | b'N' => out.extend_from_slice(&[b'?', b, self.values.len() as u8, 0]),
                    _ => out.extend_from_slice(&[b'?', b, 0]),
                }
                continue;
            }
            match b {
                b'G' => self.record(out),
                b'S' => self.streaming = true,
                0x03 => self.streaming = false,
                b'?' => self.query = true,
                _ => {}
            }
        }
    }

    fn on_tick(&mut self, out: &mut Vec<u8>) {
        if self.streaming {
            self.record(out);
        }
    }

    fn tick(&self) -> Duration {
        self.period
    }
}
