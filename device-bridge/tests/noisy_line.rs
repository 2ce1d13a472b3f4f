//! A noisy line never moves a held icon further than the plausibility gate
//! allows: byte streams written from the manuals (`independent`) with single bit
//! flips, truncated records, lost phasing bits and a UART at the wrong baud rate
//! go through the bridge's decoders and interaction; every drag that comes out is
//! checked against the true hand path, and consecutive drags never differ by
//! more than the gate's step `noise + v_max·dt`.

mod independent;

use glam::DVec3;
use independent::*;
use vsculpt_bridge::config::{
    Calibration, Config, DeviceConfig, DeviceKind, HandConfig, build_decoder,
};
use vsculpt_bridge::device::flock::FlockFormat;
use vsculpt_bridge::device::{Decoder, SourceId, Timestamp};
use vsculpt_bridge::gate::GateSettings;
use vsculpt_bridge::hand::GloveCalibration;
use vsculpt_bridge::interaction::{Command, IconKind, IconRole, IconState, IconView, Interaction};

/// Scene millimetres per tracker metre.
const SCALE: f64 = 1000.0;
/// Where the hand grabs, tracker metres.
const P0: [f64; 3] = [0.30, 0.10, -0.05];
/// Flock quantisation: one step of a 14-bit word at 36" full scale, in scene mm.
const QUANTUM: f64 = 4.0 * 36.0 / 32768.0 * INCH * SCALE;

struct Rig {
    decoders: Vec<Box<dyn Decoder>>,
    interaction: Interaction,
    gate: GateSettings,
    /// (record time, drag target) of every drag, in order.
    drags: Vec<(Timestamp, DVec3)>,
    released: bool,
}

fn config(kind: DeviceKind, format: FlockFormat) -> Config {
    let mut tracker = DeviceConfig::new("tracker", kind);
    tracker.port = Some("/dev/null".into());
    tracker.flock.format = format;
    let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    glove.port = Some("/dev/null".into());
    let c = Config {
        calibration: Calibration {
            scale: SCALE,
            ..Default::default()
        },
        devices: vec![tracker, glove],
        hands: vec![HandConfig {
            name: "right".into(),
            tracker: "tracker".into(),
            sensor: 0,
            glove: Some("glove".into()),
            reach: 20.0,
            calibration: GloveCalibration::default(),
        }],
        ..Default::default()
    };
    c.validate().unwrap();
    c
}

impl Rig {
    fn new(kind: DeviceKind, format: FlockFormat) -> Self {
        let c = config(kind, format);
        let decoders = c
            .devices
            .iter()
            .enumerate()
            .map(|(i, d)| build_decoder(SourceId(i as u16), d))
            .collect();
        let mut interaction = Interaction::new(&c);
        let p0 = DVec3::from_array(P0) * SCALE;
        interaction.set_icons([IconView {
            part: 1,
            id: 1,
            position: p0,
            target: p0,
            role: IconRole::Constraint,
            kind: IconKind::Position,
            state: IconState::Passive,
        }]);
        Self {
            decoders,
            interaction,
            gate: c.devices[0].gate,
            drags: Vec::new(),
            released: false,
        }
    }

    /// Feeds bytes of device `source` that arrived at `at` (µs).
    fn feed(&mut self, source: u16, bytes: &[u8], at: u64) {
        let mut samples = Vec::new();
        self.decoders[usize::from(source)].feed(bytes, Timestamp(at), &mut samples);
        let mut out = Vec::new();
        for s in &samples {
            self.interaction.handle(s, &mut out);
        }
        for c in out {
            match c {
                Command::Drag { target, .. } => self.drags.push((Timestamp(at), target)),
                Command::Release { .. } => self.released = true,
                _ => {}
            }
        }
    }

    fn grab(&mut self, at: u64) {
        self.feed(1, &glove(GLOVE_CLOSED), at);
        assert_eq!(self.interaction.bindings().len(), 1, "the hand grabbed");
    }

    fn release(&mut self, at: u64) {
        self.feed(1, &glove(GLOVE_OPEN), at);
        assert!(self.released);
    }

    /// Every pair of consecutive drags is within the gate's step for the time
    /// between their records (plus the wire's quantisation).
    fn assert_no_jump(&self) {
        for w in self.drags.windows(2) {
            let dt = w[1].0.since(w[0].0).as_secs_f64();
            let step = w[0].1.distance(w[1].1);
            let allowed = self.gate.max_step(dt) * SCALE + 2.0 * QUANTUM;
            assert!(
                step <= allowed,
                "drag jumped {step:.3} mm in {:.1} ms (gate allows {allowed:.3})",
                dt * 1e3
            );
        }
    }
}

