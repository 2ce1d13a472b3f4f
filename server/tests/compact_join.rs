//! The compact join (issue 18): a hello with `geometry_first` gets, after
//! its welcome, the shape as one binary frame flagged FLAG_SNAPSHOT, then a
//! snapshot whose `surface.points` is empty — and later snapshots (undo,
//! revert, restore) also come without points, since frames carry the
//! shape. A hello without it joins as before. The frame's header is read
//! from the raw bytes at the offsets protocol/README.md gives.

mod common;

use common::ws::{Client, Got, hello, next, raw};
use common::{TestServer, data_dir};
use futures_util::SinkExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::frame::FLAG_SNAPSHOT;

/// Reads messages up to and including the first snapshot: (bytes that
/// crossed the link, messages in order as "text:TYPE" / "binary", the raw
/// frames, the snapshot).
async fn join(ws: &mut common::ws::Stream) -> (usize, Vec<String>, Vec<Vec<u8>>, Value) {
    use futures_util::StreamExt;
    let mut bytes = 0;
    let mut order = Vec::new();
    let mut frames = Vec::new();
    loop {
        let m = tokio::time::timeout(common::ws::WAIT, ws.next())
            .await
            .expect("no message")
            .expect("closed")
            .expect("socket error");
        match m {
            Message::Text(t) => {
                bytes += t.len();
                let v: Value = serde_json::from_str(t.as_str()).unwrap();
                order.push(format!("text:{}", v["type"].as_str().unwrap()));
                if v["type"] == "snapshot" {
                    return (bytes, order, frames, v);
                }
            }
            Message::Binary(b) => {
                bytes += b.len();
                order.push("binary".into());
                frames.push(b.to_vec());
            }
            _ => {}
        }
    }
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

#[tokio::test]
async fn a_compact_join_sends_the_shape_first_in_binary_and_snapshots_without_points() {
    let dir = data_dir("compact-join");
    let server = TestServer::start(dir.clone()).await;
    let d = server.demo().clone();

    let mut legacy = raw(server.addr).await;
    legacy
        .send(Message::text(hello(d.id, &d.viewer, "legacy").to_string()))
        .await
        .unwrap();
    let (_, legacy_order, _, legacy_snap) = join(&mut legacy).await;
    assert_eq!(legacy_order, ["text:welcome", "text:snapshot"]);
    let points = legacy_snap["surface"]["points"].as_array().unwrap().clone();
    assert!(!points.is_empty());

    let mut compact = raw(server.addr).await;
    let mut h = hello(d.id, &d.viewer, "compact");
    h["geometry_first"] = json!(true);
    compact.send(Message::text(h.to_string())).await.unwrap();
    let (bytes, order, frames, snap) = join(&mut compact).await;
    assert_eq!(order, ["text:welcome", "binary", "text:snapshot"]);
    let frame = &frames[0];
    // Header (protocol/README.md): magic "VSGF", kind, version, flags u16 at 6, design u64 at 8, revision u64 at 16.
    assert_eq!(&frame[..4], b"VSGF");
    assert_ne!(
        u16_at(frame, 6) & FLAG_SNAPSHOT,
        0,
        "flagged as the snapshot's shape"
    );
    assert_eq!(u64_at(frame, 8), d.id);
    assert_eq!(u64_at(frame, 16), snap["revision"].as_u64().unwrap());
    assert_eq!(
        snap["surface"]["points"],
        json!([]),
        "points only in the frame"
    );
    assert_eq!(snap["surface"]["nu"], legacy_snap["surface"]["nu"]);
    // The frame holds the same net as the full snapshot (f32 on the wire).
    let decoded = vsculpt_protocol::GeometryFrame::decode(frame).unwrap();
    assert_eq!(decoded.points.len(), points.len());
    for (p, q) in decoded.points.iter().zip(&points) {
        for k in 0..3 {
            let q = q[k].as_f64().unwrap();
            assert!(
                (f64::from(p[k]) - q).abs() <= 1e-6 * q.abs().max(1.0),
                "{p:?} vs {q}"
            );
        }
    }
    // The whole compact join is smaller than the full snapshot alone.
    let full = serde_json::to_string(&legacy_snap).unwrap().len();
    assert!(
        bytes < full,
        "compact join {bytes} B, full snapshot {full} B"
    );

    // A later snapshot (an undo) comes without points to the compact client, with them to the other.
    let mut editor = Client::connect(server.addr, d.id, &d.editor, "editor").await;
    editor
        .ok(json!({"type": "create_icon", "spec": {"anchor": {"kind": "point", "u": 0.4, "v": 0.6}, "role": {"kind": "load"}, "state": "passive"}}))
        .await;
    editor.ok(json!({"type": "undo"})).await;
    for (ws, with_points) in [(&mut compact, false), (&mut legacy, true)] {
        loop {
            match next(ws).await {
                Got::Text(v) if v["type"] == "snapshot" => {
                    let n = v["surface"]["points"].as_array().unwrap().len();
                    assert_eq!(n > 0, with_points, "points in the undo snapshot: {n}");
                    break;
                }
                Got::Closed => panic!("closed"),
                _ => {}
            }
        }
    }
    server.stop().await;
    let _ = std::fs::remove_dir_all(dir);
}
