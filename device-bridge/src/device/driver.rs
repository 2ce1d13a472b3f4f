//! The one driver abstraction every device family plugs into.
//!
//! A device is split in three so that recording and replay go through exactly
//! the same parsers as live input:
//! * a [`Transport`] moves raw bytes (serial port, HID, AF_UNIX or TCP socket);
//! * a [`Decoder`] is a pure state machine from bytes to validated [`Sample`]s,
//!   resynchronising on garbage;
//! * a [`Script`] holds the commands a device family needs on open, per poll and
//!   on close.
//!
//! [`Driver`] combines the three and implements the [`Device`] trait
//! (open / read / close). Every raw chunk it reads can be copied to a recording
//! tap as a [`RawFrame`].

use super::sample::{Sample, SourceId, Timestamp};
use std::sync::mpsc::Sender;
use std::time::{Duration, Instant};
use thiserror::Error;

/// Why a device could not be opened or read.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum DeviceError {
    /// No device matched the configuration (not plugged in, socket missing).
    #[error("device not found: {0}")]
    NotFound(String),
    /// An operating-system I/O error.
    #[error("i/o error: {0}")]
    Io(String),
    /// The device or peer closed the link.
    #[error("device disconnected")]
    Disconnected,
    /// The device answered a command wrongly or not at all.
    #[error("handshake failed: {0}")]
    Handshake(String),
    /// The driver was used before `open`.
    #[error("device not open")]
    NotOpen,
}

impl From<std::io::Error> for DeviceError {
    fn from(e: std::io::Error) -> Self {
        match e.kind() {
            std::io::ErrorKind::UnexpectedEof
            | std::io::ErrorKind::BrokenPipe
            | std::io::ErrorKind::ConnectionReset
            | std::io::ErrorKind::ConnectionAborted => DeviceError::Disconnected,
            std::io::ErrorKind::NotFound => DeviceError::NotFound(e.to_string()),
            _ => DeviceError::Io(e.to_string()),
        }
    }
}

/// Counters a decoder keeps about the bytes it saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeStats {
    /// Records decoded into samples.
    pub records: u64,
    /// Bytes thrown away while looking for the start of a record.
    pub discarded_bytes: u64,
    /// Complete records rejected by a validity check (bad framing, values out of range).
    pub rejected_records: u64,
    /// Well-formed messages of any kind (for framed protocols whose peers also
    /// send non-sample messages: proof the peer is alive).
    pub messages: u64,
    /// Messages of a lossy side channel dropped as duplicates, out of order, or
    /// ahead of their descriptions (not faults: UDP does that).
    pub stale: u64,
}

impl DecodeStats {
    /// Bytes or records dropped so far.
    pub fn faults(&self) -> u64 {
        self.discarded_bytes + self.rejected_records
    }
}

/// A pure parser from raw device bytes to samples.
///
/// `feed` may be called with any split of the byte stream (one byte at a time,
/// many records at once); the output must not depend on the split. For packet
/// transports (HID) each chunk is one report.
pub trait Decoder: Send {
    /// Parses `chunk`, which arrived at `at`, appending complete samples to `out`.
    fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>);
    /// Counters since creation.
    fn stats(&self) -> DecodeStats;
    /// Forgets any partial record (after a reopen).
    fn reset(&mut self);
    /// `Some(reason)` when the stream cannot be resynchronised in place (a framed
    /// protocol whose length field was corrupt, a failed handshake): the driver
    /// then reports the link broken so that it is reopened.
    fn fatal(&self) -> Option<String> {
        None
    }
    /// Tells the decoder which USB model (vendor, product) the transport opened, for
    /// per-model quirks. The default ignores it.
    fn set_identity(&mut self, _ids: (u16, u16)) {}
    /// Parses one datagram of a lossy side channel (VRPN's UDP): whole messages,
    /// possibly lost, duplicated or out of order, never part of the byte stream.
    /// The default treats it as stream bytes.
    fn feed_datagram(&mut self, datagram: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
        self.feed(datagram, at, out);
    }
}

