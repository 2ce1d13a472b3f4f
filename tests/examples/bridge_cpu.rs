//! A measured run of the bridge's footprint against the real server (figures in
//! device-bridge/BENCHMARKS.md): a Flock of Birds streaming POS/QUAT records every
//! millisecond and a CyberGlove polled at its rate, both simulated on
//! pseudo-terminals, drive a held drag on the demo design of a real in-process
//! vsculpt server. CPU time of the bridge's threads (device runners + its runtime)
//! and of the server's runtime is read from `/proc/self/task/*/stat` over a
//! measuring window; the simulators are not counted.
//!
//! `cargo run -p vsculpt-e2e --example bridge_cpu [--release] -- [seconds]`

use glam::{DQuat, DVec3};
use std::sync::Arc;
use std::time::{Duration, Instant};
use vsculpt_bridge::config::{Calibration, Config, DeviceConfig, DeviceKind, HandConfig};
use vsculpt_bridge::hand::{GloveCalibration, glove_shape};
use vsculpt_bridge::sim::cyberglove::CyberGloveSim;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_bridge::wire::ProtocolWire;

/// CPU seconds of this process's threads whose names start with one of `prefixes`
/// (all threads when empty).
fn thread_cpu(prefixes: &[&str]) -> f64 {
    let tick = 100.0; // USER_HZ
    let mut total = 0.0;
    for t in std::fs::read_dir("/proc/self/task")
        .into_iter()
        .flatten()
        .flatten()
    {
        let Ok(stat) = std::fs::read_to_string(t.path().join("stat")) else {
            continue;
        };
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let name = &stat[open + 1..close];
        if !prefixes.is_empty() && !prefixes.iter().any(|p| name.starts_with(p)) {
            continue;
        }
        let f: Vec<&str> = stat[close + 2..].split(' ').collect();
        let ut: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0);
        let st: f64 = f.get(12).and_then(|v| v.parse().ok()).unwrap_or(0.0);
        total += (ut + st) / tick;
    }
    total
}

/// Voluntary context switches (each a wait that was woken: a wake-up) of this
/// process's threads whose names start with one of `prefixes`.
fn thread_wakeups(prefixes: &[&str]) -> u64 {
    let mut total = 0;
    for t in std::fs::read_dir("/proc/self/task")
        .into_iter()
        .flatten()
        .flatten()
    {
        let (Ok(comm), Ok(status)) = (
            std::fs::read_to_string(t.path().join("comm")),
            std::fs::read_to_string(t.path().join("status")),
        ) else {
            continue;
        };
        if !prefixes.iter().any(|p| comm.starts_with(p)) {
            continue;
        }
        total += status
            .lines()
            .find_map(|l| l.strip_prefix("voluntary_ctxt_switches:"))
            .and_then(|v| v.trim().parse::<u64>().ok())
            .unwrap_or(0);
    }
    total
}

/// The position of the demo design's first position icon, from a join snapshot.
async fn first_position_icon(url: &str) -> [f64; 3] {
    use futures_util::{SinkExt, StreamExt};
    use vsculpt_protocol::{ClientEnvelope, ClientKind, ClientMessage, PROTOCOL_VERSION};
    let (ws, _) = tokio_tungstenite::connect_async(url).await.unwrap();
    let (mut tx, mut rx) = ws.split();
    let hello = ClientEnvelope {
        req: None,
        msg: ClientMessage::Hello {
            protocol: PROTOCOL_VERSION,
            token: String::new(),
            design: 1,
            client_name: "probe".into(),
            client_kind: ClientKind::Tool,
            geometry_first: false,
            cached_geometry: None,
        },
    };
    tx.send(tokio_tungstenite::tungstenite::Message::text(
        serde_json::to_string(&hello).unwrap(),
    ))
    .await
    .unwrap();
    while let Some(Ok(m)) = rx.next().await {
        if let tokio_tungstenite::tungstenite::Message::Text(t) = m
            && let Ok(vsculpt_protocol::ServerMessage::Snapshot { parts, .. }) =
                serde_json::from_str(t.as_str())
        {
            return parts
                .iter()
                .flat_map(|p| &p.icons)
                .find(|i| i.role == vsculpt_protocol::Role::Position)
                .map(|i| i.xyz)
                .unwrap();
        }
    }
    panic!("no snapshot")
}

