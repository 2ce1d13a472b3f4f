//! End to end: the real server, the bridge, a Flock of Birds tracker and a
//! CyberGlove simulated on pseudo-terminals. The hand closes on a position icon
//! of the demo design (it becomes driving, bound to the hand), lifts it by 20 mm
//! and opens: the icon — and the surface through it — has moved by exactly that
//! on the server, and it ends passive and unbound. The session is recorded; replaying the recording against a fresh
//! server produces the same shape change.

mod bridge_support;

use bridge_support::*;
use glam::DVec3;
use std::sync::Arc;
use std::time::Duration;
use vsculpt_bridge::bridge::{run_live, run_replay};
use vsculpt_bridge::wire::ProtocolWire;
use vsculpt_protocol::IconState;

const LIFT: f64 = 20.0;

/// Grabs icon `id` (at `p`) with the studio's hand, lifts it by LIFT mm in z, releases.
async fn grab_lift_release(server: &RunningServer, studio: &Studio, id: u64, p: DVec3) {
    let (addr, token) = (server.addr, server.viewer_token.clone());
    // the bridge is connected and sees the hand: close it
    wait_bridge(server).await;
    studio.close_hand(true);
    let held = eventually(10, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, id).await;
            (i.sensors.contains(&"right-hand".to_string()) && i.holder.is_some()).then_some(i)
        }
    })
    .await
    .expect("the closed hand grabs the icon");
    assert_eq!(held.state, IconState::Driving);
    for k in 1..=20 {
        studio.move_to(p + DVec3::new(0.0, 0.0, 1.0 + LIFT * k as f64 / 20.0));
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    // the server keeps a drag's shape in its solver until the release; hold still, then let go
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(false);
    let released = eventually(10, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, id).await;
            (i.holder.is_none() && i.sensors.is_empty()).then_some(i)
        }
    })
    .await
    .expect("the opened hand releases the icon");
    assert_eq!(released.state, IconState::Passive);
    assert!(
        (released.xyz[2] - p.z - LIFT).abs() < 0.5,
        "icon at {:?}, expected z = {}",
        released.xyz,
        p.z + LIFT
    );
    assert!(
        (released.xyz[0] - p.x).abs() < 0.5 && (released.xyz[1] - p.y).abs() < 0.5,
        "{:?}",
        released.xyz
    );
}

fn max_shift(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (DVec3::from_array(*p) - DVec3::from_array(*q)).length())
        .fold(0.0, f64::max)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn hand_drags_an_icon_and_replay_repeats_it() {
    init_logs();
    let dir = temp_dir("bridge-drag");
    let server = RunningServer::start(&dir.join("data"), None).await;
    let icon = position_icon(&snapshot_icons(server.addr, &server.viewer_token).await);
    let p = DVec3::from_array(icon.xyz);
    let before = snapshot_points(server.addr, &server.viewer_token).await;

    // live session, recorded
    let studio = Studio::start(&dir, p + DVec3::new(0.0, 0.0, 1.0));
    let config = bridge_config(&dir, &server.device_url);
    let recording = dir.join("session.vsbrec");
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let (cfg, rec) = (config.clone(), recording.clone());
    let bridge = tokio::spawn(async move {
        run_live(cfg, Arc::new(ProtocolWire::default()), Some(&rec), async {
            let _ = stopped.await;
        })
        .await
    });
    grab_lift_release(&server, &studio, icon.id, p).await;
    let after = snapshot_points(server.addr, &server.viewer_token).await;
    assert!(
        max_shift(&before, &after) > 5.0,
        "the surface moved with the icon"
    );
    stop.send(()).unwrap();
    bridge.await.unwrap().unwrap();
    server.stop().await;
    drop(studio);

    // replay into a fresh server: the same drag happens again
    let server2 = RunningServer::start(&dir.join("data2"), None).await;
    let icon2 = position_icon(&snapshot_icons(server2.addr, &server2.viewer_token).await);
    assert_eq!(icon2.id, icon.id);
    assert_eq!(icon2.xyz, icon.xyz);
    let mut cfg2 = config.clone();
    cfg2.server.url = server2.device_url.clone();
    let n = run_replay(
        cfg2,
        Arc::new(ProtocolWire::default()),
        &recording,
        4.0,
        std::future::pending(),
    )
    .await
    .unwrap();
    assert!(n > 100, "replayed {n} samples");
    let replayed = icon_now(server2.addr, &server2.viewer_token, icon.id).await;
    assert!(
        (replayed.xyz[2] - p.z - LIFT).abs() < 0.5,
        "replayed icon at {:?}",
        replayed.xyz
    );
    assert_eq!(replayed.state, IconState::Passive);
    assert!(replayed.sensors.is_empty());
    let after2 = snapshot_points(server2.addr, &server2.viewer_token).await;
    assert!(
        max_shift(&after, &after2) < 0.5,
        "live and replay give the same shape"
    );
    server2.stop().await;
}