/// A byte link to a device.
pub trait Transport: Send {
    /// Opens the link.
    fn open(&mut self) -> Result<(), DeviceError>;
    /// Reads what is available, waiting at most `timeout`; `Ok(0)` on timeout.
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError>;
    /// Writes all of `bytes`.
    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError>;
    /// Closes the link (idempotent).
    fn close(&mut self);
    /// True between a successful `open` and `close`.
    fn is_open(&self) -> bool;
    /// A human-readable name (port path, socket, host).
    fn describe(&self) -> String;
    /// The USB (vendor, product) of the opened device, when the link knows it.
    fn identity(&self) -> Option<(u16, u16)> {
        None
    }
    /// True when the bytes of the last `read` were one datagram of a lossy side
    /// channel rather than stream bytes (see [`Decoder::feed_datagram`]).
    fn last_read_was_datagram(&self) -> bool {
        false
    }
}

/// One step of a command script.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    /// Write these bytes.
    Send(Vec<u8>),
    /// Read and discard everything that arrives for this long.
    Drain(Duration),
    /// Read exactly `len` bytes within `timeout` and check them.
    Expect {
        /// Bytes to read.
        len: usize,
        /// How long to wait for them.
        timeout: Duration,
        /// Check on the bytes read; failing it fails the open.
        check: Check,
    },
}

/// A check on a device's answer to a command.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Check {
    /// The answer is exactly these bytes.
    Equals(Vec<u8>),
    /// Accept anything.
    Any,
    /// The first `n` bytes each have bit 7 set (Flock `O 36`: unit accessible).
    HighBitSet(usize),
    /// The answer starts with this byte.
    StartsWith(u8),
}

impl Check {
    /// Verifies `answer`; `Err` says what was wrong.
    pub fn verify(&self, answer: &[u8]) -> Result<(), String> {
        match self {
            Check::Equals(want) => {
                if answer == want.as_slice() {
                    Ok(())
                } else {
                    Err(format!("answer {answer:02x?}, expected {want:02x?}"))
                }
            }
            Check::Any => Ok(()),
            Check::HighBitSet(n) => match answer.iter().take(*n).position(|b| b & 0x80 == 0) {
                Some(i) => Err(format!("unit {} is not accessible", i + 1)),
                None if answer.len() < *n => Err("answer too short".into()),
                None => Ok(()),
            },
            Check::StartsWith(b) => match answer.first() {
                Some(f) if f == b => Ok(()),
                _ => Err(format!("answer does not start with {b:#04x}")),
            },
        }
    }
}

/// The commands a device family needs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Script {
    /// Run in order after the transport opens.
    pub open: Vec<Step>,
    /// Sent before each read cycle in polled mode (`None` when the device streams).
    pub poll: Option<Vec<u8>>,
    /// Least time between two polls: a device is polled at its own rate, not as
    /// fast as the line answers.
    pub poll_interval: Duration,
    /// Sent before the transport closes.
    pub close: Vec<u8>,
}

/// A raw chunk of bytes as read from a device, for recording.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawFrame {
    /// Which configured device.
    pub source: SourceId,
    /// When it arrived.
    pub time: Timestamp,
    /// The bytes exactly as read.
    pub bytes: Vec<u8>,
}

/// What a driver reports to a recording tap.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TapEvent {
    /// The device was (re)opened: decoders start afresh.
    Opened {
        /// Which configured device.
        source: SourceId,
        /// When.
        time: Timestamp,
        /// USB identity of the opened device, if any.
        identity: Option<(u16, u16)>,
    },
    /// Bytes read.
    Frame(RawFrame),
    /// One datagram read from a lossy side channel (VRPN over UDP).
    Datagram(RawFrame),
    /// The device's availability changed (reported by its runner).
    Status {
        /// Which configured device.
        source: SourceId,
        /// When.
        time: Timestamp,
        /// The new status.
        status: super::runner::DeviceStatus,
    },
}

