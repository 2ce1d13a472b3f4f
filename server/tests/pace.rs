//! Paced delivery (`/ws?pace=1`, issue 16): a client's send rate matched to
//! what its link carries, as protocol/README.md ("Paced delivery") states it.
//!
//! The window's arithmetic against numbers worked by hand from the README's
//! rule, with times given (no sleeping); and over a real WebSocket, a paced
//! viewer that reports nothing while an editor drags gets no geometry past
//! its window (an unpaced client gets the drag's frames as they come), and
//! its first report brings exactly the latest frame, byte for byte the
//! editor's, the drag's intermediate frames skipped; the frame at rest
//! follows the next report.

mod common;

use common::http;
use common::ws::{Client, WAIT};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::GeometryFrame;
use vsculpt_server::ws::pace::{FLOOR, Pacer};

const MS: Duration = Duration::from_millis(1);

#[test]
fn before_any_report_the_window_is_the_floor_and_one_large_message_closes_it() {
    let t0 = Instant::now();
    let mut p = Pacer::new(t0);
    assert_eq!(p.window(), 32 * 1024);
    assert!(p.open());
    // A message larger than the window still goes (nothing was in flight) …
    p.on_sent(100_000, t0);
    assert_eq!(p.in_flight(), 100_000);
    // … and then nothing more until it is reported.
    assert!(!p.open());
    p.on_report(60_000, t0 + 50 * MS);
    assert_eq!(p.in_flight(), 40_000);
    assert!(
        !p.open(),
        "40,000 bytes in flight against a window of {}",
        p.window()
    );
}

#[test]
fn a_report_gives_the_rate_and_round_trip_and_the_window_is_twice_their_product() {
    let t0 = Instant::now();
    let mut p = Pacer::new(t0);
    // 100,000 bytes sent on an idle link at t0, reported whole at t0 + 100 ms:
    // round trip 100 ms, rate 100,000 B / 0.1 s = 1e6 B/s, window
    // 2 × 1e6 × 0.1 = 200,000 bytes.
    p.on_sent(100_000, t0);
    p.on_report(100_000, t0 + 100 * MS);
    assert_eq!(p.min_rtt(), Some(100 * MS));
    assert!(
        (p.rate().unwrap() / 1e6 - 1.0).abs() < 1e-9,
        "{:?}",
        p.rate()
    );
    assert!(p.window().abs_diff(200_000) <= 1, "{}", p.window());
    assert!(p.open());
    // Two messages back to back at t0 + 1 s (idle before: the first's clock
    // starts at its send); the second leaves with the first in flight, so
    // its sample runs from the report before it (t0 + 100 ms).
    let t1 = t0 + 1000 * MS;
    p.on_sent(50_000, t1);
    p.on_sent(50_000, t1);
    assert_eq!(p.in_flight(), 100_000);
    // Both reported at t1 + 50 ms: round trip 50 ms; the completed message is
    // the second, whose sample is 100,000 B over 0.95 s (a low one: the max
    // keeps 1e6).
    p.on_report(200_000, t1 + 50 * MS);
    assert_eq!(p.min_rtt(), Some(50 * MS));
    assert!((p.rate().unwrap() / 1e6 - 1.0).abs() < 1e-9);
    assert!(p.window().abs_diff(100_000) <= 1, "{}", p.window());
}

#[test]
fn reports_that_go_back_or_beyond_what_was_sent_cannot_widen_the_window() {
    let t0 = Instant::now();
    let mut p = Pacer::new(t0);
    p.on_sent(80_000, t0);
    p.on_report(40_000, t0 + 10 * MS);
    // Going back changes nothing.
    p.on_report(10_000, t0 + 20 * MS);
    assert_eq!(p.in_flight(), 40_000);
    // A report beyond what was sent counts as all of it, nothing more.
    p.on_report(u64::MAX, t0 + 40 * MS);
    assert_eq!(p.in_flight(), 0);
    p.on_sent(1, t0 + 50 * MS);
    assert_eq!(p.in_flight(), 1);
    assert_eq!(p.sent(), 80_001);
}

#[test]
fn the_rate_is_the_highest_of_the_last_four_seconds() {
    let t0 = Instant::now();
    let mut p = Pacer::new(t0);
    // 1e6 B/s measured at t0 + 100 ms.
    p.on_sent(100_000, t0);
    p.on_report(100_000, t0 + 100 * MS);
    // 1e5 B/s measured at t0 + 3.1 s (sent idle at t0 + 3 s): the max is
    // still the first sample.
    p.on_sent(10_000, t0 + 3000 * MS);
    p.on_report(110_000, t0 + 3100 * MS);
    assert!((p.rate().unwrap() / 1e6 - 1.0).abs() < 1e-9);
    // At t0 + 4.2 s the first sample is 4.1 s old and forgotten: 1e5 B/s.
    p.on_sent(10_000, t0 + 4100 * MS);
    p.on_report(120_000, t0 + 4200 * MS);
    assert!(
        (p.rate().unwrap() / 1e5 - 1.0).abs() < 1e-9,
        "{:?}",
        p.rate()
    );
    // Window 2 × 1e5 × 0.1 = 20,000: below the floor.
    assert_eq!(p.window(), FLOOR);
}

