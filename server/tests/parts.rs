//! A design of many parts through the real server: three surfaces and two
//! curves created and edited one by one, two surfaces joined G1 and the seam
//! dragged (the normals across it agree after every frame, to f32 in the
//! frames and to 1e-9 rad in the stored f64 shape), frames only for the
//! parts that moved, locks and hidden parts, commit, restart, restore and
//! undo across parts.

mod common;

use common::http::get;
use common::ws::{Client, Got};
use common::{TestServer, data_dir};
use glam::DVec3;
use serde_json::{Value, json};
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector};

/// A `nu × nv` bicubic (clamped uniform) surface over x ∈ [x0, x0 + w],
/// y ∈ [-50, 50], z = `z(x, y)`, as the protocol's `surface`.
fn plate_json(nu: usize, nv: usize, x0: f64, w: f64, z: impl Fn(f64, f64) -> f64) -> Value {
    let knots = |n: usize| {
        let spans = n - 3;
        let mut k = vec![0.0; 4];
        k.extend((1..spans).map(|i| i as f64 / spans as f64));
        k.extend(vec![1.0; 4]);
        k
    };
    let greville = |n: usize| -> Vec<f64> {
        let k = knots(n);
        (0..n)
            .map(|i| (k[i + 1] + k[i + 2] + k[i + 3]) / 3.0)
            .collect()
    };
    let (gu, gv) = (greville(nu), greville(nv));
    let mut points = Vec::new();
    for s in &gu {
        for t in &gv {
            let (x, y) = (x0 + w * s, 100.0 * t - 50.0);
            points.push(json!([x, y, z(x, y)]));
        }
    }
    json!({"u": {"degree": 3, "knots": knots(nu)}, "v": {"degree": 3, "knots": knots(nv)},
           "nu": nu, "nv": nv, "points": points})
}

fn curve_json(points: &[[f64; 3]]) -> Value {
    let n = points.len();
    let spans = n - 2;
    let mut k = vec![0.0; 3];
    k.extend((1..spans).map(|i| i as f64 / spans as f64));
    k.extend(vec![1.0; 3]);
    json!({"knots": {"degree": 2, "knots": k}, "points": points})
}

