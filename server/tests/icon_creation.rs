//! Creating an icon through the server never moves the shape (kernel issue
//! 15): on the demo design, every anchor kind × role a client can create, at
//! random places on the top shell (part 1), as the web client sends it (no
//! target: the server takes the surface's value at the anchor's centre)
//! leaves every control point of every part within 1e-9 of the model's
//! size, and each creation is undone again. The same on paper 003's five
//! surfaces (Table 2) bent by the paper's set-up, where a held curve must
//! also stay where it was created, between its samples too, across the
//! rebuilds from the document that every edit and undo cause, and the drags after them.

mod common;

use common::TestServer;
use common::http;
use common::ws::Client;
use serde_json::{Value, json};
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};

use common::random::Lcg;

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

/// The farthest any control point of `now` is from its place in `start`.
fn moved(now: &[[f64; 3]], start: &[[f64; 3]]) -> f64 {
    now.iter()
        .zip(start)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
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

/// Every anchor kind × role a client can create, at random places: the
/// eight point roles, then curves and inside and outside regions, each as
/// a position constraint and as a load, twice.
fn icon_specs(r: &mut Lcg) -> Vec<(Value, Value)> {
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
            specs.push((curve(r), role.clone()));
            specs.push((region(r, true), role.clone()));
            specs.push((region(r, false), role));
        }
    }
    specs
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
    let specs = icon_specs(&mut Lcg(15));
    for (anchor, role) in specs {
        let spec = json!({"anchor": anchor, "role": role, "state": "passive"});
        let reply = c
            .request(json!({"type": "create_icon", "part": 1, "spec": spec}))
            .await;
        assert_eq!(reply["type"], "ack", "{spec} → {reply}");
        let now = points(&http::get(server.addr, &path, Some(&d.editor)).await.json());
        let moved = moved(&now, &start);
        assert!(
            moved <= 1e-9 * size,
            "{spec}: moved {moved:e} mm (model size {size} mm)"
        );
        c.ok(json!({"type": "undo"})).await;
    }
    server.stop().await;
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Part `part`'s surface as the kernel's B-spline surface.
fn surface_of(design: &Value, part: u64) -> BSplineSurface {
    let doc = &common::parts::part(&design["design"], part)["body"]["surface"];
    let knots = |d: &str, k: &str| {
        let degree = doc[d].as_u64().unwrap() as usize;
        KnotVector::new(degree, serde_json::from_value(doc[k].clone()).unwrap()).unwrap()
    };
    let pts: Vec<[f64; 3]> = serde_json::from_value(doc["points"].clone()).unwrap();
    BSplineSurface::new(
        knots("u_degree", "u_knots"),
        knots("v_degree", "v_knots"),
        pts.iter().map(|p| glam::DVec3::from_array(*p)).collect(),
    )
    .unwrap()
}

/// `curve` (a curve anchor's JSON) at `n` + 1 even parameters, mapped onto
/// `surface`: ten times the kernel's own sampling of a held curve and
/// more, so a curve held only at samples shows between them.
fn along(surface: &BSplineSurface, curve: &Value, n: usize) -> Vec<glam::DVec3> {
    let degree = curve["knots"]["degree"].as_u64().unwrap() as usize;
    let knots = KnotVector::new(
        degree,
        serde_json::from_value(curve["knots"]["knots"].clone()).unwrap(),
    )
    .unwrap();
    let pts: Vec<[f64; 2]> = serde_json::from_value(curve["points"].clone()).unwrap();
    let c = BSplineCurve::new(
        knots,
        pts.iter()
            .map(|p| glam::DVec3::new(p[0], p[1], 0.0))
            .collect(),
    )
    .unwrap();
    let (a, b) = c.domain();
    (0..=n)
        .map(|i| {
            let q = c.point(a + (b - a) * i as f64 / n as f64);
            surface.point(q.x, q.y)
        })
        .collect()
}

