//! Record and replay of a session.
//!
//! `vsculpt-bridge record FILE` keeps the whole effective configuration (devices,
//! hands, calibration, menu, gates, rates — everything but the server link and its
//! token), every raw chunk each device delivered with its arrival time, the moments
//! devices were (re)opened and every change of a device's availability; `replay
//! FILE` feeds the chunks back through the very same decoders
//! ([`crate::config::build_decoder`]) and the same interaction, with the recorded
//! timestamps, so a replayed session produces exactly the commands the live one
//! did. `--speed` only paces the delivery.
//!
//! File layout (all integers little-endian):
//! * magic `VSBREC02`, `u32` length, then that many bytes of JSON: the
//!   configuration (a `VSBREC01` file holds only the device list);
//! * events until the end of the file, each `u8` tag, `u64` time in µs, `u16` device:
//!   tag 0 (frame) — `u32` length and the bytes; tag 1 (opened) — `u8` 1 and
//!   `u16` vendor, `u16` product when the device has a USB identity, else `u8` 0;
//!   tag 2 (status) — `u8` 0 open / 1 unavailable / 2 lost, `u32` length and the
//!   UTF-8 reason; tag 3 (datagram: one datagram of a lossy side channel, VRPN's
//!   UDP) — `u32` length and the bytes.

use crate::bridge::Input;
use crate::config::{Config, DeviceConfig, build_decoder};
use crate::device::runner::DeviceStatus;
use crate::device::{Decoder, RawFrame, SourceId, TapEvent, Timestamp};
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;
use std::sync::mpsc::{Sender, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use thiserror::Error;

/// File magic.
pub const MAGIC: &[u8; 8] = b"VSBREC02";
/// Magic of the first format (device list only).
pub const MAGIC_V1: &[u8; 8] = b"VSBREC01";
/// Longest status reason kept.
const MAX_REASON: u32 = 4096;
/// Largest frame accepted when reading (a device chunk is at most a few KiB).
const MAX_FRAME: u32 = 1 << 20;
/// Largest header accepted.
const MAX_HEADER: u32 = 1 << 24;

/// A recording that cannot be written or read.
#[derive(Debug, Error)]
pub enum RecordingError {
    /// I/O failure.
    #[error("recording i/o: {0}")]
    Io(#[from] std::io::Error),
    /// Not a recording, or damaged.
    #[error("not a valid recording: {0}")]
    Format(String),
}

fn write_event<W: Write>(w: &mut W, e: &TapEvent) -> std::io::Result<()> {
    match e {
        TapEvent::Frame(f) | TapEvent::Datagram(f) => {
            w.write_all(&[if matches!(e, TapEvent::Frame(_)) {
                0
            } else {
                3
            }])?;
            w.write_all(&f.time.0.to_le_bytes())?;
            w.write_all(&f.source.0.to_le_bytes())?;
            w.write_all(&(f.bytes.len() as u32).to_le_bytes())?;
            w.write_all(&f.bytes)
        }
        TapEvent::Opened {
            source,
            time,
            identity,
        } => {
            w.write_all(&[1])?;
            w.write_all(&time.0.to_le_bytes())?;
            w.write_all(&source.0.to_le_bytes())?;
            match identity {
                Some((v, p)) => {
                    w.write_all(&[1])?;
                    w.write_all(&v.to_le_bytes())?;
                    w.write_all(&p.to_le_bytes())
                }
                None => w.write_all(&[0]),
            }
        }
        TapEvent::Status {
            source,
            time,
            status,
        } => {
            w.write_all(&[2])?;
            w.write_all(&time.0.to_le_bytes())?;
            w.write_all(&source.0.to_le_bytes())?;
            let (kind, reason) = match status {
                DeviceStatus::Open => (0u8, ""),
                DeviceStatus::Unavailable(r) => (1, r.as_str()),
                DeviceStatus::Lost(r) => (2, r.as_str()),
            };
            let reason = &reason.as_bytes()[..reason.len().min(MAX_REASON as usize)];
            w.write_all(&[kind])?;
            w.write_all(&(reason.len() as u32).to_le_bytes())?;
            w.write_all(reason)
        }
    }
}

/// The configuration as a recording keeps it: without the server link, whose URL
/// carries a token.
pub fn recorded_config(config: &Config) -> Config {
    let mut c = config.clone();
    c.server = Default::default();
    c
}

/// Writes a recording from the events sent to its [`Recorder::tap`].
pub struct Recorder {
    tap: Sender<TapEvent>,
    thread: Option<JoinHandle<Result<u64, RecordingError>>>,
}

impl Recorder {
    /// Creates `path` for a session run with `config` (kept without its server
    /// link, see [`recorded_config`]) and starts the writer thread.
    pub fn create(path: &Path, config: &Config) -> Result<Self, RecordingError> {
        let mut w = BufWriter::new(std::fs::File::create(path)?);
        let header = serde_json::to_vec(&recorded_config(config))
            .map_err(|e| RecordingError::Format(e.to_string()))?;
        w.write_all(MAGIC)?;
        w.write_all(&(header.len() as u32).to_le_bytes())?;
        w.write_all(&header)?;
        w.flush()?;
        let (tap, rx) = channel::<TapEvent>();
        let thread = std::thread::spawn(move || -> Result<u64, RecordingError> {
            let mut n = 0u64;
            let mut last_flush = Instant::now();
            loop {
                match rx.recv_timeout(Duration::from_millis(200)) {
                    Ok(e) => {
                        write_event(&mut w, &e)?;
                        n += 1;
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
                }
                if last_flush.elapsed() > Duration::from_millis(500) {
                    w.flush()?;
                    last_flush = Instant::now();
                }
            }
            w.flush()?;
            Ok(n)
        });
        Ok(Self {
            tap,
            thread: Some(thread),
        })
    }

    /// A sender to hand to each driver ([`crate::device::Driver::set_tap`]).
    pub fn tap(&self) -> Sender<TapEvent> {
        self.tap.clone()
    }

    /// Stops once every tap is dropped; returns the number of events written.
    pub fn finish(mut self) -> Result<u64, RecordingError> {
        let (dummy, _) = channel();
        drop(std::mem::replace(&mut self.tap, dummy));
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| RecordingError::Format("recorder thread panicked".into()))?,
            None => Ok(0),
        }
    }
}

/// A recording opened for replay.
pub struct Recording {
    /// The configuration the session ran with (server link omitted).
    pub config: Config,
    reader: BufReader<std::fs::File>,
}

fn read_exact_or_eof<R: Read>(r: &mut R, buf: &mut [u8]) -> Result<bool, RecordingError> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..])? {
            0 if got == 0 => return Ok(false),
            0 => return Err(RecordingError::Format("truncated event".into())),
            n => got += n,
        }
    }
    Ok(true)
}

