//! Server latency and fan-out on loopback (harness = false; bounded loops,
//! 127.0.0.1 only). On an 81 × 159 bicubic design with one load icon:
//!
//! 0. join: `hello` sent → `snapshot` received (and → first geometry
//!    frame), p50 / p99 over 200 joins;
//! 1. drag → geometry frame at a second client: p50 / p99 / max over
//!    sequential drags (each waits for its frame); and drag → the dragging
//!    editor's own frame;
//! 2. bytes per geometry frame;
//! 3. viewers served at 60 frames per second: an editor drags at 60 Hz for
//!    3 s while N viewers read; the largest N at which every viewer gets at
//!    least 57 frames per second (server and clients share this machine's
//!    cores, so the figure is pessimistic);
//! 4. memory of a mesh export of a 400 × 400 bicubic design (imported as
//!    IGES): this process's resident set (server and client together)
//!    sampled every 5 ms during each STL / OBJ / glTF download and after.
//!
//! The clients are tokio-tungstenite with its defaults: Nagle on, and the
//! kernel's delayed ACKs — a client that does not ack early, as browsers
//! and most WebSocket libraries behave. Without TCP_NODELAY on the server a
//! second small write waits for that ACK (~40 ms on Linux).
//!
//! Run: `cargo bench -p vsculpt-server --bench latency`.

use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use std::net::SocketAddr;
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_server::config::Config;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn post(addr: SocketAddr, path: &str, token: &str, body: &str) -> serde_json::Value {
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!(
        "POST {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nAuthorization: Bearer {token}\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).await.unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).await.unwrap();
    let split = raw.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    serde_json::from_slice(&raw[split + 4..]).unwrap()
}

async fn connect(addr: SocketAddr, design: u64, token: &str, name: &str) -> Ws {
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    let hello = json!({"type": "hello", "protocol": vsculpt_protocol::PROTOCOL_VERSION, "token": token,
        "design": design, "client_name": name, "client_kind": "tool"});
    ws.send(Message::text(hello.to_string())).await.unwrap();
    // welcome, snapshot, first frame
    let mut got_frame = false;
    while !got_frame {
        match ws.next().await.unwrap().unwrap() {
            Message::Binary(_) => got_frame = true,
            Message::Text(t) => {
                let v: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
                assert_ne!(v["type"], "error", "{v}");
            }
            _ => {}
        }
    }
    ws
}

async fn next_frame(ws: &mut Ws) -> (Instant, vsculpt_protocol::GeometryFrame, usize) {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), ws.next())
            .await
            .unwrap()
            .unwrap()
            .unwrap();
        if let Message::Binary(b) = m {
            let t = Instant::now();
            return (
                t,
                vsculpt_protocol::GeometryFrame::decode(&b).unwrap(),
                b.len(),
            );
        }
    }
}

/// `n` joins of a viewer: ms from sending `hello` to the `snapshot` and to
/// the first geometry frame, each sorted.
async fn joins(addr: SocketAddr, id: u64, viewer: &str, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut to_snapshot = Vec::with_capacity(n);
    let mut to_frame = Vec::with_capacity(n);
    for k in 0..n {
        let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
            .await
            .unwrap();
        let hello = json!({"type": "hello", "protocol": vsculpt_protocol::PROTOCOL_VERSION,
            "token": viewer, "design": id, "client_name": format!("j{k}")});
        let t0 = Instant::now();
        ws.send(Message::text(hello.to_string())).await.unwrap();
        loop {
            match ws.next().await.unwrap().unwrap() {
                Message::Text(t) if t.as_str().contains("\"snapshot\"") => {
                    to_snapshot.push(t0.elapsed().as_secs_f64() * 1e3);
                }
                Message::Binary(_) => {
                    to_frame.push(t0.elapsed().as_secs_f64() * 1e3);
                    break;
                }
                _ => {}
            }
        }
        let _ = ws.close(None).await;
    }
    to_snapshot.sort_by(|x, y| x.partial_cmp(y).unwrap());
    to_frame.sort_by(|x, y| x.partial_cmp(y).unwrap());
    (to_snapshot, to_frame)
}

