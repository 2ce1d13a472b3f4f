//! VRPN as studios run it, against a fake server written from VRPN's wire format
//! (`independent`): the bridge pings the way VRPN clients do and a server that
//! answers stays up while its tracker is still; a server that hangs with the
//! connection open is reported lost (so a grab is released) within a second; a
//! tracker name the server does not serve is reported with the names it serves.

mod independent;

use independent::*;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use vsculpt_bridge::bridge::{VRPN_SILENCE, run_options};
use vsculpt_bridge::config::{DeviceConfig, DeviceKind, build_driver};
use vsculpt_bridge::device::SourceId;
use vsculpt_bridge::device::runner::{DeviceRunner, DeviceStatus};
use vsculpt_bridge::device::vrpn::PING_INTERVAL;

/// What the fake server does after the handshake.
#[derive(Clone, Copy, PartialEq)]
enum Then {
    /// Answers every ping with a pong and sends no poses.
    Pong,
    /// Sends nothing more, keeps the connection open.
    Hang,
}

/// Reads one VRPN message from the client: (sender, type, payload).
fn read_message(s: &mut TcpStream) -> Option<(i32, i32, Vec<u8>)> {
    let mut h = [0u8; 24];
    s.read_exact(&mut h).ok()?;
    let be = |i: usize| i32::from_be_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
    let len = be(0) as usize;
    let mut body = vec![0u8; (len - 24).div_ceil(8) * 8];
    s.read_exact(&mut body).ok()?;
    body.truncate(len - 24);
    Some((be(12), be(16), body))
}

/// Serves `senders` on loopback; reports every client message to `seen`.
fn fake_server(
    senders: &'static [&'static str],
    then: Then,
    seen: mpsc::Sender<(i32, i32, Vec<u8>)>,
) -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for conn in l.incoming() {
            let Ok(mut s) = conn else { return };
            let mut cookie = [0u8; 24];
            if s.read_exact(&mut cookie).is_err() || !cookie.starts_with(b"vrpn: ver. 07.") {
                continue;
            }
            let mut out = vrpn_cookie();
            for (i, name) in senders.iter().enumerate() {
                out.extend(vrpn_description(-1, i as i32, name));
            }
            out.extend(vrpn_description(-2, 0, "vrpn_Tracker Pos_Quat"));
            out.extend(vrpn_description(-2, 1, "vrpn_Base pong_message"));
            for _ in 0..5 {
                out.extend(vrpn_message(
                    0,
                    0,
                    &vrpn_pos_quat(0, [0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 1.0]),
                ));
            }
            if s.write_all(&out).is_err() {
                continue;
            }
            let mut client_ping: Option<i32> = None;
            let mut client_types = std::collections::HashMap::new();
            while let Some((sender, kind, payload)) = read_message(&mut s) {
                if kind == -2 && payload.len() > 4 {
                    let name = String::from_utf8_lossy(&payload[4..payload.len() - 1]).into_owned();
                    if name == "vrpn_Base ping_message" {
                        client_ping = Some(sender);
                    }
                    client_types.insert(sender, name);
                }
                let is_ping = kind >= 0 && Some(kind) == client_ping;
                let _ = seen.send((sender, kind, payload));
                if is_ping && then == Then::Pong {
                    let _ = s.write_all(&vrpn_message(0, 1, &[]));
                }
            }
        }
    });
    port
}

fn vrpn(address: String) -> DeviceConfig {
    let mut d = DeviceConfig::new("studio", DeviceKind::Vrpn);
    d.address = Some(address);
    d
}

fn run(
    d: &DeviceConfig,
) -> (
    DeviceRunner,
    mpsc::Receiver<(Instant, DeviceStatus)>,
    mpsc::Receiver<Instant>,
) {
    let (st_tx, st) = mpsc::channel();
    let (s_tx, samples) = mpsc::channel();
    let runner = DeviceRunner::spawn_with_status(
        Box::new(build_driver(SourceId(0), d)),
        run_options(d.kind),
        move |_| s_tx.send(Instant::now()).is_ok(),
        move |s| {
            let _ = st_tx.send((Instant::now(), s));
        },
    );
    (runner, st, samples)
}