/// A load icon is pulled through the spring model: whatever the server's
/// stiffness, the bridge adapts κ from the displacement the server reports
/// until the icon follows the hand within paper 003's band 0.8 ≤ Δy/Δx ≤ 1.2.
#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn hand_pulls_a_load_icon_within_the_spring_band() {
    init_logs();
    let dir = temp_dir("bridge-load");
    let server = RunningServer::start(&dir.join("data"), None).await;
    let icons = snapshot_icons(server.addr, &server.viewer_token).await;
    let load = icons
        .iter()
        .find(|i| i.role == vsculpt_protocol::Role::Load)
        .cloned()
        .expect("the demo has a load icon");
    let p = DVec3::from_array(load.xyz);
    let studio = Studio::start(&dir, p);
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let cfg = bridge_config(&dir, &server.device_url);
    let bridge = tokio::spawn(async move {
        run_live(cfg, Arc::new(ProtocolWire::default()), None, async {
            let _ = stopped.await;
        })
        .await
    });
    wait_bridge(&server).await;
    studio.close_hand(true);
    let (addr, token) = (server.addr, server.viewer_token.clone());
    eventually(10, || {
        let t = token.clone();
        async move { icon_now(addr, &t, load.id).await.holder.map(|_| ()) }
    })
    .await
    .expect("the hand takes the load icon");
    let dx = 10.0;
    for k in 1..=20 {
        studio.move_to(p + DVec3::new(0.0, 0.0, dx * k as f64 / 20.0));
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    tokio::time::sleep(Duration::from_millis(500)).await;
    studio.close_hand(false);
    let done = eventually(10, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, load.id).await;
            i.holder.is_none().then_some(i)
        }
    })
    .await
    .expect("released");
    let dy = done.xyz[2] - p.z;
    assert!(
        (0.8 * dx..=1.2 * dx).contains(&dy),
        "Δy = {dy} for Δx = {dx}"
    );
    stop.send(()).unwrap();
    bridge.await.unwrap().unwrap();
    server.stop().await;
}

/// The 3D mouse through spacenavd (a fake daemon socket): a button selects an
/// icon, pushing the cap moves it, letting go ends the drag; the menu buttons
/// put it to sleep.
#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn space_mouse_selects_moves_and_puts_an_icon_to_sleep() {
    use vsculpt_bridge::config::{DeviceConfig, DeviceKind};
    use vsculpt_bridge::sim::spacenavd::FakeSpacenavd;
    init_logs();
    let dir = temp_dir("bridge-mouse");
    let server = RunningServer::start(&dir.join("data"), None).await;
    let icons = snapshot_icons(server.addr, &server.viewer_token).await;
    let first = icons.iter().min_by_key(|i| i.id).cloned().unwrap();
    let p = DVec3::from_array(first.xyz);
    let daemon = FakeSpacenavd::start(dir.join("spnav.sock")).unwrap();
    let mut mouse = DeviceConfig::new("mouse", DeviceKind::Spacenavd);
    mouse.spacenavd.socket = Some(dir.join("spnav.sock").display().to_string());
    let mut cfg = vsculpt_bridge::config::Config {
        devices: vec![mouse],
        ..Default::default()
    };
    cfg.menu.speed = 20.0; // mm per second at full deflection
    // the 3D menu changes icon states, which the server allows editors only
    cfg.server.url = format!(
        "ws://{}/ws?design=1&token={}",
        server.addr, server.editor_token
    );
    cfg.validate().unwrap();
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let bridge = tokio::spawn(async move {
        run_live(cfg, Arc::new(ProtocolWire::default()), None, async {
            let _ = stopped.await;
        })
        .await
    });
    let connected = eventually(10, || async { (daemon.clients() > 0).then_some(()) }).await;
    assert!(connected.is_some());
    wait_bridge(&server).await;
    // button 2 selects the first icon; pull the cap towards the user at full scale
    // for 0.5 s: spacenavd's z is -350 (its z points away), the bridge's +1
    daemon.send_button(2, true);
    daemon.send_button(2, false);
    let push = std::time::Instant::now();
    for _ in 0..50 {
        daemon.send_motion([0, 0, -350, 0, 0, 0], 10);
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    daemon.send_motion([0, 0, 0, 0, 0, 0], 10);
    // The cap was held for `pushed` of wall time (0.5 s on a quiet machine, more
    // when the box is loaded and the sleeps run long): the icon moves by at most
    // 20 mm/s of that, plus one capped event step (0.1 s).
    let pushed = push.elapsed().as_secs_f64();
    let (addr, token) = (server.addr, server.viewer_token.clone());
    let moved = eventually(10, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, first.id).await;
            (i.holder.is_none() && i.xyz[2] - p.z > 5.0).then_some(i)
        }
    })
    .await;
    let now = icon_now(addr, &token, first.id).await;
    let moved = moved.unwrap_or_else(|| panic!("icon at {:?} from {p}", now.xyz));
    let most = 20.0 * (pushed + 0.1) + 1.0;
    assert!(
        moved.xyz[2] - p.z < most,
        "{:?}: more than {most} mm after {pushed} s",
        moved.xyz
    );
    // the menu: seven times "next entry" reaches "sleeping", "apply" sets it
    for _ in 0..7 {
        daemon.send_button(0, true);
        daemon.send_button(0, false);
    }
    daemon.send_button(1, true);
    daemon.send_button(1, false);
    let asleep = eventually(10, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, first.id).await;
            (i.state == IconState::Sleeping).then_some(i)
        }
    })
    .await;
    assert!(asleep.is_some(), "the menu did not put the icon to sleep");
    stop.send(()).unwrap();
    bridge.await.unwrap().unwrap();
    server.stop().await;
}
