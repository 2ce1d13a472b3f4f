//! SIGTERM stops the server binary cleanly whatever state its log reader and
//! clients are in: here the log pipe is stuck (its reader stays open but
//! never reads again, so the pipe fills and log lines are dropped) and one
//! client never reads nor answers the close. The process still ends with
//! exit 0 — the graceful path, not the deadline — and the uncommitted drag
//! is in the working state after a restart.

mod common;

use common::parts::load_icon;

use common::ChildServer;
use common::http::get;
use common::ws::Client;
use futures_util::SinkExt;
use serde_json::json;
use std::io::BufRead;
use std::process::Command;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

fn dropped(metrics: &str) -> f64 {
    metrics
        .lines()
        .find_map(|l| l.strip_prefix("vsculpt_log_lines_dropped_total "))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_stops_cleanly_with_a_stuck_log_pipe_and_a_silent_client() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let (reader, writer) = std::io::pipe().unwrap();
    let mut child = {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vsculpt-server"));
        cmd.args(["--listen", "127.0.0.1:0", "--data"])
            .arg(&data)
            .arg("--web-dir")
            .arg(data.join("no-web-client"))
            .env("RUST_LOG", "trace")
            .stdout(writer.try_clone().unwrap())
            .stderr(writer);
        cmd.spawn().unwrap()
    };
    // Read the banner, then never read again (the reader stays open).
    let mut reader = std::io::BufReader::new(reader);
    let mut banner = String::new();
    let mut lines = 0;
    while lines < 5 {
        let mut line = String::new();
        assert!(reader.read_line(&mut line).unwrap() > 0);
        if line.starts_with("vsculpt-server listening on ")
            || line.starts_with("web client: ")
            || line.starts_with("design ")
        {
            banner.push_str(&line);
            lines += 1;
        }
    }
    let (addr, designs) = common::parse_banner(&banner);
    let d = designs[0].clone();
    let admin = std::fs::read_to_string(data.join("admin-token")).unwrap();

    // A client that joins and then neither reads nor answers anything.
    let mut silent = common::ws::raw(addr).await;
    silent
        .send(Message::text(
            common::ws::hello(d.id, &d.viewer, "silent").to_string(),
        ))
        .await
        .unwrap();

    // An editor works until the stuck pipe has made the server drop lines.
    let mut ann = Client::connect(addr, d.id, &d.editor, "ann").await;
    let (icon, p) = load_icon(&ann.snapshot);
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    let mut z = p[2];
    let start = Instant::now();
    loop {
        for _ in 0..50 {
            z += 0.01;
            ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], z]}))
                .await;
        }
        let m = get(addr, "/metrics", Some(admin.trim())).await.text();
        if dropped(&m) > 0.0 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the stuck log pipe never made the server drop a line"
        );
    }
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    let working = get(addr, "/api/designs/1", Some(&d.editor)).await.json();

    sigterm(child.id());
    let status = wait_exit(&mut child, "the server did not exit on SIGTERM");
    assert_eq!(status.code(), Some(0), "{status:?}");
    drop((reader, silent, ann));

    let server = ChildServer::start(&data, 1);
    let after = get(server.addr, "/api/designs/1", Some(&d.editor))
        .await
        .json();
    assert_eq!(after["design"], working["design"]);
    assert!(server.terminate().success());
}

