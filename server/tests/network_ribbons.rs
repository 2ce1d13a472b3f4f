//! A network part's ribbon handles (paper 004 §5) through the real server:
//! `network_edit` `set_ribbon` sets a side's scale and twist on the bottle's
//! five-sided face. The mesh frame that follows is compared, sample by
//! sample, with patches the test builds itself with the kernel from the
//! curves and handles the server reports (so the server applied exactly
//! what it says), the face's interior moved (measured) while its boundary
//! stayed on the curves, and the patches the handles give join G1 across
//! every shared curve (normals on both sides at 50 points per curve piece
//! agree to 1e-9 rad). Undo restores the mesh bit for bit, redo and a
//! restart keep the handles, and bad values are refused with a clear error,
//! changing nothing. The same for a face's tuning handles (`set_tuning`):
//! the mesh is the test's kernel patches with the reported handles, the
//! interior moves, the boundary and the G1 joins stay.

mod common;

use common::http::request;
use common::ws::{WAIT, hello, raw};
use common::{TestServer, data_dir};
use futures_util::{SinkExt, StreamExt};
use glam::DVec3;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_kernel::network::{CurveNetwork, NetworkOptions, PatchSampler};
use vsculpt_protocol::MeshFrame;

/// The server's sample resolution of a face (`network_engine::MESH_RESOLUTION`).
const RESOLUTION: usize = 12;

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

async fn bottle_design(server: &TestServer) -> (u64, String, String) {
    let body = json!({"name": "ribbons", "template": "bottle"}).to_string();
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

/// The test's own kernel network of a wire network: its curves, tolerance
/// and up, with the scales and twists of `ribbons` (per face, per side;
/// a side's twist set on each of its edges) and the faces' `tuning`.
fn kernel_network(net: &Value) -> CurveNetwork {
    let curves: Vec<BSplineCurve> = net["curves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let kv = KnotVector::new(
                c["knots"]["degree"].as_u64().unwrap() as usize,
                serde_json::from_value(c["knots"]["knots"].clone()).unwrap(),
            )
            .unwrap();
            let pts = serde_json::from_value::<Vec<[f64; 3]>>(c["points"].clone())
                .unwrap()
                .into_iter()
                .map(DVec3::from)
                .collect();
            BSplineCurve::new(kv, pts).unwrap()
        })
        .collect();
    let up: [f64; 3] = serde_json::from_value(net["up"].clone()).unwrap();
    let mut k = CurveNetwork::new(
        curves,
        NetworkOptions {
            tolerance: net["tolerance"].as_f64().unwrap(),
            up: DVec3::from(up),
        },
    )
    .unwrap();
    let ribbons = net["ribbons"].as_array().expect("ribbons per face");
    assert_eq!(ribbons.len(), k.faces().len());
    for (f, sides) in ribbons.iter().enumerate() {
        for (s, h) in sides.as_array().unwrap().iter().enumerate() {
            k.set_scale(f, s, h["scale"].as_f64().unwrap()).unwrap();
            let twist = h["twist"].as_f64().unwrap();
            if twist != 0.0 {
                for e in k.faces()[f].sides[s].edges.clone() {
                    k.set_twist(e, twist).unwrap();
                }
            }
        }
    }
    let tuning = net["tuning"].as_array().expect("tuning per face");
    assert_eq!(tuning.len(), k.faces().len());
    for (f, h) in tuning.iter().enumerate() {
        let h: Vec<[f64; 3]> = serde_json::from_value(h.clone()).unwrap();
        k.set_tuning(f, h.into_iter().map(DVec3::from).collect())
            .unwrap();
    }
    k
}

/// Every face's samples of `net`, faces one after another (the order of
/// the server's mesh frame), and where each face's samples start.
fn samples(net: &CurveNetwork) -> (Vec<DVec3>, Vec<usize>) {
    let mut all = Vec::new();
    let mut starts = Vec::new();
    for p in net.patches() {
        starts.push(all.len());
        let sampler = PatchSampler::new(&p, RESOLUTION);
        all.extend(sampler.mesh().points.iter().map(|q| p.point(*q)));
    }
    starts.push(all.len());
    (all, starts)
}

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

/// The quantisation error bound of a mesh frame (half a step per axis).
fn quantum(m: &MeshFrame) -> f64 {
    m.step as f64 * 0.5 * 3f64.sqrt() + 1e-6
}

/// The largest distance between the frame's vertices and `expected`.
fn gap(m: &MeshFrame, expected: &[DVec3]) -> f64 {
    let p = positions(m);
    assert_eq!(p.len(), expected.len(), "sample count");
    p.iter()
        .zip(expected)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max)
}

