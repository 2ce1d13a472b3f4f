//! The edge clamp over the WebSocket (issue 15): `create_icon` with an
//! `edge` anchor on the demo's shell is acked, announced to every client
//! with its anchor (edge and mode) as sent, stored, and while the demo's
//! load is dragged far the clamped edge's two rows of control points (the
//! edge and the tangent plane across it) stay where they were, to 1e-9 of
//! the shape's size, while a simply supported edge holds its row only (the
//! next row moves). Derivative roles on an edge are refused, and a design
//! stored with edges reloads with them.

mod common;

use common::ws::Client;
use common::{TestServer, data_dir};
use serde_json::{Value, json};

async fn stored(server: &TestServer) -> Value {
    common::http::get(server.addr, "/api/designs/1", Some(&server.demo().editor))
        .await
        .json()["design"]
        .clone()
}

fn points(doc: &Value) -> (usize, usize, Vec<[f64; 3]>) {
    let s = common::parts::surface(doc, 1);
    let nu = s["nu"].as_u64().unwrap() as usize;
    let nv = s["nv"].as_u64().unwrap() as usize;
    (nu, nv, serde_json::from_value(s["points"].clone()).unwrap())
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Drags the demo's load 6 units up and lets go; returns the stored shape.
async fn pull(ed: &mut Client, server: &TestServer) -> (usize, usize, Vec<[f64; 3]>) {
    let (load, at) = common::parts::load_icon(&ed.snapshot);
    ed.ok(json!({"type": "drag_start", "part": 1, "icon": load}))
        .await;
    for k in 1..=3 {
        ed.send(json!({"type": "drag", "part": 1, "icon": load,
            "xyz": [at[0], at[1], at[2] + 2.0 * k as f64]}))
            .await;
    }
    ed.ok(json!({"type": "drag_end", "part": 1, "icon": load}))
        .await;
    points(&stored(server).await)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_clamped_edge_holds_its_rows_through_a_drag() {
    let dir = data_dir("edge-icon");
    let server = TestServer::start(dir.clone()).await;
    let mut ed = Client::connect(server.addr, 1, &server.demo().editor, "ann").await;
    let mut viewer = Client::connect(server.addr, 1, &server.demo().viewer, "vic").await;
    let anchor = json!({"kind": "edge", "edge": "u_min", "mode": "clamped"});
    let r = ed
        .request(json!({"type": "create_icon", "part": 1, "spec": {
            "anchor": anchor, "role": {"kind": "position"}}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    assert!(r.get("warning").is_none(), "{r}");
    let id = r["icon"].as_u64().unwrap();
    // Every client hears of it, anchor as sent.
    let created = loop {
        let e = viewer.wait_for("icon_created").await;
        if e["icon"]["id"] == id {
            break e;
        }
    };
    assert_eq!(created["icon"]["anchor"], anchor, "{created}");
    let doc = stored(&server).await;
    assert_eq!(
        common::parts::icon(&doc, 1, id)["anchor"],
        json!({"kind": "edge", "edge": "u_min", "clamped": true})
    );
    // A derivative constraint needs a point.
    ed.refused(
        json!({"type": "create_icon", "part": 1, "spec": {
            "anchor": {"kind": "edge", "edge": "v_max", "mode": "clamped"},
            "role": {"kind": "derivative", "which": "R"}}}),
        "unsupported",
    )
    .await;

    let (nu, nv, before) = points(&doc);
    let size = before.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
    let (_, _, after) = pull(&mut ed, &server).await;
    let moved = before
        .iter()
        .zip(&after)
        .map(|(a, b)| dist(*a, *b))
        .fold(0.0, f64::max);
    assert!(moved > 1e-3 * size, "the load moved nothing ({moved})");
    for i in 0..2 {
        for j in 0..nv {
            let k = i * nv + j;
            let off = dist(before[k], after[k]);
            assert!(off <= 1e-9 * size, "row {i}, point {j} off by {off:e}");
        }
    }
    assert!(nu > 4);

    // Simply supported at u_max: its row holds, the next row moves.
    let r = ed
        .request(json!({"type": "create_icon", "part": 1, "spec": {
            "anchor": {"kind": "edge", "edge": "u_max", "mode": "simply_supported"},
            "role": {"kind": "position"}}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let (_, _, before) = points(&stored(&server).await);
    let (_, _, after) = pull(&mut ed, &server).await;
    let row = |i: usize| {
        (0..nv)
            .map(|j| dist(before[i * nv + j], after[i * nv + j]))
            .fold(0.0, f64::max)
    };
    assert!(row(nu - 1) <= 1e-9 * size, "edge off by {:e}", row(nu - 1));
    assert!(row(nu - 2) > 1e-6 * size, "the next row did not move");
    assert!(row(0) <= 1e-9 * size, "the clamp let go: {:e}", row(0));
    server.stop().await;

    // Stored with its edges, the design reloads with them.
    let server = TestServer::start(dir).await;
    let doc = stored(&server).await;
    let edges = common::parts::icons(&doc, 1)
        .iter()
        .filter(|i| i["anchor"]["kind"] == "edge")
        .count();
    assert_eq!(edges, 2, "{doc}");
    server.stop().await;
}
