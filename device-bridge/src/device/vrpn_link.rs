//! VRPN's two channels as one transport: the TCP connection (cookies,
//! descriptions, pings — VRPN's reliable class) and a UDP port on which the
//! server sends its low-latency messages (tracker reports), as VRPN's own
//! clients ask for unless they are TCP-only (`vrpn_Connection.C`
//! `finish_new_connection_setup`).
//!
//! On open the transport connects over TCP, binds a UDP socket on the address
//! the TCP connection left from (VRPN's `pack_udp_description` does the same,
//! so the server has a route back), and sends our cookie followed by the UDP
//! description ([`super::vrpn::udp_description`]). Reads wait on both sockets;
//! a datagram is returned whole and flagged
//! ([`Transport::last_read_was_datagram`]) so the decoder reads it as
//! datagram, never as stream bytes. Datagrams from any address but the
//! server's are ignored.

use super::driver::{DeviceError, Transport};
use super::vrpn::{cookie, udp_description};
use std::io::{Read, Write};
use std::net::{IpAddr, SocketAddr, TcpStream, ToSocketAddrs, UdpSocket};
use std::os::fd::AsRawFd;
use std::time::{Duration, Instant};

/// The two sockets of an open VRPN connection.
struct Channels {
    tcp: TcpStream,
    udp: UdpSocket,
    server: IpAddr,
}

/// A VRPN connection with its UDP channel (`Device@host[:port]`).
pub struct VrpnUdpTransport {
    addr: String,
    connect_timeout: Duration,
    open: Option<Channels>,
    datagram: bool,
}

impl VrpnUdpTransport {
    /// A connection to the VRPN server at `addr` (`host:port`).
    pub fn new(addr: impl Into<String>) -> Self {
        Self {
            addr: addr.into(),
            connect_timeout: Duration::from_secs(2),
            open: None,
            datagram: false,
        }
    }

    /// The UDP port the server is told to send to (while open).
    pub fn udp_port(&self) -> Option<u16> {
        self.open
            .as_ref()
            .and_then(|c| c.udp.local_addr().ok())
            .map(|a| a.port())
    }

    fn connect(&self) -> Result<TcpStream, DeviceError> {
        let addrs: Vec<SocketAddr> = self
            .addr
            .to_socket_addrs()
            .map_err(|e| DeviceError::NotFound(format!("{}: {e}", self.addr)))?
            .collect();
        let mut last = DeviceError::NotFound(self.addr.clone());
        for a in addrs {
            match TcpStream::connect_timeout(&a, self.connect_timeout) {
                Ok(s) => return Ok(s),
                Err(e) => last = DeviceError::NotFound(format!("{a}: {e}")),
            }
        }
        Err(last)
    }
}

/// Waits up to `timeout` for either socket to be readable; returns (tcp, udp).
fn wait_readable(c: &Channels, timeout: Duration) -> Result<(bool, bool), DeviceError> {
    let mut fds = [
        libc::pollfd {
            fd: c.tcp.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        },
        libc::pollfd {
            fd: c.udp.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        },
    ];
    let ms = i32::try_from(timeout.as_micros().div_ceil(1000)).unwrap_or(i32::MAX);
    // SAFETY: `fds` is a valid array of two pollfd for the call's duration.
    let n = unsafe { libc::poll(fds.as_mut_ptr(), 2, ms) };
    if n < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() == std::io::ErrorKind::Interrupted {
            return Ok((false, false));
        }
        return Err(e.into());
    }
    let ready = |f: &libc::pollfd| f.revents & (libc::POLLIN | libc::POLLHUP | libc::POLLERR) != 0;
    Ok((ready(&fds[0]), ready(&fds[1])))
}

impl Transport for VrpnUdpTransport {
    fn open(&mut self) -> Result<(), DeviceError> {
        let mut tcp = self.connect()?;
        tcp.set_nodelay(true).map_err(DeviceError::from)?;
        let local = tcp.local_addr().map_err(DeviceError::from)?;
        let server = tcp.peer_addr().map_err(DeviceError::from)?.ip();
        let udp = UdpSocket::bind(SocketAddr::new(local.ip(), 0)).map_err(DeviceError::from)?;
        let port = udp.local_addr().map_err(DeviceError::from)?.port();
        let mut hello = cookie().to_vec();
        hello.extend(udp_description(port, &local.ip().to_string()));
        tcp.write_all(&hello).map_err(DeviceError::from)?;
        self.open = Some(Channels { tcp, udp, server });
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, DeviceError> {
        let c = self.open.as_mut().ok_or(DeviceError::NotOpen)?;
        let end = Instant::now() + timeout;
        loop {
            let (tcp, udp) = wait_readable(c, end.saturating_duration_since(Instant::now()))?;
            // TCP first: it carries the descriptions a datagram's messages need.
            if tcp {
                self.datagram = false;
                return match c.tcp.read(buf) {
                    Ok(0) => Err(DeviceError::Disconnected),
                    Ok(n) => Ok(n),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(0),
                    Err(e) => Err(e.into()),
                };
            }
            if udp {
                let (n, from) = c.udp.recv_from(buf).map_err(DeviceError::from)?;
                if from.ip() == c.server && n > 0 {
                    self.datagram = true;
                    return Ok(n);
                }
            }
            if Instant::now() >= end {
                return Ok(0);
            }
        }
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), DeviceError> {
        let c = self.open.as_mut().ok_or(DeviceError::NotOpen)?;
        c.tcp.write_all(bytes).map_err(DeviceError::from)
    }

    fn close(&mut self) {
        self.open = None;
    }

    fn is_open(&self) -> bool {
        self.open.is_some()
    }

    fn describe(&self) -> String {
        format!("vrpn tcp+udp {}", self.addr)
    }

    fn last_read_was_datagram(&self) -> bool {
        self.datagram
    }
}