impl Recording {
    /// Opens `path` and reads its header.
    pub fn open(path: &Path) -> Result<Self, RecordingError> {
        let mut reader = BufReader::new(std::fs::File::open(path)?);
        let mut magic = [0u8; 8];
        if !read_exact_or_eof(&mut reader, &mut magic)? || (&magic != MAGIC && &magic != MAGIC_V1) {
            return Err(RecordingError::Format("bad magic".into()));
        }
        let mut len = [0u8; 4];
        if !read_exact_or_eof(&mut reader, &mut len)? {
            return Err(RecordingError::Format("no header".into()));
        }
        let len = u32::from_le_bytes(len);
        if len > MAX_HEADER {
            return Err(RecordingError::Format("header too large".into()));
        }
        let mut header = vec![0u8; len as usize];
        if !read_exact_or_eof(&mut reader, &mut header)? {
            return Err(RecordingError::Format("no header".into()));
        }
        let bad = |e: serde_json::Error| RecordingError::Format(e.to_string());
        let config = if &magic == MAGIC_V1 {
            let devices: Vec<DeviceConfig> = serde_json::from_slice(&header).map_err(bad)?;
            Config {
                devices,
                ..Default::default()
            }
        } else {
            serde_json::from_slice(&header).map_err(bad)?
        };
        config
            .validate()
            .map_err(|e| RecordingError::Format(format!("recorded configuration: {e}")))?;
        Ok(Self { config, reader })
    }

    /// The recorded devices.
    pub fn devices(&self) -> &[DeviceConfig] {
        &self.config.devices
    }

