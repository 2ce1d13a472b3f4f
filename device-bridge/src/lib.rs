//! vsculpt-bridge: the device daemon that turns studio hardware — 3D mice,
//! 6-DOF trackers and data gloves — into sculpting input for the vsculpt server.
//!
//! * [`device`] — drivers: transports, pure decoders of each family's wire format.

pub mod device;
