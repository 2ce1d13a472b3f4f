//! The bridge's mapping onto the vsculpt protocol (`vsculpt-protocol`, version
//! [`PROTOCOL_VERSION`]): bridge [`Command`]s become client messages and server
//! messages become [`ServerEvent`]s. Everything from the server is validated
//! here (finite numbers) before it reaches the interaction.
//!
//! * grab → `bind_sensor` + `drag_start`; release → `unbind_sensor` + `drag_end`;
//! * drag → `drag` (a constraint's displaced target or a load's pulled-to point);
//!   a drag flushed ahead of a release carries a `req` so the server keeps it in order;
//! * menu → `set_state` / `set_role` (tangent = derivative `R`);
//! * hand → `device_sample` (orientation w, x, y, z; flexion in radians);
//! * device availability → `device_status`;
//! * `snapshot` → the icon set and the surface area S (of the control net) for
//!   k0 = κ S; `icon_created` / `icon_updated` / `icon_deleted`; `icon_feedback` → Δy.
//! * parts (protocol 2): the wire keeps which part each icon is on (every icon
//!   message names its part) and shows the interaction only the icons of visible,
//!   unlocked parts — a grab picks the nearest icon across those; a part hidden,
//!   locked or deleted takes its icons away, shown or unlocked brings them back.
//!   S is the largest surface part's control-net area.

use crate::interaction::{Command, DeviceCondition, IconKind, IconRole, IconState, IconView};
use crate::link::{Rejection, ServerEvent, Wire};
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use vsculpt_protocol::{
    ClientEnvelope, ClientKind, ClientMessage, Derivative, ErrorCode, Icon, PROTOCOL_VERSION, Part,
    PartShape, Role, ServerMessage, SurfaceData,
};

/// Name the bridge gives itself in presence.
pub const CLIENT_NAME: &str = "vsculpt-bridge";

/// The protocol mapping.
#[derive(Debug, Default)]
pub struct ProtocolWire {
    parts: Mutex<Parts>,
}

/// What the wire knows of the design's parts (from the snapshot and the
/// events since).
#[derive(Debug, Default)]
struct Parts {
    parts: BTreeMap<u64, PartState>,
}

#[derive(Debug, Default)]
struct PartState {
    visible: bool,
    locked: bool,
    icons: BTreeMap<u64, IconView>,
}

impl PartState {
    fn grabbable(&self) -> bool {
        self.visible && !self.locked
    }
}

impl Parts {
    fn part_of(&self, icon: u64) -> u64 {
        self.parts
            .iter()
            .find(|(_, p)| p.icons.contains_key(&icon))
            .map_or(0, |(id, _)| *id)
    }

    fn insert(&mut self, p: &Part) {
        let icons = p
            .icons
            .iter()
            .filter_map(|i| icon_view(p.id, i))
            .map(|v| (v.id, v))
            .collect();
        self.parts.insert(
            p.id,
            PartState {
                visible: p.visible,
                locked: p.locked,
                icons,
            },
        );
    }

    fn grabbable(&self) -> Vec<IconView> {
        self.parts
            .values()
            .filter(|p| p.grabbable())
            .flat_map(|p| p.icons.values().copied())
            .collect()
    }
}

fn text(msg: ClientMessage) -> String {
    envelope(None, msg)
}

fn envelope(req: Option<u64>, msg: ClientMessage) -> String {
    serde_json::to_string(&ClientEnvelope { req, msg }).unwrap_or_default()
}

/// Request numbers for drags that must stay in order (process-wide, never reused).
static NEXT_REQ: AtomicU64 = AtomicU64::new(1);

fn state_to_wire(s: IconState) -> vsculpt_protocol::IconState {
    match s {
        IconState::Driving => vsculpt_protocol::IconState::Driving,
        IconState::Passive => vsculpt_protocol::IconState::Passive,
        IconState::Sleeping => vsculpt_protocol::IconState::Sleeping,
    }
}

fn state_from_wire(s: vsculpt_protocol::IconState) -> IconState {
    match s {
        vsculpt_protocol::IconState::Driving => IconState::Driving,
        vsculpt_protocol::IconState::Passive => IconState::Passive,
        vsculpt_protocol::IconState::Sleeping => IconState::Sleeping,
    }
}

