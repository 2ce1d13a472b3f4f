//! A log writer that can never hurt the program that logs.
//!
//! Every formatted line is handed to a bounded queue with `try_send` and
//! written by one background thread. The logging code therefore never
//! blocks (a full queue drops the line), never fails (a sink that answers
//! `EPIPE`, `ENOSPC` or anything else drops the line) and never panics (a sink
//! that panics is caught, the line dropped, the thread goes on). Every line
//! that did not reach the sink is counted in [`LossyWriter::dropped`].
//!
//! Why not `tracing_appender::non_blocking`: its worker ignores write errors
//! without counting them, and its guard reports a slow shutdown with
//! `eprintln!`/`println!` from `Drop` — which panics exactly when the log
//! reader has gone away, the case this writer exists for.

use std::io::{self, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::time::{Duration, Instant};

/// Lines queued for the writer thread before new lines are dropped.
pub const QUEUE_LINES: usize = 8192;

enum Msg {
    Line(Vec<u8>),
    Flush(SyncSender<()>),
}

/// The cloneable front of the writer: `tracing_subscriber`'s `MakeWriter`.
#[derive(Clone, Debug)]
pub struct LossyWriter {
    tx: SyncSender<Msg>,
    dropped: Arc<AtomicU64>,
}

impl LossyWriter {
    /// Starts the writer thread over `sink` with a queue of `capacity` lines;
    /// dropped lines are added to `dropped`.
    pub fn spawn(
        sink: Box<dyn Write + Send>,
        capacity: usize,
        dropped: Arc<AtomicU64>,
    ) -> io::Result<Self> {
        let (tx, rx) = sync_channel(capacity.max(1));
        let counter = dropped.clone();
        std::thread::Builder::new()
            .name("log writer".into())
            .spawn(move || drain(rx, sink, &counter))?;
        Ok(Self { tx, dropped })
    }

    /// Lines that never reached the sink (queue full, write failed, sink
    /// panicked), since start.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Waits until every line queued so far is written (or dropped) and the
    /// sink flushed, at most `timeout`; true when that happened in time.
    pub fn flush(&self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let (ack_tx, ack_rx) = sync_channel(1);
        let mut msg = Msg::Flush(ack_tx);
        loop {
            match self.tx.try_send(msg) {
                Ok(()) => break,
                Err(TrySendError::Disconnected(_)) => return false,
                Err(TrySendError::Full(m)) => {
                    if Instant::now() >= deadline {
                        return false;
                    }
                    msg = m;
                    std::thread::sleep(Duration::from_millis(2));
                }
            }
        }
        ack_rx
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            .is_ok()
    }
}

fn drain(rx: Receiver<Msg>, mut sink: Box<dyn Write + Send>, dropped: &AtomicU64) {
    while let Ok(msg) = rx.recv() {
        match msg {
            Msg::Line(line) => {
                let written = catch_unwind(AssertUnwindSafe(|| sink.write_all(&line)));
                if !matches!(written, Ok(Ok(()))) {
                    dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            Msg::Flush(ack) => {
                let _ = catch_unwind(AssertUnwindSafe(|| sink.flush()));
                let _ = ack.try_send(());
            }
        }
    }
}

impl Write for LossyWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.tx.try_send(Msg::Line(buf.to_vec())).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl<'a> tracing_subscriber::fmt::MakeWriter<'a> for LossyWriter {
    type Writer = LossyWriter;

    fn make_writer(&'a self) -> Self::Writer {
        self.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// A sink that records what it got and fails or panics on demand.
    struct Sink {
        got: Arc<Mutex<Vec<u8>>>,
        mode: Arc<Mutex<Mode>>,
        gate: Option<Arc<Mutex<()>>>,
    }

    #[derive(Clone, Copy, PartialEq)]
    enum Mode {
        Ok,
        BrokenPipe,
        Panic,
    }

    impl Write for Sink {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if let Some(g) = &self.gate {
                drop(g.lock().unwrap_or_else(|p| p.into_inner()));
            }
            let mode = *self.mode.lock().unwrap();
            match mode {
                Mode::Ok => {
                    self.got.lock().unwrap().extend_from_slice(buf);
                    Ok(buf.len())
                }
                Mode::BrokenPipe => Err(io::Error::from(io::ErrorKind::BrokenPipe)),
                Mode::Panic => panic!("sink panics"),
            }
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    type Shared<T> = Arc<Mutex<T>>;

    fn sink(mode: Mode) -> (Sink, Shared<Vec<u8>>, Shared<Mode>) {
        let got = Arc::new(Mutex::new(Vec::new()));
        let m = Arc::new(Mutex::new(mode));
        (
            Sink {
                got: got.clone(),
                mode: m.clone(),
                gate: None,
            },
            got,
            m,
        )
    }

    #[test]
    fn failing_and_panicking_sinks_drop_and_count_lines_then_recover() {
        let (s, got, mode) = sink(Mode::Ok);
        let dropped = Arc::new(AtomicU64::new(0));
        let mut w = LossyWriter::spawn(Box::new(s), 64, dropped.clone()).unwrap();
        w.write_all(b"one\n").unwrap();
        assert!(w.flush(Duration::from_secs(30)));
        *mode.lock().unwrap() = Mode::BrokenPipe;
        for _ in 0..3 {
            w.write_all(b"lost\n").unwrap();
        }
        assert!(w.flush(Duration::from_secs(30)));
        assert_eq!(w.dropped(), 3);
        *mode.lock().unwrap() = Mode::Panic;
        w.write_all(b"lost too\n").unwrap();
        assert!(w.flush(Duration::from_secs(30)));
        assert_eq!(w.dropped(), 4);
        // The thread survived the panic and writes again.
        *mode.lock().unwrap() = Mode::Ok;
        w.write_all(b"two\n").unwrap();
        assert!(w.flush(Duration::from_secs(30)));
        assert_eq!(&got.lock().unwrap()[..], b"one\ntwo\n");
        assert_eq!(dropped.load(Ordering::Relaxed), 4);
    }

    #[test]
    fn a_stuck_sink_never_blocks_the_logger() {
        let (mut s, got, _) = sink(Mode::Ok);
        let gate = Arc::new(Mutex::new(()));
        s.gate = Some(gate.clone());
        let held = gate.lock().unwrap();
        let dropped = Arc::new(AtomicU64::new(0));
        let mut w = LossyWriter::spawn(Box::new(s), 4, dropped).unwrap();
        // The sink is stuck on its first line; four more fill the queue and
        // every further line is dropped at once instead of waiting.
        for _ in 0..100 {
            w.write_all(b"x\n").unwrap();
        }
        assert!(w.dropped() >= 95, "dropped {}", w.dropped());
        drop(held);
        assert!(w.flush(Duration::from_secs(30)));
        let n = got.lock().unwrap().len() / 2;
        assert_eq!(n as u64 + w.dropped(), 100);
    }
}