/// A device: open it, read samples, close it.
pub trait Device: Send {
    /// Configured name of the device.
    fn name(&self) -> &str;
    /// Opens the link and runs the device's start-up commands.
    fn open(&mut self) -> Result<(), DeviceError>;
    /// Reads for at most `timeout`, appending validated samples to `out`.
    /// Returns early once at least one sample was decoded.
    fn read(&mut self, timeout: Duration, out: &mut Vec<Sample>) -> Result<(), DeviceError>;
    /// Stops the device and closes the link.
    fn close(&mut self);
    /// The decoder's counters.
    fn stats(&self) -> DecodeStats;
}

/// Largest chunk read from a transport at once.
const READ_CHUNK: usize = 4096;

/// The generic device: transport + decoder + script.
pub struct Driver {
    name: String,
    source: SourceId,
    transport: Box<dyn Transport>,
    decoder: Box<dyn Decoder>,
    script: Script,
    tap: Option<Sender<TapEvent>>,
    buf: Vec<u8>,
    faults_seen: u64,
    in_fault: bool,
    last_poll: Option<Instant>,
    garbage_hint: Option<String>,
    /// Decoder counters when the device was last opened.
    opened_at: DecodeStats,
    /// Least time between two deliveries of a streaming device (zero: at once).
    coalesce: Duration,
    /// When the next read of a coalescing device may start.
    next_read: Option<Instant>,
}

/// Bytes of garbage, with not one valid record since the device opened, after which
/// the line is called wrong (baud rate or record format) and reopened.
pub const GARBAGE_LIMIT: u64 = 1024;

impl Driver {
    /// Assembles a driver.
    pub fn new(
        name: impl Into<String>,
        source: SourceId,
        transport: Box<dyn Transport>,
        decoder: Box<dyn Decoder>,
        script: Script,
    ) -> Self {
        Self {
            name: name.into(),
            source,
            transport,
            decoder,
            script,
            tap: None,
            buf: vec![0; READ_CHUNK],
            faults_seen: 0,
            in_fault: false,
            last_poll: None,
            garbage_hint: None,
            opened_at: DecodeStats::default(),
            coalesce: Duration::ZERO,
            next_read: None,
        }
    }

    /// Reads a streaming device in bulk: after a delivery the line is left to
    /// fill for `window`, then everything it holds is read at once and every
    /// complete record decoded (one `poll` + `read` and one hand-off per window
    /// instead of per record). A tracker streaming at 1 kHz read at the drag
    /// rate still sends each drag from a record at most one record old, since a
    /// drag leaves at most once a window anyway. Polled devices are unaffected
    /// (they are read when their answer is due).
    pub fn set_coalesce(&mut self, window: Duration) {
        self.coalesce = window;
    }

    /// What to say when the line yields only garbage (the configured baud rate and
    /// the likely ones): without it, garbage is only resynchronised on.
    pub fn set_garbage_hint(&mut self, hint: String) {
        self.garbage_hint = Some(hint);
    }

    /// Copies every raw chunk read from now on to `tap` (for `record`).
    pub fn set_tap(&mut self, tap: Sender<TapEvent>) {
        self.tap = Some(tap);
    }

    /// The configured device this driver serves.
    pub fn source(&self) -> SourceId {
        self.source
    }

