//! vsculpt-bridge: the device daemon that turns studio hardware — 3D mice,
//! 6-DOF trackers and data gloves — into sculpting input for the vsculpt server.
//!
//! * [`bridge`] — the running bridge: devices or a replay → interaction → link.
//! * [`device`] — drivers: transports, pure decoders of each family's wire format.
//! * [`sim`] — simulated devices (pty serial devices, fake spacenavd and VRPN servers, recorded HID streams).
//! * [`cli`] — the command line.
//! * [`config`] — the TOML configuration and the driver factory.
//! * [`gate`] — plausibility of tracker motion (a constant-velocity gate).
//! * [`hand`] — tracker + glove → hand pose and gesture.
//! * [`spring`] — the adaptive spring of a load drag.
//! * [`wire`] — the mapping onto the vsculpt protocol.
//! * [`interaction`] — grab / drag / release and the 3D-mouse menu, as a pure state machine.
//! * [`link`] — the WebSocket link: hello, reconnect with backoff, latest-wins sending.
//! * [`listing`] — `--list`: HID devices, serial ports, spacenavd, VRPN sources.
//! * [`outbox`] — commands waiting for the link: ordered, drags latest-wins.
//! * [`recording`] — record raw device traffic, replay it through the same decoders.

pub mod bridge;
pub mod cli;
pub mod config;
pub mod device;
pub mod gate;
pub mod hand;
pub mod interaction;
pub mod link;
pub mod listing;
pub mod outbox;
pub mod recording;
pub mod sim;
pub mod spring;
pub mod wire;
