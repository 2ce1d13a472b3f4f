//! The bridge's own runtime ([`vsculpt_bridge::bridge::runtime`], one thread):
//! a live session runs on it to its end — the device threads stopped, the
//! recording written — with nothing blocking left on the runtime's thread
//! (`block_in_place` panics on a one-thread runtime).

use glam::{DQuat, DVec3};
use std::sync::Arc;
use std::time::Duration;
use vsculpt_bridge::bridge::{Input, run_live, runtime};
use vsculpt_bridge::config::{Config, DeviceConfig, DeviceKind};
use vsculpt_bridge::recording::Replayer;
use vsculpt_bridge::sim::flock::FlockSim;
use vsculpt_bridge::sim::pty::PtySim;
use vsculpt_bridge::wire::ProtocolWire;

#[test]
fn a_live_session_on_the_bridge_runtime_stops_and_writes_its_recording() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("tracker");
    let mut flock = FlockSim::new(1, false, Duration::from_millis(2));
    flock.set_pose(0, DVec3::new(0.1, 0.2, 0.3), DQuat::IDENTITY);
    let sim = PtySim::start(flock, &link).unwrap();
    let mut device = DeviceConfig::new("tracker", DeviceKind::Flock);
    device.port = Some(link.display().to_string());
    device.settle_ms = 10;
    let config = Config {
        devices: vec![device],
        ..Default::default()
    };
    config.validate().unwrap();
    let recording = dir.path().join("session.vsbrec");

    let rt = runtime().unwrap();
    let session = rt.block_on(run_live(
        config,
        Arc::new(ProtocolWire::default()),
        Some(&recording),
        async {
            // until the tracker streams, then a little longer for records
            while !sim.device().streaming {
                tokio::time::sleep(Duration::from_millis(10)).await;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        },
    ));
    session.unwrap();

    // the device thread was stopped and the recording finished: it holds the
    // session's tracker records, which decode to the simulated pose
    let mut poses = Vec::new();
    Replayer::open(&recording)
        .unwrap()
        .play(1000.0, |input| {
            if let Input::Samples(batch) = input {
                poses.extend(batch);
            }
            true
        })
        .unwrap();
    assert!(!poses.is_empty(), "no tracker record was recorded");
    for s in &poses {
        let vsculpt_bridge::device::Reading::Pose { position, .. } = s.reading else {
            panic!("a tracker sample that is no pose: {s:?}");
        };
        assert!(
            (position - DVec3::new(0.1, 0.2, 0.3)).length() < 1e-3,
            "{position}"
        );
    }
}
