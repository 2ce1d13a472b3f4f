//! Replay reproduces a session across server restarts and line resyncs, end to
//! end with the real server: a live session (simulated Flock + CyberGlove on
//! ptys, the bridge recording) grabs a position icon, lifts it while the tracker
//! line spits garbage (the decoder resynchronises), rides out a server restart
//! mid-drag, holds still, lifts again and lets go. Its recording replayed into a
//! fresh server, and replayed at speed 1 into a server that is restarted in the
//! middle of the replay, both end with the live session's final design.
//!
//! Tolerance: 1e-12 mm on every control point and icon (the bound).
//! The replayed drags decode the same bytes through the same gate, so the final
//! target is the live one bit for bit; what differs is the path of the solves
//! (the live server saw no drags while it was down and re-solved from its
//! persisted shape after the re-grab; a replay into a fresh server saw every
//! drag, coalesced as the server's batches fell). A position constraint's solve
//! is linear in its target, so the end shape is path independent up to the
//! rounding of each step: measured 7e-15 and 1.4e-14 mm, one ulp of a ~100 mm
//! coordinate. A lost drag, a doubled one or a target off by one Flock quantum
//! (0.11 mm) is 1e-4 mm or more, far above the bound.

mod bridge_support;

use bridge_support::*;
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use vsculpt_bridge::bridge::{run_live, run_replay};
use vsculpt_bridge::config::Config;
use vsculpt_bridge::wire::ProtocolWire;
use vsculpt_protocol::{Icon, IconState};

/// Bound on the difference between the live and the replayed final design (mm).
const TOLERANCE: f64 = 1e-12;

/// Garbage the tracker line spits mid-drag: stray bytes, a record cut short, the
/// phasing bit in the wrong place.
const GARBAGE: [&[u8]; 3] = [
    &[0x00, 0x7f, 0x13, 0x55],
    &[0xc8, 0x08, 0x00, 0x70, 0x00],
    &[0xff, 0xff, 0xff, 0x80, 0x80],
];

/// The final design of a server: surface control points and icons.
struct Design {
    points: Vec<[f64; 3]>,
    icons: Vec<Icon>,
}

impl Design {
    /// Waits until nothing is held, then reads the design.
    async fn settled(server: &RunningServer) -> Self {
        let (addr, token) = (server.addr, server.viewer_token.clone());
        let icons = eventually(15, || {
            let t = token.clone();
            async move {
                let icons = snapshot_icons(addr, &t).await;
                icons.iter().all(|i| i.holder.is_none()).then_some(icons)
            }
        })
        .await
        .expect("every icon released");
        let points = snapshot_points(addr, &server.viewer_token).await;
        Self { points, icons }
    }

    /// The largest coordinate difference to `other` (points and icons).
    fn gap(&self, other: &Design) -> f64 {
        assert_eq!(self.points.len(), other.points.len());
        assert_eq!(self.icons.len(), other.icons.len());
        let pts = self.points.iter().zip(&other.points);
        let ics = self
            .icons
            .iter()
            .zip(&other.icons)
            .map(|(a, b)| (&a.xyz, &b.xyz));
        pts.chain(ics)
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
            .fold(0.0, f64::max)
    }
}

/// Waits until icon `id` is held by the right hand.
async fn wait_held(server: &RunningServer, id: u64) {
    let (addr, token) = (server.addr, server.viewer_token.clone());
    let held = eventually(20, || {
        let t = token.clone();
        async move {
            let i = icon_now(addr, &t, id).await;
            (i.holder.is_some() && i.sensors.contains(&"right-hand".to_string())).then_some(())
        }
    })
    .await;
    assert!(held.is_some(), "icon {id} never held");
}

/// Waits until a geometry frame shows icon `id` with its z at least `z` (the
/// snapshot's icons change only at grabs and releases; frames follow every drag).
async fn wait_frame_above(
    frames: &mut tokio::sync::mpsc::UnboundedReceiver<vsculpt_protocol::GeometryFrame>,
    id: u64,
    z: f64,
) {
    let reached = tokio::time::timeout(Duration::from_secs(20), async {
        while let Some(f) = frames.recv().await {
            if f.icons.iter().any(|i| i.id == id && i.xyz[2] as f64 >= z) {
                return true;
            }
        }
        false
    })
    .await;
    assert_eq!(reached, Ok(true), "icon {id} never shown above z = {z}");
}

