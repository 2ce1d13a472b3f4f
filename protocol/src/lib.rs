//! vsculpt-protocol: every message between server, device bridge and browser (to be built, issue 3).
