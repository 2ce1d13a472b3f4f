//! Free-form deformation of other parts by a body part (paper 002,
//! issue 13), through the real server over WebSocket (surface and curve
//! parts: their stored control points) and through the design model in
//! process (a DSM part's mesh vertices, which reach clients only quantised):
//! the identity lattice leaves a bound part unchanged; an affine lattice
//! move (translate + shear of every lattice point) moves control points and
//! mesh vertices affinely; a local lattice edit moves only what lies in the
//! moved point's support; binding geometry outside the body is refused and
//! changes nothing; the binding survives a restart; undo of a lattice edit
//! restores the bound part; control-point FFD's deviation from the deformed
//! surface is measured against its second-order bound.
//!
//! Expected values are computed here from the definitions: the bodies are
//! boxes with Greville control points, so a point's parameters are x / 2
//! in closed form, and B(u, v, w) is evaluated by the kernel's volume (not
//! the FFD code under test).

mod common;

use common::http::get;
use common::ws::Client;
use common::{TestServer, data_dir};
use glam::{DMat3, DVec3};
use serde_json::{Value, json};
use vsculpt_kernel::body::BSplineVolume;
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector, basis_derivs};
use vsculpt_server::design::body_part::LatticeSelect;
use vsculpt_server::design::doc::{DesignDoc, MaterialDoc, SurfaceDoc};
use vsculpt_server::design::edit::{Edit, PartEdit};
use vsculpt_server::design::model::DesignModel;
use vsculpt_server::design::part::{PartBody, RelationKind, SurfacePart};

/// Clamped knots of `degree` with `n` points, uniform on [0, 1].
fn knots(degree: usize, n: usize) -> Vec<f64> {
    let spans = n - degree;
    let mut k = vec![0.0; degree + 1];
    k.extend((1..spans).map(|i| i as f64 / spans as f64));
    k.extend(vec![1.0; degree + 1]);
    k
}

/// The Greville abscissae of `knots(degree, n)`, scaled to [0, 2].
fn greville(degree: usize, n: usize) -> Vec<f64> {
    let k = knots(degree, n);
    (0..n)
        .map(|i| 2.0 * k[i + 1..=i + degree].iter().sum::<f64>() / degree as f64)
        .collect()
}

/// The box [0, 2]³ as n³ points of `degree` at the Greville abscissae (the
/// map is then x = 2 (u, v, w)), k fastest.
fn box_points(degree: usize, n: usize) -> Vec<[f64; 3]> {
    let g = greville(degree, n);
    let mut points = Vec::new();
    for x in &g {
        for y in &g {
            for z in &g {
                points.push([*x, *y, *z]);
            }
        }
    }
    points
}

/// The protocol's `lattice` of the box.
fn box_lattice(degree: usize, n: usize) -> Value {
    let kv = json!({"degree": degree, "knots": knots(degree, n)});
    json!({"u": kv, "v": kv, "w": kv, "points": box_points(degree, n)})
}

/// The kernel volume of a box lattice with `points`.
fn volume(degree: usize, n: usize, points: &[[f64; 3]]) -> BSplineVolume {
    let kv = || KnotVector::new(degree, knots(degree, n)).unwrap();
    BSplineVolume::new(
        kv(),
        kv(),
        kv(),
        points.iter().map(|p| DVec3::from(*p)).collect(),
    )
    .unwrap()
}

/// A bicubic patch inside [x0, x0 + w] × [y0, y0 + w] with 5 × 5 points and
/// a bump in z around `z0`.
fn patch(x0: f64, y0: f64, w: f64, z0: f64) -> Value {
    let k = knots(3, 5);
    let mut points = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let (s, t) = (i as f64 / 4.0, j as f64 / 4.0);
            let z = z0 + 0.2 * (s * (1.0 - s) * t * (1.0 - t)) * 16.0 * (1.0 + 0.3 * s);
            points.push(json!([x0 + w * s, y0 + w * t * (1.0 - 0.1 * s), z]));
        }
    }
    let kv = json!({"degree": 3, "knots": k});
    json!({"u": kv, "v": kv, "nu": 5, "nv": 5, "points": points})
}

/// A quadratic curve through the box's inside.
fn curve() -> Value {
    let pts = [
        [0.3, 0.4, 0.5],
        [0.8, 1.5, 0.7],
        [1.3, 0.6, 1.4],
        [1.7, 1.6, 1.2],
    ];
    json!({"knots": {"degree": 2, "knots": knots(2, 4)}, "points": pts})
}

async fn stored(addr: std::net::SocketAddr, design: u64, token: &str) -> Value {
    get(addr, &format!("/api/designs/{design}"), Some(token))
        .await
        .json()["design"]
        .clone()
}

