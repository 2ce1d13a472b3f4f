//! Undoable edits of a design and how each changes the document: edits of
//! one part's icons and material ([`PartEdit`], named by part), and edits of
//! the product — creating, deleting and changing parts, relating them.
//! Every edit is validated against the document first (unknown ids, NaN/∞,
//! (u, v) outside the domain, a locked part); the kernel model then rebuilds
//! what the edit touched, so a refused edit changes nothing.

use super::doc::{
    AnchorDoc, DesignDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, finite_point,
};
use super::part::{
    CurveMaterialDoc, MAX_PARTS, MAX_RELATIONS, PALETTE, PartBody, PartDoc, RelationDoc,
    RelationKind, is_colour,
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

/// One undoable change of a design.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// A change of one part's icons or material.
    Part {
        /// The part.
        part: u64,
        /// The change.
        edit: PartEdit,
    },
    /// A new part (its body's icons are ignored: a part starts bare).
    CreatePart {
        /// Its name (unique).
        name: String,
        /// Its shape and material (boxed: a part is large, most edits small).
        body: Box<PartBody>,
        /// Its colour; the next of [`PALETTE`] when `None`.
        colour: Option<String>,
    },
    /// Deletes a part with its icons and relations.
    DeletePart {
        /// The part.
        part: u64,
    },
    /// Renames, shows/hides, locks/unlocks or recolours a part.
    SetPart {
        /// The part.
        part: u64,
        /// New name.
        name: Option<String>,
        /// Drawn or hidden.
        visible: Option<bool>,
        /// Locked or not.
        locked: Option<bool>,
        /// New colour.
        colour: Option<String>,
    },
    /// Ties parts together. A join's `ratio` is filled in by the model
    /// (measured by the kernel when the join is made).
    Relate(RelationKind),
    /// Removes a relation.
    Unrelate {
        /// The relation.
        relation: u64,
    },
    /// Changes a network part's curves or fairs one of its faces (the
    /// document checks the part; the model's network engine applies it).
    Network {
        /// The network part.
        part: u64,
        /// The change.
        edit: super::network_engine::NetworkEditDoc,
    },
    /// Reshapes a DSM part (`dsm_edit`; see `dsm_engine::apply_edit`).
    Dsm {
        /// The part.
        part: u64,
        /// The change.
        edit: vsculpt_protocol::DsmEdit,
    },
}

/// A part's material, by kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialEdit {
    /// A surface's six coefficients.
    Surface(MaterialDoc),
    /// A curve's two.
    Curve(CurveMaterialDoc),
}

/// What an edit created.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Created {
    /// A new icon.
    pub icon: Option<u64>,
    /// A new part.
    pub part: Option<u64>,
    /// A new relation.
    pub relation: Option<u64>,
}

/// One undoable change of a part's icons or material.
#[derive(Clone, Debug, PartialEq)]
pub enum PartEdit {
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
    SetMaterial(MaterialEdit),
    /// Move lattice points of a body part by a delta (refused if the body
    /// would fold).
    MoveLattice {
        /// Which points.
        select: super::body_part::LatticeSelect,
        /// By how much.
        delta: [f64; 3],
    },
}

impl PartEdit {
    /// The icon this edit acts on, if it acts on one.
    pub fn icon(&self) -> Option<u64> {
        match self {
            PartEdit::MoveIcon { id, .. }
            | PartEdit::SetAnchor { id, .. }
            | PartEdit::DeleteIcon { id }
            | PartEdit::SetRole { id, .. }
            | PartEdit::SetState { id, .. }
            | PartEdit::BindSensor { id, .. }
            | PartEdit::UnbindSensor { id, .. } => Some(*id),
            PartEdit::AddIcon { .. } | PartEdit::SetMaterial(_) | PartEdit::MoveLattice { .. } => {
                None
            }
        }
    }
}

fn unknown(id: u64) -> CommandError {
    CommandError::new(ErrorKind::UnknownIcon, format!("no icon {id}"))
}

fn icon_mut(icons: &mut [IconDoc], id: u64) -> Result<&mut IconDoc, CommandError> {
    icons
        .iter_mut()
        .find(|i| i.id == id)
        .ok_or_else(|| unknown(id))
}

fn unknown_part(part: u64) -> CommandError {
    CommandError::new(ErrorKind::UnknownPart, format!("no part {part}"))
}

fn locked(p: &PartDoc) -> CommandError {
    CommandError::new(
        ErrorKind::Locked,
        format!("part {} ({}) is locked: unlock it first", p.id, p.name),
    )
}

