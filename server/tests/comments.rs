//! Review comments end to end over the WebSocket: a viewer comments (and
//! still cannot edit), every client hears it at once, the pin sits at the
//! surface point S(u, v) (checked against this file's own Cox–de Boor
//! evaluation of the snapshot's surface), rights follow the link a comment
//! was written through, bad comments change nothing, the per-design limit
//! and the rate limit hold, comments stay out of undo, carry the version
//! they were written on, and survive a restart of the real binary.

mod common;

use common::ws::{Client, Got};
use common::{ChildServer, TestServer};
use serde_json::{Value, json};

/// The basis functions of degree `p` at `t` (Cox–de Boor, written here
/// independently of the kernel), clamped knots, t at the domain's end
/// taken from the left.
fn basis(knots: &[f64], p: usize, t: f64) -> Vec<f64> {
    let n = knots.len() - p - 1;
    let end = knots[n];
    let mut b: Vec<f64> = (0..knots.len() - 1)
        .map(|i| {
            let (a, c) = (knots[i], knots[i + 1]);
            if (a <= t && t < c) || (t == end && a < c && c == end) {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    for d in 1..=p {
        for i in 0..knots.len() - 1 - d {
            let l = knots[i + d] - knots[i];
            let r = knots[i + d + 1] - knots[i + 1];
            let left = if l > 0.0 {
                (t - knots[i]) / l * b[i]
            } else {
                0.0
            };
            let right = if r > 0.0 {
                (knots[i + d + 1] - t) / r * b[i + 1]
            } else {
                0.0
            };
            b[i] = left + right;
        }
    }
    b.truncate(n);
    b
}

/// S(u, v) of a snapshot's surface part.
fn eval(part: &Value, u: f64, v: f64) -> [f64; 3] {
    let s = &part["shape"]["surface"];
    let ku: Vec<f64> = serde_json::from_value(s["u"]["knots"].clone()).unwrap();
    let kv: Vec<f64> = serde_json::from_value(s["v"]["knots"].clone()).unwrap();
    let pu = s["u"]["degree"].as_u64().unwrap() as usize;
    let pv = s["v"]["degree"].as_u64().unwrap() as usize;
    let nv = s["nv"].as_u64().unwrap() as usize;
    let pts: Vec<[f64; 3]> = serde_json::from_value(s["points"].clone()).unwrap();
    let (bu, bv) = (basis(&ku, pu, u), basis(&kv, pv, v));
    let mut out = [0.0; 3];
    for (i, a) in bu.iter().enumerate() {
        for (j, b) in bv.iter().enumerate() {
            for k in 0..3 {
                out[k] += a * b * pts[i * nv + j][k];
            }
        }
    }
    out
}

fn part_of_kind<'a>(snapshot: &'a Value, kind: &str) -> &'a Value {
    snapshot["parts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["shape"]["kind"] == kind)
        .unwrap_or_else(|| panic!("no {kind} part"))
}

fn last_version(snapshot: &Value) -> u64 {
    snapshot["versions"]
        .as_array()
        .unwrap()
        .last()
        .map_or(0, |v| v["version"].as_u64().unwrap())
}

/// Everything text `c` receives until a ping barrier answers.
async fn drain(c: &mut Client) -> Vec<Value> {
    c.send(json!({"type": "ping", "req": 999_999})).await;
    let mut out = Vec::new();
    loop {
        match c.next().await {
            Got::Text(v) if v["type"] == "pong" && v["req"] == json!(999_999) => return out,
            Got::Text(v) => out.push(v),
            Got::Closed => panic!("closed"),
            _ => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_viewer_comments_every_client_sees_it_and_the_viewer_still_cannot_edit() {
    let data = common::data_dir("comments-live");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let mut editor = Client::connect(server.addr, d.id, &d.editor, "Ana").await;
    let mut viewer = Client::connect(server.addr, d.id, &d.viewer, "Ben (customer)").await;
    let mut device = Client::connect(server.addr, d.id, &d.device, "bridge").await;
    assert_eq!(viewer.snapshot["comments"], json!([]));
    let shell = part_of_kind(&viewer.snapshot, "surface").clone();
    let part = shell["id"].as_u64().unwrap();
    let version = last_version(&viewer.snapshot);
    let (u, v) = (0.37, 0.61);

    let r = viewer
        .request(
            json!({"type": "add_comment", "part": part, "anchor": {"u": u, "v": v},
                        "text": "Can this be softer?\nThe light breaks here."}),
        )
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let id = r["comment"].as_u64().expect("the ack names the comment");

    // The editor hears it live, pinned at S(u, v).
    let added = editor.wait_for("comment_added").await["comment"].clone();
    assert_eq!(added["id"], json!(id));
    assert_eq!(added["part"], json!(part));
    assert_eq!(added["anchor"]["u"], json!(u));
    assert_eq!(added["anchor"]["v"], json!(v));
    let xyz: [f64; 3] = serde_json::from_value(added["anchor"]["xyz"].clone()).unwrap();
    let want = eval(&shell, u, v);
    for k in 0..3 {
        assert!(
            (xyz[k] - want[k]).abs() < 1e-9 * (1.0 + want[k].abs()),
            "pin {xyz:?} is not S(u, v) = {want:?}"
        );
    }
    assert_eq!(added["author"], "Ben (customer)");
    assert_eq!(added["access"], "viewer");
    assert_eq!(added["version"], json!(version));
    assert_eq!(added["resolved"], json!(false));
    assert_eq!(added["text"], "Can this be softer?\nThe light breaks here.");
    assert!(added["time_ms"].as_u64().unwrap() > 1_600_000_000_000);
    // The device hears it too (the viewer's own copy may come before or
    // after its ack; the late joiner below checks what is kept).
    assert_eq!(device.wait_for("comment_added").await["comment"], added);

    // A viewer still may not edit the geometry.
    let icon = shell["icons"][0]["id"].as_u64().unwrap();
    viewer
        .refused(
            json!({"type": "move_icon", "part": part, "icon": icon, "xyz": [0.0, 0.0, 50.0]}),
            "forbidden",
        )
        .await;
    viewer
        .refused(json!({"type": "commit", "message": "x"}), "forbidden")
        .await;
    // A device may not comment.
    device
        .refused(
            json!({"type": "add_comment", "part": part, "anchor": {"u": 0.5, "v": 0.5}, "text": "hi"}),
            "forbidden",
        )
        .await;

    // The editor replies: the whole thread reaches the viewer.
    let r = editor
        .request(json!({"type": "reply_comment", "comment": id, "text": "Softened it."}))
        .await;
    let reply = r["comment"].as_u64().unwrap();
    let changed = viewer.wait_for("comment_changed").await["comment"].clone();
    assert_eq!(changed["id"], json!(id));
    assert_eq!(changed["replies"][0]["id"], json!(reply));
    assert_eq!(changed["replies"][0]["author"], "Ana");
    assert_eq!(changed["replies"][0]["access"], "editor");

    // Rights: the viewer resolves its own side's comment, not the
    // editor's; it may not delete the editor's reply; the editor may.
    let r = editor
        .request(json!({"type": "add_comment", "part": part, "anchor": {"u": 0.8, "v": 0.2}, "text": "Note to self"}))
        .await;
    let editors = r["comment"].as_u64().unwrap();
    viewer
        .refused(
            json!({"type": "resolve_comment", "comment": editors, "resolved": true}),
            "forbidden",
        )
        .await;
    viewer
        .refused(
            json!({"type": "delete_comment", "comment": reply}),
            "forbidden",
        )
        .await;
    viewer
        .ok(json!({"type": "resolve_comment", "comment": id, "resolved": true}))
        .await;
    // (The editor's own reply's `comment_changed` may still be on its way.)
    let resolved = loop {
        let c = editor.wait_for("comment_changed").await["comment"].clone();
        if c["resolved"] == json!(true) {
            break c;
        }
    };
    assert_eq!(resolved["id"], json!(id));
    assert_eq!(resolved["resolved_by"], "Ben (customer)");
    editor
        .ok(json!({"type": "delete_comment", "comment": editors}))
        .await;
    assert_eq!(
        viewer.wait_for("comment_deleted").await["comment"],
        json!(editors)
    );

    // A joiner's snapshot has the thread as it is now.
    let late = Client::connect(server.addr, d.id, &d.viewer, "late").await;
    let comments = late.snapshot["comments"].as_array().unwrap();
    assert_eq!(comments.len(), 1);
    assert_eq!(comments[0]["id"], json!(id));
    assert_eq!(comments[0]["resolved"], json!(true));
    assert_eq!(comments[0]["replies"][0]["text"], "Softened it.");
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_comments_get_a_clear_error_and_change_nothing() {
    let data = common::data_dir("comments-bad");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let mut viewer = Client::connect(server.addr, d.id, &d.viewer, "Ben").await;
    let mut other = Client::connect(server.addr, d.id, &d.editor, "Ana").await;
    let surface = part_of_kind(&viewer.snapshot, "surface")["id"]
        .as_u64()
        .unwrap();
    let curve = part_of_kind(&viewer.snapshot, "curve")["id"]
        .as_u64()
        .unwrap();
    let add = |part: u64, anchor: Value, text: &str| json!({"type": "add_comment", "part": part, "anchor": anchor, "text": text});
    let cases = [
        (add(999, json!({"u": 0.5, "v": 0.5}), "x"), "unknown_part"),
        (
            add(surface, json!({"u": 1.5, "v": 0.5}), "x"),
            "out_of_domain",
        ),
        (
            add(surface, json!({"u": 0.5, "v": -0.1}), "x"),
            "out_of_domain",
        ),
        (add(curve, json!({"u": 0.5, "v": 0.5}), "x"), "unsupported"),
        (
            add(surface, json!({"u": 0.5, "v": 0.5}), ""),
            "out_of_range",
        ),
        (
            add(surface, json!({"u": 0.5, "v": 0.5}), "   "),
            "out_of_range",
        ),
        (
            add(surface, json!({"u": 0.5, "v": 0.5}), &"x".repeat(4097)),
            "too_large",
        ),
        (add(surface, json!({"u": 0.5}), "x"), "out_of_range"),
        (
            add(surface, json!({"xyz": [0.0, 1e10, 0.0]}), "x"),
            "out_of_range",
        ),
        (add(surface, json!({}), "x"), "out_of_range"),
        (
            json!({"type": "reply_comment", "comment": 12345, "text": "x"}),
            "out_of_range",
        ),
        (
            json!({"type": "resolve_comment", "comment": 12345, "resolved": true}),
            "out_of_range",
        ),
        (
            json!({"type": "delete_comment", "comment": 12345}),
            "out_of_range",
        ),
    ];
    for (msg, code) in cases {
        viewer.refused(msg, code).await;
    }
    // Nobody heard of a comment, and a joiner sees none.
    let heard = drain(&mut other).await;
    assert!(
        heard
            .iter()
            .all(|m| !m["type"].as_str().unwrap().starts_with("comment")),
        "{heard:?}"
    );
    let late = Client::connect(server.addr, d.id, &d.viewer, "late").await;
    assert_eq!(late.snapshot["comments"], json!([]));
    // An xyz anchor on a curve part is fine and kept as given.
    let r = viewer
        .request(add(curve, json!({"xyz": [1.5, -2.0, 3.25]}), "lower?"))
        .await;
    assert_eq!(r["type"], "ack", "{r}");
    let c = other.wait_for("comment_added").await["comment"].clone();
    assert_eq!(c["anchor"], json!({"xyz": [1.5, -2.0, 3.25]}));
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_text_is_edited_by_its_authors_side_or_an_editor_and_the_comments_are_listed_over_http() {
    let data = common::data_dir("comments-edit");
    let server = TestServer::start(data.clone()).await;
    let d = server.demo().clone();
    let mut editor = Client::connect(server.addr, d.id, &d.editor, "Ana").await;
    let mut viewer = Client::connect(server.addr, d.id, &d.viewer, "Ben").await;
    let mut device = Client::connect(server.addr, d.id, &d.device, "bridge").await;
    let part = part_of_kind(&viewer.snapshot, "surface")["id"]
        .as_u64()
        .unwrap();
    let r = viewer
        .request(json!({"type": "add_comment", "part": part, "anchor": {"u": 0.3, "v": 0.4}, "text": "Softer here?"}))
        .await;
    let theirs = r["comment"].as_u64().unwrap();
    let added = editor.wait_for("comment_added").await["comment"].clone();
    let r = editor
        .request(json!({"type": "add_comment", "part": part, "anchor": {"u": 0.7, "v": 0.2}, "text": "Mine"}))
        .await;
    let mine = r["comment"].as_u64().unwrap();
    let r = editor
        .request(json!({"type": "reply_comment", "comment": theirs, "text": "Will do."}))
        .await;
    let reply = r["comment"].as_u64().unwrap();

    // The viewer's side edits its comment: every client gets the thread
    // with the new text, marked edited, and everything else as it was.
    assert!(added.get("edited_ms").is_none(), "not edited yet: {added}");
    let before_edit = now_ms();
    viewer
        .ok(json!({"type": "edit_comment", "comment": theirs, "text": "Softer here, like v3?"}))
        .await;
    let after_edit = now_ms();
    let edited = loop {
        let c = editor.wait_for("comment_changed").await["comment"].clone();
        if c["text"] == "Softer here, like v3?" {
            break c;
        }
    };
    let edited_at = edited["edited_ms"].as_u64().expect("marked edited");
    assert!(
        (before_edit..=after_edit).contains(&edited_at),
        "edited at {edited_at}, between {before_edit} and {after_edit}"
    );
    assert!(edited_at >= added["time_ms"].as_u64().unwrap());
    let mut want = added.clone();
    want["text"] = json!("Softer here, like v3?");
    want["edited_ms"] = json!(edited_at);
    want["replies"] = edited["replies"].clone();
    assert_eq!(edited, want, "only the text and its edit time change");
    assert_eq!(edited["replies"][0]["text"], "Will do.");
    assert!(
        edited["replies"][0].get("edited_ms").is_none(),
        "the reply was not edited"
    );
    // Not the editor's comment or reply; a device nothing.
    viewer
        .refused(
            json!({"type": "edit_comment", "comment": mine, "text": "x"}),
            "forbidden",
        )
        .await;
    viewer
        .refused(
            json!({"type": "edit_comment", "comment": reply, "text": "x"}),
            "forbidden",
        )
        .await;
    device
        .refused(
            json!({"type": "edit_comment", "comment": theirs, "text": "x"}),
            "forbidden",
        )
        .await;
    // Bad text or an unknown comment: refused as for a new comment.
    for (text, code) in [("  ", "out_of_range"), ("a\u{7}b", "out_of_range")] {
        viewer
            .refused(
                json!({"type": "edit_comment", "comment": theirs, "text": text}),
                code,
            )
            .await;
    }
    viewer
        .refused(
            json!({"type": "edit_comment", "comment": theirs, "text": "x".repeat(4097)}),
            "too_large",
        )
        .await;
    viewer
        .refused(
            json!({"type": "edit_comment", "comment": 12345, "text": "x"}),
            "out_of_range",
        )
        .await;
    // An editor edits anyone's: here the reply, inside the viewer's thread.
    editor
        .ok(json!({"type": "edit_comment", "comment": reply, "text": "Done in v4."}))
        .await;
    let thread = loop {
        let c = viewer.wait_for("comment_changed").await["comment"].clone();
        if c["replies"][0]["text"] == "Done in v4." {
            break c;
        }
    };
    assert_eq!(thread["id"], json!(theirs));
    assert_eq!(thread["text"], "Softer here, like v3?");
    assert_eq!(thread["edited_ms"], json!(edited_at));
    assert!(thread["replies"][0]["edited_ms"].as_u64().unwrap() >= edited_at);

    // Over HTTP, with any token of the design: what a joiner's snapshot has.
    let path = format!("/api/designs/{}/comments", d.id);
    let late = Client::connect(server.addr, d.id, &d.viewer, "late").await;
    for token in [&d.viewer, &d.editor, &d.device] {
        let r = common::http::request(server.addr, "GET", &path, Some(token.as_str()), b"").await;
        assert_eq!(r.status, 200, "{}", r.text());
        let body = r.json();
        assert_eq!(body["id"], json!(d.id));
        assert_eq!(body["comments"], late.snapshot["comments"]);
    }
    let listed = common::http::request(server.addr, "GET", &path, Some(&d.viewer), b"")
        .await
        .json();
    let ids: Vec<u64> = listed["comments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_u64().unwrap())
        .collect();
    assert_eq!(ids, [theirs, mine], "oldest first");
    assert_eq!(listed["comments"][0]["text"], "Softer here, like v3?");
    assert_eq!(listed["comments"][0]["replies"][0]["text"], "Done in v4.");
    assert_eq!(listed["comments"][0]["edited_ms"], json!(edited_at));
    assert!(
        listed["comments"][1].get("edited_ms").is_none(),
        "the editor's own comment was never edited"
    );
    // No token, a bad one, another design's: refused alike.
    let created = common::http::request(
        server.addr,
        "POST",
        "/api/designs",
        Some(&d.editor),
        br#"{"name": "other", "nu": 6, "nv": 6}"#,
    )
    .await;
    assert_eq!(created.status, 201, "{}", created.text());
    let other = created.json()["tokens"]["viewer"]
        .as_str()
        .unwrap()
        .to_string();
    for token in [None, Some("not-a-token"), Some(other.as_str())] {
        let r = common::http::request(server.addr, "GET", &path, token, b"").await;
        assert_eq!(r.status, 401, "{token:?}: {}", r.text());
    }
    let r = common::http::request(
        server.addr,
        "GET",
        &format!("/api/designs/{}/comments", d.id + 1000),
        Some(&d.viewer),
        b"",
    )
    .await;
    assert_eq!(r.status, 401);
    drop(device);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_per_design_limit_and_the_rate_limit_hold() {
    let data = common::data_dir("comments-limit");
    let server = TestServer::start_configured(
        data.clone(),
        std::path::PathBuf::from("/nonexistent-web"),
        |c| c.max_comments = 3,
    )
    .await;
    let d = server.demo().clone();
    let mut viewer = Client::connect(server.addr, d.id, &d.viewer, "Ben").await;
    let part = part_of_kind(&viewer.snapshot, "surface")["id"]
        .as_u64()
        .unwrap();
    let add =
        json!({"type": "add_comment", "part": part, "anchor": {"u": 0.5, "v": 0.5}, "text": "x"});
    let first = viewer.request(add.clone()).await["comment"]
        .as_u64()
        .unwrap();
    viewer.ok(add.clone()).await;
    viewer
        .ok(json!({"type": "reply_comment", "comment": first, "text": "r"}))
        .await;
    // Three in all (comments and replies): the fourth is refused.
    viewer.refused(add.clone(), "too_large").await;
    viewer
        .refused(
            json!({"type": "reply_comment", "comment": first, "text": "r"}),
            "too_large",
        )
        .await;
    // Deleting makes room (the comment goes with its reply: two places).
    viewer
        .ok(json!({"type": "delete_comment", "comment": first}))
        .await;
    viewer.ok(add.clone()).await;
    viewer.ok(add.clone()).await;
    viewer.refused(add.clone(), "too_large").await;

    // A flood is rate limited like any control message.
    let n = 260;
    for k in 0..n {
        let mut m = add.clone();
        m["req"] = json!(10_000 + k);
        viewer.send(m).await;
    }
    let mut rate_limited = 0;
    let mut acked = 0;
    let mut answered = 0;
    // Replies to refused messages beyond 10 a second are dropped: wait for
    // the bucket to refill, then for a barrier, instead of counting to n.
    tokio::time::sleep(std::time::Duration::from_millis(2500)).await;
    for m in drain(&mut viewer).await {
        let Some(req) = m["req"].as_u64() else {
            continue;
        };
        if !(10_000..10_000 + n).contains(&req) {
            continue;
        }
        answered += 1;
        match (m["type"].as_str(), m["code"].as_str()) {
            (Some("error"), Some("rate_limited")) => rate_limited += 1,
            (Some("ack"), _) => acked += 1,
            (Some("error"), Some("too_large")) => {}
            other => panic!("unexpected {other:?}: {m}"),
        }
    }
    assert!(
        rate_limited >= 1,
        "no rate_limited among {answered} replies"
    );
    assert_eq!(acked, 0, "the design was full");
    let late = Client::connect(server.addr, d.id, &d.viewer, "late").await;
    let comments = late.snapshot["comments"].as_array().unwrap();
    let total: usize = comments
        .iter()
        .map(|c| 1 + c["replies"].as_array().unwrap().len())
        .sum();
    assert_eq!(total, 3, "{comments:?}");
    server.stop().await;
    let _ = std::fs::remove_dir_all(&data);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn comments_carry_their_version_stay_out_of_undo_and_survive_a_restart() {
    let data = common::data_dir("comments-restart");
    let server = ChildServer::start(&data, 1);
    let d = server.designs[0].clone();
    let mut editor = Client::connect(server.addr, d.id, &d.editor, "Ana").await;
    let mut viewer = Client::connect(server.addr, d.id, &d.viewer, "Ben").await;
    let part = part_of_kind(&viewer.snapshot, "surface")["id"]
        .as_u64()
        .unwrap();
    let v0 = last_version(&viewer.snapshot);
    let add = |u: f64, text: &str| json!({"type": "add_comment", "part": part, "anchor": {"u": u, "v": 0.5}, "text": text});

    // An edit, then a comment on it: undoing the edit keeps the comment.
    editor
        .ok(json!({"type": "create_icon", "part": part, "spec": {"anchor": {"kind": "point", "u": 0.3, "v": 0.3}, "role": {"kind": "position"}}}))
        .await;
    let a = viewer.request(add(0.2, "before the commit")).await["comment"]
        .as_u64()
        .unwrap();
    editor.ok(json!({"type": "undo"})).await;
    let snap = viewer.wait_for("snapshot").await;
    assert_eq!(snap["comments"].as_array().unwrap().len(), 1, "{snap}");
    // Undo again: nothing to undo (the comment is not in the history).
    editor.refused(json!({"type": "undo"}), "conflict").await;

    let r = editor
        .request(json!({"type": "commit", "message": "softer edge"}))
        .await;
    let v1 = r["version"].as_u64().unwrap();
    assert!(v1 > v0);
    let b = viewer.request(add(0.4, "on the new version")).await["comment"]
        .as_u64()
        .unwrap();
    if v0 > 0 {
        editor
            .ok(json!({"type": "restore_version", "version": v0}))
            .await;
    }
    let c = viewer.request(add(0.6, "after restoring")).await["comment"]
        .as_u64()
        .unwrap();
    viewer
        .ok(json!({"type": "resolve_comment", "comment": a, "resolved": true}))
        .await;
    editor
        .ok(json!({"type": "reply_comment", "comment": b, "text": "ok"}))
        .await;
    viewer
        .ok(json!({"type": "edit_comment", "comment": b, "text": "on the new version, please"}))
        .await;
    let before = Client::connect(server.addr, d.id, &d.viewer, "x")
        .await
        .snapshot["comments"]
        .clone();
    let edited: Vec<&Value> = before
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c.get("edited_ms").is_some())
        .collect();
    assert_eq!(edited.len(), 1, "{before}");
    assert_eq!(edited[0]["id"], json!(b));
    drop((editor, viewer));
    assert!(server.terminate().success());

    let server = ChildServer::start(&data, 1);
    let back = Client::connect(server.addr, d.id, &d.viewer, "Ben").await;
    let comments = back.snapshot["comments"].clone();
    assert_eq!(comments, before, "comments changed across the restart");
    let by_id = |id: u64| {
        comments
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["id"] == json!(id))
            .unwrap()
            .clone()
    };
    assert_eq!(by_id(a)["version"], json!(v0));
    assert_eq!(by_id(a)["resolved"], json!(true));
    assert_eq!(by_id(a)["text"], "before the commit");
    assert_eq!(by_id(b)["version"], json!(v1));
    assert_eq!(by_id(b)["replies"][0]["text"], "ok");
    assert_eq!(
        by_id(b)["replies"][0]["version"],
        json!(if v0 > 0 { v0 } else { v1 })
    );
    assert_eq!(
        by_id(c)["version"],
        json!(if v0 > 0 { v0 } else { v1 }),
        "a comment after a restore is on the restored version"
    );
    server.kill9();
    let _ = std::fs::remove_dir_all(&data);
}

#[test]
fn a_store_from_before_comments_is_migrated_and_a_newer_one_refused() {
    use vsculpt_server::store::{NewComment, Role, Store, StoreError};
    let dir = common::data_dir("comments-migrate");
    // A database as servers before schema versions wrote it: the three
    // tables, user_version 0, one design.
    {
        let db = rusqlite::Connection::open(dir.join("vsculpt.db")).unwrap();
        db.execute_batch(SCHEMA_1_TABLES).unwrap();
        db.execute_batch(
            "INSERT INTO designs (name, created_ms, editor_token, viewer_token, device_token) VALUES ('old', 1, 'e', 'v', 'd');
             INSERT INTO versions VALUES (1, 1, 2, 'ann', 'first', x'00');",
        )
        .unwrap();
        let v: i64 = db
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .unwrap();
        assert_eq!(v, 0);
    }
    {
        let store = Store::open(&dir).unwrap();
        assert_eq!(store.designs().unwrap()[0].name, "old");
        assert_eq!(store.versions(1).unwrap().len(), 1);
        assert!(store.comments(1).unwrap().is_empty());
        let c = NewComment {
            parent: None,
            part: 1,
            uv: Some([0.25, 0.5]),
            xyz: Some([1.0, 2.0, 3.0]),
            text: "kept".into(),
            author: "Ben".into(),
            access: Role::Viewer,
            version: 1,
        };
        let stored = store.add_comment(1, &c).unwrap();
        assert_eq!(stored.comment, c);
        assert!(matches!(
            store.add_comment(
                1,
                &NewComment {
                    parent: Some(999),
                    ..c.clone()
                }
            ),
            Err(StoreError::UnknownComment(1, 999))
        ));
    }
    {
        // Opening again migrates nothing and keeps the comment.
        let store = Store::open(&dir).unwrap();
        let rows = store.comments(1).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].comment.text, "kept");
        assert_eq!(rows[0].comment.uv, Some([0.25, 0.5]));
    }
    let db = rusqlite::Connection::open(dir.join("vsculpt.db")).unwrap();
    let v: i64 = db
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .unwrap();
    assert_eq!(v, 3);
    db.pragma_update(None, "user_version", 7).unwrap();
    drop(db);
    match Store::open(&dir) {
        Err(StoreError::NewerSchema { found: 7, known: 3 }) => {}
        Err(e) => panic!("wrong refusal: {e}"),
        Ok(_) => panic!("a database of a newer schema was opened"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_store_of_schema_2_gains_edit_times_and_keeps_its_comments() {
    use vsculpt_server::store::Store;
    let dir = common::data_dir("comments-migrate-v2");
    // A database as the servers of schema version 2 wrote it (comments,
    // no edit times), written here by hand from that schema.
    {
        let db = rusqlite::Connection::open(dir.join("vsculpt.db")).unwrap();
        db.execute_batch(SCHEMA_1_TABLES).unwrap();
        db.execute_batch(
            "CREATE TABLE comments (id INTEGER PRIMARY KEY AUTOINCREMENT, design_id INTEGER NOT NULL REFERENCES designs(id),
                 parent INTEGER REFERENCES comments(id) ON DELETE CASCADE, part INTEGER NOT NULL, u REAL, v REAL, x REAL, y REAL, z REAL,
                 text TEXT NOT NULL, author TEXT NOT NULL, access TEXT NOT NULL, time_ms INTEGER NOT NULL, version INTEGER NOT NULL,
                 resolved_by TEXT, resolved_ms INTEGER);
             INSERT INTO designs (name, created_ms, editor_token, viewer_token, device_token) VALUES ('two', 1, 'e', 'v', 'd');
             INSERT INTO comments (design_id, part, u, v, text, author, access, time_ms, version)
                 VALUES (1, 1, 0.5, 0.25, 'from schema 2', 'Ben', 'viewer', 1700000000000, 1);
             PRAGMA user_version = 2;",
        )
        .unwrap();
    }
    let store = Store::open(&dir).unwrap();
    let rows = store.comments(1).unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].comment.text, "from schema 2");
    assert_eq!(rows[0].time_ms, 1_700_000_000_000);
    assert_eq!(rows[0].edited_ms, None, "never edited");
    let id = rows[0].id;
    let at = store
        .edit_comment(1, id, "edited after the migration")
        .unwrap()
        .expect("the comment is there");
    assert!(at > 1_700_000_000_000);
    let rows = store.comments(1).unwrap();
    assert_eq!(rows[0].comment.text, "edited after the migration");
    assert_eq!(rows[0].edited_ms, Some(at));
    assert_eq!(rows[0].time_ms, 1_700_000_000_000, "the first time stays");
    assert_eq!(store.edit_comment(1, id + 1, "x").unwrap(), None);
    drop(store);
    let db = rusqlite::Connection::open(dir.join("vsculpt.db")).unwrap();
    let v: i64 = db
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .unwrap();
    assert_eq!(v, 3);
    drop(db);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The three tables of the store before schema versions (and of schema
/// version 1), written here by hand from that schema.
const SCHEMA_1_TABLES: &str = "
    CREATE TABLE designs (id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, created_ms INTEGER NOT NULL,
        editor_token TEXT NOT NULL, viewer_token TEXT NOT NULL, device_token TEXT NOT NULL, deleted INTEGER NOT NULL DEFAULT 0);
    CREATE TABLE versions (design_id INTEGER NOT NULL REFERENCES designs(id), number INTEGER NOT NULL, time_ms INTEGER NOT NULL,
        author TEXT NOT NULL, message TEXT NOT NULL, snapshot BLOB NOT NULL, PRIMARY KEY (design_id, number));
    CREATE TABLE working (design_id INTEGER PRIMARY KEY REFERENCES designs(id), updated_ms INTEGER NOT NULL, snapshot BLOB NOT NULL);
";

/// Milliseconds since the Unix epoch, by the test's own clock.
fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_millis() as u64
}