/// An icon as the bridge sees it; `None` when its numbers are not finite.
pub fn icon_view(part: u64, icon: &Icon) -> Option<IconView> {
    let position = DVec3::from_array(icon.xyz);
    let target = DVec3::from_array(icon.target);
    if !position.is_finite() || !target.is_finite() {
        return None;
    }
    let (role, kind) = match icon.role {
        Role::Load => (IconRole::Load, IconKind::Position),
        Role::Position => (IconRole::Constraint, IconKind::Position),
        Role::Derivative { .. } => (IconRole::Constraint, IconKind::Tangent),
        Role::Normal => (IconRole::Constraint, IconKind::Normal),
    };
    Some(IconView {
        id: icon.id,
        part,
        position,
        target,
        role,
        kind,
        state: state_from_wire(icon.state),
    })
}

/// Area of the surface's control net (two triangles per cell): the S of k0 = κ S.
/// The net's area bounds the surface's from above and equals it for a flat plate.
pub fn control_net_area(s: &SurfaceData) -> Option<f64> {
    let (nu, nv) = (s.nu as usize, s.nv as usize);
    if nu < 2 || nv < 2 || s.points.len() != nu * nv {
        return None;
    }
    let p = |i: usize, j: usize| DVec3::from_array(s.points[i * nv + j]);
    let mut area = 0.0;
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            area += 0.5 * (b - a).cross(c - a).length() + 0.5 * (c - a).cross(d - a).length();
        }
    }
    (area.is_finite() && area > 0.0).then_some(area)
}

impl Wire for ProtocolWire {
    fn hello(&self, token: &str, design: Option<u64>) -> String {
        text(ClientMessage::Hello {
            protocol: PROTOCOL_VERSION,
            token: token.to_owned(),
            design: design.unwrap_or(1),
            client_name: CLIENT_NAME.to_owned(),
            client_kind: ClientKind::Bridge,
            geometry_first: false,
            cached_geometry: None,
        })
    }

    fn encode(&self, cmd: &Command, ordered: bool) -> Vec<String> {
        let part_of = |icon: &u64| {
            self.parts
                .lock()
                .map(|p| p.part_of(*icon))
                .unwrap_or_default()
        };
        // A drag without a request number takes the server's coalesced drag path,
        // which may overtake commands; one that precedes a release or a state change
        // carries a number so that the server applies it in order.
        if let (Command::Drag { icon, target }, true) = (cmd, ordered) {
            let req = NEXT_REQ.fetch_add(1, Ordering::Relaxed);
            return vec![envelope(
                Some(req),
                ClientMessage::Drag {
                    part: part_of(icon),
                    icon: *icon,
                    xyz: target.to_array(),
                },
            )];
        }
        let msgs = match cmd {
            Command::Grab { icon, sensor } => vec![
                ClientMessage::BindSensor {
                    part: part_of(icon),
                    icon: *icon,
                    sensor: sensor.clone(),
                },
                ClientMessage::DragStart {
                    part: part_of(icon),
                    icon: *icon,
                },
            ],
            Command::Release { icon, sensor } => vec![
                ClientMessage::UnbindSensor {
                    part: part_of(icon),
                    icon: *icon,
                    sensor: sensor.clone(),
                },
                ClientMessage::DragEnd {
                    part: part_of(icon),
                    icon: *icon,
                },
            ],
            Command::Drag { icon, target } => vec![ClientMessage::Drag {
                part: part_of(icon),
                icon: *icon,
                xyz: target.to_array(),
            }],
            Command::SetState { icon, state } => vec![ClientMessage::SetState {
                part: part_of(icon),
                icon: *icon,
                state: state_to_wire(*state),
            }],
            Command::SetRole { icon, role } => vec![ClientMessage::SetRole {
                part: part_of(icon),
                icon: *icon,
                role: match role {
                    IconRole::Load => Role::Load,
                    IconRole::Constraint => Role::Position,
                },
            }],
            Command::SetKind { icon, kind } => vec![ClientMessage::SetRole {
                part: part_of(icon),
                icon: *icon,
                role: match kind {
                    IconKind::Position => Role::Position,
                    IconKind::Tangent => Role::Derivative {
                        which: Derivative::R,
                    },
                    IconKind::Normal => Role::Normal,
                },
            }],
            Command::HandSample {
                sensor,
                position,
                orientation,
                flexion,
                time,
            } => vec![ClientMessage::DeviceSample {
                sensor: sensor.clone(),
                position: position.to_array(),
                orientation: [orientation.w, orientation.x, orientation.y, orientation.z],
                flexion: (!flexion.is_empty()).then(|| flexion.clone()),
                buttons: 0,
                time_us: time.0,
            }],
            Command::DeviceStatus {
                device,
                condition,
                message,
            } => vec![ClientMessage::DeviceStatus {
                device: device.clone(),
                condition: match condition {
                    DeviceCondition::Connected => vsculpt_protocol::DeviceCondition::Connected,
                    DeviceCondition::Disconnected => {
                        vsculpt_protocol::DeviceCondition::Disconnected
                    }
                },
                message: message.chars().take(512).collect(),
            }],
        };
        // An ordered design command carries a number: its answer (ack or error)
        // tells a replay that the server has done it.
        let numbered = ordered && self.answers(cmd, ordered) > 0;
        msgs.into_iter()
            .map(|m| {
                let req = numbered.then(|| NEXT_REQ.fetch_add(1, Ordering::Relaxed));
                envelope(req, m)
            })
            .collect()
    }

