//! The server binary keeps working when whoever read its output goes away
//! (`vsculpt-server … 2>&1 | head`, a closed terminal, a restarted log
//! shipper): stdout and stderr share one pipe that the test closes right
//! after the banner. Editors still join, drag and commit, the dropped log
//! lines are counted in `/metrics`, SIGTERM still ends the process with
//! exit 0, and the commit is there after a restart.

mod common;

use common::parts::{self, load_icon};

use common::ChildServer;
use common::http::get;
use common::ws::Client;
use serde_json::{Value, json};
use std::io::BufRead;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// Starts the binary with stdout and stderr on one pipe, reads the banner
/// (skipping log lines) and closes the pipe's only reader.
fn start_then_close_output(data: &std::path::Path) -> (Child, std::net::SocketAddr, Vec<String>) {
    let (reader, writer) = std::io::pipe().unwrap();
    let child = {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_vsculpt-server"));
        cmd.args(["--listen", "127.0.0.1:0", "--data"])
            .arg(data)
            .arg("--web-dir")
            .arg(data.join("no-web-client"))
            .env("RUST_LOG", "debug")
            .stdout(writer.try_clone().unwrap())
            .stderr(writer);
        cmd.spawn().unwrap()
        // `cmd` and its copies of the write end are dropped here.
    };
    let mut reader = std::io::BufReader::new(reader);
    let mut banner = String::new();
    let mut lines = 0;
    while lines < 5 {
        let mut line = String::new();
        assert!(
            reader.read_line(&mut line).unwrap() > 0,
            "output ended: {banner}"
        );
        if line.starts_with("vsculpt-server listening on ")
            || line.starts_with("web client: ")
            || line.starts_with("design ")
        {
            banner.push_str(&line);
            lines += 1;
        }
    }
    drop(reader);
    let (addr, designs) = common::parse_banner(&banner);
    let d = &designs[0];
    (child, addr, vec![d.editor.clone(), d.viewer.clone()])
}

fn sigterm_and_wait(mut child: Child) -> std::process::ExitStatus {
    let status = Command::new("kill")
        .args(["-15", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("the server did not exit on SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn metric(text: &str, name: &str) -> f64 {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{name} ")))
        .unwrap_or_else(|| panic!("no {name} in {text}"))
        .trim()
        .parse()
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_closed_log_reader_changes_nothing_for_editors_or_shutdown() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let (child, addr, tokens) = start_then_close_output(&data);
    let editor = &tokens[0];

    // Two editors join (each join is logged into the closed pipe).
    let mut ann = Client::connect(addr, 1, editor, "ann").await;
    let mut bob = Client::connect(addr, 1, editor, "bob").await;
    for c in [&ann, &bob] {
        assert_eq!(c.welcome["type"], "welcome");
        assert_eq!(c.snapshot["type"], "snapshot");
    }
    // A drag and a commit.
    let (icon, p) = load_icon(&ann.snapshot);
    let to = [p[0], p[1], p[2] + 9.0];
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": to}))
        .await;
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    let committed = ann
        .request(json!({"type": "commit", "message": "after the log reader left"}))
        .await;
    assert_eq!(committed["type"], "ack", "{committed}");
    let seen = bob.wait_for("committed").await;
    assert_eq!(seen["version"]["message"], "after the log reader left");
    let shape = get(addr, "/api/designs/1", Some(editor)).await.json();
    assert_ne!(
        parts::surface(&shape["design"], 1)["points"],
        Value::Null,
        "{shape}"
    );

    // The lines nobody could read were dropped and counted.
    let admin = std::fs::read_to_string(data.join("admin-token")).unwrap();
    let m = get(addr, "/metrics", Some(admin.trim())).await.text();
    assert!(metric(&m, "vsculpt_log_lines_dropped_total") > 0.0, "{m}");

    drop((ann, bob));
    let status = sigterm_and_wait(child);
    assert!(
        status.success(),
        "SIGTERM must end the server with 0: {status:?}"
    );

    let server = ChildServer::start(&data, 1);
    let after = get(server.addr, "/api/designs/1", Some(editor))
        .await
        .json();
    assert_eq!(after["design"]["parts"], shape["design"]["parts"]);
    let versions = get(server.addr, "/api/designs/1/versions", Some(editor))
        .await
        .json();
    let last = versions["versions"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(last["message"], "after the log reader left");
    assert!(server.terminate().success());
}