#[test]
fn a_hung_server_is_lost_within_a_second_an_answering_one_is_not() {
    // the bridge's budget: noticed after the silence threshold plus at most one
    // read, under a second; a healthy idle server answers several pings meanwhile
    let o = run_options(DeviceKind::Vrpn);
    assert_eq!(o.silence, Some(VRPN_SILENCE));
    assert!(VRPN_SILENCE + o.read_timeout < Duration::from_secs(1));
    assert!(PING_INTERVAL * 3 < VRPN_SILENCE);

    let (seen_tx, seen) = mpsc::channel();
    let port = fake_server(&["Tracker0"], Then::Hang, seen_tx);
    let (_runner, status, samples) = run(&vrpn(format!("Tracker0@127.0.0.1:{port}")));
    let first = samples.recv_timeout(Duration::from_secs(5)).expect("poses");
    let lost = loop {
        match status
            .recv_timeout(Duration::from_secs(10))
            .expect("the hung server is noticed")
        {
            (t, DeviceStatus::Lost(why)) => break (t, why),
            _ => continue,
        }
    };
    assert!(lost.1.contains("nothing valid received"), "{}", lost.1);
    assert!(lost.0 > first);
    // the client pinged the way VRPN clients do: its sender and the ping type
    // described first, then empty messages of that type from that sender
    let msgs: Vec<_> = seen.try_iter().collect();
    let sender = msgs
        .iter()
        .find(|m| m.1 == -1 && m.2.ends_with(b"Tracker0\0"))
        .expect("sender description")
        .0;
    let ping = msgs
        .iter()
        .find(|m| m.1 == -2 && m.2.ends_with(b"vrpn_Base ping_message\0"))
        .expect("type description")
        .0;
    assert!(
        msgs.iter()
            .any(|m| m.0 == sender && m.1 == ping && m.2.is_empty())
    );

    // a server that answers the pings keeps the device open without any pose
    let (seen_tx, _seen) = mpsc::channel();
    let port = fake_server(&["Tracker0"], Then::Pong, seen_tx);
    let (_runner, status, samples) = run(&vrpn(format!("Tracker0@tcp://127.0.0.1:{port}")));
    samples.recv_timeout(Duration::from_secs(5)).expect("poses");
    // three silence thresholds without a pose
    std::thread::sleep(VRPN_SILENCE * 3);
    let lost: Vec<_> = status
        .try_iter()
        .filter(|s| matches!(s.1, DeviceStatus::Lost(_)))
        .collect();
    assert!(
        lost.is_empty(),
        "{:?}",
        lost.iter().map(|l| &l.1).collect::<Vec<_>>()
    );
}

#[test]
fn an_unknown_tracker_name_is_reported_with_the_names_served() {
    let (seen_tx, _seen) = mpsc::channel();
    let port = fake_server(&["Tracker0", "Button0"], Then::Pong, seen_tx);
    let (_runner, status, _samples) = run(&vrpn(format!("Tracker9@127.0.0.1:{port}")));
    let why = loop {
        match status
            .recv_timeout(Duration::from_secs(10))
            .expect("reported")
        {
            (_, DeviceStatus::Lost(w)) | (_, DeviceStatus::Unavailable(w)) => break w,
            _ => continue,
        }
    };
    assert!(
        why.contains("serves no device \"Tracker9\"; it serves: Button0, Tracker0"),
        "{why}"
    );
}

#[test]
fn vrpn_addresses_as_studios_write_them() {
    let t = |a: &str| vrpn(a.into()).vrpn_target();
    assert_eq!(
        t("Tracker0@127.0.0.1"),
        Ok(("Tracker0".into(), "127.0.0.1:3883".into()))
    );
    assert_eq!(
        t("Tracker1@host:4000"),
        Ok(("Tracker1".into(), "host:4000".into()))
    );
    assert_eq!(
        t("Tracker0@tcp://host:3884"),
        Ok(("Tracker0".into(), "host:3884".into()))
    );
    assert_eq!(t("Head@tcp:host"), Ok(("Head".into(), "host:3883".into())));
    assert_eq!(
        t("Tracker0@[::1]:3884"),
        Ok(("Tracker0".into(), "[::1]:3884".into()))
    );
    assert_eq!(t("[::1]"), Ok(("Tracker0".into(), "[::1]:3883".into())));
    assert_eq!(
        t("vrpnhost"),
        Ok(("Tracker0".into(), "vrpnhost:3883".into()))
    );
    for bad in [
        "@host",
        "Tracker0@",
        "Tracker0@udp://host",
        "host:99999",
        "Tracker0@[::1",
    ] {
        assert!(t(bad).is_err(), "{bad}");
    }
    // a name in the address wins over vrpn.device
    let mut d = vrpn("Wand@host".into());
    d.vrpn.device = "Tracker0".into();
    assert_eq!(d.vrpn_target().unwrap().0, "Wand");
}
