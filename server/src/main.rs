//! The `vsculpt-server` binary.
fn main() {}
