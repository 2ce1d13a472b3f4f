//! Mesh deltas (protocol kind 8) over a real WebSocket. A viewer that asks
//! for them (`/ws?mesh_delta=1`) follows a net-node drag and a primitive
//! drag of the demo handset (a stream of `dsm_edit`s), applying each delta
//! to the frame it holds as protocol/README.md says; after every edit it
//! holds the very bytes of the mesh frame a viewer without deltas receives
//! whole. A paced viewer that missed revisions gets the whole frame. Prints
//! the bytes per drag frame, whole against delta (BENCHMARKS.md, "DSM: mesh
//! deltas"): `cargo test -p vsculpt-server --test dsm_delta -- --nocapture`.

mod common;

use common::ws::{Client, WAIT, hello};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_protocol::MeshFrame;
use vsculpt_protocol::mesh_delta::{KIND_MESH_DELTA, MeshDelta};
use vsculpt_protocol::mesh_frame::KIND_MESH;

type Stream =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// A viewer of mesh deltas: per part the last mesh frame it holds (bytes and
/// decoded), made from whole frames and deltas as protocol/README.md says.
struct DeltaViewer {
    ws: Stream,
    shown: BTreeMap<u64, (Vec<u8>, MeshFrame)>,
    /// Per part: bytes of the mesh messages received (whole or delta) and
    /// whether each was a delta, in order.
    got: BTreeMap<u64, Vec<(usize, bool)>>,
    /// Deltas whose base the viewer did not hold (the server never sends one).
    unusable: usize,
}

impl DeltaViewer {
    /// Joins with `query` (which asks for `mesh_delta=1`), up to the snapshot.
    async fn connect(addr: std::net::SocketAddr, design: u64, token: &str, query: &str) -> Self {
        let mut ws = tokio_tungstenite::connect_async(format!("ws://{addr}/ws?{query}"))
            .await
            .unwrap()
            .0;
        ws.send(Message::text(hello(design, token, "deltas").to_string()))
            .await
            .unwrap();
        let mut v = Self {
            ws,
            shown: BTreeMap::new(),
            got: BTreeMap::new(),
            unusable: 0,
        };
        while v.step().await["type"] != "snapshot" {}
        v
    }

    /// Reads one message and applies it; text comes back as JSON (`null`
    /// for binary).
    async fn step(&mut self) -> Value {
        let m = tokio::time::timeout(WAIT, self.ws.next())
            .await
            .expect("no message within 10 s")
            .expect("closed")
            .expect("socket error");
        let b = match m {
            Message::Text(t) => return serde_json::from_str(t.as_str()).unwrap(),
            Message::Binary(b) => b,
            _ => return Value::Null,
        };
        match b[4] {
            KIND_MESH => {
                let f = MeshFrame::decode(&b).unwrap();
                self.got.entry(f.part).or_default().push((b.len(), false));
                self.shown.insert(f.part, (b.to_vec(), f));
            }
            KIND_MESH_DELTA => {
                let d = MeshDelta::decode(&b).unwrap();
                self.got.entry(d.part).or_default().push((b.len(), true));
                match self.shown.get(&d.part) {
                    Some((_, base)) if base.revision == d.base => {
                        let f = d.apply(base).unwrap();
                        self.shown.insert(d.part, (f.encode().unwrap(), f));
                    }
                    _ => self.unusable += 1,
                }
            }
            // Surface, curve and body frames: not this test's.
            _ => {}
        }
        Value::Null
    }

    /// Reads until part `part` shows revision `rev` or later.
    async fn until(&mut self, part: u64, rev: u64) {
        while self.shown.get(&part).is_none_or(|s| s.1.revision < rev) {
            self.step().await;
        }
    }
}

