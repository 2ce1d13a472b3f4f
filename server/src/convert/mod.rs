//! The one place where protocol types (`vsculpt-protocol`, the stable wire)
//! meet server types (design documents, commands, events): decoding client
//! messages into commands, encoding events, snapshots and geometry frames.
//! Neither the design actor nor the kernel sees a protocol type. Parts and
//! relations are in [`parts`].

pub mod comments;
pub mod network;
pub mod parts;

use crate::design::actor::{Feedback, Presence, SnapshotView};
use crate::design::comments::CommentOp;
use crate::design::doc::{
    AnchorDoc, DerivativeDoc, EdgeSideDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc,
    UvCurveDoc,
};
use crate::design::part::{PartBody, PartDoc};
use crate::design::{Ack, Command, CommandError, DesignEvent, Edit, ErrorKind, PartEdit};
use crate::store::{DesignId, DesignRecord, Role, VersionInfo};
use axum::body::Bytes;
use axum::extract::ws::Utf8Bytes;
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_protocol as wire;
use vsculpt_protocol::{ClientMessage, ErrorCode, ServerMessage};

/// An error as sent to a client: a stable protocol code and a message.
#[derive(Clone, Debug, PartialEq)]
pub struct WireError {
    /// Stable code.
    pub code: ErrorCode,
    /// Human-readable message.
    pub message: String,
}

impl WireError {
    /// An error with `code`.
    pub fn new(code: ErrorCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }

    /// Not a valid message.
    pub fn malformed(message: impl Into<String>) -> Self {
        Self::new(ErrorCode::Malformed, message)
    }

    /// The first message was not a hello, or a second hello came.
    pub fn handshake(message: impl Into<String>) -> Self {
        Self::new(ErrorCode::BadHandshake, message)
    }

    /// A message over the limit.
    pub fn too_large(len: usize, limit: usize) -> Self {
        Self::new(
            ErrorCode::TooLarge,
            format!("message of {len} bytes exceeds the limit of {limit}"),
        )
    }

    /// A bad or missing token.
    pub fn unauthorized() -> Self {
        Self::new(
            ErrorCode::BadToken,
            "the token is not valid for this design",
        )
    }

    /// A value out of its range.
    pub fn invalid(message: impl Into<String>) -> Self {
        Self::new(ErrorCode::OutOfRange, message)
    }
}

impl From<wire::ProtocolError> for WireError {
    fn from(e: wire::ProtocolError) -> Self {
        Self::new(e.code, e.message)
    }
}

impl From<CommandError> for WireError {
    fn from(e: CommandError) -> Self {
        let code = match e.kind {
            ErrorKind::Forbidden => ErrorCode::Forbidden,
            ErrorKind::UnknownDesign => ErrorCode::UnknownDesign,
            ErrorKind::UnknownIcon => ErrorCode::UnknownIcon,
            ErrorKind::UnknownVersion => ErrorCode::UnknownVersion,
            ErrorKind::UnknownPart => ErrorCode::UnknownPart,
            ErrorKind::UnknownRelation => ErrorCode::UnknownRelation,
            ErrorKind::Locked => ErrorCode::Locked,
            ErrorKind::Incompatible => ErrorCode::Incompatible,
            ErrorKind::InvalidValue => ErrorCode::OutOfRange,
            ErrorKind::NotFinite => ErrorCode::NotFinite,
            ErrorKind::OutOfDomain => ErrorCode::OutOfDomain,
            ErrorKind::NothingToUndo | ErrorKind::Conflict => ErrorCode::Conflict,
            ErrorKind::Unsupported => ErrorCode::Unsupported,
            ErrorKind::Solver => ErrorCode::Solver,
            ErrorKind::Unavailable => ErrorCode::Unavailable,
            ErrorKind::Storage => ErrorCode::Storage,
            ErrorKind::TooLarge => ErrorCode::TooLarge,
        };
        Self::new(code, e.message)
    }
}

/// The parts of a hello the server uses.
#[derive(Clone, Debug, PartialEq)]
pub struct Hello {
    /// Token.
    pub token: String,
    /// Design to join.
    pub design: DesignId,
    /// Display name.
    pub name: String,
    /// The compact join: the shape first, in binary; snapshots without points.
    pub geometry_first: bool,
    /// The name of the join geometry the client kept from an earlier visit.
    pub cached_geometry: Option<String>,
}

