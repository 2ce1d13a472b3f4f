//! `vsculpt-bridge --list`: what the bridge can see — USB HID devices (3D mice
//! marked), serial ports, the spacenavd socket and the configured VRPN sources.
//! Every probe reports its own failure as text; none makes the listing fail.

use crate::config::{Config, DeviceKind};
use crate::device::spacemouse_hid::{SpaceMouseSettings, model};
use crate::device::spacenavd::SpacenavdSettings;
use std::fmt::Write as _;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

/// One HID device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HidEntry {
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// Product string, if any.
    pub name: String,
    /// OS path.
    pub path: String,
    /// True when the (vendor, product) is on the 3D-mouse allow-list.
    pub is_3d_mouse: bool,
}

/// What the bridge can see.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Listing {
    /// HID devices, or why they could not be enumerated.
    pub hid: Result<Vec<HidEntry>, String>,
    /// Serial port paths, or why they could not be enumerated.
    pub serial: Result<Vec<String>, String>,
    /// The spacenavd socket path and whether it exists.
    pub spacenavd: (String, bool),
    /// Configured VRPN sources: (name, address, reachable).
    pub vrpn: Vec<(String, String, bool)>,
}

/// Probes everything; `config` adds its extra HID ids, spacenavd socket and VRPN sources.
pub fn probe(config: Option<&Config>) -> Listing {
    let mut allow = SpaceMouseSettings::default().allow_list();
    let mut spnav = SpacenavdSettings::default();
    let mut vrpn = Vec::new();
    if let Some(c) = config {
        for d in &c.devices {
            match d.kind {
                DeviceKind::SpacemouseHid => allow.extend(d.spacemouse.allow_list()),
                DeviceKind::Spacenavd => spnav = d.spacenavd.clone(),
                DeviceKind::Vrpn => {
                    let addr = d.vrpn_address().unwrap_or_default();
                    let reachable = addr
                        .to_socket_addrs()
                        .ok()
                        .and_then(|mut a| a.next())
                        .is_some_and(|a| {
                            TcpStream::connect_timeout(&a, Duration::from_millis(300)).is_ok()
                        });
                    vrpn.push((format!("{}@{}", d.vrpn.device, d.name), addr, reachable));
                }
                _ => {}
            }
        }
    }
    let hid = hidapi::HidApi::new().map_err(|e| e.to_string()).map(|api| {
        api.device_list()
            .map(|d| HidEntry {
                vendor: d.vendor_id(),
                product: d.product_id(),
                name: d.product_string().unwrap_or_default().to_owned(),
                path: d.path().to_string_lossy().into_owned(),
                is_3d_mouse: allow.contains(&(d.vendor_id(), d.product_id())),
            })
            .collect()
    });
    let serial = serialport::available_ports()
        .map(|ports| ports.into_iter().map(|p| p.port_name).collect())
        .map_err(|e| e.to_string());
    let path = spnav.socket_path();
    let exists = std::path::Path::new(&path).exists();
    Listing {
        hid,
        serial,
        spacenavd: (path, exists),
        vrpn,
    }
}

impl Listing {
    /// Human-readable text.
    pub fn render(&self) -> String {
        let mut s = String::new();
        match &self.hid {
            Ok(list) => {
                let _ = writeln!(s, "HID devices: {}", list.len());
                for d in list {
                    let known = model(d.vendor, d.product).map(|m| m.name).unwrap_or("");
                    let mark = if d.is_3d_mouse { " [3D mouse]" } else { "" };
                    let _ = writeln!(
                        s,
                        "  {:04x}:{:04x} {} {}{} {}",
                        d.vendor, d.product, d.name, known, mark, d.path
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(s, "HID devices: unavailable ({e})");
            }
        }
        match &self.serial {
            Ok(list) => {
                let _ = writeln!(s, "serial ports: {}", list.len());
                for p in list {
                    let _ = writeln!(s, "  {p}");
                }
            }
            Err(e) => {
                let _ = writeln!(s, "serial ports: unavailable ({e})");
            }
        }
        let (path, exists) = &self.spacenavd;
        let _ = writeln!(
            s,
            "spacenavd: {path} ({})",
            if *exists { "present" } else { "not running" }
        );
        let _ = writeln!(s, "VRPN sources: {}", self.vrpn.len());
        for (name, addr, ok) in &self.vrpn {
            let _ = writeln!(
                s,
                "  {name} at {addr} ({})",
                if *ok { "reachable" } else { "unreachable" }
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DeviceConfig;

    #[test]
    fn probing_without_hardware_does_not_fail() {
        let mut c = Config::default();
        let mut v = DeviceConfig::new("studio", DeviceKind::Vrpn);
        v.address = Some("127.0.0.1:1".into());
        c.devices.push(v);
        let l = probe(Some(&c));
        let text = l.render();
        assert!(text.contains("HID devices"));
        assert!(text.contains("serial ports"));
        assert!(text.contains("spacenavd"));
        assert!(text.contains("Tracker0@studio at 127.0.0.1:1 (unreachable)"));
    }

    #[test]
    fn renders_marks_3d_mice() {
        let l = Listing {
            hid: Ok(vec![HidEntry {
                vendor: 0x256f,
                product: 0xc635,
                name: "SpaceMouse Compact".into(),
                path: "/dev/hidraw0".into(),
                is_3d_mouse: true,
            }]),
            serial: Err("no sysfs".into()),
            spacenavd: ("/var/run/spnav.sock".into(), false),
            vrpn: vec![],
        };
        let t = l.render();
        assert!(t.contains("256f:c635"));
        assert!(t.contains("[3D mouse]"));
        assert!(t.contains("unavailable (no sysfs)"));
    }
}