    fn answers(&self, cmd: &Command, ordered: bool) -> u64 {
        match cmd {
            Command::Grab { .. } | Command::Release { .. } => 2,
            Command::SetState { .. } | Command::SetRole { .. } | Command::SetKind { .. } => 1,
            // A coalesced drag is fire-and-forget; an ordered one is numbered.
            Command::Drag { .. } => u64::from(ordered),
            Command::HandSample { .. } | Command::DeviceStatus { .. } => 0,
        }
    }

    fn decode(&self, text: &str) -> Result<Vec<ServerEvent>, String> {
        let msg: ServerMessage = serde_json::from_str(text).map_err(|e| e.to_string())?;
        Ok(match msg {
            ServerMessage::Welcome { .. } => vec![ServerEvent::Welcome],
            ServerMessage::Snapshot { parts, .. } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                *state = Parts::default();
                for p in &parts {
                    state.insert(p);
                }
                // S of the largest surface part (the spring's k0 = κ S).
                let area = parts
                    .iter()
                    .filter_map(|p| match &p.shape {
                        PartShape::Surface { surface } => control_net_area(surface),
                        _ => None,
                    })
                    .reduce(f64::max);
                vec![ServerEvent::Icons {
                    icons: state.grabbable(),
                    area,
                }]
            }
            ServerMessage::IconCreated { part, icon }
            | ServerMessage::IconUpdated { part, icon } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                let Some(view) = icon_view(part, &icon) else {
                    return Ok(Vec::new());
                };
                let p = state.parts.entry(part).or_insert_with(|| PartState {
                    visible: true,
                    ..PartState::default()
                });
                p.icons.insert(icon.id, view);
                if p.grabbable() {
                    vec![ServerEvent::Icon(view)]
                } else {
                    Vec::new()
                }
            }
            ServerMessage::IconDeleted { part, icon } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                if let Some(p) = state.parts.get_mut(&part) {
                    p.icons.remove(&icon);
                }
                vec![ServerEvent::IconRemoved(icon)]
            }
            ServerMessage::PartCreated { part } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                state.insert(&part);
                let p = &state.parts[&part.id];
                if p.grabbable() {
                    p.icons.values().map(|v| ServerEvent::Icon(*v)).collect()
                } else {
                    Vec::new()
                }
            }
            ServerMessage::PartDeleted { part } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                state
                    .parts
                    .remove(&part)
                    .map(|p| {
                        p.icons
                            .keys()
                            .map(|i| ServerEvent::IconRemoved(*i))
                            .collect()
                    })
                    .unwrap_or_default()
            }
            ServerMessage::PartChanged {
                part,
                visible,
                locked,
                ..
            } => {
                let mut state = self.parts.lock().map_err(|_| "wire state poisoned")?;
                let Some(p) = state.parts.get_mut(&part) else {
                    return Ok(Vec::new());
                };
                let was = p.grabbable();
                p.visible = visible;
                p.locked = locked;
                match (was, p.grabbable()) {
                    (true, false) => p
                        .icons
                        .keys()
                        .map(|i| ServerEvent::IconRemoved(*i))
                        .collect(),
                    (false, true) => p.icons.values().map(|v| ServerEvent::Icon(*v)).collect(),
                    _ => Vec::new(),
                }
            }
            ServerMessage::IconFeedback { icon, actual, .. } => {
                let actual = DVec3::from_array(actual);
                if actual.is_finite() {
                    vec![ServerEvent::Feedback { icon, actual }]
                } else {
                    Vec::new()
                }
            }
            ServerMessage::Error { code, message, req } => match code {
                ErrorCode::BadToken => vec![ServerEvent::Rejected(Rejection::Token, message)],
                ErrorCode::UnknownDesign => vec![ServerEvent::Rejected(Rejection::Design, message)],
                ErrorCode::BadVersion => vec![ServerEvent::Rejected(Rejection::Version, message)],
                _ => std::iter::once(ServerEvent::Error(format!("{code:?}: {message}")))
                    .chain(req.map(ServerEvent::Reply))
                    .collect(),
            },
            ServerMessage::Ack { req, .. } => vec![ServerEvent::Reply(req)],
            ServerMessage::Pong { req: Some(req) } => vec![ServerEvent::Reply(req)],
            _ => Vec::new(),
        })
    }

    fn accepts(&self, event: &ServerEvent) -> bool {
        matches!(event, ServerEvent::Welcome)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::Timestamp;
    use glam::DQuat;
    use vsculpt_protocol::parse_client;

    /// A snapshot of two surface parts (7 visible with icons 1 and 2, 8
    /// hidden with icon 5), as a server sends it.
    const SNAPSHOT: &str = r##"{"type": "snapshot", "design": {"id": 1, "name": "d", "versions": 1}, "revision": 3,
        "parts": [
          {"id": 7, "name": "a", "visible": true, "locked": false, "colour": "#ffffff",
           "material": {"alpha11": 0.1, "alpha12": 0.0, "alpha22": 0.1, "beta11": 1.0, "beta12": 1.0, "beta22": 1.0},
           "icons": [
             {"id": 1, "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}, "state": "passive", "xyz": [0.5, 0.5, 0.0], "target": [0.5, 0.5, 0.0], "sensors": []},
             {"id": 2, "anchor": {"kind": "point", "u": 0.1, "v": 0.1}, "role": {"kind": "position"}, "state": "passive", "xyz": [0.1, 0.1, 0.0], "target": [0.1, 0.1, 0.0], "sensors": []}],
           "shape": {"kind": "surface", "surface": {"u": {"degree": 1, "knots": [0, 0, 1, 1]}, "v": {"degree": 1, "knots": [0, 0, 1, 1]}, "nu": 2, "nv": 2,
                     "points": [[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]]}}},
          {"id": 8, "name": "b", "visible": false, "locked": false, "colour": "#ffffff",
           "material": {"alpha11": 0.1, "alpha12": 0.0, "alpha22": 0.1, "beta11": 1.0, "beta12": 1.0, "beta22": 1.0},
           "icons": [
             {"id": 5, "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}, "state": "passive", "xyz": [3.0, 0.5, 0.0], "target": [3.0, 0.5, 0.0], "sensors": []}],
           "shape": {"kind": "surface", "surface": {"u": {"degree": 1, "knots": [0, 0, 1, 1]}, "v": {"degree": 1, "knots": [0, 0, 1, 1]}, "nu": 2, "nv": 2,
                     "points": [[2, 0, 0], [2, 3, 0], [4, 0, 0], [4, 3, 0]]}}}],
        "relations": [], "versions": [], "presence": [], "can_undo": false, "can_redo": false}"##;

    fn ids(ev: &[ServerEvent]) -> Vec<(&'static str, u64)> {
        ev.iter()
            .flat_map(|e| match e {
                ServerEvent::Icons { icons, .. } => icons.iter().map(|i| ("icon", i.id)).collect(),
                ServerEvent::Icon(i) => vec![("icon", i.id)],
                ServerEvent::IconRemoved(i) => vec![("removed", *i)],
                _ => Vec::new(),
            })
            .collect()
    }

    #[test]
    fn only_icons_of_visible_unlocked_parts_are_grabbable() {
        let w = ProtocolWire::default();
        let ev = w.decode(SNAPSHOT).unwrap();
        assert_eq!(ids(&ev), vec![("icon", 1), ("icon", 2)]);
        // S: the larger surface part (2 × 3 = 6, not 1 + 6).
        assert!(
            matches!(ev[0], ServerEvent::Icons { area: Some(a), .. } if (a - 6.0).abs() < 1e-12)
        );
        let change = |part: u64, visible: bool, locked: bool| {
            format!(
                r##"{{"type": "part_changed", "part": {part}, "name": "x", "visible": {visible}, "locked": {locked}, "colour": "#000000"}}"##
            )
        };
        // Locking part 7 takes its icons away; showing part 8 brings its icon.
        assert_eq!(
            ids(&w.decode(&change(7, true, true)).unwrap()),
            vec![("removed", 1), ("removed", 2)]
        );
        assert_eq!(
            ids(&w.decode(&change(8, true, false)).unwrap()),
            vec![("icon", 5)]
        );
        // An icon updated on a locked part is not offered; unlocking offers both.
        let icon = r#"{"id": 2, "anchor": {"kind": "point", "u": 0.1, "v": 0.1}, "role": {"kind": "load"}, "state": "passive", "xyz": [0.1, 0.1, 0.5], "target": [0.1, 0.1, 0.5], "sensors": []}"#;
        let ev = w
            .decode(&format!(
                r#"{{"type": "icon_updated", "part": 7, "icon": {icon}}}"#
            ))
            .unwrap();
        assert!(ev.is_empty());
        assert_eq!(
            ids(&w.decode(&change(7, true, false)).unwrap()),
            vec![("icon", 1), ("icon", 2)]
        );
        // A deleted part's icons go.
        assert_eq!(
            ids(&w.decode(r#"{"type": "part_deleted", "part": 8}"#).unwrap()),
            vec![("removed", 5)]
        );
    }

    #[test]
    fn every_command_is_a_valid_client_message() {
        let w = ProtocolWire::default();
        // Icon 1 is on part 7: every message about it names part 7.
        w.decode(SNAPSHOT).unwrap();
        let hello = parse_client(&w.hello("tok", Some(3))).unwrap();
        assert!(matches!(
            hello.msg,
            ClientMessage::Hello {
                design: 3,
                protocol: PROTOCOL_VERSION,
                client_kind: ClientKind::Bridge,
                ..
            }
        ));
        let cmds = [
            Command::Grab {
                icon: 1,
                sensor: "right".into(),
            },
            Command::Release {
                icon: 1,
                sensor: "right".into(),
            },
            Command::Drag {
                icon: 1,
                target: DVec3::new(0.1, 0.2, 0.3),
            },
            Command::SetState {
                icon: 1,
                state: IconState::Sleeping,
            },
            Command::SetRole {
                icon: 1,
                role: IconRole::Load,
            },
            Command::SetKind {
                icon: 1,
                kind: IconKind::Tangent,
            },
            Command::HandSample {
                sensor: "right".into(),
                position: DVec3::ONE,
                orientation: DQuat::from_rotation_z(0.3),
                flexion: vec![0.1; 22],
                time: Timestamp(5),
            },
            Command::DeviceStatus {
                device: "glove".into(),
                condition: DeviceCondition::Disconnected,
                message: "gone".into(),
            },
        ];
        let parsed: Vec<ClientMessage> = cmds
            .iter()
            .flat_map(|c| w.encode(c, false))
            .map(|t| parse_client(t.as_str()).unwrap().msg)
            .collect();
        assert_eq!(
            parsed[0],
            ClientMessage::BindSensor {
                part: 7,
                icon: 1,
                sensor: "right".into()
            }
        );
        assert_eq!(parsed[1], ClientMessage::DragStart { part: 7, icon: 1 });
        assert_eq!(
            parsed[2],
            ClientMessage::UnbindSensor {
                part: 7,
                icon: 1,
                sensor: "right".into()
            }
        );
        assert_eq!(parsed[3], ClientMessage::DragEnd { part: 7, icon: 1 });
        assert_eq!(
            parsed[4],
            ClientMessage::Drag {
                part: 7,
                icon: 1,
                xyz: [0.1, 0.2, 0.3]
            }
        );
        assert_eq!(
            parsed[7],
            ClientMessage::SetRole {
                part: 7,
                icon: 1,
                role: Role::Derivative {
                    which: Derivative::R
                }
            }
        );
        match &parsed[8] {
            ClientMessage::DeviceSample {
                orientation,
                flexion,
                time_us,
                ..
            } => {
                let q = DQuat::from_rotation_z(0.3);
                assert_eq!(*orientation, [q.w, q.x, q.y, q.z]);
                assert_eq!(flexion.as_ref().map(Vec::len), Some(22));
                assert_eq!(*time_us, 5);
            }
            m => panic!("{m:?}"),
        }
        assert_eq!(parsed.len(), 10);
        // an ordered drag carries a request number, a coalesced one does not
        let drag = Command::Drag {
            icon: 2,
            target: DVec3::ZERO,
        };
        assert!(
            parse_client(&w.encode(&drag, true)[0])
                .unwrap()
                .req
                .is_some()
        );
        assert!(
            parse_client(&w.encode(&drag, false)[0])
                .unwrap()
                .req
                .is_none()
        );
    }

    #[test]
    fn server_messages_become_events() {
        let w = ProtocolWire::default();
        let icon = r#"{"id": 3, "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}, "state": "passive", "xyz": [1.0, 2.0, 3.0], "target": [1.0, 2.0, 3.0], "sensors": []}"#;
        let ev = w
            .decode(&format!(
                r#"{{"type": "icon_updated", "part": 2, "icon": {icon}}}"#
            ))
            .unwrap();
        assert_eq!(
            ev,
            vec![ServerEvent::Icon(IconView {
                id: 3,
                part: 2,
                position: DVec3::new(1.0, 2.0, 3.0),
                target: DVec3::new(1.0, 2.0, 3.0),
                role: IconRole::Load,
                kind: IconKind::Position,
                state: IconState::Passive
            })]
        );
        let ev = w
            .decode(r#"{"type": "icon_feedback", "part": 2, "icon": 3, "requested": [0.5, 0.5, 0.4], "actual": [0.5, 0.5, 0.31], "revision": 13}"#)
            .unwrap();
        assert_eq!(
            ev,
            vec![ServerEvent::Feedback {
                icon: 3,
                actual: DVec3::new(0.5, 0.5, 0.31)
            }]
        );
        let ev = w
            .decode(r#"{"type": "welcome", "client_id": 4, "access": "device", "design": 1, "protocol": 1}"#)
            .unwrap();
        assert!(w.accepts(&ev[0]));
        let ev = w
            .decode(r#"{"type": "error", "code": "bad_token", "message": "no"}"#)
            .unwrap();
        assert_eq!(ev[0], ServerEvent::Rejected(Rejection::Token, "no".into()));
        let ev = w
            .decode(r#"{"type": "error", "code": "forbidden", "message": "viewer"}"#)
            .unwrap();
        assert!(matches!(&ev[0], ServerEvent::Error(e) if e.contains("viewer")));
        assert!(w.decode("{\"type\": \"nonsense\"}").is_err());
        assert!(w.decode("not json").is_err());
        assert_eq!(w.decode(r#"{"type": "pong"}"#).unwrap(), vec![]);
    }

    #[test]
    fn ordered_design_commands_are_numbered_and_their_answers_reported() {
        let w = ProtocolWire::default();
        let grab = Command::Grab {
            icon: 1,
            sensor: "right".into(),
        };
        let drag = Command::Drag {
            icon: 1,
            target: DVec3::X,
        };
        let numbered = |texts: Vec<String>| {
            texts
                .iter()
                .map(|t| parse_client(t).unwrap().req)
                .collect::<Vec<_>>()
        };
        // in order: both messages of a grab and the drag carry numbers, one
        // answer each
        let reqs = numbered(w.encode(&grab, true));
        assert_eq!(reqs.len(), 2);
        assert!(reqs.iter().all(Option::is_some));
        assert_eq!(w.answers(&grab, true), 2);
        assert!(numbered(w.encode(&drag, true))[0].is_some());
        assert_eq!(w.answers(&drag, true), 1);
        // a coalesced drag is fire-and-forget; a hand sample is never answered
        assert_eq!(numbered(w.encode(&drag, false)), vec![None]);
        assert_eq!(w.answers(&drag, false), 0);
        // acks, numbered errors and pongs are answers
        assert_eq!(
            w.decode(r#"{"type": "ack", "req": 7}"#).unwrap(),
            vec![ServerEvent::Reply(7)]
        );
        assert_eq!(
            w.decode(r#"{"type": "pong", "req": 8}"#).unwrap(),
            vec![ServerEvent::Reply(8)]
        );
        let refused = w
            .decode(
                r#"{"type": "error", "req": 9, "code": "unknown_icon", "message": "no icon 1"}"#,
            )
            .unwrap();
        assert_eq!(refused.len(), 2);
        assert_eq!(refused[1], ServerEvent::Reply(9));
    }

    #[test]
    fn control_net_area_of_a_plate() {
        let s = SurfaceData {
            u: vsculpt_protocol::Knots {
                degree: 1,
                knots: vec![0.0, 0.0, 1.0, 2.0, 2.0],
            },
            v: vsculpt_protocol::Knots {
                degree: 1,
                knots: vec![0.0, 0.0, 1.0, 1.0],
            },
            nu: 3,
            nv: 2,
            points: vec![
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [3.0, 0.0, 0.0],
                [3.0, 1.0, 0.0],
            ],
        };
        assert!((control_net_area(&s).unwrap() - 3.0).abs() < 1e-12);
        let mut bad = s.clone();
        bad.points.pop();
        assert_eq!(control_net_area(&bad), None);
    }
}
