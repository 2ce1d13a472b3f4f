//! A network part's faces in the IGES export (paper 004 §3's refit): each
//! face is a bicubic B-spline refitted over the square around its n-gon
//! domain and trimmed to the n-gon — an entity 144 pointing to its
//! (physically dependent) 128, and through a 142 to a closed planar
//! degree-1 126 in the surface's parameter space (use flag 5). The file
//! is read twice: its records by hand here (the chain of pointers, the
//! statuses, the polygon's vertices against the regular n-gon written from
//! its formula, mapped to [0, 1]²), and by the server's reader (9 curves
//! and 6 surfaces named `<part> face <k>`). Each re-read surface is
//! evaluated with the kernel and compared with the test's own kernel
//! patches of the stored curves: at the shown samples (a subset of the
//! refit's, which are twice as fine; within the stated refit tolerance,
//! 1e-5 of the size), between the refit's samples on a lattice twice as
//! fine again, along the trimming polygon (which must follow the styling
//! curves) and at its corners (the meetings).

mod common;

use common::http::{get, request};
use common::{TestServer, data_dir};
use glam::{DVec2, DVec3};
use serde_json::{Value, json};
use std::collections::HashMap;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::network::{CurveNetwork, DomainMesh, NetworkOptions};
use vsculpt_server::cad::{IgesEntity, read_iges_parts};

/// The server's sample resolution of a face (`network_engine::MESH_RESOLUTION`).
const RESOLUTION: usize = 12;
/// The refit's stated tolerance relative to the size (`REFIT_TOLERANCE`).
const TOLERANCE: f64 = 1e-5;

/// The test's kernel network of the stored part (REST `design.parts[0].body`).
fn kernel_network(body: &Value) -> CurveNetwork {
    assert_eq!(body["kind"], "network", "{body}");
    let curves: Vec<BSplineCurve> = body["curves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let kv = KnotVector::new(
                c["degree"].as_u64().unwrap() as usize,
                serde_json::from_value(c["knots"].clone()).unwrap(),
            )
            .unwrap();
            let pts: Vec<[f64; 3]> = serde_json::from_value(c["points"].clone()).unwrap();
            BSplineCurve::new(kv, pts.into_iter().map(DVec3::from).collect()).unwrap()
        })
        .collect();
    let up: [f64; 3] = serde_json::from_value(body["up"].clone()).unwrap();
    CurveNetwork::new(
        curves,
        NetworkOptions {
            tolerance: body["tolerance"].as_f64().unwrap(),
            up: DVec3::from(up),
        },
    )
    .unwrap()
}

/// A directory entry: its entity type, status and parameter fields.
struct Entry {
    entity: u32,
    status: String,
    params: Vec<String>,
}

/// The file's entries by DE sequence number, each with its parameter
/// fields (read off the fixed columns: D fields 8 wide, P data in columns
/// 1–64, `,` and `;` the delimiters this writer declares).
fn entries(text: &str) -> HashMap<usize, Entry> {
    let lines: Vec<&str> = text.lines().collect();
    let section = |c: char| -> Vec<&str> {
        lines
            .iter()
            .copied()
            .filter(|l| l.len() == 80 && l.as_bytes()[72] == c as u8)
            .collect()
    };
    let (d, p) = (section('D'), section('P'));
    let mut out = HashMap::new();
    for pair in d.chunks(2) {
        let (d1, d2) = (pair[0], pair[1]);
        let field = |l: &str, k: usize| l[8 * k..8 * k + 8].trim().to_string();
        let seq: usize = d1[73..80].trim().parse().unwrap();
        let first: usize = field(d1, 1).parse().unwrap();
        let count: usize = field(d2, 3).parse().unwrap();
        let data: String = p[first - 1..first - 1 + count]
            .iter()
            .map(|l| {
                let back: usize = l[65..72].trim().parse().unwrap();
                assert_eq!(back, seq, "P line back-pointer");
                &l[..64]
            })
            .collect();
        let data = data.trim_end();
        let data = data.strip_suffix(';').unwrap_or(data);
        out.insert(
            seq,
            Entry {
                entity: field(d1, 0).parse().unwrap(),
                status: d1[64..72].to_string(),
                params: data.split(',').map(|s| s.trim().to_string()).collect(),
            },
        );
    }
    out
}

