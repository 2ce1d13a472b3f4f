//! End-to-end tests: real server, bridge, simulated devices and a headless browser (to be built).
