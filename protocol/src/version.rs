//! The protocol version and the handshake.
//!
//! The first message of every connection is a `hello` carrying
//! [`PROTOCOL_VERSION`] and a token. The server answers `welcome`, or an
//! `error` with code `bad_version` or `bad_token` and closes the connection.
//! Any change that an older peer would misread bumps the version; adding an
//! optional field does not.

/// The version this crate speaks.
pub const PROTOCOL_VERSION: u32 = 2;
