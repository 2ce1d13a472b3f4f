//! The browser's geometry cache on the server side (issue 18): the welcome of
//! a compact join names its frames (`geometry`, the SHA-256 of exactly the
//! frames that follow it, inflated), a hello offering that name
//! (`cached_geometry`) while it still names the design's frames gets
//! `geometry_cached` and no frame, and any other name — stale after a drag,
//! forged, malformed — gets the frames. The name is recomputed here from the
//! frames as received (the hash function itself is checked against
//! hand-computed SHA-256 values in `ws::join_geometry`'s unit test).

mod common;

use common::ws::{Client, hello, next_message};
use common::{TestServer, data_dir};
use futures_util::SinkExt;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;
use vsculpt_server::ws::join_geometry::geometry_hash;

/// One compact join: the welcome, the frames between it and the snapshot
/// (inflated when deflated), the snapshot.
struct Join {
    welcome: Value,
    frames: Vec<Vec<u8>>,
    snapshot: Value,
}

impl Join {
    fn name(&self) -> &str {
        self.welcome["geometry"]
            .as_str()
            .expect("the welcome names the geometry")
    }
    fn cached(&self) -> bool {
        self.welcome["geometry_cached"] == json!(true)
    }
    /// The name recomputed from the frames as received.
    fn hash_of_frames(&self) -> String {
        geometry_hash(self.frames.iter().map(Vec::as_slice))
    }
    /// The name of the frames this client holds: those received, or, when
    /// the join confirmed its cache, those of the join `held` it kept.
    fn hash_of_frames_or(&self, held: &Join) -> String {
        if self.cached() {
            held.hash_of_frames()
        } else {
            self.hash_of_frames()
        }
    }
}

async fn join(
    server: &TestServer,
    design: u64,
    token: &str,
    cached: Option<&str>,
    deflate: bool,
) -> Join {
    let query = if deflate { "?deflate=1" } else { "" };
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{}/ws{query}", server.addr))
        .await
        .unwrap();
    let mut h = hello(design, token, "cache");
    h["geometry_first"] = json!(true);
    if let Some(name) = cached {
        h["cached_geometry"] = json!(name);
    }
    ws.send(Message::text(h.to_string())).await.unwrap();
    let mut welcome = None;
    let mut frames = Vec::new();
    loop {
        let m = next_message(&mut ws).await;
        match m {
            Message::Text(t) => {
                let v: Value = serde_json::from_str(t.as_str()).unwrap();
                match v["type"].as_str() {
                    Some("welcome") => welcome = Some(v),
                    Some("snapshot") => {
                        let welcome = welcome.expect("welcome before the snapshot");
                        return Join {
                            welcome,
                            frames,
                            snapshot: v,
                        };
                    }
                    other => panic!("unexpected {other:?} before the snapshot"),
                }
            }
            Message::Binary(b) => {
                assert!(welcome.is_some(), "a frame before the welcome");
                let frame = if b[4] == vsculpt_protocol::deflated::KIND_DEFLATED {
                    vsculpt_protocol::deflated::inflate(&b).unwrap()
                } else {
                    b.to_vec()
                };
                frames.push(frame);
            }
            _ => {}
        }
    }
}

#[tokio::test]
async fn the_welcome_names_the_frames_it_sends_and_a_client_holding_them_gets_none() {
    let server = TestServer::start(data_dir("geometry-cache-hit")).await;
    let d = server.demo().clone();

    let first = join(&server, d.id, &d.viewer, None, false).await;
    assert!(!first.frames.is_empty());
    assert_eq!(first.name(), first.hash_of_frames());
    assert_eq!(first.name().len(), 64);
    assert!(!first.cached());
    assert!(
        first.welcome.get("geometry_cached").is_none(),
        "absent when false"
    );

    // Deflated on the wire, the same frames once inflated, the same name.
    let deflated = join(&server, d.id, &d.viewer, None, true).await;
    assert_eq!(deflated.frames, first.frames);
    assert_eq!(deflated.name(), first.name());

    // Offering the name: confirmed, and the snapshot follows the welcome at once.
    let again = join(&server, d.id, &d.viewer, Some(first.name()), true).await;
    assert!(again.cached());
    assert_eq!(again.name(), first.name());
    assert!(
        again.frames.is_empty(),
        "no frame for a client that holds them"
    );
    assert_eq!(again.snapshot["parts"], first.snapshot["parts"]);

    // A join without geometry_first gets neither a name nor a confirmation.
    let mut legacy = Client::connect(server.addr, d.id, &d.viewer, "legacy").await;
    assert!(legacy.welcome.get("geometry").is_none());
    legacy.ping().await;
}

