//! Parse throughput of every decoder over a stream of valid records, and the
//! latency from a record written on a pseudo-terminal to its sample leaving the
//! driver.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use std::hint::black_box;
use std::io::Write;
use std::time::{Duration, Instant};
use vsculpt_bridge::config::{DeviceConfig, DeviceKind, build_decoder};
use vsculpt_bridge::device::cyberglove::{self, CyberGloveSettings};
use vsculpt_bridge::device::flock::{FlockSettings, encode_record, pose_words};
use vsculpt_bridge::device::{Decoder, Device, SourceId, Timestamp, fastrak, spacenavd, vrpn};

const RECORDS: usize = 1000;

fn stream(kind: DeviceKind) -> (DeviceConfig, Vec<Vec<u8>>) {
    let mut cfg = DeviceConfig::new("bench", kind);
    let chunks: Vec<Vec<u8>> = match kind {
        DeviceKind::Flock => {
            let s = FlockSettings::default();
            (0..RECORDS)
                .map(|i| {
                    encode_record(
                        &pose_words(&s, DVec3::new(i as f64 * 1e-4, 0.1, 0.2), DQuat::IDENTITY),
                        None,
                        None,
                    )
                })
                .collect()
        }
        DeviceKind::Fastrak => (0..RECORDS)
            .map(|i| {
                fastrak::encode_record(1, b' ', [i as f32 * 1e-3, 1.0, 2.0], [1.0, 0.0, 0.0, 0.0])
                    .to_vec()
            })
            .collect(),
        DeviceKind::Cyberglove => {
            let s = CyberGloveSettings::default();
            (0..RECORDS)
                .map(|i| cyberglove::encode_record(&s, &[(i % 250) as u8 + 1; 22], None))
                .collect()
        }
        DeviceKind::Vrpn => {
            let mut first = vrpn::cookie().to_vec();
            first.extend(vrpn::encode_description(
                vrpn::SENDER_DESCRIPTION,
                0,
                "Tracker0",
            ));
            first.extend(vrpn::encode_description(
                vrpn::TYPE_DESCRIPTION,
                1,
                vrpn::POS_QUAT,
            ));
            let mut v = vec![first];
            v.extend((0..RECORDS).map(|i| {
                vrpn::encode_message(
                    0,
                    0,
                    0,
                    1,
                    &vrpn::encode_pos_quat(0, [i as f64, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
                )
            }));
            v
        }
        DeviceKind::Spacenavd => (0..RECORDS)
            .map(|i| spacenavd::encode_event([0, i as i32 % 350, 0, 0, 0, 0, 0, 8]).to_vec())
            .collect(),
        DeviceKind::SpacemouseHid => (0..RECORDS)
            .map(|i| {
                let mut r = vec![if i % 2 == 0 { 1 } else { 2 }];
                for v in [i as i16 % 350, 5, -5] {
                    r.extend_from_slice(&v.to_le_bytes());
                }
                r
            })
            .collect(),
    };
    cfg.port = Some("/dev/null".into());
    (cfg, chunks)
}

fn parse(c: &mut Criterion) {
    let mut g = c.benchmark_group("parse");
    for kind in [
        DeviceKind::Flock,
        DeviceKind::Fastrak,
        DeviceKind::Cyberglove,
        DeviceKind::Vrpn,
        DeviceKind::Spacenavd,
        DeviceKind::SpacemouseHid,
    ] {
        let (cfg, chunks) = stream(kind);
        let packet = kind == DeviceKind::SpacemouseHid;
        let joined: Vec<u8> = chunks.concat();
        g.throughput(Throughput::Elements(RECORDS as u64));
        g.bench_function(kind.name(), |b| {
            let mut out = Vec::with_capacity(RECORDS);
            b.iter(|| {
                let mut d: Box<dyn Decoder> = build_decoder(SourceId(0), &cfg);
                out.clear();
                if packet {
                    for r in &chunks {
                        d.feed(r, Timestamp(0), &mut out);
                    }
                } else {
                    // serial-like 64-byte reads
                    for c in joined.chunks(64) {
                        d.feed(c, Timestamp(0), &mut out);
                    }
                }
                assert!(out.len() >= RECORDS);
                black_box(&out);
            })
        });
    }
    g.finish();
}

/// Latency: a Flock record written on the pty master until the driver returns its sample.
fn pty_latency(c: &mut Criterion) {
    let (mut master, slave) = serialport::TTYPort::pair().expect("pty");
    let path = serialport::SerialPort::name(&slave).expect("pty name");
    let mut cfg = DeviceConfig::new("flock", DeviceKind::Flock);
    cfg.port = Some(path);
    // Open without the set-up script: the bench plays the device itself.
    let mut script_free = vsculpt_bridge::device::Driver::new(
        "flock",
        SourceId(0),
        Box::new(vsculpt_bridge::device::transport::SerialTransport::new(
            cfg.port.clone().unwrap_or_default(),
            115200,
        )),
        build_decoder(SourceId(0), &cfg),
        Default::default(),
    );
    script_free.open().expect("open pty");
    let rec = encode_record(
        &pose_words(&FlockSettings::default(), DVec3::X * 0.1, DQuat::IDENTITY),
        None,
        None,
    );
    let mut out = Vec::new();
    c.bench_function("latency/flock_record_on_pty_to_sample", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                out.clear();
                let t = Instant::now();
                master.write_all(&rec).expect("write");
                while out.is_empty() {
                    script_free
                        .read(Duration::from_millis(100), &mut out)
                        .expect("read");
                }
                total += t.elapsed();
            }
            total
        })
    });
    drop(slave);
}

criterion_group!(benches, parse, pty_latency);
criterion_main!(benches);