/// A decoded client message (after the hello).
#[derive(Clone, Debug)]
pub enum Inbound {
    /// A second hello.
    Hello,
    /// Liveness check.
    Ping,
    /// A design command.
    Command(Command),
    /// The client's pointer and view camera (presence).
    Presence {
        /// The pointer, if any.
        pointer: Option<DVec3>,
        /// The view camera, if any.
        camera: Option<wire::Camera>,
    },
    /// A paced client's report of the binary bytes it has received.
    Received {
        /// The total since the connection opened.
        bytes: u64,
    },
    /// A device sample (its position becomes the bridge's pointer).
    DeviceSample {
        /// Sensor name.
        sensor: String,
        /// Position.
        position: DVec3,
    },
    /// A device's condition changed.
    DeviceStatus {
        /// Device name.
        device: String,
        /// Condition, as text.
        condition: String,
        /// Details.
        message: String,
    },
    /// List the designs.
    ListDesigns,
    /// Create a design.
    CreateDesign {
        /// Its name.
        name: String,
    },
    /// Delete a design.
    DeleteDesign {
        /// Its id.
        design: DesignId,
    },
    /// List versions.
    ListVersions,
}

/// Decodes the first message of a connection, which must be a hello with
/// this server's protocol version.
pub fn decode_hello(text: &str) -> Result<Hello, WireError> {
    // A hello of another version may carry fields this version does not
    // know (or lack ones it requires): its version is read first, so it
    // gets `bad_version`, not `malformed`.
    if text.len() <= wire::limits::MAX_MESSAGE_BYTES
        && let Ok(v) = serde_json::from_str::<serde_json::Value>(text)
        && v.get("type").and_then(|t| t.as_str()) == Some("hello")
        && let Some(p) = v.get("protocol")
        && p.as_u64() != Some(u64::from(wire::PROTOCOL_VERSION))
    {
        return Err(WireError::new(
            ErrorCode::BadVersion,
            format!(
                "protocol version {p} is not supported; this server speaks {}",
                wire::PROTOCOL_VERSION
            ),
        ));
    }
    let env = wire::parse_client(text)?;
    match env.msg {
        ClientMessage::Hello {
            protocol,
            token,
            design,
            client_name,
            geometry_first,
            cached_geometry,
            ..
        } => {
            if protocol != wire::PROTOCOL_VERSION {
                return Err(WireError::new(
                    ErrorCode::BadVersion,
                    format!(
                        "protocol version {protocol} is not supported; this server speaks {}",
                        wire::PROTOCOL_VERSION
                    ),
                ));
            }
            Ok(Hello {
                token,
                design,
                name: client_name,
                geometry_first,
                cached_geometry,
            })
        }
        _ => Err(WireError::handshake("the first message must be a hello")),
    }
}

fn req_of(text: &str) -> Option<u64> {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .and_then(|v| v.get("req").and_then(|r| r.as_u64()))
}

/// Converts a wire anchor.
pub fn anchor_from_wire(a: &wire::Anchor) -> AnchorDoc {
    match a {
        wire::Anchor::Point { u, v } => AnchorDoc::Point { u: *u, v: *v },
        wire::Anchor::Curve { curve } => AnchorDoc::Curve {
            curve: UvCurveDoc {
                degree: curve.knots.degree as usize,
                knots: curve.knots.knots.clone(),
                points: curve.points.clone(),
            },
        },
        wire::Anchor::Region {
            u0,
            v0,
            u1,
            v1,
            inside,
        } => AnchorDoc::Region {
            u0: *u0,
            v0: *v0,
            u1: *u1,
            v1: *v1,
            inside: *inside,
        },
        wire::Anchor::Edge { edge, mode } => AnchorDoc::Edge {
            edge: match edge {
                wire::EdgeSide::UMin => EdgeSideDoc::UMin,
                wire::EdgeSide::UMax => EdgeSideDoc::UMax,
                wire::EdgeSide::VMin => EdgeSideDoc::VMin,
                wire::EdgeSide::VMax => EdgeSideDoc::VMax,
            },
            clamped: *mode == wire::EdgeMode::Clamped,
        },
        wire::Anchor::Param { t } => AnchorDoc::Param { t: *t },
        wire::Anchor::Span { t0, t1 } => AnchorDoc::Span { t0: *t0, t1: *t1 },
    }
}

