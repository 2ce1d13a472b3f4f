//! The drag stream (issue 16) over a real WebSocket: a viewer that asks for
//! it (`/ws?drag_stream=1`) follows a drag of an 81 × 159 surface from a
//! drag basis (kind 5) and small drag frames (kind 6), its net computed as
//! `R + ρ·d` from the reference frame it holds. At every drag frame that net
//! is within 1e-6 of the model size of the net a client without the stream
//! receives in full; after the release the viewer holds the very bytes of
//! the full frame. Drag frames are sent one at a time (each waits for its
//! frame at both clients), so every revision reaches both.

mod common;

use common::http;
use common::ws::{Client, Got, WAIT, hello};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::GeometryFrame;
use vsculpt_protocol::deflated::{self, KIND_DEFLATED};
use vsculpt_protocol::drag_frame::{DragBasis, DragFrame, KIND_DRAG_BASIS, KIND_DRAG_FRAME};

type Stream =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// A stream client: the last full frame of each part (bytes and decoded),
/// the basis it holds and the net it shows, as protocol/README.md says.
struct StreamViewer {
    ws: Stream,
    full: BTreeMap<u64, (Vec<u8>, GeometryFrame)>,
    basis: BTreeMap<u64, DragBasis>,
    /// Per part: (revision, net shown, whether from a drag frame).
    shown: BTreeMap<u64, (u64, Vec<[f64; 3]>, bool)>,
    drag_frames: usize,
    bases: usize,
    /// Bytes received, as they crossed the link.
    bytes: usize,
    /// Deflated messages received (kind 7).
    deflated: usize,
}

impl StreamViewer {
    /// Joins; `deflate`: asks for deflated messages (kind 7) as well.
    async fn connect(addr: std::net::SocketAddr, design: u64, token: &str, deflate: bool) -> Self {
        let query = if deflate {
            "drag_stream=1&deflate=1"
        } else {
            "drag_stream=1"
        };
        let mut ws = tokio_tungstenite::connect_async(format!("ws://{addr}/ws?{query}"))
            .await
            .unwrap()
            .0;
        ws.send(Message::text(hello(design, token, "streamer").to_string()))
            .await
            .unwrap();
        let mut v = Self {
            ws,
            full: BTreeMap::new(),
            basis: BTreeMap::new(),
            shown: BTreeMap::new(),
            drag_frames: 0,
            bases: 0,
            bytes: 0,
            deflated: 0,
        };
        // Up to the snapshot, then the first frame of the part.
        loop {
            if let Some(Value::String(t)) = v.step().await.get("type").cloned()
                && t == "snapshot"
            {
                break;
            }
        }
        v
    }

    /// Reads one message and applies it; returns text messages as JSON
    /// (`null` for binary).
    async fn step(&mut self) -> Value {
        let m = tokio::time::timeout(WAIT, self.ws.next())
            .await
            .expect("no message within 10 s")
            .expect("closed")
            .expect("socket error");
        match m {
            Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            Message::Binary(b) => {
                self.bytes += b.len();
                let b = if b[4] == KIND_DEFLATED {
                    self.deflated += 1;
                    deflated::inflate(&b).unwrap()
                } else {
                    b.to_vec()
                };
                match b[4] {
                    1 | 2 => {
                        let f = GeometryFrame::decode(&b).unwrap();
                        let net = f.points.iter().map(|p| p.map(|c| c as f64)).collect();
                        self.shown.insert(f.part, (f.revision, net, false));
                        self.full.insert(f.part, (b.to_vec(), f));
                    }
                    KIND_DRAG_BASIS => {
                        let basis = DragBasis::decode(&b).unwrap();
                        self.bases += 1;
                        self.basis.insert(basis.part, basis);
                    }
                    KIND_DRAG_FRAME => {
                        let f = DragFrame::decode(&b).unwrap();
                        let basis = &self.basis[&f.part];
                        assert_eq!(basis.basis, f.basis, "a drag frame of a basis not held");
                        let (_, reference) = &self.full[&f.part];
                        assert_eq!(
                            reference.revision, basis.reference,
                            "the reference frame is not the last full frame held"
                        );
                        let net = f.apply(&reference.points, &basis.rho).unwrap();
                        self.drag_frames += 1;
                        self.shown.insert(f.part, (f.revision, net, true));
                    }
                    k => panic!("unexpected frame kind {k}"),
                }
                Value::Null
            }
            other => panic!("unexpected {other:?}"),
        }
    }

    /// Reads until part `part` shows revision `rev` or later.
    async fn until(&mut self, part: u64, rev: u64) {
        while self.shown.get(&part).is_none_or(|s| s.0 < rev) {
            self.step().await;
        }
    }
}

