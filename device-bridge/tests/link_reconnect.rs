//! The server link against a fake WebSocket server on loopback: hello first,
//! commands after acceptance, drags coalesced, reconnection with backoff when the
//! server goes away, and bindings restored on the new connection.

use futures_util::{SinkExt, StreamExt};
use glam::DVec3;
use std::sync::Arc;
use std::time::Duration;
use tokio::net::TcpListener;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::Message;
use vsculpt_bridge::bridge::Input;
use vsculpt_bridge::config::{Config, DeviceConfig, DeviceKind, HandConfig};
use vsculpt_bridge::device::{GloveValues, Reading, Sample, SourceId, Timestamp};
use vsculpt_bridge::hand::{GloveCalibration, glove_shape};
use vsculpt_bridge::interaction::{Command, IconKind, IconRole, IconState, IconView};
use vsculpt_bridge::link::{Link, LinkOptions, ServerEvent, Wire};

/// A minimal line protocol: "hello <token>", "ok", "icon <id> <x> <y> <z>", commands as Debug text.
struct TestWire;

impl Wire for TestWire {
    fn hello(&self, token: &str, design: Option<u64>) -> String {
        format!("hello {token} {}", design.unwrap_or(0))
    }
    fn encode(&self, cmd: &Command, _ordered: bool) -> Vec<String> {
        match cmd {
            // hand samples and device status are not what this test is about
            Command::HandSample { .. } | Command::DeviceStatus { .. } => vec![],
            c => vec![format!("{c:?}")],
        }
    }
    fn decode(&self, text: &str) -> Result<Vec<ServerEvent>, String> {
        let w: Vec<&str> = text.split(' ').collect();
        match w.as_slice() {
            ["ok"] => Ok(vec![ServerEvent::Welcome]),
            ["icon", id, x, y, z] => {
                let p = |s: &str| s.parse::<f64>().map_err(|e| e.to_string());
                Ok(vec![ServerEvent::Icons {
                    icons: vec![IconView {
                        part: 1,
                        id: id.parse().map_err(|_| "id")?,
                        position: DVec3::new(p(x)?, p(y)?, p(z)?),
                        target: DVec3::new(p(x)?, p(y)?, p(z)?),
                        role: IconRole::Constraint,
                        kind: IconKind::Position,
                        state: IconState::Passive,
                    }],
                    area: Some(1.0),
                }])
            }
            _ => Err(format!("unknown {text}")),
        }
    }
    fn accepts(&self, event: &ServerEvent) -> bool {
        matches!(event, ServerEvent::Icons { .. } | ServerEvent::Welcome)
    }
}

/// Accepts one connection on `listener`, checks the hello, sends the icon, and
/// forwards every text received to `seen` until `close` fires.
async fn serve_once(
    listener: &TcpListener,
    seen: mpsc::UnboundedSender<String>,
    close: tokio::sync::oneshot::Receiver<()>,
) {
    let (tcp, _) = listener.accept().await.unwrap();
    let mut ws = tokio_tungstenite::accept_async(tcp).await.unwrap();
    let hello = ws.next().await.unwrap().unwrap();
    assert_eq!(hello.to_text().unwrap(), "hello secret 4");
    ws.send(Message::text("icon 1 0 0 0")).await.unwrap();
    tokio::pin!(close);
    loop {
        tokio::select! {
            m = ws.next() => match m {
                Some(Ok(Message::Text(t))) => { let _ = seen.send(t.to_string()); }
                _ => return,
            },
            _ = &mut close => { let _ = ws.close(None).await; return; }
        }
    }
}

fn config(url: String) -> Config {
    let mut tracker = DeviceConfig::new("tracker", DeviceKind::Fastrak);
    tracker.port = Some("/dev/null".into());
    let mut glove = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    glove.port = Some("/dev/null".into());
    let mut c = Config {
        devices: vec![tracker, glove],
        ..Default::default()
    };
    c.hands.push(HandConfig {
        name: "right".into(),
        tracker: "tracker".into(),
        sensor: 0,
        glove: Some("glove".into()),
        reach: 0.1,
        calibration: GloveCalibration::default(),
    });
    c.server.url = url;
    c.validate().unwrap();
    c
}

