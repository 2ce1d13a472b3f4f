//! Server → client events, sent as JSON text; geometry goes in binary
//! frames ([`crate::frame`]).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::comment::Comment;
use crate::error::ErrorCode;
use crate::parts::{Part, PartMaterial, Relation};
use crate::types::{Access, DesignInfo, DesignTokens, Icon, PresenceEntry, Vec3, VersionInfo};

/// Everything the server tells a client.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// The hello was accepted.
    Welcome {
        /// This connection's id (as used in presence and `holder`).
        client_id: u64,
        /// What it may do.
        access: Access,
        /// The joined design.
        design: u64,
        /// The server's protocol version.
        protocol: u32,
        /// The compact join only (`geometry_first`): the SHA-256, in lower-case
        /// hex, of the geometry frames this join carries (each part's frame
        /// flagged as the snapshot's shape, inflated, in the order sent, each
        /// preceded by its length as a little-endian u32). It changes whenever
        /// any part's frame changes. A client may keep those frames under this
        /// name and offer it in a later hello's `cached_geometry`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        geometry: Option<String>,
        /// The hello's `cached_geometry` equals `geometry`: the join's frames
        /// are not sent; the client draws the ones it kept (absent: false).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        geometry_cached: bool,
    },
    /// A request succeeded.
    Ack {
        /// The request's `req`.
        req: u64,
        /// The icon a `create_icon` created.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        icon: Option<u64>,
        /// The version a `commit` created or a `revert` / `restore_version`
        /// loaded.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        version: Option<u64>,
        /// The part a `create_part` created.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        part: Option<u64>,
        /// The relation a `relate` created.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relation: Option<u64>,
        /// The comment an `add_comment` or the reply a `reply_comment`
        /// created.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        comment: Option<u64>,
        /// Set when the edit (an icon created or changed, a material) left
        /// constraints that contradict each other: the shape is their
        /// least-squares compromise, and this says by how much.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        warning: Option<String>,
    },
    /// A request failed and changed nothing.
    Error {
        /// The request's `req`, if it had one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        req: Option<u64>,
        /// The stable code.
        code: ErrorCode,
        /// What went wrong.
        message: String,
    },
    /// The full state, sent on join and after revert, undo, redo or restore.
    Snapshot {
        /// The design.
        design: DesignInfo,
        /// Increases with every change of shape.
        revision: u64,
        /// Every part, with its shape, material and icons.
        parts: Vec<Part>,
        /// Every relation between parts.
        relations: Vec<Relation>,
        /// The committed versions, oldest first.
        versions: Vec<VersionInfo>,
        /// Who is here.
        presence: Vec<PresenceEntry>,
        /// Whether undo has something to undo.
        can_undo: bool,
        /// Whether redo has something to redo.
        can_redo: bool,
        /// Every review comment of the design, oldest first (empty when
        /// omitted).
        #[serde(default)]
        comments: Vec<Comment>,
        /// The fairing jobs running now, each with its latest progress
        /// (a client joining while one runs learns of it here, not only
        /// from its next `fairing_progress`); left out when none runs.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        fairing: Vec<crate::network::FairingProgress>,
    },
    /// An icon was created.
    IconCreated {
        /// The part it belongs to.
        part: u64,
        /// The new icon.
        icon: Icon,
    },
    /// An icon changed (role, state, target, sensors, holder).
    IconUpdated {
        /// The part it belongs to.
        part: u64,
        /// The icon as it is now.
        icon: Icon,
    },
    /// An icon was deleted.
    IconDeleted {
        /// The part it belongs to.
        part: u64,
        /// Its id.
        icon: u64,
    },
    /// The material changed.
    MaterialChanged {
        /// The part it belongs to.
        part: u64,
        /// The new material.
        material: PartMaterial,
    },
    /// A version was committed.
    Committed {
        /// The new version.
        version: VersionInfo,
    },
    /// The committed versions, oldest first (the answer to `list_versions`).
    Versions {
        /// The request's `req`, if it had one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        req: Option<u64>,
        /// The versions.
        versions: Vec<VersionInfo>,
    },
    /// The designs this client's token opens (the answer to `list_designs`).
    Designs {
        /// The request's `req`, if it had one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        req: Option<u64>,
        /// The designs.
        designs: Vec<DesignInfo>,
    },
    /// Who is here and what each holds (the whole list; the server sends
    /// it in `snapshot` and then keeps clients current with
    /// `presence_changed` / `presence_left`).
    Presence {
        /// Every connected client of the design.
        clients: Vec<PresenceEntry>,
    },
    /// A client joined, or what it holds or points at changed: its entry
    /// replaces the one with the same `client` id (or is added).
    PresenceChanged {
        /// The client's entry as it is now.
        client: PresenceEntry,
    },
    /// A client left the design.
    PresenceLeft {
        /// Its client id.
        client: u64,
    },
    /// After a solve during a drag: where the dragged icon actually went,
    /// which the bridge's spring model needs (Δy in paper 003).
    IconFeedback {
        /// The part it belongs to.
        part: u64,
        /// The icon.
        icon: u64,
        /// Where the pointer asked it to be.
        requested: Vec3,
        /// Where it is on the solved surface.
        actual: Vec3,
        /// The shape revision this belongs to.
        revision: u64,
        /// Set when this frame's solve could not meet every constraint (they
        /// contradict each other): why, and by how much the shape misses
        /// them (the least-squares compromise).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        warning: Option<String>,
    },
    /// Undo/redo availability changed.
    History {
        /// Whether undo has something to undo.
        can_undo: bool,
        /// Whether redo has something to redo.
        can_redo: bool,
    },
    /// A design was created (the answer to `create_design`, to its sender
    /// only): the links to open it need these tokens.
    DesignCreated {
        /// The request's `req`, if it had one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        req: Option<u64>,
        /// The new design.
        design: DesignInfo,
        /// Its tokens.
        tokens: DesignTokens,
    },
    /// Answer to `ping`.
    Pong {
        /// The request's `req`, if it had one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        req: Option<u64>,
    },
    /// A part was added.
    PartCreated {
        /// The new part.
        part: Part,
    },
    /// A part was deleted, with its icons and relations.
    PartDeleted {
        /// Its id.
        part: u64,
    },
    /// A part was renamed, shown or hidden, locked or unlocked, recoloured.
    PartChanged {
        /// Its id.
        part: u64,
        /// Its name.
        name: String,
        /// Drawn or hidden.
        visible: bool,
        /// Locked or not.
        locked: bool,
        /// `#rrggbb`.
        colour: String,
    },
    /// A network part's curves, meetings, faces or faired faces changed
    /// (its patches follow as a mesh frame).
    NetworkChanged {
        /// Its id.
        part: u64,
        /// The network as it is now.
        network: crate::network::NetworkData,
    },
    /// A fairing job's progress (to every client, at most ten a second
    /// per job; iteration 0 when it starts).
    FairingProgress(crate::network::FairingProgress),
    /// A fairing job ended (to every client).
    FairingEnded {
        /// The network part.
        part: u64,
        /// The face.
        face: u32,
        /// The client that asked for it.
        client: u64,
        /// How it ended.
        outcome: crate::network::FairingOutcome,
        /// Sweeps run.
        iterations: u32,
        /// Whether the run converged (`applied` only; false otherwise).
        converged: bool,
        /// Why, in words.
        message: String,
    },
    /// A DSM part's shape data changed (`dsm_edit`); its new mesh follows
    /// as a mesh frame (kind 3).
    DsmChanged {
        /// The part.
        part: u64,
        /// Its groups and primitives now.
        dsm: crate::dsm::DsmData,
    },
    /// Parts were tied together.
    RelationCreated {
        /// The new relation.
        relation: Relation,
    },
    /// A relation was removed.
    RelationDeleted {
        /// Its id.
        relation: u64,
    },
    /// A comment was pinned (to every client of the design).
    CommentAdded {
        /// The new comment.
        comment: Comment,
    },
    /// A comment got a reply, lost one, or was resolved or reopened: the
    /// whole thread as it is now.
    CommentChanged {
        /// The comment.
        comment: Comment,
    },
    /// A comment was deleted with its replies.
    CommentDeleted {
        /// Its id.
        comment: u64,
    },
}