fn anchor_to_wire(a: &AnchorDoc) -> wire::Anchor {
    match a {
        AnchorDoc::Point { u, v } => wire::Anchor::Point { u: *u, v: *v },
        AnchorDoc::Curve { curve } => wire::Anchor::Curve {
            curve: wire::UvCurve {
                knots: wire::Knots {
                    degree: curve.degree as u32,
                    knots: curve.knots.clone(),
                },
                points: curve.points.clone(),
            },
        },
        AnchorDoc::Region {
            u0,
            v0,
            u1,
            v1,
            inside,
        } => wire::Anchor::Region {
            u0: *u0,
            v0: *v0,
            u1: *u1,
            v1: *v1,
            inside: *inside,
        },
        AnchorDoc::Edge { edge, clamped } => wire::Anchor::Edge {
            edge: match edge {
                EdgeSideDoc::UMin => wire::EdgeSide::UMin,
                EdgeSideDoc::UMax => wire::EdgeSide::UMax,
                EdgeSideDoc::VMin => wire::EdgeSide::VMin,
                EdgeSideDoc::VMax => wire::EdgeSide::VMax,
            },
            mode: if *clamped {
                wire::EdgeMode::Clamped
            } else {
                wire::EdgeMode::SimplySupported
            },
        },
        AnchorDoc::Param { t } => wire::Anchor::Param { t: *t },
        AnchorDoc::Span { t0, t1 } => wire::Anchor::Span { t0: *t0, t1: *t1 },
    }
}

/// Converts a wire role.
pub fn role_from_wire(r: wire::Role) -> IconRoleDoc {
    match r {
        wire::Role::Load => IconRoleDoc::Load,
        wire::Role::Position => IconRoleDoc::Position,
        wire::Role::Normal => IconRoleDoc::Normal,
        wire::Role::Derivative { which } => IconRoleDoc::Derivative {
            which: match which {
                wire::Derivative::R => DerivativeDoc::R,
                wire::Derivative::V => DerivativeDoc::V,
                wire::Derivative::R2 => DerivativeDoc::R2,
                wire::Derivative::V2 => DerivativeDoc::V2,
                wire::Derivative::RV => DerivativeDoc::RV,
            },
        },
    }
}

fn role_to_wire(r: IconRoleDoc) -> wire::Role {
    match r {
        IconRoleDoc::Load => wire::Role::Load,
        IconRoleDoc::Position => wire::Role::Position,
        IconRoleDoc::Normal => wire::Role::Normal,
        IconRoleDoc::Derivative { which } => wire::Role::Derivative {
            which: match which {
                DerivativeDoc::R => wire::Derivative::R,
                DerivativeDoc::V => wire::Derivative::V,
                DerivativeDoc::R2 => wire::Derivative::R2,
                DerivativeDoc::V2 => wire::Derivative::V2,
                DerivativeDoc::RV => wire::Derivative::RV,
            },
        },
    }
}

fn state_from_wire(s: wire::IconState) -> IconStateDoc {
    match s {
        wire::IconState::Driving => IconStateDoc::Driving,
        wire::IconState::Passive => IconStateDoc::Passive,
        wire::IconState::Sleeping => IconStateDoc::Sleeping,
    }
}

fn state_to_wire(s: IconStateDoc) -> wire::IconState {
    match s {
        IconStateDoc::Driving => wire::IconState::Driving,
        IconStateDoc::Passive => wire::IconState::Passive,
        IconStateDoc::Sleeping => wire::IconState::Sleeping,
    }
}

pub(crate) fn material_from_wire(m: &wire::Material) -> MaterialDoc {
    MaterialDoc {
        alpha11: m.alpha11,
        alpha12: m.alpha12,
        alpha22: m.alpha22,
        beta11: m.beta11,
        beta12: m.beta12,
        beta22: m.beta22,
    }
}

pub(crate) fn material_to_wire(m: &MaterialDoc) -> wire::Material {
    wire::Material {
        alpha11: m.alpha11,
        alpha12: m.alpha12,
        alpha22: m.alpha22,
        beta11: m.beta11,
        beta12: m.beta12,
        beta22: m.beta22,
    }
}

