//! A DSM part edited through the real server re-meshes incrementally (the
//! kernel's `IncrementalMesh`): after a sequence of `dsm_edit`s — moves, a
//! resize, a density change, primitives added, removed and moved between
//! groups — its mesh frame is the one a fresh part built from the final
//! document gets, quantum for quantum and triangle for triangle.

mod common;

use common::TestServer;
use common::data_dir;
use common::http::get;
use common::ws::Client;
use serde_json::{Value, json};
use vsculpt_protocol::MeshFrame;

/// A handset-like part: a body with end caps, a dimple, a button, a screen
/// recess and a camera boss (add); a lanyard hole (subtract); a grip ball
/// (no term) incorporated by a thumb rest (add).
fn handset(cells: u32) -> Value {
    json!({"de": 1.0, "cells": cells, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [0.0, 0.0, 0.0], "shape": {"type": "box", "half": [1.6, 0.8, 0.3]}},
            {"id": 2, "at": [1.5, 0.0, 0.0], "shape": {"type": "density_sphere", "density": 3.0, "reducing": 3.0}},
            {"id": 3, "at": [-1.5, 0.0, 0.0], "shape": {"type": "density_sphere", "density": 3.0, "reducing": 3.0}},
            {"id": 4, "at": [1.3, 0.0, 0.38], "shape": {"type": "sphere", "radius": 0.12, "negative": true}},
            {"id": 5, "at": [-0.6, 0.82, 0.0], "shape": {"type": "box", "half": [0.12, 0.04, 0.06]}},
            {"id": 6, "at": [0.0, 0.0, 0.3], "shape": {"type": "box", "half": [1.1, 0.6, 0.05], "negative": true}},
            {"id": 7, "at": [1.0, 0.45, -0.3], "shape": {"type": "cylinder", "radius": 0.14, "half_height": 0.06}}
        ]},
        {"op": "subtract", "primitives": [
            {"id": 8, "at": [-1.4, 0.55, 0.0], "shape": {"type": "cylinder", "radius": 0.09, "half_height": 0.5}}
        ]},
        {"op": "none", "primitives": [
            {"id": 9, "at": [0.6, -0.35, -0.3], "shape": {"type": "sphere", "radius": 0.25}}
        ]},
        {"op": "add", "incorporated": [2], "primitives": [
            {"id": 10, "at": [0.6, -0.35, -0.45], "shape": {"type": "density_sphere", "density": 1.3, "reducing": 6.0}}
        ]}
    ]})
}

fn create(name: &str, dsm: Value) -> Value {
    json!({"type": "create_part", "spec": {"name": name, "shape": {"kind": "dsm", "dsm": dsm}}})
}

/// A frame's origin, step, positions, normals and triangles.
type Geometry<'a> = (
    &'a [f32; 3],
    f32,
    &'a [[u16; 3]],
    &'a [[i16; 3]],
    &'a [[u32; 3]],
);

/// The frame's geometry (everything but the design, part, revision and flags).
fn geometry(m: &MeshFrame) -> Geometry<'_> {
    (&m.origin, m.step, &m.positions, &m.normals, &m.triangles)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn edits_through_the_websocket_mesh_as_a_fresh_part_of_the_final_doc() {
    let data = data_dir("dsm-incremental");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let (addr, design) = (server.addr, d.id);
    let mut ed = Client::connect(addr, design, &d.editor, "ann").await;
    let mut viewer = Client::connect(addr, design, &d.viewer, "bob").await;

    let r = ed.request(create("edited", handset(64))).await;
    assert_eq!(r["type"], "ack", "{r}");
    let part = r["part"].as_u64().unwrap();
    let mut last = viewer.mesh_of_after(part, 0).await;
    assert!(
        last.triangles.len() > 500,
        "{} triangles",
        last.triangles.len()
    );

    let edits = [
        json!({"op": "move_primitive", "id": 5, "at": [-0.55, 0.82, 0.0]}),
        json!({"op": "move_primitive", "id": 5, "at": [-0.5, 0.82, 0.02]}),
        json!({"op": "resize_primitive", "id": 4, "shape": {"type": "sphere", "radius": 0.16, "negative": true}}),
        json!({"op": "move_primitive", "id": 7, "at": [1.05, 0.42, -0.3]}),
        json!({"op": "set_density", "id": 10, "density": 1.6, "reducing": 6.0}),
        json!({"op": "add_primitive", "group": 0, "primitive": {"id": 11, "at": [-0.3, 0.3, -0.3],
            "shape": {"type": "box", "half": [0.15, 0.12, 0.1], "negative": true}}}),
        json!({"op": "add_primitive", "group": 0, "primitive": {"id": 12, "at": [0.2, -0.85, 0.0],
            "shape": {"type": "sphere", "radius": 0.16}}}),
        json!({"op": "remove_primitive", "id": 11}),
        json!({"op": "move_primitive", "id": 8, "at": [-1.36, 0.5, 0.0]}),
        json!({"op": "change_group", "id": 12, "group": 1}),
        json!({"op": "move_primitive", "id": 9, "at": [0.62, -0.33, -0.3]}),
    ];
    for edit in edits {
        ed.ok(json!({"type": "dsm_edit", "part": part, "edit": edit.clone()}))
            .await;
        let m = viewer.mesh_of_after(part, last.revision).await;
        // Every edit shows in the mesh (so a stale region would show too).
        assert!(geometry(&m) != geometry(&last), "{edit} changed nothing");
        last = m;
    }

    // A fresh part of the final document.
    let doc = get(addr, &format!("/api/designs/{design}"), Some(&d.editor))
        .await
        .json()["design"]
        .clone();
    let dsm = doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == part)
        .unwrap()["body"]["dsm"]
        .clone();
    assert_eq!(dsm["groups"][1]["primitives"][1]["id"], 12);
    let r = ed.request(create("fresh", dsm)).await;
    assert_eq!(r["type"], "ack", "{r}");
    let fresh = r["part"].as_u64().unwrap();
    let m = viewer.mesh_of_after(fresh, 0).await;
    assert_eq!(m.positions.len(), last.positions.len());
    assert!(
        geometry(&m) == geometry(&last),
        "the edited part's mesh differs from a fresh part's"
    );

    drop(ed);
    drop(viewer);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

