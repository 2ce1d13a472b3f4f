//! vsculpt-protocol: every message between the server, the device bridge and
//! the browser. It knows nothing of the kernel, so the wire stays stable
//! while the solver changes.
//!
//! # Layout
//!
//! * [`version`] — the protocol version and the handshake rules.
//! * [`error`] — stable error codes ([`ErrorCode`]) and decode failures.
//! * [`limits`] — sizes beyond which a message is refused.
//! * [`types`] — value types shared by messages: surfaces, icons, materials,
//!   versions, presence.
//! * [`comment`] — review comments pinned to points of parts, with replies.
//! * [`parts`] — the parts of a product (one per shape kind) and the
//!   relations between them (joins, bindings).
//! * [`client`] — client → server messages ([`ClientMessage`]) and
//!   [`parse_client`], the one entry point for untrusted text.
//! * [`server`] — server → client events ([`ServerMessage`]).
//! * [`validate`] — checks every client message before it touches state.
//! * [`frame`] — the binary geometry frame ([`GeometryFrame`]).
//! * [`schema`] — the JSON Schema of every message, generated from the
//!   types (checked in as `protocol/schema/protocol.schema.json`).
//! * [`dsm`] — a Density Spatial Model part's shape and its edits.
//! * [`network`] — a styling-curve network part's shape and its edits.
//! * [`mesh_frame`] — the binary mesh frame (kind 3, [`MeshFrame`]).
//! * [`mesh_delta`] — a mesh frame as the changes from an earlier one the
//!   client holds (kind 8), for clients that ask for it (`/ws?mesh_delta=1`).
//! * [`body`] — a Coons body part's lattice, its edits and morph time.
//! * [`body_frame`] — the binary body frame (kind 4, [`BodyFrame`]).
//! * [`drag_frame`] — the drag stream: a part's drag basis (kind 5) and
//!   its drag frames (kind 6), for clients that ask for it (`/ws?drag_stream=1`).
//! * [`deflated`] — any binary message byte-shuffled and DEFLATE-compressed
//!   (kind 7), for clients that ask for it (`/ws?deflate=1`).
//!
//! `protocol/README.md` documents the sequence of a connection, an example
//! of every message and the frame layout byte by byte.

pub mod body;
pub mod body_frame;
pub mod client;
pub mod comment;
pub mod deflated;
pub mod drag_frame;
pub mod dsm;
pub mod error;
pub mod frame;
pub mod limits;
pub mod mesh_delta;
pub mod mesh_frame;
pub mod mesh_patch;
pub mod network;
pub mod parts;
pub mod schema;
pub mod server;
pub mod types;
pub mod validate;
pub mod version;

pub use body::{BodyData, BodyEdit, BodyFace, LatticeData, LatticeSelection};
pub use body_frame::BodyFrame;
pub use client::{ClientEnvelope, ClientMessage, parse_client};
pub use comment::{Comment, CommentAnchor, CommentReply};
pub use dsm::{DsmData, DsmEdit, DsmGroup, DsmOp, DsmPrimitive, DsmPrimitiveShape};
pub use error::{ErrorCode, ProtocolError};
pub use frame::{FrameIcon, GeometryFrame};
pub use mesh_frame::MeshFrame;
pub use network::{
    FairingGoal, FairingOutcome, FairingProgress, FairingRequest, FairnessMeasure, NetworkData,
    NetworkEdit,
};
pub use parts::*;
pub use server::ServerMessage;
pub use types::*;
pub use version::PROTOCOL_VERSION;
