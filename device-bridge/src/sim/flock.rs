//! A simulated Ascension Flock of Birds that answers the commands of
//! [`crate::device::flock`] as the real flock does: `B` point (one record per bird,
//! stops streaming), `@` stream, `Y`/`]` record format, `0xF0 + addr` routing,
//! `P 35 1` group mode, `P 50 n` auto-configure, `L h s` hemisphere, `O 36` flock
//! status (14 bytes), `O 16` expanded error code (2 bytes), `G` sleep, `F` run.

use super::pty::SerialDevice;
use crate::device::flock::{FlockFormat, FlockSettings, encode_record, pose_words};
use glam::{DQuat, DVec3};
use std::time::Duration;

/// The simulated flock's state.
pub struct FlockSim {
    /// Per bird: position (metres) and orientation.
    pub poses: Vec<(DVec3, DQuat)>,
    /// Per bird: selected record format.
    pub formats: Vec<FlockFormat>,
    /// Group mode on.
    pub group_mode: bool,
    /// Streaming.
    pub streaming: bool,
    /// Full scale in inches.
    pub full_scale_inches: f64,
    /// An ERT is unit 1.
    pub ert: bool,
    /// Commands received, for assertions.
    pub log: Vec<u8>,
    pending: Vec<u8>,
    route: Option<u8>,
    period: Duration,
}

impl FlockSim {
    /// A flock of `birds` receivers (at FBB addresses 1.., after the ERT if any),
    /// streaming every `period` when asked to.
    pub fn new(birds: usize, ert: bool, period: Duration) -> Self {
        Self {
            poses: vec![(DVec3::ZERO, DQuat::IDENTITY); birds],
            formats: vec![FlockFormat::PosAngles; birds],
            group_mode: false,
            streaming: false,
            full_scale_inches: if ert { 144.0 } else { 36.0 },
            ert,
            log: Vec::new(),
            pending: Vec::new(),
            route: None,
            period,
        }
    }

    /// Sets bird `i`'s pose.
    pub fn set_pose(&mut self, i: usize, position: DVec3, orientation: DQuat) {
        if let Some(p) = self.poses.get_mut(i) {
            *p = (position, orientation);
        }
    }

    fn records(&self, out: &mut Vec<u8>) {
        let birds = if self.group_mode { self.poses.len() } else { 1 };
        for i in 0..birds {
            let s = FlockSettings {
                format: self.formats[i],
                full_scale_inches: self.full_scale_inches,
                ..Default::default()
            };
            let (p, q) = self.poses[i];
            let addr = (self.group_mode).then_some(i as u8 + 1 + u8::from(self.ert));
            out.extend(encode_record(&pose_words(&s, p, q), None, addr));
        }
    }

    /// Bytes a command needs after its command byte, if it is complete in `b`.
    fn command_len(b: &[u8]) -> Option<usize> {
        let need = match b[0] {
            b'P' => {
                let code = *b.get(1)?;
                match code {
                    35 | 50 | 3 => 3,
                    _ => 2,
                }
            }
            b'O' => 2,
            b'L' => 3,
            b'M' => 2,
            _ => 1,
        };
        (b.len() >= need).then_some(need)
    }

    fn execute(&mut self, cmd: &[u8], out: &mut Vec<u8>) {
        let target = self
            .route
            .take()
            .map(|a| a.saturating_sub(1 + u8::from(self.ert)) as usize);
        match cmd[0] {
            b'B' => {
                self.streaming = false;
                self.records(out);
            }
            b'@' => self.streaming = true,
            b'G' => self.streaming = false,
            b'Y' | b']' => {
                let f = if cmd[0] == b'Y' {
                    FlockFormat::PosAngles
                } else {
                    FlockFormat::PosQuat
                };
                match target {
                    Some(i) => {
                        if let Some(slot) = self.formats.get_mut(i) {
                            *slot = f;
                        }
                    }
                    None => self.formats.iter_mut().for_each(|s| *s = f),
                }
            }
            b'P' if cmd[1] == 35 => self.group_mode = cmd[2] != 0,
            b'O' if cmd[1] == 36 => {
                let mut status = [0u8; 14];
                let units = self.poses.len() + usize::from(self.ert);
                for (i, s) in status.iter_mut().take(units).enumerate() {
                    // accessible, running, receiver (unit 1 is the transmitter)
                    *s = 0x80 | 0x40 | if i == 0 && self.ert { 0 } else { 0x20 };
                }
                out.extend_from_slice(&status);
            }
            b'O' if cmd[1] == 16 => out.extend_from_slice(&[0, 0]),
            c if (0xF1..=0xFE).contains(&c) => self.route = Some(c - 0xF0),
            _ => {}
        }
    }
}

impl SerialDevice for FlockSim {
    fn on_input(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        self.log.extend_from_slice(bytes);
        self.pending.extend_from_slice(bytes);
        while !self.pending.is_empty() {
            let Some(n) = Self::command_len(&self.pending) else {
                break;
            };
            let cmd: Vec<u8> = self.pending.drain(..n).collect();
            self.execute(&cmd, out);
        }
    }

    fn on_tick(&mut self, out: &mut Vec<u8>) {
        if self.streaming {
            self.records(out);
        }
    }

    fn tick(&self) -> Duration {
        self.period
    }
}
