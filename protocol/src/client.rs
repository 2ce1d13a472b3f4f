//! Client → server messages and [`parse_client`], the single entry point
//! for untrusted text from the network.
//!
//! Every message is a JSON object with a `type` tag and an optional `req`
//! number that the server echoes in its `ack` or `error`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::error::{ErrorCode, ProtocolError};
use crate::limits::MAX_MESSAGE_BYTES;
use crate::parts::{PartMaterial, PartSpec, RelationSpec};
use crate::types::{Anchor, Camera, ClientKind, DeviceCondition, IconSpec, IconState, Role, Vec3};

/// A client message with its optional request number.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ClientEnvelope {
    /// Echoed in the reply (`ack` or `error`) so the client can match them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub req: Option<u64>,
    /// The message.
    #[serde(flatten)]
    pub msg: ClientMessage,
}

/// Everything a client may ask of the server.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ClientMessage {
    /// The first message of a connection.
    Hello {
        /// Must equal [`crate::PROTOCOL_VERSION`].
        protocol: u32,
        /// An editor, viewer or device token.
        token: String,
        /// The design to join.
        design: u64,
        /// A display name for presence (optional; the server names the
        /// client after its access and id when empty).
        #[serde(default)]
        client_name: String,
        /// What kind of program this is (optional; `tool` when omitted).
        #[serde(default)]
        client_kind: ClientKind,
        /// The compact join (optional; `false` when omitted): the server
        /// sends the shape first, as a binary geometry frame flagged
        /// [`crate::frame::FLAG_SNAPSHOT`], and every `snapshot` to this
        /// client leaves `surface.points` empty (the shape comes in frames).
        /// A client on a slow link draws the picture before the icons,
        /// history and presence arrive, and the control net crosses the link
        /// once, in binary, instead of twice (JSON and binary).
        #[serde(default)]
        geometry_first: bool,
        /// The geometry this client holds from an earlier visit (optional;
        /// only with `geometry_first`): the `geometry` hash a `welcome` named
        /// when the client last received a compact join of this design. When
        /// it equals the hash of the frames the join would send now, the
        /// server skips them (the `welcome` says `geometry_cached`) and the
        /// client draws the frames it kept; any other value (stale, forged,
        /// malformed) gets the frames as usual.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cached_geometry: Option<String>,
    },
    /// List the designs (answered with `designs`, carrying `req`).
    ListDesigns,
    /// Create a flat 16 × 12 plate design (editors only; answered with
    /// `design_created`, carrying `req` and the new design's tokens).
    CreateDesign {
        /// Its name.
        name: String,
    },
    /// Delete a design other than the one joined (editors only).
    DeleteDesign {
        /// Its id.
        design: u64,
    },
    /// Create an icon (answered with `icon_created`).
    CreateIcon {
        /// The part it acts on.
        part: u64,
        /// What it should be.
        spec: IconSpec,
    },
    /// Re-anchor an icon (move it in (u,v), or reshape its curve/region).
    EditIcon {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// Its new anchor.
        anchor: Anchor,
    },
    /// Set an icon's target (a constraint's position/vector/normal; a
    /// load's pulled-to point) and solve.
    MoveIcon {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// The new target.
        xyz: Vec3,
    },
    /// Delete an icon.
    DeleteIcon {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
    },
    /// Switch an icon's role (constraint ↔ load; position ↔ tangent ↔ normal).
    SetRole {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// The new role.
        role: Role,
    },
    /// Switch an icon's state.
    SetState {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// The new state.
        state: IconState,
    },
    /// Bind a device sensor to an icon.
    BindSensor {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// The sensor, e.g. "right-hand".
        sensor: String,
    },
    /// Unbind a device sensor from an icon.
    UnbindSensor {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// The sensor.
        sensor: String,
    },
    /// Grab an icon: it becomes driving and held by this client.
    DragStart {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
    },
    /// Drag a held icon to `xyz` (coalesced: only the newest counts).
    Drag {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
        /// Where the pointer or hand is.
        xyz: Vec3,
    },
    /// Release a held icon: it becomes passive and the shape is kept.
    DragEnd {
        /// The part it acts on.
        part: u64,
        /// The icon.
        icon: u64,
    },
    /// A device sample from the bridge.
    DeviceSample {
        /// The sensor, e.g. "right-hand".
        sensor: String,
        /// Position in model space.
        position: Vec3,
        /// Orientation quaternion (w, x, y, z).
        orientation: [f64; 4],
        /// Glove finger flexion in radians, if a glove is part of the sensor.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        flexion: Option<Vec<f64>>,
        /// Button bitmask.
        #[serde(default)]
        buttons: u32,
        /// Device time, microseconds (optional, 0 when omitted).
        #[serde(default)]
        time_us: u64,
    },
    /// A device's condition changed.
    DeviceStatus {
        /// The device name from the bridge's config.
        device: String,
        /// Its condition.
        condition: DeviceCondition,
        /// Details.
        #[serde(default)]
        message: String,
    },
    /// Set the material (α, β).
    SetMaterial {
        /// The part it acts on.
        part: u64,
        /// The new material (a curve part takes `alpha` and `beta`).
        material: PartMaterial,
    },
    /// Commit the current shape as a new version.
    Commit {
        /// The commit message.
        message: String,
    },
    /// Back to the last committed version.
    Revert,
    /// Undo the last edit.
    Undo,
    /// Redo the last undone edit.
    Redo,
    /// List the committed versions (answered with `versions`, carrying `req`).
    ListVersions,
    /// Make a committed version the working state.
    RestoreVersion {
        /// The version number.
        version: u64,
    },
    /// Tell others where this client's pointer or hand and its view camera
    /// are. Each message states both: a field left out means "none".
    Presence {
        /// The pointer, if any.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pointer: Option<Vec3>,
        /// The view camera, if any (others may follow it).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        camera: Option<Camera>,
    },
    /// Liveness check (answered with `pong`, carrying `req`).
    Ping,
    /// How many bytes of binary messages this client has received on this
    /// connection, in total (their WebSocket payloads, as sent). A client
    /// that opened `/ws?pace=1` sends it as binary messages arrive; the
    /// server keeps the bytes it sent and the client has not reported within
    /// a window measured from these reports (README, "Paced delivery").
    /// Without `pace=1` it changes nothing. A stream message, like `drag`.
    Received {
        /// The total since the connection opened.
        bytes: u64,
    },
    /// Add a part to the design; answered `ack {part}` and `part_created`
    /// to everyone.
    CreatePart {
        /// What it should be.
        spec: PartSpec,
    },
    /// Delete a part with its icons and relations.
    DeletePart {
        /// The part.
        part: u64,
    },
    /// Rename, show or hide, lock or unlock, or recolour a part (fields
    /// left out stay as they are); answered `part_changed`.
    SetPart {
        /// The part.
        part: u64,
        /// A new name.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
        /// Drawn or hidden.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        visible: Option<bool>,
        /// Locked parts refuse edits and drags.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        locked: Option<bool>,
        /// `#rrggbb`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        colour: Option<String>,
    },
    /// Tie parts together (a join or a binding); answered `ack {relation}`
    /// and `relation_created`.
    Relate {
        /// What to tie.
        relation: RelationSpec,
    },
    /// Remove a relation; the parts keep their shapes.
    Unrelate {
        /// The relation.
        relation: u64,
    },
    /// Reshape a DSM part: add, move, resize or remove a primitive, set its
    /// density and reducing factor, move it to another group, or drag a net
    /// node. Answered `ack`, then `dsm_changed` to every client and a mesh
    /// frame (kind 3) of the part. A refused edit changes nothing.
    DsmEdit {
        /// The DSM part.
        part: u64,
        /// What to change.
        edit: crate::dsm::DsmEdit,
    },
    /// Reshape a network part (move a control point, drag a point of a
    /// curve, add or remove a curve) or fair one of its faces: answered
    /// `ack`, `network_changed` and a mesh frame (kind 3) of the part to
    /// every client; a refused edit changes nothing. A fair runs as a job
    /// (`fairing_progress` to everyone while it runs, `fairing_ended` when
    /// it ends); its `ack` comes when its result is applied, an error when
    /// it is cancelled, discarded or refused.
    NetworkEdit {
        /// The network part.
        part: u64,
        /// What to change.
        edit: crate::network::NetworkEdit,
    },
    /// Cancel the fairing job running on face `face` of network part
    /// `part` (editors only): it stops within one sweep, nothing changes,
    /// every client gets `fairing_ended` with `cancelled`. No job there is
    /// `out_of_range`.
    CancelFairing {
        /// The network part.
        part: u64,
        /// The face.
        face: u32,
    },
    /// Move lattice points of a body part (one point, a face's or an
    /// edge's) by a delta; answered `ack` and a body frame (kind 4) to
    /// everyone. An edit that folds the body (det J ≤ 0) is refused with
    /// where it folds, and changes nothing. Undoable.
    BodyEdit {
        /// The body part.
        part: u64,
        /// What to move.
        edit: crate::body::BodyEdit,
    },
    /// Show a body part with a morph target at time `t` ∈ [0, 1] (0 the
    /// body, 1 its target): every client gets the body frame at `t`. Not
    /// an edit: nothing is stored or undone.
    BodyMorph {
        /// The body part.
        part: u64,
        /// The time.
        t: f64,
    },
    /// Pin a comment to a point of a part (viewers too: the customer's
    /// feedback). Answered `ack {comment}` and `comment_added` to every
    /// client. Not an edit: nothing is undone; it is stored at once.
    AddComment {
        /// The part it is pinned to.
        part: u64,
        /// Where on the part.
        anchor: crate::comment::CommentAnchor,
        /// What it says.
        text: String,
    },
    /// Reply to a comment: answered `ack {comment}` (the reply's id) and
    /// `comment_changed` with the whole thread.
    ReplyComment {
        /// The comment replied to.
        comment: u64,
        /// What the reply says.
        text: String,
    },
    /// Mark a comment resolved or open again: `comment_changed`.
    ResolveComment {
        /// The comment.
        comment: u64,
        /// Resolved (true) or open (false).
        resolved: bool,
    },
    /// Delete a comment with its replies (`comment_deleted`), or one reply
    /// (`comment_changed` with the thread left).
    DeleteComment {
        /// The comment's or reply's id.
        comment: u64,
    },
    /// Replace the text of a comment or reply (`comment_changed` with the
    /// thread); its author's side or an editor, as for deleting it.
    EditComment {
        /// The comment's or reply's id.
        comment: u64,
        /// The new text (the same rules as a new comment's).
        text: String,
    },
}

