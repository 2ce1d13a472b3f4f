//! VRPN over UDP, against a fake server written from VRPN's sources
//! (`vrpn_Connection.C`; generators in `independent`): the bridge connects over
//! TCP, sends its cookie and a UDP description (type −3, the port in the sender
//! field, its IP address as a NUL-terminated string); the server answers with its
//! cookie and descriptions over TCP and then sends tracker reports as UDP
//! datagrams to that port, one or several messages per datagram. Datagrams that
//! arrive twice or late (by the channel's sequence number, or by time from a
//! server that leaves the number 0) and malformed ones are dropped; the poses
//! that come out are exactly the in-order ones. `Tracker0@tcp://` stays TCP-only.

mod independent;

use independent::*;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream, UdpSocket};
use std::time::{Duration, Instant};
use vsculpt_bridge::config::{DeviceConfig, DeviceKind, build_driver};
use vsculpt_bridge::device::{Device, Reading, Sample, SourceId};

/// Reads one VRPN message from the client: (sender, type, payload).
fn read_message(s: &mut TcpStream) -> (i32, i32, Vec<u8>) {
    let mut h = [0u8; 24];
    s.read_exact(&mut h).unwrap();
    let be = |i: usize| i32::from_be_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
    let len = be(0) as usize;
    let mut body = vec![0u8; (len - 24).div_ceil(8) * 8];
    s.read_exact(&mut body).unwrap();
    body.truncate(len - 24);
    (be(12), be(16), body)
}

/// A fake server's side of the handshake: returns the client's TCP stream and the
/// UDP address it announced (or `None` when it announced none before a ping).
fn accept(l: &TcpListener) -> (TcpStream, Option<std::net::SocketAddr>) {
    let (mut s, _) = l.accept().unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut cookie = [0u8; 24];
    s.read_exact(&mut cookie).unwrap();
    assert!(cookie.starts_with(b"vrpn: ver. 07."));
    let mut out = vrpn_cookie();
    out.extend(vrpn_description(-1, 0, "Tracker0"));
    out.extend(vrpn_description(-2, 3, "vrpn_Tracker Pos_Quat"));
    s.write_all(&out).unwrap();
    // the client's messages until its first ping (sender/type descriptions, ping)
    let mut udp = None;
    loop {
        let (sender, kind, payload) = read_message(&mut s);
        match kind {
            -3 => {
                let ip = std::str::from_utf8(&payload[..payload.len() - 1]).unwrap();
                assert_eq!(payload.last(), Some(&0), "NUL-terminated host");
                udp = Some(format!("{ip}:{sender}").parse().unwrap());
            }
            k if k >= 0 => return (s, udp),
            _ => {}
        }
    }
}