fn record(kind: DeviceKind, format: FlockFormat, p: DVec3) -> Vec<u8> {
    let q = [1.0, 0.0, 0.0, 0.0];
    match (kind, format) {
        (DeviceKind::Fastrak, _) => fastrak(p.to_array(), q),
        (_, FlockFormat::PosQuat) => flock_pos_quat(p.to_array(), [0.99997, 0.0, 0.0, 0.0]),
        (_, FlockFormat::PosAngles) => flock_pos_angles(p.to_array(), [10.0, -5.0, 2.0]),
    }
}

/// Holds still (or moves back and forth along x at up to `speed` m/s) for `n` records `period` µs
/// apart, corrupting the records `corrupt` picks; returns the rig after release.
fn session(
    kind: DeviceKind,
    format: FlockFormat,
    period: u64,
    n: usize,
    speed: f64,
    mut corrupt: impl FnMut(usize, Vec<u8>) -> Vec<u8>,
) -> Rig {
    let mut rig = Rig::new(kind, format);
    let p0 = DVec3::from_array(P0);
    let mut t = 1_000_000u64;
    for _ in 0..5 {
        rig.feed(0, &record(kind, format, p0), t);
        t += period;
    }
    rig.grab(t);
    let start = t;
    let mut worst = 0.0f64;
    for k in 0..n {
        t += period;
        // back and forth along x, 0.1 m either side, `speed` at the centre
        let w = speed / 0.1;
        let p = p0 + DVec3::X * 0.1 * (w * (t - start) as f64 * 1e-6).sin();
        let bytes = corrupt(k, record(kind, format, p));
        let before = rig.drags.len();
        rig.feed(0, &bytes, t);
        // a drag after this record is where the hand really is, within the gate
        let allowed = rig.gate.max_residual(period as f64 * 1e-6) * SCALE + QUANTUM;
        for (_, target) in &rig.drags[before..] {
            let d = target.distance(p * SCALE);
            worst = worst.max(d / allowed);
            assert!(d <= allowed, "record {k}: drag {d:.3} mm off the hand");
        }
    }
    rig.release(t + period);
    rig.assert_no_jump();
    eprintln!("{kind:?} {format:?} {period} µs {speed} m/s: worst drag at {worst:.2} of the gate");
    rig
}

#[test]
fn single_bit_flips_never_become_drags_beyond_the_noise() {
    for (kind, format) in [
        (DeviceKind::Flock, FlockFormat::PosQuat),
        (DeviceKind::Flock, FlockFormat::PosAngles),
        (DeviceKind::Fastrak, FlockFormat::PosQuat),
    ] {
        for (period, speed) in [(1250, 0.0), (10_000, 0.0), (1250, 0.4), (10_000, 0.4)] {
            let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ period);
            let rig = session(kind, format, period, 1500, speed, |k, r| {
                if k % 10 == 3 {
                    let byte = rng.below(r.len());
                    flip(&r, byte, rng.below(8) as u32)
                } else {
                    r
                }
            });
            assert!(
                rig.interaction.rejected_poses() > 0,
                "{kind:?} {format:?}: some flipped records must have been refused"
            );
            assert!(rig.drags.len() > 10);
        }
    }
}

#[test]
fn truncated_records_and_lost_phasing_bits_never_move_the_icon() {
    for period in [1250, 10_000] {
        let mut rng = Rng(42 + period);
        let rig = session(
            DeviceKind::Flock,
            FlockFormat::PosQuat,
            period,
            1500,
            0.3,
            |k, mut r| match k % 17 {
                5 => {
                    let keep = 1 + rng.below(r.len() - 1);
                    r.truncate(keep);
                    r
                }
                11 => {
                    r[0] &= 0x7f;
                    r
                }
                13 => {
                    // a phasing bit where none belongs
                    let i = 1 + rng.below(r.len() - 1);
                    r[i] |= 0x80;
                    r
                }
                _ => r,
            },
        );
        assert!(rig.drags.len() > 10);
    }
}