    fn run_step(&mut self, step: &Step) -> Result<(), DeviceError> {
        match step {
            Step::Send(bytes) => self.transport.write(bytes),
            Step::Drain(d) => {
                let end = Instant::now() + *d;
                loop {
                    let now = Instant::now();
                    if now >= end {
                        return Ok(());
                    }
                    self.transport.read(&mut self.buf, end - now)?;
                }
            }
            Step::Expect {
                len,
                timeout,
                check,
            } => {
                let end = Instant::now() + *timeout;
                let mut got = Vec::with_capacity(*len);
                while got.len() < *len {
                    let now = Instant::now();
                    if now >= end {
                        return Err(DeviceError::Handshake(format!(
                            "expected {len} bytes, got {}",
                            got.len()
                        )));
                    }
                    let want = (*len - got.len()).min(self.buf.len());
                    let n = self.transport.read(&mut self.buf[..want], end - now)?;
                    got.extend_from_slice(&self.buf[..n]);
                }
                check.verify(&got).map_err(DeviceError::Handshake)
            }
        }
    }

    /// Reads and decodes until `end`, or until a sample beyond `start_len` is decoded.
    fn read_until(
        &mut self,
        end: Instant,
        out: &mut Vec<Sample>,
        start_len: usize,
    ) -> Result<(), DeviceError> {
        loop {
            let now = Instant::now();
            if now >= end {
                return Ok(());
            }
            let n = self.transport.read(&mut self.buf, end - now)?;
            if n == 0 {
                continue;
            }
            let at = Timestamp::now();
            let datagram = self.transport.last_read_was_datagram();
            if let Some(tap) = &self.tap {
                let frame = RawFrame {
                    source: self.source,
                    time: at,
                    bytes: self.buf[..n].to_vec(),
                };
                // A closed recorder only stops the recording, never the device.
                let _ = tap.send(if datagram {
                    TapEvent::Datagram(frame)
                } else {
                    TapEvent::Frame(frame)
                });
            }
            if datagram {
                self.decoder.feed_datagram(&self.buf[..n], at, out);
            } else {
                self.decoder.feed(&self.buf[..n], at, out);
            }
            let produced = out.len() > start_len;
            self.note_faults(produced);
            if let Some(reason) = self.decoder.fatal() {
                return Err(DeviceError::Handshake(reason));
            }
            if let Some(hint) = &self.garbage_hint {
                let st = self.decoder.stats();
                let garbage = st.faults() - self.opened_at.faults();
                if st.records == self.opened_at.records && garbage >= GARBAGE_LIMIT {
                    return Err(DeviceError::Handshake(format!(
                        "{garbage} bytes and not one valid record: {hint}"
                    )));
                }
            }
            if produced {
                return Ok(());
            }
        }
    }

    fn note_faults(&mut self, produced: bool) {
        let faults = self.decoder.stats().faults();
        if faults > self.faults_seen {
            if !self.in_fault {
                tracing::warn!(
                    device = %self.name,
                    dropped = faults - self.faults_seen,
                    "bad bytes from device; resynchronising"
                );
                self.in_fault = true;
            }
            self.faults_seen = faults;
        } else if produced && self.in_fault {
            tracing::info!(device = %self.name, "device back in sync");
            self.in_fault = false;
        }
    }
}

impl Device for Driver {
    fn name(&self) -> &str {
        &self.name
    }

    fn open(&mut self) -> Result<(), DeviceError> {
        self.transport.open()?;
        self.decoder.reset();
        self.last_poll = None;
        self.next_read = None;
        self.opened_at = self.decoder.stats();
        let identity = self.transport.identity();
        if let Some(ids) = identity {
            self.decoder.set_identity(ids);
        }
        if let Some(tap) = &self.tap {
            let _ = tap.send(TapEvent::Opened {
                source: self.source,
                time: Timestamp::now(),
                identity,
            });
        }
        let steps = self.script.open.clone();
        for step in &steps {
            if let Err(e) = self.run_step(step) {
                self.transport.close();
                return Err(e);
            }
        }
        Ok(())
    }

