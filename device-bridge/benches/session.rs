//! The bridge under a 1000 samples/s tracker: per-sample pipeline cost (decode →
//! interaction → outbox) and the CPU the bridge's own threads use while a Flock
//! simulated on a pty streams at 1 kHz into a held drag sent to a WebSocket sink.
//!
//! `session/cpu_per_second_at_1khz` reports, as its "time", the CPU time the
//! bridge threads (device runner and link runtime) consumed during one second of
//! 1 kHz input: 50 ms means 5 % of one core.

use criterion::{Criterion, criterion_group, criterion_main};
use futures_util::StreamExt;
use glam::{DQuat, DVec3};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use vsculpt_bridge::bridge::Input;
use vsculpt_bridge::config::{
    Config, DeviceConfig, DeviceKind, HandConfig, build_decoder, build_driver,
};
use vsculpt_bridge::device::flock::{FlockSettings, encode_record, pose_words};
use vsculpt_bridge::device::runner::{DeviceRunner, RunOptions};
use vsculpt_bridge::device::{GloveValues, Reading, Sample, SourceId, Timestamp};
use vsculpt_bridge::hand::{GloveCalibration, glove_shape};
use vsculpt_bridge::interaction::{IconKind, IconRole, IconState, IconView, Interaction};
use vsculpt_bridge::link::Wire;
use vsculpt_bridge::outbox::Outbox;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_bridge::wire::ProtocolWire;

/// What a protocol-v1 server says to a joining device: welcome, then a snapshot
/// with one position icon at the origin.
const WELCOME: &str =
    r#"{"type": "welcome", "client_id": 1, "access": "device", "design": 1, "protocol": 1}"#;
const SNAPSHOT: &str = r#"{"type": "snapshot", "design": {"id": 1, "name": "bench", "versions": 0}, "revision": 0,
 "surface": {"u": {"degree": 1, "knots": [0, 0, 1, 1]}, "v": {"degree": 1, "knots": [0, 0, 1, 1]}, "nu": 2, "nv": 2,
             "points": [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]]},
 "material": {"alpha11": 1, "alpha12": 0, "alpha22": 1, "beta11": 1, "beta12": 1, "beta22": 1},
 "icons": [{"id": 1, "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "position"}, "state": "passive",
            "xyz": [0, 0, 0], "target": [0, 0, 0], "sensors": []}],
 "versions": [], "presence": [], "can_undo": false, "can_redo": false}"#;

/// A WebSocket server on its own runtime that greets like the vsculpt server and
/// reports the arrival time of every `drag` to `arrived`.
fn sink(
    arrived: Option<std::sync::mpsc::Sender<std::time::Instant>>,
) -> (tokio::runtime::Runtime, std::net::SocketAddr) {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("sink")
        .enable_all()
        .build()
        .expect("sink runtime");
    let listener = rt
        .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
        .expect("bind");
    let addr = listener.local_addr().expect("addr");
    rt.spawn(async move {
        while let Ok((tcp, _)) = listener.accept().await {
            let arrived = arrived.clone();
            tokio::spawn(async move {
                use futures_util::SinkExt;
                let Ok(ws) = tokio_tungstenite::accept_async(tcp).await else {
                    return;
                };
                let (mut tx, mut rx) = ws.split();
                let _ = rx.next().await;
                for m in [WELCOME, SNAPSHOT] {
                    let _ = tx
                        .send(tokio_tungstenite::tungstenite::Message::text(m))
                        .await;
                }
                while let Some(Ok(m)) = rx.next().await {
                    if let Some(a) = &arrived
                        && m.to_text().is_ok_and(|t| t.contains("\"type\":\"drag\""))
                    {
                        let _ = a.send(std::time::Instant::now());
                    }
                }
            });
        }
    });
    (rt, addr)
}

fn config(port: &str) -> Config {
    let mut tracker = DeviceConfig::new("tracker", DeviceKind::Flock);
    tracker.port = Some(port.into());
    tracker.settle_ms = 10;
    let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    glove.port = Some("/dev/null".into());
    let mut c = Config {
        devices: vec![tracker, glove],
        ..Default::default()
    };
    c.hands.push(HandConfig {
        name: "right".into(),
        tracker: "tracker".into(),
        sensor: 0,
        glove: Some("glove".into()),
        reach: 1.0,
        calibration: GloveCalibration::default(),
    });
    c
}

