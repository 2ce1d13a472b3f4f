//! A commit must not stall the design. A commit is one durable store
//! transaction ending in an fsync; before this test it ran inside the
//! design's actor, so every client of the design waited for it (the p99 of
//! an editor's own drag frame was a commit's fsync). Here the store is
//! stalled outright while a commit is being written (a test-only hold on
//! its connection, `fault-injection`): another client's drags must still
//! get their geometry frames, and those come before the commit's reply,
//! which waits until the write is durable and then carries the version.
//! Ordering is asserted, never timing: the stall is lifted only after the
//! other client has its frames. The committed snapshot is the design as it
//! was when the commit was asked; edits made while it is written belong to
//! the next version. A commit whose write fails changes nothing, and two
//! commits asked together give consecutive versions in the order asked.
//! Every check of what is committed is made after a restart. A review
//! comment's write (a viewer may comment) holds up no drag either.

mod common;

use common::http::get;
use common::parts::{self, SHELL, load_icon};
use common::store_server::StoreServer;
use common::ws::{Client, Got};
use futures_util::{FutureExt, StreamExt};
use serde_json::{Value, json};
use std::path::Path;
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_server::design::DesignDoc;

/// How long a drag may go unanswered before the test calls it held up by
/// the commit: a failure guard, not a latency bound (the frames of the drags
/// arrive in milliseconds). Shorter than the test client's own 10 s wait for
/// any message, so the failure says what it is.
const ANSWER_WITHIN: Duration = Duration::from_secs(8);

/// The server of these tests. No working-state write becomes due during a
/// test (a long `persist_delay`), so the only store write a test waits for
/// is its commit; stopping the server still writes it.
async fn start(data: &Path) -> StoreServer {
    StoreServer::start(data, Duration::from_secs(600)).await
}

/// The design as the actor holds it now (REST: asks the store for the
/// token, so not while the store is stalled).
async fn in_memory(s: &StoreServer) -> Value {
    get(
        s.addr,
        &format!("/api/designs/{}", s.design.id),
        Some(&s.design.tokens.editor),
    )
    .await
    .json()["design"]
        .clone()
}

