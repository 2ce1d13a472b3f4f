//! Fault injection end to end (real server, bridge, simulated Flock + CyberGlove):
//! corrupt bytes in the tracker stream never move the icon off the hand's path;
//! a tracker unplugged mid-drag releases the icon and, plugged back, drags again;
//! a server restart mid-drag is ridden out — the bridge reconnects, restores its
//! binding and the drag ends where the hand is.

mod bridge_support;

use bridge_support::*;
use glam::DVec3;
use std::sync::Arc;
use std::time::Duration;
use vsculpt_bridge::bridge::run_live;
use vsculpt_bridge::wire::ProtocolWire;
use vsculpt_protocol::IconState;

/// Starts the bridge on `config`; returns its stop switch and task.
fn start_bridge(
    config: vsculpt_bridge::config::Config,
) -> (
    tokio::sync::oneshot::Sender<()>,
    tokio::task::JoinHandle<()>,
) {
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let task = tokio::spawn(async move {
        run_live(config, Arc::new(ProtocolWire::default()), None, async {
            let _ = stopped.await;
        })
        .await
        .unwrap();
    });
    (stop, task)
}

async fn wait_held(server: &RunningServer, id: u64, held: bool) -> vsculpt_protocol::Icon {
    let (addr, token) = (server.addr, server.viewer_token.clone());
    eventually(15, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, id).await;
            let is_held = i.holder.is_some() && i.sensors.contains(&"right-hand".to_string());
            let is_free = i.holder.is_none() && i.sensors.is_empty();
            ((held && is_held) || (!held && is_free)).then_some(i)
        }
    })
    .await
    .unwrap_or_else(|| {
        panic!(
            "icon {id} never became {}",
            if held { "held" } else { "free" }
        )
    })
}

