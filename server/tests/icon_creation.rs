//! Creating an icon through the server never moves the shape (kernel issue
//! 15): on the demo design, every anchor kind × role a client can create, at
//! random places on the top shell (part 1), as the web client sends it (no
//! target: the server takes the surface's value at the anchor's centre)
//! leaves every control point of every part within 1e-9 of the model's
//! size, and each creation is undone again.

mod common;

use common::TestServer;
use common::http;
use common::ws::Client;
use serde_json::{Value, json};

/// A small deterministic generator (64-bit LCG, top bits).
struct Lcg(u64);

impl Lcg {
    fn within(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Every control point of every part (surfaces and curves), in order.
fn points(design: &Value) -> Vec<[f64; 3]> {
    let doc = &design["design"];
    let mut out = Vec::new();
    for id in common::parts::part_ids(doc) {
        let body = &common::parts::part(doc, id)["body"];
        if body["kind"] == "body" {
            continue; // the demo's spool: a lattice, no icons
        }
        let shape = &body[body["kind"].as_str().unwrap()];
        out.extend(
            shape["points"]
                .as_array()
                .unwrap_or_else(|| panic!("no points on part {id} in {design}"))
                .iter()
                .map(|p| {
                    let c = |k: usize| p[k].as_f64().unwrap();
                    [c(0), c(1), c(2)]
                }),
        );
    }
    out
}

/// A clicked curve as the web client builds it (web-client/src/app.js).
fn curve(r: &mut Lcg) -> Value {
    let n = 2 + (r.within(0.0, 3.999) as usize);
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|_| [r.within(0.03, 0.97), r.within(0.03, 0.97)])
        .collect();
    let degree = 3.min(n - 1);
    let mut knots = vec![0.0; degree + 1];
    for k in 1..n - degree {
        knots.push(k as f64 / (n - degree) as f64);
    }
    knots.extend(std::iter::repeat_n(1.0, degree + 1));
    json!({"kind": "curve", "curve": {"knots": {"degree": degree, "knots": knots}, "points": pts}})
}

fn region(r: &mut Lcg, inside: bool) -> Value {
    let (u0, v0) = (r.within(0.02, 0.6), r.within(0.02, 0.6));
    json!({"kind": "region", "u0": u0, "v0": v0,
           "u1": u0 + r.within(0.1, 0.35), "v1": v0 + r.within(0.1, 0.35), "inside": inside})
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn creating_any_icon_on_the_demo_moves_nothing() {
    let dir = common::data_dir("icon-creation");
    let server = TestServer::start(dir.clone()).await;
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    let path = format!("/api/designs/{}", d.id);
    let start = points(&http::get(server.addr, &path, Some(&d.editor)).await.json());
    let size = {
        let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
        for p in &start {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    };
    let mut r = Lcg(15);
    let mut specs = Vec::new();
    let point_roles = [
        json!({"kind": "position"}),
        json!({"kind": "load"}),
        json!({"kind": "normal"}),
        json!({"kind": "derivative", "which": "R"}),
        json!({"kind": "derivative", "which": "V"}),
        json!({"kind": "derivative", "which": "R2"}),
        json!({"kind": "derivative", "which": "V2"}),
        json!({"kind": "derivative", "which": "RV"}),
    ];
    for role in point_roles {
        let anchor = json!({"kind": "point", "u": r.within(0.02, 0.98), "v": r.within(0.02, 0.98)});
        specs.push((anchor, role));
    }
    for _ in 0..2 {
        for role in [json!({"kind": "position"}), json!({"kind": "load"})] {
            specs.push((curve(&mut r), role.clone()));
            specs.push((region(&mut r, true), role.clone()));
            specs.push((region(&mut r, false), role));
        }
    }
    for (anchor, role) in specs {
        let spec = json!({"anchor": anchor, "role": role, "state": "passive"});
        let reply = c
            .request(json!({"type": "create_icon", "part": 1, "spec": spec}))
            .await;
        assert_eq!(reply["type"], "ack", "{spec} → {reply}");
        let now = points(&http::get(server.addr, &path, Some(&d.editor)).await.json());
        let moved = now
            .iter()
            .zip(&start)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        assert!(
            moved <= 1e-9 * size,
            "{spec}: moved {moved:e} mm (model size {size} mm)"
        );
        c.ok(json!({"type": "undo"})).await;
    }
    server.stop().await;
    std::fs::remove_dir_all(&dir).unwrap();
}
