//! A DSM part (paper 001) through the real server: created, reshaped by
//! `dsm_edit`, its mesh frames (kind 3) checked by a second client against
//! the primitives' own surfaces (a geometric sphere |p − c| = R, a
//! sphere-based density primitive's r = ln(D/D_e)/a), undone, redone,
//! persisted across a restart, exported; bad edits refused with a clear
//! error and nothing changed.

mod common;

use common::http::get;
use common::ws::{Client, Got};
use common::{TestServer, data_dir};
use serde_json::{Value, json};
use vsculpt_protocol::MeshFrame;

fn sphere_part(cells: u32) -> Value {
    json!({"name": "blob", "shape": {"kind": "dsm", "dsm": {"de": 1.0, "cells": cells, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [0.0, 0.0, 0.0], "shape": {"type": "sphere", "radius": 1.0}}
        ]}
    ]}}})
}

/// The largest | |v − c| − r | over the frame's vertices, each vertex taken
/// against the nearest of the spheres (c, r).
fn deviation(m: &MeshFrame, spheres: &[([f64; 3], f64)]) -> f64 {
    (0..m.positions.len())
        .map(|i| {
            let p = m.position(i);
            spheres
                .iter()
                .map(|(c, r)| {
                    let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2))
                        .sqrt();
                    (d - r).abs()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// Every vertex is within `tol` of one of the spheres, and some vertex is
/// on each.
fn assert_on_spheres(m: &MeshFrame, spheres: &[([f64; 3], f64)], tol: f64) {
    assert!(!m.triangles.is_empty());
    let dev = deviation(m, spheres);
    assert!(
        dev <= tol,
        "a vertex is {dev} off the spheres (tolerance {tol})"
    );
    for s in spheres {
        let on = (0..m.positions.len()).any(|i| {
            let p = m.position(i);
            let d = ((p[0] - s.0[0]).powi(2) + (p[1] - s.0[1]).powi(2) + (p[2] - s.0[2]).powi(2))
                .sqrt();
            (d - s.1).abs() <= tol
        });
        assert!(on, "no vertex on sphere {s:?}");
    }
}

/// Tolerance: the frame's quantisation (half a step per axis) plus the
/// projection's 1e-9 slack.
fn tol(m: &MeshFrame) -> f64 {
    m.step as f64 * 0.5 * 3f64.sqrt() + 1e-6
}

async fn stored(addr: std::net::SocketAddr, design: u64, token: &str) -> Value {
    get(addr, &format!("/api/designs/{design}"), Some(token))
        .await
        .json()["design"]
        .clone()
}

fn stored_dsm(doc: &Value, id: u64) -> Value {
    doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == id)
        .unwrap_or_else(|| panic!("no part {id}"))["body"]["dsm"]
        .clone()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dsm_part_is_created_edited_undone_persisted_and_exported() {
    let data = data_dir("dsm-parts");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let (addr, design) = (server.addr, d.id);
    let mut ed = Client::connect(addr, design, &d.editor, "ann").await;
    let mut viewer = Client::connect(addr, design, &d.viewer, "bob").await;

    // Created: the viewer hears of it and gets its mesh, on the unit sphere.
    let r = ed
        .request(json!({"type": "create_part", "spec": sphere_part(16)}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let part = r["part"].as_u64().unwrap();
    let created = viewer.wait_for("part_created").await;
    assert_eq!(created["part"]["shape"]["kind"], "dsm");
    let m = viewer.mesh_of_after(part, 0).await;
    assert_on_spheres(&m, &[([0.0; 3], 1.0)], tol(&m));
    // Closed: V − E + F = 2.
    let mut edges = std::collections::HashSet::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    assert_eq!(
        m.positions.len() as i64 - edges.len() as i64 + m.triangles.len() as i64,
        2
    );
    let rev0 = m.revision;

    // Moved: the new mesh is the sphere about the new centre.
    ed.ok(json!({"type": "dsm_edit", "part": part,
                 "edit": {"op": "move_primitive", "id": 1, "at": [0.5, -0.25, 0.0]}}))
        .await;
    let changed = viewer.wait_for("dsm_changed").await;
    assert_eq!(
        changed["dsm"]["groups"][0]["primitives"][0]["at"],
        json!([0.5, -0.25, 0.0])
    );
    let m = viewer.mesh_of_after(part, rev0).await;
    assert_on_spheres(&m, &[([0.5, -0.25, 0.0], 1.0)], tol(&m));
    let rev1 = m.revision;

    // A sphere-based density primitive in a new group, apart from the
    // sphere: its surface is r = ln(D / D_e) / a = ln(e²) / 2 = 1.
    let dd = std::f64::consts::E.powi(2);
    ed.ok(json!({"type": "dsm_edit", "part": part, "edit": {"op": "add_primitive", "group": 1,
                 "primitive": {"id": 2, "at": [4.0, 0.0, 0.0],
                               "shape": {"type": "density_sphere", "density": dd, "reducing": 2.0}}}}))
        .await;
    let m = viewer.mesh_of_after(part, rev1).await;
    // The density sphere's vertices are projected onto its level set; the
    // 1e-9 relative culling moves it by far less than the quantisation.
    assert_on_spheres(
        &m,
        &[([0.5, -0.25, 0.0], 1.0), ([4.0, 0.0, 0.0], 1.0)],
        tol(&m),
    );
    let rev2 = m.revision;

    // Bad edits: refused with a clear error, nothing changes.
    let before = stored(addr, design, &d.editor).await;
    let bad = [
        (
            json!({"op": "move_primitive", "id": 99, "at": [0, 0, 0]}),
            "out_of_range",
        ),
        (
            json!({"op": "move_primitive", "id": 1, "at": [1e300, 0, 0]}),
            "out_of_range",
        ),
        (
            json!({"op": "set_density", "id": 1, "density": 2.0, "reducing": 1.0}),
            "incompatible",
        ),
        (
            json!({"op": "set_density", "id": 2, "density": 0.0, "reducing": 1.0}),
            "out_of_range",
        ),
        (
            json!({"op": "change_group", "id": 2, "group": 9}),
            "out_of_range",
        ),
        (
            json!({"op": "drag_node", "id": 1, "node": 0, "height": 1.0}),
            "incompatible",
        ),
        (
            json!({"op": "resize_primitive", "id": 1, "shape": {"type": "box", "half": [1, 1, 1]}}),
            "out_of_range",
        ),
        (
            json!({"op": "add_primitive", "group": 0, "primitive": {"id": 1, "at": [0, 0, 0],
                "shape": {"type": "sphere", "radius": 1.0}}}),
            "conflict",
        ),
        (
            json!({"op": "add_primitive", "group": 0, "primitive": {"id": 3, "at": [0, 0, 0],
                "shape": {"type": "net", "nu": 100000, "nv": 3, "spacing": [1, 1], "heights": [1.0], "reducing": 1.0}}}),
            "out_of_range",
        ),
    ];
    for (edit, code) in bad {
        ed.refused(
            json!({"type": "dsm_edit", "part": part, "edit": edit}),
            code,
        )
        .await;
    }
    // NaN / ∞ cannot pass the JSON layer.
    ed.send_text(&format!(
        "{{\"type\": \"dsm_edit\", \"req\": 500, \"part\": {part}, \"edit\": {{\"op\": \"move_primitive\", \"id\": 1, \"at\": [NaN, 0, 0]}}}}"
    ))
    .await;
    let e = ed.wait_for("error").await;
    assert!(e["code"] == "malformed" || e["code"] == "not_finite", "{e}");
    // Unknown part, and a dsm_edit on a surface part.
    ed.refused(
        json!({"type": "dsm_edit", "part": 777, "edit": {"op": "remove_primitive", "id": 1}}),
        "unknown_part",
    )
    .await;
    ed.refused(
        json!({"type": "dsm_edit", "part": 1, "edit": {"op": "remove_primitive", "id": 1}}),
        "incompatible",
    )
    .await;
    // Icons on a dsm part are refused.
    ed.refused(
        json!({"type": "create_icon", "part": part, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "position"}, "state": "passive"}}),
        "unsupported",
    )
    .await;
    // A part with too many primitives, or NaN-free but huge counts.
    let many: Vec<Value> = (0..300)
        .map(|i| json!({"id": i, "at": [i as f64, 0, 0], "shape": {"type": "sphere", "radius": 0.1}}))
        .collect();
    ed.refused(
        json!({"type": "create_part", "spec": {"name": "many", "shape": {"kind": "dsm", "dsm":
            {"de": 1.0, "cells": 16, "groups": [{"op": "add", "primitives": many}]}}}}),
        "too_large",
    )
    .await;
    ed.refused(
        json!({"type": "create_part", "spec": {"name": "fine", "shape": {"kind": "dsm", "dsm":
            {"de": 1.0, "cells": 100000, "groups": []}}}}),
        "out_of_range",
    )
    .await;
    ed.ping().await;
    let after = stored(addr, design, &d.editor).await;
    assert_eq!(after["parts"], before["parts"]);

    // Undo takes the density primitive away again; redo brings it back.
    ed.ok(json!({"type": "undo"})).await;
    let m = viewer.mesh_of_after(part, rev2).await;
    assert_on_spheres(&m, &[([0.5, -0.25, 0.0], 1.0)], tol(&m));
    let dsm = stored_dsm(&stored(addr, design, &d.editor).await, part);
    assert_eq!(dsm["groups"].as_array().unwrap().len(), 1);
    ed.ok(json!({"type": "redo"})).await;
    let m = viewer.mesh_of_after(part, m.revision).await;
    assert_on_spheres(
        &m,
        &[([0.5, -0.25, 0.0], 1.0), ([4.0, 0.0, 0.0], 1.0)],
        tol(&m),
    );

    // Export of the dsm part (OBJ): its vertices on the same spheres (f32).
    let obj = get(
        addr,
        &format!("/api/designs/{design}/export.obj?part={part}"),
        Some(&d.viewer),
    )
    .await;
    assert_eq!(obj.status, 200);
    let text = obj.text();
    let mut n = 0;
    for l in text.lines().filter(|l| l.starts_with("v ")) {
        let p: Vec<f64> = l[2..]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let on = |c: [f64; 3]| {
            (((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt() - 1.0)
                .abs()
                < 1e-5
        };
        assert!(on([0.5, -0.25, 0.0]) || on([4.0, 0.0, 0.0]), "{l}");
        n += 1;
    }
    assert!(n > 100, "{n} vertices");
    // IGES has no form for it: a clear refusal.
    let iges = get(
        addr,
        &format!("/api/designs/{design}/export.igs?part={part}"),
        Some(&d.viewer),
    )
    .await;
    assert_ne!(iges.status, 200);

    // Persisted across a restart: the same data, the same mesh.
    let before_restart = stored(addr, design, &d.editor).await;
    drop(ed);
    drop(viewer);
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    let after_restart = stored(addr, design, &d.editor).await;
    assert_eq!(after_restart["parts"], before_restart["parts"]);
    let mut viewer = Client::connect(addr, design, &d.viewer, "bob").await;
    let shape = viewer.snapshot["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == part)
        .unwrap()["shape"]
        .clone();
    assert_eq!(shape["kind"], "dsm");
    assert_eq!(shape["dsm"], stored_dsm(&after_restart, part));
    let m = loop {
        match viewer.next().await {
            Got::Mesh(m) if m.part == part => break m,
            Got::Closed => panic!("closed"),
            _ => {}
        }
    };
    assert_on_spheres(
        &m,
        &[([0.5, -0.25, 0.0], 1.0), ([4.0, 0.0, 0.0], 1.0)],
        tol(&m),
    );
    drop(viewer);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
