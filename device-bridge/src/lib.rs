//! vsculpt-bridge: the device daemon that turns studio hardware — 3D mice,
//! 6-DOF trackers and data gloves — into sculpting input for the vsculpt server.
//!
//! * [`device`] — drivers: transports, pure decoders of each family's wire format.
//! * [`sim`] — simulated devices (pty serial devices, fake spacenavd and VRPN servers, recorded HID streams).
//! * [`config`] — the TOML configuration and the driver factory.
//! * [`hand`] — tracker + glove → hand pose and gesture.
//! * [`spring`] — the adaptive spring of a load drag.
//! * [`interaction`] — grab / drag / release and the 3D-mouse menu, as a pure state machine.
//! * [`listing`] — `--list`: HID devices, serial ports, spacenavd, VRPN sources.
//! * [`recording`] — record raw device traffic, replay it through the same decoders.

pub mod config;
pub mod device;
pub mod hand;
pub mod interaction;
pub mod listing;
pub mod recording;
pub mod sim;
pub mod spring;
