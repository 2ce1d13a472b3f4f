//! A fake spacenavd: an AF_UNIX listener that writes protocol-v0 events (32 bytes,
//! eight native-endian `i32`) to every connected client.

use crate::device::spacenavd::encode_event;
use std::io::Write;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// The fake daemon.
pub struct FakeSpacenavd {
    path: PathBuf,
    clients: Arc<Mutex<Vec<UnixStream>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeSpacenavd {
    /// Listens at `path`.
    pub fn start(path: impl Into<PathBuf>) -> std::io::Result<Self> {
        let path = path.into();
        let _ = std::fs::remove_file(&path);
        let listener = UnixListener::bind(&path)?;
        listener.set_nonblocking(true)?;
        let clients = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let (c, s) = (clients.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((stream, _)) => c.lock().unwrap_or_else(|e| e.into_inner()).push(stream),
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        Ok(Self {
            path,
            clients,
            stop,
            thread: Some(thread),
        })
    }

    /// The socket path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of connected clients.
    pub fn clients(&self) -> usize {
        self.clients.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// Sends raw bytes to every client (drops clients that are gone).
    pub fn send_raw(&self, bytes: &[u8]) {
        let mut c = self.clients.lock().unwrap_or_else(|e| e.into_inner());
        c.retain_mut(|s| s.write_all(bytes).is_ok());
    }

    /// Sends a motion event (raw axis values, period in ms).
    pub fn send_motion(&self, axes: [i32; 6], period_ms: i32) {
        let [x, y, z, rx, ry, rz] = axes;
        self.send_raw(&encode_event([0, x, y, z, rx, ry, rz, period_ms]));
    }

    /// Sends a button press or release.
    pub fn send_button(&self, button: i32, pressed: bool) {
        let kind = if pressed { 1 } else { 2 };
        self.send_raw(&encode_event([
            kind,
            button,
            i32::from(pressed),
            0,
            0,
            0,
            0,
            0,
        ]));
    }

    /// Closes every client connection (the daemon restarting).
    pub fn drop_clients(&self) {
        self.clients
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }
}

impl Drop for FakeSpacenavd {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_file(&self.path);
    }
}
