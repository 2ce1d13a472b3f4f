//! Coons body parts (paper 002, issue 13) through the real server over
//! WebSocket: a body created, its lattice edited (a point, a face, an edge)
//! with body frames (kind 4) reaching a viewer, a fold refused with where
//! it folds and nothing changed, undo, a restart that keeps the body, the
//! morph time streamed to viewers, bad input refused with clear errors;
//! and the exports: the interior as a hexahedral `.vtu` read back by
//! `vtkio` (a reader we did not write: cell count and the sum of the hex
//! volumes against the body's volume), the boundary as six IGES 128 faces,
//! the boundary in the STL export.

mod common;

use common::http::get;
use common::ws::{hello, raw};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use glam::DVec3;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_kernel::body::{BSplineVolume, interior};
use vsculpt_kernel::bspline::KnotVector;
use vsculpt_protocol::BodyFrame;
use vsculpt_protocol::body_frame::KIND_BODY;

/// A socket that reads JSON and body frames (other frames are skipped).
struct Peer {
    ws: common::ws::Stream,
    req: u64,
    snapshot: Value,
}

enum In {
    Text(Value),
    Body(Box<BodyFrame>),
}

impl Peer {
    async fn connect(addr: std::net::SocketAddr, design: u64, token: &str) -> Self {
        let mut ws = raw(addr).await;
        ws.send(Message::text(hello(design, token, "body-test").to_string()))
            .await
            .unwrap();
        let mut p = Self {
            ws,
            req: 100,
            snapshot: Value::Null,
        };
        loop {
            if let In::Text(v) = p.next().await
                && v["type"] == "snapshot"
            {
                p.snapshot = v;
                return p;
            }
        }
    }

    async fn next(&mut self) -> In {
        loop {
            let m = tokio::time::timeout(std::time::Duration::from_secs(20), self.ws.next())
                .await
                .expect("no message within 20 s")
                .expect("closed")
                .expect("socket error");
            match m {
                Message::Text(t) => return In::Text(serde_json::from_str(t.as_str()).unwrap()),
                Message::Binary(b) if b.len() > 4 && b[4] == KIND_BODY => {
                    return In::Body(Box::new(BodyFrame::decode(&b).expect("a valid body frame")));
                }
                _ => {}
            }
        }
    }

    /// Sends `msg` with a new `req`; the reply (`ack` or `error`).
    async fn request(&mut self, mut msg: Value) -> Value {
        self.req += 1;
        msg["req"] = json!(self.req);
        self.ws.send(Message::text(msg.to_string())).await.unwrap();
        loop {
            if let In::Text(v) = self.next().await
                && (v["type"] == "ack" || v["type"] == "error")
                && v["req"] == json!(self.req)
            {
                return v;
            }
        }
    }

    async fn ok(&mut self, msg: Value) -> Value {
        let r = self.request(msg.clone()).await;
        assert_eq!(r["type"], "ack", "{msg} → {r}");
        r
    }

    async fn refused(&mut self, msg: Value, code: &str) -> String {
        let r = self.request(msg.clone()).await;
        assert_eq!(r["type"], "error", "{msg} → {r}");
        assert_eq!(r["code"], code, "{msg} → {r}");
        r["message"].as_str().unwrap().to_string()
    }

    /// The next body frame of `part` with revision ≥ `after`.
    async fn body_frame(&mut self, part: u64, after: u64) -> BodyFrame {
        loop {
            if let In::Body(f) = self.next().await
                && f.part == part
                && f.revision >= after
            {
                return *f;
            }
        }
    }
}

/// Clamped knots of `degree` with `n` points, uniform on [0, 1].
fn knots(degree: usize, n: usize) -> Vec<f64> {
    let spans = n - degree;
    let mut k = vec![0.0; degree + 1];
    k.extend((1..spans).map(|i| i as f64 / spans as f64));
    k.extend(vec![1.0; degree + 1]);
    k
}

