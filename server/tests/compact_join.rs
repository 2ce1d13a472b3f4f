//! The compact join (issue 18): a hello with `geometry_first` gets, after
//! its welcome, the shape of every part as one binary frame each, flagged
//! FLAG_SNAPSHOT, then a snapshot whose parts' `points` are empty — and later snapshots (undo,
//! revert, restore) also come without points, since frames carry the
//! shape. A hello without it joins as before. The frame's header is read
//! from the raw bytes at the offsets protocol/README.md gives.

mod common;

use common::parts;
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
    let shape_of = |snap: &Value, id: u64| -> Value {
        let shape = &parts::part(snap, id)["shape"];
        shape[shape["kind"].as_str().unwrap()].clone()
    };
    // The surface and curve parts (the demo's body part, the spool, holds a
    // lattice and is drawn from body frames).
    let ids: Vec<u64> = parts::part_ids(&legacy_snap)
        .into_iter()
        .filter(|id| parts::part(&legacy_snap, *id)["shape"]["kind"] != "body")
        .collect();
    assert_eq!(ids.len(), 4, "the demo has four surface and curve parts");
    for &id in &ids {
        assert!(
            !shape_of(&legacy_snap, id)["points"]
                .as_array()
                .unwrap()
                .is_empty()
        );
    }

    let mut compact = raw(server.addr).await;
    let mut h = hello(d.id, &d.viewer, "compact");
    h["geometry_first"] = json!(true);
    compact.send(Message::text(h.to_string())).await.unwrap();
    let (bytes, order, frames, snap) = join(&mut compact).await;
    // The frames between the welcome and the snapshot.
    let mut expected = vec!["text:welcome".to_string()];
    expected.extend(frames.iter().map(|_| "binary".to_string()));
    expected.push("text:snapshot".into());
    assert_eq!(order, expected);
    let mut framed = Vec::new();
    for frame in &frames {
        if frame[4] == vsculpt_protocol::body_frame::KIND_BODY {
            continue;
        }
        // Header (protocol/README.md): magic "VSGF", kind u8 at 4, version
        // u8 at 5, flags u16 at 6, design u64 at 8, part u64 at 16,
        // revision u64 at 24.
        assert_eq!(&frame[..4], b"VSGF");
        assert_eq!(frame[5], 2, "protocol version");
        assert_ne!(
            u16_at(frame, 6) & FLAG_SNAPSHOT,
            0,
            "flagged as the snapshot's shape"
        );
        assert_eq!(u64_at(frame, 8), d.id);
        let id = u64_at(frame, 16);
        framed.push(id);
        assert_eq!(u64_at(frame, 24), snap["revision"].as_u64().unwrap());
        let kind = parts::part(&snap, id)["shape"]["kind"].clone();
        assert_eq!(frame[4], if kind == "surface" { 1 } else { 2 }, "{kind}");
        let (short, full) = (shape_of(&snap, id), shape_of(&legacy_snap, id));
        assert_eq!(short["points"], json!([]), "points only in the frame");
        if kind == "surface" {
            assert_eq!(short["nu"], full["nu"]);
            assert_eq!(short["nv"], full["nv"]);
        }
        // The frame holds the same net as the full snapshot (f32 on the wire).
        let points = full["points"].as_array().unwrap();
        let decoded = vsculpt_protocol::GeometryFrame::decode(frame).unwrap();
        assert_eq!(decoded.part, id);
        assert_eq!(decoded.points.len(), points.len());
        for (p, q) in decoded.points.iter().zip(points) {
            for k in 0..3 {
                let q = q[k].as_f64().unwrap();
                assert!(
                    (f64::from(p[k]) - q).abs() <= 1e-6 * q.abs().max(1.0),
                    "{p:?} vs {q}"
                );
            }
        }
    }
    framed.sort_unstable();
    assert_eq!(framed, ids, "one frame for each part");
    // The whole compact join is smaller than the full snapshot alone (body
    // frames aside: every client gets those, compact or not).
    let body_bytes: usize = frames
        .iter()
        .filter(|f| f[4] == vsculpt_protocol::body_frame::KIND_BODY)
        .map(Vec::len)
        .sum();
    let bytes = bytes - body_bytes;
    let full = serde_json::to_string(&legacy_snap).unwrap().len();
    assert!(
        bytes < full,
        "compact join {bytes} B, full snapshot {full} B"
    );

    // A later snapshot (an undo) comes without points to the compact client, with them to the other.
    let mut editor = Client::connect(server.addr, d.id, &d.editor, "editor").await;
    editor
        .ok(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.4, "v": 0.6}, "role": {"kind": "load"}, "state": "passive"}}))
        .await;
    editor.ok(json!({"type": "undo"})).await;
    for (ws, with_points) in [(&mut compact, false), (&mut legacy, true)] {
        loop {
            match next(ws).await {
                Got::Text(v) if v["type"] == "snapshot" => {
                    for id in parts::part_ids(&v) {
                        let shape = &parts::part(&v, id)["shape"];
                        // A body part (the demo's spool) holds a lattice, not points.
                        if shape["kind"] == "body" {
                            continue;
                        }
                        let n = shape[shape["kind"].as_str().unwrap()]["points"]
                            .as_array()
                            .unwrap()
                            .len();
                        assert_eq!(
                            n > 0,
                            with_points,
                            "points of part {id} in the undo snapshot: {n}"
                        );
                    }
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
