//! The server keeps the promises of `protocol/README.md`, checked with the
//! README's own examples: every client example sent with a `req` gets
//! exactly one reply carrying that `req` (an `ack`, the query's answer or an
//! `error`); `ack` carries the created icon and the committed version;
//! `create_design` over the WebSocket returns the tokens that open the new
//! design; the optional hello and device-sample fields may be left out.

mod common;

use common::TestServer;
use common::ws::{Client, Got};
use serde_json::{Value, json};

/// The README's JSON examples tagged `json client`.
fn client_examples() -> Vec<Value> {
    let text = include_str!("../../protocol/README.md");
    let mut out = Vec::new();
    let mut cur: Option<String> = None;
    for line in text.lines() {
        match &mut cur {
            None if line.trim() == "```json client" => cur = Some(String::new()),
            Some(body) if line.trim() == "```" => {
                out.push(serde_json::from_str(body).unwrap());
                cur = None;
            }
            Some(body) => body.push_str(line),
            None => {}
        }
    }
    out
}

/// Sends `msg` with `req`, then a `ping` barrier; the replies carrying
/// `req` that arrive before the barrier's `pong`.
async fn replies(c: &mut Client, mut msg: Value, req: u64) -> Vec<Value> {
    msg["req"] = json!(req);
    c.send(msg).await;
    let barrier = req + 1_000_000;
    c.send(json!({"type": "ping", "req": barrier})).await;
    let mut out = Vec::new();
    loop {
        match c.next().await {
            Got::Text(v) if v["type"] == "pong" && v["req"] == json!(barrier) => return out,
            Got::Text(v) if v["req"] == json!(req) => out.push(v),
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_request_with_req_gets_exactly_one_reply() {
    let server = TestServer::start(common::data_dir("readme-replies")).await;
    let d = server.demo().clone();
    for (role, token) in [
        ("viewer", &d.viewer),
        ("device", &d.device),
        ("editor", &d.editor),
    ] {
        let mut c = Client::connect(server.addr, d.id, token, role).await;
        for (k, example) in client_examples().into_iter().enumerate() {
            let ty = example["type"].as_str().unwrap().to_string();
            let got = replies(&mut c, example, 100 + k as u64).await;
            assert_eq!(got.len(), 1, "{role} {ty}: {got:?}");
            let expected = match ty.as_str() {
                "ping" => "pong",
                "list_designs" => "designs",
                "list_versions" => "versions",
                "create_design" if role == "editor" => "design_created",
                _ => "",
            };
            if !expected.is_empty() {
                assert_eq!(got[0]["type"], expected, "{role} {ty}: {got:?}");
            } else {
                assert!(
                    got[0]["type"] == "ack" || got[0]["type"] == "error",
                    "{role} {ty}: {got:?}"
                );
            }
        }
    }
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn acks_carry_what_was_made_and_created_designs_open() {
    let server = TestServer::start(common::data_dir("readme-acks")).await;
    let d = server.demo().clone();
    // The shortest hello, no client_name or client_kind.
    let mut c = Client::connect(server.addr, d.id, &d.editor, "").await;
    let ack = c
        .request(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.3, "v": 0.3}, "role": {"kind": "load"}}}))
        .await;
    assert_eq!(ack["type"], "ack");
    let state = common::http::get(
        server.addr,
        &format!("/api/designs/{}", d.id),
        Some(&d.editor),
    )
    .await
    .json();
    let icons = common::parts::icons(&state["design"], 1);
    let newest = icons
        .iter()
        .map(|i| i["id"].as_u64().unwrap())
        .max()
        .unwrap();
    assert_eq!(ack["icon"], newest, "{ack}");
    let ack = c.request(json!({"type": "commit", "message": "m"})).await;
    let listed = replies(&mut c, json!({"type": "list_versions"}), 5).await;
    let versions = listed[0]["versions"].as_array().unwrap();
    assert_eq!(ack["version"], versions.last().unwrap()["version"], "{ack}");
    assert_eq!(ack["version"], versions.len() as u64);
    let ack = c
        .request(json!({"type": "restore_version", "version": 1}))
        .await;
    assert_eq!(ack["version"], 1, "{ack}");
    // A device sample without time_us (optional).
    let mut dev = Client::connect(server.addr, d.id, &d.device, "bridge").await;
    dev.ok(json!({"type": "device_sample", "sensor": "h", "position": [0.0, 0.0, 0.0], "orientation": [1.0, 0.0, 0.0, 0.0]}))
        .await;

    // create_design: the tokens come back and open the new design.
    let got = replies(
        &mut c,
        json!({"type": "create_design", "name": "kettle"}),
        7,
    )
    .await;
    assert_eq!(got.len(), 1);
    let r = &got[0];
    assert_eq!(r["type"], "design_created", "{r}");
    let id = r["design"]["id"].as_u64().unwrap();
    assert_eq!(r["design"]["name"], "kettle");
    for (access, token) in
        ["editor", "viewer", "device"].map(|a| (a, r["tokens"][a].as_str().unwrap().to_string()))
    {
        let k = Client::connect(server.addr, id, &token, "new").await;
        assert_eq!(k.welcome["access"], access);
    }
    server.stop().await;
}
