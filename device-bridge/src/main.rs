//! The `vsculpt-bridge` binary: the command line of [`vsculpt_bridge::cli`] with
//! the vsculpt protocol as its wire.

use std::process::ExitCode;
use std::sync::Arc;

fn main() -> ExitCode {
    vsculpt_bridge::cli::main(Arc::new(vsculpt_bridge::wire::ProtocolWire::default()))
}
