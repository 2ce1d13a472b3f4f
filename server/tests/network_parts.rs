//! A styling-curve network part (paper 004) through the real server: the
//! bottle template's network (nine curves, six faces, one five-sided) is
//! sent to every client with its meetings and faces and its patches as mesh
//! frames (kind 3) whose boundary lies on the curves; a dragged curve point
//! reaches a second client (new curve through the dragged point, meetings
//! kept, patches on the new curves); undo, redo, fairing (boundary points
//! never move), restart persistence, exports; bad input (NaN, huge counts,
//! unknown ids, a network with no faces, principal-curvature goals) is refused with a
//! clear error and changes nothing.

mod common;

use common::http::{get, request};
use common::ws::{WAIT, hello, raw};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use glam::DVec3;
use serde_json::{Value, json};
use std::collections::HashMap;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_protocol::MeshFrame;

/// A client that keeps text messages and mesh frames apart.
struct Net {
    ws: common::ws::Stream,
    snapshot: Value,
    req: u64,
}

enum In {
    Text(Value),
    Mesh(MeshFrame),
}

impl Net {
    async fn connect(addr: std::net::SocketAddr, design: u64, token: &str) -> Self {
        let mut ws = raw(addr).await;
        ws.send(Message::text(hello(design, token, "net").to_string()))
            .await
            .unwrap();
        let mut n = Self {
            ws,
            snapshot: Value::Null,
            req: 1,
        };
        let w = n.text().await;
        assert_eq!(w["type"], "welcome", "{w}");
        n.snapshot = n.text().await;
        assert_eq!(n.snapshot["type"], "snapshot");
        n
    }

    async fn next(&mut self) -> In {
        loop {
            let m = tokio::time::timeout(WAIT, self.ws.next())
                .await
                .expect("no message within 10 s")
                .expect("closed")
                .unwrap();
            match m {
                Message::Text(t) => return In::Text(serde_json::from_str(t.as_str()).unwrap()),
                Message::Binary(b) => return In::Mesh(MeshFrame::decode(&b).expect("mesh frame")),
                _ => {}
            }
        }
    }

    async fn text(&mut self) -> Value {
        loop {
            if let In::Text(v) = self.next().await {
                return v;
            }
        }
    }

    async fn wait_for(&mut self, ty: &str) -> Value {
        loop {
            let v = self.text().await;
            if v["type"] == ty {
                return v;
            }
        }
    }

    async fn mesh(&mut self) -> MeshFrame {
        loop {
            if let In::Mesh(m) = self.next().await {
                return m;
            }
        }
    }

    async fn mesh_after(&mut self, rev: u64) -> MeshFrame {
        loop {
            if let In::Mesh(m) = self.next().await
                && m.revision > rev
            {
                return m;
            }
        }
    }

    async fn request(&mut self, mut msg: Value) -> Value {
        let req = self.req;
        self.req += 1;
        msg["req"] = json!(req);
        self.ws.send(Message::text(msg.to_string())).await.unwrap();
        loop {
            let v = self.text().await;
            if v["req"] == json!(req) {
                return v;
            }
        }
    }

    async fn refused(&mut self, msg: Value, code: &str) -> String {
        let r = self.request(msg.clone()).await;
        assert_eq!(r["type"], "error", "{msg} → {r}");
        assert_eq!(r["code"], code, "{msg} → {r}");
        r["message"].as_str().unwrap().to_string()
    }
}

/// The kernel curves of a wire network.
fn curves_of(network: &Value) -> Vec<BSplineCurve> {
    network["curves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let kv = KnotVector::new(
                c["knots"]["degree"].as_u64().unwrap() as usize,
                serde_json::from_value(c["knots"]["knots"].clone()).unwrap(),
            )
            .unwrap();
            let pts: Vec<DVec3> = serde_json::from_value::<Vec<[f64; 3]>>(c["points"].clone())
                .unwrap()
                .into_iter()
                .map(DVec3::from)
                .collect();
            BSplineCurve::new(kv, pts).unwrap()
        })
        .collect()
}

/// Distance from `p` to curve `c`: the nearest of 400 samples refined by
/// Newton's method on (c(t) − p)·c′(t) = 0.
fn distance(c: &BSplineCurve, p: DVec3) -> f64 {
    let (a, b) = c.domain();
    let mut t = (0..=400)
        .map(|k| a + (b - a) * k as f64 / 400.0)
        .min_by(|x, y| c.point(*x).distance(p).total_cmp(&c.point(*y).distance(p)))
        .unwrap();
    for _ in 0..20 {
        let d = c.derivs(t);
        let f = (d.p - p).dot(d.d1);
        let df = d.d1.length_squared() + (d.p - p).dot(d.d2);
        if df.abs() < 1e-300 {
            break;
        }
        t = (t - f / df).clamp(a, b);
    }
    c.point(t).distance(p)
}