async fn lift(studio: &Studio, from: DVec3, to: DVec3, steps: usize) {
    for k in 1..=steps {
        studio.move_to(from + (to - from) * (k as f64 / steps as f64));
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn corrupt_tracker_bytes_never_move_the_icon_off_the_hand_path() {
    init_logs();
    let dir = temp_dir("bridge-corrupt");
    let server = RunningServer::start(&dir.join("data"), None).await;
    let icon = position_icon(&snapshot_icons(server.addr, &server.viewer_token).await);
    let p = DVec3::from_array(icon.xyz);
    let mut frames = watch_frames(server.addr, &server.viewer_token).await;
    let studio = Studio::start(&dir, p);
    let (stop, bridge) = start_bridge(bridge_config(&dir, &server.device_url));
    wait_bridge(&server).await;
    studio.close_hand(true);
    wait_held(&server, icon.id, true).await;
    // lift by 20 mm while the line spits garbage: stray bytes, records cut short,
    // bytes with the phasing bit in the wrong place, a record whose quaternion is zero
    let garbage: [&[u8]; 5] = [
        &[0x00, 0x7f, 0x13, 0x55],
        &[0xc8, 0x08, 0x00, 0x70, 0x00],
        &[0xff, 0xff, 0xff, 0x80, 0x80],
        &[0x80, 0x7f, 0x7f, 0x7f, 0x7f, 0x7f, 0, 0, 0, 0, 0, 0, 0, 0],
        &[0x9f, 0x01, 0x02],
    ];
    for k in 1..=40 {
        studio.move_to(p + DVec3::new(0.0, 0.0, 20.0 * k as f64 / 40.0));
        studio.tracker.inject(garbage[k % garbage.len()]);
        tokio::time::sleep(Duration::from_millis(15)).await;
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(false);
    let done = wait_held(&server, icon.id, false).await;
    assert!(
        (done.xyz[2] - p.z - 20.0).abs() < 0.5,
        "icon at {:?}",
        done.xyz
    );
    assert_eq!(done.state, IconState::Passive);
    // every frame the server sent put the icon on the hand's path
    let mut seen = 0;
    while let Ok(f) = frames.try_recv() {
        if let Some(fi) = f.icons.iter().find(|i| i.id == icon.id) {
            let q = DVec3::new(fi.xyz[0] as f64, fi.xyz[1] as f64, fi.xyz[2] as f64);
            assert!(
                (q.x - p.x).abs() < 0.5 && (q.y - p.y).abs() < 0.5,
                "off the path: {q}"
            );
            assert!(q.z > p.z - 0.5 && q.z < p.z + 20.5, "off the path: {q}");
            seen += 1;
        }
    }
    assert!(seen > 5, "only {seen} frames showed the icon");
    stop.send(()).unwrap();
    bridge.await.unwrap();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn tracker_unplugged_mid_drag_releases_and_drags_again_when_back() {
    init_logs();
    let dir = temp_dir("bridge-unplug");
    let server = RunningServer::start(&dir.join("data"), None).await;
    let icon = position_icon(&snapshot_icons(server.addr, &server.viewer_token).await);
    let p = DVec3::from_array(icon.xyz);
    let mut studio = Studio::start(&dir, p);
    let (stop, bridge) = start_bridge(bridge_config(&dir, &server.device_url));
    wait_bridge(&server).await;
    studio.close_hand(true);
    wait_held(&server, icon.id, true).await;
    lift(&studio, p, p + DVec3::new(0.0, 0.0, 10.0), 10).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    // the tracker goes away: the bridge lets go of the icon (no drag from a stale hand)
    studio.tracker.unplug();
    let released = wait_held(&server, icon.id, false).await;
    assert!(
        (released.xyz[2] - p.z - 10.0).abs() < 0.5,
        "kept at {:?}",
        released.xyz
    );
    // it comes back; the hand opens and closes again and drags on
    studio.tracker.device().streaming = false;
    studio.tracker.plug().unwrap();
    studio.close_hand(false);
    // the bridge reopens it (with backoff) and restarts the stream
    let back = eventually(15, || async {
        studio.tracker.device().streaming.then_some(())
    })
    .await;
    assert!(back.is_some(), "the bridge never reopened the tracker");
    let q = DVec3::from_array(released.xyz);
    studio.move_to(q);
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(true);
    wait_held(&server, icon.id, true).await;
    lift(&studio, q, q + DVec3::new(0.0, 0.0, 10.0), 10).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(false);
    let done = wait_held(&server, icon.id, false).await;
    assert!(
        (done.xyz[2] - p.z - 20.0).abs() < 0.5,
        "icon at {:?}",
        done.xyz
    );
    stop.send(()).unwrap();
    bridge.await.unwrap();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn server_restart_mid_drag_restores_the_binding() {
    init_logs();
    let dir = temp_dir("bridge-restart");
    let data = dir.join("data");
    let server = RunningServer::start(&data, None).await;
    let addr = server.addr;
    let icon = position_icon(&snapshot_icons(server.addr, &server.viewer_token).await);
    let p = DVec3::from_array(icon.xyz);
    let studio = Studio::start(&dir, p);
    let (stop, bridge) = start_bridge(bridge_config(&dir, &server.device_url));
    wait_bridge(&server).await;
    studio.close_hand(true);
    wait_held(&server, icon.id, true).await;
    lift(&studio, p, p + DVec3::new(0.0, 0.0, 8.0), 8).await;
    // the server goes down with the hand still closed, and comes back on the same address
    server.stop().await;
    lift(
        &studio,
        p + DVec3::new(0.0, 0.0, 8.0),
        p + DVec3::new(0.0, 0.0, 14.0),
        6,
    )
    .await;
    let server = RunningServer::start(&data, Some(addr)).await;
    // the bridge reconnects and takes the icon again with the same hand
    wait_held(&server, icon.id, true).await;
    lift(
        &studio,
        p + DVec3::new(0.0, 0.0, 14.0),
        p + DVec3::new(0.0, 0.0, 20.0),
        6,
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(false);
    let done = wait_held(&server, icon.id, false).await;
    assert!(
        (done.xyz[2] - p.z - 20.0).abs() < 0.5,
        "icon at {:?}",
        done.xyz
    );
    assert_eq!(done.state, IconState::Passive);
    stop.send(()).unwrap();
    bridge.await.unwrap();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rejected_token_stops_the_bridge_with_a_clear_message() {
    init_logs();
    let dir = temp_dir("bridge-token");
    let server = RunningServer::start(&dir.join("data"), None).await;
    // a device that keeps retrying (its socket does not exist) keeps the bridge up
    let mut mouse = vsculpt_bridge::config::DeviceConfig::new(
        "mouse",
        vsculpt_bridge::config::DeviceKind::Spacenavd,
    );
    mouse.spacenavd.socket = Some(dir.join("no-such.sock").display().to_string());
    let mut config = vsculpt_bridge::config::Config {
        devices: vec![mouse],
        ..Default::default()
    };
    config.server.url = format!("ws://{}/ws?design=1&token=not-a-token", server.addr);
    let run = run_live(
        config,
        Arc::new(ProtocolWire::default()),
        None,
        std::future::pending(),
    );
    let err = tokio::time::timeout(Duration::from_secs(15), run)
        .await
        .expect("the bridge stops instead of retrying forever")
        .expect_err("a rejected token is an error");
    let text = err.to_string();
    assert!(text.contains("token rejected for design 1"), "{text}");
    server.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}