    /// The next event; `Ok(None)` at the end.
    pub fn next_event(&mut self) -> Result<Option<TapEvent>, RecordingError> {
        let r = &mut self.reader;
        let mut head = [0u8; 11];
        if !read_exact_or_eof(r, &mut head)? {
            return Ok(None);
        }
        let time = Timestamp(u64::from_le_bytes(
            head[1..9].try_into().unwrap_or_default(),
        ));
        let source = SourceId(u16::from_le_bytes([head[9], head[10]]));
        if usize::from(source.0) >= self.config.devices.len() {
            return Err(RecordingError::Format(format!(
                "unknown device {}",
                source.0
            )));
        }
        match head[0] {
            tag @ (0 | 3) => {
                let mut len = [0u8; 4];
                if !read_exact_or_eof(r, &mut len)? {
                    return Err(RecordingError::Format("truncated frame".into()));
                }
                let len = u32::from_le_bytes(len);
                if len > MAX_FRAME {
                    return Err(RecordingError::Format("frame too large".into()));
                }
                let mut bytes = vec![0u8; len as usize];
                if len > 0 && !read_exact_or_eof(r, &mut bytes)? {
                    return Err(RecordingError::Format("truncated frame".into()));
                }
                let frame = RawFrame {
                    source,
                    time,
                    bytes,
                };
                Ok(Some(if tag == 0 {
                    TapEvent::Frame(frame)
                } else {
                    TapEvent::Datagram(frame)
                }))
            }
            1 => {
                let mut flag = [0u8; 1];
                if !read_exact_or_eof(r, &mut flag)? {
                    return Err(RecordingError::Format("truncated open event".into()));
                }
                let identity = if flag[0] == 1 {
                    let mut ids = [0u8; 4];
                    if !read_exact_or_eof(r, &mut ids)? {
                        return Err(RecordingError::Format("truncated open event".into()));
                    }
                    Some((
                        u16::from_le_bytes([ids[0], ids[1]]),
                        u16::from_le_bytes([ids[2], ids[3]]),
                    ))
                } else {
                    None
                };
                Ok(Some(TapEvent::Opened {
                    source,
                    time,
                    identity,
                }))
            }
            2 => {
                let mut head = [0u8; 5];
                if !read_exact_or_eof(r, &mut head)? {
                    return Err(RecordingError::Format("truncated status event".into()));
                }
                let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]);
                if len > MAX_REASON {
                    return Err(RecordingError::Format("status reason too long".into()));
                }
                let mut reason = vec![0u8; len as usize];
                if len > 0 && !read_exact_or_eof(r, &mut reason)? {
                    return Err(RecordingError::Format("truncated status event".into()));
                }
                let reason = String::from_utf8_lossy(&reason).into_owned();
                let status = match head[0] {
                    0 => DeviceStatus::Open,
                    1 => DeviceStatus::Unavailable(reason),
                    2 => DeviceStatus::Lost(reason),
                    k => return Err(RecordingError::Format(format!("unknown status {k}"))),
                };
                Ok(Some(TapEvent::Status {
                    source,
                    time,
                    status,
                }))
            }
            t => Err(RecordingError::Format(format!("unknown event tag {t}"))),
        }
    }
}

/// Replays a recording through fresh decoders.
pub struct Replayer {
    recording: Recording,
    decoders: Vec<Box<dyn Decoder>>,
}

impl Replayer {
    /// Opens `path` and builds one decoder per recorded device.
    pub fn open(path: &Path) -> Result<Self, RecordingError> {
        let recording = Recording::open(path)?;
        let decoders = recording
            .config
            .devices
            .iter()
            .enumerate()
            .map(|(i, d)| build_decoder(SourceId(i as u16), d))
            .collect();
        Ok(Self {
            recording,
            decoders,
        })
    }

    /// The recorded devices.
    pub fn devices(&self) -> &[DeviceConfig] {
        self.recording.devices()
    }

    /// The recorded configuration (server link omitted).
    pub fn config(&self) -> &Config {
        &self.recording.config
    }