/// The mesh's positions in model units.
fn positions(m: &MeshFrame) -> Vec<DVec3> {
    m.positions
        .iter()
        .map(|q| {
            DVec3::new(
                m.origin[0] as f64 + q[0] as f64 * m.step as f64,
                m.origin[1] as f64 + q[1] as f64 * m.step as f64,
                m.origin[2] as f64 + q[2] as f64 * m.step as f64,
            )
        })
        .collect()
}

/// The vertices on the mesh's boundary (edges of one triangle only).
fn boundary(m: &MeshFrame) -> Vec<usize> {
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut v: Vec<usize> = count
        .iter()
        .filter(|(_, n)| **n == 1)
        .flat_map(|((a, b), _)| [*a as usize, *b as usize])
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The largest distance from a boundary vertex of the mesh to the nearest
/// curve.
fn boundary_gap(m: &MeshFrame, curves: &[BSplineCurve]) -> f64 {
    let pos = positions(m);
    boundary(m)
        .iter()
        .map(|&i| {
            curves
                .iter()
                .map(|c| distance(c, pos[i]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The quantisation error bound of a mesh frame (half a step per axis).
fn quantum(m: &MeshFrame) -> f64 {
    m.step as f64 * 0.5 * 3f64.sqrt() + 1e-6
}

async fn bottle_design(server: &TestServer, name: &str) -> (u64, String, String) {
    let body = json!({"name": name, "template": "bottle"}).to_string();
    let r = request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&server.admin),
        body.as_bytes(),
    )
    .await;
    assert_eq!(r.status, 201, "{}", r.text());
    let v = r.json();
    (
        v["id"].as_u64().unwrap(),
        v["tokens"]["editor"].as_str().unwrap().to_string(),
        v["tokens"]["viewer"].as_str().unwrap().to_string(),
    )
}

fn network(snapshot: &Value) -> Value {
    let p = &snapshot["parts"][0];
    assert_eq!(p["shape"]["kind"], "network", "{p}");
    p["shape"]["network"].clone()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bottle_drag_undo_fair_restart_through_the_server() {
    let data = data_dir("network-parts");
    let server = TestServer::start(data.clone()).await;
    let (id, editor, viewer) = bottle_design(&server, "bottle").await;
    let mut a = Net::connect(server.addr, id, &editor).await;
    let mut b = Net::connect(server.addr, id, &viewer).await;
    let net0 = network(&b.snapshot);
    let faces = net0["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 6, "{net0}");
    let sides: Vec<usize> = faces
        .iter()
        .map(|f| f["sides"].as_array().unwrap().len())
        .collect();
    assert_eq!(sides.iter().filter(|&&n| n == 5).count(), 1, "{sides:?}");
    let curves0 = curves_of(&net0);
    assert_eq!(curves0.len(), 9);
    // Every meeting point lies on each of its curves at its parameter.
    for m in net0["meetings"].as_array().unwrap() {
        let p = DVec3::from(serde_json::from_value::<[f64; 3]>(m["point"].clone()).unwrap());
        for ct in m["curves"].as_array().unwrap() {
            let (c, t) = (ct[0].as_u64().unwrap() as usize, ct[1].as_f64().unwrap());
            assert!(curves0[c].point(t).distance(p) < 1e-8);
        }
    }
    let first = b.mesh().await;
    assert_eq!(first.part, 1);
    let gap = boundary_gap(&first, &curves0);
    assert!(
        gap <= quantum(&first),
        "join mesh boundary off the curves by {gap}"
    );

    // Drag the bottom ring's front point (between its meetings at ±30°)
    // outwards by 0.1.
    let t = 0.5;
    let from = curves0[0].point(t);
    let to = from + DVec3::new(0.1, 0.0, 0.0);
    let r = a
        .request(json!({"type": "network_edit", "part": 1,
            "edit": {"op": "drag_point", "curve": 0, "t": t, "xyz": to.to_array()}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let changed = b.wait_for("network_changed").await;
    let net1 = changed["network"].clone();
    let curves1 = curves_of(&net1);
    assert!(
        curves1[0].point(t).distance(to) < 1e-9,
        "the curve passes the dragged point"
    );
    // Its meetings stay where they were.
    for m in net0["meetings"].as_array().unwrap() {
        for ct in m["curves"].as_array().unwrap() {
            if ct[0] == 0 {
                let tm = ct[1].as_f64().unwrap();
                assert!(curves1[0].point(tm).distance(curves0[0].point(tm)) < 1e-9);
            }
        }
    }
    let dragged = b.mesh_after(first.revision).await;
    let gap = boundary_gap(&dragged, &curves1);
    assert!(
        gap <= quantum(&dragged),
        "dragged mesh boundary off the new curves by {gap}"
    );
    // The old curves no longer describe the boundary: the check can fail.
    assert!(boundary_gap(&dragged, &curves0) > 0.05);

    // Undo: back to the first curves bit for bit, the same mesh.
    let r = a.request(json!({"type": "undo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap)["curves"], net0["curves"]);
    let undone = b.mesh_after(dragged.revision).await;
    assert_eq!(undone.positions, first.positions);
    assert_eq!(undone.triangles, first.triangles);
    let r = a.request(json!({"type": "redo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap)["curves"], net1["curves"]);
    let redone = b.mesh_after(undone.revision).await;

    // Fair the five-sided face toward its boundary's mean curvature.
    let five = sides.iter().position(|&n| n == 5).unwrap();
    let r = a
        .request(
            json!({"type": "network_edit", "part": 1, "edit": {"op": "fair",
            "face": five, "measure": "mean", "goal": "from_boundary", "max_iterations": 50}}),
        )
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let changed = b.wait_for("network_changed").await;
    assert_eq!(changed["network"]["faired"], json!([five]));
    let faired = b.mesh_after(redone.revision).await;
    let (p0, p1) = (positions(&redone), positions(&faired));
    let bnd: std::collections::BTreeSet<usize> = boundary(&redone).into_iter().collect();
    let moved_inside = (0..p0.len())
        .filter(|i| !bnd.contains(i))
        .map(|i| p0[i].distance(p1[i]))
        .fold(0.0, f64::max);
    let moved_boundary = bnd
        .iter()
        .map(|&i| p0[i].distance(p1[i]))
        .fold(0.0, f64::max);
    assert!(moved_inside > 1e-4, "fairing moved nothing inside");
    assert!(
        moved_boundary <= 2.0 * quantum(&faired),
        "fairing moved the boundary by {moved_boundary}"
    );

    // Exports: the patches as STL, the curves as IGES 126 entities, the
    // faces as trimmed refits (144).
    let stl = get(
        server.addr,
        &format!("/api/designs/{id}/export.stl?part=1"),
        Some(&editor),
    )
    .await;
    assert_eq!(stl.status, 200, "{}", stl.text());
    let tris = u32::from_le_bytes(stl.body[80..84].try_into().unwrap()) as usize;
    assert_eq!(tris, faired.triangles.len());
    let igs = get(
        server.addr,
        &format!("/api/designs/{id}/export.igs"),
        Some(&editor),
    )
    .await;
    assert_eq!(igs.status, 200);
    let text = igs.text();
    let independent = |ty: &str| {
        text.lines()
            .filter(|l| {
                // A directory entry is two lines; its first has an odd
                // sequence number. Independent: status 00000000.
                l.len() == 80
                    && &l[72..73] == "D"
                    && l[..8].trim() == ty
                    && &l[64..72] == "00000000"
                    && l[73..].trim().parse::<u32>().is_ok_and(|n| n % 2 == 1)
            })
            .count()
    };
    assert_eq!(independent("126"), 9, "one 126 per styling curve");
    // Each face (the faired one too) as its refit trimmed to the face
    // (`tests/network_iges.rs`).
    assert_eq!(independent("144"), 6, "one 144 per face");

    // Restart on the same data: the dragged, faired network comes back.
    let before = network(&Net::connect(server.addr, id, &viewer).await.snapshot);
    drop((a, b));
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let c = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&c.snapshot), before);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_network_input_is_refused_and_changes_nothing() {
    let data = data_dir("network-bad");
    let server = TestServer::start(data.clone()).await;
    let (id, editor, viewer) = bottle_design(&server, "bottle").await;
    let mut a = Net::connect(server.addr, id, &editor).await;
    let before = network(&a.snapshot);
    let edit = |e: Value| json!({"type": "network_edit", "part": 1, "edit": e});
    // NaN and ∞ never reach the design.
    a.ws.send(Message::text(
        "{\"type\": \"network_edit\", \"req\": 90, \"part\": 1, \"edit\": {\"op\": \"move_point\", \"curve\": 0, \"index\": 3, \"xyz\": [NaN, 0, 0]}}",
    ))
    .await
    .unwrap();
    let e = a.wait_for("error").await;
    assert!(e["code"] == "malformed" || e["code"] == "not_finite", "{e}");
    a.refused(
        edit(json!({"op": "drag_point", "curve": 0, "t": 0.5, "xyz": [1e300, 0, 0]})),
        "out_of_range",
    )
    .await;
    // Unknown ids.
    let m = a
        .refused(
            edit(json!({"op": "move_point", "curve": 99, "index": 0, "xyz": [0, 0, 0]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("no curve 99"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "move_point", "curve": 0, "index": 5000, "xyz": [0, 0, 0]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("no control point 5000"), "{m}");
    a.refused(
        edit(json!({"op": "fair", "face": 6, "measure": "mean", "goal": "from_boundary"})),
        "out_of_range",
    )
    .await;
    a.refused(
        json!({"type": "network_edit", "part": 77, "edit": {"op": "remove_curve", "curve": 0}}),
        "unknown_part",
    )
    .await;
    // Principal-curvature goals are refused by the kernel.
    let m = a
        .refused(
            edit(
                json!({"op": "fair", "face": 0, "measure": "max_principal", "goal": {"constant": 1.0}}),
            ),
            "out_of_range",
        )
        .await;
    assert!(m.contains("Gaussian"), "{m}");
    // Huge counts.
    let many: Vec<[f64; 3]> = (0..2000).map(|k| [k as f64, 0.0, 0.0]).collect();
    let mut knots = vec![0.0; 2];
    knots.extend((1..1999).map(|k| k as f64));
    knots.extend([1999.0; 2]);
    let r = a
        .request(edit(json!({"op": "add_curve", "curve": {"knots": {"degree": 1, "knots": knots}, "points": many}})))
        .await;
    assert_eq!(r["type"], "error", "{r}");
    assert_eq!(r["code"], "too_large", "{r}");
    let max_iter = edit(
        json!({"op": "fair", "face": 0, "measure": "mean", "goal": "from_boundary", "max_iterations": 200_000}),
    );
    a.refused(max_iter, "out_of_range").await;
    // An edit that opens a face: the bottom ring removed leaves the
    // meridians' lower ends free.
    let m = a
        .refused(
            edit(json!({"op": "remove_curve", "curve": 0})),
            "incompatible",
        )
        .await;
    assert!(m.contains("open"), "{m}");
    // A control point moved at a meeting loses it.
    let r = a
        .request(edit(
            json!({"op": "move_point", "curve": 0, "index": 0, "xyz": [0.0, -1.5, 0.0]}),
        ))
        .await;
    assert_eq!(r["code"], "incompatible", "{r}");
    // A drag at a meeting is refused.
    a.refused(
        edit(json!({"op": "drag_point", "curve": 0, "t": 0.0, "xyz": [0.0, -1.1, 0.0]})),
        "out_of_range",
    )
    .await;
    // A network enclosing no face: two crossing lines.
    let line = |p: [f64; 3], q: [f64; 3]| json!({"knots": {"degree": 1, "knots": [0, 0, 1, 1]}, "points": [p, q]});
    let r = a
        .request(json!({"type": "create_part", "spec": {"name": "cross", "shape": {"kind": "network",
            "network": {"curves": [line([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]), line([0.0, -1.0, 0.0], [0.0, 1.0, 0.0])],
                        "tolerance": 1e-6, "up": [0, 0, 1]}}}}))
        .await;
    assert_eq!(r["type"], "error", "{r}");
    assert_eq!(r["code"], "incompatible", "{r}");
    // Icons and materials are not a network's.
    a.refused(
        json!({"type": "set_material", "part": 1, "material": {"alpha": 1.0, "beta": 1.0}}),
        "incompatible",
    )
    .await;
    // Nothing changed: a new client sees the same network, one part, and
    // nothing to undo.
    let fresh = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&fresh.snapshot), before);
    assert_eq!(fresh.snapshot["parts"].as_array().unwrap().len(), 1);
    assert_eq!(fresh.snapshot["can_undo"], false, "{}", fresh.snapshot);
    // A good triangle network is created and drawn.
    let r = a
        .request(json!({"type": "create_part", "spec": {"name": "triangle", "shape": {"kind": "network",
            "network": {"curves": [line([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), line([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), line([0.0, 1.0, 0.0], [0.0, 0.0, 0.0])],
                        "tolerance": 1e-6, "up": [0, 0, 1]}}}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let fresh = Net::connect(server.addr, id, &viewer).await;
    let created = &fresh.snapshot["parts"][1];
    assert_eq!(created["shape"]["kind"], "network", "{created}");
    assert_eq!(
        created["shape"]["network"]["faces"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
