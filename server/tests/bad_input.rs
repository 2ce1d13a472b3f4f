//! Every class of bad input gets its stable error code, changes nothing and
//! leaves the connection and the server alive: malformed JSON, an unknown
//! message, an oversized message, non-finite and out-of-range numbers,
//! unknown ids, (u, v) outside the domain, a bad handshake (version, token,
//! first message), binary from a client, and requests for a deleted design.

mod common;

use common::TestServer;
use common::http;
use common::ws::{self, Client, Got};
use futures_util::SinkExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

async fn state(server: &TestServer, token: &str) -> Value {
    let d = server.demo();
    let r = http::get(server.addr, &format!("/api/designs/{}", d.id), Some(token)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    r.json()["design"].clone()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_messages_get_their_codes_and_change_nothing() {
    let server = TestServer::start(common::data_dir("bad")).await;
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    let before = state(&server, &d.editor).await;

    // Malformed JSON: no req can be read, the error carries none.
    c.send_text("{\"type\": \"move_icon\", \"part\": 1, \"icon\": 1,")
        .await;
    let e = c.wait_for("error").await;
    assert_eq!(e["code"], "malformed");
    assert!(e.get("req").is_none());
    c.send_text("not json at all").await;
    assert_eq!(c.wait_for("error").await["code"], "malformed");
    // A field of the wrong type: malformed, with the req echoed.
    c.refused(
        json!({"type": "move_icon", "part": 1, "icon": "one", "xyz": [0, 0, 0]}),
        "malformed",
    )
    .await;
    c.refused(
        json!({"type": "move_icon", "part": 1, "icon": 1}),
        "malformed",
    )
    .await;
    // Version 2: an icon message names its part; without one it is
    // malformed, and an icon named on a part it is not on (or a part that
    // does not exist) is refused with `unknown_part`.
    c.refused(
        json!({"type": "move_icon", "icon": 1, "xyz": [0.0, 0.0, 0.0]}),
        "malformed",
    )
    .await;
    c.refused(
        json!({"type": "move_icon", "part": 2, "icon": 1, "xyz": [0.0, 0.0, 0.0]}),
        "unknown_part",
    )
    .await;
    c.refused(
        json!({"type": "drag_start", "part": 99, "icon": 1}),
        "unknown_part",
    )
    .await;
    c.refused(
        json!({"type": "set_material", "part": 99, "material": {"alpha11": 0.1, "alpha12": 0.0, "alpha22": 0.1, "beta11": 1.0, "beta12": 1.0, "beta22": 1.0}}),
        "unknown_part",
    )
    .await;
    // Unknown message.
    c.refused(json!({"type": "teleport", "icon": 1}), "unknown_message")
        .await;
    // Oversized message (over 256 KiB).
    let big = format!(
        "{{\"type\": \"commit\", \"req\": 77, \"message\": \"{}\"}}",
        "x".repeat(300 * 1024)
    );
    c.send_text(&big).await;
    let e = c.wait_for("error").await;
    assert_eq!(e["code"], "too_large");
    // ∞ cannot be written in JSON; the nearest thing is a literal that
    // overflows f64, which the JSON layer refuses.
    c.send_text(
        "{\"type\": \"move_icon\", \"part\": 1, \"req\": 8, \"icon\": 1, \"xyz\": [1e999, 0, 0]}",
    )
    .await;
    let e = c.wait_for("error").await;
    assert!(e["code"] == "malformed" || e["code"] == "not_finite", "{e}");
    c.send_text("{\"type\": \"drag\", \"part\": 1, \"req\": 9, \"icon\": 1, \"xyz\": [NaN, 0, 0]}")
        .await;
    let e = c.wait_for("error").await;
    assert!(e["code"] == "malformed" || e["code"] == "not_finite", "{e}");
    // Out of range magnitudes.
    c.refused(
        json!({"type": "move_icon", "part": 1, "icon": 1, "xyz": [1e300, 0.0, 0.0]}),
        "out_of_range",
    )
    .await;
    c.refused(json!({"type": "set_material", "part": 1, "material": {"alpha11": -1.0, "alpha12": 0.0, "alpha22": 1.0, "beta11": 1.0, "beta12": 1.0, "beta22": 1.0}}), "out_of_range").await;
    // Unknown ids.
    c.refused(
        json!({"type": "move_icon", "part": 1, "icon": 999, "xyz": [0.0, 0.0, 0.0]}),
        "unknown_icon",
    )
    .await;
    c.refused(
        json!({"type": "delete_icon", "part": 1, "icon": 999}),
        "unknown_icon",
    )
    .await;
    c.refused(
        json!({"type": "drag_start", "part": 1, "icon": 999}),
        "unknown_icon",
    )
    .await;
    c.refused(
        json!({"type": "drag", "part": 1, "icon": 999, "xyz": [0.0, 0.0, 0.0]}),
        "unknown_icon",
    )
    .await;
    c.refused(
        json!({"type": "set_state", "part": 1, "icon": 999, "state": "sleeping"}),
        "unknown_icon",
    )
    .await;
    c.refused(
        json!({"type": "restore_version", "version": 999}),
        "unknown_version",
    )
    .await;
    c.refused(
        json!({"type": "delete_design", "design": 999}),
        "unknown_design",
    )
    .await;
    // (u, v) outside the domain [0, 1]².
    c.refused(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 1.5, "v": 0.5}, "role": {"kind": "position"}}}), "out_of_domain").await;
    c.refused(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": -0.01}, "role": {"kind": "load"}}}), "out_of_domain").await;
    c.refused(
        json!({"type": "edit_icon", "part": 1, "icon": 1, "anchor": {"kind": "point", "u": 2.0, "v": 0.5}}),
        "out_of_domain",
    )
    .await;
    c.refused(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "region", "u0": 0.2, "v0": 0.2, "u1": 1.2, "v1": 0.5, "inside": true}, "role": {"kind": "load"}}}), "out_of_domain").await;
    // Nothing to redo.
    c.refused(json!({"type": "redo"}), "conflict").await;
    // A client sends binary.
    c.ws.send(Message::binary(vec![1u8, 2, 3])).await.unwrap();
    assert_eq!(c.wait_for("error").await["code"], "malformed");
    // A second hello.
    c.refused(ws::hello(d.id, &d.editor, "again"), "bad_handshake")
        .await;

    // Alive, and nothing changed.
    c.ping().await;
    assert_eq!(state(&server, &d.editor).await, before);
    assert_eq!(http::get(server.addr, "/healthz", None).await.status, 200);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_handshakes_are_refused_and_closed() {
    let server = TestServer::start(common::data_dir("handshake")).await;
    let d = server.demo().clone();
    // Wrong token, wrong design, wrong version, not a hello first.
    let e = Client::try_connect(server.addr, d.id, "0123", "x")
        .await
        .err()
        .unwrap();
    assert_eq!(e["code"], "bad_token");
    let e = Client::try_connect(server.addr, 42, &d.editor, "x")
        .await
        .err()
        .unwrap();
    assert_eq!(e["code"], "bad_token");
    let mut s = ws::raw(server.addr).await;
    let mut h = ws::hello(d.id, &d.editor, "x");
    h["protocol"] = json!(99);
    s.send(Message::text(h.to_string())).await.unwrap();
    match ws::next(&mut s).await {
        Got::Text(v) => assert_eq!(v["code"], "bad_version"),
        other => panic!("{other:?}"),
    }
    assert!(matches!(ws::next(&mut s).await, Got::Closed));
    let mut s = ws::raw(server.addr).await;
    s.send(Message::text(json!({"type": "ping"}).to_string()))
        .await
        .unwrap();
    match ws::next(&mut s).await {
        Got::Text(v) => assert_eq!(v["code"], "bad_handshake"),
        other => panic!("{other:?}"),
    }
    let mut s = ws::raw(server.addr).await;
    s.send(Message::text("garbage")).await.unwrap();
    match ws::next(&mut s).await {
        Got::Text(v) => assert_eq!(v["code"], "malformed"),
        other => panic!("{other:?}"),
    }
    // The server is fine.
    let mut c = Client::connect(server.addr, d.id, &d.viewer, "v").await;
    c.ping().await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_deleted_design_refuses_everything() {
    let server = TestServer::start(common::data_dir("deleted")).await;
    let admin = server.admin.clone();
    // A second design to delete, with its own tokens.
    let r = http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&admin),
        br#"{"name": "kettle"}"#,
    )
    .await;
    assert_eq!(r.status, 201, "{}", r.text());
    let created = r.json();
    let id = created["id"].as_u64().unwrap();
    let editor = created["tokens"]["editor"].as_str().unwrap().to_string();
    let mut a = Client::connect(server.addr, id, &editor, "a").await;
    let mut b = Client::connect(server.addr, id, &editor, "b").await;
    a.ok(json!({"type": "delete_design", "design": id})).await;
    // b hears of the deletion; its icon edits now fail.
    let e = b.wait_for("error").await;
    assert_eq!(e["code"], "unknown_design");
    b.refused(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}}}), "unknown_design").await;
    b.refused(
        json!({"type": "drag_start", "part": 1, "icon": 1}),
        "unknown_design",
    )
    .await;
    // New connections and REST calls are refused.
    let e = Client::try_connect(server.addr, id, &editor, "c")
        .await
        .err()
        .unwrap();
    assert_eq!(e["code"], "bad_token");
    let r = http::get(server.addr, &format!("/api/designs/{id}"), Some(&editor)).await;
    assert_eq!(r.status, 401);
    // The demo is untouched and the server alive.
    let d = server.demo().clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    c.ping().await;
    b.ping().await;
    server.stop().await;
}
