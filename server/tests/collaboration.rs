//! Live collaboration on the real server (in-process, ephemeral port,
//! tokio-tungstenite clients): two editors and a viewer see the same state,
//! a drag by one editor reaches the others as geometry frames (per part:
//! the demo's shell and the side panels joined to it), presence
//! shows who holds what, events arrive in order at everyone, and a viewer's
//! edits are refused without changing anything.

mod common;

use common::TestServer;
use common::http;
use common::parts::{self, SHELL, SIDES};
use common::ws::Client;
use serde_json::{Value, json};

fn icon_of_role(snapshot: &Value, kind: &str) -> Value {
    parts::icon_of_role(snapshot, SHELL, kind)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_editors_and_a_viewer_share_state_and_drags() {
    let server = TestServer::start(common::data_dir("collab")).await;
    let d = server.demo().clone();
    assert_eq!(d.name, "demo");
    let mut a = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    let mut b = Client::connect(server.addr, d.id, &d.editor, "bob").await;
    let mut v = Client::connect(server.addr, d.id, &d.viewer, "vic").await;
    assert_eq!(a.welcome["access"], "editor");
    assert_eq!(b.welcome["access"], "editor");
    assert_eq!(v.welcome["access"], "viewer");

    // The same state everywhere: every part (shape, material, icons),
    // relations, versions.
    for c in [&b, &v] {
        for key in ["parts", "relations", "versions"] {
            assert_eq!(c.snapshot[key], a.snapshot[key], "{key} differs");
        }
    }
    assert_eq!(parts::part_ids(&a.snapshot), vec![1, 2, 3, 4, 5]);
    assert_eq!(parts::surface(&a.snapshot, SHELL)["nu"], 16);
    assert_eq!(parts::surface(&a.snapshot, SHELL)["nv"], 12);
    assert_eq!(parts::icons(&a.snapshot, SHELL).len(), 4);

    // Every client gets the current geometry of every part on joining.
    let fa = a.join_frames().await;
    let fb = b.join_frames().await;
    let fv = v.join_frames().await;
    assert_eq!(fa.len(), 4);
    for k in 0..fa.len() {
        assert_eq!(fa[k].part, fb[k].part);
        assert_eq!(fa[k].points, fb[k].points);
        assert_eq!(fa[k].points, fv[k].points);
    }
    assert_eq!((fa[0].part, fa[0].nu, fa[0].nv), (SHELL, 16, 12));
    for f in &fa {
        let shape = &parts::part(&a.snapshot, f.part)["shape"];
        let snap_points = shape[shape["kind"].as_str().unwrap()]["points"]
            .as_array()
            .unwrap();
        assert_eq!(f.points.len(), snap_points.len(), "part {}", f.part);
        for (k, p) in f.points.iter().enumerate() {
            for c in 0..3 {
                assert_eq!(p[c], snap_points[k][c].as_f64().unwrap() as f32);
            }
        }
    }
    let (fb, fv) = (&fb[0], &fv[0]);

    // Presence: the viewer (the last to join) sees three clients.
    let names: Vec<&str> = v.snapshot["presence"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, vec!["ann", "bob", "vic"]);

    // Ann drags the load icon up by 10.
    let load = icon_of_role(&a.snapshot, "load");
    let id = load["id"].as_u64().unwrap();
    let start: Vec<f64> = load["xyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    a.ok(json!({"type": "drag_start", "part": 1, "icon": id}))
        .await;
    let held = loop {
        let p = b.wait_for("presence_changed").await;
        let c = &p["client"];
        if c["name"] == "ann" && c["holding"] == json!(id) {
            break c.clone();
        }
    };
    assert_eq!(held["access"], "editor");
    for step in 1..=5 {
        let z = start[2] + 2.0 * step as f64;
        a.send(json!({"type": "drag", "part": 1, "icon": id, "xyz": [start[0], start[1], z]}))
            .await;
    }
    let icon_z = |f: &vsculpt_protocol::GeometryFrame| {
        f.icons.iter().find(|i| i.id == id).unwrap().xyz[2] as f64
    };
    let side_points: Vec<_> = SIDES
        .iter()
        .map(|s| fa.iter().find(|f| f.part == *s).unwrap().points.clone())
        .collect();
    for (c, f0) in [(&mut b, fb), (&mut v, fv)] {
        // Frames until the drag settles (coalescing may skip some), per part.
        let mut last = c.frame_of_after(SHELL, f0.revision).await;
        let mut sides = vec![None; SIDES.len()];
        while let Ok(f) =
            tokio::time::timeout(std::time::Duration::from_millis(500), c.frame()).await
        {
            if f.part == SHELL {
                last = f;
            } else if let Some(k) = SIDES.iter().position(|s| *s == f.part) {
                sides[k] = Some(f);
            }
        }
        // The side panels are joined G1 to the shell: pulling the shell
        // moves them too, and their frames come too, flagged as a drag.
        for (k, side) in sides.iter().enumerate() {
            let side = side
                .as_ref()
                .unwrap_or_else(|| panic!("no frame of side panel {}", SIDES[k]));
            assert_ne!(
                side.points, side_points[k],
                "side {} did not move",
                SIDES[k]
            );
            assert_eq!(
                side.flags & vsculpt_protocol::frame::FLAG_DRAG,
                vsculpt_protocol::frame::FLAG_DRAG
            );
        }
        // The load pulls through the spring model: the icon follows the
        // pointer with a ratio the kernel keeps within [0.8, 1.2].
        let rise = icon_z(&last) - start[2];
        assert!(rise > 0.5 * 10.0 && rise < 1.3 * 10.0, "rise {rise}");
        assert_ne!(
            last.points, f0.points,
            "the drag must change the control points"
        );
        assert_eq!(
            last.flags & vsculpt_protocol::frame::FLAG_DRAG,
            vsculpt_protocol::frame::FLAG_DRAG
        );
    }
    // Ann hears where the icon went (for the spring model).
    let fb_msg = a.wait_for("icon_feedback").await;
    assert_eq!(fb_msg["icon"], json!(id));
    assert_eq!(fb_msg["part"], json!(SHELL));

    // Bob cannot grab what Ann holds.
    b.refused(
        json!({"type": "drag_start", "part": 1, "icon": id}),
        "conflict",
    )
    .await;
    a.ok(json!({"type": "drag_end", "part": 1, "icon": id}))
        .await;

    // The viewer can change nothing.
    let before = http::get(
        server.addr,
        &format!("/api/designs/{}", d.id),
        Some(&d.viewer),
    )
    .await
    .json();
    v.refused(
        json!({"type": "move_icon", "part": 1, "icon": 1, "xyz": [0.0, 0.0, 0.0]}),
        "forbidden",
    )
    .await;
    v.refused(
        json!({"type": "drag", "part": 1, "icon": id, "xyz": [0.0, 0.0, 50.0]}),
        "forbidden",
    )
    .await;
    v.refused(
        json!({"type": "drag_start", "part": 1, "icon": id}),
        "forbidden",
    )
    .await;
    v.refused(
        json!({"type": "delete_icon", "part": 1, "icon": 1}),
        "forbidden",
    )
    .await;
    v.refused(json!({"type": "commit", "message": "mine"}), "forbidden")
        .await;
    v.refused(json!({"type": "undo"}), "forbidden").await;
    v.refused(json!({"type": "set_material", "part": 1, "material": {"alpha11": 1.0, "alpha12": 0.0, "alpha22": 1.0, "beta11": 1.0, "beta12": 1.0, "beta22": 1.0}}), "forbidden").await;
    v.send(json!({"type": "drag", "part": 1, "icon": id, "xyz": [0.0, 0.0, 80.0]}))
        .await;
    assert_eq!(v.wait_for("error").await["code"], "forbidden");
    let after = http::get(
        server.addr,
        &format!("/api/designs/{}", d.id),
        Some(&d.viewer),
    )
    .await
    .json();
    assert_eq!(before["design"], after["design"]);
    v.ping().await;

    // Bob creates an icon: everyone hears of it, in order, with the commit after.
    let r = b
        .request(json!({"type": "create_icon", "part": 1, "spec": {"anchor": {"kind": "point", "u": 0.5, "v": 0.2}, "role": {"kind": "position"}}}))
        .await;
    assert_eq!(r["type"], "ack");
    b.ok(json!({"type": "commit", "message": "pinned the side"}))
        .await;
    for c in [&mut a, &mut v] {
        let created = c.wait_for("icon_created").await;
        assert_eq!(created["part"], json!(SHELL));
        assert_eq!(
            created["icon"]["anchor"],
            json!({"kind": "point", "u": 0.5, "v": 0.2})
        );
        let committed = c.wait_for("committed").await;
        assert_eq!(committed["version"]["message"], "pinned the side");
        assert_eq!(committed["version"]["author"], "bob");
        assert_eq!(committed["version"]["version"], 2);
    }

    // Undo and redo go to everyone as snapshots.
    a.ok(json!({"type": "undo"})).await;
    let s = v.wait_for("snapshot").await;
    assert_eq!(parts::icons(&s, SHELL).len(), 4);
    a.ok(json!({"type": "redo"})).await;
    let s = v.wait_for("snapshot").await;
    assert_eq!(parts::icons(&s, SHELL).len(), 5);

    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_device_drags_but_cannot_edit_or_commit() {
    let server = TestServer::start(common::data_dir("device")).await;
    let d = server.demo().clone();
    let mut dev = Client::connect(server.addr, d.id, &d.device, "bridge").await;
    assert_eq!(dev.welcome["access"], "device");
    let load = icon_of_role(&dev.snapshot, "load");
    let id = load["id"].as_u64().unwrap();
    dev.ok(json!({"type": "drag_start", "part": 1, "icon": id}))
        .await;
    dev.ok(json!({"type": "drag", "part": 1, "icon": id, "xyz": [0.0, 0.0, 60.0]}))
        .await;
    dev.ok(json!({"type": "drag_end", "part": 1, "icon": id}))
        .await;
    dev.ok(json!({"type": "bind_sensor", "part": 1, "icon": id, "sensor": "right-hand"}))
        .await;
    dev.ok(json!({"type": "device_sample", "sensor": "right-hand", "position": [1.0, 2.0, 3.0], "orientation": [1.0, 0.0, 0.0, 0.0], "time_us": 5})).await;
    dev.ok(json!({"type": "device_status", "device": "glove", "condition": "connected"}))
        .await;
    // The 3D mouse's menu: role and state switches are allowed.
    dev.ok(json!({"type": "set_state", "part": 1, "icon": id, "state": "sleeping"}))
        .await;
    dev.ok(json!({"type": "set_role", "part": 1, "icon": id, "role": {"kind": "load"}}))
        .await;
    dev.ok(json!({"type": "set_state", "part": 1, "icon": id, "state": "passive"}))
        .await;
    dev.ok(json!({"type": "bind_sensor", "part": 1, "icon": id, "sensor": "right-hand"}))
        .await;
    dev.refused(json!({"type": "commit", "message": "x"}), "forbidden")
        .await;
    dev.refused(
        json!({"type": "delete_icon", "part": 1, "icon": 1}),
        "forbidden",
    )
    .await;
    dev.refused(json!({"type": "create_design", "name": "x"}), "forbidden")
        .await;
    let state = http::get(
        server.addr,
        &format!("/api/designs/{}", d.id),
        Some(&d.editor),
    )
    .await
    .json();
    let icon = parts::icon(&state["design"], SHELL, id).clone();
    assert_eq!(icon["sensors"], json!(["right-hand"]));
    // A bound sensor makes the icon driving (paper 003).
    assert_eq!(icon["state"], "driving");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_stops_reading_resyncs_instead_of_queueing() {
    use common::ws::Got;
    let server = TestServer::start(common::data_dir("lag")).await;
    let d = server.demo().clone();
    let mut slow = Client::connect(server.addr, d.id, &d.viewer, "slow").await;
    // Far more events than the event channel holds (256) and than the
    // socket buffers absorb, while the slow client reads nothing: 45
    // editors each send 900 presence updates, within the per-client rate
    // limit's burst (1000), so none is refused.
    let (editors, each) = (45, 900);
    let mut fast = Vec::new();
    for e in 0..editors {
        fast.push(Client::connect(server.addr, d.id, &d.editor, &format!("fast{e}")).await);
    }
    for (e, c) in fast.iter_mut().enumerate() {
        for k in 0..each {
            c.send(json!({"type": "presence", "pointer": [k as f64, e as f64, 0.0]}))
                .await;
        }
    }
    // Each connection's messages reach the design in order: once the last
    // editor's ping is answered, its last presence has been handled.
    fast.last_mut().unwrap().ping().await;
    let n = editors * each;
    let last = format!("fast{}", editors - 1);
    // The slow client now reads: somewhere in its stream there is a fresh
    // snapshot (the resync), and it ends up with the final presence.
    let mut resyncs = 0;
    let mut presences = 0;
    loop {
        match slow.next().await {
            Got::Text(v) if v["type"] == "snapshot" || v["type"] == "presence_changed" => {
                let list = if v["type"] == "snapshot" {
                    resyncs += 1;
                    v["presence"].as_array().unwrap().clone()
                } else {
                    presences += 1;
                    vec![v["client"].clone()]
                };
                let done = list.iter().any(|c| {
                    c["name"] == last.as_str()
                        && c["pointer"] == json!([(each - 1) as f64, (editors - 1) as f64, 0.0])
                });
                if done {
                    break;
                }
            }
            Got::Closed => panic!("the slow client was dropped"),
            _ => {}
        }
    }
    assert!(resyncs >= 1, "no resync after {presences} presence events");
    assert!(presences < n, "every event was queued: {presences}");
    slow.ping().await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn designs_and_versions_over_the_websocket() {
    let server = TestServer::start(common::data_dir("ws-designs")).await;
    let d = server.demo().clone();
    let mut e = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    let mut v = Client::connect(server.addr, d.id, &d.viewer, "vi").await;
    e.send(json!({"type": "list_designs", "req": 1})).await;
    let l = e.wait_for("designs").await;
    assert_eq!(
        l["designs"],
        json!([{"id": d.id, "name": "demo", "versions": 1}])
    );
    e.send(json!({"type": "create_design", "req": 2, "name": "kettle"}))
        .await;
    let c = e.wait_for("design_created").await;
    assert_eq!(c["req"], 2);
    assert_eq!(c["design"]["name"], "kettle");
    assert_eq!(c["tokens"]["editor"].as_str().unwrap().len(), 64);
    let admin = http::get(server.addr, "/api/designs", Some(&server.admin))
        .await
        .json();
    assert_eq!(admin["designs"].as_array().unwrap().len(), 2);
    v.refused(
        json!({"type": "create_design", "name": "mine"}),
        "forbidden",
    )
    .await;
    e.ok(json!({"type": "commit", "message": "first"})).await;
    v.send(json!({"type": "list_versions"})).await;
    let vs = v.wait_for("versions").await;
    let msgs: Vec<&str> = vs["versions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["message"].as_str().unwrap())
        .collect();
    assert_eq!(msgs, vec!["created", "first"]);
    e.ok(json!({"type": "restore_version", "version": 1})).await;
    v.wait_for("snapshot").await;
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn edits_are_solved_by_the_kernel() {
    let server = TestServer::start(common::data_dir("solve")).await;
    let d = server.demo().clone();
    let mut e = Client::connect(server.addr, d.id, &d.editor, "ed").await;
    let pin = icon_of_role(&e.snapshot, "position");
    let id = pin["id"].as_u64().unwrap();
    let p: [f64; 3] = serde_json::from_value(pin["xyz"].clone()).unwrap();
    // Moving a position constraint's target moves the surface through it.
    let to = [p[0], p[1] + 1.0, p[2] + 6.0];
    e.ok(json!({"type": "move_icon", "part": 1, "icon": id, "xyz": to}))
        .await;
    let s = http::get(server.addr, "/api/designs/1", Some(&d.viewer))
        .await
        .json();
    let icon = parts::icon(&s["design"], SHELL, id).clone();
    let xyz: [f64; 3] = serde_json::from_value(icon["xyz"].clone()).unwrap();
    for k in 0..3 {
        assert!((xyz[k] - to[k]).abs() < 1e-6, "{xyz:?} vs {to:?}");
    }
    // Sleeping, it holds nothing; its state round-trips.
    // (No req: the event may overtake an ack, and `ok` would skip it.)
    e.send(json!({"type": "set_state", "part": 1, "icon": id, "state": "sleeping"}))
        .await;
    // Updates arrive in order; the move above updated every icon the
    // solve moved, so look for this icon's new state.
    let mut u = e.wait_for("icon_updated").await;
    while !(u["icon"]["id"] == json!(id) && u["icon"]["state"] == "sleeping") {
        u = e.wait_for("icon_updated").await;
    }
    // Switching role: position → normal (target becomes the current normal).
    e.send(json!({"type": "set_role", "part": 1, "icon": id, "role": {"kind": "normal"}}))
        .await;
    let mut u = e.wait_for("icon_updated").await;
    while !(u["icon"]["id"] == json!(id) && u["icon"]["role"] == json!({"kind": "normal"})) {
        u = e.wait_for("icon_updated").await;
    }
    let n: [f64; 3] = serde_json::from_value(u["icon"]["target"].clone()).unwrap();
    assert!(((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-9);
    // The material change reaches everyone.
    e.send(json!({"type": "set_material", "part": 1, "material": {"alpha11": 0.02, "alpha12": 0.0, "alpha22": 0.02, "beta11": 2.0, "beta12": 1.0, "beta22": 2.0}})).await;
    let m = e.wait_for("material_changed").await;
    assert_eq!(m["part"], json!(SHELL));
    assert_eq!(m["material"]["beta11"], 2.0);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn presence_travels_by_deltas() {
    let server = TestServer::start(common::data_dir("presence-deltas")).await;
    let d = server.demo().clone();
    let mut a = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    // Ann hears of her own arrival first (she subscribed before it).
    let own = a.wait_for("presence_changed").await;
    assert_eq!(own["client"]["client"], json!(a.client_id()));
    // Twenty joins: each reaches ann as one entry, never the whole list.
    let mut others = Vec::new();
    for k in 0..20 {
        let c = Client::connect(server.addr, d.id, &d.viewer, &format!("v{k}")).await;
        let m = a.wait_for("presence_changed").await;
        assert_eq!(m["client"]["client"], json!(c.client_id()), "{m}");
        assert_eq!(m["client"]["name"], format!("v{k}"));
        assert!(m.get("clients").is_none());
        others.push(c);
    }
    // A pointer move: one entry.
    let mut b = others.pop().unwrap();
    b.send(json!({"type": "presence", "pointer": [1.0, 2.0, 3.0]}))
        .await;
    let m = a.wait_for("presence_changed").await;
    assert_eq!(m["client"]["pointer"], json!([1.0, 2.0, 3.0]));
    // A departure: only its id.
    let gone = b.client_id();
    drop(b);
    let m = a.wait_for("presence_left").await;
    assert_eq!(m, json!({"type": "presence_left", "client": gone}));
    // A late joiner still gets the whole list once, in its snapshot.
    let late = Client::connect(server.addr, d.id, &d.viewer, "late").await;
    assert_eq!(
        late.snapshot["presence"].as_array().unwrap().len(),
        1 + 19 + 1
    );
    server.stop().await;
}

/// The reviewer's "follow the designer": an editor's presence carries its
/// view camera to everyone, a late joiner finds it in its snapshot, a
/// pointer-only presence clears it, and a camera that is not one is refused
/// without changing anybody's presence.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_editors_camera_reaches_viewers_through_presence() {
    let server = TestServer::start(common::data_dir("camera")).await;
    let d = server.demo().clone();
    let mut a = Client::connect(server.addr, d.id, &d.editor, "ann").await;
    let mut v = Client::connect(server.addr, d.id, &d.viewer, "vic").await;
    let ann = a.welcome["client_id"].clone();
    let camera = json!({"eye": [310.5, -220.25, 140.0], "target": [12.0, 8.0, -3.5], "fov": 40.0});
    a.ok(json!({"type": "presence", "camera": camera.clone()}))
        .await;
    let seen = loop {
        let p = v.wait_for("presence_changed").await;
        if p["client"]["client"] == ann && p["client"].get("camera").is_some() {
            break p["client"].clone();
        }
    };
    assert_eq!(seen["camera"], camera);
    assert_eq!(seen["access"], "editor");

    // Refused: the eye at the target; ann's camera stays.
    a.refused(
        json!({"type": "presence", "camera": {"eye": [1, 1, 1], "target": [1, 1, 1], "fov": 40}}),
        "out_of_range",
    )
    .await;
    let w = Client::connect(server.addr, d.id, &d.viewer, "wes").await;
    let entry = w.snapshot["presence"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["client"] == ann)
        .unwrap()
        .clone();
    assert_eq!(entry["camera"], camera, "a late joiner sees the camera");

    // A presence without a camera says "none".
    a.ok(json!({"type": "presence", "pointer": [1.0, 2.0, 3.0]}))
        .await;
    let cleared = loop {
        let p = v.wait_for("presence_changed").await;
        if p["client"]["client"] == ann && p["client"].get("pointer").is_some() {
            break p["client"].clone();
        }
    };
    assert!(cleared.get("camera").is_none(), "{cleared}");
}
