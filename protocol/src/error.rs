//! Stable error codes (serialised as snake_case strings, never renumbered)
//! and the error type of decoding and validation.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why a request failed. Clients may match on these; they never change meaning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// The hello's protocol version is not the server's.
    BadVersion,
    /// The token is unknown or not valid for this design.
    BadToken,
    /// The first message was not a hello, or a hello came twice.
    BadHandshake,
    /// Not JSON, or a field has the wrong type.
    Malformed,
    /// The `type` is not a known message.
    UnknownMessage,
    /// The message or a field in it exceeds a limit.
    TooLarge,
    /// A number is NaN or infinite.
    NotFinite,
    /// A number or size is outside its allowed range.
    OutOfRange,
    /// No design with that id.
    UnknownDesign,
    /// No icon with that id in the design.
    UnknownIcon,
    /// No version with that number.
    UnknownVersion,
    /// No part with that id in the design (or the icon is not on that part).
    UnknownPart,
    /// No relation with that id in the design.
    UnknownRelation,
    /// The part is locked: unlock it first.
    Locked,
    /// The parts cannot be related that way (edges of different size,
    /// degree or knots; a binding to something that is not a curve icon).
    Incompatible,
    /// A (u,v) parameter lies outside the surface's domain.
    OutOfDomain,
    /// The client's role may not do this (a viewer editing).
    Forbidden,
    /// Someone else holds the icon, or nothing to undo/redo.
    Conflict,
    /// The request is valid but the kind of icon does not allow it.
    Unsupported,
    /// The solver could not satisfy the request.
    Solver,
    /// Something failed inside the server; the request changed nothing.
    Internal,
    /// The design is restarting after a failure (or the server is stopping):
    /// reconnect and retry in a moment.
    Unavailable,
    /// The store could not write (disk full, read-only, I/O error): nothing
    /// was stored, the server keeps the design in memory and retries; retry
    /// the request once space is back.
    Storage,
    /// The client sent more messages than its rate limit allows
    /// ([`crate::limits::CONTROL_RATE`], [`crate::limits::STREAM_RATE`]):
    /// the message was dropped and changed nothing; slow down.
    RateLimited,
}

/// A message that could not be decoded or failed validation.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("{code:?}: {message}")]
pub struct ProtocolError {
    /// The stable code.
    pub code: ErrorCode,
    /// A human-readable explanation.
    pub message: String,
}

impl ProtocolError {
    /// An error with `code` and `message`.
    pub fn new(code: ErrorCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }
}
