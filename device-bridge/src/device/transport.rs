//! Byte transports: the four kinds of link a device sits behind — an RS-232
//! port (`serialport`), a USB HID device (`hidapi`), an AF_UNIX stream socket
//! (spacenavd) and a TCP connection (VRPN). Each implements
//! [`Transport`]; none of them knows anything about the bytes it carries.

use super::driver::{DeviceError, Transport};
use std::ffi::CString;
use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::Duration;

/// Shortest timeout handed to the OS (a zero timeout means "block forever" to some APIs).
const MIN_TIMEOUT: Duration = Duration::from_millis(1);

fn clamp_timeout(t: Duration) -> Duration {
    t.max(MIN_TIMEOUT)
}

fn is_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::TimedOut
            | std::io::ErrorKind::WouldBlock
            | std::io::ErrorKind::Interrupted
    )
}

/// An RS-232 port (8N1, no flow control) opened by path.
pub struct SerialTransport {
    path: String,
    baud: u32,
    port: Option<serialport::TTYPort>,
}

impl SerialTransport {
    /// A port at `path` (e.g. `/dev/ttyUSB0`) at `baud`.
    pub fn new(path: impl Into<String>, baud: u32) -> Self {
        Self {
            path: path.into(),
            baud,
            port: None,
        }
    }
}

impl Transport for SerialTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        if !std::path::Path::new(&self.path).exists() {
            return Err(DeviceError::NotFound(self.path.clone()));
        }
        let port = serialport::new(&self.path, self.baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::from_millis(10))
            .open_native()
            .map_err(|e| match e.kind() {
                serialport::ErrorKind::NoDevice => DeviceError::NotFound(self.path.clone()),
                _ => DeviceError::Io(format!("{}: {e}", self.path)),
            })?;
        self.port = Some(port);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
        let port = self.port.as_mut().ok_or(DeviceError::NotOpen)?;
        serialport::SerialPort::set_timeout(port, clamp_timeout(timeout))
            .map_err(|e| DeviceError::Io(e.to_string()))?;
        match port.read(buf) {
            Ok(n) => Ok(n),
            Err(e) if is_timeout(&e) => Ok(0),
            Err(e) => Err(DeviceError::Io(format!("{}: {e}", self.path))),
        }
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        let port = self.port.as_mut().ok_or(DeviceError::NotOpen)?;
        port.write_all(bytes)
            .and_then(|_| port.flush())
            .map_err(|e| DeviceError::Io(format!("{}: {e}", self.path)))
    }

    fn close(&mut self) {
        self.port = None;
    }

    fn is_open(&self) -> bool {
        self.port.is_some()
    }

    fn describe(&self) -> String {
        format!("serial {} @ {} baud", self.path, self.baud)
    }
}

/// Which HID device to open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HidSelector {
    /// The first device whose (vendor, product) is in the list.
    AnyOf(Vec<(u16, u16)>),
    /// A device by its OS path (e.g. `/dev/hidraw3`).
    Path(String),
}

/// A USB HID device read one input report at a time (report id in byte 0).
pub struct HidTransport {
    selector: HidSelector,
    device: Option<hidapi::HidDevice>,
    opened: Option<(u16, u16)>,
}

impl HidTransport {
    /// A transport for the device chosen by `selector`.
    pub fn new(selector: HidSelector) -> Self {
        Self {
            selector,
            device: None,
            opened: None,
        }
    }
}

impl Transport for HidTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        let api = hidapi::HidApi::new().map_err(|e| DeviceError::Io(e.to_string()))?;
        let (device, ids) = match &self.selector {
            HidSelector::Path(p) => {
                let c = CString::new(p.as_bytes()).map_err(|_| DeviceError::NotFound(p.clone()))?;
                let d = api
                    .open_path(&c)
                    .map_err(|e| DeviceError::NotFound(format!("{p}: {e}")))?;
                let ids = d
                    .get_device_info()
                    .map(|i| (i.vendor_id(), i.product_id()))
                    .unwrap_or((0, 0));
                (d, ids)
            }
            HidSelector::AnyOf(list) => {
                let info = api
                    .device_list()
                    .find(|d| list.contains(&(d.vendor_id(), d.product_id())))
                    .ok_or_else(|| DeviceError::NotFound("no allowed 3D mouse on USB".into()))?;
                let ids = (info.vendor_id(), info.product_id());
                let d = info
                    .open_device(&api)
                    .map_err(|e| DeviceError::Io(e.to_string()))?;
                (d, ids)
            }
        };
        self.device = Some(device);
        self.opened = Some(ids);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
        let dev = self.device.as_ref().ok_or(DeviceError::NotOpen)?;
        let ms = i32::try_from(clamp_timeout(timeout).as_millis()).unwrap_or(i32::MAX);
        dev.read_timeout(buf, ms)
            .map_err(|e| DeviceError::Io(e.to_string()))
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        let dev = self.device.as_ref().ok_or(DeviceError::NotOpen)?;
        dev.write(bytes)
            .map(|_| ())
            .map_err(|e| DeviceError::Io(e.to_string()))
    }

    fn close(&mut self) {
        self.device = None;
    }

    fn is_open(&self) -> bool {
        self.device.is_some()
    }

    fn identity(&self) -> Option<(u16, u16)> {
        self.opened
    }

    fn describe(&self) -> String {
        match &self.selector {
            HidSelector::Path(p) => format!("hid {p}"),
            HidSelector::AnyOf(l) => format!("hid (any of {} ids)", l.len()),
        }
    }
}