/// A raw viewer socket.
type Raw =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Reads one message: Ok(text as JSON) or Err(binary bytes).
async fn read(ws: &mut Raw) -> Result<Value, Vec<u8>> {
    loop {
        let m = tokio::time::timeout(WAIT, ws.next())
            .await
            .expect("no message within 10 s")
            .expect("closed")
            .expect("socket error");
        match m {
            Message::Text(t) => return Ok(serde_json::from_str(t.as_str()).unwrap()),
            Message::Binary(b) => return Err(b.to_vec()),
            _ => continue,
        }
    }
}

#[tokio::test]
async fn a_paced_viewer_gets_nothing_past_its_window_and_then_exactly_the_latest_frame() {
    let dir = data_dir("pace");
    let server = TestServer::start(dir.clone()).await;
    let d = server.demo().clone();
    let body = br#"{"name": "big", "nu": 81, "nv": 159}"#;
    let c = http::request(server.addr, "POST", "/api/designs", Some(&d.editor), body).await;
    assert_eq!(c.status, 201);
    let created = c.json();
    let id = created["id"].as_u64().unwrap();
    let editor_token = created["tokens"]["editor"].as_str().unwrap().to_string();
    let viewer_token = created["tokens"]["viewer"].as_str().unwrap().to_string();

    let mut ed = Client::connect(server.addr, id, &editor_token, "editor").await;
    let part = ed.snapshot["parts"][0]["id"].as_u64().unwrap();
    let first = ed.frame_of(part).await;
    // An unpaced viewer, for contrast, and the paced one (plain full frames:
    // 156 KB each, far over the 32 KiB window).
    let mut unpaced = Client::connect(server.addr, id, &viewer_token, "unpaced").await;
    assert_eq!(unpaced.frame_of(part).await.revision, first.revision);
    let mut ws = tokio_tungstenite::connect_async(format!("ws://{}/ws?pace=1", server.addr))
        .await
        .unwrap()
        .0;
    let hello = common::ws::hello(id, &viewer_token, "paced");
    ws.send(Message::text(hello.to_string())).await.unwrap();
    let mut received = 0u64;
    let mut frames = Vec::new();
    while frames.is_empty() {
        if let Err(b) = read(&mut ws).await {
            received += b.len() as u64;
            frames.push(GeometryFrame::decode(&b).unwrap());
        }
    }
    assert_eq!(frames[0].revision, first.revision);
    assert!(
        received > FLOOR,
        "the first frame ({received} bytes) fills the window"
    );

    // A drag of ten frames; the editor sees each.
    let created = ed
        .request(json!({"type": "create_icon", "part": part,
            "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}))
        .await;
    assert_eq!(created["type"], "ack", "{created}");
    let icon = created["icon"].as_u64().unwrap();
    ed.ok(json!({"type": "drag_start", "part": part, "icon": icon}))
        .await;
    let mut truth = first.clone();
    for k in 1..=10 {
        ed.send(
            json!({"type": "drag", "part": part, "icon": icon, "xyz": [0.5, 0.5, 0.05 * k as f64]}),
        )
        .await;
        truth = ed.frame_of_drag(part).await;
    }
    let last = truth.revision;
    // The unpaced viewer is sent the drag's frames as they come.
    let mut seen = 0;
    while unpaced.frame_of(part).await.revision < last {
        seen += 1;
    }
    assert!(
        seen >= 1,
        "the unpaced viewer skipped every frame of the drag"
    );
    // The paced viewer, which reported nothing: its answer to a ping comes
    // with no geometry before it (the writer answers in order after what it
    // already sent).
    ws.send(Message::text(json!({"type": "ping", "req": 1}).to_string()))
        .await
        .unwrap();
    loop {
        match read(&mut ws).await {
            Ok(v) if v["type"] == "pong" => break,
            Ok(_) => {}
            Err(b) => panic!(
                "a paced viewer that reported nothing got {} more bytes past its window",
                b.len()
            ),
        }
    }
    // It reports its first frame: the next frame is the latest, whole.
    ws.send(Message::text(
        json!({"type": "received", "bytes": received}).to_string(),
    ))
    .await
    .unwrap();
    let next = loop {
        if let Err(b) = read(&mut ws).await {
            received += b.len() as u64;
            break GeometryFrame::decode(&b).unwrap();
        }
    };
    assert_eq!(
        next.revision, last,
        "the frame after a report is the latest, not an intermediate one"
    );
    assert_eq!(next, truth);

    // The release: the frame at rest comes after the next report.
    ed.send(json!({"type": "drag_end", "part": part, "icon": icon}))
        .await;
    let rest = ed.frame_of_after(part, last).await;
    ws.send(Message::text(
        json!({"type": "received", "bytes": received}).to_string(),
    ))
    .await
    .unwrap();
    let at_rest = loop {
        if let Err(b) = read(&mut ws).await {
            let f = GeometryFrame::decode(&b).unwrap();
            if f.revision >= rest.revision {
                break f;
            }
        }
    };
    assert_eq!(
        at_rest, rest,
        "the paced viewer does not end on the editor's frame at rest"
    );

    // A `received` on an unpaced connection changes nothing and is acked.
    unpaced
        .ok(json!({"type": "received", "bytes": 12345}))
        .await;
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}