/// A kernel surface from the protocol's `surface` (f64 from JSON, or the
/// frame's f32 points when given).
fn surface_of(s: &Value, points: Option<&[[f32; 3]]>) -> BSplineSurface {
    let kv = |k: &Value| {
        KnotVector::new(
            k["degree"].as_u64().unwrap() as usize,
            serde_json::from_value(k["knots"].clone()).unwrap(),
        )
        .unwrap()
    };
    let pts: Vec<DVec3> = match points {
        Some(p) => p
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect(),
        None => s["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| DVec3::from_array(serde_json::from_value(p.clone()).unwrap()))
            .collect(),
    };
    BSplineSurface::new(kv(&s["u"]), kv(&s["v"]), pts).unwrap()
}

/// The largest angle (radians) between the normals of `a` at u = u_max and
/// of `b` at u = u_min, at 50 points along the seam, and the largest gap
/// between the seam points.
fn seam_mismatch(a: &BSplineSurface, b: &BSplineSurface) -> (f64, f64) {
    let ((_, a1), (av0, av1)) = a.domain();
    let ((b0, _), (bv0, bv1)) = b.domain();
    let (mut angle, mut gap) = (0.0f64, 0.0f64);
    for k in 0..50 {
        let s = k as f64 / 49.0;
        let (va, vb) = (av0 + s * (av1 - av0), bv0 + s * (bv1 - bv0));
        let (na, nb) = (a.normal(a1, va), b.normal(b0, vb));
        // atan2(|a × b|, a · b): exact near 0, where acos loses half the
        // digits (1.5e-8 rad for parallel unit vectors).
        angle = angle.max(na.cross(nb).length().atan2(na.dot(nb)));
        gap = gap.max((a.point(a1, va) - b.point(b0, vb)).length());
    }
    (angle, gap)
}

/// The frames of revision `rev` (older ones skipped). A writer sends the
/// frames of one published set back to back, so once the first of `rev` is
/// in, a ping sent then is answered after the last of them.
async fn frames_of(viewer: &mut Client, rev: u64) -> Vec<vsculpt_protocol::GeometryFrame> {
    let mut out = Vec::new();
    loop {
        match viewer.next().await {
            Got::Frame(f) if f.revision == rev => {
                out.push(f);
                break;
            }
            Got::Frame(f) if f.revision > rev => {
                panic!("revision {} came before {rev}", f.revision)
            }
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
    viewer.send(json!({"type": "ping"})).await;
    loop {
        match viewer.next().await {
            Got::Frame(f) if f.revision == rev => out.push(f),
            Got::Frame(f) => panic!("a frame of revision {} among those of {rev}", f.revision),
            Got::Text(v) if v["type"] == "pong" => return out,
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
}

/// Sends `msg` (with its `req`) and returns the `snapshot` it causes, with
/// its ack seen too (they may come in either order).
async fn acked_snapshot(ed: &mut Client, msg: Value) -> Value {
    let req = msg["req"].clone();
    ed.send(msg).await;
    let (mut acked, mut snap) = (false, None);
    while !(acked && snap.is_some()) {
        match ed.next().await {
            Got::Text(v) if v["type"] == "ack" && v["req"] == req => acked = true,
            Got::Text(v) if v["type"] == "error" && v["req"] == req => panic!("{v}"),
            Got::Text(v) if v["type"] == "snapshot" => snap = Some(v),
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
    snap.unwrap()
}

fn part(snapshot: &Value, id: u64) -> &Value {
    snapshot["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == id)
        .unwrap_or_else(|| panic!("no part {id} in {snapshot}"))
}

async fn stored(addr: std::net::SocketAddr, design: u64, token: &str) -> Value {
    get(addr, &format!("/api/designs/{design}"), Some(token))
        .await
        .json()["design"]
        .clone()
}

/// The stored (f64) surface of part `id` in a stored document.
fn stored_surface(doc: &Value, id: u64) -> BSplineSurface {
    let p = doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == id)
        .unwrap();
    let s = &p["body"]["surface"];
    let proto = json!({
        "u": {"degree": s["u_degree"], "knots": s["u_knots"]},
        "v": {"degree": s["v_degree"], "knots": s["v_knots"]},
        "points": s["points"],
    });
    surface_of(&proto, None)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_surfaces_two_curves_joined_dragged_committed_restarted_restored_undone() {
    let data = data_dir("parts");
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    let mut ed = Client::connect(addr, 1, &server.demo().editor, "ann").await;
    // A fresh design of one plate (part 1), then two more surfaces and two
    // curves.
    ed.send(json!({"type": "create_design", "req": 100, "name": "panels"}))
        .await;
    let made = ed.wait_for("design_created").await;
    assert_eq!(made["type"], "design_created", "{made}");
    let design = made["design"]["id"].as_u64().unwrap();
    let token = made["tokens"]["editor"].as_str().unwrap().to_string();
    let mut ed = Client::connect(addr, design, &token, "ann").await;
    let mut viewer = Client::connect(
        addr,
        design,
        made["tokens"]["viewer"].as_str().unwrap(),
        "vic",
    )
    .await;
    let snap = ed.snapshot.clone();
    assert_eq!(snap["parts"].as_array().unwrap().len(), 1);
    let a = snap["parts"][0]["id"].as_u64().unwrap();
    let a_surface = &snap["parts"][0]["shape"]["surface"];
    let nv = a_surface["nv"].as_u64().unwrap() as usize;
    // Part B continues A across its u_max edge (x = 50) with the same v knots.
    let b_shape = plate_json(6, nv, 50.0, 60.0, |x, _| 0.1 * (x - 50.0));
    let r = ed
        .request(json!({"type": "create_part", "spec": {"name": "wing",
            "shape": {"kind": "surface", "surface": b_shape.clone()}}}))
        .await;
    let b = r["part"].as_u64().unwrap_or_else(|| panic!("{r}"));
    let r = ed
        .request(json!({"type": "create_part", "spec": {"name": "lid",
            "shape": {"kind": "surface", "surface": plate_json(5, 4, -50.0, 40.0, |_, _| 30.0)},
            "colour": "#336699"}}))
        .await;
    let c = r["part"].as_u64().unwrap();
    let mut curves = Vec::new();
    for (name, y) in [("crease", 10.0), ("rim", -30.0)] {
        let pts: Vec<[f64; 3]> = (0..6).map(|i| [-40.0 + 16.0 * i as f64, y, 40.0]).collect();
        let r = ed
            .request(json!({"type": "create_part", "spec": {"name": name,
                "shape": {"kind": "curve", "curve": curve_json(&pts)},
                "material": {"alpha": 0.01, "beta": 1.0}}}))
            .await;
        curves.push(r["part"].as_u64().unwrap_or_else(|| panic!("{r}")));
    }
    // Everyone hears of every part.
    for _ in 0..4 {
        viewer.wait_for("part_created").await;
    }
    // A name is unique, a colour is #rrggbb, a curve material on a surface is refused.
    ed.refused(
        json!({"type": "create_part", "spec": {"name": "wing",
            "shape": {"kind": "surface", "surface": plate_json(4, 4, 0.0, 10.0, |_, _| 0.0)}}}),
        "conflict",
    )
    .await;
    ed.refused(
        json!({"type": "set_part", "part": c, "colour": "blue"}),
        "out_of_range",
    )
    .await;

    // Edit each part: an icon on every part, on the part it names.
    let mut icons = Vec::new();
    for p in [a, b, c] {
        let r = ed
            .request(json!({"type": "create_icon", "part": p, "spec": {
                "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}))
            .await;
        icons.push(r["icon"].as_u64().unwrap_or_else(|| panic!("{r}")));
    }
    for &p in &curves {
        let r = ed
            .request(json!({"type": "create_icon", "part": p, "spec": {
                "anchor": {"kind": "param", "t": 0.5}, "role": {"kind": "position"}}}))
            .await;
        icons.push(r["icon"].as_u64().unwrap_or_else(|| panic!("{r}")));
    }
    // Icon ids are unique across the design.
    let mut unique = icons.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), icons.len());
    // Surface anchors on a curve and curve anchors on a surface are refused;
    // an icon named on another part is refused.
    ed.refused(
        json!({"type": "create_icon", "part": curves[0], "spec": {
            "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}),
        "out_of_range",
    )
    .await;
    ed.refused(
        json!({"type": "create_icon", "part": a, "spec": {
            "anchor": {"kind": "param", "t": 0.5}, "role": {"kind": "load"}}}),
        "out_of_range",
    )
    .await;
    ed.refused(
        json!({"type": "set_state", "part": b, "icon": icons[0], "state": "sleeping"}),
        "unknown_part",
    )
    .await;
    ed.refused(
        json!({"type": "set_state", "part": 999, "icon": icons[0], "state": "sleeping"}),
        "unknown_part",
    )
    .await;

    // Drag the curve's icon: only the curve's frame comes.
    ed.ok(json!({"type": "drag_start", "part": curves[0], "icon": icons[3]}))
        .await;
    ed.send(json!({"type": "drag", "part": curves[0], "icon": icons[3], "xyz": [0.0, 10.0, 55.0]}))
        .await;
    let rev = ed.wait_for("icon_feedback").await["revision"]
        .as_u64()
        .unwrap();
    let frames = frames_of(&mut viewer, rev).await;
    assert_eq!(frames.len(), 1, "one part moved");
    assert_eq!(frames[0].part, curves[0]);
    assert_eq!(frames[0].kind, vsculpt_protocol::frame::KIND_CURVE);
    ed.ok(json!({"type": "drag_end", "part": curves[0], "icon": icons[3]}))
        .await;

    // Join A and B G1 along A's u_max and B's u_min.
    let r = ed
        .request(json!({"type": "relate", "relation": {"kind": "join",
            "a": {"part": a, "edge": "u_max"}, "b": {"part": b, "edge": "u_min"},
            "continuity": "g1"}}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let join = r["relation"].as_u64().unwrap();
    let created = viewer.wait_for("relation_created").await;
    assert_eq!(created["relation"]["id"], join);
    assert_eq!(created["relation"]["continuity"], "g1");
    // An edge of another size is incompatible and changes nothing.
    ed.refused(
        json!({"type": "relate", "relation": {"kind": "join",
            "a": {"part": a, "edge": "v_max"}, "b": {"part": c, "edge": "u_min"},
            "continuity": "g0"}}),
        "incompatible",
    )
    .await;
    let doc = stored(addr, design, &token).await;
    let (angle, gap) = seam_mismatch(&stored_surface(&doc, a), &stored_surface(&doc, b));
    assert!(
        angle < 1e-9 && gap < 1e-9,
        "after join: {angle} rad, gap {gap}"
    );

    // Drag the seam: a load on A's edge, pulled up in 8 frames. After every
    // frame, frames come for A and B only, and their seam agrees to f32.
    let r = ed
        .request(json!({"type": "create_icon", "part": a, "spec": {
            "anchor": {"kind": "point", "u": 1.0, "v": 0.5}, "role": {"kind": "load"}}}))
        .await;
    let seam_icon = r["icon"].as_u64().unwrap();
    ed.ok(json!({"type": "drag_start", "part": a, "icon": seam_icon}))
        .await;
    let start: [f64; 3] = {
        let doc = stored(addr, design, &token).await;
        let s = stored_surface(&doc, a);
        let ((_, u1), _) = s.domain();
        s.point(u1, 0.5).to_array()
    };
    let mut latest: std::collections::BTreeMap<u64, vsculpt_protocol::GeometryFrame> =
        Default::default();
    let shapes: std::collections::BTreeMap<u64, Value> = [
        (a, part(&ed.snapshot, a)["shape"]["surface"].clone()),
        (b, b_shape.clone()),
    ]
    .into_iter()
    .collect();
    for k in 1..=8 {
        let to = [start[0], start[1], start[2] + 2.0 * k as f64];
        ed.send(json!({"type": "drag", "part": a, "icon": seam_icon, "xyz": to}))
            .await;
        let rev = ed.wait_for("icon_feedback").await["revision"]
            .as_u64()
            .unwrap();
        // Both joined parts' frames of this solve, nothing of the others.
        let got = frames_of(&mut viewer, rev).await;
        let mut parts: Vec<u64> = got.iter().map(|f| f.part).collect();
        parts.sort_unstable();
        assert_eq!(parts, vec![a, b], "frame {k}");
        for f in got {
            latest.insert(f.part, f);
        }
        let (fa, fb) = (&latest[&a], &latest[&b]);
        let (angle, gap) = seam_mismatch(
            &surface_of(&shapes[&a], Some(&fa.points)),
            &surface_of(&shapes[&b], Some(&fb.points)),
        );
        assert!(
            angle < 1e-4 && gap < 1e-3,
            "frame {k}: {angle} rad, gap {gap}"
        );
    }
    ed.ok(json!({"type": "drag_end", "part": a, "icon": seam_icon}))
        .await;
    let doc = stored(addr, design, &token).await;
    let (sa, sb) = (stored_surface(&doc, a), stored_surface(&doc, b));
    let (angle, gap) = seam_mismatch(&sa, &sb);
    assert!(
        angle < 1e-9 && gap < 1e-9,
        "after the drag: {angle} rad, gap {gap}"
    );
    // The seam moved (both panels followed).
    let ((_, u1), _) = sa.domain();
    assert!(sa.point(u1, 0.5).z - start[2] > 5.0);

    // A locked part refuses drags and edits; a hidden part stays in the design.
    ed.ok(json!({"type": "set_part", "part": c, "locked": true, "visible": false}))
        .await;
    let changed = viewer.wait_for("part_changed").await;
    assert_eq!(
        (changed["locked"].clone(), changed["visible"].clone()),
        (json!(true), json!(false))
    );
    ed.refused(
        json!({"type": "drag_start", "part": c, "icon": icons[2]}),
        "locked",
    )
    .await;
    ed.refused(
        json!({"type": "delete_icon", "part": c, "icon": icons[2]}),
        "locked",
    )
    .await;
    ed.refused(json!({"type": "delete_part", "part": c}), "locked")
        .await;

    // Commit, restart, everything is back.
    let r = ed
        .request(json!({"type": "commit", "message": "panels joined"}))
        .await;
    let committed = r["version"].as_u64().unwrap();
    let before_restart = stored(addr, design, &token).await;
    drop(ed);
    drop(viewer);
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    let mut ed = Client::connect(addr, design, &token, "ann").await;
    let after_restart = stored(addr, design, &token).await;
    assert_eq!(after_restart["parts"], before_restart["parts"]);
    assert_eq!(after_restart["relations"], before_restart["relations"]);
    assert_eq!(ed.snapshot["parts"].as_array().unwrap().len(), 5);
    assert_eq!(ed.snapshot["relations"].as_array().unwrap().len(), 1);
    // Dragging after the restart still holds the seam.
    ed.ok(json!({"type": "drag_start", "part": b, "icon": icons[1]}))
        .await;
    ed.send(json!({"type": "drag", "part": b, "icon": icons[1], "xyz": [80.0, 0.0, 20.0]}))
        .await;
    ed.ok(json!({"type": "drag_end", "part": b, "icon": icons[1]}))
        .await;
    let doc = stored(addr, design, &token).await;
    let (angle, gap) = seam_mismatch(&stored_surface(&doc, a), &stored_surface(&doc, b));
    assert!(
        angle < 1e-9 && gap < 1e-9,
        "after a restart: {angle} rad, gap {gap}"
    );

    // Undo across parts: a change to the curve and one to B, undone in turn.
    ed.ok(json!({"type": "delete_icon", "part": curves[1], "icon": icons[4]}))
        .await;
    ed.ok(json!({"type": "set_part", "part": b, "name": "left wing"}))
        .await;
    let s = acked_snapshot(&mut ed, json!({"type": "undo", "req": 901})).await;
    assert_eq!(part(&s, b)["name"], "wing");
    assert!(part(&s, curves[1])["icons"].as_array().unwrap().is_empty());
    let s = acked_snapshot(&mut ed, json!({"type": "undo", "req": 902})).await;
    assert_eq!(part(&s, curves[1])["icons"][0]["id"], icons[4]);

    // Restore the first version (one plate) and back to the commit.
    let s = acked_snapshot(
        &mut ed,
        json!({"type": "restore_version", "req": 903, "version": 1}),
    )
    .await;
    assert_eq!(s["parts"].as_array().unwrap().len(), 1);
    assert!(s["relations"].as_array().unwrap().is_empty());
    let s = acked_snapshot(
        &mut ed,
        json!({"type": "restore_version", "req": 904, "version": committed}),
    )
    .await;
    assert_eq!(s["parts"].as_array().unwrap().len(), 5);
    let restored = stored(addr, design, &token).await;
    assert_eq!(restored["parts"], before_restart["parts"]);

    // Deleting a joined part deletes its join.
    ed.ok(json!({"type": "set_part", "part": b, "locked": false}))
        .await;
    ed.ok(json!({"type": "delete_part", "part": b})).await;
    let doc = stored(addr, design, &token).await;
    assert!(doc["relations"].as_array().unwrap().is_empty());
    server.stop().await;
}