/// Largest angle between the normals of the two patches on each curve
/// piece shared by two faces, at 50 interior points per piece (atan2 of
/// |n0 × n1| and n0·n1, which resolves angles far below 1e-9).
fn g1_error(net: &CurveNetwork) -> (f64, usize) {
    let patches = net.patches();
    let topo = net.topology();
    let (mut worst, mut shared) = (0.0f64, 0);
    for (e, edge) in topo.edges.iter().enumerate() {
        let holders: Vec<(usize, usize)> = topo
            .faces
            .iter()
            .enumerate()
            .flat_map(|(f, face)| {
                face.sides
                    .iter()
                    .enumerate()
                    .filter(move |(_, s)| s.edges.contains(&e))
                    .map(move |(i, _)| (f, i))
            })
            .collect();
        if holders.len() != 2 {
            continue;
        }
        shared += 1;
        for k in 1..=50 {
            let t = edge.t0 + (edge.t1 - edge.t0) * k as f64 / 51.0;
            let n: Vec<DVec3> = holders
                .iter()
                .map(|&(f, i)| {
                    let p = &patches[f];
                    let r = &p.ribbons()[i];
                    let s = (t - r.t_start) / (r.t_end - r.t_start);
                    p.normal(p.domain().side_point(i, s))
                })
                .collect();
            worst = worst.max(n[0].cross(n[1]).length().atan2(n[0].dot(n[1])));
        }
    }
    (worst, shared)
}