fn pose(seq: u32, usec: u32, x: f64) -> Vec<u8> {
    vrpn_udp_message(
        seq,
        7,
        usec,
        0,
        3,
        &vrpn_pos_quat(0, [x, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
    )
}

/// Reads from `d` until `n` poses came or `secs` pass; their x.
fn read_poses(d: &mut dyn Device, n: usize, secs: u64) -> Vec<f64> {
    let mut out: Vec<Sample> = Vec::new();
    let end = Instant::now() + Duration::from_secs(secs);
    let mut xs = Vec::new();
    while xs.len() < n && Instant::now() < end {
        out.clear();
        d.read(Duration::from_millis(50), &mut out).unwrap();
        for s in &out {
            if let Reading::Pose { position, .. } = s.reading {
                xs.push(position.x);
            }
        }
    }
    xs
}

#[test]
fn tracker_reports_over_udp_in_order_only() {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some(format!("Tracker0@127.0.0.1:{port}"));
    let mut d = build_driver(SourceId(0), &cfg);
    let server = std::thread::spawn(move || accept(&l));
    d.open().unwrap();
    // the first read lets the client's first ping out
    let mut out = Vec::new();
    d.read(Duration::from_millis(300), &mut out).unwrap();
    let (_tcp, udp_to) = server.join().unwrap();
    let udp_to = udp_to.expect("the client announced a UDP port");
    assert_eq!(udp_to.ip().to_string(), "127.0.0.1");
    let udp = UdpSocket::bind("127.0.0.1:0").unwrap();
    let datagrams: Vec<Vec<u8>> = vec![
        pose(10, 100, 1.0),
        pose(10, 100, 1.0),                                // duplicate: dropped
        [pose(11, 200, 2.0), pose(12, 300, 3.0)].concat(), // two messages in one
        pose(11, 200, 2.0),                                // late: dropped
        pose(9, 50, 0.5),                                  // older still: dropped
        pose(13, 400, 4.0)[..40].to_vec(),                 // truncated: dropped whole
        [pose(14, 500, 5.0), vec![0xff; 24]].concat(),     // bad second message: all dropped
        pose(15, 600, 6.0),
    ];
    for g in &datagrams {
        udp.send_to(g, udp_to).unwrap();
        // keep the order on loopback
        std::thread::sleep(Duration::from_millis(5));
    }
    let xs = read_poses(&mut d, 4, 5);
    assert_eq!(xs, vec![1.0, 2.0, 3.0, 6.0]);
    // nothing more comes
    assert!(read_poses(&mut d, 1, 1).is_empty());
    let st = d.stats();
    assert_eq!(st.records, 4);
    assert_eq!(st.stale, 3);
    assert_eq!(st.rejected_records, 2);
    // datagrams from another host's port are not the server's: a foreign sender
    // on another address is ignored (here: 127.0.0.2, when the system has it)
    if let Ok(other) = UdpSocket::bind("127.0.0.2:0") {
        other.send_to(&pose(16, 700, 7.0), udp_to).unwrap();
        assert!(read_poses(&mut d, 1, 1).is_empty());
    }
}

#[test]
fn a_server_that_leaves_the_sequence_at_zero_is_ordered_by_time() {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some(format!("Tracker0@127.0.0.1:{port}"));
    let mut d = build_driver(SourceId(0), &cfg);
    let server = std::thread::spawn(move || accept(&l));
    d.open().unwrap();
    let mut out = Vec::new();
    d.read(Duration::from_millis(300), &mut out).unwrap();
    let (_tcp, udp_to) = server.join().unwrap();
    let udp = UdpSocket::bind("127.0.0.1:0").unwrap();
    for g in [
        pose(0, 100, 1.0),
        pose(0, 300, 3.0),
        pose(0, 200, 2.0),
        pose(0, 300, 3.0),
        pose(0, 400, 4.0),
    ] {
        udp.send_to(&g, udp_to.unwrap()).unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(read_poses(&mut d, 3, 5), vec![1.0, 3.0, 4.0]);
}

#[test]
fn tcp_only_addresses_announce_no_udp_port() {
    let l = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = l.local_addr().unwrap().port();
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some(format!("Tracker0@tcp://127.0.0.1:{port}"));
    let mut d = build_driver(SourceId(0), &cfg);
    let server = std::thread::spawn(move || accept(&l));
    d.open().unwrap();
    let mut out = Vec::new();
    d.read(Duration::from_millis(300), &mut out).unwrap();
    let (mut tcp, udp_to) = server.join().unwrap();
    assert_eq!(udp_to, None);
    // reports on TCP still arrive
    tcp.write_all(&pose(0, 100, 1.5)).unwrap();
    assert_eq!(read_poses(&mut d, 1, 5), vec![1.5]);
    // and `udp = false` does the same for a plain address
    let mut cfg = DeviceConfig::new("studio", DeviceKind::Vrpn);
    cfg.address = Some("Tracker0@127.0.0.1".into());
    assert!(cfg.vrpn_udp());
    cfg.vrpn.udp = false;
    assert!(!cfg.vrpn_udp());
}