/// The box [0, 2]³ as a lattice of `n³` points of `degree` at the Greville
/// abscissae (so the map is affine), as the protocol's `lattice`.
fn box_lattice(degree: usize, n: usize) -> Value {
    let k = knots(degree, n);
    let g: Vec<f64> = (0..n)
        .map(|i| 2.0 * k[i + 1..=i + degree].iter().sum::<f64>() / degree as f64)
        .collect();
    let mut points = Vec::new();
    for x in &g {
        for y in &g {
            for z in &g {
                points.push(json!([x, y, z]));
            }
        }
    }
    let kv = json!({"degree": degree, "knots": k});
    json!({"u": kv, "v": kv, "w": kv, "points": points})
}

fn lattice_points(l: &Value) -> Vec<[f64; 3]> {
    serde_json::from_value(l["points"].clone()).unwrap()
}

/// A kernel volume from a stored (document) lattice.
fn stored_volume(l: &Value) -> BSplineVolume {
    let kv = |d: usize| {
        KnotVector::new(
            l["degrees"][d].as_u64().unwrap() as usize,
            serde_json::from_value(l["knots"][d].clone()).unwrap(),
        )
        .unwrap()
    };
    let pts: Vec<[f64; 3]> = serde_json::from_value(l["points"].clone()).unwrap();
    BSplineVolume::new(
        kv(0),
        kv(1),
        kv(2),
        pts.into_iter().map(DVec3::from).collect(),
    )
    .unwrap()
}

async fn stored(addr: std::net::SocketAddr, design: u64, token: &str) -> Value {
    get(addr, &format!("/api/designs/{design}"), Some(token))
        .await
        .json()["design"]
        .clone()
}

fn stored_body(doc: &Value, part: u64) -> &Value {
    doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == json!(part))
        .unwrap_or_else(|| panic!("no part {part} in {doc}"))
}

fn close(a: [f32; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| (a[i] as f64 - b[i]).abs() < 1e-5)
}