fn grab() -> Sample {
    Sample {
        source: SourceId(1),
        time: Timestamp::now(),
        reading: Reading::Glove(GloveValues::new(&glove_shape(22, 1.0, 1.0)).expect("glove")),
    }
}

fn per_sample(c: &mut Criterion) {
    let cfg = config("/dev/null");
    let s = FlockSettings::default();
    let records: Vec<Vec<u8>> = (0..1000)
        .map(|i| {
            encode_record(
                &pose_words(&s, DVec3::new(i as f64 * 1e-4, 0.0, 0.0), DQuat::IDENTITY),
                None,
                None,
            )
        })
        .collect();
    let mut interaction = Interaction::new(&cfg);
    interaction.set_icons([IconView {
        part: 1,
        id: 1,
        position: DVec3::ZERO,
        target: DVec3::ZERO,
        role: IconRole::Constraint,
        kind: IconKind::Position,
        state: IconState::Passive,
    }]);
    let mut cmds = Vec::new();
    interaction.handle(&grab(), &mut cmds);
    let mut decoder = build_decoder(SourceId(0), &cfg.devices[0]);
    let mut outbox = Outbox::new();
    let wire = ProtocolWire::default();
    let mut samples = Vec::new();
    let mut i = 0usize;
    c.bench_function("pipeline/record_to_encoded_drag", |b| {
        b.iter(|| {
            samples.clear();
            cmds.clear();
            decoder.feed(
                &records[i % records.len()],
                Timestamp(i as u64),
                &mut samples,
            );
            i += 1;
            for s in &samples {
                interaction.handle(s, &mut cmds);
            }
            for c in cmds.drain(..) {
                outbox.push(c);
            }
            for c in outbox.drain() {
                std::hint::black_box(wire.encode(&c.0, c.1));
            }
        })
    });
}

/// CPU time (user + system) of this process's threads whose names start with one of `prefixes`.
fn thread_cpu(prefixes: &[&str]) -> Duration {
    let tick = 100.0; // USER_HZ on Linux
    let mut total = 0.0;
    if let Ok(dir) = std::fs::read_dir("/proc/self/task") {
        for t in dir.flatten() {
            let Ok(stat) = std::fs::read_to_string(t.path().join("stat")) else {
                continue;
            };
            let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
                continue;
            };
            let name = &stat[open + 1..close];
            if !prefixes.iter().any(|p| name.starts_with(p)) {
                continue;
            }
            let fields: Vec<&str> = stat[close + 2..].split(' ').collect();
            // fields[11], fields[12] = utime, stime (fields 14 and 15 of stat)
            let ut: f64 = fields.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0);
            let st: f64 = fields.get(12).and_then(|v| v.parse().ok()).unwrap_or(0.0);
            total += (ut + st) / tick;
        }
    }
    Duration::from_secs_f64(total)
}