/// An icon as clients see it.
pub fn icon_to_wire(i: &IconDoc, holder: Option<u64>) -> wire::Icon {
    wire::Icon {
        id: i.id,
        anchor: anchor_to_wire(&i.anchor),
        role: role_to_wire(i.role),
        state: state_to_wire(i.state),
        xyz: i.xyz,
        target: i.target,
        sensors: i.sensors.clone(),
        holder,
    }
}

pub(crate) fn access(role: Role) -> wire::Access {
    match role {
        Role::Editor => wire::Access::Editor,
        Role::Viewer => wire::Access::Viewer,
        Role::Device => wire::Access::Device,
    }
}

fn version_to_wire(v: &VersionInfo) -> wire::VersionInfo {
    wire::VersionInfo {
        version: v.number,
        time_ms: v.time_ms.max(0) as u64,
        author: v.author.clone(),
        message: v.message.clone(),
    }
}

fn presence_entry(p: &Presence) -> wire::PresenceEntry {
    wire::PresenceEntry {
        client: p.client.id,
        name: p.client.name.clone(),
        access: access(p.client.role),
        holding: p.holding,
        pointer: p.pointer,
        camera: p.camera,
    }
}

fn presence_to_wire(p: &[Presence]) -> Vec<wire::PresenceEntry> {
    p.iter().map(presence_entry).collect()
}

