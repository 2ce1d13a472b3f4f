//! A drag whose constraints contradict each other (two position icons at
//! one point of the demo's shell, one dragged away from the other) gets the
//! least-squares answer and an `icon_feedback` that says so in `warning`; a
//! drag that meets every constraint carries none. An edit (create_icon,
//! move_icon) that leaves them contradictory is acked with the warning.

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

/// An edit that leaves contradictory constraints (a second position icon
/// at a held point, asked to be 5 mm above it) is applied as the
/// least-squares compromise and its `ack` carries the warning; an edit that
/// meets every constraint (the first icon, holding the shape where it is)
/// has none.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_contradictory_edit_is_acked_with_a_warning() {
    let server = TestServer::start(data_dir("edit-warning")).await;
    let mut ed = Client::connect(server.addr, 1, &server.demo().editor, "ann").await;
    let spec = |target: Option<[f64; 3]>| {
        let mut s = json!({"anchor": {"kind": "point", "u": 0.45, "v": 0.7},
            "role": {"kind": "position"}});
        if let Some(t) = target {
            s["target"] = json!(t);
        }
        json!({"type": "create_icon", "part": 1, "spec": s})
    };
    let r = ed.request(spec(None)).await;
    assert_eq!(r["type"], "ack", "{r}");
    assert!(r.get("warning").is_none(), "{r}");
    let first = r["icon"].as_u64().unwrap();
    let doc = common::http::get(server.addr, "/api/designs/1", Some(&server.demo().editor))
        .await
        .json();
    let p: [f64; 3] =
        serde_json::from_value(common::parts::icon(&doc["design"], 1, first)["xyz"].clone())
            .unwrap();
    let r = ed.request(spec(Some([p[0], p[1], p[2] + 5.0]))).await;
    assert_eq!(r["type"], "ack", "{r}");
    let w = r["warning"]
        .as_str()
        .unwrap_or_else(|| panic!("no warning: {r}"));
    assert!(w.contains("contradict"), "{w}");
    let second = r["icon"].as_u64().unwrap();
    // Moving it back onto the first one's point: met again, no warning.
    let r = ed
        .request(json!({"type": "move_icon", "part": 1, "icon": second, "xyz": p}))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    assert!(r.get("warning").is_none(), "{r}");
    // And away again: the move's ack warns.
    let r = ed
        .request(json!({"type": "move_icon", "part": 1, "icon": second,
            "xyz": [p[0], p[1], p[2] - 4.0]}))
        .await;
    assert!(
        r["warning"]
            .as_str()
            .is_some_and(|w| w.contains("contradict")),
        "{r}"
    );
    server.stop().await;
}
