//! Supervision in the bridge: a device whose code panics is restarted with
//! backoff (and the server is told why through its status), and a link task
//! that panics is restarted and reconnects. The faults come from test code
//! plugged in through the public `Device` and `Wire` traits.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use vsculpt_bridge::device::driver::{DecodeStats, Device, DeviceError};
use vsculpt_bridge::device::runner::{DeviceRunner, DeviceStatus, RunOptions};
use vsculpt_bridge::device::{Reading, Sample, SourceId, Timestamp};
use vsculpt_bridge::interaction::Command;
use vsculpt_bridge::link::{Link, LinkOptions, ServerEvent, Wire};
use vsculpt_bridge::wire::ProtocolWire;

/// A device whose 3rd and 6th reads panic (a decoder bug); every other read
/// gives one button sample numbered by the read.
struct Flaky {
    reads: u32,
}

impl Device for Flaky {
    fn name(&self) -> &str {
        "flaky"
    }
    fn open(&mut self) -> Result<(), DeviceError> {
        Ok(())
    }
    fn read(&mut self, _timeout: Duration, out: &mut Vec<Sample>) -> Result<(), DeviceError> {
        self.reads += 1;
        if self.reads == 3 || self.reads == 6 {
            panic!("decoder bug at read {}", self.reads);
        }
        std::thread::sleep(Duration::from_millis(2));
        out.push(Sample {
            source: SourceId(0),
            time: Timestamp::now(),
            reading: Reading::Button {
                button: self.reads as u16,
                pressed: true,
            },
        });
        Ok(())
    }
    fn close(&mut self) {}
    fn stats(&self) -> DecodeStats {
        DecodeStats::default()
    }
}

#[test]
fn a_panicking_device_is_restarted_and_reported() {
    let (tx, rx) = mpsc::channel::<u16>();
    let (stx, srx) = mpsc::channel::<DeviceStatus>();
    let options = RunOptions {
        backoff_min: Duration::from_millis(10),
        silence: None,
        ..Default::default()
    };
    let mut runner = DeviceRunner::spawn_with_status(
        Box::new(Flaky { reads: 0 }),
        options,
        move |s| {
            s.iter().all(|s| match s.reading {
                Reading::Button { button, .. } => tx.send(button).is_ok(),
                _ => true,
            })
        },
        move |st| {
            let _ = stx.send(st);
        },
    );
    // Samples from reads past both panics arrive.
    let end = Instant::now() + Duration::from_secs(30);
    let mut last = 0;
    while last < 8 && Instant::now() < end {
        if let Ok(b) = rx.recv_timeout(Duration::from_millis(100)) {
            last = b;
        }
    }
    runner.stop();
    assert!(
        last >= 8,
        "the device stopped delivering after a panic (last read {last})"
    );
    assert_eq!(runner.stats().panics.load(Ordering::Relaxed), 2);
    let lost: Vec<String> = srx
        .try_iter()
        .filter_map(|s| match s {
            DeviceStatus::Lost(m) => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(lost.len(), 2, "{lost:?}");
    assert!(
        lost[0].starts_with("device task failed (decoder bug at read 3); restarting in "),
        "{lost:?}"
    );
}

/// The protocol wire, except that decoding the first server message panics.
struct PanicsOnce {
    armed: AtomicBool,
    hellos: AtomicU32,
    inner: ProtocolWire,
}

impl Wire for PanicsOnce {
    fn hello(&self, token: &str, design: Option<u64>) -> String {
        self.hellos.fetch_add(1, Ordering::SeqCst);
        self.inner.hello(token, design)
    }
    fn encode(&self, cmd: &Command, ordered: bool) -> Vec<String> {
        self.inner.encode(cmd, ordered)
    }
    fn decode(&self, text: &str) -> Result<Vec<ServerEvent>, String> {
        if self.armed.swap(false, Ordering::SeqCst) {
            panic!("wire bug");
        }
        self.inner.decode(text)
    }
    fn decode_binary(&self, bytes: &[u8]) -> Vec<ServerEvent> {
        self.inner.decode_binary(bytes)
    }
    fn accepts(&self, event: &ServerEvent) -> bool {
        self.inner.accepts(event)
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_panicking_link_task_is_restarted_and_reconnects() {
    let dir = tempfile::tempdir().unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let config =
        vsculpt_server::config::Config::new(dir.path().join("data"), dir.path().join("web"));
    let shutdown = vsculpt_server::shutdown::Shutdown::new();
    let server = vsculpt_server::server::Server::start(listener, config, shutdown.clone())
        .await
        .unwrap();
    let addr = server.local_addr();
    let token = server.designs().unwrap()[0].tokens.device.clone();
    let serving = tokio::spawn(server.run());

    let wire = Arc::new(PanicsOnce {
        inner: ProtocolWire::default(),
        armed: AtomicBool::new(true),
        hellos: AtomicU32::new(0),
    });
    let (etx, mut events) = tokio::sync::mpsc::unbounded_channel();
    let mut o = LinkOptions::new(format!("ws://{addr}/ws?design=1&token={token}"));
    o.backoff_min = Duration::from_millis(20);
    let link = Link::spawn(o, wire.clone(), etx);
    let connected = tokio::time::timeout(Duration::from_secs(30), async {
        while let Some(ev) = events.recv().await {
            if ev == ServerEvent::Connected {
                return true;
            }
        }
        false
    })
    .await;
    assert_eq!(
        connected,
        Ok(true),
        "the link never connected after its panic"
    );
    let stats = link.stats();
    assert_eq!(stats.restarts, 1);
    assert_eq!(stats.connections, 1);
    assert_eq!(wire.hellos.load(Ordering::SeqCst), 2);
    drop(link);
    shutdown.trigger();
    serving.await.unwrap().unwrap();
}