fn farthest(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

/// Drags load `icon` on `part` by `by` in `steps` frames and releases it.
async fn drag_load(c: &mut Client, part: u64, icon: u64, from: [f64; 3], by: [f64; 3]) {
    c.ok(json!({"type": "drag_start", "part": part, "icon": icon}))
        .await;
    let steps = 8;
    for s in 1..=steps {
        let f = s as f64 / steps as f64;
        let xyz = [
            from[0] + by[0] * f,
            from[1] + by[1] * f,
            from[2] + by[2] * f,
        ];
        c.send(json!({"type": "drag", "part": part, "icon": icon, "xyz": xyz}))
            .await;
        loop {
            let fb = c.wait_for("icon_feedback").await;
            if fb["icon"] == icon && fb["requested"] == json!(xyz) {
                assert!(fb.get("warning").is_none(), "{fb}");
                break;
            }
        }
    }
    c.ok(json!({"type": "drag_end", "part": part, "icon": icon}))
        .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn on_the_papers_five_surfaces_icons_move_nothing_and_a_held_curve_stays() {
    let dir = common::data_dir("icon-creation-paper");
    let server = TestServer::start(dir.clone()).await;
    let d = server.demo().clone();
    for (nu, nv) in [(20, 15), (38, 32), (42, 40), (91, 54), (81, 159)] {
        let body = format!(r#"{{"name": "paper {nu}x{nv}", "nu": {nu}, "nv": {nv}}}"#);
        let created = http::request(
            server.addr,
            "POST",
            "/api/designs",
            Some(&d.editor),
            body.as_bytes(),
        )
        .await;
        assert_eq!(created.status, 201);
        let created = created.json();
        let id = created["id"].as_u64().unwrap();
        let token = created["tokens"]["editor"].as_str().unwrap().to_string();
        let path = format!("/api/designs/{id}");
        let mut c = Client::connect(server.addr, id, &token, "ann").await;
        let part = c.snapshot["parts"][0]["id"].as_u64().unwrap();
        let get = || http::get(server.addr, &path, Some(&token));

        // The paper's set-up: four point constraints, a held cubic curve
        // across the surface, a point load.
        for (u, v) in [(0.2, 0.2), (0.8, 0.2), (0.2, 0.8), (0.8, 0.8)] {
            c.ok(json!({"type": "create_icon", "part": part, "spec": {
                "anchor": {"kind": "point", "u": u, "v": v}, "role": {"kind": "position"}}}))
                .await;
        }
        // On 81 × 159 the held curve is the paper's straight one (a
        // free-form one across the plate is held by ~1250 equations whose
        // set-up still takes ~0.7 s release, kernel/README.md "Known
        // limits"); the random curves below are free-form everywhere.
        let big = nu * nv > 10_000;
        let held = if big {
            json!({"knots": {"degree": 1, "knots": [0, 0, 1, 1]}, "points": [[0.1, 0.1], [0.9, 0.1]]})
        } else {
            json!({"knots": {"degree": 3, "knots": [0, 0, 0, 0, 0.5, 1, 1, 1, 1]},
                "points": [[0.1, 0.12], [0.3, 0.3], [0.5, 0.05], [0.7, 0.35], [0.92, 0.15]]})
        };
        c.ok(json!({"type": "create_icon", "part": part, "spec": {
            "anchor": {"kind": "curve", "curve": held}, "role": {"kind": "position"}}}))
            .await;
        let load = c
            .request(json!({"type": "create_icon", "part": part, "spec": {
                "anchor": {"kind": "point", "u": 0.5, "v": 0.6}, "role": {"kind": "load"}}}))
            .await;
        assert_eq!(load["type"], "ack", "{load}");
        let load = load["icon"].as_u64().unwrap();
        let design = get().await.json();
        let flat = surface_of(&design, part);
        let curve_at = along(&flat, &held, 400);
        let size = {
            let p = points(&design);
            let (lo, hi) = p
                .iter()
                .fold(([f64::MAX; 3], [f64::MIN; 3]), |(mut lo, mut hi), q| {
                    for k in 0..3 {
                        lo[k] = lo[k].min(q[k]);
                        hi[k] = hi[k].max(q[k]);
                    }
                    (lo, hi)
                });
            (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
        };
        let load_at = |design: &Value| -> [f64; 3] {
            let icon = common::parts::icon(&design["design"], part, load);
            serde_json::from_value(icon["xyz"].clone()).unwrap()
        };

        // Bend it: the load pulled up by a fifth of the model's size.
        drag_load(&mut c, part, load, load_at(&design), [0.0, 0.0, 0.2 * size]).await;
        let bent = get().await.json();
        let start = points(&bent);
        let lifted = farthest(
            &along(
                &flat,
                &json!({"knots": {"degree": 1, "knots": [0, 0, 1, 1]},
                "points": [[0.5, 0.6], [0.5, 0.6]]}),
                0,
            ),
            &along(
                &surface_of(&bent, part),
                &json!({"knots": {"degree": 1, "knots": [0, 0, 1, 1]},
                "points": [[0.5, 0.6], [0.5, 0.6]]}),
                0,
            ),
        );
        assert!(
            lifted > 0.05 * size,
            "{nu}x{nv}: the load moved the shape {lifted}"
        );
        let drift = farthest(&along(&surface_of(&bent, part), &held, 400), &curve_at);
        assert!(
            drift <= 1e-9 * size,
            "{nu}x{nv}: the held curve moved {drift:e}"
        );

        // Every icon kind × role on the bent shape moves nothing.
        for (anchor, role) in icon_specs(&mut Lcg(nu as u64 * 1000 + nv as u64)) {
            let spec = json!({"anchor": anchor, "role": role, "state": "passive"});
            let reply = c
                .request(json!({"type": "create_icon", "part": part, "spec": spec}))
                .await;
            assert_eq!(reply["type"], "ack", "{nu}x{nv}: {spec} → {reply}");
            let now = points(&get().await.json());
            let moved = moved(&now, &start);
            assert!(
                moved <= 1e-9 * size,
                "{nu}x{nv}: {spec}: moved {moved:e} (size {size})"
            );
            c.ok(json!({"type": "undo"})).await;
        }

        // After those rebuilds (every edit and undo rebuilds the part), a kept icon
        // and a second pull: the
        // curve is still where it was created, everywhere along it.
        c.ok(json!({"type": "create_icon", "part": part, "spec": {
            "anchor": {"kind": "point", "u": 0.9, "v": 0.9}, "role": {"kind": "load"}}}))
            .await;
        let design = get().await.json();
        drag_load(
            &mut c,
            part,
            load,
            load_at(&design),
            [0.05 * size, 0.0, -0.3 * size],
        )
        .await;
        let last = get().await.json();
        let drift = farthest(&along(&surface_of(&last, part), &held, 400), &curve_at);
        assert!(
            drift <= 1e-9 * size,
            "{nu}x{nv}: after a rebuild the held curve moved {drift:e}"
        );
        for (u, v) in [(0.2, 0.2), (0.8, 0.2), (0.2, 0.8), (0.8, 0.8)] {
            let (p, q) = (flat.point(u, v), surface_of(&last, part).point(u, v));
            assert!(
                p.distance(q) <= 1e-9 * size,
                "{nu}x{nv}: point ({u}, {v}) moved"
            );
        }
    }
    server.stop().await;
    std::fs::remove_dir_all(&dir).unwrap();
}
