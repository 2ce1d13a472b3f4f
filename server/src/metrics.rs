//! Service metrics in the Prometheus text format (`GET /metrics`): open
//! designs, connected clients, solve count and time, geometry frames sent and
//! the frame rate over the last full second, design actors that panicked
//! and were restarted, log lines dropped. Plain atomics, shared by
//! every task, no locks on the hot path.

use std::fmt::Write;
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Counters and gauges of one server.
#[derive(Debug)]
pub struct Metrics {
    started: Instant,
    designs_open: AtomicI64,
    clients: AtomicI64,
    solves: AtomicU64,
    solve_nanos: AtomicU64,
    solve_max_nanos: AtomicU64,
    frames: AtomicU64,
    frame_bytes: AtomicU64,
    errors: AtomicU64,
    rate_limited: AtomicU64,
    actor_panics: AtomicU64,
    actor_restarts: AtomicU64,
    store_write_errors: AtomicU64,
    fps_second: AtomicU64,
    fps_current: AtomicU64,
    fps_last: AtomicU64,
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

impl Metrics {
    /// All zero.
    pub fn new() -> Self {
        Self {
            started: Instant::now(),
            designs_open: AtomicI64::new(0),
            clients: AtomicI64::new(0),
            solves: AtomicU64::new(0),
            solve_nanos: AtomicU64::new(0),
            solve_max_nanos: AtomicU64::new(0),
            frames: AtomicU64::new(0),
            frame_bytes: AtomicU64::new(0),
            errors: AtomicU64::new(0),
            rate_limited: AtomicU64::new(0),
            actor_panics: AtomicU64::new(0),
            actor_restarts: AtomicU64::new(0),
            store_write_errors: AtomicU64::new(0),
            fps_second: AtomicU64::new(0),
            fps_current: AtomicU64::new(0),
            fps_last: AtomicU64::new(0),
        }
    }

    /// A design actor started (+1) or stopped (−1).
    pub fn design_open(&self, delta: i64) {
        self.designs_open.fetch_add(delta, Ordering::Relaxed);
    }

    /// A client connected (+1) or left (−1).
    pub fn client(&self, delta: i64) {
        self.clients.fetch_add(delta, Ordering::Relaxed);
    }

    /// Currently connected clients.
    pub fn clients(&self) -> i64 {
        self.clients.load(Ordering::Relaxed)
    }

    /// One solve took `d`.
    pub fn solve(&self, d: Duration) {
        let n = d.as_nanos() as u64;
        self.solves.fetch_add(1, Ordering::Relaxed);
        self.solve_nanos.fetch_add(n, Ordering::Relaxed);
        self.solve_max_nanos.fetch_max(n, Ordering::Relaxed);
    }

    /// A geometry frame of `bytes` went to one client.
    pub fn frame_sent(&self, bytes: usize) {
        self.frames.fetch_add(1, Ordering::Relaxed);
        self.frame_bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        let sec = self.started.elapsed().as_secs() + 1;
        let prev = self.fps_second.load(Ordering::Relaxed);
        if prev != sec
            && self
                .fps_second
                .compare_exchange(prev, sec, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
        {
            let done = self.fps_current.swap(0, Ordering::Relaxed);
            self.fps_last
                .store(if sec == prev + 1 { done } else { 0 }, Ordering::Relaxed);
        }
        self.fps_current.fetch_add(1, Ordering::Relaxed);
    }

    /// An error message went to a client.
    pub fn error_sent(&self) {
        self.errors.fetch_add(1, Ordering::Relaxed);
    }

    /// A client message was dropped for exceeding its rate limit.
    pub fn rate_limited(&self) {
        self.rate_limited.fetch_add(1, Ordering::Relaxed);
    }

    /// A design actor panicked.
    pub fn actor_panic(&self) {
        self.actor_panics.fetch_add(1, Ordering::Relaxed);
    }

    /// A design actor was restarted after a panic.
    pub fn actor_restart(&self) {
        self.actor_restarts.fetch_add(1, Ordering::Relaxed);
    }

    /// A working-state write failed (it is retried).
    pub fn store_write_failed(&self) {
        self.store_write_errors.fetch_add(1, Ordering::Relaxed);
    }

    /// Geometry frames sent over the last full second.
    pub fn frames_per_second(&self) -> u64 {
        let sec = self.started.elapsed().as_secs() + 1;
        let at = self.fps_second.load(Ordering::Relaxed);
        if at == sec {
            self.fps_last.load(Ordering::Relaxed)
        } else if at + 1 == sec {
            self.fps_current.load(Ordering::Relaxed)
        } else {
            0
        }
    }

    /// The Prometheus text exposition.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let mut metric = |name: &str, kind: &str, help: &str, value: String| {
            let _ = writeln!(s, "# HELP {name} {help}");
            let _ = writeln!(s, "# TYPE {name} {kind}");
            let _ = writeln!(s, "{name} {value}");
        };
        let solves = self.solves.load(Ordering::Relaxed);
        let nanos = self.solve_nanos.load(Ordering::Relaxed);
        metric(
            "vsculpt_designs_open",
            "gauge",
            "Designs with a running actor.",
            self.designs_open.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_clients",
            "gauge",
            "Connected WebSocket clients.",
            self.clients().to_string(),
        );
        metric(
            "vsculpt_solves_total",
            "counter",
            "Solver runs (solves and drag frames).",
            solves.to_string(),
        );
        metric(
            "vsculpt_solve_seconds_total",
            "counter",
            "Time spent in the solver.",
            format!("{}", nanos as f64 * 1e-9),
        );
        metric(
            "vsculpt_solve_seconds_mean",
            "gauge",
            "Mean solver time.",
            format!(
                "{}",
                if solves > 0 {
                    nanos as f64 * 1e-9 / solves as f64
                } else {
                    0.0
                }
            ),
        );
        metric(
            "vsculpt_solve_seconds_max",
            "gauge",
            "Longest solver run.",
            format!(
                "{}",
                self.solve_max_nanos.load(Ordering::Relaxed) as f64 * 1e-9
            ),
        );
        metric(
            "vsculpt_frames_sent_total",
            "counter",
            "Geometry frames sent to clients.",
            self.frames.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_frame_bytes_total",
            "counter",
            "Bytes of geometry frames sent to clients.",
            self.frame_bytes.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_frames_per_second",
            "gauge",
            "Geometry frames sent over the last full second.",
            self.frames_per_second().to_string(),
        );
        metric(
            "vsculpt_errors_sent_total",
            "counter",
            "Error messages sent to clients.",
            self.errors.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_rate_limited_total",
            "counter",
            "Client messages dropped for exceeding the per-connection rate limit.",
            self.rate_limited.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_actor_panics_total",
            "counter",
            "Design actors that panicked (each is restarted from its persisted state).",
            self.actor_panics.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_actor_restarts_total",
            "counter",
            "Design actors restarted after a panic.",
            self.actor_restarts.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_store_write_errors_total",
            "counter",
            "Working-state writes that failed (disk full, read-only); each is retried.",
            self.store_write_errors.load(Ordering::Relaxed).to_string(),
        );
        metric(
            "vsculpt_log_lines_dropped_total",
            "counter",
            "Log lines dropped (log reader gone, log sink failing or too slow).",
            vsculpt_logging::dropped_lines().to_string(),
        );
        metric(
            "vsculpt_uptime_seconds",
            "gauge",
            "Seconds since start.",
            format!("{}", self.started.elapsed().as_secs_f64()),
        );
        s
    }
}
