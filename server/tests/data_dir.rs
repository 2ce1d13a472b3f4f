//! One server owns a data directory, and a running studio can be backed up
//! and restored — with the real binary, as an operator would:
//!
//! * a second server on a directory in use exits non-zero with a message
//!   naming the directory and the owner's pid; the first serves on;
//! * `backup` taken while an editor drags and commits as fast as it can is
//!   a sound SQLite file holding every version acked before it began;
//!   `restore` puts it in a fresh directory a server then serves; both
//!   refuse to overwrite without `--force`, and `restore` refuses a
//!   directory a server owns.

mod common;

use common::parts::load_icon;

use common::ChildServer;
use common::http::get;
use common::ws::Client;
use serde_json::{Value, json};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vsculpt-server"))
}

/// Runs `cmd` to its end (generous limit: a hang is a failure).
fn finish(mut cmd: Command) -> Output {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("{cmd:?} did not exit");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn messages(versions: &Value) -> Vec<String> {
    versions["versions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["message"].as_str().unwrap().to_string())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_server_on_a_directory_in_use_exits_naming_the_owner() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let first = ChildServer::start(&data, 1);
    let d = first.designs[0].clone();
    let mut ann = Client::connect(first.addr, d.id, &d.editor, "ann").await;

    let mut second = bin();
    second
        .args(["--listen", "127.0.0.1:0", "--data"])
        .arg(&data)
        .arg("--web-dir")
        .arg(data.join("no-web-client"));
    let out = tokio::task::spawn_blocking(move || finish(second))
        .await
        .unwrap();
    assert!(!out.status.success(), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    let expected = format!(
        "data directory {} is in use by another vsculpt-server (pid {})",
        data.display(),
        first.child.id()
    );
    assert!(err.contains(&expected), "{err}");
    assert!(out.stdout.is_empty(), "no banner from the second server");

    // The first serves on, undisturbed.
    let (icon, p) = load_icon(&ann.snapshot);
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 4.0]}))
        .await;
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "commit", "message": "still mine"}))
        .await;
    let v = get(first.addr, "/api/designs/1/versions", Some(&d.viewer))
        .await
        .json();
    assert_eq!(messages(&v), vec!["created", "still mine"]);
    drop(ann);
    assert!(first.terminate().success());
}

fn sqlite_check(db: &Path) -> (String, Vec<String>) {
    let conn =
        rusqlite::Connection::open_with_flags(db, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .unwrap();
    let check: String = conn
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    let mut stmt = conn
        .prepare("SELECT message FROM versions WHERE design_id = 1 ORDER BY number")
        .unwrap();
    let msgs = stmt
        .query_map([], |r| r.get::<_, String>(0))
        .unwrap()
        .collect::<Result<Vec<_>, _>>()
        .unwrap();
    (check, msgs)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_backup_of_a_busy_studio_is_sound_and_restores() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let out = dir.path().join("studio.vsbak");
    let server = ChildServer::start(&data, 1);
    let d = server.designs[0].clone();
    let addr = server.addr;

    // An editor drags and commits as fast as the server acks.
    let acked = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let editor = {
        let (acked, stop, token) = (acked.clone(), stop.clone(), d.editor.clone());
        tokio::spawn(async move {
            let mut c = Client::connect(addr, 1, &token, "ann").await;
            let (icon, p) = load_icon(&c.snapshot);
            for k in 1..=400u64 {
                if stop.load(Ordering::SeqCst) {
                    break;
                }
                let z = p[2] + 0.05 * k as f64;
                c.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
                    .await;
                c.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], z]}))
                    .await;
                c.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
                    .await;
                c.ok(json!({"type": "commit", "message": format!("step {k}")}))
                    .await;
                acked.store(k, Ordering::SeqCst);
            }
        })
    };
    while acked.load(Ordering::SeqCst) < 3 {
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let before = acked.load(Ordering::SeqCst);
    let mut backup = bin();
    backup.arg("backup").arg("--data").arg(&data).arg(&out);
    let done = tokio::task::spawn_blocking(move || finish(backup))
        .await
        .unwrap();
    assert!(done.status.success(), "{done:?}");
    let said = String::from_utf8_lossy(&done.stdout).to_string();
    assert!(said.starts_with("backed up 1 designs, "), "{said}");
    stop.store(true, Ordering::SeqCst);
    editor.await.unwrap();

    let (check, msgs) = sqlite_check(&out);
    assert_eq!(check, "ok");
    let wanted: Vec<String> = std::iter::once("created".to_string())
        .chain((1..=before).map(|k| format!("step {k}")))
        .collect();
    assert!(msgs.len() >= wanted.len(), "{msgs:?}");
    assert_eq!(msgs[..wanted.len()], wanted[..]);

    // No overwriting without --force.
    let bytes = std::fs::read(&out).unwrap();
    let mut again = bin();
    again.arg("backup").arg("--data").arg(&data).arg(&out);
    let refused = tokio::task::spawn_blocking(move || finish(again))
        .await
        .unwrap();
    assert!(!refused.status.success());
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("exists; give --force"),
        "{refused:?}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), bytes);

    // Restore: not into the running server's directory; into a fresh one.
    let mut busy = bin();
    busy.arg("restore").arg("--data").arg(&data).arg(&out);
    let refused = tokio::task::spawn_blocking(move || finish(busy))
        .await
        .unwrap();
    assert!(!refused.status.success());
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("is in use by another vsculpt-server"),
        "{refused:?}"
    );
    let fresh = dir.path().join("restored");
    let mut restore = bin();
    restore.arg("restore").arg("--data").arg(&fresh).arg(&out);
    let restored = tokio::task::spawn_blocking(move || finish(restore))
        .await
        .unwrap();
    assert!(restored.status.success(), "{restored:?}");
    let mut twice = bin();
    twice.arg("restore").arg("--data").arg(&fresh).arg(&out);
    let refused = tokio::task::spawn_blocking(move || finish(twice))
        .await
        .unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("exists; give --force"));

    // A server on the restored copy serves every version acked before the
    // backup began, identical to the original's.
    let copy = ChildServer::start(&fresh, 1);
    assert_eq!(copy.designs[0].editor, d.editor, "tokens come back too");
    let v = get(copy.addr, "/api/designs/1/versions", Some(&d.viewer))
        .await
        .json();
    assert_eq!(messages(&v)[..wanted.len()], wanted[..]);
    for n in [2, before + 1] {
        let path = format!("/api/designs/1/versions/{n}");
        let a = get(addr, &path, Some(&d.viewer)).await.json();
        let b = get(copy.addr, &path, Some(&d.viewer)).await.json();
        assert_eq!(a["design"], b["design"], "version {n}");
    }
    assert!(copy.terminate().success());
    assert!(server.terminate().success());
}