/// Sends SIGTERM to `pid`.
fn sigterm(pid: u32) {
    let ok = Command::new("kill")
        .args(["-15", &pid.to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// Waits up to 30 s for `child` to exit; kills it and panics with `why` if it does not.
fn wait_exit(child: &mut std::process::Child, why: &str) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("{why}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The server binary over `data` with design `hang`'s actor stuck at stop
/// (test-only `VSCULPT_FAULT_HANG_ON_STOP`), stderr as given: the child and
/// its stdout, read up to the end of its banner (the first five lines), and
/// the banner.
fn spawn_hanging(
    data: &std::path::Path,
    hang: u64,
    stderr: std::process::Stdio,
) -> (
    std::process::Child,
    std::io::BufReader<std::process::ChildStdout>,
    String,
) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vsculpt-server"))
        .args(["--listen", "127.0.0.1:0", "--data"])
        .arg(data)
        .arg("--web-dir")
        .arg(data.join("no-web-client"))
        .env("VSCULPT_FAULT_HANG_ON_STOP", hang.to_string())
        .stdout(std::process::Stdio::piped())
        .stderr(stderr)
        .spawn()
        .unwrap();
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut banner = String::new();
    for _ in 0..5 {
        assert!(out.read_line(&mut banner).unwrap() > 0);
    }
    (child, out, banner)
}

/// With the test-only `VSCULPT_FAULT_HANG_ON_STOP` (a `fault-injection`
/// build), design 2's actor never finishes its stop, as if stuck in a solve.
/// SIGTERM still ends the process — exit 1, saying some designs could not be
/// flushed — and design 1's uncommitted drag was flushed.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_ends_the_process_even_with_a_stuck_actor_flushing_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let (mut child, _out, banner) = spawn_hanging(&data, 2, std::process::Stdio::null());
    let (addr, designs) = common::parse_banner(&banner);
    let d = designs[0].clone();
    let admin = std::fs::read_to_string(data.join("admin-token")).unwrap();
    let created = common::http::request(
        addr,
        "POST",
        "/api/designs",
        Some(admin.trim()),
        br#"{"name": "lid", "nu": 8, "nv": 6}"#,
    )
    .await;
    assert_eq!(created.status, 201);
    let lid = created.json();
    let lid_editor = lid["tokens"]["editor"].as_str().unwrap().to_string();
    assert_eq!(lid["id"], 2);
    // Both designs have running actors; design 1 has an uncommitted drag.
    let _lid = Client::connect(addr, 2, &lid_editor, "bob").await;
    let mut ann = Client::connect(addr, d.id, &d.editor, "ann").await;
    let (icon, p) = load_icon(&ann.snapshot);
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 7.0]}))
        .await;
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    let working = get(addr, "/api/designs/1", Some(&d.editor)).await.json();

    sigterm(child.id());
    let status = wait_exit(
        &mut child,
        "a stuck actor kept the server from exiting on SIGTERM",
    );
    assert_eq!(status.code(), Some(1), "{status:?}");
    drop(ann);

    let server = ChildServer::start(&data, 2);
    let after = get(server.addr, "/api/designs/1", Some(&d.editor))
        .await
        .json();
    assert_eq!(after["design"], working["design"]);
    assert!(server.terminate().success());
}

/// A second SIGTERM ends a shutdown that is stuck (design 1's actor never
/// finishes its stop, test-only `VSCULPT_FAULT_HANG_ON_STOP`) at once: the
/// log says "second signal", not the deadline's "not finished in time",
/// and the exit code is the forced one (1). Told apart by what the server
/// says, not by timing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_sigterm_exits_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let (mut child, _out, banner) = spawn_hanging(&data, 1, std::process::Stdio::piped());
    // Every log line, as it comes.
    let (tx, rx) = std::sync::mpsc::channel::<String>();
    let err = std::io::BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || {
        for line in err.lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    let (addr, designs) = common::parse_banner(&banner);
    let d = designs[0].clone();
    let _ann = Client::connect(addr, d.id, &d.editor, "ann").await;
    sigterm(child.id());
    let mut log = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !log.iter().any(|l: &String| l.contains("shutting down")) {
        let line = rx
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            .expect("the server did not say it is shutting down");
        log.push(line);
    }
    sigterm(child.id());
    let status = wait_exit(&mut child, "the server did not exit on a second SIGTERM");
    while let Ok(line) = rx.recv_timeout(Duration::from_secs(2)) {
        log.push(line);
    }
    let log = log.join("\n");
    assert_eq!(status.code(), Some(1), "{status:?}\n{log}");
    assert!(log.contains("second signal: exiting now"), "{log}");
    assert!(!log.contains("not finished in time"), "{log}");
}