    fn read(&mut self, timeout: Duration, out: &mut Vec<Sample>) -> Result<(), DeviceError> {
        if !self.transport.is_open() {
            return Err(DeviceError::NotOpen);
        }
        let start_len = out.len();
        let end = Instant::now() + timeout;
        if let Some(poll) = self.script.poll.clone() {
            if let Some(last) = self.last_poll {
                let next = last + self.script.poll_interval;
                if next > Instant::now() {
                    // Not due yet: take what arrives meanwhile (a late answer).
                    self.read_until(next.min(end), out, start_len)?;
                    if out.len() > start_len || Instant::now() < next {
                        return Ok(());
                    }
                }
            }
            self.transport.write(&poll)?;
            self.last_poll = Some(Instant::now());
        } else if let Some(next) = self.next_read {
            // Coalescing: let the line fill until the window is over.
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next.min(end) - now);
            }
        }
        self.read_until(end, out, start_len)?;
        if !self.coalesce.is_zero() && out.len() > start_len {
            self.next_read = Some(Instant::now() + self.coalesce);
        }
        Ok(())
    }

    fn close(&mut self) {
        if self.transport.is_open() {
            let bytes = self.script.close.clone();
            if !bytes.is_empty() {
                let _ = self.transport.write(&bytes);
            }
            self.transport.close();
        }
    }

    fn stats(&self) -> DecodeStats {
        self.decoder.stats()
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        self.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::sample::Reading;
    use std::sync::{Arc, Mutex};

    /// A device that answers every write at once with one byte.
    struct Instant1 {
        writes: Arc<Mutex<Vec<Instant>>>,
        pending: usize,
        open: bool,
    }

    impl Transport for Instant1 {
        fn open(&mut self) -> Result<(), DeviceError> {
            self.open = true;
            Ok(())
        }
        fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
            if self.pending > 0 {
                self.pending -= 1;
                buf[0] = 1;
                return Ok(1);
            }
            std::thread::sleep(timeout.min(Duration::from_millis(1)));
            Ok(0)
        }
        fn write(&mut self, _bytes: &[u8]) -> Result<(), DeviceError> {
            self.writes.lock().unwrap().push(Instant::now());
            self.pending += 1;
            Ok(())
        }
        fn close(&mut self) {
            self.open = false;
        }
        fn is_open(&self) -> bool {
            self.open
        }
        fn describe(&self) -> String {
            "instant".into()
        }
    }

    /// Every byte is a sample.
    struct Bytes(DecodeStats);

    impl Decoder for Bytes {
        fn feed(&mut self, chunk: &[u8], at: Timestamp, out: &mut Vec<Sample>) {
            for _ in chunk {
                self.0.records += 1;
                out.push(Sample {
                    source: SourceId(0),
                    time: at,
                    reading: Reading::Button {
                        button: 0,
                        pressed: true,
                    },
                });
            }
        }
        fn stats(&self) -> DecodeStats {
            self.0
        }
        fn reset(&mut self) {}
    }

    #[test]
    fn a_polled_device_is_polled_at_its_own_rate() {
        let writes = Arc::new(Mutex::new(Vec::new()));
        let transport = Instant1 {
            writes: writes.clone(),
            pending: 0,
            open: false,
        };
        let interval = Duration::from_millis(15);
        let script = Script {
            poll: Some(vec![b'G']),
            poll_interval: interval,
            ..Default::default()
        };
        let mut d = Driver::new(
            "glove",
            SourceId(0),
            Box::new(transport),
            Box::new(Bytes(DecodeStats::default())),
            script,
        );
        d.open().unwrap();
        let mut out = Vec::new();
        // a line that answers at once would be polled thousands of times a second;
        // read calls as fast as they return give one poll per interval
        while out.len() < 5 {
            d.read(Duration::from_millis(50), &mut out).unwrap();
        }
        let w = writes.lock().unwrap();
        assert_eq!(w.len(), 5);
        for pair in w.windows(2) {
            assert!(pair[1] - pair[0] >= interval, "{:?}", pair[1] - pair[0]);
        }
    }

    /// A line that carries one byte a millisecond from the moment it opens.
    struct Stream1k {
        opened: Option<Instant>,
        taken: usize,
        reads: Arc<Mutex<Vec<Instant>>>,
    }

    impl Transport for Stream1k {
        fn open(&mut self) -> Result<(), DeviceError> {
            self.opened = Some(Instant::now());
            Ok(())
        }
        fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
            let now = Instant::now();
            let sent = self.opened.map_or(0, |o| (now - o).as_millis() as usize);
            let n = (sent - self.taken).min(buf.len());
            if n == 0 {
                std::thread::sleep(timeout.min(Duration::from_millis(1)));
                return Ok(0);
            }
            self.taken += n;
            self.reads.lock().unwrap().push(now);
            buf[..n].fill(7);
            Ok(n)
        }
        fn write(&mut self, _bytes: &[u8]) -> Result<(), DeviceError> {
            Ok(())
        }
        fn close(&mut self) {
            self.opened = None;
        }
        fn is_open(&self) -> bool {
            self.opened.is_some()
        }
        fn describe(&self) -> String {
            "stream".into()
        }
    }

    #[test]
    fn a_coalescing_stream_is_read_in_bulk_once_a_window() {
        let reads = Arc::new(Mutex::new(Vec::new()));
        let transport = Stream1k {
            opened: None,
            taken: 0,
            reads: reads.clone(),
        };
        let mut d = Driver::new(
            "tracker",
            SourceId(0),
            Box::new(transport),
            Box::new(Bytes(DecodeStats::default())),
            Script::default(),
        );
        let window = Duration::from_millis(10);
        d.set_coalesce(window);
        d.open().unwrap();
        let mut batches = Vec::new();
        while batches.len() < 6 {
            let mut out = Vec::new();
            d.read(Duration::from_millis(50), &mut out).unwrap();
            if !out.is_empty() {
                batches.push(out.len());
            }
        }
        // one read per window, each taking every record the window brought
        let r = reads.lock().unwrap();
        assert_eq!(r.len(), batches.len(), "{batches:?}");
        for pair in r.windows(2) {
            assert!(pair[1] - pair[0] >= window, "{:?}", pair[1] - pair[0]);
        }
        assert!(batches[1..].iter().all(|&n| n >= 10), "{batches:?}");
    }

    /// A line that only ever yields bytes without a valid record.
    struct Noise(u64, bool);

    impl Transport for Noise {
        fn open(&mut self) -> Result<(), DeviceError> {
            self.1 = true;
            Ok(())
        }
        fn read(&mut self, buf: &mut [u8], _timeout: Duration) -> Result<usize, DeviceError> {
            for b in buf.iter_mut().take(64) {
                self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1);
                // bytes without the Flock's phasing bit
                *b = (self.0 >> 33) as u8 & 0x7f;
            }
            Ok(64)
        }
        fn write(&mut self, _bytes: &[u8]) -> Result<(), DeviceError> {
            Ok(())
        }
        fn close(&mut self) {
            self.1 = false;
        }
        fn is_open(&self) -> bool {
            self.1
        }
        fn describe(&self) -> String {
            "noise".into()
        }
    }

    #[test]
    fn a_line_of_garbage_names_the_likely_cause() {
        let mut d = Driver::new(
            "tracker",
            SourceId(0),
            Box::new(Noise(7, false)),
            Box::new(crate::device::flock::FlockDecoder::new(
                SourceId(0),
                Default::default(),
            )),
            Script::default(),
        );
        d.set_garbage_hint("wrong baud rate? configured 115200".into());
        d.open().unwrap();
        let mut out = Vec::new();
        let err = loop {
            if let Err(e) = d.read(Duration::from_millis(10), &mut out) {
                break e.to_string();
            }
        };
        assert!(out.is_empty());
        assert!(
            err.contains("not one valid record: wrong baud rate? configured 115200"),
            "{err}"
        );
    }
}
