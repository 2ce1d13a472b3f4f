//! Shared harness of the bridge end-to-end tests: the real server in-process on
//! loopback, protocol clients that watch a design, and a bridge configuration
//! whose tracker (Flock of Birds) and glove (CyberGlove) are simulated on
//! pseudo-terminals.

#![allow(dead_code)]

use futures_util::{SinkExt, StreamExt};
use glam::{DQuat, DVec3};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_bridge::config::{Calibration, Config, DeviceConfig, DeviceKind, HandConfig};
use vsculpt_bridge::hand::{GloveCalibration, glove_shape};
use vsculpt_bridge::sim::cyberglove::CyberGloveSim;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_protocol::{
    ClientEnvelope, ClientKind, ClientMessage, GeometryFrame, Icon, PROTOCOL_VERSION, Role,
    ServerMessage,
};
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;

/// Tracker metres → model millimetres.
pub const SCALE: f64 = 1000.0;

/// Logs to the test output when `RUST_LOG` is set.
pub fn init_logs() {
    if std::env::var("RUST_LOG").is_ok() {
        let _ = tracing_subscriber::fmt()
            .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
            .with_test_writer()
            .try_init();
    }
}

/// A fresh directory under the system temp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-e2e-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A running in-process server.
pub struct RunningServer {
    pub addr: SocketAddr,
    pub device_url: String,
    pub viewer_token: String,
    pub editor_token: String,
    pub shutdown: Shutdown,
    pub task: tokio::task::JoinHandle<()>,
}

impl RunningServer {
    /// Starts a server on `data`, on `addr` (or a free port).
    pub async fn start(data: &Path, addr: Option<SocketAddr>) -> Self {
        let listener =
            tokio::net::TcpListener::bind(addr.unwrap_or_else(|| "127.0.0.1:0".parse().unwrap()))
                .await
                .unwrap();
        let mut config = vsculpt_server::config::Config::new(data.to_path_buf(), data.join("web"));
        config.persist_delay = Duration::from_millis(50);
        let shutdown = Shutdown::new();
        let server = Server::start(listener, config, shutdown.clone())
            .await
            .unwrap();
        let addr = server.local_addr();
        let links = server.links().unwrap();
        let line = |kind: &str| {
            links
                .lines()
                .find(|l| l.starts_with("design 1 ") && l.contains(&format!(" {kind}: ")))
                .unwrap_or_else(|| panic!("no {kind} line in {links}"))
                .split(&format!(" {kind}: ")[..])
                .nth(1)
                .unwrap()
                .to_string()
        };
        let device_url = line("device");
        let viewer_token = line("viewer").split("token=").nth(1).unwrap().to_string();
        let editor_token = line("editor").split("token=").nth(1).unwrap().to_string();
        let task = tokio::spawn(async move {
            let _ = server.run().await;
        });
        Self {
            addr,
            device_url,
            viewer_token,
            editor_token,
            shutdown,
            task,
        }
    }

    /// Stops the server and waits for it.
    pub async fn stop(self) {
        self.shutdown.trigger();
        let _ = self.task.await;
    }
}

/// A protocol client of design 1 with `token`; returns its message stream after the hello.
pub async fn join(
    addr: SocketAddr,
    token: &str,
) -> (
    futures_util::stream::SplitSink<
        tokio_tungstenite::WebSocketStream<
            tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>,
        >,
        Message,
    >,
    mpsc::UnboundedReceiver<ServerMessage>,
) {
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
            client_name: "e2e".into(),
            client_kind: ClientKind::Tool,
            geometry_first: false,
            cached_geometry: None,
        },
    };
    tx.send(Message::text(serde_json::to_string(&hello).unwrap()))
        .await
        .unwrap();
    let (mtx, mrx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        while let Some(Ok(m)) = rx.next().await {
            if let Message::Text(t) = m
                && let Ok(msg) = serde_json::from_str::<ServerMessage>(t.as_str())
                && mtx.send(msg).is_err()
            {
                return;
            }
        }
    });
    (tx, mrx)
}

/// Every binary geometry frame design 1 sends to a client with `token`, decoded.
pub async fn watch_frames(addr: SocketAddr, token: &str) -> mpsc::UnboundedReceiver<GeometryFrame> {
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
            client_name: "e2e-frames".into(),
            client_kind: ClientKind::Tool,
            geometry_first: false,
            cached_geometry: None,
        },
    };
    tx.send(Message::text(serde_json::to_string(&hello).unwrap()))
        .await
        .unwrap();
    let (ftx, frx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        let _keep = tx;
        while let Some(Ok(m)) = rx.next().await {
            if let Message::Binary(b) = m
                && let Ok(f) = GeometryFrame::decode(&b)
                && ftx.send(f).is_err()
            {
                return;
            }
        }
    });
    frx
}