    /// Plays the recording at `speed` × real time (`f64::INFINITY` = as fast as
    /// possible), handing each batch of samples and each recorded status change to
    /// `sink` (false stops). Samples carry their recorded times whatever the speed:
    /// the speed only paces the delivery. Returns the number of samples produced.
    pub fn play(
        mut self,
        speed: f64,
        mut sink: impl FnMut(Input) -> bool,
    ) -> Result<u64, RecordingError> {
        if speed.is_nan() || speed <= 0.0 {
            return Err(RecordingError::Format(format!(
                "speed must be positive, got {speed}"
            )));
        }
        let start = Instant::now();
        let mut first: Option<Timestamp> = None;
        let mut out = Vec::new();
        let mut produced = 0u64;
        while let Some(event) = self.recording.next_event()? {
            let (source, time) = match &event {
                TapEvent::Frame(f) | TapEvent::Datagram(f) => (f.source, f.time),
                TapEvent::Opened { source, time, .. } | TapEvent::Status { source, time, .. } => {
                    (*source, *time)
                }
            };
            let t0 = *first.get_or_insert(time);
            let offset = time
                .since(t0)
                .div_f64(if speed.is_finite() { speed } else { f64::MAX });
            if speed.is_finite() {
                let due = start + offset;
                let now = Instant::now();
                if due > now {
                    std::thread::sleep(due - now);
                }
            }
            let decoder = &mut self.decoders[usize::from(source.0)];
            let (f, datagram) = match event {
                TapEvent::Opened { identity, .. } => {
                    decoder.reset();
                    if let Some(ids) = identity {
                        decoder.set_identity(ids);
                    }
                    continue;
                }
                TapEvent::Status { status, .. } => {
                    if !sink(Input::Status(source, status)) {
                        break;
                    }
                    continue;
                }
                TapEvent::Frame(f) => (f, false),
                TapEvent::Datagram(f) => (f, true),
            };
            out.clear();
            if datagram {
                decoder.feed_datagram(&f.bytes, f.time, &mut out);
            } else {
                decoder.feed(&f.bytes, f.time, &mut out);
            }
            if decoder.fatal().is_some() {
                // As live: the link would be reopened; start the decoder afresh.
                decoder.reset();
            }
            if !out.is_empty() {
                produced += out.len() as u64;
                if !sink(Input::Samples(std::mem::take(&mut out))) {
                    break;
                }
            }
        }
        Ok(produced)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DeviceKind;
    use crate::device::flock::{FlockSettings, encode_record, pose_words};
    use glam::{DQuat, DVec3};

    fn temp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("vsculpt-rec-{}-{name}", std::process::id()))
    }

    /// VRPN's UDP datagrams are recorded as datagrams and replayed through the
    /// decoder's datagram path: a duplicate is dropped in replay as it was live.
    #[test]
    fn datagrams_replay_as_datagrams() {
        use crate::device::vrpn::{
            POS_QUAT, SENDER_DESCRIPTION, TYPE_DESCRIPTION, cookie, encode_description,
            encode_pos_quat,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("udp.vsbrec");
        let mut vrpn = DeviceConfig::new("studio", DeviceKind::Vrpn);
        vrpn.address = Some("Tracker0@host".into());
        let config = Config {
            devices: vec![vrpn],
            ..Default::default()
        };
        let rec = Recorder::create(&path, &config).unwrap();
        let tap = rec.tap();
        let mut tcp = cookie().to_vec();
        tcp.extend(encode_description(SENDER_DESCRIPTION, 0, "Tracker0"));
        tcp.extend(encode_description(TYPE_DESCRIPTION, 4, POS_QUAT));
        let frame = |t: u64, bytes: Vec<u8>| RawFrame {
            source: SourceId(0),
            time: Timestamp(t),
            bytes,
        };
        let udp = |seq: u32, x: f64| {
            let mut m = crate::device::vrpn::encode_message(
                1,
                seq,
                0,
                4,
                &encode_pos_quat(0, [x, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
            );
            m[20..24].copy_from_slice(&seq.to_be_bytes());
            m
        };
        tap.send(TapEvent::Frame(frame(10, tcp))).unwrap();
        for (t, seq, x) in [(20, 1, 0.1), (30, 1, 0.1), (40, 2, 0.2)] {
            tap.send(TapEvent::Datagram(frame(t, udp(seq, x)))).unwrap();
        }
        drop(tap);
        assert_eq!(rec.finish().unwrap(), 4);
        let mut xs = Vec::new();
        Replayer::open(&path)
            .unwrap()
            .play(f64::INFINITY, |i| {
                if let Input::Samples(s) = i {
                    for s in s {
                        if let crate::device::Reading::Pose { position, .. } = s.reading {
                            xs.push(position.x);
                        }
                    }
                }
                true
            })
            .unwrap();
        assert_eq!(xs, vec![0.1, 0.2]);
    }

    #[test]
    fn round_trip_reproduces_the_samples() {
        let path = temp("rt");
        let mut flock = DeviceConfig::new("tracker", DeviceKind::Flock);
        flock.port = Some("/dev/null".into());
        let mouse = DeviceConfig::new("mouse", DeviceKind::SpacemouseHid);
        let devices = vec![flock.clone(), mouse];
        let config = Config {
            devices: devices.clone(),
            ..Default::default()
        };
        let rec = Recorder::create(&path, &config).unwrap();
        let tap = rec.tap();
        let s = FlockSettings::default();
        let rec_bytes = encode_record(
            &pose_words(&s, DVec3::new(0.1, 0.0, 0.0), DQuat::IDENTITY),
            None,
            None,
        );
        tap.send(TapEvent::Opened {
            source: SourceId(1),
            time: Timestamp(10),
            identity: Some((0x046d, 0xc603)),
        })
        .unwrap();
        // a record split over two frames, garbage in between
        tap.send(TapEvent::Frame(RawFrame {
            source: SourceId(0),
            time: Timestamp(100),
            bytes: rec_bytes[..5].to_vec(),
        }))
        .unwrap();
        tap.send(TapEvent::Frame(RawFrame {
            source: SourceId(0),
            time: Timestamp(200),
            bytes: rec_bytes[5..].to_vec(),
        }))
        .unwrap();
        tap.send(TapEvent::Frame(RawFrame {
            source: SourceId(0),
            time: Timestamp(300),
            bytes: vec![1, 2, 3],
        }))
        .unwrap();
        // 13-byte report from a Plus XT (no axis swap): y stays y
        let mut rep = vec![1u8];
        for v in [0i16, 175, 0, 0, 0, 0] {
            rep.extend_from_slice(&v.to_le_bytes());
        }
        tap.send(TapEvent::Frame(RawFrame {
            source: SourceId(1),
            time: Timestamp(400),
            bytes: rep,
        }))
        .unwrap();
        drop(tap);
        assert_eq!(rec.finish().unwrap(), 5);

        let r = Replayer::open(&path).unwrap();
        assert_eq!(r.devices(), &devices[..]);
        let mut got = Vec::new();
        let n = r
            .play(f64::INFINITY, |i| {
                if let Input::Samples(s) = i {
                    got.extend(s);
                }
                true
            })
            .unwrap();
        assert_eq!(n, 2);
        assert_eq!(got[0].source, SourceId(0));
        assert!(
            matches!(got[0].reading, crate::device::Reading::Pose { position, .. } if (position.x - 0.1).abs() < 1e-3)
        );
        assert!(
            // half deflection through the default dead zone of 0.05: (0.5 − 0.05) / 0.95
            matches!(got[1].reading, crate::device::Reading::Motion { translation, .. } if (translation.y - 0.45 / 0.95).abs() < 1e-12)
        );
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn damaged_files_are_errors_not_panics() {
        let path = temp("bad");
        std::fs::write(&path, b"NOTAREC!").unwrap();
        assert!(Replayer::open(&path).is_err());
        let mut flock = DeviceConfig::new("tracker", DeviceKind::Flock);
        flock.port = Some("/dev/null".into());
        let config = Config {
            devices: vec![flock],
            ..Default::default()
        };
        let rec = Recorder::create(&path, &config).unwrap();
        rec.tap()
            .send(TapEvent::Frame(RawFrame {
                source: SourceId(0),
                time: Timestamp(1),
                bytes: vec![0x80; 20],
            }))
            .unwrap();
        rec.finish().unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        bytes.truncate(bytes.len() - 3);
        bytes.extend_from_slice(&[9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9]);
        std::fs::write(&path, &bytes).unwrap();
        let r = Replayer::open(&path).unwrap();
        assert!(r.play(f64::INFINITY, |_| true).is_err());
        let r = Replayer::open(&path).unwrap();
        assert!(r.play(0.0, |_| true).is_err());
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn replay_paces_at_the_requested_speed() {
        let path = temp("pace");
        let mut flock = DeviceConfig::new("tracker", DeviceKind::Flock);
        flock.port = Some("/dev/null".into());
        let config = Config {
            devices: vec![flock],
            ..Default::default()
        };
        let rec = Recorder::create(&path, &config).unwrap();
        let s = FlockSettings::default();
        let bytes = encode_record(&pose_words(&s, DVec3::ZERO, DQuat::IDENTITY), None, None);
        for i in 0..3u64 {
            rec.tap()
                .send(TapEvent::Frame(RawFrame {
                    source: SourceId(0),
                    time: Timestamp(i * 100_000),
                    bytes: bytes.clone(),
                }))
                .unwrap();
        }
        rec.finish().unwrap();
        let mut times = Vec::new();
        let t = Instant::now();
        Replayer::open(&path)
            .unwrap()
            .play(2.0, |i| {
                if let Input::Samples(s) = i {
                    times.push(s[0].time);
                }
                true
            })
            .unwrap();
        // 200 ms recorded at speed 2 takes at least 100 ms; the samples keep their
        // recorded times (100 ms apart): the speed paces the delivery only
        assert!(t.elapsed() >= Duration::from_millis(100));
        assert_eq!(
            times,
            vec![Timestamp(0), Timestamp(100_000), Timestamp(200_000)]
        );
        let _ = std::fs::remove_file(&path);
    }
}
