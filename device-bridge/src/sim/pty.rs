//! A simulated serial device on a pseudo-terminal pair.
//!
//! [`PtySim`] owns the master end of a `serialport::TTYPort::pair()` and runs a
//! [`SerialDevice`] behaviour on it in a thread: bytes the driver writes reach
//! `on_input`, and the behaviour's answers (and its streamed records, on every
//! tick) go back. The slave end is reachable through a stable symlink, so a test
//! can "unplug" the device (the master closes, the driver's reads fail) and "plug
//! it back" on a new pty behind the same path.

use std::io::{Read, Write};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The behaviour of a simulated serial device.
pub trait SerialDevice: Send + 'static {
    /// Handles bytes written by the host, appending the device's answer to `out`.
    fn on_input(&mut self, bytes: &[u8], out: &mut Vec<u8>);
    /// Called every [`SerialDevice::tick`]; appends streamed records to `out`.
    fn on_tick(&mut self, out: &mut Vec<u8>);
    /// Period of `on_tick`.
    fn tick(&self) -> Duration;
}

/// Bytes kept for the host before the oldest are dropped.
const BACKLOG: usize = 16 * 1024;

struct Shared<D> {
    device: Mutex<D>,
    inject: Mutex<Vec<u8>>,
}

/// A simulated device on a pty, reachable at [`PtySim::link`].
pub struct PtySim<D: SerialDevice> {
    shared: Arc<Shared<D>>,
    link: PathBuf,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

fn set_nonblocking(fd: i32) -> std::io::Result<()> {
    // SAFETY: fcntl on a file descriptor we own, with integer flags only.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: as above.
    if unsafe { libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

impl<D: SerialDevice> PtySim<D> {
    /// Starts `device` on a new pty; the slave is reachable through the symlink `link`.
    pub fn start(device: D, link: impl Into<PathBuf>) -> std::io::Result<Self> {
        let mut sim = Self {
            shared: Arc::new(Shared {
                device: Mutex::new(device),
                inject: Mutex::new(Vec::new()),
            }),
            link: link.into(),
            stop: Arc::new(AtomicBool::new(false)),
            thread: None,
        };
        sim.plug()?;
        Ok(sim)
    }

    /// The path a driver opens (a symlink to the current pty slave).
    pub fn link(&self) -> &Path {
        &self.link
    }

    /// The behaviour, to change what the device reports.
    pub fn device(&self) -> MutexGuard<'_, D> {
        self.shared.device.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Writes raw bytes to the host as they are (fault injection).
    pub fn inject(&self, bytes: &[u8]) {
        self.shared
            .inject
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(bytes);
    }

    /// Unplugs the device: the pty closes and the link disappears.
    pub fn unplug(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_file(&self.link);
    }

    /// Plugs the device back on a fresh pty behind the same link.
    pub fn plug(&mut self) -> std::io::Result<()> {
        self.unplug();
        let (master, slave) = serialport::TTYPort::pair().map_err(std::io::Error::other)?;
        let slave_path = serialport::SerialPort::name(&slave)
            .ok_or_else(|| std::io::Error::other("pty without a name"))?;
        set_nonblocking(master.as_raw_fd())?;
        std::os::unix::fs::symlink(&slave_path, &self.link)?;
        self.stop = Arc::new(AtomicBool::new(false));
        let stop = self.stop.clone();
        let shared = self.shared.clone();
        self.thread = Some(std::thread::spawn(move || run(master, slave, shared, stop)));
        Ok(())
    }
}

impl<D: SerialDevice> Drop for PtySim<D> {
    fn drop(&mut self) {
        self.unplug();
    }
}

fn run<D: SerialDevice>(
    mut master: serialport::TTYPort,
    slave: serialport::TTYPort,
    shared: Arc<Shared<D>>,
    stop: Arc<AtomicBool>,
) {
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    let _ = serialport::SerialPort::set_timeout(&mut master, Duration::from_millis(1));
    let mut next_tick = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        match master.read(&mut buf) {
            Ok(n) if n > 0 => {
                let mut d = shared.device.lock().unwrap_or_else(|e| e.into_inner());
                d.on_input(&buf[..n], &mut out);
            }
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_micros(200));
            }
            // EIO while no one holds the slave open, or a timeout: try again shortly.
            Err(_) => std::thread::sleep(Duration::from_micros(200)),
        }
        let now = Instant::now();
        if now >= next_tick {
            let mut d = shared.device.lock().unwrap_or_else(|e| e.into_inner());
            d.on_tick(&mut out);
            next_tick = now + d.tick();
        }
        {
            let mut inj = shared.inject.lock().unwrap_or_else(|e| e.into_inner());
            out.append(&mut inj);
        }
        if !out.is_empty() {
            if let Ok(n) = master.write(&out) {
                out.drain(..n);
            }
            // Nobody reading: drop the backlog, as an overflowing serial line would.
            if out.len() > BACKLOG {
                out.clear();
            }
        }
    }
    drop(slave);
}