/// The encoded bytes of a viewer's (decoded) whole frame.
fn bytes(m: &MeshFrame) -> Vec<u8> {
    m.encode().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_viewer_following_drags_through_deltas_holds_the_whole_frames_bytes() {
    let data = data_dir("dsm-delta");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let (addr, design) = (server.addr, d.id);
    let mut ed = Client::connect(addr, design, &d.editor, "ann").await;
    let mut whole = Client::connect(addr, design, &d.viewer, "bob").await;
    let mut deltas = DeltaViewer::connect(addr, design, &d.viewer, "mesh_delta=1").await;

    let handset = serde_json::to_value(vsculpt_server::design::demo::handset_dsm()).unwrap();
    let r = ed
        .request(json!({"type": "create_part", "spec": {"name": "handset", "shape": {"kind": "dsm", "dsm": handset}}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let part = r["part"].as_u64().unwrap();
    let first = whole.mesh_of_after(part, 0).await;
    deltas.until(part, first.revision).await;
    assert_eq!(deltas.shown[&part].0, bytes(&first));

    // The net (primitive 4, 5 × 4 nodes): node 7 pulled up step by step;
    // then the lanyard hole (primitive 5) moved sideways step by step.
    let steps = 6;
    let node_drag = (1..=steps)
        .map(|k| json!({"op": "drag_node", "id": 4, "node": 7, "height": 0.26 + 0.01 * k as f64}));
    let hole_drag = (1..=steps)
        .map(|k| json!({"op": "move_primitive", "id": 5, "at": [1.15, 0.01 * k as f64, 0.0]}));
    let mut last = first;
    let mut whole_bytes = Vec::new();
    for edit in node_drag.chain(hole_drag) {
        ed.ok(json!({"type": "dsm_edit", "part": part, "edit": edit.clone()}))
            .await;
        let m = whole.mesh_of_after(part, last.revision).await;
        assert!(m.positions != last.positions, "{edit} changed nothing");
        deltas.until(part, m.revision).await;
        let (held, shown) = &deltas.shown[&part];
        assert_eq!(shown.revision, m.revision);
        assert!(
            *held == bytes(&m),
            "after {edit}: the frame made from deltas differs"
        );
        whole_bytes.push(bytes(&m).len());
        last = m;
    }
    assert_eq!(deltas.unusable, 0);
    // The mesh messages of the two drags (after the part's first frame):
    // mean bytes per drag frame, and how many came as deltas.
    let g = &deltas.got[&part];
    assert_eq!(g.len(), 1 + 2 * steps, "one message per revision: {g:?}");
    let mean = |x: &[usize]| x.iter().sum::<usize>() as f64 / x.len() as f64;
    let sizes: Vec<usize> = g[1..].iter().map(|x| x.0).collect();
    let count = |r: std::ops::Range<usize>| g[1..][r].iter().filter(|x| x.1).count();
    let (node_deltas, hole_deltas) = (count(0..steps), count(steps..2 * steps));
    assert!(
        node_deltas + hole_deltas >= steps,
        "{node_deltas} + {hole_deltas} deltas of {} edits",
        2 * steps
    );
    let (node_whole, hole_whole) = (mean(&whole_bytes[..steps]), mean(&whole_bytes[steps..]));
    let (node_sent, hole_sent) = (mean(&sizes[..steps]), mean(&sizes[steps..]));
    println!(
        "mesh bytes per drag frame (demo handset, 40 cells, {} vertices, {} triangles):\n  \
         net node drag: whole {node_whole:.0} → sent {node_sent:.0} ({:.1}×; {node_deltas} of {steps} as deltas)\n  \
         hole move:     whole {hole_whole:.0} → sent {hole_sent:.0} ({:.1}×; {hole_deltas} of {steps} as deltas)",
        last.positions.len(),
        last.triangles.len(),
        node_whole / node_sent,
        hole_whole / hole_sent,
    );
    drop(ed);
    drop(whole);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_paced_viewer_that_missed_revisions_gets_the_whole_frame() {
    let data = data_dir("dsm-delta-missed");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let mut ed = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    // A design of its own: a small plate, then the handset.
    ed.send(json!({"type": "create_design", "req": 900, "name": "concept"}))
        .await;
    let c = ed.wait_for("design_created").await;
    let design = c["design"]["id"].as_u64().unwrap();
    let (editor, viewer) = (
        c["tokens"]["editor"].as_str().unwrap().to_string(),
        c["tokens"]["viewer"].as_str().unwrap().to_string(),
    );
    drop(ed);
    let mut ed = Client::connect(server.addr, design, &editor, "ann").await;
    let mut whole = Client::connect(server.addr, design, &viewer, "bob").await;
    // Paced and never reporting: its window stays at the floor (32 KiB).
    let mut paced = DeltaViewer::connect(server.addr, design, &viewer, "mesh_delta=1&pace=1").await;

    // At 64 cells the handset's frame (about 80 kB) is over the window.
    let mut handset = serde_json::to_value(vsculpt_server::design::demo::handset_dsm()).unwrap();
    handset["cells"] = json!(64);
    let r = ed
        .request(json!({"type": "create_part", "spec": {"name": "handset", "shape": {"kind": "dsm", "dsm": handset}}}))
        .await;
    let part = r["part"].as_u64().unwrap();
    let first = whole.mesh_of_after(part, 0).await;
    // The first frame goes (the window was open) and fills the window.
    paced.until(part, first.revision).await;
    assert!(paced.got[&part][0].0 > 32 * 1024, "{:?}", paced.got[&part]);
    let mut last = first;
    for k in 1..=3 {
        ed.ok(json!({"type": "dsm_edit", "part": part, "edit":
            {"op": "move_primitive", "id": 5, "at": [1.15, 0.01 * k as f64, 0.0]}}))
            .await;
        last = whole.mesh_of_after(part, last.revision).await;
    }
    // It reports what it received (more: counts as all): the latest revision
    // comes whole, and only it (the window was shut meanwhile; the revision
    // before it, the delta's base, never reached this viewer).
    let received: usize = paced.got.values().flatten().map(|x| x.0).sum::<usize>() + 100_000;
    paced
        .ws
        .send(Message::text(
            json!({"type": "received", "bytes": received}).to_string(),
        ))
        .await
        .unwrap();
    paced.until(part, last.revision).await;
    let got = &paced.got[&part];
    assert_eq!(got.len(), 2, "{got:?}");
    assert!(!got[1].1, "the frame after the missed revisions is whole");
    assert_eq!(paced.shown[&part].0, bytes(&last));
    assert_eq!(paced.unusable, 0);
    drop(ed);
    drop(whole);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