async fn recv_until(
    rx: &mut mpsc::UnboundedReceiver<String>,
    pred: impl Fn(&str) -> bool,
) -> Vec<String> {
    let mut all = Vec::new();
    let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
    loop {
        let m = tokio::time::timeout_at(deadline, rx.recv())
            .await
            .unwrap_or_else(|_| panic!("timed out after {all:?}"))
            .expect("closed");
        let done = pred(&m);
        all.push(m);
        if done {
            return all;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reconnects_and_restores_bindings_and_coalesces_drags() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let url = format!(
        "ws://{}/ws?design=4&token=secret",
        listener.local_addr().unwrap()
    );
    let cfg = config(url.clone());
    let (samples_tx, samples_rx) = mpsc::unbounded_channel::<Input>();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let cfg2 = cfg.clone();
    let bridge = tokio::spawn(async move {
        vsculpt_bridge::bridge::drive(&cfg2, Arc::new(TestWire), samples_rx, async {
            let _ = stop_rx.await;
        })
        .await
    });

    // first server life
    let (seen_tx, mut seen) = mpsc::unbounded_channel();
    let (close1, close1_rx) = tokio::sync::oneshot::channel();
    let l = Arc::new(listener);
    let l2 = l.clone();
    let s1 = {
        let seen_tx = seen_tx.clone();
        tokio::spawn(async move { serve_once(&l2, seen_tx, close1_rx).await })
    };

    let pose = |x: f64| Sample {
        source: SourceId(0),
        time: Timestamp::now(),
        reading: Reading::Pose {
            sensor: 0,
            position: DVec3::new(x, 0.0, 0.0),
            orientation: glam::DQuat::IDENTITY,
        },
    };
    let glove = |f: f64| Sample {
        source: SourceId(1),
        time: Timestamp::now(),
        reading: Reading::Glove(GloveValues::new(&glove_shape(22, f, f)).unwrap()),
    };
    // wait until the icon is known, then grab it
    tokio::time::sleep(Duration::from_millis(300)).await;
    // (the tracker's gate confirms a track over three records before the hand has a pose)
    samples_tx
        .send(Input::Samples(vec![
            pose(0.0),
            pose(0.0),
            pose(0.0),
            glove(1.0),
        ]))
        .unwrap();
    let got = recv_until(&mut seen, |m| m.starts_with("Grab")).await;
    assert!(
        got[0].starts_with("Grab { icon: 1, sensor: \"right\""),
        "{got:?}"
    );
    // a burst of 200 poses in one batch: the first drag leaves, the rest wait for
    // the next drag slot and only the newest of them is sent
    samples_tx
        .send(Input::Samples(
            (1..=200).map(|i| pose(i as f64 * 1e-4)).collect(),
        ))
        .unwrap();
    let got = recv_until(&mut seen, |m| m.contains("DVec3(0.02,")).await;
    assert!(got.len() <= 2, "{got:?}");

    // the server restarts
    close1.send(()).unwrap();
    s1.await.unwrap();
    let (_close2, close2_rx) = tokio::sync::oneshot::channel::<()>();
    let l3 = l.clone();
    let s2 = tokio::spawn(async move { serve_once(&l3, seen_tx, close2_rx).await });
    // on the new connection the held icon is bound again and dragged to where the hand is
    let got = recv_until(&mut seen, |m| m.starts_with("Drag")).await;
    assert!(
        got.iter().any(|m| m.starts_with("Grab { icon: 1")),
        "{got:?}"
    );
    assert!(got.last().unwrap().contains("DVec3(0.02,"), "{got:?}");
    // release after the restart
    samples_tx.send(Input::Samples(vec![glove(0.0)])).unwrap();
    let got = recv_until(&mut seen, |m| m.starts_with("Release")).await;
    assert!(
        got.iter().any(|m| m.starts_with("Release { icon: 1")),
        "{got:?}"
    );
    stop_tx.send(()).unwrap();
    bridge.await.unwrap().unwrap();
    s2.abort();
}

#[tokio::test]
async fn unreachable_server_is_retried_without_events_piling_up() {
    // nothing listens on this port
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = l.local_addr().unwrap();
    drop(l);
    let (tx, mut rx) = mpsc::unbounded_channel();
    let mut o = LinkOptions::new(format!("ws://{addr}/ws?token=x"));
    o.backoff_min = Duration::from_millis(10);
    o.backoff_max = Duration::from_millis(40);
    let link = Link::spawn(o, Arc::new(TestWire), tx);
    link.send([Command::Release {
        icon: 3,
        sensor: "right".into(),
    }]);
    let mut disconnects = 0;
    let deadline = tokio::time::Instant::now() + Duration::from_millis(400);
    while let Ok(Some(ev)) = tokio::time::timeout_at(deadline, rx.recv()).await {
        assert_eq!(ev, ServerEvent::Disconnected);
        disconnects += 1;
    }
    // backoff: far fewer attempts than 400 ms / 10 ms
    assert!((2..=15).contains(&disconnects), "{disconnects}");
    assert_eq!(link.stats().connections, 0);
}
