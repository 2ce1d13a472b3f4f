//! The HTTP surface of the real server: health, metrics and token checks,
//! the static client and its missing-client page, the REST API (designs,
//! versions), mesh exports that parse as valid OBJ / STL / glTF, and IGES
//! export → import giving back the same control points.

mod common;

use common::parts;

use base64::Engine;
use common::TestServer;
use common::http::{self, get};
use serde_json::json;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn health_metrics_and_tokens() {
    let server = TestServer::start(common::data_dir("http-tokens")).await;
    let d = server.demo().clone();
    let h = get(server.addr, "/healthz", None).await;
    assert_eq!((h.status, h.json()), (200, json!({"status": "ok"})));
    // Without a valid token only the static client and /healthz answer.
    for path in [
        "/metrics",
        "/api/designs",
        "/api/designs/1",
        "/api/designs/1/versions",
        "/api/designs/1/export.obj",
    ] {
        assert_eq!(get(server.addr, path, None).await.status, 401, "{path}");
        assert_eq!(
            get(server.addr, path, Some("nope")).await.status,
            401,
            "{path}"
        );
    }
    // ?token= works as well as the header.
    let r = get(
        server.addr,
        &format!("/api/designs/1?token={}", d.viewer),
        None,
    )
    .await;
    assert_eq!(r.status, 200);
    let m = get(server.addr, "/metrics", Some(&d.editor)).await;
    assert_eq!(m.status, 200);
    let text = m.text();
    for name in [
        "vsculpt_designs_open",
        "vsculpt_clients",
        "vsculpt_solves_total",
        "vsculpt_solve_seconds_mean",
        "vsculpt_frames_per_second",
        "vsculpt_frames_sent_total",
    ] {
        assert!(text.contains(&format!("# TYPE {name} ")), "{name} missing");
    }
    assert_eq!(
        get(server.addr, "/metrics", Some(&d.viewer)).await.status,
        401
    );
    assert_eq!(
        get(server.addr, "/metrics", Some(&server.admin))
            .await
            .status,
        200
    );
    // Listings: a design token sees its design, the admin sees all.
    let l = get(server.addr, "/api/designs", Some(&d.viewer))
        .await
        .json();
    assert_eq!(l["designs"].as_array().unwrap().len(), 1);
    assert_eq!(l["designs"][0]["role"], "viewer");
    // Creating needs an editor or the admin.
    let body = br#"{"name": "lid", "nu": 8, "nv": 6}"#;
    assert_eq!(
        http::request(server.addr, "POST", "/api/designs", Some(&d.viewer), body)
            .await
            .status,
        401
    );
    let c = http::request(server.addr, "POST", "/api/designs", Some(&d.editor), body).await;
    assert_eq!(c.status, 201);
    let created = c.json();
    let id = created["id"].as_u64().unwrap();
    let s = get(
        server.addr,
        &format!("/api/designs/{id}"),
        Some(created["tokens"]["viewer"].as_str().unwrap()),
    )
    .await
    .json();
    assert_eq!(parts::part_ids(&s["design"]), vec![parts::PLATE]);
    assert_eq!(parts::surface(&s["design"], parts::PLATE)["nu"], 8);
    assert_eq!(parts::surface(&s["design"], parts::PLATE)["nv"], 6);
    // The demo's tokens do not open the new design.
    assert_eq!(
        get(server.addr, &format!("/api/designs/{id}"), Some(&d.editor))
            .await
            .status,
        401
    );
    let all = get(server.addr, "/api/designs", Some(&server.admin))
        .await
        .json();
    assert_eq!(all["designs"].as_array().unwrap().len(), 2);
    // Bad bodies.
    let bad = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&d.editor),
        b"{nope",
    )
    .await;
    assert_eq!(
        (bad.status, bad.json()["error"]["code"].as_str()),
        (400, Some("malformed"))
    );
    let bad = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&d.editor),
        br#"{"name": "x", "nu": 10000}"#,
    )
    .await;
    assert_eq!(bad.status, 400);
    // Versions: creation is version 1.
    let v = get(server.addr, "/api/designs/1/versions", Some(&d.viewer))
        .await
        .json();
    assert_eq!(v["versions"][0]["number"], 1);
    let v1 = get(server.addr, "/api/designs/1/versions/1", Some(&d.viewer))
        .await
        .json();
    assert_eq!(v1["design"]["name"], "demo");
    assert_eq!(
        get(server.addr, "/api/designs/1/versions/9", Some(&d.viewer))
            .await
            .status,
        404
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn static_client_and_missing_client_page() {
    let data = common::data_dir("http-static");
    // No client installed: `/` says how to install it.
    let server = TestServer::start(data.clone()).await;
    let r = get(server.addr, "/", None).await;
    assert_eq!(r.status, 503);
    assert!(r.text().contains("scripts/run.sh"));
    assert!(r.text().contains("npm ci"));
    server.stop().await;
    // A client folder with its packages.
    let web = data.join("web");
    std::fs::create_dir_all(web.join("src")).unwrap();
    std::fs::create_dir_all(web.join("node_modules/three/build")).unwrap();
    std::fs::create_dir_all(web.join("node_modules/iwer")).unwrap();
    std::fs::write(
        web.join("index.html"),
        "<!doctype html><title>vsculpt</title>",
    )
    .unwrap();
    std::fs::write(web.join("src/main.js"), "export const x = 1;").unwrap();
    std::fs::write(
        web.join("node_modules/three/build/three.module.js"),
        "export {};",
    )
    .unwrap();
    std::fs::write(web.join("node_modules/iwer/index.js"), "export {};").unwrap();
    let profiles = web.join("node_modules/@webxr-input-profiles/assets/dist/profiles");
    std::fs::create_dir_all(profiles.join("generic-trigger")).unwrap();
    std::fs::write(profiles.join("profilesList.json"), "{}").unwrap();
    std::fs::write(
        profiles.join("generic-trigger/right.glb"),
        b"glTF\x02\0\0\0",
    )
    .unwrap();
    let server = TestServer::start_with(data.clone(), web).await;
    let r = get(server.addr, "/", None).await;
    assert_eq!(r.status, 200);
    assert!(r.text().contains("<title>vsculpt</title>"));
    assert!(r.header("content-type").unwrap().starts_with("text/html"));
    let js = get(server.addr, "/src/main.js", None).await;
    assert_eq!(js.status, 200);
    assert!(js.header("content-type").unwrap().contains("javascript"));
    assert_eq!(
        get(server.addr, "/vendor/three/build/three.module.js", None)
            .await
            .status,
        200
    );
    assert_eq!(
        get(server.addr, "/vendor/iwer/index.js", None).await.status,
        200
    );
    let list = get(
        server.addr,
        "/vendor/webxr-profiles/profilesList.json",
        None,
    )
    .await;
    assert_eq!(list.status, 200);
    assert_eq!(list.text(), "{}");
    let glb = get(
        server.addr,
        "/vendor/webxr-profiles/generic-trigger/right.glb",
        None,
    )
    .await;
    assert_eq!(glb.status, 200);
    assert!(glb.text().starts_with("glTF"));
    assert_eq!(
        get(
            server.addr,
            "/vendor/webxr-profiles/generic-trigger/left.glb",
            None
        )
        .await
        .status,
        404
    );
    assert_eq!(get(server.addr, "/src/missing.js", None).await.status, 404);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mesh_exports_are_valid_files() {
    let server = TestServer::start(common::data_dir("http-mesh")).await;
    let d = server.demo().clone();
    let path = |ext: &str| format!("/api/designs/{}/export.{ext}", d.id);

    // OBJ: vertices, normals, faces with indices in range.
    let obj = get(server.addr, &path("obj"), Some(&d.viewer)).await;
    assert_eq!(obj.status, 200);
    let text = obj.text();
    let v = text.lines().filter(|l| l.starts_with("v ")).count();
    let vn = text.lines().filter(|l| l.starts_with("vn ")).count();
    let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
    assert!(v > 100);
    assert_eq!(v, vn);
    for f in &faces {
        let idx: Vec<usize> = f[2..]
            .split_whitespace()
            .map(|c| c.split("//").next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(idx.len(), 3);
        assert!(idx.iter().all(|&i| i >= 1 && i <= v));
    }

    // STL: 84 + 50 n bytes, finite unit facet normals.
    let stl = get(server.addr, &path("stl"), Some(&d.viewer)).await.body;
    let n = u32::from_le_bytes(stl[80..84].try_into().unwrap()) as usize;
    assert_eq!(n, faces.len());
    assert_eq!(stl.len(), 84 + 50 * n);
    for t in 0..n {
        let o = 84 + 50 * t;
        let f = |k: usize| f32::from_le_bytes(stl[o + 4 * k..o + 4 * k + 4].try_into().unwrap());
        let len = (f(0) * f(0) + f(1) * f(1) + f(2) * f(2)).sqrt();
        assert!(len == 0.0 || (len - 1.0).abs() < 1e-3);
        assert!((0..12).all(|k| f(k).is_finite()));
    }

    // glTF: JSON with a buffer whose length matches, accessors in bounds,
    // indices in range.
    let g = get(server.addr, &path("gltf"), Some(&d.viewer)).await;
    assert!(g.header("content-type").unwrap().contains("gltf"));
    let doc = g.json();
    assert_eq!(doc["asset"]["version"], "2.0");
    let uri = doc["buffers"][0]["uri"].as_str().unwrap();
    let buf = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(",").unwrap().1)
        .unwrap();
    assert_eq!(
        doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
        buf.len()
    );
    let count = |k: usize| doc["accessors"][k]["count"].as_u64().unwrap() as usize;
    assert_eq!(count(0), v);
    assert_eq!(count(1), v);
    assert_eq!(count(2), 3 * n);
    let view = &doc["bufferViews"][2];
    let off = view["byteOffset"].as_u64().unwrap() as usize;
    assert_eq!(view["byteLength"].as_u64().unwrap() as usize, 4 * count(2));
    for k in 0..count(2) {
        let i = u32::from_le_bytes(buf[off + 4 * k..off + 4 * k + 4].try_into().unwrap()) as usize;
        assert!(i < v);
    }
    assert_eq!(
        get(server.addr, &path("dwg"), Some(&d.viewer)).await.status,
        404
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn iges_export_import_round_trip() {
    let server = TestServer::start(common::data_dir("http-iges")).await;
    let d = server.demo().clone();
    let state = get(server.addr, "/api/designs/1", Some(&d.editor))
        .await
        .json();
    let igs = get(server.addr, "/api/designs/1/export.igs", Some(&d.viewer)).await;
    assert_eq!(igs.status, 200);
    let text = igs.text();
    assert!(text.lines().all(|l| l.len() == 80));
    // The exported file parses on its own to the same control points: the
    // whole product, every surface part (128) in order, then `?part=`.
    let surfaces: Vec<u64> = parts::part_ids(&state["design"])
        .into_iter()
        .filter(|id| parts::part(&state["design"], *id)["body"]["kind"] == "surface")
        .collect();
    assert_eq!(surfaces, vec![1, 2, 3]);
    // The demo's body part (the spool, last) adds its six boundary faces.
    let bodies = parts::part_ids(&state["design"])
        .into_iter()
        .filter(|id| parts::part(&state["design"], *id)["body"]["kind"] == "body")
        .count();
    assert_eq!(bodies, 1);
    let parsed = vsculpt_server::cad::read_iges(&text).unwrap();
    assert_eq!(parsed.len(), surfaces.len() + 6 * bodies);
    for (surface, id) in parsed.iter().zip(&surfaces) {
        let points: Vec<[f64; 3]> = surface.points.iter().map(|p| p.to_array()).collect();
        let original: Vec<[f64; 3]> =
            serde_json::from_value(parts::surface(&state["design"], *id)["points"].clone())
                .unwrap();
        assert_eq!(points, original, "part {id}");
    }
    let shell = get(
        server.addr,
        "/api/designs/1/export.igs?part=1",
        Some(&d.viewer),
    )
    .await;
    assert_eq!(shell.status, 200);
    let shell = shell.text();
    let parsed = vsculpt_server::cad::read_iges(&shell).unwrap();
    assert_eq!(parsed.len(), 1);
    let points: Vec<[f64; 3]> = parsed[0].points.iter().map(|p| p.to_array()).collect();
    let original: Vec<[f64; 3]> =
        serde_json::from_value(parts::surface(&state["design"], 1)["points"].clone()).unwrap();
    assert_eq!(points, original);

    // Into a new design: the same surfaces come back through import.
    let c = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&server.admin),
        br#"{"name": "copy"}"#,
    )
    .await
    .json();
    let id = c["id"].as_u64().unwrap();
    let editor = c["tokens"]["editor"].as_str().unwrap();
    let viewer = c["tokens"]["viewer"].as_str().unwrap();
    let p = format!("/api/designs/{id}/import");
    // Viewers may not import; broken files are refused; nothing changes.
    assert_eq!(
        http::request(server.addr, "POST", &p, Some(viewer), text.as_bytes())
            .await
            .status,
        403
    );
    let bad = http::request(server.addr, "POST", &p, Some(editor), b"not an iges file").await;
    assert_eq!(bad.status, 400);
    let untouched = get(server.addr, &format!("/api/designs/{id}"), Some(viewer))
        .await
        .json();
    assert_eq!(parts::part_ids(&untouched["design"]), vec![parts::PLATE]);
    // `?part=1` replaces the plate's shape with the shell's.
    let r = http::request(
        server.addr,
        "POST",
        &format!("{p}?part=1"),
        Some(editor),
        shell.as_bytes(),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["parts"], json!([1]));
    let copy = get(server.addr, &format!("/api/designs/{id}"), Some(viewer))
        .await
        .json();
    assert_eq!(parts::part_ids(&copy["design"]), vec![parts::PLATE]);
    assert_eq!(
        parts::surface(&copy["design"], parts::PLATE),
        parts::surface(&state["design"], 1)
    );
    // The whole product: every part of the file is added as a new part,
    // each with the shape it was exported with.
    let r = http::request(server.addr, "POST", &p, Some(editor), text.as_bytes()).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let added: Vec<u64> = serde_json::from_value(r.json()["parts"].clone()).unwrap();
    // Surface and curve parts come back as they were; a body comes back as
    // its six faces (surface parts), after them.
    let originals: Vec<u64> = parts::part_ids(&state["design"])
        .into_iter()
        .filter(|id| parts::part(&state["design"], *id)["body"]["kind"] != "body")
        .collect();
    assert_eq!(added.len(), originals.len() + 6 * bodies, "{}", r.text());
    let copy = get(server.addr, &format!("/api/designs/{id}"), Some(viewer))
        .await
        .json();
    assert_eq!(parts::part_ids(&copy["design"]).len(), 1 + added.len());
    for (new, old) in added.iter().zip(&originals) {
        let (n, o) = (
            &parts::part(&copy["design"], *new)["body"],
            &parts::part(&state["design"], *old)["body"],
        );
        assert_eq!(n["kind"], o["kind"], "part {old}");
        let kind = o["kind"].as_str().unwrap();
        assert_eq!(n[kind], o[kind], "part {old} → {new}");
    }
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn iges_of_a_non_ascii_name_exports_and_reimports() {
    let server = TestServer::start(common::data_dir("http-iges-name")).await;
    // A name whose é falls on the Start record's 72-column boundary, and
    // more non-ASCII after it.
    let name = format!("{}é — crème brûlée", "n".repeat(15));
    let body = json!({ "name": name }).to_string();
    let c = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&server.admin),
        body.as_bytes(),
    )
    .await;
    assert_eq!(c.status, 201, "{}", c.text());
    let c = c.json();
    let id = c["id"].as_u64().unwrap();
    let editor = c["tokens"]["editor"].as_str().unwrap();
    let igs = get(
        server.addr,
        &format!("/api/designs/{id}/export.igs"),
        Some(editor),
    )
    .await;
    assert_eq!(igs.status, 200);
    let text = igs.text();
    assert!(text.is_ascii() && text.lines().all(|l| l.len() == 80));
    let before = get(server.addr, &format!("/api/designs/{id}"), Some(editor))
        .await
        .json();
    let p = format!("/api/designs/{id}/import");
    let r = http::request(server.addr, "POST", &p, Some(editor), text.as_bytes()).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let after = get(server.addr, &format!("/api/designs/{id}"), Some(editor))
        .await
        .json();
    // The file's surface comes back as a new part with the plate's shape.
    let added: Vec<u64> = serde_json::from_value(r.json()["parts"].clone()).unwrap();
    assert_eq!(added.len(), 1, "{}", r.text());
    assert_eq!(
        parts::surface(&after["design"], added[0]),
        parts::surface(&before["design"], parts::PLATE)
    );
    assert_eq!(
        parts::part(&after["design"], parts::PLATE),
        parts::part(&before["design"], parts::PLATE)
    );

    // A coordinate of 1e300 (or 2e9) is refused with a clear error and
    // changes nothing.
    for big in ["1.0E300", "2.0E9"] {
        let surface = vsculpt_server::cad::read_iges(&text).unwrap().remove(0);
        let mut s = surface.clone();
        s.points[0].z = big.parse().unwrap();
        let bad =
            vsculpt_server::cad::write_iges(&s, &vsculpt_server::cad::IgesMeta::now("big", "test"))
                .unwrap();
        let r = http::request(server.addr, "POST", &p, Some(editor), bad.as_bytes()).await;
        assert_eq!(r.status, 400, "{}", r.text());
        assert_eq!(r.json()["error"]["code"], "out_of_range");
        assert!(
            r.json()["error"]["message"]
                .as_str()
                .unwrap()
                .contains("1e9")
        );
    }
    let again = get(server.addr, &format!("/api/designs/{id}"), Some(editor))
        .await
        .json();
    assert_eq!(again["design"], after["design"]);
    server.stop().await;
}