/// Decodes one client message after the hello. On failure returns the
/// request number (when it could be read) with the error.
pub fn decode(text: &str) -> Result<(Option<u64>, Inbound), (Option<u64>, WireError)> {
    let env = wire::parse_client(text).map_err(|e| (req_of(text), WireError::from(e)))?;
    let req = env.req;
    use ClientMessage as M;
    let edit = |e: Edit| Inbound::Command(Command::Edit(e));
    let inbound = match env.msg {
        M::Hello { .. } => Inbound::Hello,
        M::Ping => Inbound::Ping,
        M::Received { bytes } => Inbound::Received { bytes },
        M::ListDesigns => Inbound::ListDesigns,
        M::CreateDesign { name } => Inbound::CreateDesign { name },
        M::DeleteDesign { design } => Inbound::DeleteDesign { design },
        M::ListVersions => Inbound::ListVersions,
        M::CreateIcon { part, spec } => edit(Edit::Part {
            part,
            edit: PartEdit::AddIcon {
                anchor: anchor_from_wire(&spec.anchor),
                role: role_from_wire(spec.role),
                state: state_from_wire(spec.state),
                target: spec.target,
            },
        }),
        M::EditIcon { part, icon, anchor } => edit(Edit::Part {
            part,
            edit: PartEdit::SetAnchor {
                id: icon,
                anchor: anchor_from_wire(&anchor),
            },
        }),
        M::MoveIcon { part, icon, xyz } => edit(Edit::Part {
            part,
            edit: PartEdit::MoveIcon { id: icon, xyz },
        }),
        M::DeleteIcon { part, icon } => edit(Edit::Part {
            part,
            edit: PartEdit::DeleteIcon { id: icon },
        }),
        M::SetRole { part, icon, role } => edit(Edit::Part {
            part,
            edit: PartEdit::SetRole {
                id: icon,
                role: role_from_wire(role),
            },
        }),
        M::SetState { part, icon, state } => edit(Edit::Part {
            part,
            edit: PartEdit::SetState {
                id: icon,
                state: state_from_wire(state),
            },
        }),
        M::BindSensor { part, icon, sensor } => edit(Edit::Part {
            part,
            edit: PartEdit::BindSensor { id: icon, sensor },
        }),
        M::UnbindSensor { part, icon, sensor } => edit(Edit::Part {
            part,
            edit: PartEdit::UnbindSensor { id: icon, sensor },
        }),
        M::SetMaterial { part, material } => edit(Edit::Part {
            part,
            edit: PartEdit::SetMaterial(parts::part_material_from_wire(&material)),
        }),
        M::DsmEdit { part, edit: e } => edit(Edit::Dsm { part, edit: e }),
        M::NetworkEdit { part, edit: e } => edit(Edit::Network {
            part,
            edit: network::edit_from_wire(&e),
        }),
        M::BodyEdit { part, edit: e } => edit(Edit::Part {
            part,
            edit: PartEdit::MoveLattice {
                select: parts::lattice_select(&e.select),
                delta: e.delta,
            },
        }),
        M::BodyMorph { part, t } => Inbound::Command(Command::BodyMorph { part, t }),
        M::CancelFairing { part, face } => Inbound::Command(Command::CancelFairing {
            part,
            face: face as usize,
        }),
        M::CreatePart { spec } => edit(parts::create_part(&spec)),
        M::DeletePart { part } => edit(Edit::DeletePart { part }),
        M::SetPart {
            part,
            name,
            visible,
            locked,
            colour,
        } => edit(Edit::SetPart {
            part,
            name,
            visible,
            locked,
            colour,
        }),
        M::Relate { relation } => edit(Edit::Relate(parts::relation_from_wire(&relation))),
        M::Unrelate { relation } => edit(Edit::Unrelate { relation }),
        M::AddComment { part, anchor, text } => {
            Inbound::Command(Command::Comment(CommentOp::Add {
                part,
                uv: anchor.uv().map(|(u, v)| [u, v]),
                xyz: anchor.xyz,
                text,
            }))
        }
        M::ReplyComment { comment, text } => {
            Inbound::Command(Command::Comment(CommentOp::Reply { comment, text }))
        }
        M::ResolveComment { comment, resolved } => {
            Inbound::Command(Command::Comment(CommentOp::Resolve { comment, resolved }))
        }
        M::DeleteComment { comment } => {
            Inbound::Command(Command::Comment(CommentOp::Delete { comment }))
        }
        M::EditComment { comment, text } => {
            Inbound::Command(Command::Comment(CommentOp::Edit { comment, text }))
        }
        M::DragStart { part, icon } => Inbound::Command(Command::Grab { part, icon }),
        M::Drag { part, icon, xyz } => Inbound::Command(Command::Drag {
            part,
            icon,
            xyz: DVec3::from(xyz),
        }),
        M::DragEnd { part, icon } => Inbound::Command(Command::Release { part, icon }),
        M::Commit { message } => Inbound::Command(Command::Commit { message }),
        M::Revert => Inbound::Command(Command::Revert),
        M::Undo => Inbound::Command(Command::Undo),
        M::Redo => Inbound::Command(Command::Redo),
        M::RestoreVersion { version } => Inbound::Command(Command::Restore { version }),
        M::Presence { pointer, camera } => Inbound::Presence {
            pointer: pointer.map(DVec3::from),
            camera,
        },
        M::DeviceSample {
            sensor, position, ..
        } => Inbound::DeviceSample {
            sensor,
            position: DVec3::from(position),
        },
        M::DeviceStatus {
            device,
            condition,
            message,
        } => Inbound::DeviceStatus {
            device,
            condition: format!("{condition:?}").to_lowercase(),
            message,
        },
    };
    Ok((req, inbound))
}

pub(crate) fn text(m: &ServerMessage) -> Utf8Bytes {
    // Server messages hold finite floats and plain data: serialising them
    // cannot fail.
    serde_json::to_string(m).unwrap_or_default().into()
}

/// `welcome`; `geometry` names a compact join's frames, `geometry_cached`
/// says the client kept them (so they are not sent).
pub fn welcome(
    client: u64,
    design: DesignId,
    role: Role,
    geometry: Option<String>,
    geometry_cached: bool,
) -> Utf8Bytes {
    text(&ServerMessage::Welcome {
        client_id: client,
        access: access(role),
        design,
        protocol: wire::PROTOCOL_VERSION,
        geometry,
        geometry_cached,
    })
}

/// `error` (echoing `req`).
pub fn error(req: Option<u64>, e: &WireError) -> Utf8Bytes {
    text(&ServerMessage::Error {
        req,
        code: e.code,
        message: e.message.clone(),
    })
}

/// `ack` for a request with a number (with the icon it created or the
/// version it made or loaded); nothing for one without.
pub fn ack(req: Option<u64>, ack: &Ack) -> Option<Utf8Bytes> {
    req.map(|req| {
        text(&ServerMessage::Ack {
            req,
            icon: ack.created_icon,
            version: ack.version,
            part: ack.created_part,
            relation: ack.created_relation,
            comment: ack.created_comment,
            warning: ack.warning.clone(),
        })
    })
}