/// Reads from a stream socket with a timeout; `Ok(0)` on timeout, `Disconnected` on EOF.
fn read_stream<S: Read>(
    s: &mut S,
    set: impl FnOnce(&S, Duration) -> std::io::Result<()>,
    buf: &mut [u8],
    timeout: Duration,
) -> Result<usize, DeviceError> {
    set(s, clamp_timeout(timeout)).map_err(DeviceError::from)?;
    match s.read(buf) {
        Ok(0) => Err(DeviceError::Disconnected),
        Ok(n) => Ok(n),
        Err(e) if is_timeout(&e) => Ok(0),
        Err(e) => Err(e.into()),
    }
}

/// An AF_UNIX stream socket (spacenavd's `/var/run/spnav.sock`).
pub struct UnixTransport {
    path: PathBuf,
    stream: Option<UnixStream>,
}

impl UnixTransport {
    /// A socket at `path`.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            stream: None,
        }
    }
}

impl Transport for UnixTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        let s = UnixStream::connect(&self.path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound | std::io::ErrorKind::ConnectionRefused => {
                DeviceError::NotFound(self.path.display().to_string())
            }
            _ => DeviceError::Io(e.to_string()),
        })?;
        self.stream = Some(s);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
        let s = self.stream.as_mut().ok_or(DeviceError::NotOpen)?;
        read_stream(s, |s, t| s.set_read_timeout(Some(t)), buf, timeout)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        let s = self.stream.as_mut().ok_or(DeviceError::NotOpen)?;
        s.write_all(bytes).map_err(DeviceError::from)
    }

    fn close(&mut self) {
        self.stream = None;
    }

    fn is_open(&self) -> bool {
        self.stream.is_some()
    }

    fn describe(&self) -> String {
        format!("unix socket {}", self.path.display())
    }
}

/// A TCP connection with Nagle off (VRPN's TCP-only mode).
pub struct TcpTransport {
    addr: String,
    connect_timeout: Duration,
    stream: Option<TcpStream>,
}

impl TcpTransport {
    /// A connection to `addr` (`host:port`).
    pub fn new(addr: impl Into<String>) -> Self {
        Self {
            addr: addr.into(),
            connect_timeout: Duration::from_secs(2),
            stream: None,
        }
    }
}

impl Transport for TcpTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        let addrs: Vec<_> = self
            .addr
            .to_socket_addrs()
            .map_err(|e| DeviceError::NotFound(format!("{}: {e}", self.addr)))?
            .collect();
        let mut last = DeviceError::NotFound(self.addr.clone());
        for a in addrs {
            match TcpStream::connect_timeout(&a, self.connect_timeout) {
                Ok(s) => {
                    s.set_nodelay(true).map_err(DeviceError::from)?;
                    self.stream = Some(s);
                    return Ok(());
                }
                Err(e) => last = DeviceError::NotFound(format!("{a}: {e}")),
            }
        }
        Err(last)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
        let s = self.stream.as_mut().ok_or(DeviceError::NotOpen)?;
        read_stream(s, |s, t| s.set_read_timeout(Some(t)), buf, timeout)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        let s = self.stream.as_mut().ok_or(DeviceError::NotOpen)?;
        s.write_all(bytes).map_err(DeviceError::from)
    }

    fn close(&mut self) {
        self.stream = None;
    }

    fn is_open(&self) -> bool {
        self.stream.is_some()
    }

    fn describe(&self) -> String {
        format!("tcp {}", self.addr)
    }
}