fn stored_part(doc: &Value, part: u64) -> &Value {
    doc["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == json!(part))
        .unwrap_or_else(|| panic!("no part {part} in {doc}"))
}

/// The stored control points of a surface or curve part.
fn control_points(doc: &Value, part: u64) -> Vec<DVec3> {
    let b = &stored_part(doc, part)["body"];
    let pts = if b["kind"] == "surface" {
        &b["surface"]["points"]
    } else {
        &b["curve"]["points"]
    };
    serde_json::from_value::<Vec<[f64; 3]>>(pts.clone())
        .unwrap()
        .into_iter()
        .map(DVec3::from)
        .collect()
}

async fn ok(c: &mut Client, msg: Value) -> Value {
    let v = c.request(msg.clone()).await;
    assert_eq!(v["type"], "ack", "{msg} → {v}");
    v
}

async fn refused(c: &mut Client, msg: Value, code: &str) -> String {
    let v = c.request(msg.clone()).await;
    assert_eq!(v["type"], "error", "{msg} → {v}");
    assert_eq!(v["code"], code, "{msg} → {v}");
    v["message"].as_str().unwrap().to_string()
}

async fn create(c: &mut Client, name: &str, kind: &str, shape: Value) -> u64 {
    let r = ok(
        c,
        json!({"type": "create_part", "req": 1, "spec": {"name": name, "shape": {"kind": kind, kind: shape}}}),
    )
    .await;
    r["part"].as_u64().unwrap()
}

async fn move_point(c: &mut Client, body: u64, ijk: [usize; 3], delta: DVec3) {
    ok(
        c,
        json!({"type": "body_edit", "req": 2, "part": body, "edit": {"select": {"point": ijk}, "delta": delta.to_array()}}),
    )
    .await;
}

/// The affine map of the tests: a shear plus a translation.
fn affine() -> (DMat3, DVec3) {
    let a = DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.08, 1.0, 0.0),
        DVec3::new(-0.05, 0.06, 1.0),
    );
    (a, DVec3::new(0.04, -0.03, 0.05))
}

