//! The binary's command line: `--list` works with no hardware at all, a bad
//! configuration or speed is a clear error (exit code, message), and `replay`
//! of a recording without a server plays it through and exits.

use std::process::Command;
use vsculpt_bridge::config::{DeviceConfig, DeviceKind};
use vsculpt_bridge::device::flock::{FlockSettings, encode_record, pose_words};
use vsculpt_bridge::device::{RawFrame, SourceId, TapEvent, Timestamp};
use vsculpt_bridge::recording::Recorder;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vsculpt-bridge"))
}

fn temp(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("vsculpt-cli-{}-{name}", std::process::id()))
}

#[test]
fn list_without_hardware_succeeds() {
    let out = bin()
        .arg("--list")
        .env("SPNAV_SOCKET", "/nonexistent/spnav.sock")
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("HID devices"), "{text}");
    assert!(text.contains("serial ports"), "{text}");
    assert!(
        text.contains("spacenavd: /nonexistent/spnav.sock (not running)"),
        "{text}"
    );
    assert!(text.contains("VRPN sources: 0"), "{text}");
}

#[test]
fn bad_configuration_and_speed_are_errors() {
    let cfg = temp("bad.toml");
    std::fs::write(&cfg, "[[device]]\nname = \"t\"\nkind = \"flock\"\n").unwrap();
    let out = bin()
        .arg("--config")
        .arg(&cfg)
        .arg("--list")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("needs `port`"));
    let out = bin()
        .args(["replay", "/nonexistent.vsbrec", "--speed", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("speed"));
    let out = bin()
        .args(["replay", "/nonexistent.vsbrec"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn replay_without_a_server_plays_and_exits() {
    let rec = temp("play.vsbrec");
    let mut d = DeviceConfig::new("tracker", DeviceKind::Flock);
    d.port = Some("/dev/null".into());
    let config = vsculpt_bridge::config::Config {
        devices: vec![d],
        ..Default::default()
    };
    let r = Recorder::create(&rec, &config).unwrap();
    let bytes = encode_record(
        &pose_words(
            &FlockSettings::default(),
            glam::DVec3::X * 0.1,
            glam::DQuat::IDENTITY,
        ),
        None,
        None,
    );
    for i in 0..10u64 {
        r.tap()
            .send(TapEvent::Frame(RawFrame {
                source: SourceId(0),
                time: Timestamp(i * 10_000),
                bytes: bytes.clone(),
            }))
            .unwrap();
    }
    r.finish().unwrap();
    let out = bin()
        .args(["replay", "--speed", "10"])
        .arg(&rec)
        .env("RUST_LOG", "info")
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("samples=10"),
        "{out:?}"
    );
}