/// A box with a small box bump on its +x face: the bump's bounding ball
/// stays inside the box's, so moving the bump outwards changes the mesh's
/// extent (x: 2.05 → 2.08) but not the model's bounds or its grid.
fn bumped_box(bump_x: f64) -> Value {
    json!({"de": 1.0, "cells": 32, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [0.0, 0.0, 0.0], "shape": {"type": "box", "half": [1.0, 0.5, 0.3]}},
            {"id": 2, "at": [bump_x, 0.0, 0.0], "shape": {"type": "box", "half": [0.1, 0.1, 0.1]}}
        ]}
    ]})
}

/// The sorted (quantised position, normal) pairs of the frame's vertices
/// farther than `r` from every point of `away`.
fn far_vertices(m: &MeshFrame, away: &[[f64; 3]], r: f64) -> Vec<([u16; 3], [i16; 3])> {
    let mut v: Vec<_> = (0..m.positions.len())
        .filter(|&i| {
            let p = m.position(i);
            away.iter()
                .all(|c| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt() > r)
        })
        .map(|i| (m.positions[i], m.normals[i]))
        .collect();
    v.sort_unstable();
    v
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_drag_inside_the_bounds_keeps_every_far_vertex_quantum_for_quantum() {
    let data = data_dir("dsm-fixed-quanta");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let (addr, design) = (server.addr, d.id);
    let mut ed = Client::connect(addr, design, &d.editor, "ann").await;
    let mut viewer = Client::connect(addr, design, &d.viewer, "bob").await;
    let r = ed.request(create("bumped", bumped_box(0.95))).await;
    assert_eq!(r["type"], "ack", "{r}");
    let part = r["part"].as_u64().unwrap();
    let before = viewer.mesh_of_after(part, 0).await;
    ed.ok(json!({"type": "dsm_edit", "part": part,
                 "edit": {"op": "move_primitive", "id": 2, "at": [0.98, 0.0, 0.0]}}))
        .await;
    let after = viewer.mesh_of_after(part, before.revision).await;
    // The frames' quantisation is the part's grid: the same in both.
    assert_eq!((before.origin, before.step), (after.origin, after.step));
    // The grid spans the box's bounding ball (radius |half|): cell size
    // 2·radius / 32 rounded up to a power of 2^(1/16), origin the ball's low
    // corner rounded down to a multiple of it, less two cells (the frame's
    // origin).
    let radius = (1.0f64 + 0.25 + 0.09).sqrt();
    let h = ((16.0 * (2.0 * radius / 32.0).log2()).ceil() / 16.0).exp2();
    for a in 0..3 {
        let o = before.origin[a] as f64;
        assert!(
            (o - ((-radius / h).floor() - 2.0) * h).abs() < 1e-6,
            "origin {:?}",
            before.origin
        );
    }
    // Away from the bump (its ball 0.17, the mesher's reach margin of two
    // cells and a cell's own reach of two more) nothing moved: the same
    // quanta, so a delta frame could leave those vertices out.
    let away = [[0.95, 0.0, 0.0], [0.98, 0.0, 0.0]];
    let r = 0.18 + 6.0 * h;
    let (fb, fa) = (
        far_vertices(&before, &away, r),
        far_vertices(&after, &away, r),
    );
    assert!(fb.len() > before.positions.len() / 2, "{} far", fb.len());
    assert_eq!(fb, fa);
    // The bump did move.
    let xmax = |m: &MeshFrame| {
        (0..m.positions.len())
            .map(|i| m.position(i)[0])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    assert!((xmax(&before) - 1.05).abs() < 1e-4, "{}", xmax(&before));
    assert!((xmax(&after) - 1.08).abs() < 1e-4, "{}", xmax(&after));
    drop(ed);
    drop(viewer);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