fn max_dist(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bound_parts_follow_identity_and_affine_lattices_exactly_and_undo_and_restart_keep_the_binding()
 {
    let data = data_dir("body-ffd-affine");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;

    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(2, 3)}),
    )
    .await;
    let surf = create(&mut ed, "skin", "surface", patch(0.3, 0.4, 1.2, 0.9)).await;
    let line = create(&mut ed, "line", "curve", curve()).await;
    let before = stored(addr, design, &editor).await;
    let (s0, c0) = (control_points(&before, surf), control_points(&before, line));

    // Binding moves nothing; the relation is listed and stored.
    let r = ok(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": surf}}),
    )
    .await;
    let rel = r["relation"].as_u64().unwrap();
    ok(
        &mut ed,
        json!({"type": "relate", "req": 4, "relation": {"kind": "ffd", "body": body, "part": line}}),
    )
    .await;
    // A part follows one body at most.
    let msg = refused(
        &mut ed,
        json!({"type": "relate", "req": 5, "relation": {"kind": "ffd", "body": body, "part": surf}}),
        "conflict",
    )
    .await;
    assert!(msg.contains(&format!("relation {rel}")), "{msg}");
    let bound = stored(addr, design, &editor).await;
    assert_eq!(control_points(&bound, surf), s0);
    let ffd: Vec<&Value> = bound["relations"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["kind"]["kind"] == "ffd")
        .collect();
    assert_eq!(ffd.len(), 2, "{}", bound["relations"]);

    // The identity lattice: a zero move leaves both parts unchanged (1e-12).
    move_point(&mut ed, body, [1, 1, 1], DVec3::ZERO).await;
    let same = stored(addr, design, &editor).await;
    assert!(max_dist(&control_points(&same, surf), &s0) <= 1e-12);
    assert!(max_dist(&control_points(&same, line), &c0) <= 1e-12);

    // An affine move of every lattice point (one point at a time: each step
    // is a non-affine lattice, the composition is the affine map).
    let (a, t) = affine();
    let pts = box_points(2, 3);
    for (idx, p) in pts.iter().enumerate() {
        let x = DVec3::from(*p);
        let ijk = [idx / 9, (idx / 3) % 3, idx % 3];
        move_point(&mut ed, body, ijk, a * x + t - x).await;
    }
    let moved = stored(addr, design, &editor).await;
    let want = |v: &[DVec3]| v.iter().map(|x| a * *x + t).collect::<Vec<_>>();
    let (es, ec) = (
        max_dist(&control_points(&moved, surf), &want(&s0)),
        max_dist(&control_points(&moved, line), &want(&c0)),
    );
    assert!(es <= 1e-12 && ec <= 1e-12, "surface {es:e}, curve {ec:e}");

    // Undo of the last lattice edit gives back the bound parts as they were.
    let before_last = {
        ok(&mut ed, json!({"type": "undo", "req": 6})).await;
        stored(addr, design, &editor).await
    };
    ok(&mut ed, json!({"type": "redo", "req": 7})).await;
    assert_eq!(
        control_points(&stored(addr, design, &editor).await, surf),
        control_points(&moved, surf)
    );
    ok(&mut ed, json!({"type": "undo", "req": 8})).await;
    let undone = stored(addr, design, &editor).await;
    assert_eq!(
        control_points(&undone, surf),
        control_points(&before_last, surf)
    );
    assert_ne!(
        control_points(&undone, surf),
        control_points(&moved, surf),
        "the last lattice edit did not move the surface"
    );

    // A restart keeps the binding: a further lattice edit still moves the part.
    drop(ed);
    server.stop().await;
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    let again = stored(addr, design, &editor).await;
    assert_eq!(again["relations"], undone["relations"]);
    assert_eq!(control_points(&again, surf), control_points(&undone, surf));
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    let x = DVec3::from(pts[26]);
    move_point(&mut ed, body, [2, 2, 2], a * x + t - x).await;
    let after = stored(addr, design, &editor).await;
    assert!(
        max_dist(&control_points(&after, surf), &want(&s0)) <= 1e-12,
        "after the restart the surface did not follow"
    );

    // Unbinding keeps the shape; the next lattice edit no longer moves it.
    ok(
        &mut ed,
        json!({"type": "unrelate", "req": 9, "relation": rel}),
    )
    .await;
    move_point(&mut ed, body, [1, 1, 1], DVec3::new(0.2, 0.0, 0.0)).await;
    let unbound = stored(addr, design, &editor).await;
    assert_eq!(control_points(&unbound, surf), control_points(&after, surf));
    assert_ne!(control_points(&unbound, line), control_points(&after, line));

    // Deleting the body unbinds (the curve keeps its shape).
    ok(
        &mut ed,
        json!({"type": "delete_part", "req": 10, "part": body}),
    )
    .await;
    let gone = stored(addr, design, &editor).await;
    assert!(
        !gone["relations"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r["kind"]["kind"] == "ffd")
    );
    assert_eq!(control_points(&gone, line), control_points(&unbound, line));
    drop(ed);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_local_lattice_edit_moves_only_the_control_points_in_its_support() {
    let data = data_dir("body-ffd-local");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    // Degree 2, 5 points per direction: knots 0, 1/3, 2/3, 1.
    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(2, 5)}),
    )
    .await;
    let surf = create(&mut ed, "skin", "surface", patch(0.1, 0.1, 1.8, 0.7)).await;
    ok(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": surf}}),
    )
    .await;
    let s0 = control_points(&stored(addr, design, &editor).await, surf);
    // Point (1, 1, 1): N₁ of knots (0, 0, 1/3, 2/3) is > 0 on (0, 2/3) only,
    // x ∈ (0, 4/3) per direction.
    move_point(&mut ed, body, [1, 1, 1], DVec3::new(0.1, -0.05, 0.08)).await;
    let s1 = control_points(&stored(addr, design, &editor).await, surf);
    let (mut inside, mut outside) = (0, 0);
    for (p, q) in s0.iter().zip(&s1) {
        // Well inside (N₁ vanishes to second order at the support's ends).
        let in_support = p.to_array().iter().all(|&c| c > 0.1 && c < 4.0 / 3.0 - 0.1);
        let out_support = p.to_array().iter().any(|&c| c > 4.0 / 3.0 + 1e-9);
        if out_support {
            outside += 1;
            assert_eq!(p, q, "a control point outside the support moved");
        } else if in_support {
            inside += 1;
            assert!((*q - *p).length() > 1e-4, "{p} in the support did not move");
        }
    }
    assert!(
        inside >= 4 && outside >= 4,
        "{inside} inside, {outside} outside"
    );
    drop(ed);
    server.stop().await;
}

