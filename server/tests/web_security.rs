//! Hostile web pages and local users are kept out: `/ws` and the REST API
//! refuse a foreign `Origin` (and `null`) but serve the server's own pages,
//! configured origins and programs that send none; every answer carries
//! `Referrer-Policy: no-referrer`; API errors are JSON even when axum's own
//! extractors refuse; the data directory is 0700 and the database files
//! 0600.

mod common;

use common::TestServer;
use common::http::{self, get};
use common::ws::Client;
use futures_util::SinkExt;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

/// Opens `/ws` with an `Origin` header: the HTTP status of the handshake.
async fn ws_status(addr: std::net::SocketAddr, origin: &str) -> u16 {
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    req.headers_mut().insert("origin", origin.parse().unwrap());
    match tokio_tungstenite::connect_async(req).await {
        Ok((mut ws, resp)) => {
            let _ = ws.send(Message::Close(None)).await;
            resp.status().as_u16()
        }
        Err(tokio_tungstenite::tungstenite::Error::Http(resp)) => resp.status().as_u16(),
        Err(e) => panic!("{e}"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn foreign_origins_are_refused() {
    let data = common::data_dir("origin");
    let web = data.join("no-web-client");
    let server = TestServer::start_configured(data, web, |c| {
        c.allowed_origins = vec!["https://review.example".into()]
    })
    .await;
    let addr = server.addr;
    let d = server.demo().clone();
    let own = format!("http://{addr}");
    // WebSocket handshakes.
    assert_eq!(ws_status(addr, "http://evil.example").await, 403);
    assert_eq!(ws_status(addr, "null").await, 403);
    assert_eq!(
        ws_status(addr, &format!("http://{addr}.evil.example")).await,
        403
    );
    assert_eq!(ws_status(addr, &own).await, 101);
    assert_eq!(ws_status(addr, "https://review.example").await, 101);
    // No Origin (the bridge, scripts): served, the token still decides.
    Client::connect(addr, d.id, &d.viewer, "script")
        .await
        .ping()
        .await;

    // REST, with a valid token.
    let path = format!("/api/designs/{}", d.id);
    for origin in ["http://evil.example", "null"] {
        let r = http::request_with(
            addr,
            "GET",
            &path,
            Some(&d.editor),
            &[("Origin", origin)],
            b"",
        )
        .await;
        assert_eq!(r.status, 403, "{origin}");
        assert_eq!(r.json()["error"]["code"], "forbidden");
        let r = http::request_with(
            addr,
            "POST",
            "/api/designs",
            Some(&server.admin),
            &[("Origin", origin)],
            br#"{"name": "planted"}"#,
        )
        .await;
        assert_eq!(r.status, 403, "{origin}");
    }
    let r = http::request_with(
        addr,
        "GET",
        &path,
        Some(&d.editor),
        &[("Origin", &own)],
        b"",
    )
    .await;
    assert_eq!(r.status, 200);
    let r = get(addr, "/api/designs", Some(&server.admin)).await;
    assert_eq!(
        r.json()["designs"].as_array().unwrap().len(),
        1,
        "nothing was created"
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn answers_send_no_referrer_and_errors_are_json() {
    let server = TestServer::start(common::data_dir("referrer")).await;
    let d = server.demo().clone();
    for path in [
        "/",
        "/healthz",
        "/api/designs",
        "/api/designs/1",
        "/nope.js",
    ] {
        let r = get(server.addr, path, Some(&d.viewer)).await;
        assert_eq!(r.header("referrer-policy"), Some("no-referrer"), "{path}");
    }
    // Refusals by axum's extractors, not by our handlers.
    let cases: [(&str, &str, &[u8], u16, &str); 3] = [
        ("GET", "/api/designs/abc", b"", 400, "malformed"),
        ("DELETE", "/api/designs/1", b"", 405, "unknown_message"),
        ("GET", "/ws", b"", 400, "malformed"),
    ];
    for (method, path, body, status, code) in cases {
        let r = http::request(server.addr, method, path, Some(&d.editor), body).await;
        assert_eq!(r.status, status, "{method} {path}: {}", r.text());
        assert!(
            r.header("content-type")
                .unwrap()
                .starts_with("application/json"),
            "{method} {path}"
        );
        assert_eq!(r.json()["error"]["code"], code, "{method} {path}");
        assert!(!r.json()["error"]["message"].as_str().unwrap().is_empty());
    }
    // A body one byte over the 16 MiB limit (all of it is read before the
    // refusal, so the answer arrives cleanly).
    let big = vec![b'x'; (16 << 20) + 1];
    let p = format!("/api/designs/{}/import", d.id);
    let r = http::request(server.addr, "POST", &p, Some(&d.editor), &big).await;
    assert_eq!(r.status, 413);
    assert_eq!(r.json()["error"]["code"], "too_large");
    server.stop().await;
}

#[cfg(unix)]
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_data_directory_is_private() {
    use std::os::unix::fs::PermissionsExt;
    let data = common::data_dir("private");
    let server = TestServer::start(data.clone()).await;
    // A commit makes sure the WAL exists.
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    c.ok(serde_json::json!({"type": "commit", "message": "wal"}))
        .await;
    let mode = |name: &str| {
        std::fs::metadata(data.join(name))
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .permissions()
            .mode()
            & 0o777
    };
    assert_eq!(mode(""), 0o700);
    assert_eq!(mode("vsculpt.db"), 0o600);
    assert_eq!(mode("vsculpt.db-wal"), 0o600);
    assert_eq!(mode("admin-token"), 0o600);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
