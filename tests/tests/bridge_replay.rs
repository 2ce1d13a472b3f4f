//! Replay is the session, end to end with the real server: a recording made of
//! byte streams written from the manuals (a Flock of Birds and a CyberGlove in the
//! right hand, a 3D mouse through spacenavd) — with the tracker lost mid-drag —
//! replayed the way the README shows (`vsculpt-bridge --server URL replay FILE`:
//! no configuration but the server link) at speeds 1, 2 and 10 into fresh servers
//! gives the same final design to 1e-12; the lost tracker released its icon where
//! the hand was. Also: a device link gets geometry frames only when it asks.

mod bridge_support;
#[path = "../../device-bridge/tests/independent/mod.rs"]
mod independent;

use bridge_support::*;
use futures_util::{SinkExt, StreamExt};
use glam::DVec3;
use independent::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_bridge::bridge::run_replay;
use vsculpt_bridge::config::{Config, DeviceConfig, DeviceKind};
use vsculpt_bridge::device::runner::DeviceStatus;
use vsculpt_bridge::device::{RawFrame, SourceId, TapEvent, Timestamp};
use vsculpt_bridge::recording::Recorder;
use vsculpt_bridge::wire::ProtocolWire;
use vsculpt_protocol::{ClientEnvelope, ClientKind, ClientMessage, IconState, PROTOCOL_VERSION};

/// A scratch directory under the build's own temp dir, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Self(d)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Lift (mm) before the tracker is lost.
const LIFT: f64 = 8.0;

/// Records the session with the hand at icon `p` (scene mm).
fn record_session(path: &Path, p: DVec3) {
    let mut config = bridge_config(Path::new("/dev/recorded"), "");
    let mut mouse = DeviceConfig::new("mouse", DeviceKind::Spacenavd);
    mouse.spacenavd.socket = Some("/nonexistent/spnav.sock".into());
    config.devices.push(mouse);
    config.menu.speed = 20.0;
    config.validate().unwrap();
    let rec = Recorder::create(path, &config).unwrap();
    let tap = rec.tap();
    let q = [0.99997, 0.0, 0.0, 0.0];
    let tracker = |mm: DVec3| flock_pos_quat((mm / SCALE).to_array(), q);
    let mut t = 10_000_000u64;
    let frame = |d: u16, t: u64, bytes: Vec<u8>| {
        TapEvent::Frame(RawFrame {
            source: SourceId(d),
            time: Timestamp(t),
            bytes,
        })
    };
    let status = |d: u16, t: u64, status: DeviceStatus| TapEvent::Status {
        source: SourceId(d),
        time: Timestamp(t),
        status,
    };
    for d in 0..3 {
        tap.send(status(d, t, DeviceStatus::Open)).unwrap();
    }
    for _ in 0..20 {
        t += 4000;
        tap.send(frame(0, t, tracker(p))).unwrap();
    }
    t += 1000;
    tap.send(frame(1, t, glove(GLOVE_CLOSED))).unwrap();
    for k in 1..=40 {
        t += 4000;
        let at = p + DVec3::Z * LIFT * k as f64 / 40.0;
        tap.send(frame(0, t, tracker(at))).unwrap();
    }
    // the tracker is unplugged with the hand closed, comes back, moves on: no drag
    t += 4000;
    tap.send(status(
        0,
        t,
        DeviceStatus::Lost("device disconnected".into()),
    ))
    .unwrap();
    t += 300_000;
    tap.send(status(0, t, DeviceStatus::Open)).unwrap();
    for k in 0..30 {
        t += 4000;
        let at = p + DVec3::Z * (LIFT + k as f64);
        tap.send(frame(0, t, tracker(at))).unwrap();
    }
    tap.send(frame(1, t, glove(GLOVE_OPEN))).unwrap();
    // the 3D mouse selects the next icon and pulls it towards the user twice
    t += 20_000;
    tap.send(frame(2, t, spnav([1, 2, 1, 0, 0, 0, 0, 0])))
        .unwrap();
    tap.send(frame(2, t, spnav([2, 2, 0, 0, 0, 0, 0, 0])))
        .unwrap();
    for push in 0..2 {
        for _ in 0..25 {
            t += 10_000;
            tap.send(frame(2, t, spnav([0, 120, 0, -350, 0, 0, 0, 10])))
                .unwrap();
        }
        t += 10_000;
        tap.send(frame(2, t, spnav([0, 0, 0, 0, 0, 0, 0, 10])))
            .unwrap();
        t += 300_000 * (push + 1);
    }
    drop(tap);
    rec.finish().unwrap();
}