/// The `type` tags of every client message, for telling an unknown type
/// from a malformed message.
pub const CLIENT_TYPES: &[&str] = &[
    "hello",
    "list_designs",
    "create_design",
    "delete_design",
    "create_icon",
    "edit_icon",
    "move_icon",
    "delete_icon",
    "set_role",
    "set_state",
    "bind_sensor",
    "unbind_sensor",
    "drag_start",
    "drag",
    "drag_end",
    "device_sample",
    "device_status",
    "set_material",
    "commit",
    "revert",
    "undo",
    "redo",
    "list_versions",
    "restore_version",
    "presence",
    "ping",
    "received",
    "create_part",
    "delete_part",
    "set_part",
    "relate",
    "unrelate",
    "dsm_edit",
    "network_edit",
    "cancel_fairing",
    "body_edit",
    "body_morph",
    "add_comment",
    "reply_comment",
    "resolve_comment",
    "delete_comment",
    "edit_comment",
];

/// Parses and validates one text message from a client: `too_large`,
/// `malformed`, `unknown_message`, `not_finite` or `out_of_range` on failure.
/// Never panics, whatever the input.
pub fn parse_client(text: &str) -> Result<ClientEnvelope, ProtocolError> {
    if text.len() > MAX_MESSAGE_BYTES {
        return Err(ProtocolError::new(
            ErrorCode::TooLarge,
            format!(
                "message of {} bytes exceeds {MAX_MESSAGE_BYTES}",
                text.len()
            ),
        ));
    }
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| ProtocolError::new(ErrorCode::Malformed, format!("not JSON: {e}")))?;
    let Some(kind) = value.get("type") else {
        return Err(ProtocolError::new(
            ErrorCode::Malformed,
            "no \"type\" field",
        ));
    };
    let Some(kind) = kind.as_str().map(str::to_owned) else {
        return Err(ProtocolError::new(
            ErrorCode::Malformed,
            "\"type\" is not a string",
        ));
    };
    if !CLIENT_TYPES.contains(&kind.as_str()) {
        let shown: String = kind.chars().take(64).collect();
        return Err(ProtocolError::new(
            ErrorCode::UnknownMessage,
            format!("unknown message type {shown:?}"),
        ));
    }
    let envelope: ClientEnvelope = serde_json::from_value(value)
        .map_err(|e| ProtocolError::new(ErrorCode::Malformed, format!("bad {kind}: {e}")))?;
    envelope.msg.validate()?;
    Ok(envelope)
}
