//! Replay is the session: a recording (written through the [`Recorder`] from byte
//! streams generated independently from the manuals) holds the whole configuration
//! and every device status change, and replaying it — at any speed — drives the
//! interaction to exactly the commands a live run of the same bytes at the same
//! times gives: a device lost mid-drag releases the grab, a 3D-mouse push
//! integrates over the recorded time, not the compressed playback time.

mod independent;

use glam::DVec3;
use independent::*;
use std::path::{Path, PathBuf};
use vsculpt_bridge::bridge::Input;
use vsculpt_bridge::config::{
    Calibration, Config, DeviceConfig, DeviceKind, HandConfig, build_decoder,
};
use vsculpt_bridge::device::runner::DeviceStatus;
use vsculpt_bridge::device::{RawFrame, SourceId, TapEvent, Timestamp};
use vsculpt_bridge::hand::GloveCalibration;
use vsculpt_bridge::interaction::{Command, IconKind, IconRole, IconState, IconView, Interaction};
use vsculpt_bridge::recording::{Recorder, Replayer};

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("replay-tests");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(format!("{name}-{}.vsbrec", std::process::id()))
}

fn studio() -> Config {
    let mut tracker = DeviceConfig::new("tracker", DeviceKind::Flock);
    tracker.port = Some("/dev/ttyUSB0".into());
    let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    glove.port = Some("/dev/ttyUSB1".into());
    let mut mouse = DeviceConfig::new("mouse", DeviceKind::Spacenavd);
    mouse.spacenavd.socket = Some("/nonexistent".into());
    let mut c = Config {
        calibration: Calibration {
            scale: 1000.0,
            ..Default::default()
        },
        devices: vec![tracker, glove, mouse],
        hands: vec![HandConfig {
            name: "right".into(),
            tracker: "tracker".into(),
            sensor: 0,
            glove: Some("glove".into()),
            reach: 20.0,
            calibration: GloveCalibration {
                open: vec![35],
                closed: vec![210],
            },
        }],
        ..Default::default()
    };
    c.menu.speed = 20.0;
    c.server.url = "ws://127.0.0.1:1/ws?design=1&token=secret".into();
    c.validate().unwrap();
    c
}

fn icons() -> Vec<IconView> {
    [
        (1, DVec3::new(300.0, 100.0, -50.0)),
        (2, DVec3::new(0.0, 0.0, 0.0)),
    ]
    .into_iter()
    .map(|(id, p)| IconView {
        part: 1,
        id,
        position: p,
        target: p,
        role: IconRole::Constraint,
        kind: IconKind::Position,
        state: IconState::Passive,
    })
    .collect()
}

enum Ev {
    Bytes(u16, u64, Vec<u8>),
    Status(u16, u64, DeviceStatus),
}

/// A session: the hand grabs icon 1 and lifts it, the tracker is lost mid-drag and
/// comes back while the hand is still closed (no drag may follow), then the 3D
/// mouse selects the next icon and pulls it towards the user twice.
fn session() -> Vec<Ev> {
    let mut ev = Vec::new();
    let q = [0.99997, 0.0, 0.0, 0.0];
    let mut t = 5_000_000u64;
    let at = |mm: f64| [0.300, 0.100, -0.050 + mm * 1e-3];
    for _ in 0..10 {
        ev.push(Ev::Bytes(0, t, flock_pos_quat(at(0.0), q)));
        t += 5000;
    }
    ev.push(Ev::Bytes(1, t, glove(GLOVE_CLOSED)));
    for k in 1..=40 {
        t += 5000;
        ev.push(Ev::Bytes(0, t, flock_pos_quat(at(k as f64 * 0.25), q)));
    }
    t += 5000;
    ev.push(Ev::Status(
        0,
        t,
        DeviceStatus::Lost("device disconnected".into()),
    ));
    t += 200_000;
    ev.push(Ev::Status(0, t, DeviceStatus::Open));
    for k in 0..20 {
        t += 5000;
        ev.push(Ev::Bytes(0, t, flock_pos_quat(at(10.0 + k as f64), q)));
    }
    ev.push(Ev::Bytes(1, t, glove(GLOVE_OPEN)));
    // the 3D mouse: select the next icon (the first), a short push and rest, half a
    // second untouched, then 31 events 10 ms apart pulling the cap fully towards
    // the user (spacenavd z = -350), then rest
    t += 10_000;
    ev.push(Ev::Bytes(2, t, spnav([1, 2, 1, 0, 0, 0, 0, 0])));
    ev.push(Ev::Bytes(2, t, spnav([2, 2, 0, 0, 0, 0, 0, 0])));
    for _ in 0..5 {
        t += 10_000;
        ev.push(Ev::Bytes(2, t, spnav([0, 0, 0, -350, 0, 0, 0, 10])));
    }
    t += 10_000;
    ev.push(Ev::Bytes(2, t, spnav([0, 0, 0, 0, 0, 0, 0, 10])));
    t += 500_000;
    for _ in 0..31 {
        t += 10_000;
        ev.push(Ev::Bytes(2, t, spnav([0, 0, 0, -350, 0, 0, 0, 10])));
    }
    t += 10_000;
    ev.push(Ev::Bytes(2, t, spnav([0, 0, 0, 0, 0, 0, 0, 10])));
    ev
}

