//! Device drivers: one driver abstraction ([`driver`]), the byte links
//! ([`transport`]) and one file per device family, each a pure decoder of the
//! family's published wire format plus the commands it needs.

pub mod cyberglove;
pub mod driver;
pub mod fastrak;
pub mod flock;
pub mod mouse_axes;
pub mod runner;
pub mod sample;
pub mod spacemouse_hid;
pub mod spacenavd;
pub mod transport;
pub mod vrpn;
pub mod vrpn_link;

pub use driver::{
    DecodeStats, Decoder, Device, DeviceError, Driver, RawFrame, Script, Step, TapEvent, Transport,
};
pub use sample::{GloveValues, Reading, Sample, SourceId, Timestamp};
