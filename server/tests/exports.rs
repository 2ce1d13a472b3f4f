//! Mesh exports are bounded and streamed: the tessellation never exceeds
//! the vertex budget (coarsened to fit, still a valid closed grid of the
//! whole surface; a product's parts share the budget), the body goes out
//! chunked (never assembled whole), and the default budget is one million
//! vertices.

mod common;

use common::TestServer;
use common::http::get;
use vsculpt_server::export::{DEFAULT_MAX_EXPORT_VERTICES, SAMPLES_PER_SPAN, samples};

#[test]
fn sample_counts_fit_the_budget() {
    assert_eq!(DEFAULT_MAX_EXPORT_VERTICES, 1_000_000);
    // Small surfaces keep the full density.
    assert_eq!(samples(13, 9, 1_000_000), (13 * 8 + 1, 9 * 8 + 1));
    assert_eq!(SAMPLES_PER_SPAN, 8);
    // A 400 × 400 bicubic net has 397 spans each way: 8 per span would be
    // 10.1 M vertices; the largest whole density that fits is 2.
    let (a, b) = samples(397, 397, 1_000_000);
    assert_eq!((a, b), (2 * 397 + 1, 2 * 397 + 1));
    assert!(a * b <= 1_000_000);
    // More spans than the budget allows at one sample each: scaled, ≥ 2.
    let (a, b) = samples(5000, 10, 1000);
    assert!(a * b <= 1000 && a >= 2 && b >= 2, "{a} × {b}");
    for budget in [4, 5, 17, 100, 999, 12_345] {
        for (su, sv) in [(1, 1), (3, 200), (200, 3), (397, 397)] {
            let (a, b) = samples(su, sv, budget);
            assert!(
                a * b <= budget && a >= 2 && b >= 2,
                "{su}×{sv} in {budget}: {a}×{b}"
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mesh_exports_keep_to_the_vertex_budget_and_stream() {
    let data = common::data_dir("export-budget");
    let web = data.join("no-web-client");
    let budget = 500;
    let server = TestServer::start_configured(data, web, |c| c.export_max_vertices = budget).await;
    let d = server.demo().clone();
    let path = |ext: &str| format!("/api/designs/{}/export.{ext}", d.id);

    // The top shell alone (`?part=1`).
    let shell = |ext: &str| format!("{}?part=1", path(ext));
    let obj = get(server.addr, &shell("obj"), Some(&d.viewer)).await;
    assert_eq!(obj.status, 200);
    assert_eq!(obj.header("transfer-encoding"), Some("chunked"));
    assert!(obj.header("content-length").is_none());
    let text = obj.text();
    let v = text.lines().filter(|l| l.starts_with("v ")).count();
    let f = text.lines().filter(|l| l.starts_with("f ")).count();
    // The shell is 16 × 12 bicubic (13 × 9 spans): 8 per span would be
    // 105 × 73 = 7665 vertices; one per span, 14 × 10 = 140, fits 500.
    assert!(v <= budget, "{v} vertices");
    assert_eq!(v, 14 * 10);
    assert_eq!(f, 2 * 13 * 9);

    let stl = get(server.addr, &shell("stl"), Some(&d.viewer)).await;
    assert_eq!(stl.header("transfer-encoding"), Some("chunked"));
    let n = u32::from_le_bytes(stl.body[80..84].try_into().unwrap()) as usize;
    assert_eq!((n, stl.body.len()), (f, 84 + 50 * f));

    let gltf = get(server.addr, &shell("gltf"), Some(&d.viewer)).await;
    let doc = gltf.json();
    assert_eq!(doc["accessors"][0]["count"], v);
    assert_eq!(doc["accessors"][2]["count"], 3 * f);

    // The whole product: the budget is shared by the surface parts by
    // their knot spans — the shell 13 × 9 = 117, each side panel 13 × 1 =
    // 13, of 143: the shell gets 409 vertices (one sample per span, 140;
    // two would be 27 × 19 = 513), each side 45 (14 × 2 = 28; two per span
    // would be 27 × 3 = 81). The feature line is a curve: no mesh. The
    // spool body (a tricubic 5 × 5 × 7 cube: 2, 2 and 4 spans) adds its six
    // faces at one sample per span: four of 3 × 5 and two of 3 × 3
    // vertices (78), 4 · 2 · 8 + 2 · 2 · 4 = 80 triangles.
    let obj = get(server.addr, &path("obj"), Some(&d.viewer)).await;
    assert_eq!(obj.status, 200);
    assert_eq!(obj.header("transfer-encoding"), Some("chunked"));
    let text = obj.text();
    let v = text.lines().filter(|l| l.starts_with("v ")).count();
    let f = text.lines().filter(|l| l.starts_with("f ")).count();
    assert!(v <= budget, "{v} vertices");
    assert_eq!(v, 14 * 10 + 2 * 14 * 2 + 78);
    assert_eq!(f, 2 * 13 * 9 + 2 * (2 * 13) + 80);
    let stl = get(server.addr, &path("stl"), Some(&d.viewer)).await;
    let n = u32::from_le_bytes(stl.body[80..84].try_into().unwrap()) as usize;
    assert_eq!((n, stl.body.len()), (f, 84 + 50 * f));
    let gltf = get(server.addr, &path("gltf"), Some(&d.viewer)).await;
    let doc = gltf.json();
    assert_eq!(doc["accessors"][0]["count"], v);
    assert_eq!(doc["accessors"][2]["count"], 3 * f);

    let igs = get(server.addr, &path("igs"), Some(&d.viewer)).await;
    assert_eq!(igs.status, 200);
    // Every part: three surfaces, the feature line and the spool's six faces.
    assert_eq!(
        vsculpt_server::cad::read_iges_parts(&igs.text())
            .unwrap()
            .len(),
        10
    );
    server.stop().await;
}
