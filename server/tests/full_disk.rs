//! A data directory that fills up during a session (a test-only size cap on
//! the database, SQLite's `max_page_count`, from the `fault-injection`
//! feature: writes past it fail with `SQLITE_FULL` as on a full disk), and
//! one that turns read-only (SQLite's `query_only`: writes fail with
//! `SQLITE_READONLY` as on a disk remounted read-only). Commits and new
//! designs get the `storage` code and change nothing, edits go on in memory,
//! the working state is written again by itself once the disk is back,
//! commits succeed again, and nothing acked is lost across a restart.

mod common;

use common::parts::{self, load_icon};

use common::http::get;
use common::store_server::StoreServer;
use common::ws::Client;
use serde_json::{Value, json};
use std::path::Path;
use std::time::Duration;
use vsculpt_server::design::DesignDoc;
use vsculpt_server::store::{DesignRecord, Store};

async fn start(data: &Path) -> StoreServer {
    StoreServer::start(data, Duration::from_millis(100)).await
}

async fn drag(c: &mut Client, icon: u64, to: [f64; 3]) {
    c.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    c.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": to}))
        .await;
    c.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
}

/// The working state as stored.
fn stored(store: &Store, d: &DesignRecord) -> Value {
    let bytes = store.working(d.id).unwrap().unwrap();
    serde_json::to_value(DesignDoc::from_bytes(&bytes).unwrap()).unwrap()
}

/// While the disk refuses writes, the work done in memory is not stored
/// (after giving the writer time to try and fail).
async fn work_is_only_in_memory(store: &Store, d: &DesignRecord, in_memory: &Value) {
    tokio::time::sleep(Duration::from_millis(400)).await;
    assert_ne!(
        parts::icons(&stored(store, d), 1),
        parts::icons(&in_memory["design"], 1)
    );
}

/// A running server on `data`, its editor `ann` and what it has acked so far.
struct Session {
    server: StoreServer,
    ann: Client,
    acked: Vec<String>,
}

/// Once the disk takes writes again: the working state kept in memory is
/// written by itself, a commit is acked, and after a restart every acked
/// version (and nothing refused) and the in-memory design are there.
async fn recovers(data: &Path, store: &Store, d: &DesignRecord, s: Session, in_memory: &Value) {
    let Session {
        server,
        mut ann,
        mut acked,
    } = s;
    let mut saved = false;
    for _ in 0..400 {
        if parts::icons(&stored(store, d), 1) == parts::icons(&in_memory["design"], 1) {
            saved = true;
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    assert!(
        saved,
        "the working state was never written after the disk took writes again"
    );
    ann.ok(json!({"type": "commit", "message": "disk is back"}))
        .await;
    acked.push("disk is back".into());
    drop(ann);
    server.stop().await;

    let server = start(data).await;
    let addr = server.addr;
    let v = get(addr, "/api/designs/1/versions", Some(&d.tokens.viewer))
        .await
        .json();
    let msgs: Vec<&str> = v["versions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["message"].as_str().unwrap())
        .collect();
    assert_eq!(msgs, acked);
    let now = get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    assert_eq!(now["design"]["parts"], in_memory["design"]["parts"]);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_disk_refuses_commits_keeps_the_work_and_recovers() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(&data).await;
    let (addr, store, d) = (server.addr, server.store.clone(), server.design.clone());
    let admin = server.admin.clone();
    let mut ann = Client::connect(addr, d.id, &d.tokens.editor, "ann").await;
    let (icon, p) = load_icon(&ann.snapshot);

    // Cap the database where it is and commit until the space runs out.
    store
        .limit_pages(Some(store.page_count().unwrap()))
        .unwrap();
    let mut acked = vec!["created".to_string()];
    let mut refused = None;
    for k in 1..=40 {
        drag(&mut ann, icon, [p[0], p[1], p[2] + k as f64]).await;
        let msg = format!("step {k}");
        let r = ann.request(json!({"type": "commit", "message": msg})).await;
        if r["type"] == "ack" {
            acked.push(msg);
        } else {
            refused = Some(r);
            break;
        }
    }
    let refused = refused.expect("the capped database never filled up");
    assert_eq!(refused["code"], "storage", "{refused}");
    assert!(
        refused["message"].as_str().unwrap().contains("full"),
        "{refused}"
    );

    // Work goes on in memory: the working state grows (new icons), its
    // writes fail and are retried; commits keep being refused.
    for k in 0..12 {
        let u = 0.1 + 0.06 * k as f64;
        ann.ok(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": u, "v": 0.35}, "role": {"kind": "position"}}}))
            .await;
    }
    let again = ann
        .request(json!({"type": "commit", "message": "refused"}))
        .await;
    assert_eq!(again["code"], "storage", "{again}");
    let in_memory = get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    assert_eq!(parts::icons(&in_memory["design"], 1).len(), 16);
    work_is_only_in_memory(&store, &d, &in_memory).await;
    let m = get(addr, "/metrics", Some(&admin)).await.text();
    assert!(!m.contains("vsculpt_store_write_errors_total 0\n"), "{m}");

    // Space comes back.
    store.limit_pages(None).unwrap();
    let session = Session { server, ann, acked };
    recovers(&data, &store, &d, session, &in_memory).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_read_only_disk_refuses_every_write_keeps_the_work_and_recovers() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(&data).await;
    let (addr, store, d) = (server.addr, server.store.clone(), server.design.clone());
    let mut ann = Client::connect(addr, d.id, &d.tokens.editor, "ann").await;
    let (icon, p) = load_icon(&ann.snapshot);
    ann.ok(json!({"type": "commit", "message": "before"})).await;

    store.read_only(true).unwrap();
    // A commit is refused with `storage`, saying why.
    drag(&mut ann, icon, [p[0], p[1], p[2] + 5.0]).await;
    let r = ann
        .request(json!({"type": "commit", "message": "refused"}))
        .await;
    assert_eq!(r["code"], "storage", "{r}");
    assert!(r["message"].as_str().unwrap().contains("readonly"), "{r}");
    // So is a new design (the other write path of a client), and nothing
    // is created.
    ann.send(json!({"type": "create_design", "req": 77, "name": "nope"}))
        .await;
    let r = loop {
        let v = ann.wait_for("error").await;
        if v["req"] == 77 {
            break v;
        }
    };
    assert_eq!(r["code"], "storage", "{r}");
    let list = get(addr, "/api/designs", Some(&d.tokens.editor))
        .await
        .json();
    assert_eq!(list["designs"].as_array().unwrap().len(), 1, "{list}");
    // Edits go on in memory; the working state cannot be written.
    for k in 0..3 {
        let u = 0.2 + 0.2 * k as f64;
        ann.ok(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": u, "v": 0.2}, "role": {"kind": "position"}}}))
            .await;
    }
    let in_memory = get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    work_is_only_in_memory(&store, &d, &in_memory).await;

    // The disk is writable again.
    store.read_only(false).unwrap();
    let session = Session {
        server,
        ann,
        acked: vec!["created".into(), "before".into()],
    };
    recovers(&data, &store, &d, session, &in_memory).await;
}