/// Waits until a store call waits behind the stall: the commit's write has
/// started.
async fn write_started(s: &StoreServer) {
    for _ in 0..2000 {
        if s.store.waiting() > 0 {
            return;
        }
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    panic!("the commit never reached the store");
}

/// What a restarted server has committed: (number, message, document).
async fn committed_after_restart(data: &Path) -> (Vec<(u64, String, Value)>, Value) {
    let s = start(data).await;
    let id = s.design.id;
    let versions = s
        .store
        .versions(id)
        .unwrap()
        .into_iter()
        .map(|v| {
            let (_, bytes) = s.store.version(id, v.number).unwrap().unwrap();
            let doc = serde_json::to_value(DesignDoc::from_bytes(&bytes).unwrap()).unwrap();
            (v.number, v.message, doc)
        })
        .collect();
    let working = in_memory(&s).await;
    s.stop().await;
    (versions, working)
}

/// Sends a request with `req` without waiting for its reply.
async fn ask(c: &mut Client, req: u64, mut msg: Value) {
    msg["req"] = json!(req);
    c.send(msg).await;
}

/// Drags `icon` of the shell to `z` above `p` and waits for the geometry
/// frame of that drag (a shell frame newer than `after`); its revision.
async fn dragged(c: &mut Client, icon: u64, p: [f64; 3], z: f64, after: u64) -> u64 {
    c.send(json!({"type": "drag", "part": SHELL, "icon": icon, "xyz": [p[0], p[1], p[2] + z]}))
        .await;
    let f = tokio::time::timeout(ANSWER_WITHIN, c.frame_of_after(SHELL, after))
        .await
        .expect("no geometry frame of a drag while a store write was held up");
    f.revision
}

/// The text messages `c` has received so far, without waiting for more
/// (frames are skipped).
fn texts_so_far(c: &mut Client) -> Vec<Value> {
    let mut got = Vec::new();
    while let Some(Some(Ok(m))) = c.ws.next().now_or_never() {
        if let Message::Text(t) = m {
            got.push(serde_json::from_str(t.as_str()).unwrap());
        }
    }
    got
}

/// The reply to `req` (skipping events and frames), noting each
/// `committed` event seen on the way in `events`.
async fn reply_to(c: &mut Client, req: u64, events: &mut Vec<Value>) -> Value {
    loop {
        match c.next().await {
            Got::Text(v) if v["req"] == json!(req) => return v,
            Got::Text(v) if v["type"] == "committed" => events.push(v),
            Got::Closed => panic!("closed while waiting for the reply to {req}"),
            _ => {}
        }
    }
}

/// The next `committed` event.
async fn committed(c: &mut Client) -> Value {
    c.wait_for("committed").await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_commit_being_written_holds_up_no_drag_and_is_answered_once_durable() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let s = start(&data).await;
    let mut ann = s.connect("ann").await;
    let mut bob = s.connect("bob").await;
    let (icon, p) = load_icon(&bob.snapshot);
    bob.ok(json!({"type": "drag_start", "part": SHELL, "icon": icon}))
        .await;
    let asked = in_memory(&s).await;

    // The disk stalls; ann commits; her commit's write starts and waits.
    let release = s.store.stall();
    ask(
        &mut ann,
        1,
        json!({"type": "commit", "message": "shoulder"}),
    )
    .await;
    write_started(&s).await;

    // Meanwhile bob drags and gets the frame of every drag.
    let mut order: Vec<String> = Vec::new();
    let mut rev = 0;
    for k in 1..=5 {
        rev = dragged(&mut bob, icon, p, k as f64, rev).await;
        order.push(format!("bob's frame {rev}"));
    }
    // Nobody has heard of the commit: it is not durable yet.
    for v in texts_so_far(&mut ann) {
        assert_ne!(
            v["req"],
            json!(1),
            "the commit was answered before it was durable: {v}"
        );
        assert_ne!(v["type"], "committed", "{v}");
    }
    for v in texts_so_far(&mut bob) {
        assert_ne!(v["type"], "committed", "{v}");
    }

    // The disk is back: the write lands, then the reply with the version.
    drop(release);
    let mut events = Vec::new();
    let r = reply_to(&mut ann, 1, &mut events).await;
    order.push("ann's commit reply".into());
    assert_eq!(r["type"], "ack", "{r}");
    assert_eq!(r["version"], 2, "{r}");
    assert_eq!(
        order.iter().position(|o| o == "ann's commit reply"),
        Some(order.len() - 1),
        "{order:?}"
    );
    assert!(order[..5].iter().all(|o| o.starts_with("bob's frame")));
    let seen = committed(&mut bob).await;
    assert_eq!(seen["version"]["version"], 2, "{seen}");
    assert_eq!(seen["version"]["message"], "shoulder", "{seen}");
    bob.ok(json!({"type": "drag_end", "part": SHELL, "icon": icon}))
        .await;
    let dragged_state = in_memory(&s).await;
    assert_ne!(
        parts::icons(&dragged_state, SHELL),
        parts::icons(&asked, SHELL)
    );
    drop((ann, bob));
    s.stop().await;

    // After a restart: version 2 is the design as it was when the commit
    // was asked (bob's drags meanwhile are not in it); the working state
    // has them.
    let (versions, working) = committed_after_restart(&data).await;
    let numbers: Vec<(u64, &str)> = versions.iter().map(|(n, m, _)| (*n, m.as_str())).collect();
    assert_eq!(numbers, vec![(1, "created"), (2, "shoulder")]);
    assert_eq!(versions[1].2["parts"], asked["parts"]);
    assert_eq!(working["parts"], dragged_state["parts"]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_commit_whose_write_fails_changes_nothing_and_the_next_one_is_stored() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let s = start(&data).await;
    let mut ann = s.connect("ann").await;
    let mut bob = s.connect("bob").await;
    let (icon, p) = load_icon(&bob.snapshot);
    bob.ok(json!({"type": "drag_start", "part": SHELL, "icon": icon}))
        .await;

    // The disk refuses writes (read-only) and stalls; ann commits.
    s.store.read_only(true).unwrap();
    let release = s.store.stall();
    ask(&mut ann, 1, json!({"type": "commit", "message": "refused"})).await;
    write_started(&s).await;
    let mut rev = 0;
    for k in 1..=3 {
        rev = dragged(&mut bob, icon, p, k as f64, rev).await;
    }
    drop(release);
    let mut events = Vec::new();
    let r = reply_to(&mut ann, 1, &mut events).await;
    assert_eq!(r["type"], "error", "{r}");
    assert_eq!(r["code"], "storage", "{r}");
    let why = r["message"].as_str().unwrap();
    assert!(
        why.contains("readonly") && why.contains("not stored"),
        "{r}"
    );
    assert!(events.is_empty(), "{events:?}");
    // Nothing changed: the versions are as before, the work is kept.
    let v = ann.request(json!({"type": "list_versions"})).await;
    let numbers: Vec<u64> = v["versions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["version"].as_u64().unwrap())
        .collect();
    assert_eq!(numbers, vec![1], "{v}");
    bob.ok(json!({"type": "drag_end", "part": SHELL, "icon": icon}))
        .await;

    // The disk takes writes again: the next commit is stored, with the work.
    s.store.read_only(false).unwrap();
    let kept = in_memory(&s).await;
    let r = ann
        .request(json!({"type": "commit", "message": "disk is back"}))
        .await;
    assert_eq!(r["version"], 2, "{r}");
    drop((ann, bob));
    s.stop().await;

    let (versions, _) = committed_after_restart(&data).await;
    let numbers: Vec<(u64, &str)> = versions.iter().map(|(n, m, _)| (*n, m.as_str())).collect();
    assert_eq!(numbers, vec![(1, "created"), (2, "disk is back")]);
    assert_eq!(versions[1].2["parts"], kept["parts"]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_commits_asked_together_give_consecutive_versions_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let s = start(&data).await;
    let mut ann = s.connect("ann").await;
    let mut cy = s.connect("cy").await;
    let mut bob = s.connect("bob").await;
    let (icon, p) = load_icon(&bob.snapshot);
    bob.ok(json!({"type": "drag_start", "part": SHELL, "icon": icon}))
        .await;
    let first_state = in_memory(&s).await;

    // Ann's commit is being written (stalled); bob drags; then cy commits:
    // her commit queues behind ann's, with bob's drag in it.
    let release = s.store.stall();
    ask(&mut ann, 1, json!({"type": "commit", "message": "first"})).await;
    write_started(&s).await;
    let rev = dragged(&mut bob, icon, p, 4.0, 0).await;
    ask(&mut cy, 1, json!({"type": "commit", "message": "second"})).await;
    dragged(&mut bob, icon, p, 5.0, rev).await;
    drop(release);

    let mut events = Vec::new();
    let a = reply_to(&mut ann, 1, &mut events).await;
    let c = reply_to(&mut cy, 1, &mut events).await;
    assert_eq!(
        (a["version"].clone(), c["version"].clone()),
        (json!(2), json!(3)),
        "{a} {c}"
    );
    // Everyone hears them in that order.
    let e1 = committed(&mut bob).await;
    let e2 = committed(&mut bob).await;
    assert_eq!(
        (&e1["version"]["version"], &e1["version"]["message"]),
        (&json!(2), &json!("first"))
    );
    assert_eq!(
        (&e2["version"]["version"], &e2["version"]["message"]),
        (&json!(3), &json!("second"))
    );
    drop((ann, bob, cy));
    s.stop().await;

    let (versions, _) = committed_after_restart(&data).await;
    let numbers: Vec<(u64, &str)> = versions.iter().map(|(n, m, _)| (*n, m.as_str())).collect();
    assert_eq!(numbers, vec![(1, "created"), (2, "first"), (3, "second")]);
    assert_eq!(versions[1].2["parts"], first_state["parts"]);
    // Bob's first drag came after ann's commit and before cy's.
    assert_ne!(
        parts::icons(&versions[2].2, SHELL),
        parts::icons(&first_state, SHELL)
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_comment_being_written_holds_up_no_drag_and_is_answered_once_durable() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let s = start(&data).await;
    let mut bob = s.connect("bob").await;
    let mut customer =
        Client::connect(s.addr, s.design.id, &s.design.tokens.viewer, "customer").await;
    let (icon, p) = load_icon(&bob.snapshot);
    bob.ok(json!({"type": "drag_start", "part": SHELL, "icon": icon}))
        .await;

    // The disk stalls; the customer comments; the comment's write waits.
    let release = s.store.stall();
    ask(
        &mut customer,
        1,
        json!({"type": "add_comment", "part": SHELL, "anchor": {"u": 0.4, "v": 0.6}, "text": "Softer here?"}),
    )
    .await;
    write_started(&s).await;
    // A second request queues behind it and is checked in its turn.
    ask(
        &mut customer,
        2,
        json!({"type": "reply_comment", "comment": 1, "text": "and the rim"}),
    )
    .await;

    // Meanwhile bob drags and gets the frame of every drag.
    let mut rev = 0;
    for k in 1..=5 {
        rev = dragged(&mut bob, icon, p, k as f64, rev).await;
    }
    // Nobody has heard of the comment: it is not durable yet.
    for v in texts_so_far(&mut customer) {
        assert!(
            v["req"] != json!(1) && v["req"] != json!(2),
            "answered before durable: {v}"
        );
        assert_ne!(v["type"], "comment_added", "{v}");
    }
    for v in texts_so_far(&mut bob) {
        assert_ne!(v["type"], "comment_added", "{v}");
    }

    // The disk is back: the comment lands, then its reply, in that order.
    drop(release);
    let mut events = Vec::new();
    let first = reply_to(&mut customer, 1, &mut events).await;
    assert_eq!(first["type"], "ack", "{first}");
    let id = first["comment"]
        .as_u64()
        .expect("the ack names the comment");
    let second = reply_to(&mut customer, 2, &mut events).await;
    assert_eq!(second["type"], "ack", "{second}");
    let added = bob.wait_for("comment_added").await;
    assert_eq!(added["comment"]["id"], json!(id), "{added}");
    assert_eq!(added["comment"]["text"], "Softer here?");
    let changed = bob.wait_for("comment_changed").await;
    assert_eq!(
        changed["comment"]["replies"][0]["text"], "and the rim",
        "{changed}"
    );
    drop(bob);
    drop(customer);
    s.stop().await;
}
