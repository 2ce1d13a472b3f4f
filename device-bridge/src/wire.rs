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

use crate::interaction::{Command, DeviceCondition, IconKind, IconRole, IconState, IconView};
use crate::link::{Rejection, ServerEvent, Wire};
use glam::DVec3;
use std::sync::atomic::{AtomicU64, Ordering};
use vsculpt_protocol::{
    ClientEnvelope, ClientKind, ClientMessage, Derivative, ErrorCode, Icon, PROTOCOL_VERSION, Role,
    ServerMessage, SurfaceData,
};

/// Name the bridge gives itself in presence.
pub const CLIENT_NAME: &str = "vsculpt-bridge";

/// The protocol mapping.
#[derive(Clone, Copy, Debug, Default)]
pub struct ProtocolWire;

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
pub fn icon_view(icon: &Icon) -> Option<IconView> {
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
        })
    }

    fn encode(&self, cmd: &Command, ordered: bool) -> Vec<String> {
        // A drag without a request number takes the server's coalesced drag path,
        // which may overtake commands; one that precedes a release or a state change
        // carries a number so that the server applies it in order.
        if let (Command::Drag { icon, target }, true) = (cmd, ordered) {
            let req = NEXT_REQ.fetch_add(1, Ordering::Relaxed);
            return vec![envelope(
                Some(req),
                ClientMessage::Drag {
                    icon: *icon,
                    xyz: target.to_array(),
                },
            )];
        }
        let msgs = match cmd {
            Command::Grab { icon, sensor } => vec![
                ClientMessage::BindSensor {
                    icon: *icon,
                    sensor: sensor.clone(),
                },
                ClientMessage::DragStart { icon: *icon },
            ],
            Command::Release { icon, sensor } => vec![
                ClientMessage::UnbindSensor {
                    icon: *icon,
                    sensor: sensor.clone(),
                },
                ClientMessage::DragEnd { icon: *icon },
            ],
            Command::Drag { icon, target } => vec![ClientMessage::Drag {
                icon: *icon,
                xyz: target.to_array(),
            }],
            Command::SetState { icon, state } => vec![ClientMessage::SetState {
                icon: *icon,
                state: state_to_wire(*state),
            }],
            Command::SetRole { icon, role } => vec![ClientMessage::SetRole {
                icon: *icon,
                role: match role {
                    IconRole::Load => Role::Load,
                    IconRole::Constraint => Role::Position,
                },
            }],
            Command::SetKind { icon, kind } => vec![ClientMessage::SetRole {
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
        msgs.into_iter().map(text).collect()
    }

    fn decode(&self, text: &str) -> Result<Vec<ServerEvent>, String> {
        let msg: ServerMessage = serde_json::from_str(text).map_err(|e| e.to_string())?;
        Ok(match msg {
            ServerMessage::Welcome { .. } => vec![ServerEvent::Welcome],
            ServerMessage::Snapshot { surface, icons, .. } => vec![ServerEvent::Icons {
                icons: icons.iter().filter_map(icon_view).collect(),
                area: control_net_area(&surface),
            }],
            ServerMessage::IconCreated { icon } | ServerMessage::IconUpdated { icon } => {
                icon_view(&icon)
                    .map(ServerEvent::Icon)
                    .into_iter()
                    .collect()
            }
            ServerMessage::IconDeleted { icon } => vec![ServerEvent::IconRemoved(icon)],
            ServerMessage::IconFeedback { icon, actual, .. } => {
                let actual = DVec3::from_array(actual);
                if actual.is_finite() {
                    vec![ServerEvent::Feedback { icon, actual }]
                } else {
                    Vec::new()
                }
            }
            ServerMessage::Error { code, message, .. } => match code {
                ErrorCode::BadToken => vec![ServerEvent::Rejected(Rejection::Token, message)],
                ErrorCode::UnknownDesign => vec![ServerEvent::Rejected(Rejection::Design, message)],
                ErrorCode::BadVersion => vec![ServerEvent::Rejected(Rejection::Version, message)],
                _ => vec![ServerEvent::Error(format!("{code:?}: {message}"))],
            },
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

    #[test]
    fn every_command_is_a_valid_client_message() {
        let w = ProtocolWire;
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
            .map(|t| parse_client(&t).unwrap().msg)
            .collect();
        assert_eq!(
            parsed[0],
            ClientMessage::BindSensor {
                icon: 1,
                sensor: "right".into()
            }
        );
        assert_eq!(parsed[1], ClientMessage::DragStart { icon: 1 });
        assert_eq!(
            parsed[2],
            ClientMessage::UnbindSensor {
                icon: 1,
                sensor: "right".into()
            }
        );
        assert_eq!(parsed[3], ClientMessage::DragEnd { icon: 1 });
        assert_eq!(
            parsed[4],
            ClientMessage::Drag {
                icon: 1,
                xyz: [0.1, 0.2, 0.3]
            }
        );
        assert_eq!(
            parsed[7],
            ClientMessage::SetRole {
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
        let w = ProtocolWire;
        let icon = r#"{"id": 3, "anchor": {"kind": "point", "u": 0.5, "v": 0.5}, "role": {"kind": "load"}, "state": "passive", "xyz": [1.0, 2.0, 3.0], "target": [1.0, 2.0, 3.0], "sensors": []}"#;
        let ev = w
            .decode(&format!(r#"{{"type": "icon_updated", "icon": {icon}}}"#))
            .unwrap();
        assert_eq!(
            ev,
            vec![ServerEvent::Icon(IconView {
                id: 3,
                position: DVec3::new(1.0, 2.0, 3.0),
                target: DVec3::new(1.0, 2.0, 3.0),
                role: IconRole::Load,
                kind: IconKind::Position,
                state: IconState::Passive
            })]
        );
        let ev = w
            .decode(r#"{"type": "icon_feedback", "icon": 3, "requested": [0.5, 0.5, 0.4], "actual": [0.5, 0.5, 0.31], "revision": 13}"#)
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