/// The icons of design 1 (every part's) as a new client sees them (its join
/// snapshot).
pub async fn snapshot_icons(addr: SocketAddr, token: &str) -> Vec<Icon> {
    let (_tx, mut rx) = join(addr, token).await;
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), rx.recv())
            .await
            .unwrap()
            .unwrap();
        if let ServerMessage::Snapshot { parts, .. } = m {
            return parts.into_iter().flat_map(|p| p.icons).collect();
        }
    }
}

/// Waits until the bridge has joined the design (it is in the presence list), then
/// a little longer for its devices to stream.
pub async fn wait_bridge(server: &RunningServer) {
    let (addr, token) = (server.addr, server.viewer_token.clone());
    let joined = eventually(20, || {
        let t = token.clone();
        async move {
            let (_tx, mut rx) = join(addr, &t).await;
            loop {
                let m = tokio::time::timeout(Duration::from_secs(10), rx.recv())
                    .await
                    .ok()??;
                if let ServerMessage::Snapshot { presence, .. } = m {
                    return presence
                        .iter()
                        .any(|p| p.name == vsculpt_bridge::wire::CLIENT_NAME)
                        .then_some(());
                }
            }
        }
    })
    .await;
    assert!(joined.is_some(), "the bridge never joined the design");
    tokio::time::sleep(Duration::from_millis(400)).await;
}

/// The snapshot's control points: every part's, in part order (the demo's
/// joined panels and bound curve move with the shell).
pub async fn snapshot_points(addr: SocketAddr, token: &str) -> Vec<[f64; 3]> {
    let (_tx, mut rx) = join(addr, token).await;
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), rx.recv())
            .await
            .unwrap()
            .unwrap();
        if let ServerMessage::Snapshot { parts, .. } = m {
            return parts
                .into_iter()
                .flat_map(|p| match p.shape {
                    vsculpt_protocol::PartShape::Surface { surface } => surface.points,
                    vsculpt_protocol::PartShape::Curve { curve } => curve.points,
                    vsculpt_protocol::PartShape::Dsm { .. }
                    | vsculpt_protocol::PartShape::Network { .. }
                    | vsculpt_protocol::PartShape::Body { .. } => Vec::new(),
                })
                .collect();
        }
    }
}

/// The first position-constraint icon of the demo design.
pub fn position_icon(icons: &[Icon]) -> Icon {
    icons
        .iter()
        .find(|i| i.role == Role::Position)
        .cloned()
        .expect("the demo has a position icon")
}

/// Simulated tracker and glove on ptys, reachable through symlinks in `dir`.
pub struct Studio {
    pub tracker: PtySim<FlockSim>,
    pub glove: PtySim<CyberGloveSim>,
}

impl Studio {
    /// Starts the simulated devices; the hand rests open at `at` (model mm).
    pub fn start(dir: &Path, at: DVec3) -> Self {
        let mut flock = FlockSim::new(1, false, Duration::from_millis(4));
        flock.set_pose(0, at / SCALE, DQuat::IDENTITY);
        let tracker = PtySim::start(flock, dir.join("tracker")).unwrap();
        let mut g = CyberGloveSim::new(22, 40, Duration::from_millis(4));
        g.values = glove_shape(22, 0.0, 0.0);
        let glove = PtySim::start(g, dir.join("glove")).unwrap();
        Self { tracker, glove }
    }

    /// Moves the hand to `at` (model mm).
    pub fn move_to(&self, at: DVec3) {
        self.tracker
            .device()
            .set_pose(0, at / SCALE, DQuat::IDENTITY);
    }

    /// Closes (grab) or opens (release) the hand.
    pub fn close_hand(&self, closed: bool) {
        let f = if closed { 1.0 } else { 0.0 };
        self.glove.device().values = glove_shape(22, f, f);
    }
}

/// The bridge configuration for a [`Studio`] in `dir`, talking to `url`.
pub fn bridge_config(dir: &Path, url: &str) -> Config {
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

/// Polls `f` every 50 ms until it returns `Some` or `secs` pass.
pub async fn eventually<T, F: std::future::Future<Output = Option<T>>>(
    secs: u64,
    mut f: impl FnMut() -> F,
) -> Option<T> {
    let end = tokio::time::Instant::now() + Duration::from_secs(secs);
    while tokio::time::Instant::now() < end {
        if let Some(t) = f().await {
            return Some(t);
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    None
}

/// The icon `id` in the current snapshot.
pub async fn icon_now(addr: SocketAddr, token: &str, id: u64) -> Icon {
    snapshot_icons(addr, token)
        .await
        .into_iter()
        .find(|i| i.id == id)
        .expect("icon still there")
}