fn size(points: &[[f32; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c] as f64);
            hi[c] = hi[c].max(p[c] as f64);
        }
    }
    (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

#[tokio::test]
async fn a_stream_viewer_follows_a_drag_to_1e6_and_ends_on_the_full_frames_bytes() {
    let dir = data_dir("drag-stream");
    let server = TestServer::start(dir.clone()).await;
    let d = server.demo().clone();
    let body = br#"{"name": "big", "nu": 81, "nv": 159}"#;
    let c = http::request(server.addr, "POST", "/api/designs", Some(&d.editor), body).await;
    assert_eq!(c.status, 201);
    let created = c.json();
    let id = created["id"].as_u64().unwrap();
    let editor_token = created["tokens"]["editor"].as_str().unwrap().to_string();
    let viewer_token = created["tokens"]["viewer"].as_str().unwrap().to_string();

    // The editor (no stream: full frames, the reference) and the viewer.
    let mut ed = Client::connect(server.addr, id, &editor_token, "editor").await;
    let part = ed.snapshot["parts"][0]["id"].as_u64().unwrap();
    let first = ed.frame_of(part).await;
    // Two stream viewers: one asks for deflated messages as well.
    let mut viewers = [
        StreamViewer::connect(server.addr, id, &viewer_token, false).await,
        StreamViewer::connect(server.addr, id, &viewer_token, true).await,
    ];
    for viewer in &mut viewers {
        viewer.until(part, first.revision).await;
    }

    for (role, u, v) in [("load", 0.5, 0.5), ("position", 0.3, 0.7)] {
        let created = ed
            .request(json!({"type": "create_icon", "part": part,
                "spec": {"anchor": {"kind": "point", "u": u, "v": v}, "role": {"kind": role}}}))
            .await;
        assert_eq!(created["type"], "ack", "{created}");
        let icon = created["icon"].as_u64().unwrap();
        ed.ok(json!({"type": "drag_start", "part": part, "icon": icon}))
            .await;
        let start = viewers.each_ref().map(|v| v.drag_frames);
        let steps = 40;
        for k in 1..=steps {
            let z = 0.02 * k as f64;
            ed.send(json!({"type": "drag", "part": part, "icon": icon, "xyz": [u, v, z]}))
                .await;
            let truth = ed.frame_of_drag(part).await;
            for viewer in &mut viewers {
                viewer.until(part, truth.revision).await;
                let (rev, net, _) = &viewer.shown[&part];
                assert_eq!(*rev, truth.revision);
                let tol = 1e-6 * size(&truth.points);
                let worst = net
                    .iter()
                    .zip(&truth.points)
                    .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c] as f64).abs()))
                    .fold(0.0f64, f64::max);
                assert!(
                    worst <= tol,
                    "{role} drag step {k}: the viewer's net is {worst:e} off (tolerance {tol:e})"
                );
            }
        }
        let last = viewers[0].shown[&part].0;
        for (viewer, start) in viewers.iter().zip(start) {
            let streamed = viewer.drag_frames - start;
            assert!(
                streamed >= steps - 2,
                "{role}: only {streamed} of {steps} drag frames came as stream frames"
            );
        }
        ed.send(json!({"type": "drag_end", "part": part, "icon": icon}))
            .await;
        // At rest: a full frame, the same bytes at both clients.
        let rest = loop {
            match ed.next().await {
                Got::Frame(f) if f.part == part && f.flags & 1 == 0 && f.revision > last => {
                    break f;
                }
                Got::Closed => panic!("closed"),
                _ => {}
            }
        };
        for viewer in &mut viewers {
            viewer.until(part, rest.revision).await;
            let (rev, _, from_drag) = &viewer.shown[&part];
            assert_eq!(*rev, rest.revision);
            assert!(!from_drag, "the shape at rest came from a drag frame");
            let (bytes, _) = &viewer.full[&part];
            assert_eq!(
                GeometryFrame::decode(bytes).unwrap(),
                rest,
                "{role}: the viewer's shape at rest differs from the editor's"
            );
        }
    }
    // 80 drag frames cost far less than one full frame each.
    let full = first.encode().unwrap().len();
    for viewer in &viewers {
        assert!(viewer.bases >= 2, "one basis per grab at least");
        assert!(
            viewer.bytes < 12 * full,
            "the viewer received {} bytes (a full frame is {full})",
            viewer.bytes
        );
    }
    // The same messages, deflated: full frames and bases as kind 7, the
    // whole session in well under half the bytes.
    let [plain, small] = &viewers;
    assert_eq!(plain.deflated, 0);
    assert!(small.deflated >= 4, "{} deflated messages", small.deflated);
    assert_eq!(plain.drag_frames, small.drag_frames);
    eprintln!(
        "drag session: {} bytes plain, {} bytes deflated",
        plain.bytes, small.bytes
    );
    assert!(
        small.bytes * 2 < plain.bytes,
        "deflated {} bytes against {} plain",
        small.bytes,
        plain.bytes
    );
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}
