//! The cost of one log line for the task that logs: a `tracing` event
//! formatted by the fmt layer and handed to the [`LossyWriter`] (its sink
//! discarding, or failing every write like a closed stderr), against the same
//! event written synchronously to a discarding writer (the baseline: what a
//! plain `with_writer(io::sink)` costs).
//!
//!     cargo bench -p vsculpt-logging --bench log_line -- --warm-up-time 1 --measurement-time 3

use criterion::{Criterion, criterion_group, criterion_main};
use std::io;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use vsculpt_logging::{LossyWriter, QUEUE_LINES};

/// A sink failing like a pipe whose reader went away.
struct ClosedPipe;

impl io::Write for ClosedPipe {
    fn write(&mut self, _: &[u8]) -> io::Result<usize> {
        Err(io::Error::from(io::ErrorKind::BrokenPipe))
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

fn event() {
    tracing::info!(
        design = 1u64,
        client = 42u64,
        role = "editor",
        "client joined"
    );
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("log_line");
    let sync = tracing_subscriber::fmt()
        .with_writer(io::sink)
        .with_ansi(false)
        .finish();
    tracing::subscriber::with_default(sync, || {
        g.bench_function("sync_discarding_writer", |b| b.iter(event));
    });
    for (name, sink) in [
        (
            "lossy_discarding_sink",
            Box::new(io::sink()) as Box<dyn io::Write + Send>,
        ),
        ("lossy_closed_pipe", Box::new(ClosedPipe)),
    ] {
        let w = LossyWriter::spawn(sink, QUEUE_LINES, Arc::new(AtomicU64::new(0))).unwrap();
        let sub = tracing_subscriber::fmt()
            .with_writer(w)
            .with_ansi(false)
            .finish();
        tracing::subscriber::with_default(sub, || {
            g.bench_function(name, |b| b.iter(event));
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