fn check_part_name(doc: &DesignDoc, name: &str, except: Option<u64>) -> Result<(), CommandError> {
    let name_ok =
        !name.trim().is_empty() && name.len() <= 200 && !name.chars().any(char::is_control);
    if !name_ok {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a part name has 1 to 200 bytes and no control characters",
        ));
    }
    if doc
        .parts
        .iter()
        .any(|p| p.name == name && Some(p.id) != except)
    {
        return Err(CommandError::new(
            ErrorKind::Conflict,
            format!("a part named {name:?} exists already"),
        ));
    }
    Ok(())
}

fn check_colour(c: &str) -> Result<(), CommandError> {
    if !is_colour(c) {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "colour must be #rrggbb",
        ));
    }
    Ok(())
}

/// `doc` with `edit` applied, and what it created. `query` answers where a
/// part's geometry is (for icon placement): it is asked only about the part
/// the edit names. Relations are checked for kinds and ids here; the kernel
/// checks geometric compatibility when the model rebuilds.
pub fn apply<'q>(
    doc: &DesignDoc,
    edit: &Edit,
    query: &dyn Fn(u64) -> Option<Box<dyn SurfaceQuery + 'q>>,
) -> Result<(DesignDoc, Created), CommandError> {
    let mut doc = doc.clone();
    let mut created = Created::default();
    match edit {
        Edit::Network { part, .. } => {
            let p = doc.part(*part).ok_or_else(|| unknown_part(*part))?;
            if p.locked {
                return Err(locked(p));
            }
            if !matches!(p.body, PartBody::Network(_)) {
                return Err(CommandError::new(
                    ErrorKind::Incompatible,
                    format!("part {part} is a {}, not a network", p.body.kind()),
                ));
            }
        }
        Edit::Part { part, .. }
            if matches!(doc.part(*part).map(|p| &p.body), Some(PartBody::Network(_))) =>
        {
            return Err(CommandError::new(
                ErrorKind::Incompatible,
                format!(
                    "part {part} is a network: it has no icons or material; edit its curves (network_edit)"
                ),
            ));
        }
        Edit::Part { part, edit } => {
            if let Some(icon) = edit.icon()
                && let Some((other, _)) = doc.icon(icon)
                && other.id != *part
            {
                return Err(CommandError::new(
                    ErrorKind::UnknownPart,
                    format!("icon {icon} is on part {}, not part {part}", other.id),
                ));
            }
            if let Some(p) = doc.part(*part)
                && let PartBody::Dsm(_) = p.body
            {
                return Err(CommandError::new(
                    ErrorKind::Unsupported,
                    format!(
                        "part {part} is a dsm part: it has no icons or material; reshape it with dsm_edit"
                    ),
                ));
            }
            if let Some(p) = doc.part_mut(*part)
                && let PartBody::Body(b) = &mut p.body
            {
                if p.locked {
                    return Err(locked(p));
                }
                let PartEdit::MoveLattice { select, delta } = edit else {
                    return Err(CommandError::new(
                        ErrorKind::Unsupported,
                        format!(
                            "part {part} is a body: it is shaped by its lattice (body_edit), not by icons or a material"
                        ),
                    ));
                };
                let before = b.lattice.clone();
                b.move_points(*select, *delta)?;
                super::ffd_binding::follow_body(&mut doc, *part, &before)?;
                return Ok((doc, created));
            }
            let q = query(*part).ok_or_else(|| unknown_part(*part))?;
            let total_icons = doc.icons().count();
            let mut next_icon = doc.next_icon;
            let p = doc.part_mut(*part).ok_or_else(|| unknown_part(*part))?;
            if p.locked {
                return Err(locked(p));
            }
            created.icon = apply_part(&mut p.body, edit, &*q, &mut next_icon, total_icons)?;
            doc.next_icon = next_icon;
        }
        Edit::CreatePart { name, body, colour } => {
            if doc.parts.len() >= MAX_PARTS {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("a design holds at most {MAX_PARTS} parts"),
                ));
            }
            check_part_name(&doc, name, None)?;
            let colour = match colour {
                Some(c) => {
                    check_colour(c)?;
                    c.clone()
                }
                None => PALETTE[doc.parts.len() % PALETTE.len()].to_string(),
            };
            let mut body = (**body).clone();
            body.icons_mut().clear();
            body.validate()?;
            let id = doc.next_part;
            doc.next_part += 1;
            doc.parts.push(PartDoc {
                id,
                name: name.trim().to_string(),
                visible: true,
                locked: false,
                colour,
                body,
            });
            created.part = Some(id);
        }
        Edit::DeletePart { part } => {
            let p = doc.part(*part).ok_or_else(|| unknown_part(*part))?;
            if p.locked {
                return Err(locked(p));
            }
            doc.parts.retain(|p| p.id != *part);
            doc.relations.retain(|r| !r.kind.parts().contains(part));
        }
        Edit::SetPart {
            part,
            name,
            visible,
            locked,
            colour,
        } => {
            if let Some(n) = name {
                check_part_name(&doc, n.trim(), Some(*part))?;
            }
            if let Some(c) = colour {
                check_colour(c)?;
            }
            let p = doc.part_mut(*part).ok_or_else(|| unknown_part(*part))?;
            if let Some(n) = name {
                p.name = n.trim().to_string();
            }
            if let Some(v) = visible {
                p.visible = *v;
            }
            if let Some(l) = locked {
                p.locked = *l;
            }
            if let Some(c) = colour {
                p.colour = c.clone();
            }
        }
        Edit::Relate(kind) => {
            if doc.relations.len() >= MAX_RELATIONS {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("a design holds at most {MAX_RELATIONS} relations"),
                ));
            }
            let incompatible = |m: &str| CommandError::new(ErrorKind::Incompatible, m.to_string());
            let kind_of = |id: u64| doc.part(id).map(|p| (p.body.kind(), p.locked));
            match kind {
                RelationKind::Join { a, b, .. } => {
                    for id in [a, b] {
                        match kind_of(*id) {
                            None => return Err(unknown_part(*id)),
                            Some((_, true)) => {
                                return Err(locked(doc.part(*id).unwrap_or(&doc.parts[0])));
                            }
                            Some(("surface", _)) => {}
                            Some(_) => {
                                return Err(incompatible(
                                    "only surface parts are joined along edges",
                                ));
                            }
                        }
                    }
                }
                RelationKind::Binding { curve, surface, .. } => {
                    match kind_of(*curve) {
                        None => return Err(unknown_part(*curve)),
                        Some(("curve", _)) => {}
                        Some(_) => {
                            return Err(incompatible("a binding's `curve` must be a curve part"));
                        }
                    }
                    match kind_of(*surface) {
                        None => return Err(unknown_part(*surface)),
                        Some((_, true)) => {
                            return Err(locked(doc.part(*surface).unwrap_or(&doc.parts[0])));
                        }
                        Some(("surface", _)) => {}
                        Some(_) => {
                            return Err(incompatible(
                                "a binding's `surface` must be a surface part",
                            ));
                        }
                    }
                }
                RelationKind::Ffd { body, part, .. } => {
                    super::ffd_binding::check_bind(&doc, *body, *part)?;
                }
            }
            let id = doc.next_relation;
            doc.next_relation += 1;
            doc.relations.push(RelationDoc {
                id,
                kind: kind.clone(),
            });
            created.relation = Some(id);
        }
        Edit::Dsm { part, edit } => {
            let p = doc.part_mut(*part).ok_or_else(|| unknown_part(*part))?;
            if p.locked {
                return Err(locked(p));
            }
            let kind = p.body.kind();
            let PartBody::Dsm(d) = &mut p.body else {
                return Err(CommandError::new(
                    ErrorKind::Incompatible,
                    format!("part {part} is a {kind} part: dsm_edit needs a dsm part"),
                ));
            };
            d.dsm = super::dsm_engine::apply_edit(&d.dsm, edit)?;
        }
        Edit::Unrelate { relation } => {
            let before = doc.relations.len();
            doc.relations.retain(|r| r.id != *relation);
            if doc.relations.len() == before {
                return Err(CommandError::new(
                    ErrorKind::UnknownRelation,
                    format!("no relation {relation}"),
                ));
            }
        }
    }
    Ok((doc, created))
}