/// The stored icons of part `part`, by id: (role, xyz, target).
fn icons_of(doc: &Value, part: u64) -> Vec<(u64, Value, DVec3, DVec3)> {
    stored_part(doc, part)["body"]["icons"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            let v =
                |k: &str| DVec3::from(serde_json::from_value::<[f64; 3]>(i[k].clone()).unwrap());
            (
                i["id"].as_u64().unwrap(),
                i["role"].clone(),
                v("xyz"),
                v("target"),
            )
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tangent_and_normal_targets_of_a_bound_surface_follow_the_lattice_s_derivative() {
    let data = data_dir("body-ffd-vectors");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    let (degree, n) = (2, 3);
    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(degree, n)}),
    )
    .await;
    let surf = create(&mut ed, "skin", "surface", patch(0.3, 0.4, 1.2, 0.9)).await;
    for (u, v, role) in [
        (0.4, 0.6, json!({"kind": "derivative", "which": "R"})),
        (0.7, 0.3, json!({"kind": "derivative", "which": "V"})),
        (0.55, 0.35, json!({"kind": "normal"})),
        (0.3, 0.3, json!({"kind": "derivative", "which": "R2"})),
    ] {
        let spec =
            json!({"anchor": {"kind": "point", "u": u, "v": v}, "role": role, "state": "passive"});
        ok(
            &mut ed,
            json!({"type": "create_icon", "req": 2, "part": surf, "spec": spec}),
        )
        .await;
    }
    ok(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": surf}}),
    )
    .await;
    let before = icons_of(&stored(addr, design, &editor).await, surf);
    assert_eq!(before.len(), 4);

    // One lattice point moved: a non-affine change φ(y) = y + B_new(p) −
    // B_old(p) with p = y / 2 (the box's closed-form inverse), whose
    // derivative is taken here by central differences of that formula.
    let delta = DVec3::new(0.15, -0.1, 0.12);
    move_point(&mut ed, body, [1, 1, 1], delta).await;
    let old_pts = box_points(degree, n);
    let mut new_pts = old_pts.clone();
    let centre = (n / 2 * n + n / 2) * n + n / 2;
    new_pts[centre] = (DVec3::from(new_pts[centre]) + delta).to_array();
    let (old, new) = (volume(degree, n, &old_pts), volume(degree, n, &new_pts));
    let phi = |y: DVec3| {
        let p = y / 2.0;
        y + new.point(p.x, p.y, p.z) - old.point(p.x, p.y, p.z)
    };
    let dphi = |x: DVec3| {
        let h = 1e-5;
        let col = |e: DVec3| (phi(x + e * h) - phi(x - e * h)) / (2.0 * h);
        DMat3::from_cols(col(DVec3::X), col(DVec3::Y), col(DVec3::Z))
    };
    let after = icons_of(&stored(addr, design, &editor).await, surf);
    for ((id, role, xyz, t0), (id2, _, _, t1)) in before.iter().zip(&after) {
        assert_eq!(id, id2);
        let d = dphi(*xyz);
        let want = match role["kind"].as_str().unwrap() {
            "normal" => (d.inverse().transpose() * *t0).normalize() * t0.length(),
            _ if role["which"] == "R2" => *t0,
            _ => d * *t0,
        };
        assert!(
            (*t1 - want).length() <= 1e-8 * want.length().max(1.0),
            "{role}: target {t0} became {t1}, want {want}"
        );
        assert!(
            role["which"] == "R2" || (*t1 - *t0).length() > 1e-3,
            "{role}: the target did not change"
        );
    }
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn binding_geometry_outside_the_body_or_of_the_wrong_kind_is_refused_and_changes_nothing() {
    let data = data_dir("body-ffd-refused");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(2, 3)}),
    )
    .await;
    // The patch reaches x = 0.5 + 1.8 = 2.3 > 2: its last row is outside.
    let surf = create(&mut ed, "wide", "surface", patch(0.5, 0.1, 1.8, 1.0)).await;
    let other = create(
        &mut ed,
        "box2",
        "body",
        json!({"lattice": box_lattice(2, 3)}),
    )
    .await;
    let before = stored(addr, design, &editor).await;
    let msg = refused(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": surf}}),
        "out_of_range",
    )
    .await;
    // Control point 20 is the first of the row at x = 2.3.
    assert!(
        msg.contains("control point 20 at (2.3000,") && msg.contains("outside the body"),
        "{msg}"
    );
    assert!(msg.contains("(0.3000 from it; 5 of 25 outside)"), "{msg}");
    // A body cannot be bound to a body; the `body` must be a body.
    refused(
        &mut ed,
        json!({"type": "relate", "req": 4, "relation": {"kind": "ffd", "body": body, "part": other}}),
        "incompatible",
    )
    .await;
    refused(
        &mut ed,
        json!({"type": "relate", "req": 5, "relation": {"kind": "ffd", "body": surf, "part": body}}),
        "incompatible",
    )
    .await;
    refused(
        &mut ed,
        json!({"type": "relate", "req": 6, "relation": {"kind": "ffd", "body": body, "part": 999}}),
        "unknown_part",
    )
    .await;
    assert_eq!(stored(addr, design, &editor).await, before);
    drop(ed);
    server.stop().await;
}

/// A model holding the box body (part 1) and a DSM sphere of radius 0.5 at
/// (1, 1, 1) (part 2), bound (relation 1).
fn dsm_model(degree: usize, n: usize) -> DesignModel {
    let body: PartBody = serde_json::from_value(json!({"kind": "body", "lattice": {
        "degrees": [degree, degree, degree],
        "knots": [knots(degree, n), knots(degree, n), knots(degree, n)],
        "points": box_points(degree, n)}}))
    .unwrap();
    let dsm: PartBody = serde_json::from_value(
        json!({"kind": "dsm", "dsm": {"de": 1.0, "cells": 24, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [0.9, 1.0, 1.1], "shape": {"type": "sphere", "radius": 0.5}}]}]}}),
    )
    .unwrap();
    let doc = DesignDoc::single("ffd", "box", body);
    let mut m = DesignModel::load(&doc).unwrap();
    m.apply(Edit::CreatePart {
        name: "blob".into(),
        body: Box::new(dsm),
        colour: None,
    })
    .unwrap();
    let (_, moved) = m
        .apply(Edit::Relate(RelationKind::Ffd {
            body: 1,
            part: 2,
            rest: None,
        }))
        .unwrap();
    assert_eq!(moved, vec![2]);
    m
}

