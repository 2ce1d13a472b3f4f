//! Messages that say what to do: the example configuration documents every
//! setting the code reads (and is valid), a glove off its box says so, and
//! `check-config` validates a file and prints the effective settings.

mod independent;

use independent::*;
use std::collections::BTreeSet;
use std::process::Command;
use vsculpt_bridge::config::{Config, DeviceConfig, DeviceKind, HandConfig, build_decoder};
use vsculpt_bridge::device::{SourceId, Timestamp};
use vsculpt_bridge::hand::GloveCalibration;

const EXAMPLE: &str = include_str!("../vsculpt-bridge.example.toml");

fn keys(v: &toml::Value, out: &mut BTreeSet<String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                // menu buttons are numbered, not named settings
                if k.parse::<u16>().is_err() {
                    out.insert(k.clone());
                }
                keys(v, out);
            }
        }
        toml::Value::Array(a) => a.iter().for_each(|v| keys(v, out)),
        _ => {}
    }
}

#[test]
fn the_example_documents_every_setting_the_code_reads() {
    // every key the code serialises, for a device of every kind, a hand and the rest
    let mut devices = Vec::new();
    for (i, kind) in [
        DeviceKind::Flock,
        DeviceKind::Fastrak,
        DeviceKind::Cyberglove,
        DeviceKind::SpacemouseHid,
        DeviceKind::Spacenavd,
        DeviceKind::Vrpn,
    ]
    .into_iter()
    .enumerate()
    {
        let mut d = DeviceConfig::new(format!("d{i}"), kind);
        d.port = Some("/dev/x".into());
        d.baud = Some(115_200);
        d.address = Some("Tracker0@host".into());
        d.spacemouse.path = Some("/dev/hidraw0".into());
        d.spacenavd.socket = Some("/s".into());
        devices.push(d);
    }
    let mut c = Config {
        devices,
        hands: vec![HandConfig {
            name: "right".into(),
            tracker: "d0".into(),
            sensor: 0,
            glove: Some("d2".into()),
            reach: 0.05,
            calibration: GloveCalibration::default(),
        }],
        ..Default::default()
    };
    c.server.token = Some("t".into());
    c.server.design = Some(1);
    c.menu.device = Some("d3".into());
    c.validate().unwrap();
    let mut read = BTreeSet::new();
    keys(&toml::from_str(&c.to_toml()).unwrap(), &mut read);
    let missing: Vec<&String> = read
        .iter()
        .filter(|k| {
            !EXAMPLE.contains(&format!("{k} ="))
                && !EXAMPLE.contains(&format!("[{k}]"))
                && !EXAMPLE.contains(&format!("[[{k}]]"))
        })
        .collect();
    assert!(
        missing.is_empty(),
        "the example does not mention {missing:?}"
    );
    assert!(read.len() > 50, "{read:?}");
    // and what it sets is valid
    Config::parse(EXAMPLE).unwrap();
}

#[test]
fn a_glove_off_its_box_says_so() {
    let mut d = DeviceConfig::new("glove", DeviceKind::Cyberglove);
    d.port = Some("/dev/x".into());
    let mut dec = build_decoder(SourceId(0), &d);
    let mut out = Vec::new();
    dec.feed(&glove(100), Timestamp(0), &mut out);
    assert_eq!(out.len(), 1);
    assert!(dec.fatal().is_none());
    // the reply with the error pair 'e','g' (glove unplugged), asr_cyberglove_lib
    let mut off = vec![b'G'];
    off.extend([100u8; 22]);
    off.extend([b'e', b'g', 0]);
    dec.feed(&off, Timestamp(1), &mut out);
    assert_eq!(out.len(), 1, "no reading from a glove off its box");
    let why = dec.fatal().expect("reported");
    assert!(why.contains("not plugged into its box"), "{why}");
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vsculpt-bridge"))
}

#[test]
fn check_config_prints_the_effective_settings_or_says_what_is_wrong() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let good = dir.join(format!("check-good-{}.toml", std::process::id()));
    std::fs::write(&good, EXAMPLE).unwrap();
    let out = bin().arg("check-config").arg(&good).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{out:?}");
    assert!(text.contains("valid — 3 device(s), 1 hand(s)"), "{text}");
    // defaults filled in, the token hidden
    assert!(text.contains("drag_hz = 120.0"), "{text}");
    assert!(text.contains("max_acceleration = 10.0"), "{text}");
    assert!(text.contains("token=<hidden>"), "{text}");
    assert!(!text.contains("REPLACE-WITH-DEVICE-TOKEN"), "{text}");

    let bad = dir.join(format!("check-bad-{}.toml", std::process::id()));
    std::fs::write(&bad, EXAMPLE.replace("baud = 115200", "baud = 11520")).unwrap();
    let out = bin().arg("check-config").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("baud 11520 is not a standard rate; did you mean 115200?"),
        "{err}"
    );
    let _ = std::fs::remove_file(&good);
    let _ = std::fs::remove_file(&bad);

    // --help names the configuration file, its keys and the example
    let out = bin().arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "vsculpt-bridge.toml",
        "vsculpt-bridge.example.toml",
        "check-config",
        "drag_hz",
        "poll_hz",
        "Tracker0@tcp://host:port",
    ] {
        assert!(help.contains(needle), "{needle}: {help}");
    }
}