async fn create_body(ed: &mut Peer, name: &str, body: Value) -> u64 {
    let r = ed
        .ok(json!({"type": "create_part", "spec": {"name": name, "shape": {"kind": "body", "body": body}}}))
        .await;
    r["part"].as_u64().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lattice_edits_reach_a_viewer_a_fold_is_refused_with_where_undo_and_restart_keep_the_body()
{
    let data = data_dir("body-edits");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let (editor, viewer) = (server.demo().editor.clone(), server.demo().viewer.clone());
    let mut ed = Peer::connect(addr, design, &editor).await;
    let mut vw = Peer::connect(addr, design, &viewer).await;

    // Degree 2, 3 × 3 × 3 points: the box [0, 2]³ (the middle point at 1).
    let lattice = box_lattice(2, 3);
    let part = create_body(&mut ed, "block", json!({ "lattice": lattice })).await;
    let first = vw.body_frame(part, 0).await;
    assert_eq!(first.counts, [3, 3, 3]);
    let pts = lattice_points(&lattice);
    for (a, b) in first.lattice.iter().zip(&pts) {
        assert!(close(*a, *b), "{a:?} vs {b:?}");
    }
    // Six faces of 17 × 17 vertices; 36 isoparametric lines of 33 samples.
    assert_eq!(first.positions.len(), 6 * 17 * 17);
    assert_eq!(first.line_dirs.len(), 36);
    assert_eq!(first.line_points.len(), 36 * 33);
    // The boundary is the box: every vertex on a face of [0, 2]³, normals outward.
    for (p, n) in first.positions.iter().zip(&first.normals) {
        let on: Vec<usize> = (0..3)
            .filter(|&a| p[a].abs() < 1e-5 || (p[a] - 2.0).abs() < 1e-5)
            .collect();
        assert!(!on.is_empty(), "{p:?} is not on the box's boundary");
        let a = on[0];
        let outward = if p[a] < 1.0 { -1.0 } else { 1.0 };
        if on.len() == 1 {
            assert!((n[a] - outward).abs() < 1e-4, "normal {n:?} at {p:?}");
        }
    }

    // One inner point: the interior changes, the boundary does not.
    let centre = 13; // (1, 1, 1)
    ed.ok(json!({"type": "body_edit", "part": part, "edit": {"select": {"point": [1, 1, 1]}, "delta": [0.3, 0.0, 0.0]}}))
        .await;
    let moved = vw.body_frame(part, first.revision + 1).await;
    assert!(close(moved.lattice[centre], [1.3, 1.0, 1.0]));
    for (k, (a, b)) in moved.lattice.iter().zip(&first.lattice).enumerate() {
        if k != centre {
            assert_eq!(a, b, "lattice point {k} moved");
        }
    }
    assert_eq!(moved.positions, first.positions, "the boundary moved");
    let doc = stored(addr, design, &editor).await;
    let body = &stored_body(&doc, part)["body"];
    assert_eq!(body["kind"], "body");
    assert_eq!(body["lattice"]["points"][centre], json!([1.3, 1.0, 1.0]));

    // A fold: the inner point pushed far through the face x = 2 (x_u at
    // u = 1 is 2(1 − δ N₁(v) N₁(w)) ≥ 2(1 − δ/4): δ = 6 folds). Refused, with
    // where; det J there is ≤ 0 (checked here by plain evaluation), and
    // nothing changed.
    let msg = ed
        .refused(
            json!({"type": "body_edit", "part": part, "edit": {"select": {"point": [1, 1, 1]}, "delta": [6.0, 0.0, 0.0]}}),
            "out_of_range",
        )
        .await;
    assert!(msg.contains("folds the body at (u, v, w) = ("), "{msg}");
    let uvw: Vec<f64> = msg
        .split("(u, v, w) = (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap()
        .split(", ")
        .map(|s| s.parse().unwrap())
        .collect();
    let mut folded = body["lattice"].clone();
    folded["points"][centre] = json!([7.3, 1.0, 1.0]);
    let det = stored_volume(&folded).derivs(uvw[0], uvw[1], uvw[2]).det();
    assert!(det <= 1e-9, "det J = {det} at {uvw:?}");
    assert!(
        stored_volume(&body["lattice"])
            .derivs(uvw[0], uvw[1], uvw[2])
            .det()
            > 0.0
    );
    assert_eq!(
        stored_body(&stored(addr, design, &editor).await, part)["body"],
        *body
    );

    // A face's points: the top (w = max) up by 0.5.
    ed.ok(json!({"type": "body_edit", "part": part, "edit": {"select": {"face": "w_max"}, "delta": [0.0, 0.0, 0.5]}}))
        .await;
    let up = vw.body_frame(part, moved.revision + 1).await;
    for (k, (a, b)) in up.lattice.iter().zip(&moved.lattice).enumerate() {
        let dz = if k % 3 == 2 { 0.5 } else { 0.0 };
        assert!(
            (a[2] - b[2] - dz).abs() < 1e-6 && a[0] == b[0] && a[1] == b[1],
            "point {k}"
        );
    }
    let top = up.positions.iter().map(|p| p[2]).fold(f32::MIN, f32::max);
    assert!((top - 2.5).abs() < 1e-5, "top at {top}");

    // An edge's points: u = max, v = max (three points along w).
    ed.ok(json!({"type": "body_edit", "part": part, "edit": {"select": {"edge": ["u_max", "v_max"]}, "delta": [0.2, 0.2, 0.0]}}))
        .await;
    let edged = vw.body_frame(part, up.revision + 1).await;
    let changed: Vec<usize> = (0..27)
        .filter(|&k| edged.lattice[k] != up.lattice[k])
        .collect();
    assert_eq!(changed, vec![24, 25, 26]);

    // Undo takes the edge edit back (snapshot and a new frame).
    ed.ok(json!({"type": "undo"})).await;
    let undone = vw.body_frame(part, edged.revision + 1).await;
    assert_eq!(undone.lattice, up.lattice);
    let before_restart = stored(addr, design, &editor).await;
    assert_eq!(
        lattice_points(&stored_body(&before_restart, part)["body"]["lattice"])[24],
        [2.0, 2.0, 0.0]
    );

    // Restart: the body is back as it was, drawn again.
    drop(ed);
    drop(vw);
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    assert_eq!(
        stored_body(&stored(addr, design, &editor).await, part),
        stored_body(&before_restart, part)
    );
    let mut vw = Peer::connect(addr, design, &viewer).await;
    let again = vw.body_frame(part, 0).await;
    assert_eq!(again.lattice, up.lattice);
    assert_eq!(again.positions, up.positions);
    // A viewer may not edit.
    vw.refused(
        json!({"type": "body_edit", "part": part, "edit": {"select": {"point": [0, 0, 0]}, "delta": [0.1, 0.0, 0.0]}}),
        "forbidden",
    )
    .await;
    drop(vw);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_spool_morph_streams_frames_to_viewers() {
    let data = data_dir("body-morph");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let mut ed = Peer::connect(addr, design, &server.demo().editor).await;
    let mut vw = Peer::connect(addr, design, &server.demo().viewer).await;
    let mut spec = get(addr, "/api/demo-parts/spool", None).await.json();
    assert_eq!(spec["shape"]["kind"], "body");
    // The demo design has a "spool" already; part names are unique.
    spec["name"] = json!("spool 2");
    let r = ed.ok(json!({"type": "create_part", "spec": spec})).await;
    let part = r["part"].as_u64().unwrap();
    let cube = vw.body_frame(part, 0).await;
    assert_eq!(cube.t, 0.0);
    let radius = |f: &BodyFrame| {
        f.positions
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt())
            .fold(0.0f32, f32::max)
    };
    // The cube [−30, 30]³: its farthest points from the axis are the corners.
    assert!((radius(&cube) - 30.0 * 2f32.sqrt()).abs() < 1e-3);
    let mut last = cube.revision;
    let mut radii = Vec::new();
    let mut frames = Vec::new();
    for t in [0.25, 0.5, 0.75, 1.0] {
        ed.ok(json!({"type": "body_morph", "part": part, "t": t}))
            .await;
        let f = vw.body_frame(part, last + 1).await;
        assert_eq!(f.t, t as f32);
        last = f.revision;
        radii.push(radius(&f));
        frames.push(f);
    }
    // At t = 1 the spool: flanges of radius 1.5 · 30 (the square-to-disc
    // map keeps the corner (1, 1) at distance 1.5 · 30 · √(1/2 + 1/2)).
    assert!(
        (radii[3] - 45.0).abs() < 0.5,
        "spool flange radius {}",
        radii[3]
    );
    // In between, the flange grows with t.
    assert!(radii.windows(2).all(|w| w[0] < w[1]), "{radii:?}");
    // The waist: at mid-height (z = 0, w = 1/2) the spool's boundary is a
    // combination of the three waist layers only, all of radius 0.7 · 30.
    let spool = &frames[3];
    let waist = spool
        .positions
        .iter()
        .filter(|p| p[2].abs() < 1e-3)
        .map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt())
        .fold(0.0f32, f32::max);
    assert!(waist > 15.0 && waist < 21.0 + 1e-3, "waist radius {waist}");
    // Not an edit: the stored body is the spec's (the cube), t is not stored.
    let doc = stored(addr, design, &server.demo().editor).await;
    assert_eq!(
        lattice_points(&stored_body(&doc, part)["body"]["lattice"]),
        lattice_points(&spec["shape"]["body"]["lattice"])
    );
    ed.refused(
        json!({"type": "body_morph", "part": part, "t": 1.5}),
        "out_of_range",
    )
    .await;
    drop(ed);
    drop(vw);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

/// The axis-aligned box around `points`.
fn bounds(points: impl IntoIterator<Item = [f64; 3]>) -> ([f64; 3], [f64; 3]) {
    points
        .into_iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                [0, 1, 2].map(|a| lo[a].min(p[a])),
                [0, 1, 2].map(|a| hi[a].max(p[a])),
            )
        })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_first_start_demo_has_the_spool_clear_of_the_mouse_and_its_morph_plays_to_viewers() {
    let data = data_dir("body-demo");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let token = server.demo().editor.clone();
    let doc = stored(addr, design, &token).await;
    let bodies: Vec<&Value> = doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["body"]["kind"] == "body")
        .collect();
    assert_eq!(bodies.len(), 1, "the demo has one body part");
    let spool = bodies[0];
    let part = spool["id"].as_u64().unwrap();
    assert_eq!(spool["name"], "spool");
    assert!(spool["visible"].as_bool().unwrap());
    let cube = stored_volume(&spool["body"]["lattice"]);
    let target = stored_volume(&spool["body"]["morph_target"]);
    // Stored as the cube of side 60 (figure 10 starts from it), its target
    // the spool: interior volume 60³ exactly (an affine map).
    assert!((interior::volume(&cube) - 216_000.0).abs() < 1e-6 * 216_000.0);
    // Clear of the mouse: every B-spline lies in the convex hull of its
    // control points, and every morph frame's control points lie between
    // the cube's and the spool's (the eased path blends them), so the boxes
    // around the control points bound everything ever drawn.
    let body_box = bounds(
        cube.points()
            .iter()
            .chain(target.points())
            .map(|p| p.to_array()),
    );
    let mut others = Vec::new();
    for p in doc["parts"].as_array().unwrap() {
        let b = &p["body"];
        let pts = match b["kind"].as_str().unwrap() {
            "surface" => &b["surface"]["points"],
            "curve" => &b["curve"]["points"],
            "body" => continue,
            other => panic!("unexpected demo part kind {other}"),
        };
        others.extend(lattice_points(&json!({ "points": pts })));
    }
    assert!(others.len() > 100, "the mouse's control points");
    let mouse_box = bounds(others);
    let gap = (0..3)
        .map(|a| (body_box.0[a] - mouse_box.1[a]).max(mouse_box.0[a] - body_box.1[a]))
        .fold(f64::MIN, f64::max);
    assert!(
        gap > 20.0,
        "the spool is {gap} mm clear of the mouse: {body_box:?} {mouse_box:?}"
    );

    // A viewer sees the cube, then the spool when the editor plays the
    // morph to t = 1: the flange radius about the spool's axis is 45.
    let mut ed = Peer::connect(addr, design, &token).await;
    let mut vw = Peer::connect(addr, design, &server.demo().viewer).await;
    let axis = [
        (body_box.0[0] + body_box.1[0]) / 2.0,
        (body_box.0[1] + body_box.1[1]) / 2.0,
    ];
    let radius = |f: &BodyFrame| {
        f.positions
            .iter()
            .map(|p| ((p[0] as f64 - axis[0]).powi(2) + (p[1] as f64 - axis[1]).powi(2)).sqrt())
            .fold(0.0f64, f64::max)
    };
    let first = vw.body_frame(part, 0).await;
    assert_eq!(first.t, 0.0);
    assert!(
        (radius(&first) - 30.0 * 2f64.sqrt()).abs() < 1e-3,
        "{}",
        radius(&first)
    );
    let mut last = first.revision;
    for k in 1..=10 {
        let t = k as f64 / 10.0;
        ed.ok(json!({"type": "body_morph", "part": part, "t": t}))
            .await;
        let f = vw.body_frame(part, last + 1).await;
        assert_eq!(f.t, t as f32);
        last = f.revision;
        if k == 10 {
            assert!((radius(&f) - 45.0).abs() < 0.5, "flange {}", radius(&f));
        }
    }
    drop(ed);
    drop(vw);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_body_input_is_refused_with_clear_errors_and_changes_nothing() {
    let data = data_dir("body-bad");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let token = server.demo().editor.clone();
    let mut ed = Peer::connect(addr, design, &token).await;
    let part = create_body(&mut ed, "block", json!({ "lattice": box_lattice(1, 2) })).await;
    let before = stored(addr, design, &token).await;
    let body = |lattice: Value| json!({"type": "create_part", "spec": {"name": "bad", "shape": {"kind": "body", "body": {"lattice": lattice}}}});
    let edit = |p: u64, select: Value, delta: Value| json!({"type": "body_edit", "part": p, "edit": {"select": select, "delta": delta}});

    // NaN is not JSON; a huge number is out of range; 1e999 does not parse.
    ed.refused(
        json!({"type": "body_edit", "part": part, "edit": {"select": {"point": [0, 0, 0]}, "delta": [1e300, 0, 0]}}),
        "out_of_range",
    )
    .await;
    let r = {
        ed.req += 1;
        let text = format!(
            "{{\"type\": \"body_edit\", \"req\": {}, \"part\": {part}, \"edit\": {{\"select\": {{\"point\": [0, 0, 0]}}, \"delta\": [NaN, 0, 0]}}}}",
            ed.req
        );
        ed.ws.send(Message::text(text)).await.unwrap();
        loop {
            if let In::Text(v) = ed.next().await
                && v["type"] == "error"
            {
                break v;
            }
        }
    };
    assert_eq!(r["code"], "malformed", "{r}");
    // Huge sizes: 40 points along u.
    let mut big = box_lattice(1, 2);
    big["u"] = json!({"degree": 1, "knots": knots(1, 40)});
    assert!(
        ed.refused(body(big), "too_large")
            .await
            .contains("at most 32 points per direction")
    );
    let mut many = box_lattice(1, 2);
    many["points"] = json!(vec![[0.0, 0.0, 0.0]; 9]);
    assert!(
        ed.refused(body(many), "out_of_range")
            .await
            .contains("9 control points")
    );
    let mut deg = box_lattice(1, 2);
    deg["w"] = json!({"degree": 7, "knots": knots(7, 8)});
    ed.refused(body(deg), "out_of_range").await;
    let mut dec = box_lattice(2, 3);
    dec["v"] = json!({"degree": 2, "knots": [0, 0, 0, 1, 1, 0.5]});
    assert!(
        ed.refused(body(dec), "out_of_range")
            .await
            .contains("knots along v")
    );
    // A lattice turned inside out (x mirrored) folds from the start.
    let mut inverted = box_lattice(1, 2);
    for p in inverted["points"].as_array_mut().unwrap() {
        p[0] = json!(2.0 - p[0].as_f64().unwrap());
    }
    assert!(
        ed.refused(body(inverted), "out_of_range")
            .await
            .contains("folds the body")
    );
    // A body has no material.
    ed.refused(
        json!({"type": "create_part", "spec": {"name": "m", "shape": {"kind": "body", "body": {"lattice": box_lattice(1, 2)}}, "material": {"alpha": 1, "beta": 1}}}),
        "out_of_range",
    )
    .await;
    // Unknown ids, wrong kinds, indices outside the lattice, bad edges, bad times.
    ed.refused(
        edit(999, json!({"point": [0, 0, 0]}), json!([0.1, 0, 0])),
        "unknown_part",
    )
    .await;
    let m = ed
        .refused(
            edit(1, json!({"point": [0, 0, 0]}), json!([0.1, 0, 0])),
            "unsupported",
        )
        .await;
    assert!(m.contains("body"), "{m}");
    assert!(
        ed.refused(
            edit(part, json!({"point": [2, 0, 0]}), json!([0.1, 0, 0])),
            "out_of_range"
        )
        .await
        .contains("outside a 2×2×2 lattice")
    );
    ed.refused(
        edit(
            part,
            json!({"edge": ["u_min", "u_max"]}),
            json!([0.1, 0, 0]),
        ),
        "out_of_range",
    )
    .await;
    ed.refused(
        edit(part, json!({"face": "x_min"}), json!([0.1, 0, 0])),
        "malformed",
    )
    .await;
    ed.refused(
        json!({"type": "body_morph", "part": part, "t": 0.5}),
        "unsupported",
    )
    .await;
    ed.refused(
        json!({"type": "body_morph", "part": 999, "t": 0.5}),
        "unknown_part",
    )
    .await;
    ed.refused(
        json!({"type": "create_icon", "part": part, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "position"}, "state": "passive"}}),
        "unsupported",
    )
    .await;
    assert_eq!(stored(addr, design, &token).await, before);
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

