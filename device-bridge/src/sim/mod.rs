//! Simulated devices for tests, benches and demos: serial devices on pseudo-terminals
//! speaking their wire formats byte for byte ([`pty`], [`flock`], [`fastrak`],
//! [`cyberglove`]), a fake spacenavd socket ([`spacenavd`]), a fake VRPN server on
//! loopback ([`vrpn`]), recorded HID report streams ([`hid`]) and an in-memory
//! transport to replay them ([`scripted`]).

pub mod cyberglove;
pub mod fastrak;
pub mod flock;
pub mod hid;
pub mod pty;
pub mod scripted;
pub mod spacenavd;
pub mod vrpn;
