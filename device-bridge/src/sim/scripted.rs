//! An in-memory [`Transport`] that hands out a fixed list of chunks — recorded HID
//! reports, captured serial bytes — and records what the driver writes.

use crate::device::driver::{DeviceError, Transport};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A transport replaying `chunks`; after the last one it reports the device gone.
pub struct ScriptedTransport {
    chunks: VecDeque<Vec<u8>>,
    identity: Option<(u16, u16)>,
    written: Arc<Mutex<Vec<u8>>>,
    open: bool,
}

impl ScriptedTransport {
    /// A transport that will return each of `chunks` from one `read`.
    pub fn new(chunks: impl IntoIterator<Item = Vec<u8>>, identity: Option<(u16, u16)>) -> Self {
        Self {
            chunks: chunks.into_iter().collect(),
            identity,
            written: Arc::new(Mutex::new(Vec::new())),
            open: false,
        }
    }

    /// A handle to every byte the driver wrote.
    pub fn written(&self) -> Arc<Mutex<Vec<u8>>> {
        self.written.clone()
    }
}

impl Transport for ScriptedTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        self.open = true;
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> Result<usize, DeviceError> {
        if !self.open {
            return Err(DeviceError::NotOpen);
        }
        let Some(mut c) = self.chunks.pop_front() else {
            return Err(DeviceError::Disconnected);
        };
        let n = c.len().min(buf.len());
        buf[..n].copy_from_slice(&c[..n]);
        if n < c.len() {
            self.chunks.push_front(c.split_off(n));
        }
        Ok(n)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        self.written
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(bytes);
        Ok(())
    }

    fn close(&mut self) {
        self.open = false;
    }

    fn is_open(&self) -> bool {
        self.open
    }

    fn describe(&self) -> String {
        "scripted".into()
    }

    fn identity(&self) -> Option<(u16, u16)> {
        self.identity
    }
}