/// Replays `path` as `vsculpt-bridge --server URL replay FILE --speed S` does,
/// into a fresh server; returns its surface and icons once nothing is held.
async fn replay_into_fresh_server(
    dir: &Path,
    path: &Path,
    speed: f64,
) -> (Vec<[f64; 3]>, Vec<vsculpt_protocol::Icon>) {
    let server = RunningServer::start(&dir.join(format!("data-{speed}")), None).await;
    let mut config = Config::default();
    config.server.url = server.device_url.clone();
    let n = run_replay(
        config,
        Arc::new(ProtocolWire::default()),
        path,
        speed,
        std::future::pending(),
    )
    .await
    .unwrap();
    assert!(n > 100, "replayed {n} samples");
    let (addr, token) = (server.addr, server.viewer_token.clone());
    let icons = eventually(10, || {
        let t = token.clone();
        async move {
            let icons = snapshot_icons(addr, &t).await;
            icons.iter().all(|i| i.holder.is_none()).then_some(icons)
        }
    })
    .await
    .expect("every icon released");
    let points = snapshot_points(addr, &token).await;
    server.stop().await;
    (points, icons)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn replay_gives_the_same_design_at_every_speed() {
    init_logs();
    let scratch = Scratch::new("bridge-replay");
    let dir = scratch.0.clone();
    let probe = RunningServer::start(&dir.join("probe"), None).await;
    let before_icons = snapshot_icons(probe.addr, &probe.viewer_token).await;
    let before = snapshot_points(probe.addr, &probe.viewer_token).await;
    probe.stop().await;
    let icon = position_icon(&before_icons);
    let p = DVec3::from_array(icon.xyz);
    let recording = dir.join("session.vsbrec");
    record_session(&recording, p);

    let mut results = Vec::new();
    for speed in [1.0, 2.0, 10.0] {
        results.push(replay_into_fresh_server(&dir, &recording, speed).await);
    }
    let (points, icons) = &results[0];
    // the session changed the design: the hand's icon was lifted by LIFT and let
    // go when the tracker was lost (the Flock's 14-bit words quantise at 0.11 mm)
    let lifted = icons.iter().find(|i| i.id == icon.id).unwrap();
    assert!(
        (lifted.xyz[2] - p.z - LIFT).abs() < 0.2,
        "icon at {:?} from {p}",
        lifted.xyz
    );
    assert!(lifted.sensors.is_empty());
    assert_eq!(lifted.state, IconState::Passive);
    let moved = before
        .iter()
        .zip(points)
        .map(|(a, b)| (DVec3::from_array(*a) - DVec3::from_array(*b)).length())
        .fold(0.0, f64::max);
    assert!(moved > 1.0, "the design changed ({moved})");
    // … identically at every speed
    for (speed, (pts, ics)) in [2.0, 10.0].iter().zip(&results[1..]) {
        let gap = points
            .iter()
            .zip(pts)
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
            .fold(0.0, f64::max);
        assert!(
            gap <= 1e-12,
            "speed {speed}: control points differ by {gap}"
        );
        for (a, b) in icons.iter().zip(ics) {
            let d = (0..3)
                .map(|k| (a.xyz[k] - b.xyz[k]).abs())
                .fold(0.0, f64::max);
            assert!(d <= 1e-12, "speed {speed}: icon {} differs by {d}", a.id);
        }
    }
}

/// Reads messages until the server's pong; true when a geometry frame came first.
async fn frames_before_pong(url: &str) -> bool {
    let (ws, _) = tokio_tungstenite::connect_async(url).await.unwrap();
    let (mut tx, mut rx) = ws.split();
    let hello = ClientEnvelope {
        req: None,
        msg: ClientMessage::Hello {
            protocol: PROTOCOL_VERSION,
            token: String::new(),
            design: 1,
            client_name: "e2e-device".into(),
            client_kind: ClientKind::Bridge,
            geometry_first: false,
            cached_geometry: None,
        },
    };
    tx.send(Message::text(serde_json::to_string(&hello).unwrap()))
        .await
        .unwrap();
    let ping = ClientEnvelope {
        req: None,
        msg: ClientMessage::Ping,
    };
    tx.send(Message::text(serde_json::to_string(&ping).unwrap()))
        .await
        .unwrap();
    let mut binary = false;
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), rx.next())
            .await
            .expect("the server answers")
            .expect("open")
            .unwrap();
        match m {
            Message::Binary(_) => binary = true,
            Message::Text(t) if t.as_str().contains("\"pong\"") => return binary,
            _ => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_device_link_gets_geometry_frames_only_when_it_asks() {
    let scratch = Scratch::new("bridge-frames");
    let server = RunningServer::start(&scratch.0.join("data"), None).await;
    // the writer sends the current geometry first of all, before any reply
    assert!(!frames_before_pong(&server.device_url).await);
    assert!(frames_before_pong(&format!("{}&geometry=1", server.device_url)).await);
    server.stop().await;
}