fn record(path: &Path, config: &Config) {
    let rec = Recorder::create(path, config).unwrap();
    let tap = rec.tap();
    for e in session() {
        let ev = match e {
            Ev::Bytes(d, t, bytes) => TapEvent::Frame(RawFrame {
                source: SourceId(d),
                time: Timestamp(t),
                bytes,
            }),
            Ev::Status(d, t, status) => TapEvent::Status {
                source: SourceId(d),
                time: Timestamp(t),
                status,
            },
        };
        tap.send(ev).unwrap();
    }
    drop(tap);
    rec.finish().unwrap();
}

/// What the interaction makes of `inputs` (hand samples left out: they only inform
/// other clients).
fn interact(config: &Config, inputs: impl IntoIterator<Item = Input>) -> Vec<Command> {
    let mut i = Interaction::new(config);
    i.set_icons(icons());
    let mut out = Vec::new();
    for input in inputs {
        match input {
            Input::Samples(s) => s.iter().for_each(|s| i.handle(s, &mut out)),
            Input::Status(source, DeviceStatus::Lost(_)) => i.device_lost(source, &mut out),
            Input::Status(..) => {}
        }
    }
    out.retain(|c| !matches!(c, Command::HandSample { .. }));
    out
}

/// The live run of the same bytes at the same times, for comparison.
fn live(config: &Config) -> Vec<Command> {
    let mut decoders: Vec<_> = config
        .devices
        .iter()
        .enumerate()
        .map(|(i, d)| build_decoder(SourceId(i as u16), d))
        .collect();
    let inputs = session().into_iter().map(|e| match e {
        Ev::Bytes(d, t, bytes) => {
            let mut s = Vec::new();
            decoders[usize::from(d)].feed(&bytes, Timestamp(t), &mut s);
            Input::Samples(s)
        }
        Ev::Status(d, _, status) => Input::Status(SourceId(d), status),
    });
    interact(config, inputs.collect::<Vec<_>>())
}

fn replay(path: &Path, speed: f64) -> (Config, Vec<Command>) {
    let r = Replayer::open(path).unwrap();
    let config = r.config().clone();
    let mut inputs = Vec::new();
    r.play(speed, |i| {
        inputs.push(i);
        true
    })
    .unwrap();
    let cmds = interact(&config, inputs);
    (config, cmds)
}

#[test]
fn replay_at_any_speed_is_the_live_session() {
    let config = studio();
    let path = scratch("session");
    record(&path, &config);
    let want = live(&config);
    for speed in [1.0, 2.0, 10.0, f64::INFINITY] {
        let (recorded, got) = replay(&path, speed);
        // the header holds the whole configuration but not the server link (token)
        assert_eq!(recorded.hands, config.hands);
        assert_eq!(recorded.calibration, config.calibration);
        assert_eq!(recorded.menu, config.menu);
        assert_eq!(recorded.devices, config.devices);
        assert_eq!(recorded.server.url, "");
        assert_eq!(got, want, "speed {speed}");
    }
    let _ = std::fs::remove_file(&path);

    // what the session did: grab, lift 10 mm, the tracker lost releases at +10 mm;
    // nothing moves while the tracker is back with the hand still closed
    let release = want
        .iter()
        .position(|c| matches!(c, Command::Release { icon: 1, sensor } if sensor == "right"))
        .expect("the lost tracker releases the icon");
    assert!(matches!(&want[0], Command::Grab { icon: 1, .. }));
    let Some(Command::Drag { target, .. }) = want[..release].last() else {
        panic!("{want:?}")
    };
    assert!((target.z - (-50.0 + 10.0)).abs() < 0.15, "{target}");
    // the hand's grab selected icon 1, "select next" took icon 2; the second mouse
    // push pulled it (from where it was reported, its start) at 20 mm/s for 30 intervals of 10 ms: 6 mm
    // towards the user (+z), not more (no phantom motion from the pause before it)
    let mouse_drags: Vec<DVec3> = want[release..]
        .iter()
        .filter_map(|c| match c {
            Command::Drag { target, .. } => Some(*target),
            _ => None,
        })
        .collect();
    let last = mouse_drags.last().expect("the mouse dragged");
    let start = icons()[1].position;
    assert!((*last - (start + DVec3::Z * 6.0)).length() < 1e-9, "{last}");
    assert!(matches!(want.last(), Some(Command::Release { icon: 2, sensor }) if sensor == "mouse"));
}
