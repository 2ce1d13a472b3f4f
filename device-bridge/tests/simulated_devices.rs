//! Drivers against simulated devices speaking the published wire formats:
//! Flock of Birds, Fastrak and CyberGlove on pseudo-terminals, a fake spacenavd
//! socket, a fake VRPN server on loopback, and recorded HID report streams.

use glam::{DQuat, DVec3, EulerRot};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use vsculpt_bridge::config::{DeviceConfig, DeviceKind, build_decoder, build_driver};
use vsculpt_bridge::device::flock::{FlockFormat, FlockSettings};
use vsculpt_bridge::device::runner::{DeviceRunner, RunOptions};
use vsculpt_bridge::device::{Device, Driver, Reading, Sample, SourceId};
use vsculpt_bridge::sim::cyberglove::CyberGloveSim;
use vsculpt_bridge::sim::fastrak::FastrakSim;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::hid::{COMPACT_ID, COMPACT_SESSION, WIRELESS_ID, WIRELESS_SESSION};
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_bridge::sim::scripted::ScriptedTransport;
use vsculpt_bridge::sim::spacenavd::FakeSpacenavd;
use vsculpt_bridge::sim::vrpn::FakeVrpnServer;

fn temp_path(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-bridge-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Reads from `dev` until `pred` holds for a sample or `secs` pass.
fn read_until(dev: &mut dyn Device, secs: u64, pred: impl Fn(&Sample) -> bool) -> Option<Sample> {
    let end = Instant::now() + Duration::from_secs(secs);
    let mut out = Vec::new();
    while Instant::now() < end {
        out.clear();
        let _ = dev.read(Duration::from_millis(50), &mut out);
        if let Some(s) = out.iter().find(|s| pred(s)) {
            return Some(*s);
        }
    }
    None
}

fn pose_of(s: &Sample) -> (u16, DVec3, DQuat) {
    match s.reading {
        Reading::Pose {
            sensor,
            position,
            orientation,
        } => (sensor, position, orientation),
        ref r => panic!("not a pose: {r:?}"),
    }
}

#[test]
fn flock_group_mode_on_a_pty() {
    let link = temp_path("flock");
    let mut sim = FlockSim::new(2, false, Duration::from_millis(5));
    let q1 = DQuat::from_euler(EulerRot::ZYX, 0.5, 0.2, -0.3);
    sim.set_pose(0, DVec3::new(0.1, 0.2, -0.3), DQuat::IDENTITY);
    sim.set_pose(1, DVec3::new(-0.2, 0.05, 0.4), q1);
    let sim = PtySim::start(sim, &link).unwrap();
    let mut cfg = DeviceConfig::new("flock", DeviceKind::Flock);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 20;
    cfg.flock = FlockSettings {
        birds: 2,
        group_mode: true,
        format: FlockFormat::PosQuat,
        ..Default::default()
    };
    let mut d = build_driver(SourceId(0), &cfg);
    d.open().unwrap();
    let s1 = read_until(&mut d, 5, |s| pose_of(s).0 == 1).expect("bird 2 pose");
    let (_, p, q) = pose_of(&s1);
    assert!((p - DVec3::new(-0.2, 0.05, 0.4)).length() < 2e-4, "{p}");
    assert!(q.dot(q1).abs() > 1.0 - 1e-6);
    let s0 = read_until(&mut d, 5, |s| pose_of(s).0 == 0).expect("bird 1 pose");
    assert!((pose_of(&s0).1 - DVec3::new(0.1, 0.2, -0.3)).length() < 2e-4);
    // the device saw the documented set-up: group mode, POS/QUAT routed to each bird, stream
    {
        let dev = sim.device();
        assert!(dev.group_mode && dev.streaming);
        assert_eq!(dev.formats, vec![FlockFormat::PosQuat; 2]);
        assert!(dev.log.windows(3).any(|w| w == [b'P', 35, 1]));
        assert!(dev.log.windows(2).any(|w| w == [0xF2, b']']));
    }
    // garbage and a broken record in the middle of the stream: never a wrong pose
    sim.inject(&[0x00, 0x13, 0x80, 0x7f, 0x7f, 0xff, 0x01]);
    sim.device()
        .set_pose(0, DVec3::new(0.3, 0.0, 0.0), DQuat::IDENTITY);
    let s = read_until(&mut d, 5, |s| {
        let (sensor, p, _) = pose_of(s);
        sensor == 0 && (p.x - 0.3).abs() < 1e-3
    });
    assert!(s.is_some());
    for _ in 0..20 {
        let mut out = Vec::new();
        d.read(Duration::from_millis(20), &mut out).unwrap();
        for s in &out {
            let (sensor, p, _) = pose_of(s);
            let expect = if sensor == 0 {
                DVec3::new(0.3, 0.0, 0.0)
            } else {
                DVec3::new(-0.2, 0.05, 0.4)
            };
            assert!(
                (p - expect).length() < 2e-4,
                "wrong pose {p} for sensor {sensor}"
            );
        }
    }
    assert!(d.stats().faults() > 0);
    d.close();
    let end = Instant::now() + Duration::from_secs(2);
    while !sim.device().log.ends_with(b"BG") && Instant::now() < end {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(sim.device().log.ends_with(b"BG"));
}

#[test]
fn flock_polled_pos_angles() {
    let link = temp_path("flock-poll");
    let mut sim = FlockSim::new(1, false, Duration::from_millis(5));
    let q = DQuat::from_euler(EulerRot::ZYX, 1.0, 0.3, 0.2);
    sim.set_pose(0, DVec3::new(0.05, -0.1, 0.2), q);
    let sim = PtySim::start(sim, &link).unwrap();
    let mut cfg = DeviceConfig::new("flock", DeviceKind::Flock);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    cfg.flock = FlockSettings {
        format: FlockFormat::PosAngles,
        stream: false,
        ..Default::default()
    };
    let mut d = build_driver(SourceId(0), &cfg);
    d.open().unwrap();
    let s = read_until(&mut d, 5, |_| true).expect("a polled record");
    let (_, p, q2) = pose_of(&s);
    assert!((p - DVec3::new(0.05, -0.1, 0.2)).length() < 2e-4);
    assert!(q2.dot(q).abs() > 1.0 - 1e-5);
    assert!(!sim.device().streaming);
}

#[test]
fn fastrak_binary_records_on_a_pty() {
    let link = temp_path("fastrak");
    let mut sim = FastrakSim::new(2, Duration::from_millis(5));
    let q = DQuat::from_rotation_y(0.7);
    sim.poses[1] = (DVec3::new(0.3, -0.2, 0.1), q);
    let sim = PtySim::start(sim, &link).unwrap();
    let mut cfg = DeviceConfig::new("fastrak", DeviceKind::Fastrak);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    cfg.fastrak.stations = 2;
    let mut d = build_driver(SourceId(3), &cfg);
    d.open().unwrap();
    let s = read_until(&mut d, 5, |s| pose_of(s).0 == 1).expect("station 2");
    assert_eq!(s.source, SourceId(3));
    let (_, p, q2) = pose_of(&s);
    assert!((p - DVec3::new(0.3, -0.2, 0.1)).length() < 1e-6);
    assert!(q2.dot(q).abs() > 1.0 - 1e-6);
    assert!(sim.device().binary && sim.device().continuous);
    // corrupt bytes in the stream are skipped
    sim.inject(b"0\x31garbage0");
    assert!(read_until(&mut d, 5, |s| pose_of(s).0 == 1).is_some());
}

#[test]
fn cyberglove_polled_on_a_pty() {
    let link = temp_path("glove");
    let mut sim = CyberGloveSim::new(22, 100, Duration::from_millis(5));
    sim.values[4] = 71; // a sensor equal to 'G'
    let sim = PtySim::start(sim, &link).unwrap();
    let mut cfg = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    let mut d = build_driver(SourceId(1), &cfg);
    d.open().unwrap();
    let s = read_until(&mut d, 5, |_| true).expect("glove record");
    match s.reading {
        Reading::Glove(g) => {
            assert_eq!(g.len(), 22);
            assert_eq!(g.as_slice()[4], 71);
            assert_eq!(g.as_slice()[0], 100);
        }
        ref r => panic!("{r:?}"),
    }
    // an unplugged glove (e g) never yields values, and the driver says why
    sim.device().unplugged = true;
    let mut out = Vec::new();
    let mut err = None;
    for _ in 0..50 {
        if let Err(e) = d.read(Duration::from_millis(20), &mut out) {
            err = Some(e.to_string());
            break;
        }
    }
    assert!(out.is_empty());
    let err = err.expect("an unplugged glove is reported");
    assert!(err.contains("not plugged into its box"), "{err}");
}

#[test]
fn cyberglove_streaming_18_sensors() {
    let link = temp_path("glove18");
    let sim = PtySim::start(CyberGloveSim::new(18, 30, Duration::from_millis(5)), &link).unwrap();
    let mut cfg = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    cfg.cyberglove.sensors = 18;
    cfg.cyberglove.stream = true;
    let mut d = build_driver(SourceId(1), &cfg);
    d.open().unwrap();
    assert!(
        read_until(
            &mut d,
            5,
            |s| matches!(s.reading, Reading::Glove(g) if g.len() == 18)
        )
        .is_some()
    );
    assert!(sim.device().streaming);
    d.close();
    std::thread::sleep(Duration::from_millis(50));
    assert!(!sim.device().streaming);
}

#[test]
fn spacenavd_socket() {
    let path = temp_path("spnav.sock");
    let daemon = FakeSpacenavd::start(&path).unwrap();
    let mut cfg = DeviceConfig::new("mouse", DeviceKind::Spacenavd);
    cfg.spacenavd.socket = Some(path.display().to_string());
    // no dead zone: this test is about the wire format (the calibration has its own)
    cfg.spacenavd.deadzone = [0.0; 6];
    let mut d = build_driver(SourceId(2), &cfg);
    d.open().unwrap();
    let end = Instant::now() + Duration::from_secs(5);
    while daemon.clients() == 0 && Instant::now() < end {
        std::thread::sleep(Duration::from_millis(5));
    }
    // spacenavd's z points away from the user: -175 is the cap pulled half towards
    // the user, +0.5 in the bridge's right-handed frame
    daemon.send_motion([350, 0, -175, 0, 35, 0], 8);
    daemon.send_button(1, true);
    let mut got = Vec::new();
    let end = Instant::now() + Duration::from_secs(5);
    while got.len() < 2 && Instant::now() < end {
        d.read(Duration::from_millis(20), &mut got).unwrap();
    }
    let got: Vec<Reading> = got.iter().map(|s| s.reading).collect();
    assert_eq!(
        got,
        vec![
            Reading::Motion {
                translation: DVec3::new(1.0, 0.0, 0.5),
                rotation: DVec3::new(0.0, 0.1, 0.0)
            },
            Reading::Button {
                button: 1,
                pressed: true
            }
        ]
    );
    // the daemon restarting: the read fails, a reopen works
    daemon.drop_clients();
    let mut out = Vec::new();
    let end = Instant::now() + Duration::from_secs(5);
    let mut failed = false;
    while Instant::now() < end {
        if d.read(Duration::from_millis(20), &mut out).is_err() {
            failed = true;
            break;
        }
    }
    assert!(failed);
    d.close();
    d.open().unwrap();
}

#[test]
fn vrpn_tracker_over_tcp() {
    let server = FakeVrpnServer::start("Tracker0", 2, Duration::from_millis(5)).unwrap();
    let q = DQuat::from_rotation_x(0.4);
    server.set_pose(1, DVec3::new(1.0, 2.0, 3.0), q);
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some(server.addr().to_string());
    let mut d = build_driver(SourceId(4), &cfg);
    d.open().unwrap();
    let s = read_until(&mut d, 5, |s| pose_of(s).0 == 1).expect("pose from VRPN");
    let (_, p, q2) = pose_of(&s);
    assert!((p - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-12);
    assert!(q2.dot(q).abs() > 1.0 - 1e-12);
    // only Tracker0's poses: a device of another name gets nothing
    let mut cfg2 = cfg.clone();
    cfg2.vrpn.device = "Tracker9".into();
    let mut d2 = build_driver(SourceId(5), &cfg2);
    d2.open().unwrap();
    assert!(read_until(&mut d2, 1, |_| true).is_none());
}

fn replay_hid(session: &[&[u8]], id: (u16, u16)) -> Vec<Reading> {
    let mut cfg = DeviceConfig::new("mouse", DeviceKind::SpacemouseHid);
    // no dead zone: these tests are about the report format
    cfg.spacemouse.deadzone = [0.0; 6];
    let t = ScriptedTransport::new(session.iter().map(|r| r.to_vec()), Some(id));
    let mut d = Driver::new(
        "mouse",
        SourceId(0),
        Box::new(t),
        build_decoder(SourceId(0), &cfg),
        Default::default(),
    );
    d.open().unwrap();
    let mut out = Vec::new();
    while d.read(Duration::from_millis(10), &mut out).is_ok() {}
    out.into_iter().map(|s| s.reading).collect()
}

#[test]
fn recorded_hid_streams_through_the_hid_parser() {
    let r = replay_hid(COMPACT_SESSION, COMPACT_ID);
    assert_eq!(r.len(), 8);
    // the full-right push (x = +350) comes out as +1 on x
    assert!(
        r.iter()
            .any(|m| matches!(m, Reading::Motion { translation, .. } if translation.x == 1.0))
    );
    assert!(r.contains(&Reading::Button {
        button: 0,
        pressed: true
    }));
    assert!(r.contains(&Reading::Button {
        button: 0,
        pressed: false
    }));
    let w = replay_hid(WIRELESS_SESSION, WIRELESS_ID);
    // battery ignored; the combined report carries x = -350 and rz = 175 → y-z swapped/inverted: ry = -0.5
    assert_eq!(
        w[0],
        Reading::Motion {
            translation: DVec3::new(-1.0, -0.0, -0.0),
            rotation: DVec3::new(0.0, -0.5, -0.0)
        }
    );
    assert_eq!(
        &w[1..4],
        &[
            Reading::Button {
                button: 1,
                pressed: true
            },
            Reading::Button {
                button: 0,
                pressed: true
            },
            Reading::Button {
                button: 0,
                pressed: false
            },
        ]
    );
}

#[test]
fn unplugged_tracker_comes_back_through_the_runner() {
    let link = temp_path("flock-plug");
    let mut sim = FlockSim::new(1, false, Duration::from_millis(5));
    sim.set_pose(0, DVec3::new(0.1, 0.0, 0.0), DQuat::IDENTITY);
    let mut sim = PtySim::start(sim, &link).unwrap();
    let mut cfg = DeviceConfig::new("flock", DeviceKind::Flock);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    let (tx, rx) = mpsc::channel::<Sample>();
    let options = RunOptions {
        silence: Some(Duration::from_millis(500)),
        ..Default::default()
    };
    let runner = DeviceRunner::spawn(
        Box::new(build_driver(SourceId(0), &cfg)),
        options,
        move |s| s.iter().all(|s| tx.send(*s).is_ok()),
    );
    let first = rx
        .recv_timeout(Duration::from_secs(5))
        .expect("samples before the unplug");
    assert!((pose_of(&first).1.x - 0.1).abs() < 1e-3);
    sim.unplug();
    std::thread::sleep(Duration::from_millis(300));
    while rx.try_recv().is_ok() {}
    sim.device()
        .set_pose(0, DVec3::new(0.2, 0.0, 0.0), DQuat::IDENTITY);
    sim.plug().unwrap();
    let end = Instant::now() + Duration::from_secs(10);
    let mut back = false;
    while Instant::now() < end {
        if let Ok(s) = rx.recv_timeout(Duration::from_millis(100))
            && (pose_of(&s).1.x - 0.2).abs() < 1e-3
        {
            back = true;
            break;
        }
    }
    assert!(back, "no pose after re-plugging");
    assert!(
        runner
            .stats()
            .opens
            .load(std::sync::atomic::Ordering::Relaxed)
            >= 2
    );
}

#[test]
fn cyberglove_with_the_wrong_sensor_count_is_refused() {
    let link = temp_path("glove-count");
    let _sim = PtySim::start(CyberGloveSim::new(22, 50, Duration::from_millis(5)), &link).unwrap();
    let mut cfg = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    cfg.port = Some(link.display().to_string());
    cfg.settle_ms = 10;
    cfg.cyberglove.sensors = 18;
    let mut d = build_driver(SourceId(1), &cfg);
    let e = d.open().unwrap_err();
    assert!(
        matches!(e, vsculpt_bridge::device::DeviceError::Handshake(_)),
        "{e}"
    );
}

#[test]
fn vrpn_server_dropping_the_client_is_ridden_out_by_the_runner() {
    let server = FakeVrpnServer::start("Tracker0", 1, Duration::from_millis(5)).unwrap();
    server.set_pose(0, DVec3::new(0.5, 0.0, 0.0), DQuat::IDENTITY);
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some(server.addr().to_string());
    let (tx, rx) = mpsc::channel::<Sample>();
    let options = RunOptions {
        silence: None,
        ..Default::default()
    };
    let runner = DeviceRunner::spawn(
        Box::new(build_driver(SourceId(0), &cfg)),
        options,
        move |s| s.iter().all(|s| tx.send(*s).is_ok()),
    );
    assert!(rx.recv_timeout(Duration::from_secs(5)).is_ok());
    server.drop_clients();
    server.set_pose(0, DVec3::new(0.7, 0.0, 0.0), DQuat::IDENTITY);
    let end = Instant::now() + Duration::from_secs(10);
    let mut back = false;
    while Instant::now() < end {
        if let Ok(s) = rx.recv_timeout(Duration::from_millis(100))
            && (pose_of(&s).1.x - 0.7).abs() < 1e-9
        {
            back = true;
            break;
        }
    }
    assert!(back, "no pose after the server dropped the client");
    assert!(
        runner
            .stats()
            .opens
            .load(std::sync::atomic::Ordering::Relaxed)
            >= 2
    );
}
