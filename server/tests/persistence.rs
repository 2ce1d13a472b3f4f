//! Persistence across process lifetimes, with the real binary as a child
//! process: commit, SIGTERM, restart on the same data directory → designs,
//! versions and the (uncommitted) working state are back; kill -9 in the
//! middle of a session → every committed version survives.

mod common;

use common::parts::{self, load_icon};

use common::ChildServer;
use common::http::get;
use common::ws::Client;
use serde_json::json;
use std::time::Duration;

async fn drag(c: &mut Client, icon: u64, to: [f64; 3]) {
    c.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    c.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": to}))
        .await;
    c.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn commit_stop_restart_brings_everything_back() {
    let data = common::data_dir("restart");
    let server = ChildServer::start(&data, 1);
    let d = server.designs[0].clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    let (icon, p) = load_icon(&c.snapshot);
    drag(&mut c, icon, [p[0], p[1], p[2] + 8.0]).await;
    c.ok(json!({"type": "commit", "message": "raised the palm rest"}))
        .await;
    let committed = get(server.addr, "/api/designs/1", Some(&d.editor))
        .await
        .json();
    // Uncommitted work after the commit: a second drag and a new icon.
    drag(&mut c, icon, [p[0], p[1], p[2] + 13.0]).await;
    c.ok(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.4, "v": 0.7}, "role": {"kind": "position"}}})).await;
    let working = get(server.addr, "/api/designs/1", Some(&d.editor))
        .await
        .json();
    assert_ne!(working["design"], committed["design"]);
    drop(c);
    let status = server.terminate();
    assert!(
        status.success(),
        "SIGTERM must end the server cleanly: {status:?}"
    );

    let server = ChildServer::start(&data, 1);
    let d2 = server.designs[0].clone();
    assert_eq!((d2.id, d2.name.as_str()), (d.id, "demo"));
    assert_eq!(
        (d2.editor.as_str(), d2.viewer.as_str(), d2.device.as_str()),
        (d.editor.as_str(), d.viewer.as_str(), d.device.as_str())
    );
    // The working state, uncommitted edits included.
    let back = get(server.addr, "/api/designs/1", Some(&d.viewer))
        .await
        .json();
    assert_eq!(back["design"], working["design"]);
    // The versions.
    let v = get(server.addr, "/api/designs/1/versions", Some(&d.viewer))
        .await
        .json();
    let versions = v["versions"].as_array().unwrap();
    assert_eq!(versions.len(), 2);
    assert_eq!(versions[1]["message"], "raised the palm rest");
    assert_eq!(versions[1]["author"], "ann");
    let v2 = get(server.addr, "/api/designs/1/versions/2", Some(&d.viewer))
        .await
        .json();
    assert_eq!(v2["design"], committed["design"]);
    // A client joining sees the same, and revert goes back to the commit.
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    assert_eq!(c.snapshot["versions"].as_array().unwrap().len(), 2);
    c.ok(json!({"type": "revert"})).await;
    let reverted = get(server.addr, "/api/designs/1", Some(&d.viewer))
        .await
        .json();
    assert_eq!(
        parts::icons(&reverted["design"], 1),
        parts::icons(&committed["design"], 1)
    );
    assert_eq!(reverted["design"], committed["design"]);
    drop(c);
    assert!(server.terminate().success());
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn kill_9_keeps_every_committed_version() {
    let data = common::data_dir("kill9");
    let server = ChildServer::start(&data, 1);
    let d = server.designs[0].clone();
    let mut c = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    let (icon, p) = load_icon(&c.snapshot);
    let mut states = Vec::new();
    for k in 1..=3 {
        drag(&mut c, icon, [p[0], p[1], p[2] + 4.0 * k as f64]).await;
        c.ok(json!({"type": "commit", "message": format!("step {k}")}))
            .await;
        states.push(
            get(server.addr, "/api/designs/1", Some(&d.editor))
                .await
                .json(),
        );
    }
    // Mid-session: a drag in flight, then SIGKILL right after the last ack.
    c.send(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    c.send(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 30.0]}))
        .await;
    c.ok(json!({"type": "commit", "message": "step 4"})).await;
    server.kill9();
    drop(c);

    let server = ChildServer::start(&data, 1);
    let v = get(server.addr, "/api/designs/1/versions", Some(&d.viewer))
        .await
        .json();
    let messages: Vec<&str> = v["versions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["message"].as_str().unwrap())
        .collect();
    assert_eq!(
        messages,
        vec!["created", "step 1", "step 2", "step 3", "step 4"]
    );
    for (k, s) in states.iter().enumerate() {
        let got = get(
            server.addr,
            &format!("/api/designs/1/versions/{}", k + 2),
            Some(&d.viewer),
        )
        .await
        .json();
        assert_eq!(got["design"], s["design"], "version {}", k + 2);
    }
    // The last commit carries the dragged shape.
    let last = get(server.addr, "/api/designs/1/versions/5", Some(&d.viewer))
        .await
        .json();
    assert_ne!(
        parts::surface(&last["design"], 1),
        parts::surface(&states[2]["design"], 1)
    );
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert!(server.terminate().success());
    let _ = std::fs::remove_dir_all(&data);
}
