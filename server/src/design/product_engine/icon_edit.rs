//! An icon or material edit of a surface part applied to the live kernel
//! design (issue 15), instead of rebuilding the part from its document.
//!
//! A rebuild builds a new `Design` (a fresh factorisation of the thin-plate
//! stiffness, every icon placed and captured again, every column of the
//! constrained solve computed afresh): 60 ms and more on the paper's
//! 81 × 159 surface whatever the edit. Applied in place, an edit reaches
//! the kernel's incremental paths: a new or removed constraint updates the
//! Schur complement by its own rows, a pinned-set change updates the
//! factor without a numeric refactor (settled later, when the design is
//! idle: [`ProductEngine::settle_idle`]), an icon that holds the shape
//! where it is solves nothing.
//!
//! The kernel state an edit leaves is the one a rebuild from the edited
//! document gives (the same icons, roles, targets, states and sensors; a
//! state read from the document as [`kernel_state`] maps it; the shape as
//! it is becomes the reference shape, as a design built from its control
//! points has them), so the
//! document stays the truth for undo, reload and restart. What cannot be
//! applied in place (a curve part, an edit during a drag, a kernel refusal)
//! returns `None` and the caller rebuilds as before, which also gives the
//! rebuild's own error.

use super::super::doc::IconDoc;
use super::super::edit::{MaterialEdit, PartEdit};
use super::super::engine::{anchor, material, role, state};
use super::super::error::CommandError;
use super::super::part::PartBody;
use super::{ProductEngine, ids_of};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::icon::{IconId, IconSpec, IconState, SensorId};
use vsculpt_kernel::product::{Part, PartId};

/// The state a rebuild gives the kernel icon of `doc`
/// ([`IconDoc::kernel_state`]).
pub(crate) fn kernel_state(doc: &IconDoc) -> IconState {
    state(doc.kernel_state())
}

/// One kernel call, with what it needs resolved from the documents first
/// (so the closure run inside the product's edit cannot fail on a
/// document lookup).
enum Step {
    Add(IconSpec),
    Remove(IconId),
    Target(IconId, glam::DVec3),
    Anchor(IconId, vsculpt_kernel::icon::Anchor),
    Role(IconId, vsculpt_kernel::icon::Role),
    State(IconId, IconState),
    Bind(IconId, SensorId),
    Unbind(IconId, SensorId),
    Material(vsculpt_kernel::energy::SurfaceMaterial),
    /// Nothing changes in the kernel (the document's change is one a
    /// rebuild ignores too, e.g. a load's target); the part is solved.
    Nothing,
}

fn icon_of(body: &PartBody, id: u64) -> Option<&IconDoc> {
    body.icons().iter().find(|i| i.id == id)
}

impl ProductEngine {
    /// Applies `edit` of surface part `id` in place: `before` and `after`
    /// are the part's body before and after the document edit, `created`
    /// the new icon's document id. Returns the parts that moved, or `None`
    /// when the edit must be applied by a rebuild (nothing has changed
    /// then).
    pub fn edit_in_place(
        &mut self,
        id: u64,
        edit: &PartEdit,
        before: &PartBody,
        after: &PartBody,
        created: Option<u64>,
    ) -> Option<Vec<u64>> {
        let (PartBody::Surface(_), PartBody::Surface(_)) = (before, after) else {
            return None;
        };
        let Some(Part::Surface(design)) = self.product.part(PartId(id)) else {
            return None;
        };
        if design.dragging().is_some() {
            return None;
        }
        let step = self.step(id, design, edit, before, after, created).ok()??;
        let added = matches!(step, Step::Add(_));
        let removed = match step {
            Step::Remove(kid) => Some(kid),
            _ => None,
        };
        let edited = self
            .product
            .edit_surface(PartId(id), |d| -> Result<Option<IconId>, _> {
                // A rebuild's reference shape is the shape as it is (a
                // constraint dragged and released leaves it bent elastically
                // from the old one): the same here, so removing that
                // constraint moves nothing, as after a reload.
                d.keep_shape();
                Ok(match step {
                    Step::Add(spec) => Some(d.add_icon(spec)?),
                    Step::Remove(kid) => {
                        d.remove_icon(kid)?;
                        None
                    }
                    Step::Target(kid, t) => {
                        d.set_target(kid, t)?;
                        None
                    }
                    Step::Anchor(kid, a) => {
                        d.set_anchor(kid, a)?;
                        None
                    }
                    Step::Role(kid, r) => {
                        d.set_role(kid, r)?;
                        None
                    }
                    Step::State(kid, s) => {
                        d.set_state(kid, s)?;
                        None
                    }
                    Step::Bind(kid, s) => {
                        d.bind_sensor(kid, s)?;
                        None
                    }
                    Step::Unbind(kid, s) => {
                        d.unbind_sensor(kid, &s)?;
                        None
                    }
                    Step::Material(m) => {
                        d.set_material(m)?;
                        None
                    }
                    Step::Nothing => None,
                })
            });
        let edited = edited.ok()?;
        let map = self.ids.entry(id).or_default();
        if added && let (Some(doc_id), Some(kid)) = (created, edited.value) {
            map.insert(doc_id, kid);
        }
        if let Some(kid) = removed {
            map.retain(|_, k| *k != kid);
        }
        self.grabbed.remove(&id);
        let mut moved = ids_of(&edited.changed);
        moved.push(id);
        moved.sort_unstable();
        moved.dedup();
        Some(moved)
    }