/// `pong` (echoing `req`).
pub fn pong(req: Option<u64>) -> Utf8Bytes {
    text(&ServerMessage::Pong { req })
}

/// `designs` (echoing `req`).
pub fn design_list(req: Option<u64>, designs: &[(DesignId, String, u64)]) -> Utf8Bytes {
    text(&ServerMessage::Designs {
        req,
        designs: designs
            .iter()
            .map(|(id, name, versions)| wire::DesignInfo {
                id: *id,
                name: name.clone(),
                versions: *versions,
            })
            .collect(),
    })
}

/// `design_created`, for its creator only: the new design with its tokens.
pub fn design_created(req: Option<u64>, rec: &DesignRecord) -> Utf8Bytes {
    text(&ServerMessage::DesignCreated {
        req,
        design: wire::DesignInfo {
            id: rec.id,
            name: rec.name.clone(),
            versions: 1,
        },
        tokens: wire::DesignTokens {
            editor: rec.tokens.editor.clone(),
            viewer: rec.tokens.viewer.clone(),
            device: rec.tokens.device.clone(),
        },
    })
}

/// `versions` (echoing `req`).
pub fn versions(req: Option<u64>, v: &[VersionInfo]) -> Utf8Bytes {
    text(&ServerMessage::Versions {
        req,
        versions: v.iter().map(version_to_wire).collect(),
    })
}

fn holders(presence: &[Presence]) -> BTreeMap<u64, u64> {
    presence
        .iter()
        .filter_map(|p| p.holding.map(|icon| (icon, p.client.id)))
        .collect()
}

/// `snapshot`: the full state; with `points` false, every part's control
/// points are left empty for a client of the compact join, which has the
/// shapes from frames.
pub fn snapshot(v: &SnapshotView, points: bool) -> Utf8Bytes {
    let holders = holders(&v.presence);
    text(&ServerMessage::Snapshot {
        design: wire::DesignInfo {
            id: v.design,
            name: v.doc.name.clone(),
            versions: v.versions.len() as u64,
        },
        revision: v.revision,
        parts: v
            .doc
            .parts
            .iter()
            .map(|p| parts::part_to_wire(p, &holders, points))
            .collect(),
        relations: v
            .doc
            .relations
            .iter()
            .map(parts::relation_to_wire)
            .collect(),
        versions: v.versions.iter().map(version_to_wire).collect(),
        presence: presence_to_wire(&v.presence),
        can_undo: v.can_undo,
        can_redo: v.can_redo,
        comments: v.comments.iter().map(comments::thread_to_wire).collect(),
        fairing: v.fairing.iter().map(network::fairing_progress).collect(),
    })
}