/// `body` with `edit` applied; returns the created icon's id.
fn apply_part(
    body: &mut PartBody,
    edit: &PartEdit,
    surface: &dyn SurfaceQuery,
    next_icon: &mut u64,
    total_icons: usize,
) -> Result<Option<u64>, CommandError> {
    let mut created = None;
    let check_anchor = |body: &PartBody, anchor: &AnchorDoc| match body {
        PartBody::Surface(s) => anchor.validate(&s.surface),
        PartBody::Curve(c) => anchor.validate_on_curve(&c.curve),
        PartBody::Network(_) => Err(CommandError::new(
            ErrorKind::Incompatible,
            "a network part has no icons",
        )),
        PartBody::Dsm(_) => Err(CommandError::new(
            ErrorKind::Unsupported,
            "a dsm part has no icons",
        )),
        PartBody::Body(_) => Err(CommandError::new(
            ErrorKind::Unsupported,
            "a body part has no icons",
        )),
    };
    let check_kind_role = |body: &PartBody, role: IconRoleDoc| match body {
        PartBody::Curve(_) => super::curve_engine::curve_role(role).map(|_| ()),
        PartBody::Surface(_) | PartBody::Network(_) | PartBody::Dsm(_) => Ok(()),
        PartBody::Body(_) => Err(CommandError::new(
            ErrorKind::Unsupported,
            "a body part has no icons",
        )),
    };
    match edit {
        PartEdit::MoveLattice { .. } => {
            return Err(CommandError::new(
                ErrorKind::Unsupported,
                "only a body part has a lattice to move",
            ));
        }
        PartEdit::AddIcon {
            anchor,
            role,
            state,
            target,
        } => {
            if total_icons >= MAX_ICONS {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("a design holds at most {MAX_ICONS} icons"),
                ));
            }
            check_anchor(body, anchor)?;
            check_kind_role(body, *role)?;
            let target = match target {
                Some(p) => finite_point(*p)?.to_array(),
                None => surface.current_target(anchor, *role),
            };
            check_role(*role, target)?;
            let id = *next_icon;
            *next_icon += 1;
            body.icons_mut().push(IconDoc {
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
        PartEdit::MoveIcon { id, xyz } => {
            let p = finite_point(*xyz)?.to_array();
            let icon = icon_mut(body.icons_mut(), *id)?;
            check_role(icon.role, p)?;
            icon.target = p;
        }
        PartEdit::SetAnchor { id, anchor } => {
            check_anchor(body, anchor)?;
            let xyz = surface.point_at(anchor);
            let icon = icon_mut(body.icons_mut(), *id)?;
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
        PartEdit::DeleteIcon { id } => {
            let icons = body.icons_mut();
            let before = icons.len();
            icons.retain(|i| i.id != *id);
            if icons.len() == before {
                return Err(unknown(*id));
            }
        }
        PartEdit::SetRole { id, role } => {
            check_kind_role(body, *role)?;
            let icon = icon_mut(body.icons_mut(), *id)?;
            if icon.role != *role {
                icon.target = surface.current_target(&icon.anchor, *role);
                icon.role = *role;
            }
        }
        PartEdit::SetState { id, state } => {
            let icon = icon_mut(body.icons_mut(), *id)?;
            let was = icon.kernel_state();
            let now = IconDoc {
                state: *state,
                ..icon.clone()
            }
            .kernel_state();
            if was != now
                && (was == IconStateDoc::Sleeping
                    || now == IconStateDoc::Sleeping
                    || icon.role == IconRoleDoc::Load)
            {
                // Waking up or going to sleep holds the surface as it is
                // now (a woken constraint whose old target the shape has
                // left would pull it back); a load changing state is
                // re-attached where the surface is (paper 003's states:
                // only a driving icon moves the shape).
                icon.target = surface.current_target(&icon.anchor, icon.role);
            }
            icon.state = *state;
        }
        PartEdit::BindSensor { id, sensor } => {
            if sensor.is_empty() || sensor.len() > 64 {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    "a sensor name has 1 to 64 characters",
                ));
            }
            let icon = icon_mut(body.icons_mut(), *id)?;
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
        PartEdit::UnbindSensor { id, sensor } => {
            let icon = icon_mut(body.icons_mut(), *id)?;
            let before = icon.sensors.len();
            icon.sensors.retain(|s| s != sensor);
            if icon.sensors.len() == before {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    format!("sensor {sensor} is not bound to icon {id}"),
                ));
            }
        }
        PartEdit::SetMaterial(m) => match (body, m) {
            (PartBody::Surface(s), MaterialEdit::Surface(m)) => {
                m.validate()?;
                s.material = *m;
            }
            (PartBody::Curve(c), MaterialEdit::Curve(m)) => {
                m.validate()?;
                c.material = *m;
            }
            _ => {
                return Err(CommandError::new(
                    ErrorKind::InvalidValue,
                    "the material does not fit the part's kind (six coefficients for a surface, alpha and beta for a curve)",
                ));
            }
        },
    }
    Ok(created)
}

fn check_role(role: IconRoleDoc, target: [f64; 3]) -> Result<(), CommandError> {
    if role == IconRoleDoc::Normal && target.iter().map(|x| x * x).sum::<f64>() < 1e-24 {
        return Err(CommandError::new(
            ErrorKind::InvalidValue,
            "a normal constraint needs a non-zero direction",
        ));
    }
    Ok(())
}