fn lattice_move(m: &mut DesignModel, ijk: [usize; 3], delta: DVec3) -> Vec<u64> {
    m.apply(Edit::Part {
        part: 1,
        edit: PartEdit::MoveLattice {
            select: LatticeSelect::Point(ijk),
            delta: delta.to_array(),
        },
    })
    .unwrap()
    .1
}

#[test]
fn a_bound_dsm_mesh_follows_its_body_exactly_and_locally() {
    let mut m = dsm_model(2, 3);
    let rest: Vec<DVec3> = m.dsm_mesh(2).unwrap().positions.clone();
    assert!(rest.len() > 500, "{} vertices", rest.len());
    // The stored relation holds the rest lattice.
    match &m.doc().relations[0].kind {
        RelationKind::Ffd { rest: Some(r), .. } => assert_eq!(r.points, box_points(2, 3)),
        other => panic!("{other:?}"),
    }
    // Identity: a zero move.
    lattice_move(&mut m, [1, 1, 1], DVec3::ZERO);
    assert!(max_dist(&m.dsm_mesh(2).unwrap().positions, &rest) <= 1e-12);

    // Affine: every lattice point through (A, t); each vertex to A x + t.
    let (a, t) = affine();
    let pts = box_points(2, 3);
    for (idx, p) in pts.iter().enumerate() {
        let x = DVec3::from(*p);
        let moved = lattice_move(&mut m, [idx / 9, (idx / 3) % 3, idx % 3], a * x + t - x);
        assert!(moved.contains(&1) && moved.contains(&2), "{moved:?}");
    }
    let want: Vec<DVec3> = rest.iter().map(|x| a * *x + t).collect();
    let e = max_dist(&m.dsm_mesh(2).unwrap().positions, &want);
    assert!(e <= 1e-12, "affine error {e:e}");

    // Non-affine: the centre moves; each vertex is B(x / 2) of the new
    // lattice, evaluated by the kernel's volume.
    lattice_move(&mut m, [1, 1, 1], DVec3::new(0.25, -0.1, 0.15));
    let lattice: Vec<[f64; 3]> = match &m.doc().part(1).unwrap().body {
        PartBody::Body(b) => b.lattice.points.clone(),
        _ => unreachable!(),
    };
    let vol = volume(2, 3, &lattice);
    let exact: Vec<DVec3> = rest
        .iter()
        .map(|x| vol.point(x.x / 2.0, x.y / 2.0, x.z / 2.0))
        .collect();
    let e = max_dist(&m.dsm_mesh(2).unwrap().positions, &exact);
    assert!(e <= 1e-12, "x ≠ B(u, v, w): {e:e}");
    // Normals of the deformed mesh: unit, and facing away from the centre
    // of the (still star-shaped) blob.
    let mesh = m.dsm_mesh(2).unwrap();
    let c = mesh.positions.iter().copied().sum::<DVec3>() / mesh.positions.len() as f64;
    let facing = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .filter(|(p, n)| (**p - c).dot(**n) > 0.0 && (n.length() - 1.0).abs() < 1e-9)
        .count();
    assert!(
        facing * 100 >= mesh.positions.len() * 99,
        "{facing} of {}",
        mesh.positions.len()
    );

    // Undo gives back the mesh before that edit; unbinding its own shape.
    let affine_mesh = want;
    let doc_before = m.doc().clone();
    let mut m2 = DesignModel::load(&doc_before).unwrap();
    assert!(max_dist(&m2.dsm_mesh(2).unwrap().positions, &exact) <= 1e-12);
    let undone = m2.apply(Edit::Unrelate { relation: 1 }).unwrap().1;
    assert_eq!(undone, vec![2]);
    assert!(max_dist(&m2.dsm_mesh(2).unwrap().positions, &rest) <= 1e-12);
    let _ = affine_mesh;
}