/// `n` drags by the editor `a` of `icon`, each waiting for its own frame
/// (revision above `after`): ms, sorted.
async fn own_frames(a: &mut Ws, icon: u64, after: u64, n: usize) -> Vec<f64> {
    let mut own = Vec::with_capacity(n);
    let mut last = after;
    for k in 0..n {
        let z = 5.0 * ((k % 40) as f64 / 40.0);
        let msg = json!({"type": "drag", "part": 1, "icon": icon, "xyz": [0.0, 0.0, z + 0.002 * k as f64]})
            .to_string();
        let t0 = Instant::now();
        a.send(Message::text(msg)).await.unwrap();
        loop {
            let (t1, f, _) = next_frame(a).await;
            if f.revision > last {
                last = f.revision;
                own.push((t1 - t0).as_secs_f64() * 1e3);
                break;
            }
        }
    }
    own.sort_by(|x, y| x.partial_cmp(y).unwrap());
    own
}

/// Starts a server over a fresh data dir with an 81 × 159 design, an editor
/// connection holding a load icon (grabbed) and the viewer token.
async fn bench_server(
    nodelay: bool,
    tag: &str,
) -> (
    SocketAddr,
    String,
    Shutdown,
    tokio::task::JoinHandle<()>,
    std::path::PathBuf,
    u64,
    String,
    Ws,
    u64,
) {
    let data = std::env::temp_dir().join(format!("vsculpt-bench-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&data);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut config = Config::new(data.clone(), data.join("no-web"));
    config.demo = false;
    config.tcp_nodelay = nodelay;
    // A 400 × 400 IGES file is about 16 MB.
    config.max_body_bytes = 64 << 20;
    let shutdown = Shutdown::new();
    let server = Server::start(listener, config, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let admin = server.admin_token().to_string();
    let task = tokio::spawn(async move {
        let _ = server.run().await;
    });
    let created = post(
        addr,
        "/api/designs",
        &admin,
        r#"{"name": "bench", "nu": 81, "nv": 159}"#,
    )
    .await;
    let id = created["id"].as_u64().unwrap();
    let editor = created["tokens"]["editor"].as_str().unwrap().to_string();
    let viewer = created["tokens"]["viewer"].as_str().unwrap().to_string();
    let mut a = connect(addr, id, &editor, "driver").await;
    let spec = json!({"type": "create_icon", "part": 1, "req": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}});
    a.send(Message::text(spec.to_string())).await.unwrap();
    let icon = loop {
        if let Message::Text(t) = a.next().await.unwrap().unwrap() {
            let v: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
            if v["type"] == "icon_created" {
                break v["icon"]["id"].as_u64().unwrap();
            }
        }
    };
    a.send(Message::text(
        json!({"type": "drag_start", "part": 1, "icon": icon}).to_string(),
    ))
    .await
    .unwrap();
    (addr, admin, shutdown, task, data, id, viewer, a, icon)
}

/// The same-run baseline: join and own-frame latency with TCP_NODELAY off
/// on the server (the code before this change).
async fn nagle_baseline() {
    let (addr, _admin, shutdown, task, data, id, viewer, mut a, icon) =
        bench_server(false, "nagle").await;
    let (snap, frame) = joins(addr, id, &viewer, 50).await;
    let own = own_frames(&mut a, icon, 0, 100).await;
    println!(
        "baseline without TCP_NODELAY: join hello -> snapshot p50 {:.3} ms, p99 {:.3} ms; -> first frame p50 {:.3} ms, p99 {:.3} ms (50 joins); own frame p50 {:.3} ms, p99 {:.3} ms (100 drags)",
        percentile(&snap, 0.5),
        percentile(&snap, 0.99),
        percentile(&frame, 0.5),
        percentile(&frame, 0.99),
        percentile(&own, 0.5),
        percentile(&own, 0.99)
    );
    drop(a);
    shutdown.trigger();
    let _ = task.await;
    let _ = std::fs::remove_dir_all(&data);
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

async fn run() {
    nagle_baseline().await;
    let (addr, admin, shutdown, task, data, id, viewer, mut a, icon) =
        bench_server(true, "main").await;
    let mut b = connect(addr, id, &viewer, "watcher").await;
    // `connect` read b's first frame; every frame from here on is new.
    let mut last_rev = 0;

    // 0: joins.
    let (to_snapshot, to_frame) = joins(addr, id, &viewer, 200).await;
    println!(
        "join: hello -> snapshot p50 {:.3} ms, p99 {:.3} ms; hello -> first frame p50 {:.3} ms, p99 {:.3} ms (200 joins)",
        percentile(&to_snapshot, 0.5),
        percentile(&to_snapshot, 0.99),
        percentile(&to_frame, 0.5),
        percentile(&to_frame, 0.99)
    );

    // 1 + 2: sequential drag → frame latency.
    let n = 1000;
    let mut lat = Vec::with_capacity(n);
    let mut bytes = 0;
    for k in 0..n {
        let z = 5.0 * ((k % 40) as f64 / 40.0);
        let msg = json!({"type": "drag", "part": 1, "icon": icon, "xyz": [0.0, 0.0, z + 0.001 * k as f64]})
            .to_string();
        let t0 = Instant::now();
        a.send(Message::text(msg)).await.unwrap();
        loop {
            let (t1, f, len) = next_frame(&mut b).await;
            if f.revision > last_rev {
                last_rev = f.revision;
                lat.push((t1 - t0).as_secs_f64() * 1e3);
                bytes = len;
                break;
            }
        }
    }
    // Drain a's frames/feedback so its socket does not back up.
    let drain = tokio::spawn(async move {
        while let Ok(Some(Ok(_))) = tokio::time::timeout(Duration::from_millis(500), a.next()).await
        {
        }
        a
    });
    let mut a = drain.await.unwrap();
    lat.sort_by(|x, y| x.partial_cmp(y).unwrap());
    println!(
        "design 81 x 159 ({} control points), {} sequential drags",
        81 * 159,
        n
    );
    println!(
        "drag -> frame at a second client: p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        percentile(&lat, 0.5),
        percentile(&lat, 0.99),
        lat[lat.len() - 1]
    );
    println!("bytes per geometry frame: {bytes}");
    drop(b);

    // 1b: the dragging editor's own frame.
    let own = own_frames(&mut a, icon, last_rev, n).await;
    println!(
        "drag -> the editor's own frame: p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        percentile(&own, 0.5),
        percentile(&own, 0.99),
        own[own.len() - 1]
    );

    // 3: viewers at 60 fps.
    let mut best = 0;
    for viewers in [10usize, 25, 50, 75, 100, 150] {
        let mut tasks = Vec::new();
        for k in 0..viewers {
            let mut ws = connect(addr, id, &viewer, &format!("v{k}")).await;
            tasks.push(tokio::spawn(async move {
                let mut frames = 0u64;
                let end = Instant::now() + Duration::from_millis(3500);
                loop {
                    let left = end.saturating_duration_since(Instant::now());
                    match tokio::time::timeout(left, ws.next()).await {
                        Ok(Some(Ok(Message::Binary(_)))) => frames += 1,
                        Ok(Some(Ok(_))) => {}
                        _ => break,
                    }
                }
                frames
            }));
        }
        tokio::time::sleep(Duration::from_millis(300)).await;
        let mut tick = tokio::time::interval(Duration::from_micros(16_667));
        let t0 = Instant::now();
        for k in 0..180 {
            tick.tick().await;
            let msg =
                json!({"type": "drag", "part": 1, "icon": icon, "xyz": [0.0, 0.0, 3.0 + 0.01 * k as f64]})
                    .to_string();
            a.send(Message::text(msg)).await.unwrap();
        }
        let secs = t0.elapsed().as_secs_f64();
        let mut counts = Vec::new();
        for t in tasks {
            counts.push(t.await.unwrap());
        }
        counts.sort_unstable();
        let min_fps = counts[0] as f64 / secs;
        let median_fps = counts[counts.len() / 2] as f64 / secs;
        println!(
            "{viewers:>4} viewers: frames per viewer per second min {min_fps:.1}, median {median_fps:.1} (driver sent 180 drags in {secs:.2} s)"
        );
        if min_fps >= 57.0 {
            best = viewers;
        } else {
            break;
        }
        while let Ok(Some(Ok(_))) = tokio::time::timeout(Duration::from_millis(300), a.next()).await
        {
        }
    }
    println!("viewers served at 60 fps (every viewer >= 57 frames/s): {best}");

    // 4: export memory at 400 x 400.
    export_memory(addr, &admin).await;
    shutdown.trigger();
    let _ = task.await;
    let _ = std::fs::remove_dir_all(&data);
}

/// This process's resident set size in MiB (Linux).
fn rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1).map(str::to_owned))
        })
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// Downloads `path`, counting bytes without keeping them.
async fn download(addr: SocketAddr, path: &str, token: &str) -> usize {
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!(
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nAuthorization: Bearer {token}\r\n\r\n"
    );
    s.write_all(req.as_bytes()).await.unwrap();
    let mut buf = vec![0u8; 1 << 16];
    let mut total = 0;
    loop {
        let n = s.read(&mut buf).await.unwrap();
        if n == 0 {
            return total;
        }
        total += n;
    }
}