/// The volume of the trilinear hexahedron with VTK-ordered corners `c`:
/// ∫ det J over [0, 1]³ by 2 × 2 × 2 Gauss points (exact: det J of a
/// trilinear map has degree 2 in each variable).
fn hex_volume(c: &[DVec3; 8]) -> f64 {
    let g = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
    // VTK order: (0,0,0) (1,0,0) (1,1,0) (0,1,0) then the same at z = 1.
    let at = |x: usize, y: usize, z: usize| c[[[0, 3], [1, 2]][x][y] + 4 * z];
    let mut v = 0.0;
    for &r in &g {
        for &s in &g {
            for &t in &g {
                let d = |dir: usize| {
                    let mut sum = DVec3::ZERO;
                    for x in 0..2 {
                        for y in 0..2 {
                            for z in 0..2 {
                                let w = |k: usize, a: f64| if k == 0 { 1.0 - a } else { a };
                                let dw = |k: usize| if k == 0 { -1.0 } else { 1.0 };
                                let f = match dir {
                                    0 => dw(x) * w(y, s) * w(z, t),
                                    1 => w(x, r) * dw(y) * w(z, t),
                                    _ => w(x, r) * w(y, s) * dw(z),
                                };
                                sum += at(x, y, z) * f;
                            }
                        }
                    }
                    sum
                };
                v += 0.125 * d(0).dot(d(1).cross(d(2)));
            }
        }
    }
    v
}

