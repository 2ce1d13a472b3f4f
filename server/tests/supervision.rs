//! Supervision of design actors, with the test-only fault injection of the
//! `fault-injection` feature (an in-process API; nothing on the network
//! reaches it): an actor made to panic mid-drag is restarted from the
//! design's last persisted working state; its clients are told
//! (`unavailable`) and disconnected, joins are refused with `unavailable`
//! while it is down, `/healthz` reports degraded meanwhile, the panic is
//! counted, and nothing committed is lost.

mod common;

use common::parts::{self, load_icon};

use common::http::get;
use common::ws::{Client, Got};
use serde_json::{Value, json};
use std::time::Duration;
use vsculpt_server::config::Config;
use vsculpt_server::design::DesignDoc;
use vsculpt_server::server::Server;
use vsculpt_server::shutdown::Shutdown;
use vsculpt_server::store::Store;

fn metric(text: &str, name: &str) -> f64 {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{name} ")))
        .unwrap_or_else(|| panic!("no {name} in {text}"))
        .trim()
        .parse()
        .unwrap()
}

/// Reads everything up to the close; the codes of the errors seen.
async fn error_codes_until_closed(c: &mut Client) -> Vec<String> {
    let mut codes = Vec::new();
    loop {
        match c.next().await {
            Got::Closed => return codes,
            Got::Text(v) if v["type"] == "error" => {
                codes.push(v["code"].as_str().unwrap_or("").to_string())
            }
            _ => {}
        }
    }
}

/// Polls `/healthz` until its status is `want`.
async fn health_becomes(addr: std::net::SocketAddr, want: &str) -> Value {
    for _ in 0..400 {
        let h = get(addr, "/healthz", None).await.json();
        if h["status"] == want {
            return h;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    panic!("/healthz never said {want}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_panicking_actor_restarts_from_its_persisted_state() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let mut config = Config::new(data.clone(), data.join("no-web-client"));
    config.persist_delay = Duration::from_millis(100);
    let shutdown = Shutdown::new();
    let server = Server::start(listener, config, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let hub = server.hub();
    let admin = server.admin_token().to_string();
    let d = server.designs().unwrap()[0].clone();
    let serving = tokio::spawn(server.run());

    let mut ann = Client::connect(addr, d.id, &d.tokens.editor, "ann").await;
    let mut bob = Client::connect(addr, d.id, &d.tokens.viewer, "bob").await;
    let (icon, p) = load_icon(&ann.snapshot);
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 6.0]}))
        .await;
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "commit", "message": "before the fault"}))
        .await;
    let committed = get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    // Mid-drag: the icon is held and moved when the actor panics.
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 12.0]}))
        .await;
    hub.hold_restarts(true);
    hub.inject_panic(d.id).await.unwrap();

    // Both clients hear why and are disconnected.
    for c in [&mut ann, &mut bob] {
        let codes = error_codes_until_closed(c).await;
        assert!(codes.iter().any(|c| c == "unavailable"), "{codes:?}");
    }
    let h = health_becomes(addr, "degraded").await;
    assert_eq!(h["designs_down"], json!([d.id]), "{h}");
    let refused = Client::try_connect(addr, d.id, &d.tokens.editor, "ann")
        .await
        .err()
        .expect("a join while the design is down must be refused");
    assert_eq!(refused["code"], "unavailable", "{refused}");
    let m = get(addr, "/metrics", Some(&admin)).await.text();
    assert_eq!(metric(&m, "vsculpt_actor_panics_total"), 1.0);

    // The last persisted working state, as the store has it now.
    let persisted = {
        let store = Store::open(&data).unwrap();
        let bytes = store.working(d.id).unwrap().unwrap();
        serde_json::to_value(DesignDoc::from_bytes(&bytes).unwrap()).unwrap()
    };
    hub.hold_restarts(false);
    health_becomes(addr, "ok").await;

    let mut ann = Client::connect(addr, d.id, &d.tokens.editor, "ann").await;
    let now = get(addr, "/api/designs/1", Some(&d.tokens.editor))
        .await
        .json();
    for id in parts::part_ids(&persisted) {
        assert_eq!(
            parts::part(&now["design"], id),
            parts::part(&persisted, id),
            "part {id}"
        );
    }
    assert_eq!(now["design"]["parts"], persisted["parts"]);
    assert_eq!(now["design"]["relations"], persisted["relations"]);
    // Nothing committed is lost.
    let v2 = get(addr, "/api/designs/1/versions/2", Some(&d.tokens.viewer))
        .await
        .json();
    assert_eq!(v2["version"]["message"], "before the fault", "{v2}");
    assert_eq!(v2["design"], committed["design"]);
    // The restarted actor works: drag and commit again.
    ann.ok(json!({"type": "drag_start", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "drag", "part": 1, "icon": icon, "xyz": [p[0], p[1], p[2] + 3.0]}))
        .await;
    ann.ok(json!({"type": "drag_end", "part": 1, "icon": icon}))
        .await;
    ann.ok(json!({"type": "commit", "message": "after the restart"}))
        .await;
    let m = get(addr, "/metrics", Some(&admin)).await.text();
    assert_eq!(metric(&m, "vsculpt_actor_restarts_total"), 1.0);
    drop(ann);
    shutdown.trigger();
    serving.await.unwrap().unwrap();
}