async fn export_memory(addr: SocketAddr, admin: &str) {
    use vsculpt_server::cad::{IgesMeta, IgesSurface, write_iges};
    let n = 400;
    let knots = |n: usize| {
        let mut k = vec![0.0; 4];
        k.extend((1..n - 3).map(|s| s as f64 / (n - 3) as f64));
        k.extend([1.0; 4]);
        k
    };
    let mut points = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            points.push(glam::DVec3::new(
                100.0 * x,
                100.0 * y,
                10.0 * (6.0 * x).sin() * (4.0 * y).cos(),
            ));
        }
    }
    let surface = IgesSurface {
        u_degree: 3,
        v_degree: 3,
        u_knots: knots(n),
        v_knots: knots(n),
        nu: n,
        nv: n,
        points,
    };
    let igs = write_iges(&surface, &IgesMeta::now("big", "bench")).unwrap();
    drop(surface);
    let created = post(addr, "/api/designs", admin, r#"{"name": "big"}"#).await;
    let id = created["id"].as_u64().unwrap();
    let t = Instant::now();
    // `?part=1`: the surface replaces the new design's plate (part 1), so
    // the design is the 400 × 400 surface alone (without it, the file's
    // surface would be added beside the plate as a new part).
    let r = post(
        addr,
        &format!("/api/designs/{id}/import?part=1"),
        admin,
        &igs,
    )
    .await;
    assert!(r.get("error").is_none(), "{r}");
    assert_eq!(r["parts"], json!([1]), "{r}");
    println!(
        "400 x 400 IGES import ({} bytes): {:.2} s",
        igs.len(),
        t.elapsed().as_secs_f64()
    );
    drop(igs);
    let before = rss_mib();
    for ext in ["stl", "obj", "gltf"] {
        let peak = std::sync::Arc::new(std::sync::Mutex::new(0.0f64));
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let sampler = {
            let (peak, stop) = (peak.clone(), stop.clone());
            std::thread::spawn(move || {
                while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                    let r = rss_mib();
                    let mut p = peak.lock().unwrap();
                    *p = p.max(r);
                    drop(p);
                    std::thread::sleep(Duration::from_millis(5));
                }
            })
        };
        let t = Instant::now();
        let bytes = download(addr, &format!("/api/designs/{id}/export.{ext}"), admin).await;
        let secs = t.elapsed().as_secs_f64();
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        sampler.join().unwrap();
        tokio::time::sleep(Duration::from_millis(200)).await;
        println!(
            "export.{ext} of 400 x 400: {:.1} MB in {secs:.2} s; RSS before {before:.0} MiB, peak {:.0} MiB, after {:.0} MiB",
            bytes as f64 / 1e6,
            *peak.lock().unwrap(),
            rss_mib()
        );
    }
}

fn main() {
    // `cargo test --benches` runs benches with --bench absent; only measure
    // when asked to.
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(run());
}
