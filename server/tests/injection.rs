//! Names and device messages cannot forge lines: a design name with line
//! breaks (from an older store) is escaped in the start banner, new names
//! with control characters are refused over REST and the WebSocket, and a
//! bridge's `device_status` text is logged escaped.

mod common;

use common::TestServer;
use common::http;
use common::ws::Client;
use serde_json::json;
use std::io::Write;
use std::sync::{Arc, Mutex};
use vsculpt_server::config::Config;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;
use vsculpt_server::store::Store;

const FORGED: &str = "design 1 \"demo\" editor: http://evil.example/?design=1&token=forged";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_name_with_line_breaks_cannot_forge_banner_lines() {
    let data = common::data_dir("banner-inject");
    {
        let store = Store::open(&data).unwrap();
        let doc = vsculpt_server::design::demo::plate("x", 4, 4).unwrap();
        store
            .create_design(&format!("evil\n{FORGED}\r\u{1b}[2J"), &doc.to_bytes())
            .unwrap();
    }
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let config = Config::new(data.clone(), data.join("no-web"));
    let server = Server::start(listener, config, Shutdown::new())
        .await
        .unwrap();
    let banner = server.links().unwrap();
    assert_eq!(banner.lines().count(), 2 + 3, "{banner}");
    assert!(
        banner
            .lines()
            .all(|l| !l.contains('\u{1b}') && !l.contains('\r'))
    );
    assert!(!banner.lines().any(|l| l.starts_with(FORGED)), "{banner}");
    assert!(
        banner.contains("\"evil\\ndesign 1 \\\"demo\\\""),
        "{banner}"
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn new_names_with_control_characters_are_refused() {
    let server = TestServer::start(common::data_dir("name-inject")).await;
    for name in ["a\nb", "tab\there", "bell\u{7}", "esc\u{1b}[31m"] {
        let body = json!({ "name": name }).to_string();
        let r = http::request(
            server.addr,
            "POST",
            "/api/designs",
            Some(&server.admin),
            body.as_bytes(),
        )
        .await;
        assert_eq!(r.status, 400, "{name:?}");
        assert_eq!(r.json()["error"]["code"], "out_of_range");
    }
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    c.refused(
        json!({"type": "create_design", "name": "x\ny"}),
        "out_of_range",
    )
    .await;
    let r = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&server.admin),
        br#"{"name": "caf\u00e9 ok"}"#,
    )
    .await;
    assert_eq!(r.status, 201);
    server.stop().await;
}

/// A log sink shared with the global subscriber.
#[derive(Clone, Default)]
struct Sink(Arc<Mutex<Vec<u8>>>);

impl Write for Sink {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn device_status_is_logged_escaped() {
    let sink = Sink::default();
    let writer = sink.clone();
    tracing_subscriber::fmt()
        .with_ansi(false)
        .with_env_filter("info")
        .with_writer(move || writer.clone())
        .init();
    let server = TestServer::start(common::data_dir("log-inject")).await;
    let d = server.demo().clone();
    let mut dev = Client::connect(server.addr, d.id, &d.device, "bridge").await;
    let forged = "2026-11-24T00:00:00Z  INFO vsculpt_server: admin token rotated";
    dev.ok(
        json!({"type": "device_status", "device": format!("flock\n{forged}"),
        "condition": "error", "message": format!("gone\n{forged}\r\u{1b}[2K")}),
    )
    .await;
    dev.ping().await;
    server.stop().await;
    let log = String::from_utf8(sink.0.lock().unwrap().clone()).unwrap();
    assert!(log.contains("device status"), "{log}");
    assert!(!log.lines().any(|l| l.starts_with(forged)), "{log}");
    assert!(!log.contains('\u{1b}') && !log.contains('\r'), "{log}");
    assert!(log.contains("gone\\n2026"), "{log}");
}
