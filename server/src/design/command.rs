//! What clients ask of a design actor, protocol-neutral: the ws layer maps
//! protocol messages to these (see `convert`), the actor checks the
//! client's role and runs them in order.

use super::model::Edit;
use glam::DVec3;

/// A command from one client.
#[derive(Clone, Debug)]
pub enum Command {
    /// An undoable change of icons, material or surface.
    Edit(Edit),
    /// Grab an icon: it becomes driving and held by this client.
    Grab {
        /// The part it is on.
        part: u64,
        /// The icon.
        icon: u64,
    },
    /// Move a held icon to `xyz` (a drag frame; coalesced per client).
    Drag {
        /// The part it is on.
        part: u64,
        /// The dragged icon.
        icon: u64,
        /// Where the icon's handle is now.
        xyz: DVec3,
    },
    /// End a drag: the icon keeps the shape it reached.
    Release {
        /// The part it is on.
        part: u64,
        /// The released icon.
        icon: u64,
    },
    /// Store the working state as a new version.
    Commit {
        /// The commit message.
        message: String,
    },
    /// Back to the last committed version.
    Revert,
    /// Undo the last change.
    Undo,
    /// Redo the last undone change.
    Redo,
    /// Make a stored version the working state.
    Restore {
        /// Version number.
        version: u64,
    },
    /// Cancel the fairing job on a face of a network part (see
    /// `fairing_job`).
    CancelFairing {
        /// The network part.
        part: u64,
        /// The face.
        face: usize,
    },
    /// Add, answer, resolve or delete a review comment (not an edit: not
    /// undone; written to the store before it is answered).
    Comment(super::comments::CommentOp),
    /// Show a body part at morph time `t` (not stored, not undone).
    BodyMorph {
        /// The body part.
        part: u64,
        /// The time in [0, 1].
        t: f64,
    },
}

impl Command {
    /// Whether the command changes the design's shape or icons.
    pub fn edits(&self) -> bool {
        matches!(
            self,
            Command::Edit(_)
                | Command::Grab { .. }
                | Command::Drag { .. }
                | Command::Release { .. }
                | Command::BodyMorph { .. }
                | Command::CancelFairing { .. }
        )
    }
}

/// What an accepted command produced, for the client that sent it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ack {
    /// The id of an icon the command created.
    pub created_icon: Option<u64>,
    /// The version a commit created or a restore/revert loaded.
    pub version: Option<u64>,
    /// The id of a part the command created.
    pub created_part: Option<u64>,
    /// The id of a relation the command created.
    pub created_relation: Option<u64>,
    /// The id of a comment or reply the command created.
    pub created_comment: Option<u64>,
    /// Set when an edit left the constraints contradicting each other: the
    /// shape is their least-squares compromise (the text says by how much).
    pub warning: Option<String>,
}
