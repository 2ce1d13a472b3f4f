//! Why a design command was refused: a stable code (mapped to the
//! protocol's error codes in `convert`) and a human message.

use thiserror::Error;

/// Stable classes of refusal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The client's role may not do this (e.g. a viewer editing).
    Forbidden,
    /// The design does not exist (or was deleted).
    UnknownDesign,
    /// No icon with that id.
    UnknownIcon,
    /// No version with that number.
    UnknownVersion,
    /// No part with that id (or the icon is not on that part).
    UnknownPart,
    /// No relation with that id.
    UnknownRelation,
    /// The part is locked.
    Locked,
    /// The parts cannot be related that way.
    Incompatible,
    /// A value is out of its range or otherwise invalid.
    InvalidValue,
    /// A number is NaN or infinite.
    NotFinite,
    /// Someone else holds the icon.
    Conflict,
    /// The kind of icon does not allow this.
    Unsupported,
    /// A (u, v) parameter lies outside the surface's domain.
    OutOfDomain,
    /// Undo or redo with nothing to undo / redo.
    NothingToUndo,
    /// The solver could not honour the constraints.
    Solver,
    /// The design's actor is gone or overloaded.
    Unavailable,
    /// Storage failed.
    Storage,
    /// A size or count over its limit (the design's comments).
    TooLarge,
}

/// A refused command.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("{message}")]
pub struct CommandError {
    /// The class of refusal.
    pub kind: ErrorKind,
    /// What happened, for people.
    pub message: String,
}

impl CommandError {
    /// An error of `kind` with `message`.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
        }
    }
}
