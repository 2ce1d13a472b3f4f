//! Undoable edits of a design and how each changes the document. Every edit
//! is validated against the document first (unknown ids, NaN/∞, (u, v)
//! outside the domain); the kernel model then rebuilds from the edited
//! document, so a refused edit changes nothing.

use super::doc::{
    AnchorDoc, DesignDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, finite_point,
};
use super::error::{CommandError, ErrorKind};

/// Most icons one design may hold.
pub const MAX_ICONS: usize = 512;
/// Most sensors bound to one icon.
pub const MAX_SENSORS: usize = 16;

/// One undoable change.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Create an icon; `xyz` defaults to the surface point at the anchor.
    AddIcon {
        /// Where.
        anchor: AnchorDoc,
        /// What it does.
        role: IconRoleDoc,
        /// Its state.
        state: IconStateDoc,
        /// Handle / target point.
        xyz: Option<[f64; 3]>,
        /// T or N for derivative / normal constraints.
        vector: Option<[f64; 3]>,
    },
    /// Move an icon's handle (a constraint's target) and solve.
    MoveIcon {
        /// Icon.
        id: u64,
        /// New handle point.
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
        /// T or N when the new role needs one.
        vector: Option<[f64; 3]>,
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
    doc.icons.iter_mut().find(|i| i.id == id).ok_or_else(|| unknown(id))
}

fn check_vector(v: Option<[f64; 3]>) -> Result<(), CommandError> {
    if let Some(v) = v {
        finite_point(v)?;
    }
    Ok(())
}

/// Applies `edit` to a copy of `doc`. `surface_point` gives the surface
/// point at (u, v) for icons created without `xyz`. Returns the new document
/// and the id of a created icon.
pub fn apply(
    doc: &DesignDoc,
    edit: &Edit,
    surface_point: &dyn Fn(f64, f64) -> [f64; 3],
) -> Result<(DesignDoc, Option<u64>), CommandError> {
    let mut doc = doc.clone();
    let mut created = None;
    match edit {
        Edit::AddIcon {
            anchor,
            role,
            state,
            xyz,
            vector,
        } => {
            if doc.icons.len() >= MAX_ICONS {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("a design holds at most {MAX_ICONS} icons"),
                ));
            }
            anchor.validate(&doc.surface)?;
            check_vector(*vector)?;
            let [u, v] = anchor.params()[0];
            let xyz = match xyz {
                Some(p) => finite_point(*p)?.to_array(),
                None => surface_point(u, v),
            };
            let id = doc.next_icon;
            doc.next_icon += 1;
            doc.icons.push(IconDoc {
                id,
                anchor: anchor.clone(),
                role: *role,
                state: *state,
                xyz,
                vector: *vector,
                sensors: Vec::new(),
            });
            created = Some(id);
        }
        Edit::MoveIcon { id, xyz } => {
            let p = finite_point(*xyz)?;
            icon_mut(&mut doc, *id)?.xyz = p.to_array();
        }
        Edit::SetAnchor { id, anchor } => {
            anchor.validate(&doc.surface)?;
            let [u, v] = anchor.params()[0];
            let p = surface_point(u, v);
            let icon = icon_mut(&mut doc, *id)?;
            icon.anchor = anchor.clone();
            icon.xyz = p;
        }
        Edit::DeleteIcon { id } => {
            let before = doc.icons.len();
            doc.icons.retain(|i| i.id != *id);
            if doc.icons.len() == before {
                return Err(unknown(*id));
            }
        }
        Edit::SetRole { id, role, vector } => {
            check_vector(*vector)?;
            let icon = icon_mut(&mut doc, *id)?;
            icon.role = *role;
            if vector.is_some() {
                icon.vector = *vector;
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
