//! The bridge binary keeps working when whoever read its log goes away: its
//! stderr is a pipe the test closes once the bridge is connected. Hand
//! samples from a simulated tracker and glove (on pseudo-terminals) still
//! reach a real server (in-process), through a tracker unplug and re-plug
//! (which the bridge logs into the closed pipe).

use futures_util::{SinkExt, StreamExt};
use glam::{DQuat, DVec3};
use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_bridge::config::{Calibration, Config, DeviceConfig, DeviceKind, HandConfig};
use vsculpt_bridge::hand::{GloveCalibration, glove_shape};
use vsculpt_bridge::sim::cyberglove::CyberGloveSim;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_protocol::{
    ClientEnvelope, ClientKind, ClientMessage, PROTOCOL_VERSION, ServerMessage,
};

/// Tracker metres → model millimetres.
const SCALE: f64 = 1000.0;

fn config(dir: &Path, url: &str) -> Config {
    let mut tracker = DeviceConfig::new("tracker", DeviceKind::Flock);
    tracker.port = Some(dir.join("tracker").display().to_string());
    tracker.settle_ms = 20;
    let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    glove.port = Some(dir.join("glove").display().to_string());
    glove.settle_ms = 20;
    let mut c = Config {
        calibration: Calibration {
            translation: [0.0; 3],
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: SCALE,
        },
        devices: vec![tracker, glove],
        hands: vec![HandConfig {
            name: "right-hand".into(),
            tracker: "tracker".into(),
            sensor: 0,
            glove: Some("glove".into()),
            reach: 5.0,
            calibration: GloveCalibration::default(),
        }],
        ..Default::default()
    };
    c.server.url = url.to_string();
    c.validate().unwrap();
    c
}

/// Where the bridge's hand is, as every viewer of design 1 sees it (presence).
async fn watch_hand(addr: std::net::SocketAddr, token: &str) -> mpsc::UnboundedReceiver<DVec3> {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    let (mut tx, mut rx) = ws.split();
    let hello = ClientEnvelope {
        req: None,
        msg: ClientMessage::Hello {
            protocol: PROTOCOL_VERSION,
            token: token.into(),
            design: 1,
            client_name: "watcher".into(),
            client_kind: ClientKind::Tool,
            geometry_first: false,
            cached_geometry: None,
        },
    };
    tx.send(Message::text(serde_json::to_string(&hello).unwrap()))
        .await
        .unwrap();
    let (htx, hrx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        let _keep = tx;
        while let Some(Ok(m)) = rx.next().await {
            let Message::Text(t) = m else { continue };
            let Ok(msg) = serde_json::from_str::<ServerMessage>(t.as_str()) else {
                continue;
            };
            let clients = match msg {
                ServerMessage::Presence { clients } => clients,
                ServerMessage::PresenceChanged { client } => vec![client],
                ServerMessage::Snapshot { presence, .. } => presence,
                _ => continue,
            };
            for c in clients {
                if c.name == vsculpt_bridge::wire::CLIENT_NAME
                    && let Some(p) = c.pointer
                    && htx.send(DVec3::from_array(p)).is_err()
                {
                    return;
                }
            }
        }
    });
    hrx
}

/// Waits until the hand is seen within 0.5 mm of `at`.
async fn seen_at(hand: &mut mpsc::UnboundedReceiver<DVec3>, at: DVec3) {
    let found = tokio::time::timeout(Duration::from_secs(30), async {
        while let Some(p) = hand.recv().await {
            if p.distance(at) < 0.5 {
                return true;
            }
        }
        false
    })
    .await;
    assert_eq!(found, Ok(true), "the server never saw the hand at {at}");
}

fn sigterm(mut child: Child) -> std::process::ExitStatus {
    let ok = Command::new("kill")
        .args(["-15", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    for _ in 0..1500 {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    panic!("the bridge did not exit on SIGTERM");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn samples_reach_the_server_after_the_log_reader_left_through_an_unplug() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut sc = vsculpt_server::config::Config::new(dir.join("data"), dir.join("web"));
    sc.persist_delay = Duration::from_millis(50);
    let shutdown = vsculpt_server::shutdown::Shutdown::new();
    let server = vsculpt_server::server::Server::start(listener, sc, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let design = &server.designs().unwrap()[0];
    let device_url = format!("ws://{addr}/ws?design=1&token={}", design.tokens.device);
    let viewer = design.tokens.viewer.clone();
    let serving = tokio::spawn(server.run());

    let a = DVec3::new(0.0, -200.0, 150.0);
    let mut flock = FlockSim::new(1, false, Duration::from_millis(4));
    flock.set_pose(0, a / SCALE, DQuat::IDENTITY);
    let mut tracker = PtySim::start(flock, dir.join("tracker")).unwrap();
    let mut g = CyberGloveSim::new(22, 40, Duration::from_millis(4));
    g.values = glove_shape(22, 0.0, 0.0);
    let _glove = PtySim::start(g, dir.join("glove")).unwrap();
    let cfg = dir.join("bridge.toml");
    std::fs::write(&cfg, config(dir, &device_url).to_toml()).unwrap();
    let mut hand = watch_hand(addr, &viewer).await;

    let (reader, writer) = std::io::pipe().unwrap();
    let child = {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vsculpt-bridge"));
        cmd.arg("--config")
            .arg(&cfg)
            .arg("run")
            .env("RUST_LOG", "debug")
            .stdin(Stdio::null())
            .stdout(writer.try_clone().unwrap())
            .stderr(writer);
        cmd.spawn().unwrap()
    };
    let mut reader = std::io::BufReader::new(reader);
    let mut log = String::new();
    while !log.contains("connected to server") {
        let mut line = String::new();
        assert!(reader.read_line(&mut line).unwrap() > 0, "log ended: {log}");
        log.push_str(&line);
    }
    drop(reader);

    seen_at(&mut hand, a).await;
    let b = a + DVec3::new(12.0, 0.0, 5.0);
    tracker.device().set_pose(0, b / SCALE, DQuat::IDENTITY);
    seen_at(&mut hand, b).await;
    // Unplugged (logged as lost, then reopen attempts), and back.
    tracker.unplug();
    tokio::time::sleep(Duration::from_millis(300)).await;
    let c = a + DVec3::new(-20.0, 7.0, 0.0);
    tracker.device().set_pose(0, c / SCALE, DQuat::IDENTITY);
    tracker.plug().unwrap();
    seen_at(&mut hand, c).await;

    let status = sigterm(child);
    assert!(status.success(), "{status:?}");
    shutdown.trigger();
    serving.await.unwrap().unwrap();
}
