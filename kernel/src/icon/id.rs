//! Identifiers: icons within a design, and the device sensors bound to them.

/// An icon's id, unique within its design and never reused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct IconId(pub u64);

/// A device sensor (a tracker, a hand, a 3D mouse) as named by the bridge's
/// configuration, e.g. "right-hand".
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SensorId(pub String);
