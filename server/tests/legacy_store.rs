//! A store written before parts (document format 1, by the server at commit
//! 6d6942d: see tests/fixtures/v1-store/README.md) opens with today's server:
//! each old design is a one-part design with exactly the stored shape, icons
//! (same ids), material and versions; restoring an old version works; what
//! the new server writes back reads again after a restart.

mod common;

use common::http::get;
use common::ws::{Client, Got};
use common::{TestServer, data_dir};
use serde_json::{Value, json};

const FIXTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/v1-store/vsculpt.db"
);

/// The format-1 documents in the fixture, read with SQLite directly (not
/// through the server): the working state and each version.
fn v1_docs() -> (Value, Vec<(u64, Value)>) {
    let db =
        rusqlite::Connection::open_with_flags(FIXTURE, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .unwrap();
    let working: Vec<u8> = db
        .query_row(
            "SELECT snapshot FROM working WHERE design_id = 1",
            [],
            |r| r.get(0),
        )
        .unwrap();
    let mut stmt = db
        .prepare("SELECT number, snapshot FROM versions WHERE design_id = 1 ORDER BY number")
        .unwrap();
    let versions = stmt
        .query_map([], |r| {
            Ok((r.get::<_, i64>(0)? as u64, r.get::<_, Vec<u8>>(1)?))
        })
        .unwrap()
        .map(|v| {
            let (n, b) = v.unwrap();
            (n, serde_json::from_slice(&b).unwrap())
        })
        .collect();
    (serde_json::from_slice(&working).unwrap(), versions)
}

/// Checks that stored document `new` (format 2) is `old` (format 1) as one
/// surface part: same surface (every knot and control point bit for bit),
/// material, icons.
fn same_as_v1(new: &Value, old: &Value) {
    assert_eq!(old["format"], 1);
    assert_eq!(new["format"], 2);
    assert_eq!(new["name"], old["name"]);
    let parts = new["parts"].as_array().unwrap();
    assert_eq!(parts.len(), 1, "{new}");
    let body = &parts[0]["body"];
    assert_eq!(body["kind"], "surface");
    assert_eq!(body["surface"], old["surface"]);
    assert_eq!(body["material"], old["material"]);
    assert_eq!(body["icons"], old["icons"]);
    assert_eq!(new["next_icon"], old["next_icon"]);
    assert!(new["relations"].as_array().unwrap().is_empty());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_store_from_before_parts_opens_as_one_part_designs() {
    let (working, versions) = v1_docs();
    assert_eq!(versions.len(), 2, "the fixture has versions 1 and 2");
    // The working state differs from the last commit (a material and an
    // icon were changed after it), so both are checked.
    assert_ne!(working["material"], versions[1].1["material"]);

    let data = data_dir("legacy-store");
    std::fs::copy(FIXTURE, data.join("vsculpt.db")).unwrap();
    let server = TestServer::start(data.clone()).await;
    let addr = server.addr;
    assert_eq!(server.designs.len(), 1, "no demo is added to a used store");
    let token = server.demo().editor.clone();

    // The working state.
    let got = get(addr, "/api/designs/1", Some(&token)).await.json();
    same_as_v1(&got["design"], &working);
    // Every version.
    for (n, old) in &versions {
        let got = get(addr, &format!("/api/designs/1/versions/{n}"), Some(&token))
            .await
            .json();
        same_as_v1(&got["design"], old);
    }
    // A client sees one part with the old icons and the old shape.
    let mut ed = Client::connect(addr, 1, &token, "ann").await;
    let part = &ed.snapshot["parts"][0];
    assert_eq!(part["name"], "surface");
    let ids: Vec<u64> = part["icons"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["id"].as_u64().unwrap())
        .collect();
    assert_eq!(ids, vec![1, 2, 3, 4, 5, 6]);
    assert_eq!(
        part["shape"]["surface"]["points"],
        working["surface"]["points"]
    );
    // Restoring the old version 2 works and is what version 2 held.
    ed.send(json!({"type": "restore_version", "req": 1, "version": 2}))
        .await;
    let (mut acked, mut snap) = (false, None);
    while !(acked && snap.is_some()) {
        match ed.next().await {
            Got::Text(v) if v["type"] == "ack" && v["req"] == 1 => acked = true,
            Got::Text(v) if v["type"] == "error" => panic!("{v}"),
            Got::Text(v) if v["type"] == "snapshot" => snap = Some(v),
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
    let snap = snap.unwrap();
    assert_eq!(
        snap["parts"][0]["shape"]["surface"]["points"],
        versions[1].1["surface"]["points"]
    );
    // Old icons still drag (the load, on part 1), and a new commit is
    // written in the new format and reads back after a restart.
    let load = snap["parts"][0]["icons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["role"]["kind"] == "load")
        .unwrap()["id"]
        .as_u64()
        .unwrap();
    ed.ok(json!({"type": "drag_start", "part": 1, "icon": load}))
        .await;
    ed.ok(json!({"type": "drag", "part": 1, "icon": load, "xyz": [10.0, 0.0, 60.0]}))
        .await;
    ed.ok(json!({"type": "drag_end", "part": 1, "icon": load}))
        .await;
    let r = ed
        .request(json!({"type": "commit", "message": "after the upgrade"}))
        .await;
    assert_eq!(r["version"], 3, "{r}");
    let committed = get(addr, "/api/designs/1/versions/3", Some(&token))
        .await
        .json()["design"]
        .clone();
    assert_eq!(committed["format"], 2);
    drop(ed);
    server.stop().await;
    let server = TestServer::start(data).await;
    let again = get(server.addr, "/api/designs/1", Some(&token))
        .await
        .json()["design"]
        .clone();
    assert_eq!(again["parts"], committed["parts"]);
    let v1 = get(server.addr, "/api/designs/1/versions/1", Some(&token))
        .await
        .json();
    same_as_v1(&v1["design"], &versions[0].1);
    server.stop().await;
}