#[tokio::test]
async fn a_stale_forged_or_malformed_name_gets_the_frames() {
    let server = TestServer::start(data_dir("geometry-cache-forged")).await;
    let d = server.demo().clone();
    let truth = join(&server, d.id, &d.viewer, None, false).await;
    let name = truth.name().to_string();
    let mut near = name.clone().into_bytes();
    near[63] = if near[63] == b'0' { b'1' } else { b'0' };
    let forged = [
        String::new(),
        "0".repeat(64),
        name.to_uppercase(),
        format!("{name}0"),
        name[..63].to_string(),
        String::from_utf8(near).unwrap(),
        "not a hash at all".into(),
    ];
    for offered in &forged {
        let j = join(&server, d.id, &d.viewer, Some(offered), false).await;
        assert!(!j.cached(), "{offered:?} was taken");
        assert_eq!(j.frames, truth.frames, "{offered:?}: the full frames");
        assert_eq!(j.name(), name);
    }
    // A name that is not a string is a malformed hello: refused, nothing joined.
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{}/ws", server.addr))
        .await
        .unwrap();
    let mut h = hello(d.id, &d.viewer, "odd");
    h["geometry_first"] = json!(true);
    h["cached_geometry"] = json!(42);
    ws.send(Message::text(h.to_string())).await.unwrap();
    let m = next_message(&mut ws).await;
    let v: Value = serde_json::from_str(m.to_text().unwrap()).unwrap();
    assert_eq!(v["type"], "error", "{v}");
}

#[tokio::test]
async fn the_name_changes_with_the_geometry_a_drag_a_commit_an_undo() {
    let server = TestServer::start(data_dir("geometry-cache-change")).await;
    let d = server.demo().clone();
    let before = join(&server, d.id, &d.viewer, None, false).await;

    // Another client drags a surface.
    let mut ed = Client::connect(server.addr, d.id, &d.editor, "editor").await;
    let part = ed.snapshot["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["shape"]["kind"] == "surface")
        .unwrap()["id"]
        .as_u64()
        .unwrap();
    let icon = ed.grab_load_icon(part, 0.5, 0.5).await;
    ed.ok(json!({"type": "drag", "part": part, "icon": icon, "xyz": [0.5, 0.5, 0.3]}))
        .await;
    ed.ok(json!({"type": "drag_end", "part": part, "icon": icon}))
        .await;

    let dragged = join(&server, d.id, &d.viewer, Some(before.name()), false).await;
    assert!(!dragged.cached(), "the name from before the drag is stale");
    assert_ne!(dragged.frames, before.frames);
    assert_ne!(dragged.name(), before.name());
    assert_eq!(dragged.name(), dragged.hash_of_frames());

    // A commit: whatever frames the join then sends, the name is theirs, and
    // the name from before is confirmed only if the frames are the same bytes.
    ed.ok(json!({"type": "commit", "message": "dragged"})).await;
    let committed = join(&server, d.id, &d.viewer, Some(dragged.name()), false).await;
    assert_eq!(committed.name(), committed.hash_of_frames_or(&dragged));
    assert_eq!(committed.cached(), committed.name() == dragged.name());

    // Undo the drag: the shape goes back, the name moves on from the dragged one.
    ed.ok(json!({"type": "undo"})).await;
    let undone = join(&server, d.id, &d.viewer, Some(committed.name()), false).await;
    assert!(!undone.cached());
    assert_ne!(undone.name(), committed.name());
    assert_eq!(undone.name(), undone.hash_of_frames());
}
