//! What an online backup costs the editors (issue 21): an editor drags an
//! 81 × 159 design and commits at full rate through the real server on
//! loopback, first alone, then while `vsculpt-server backup`'s code
//! (`store::backup::backup`: SQLite's online backup API in paced slices from
//! one read transaction, then an integrity check of the copy) runs back to
//! back in another thread. Reported for both phases in the same run: drag →
//! the editor's `icon_feedback` and commit → `ack` latency (p50 / p99 /
//! max), the largest `vsculpt.db-wal` seen after an ack, and the backups'
//! count, duration and size. The store holds 40 committed versions of the
//! design first (≈ 0.6 MB each), so a backup copies tens of MB.
//!
//! Run: `cargo bench -p vsculpt-server --bench backup_pause` (with
//! `VSCULPT_BENCH_TRACE=1`: the store's per-commit and per-checkpoint debug
//! events on stderr, and a line per ack and per backup).

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_server::config::Config;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn next_text(ws: &mut Ws) -> Value {
    loop {
        if let Message::Text(t) = ws.next().await.unwrap().unwrap() {
            return serde_json::from_str(t.as_str()).unwrap();
        }
    }
}

async fn until(ws: &mut Ws, f: impl Fn(&Value) -> bool) -> Value {
    loop {
        let v = next_text(ws).await;
        if f(&v) {
            return v;
        }
    }
}

fn pct(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// What one phase measured.
#[derive(Default)]
struct Phase {
    /// Drag → feedback, ms.
    drags: Vec<f64>,
    /// Commit → ack, ms.
    commits: Vec<f64>,
    /// The largest WAL file seen after an ack, bytes.
    wal_max: u64,
}

/// `n` rounds of a drag frame (waiting for its feedback) with a commit
/// every fifth round.
async fn editor_rounds(ws: &mut Ws, icon: u64, n: usize, req: &mut u64, wal: &Path) -> Phase {
    let mut phase = Phase::default();
    for k in 0..n {
        let z = 2.0 + (k % 20) as f64 * 0.25;
        let t0 = Instant::now();
        ws.send(Message::text(
            json!({"type": "drag", "part": 1, "icon": icon, "xyz": [0.0, 0.0, z]}).to_string(),
        ))
        .await
        .unwrap();
        until(ws, |v| v["type"] == "icon_feedback").await;
        phase.drags.push(t0.elapsed().as_secs_f64() * 1e3);
        if k % 5 == 4 {
            *req += 1;
            let r = *req;
            let t0 = Instant::now();
            ws.send(Message::text(
                json!({"type": "commit", "req": r, "message": format!("round {k}")}).to_string(),
            ))
            .await
            .unwrap();
            let a = until(ws, |v| v["req"] == r).await;
            assert_eq!(a["type"], "ack", "{a}");
            tracing::debug!(target: "vsculpt_server::store::bench", ms = t0.elapsed().as_secs_f64() * 1e3, "ack");
            phase.commits.push(t0.elapsed().as_secs_f64() * 1e3);
            let len = std::fs::metadata(wal).map_or(0, |m| m.len());
            phase.wal_max = phase.wal_max.max(len);
        }
    }
    phase
}

async fn run() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let wal = data.join("vsculpt.db-wal");
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut config = Config::new(data.clone(), data.join("no-web"));
    config.demo = false;
    let shutdown = Shutdown::new();
    let server = Server::start(listener, config, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let admin = server.admin_token().to_string();
    let task = tokio::spawn(async move {
        let _ = server.run().await;
    });
    let created: Value = {
        let body = r#"{"name": "bench", "nu": 81, "nv": 159}"#;
        let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let req = format!(
            "POST /api/designs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer {admin}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            body.len()
        );
        s.write_all(req.as_bytes()).await.unwrap();
        let mut out = String::new();
        s.read_to_string(&mut out).await.unwrap();
        serde_json::from_str(out.split("\r\n\r\n").nth(1).unwrap()).unwrap()
    };
    let id = created["id"].as_u64().unwrap();
    let editor = created["tokens"]["editor"].as_str().unwrap();
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    ws.send(Message::text(
        json!({"type": "hello", "protocol": vsculpt_protocol::PROTOCOL_VERSION, "token": editor, "design": id, "client_name": "bench"}).to_string(),
    ))
    .await
    .unwrap();
    until(&mut ws, |v| v["type"] == "snapshot").await;
    ws.send(Message::text(json!({"type": "create_icon", "part": 1, "req": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}).to_string())).await.unwrap();
    let icon = until(&mut ws, |v| v["req"] == 1).await["icon"]
        .as_u64()
        .unwrap();
    let mut req = 1;
    // 40 versions first, so a backup has something to copy.
    editor_rounds(&mut ws, icon, 200, &mut req, &wal).await;
    let db_bytes = std::fs::metadata(data.join("vsculpt.db")).map_or(0, |m| m.len());

    let mut alone = editor_rounds(&mut ws, icon, 300, &mut req, &wal).await;

    let stop = Arc::new(AtomicBool::new(false));
    let backups = {
        let (stop, data) = (stop.clone(), data.clone());
        std::thread::spawn(move || {
            let mut took = Vec::new();
            let out = data.with_file_name("backup.db");
            while !stop.load(Ordering::Relaxed) {
                let t0 = Instant::now();
                tracing::debug!(target: "vsculpt_server::store::bench", "backup begins");
                vsculpt_server::store::backup::backup(&data, &out, true).unwrap();
                tracing::debug!(target: "vsculpt_server::store::bench", "backup ends");
                took.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            let size = std::fs::metadata(&out).map_or(0, |m| m.len());
            let _ = std::fs::remove_file(&out);
            (took, size)
        })
    };
    let mut busy = editor_rounds(&mut ws, icon, 300, &mut req, &wal).await;
    stop.store(true, Ordering::Relaxed);
    let (mut took, size) = backups.join().unwrap();

    println!("store before the phases: {:.1} MB", db_bytes as f64 / 1e6);
    for (name, p) in [("alone", &mut alone), ("backups running", &mut busy)] {
        let (d, c) = (&mut p.drags, &mut p.commits);
        println!(
            "{name:>16}: drag -> feedback p50 {:.2} ms p99 {:.2} ms max {:.2} ms ({} drags); commit -> ack p50 {:.2} ms p99 {:.2} ms max {:.2} ms ({} commits); WAL up to {:.1} MB",
            pct(d, 0.5),
            pct(d, 0.99),
            pct(d, 1.0),
            d.len(),
            pct(c, 0.5),
            pct(c, 0.99),
            pct(c, 1.0),
            c.len(),
            p.wal_max as f64 / 1e6
        );
    }
    println!(
        "backups during the second phase: {} of {:.1} MB, each p50 {:.0} ms, max {:.0} ms",
        took.len(),
        size as f64 / 1e6,
        pct(&mut took, 0.5),
        pct(&mut took, 1.0)
    );
    drop(ws);
    shutdown.trigger();
    let _ = tokio::time::timeout(Duration::from_secs(10), task).await;
}

fn main() {
    // `VSCULPT_BENCH_TRACE=1`: the store's debug events (each commit's lock,
    // write and commit times; each checkpoint's frames and time) on stderr.
    if std::env::var_os("VSCULPT_BENCH_TRACE").is_some() {
        tracing_subscriber::fmt()
            .with_env_filter("vsculpt_server::store=debug")
            .with_writer(std::io::stderr)
            .init();
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(run());
}