#[test]
fn a_local_lattice_edit_recomputes_only_the_dsm_vertices_in_its_support() {
    let mut m = dsm_model(2, 5);
    let rest: Vec<DVec3> = m.dsm_mesh(2).unwrap().positions.clone();
    // Point (1, 1, 1) of 5: support x ∈ (0, 4/3) per direction.
    lattice_move(&mut m, [1, 1, 1], DVec3::new(0.05, 0.04, -0.03));
    let now = &m.dsm_mesh(2).unwrap().positions;
    let (mut moved, mut kept) = (0, 0);
    for (p, q) in rest.iter().zip(now) {
        if p.to_array().iter().any(|&c| c > 4.0 / 3.0 + 1e-9) {
            assert_eq!(p, q, "vertex {p} outside the support moved");
            kept += 1;
        } else if p.to_array().iter().all(|&c| c < 4.0 / 3.0 - 0.1) {
            assert!((*q - *p).length() > 1e-6, "{p} in the support did not move");
            moved += 1;
        }
    }
    assert!(moved > 50 && kept > 50, "{moved} moved, {kept} kept");
    // The normals (recomputed only around what moved, from triangle cross
    // products kept between moves) are the area-weighted normals of the
    // deformed triangles everywhere, after each of several moves.
    let normals_hold = |m: &DesignModel, when: &str| {
        let mesh = m.dsm_mesh(2).unwrap();
        let mut want = vec![DVec3::ZERO; mesh.positions.len()];
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            for i in t {
                want[*i as usize] += (b - a).cross(c - a);
            }
        }
        for (k, (n, w)) in mesh.normals.iter().zip(&want).enumerate() {
            assert!(
                (*n - w.normalize()).length() < 1e-12,
                "{when}: normal {k}: {n} vs {w}"
            );
        }
    };
    normals_hold(&m, "first move");
    lattice_move(&mut m, [3, 2, 3], DVec3::new(-0.04, 0.06, 0.05));
    normals_hold(&m, "second move, another point");
    lattice_move(&mut m, [1, 1, 1], DVec3::new(-0.05, -0.04, 0.03));
    normals_hold(&m, "the first point back");
}

#[test]
fn a_dsm_mesh_outside_the_body_is_refused_and_changes_nothing() {
    let body: PartBody = serde_json::from_value(json!({"kind": "body", "lattice": {
        "degrees": [2, 2, 2], "knots": [knots(2, 3), knots(2, 3), knots(2, 3)],
        "points": box_points(2, 3)}}))
    .unwrap();
    let dsm: PartBody = serde_json::from_value(
        json!({"kind": "dsm", "dsm": {"de": 1.0, "cells": 16, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [1.8, 1.0, 1.0], "shape": {"type": "sphere", "radius": 0.5}}]}]}}),
    )
    .unwrap();
    let mut m = DesignModel::load(&DesignDoc::single("ffd", "box", body)).unwrap();
    m.apply(Edit::CreatePart {
        name: "blob".into(),
        body: Box::new(dsm),
        colour: None,
    })
    .unwrap();
    let before = m.doc().clone();
    let e = m
        .apply(Edit::Relate(RelationKind::Ffd {
            body: 1,
            part: 2,
            rest: None,
        }))
        .unwrap_err();
    assert!(
        e.message.starts_with("mesh vertex ") && e.message.contains("outside the body"),
        "{}",
        e.message
    );
    assert_eq!(*m.doc(), before);
}

/// Control-point FFD against the deformed surface φ ∘ S, φ(x) = B_new(x / 2)
/// (the rest body is the affine box): the deviation at a fine grid stays
/// within the second-order bound ½ M Σᵢ Nᵢ(s) ‖Pᵢ − S(s)‖², where M bounds
/// ‖D²φ[h, h]‖ / ‖h‖²: only the centre point (1, 1, 1) of the degree-2,
/// one-span lattice moved, by Δ, so φ = identity + Δ N(u) N(v) N(w) with
/// N(t) = 2t(1 − t); its Hessian in (u, v, w) has |∂ᵤᵤ| ≤ 4·¼ = 1 and
/// |∂ᵤᵥ| ≤ 2·2·½ = 2, Frobenius norm ≤ √27, and u = x / 2 gives ¼ of that.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_point_ffd_stays_within_its_second_order_bound_of_the_deformed_surface() {
    let data = data_dir("body-ffd-deviation");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(2, 3)}),
    )
    .await;
    let surf = create(&mut ed, "skin", "surface", patch(0.2, 0.2, 1.6, 0.8)).await;
    ok(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": surf}}),
    )
    .await;
    let s0 = control_points(&stored(addr, design, &editor).await, surf);
    let delta = DVec3::new(0.3, 0.2, -0.25);
    move_point(&mut ed, body, [1, 1, 1], delta).await;
    let s1 = control_points(&stored(addr, design, &editor).await, surf);
    let mut lattice = box_points(2, 3);
    for a in 0..3 {
        lattice[13][a] += delta[a];
    }
    let vol = volume(2, 3, &lattice);
    let phi = |x: DVec3| vol.point(x.x / 2.0, x.y / 2.0, x.z / 2.0);
    // Control-point FFD is φ of each control point (the solver, without
    // icons, changes nothing).
    let e = max_dist(&s1, &s0.iter().map(|p| phi(*p)).collect::<Vec<_>>());
    assert!(e <= 1e-12, "control points are not φ(P): {e:e}");
    let kv = || KnotVector::new(3, knots(3, 5)).unwrap();
    let before = BSplineSurface::new(kv(), kv(), s0.clone()).unwrap();
    let after = BSplineSurface::new(kv(), kv(), s1).unwrap();
    let m = delta.length() * 27f64.sqrt() / 4.0;
    let (mut worst, mut worst_ratio) = (0.0f64, 0.0f64);
    for i in 0..=60 {
        for j in 0..=60 {
            let (s, t) = (i as f64 / 60.0, j as f64 / 60.0);
            let p = before.point(s, t);
            let dev = (after.point(s, t) - phi(p)).length();
            let (bu, bv) = (basis_derivs(&kv(), s, 0), basis_derivs(&kv(), t, 0));
            let mut spread = 0.0;
            for (a, na) in bu.row(0).iter().enumerate() {
                for (b, nb) in bv.row(0).iter().enumerate() {
                    let q = s0[(bu.first + a) * 5 + bv.first + b];
                    spread += na * nb * (q - p).length_squared();
                }
            }
            let bound = 0.5 * m * spread;
            assert!(dev <= bound + 1e-12, "({s}, {t}): {dev:e} > {bound:e}");
            worst = worst.max(dev);
            if bound > 1e-9 {
                worst_ratio = worst_ratio.max(dev / bound);
            }
        }
    }
    // It is an approximation: the deviation is real, and measured.
    assert!(worst > 1e-5, "deviation {worst:e}");
    println!("control-point FFD: largest deviation {worst:.3e}, ≤ {worst_ratio:.2} of the bound");
    drop(ed);
    server.stop().await;
}

