//! A drag whose constraints contradict each other (two position icons at
//! one point of the demo's shell, one dragged away from the other) gets the
//! least-squares answer and an `icon_feedback` that says so in `warning`; a
//! drag that meets every constraint carries none.

mod common;

use common::ws::Client;
use common::{TestServer, data_dir};
use serde_json::{Value, json};

async fn feedback(c: &mut Client, icon: u64, xyz: [f64; 3]) -> Value {
    c.send(json!({"type": "drag", "part": 1, "icon": icon, "xyz": xyz}))
        .await;
    loop {
        let f = c.wait_for("icon_feedback").await;
        if f["icon"] == icon && f["requested"] == json!(xyz) {
            return f;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn contradictory_constraints_come_back_as_a_warning() {
    let server = TestServer::start(data_dir("solve-warning")).await;
    let mut ed = Client::connect(server.addr, 1, &server.demo().editor, "ann").await;
    let mut ids = Vec::new();
    for _ in 0..2 {
        let r = ed
            .request(json!({"type": "create_icon", "part": 1, "spec": {
                "anchor": {"kind": "point", "u": 0.45, "v": 0.7}, "role": {"kind": "position"}}}))
            .await;
        ids.push(r["icon"].as_u64().unwrap_or_else(|| panic!("{r}")));
    }
    // Where the icons are: from the stored document.
    let doc = common::http::get(server.addr, "/api/designs/1", Some(&server.demo().editor))
        .await
        .json();
    let icon = common::parts::icons(&doc["design"], 1)
        .iter()
        .find(|i| i["id"] == ids[0])
        .unwrap();
    let p: [f64; 3] = serde_json::from_value(icon["xyz"].clone()).unwrap();

    // The load alone: every constraint met, no warning.
    let load = common::parts::load_icon(&ed.snapshot).0;
    let lp = common::parts::load_icon(&ed.snapshot).1;
    ed.ok(json!({"type": "drag_start", "part": 1, "icon": load}))
        .await;
    let f = feedback(&mut ed, load, [lp[0], lp[1], lp[2] + 3.0]).await;
    assert!(f.get("warning").is_none(), "{f}");
    ed.ok(json!({"type": "drag_end", "part": 1, "icon": load}))
        .await;

    // One of the two pins dragged 5 mm up while the other holds the point.
    ed.ok(json!({"type": "drag_start", "part": 1, "icon": ids[0]}))
        .await;
    let f = feedback(&mut ed, ids[0], [p[0], p[1], p[2] + 5.0]).await;
    let w = f["warning"]
        .as_str()
        .unwrap_or_else(|| panic!("no warning: {f}"));
    assert!(w.contains("contradict"), "{w}");
    // The compromise: the icon is neither where it was asked to go nor held.
    let actual: [f64; 3] = serde_json::from_value(f["actual"].clone()).unwrap();
    assert!(
        actual[2] - p[2] > 0.5 && p[2] + 5.0 - actual[2] > 0.5,
        "{f}"
    );
    ed.ok(json!({"type": "drag_end", "part": 1, "icon": ids[0]}))
        .await;
    server.stop().await;
}