/// Moves the simulated hand from `from` to `to` in `steps`, 25 ms apart, injecting
/// garbage on the tracker line at each step when `noisy`.
async fn lift(studio: &Studio, from: DVec3, to: DVec3, steps: usize, noisy: bool) {
    for k in 1..=steps {
        studio.move_to(from + (to - from) * (k as f64 / steps as f64));
        if noisy {
            studio.tracker.inject(GARBAGE[k % GARBAGE.len()]);
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
}

/// Records a live session in `dir` (restart, resync, still hold); returns the
/// recording, the icon dragged, its start and the live final design.
async fn record_live(dir: &Path) -> (PathBuf, Icon, Design) {
    let data = dir.join("live-data");
    let server = RunningServer::start(&data, None).await;
    let addr = server.addr;
    let icon = position_icon(&snapshot_icons(server.addr, &server.viewer_token).await);
    let p = DVec3::from_array(icon.xyz);
    let studio = Studio::start(dir, p);
    let recording = dir.join("live.vsbrec");
    let config = bridge_config(dir, &server.device_url);
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let rec = recording.clone();
    let bridge = tokio::spawn(async move {
        run_live(
            config,
            Arc::new(ProtocolWire::default()),
            Some(&rec),
            async {
                let _ = stopped.await;
            },
        )
        .await
        .unwrap();
    });
    wait_bridge(&server).await;
    studio.close_hand(true);
    wait_held(&server, icon.id).await;
    let at = |dz: f64| p + DVec3::new(0.0, 0.0, dz);
    // lift 8 mm through a noisy line
    lift(&studio, at(0.0), at(8.0), 8, true).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    // the server goes down with the hand closed; the hand moves on; it comes back
    server.stop().await;
    lift(&studio, at(8.0), at(14.0), 6, false).await;
    let server = RunningServer::start(&data, Some(addr)).await;
    wait_held(&server, icon.id).await;
    lift(&studio, at(14.0), at(20.0), 6, false).await;
    // a still hold long enough for a restart in the middle of a replay
    tokio::time::sleep(Duration::from_millis(2500)).await;
    lift(&studio, at(20.0), at(24.0), 4, false).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    studio.close_hand(false);
    let live = Design::settled(&server).await;
    stop.send(()).unwrap();
    bridge.await.unwrap();
    server.stop().await;
    let done = live.icons.iter().find(|i| i.id == icon.id).unwrap();
    assert!(
        (done.xyz[2] - p.z - 24.0).abs() < 0.5,
        "live session left the icon at {:?}",
        done.xyz
    );
    assert_eq!(done.state, IconState::Passive);
    (recording, icon, live)
}

/// Replays `recording` into a server on `data` at `speed`, the way
/// `vsculpt-bridge --server URL replay FILE` does.
fn start_replay(url: String, recording: PathBuf, speed: f64) -> tokio::task::JoinHandle<u64> {
    tokio::spawn(async move {
        let mut config = Config::default();
        config.server.url = url;
        run_replay(
            config,
            Arc::new(ProtocolWire::default()),
            &recording,
            speed,
            std::future::pending(),
        )
        .await
        .unwrap()
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn replay_reproduces_a_session_with_server_restarts_and_resyncs() {
    init_logs();
    let dir = temp_dir("bridge-replay-restart");
    let (recording, icon, live) = record_live(&dir).await;
    let p = DVec3::from_array(icon.xyz);

    // 1. the session (restart while recording) replayed into a fresh server
    let fresh = RunningServer::start(&dir.join("fresh-data"), None).await;
    let n = start_replay(fresh.device_url.clone(), recording.clone(), 10.0)
        .await
        .unwrap();
    assert!(n > 100, "replayed {n} samples");
    let replayed = Design::settled(&fresh).await;
    fresh.stop().await;
    let gap = live.gap(&replayed);
    eprintln!("fresh replay vs live: {gap:e} mm");
    assert!(
        gap <= TOLERANCE,
        "fresh replay differs from the live session by {gap} mm"
    );

    // 2. replayed at speed 1 into a server restarted during the still hold
    let data = dir.join("restart-data");
    let server = RunningServer::start(&data, None).await;
    let addr = server.addr;
    let mut frames = watch_frames(server.addr, &server.viewer_token).await;
    let replay = start_replay(server.device_url.clone(), recording.clone(), 1.0);
    wait_frame_above(&mut frames, icon.id, p.z + 19.5).await;
    wait_held(&server, icon.id).await;
    server.stop().await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let server = RunningServer::start(&data, Some(addr)).await;
    let n = replay.await.unwrap();
    assert!(n > 100, "replayed {n} samples");
    let replayed = Design::settled(&server).await;
    server.stop().await;
    let gap = live.gap(&replayed);
    eprintln!("replay across a restart vs live: {gap:e} mm");
    assert!(
        gap <= TOLERANCE,
        "replay across a server restart differs from the live session by {gap} mm"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