/// The regular n-gon domain's vertex j, from the kernel's documented
/// formula (cos, sin of 2πj/n + π/2 − π/n), mapped from [−1, 1]² to [0, 1]².
fn polygon_vertex(n: usize, j: usize) -> [f64; 2] {
    let a = std::f64::consts::TAU * j as f64 / n as f64 + std::f64::consts::FRAC_PI_2
        - std::f64::consts::PI / n as f64;
    [(a.cos() + 1.0) / 2.0, (a.sin() + 1.0) / 2.0]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn network_faces_are_exported_as_refits_trimmed_to_their_faces() {
    let data = data_dir("network-iges");
    let server = TestServer::start(data.clone()).await;
    let body = json!({"name": "bottle iges", "template": "bottle"}).to_string();
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
    let id = v["id"].as_u64().unwrap();
    let editor = v["tokens"]["editor"].as_str().unwrap().to_string();
    let state = get(server.addr, &format!("/api/designs/{id}"), Some(&editor))
        .await
        .json();
    let part = &state["design"]["parts"][0];
    let name = part["name"].as_str().unwrap().to_string();
    let net = kernel_network(&part["body"]);
    let patches = net.patches();
    assert_eq!(patches.len(), 6);

    let igs = get(
        server.addr,
        &format!("/api/designs/{id}/export.igs"),
        Some(&editor),
    )
    .await;
    assert_eq!(igs.status, 200, "{}", igs.text());
    let text = igs.text();

    // The records: 9 independent 126 (the curves), 6 independent 144, each
    // with its dependent 128, and a 142 whose parameter-space curve is the
    // face's polygon.
    let e = entries(&text);
    let independent = |t: u32| {
        e.values()
            .filter(|x| x.entity == t && x.status == "00000000")
            .count()
    };
    assert_eq!(independent(126), 9, "one 126 per styling curve");
    assert_eq!(independent(144), 6, "one 144 per face");
    assert_eq!(independent(128), 0, "the refits belong to their 144s");
    let mut trimmed: Vec<usize> = e
        .iter()
        .filter(|(_, x)| x.entity == 144)
        .map(|(de, _)| *de)
        .collect();
    trimmed.sort();
    for (face, de) in trimmed.iter().enumerate() {
        let t = &e[de];
        let ptr = |k: usize| -> usize { t.params[k].parse().unwrap() };
        assert_eq!(&t.params[2..4], ["1", "0"], "144 N1 = 1, N2 = 0");
        let s = &e[&ptr(1)];
        assert_eq!((s.entity, s.status.as_str()), (128, "00010000"));
        let c = &e[&ptr(4)];
        assert_eq!((c.entity, c.status.as_str()), (142, "00010000"));
        let cptr = |k: usize| -> usize { c.params[k].parse().unwrap() };
        assert_eq!(cptr(2), ptr(1), "142 on the 144's surface");
        assert_eq!((c.params[4].as_str(), c.params[5].as_str()), ("0", "1"));
        let b = &e[&cptr(3)];
        assert_eq!((b.entity, b.status.as_str()), (126, "00010500"));
        // 126: K, M = 1, planar, closed, polynomial; the points.
        let k: usize = b.params[1].parse().unwrap();
        let n = patches[face].sides();
        assert_eq!(k, n, "face {face}: {n} sides, {} loop points", k + 1);
        assert_eq!(&b.params[2..6], ["1", "1", "1", "1"]);
        let at = 7 + (k + 3) + (k + 1);
        let pts: Vec<f64> = b.params[at..at + 3 * (k + 1)]
            .iter()
            .map(|x| x.parse().unwrap())
            .collect();
        for j in 0..=n {
            let want = polygon_vertex(n, j % n);
            let got = [pts[3 * j], pts[3 * j + 1], pts[3 * j + 2]];
            assert!(
                (got[0] - want[0]).abs() < 1e-12
                    && (got[1] - want[1]).abs() < 1e-12
                    && got[2] == 0.0,
                "face {face} loop point {j}: {got:?} vs {want:?}"
            );
        }
    }

    // Read back: the curves and the six refits, named by face.
    let parts = read_iges_parts(&text).unwrap();
    let surfaces: Vec<(String, BSplineSurface)> = parts
        .iter()
        .filter_map(|p| match &p.entity {
            IgesEntity::Surface(s) => Some((
                p.name.clone().unwrap_or_default(),
                BSplineSurface::new(
                    KnotVector::new(s.u_degree, s.u_knots.clone()).unwrap(),
                    KnotVector::new(s.v_degree, s.v_knots.clone()).unwrap(),
                    s.points.clone(),
                )
                .unwrap(),
            )),
            _ => None,
        })
        .collect();
    assert_eq!(parts.len(), 15);
    assert_eq!(surfaces.len(), 6);

    // Against the test's kernel patches.
    let mut all = Vec::new();
    for p in &patches {
        let dm = DomainMesh::new(p.domain(), RESOLUTION);
        all.extend(dm.points.iter().map(|q| p.point(*q)));
    }
    let (lo, hi) = all.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let size = (hi - lo).length();
    let uv = |q: DVec2| ((q.x + 1.0) / 2.0, (q.y + 1.0) / 2.0);
    for (face, (pname, s)) in surfaces.iter().enumerate() {
        assert_eq!(*pname, format!("{name} face {face}"));
        let p = &patches[face];
        let gap = |q: DVec2| {
            let (u, v) = uv(q);
            s.point(u, v).distance(p.point(q))
        };
        let at_samples = DomainMesh::new(p.domain(), RESOLUTION)
            .points
            .iter()
            .map(|q| gap(*q))
            .fold(0.0, f64::max);
        let between = DomainMesh::new(p.domain(), 4 * RESOLUTION)
            .points
            .iter()
            .map(|q| gap(*q))
            .fold(0.0, f64::max);
        let n = p.sides();
        let along = (0..n)
            .flat_map(|i| (0..=50).map(move |k| (i, k as f64 / 50.0)))
            .map(|(i, t)| gap(p.domain().side_point(i, t)))
            .fold(0.0, f64::max);
        let corners = (0..n)
            .map(|j| {
                let [u, v] = polygon_vertex(n, j);
                s.point(u, v).distance(p.ribbons()[j].point(0.0))
            })
            .fold(0.0, f64::max);
        println!(
            "face {face} ({n} sides): refit off the patch by {:.2e} at the samples, {:.2e} between the refit's samples, {:.2e} along the trimming polygon, {:.2e} at the corners (relative to the size {size:.3})",
            at_samples / size,
            between / size,
            along / size,
            corners / size
        );
        assert!(at_samples <= TOLERANCE * size, "face {face}: {at_samples}");
        assert!(
            corners <= TOLERANCE * size,
            "face {face} corners: {corners}"
        );
        assert!(
            between <= 1e-3 * size,
            "face {face} between samples: {between}"
        );
        assert!(
            along <= 1e-3 * size,
            "face {face} along its curves: {along}"
        );
    }
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}