fn main() {
    if std::env::var("RUST_LOG").is_ok() {
        tracing_subscriber::fmt()
            .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
            .init();
    }
    let seconds: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../target/tmp"))
        .join(format!("bridge-cpu-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();

    // the real server, in its own runtime
    let server_rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("server-rt")
        .enable_all()
        .build()
        .unwrap();
    let data = dir.join("data");
    let (addr, device_url, shutdown, icon) = server_rt.block_on(async {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let config = vsculpt_server::config::Config::new(data.clone(), data.join("web"));
        let shutdown = vsculpt_server::shutdown::Shutdown::new();
        let server = vsculpt_server::server::Server::start(listener, config, shutdown.clone())
            .await
            .unwrap();
        let addr = server.local_addr();
        let links = server.links().unwrap();
        let device_url = links
            .lines()
            .find(|l| l.starts_with("design 1 ") && l.contains(" device: "))
            .and_then(|l| l.split(" device: ").nth(1))
            .unwrap()
            .to_string();
        tokio::spawn(async move {
            let _ = server.run().await;
        });
        let icon = first_position_icon(&device_url).await;
        (addr, device_url, shutdown, icon)
    });
    let _ = addr;

    // the studio: a Flock at 1 kHz and a glove on ptys, the hand at an icon
    let p = DVec3::from_array(icon);
    let mut flock = FlockSim::new(1, false, Duration::from_millis(1));
    flock.set_pose(0, p / 1000.0, DQuat::IDENTITY);
    let tracker = PtySim::start(flock, dir.join("tracker")).unwrap();
    let mut g = CyberGloveSim::new(22, 40, Duration::from_millis(4));
    g.values = glove_shape(22, 0.0, 0.0);
    let glove = PtySim::start(g, dir.join("glove")).unwrap();

    let mut t = DeviceConfig::new("tracker", DeviceKind::Flock);
    t.port = Some(dir.join("tracker").display().to_string());
    t.settle_ms = 20;
    let mut gl = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    gl.port = Some(dir.join("glove").display().to_string());
    gl.settle_ms = 20;
    let mut config = Config {
        calibration: Calibration {
            scale: 1000.0,
            ..Default::default()
        },
        devices: vec![t, gl],
        hands: vec![HandConfig {
            name: "right-hand".into(),
            tracker: "tracker".into(),
            sensor: 0,
            glove: Some("glove".into()),
            reach: 40.0,
            calibration: GloveCalibration::default(),
        }],
        ..Default::default()
    };
    config.server.url = device_url;
    config.validate().unwrap();

    // the bridge on the runtime the binary uses (`bridge::runtime`: one thread,
    // here a thread named like its blocking pool so both are counted)
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let bridge = std::thread::Builder::new()
        .name("bridge-rt".into())
        .spawn(move || {
            let rt = vsculpt_bridge::bridge::runtime().unwrap();
            rt.block_on(vsculpt_bridge::bridge::run_live(
                config,
                Arc::new(ProtocolWire::default()),
                None,
                async {
                    let _ = stopped.await;
                },
            ))
        })
        .unwrap();
    std::thread::sleep(Duration::from_secs(2));
    glove.device().values = glove_shape(22, 1.0, 1.0);
    std::thread::sleep(Duration::from_millis(500));

    // the held hand moves slowly (±2 mm at 0.5 Hz) while the devices stream
    let mover_stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let ms = mover_stop.clone();
    let start = Instant::now();
    let mover = std::thread::spawn(move || {
        while !ms.load(std::sync::atomic::Ordering::Relaxed) {
            let s = start.elapsed().as_secs_f64();
            let at = p + DVec3::Z * 2.0 * (std::f64::consts::PI * s).sin();
            tracker.device().set_pose(0, at / 1000.0, DQuat::IDENTITY);
            std::thread::sleep(Duration::from_millis(5));
        }
        tracker
    });

    let (b0, s0, all0) = (
        thread_cpu(&["device ", "bridge-rt"]),
        thread_cpu(&["server-rt"]),
        thread_cpu(&[]),
    );
    let (d0, r0) = (thread_wakeups(&["device "]), thread_wakeups(&["bridge-rt"]));
    let wall = Instant::now();
    std::thread::sleep(Duration::from_secs(seconds));
    let secs = wall.elapsed().as_secs_f64();
    let (b1, s1, all1) = (
        thread_cpu(&["device ", "bridge-rt"]),
        thread_cpu(&["server-rt"]),
        thread_cpu(&[]),
    );
    let (d1, r1) = (thread_wakeups(&["device "]), thread_wakeups(&["bridge-rt"]));
    let pct = |cpu: f64| 100.0 * cpu / secs;
    println!(
        "wake-ups per second: device threads {:.0}, bridge runtime {:.0}",
        (d1 - d0) as f64 / secs,
        (r1 - r0) as f64 / secs
    );
    println!("window {secs:.1} s");
    println!(
        "bridge (device runners + bridge runtime): {:.2} % of one core",
        pct(b1 - b0)
    );
    println!("server runtime: {:.2} % of one core", pct(s1 - s0));
    println!(
        "bridge + server: {:.2} % of one core",
        pct(b1 - b0 + s1 - s0)
    );
    println!(
        "whole process (with the simulators and the mover): {:.2} % of one core",
        pct(all1 - all0)
    );

    mover_stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let tracker = mover.join().unwrap();
    let _ = stop.send(());
    let _ = bridge.join();
    shutdown.trigger();
    drop(tracker);
    drop(glove);
    drop(server_rt);
    let _ = std::fs::remove_dir_all(&dir);
}