fn session_cpu(c: &mut Criterion) {
    let link = std::env::temp_dir().join(format!("vsculpt-bench-flock-{}", std::process::id()));
    let mut sim = FlockSim::new(1, false, Duration::from_millis(1));
    sim.set_pose(0, DVec3::new(0.01, 0.0, 0.0), DQuat::IDENTITY);
    let sim = PtySim::start(sim, &link).expect("pty");
    let (_sink_rt, addr) = sink(None);
    let mut cfg = config(&link.display().to_string());
    cfg.server.url = format!("ws://{addr}/ws?token=t");
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("bridge-rt")
        .enable_all()
        .build()
        .expect("bridge runtime");
    let (tx, rx) = mpsc::unbounded_channel::<Input>();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let cfg2 = cfg.clone();
    let engine = rt.spawn(async move {
        vsculpt_bridge::bridge::drive(&cfg2, Arc::new(ProtocolWire::default()), rx, async {
            let _ = stop_rx.await;
        })
        .await
    });
    let tx2 = tx.clone();
    let mut runner = DeviceRunner::spawn(
        Box::new(build_driver(SourceId(0), &cfg.devices[0])),
        RunOptions::default(),
        move |s| tx2.send(Input::Samples(s.to_vec())).is_ok(),
    );
    std::thread::sleep(Duration::from_millis(500));
    tx.send(Input::Samples(vec![grab()])).expect("grab");
    std::thread::sleep(Duration::from_millis(200));
    let mut g = c.benchmark_group("session");
    g.sample_size(10);
    g.bench_function("cpu_per_second_at_1khz", |b| {
        b.iter_custom(|iters| {
            let mut cpu = Duration::ZERO;
            for _ in 0..iters {
                let before = thread_cpu(&["device ", "bridge-rt"]);
                let samples0 = runner
                    .stats()
                    .samples
                    .load(std::sync::atomic::Ordering::Relaxed);
                std::thread::sleep(Duration::from_secs(1));
                let samples1 = runner
                    .stats()
                    .samples
                    .load(std::sync::atomic::Ordering::Relaxed);
                assert!(
                    samples1 - samples0 > 500,
                    "tracker rate too low: {}",
                    samples1 - samples0
                );
                cpu += thread_cpu(&["device ", "bridge-rt"]).saturating_sub(before);
            }
            cpu
        })
    });
    g.finish();
    let rate = runner
        .stats()
        .samples
        .load(std::sync::atomic::Ordering::Relaxed);
    eprintln!("samples delivered during the session: {rate}");
    runner.stop();
    let _ = stop_tx.send(());
    let _ = rt.block_on(engine);
    drop(sim);
}

/// Latency: a Flock record written on the pty master until the drag it causes
/// arrives, as a WebSocket message, at a server on loopback.
fn record_to_server(c: &mut Criterion) {
    use std::io::Write;
    let (mut master, slave) = serialport::TTYPort::pair().expect("pty");
    let port = serialport::SerialPort::name(&slave).expect("pty name");
    let (arrived_tx, arrived) = std::sync::mpsc::channel::<std::time::Instant>();
    let (_sink_rt, addr) = sink(Some(arrived_tx));
    let mut cfg = config(&port);
    cfg.server.url = format!("ws://{addr}/ws?token=t");
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .expect("bridge runtime");
    let (tx, rx) = mpsc::unbounded_channel::<Input>();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let cfg2 = cfg.clone();
    let engine = rt.spawn(async move {
        vsculpt_bridge::bridge::drive(&cfg2, Arc::new(ProtocolWire::default()), rx, async {
            let _ = stop_rx.await;
        })
        .await
    });
    // the driver without its set-up script: the bench plays the tracker itself
    let driver = vsculpt_bridge::device::Driver::new(
        "tracker",
        SourceId(0),
        Box::new(vsculpt_bridge::device::transport::SerialTransport::new(
            port.clone(),
            115_200,
        )),
        build_decoder(SourceId(0), &cfg.devices[0]),
        Default::default(),
    );
    let tx2 = tx.clone();
    let mut runner = DeviceRunner::spawn(
        Box::new(driver),
        RunOptions {
            silence: None,
            ..Default::default()
        },
        move |s| tx2.send(Input::Samples(s.to_vec())).is_ok(),
    );
    let s = FlockSettings::default();
    let record = |x: f64| {
        encode_record(
            &pose_words(&s, DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY),
            None,
            None,
        )
    };
    std::thread::sleep(Duration::from_millis(500));
    master.write_all(&record(0.0)).expect("write");
    std::thread::sleep(Duration::from_millis(100));
    tx.send(Input::Samples(vec![grab()])).expect("grab");
    std::thread::sleep(Duration::from_millis(200));
    while arrived.try_recv().is_ok() {}
    let mut i = 0u32;
    c.bench_function("latency/record_on_pty_to_server_message", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                i = i.wrapping_add(1);
                let rec = record(f64::from(i % 500) * 1e-4);
                let t = std::time::Instant::now();
                master.write_all(&rec).expect("write");
                let at = arrived
                    .recv_timeout(Duration::from_secs(2))
                    .expect("the drag reached the server");
                total += at.saturating_duration_since(t);
            }
            total
        })
    });
    runner.stop();
    let _ = stop_tx.send(());
    let _ = rt.block_on(engine);
    drop(slave);
}

criterion_group!(benches, per_sample, record_to_server, session_cpu);
criterion_main!(benches);
