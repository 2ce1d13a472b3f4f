//! vsculpt-bridge: the device daemon for 3D mice, trackers and gloves (to be built, issue 4).