/// The smoothstep timing of the eased morph path, s = 3t² − 2t³.
fn eased(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// A bound DSM part and a bound surface follow their body's metamorphosis
/// as it plays, the document untouched. Expected values from the
/// definitions: the body is the affine box [0, 2]³ (a point's parameters
/// are x / 2) morphing along straight eased paths to a lattice whose
/// centre moved, so a carried point is A(x/2) + s(t) (B(x/2) − A(x/2)) with
/// A, B the two bodies evaluated by the kernel's volume (not the FFD code).
#[test]
fn bound_parts_follow_the_body_s_metamorphosis_exactly_and_the_document_stays() {
    let rest = box_points(2, 3);
    let mut target = rest.clone();
    target[13] = [1.3, 0.8, 1.15]; // the centre (1, 1, 1) moved
    target[26] = [2.2, 2.1, 2.3]; // and a corner: the boundary changes too
    let body: PartBody = serde_json::from_value(json!({"kind": "body",
        "lattice": {"degrees": [2, 2, 2], "knots": [knots(2, 3), knots(2, 3), knots(2, 3)], "points": rest},
        "morph_target": {"degrees": [2, 2, 2], "knots": [knots(2, 3), knots(2, 3), knots(2, 3)], "points": target}}))
    .unwrap();
    let mut m = DesignModel::load(&DesignDoc::single("morph", "box", body)).unwrap();
    let dsm: PartBody = serde_json::from_value(
        json!({"kind": "dsm", "dsm": {"de": 1.0, "cells": 20, "groups": [
        {"op": "add", "primitives": [
            {"id": 1, "at": [0.9, 1.0, 1.1], "shape": {"type": "sphere", "radius": 0.5}}]}]}}),
    )
    .unwrap();
    let surface = PartBody::Surface(SurfacePart {
        surface: SurfaceDoc {
            u_degree: 3,
            v_degree: 3,
            u_knots: knots(3, 5),
            v_knots: knots(3, 5),
            nu: 5,
            nv: 5,
            points: serde_json::from_value(patch(0.3, 0.4, 1.2, 1.0)["points"].clone()).unwrap(),
        },
        material: MaterialDoc::default(),
        icons: Vec::new(),
        kappa: None,
        spring_size: None,
    });
    for (name, b) in [("blob", dsm), ("patch", surface)] {
        m.apply(Edit::CreatePart {
            name: name.into(),
            body: Box::new(b),
            colour: None,
        })
        .unwrap();
    }
    for part in [2, 3] {
        m.apply(Edit::Relate(RelationKind::Ffd {
            body: 1,
            part,
            rest: None,
        }))
        .unwrap();
    }
    let doc = m.doc().clone();
    let mesh0 = m.dsm_mesh(2).unwrap().positions.clone();
    let patch0 = control_points(&serde_json::to_value(&doc).unwrap(), 3);
    let frame_points = |m: &DesignModel| -> Vec<DVec3> {
        let g = m.geometry(1, 3, 7, false).unwrap();
        vsculpt_protocol::GeometryFrame::decode(&g.frame)
            .unwrap()
            .points
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect()
    };
    let (a, b) = (volume(2, 3, &rest), volume(2, 3, &target));
    let carried = |x: DVec3, t: f64| {
        let (pa, pb) = (
            a.point(x.x / 2.0, x.y / 2.0, x.z / 2.0),
            b.point(x.x / 2.0, x.y / 2.0, x.z / 2.0),
        );
        pa + (pb - pa) * eased(t)
    };
    for t in [0.3, 0.5, 1.0] {
        let moved = m.set_morph_time(1, t).unwrap();
        assert_eq!(
            moved,
            vec![1, 2, 3],
            "the body and both bound parts are resent"
        );
        let want: Vec<DVec3> = mesh0.iter().map(|x| carried(*x, t)).collect();
        let e = max_dist(&m.dsm_mesh(2).unwrap().positions, &want);
        assert!(e <= 1e-12, "t = {t}: mesh off by {e:e}");
        // The surface frame (f32) shows the carried control points.
        let want: Vec<DVec3> = patch0.iter().map(|x| carried(*x, t)).collect();
        let e = max_dist(&frame_points(&m), &want);
        assert!(e <= 1e-6, "t = {t}: surface off by {e:e}");
        // It is a real move (the corner and centre travel).
        assert!(max_dist(&want, &patch0) > 1e-3);
        // Nothing stored changed.
        assert_eq!(*m.doc(), doc);
    }
    // The deformed mesh's normals are those of its triangles.
    let mesh = m.dsm_mesh(2).unwrap();
    let mut want = vec![DVec3::ZERO; mesh.positions.len()];
    for tri in &mesh.triangles {
        let [p, q, r] = tri.map(|i| mesh.positions[i as usize]);
        for i in tri {
            want[*i as usize] += (q - p).cross(r - p);
        }
    }
    for (n, w) in mesh.normals.iter().zip(&want) {
        assert!((*n - w.normalize()).length() < 1e-12);
    }
    // Back to t = 0: everything as stored, exactly.
    assert_eq!(m.set_morph_time(1, 0.0).unwrap(), vec![1, 2, 3]);
    assert_eq!(m.dsm_mesh(2).unwrap().positions, mesh0);
    let e = max_dist(&frame_points(&m), &patch0);
    assert!(e <= 1e-6, "surface at t = 0 off by {e:e}");
}

/// The STL export of a DSM part bound to a body is the mesh the body
/// deforms: the box [0, 2]³ of degree 1 with its top face raised by 0.5 is
/// the stretch z → 1.25 z (x, y kept), so every exported vertex is the
/// unbound export's vertex stretched (the same DSM data meshes the same).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_export_of_a_bound_dsm_part_is_deformed_by_its_body() {
    let data = data_dir("body-ffd-export");
    let server = TestServer::start(data.clone()).await;
    let (addr, design) = (server.addr, server.demo().id);
    let editor = server.demo().editor.clone();
    let mut ed = Client::connect(addr, design, &editor, "ffd").await;
    let body = create(
        &mut ed,
        "box",
        "body",
        json!({"lattice": box_lattice(1, 2)}),
    )
    .await;
    let blob = create(
        &mut ed,
        "blob",
        "dsm",
        json!({"de": 1.0, "cells": 20, "groups": [{"op": "add", "primitives": [
            {"id": 1, "at": [0.9, 1.0, 1.1], "shape": {"type": "sphere", "radius": 0.5}}]}]}),
    )
    .await;
    let stl = |bytes: &[u8]| -> Vec<DVec3> {
        let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
        assert_eq!(bytes.len(), 84 + 50 * n);
        let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64;
        (0..n)
            .flat_map(|t| {
                (0..3).map(move |v| {
                    let o = 84 + 50 * t + 12 + 12 * v;
                    DVec3::new(f(o), f(o + 4), f(o + 8))
                })
            })
            .collect()
    };
    let url = format!("/api/designs/{design}/export.stl?part={blob}");
    let before = get(addr, &url, Some(&editor)).await;
    assert_eq!(before.status, 200);
    let v0 = stl(&before.body);
    assert!(v0.len() > 300);
    ok(
        &mut ed,
        json!({"type": "relate", "req": 3, "relation": {"kind": "ffd", "body": body, "part": blob}}),
    )
    .await;
    ok(
        &mut ed,
        json!({"type": "body_edit", "req": 4, "part": body, "edit": {"select": {"face": "w_max"}, "delta": [0.0, 0.0, 0.5]}}),
    )
    .await;
    let after = get(addr, &url, Some(&editor)).await;
    assert_eq!(after.status, 200);
    let v1 = stl(&after.body);
    let want: Vec<DVec3> = v0
        .iter()
        .map(|p| DVec3::new(p.x, p.y, 1.25 * p.z))
        .collect();
    let e = max_dist(&v1, &want);
    assert!(
        e <= 1e-5,
        "exported vertices off the stretched mesh by {e:e}"
    );
    assert!(max_dist(&v1, &v0) > 0.1, "the export is deformed");
    drop(ed);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
