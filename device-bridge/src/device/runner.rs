//! Keeps one device running in its own thread: opens it, reads samples into a
//! sink, and when the device fails (unplugged, garbage it cannot resync from, a
//! VRPN server gone) closes it and reopens it with exponential backoff. Each
//! kind of failure is logged once, and recovery once.
//!
//! The thread supervises itself: a panic anywhere in the device's code is
//! caught, logged with the device's name, counted ([`RunStats::panics`]),
//! reported as [`DeviceStatus::Lost`] (so the server hears it) and the device
//! is closed and started again after the same backoff.

use super::driver::{Device, DeviceError};
use super::sample::Sample;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Timing of a device runner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Longest single read.
    pub read_timeout: Duration,
    /// First reopen delay.
    pub backoff_min: Duration,
    /// Longest reopen delay.
    pub backoff_max: Duration,
    /// Reopen when an open device sends no valid sample for this long (`None` for
    /// devices that are legitimately silent, like an untouched 3D mouse).
    pub silence: Option<Duration>,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            read_timeout: Duration::from_millis(50),
            backoff_min: Duration::from_millis(50),
            backoff_max: Duration::from_secs(2),
            silence: Some(Duration::from_secs(3)),
        }
    }
}

/// A change in a device's availability.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceStatus {
    /// The device is open and configured.
    Open,
    /// The device cannot be opened (yet); the reason.
    Unavailable(String),
    /// The device was open and failed; it is being reopened.
    Lost(String),
}

/// Counters of a running device.
#[derive(Debug, Default)]
pub struct RunStats {
    /// Samples delivered.
    pub samples: AtomicU64,
    /// Successful opens.
    pub opens: AtomicU64,
    /// Failures (open errors and lost devices).
    pub failures: AtomicU64,
    /// Panics caught in the device's code (each followed by a restart).
    pub panics: AtomicU64,
}

/// A device running in a thread; dropping it stops the thread and closes the device.
pub struct DeviceRunner {
    name: String,
    stop: Arc<AtomicBool>,
    stats: Arc<RunStats>,
    thread: Option<JoinHandle<()>>,
}

impl DeviceRunner {
    /// Starts `device`; every batch of samples goes to `sink`, which returns false
    /// to stop the runner.
    pub fn spawn(
        device: Box<dyn Device>,
        options: RunOptions,
        sink: impl FnMut(&[Sample]) -> bool + Send + 'static,
    ) -> Self {
        Self::spawn_with_status(device, options, sink, |_| {})
    }

    /// Like [`DeviceRunner::spawn`], also reporting every change of the device's
    /// [`DeviceStatus`] to `status`.
    pub fn spawn_with_status(
        mut device: Box<dyn Device>,
        options: RunOptions,
        mut sink: impl FnMut(&[Sample]) -> bool + Send + 'static,
        mut status: impl FnMut(DeviceStatus) + Send + 'static,
    ) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let stats = Arc::new(RunStats::default());
        let name = device.name().to_owned();
        let (s, st) = (stop.clone(), stats.clone());
        let thread = std::thread::Builder::new()
            .name(format!("device {name}"))
            .spawn(move || supervise(device.as_mut(), options, &mut sink, &mut status, &s, &st))
            .ok();
        if thread.is_none() {
            tracing::error!(device = %name, "cannot start a thread for the device");
        }
        Self {
            name,
            stop,
            stats,
            thread,
        }
    }

    /// The device's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Counters.
    pub fn stats(&self) -> &RunStats {
        &self.stats
    }

    /// Stops the runner and waits for it.
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for DeviceRunner {
    fn drop(&mut self) {
        self.stop();
    }
}

fn sleep_unless_stopped(d: Duration, stop: &AtomicBool) {
    let end = Instant::now() + d;
    while !stop.load(Ordering::SeqCst) {
        let now = Instant::now();
        if now >= end {
            return;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(20)));
    }
}

fn same_kind(a: &DeviceError, b: &DeviceError) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
}

/// The text of a panic payload.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a non-text panic".into()
    }
}