#[test]
fn a_wrong_baud_burst_mid_drag_never_jumps_the_icon() {
    // 300 ms of the line read at the wrong rate (a device reset to its DIP-switch
    // baud), while the hand moves on; then clean again
    for rx in [9600.0, 38400.0, 57600.0] {
        let period = 2000;
        let mut rig = Rig::new(DeviceKind::Flock, FlockFormat::PosQuat);
        let p0 = DVec3::from_array(P0);
        let mut t = 1_000_000u64;
        for _ in 0..5 {
            rig.feed(0, &flock_pos_quat(P0, [0.99997, 0.0, 0.0, 0.0]), t);
            t += period;
        }
        rig.grab(t);
        let mut p = p0;
        for k in 0..600 {
            t += period;
            p += DVec3::X * 0.2 * period as f64 * 1e-6; // 0.2 m/s
            let r = flock_pos_quat(p.to_array(), [0.99997, 0.0, 0.0, 0.0]);
            let bytes = if (100..250).contains(&k) {
                wrong_baud(&r, 115_200.0, rx)
            } else {
                r
            };
            rig.feed(0, &bytes, t);
        }
        rig.release(t + period);
        rig.assert_no_jump();
        // after the burst the drag follows the hand again, re-anchored (the part of
        // the motion made while the line was garbage is not replayed as a jump)
        let last = rig.drags.last().unwrap().1;
        let moved_clean = 0.2 * (600 - 150) as f64 * period as f64 * 1e-6 * SCALE;
        let offset = last - p0 * SCALE;
        assert!(
            offset.y.abs() < 3.5 && offset.z.abs() < 3.5,
            "{rx}: {offset:?}"
        );
        assert!(
            offset.x <= 0.2 * 600.0 * period as f64 * 1e-6 * SCALE + 3.5
                && offset.x >= moved_clean - 40.0,
            "{rx}: moved {offset:?}, clean motion {moved_clean}"
        );
    }
}

#[test]
fn a_record_that_fails_its_checks_is_counted() {
    // a unit-norm check and the framing: both count as rejected, never as samples
    let mut d = build_decoder(
        SourceId(0),
        &config(DeviceKind::Fastrak, FlockFormat::PosQuat).devices[0],
    );
    let mut out = Vec::new();
    let good = fastrak(P0, [1.0, 0.0, 0.0, 0.0]);
    d.feed(&good, Timestamp(0), &mut out);
    let mut bad_trailer = good.clone();
    bad_trailer[31] = b'x';
    d.feed(&bad_trailer, Timestamp(1), &mut out);
    d.feed(&fastrak(P0, [0.5, 0.0, 0.0, 0.0]), Timestamp(2), &mut out);
    assert_eq!(out.len(), 1);
    assert_eq!(d.stats().rejected_records, 2);
}

/// A line that plays back fixed bytes, 64 at a time.
struct Playback(Vec<u8>, usize, bool);

impl vsculpt_bridge::device::Transport for Playback {
    fn open(&mut self) -> Result<(), vsculpt_bridge::device::DeviceError> {
        self.2 = true;
        Ok(())
    }
    fn read(
        &mut self,
        buf: &mut [u8],
        _timeout: std::time::Duration,
    ) -> Result<usize, vsculpt_bridge::device::DeviceError> {
        let n = (self.0.len() - self.1).min(64).min(buf.len());
        buf[..n].copy_from_slice(&self.0[self.1..self.1 + n]);
        self.1 += n;
        Ok(n)
    }
    fn write(&mut self, _bytes: &[u8]) -> Result<(), vsculpt_bridge::device::DeviceError> {
        Ok(())
    }
    fn close(&mut self) {
        self.2 = false;
    }
    fn is_open(&self) -> bool {
        self.2
    }
    fn describe(&self) -> String {
        "playback".into()
    }
}

#[test]
fn a_wrong_baud_rate_is_named_with_the_likely_rates() {
    use vsculpt_bridge::device::{Device, Driver, Script};
    // the Flock's DIP switches say 115200; the configuration says 38400
    let mut c = config(DeviceKind::Flock, FlockFormat::PosQuat);
    c.devices[0].baud = Some(38_400);
    let mut sent = Vec::new();
    for k in 0..3000 {
        let p = DVec3::from_array(P0) + DVec3::X * 1e-4 * k as f64;
        sent.extend(flock_pos_quat(p.to_array(), [0.99997, 0.0, 0.0, 0.0]));
    }
    let line = wrong_baud(&sent, 115_200.0, 38_400.0);
    let mut d = Driver::new(
        "tracker",
        SourceId(0),
        Box::new(Playback(line, 0, false)),
        build_decoder(SourceId(0), &c.devices[0]),
        Script::default(),
    );
    d.set_garbage_hint(c.devices[0].line_hint().unwrap());
    d.open().unwrap();
    let mut out = Vec::new();
    let mut err = None;
    for _ in 0..1000 {
        if let Err(e) = d.read(std::time::Duration::from_millis(1), &mut out) {
            err = Some(e.to_string());
            break;
        }
    }
    let err = err.expect("the garbage is reported");
    assert!(out.is_empty(), "{} records decoded from garbage", out.len());
    assert!(err.contains("wrong baud rate? configured 38400"), "{err}");
    assert!(err.contains("115200"), "{err}");
}
