//! Per-client rate limits on `/ws` (protocol/README.md, "Limits"): a client
//! that floods control messages gets `rate_limited` errors carrying the
//! refused request's `req`, those errors are themselves limited, and the
//! connection stays up and works again once the client slows down; drag
//! frames have their own, larger budget, so a dragging editor sending far
//! more frames than the control burst is never refused.

mod common;

use common::TestServer;
use common::parts::{SHELL, load_icon};
use common::ws::{Client, Got};
use futures_util::SinkExt;
use serde_json::{Value, json};
use std::collections::BTreeSet;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::limits::{CONTROL_BURST, CONTROL_RATE, STREAM_BURST};

/// Sends every message without waiting for replies.
async fn flood(c: &mut Client, msgs: impl IntoIterator<Item = Value>) {
    for m in msgs {
        c.ws.feed(Message::text(m.to_string())).await.unwrap();
    }
    c.ws.flush().await.unwrap();
}

/// Reads text messages until a `pong` with `req` arrives; the messages
/// before it.
async fn until_pong(c: &mut Client, req: u64) -> Vec<Value> {
    let mut out = Vec::new();
    loop {
        match c.next().await {
            Got::Text(v) if v["type"] == "pong" && v["req"] == json!(req) => return out,
            Got::Text(v) => out.push(v),
            Got::Frame(_) | Got::Mesh(_) => {}
            Got::Closed => panic!("the server closed a rate-limited connection"),
        }
    }
}

/// Waits long enough for the control bucket to refill completely, then
/// pings until one is answered: the replies that came before.
async fn settle(c: &mut Client, req: u64) -> Vec<Value> {
    let refill = Duration::from_secs_f64(f64::from(CONTROL_BURST) / f64::from(CONTROL_RATE));
    tokio::time::sleep(refill + Duration::from_millis(200)).await;
    c.send(json!({"type": "ping", "req": req})).await;
    until_pong(c, req).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flood_is_answered_rate_limited_and_the_connection_survives() {
    let server = TestServer::start(common::data_dir("rate-flood")).await;
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.viewer, "flooder").await;
    let n = 1000u64;
    flood(
        &mut c,
        (1..=n).map(|req| json!({"type": "ping", "req": req})),
    )
    .await;
    let got = settle(&mut c, 1_000_000).await;

    let pongs: BTreeSet<u64> = got
        .iter()
        .filter(|v| v["type"] == "pong")
        .map(|v| v["req"].as_u64().unwrap())
        .collect();
    let limited: Vec<&Value> = got
        .iter()
        .filter(|v| v["type"] == "error" && v["code"] == "rate_limited")
        .collect();
    assert!(
        pongs.len() >= CONTROL_BURST as usize,
        "a burst within the limit was refused: {} pongs",
        pongs.len()
    );
    assert!(
        (pongs.len() as u64) < n,
        "{n} pings at once were all answered: no rate limit"
    );
    assert!(!limited.is_empty(), "no rate_limited error came back");
    for e in &limited {
        let req = e["req"].as_u64().expect("rate_limited carries the req");
        assert!((1..=n).contains(&req) && !pongs.contains(&req), "{e}");
        assert!(e["message"].as_str().unwrap().contains("slow down"), "{e}");
    }
    let refused = n as usize - pongs.len();
    assert!(
        limited.len() < refused,
        "one error per refused message ({refused}): errors are not rate-limited"
    );
    let replies: Vec<&Value> = got.iter().filter(|v| v.get("req").is_some()).collect();
    assert_eq!(
        replies.len(),
        pongs.len() + limited.len(),
        "unexpected replies: {replies:?}"
    );

    // Slowed down, the client is served normally on the same connection.
    for k in 0..5 {
        c.send(json!({"type": "list_versions", "req": 2_000_000 + k}))
            .await;
        let v = c.wait_for("versions").await;
        assert_eq!(v["req"], json!(2_000_000 + k));
    }
    let m = common::http::get(server.addr, "/metrics", Some(&server.admin))
        .await
        .text();
    let line = m
        .lines()
        .find(|l| l.starts_with("vsculpt_rate_limited_total "))
        .unwrap_or_else(|| panic!("no vsculpt_rate_limited_total in {m}"));
    assert_eq!(line, format!("vsculpt_rate_limited_total {refused}"));
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dragging_editor_is_not_held_to_the_control_limit() {
    let server = TestServer::start(common::data_dir("rate-drag")).await;
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "dragger").await;
    let (icon, xyz) = load_icon(&c.snapshot);
    c.send(json!({"type": "drag_start", "part": SHELL, "icon": icon, "req": 1}))
        .await;
    // Three times the control burst of drag frames at once (a 3D mouse
    // catching up after a stall), well within the drag budget.
    let frames = 3 * CONTROL_BURST;
    assert!(frames < STREAM_BURST);
    flood(
        &mut c,
        (0..frames).map(|k| {
            let z = xyz[2] + 0.001 * f64::from(k % 50);
            json!({"type": "drag", "part": SHELL, "icon": icon, "xyz": [xyz[0], xyz[1], z]})
        }),
    )
    .await;
    c.send(json!({"type": "drag_end", "part": SHELL, "icon": icon, "req": 2}))
        .await;
    c.send(json!({"type": "ping", "req": 3})).await;
    let got = until_pong(&mut c, 3).await;
    let errors: Vec<&Value> = got.iter().filter(|v| v["type"] == "error").collect();
    assert!(errors.is_empty(), "drag frames were refused: {errors:?}");
    let acks: Vec<u64> = got
        .iter()
        .filter(|v| v["type"] == "ack")
        .map(|v| v["req"].as_u64().unwrap())
        .collect();
    assert_eq!(acks, vec![1, 2]);
    server.stop().await;
}