/// [`run`], restarted with backoff whenever it panics, until `stop`.
fn supervise(
    device: &mut dyn Device,
    o: RunOptions,
    sink: &mut dyn FnMut(&[Sample]) -> bool,
    status: &mut dyn FnMut(DeviceStatus),
    stop: &AtomicBool,
    stats: &RunStats,
) {
    let mut backoff = o.backoff_min;
    loop {
        let ran = catch_unwind(AssertUnwindSafe(|| {
            run(&mut *device, o, &mut *sink, &mut *status, stop, stats)
        }));
        let Err(panic) = ran else { return };
        let name = device.name().to_owned();
        let what = panic_text(&*panic);
        stats.panics.fetch_add(1, Ordering::Relaxed);
        tracing::error!(device = %name, panic = %what, ?backoff, "device task panicked; restarting");
        let _ = catch_unwind(AssertUnwindSafe(|| {
            device.close();
            status(DeviceStatus::Lost(format!(
                "device task failed ({what}); restarting in {} ms",
                backoff.as_millis()
            )));
        }));
        sleep_unless_stopped(backoff, stop);
        backoff = (backoff * 2).min(o.backoff_max);
        if stop.load(Ordering::SeqCst) {
            return;
        }
    }
}

fn run(
    device: &mut dyn Device,
    o: RunOptions,
    sink: &mut dyn FnMut(&[Sample]) -> bool,
    status: &mut dyn FnMut(DeviceStatus),
    stop: &AtomicBool,
    stats: &RunStats,
) {
    let name = device.name().to_owned();
    let mut backoff = o.backoff_min;
    let mut last_error: Option<DeviceError> = None;
    let mut last_loss: Option<DeviceError> = None;
    let mut buf = Vec::with_capacity(64);
    while !stop.load(Ordering::SeqCst) {
        if let Err(e) = device.open() {
            stats.failures.fetch_add(1, Ordering::Relaxed);
            if last_error.as_ref().is_none_or(|l| !same_kind(l, &e)) {
                tracing::warn!(device = %name, error = %e, "cannot open device; retrying");
                status(DeviceStatus::Unavailable(e.to_string()));
            }
            last_error = Some(e);
            sleep_unless_stopped(backoff, stop);
            backoff = (backoff * 2).min(o.backoff_max);
            continue;
        }
        stats.opens.fetch_add(1, Ordering::Relaxed);
        status(DeviceStatus::Open);
        if last_error.take().is_some() {
            if last_loss.is_some() {
                // The same failure repeating (a glove off its box): said once.
                tracing::debug!(device = %name, "device open again");
            } else {
                tracing::info!(device = %name, "device open again");
            }
        } else {
            tracing::info!(device = %name, "device open");
        }
        let mut last_sample = Instant::now();
        let mut activity = device.stats().messages;
        let mut delivered = false;
        let failure = loop {
            if stop.load(Ordering::SeqCst) {
                break None;
            }
            buf.clear();
            let r = device.read(o.read_timeout, &mut buf);
            if !buf.is_empty() {
                if !delivered && last_loss.is_some() {
                    // Samples flow again: the next failure is news.
                    last_loss = None;
                }
                delivered = true;
                last_sample = Instant::now();
                backoff = o.backoff_min;
                stats.samples.fetch_add(buf.len() as u64, Ordering::Relaxed);
                if !sink(&buf) {
                    stop.store(true, Ordering::SeqCst);
                    break None;
                }
            }
            if let Err(e) = r {
                break Some(e);
            }
            let messages = device.stats().messages;
            if messages != activity {
                // A message that is no sample (a VRPN pong) proves the peer alive too.
                activity = messages;
                last_sample = Instant::now();
            }
            if o.silence.is_some_and(|s| last_sample.elapsed() > s) {
                break Some(DeviceError::Handshake(format!(
                    "nothing valid received for {:?}",
                    o.silence.unwrap_or_default()
                )));
            }
        };
        device.close();
        if let Some(e) = failure {
            stats.failures.fetch_add(1, Ordering::Relaxed);
            if last_loss.as_ref() == Some(&e) {
                tracing::debug!(device = %name, error = %e, "device lost again; reopening");
            } else {
                tracing::warn!(device = %name, error = %e, "device lost; reopening");
            }
            last_loss = Some(e.clone());
            status(DeviceStatus::Lost(e.to_string()));
            last_error = Some(e);
            sleep_unless_stopped(backoff, stop);
            backoff = (backoff * 2).min(o.backoff_max);
        }
    }
}