/// Cells, their summed volume and the smallest cell volume of a `.vtu`
/// file, as `vtkio` reads it.
fn read_vtu(text: &str) -> (usize, f64, f64, usize) {
    use vtkio::model::{DataSet, Piece, VertexNumbers};
    let vtk = vtkio::Vtk::parse_xml(text.as_bytes()).expect("vtkio reads the file");
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid");
    };
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("not an inline piece");
    };
    let pts: Vec<f64> = piece.points.clone().cast_into().unwrap();
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &piece.cells.cell_verts
    else {
        panic!("not XML cells");
    };
    assert!(
        piece
            .cells
            .types
            .iter()
            .all(|t| *t == vtkio::model::CellType::Hexahedron)
    );
    let mut total = 0.0;
    let mut smallest = f64::INFINITY;
    let mut start = 0usize;
    for &end in offsets {
        let ids = &connectivity[start..end as usize];
        assert_eq!(ids.len(), 8);
        let c: [DVec3; 8] = std::array::from_fn(|k| {
            let i = ids[k] as usize;
            DVec3::new(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2])
        });
        let v = hex_volume(&c);
        total += v;
        smallest = smallest.min(v);
        start = end as usize;
    }
    (offsets.len(), total, smallest, pts.len() / 3)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn exports_the_interior_as_vtu_read_by_vtkio_and_the_boundary_as_iges_and_stl() {
    let data = data_dir("body-export");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let token = server.demo().editor.clone();
    let mut ed = Peer::connect(addr, design, &token).await;
    // The box [0, 2]³, tricubic 5 × 5 × 5 (2 spans a direction), an inner
    // point moved: the interior is no longer affine, the boundary is the box.
    let part = create_body(&mut ed, "block", json!({ "lattice": box_lattice(3, 5) })).await;
    ed.ok(json!({"type": "body_edit", "part": part, "edit": {"select": {"point": [2, 2, 2]}, "delta": [0.3, -0.2, 0.25]}}))
        .await;
    let mut spec = get(addr, "/api/demo-parts/spool", None).await.json();
    spec["name"] = json!("spool 2"); // the demo design has a "spool" already
    let spool = ed.ok(json!({"type": "create_part", "spec": spec})).await["part"]
        .as_u64()
        .unwrap();

    let vtu = get(
        addr,
        &format!("/api/designs/{design}/export.vtu?part={part}"),
        Some(&token),
    )
    .await;
    assert_eq!(vtu.status, 200);
    let (cells, total, smallest, points) = read_vtu(&vtu.text());
    // 4 cells per knot span: 8 per direction.
    assert_eq!(cells, 8 * 8 * 8);
    assert_eq!(points, 9 * 9 * 9);
    assert!(smallest > 0.0);
    // The hexes tile the box exactly (their boundary faces lie in its
    // planes); the kernel's exact integral of det J agrees.
    assert!((total - 8.0).abs() < 1e-9, "hex volumes sum to {total}");
    let doc = stored(addr, design, &token).await;
    let block = stored_volume(&stored_body(&doc, part)["body"]["lattice"]);
    assert!((interior::volume(&block) - 8.0).abs() < 1e-9);

    // The demo spool part is stored as the cube [−30, 30]³ (t = 0; the
    // spool is its morph target): its grid is exact too.
    let vtu = get(
        addr,
        &format!("/api/designs/{design}/export.vtu?part={spool}"),
        Some(&token),
    )
    .await;
    let (cells, total, smallest, _) = read_vtu(&vtu.text());
    let cube = stored_volume(&stored_body(&doc, spool)["body"]["lattice"]);
    let spans = |d| cube.knots(d).spans().len() * 4;
    use vsculpt_kernel::body::Dir;
    assert_eq!(cells, spans(Dir::U) * spans(Dir::V) * spans(Dir::W));
    assert!(smallest > 0.0);
    let exact = interior::volume(&cube);
    assert!(
        (total - exact).abs() < 1e-9 * exact,
        "the stored spool part is the cube at t = 0: {total} vs {exact}"
    );
    assert!((exact - 216_000.0).abs() < 1e-6 * exact);
    // Every body at once (no part named): the three grids (the block, the
    // spool added here and the demo design's own spool, also a cube).
    let all = get(
        addr,
        &format!("/api/designs/{design}/export.vtu"),
        Some(&token),
    )
    .await;
    let (cells_all, total_all, _, _) = read_vtu(&all.text());
    assert_eq!(cells_all, 512 + 2 * cells);
    assert!((total_all - 8.0 - 2.0 * exact).abs() < 1e-6 * exact);
    // Not a body: refused.
    let r = get(
        addr,
        &format!("/api/designs/{design}/export.vtu?part=1"),
        Some(&token),
    )
    .await;
    assert_eq!(r.status, 404);

    // IGES: six 128 faces, named by face, each the body's face.
    let igs = get(
        addr,
        &format!("/api/designs/{design}/export.igs?part={part}"),
        Some(&token),
    )
    .await;
    assert_eq!(igs.status, 200);
    let parts = vsculpt_server::cad::read_iges_parts(&igs.text()).unwrap();
    assert_eq!(parts.len(), 6);
    let names: Vec<String> = parts.iter().map(|p| p.name.clone().unwrap()).collect();
    assert_eq!(
        names,
        ["u_min", "u_max", "v_min", "v_max", "w_min", "w_max"].map(|f| format!("block {f}"))
    );
    for p in &parts {
        let vsculpt_server::cad::IgesEntity::Surface(s) = &p.entity else {
            panic!("not a surface");
        };
        // Every control point of a face of the box lies on one of its planes.
        let plane = (0..3)
            .find(|&a| {
                s.points
                    .iter()
                    .all(|q| (q[a] - s.points[0][a]).abs() < 1e-12)
            })
            .expect("a planar face");
        let at = s.points[0][plane];
        assert!(at.abs() < 1e-12 || (at - 2.0).abs() < 1e-12);
    }

    // STL: the boundary, its bounding box the box's.
    let stl = get(
        addr,
        &format!("/api/designs/{design}/export.stl?part={part}"),
        Some(&token),
    )
    .await;
    assert_eq!(stl.status, 200);
    let b = &stl.body;
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert!(n > 0);
    assert_eq!(b.len(), 84 + 50 * n);
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for t in 0..n {
        let o = 84 + 50 * t;
        let normal: Vec<f32> = (0..3)
            .map(|a| f32::from_le_bytes(b[o + 4 * a..o + 4 * a + 4].try_into().unwrap()))
            .collect();
        let mut c = [0.0f32; 3];
        for v in 0..3 {
            for a in 0..3 {
                let x = f32::from_le_bytes(
                    b[o + 12 + 12 * v + 4 * a..o + 16 + 12 * v + 4 * a]
                        .try_into()
                        .unwrap(),
                );
                lo[a] = lo[a].min(x);
                hi[a] = hi[a].max(x);
                c[a] += x / 3.0;
            }
        }
        // Outward: the normal points away from the box's centre.
        let out: f32 = (0..3).map(|a| normal[a] * (c[a] - 1.0)).sum();
        assert!(out > 0.0, "triangle {t} faces inward");
    }
    for a in 0..3 {
        assert!(
            lo[a].abs() < 1e-5 && (hi[a] - 2.0).abs() < 1e-5,
            "{lo:?} {hi:?}"
        );
    }
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
