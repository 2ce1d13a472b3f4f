//! A slow disk must not stall a drag. The working state is written at most
//! `persist_delay` after a change; that write (with its fsync) takes tens of
//! milliseconds on a real disk and, before this test, ran inside the design's
//! actor, so every drag arriving meanwhile waited for it (the p99 of the
//! editor's own frame was the fsync time). Here the store is stalled
//! outright (a test-only hold on its connection, from the `fault-injection`
//! feature) while a working-state write is due: drags must still be
//! answered, and once the disk is back the newest state is what is stored.

mod common;

use common::parts::load_icon;
use common::store_server::StoreServer;
use common::ws::Client;
use serde_json::{Value, json};
use std::time::Duration;
use vsculpt_server::design::DesignDoc;

/// Long enough that a drag waiting on the stalled store fails the test,
/// short of the test harness's own limits.
const ANSWER_WITHIN: Duration = Duration::from_secs(10);

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn drags_are_answered_while_the_working_state_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = StoreServer::start(&data, Duration::from_millis(50)).await;
    let (addr, store, d) = (server.addr, server.store.clone(), server.design.clone());
    let mut ann = Client::connect(addr, d.id, &d.tokens.editor, "ann").await;
    let (icon, p) = load_icon(&ann.snapshot);
    let stored_doc = || {
        let bytes = store.working(d.id).unwrap().unwrap();
        serde_json::to_value(DesignDoc::from_bytes(&bytes).unwrap()).unwrap()
    };
    let before = stored_doc();

    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    // The disk stalls; the first drag schedules a working-state write, which
    // starts after `persist_delay` and then waits for the disk.
    let release = store.stall();
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 1.0]}))
        .await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    for k in 2..=20 {
        let z = p[2] + k as f64;
        let answered = tokio::time::timeout(
            ANSWER_WITHIN,
            ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], z]})),
        )
        .await;
        assert!(
            answered.is_ok(),
            "drag {k} waited for the stalled working-state write"
        );
    }
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    // The disk is back (REST looks its token up in the store, so it asks
    // only now): the write in flight lands, then the newest state.
    drop(release);
    let in_memory = common::http::get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    let mut stored: Option<Value> = None;
    for _ in 0..400 {
        let now = stored_doc();
        if now["parts"] == in_memory["design"]["parts"] {
            stored = Some(now);
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    let stored = stored.expect("the newest working state was never written");
    // It is the dragged state, not the design as it started.
    assert_ne!(stored["parts"], before["parts"]);
    drop(ann);
    server.stop().await;
}
