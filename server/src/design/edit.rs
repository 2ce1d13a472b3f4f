//! Undoable edits of a design and how each changes the document. Every edit
//! is validated against the document first (unknown ids, NaN/∞, (u, v)
//! outside the domain); the kernel model then rebuilds from the edited
//! document, so a refused edit changes nothing.

use super::doc::{
    AnchorDoc, DesignDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, finite_point,
};

/// What an edit needs to know of the current surface.
pub trait SurfaceQuery {
    /// The surface point at an anchor's centre.
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3];
    /// The value a new constraint of `role` at `anchor` starts with (the
    /// surface's current point, derivative or normal there).
    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3];
}
use super::error::{CommandError, ErrorKind};

/// Most icons one design may hold.
pub const MAX_ICONS: usize = 512;
/// Most sensors bound to one icon.
pub const MAX_SENSORS: usize = 16;

/// One undoable change.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Create an icon; `target` defaults to the surface's current value.
    AddIcon {
        /// Where.
        anchor: AnchorDoc,
        /// What it does.
        role: IconRoleDoc,
        /// Its state.
        state: IconStateDoc,
        /// Position, derivative vector or normal direction.
        target: Option<[f64; 3]>,
    },
    /// Set an icon's target and solve.
    MoveIcon {
        /// Icon.
        id: u64,
        /// New target.
        xyz: [f64; 3],
    },
    /// Move an icon on the surface (new (u, v)).
    SetAnchor {
        /// Icon.
        id: u64,
        /// New anchor.
        anchor: AnchorDoc,
    },
    /// Delete an icon.
    DeleteIcon {
        /// Icon.
        id: u64,
    },
    /// Switch what an icon does (constraint ↔ load, position ↔ tangent ↔ normal).
    SetRole {
        /// Icon.
        id: u64,
        /// New role.
        role: IconRoleDoc,
    },
    /// Switch an icon's state.
    SetState {
        /// Icon.
        id: u64,
        /// New state.
        state: IconStateDoc,
    },
    /// Bind a sensor to an icon.
    BindSensor {
        /// Icon.
        id: u64,
        /// Sensor name.
        sensor: String,
    },
    /// Unbind a sensor.
    UnbindSensor {
        /// Icon.
        id: u64,
        /// Sensor name.
        sensor: String,
    },
    /// Change the material.
    SetMaterial(MaterialDoc),
}

fn unknown(id: u64) -> CommandError {
    CommandError::new(ErrorKind::UnknownIcon, format!("no icon {id}"))
}

fn icon_mut(doc: &mut DesignDoc, id: u64) -> Result<&mut IconDoc, CommandError> {
    doc.icons
        .iter_mut()
        .find(|i| i.id == id)
        .ok_or_else(|| unknown(id))
}

/// Applies `edit` to a copy of `doc`, asking `surface` for positions and
/// default targets. Returns the new document and the id of a created icon.
pub fn apply(
    doc: &DesignDoc,
    edit: &Edit,
    surface: &dyn SurfaceQuery,
) -> Result<(DesignDoc, Option<u64>), CommandError> {
    let mut doc = doc.clone();
    let mut created = None;
    match edit {
        Edit::AddIcon {
            anchor,
            role,
            state,
            target,
        } => {
            if doc.icons.len() >= MAX_ICONS {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("a design holds at most {MAX_ICONS} icons"),
                ));
            }
            anchor.validate(&doc.surface)?;
            let target = match target {
                Some(p) => finite_point(*p)?.to_array(),
                None => surface.current_target(anchor, *role),
            };
            check_role(*role, target)?;
            let id = doc.next_icon;
            doc.next_icon += 1;
            doc.icons.push(IconDoc {
                id,
                anchor: anchor.clone(),
                role: *role,
                state: *state,
                xyz: surface.point_at(anchor),
                target,
                sensors: Vec::new(),
            });
            created = Some(id);
        }
        Edit::MoveIcon { id, xyz } => {
            let p = finite_point(*xyz)?.to_array();
            let icon = icon_mut(&mut doc, *id)?;
            check_role(icon.role, p)?;
            icon.target = p;
        }
        Edit::SetAnchor { id, anchor } => {
            anchor.validate(&doc.surface)?;
            let xyz = surface.point_at(anchor);
            let icon = icon_mut(&mut doc, *id)?;
            let moved = icon.anchor != *anchor;
            icon.anchor = anchor.clone();
            icon.xyz = xyz;
            if moved && icon.role != IconRoleDoc::Position && icon.role != IconRoleDoc::Load {
                // A tangent or normal constraint moved along the surface keeps
                // the surface's current value there until its target is set.
                icon.target = surface.current_target(anchor, icon.role);
            } else if moved {
                icon.target = xyz;
            }
        }
        Edit::DeleteIcon { id } => {
            let before = doc.icons.len();
            doc.icons.retain(|i| i.id != *id);
            if doc.icons.len() == before {
                return Err(unknown(*id));
            }
        }
        Edit::SetRole { id, role } => {
            let icon = icon_mut(&mut doc, *id)?;
            if icon.role != *role {
                icon.target = surface.current_target(&icon.anchor, *role);
                icon.role = *role;
            }
        }
        Edit::SetState { id, state } => {
            icon_mut(&mut doc, *id)?.state = *state;
        }
        Edit::BindSensor { id, sensor } => {
            if sensor.is_empty() || sensor.len() > 64 {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    "a sensor name has 1 to 64 characters",
                ));
            }
            let icon = icon_mut(&mut doc, *id)?;
            if !icon.sensors.contains(sensor) {
                if icon.sensors.len() >= MAX_SENSORS {
                    return Err(CommandError::new(
                        ErrorKind::InvalidValue,
                        "too many sensors on one icon",
                    ));
                }
                icon.sensors.push(sensor.clone());
            }
        }
        Edit::UnbindSensor { id, sensor } => {
            let icon = icon_mut(&mut doc, *id)?;
            let before = icon.sensors.len();
            icon.sensors.retain(|s| s != sensor);
            if icon.sensors.len() == before {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("sensor {sensor} is not bound to icon {id}"),
                ));
            }
        }
        Edit::SetMaterial(m) => {
            m.validate()?;
            doc.material = *m;
        }
    }
    Ok((doc, created))
}

/// A normal constraint needs a non-zero direction.
fn check_role(role: IconRoleDoc, target: [f64; 3]) -> Result<(), CommandError> {
    if role == IconRoleDoc::Normal && target.iter().map(|x| x * x).sum::<f64>() < 1e-24 {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a normal constraint needs a non-zero direction",
        ));
    }
    Ok(())
}