/// The message of an event (`None` for events with no wire form); a
/// snapshot or a new part carries its points unless `points` is false (the
/// compact join).
pub fn event(e: &DesignEvent, points: bool) -> Option<Utf8Bytes> {
    Some(match e {
        DesignEvent::Snapshot(v) => snapshot(v, points),
        DesignEvent::IconCreated(part, i, holder) => text(&ServerMessage::IconCreated {
            part: *part,
            icon: icon_to_wire(i, *holder),
        }),
        DesignEvent::IconUpdated(part, i, holder) => text(&ServerMessage::IconUpdated {
            part: *part,
            icon: icon_to_wire(i, *holder),
        }),
        DesignEvent::IconDeleted(part, id) => text(&ServerMessage::IconDeleted {
            part: *part,
            icon: *id,
        }),
        DesignEvent::MaterialChanged(part, m) => text(&ServerMessage::MaterialChanged {
            part: *part,
            material: parts::part_material_to_wire(m),
        }),
        DesignEvent::PartCreated(p, holders) => text(&ServerMessage::PartCreated {
            part: parts::part_to_wire(p, holders, points),
        }),
        DesignEvent::PartDeleted(id) => text(&ServerMessage::PartDeleted { part: *id }),
        DesignEvent::PartChanged(p) => text(&ServerMessage::PartChanged {
            part: p.id,
            name: p.name.clone(),
            visible: p.visible,
            locked: p.locked,
            colour: p.colour.clone(),
        }),
        DesignEvent::NetworkChanged(part, v) => text(&ServerMessage::NetworkChanged {
            part: *part,
            network: network::network_to_wire(v),
        }),
        DesignEvent::FairingProgress(p) => network::fairing_progress_to_wire(p),
        DesignEvent::FairingEnded(e) => network::fairing_ended_to_wire(e),
        DesignEvent::DsmChanged(p) => match &p.body {
            PartBody::Dsm(d) => text(&ServerMessage::DsmChanged {
                part: p.id,
                dsm: d.dsm.clone(),
            }),
            _ => Utf8Bytes::default(),
        },
        DesignEvent::RelationCreated(r) => text(&ServerMessage::RelationCreated {
            relation: parts::relation_to_wire(r),
        }),
        DesignEvent::RelationDeleted(id) => text(&ServerMessage::RelationDeleted { relation: *id }),
        DesignEvent::Comment(c) => text(&comments::change_to_wire(c)),
        DesignEvent::Committed(v) => text(&ServerMessage::Committed {
            version: version_to_wire(v),
        }),
        DesignEvent::PresenceChanged(p) => text(&ServerMessage::PresenceChanged {
            client: presence_entry(p),
        }),
        DesignEvent::PresenceLeft(client) => text(&ServerMessage::PresenceLeft { client: *client }),
        DesignEvent::History { can_undo, can_redo } => text(&ServerMessage::History {
            can_undo: *can_undo,
            can_redo: *can_redo,
        }),
        DesignEvent::Deleted(design) => text(&ServerMessage::Error {
            req: None,
            code: ErrorCode::UnknownDesign,
            message: format!("design {design} was deleted"),
        }),
    })
}

/// `icon_feedback` for the dragging client.
pub fn feedback(f: &Feedback) -> Utf8Bytes {
    text(&ServerMessage::IconFeedback {
        part: f.part,
        icon: f.icon,
        requested: f.requested.to_array(),
        actual: f.actual.to_array(),
        revision: f.revision,
        warning: f.warning.clone(),
    })
}

/// The binary geometry frame of one part: knots, control points (f32) and
/// the positions of its icons.
pub fn geometry_frame(
    design: DesignId,
    revision: u64,
    drag: bool,
    part: &PartDoc,
    points: &[DVec3],
    icons: &[(u64, DVec3)],
) -> Bytes {
    let (kind, degree_u, degree_v, nu, nv, knots_u, knots_v) = match &part.body {
        PartBody::Surface(p) => {
            let s = &p.surface;
            (
                wire::frame::KIND_SURFACE,
                s.u_degree as u8,
                s.v_degree as u8,
                s.nu as u32,
                s.nv as u32,
                s.u_knots.clone(),
                s.v_knots.clone(),
            )
        }
        // Network and DSM parts travel as mesh frames
        // (`NetworkEngine::frame`, `DesignModel::geometry`).
        PartBody::Network(_) | PartBody::Dsm(_) => return Bytes::new(),
        PartBody::Curve(c) => {
            let c = &c.curve;
            (
                wire::frame::KIND_CURVE,
                c.degree as u8,
                0,
                c.points.len() as u32,
                1,
                c.knots.clone(),
                Vec::new(),
            )
        }
        // A body part's frame is a body frame (kind 4) from its engine.
        PartBody::Body(_) => return Bytes::new(),
    };
    let frame = wire::GeometryFrame {
        kind,
        design,
        part: part.id,
        revision,
        flags: if drag { wire::frame::FLAG_DRAG } else { 0 },
        degree_u,
        degree_v,
        nu,
        nv,
        knots_u,
        knots_v,
        points: points
            .iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect(),
        icons: icons
            .iter()
            .map(|(id, p)| wire::FrameIcon {
                id: *id,
                xyz: [p.x as f32, p.y as f32, p.z as f32],
            })
            .collect(),
    };
    match frame.encode() {
        Ok(b) => Bytes::from(b),
        Err(e) => {
            // Only non-finite numbers or absurd sizes fail; the engine
            // never publishes either, so this is a bug worth a loud log.
            tracing::error!(design, "cannot encode geometry frame: {e}");
            Bytes::new()
        }
    }
}