/// The five-sided face and one of its sides that another face shares.
fn five_and_shared_side(k: &CurveNetwork) -> (usize, usize) {
    let five = k.faces().iter().position(|f| f.sides.len() == 5).unwrap();
    let side = (0..5)
        .find(|&s| {
            let e = k.faces()[five].sides[s].edges[0];
            k.faces()
                .iter()
                .enumerate()
                .any(|(g, f)| g != five && f.sides.iter().any(|x| x.edges.contains(&e)))
        })
        .expect("a shared side");
    (five, side)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ribbon_edit_reshapes_the_face_inside_keeps_boundary_and_g1_undoes_and_persists() {
    let data = data_dir("network-ribbons");
    let server = TestServer::start(data.clone()).await;
    let (id, editor, viewer) = bottle_design(&server).await;
    let mut a = Net::connect(server.addr, id, &editor).await;
    let mut b = Net::connect(server.addr, id, &viewer).await;
    let net0 = network(&b.snapshot);
    // Default handles: scale 1, twist 0 on every side.
    for sides in net0["ribbons"].as_array().unwrap() {
        for h in sides.as_array().unwrap() {
            assert_eq!(*h, json!({"scale": 1.0, "twist": 0.0}), "{net0}");
        }
    }
    let k0 = kernel_network(&net0);
    let (five, side) = five_and_shared_side(&k0);
    let (plain, starts) = samples(&k0);
    let first = b.mesh().await;
    assert!(gap(&first, &plain) <= quantum(&first));

    let (scale, twist) = (2.5, 0.3);
    let r = a
        .request(
            json!({"type": "network_edit", "part": 1, "edit": {"op": "set_ribbon",
            "face": five, "side": side, "scale": scale, "twist": twist}}),
        )
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let changed = b.wait_for("network_changed").await;
    let net1 = changed["network"].clone();
    assert_eq!(
        net1["ribbons"][five][side],
        json!({"scale": scale, "twist": twist}),
        "{net1}"
    );
    assert_eq!(net1["curves"], net0["curves"]);
    let edited = b.mesh_after(first.revision).await;

    // The server's mesh is the kernel's patches with the reported handles.
    let k1 = kernel_network(&net1);
    let (handled, _) = samples(&k1);
    let off = gap(&edited, &handled);
    assert!(
        off <= quantum(&edited),
        "mesh off the handled patches by {off}"
    );

    // The five-sided face's interior moved; its boundary did not.
    let p0 = positions(&first);
    let p1 = positions(&edited);
    let bnd = PatchSampler::new(&k0.patch(five).unwrap(), RESOLUTION)
        .mesh()
        .boundary
        .clone();
    let (mut inside, mut on_boundary) = (0.0f64, 0.0f64);
    for (j, is_b) in bnd.iter().enumerate() {
        let d = p0[starts[five] + j].distance(p1[starts[five] + j]);
        if *is_b {
            on_boundary = on_boundary.max(d);
        } else {
            inside = inside.max(d);
        }
    }
    println!(
        "ribbon edit: interior moved {inside:.4}, boundary {on_boundary:.2e}, mesh vs kernel {off:.2e}"
    );
    assert!(inside > 0.01, "the interior moved only {inside}");
    assert!(
        on_boundary <= 2.0 * quantum(&edited),
        "the boundary moved by {on_boundary}"
    );
    // G1 across every shared curve with the handles.
    let (g, shared) = g1_error(&k1);
    println!("ribbon edit: normal angle {g:.2e} rad over {shared} shared edges");
    assert!(shared >= 6, "{shared} shared edges");
    assert!(g <= 1e-9, "normals differ by {g} rad across shared curves");

    // Undo: the mesh as it was, bit for bit, and the handles back to 1, 0.
    let r = a.request(json!({"type": "undo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap), net0);
    let undone = b.mesh_after(edited.revision).await;
    assert_eq!(undone.positions, first.positions);
    assert_eq!(undone.normals, first.normals);
    assert_eq!(undone.triangles, first.triangles);
    // Redo, then restart: the handles and the mesh come back.
    let r = a.request(json!({"type": "redo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap), net1);
    let redone = b.mesh_after(undone.revision).await;
    assert_eq!(redone.positions, edited.positions);
    drop((a, b));
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let mut c = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&c.snapshot), net1);
    let again = c.mesh().await;
    assert_eq!(again.positions, edited.positions);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_ribbon_edits_are_refused_and_change_nothing() {
    let data = data_dir("network-ribbons-bad");
    let server = TestServer::start(data.clone()).await;
    let (id, editor, viewer) = bottle_design(&server).await;
    let mut a = Net::connect(server.addr, id, &editor).await;
    let before = network(&a.snapshot);
    let k = kernel_network(&before);
    let (five, _) = five_and_shared_side(&k);
    let four = k.faces().iter().position(|f| f.sides.len() == 4).unwrap();
    let edit = |e: Value| json!({"type": "network_edit", "part": 1, "edit": e});
    // NaN never reaches the design.
    a.ws.send(Message::text(format!(
        "{{\"type\": \"network_edit\", \"req\": 90, \"part\": 1, \"edit\": {{\"op\": \"set_ribbon\", \"face\": {five}, \"side\": 0, \"scale\": NaN}}}}"
    )))
    .await
    .unwrap();
    let e = a.wait_for("error").await;
    assert!(e["code"] == "malformed" || e["code"] == "not_finite", "{e}");
    for bad in [0.0, -1.0, 0.05, 10.5, 1e300] {
        let m = a
            .refused(
                edit(json!({"op": "set_ribbon", "face": five, "side": 0, "scale": bad})),
                "out_of_range",
            )
            .await;
        assert!(m.contains("scale"), "{m}");
    }
    for bad in [1.6, -1.6, 3.0] {
        let m = a
            .refused(
                edit(json!({"op": "set_ribbon", "face": five, "side": 0, "twist": bad})),
                "out_of_range",
            )
            .await;
        assert!(m.contains("twist"), "{m}");
    }
    // A good scale with a bad twist changes neither.
    a.refused(
        edit(json!({"op": "set_ribbon", "face": five, "side": 0, "scale": 2.0, "twist": 2.0})),
        "out_of_range",
    )
    .await;
    let m = a
        .refused(
            edit(json!({"op": "set_ribbon", "face": 6, "side": 0, "scale": 2.0})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("no face 6"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "set_ribbon", "face": four, "side": 4, "scale": 2.0})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("no side 4"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "set_ribbon", "face": five, "side": 0})),
            "malformed",
        )
        .await;
    assert!(m.contains("scale or a twist"), "{m}");
    // Nothing changed: a new client sees the same network, nothing to undo.
    let fresh = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&fresh.snapshot), before);
    assert_eq!(fresh.snapshot["can_undo"], false, "{}", fresh.snapshot);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_tuning_edit_moves_the_interior_only_keeps_g1_undoes_persists_and_refuses_bad_handles() {
    let data = data_dir("network-tuning");
    let server = TestServer::start(data.clone()).await;
    let (id, editor, viewer) = bottle_design(&server).await;
    let mut a = Net::connect(server.addr, id, &editor).await;
    let mut b = Net::connect(server.addr, id, &viewer).await;
    let net0 = network(&b.snapshot);
    // Default: n + 1 zero handles per face.
    let k0 = kernel_network(&net0);
    for (f, h) in net0["tuning"].as_array().unwrap().iter().enumerate() {
        assert_eq!(
            *h,
            json!(vec![[0.0, 0.0, 0.0]; k0.faces()[f].sides.len() + 1]),
            "{net0}"
        );
    }
    let (five, _) = five_and_shared_side(&k0);
    let (plain, starts) = samples(&k0);
    let first = b.mesh().await;
    assert!(gap(&first, &plain) <= quantum(&first));

    // Bad handles: refused, nothing changes.
    let edit = |e: Value| json!({"type": "network_edit", "part": 1, "edit": e});
    let m = a
        .refused(
            edit(json!({"op": "set_tuning", "face": five, "handles": vec![[0.0, 0.0, 0.1]; 5]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("takes 6 tuning handles"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "set_tuning", "face": five, "handles": vec![[0.0, 0.0, 0.1]; 3]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("tuning handles"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "set_tuning", "face": five, "handles": vec![[0.0, 1e300, 0.0]; 6]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("handles"), "{m}");
    let m = a
        .refused(
            edit(json!({"op": "set_tuning", "face": 6, "handles": vec![[0.0, 0.0, 0.1]; 5]})),
            "out_of_range",
        )
        .await;
    assert!(m.contains("no face 6"), "{m}");
    let fresh = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&fresh.snapshot), net0);
    assert_eq!(fresh.snapshot["can_undo"], false, "{}", fresh.snapshot);
    drop(fresh);

    // The centre pushed along the face's normal at its centre, one corner sideways.
    let n = k0.patch(five).unwrap().normal(glam::DVec2::ZERO);
    let mut handles = vec![[0.0; 3]; 6];
    handles[0] = (n * 0.15).to_array();
    handles[2] = [0.05, -0.03, 0.02];
    let r = a
        .request(edit(
            json!({"op": "set_tuning", "face": five, "handles": handles}),
        ))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let changed = b.wait_for("network_changed").await;
    let net1 = changed["network"].clone();
    assert_eq!(net1["tuning"][five], json!(handles), "{net1}");
    assert_eq!(net1["curves"], net0["curves"]);
    assert_eq!(net1["ribbons"], net0["ribbons"]);
    let edited = b.mesh_after(first.revision).await;
    let k1 = kernel_network(&net1);
    let (tuned, _) = samples(&k1);
    let off = gap(&edited, &tuned);
    assert!(
        off <= quantum(&edited),
        "mesh off the tuned patches by {off}"
    );

    // The five-sided face's interior moved — at its centre by the sum of
    // the handles (there every weight is 1: β/β(centre) = 1 and each
    // corner's n λ_k = 1) — while its boundary and every other face did not.
    let p0 = positions(&first);
    let p1 = positions(&edited);
    let dm = PatchSampler::new(&k0.patch(five).unwrap(), RESOLUTION)
        .mesh()
        .clone();
    let sum: DVec3 = handles.iter().map(|h| DVec3::from(*h)).sum();
    let (mut inside, mut on_boundary, mut centre) = (0.0f64, 0.0f64, f64::NAN);
    for (j, is_b) in dm.boundary.iter().enumerate() {
        let d = p0[starts[five] + j].distance(p1[starts[five] + j]);
        if *is_b {
            on_boundary = on_boundary.max(d);
        } else {
            inside = inside.max(d);
        }
        if dm.points[j].length() < 1e-12 {
            centre = (p1[starts[five] + j] - p0[starts[five] + j]).distance(sum);
        }
    }
    let others = (0..starts.len() - 1)
        .filter(|&f| f != five)
        .flat_map(|f| starts[f]..starts[f + 1])
        .map(|j| p0[j].distance(p1[j]))
        .fold(0.0f64, f64::max);
    println!(
        "tuning edit: interior moved {inside:.4} (centre off the handles' sum by {centre:.2e}), boundary {on_boundary:.2e}, other faces {others:.2e}, mesh vs kernel {off:.2e}"
    );
    assert!(
        centre <= 2.0 * quantum(&edited),
        "centre off the handles' sum by {centre}"
    );
    assert!(
        inside >= sum.length() - 2.0 * quantum(&edited),
        "interior moved {inside}"
    );
    assert!(
        on_boundary <= 2.0 * quantum(&edited),
        "boundary moved {on_boundary}"
    );
    assert!(
        others <= 2.0 * quantum(&edited),
        "other faces moved {others}"
    );
    let (g, shared) = g1_error(&k1);
    println!("tuning edit: normal angle {g:.2e} rad over {shared} shared edges");
    assert!(g <= 1e-9, "normals differ by {g} rad across shared curves");

    // Undo: bit for bit; redo and a restart keep the handles.
    let r = a.request(json!({"type": "undo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap), net0);
    let undone = b.mesh_after(edited.revision).await;
    assert_eq!(undone.positions, first.positions);
    assert_eq!(undone.normals, first.normals);
    let r = a.request(json!({"type": "redo"})).await;
    assert_eq!(r["type"], "ack", "{r}");
    let snap = b.wait_for("snapshot").await;
    assert_eq!(network(&snap), net1);
    drop((a, b));
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let mut c = Net::connect(server.addr, id, &viewer).await;
    assert_eq!(network(&c.snapshot), net1);
    let again = c.mesh().await;
    assert_eq!(again.positions, edited.positions);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