    /// The kernel call `edit` makes on `design`; `Ok(None)` when it has
    /// none that gives what a rebuild gives.
    fn step(
        &self,
        id: u64,
        design: &Design,
        edit: &PartEdit,
        before: &PartBody,
        after: &PartBody,
        created: Option<u64>,
    ) -> Result<Option<Step>, CommandError> {
        let kid = |icon: u64| self.kid(id, icon);
        Ok(Some(match edit {
            PartEdit::AddIcon { .. } => {
                let Some(doc) = created.and_then(|c| icon_of(after, c)) else {
                    return Ok(None);
                };
                Step::Add(IconSpec {
                    anchor: anchor(&doc.anchor)?,
                    role: role(doc.role),
                    state: kernel_state(doc),
                    target: Some(glam::DVec3::from(doc.target)),
                })
            }
            PartEdit::DeleteIcon { id: icon } => Step::Remove(kid(*icon)?),
            PartEdit::MoveIcon { id: icon, .. } => {
                let k = kid(*icon)?;
                let (Some(doc), Some(live)) = (icon_of(after, *icon), design.icon(k)) else {
                    return Ok(None);
                };
                if live.role == vsculpt_kernel::icon::Role::Load {
                    // A rebuild re-attaches a load where the surface is.
                    Step::Nothing
                } else {
                    Step::Target(k, glam::DVec3::from(doc.target))
                }
            }
            PartEdit::SetAnchor { id: icon, .. } => {
                let k = kid(*icon)?;
                let (Some(old), Some(new)) = (icon_of(before, *icon), icon_of(after, *icon)) else {
                    return Ok(None);
                };
                if old.anchor == new.anchor {
                    Step::Nothing
                } else {
                    Step::Anchor(k, anchor(&new.anchor)?)
                }
            }
            PartEdit::SetRole { id: icon, role: r } => {
                let k = kid(*icon)?;
                match icon_of(before, *icon) {
                    Some(old) if old.role == *r => Step::Nothing,
                    Some(_) => Step::Role(k, role(*r)),
                    None => return Ok(None),
                }
            }
            PartEdit::SetState { id: icon, .. } => {
                let k = kid(*icon)?;
                let Some(doc) = icon_of(after, *icon) else {
                    return Ok(None);
                };
                Step::State(k, kernel_state(doc))
            }
            PartEdit::BindSensor { id: icon, sensor } => {
                Step::Bind(kid(*icon)?, SensorId(sensor.clone()))
            }
            PartEdit::UnbindSensor { id: icon, sensor } => {
                Step::Unbind(kid(*icon)?, SensorId(sensor.clone()))
            }
            PartEdit::SetMaterial(MaterialEdit::Surface(m)) => Step::Material(material(m)),
            PartEdit::SetMaterial(MaterialEdit::Curve(_)) | PartEdit::MoveLattice { .. } => {
                return Ok(None);
            }
        }))
    }
}
