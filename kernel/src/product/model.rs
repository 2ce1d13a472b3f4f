//! The product: its parts, the joins and bindings between them, and the
//! groups they form for solving.
//!
//! A part with no join and no binding is solved by its own design, exactly
//! as alone: [`Product::drag`] on it is one map lookup and the part's own
//! [`Design::drag`] (or [`CurveDesign::drag`]). Surface parts connected by
//! joins, or holding a bound curve, form a group solved jointly (see
//! `group.rs`); a drag on any member moves the whole group. A curve part
//! drives the surfaces bound to it: after the curve's own solve each of
//! their groups is re-solved with the curve's new control points as
//! targets (a full solve per frame, not the drag fast path).
//!
//! Every edit solves what it touched and returns the [`ChangedParts`]: the
//! only parts whose control points or icons changed. A refused edit (bad
//! input, incompatible edges, a failed solve) changes nothing.
//!
//! To rebuild a stored product: [`Product::insert_part`] each part (ids
//! kept), [`Product::insert_join`] and [`Product::insert_binding`] each
//! relation as stored (nothing is solved or baked), then
//! [`Product::solve_all`]. To undo across parts: [`Product::restore_part`]
//! each part of the version (a [`super::PartSnapshot`]), then
//! [`Product::solve_all`].

use std::collections::BTreeMap;

use glam::DVec3;

use super::group::SolveGroup;
use super::{
    Binding, BindingId, BindingSpec, ChangedParts, Join, JoinId, JoinSpec, Part, PartId, PartKind,
    PartSnapshot, ProductError,
};
use crate::curve_design::CurveDesign;
use crate::design::{Design, DesignError};
use crate::icon::IconId;
use crate::solve::{SolveReport, SolveWarning};

/// The result of a drag frame on a part.
#[derive(Clone, Debug, PartialEq)]
pub struct PartDrag {
    /// Where the pointer asked the icon to go.
    pub requested: DVec3,
    /// Where the icon is on the solved part.
    pub actual: DVec3,
    /// The dragged part's solve (for a surface part; a curve part's design
    /// does not report one).
    pub report: Option<SolveReport>,
    /// The parts that moved: the part, its joint group, and for a curve the
    /// surfaces bound to it (with their groups).
    pub changed: ChangedParts,
}

/// The result of an edit.
#[derive(Clone, Debug, PartialEq)]
pub struct Edited<R> {
    /// What the edit returned.
    pub value: R,
    /// The parts that changed.
    pub changed: ChangedParts,
}

/// What [`Product::remove_part`] took out.
#[derive(Debug)]
pub struct RemovedPart {
    /// The part.
    pub part: Part,
    /// The joins it was in (removed with it).
    pub joins: Vec<(JoinId, Join)>,
    /// The bindings it was in (removed with it).
    pub bindings: Vec<(BindingId, Binding)>,
    /// The remaining parts that changed (its former group partners).
    pub changed: ChangedParts,
}

/// A product: any number of parts of any kind, joins between surface
/// parts, curves bound to surfaces.
#[derive(Debug, Default)]
pub struct Product {
    parts: BTreeMap<PartId, Part>,
    joins: BTreeMap<JoinId, Join>,
    bindings: BTreeMap<BindingId, Binding>,
    groups: Vec<SolveGroup>,
    /// The group of every grouped surface part.
    group_of: BTreeMap<PartId, usize>,
    next_part: u64,
    next_join: u64,
    next_binding: u64,
    /// The warning of the last [`Self::solve`] of a surface part.
    last_warning: Option<SolveWarning>,
}

impl Product {
    /// An empty product.
    pub fn new() -> Self {
        Self::default()
    }

    // ---- parts -----------------------------------------------------------

    /// Adds a part under a fresh id (one above every id used so far).
    pub fn add_part(&mut self, part: Part) -> PartId {
        let id = PartId(self.next_part);
        self.parts.insert(id, part);
        self.next_part += 1;
        id
    }

    /// Adds a part under a given id (rebuilding a stored product).
    pub fn insert_part(&mut self, id: PartId, part: Part) -> Result<(), ProductError> {
        if self.parts.contains_key(&id) {
            return Err(ProductError::DuplicatePart(id));
        }
        self.parts.insert(id, part);
        self.next_part = self.next_part.max(id.0.saturating_add(1));
        Ok(())
    }

    /// Removes a part with every join and binding it is in. Its former
    /// group partners keep their current shape (baked as their reference).
    pub fn remove_part(&mut self, id: PartId) -> Result<RemovedPart, ProductError> {
        if !self.parts.contains_key(&id) {
            return Err(ProductError::UnknownPart(id));
        }
        let joins: Vec<JoinId> = self
            .joins
            .iter()
            .filter(|(_, j)| j.spec.a == id || j.spec.b == id)
            .map(|(k, _)| *k)
            .collect();
        let bindings: Vec<BindingId> = self
            .bindings
            .iter()
            .filter(|(_, b)| b.spec.curve == id || b.spec.surface == id)
            .map(|(k, _)| *k)
            .collect();
        let mut touched: Vec<PartId> = Vec::new();
        for jid in &joins {
            touched.extend(self.keep_group_shape(self.joins[jid].spec.a));
        }
        for bid in &bindings {
            touched.extend(self.keep_group_shape(self.bindings[bid].spec.surface));
        }
        touched.extend(self.keep_group_shape(id));
        let joins: Vec<(JoinId, Join)> = joins
            .into_iter()
            .filter_map(|k| self.joins.remove(&k).map(|j| (k, j)))
            .collect();
        let bindings: Vec<(BindingId, Binding)> = bindings
            .into_iter()
            .filter_map(|k| self.bindings.remove(&k).map(|b| (k, b)))
            .collect();
        let Some(part) = self.parts.remove(&id) else {
            return Err(ProductError::UnknownPart(id));
        };
        self.group_of.remove(&id);
        self.regroup()?;
        Ok(RemovedPart {
            part,
            joins,
            bindings,
            changed: ChangedParts::from_ids(touched.into_iter().filter(|&p| p != id)),
        })
    }

    /// One part.
    pub fn part(&self, id: PartId) -> Option<&Part> {
        self.parts.get(&id)
    }

    /// Every part, by ascending id.
    pub fn parts(&self) -> impl Iterator<Item = (PartId, &Part)> {
        self.parts.iter().map(|(k, p)| (*k, p))
    }

    /// How many parts.
    pub fn len(&self) -> usize {
        self.parts.len()
    }

    /// Whether there are no parts.
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    /// A surface part's design.
    pub fn surface(&self, id: PartId) -> Option<&Design> {
        self.parts.get(&id).and_then(Part::as_surface)
    }

    /// Whether a surface part has a pin change whose refactor is deferred
    /// ([`Design::pins_pending`]).
    pub fn pins_pending(&self) -> bool {
        self.parts
            .values()
            .filter_map(Part::as_surface)
            .any(Design::pins_pending)
    }

    /// Settles the deferred refactor of every surface part that has one
    /// ([`Design::settle_pins`]): for a host to call when idle, so the next
    /// grab does not pay it. No shape changes. Returns the parts settled.
    pub fn settle_pins(&mut self) -> Result<Vec<PartId>, ProductError> {
        let mut settled = Vec::new();
        for (id, part) in &mut self.parts {
            if let Some(d) = part.as_surface_mut()
                && d.pins_pending()
                && d.settle_pins()?
            {
                settled.push(*id);
            }
        }
        Ok(settled)
    }

    /// Every surface part solved alone here takes the solver of the part
    /// with the same id in `old`, when `old` solves it alone too
    /// ([`Design::adopt_solver`]: same knots and material): a product
    /// built afresh from a stored state keeps the factorisations of the
    /// one it replaces. Returns the parts that took one.
    pub fn adopt_solvers(&mut self, old: &mut Product) -> Vec<PartId> {
        let mut taken = Vec::new();
        for (id, part) in &mut self.parts {
            if self.group_of.contains_key(id) || old.group_of.contains_key(id) {
                continue;
            }
            if let (Some(new), Some(was)) = (
                part.as_surface_mut(),
                old.parts.get_mut(id).and_then(Part::as_surface_mut),
            ) && new.adopt_solver(was)
            {
                taken.push(*id);
            }
        }
        taken
    }

    /// A curve part's design.
    pub fn curve(&self, id: PartId) -> Option<&CurveDesign> {
        self.parts.get(&id).and_then(Part::as_curve)
    }

    /// A part's current control points (after the last solve).
    pub fn control_points(&self, id: PartId) -> Option<&[DVec3]> {
        self.parts.get(&id).map(Part::control_points)
    }

    /// The parts solved together with `id` (itself included): its joint
    /// group, or just itself.
    pub fn solved_with(&self, id: PartId) -> ChangedParts {
        match self.group_of.get(&id) {
            Some(&g) => ChangedParts::shared(self.groups[g].ids.clone()),
            None => ChangedParts::one(id),
        }
    }

    /// Replaces a part's value by `snapshot` (undo, redo, restore of a
    /// version), as stored: nothing is solved — call [`Self::solve_all`]
    /// (or [`Self::solve`]) once every part of a version is back. The part
    /// keeps its relations, which must still fit the restored shape's knots
    /// (else [`ProductError::Incompatible`]); on error nothing changes.
    pub fn restore_part(
        &mut self,
        id: PartId,
        snapshot: &PartSnapshot,
    ) -> Result<(), ProductError> {
        let part = self
            .parts
            .get_mut(&id)
            .ok_or(ProductError::UnknownPart(id))?;
        if part.kind() != snapshot.kind() {
            return Err(ProductError::WrongKind {
                part: id,
                expected: snapshot.kind(),
            });
        }
        let before = part.snapshot();
        part.restore(snapshot)?;
        let fits = self.check_relations_of(id).and_then(|()| {
            if let Some(&g) = self.group_of.get(&id) {
                if self.groups[g].member(id).is_some_and(|m| {
                    self.groups[g].members[m].len != self.parts[&id].control_points().len()
                }) {
                    return Err(ProductError::Incompatible(format!(
                        "part {} would change its control-point count while joined",
                        id.0
                    )));
                }
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            }
            Ok(())
        });
        if let Err(e) = fits {
            if let Some(part) = self.parts.get_mut(&id) {
                part.restore(&before)?;
            }
            if let Some(&g) = self.group_of.get(&id) {
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            }
            return Err(e);
        }
        Ok(())
    }

    /// Every join and binding of `id` still fits the parts' knots.
    fn check_relations_of(&self, id: PartId) -> Result<(), ProductError> {
        for j in self.joins.values() {
            if j.spec.a == id || j.spec.b == id {
                self.check_join(j.spec)?;
            }
        }
        for b in self.bindings.values() {
            if b.spec.curve == id || b.spec.surface == id {
                self.check_binding(b.spec)?;
            }
        }
        Ok(())
    }

    // ---- edits -----------------------------------------------------------

    /// Edits a surface part (add, remove or change icons, material, …)
    /// and solves it with its group. On error (the edit's or the solve's)
    /// the product is as before (the part is restored from a snapshot taken
    /// first, so a closure that fails half-way leaves nothing behind). An
    /// edit that keeps the part's shape as its reference (a load released
    /// by unbinding its last sensor) keeps every group member's shape too,
    /// as [`Self::release`] does. Use [`Self::drag`], [`Self::release`] and
    /// [`Self::move_icon`] for pointer actions ([`Design::move_icon`] would
    /// solve the part without its group).
    pub fn edit_surface<R>(
        &mut self,
        id: PartId,
        f: impl FnOnce(&mut Design) -> Result<R, DesignError>,
    ) -> Result<Edited<R>, ProductError> {
        let d = self.surface_mut(id)?;
        let before = d.snapshot();
        let result = f(d);
        // A bake inside the edit: the partners keep their shapes as well.
        let mut partners = Vec::new();
        if result.is_ok()
            && let Some(&g) = self.group_of.get(&id)
            && self.surface_ref(id)?.reference() != &before.reference[..]
        {
            for &m in self.groups[g].ids.iter() {
                if m != id
                    && let Some(d) = self.parts.get(&m).and_then(Part::as_surface)
                {
                    partners.push((m, d.snapshot()));
                }
            }
            self.keep_group_shape(id);
        }
        let solved = match result {
            Ok(value) => self
                .solve_surface(id)
                .map(|changed| Edited { value, changed }),
            Err(e) => Err(e.into()),
        };
        if solved.is_err() {
            self.surface_mut(id)?.restore(&before)?;
            for (m, snapshot) in &partners {
                self.surface_mut(*m)?.restore(snapshot)?;
            }
            if let Some(&g) = self.group_of.get(&id) {
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            }
        }
        solved
    }

    /// Edits a curve part and solves it, then the surfaces bound to it. On
    /// error (the edit's or a solve's) the product is as before.
    pub fn edit_curve<R>(
        &mut self,
        id: PartId,
        f: impl FnOnce(&mut CurveDesign) -> Result<R, DesignError>,
    ) -> Result<Edited<R>, ProductError> {
        let c = self.curve_mut(id)?;
        let before = c.snapshot();
        let solved = match f(c) {
            Ok(value) => self
                .solve_curve(id)
                .map(|changed| Edited { value, changed }),
            Err(e) => Err(e.into()),
        };
        if solved.is_err() {
            // Back to the curve as it was, and the bound surfaces with it.
            self.curve_mut(id)?.restore(&before)?;
            self.follow_curve(id)?;
        }
        solved
    }

    /// Solves one part (with its group; a curve with the surfaces bound to
    /// it).
    pub fn solve(&mut self, id: PartId) -> Result<ChangedParts, ProductError> {
        match self.parts.get(&id).map(Part::kind) {
            None => Err(ProductError::UnknownPart(id)),
            Some(PartKind::Surface) => self.solve_surface(id),
            Some(PartKind::Curve) => self.solve_curve(id),
        }
    }

    /// Solves every part: curves first, then every surface and group.
    pub fn solve_all(&mut self) -> Result<(), ProductError> {
        let ids: Vec<(PartId, PartKind)> = self.parts.iter().map(|(k, p)| (*k, p.kind())).collect();
        for (id, kind) in &ids {
            if *kind == PartKind::Curve {
                self.curve_mut(*id)?.solve()?;
            }
        }
        for (id, kind) in &ids {
            if *kind == PartKind::Surface && !self.group_of.contains_key(id) {
                self.surface_mut(*id)?.solve()?;
            }
        }
        for g in 0..self.groups.len() {
            self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            self.groups[g].solve(&mut self.parts)?;
        }
        Ok(())
    }

    /// A drag frame: the pointer holding icon `icon` of part `part` is at
    /// `xyz`. On a part alone this is exactly the part's own drag; in a
    /// group, the group's drag fast path (another member's running drag is
    /// folded into its target first).
    pub fn drag(
        &mut self,
        part: PartId,
        icon: IconId,
        xyz: DVec3,
    ) -> Result<PartDrag, ProductError> {
        let Some(p) = self.parts.get_mut(&part) else {
            return Err(ProductError::UnknownPart(part));
        };
        match p {
            Part::Surface(d) => {
                let Some(&g) = self.group_of.get(&part) else {
                    let r = d.drag(icon, xyz)?;
                    return Ok(PartDrag {
                        requested: r.requested,
                        actual: r.actual,
                        report: Some(r.report),
                        changed: ChangedParts::one(part),
                    });
                };
                self.drag_in_group(g, part, icon, xyz)
            }
            Part::Curve(c) => {
                let actual = c.drag(icon, xyz)?;
                let changed = self.follow_curve(part)?;
                Ok(PartDrag {
                    requested: xyz,
                    actual,
                    report: None,
                    changed,
                })
            }
        }
    }

    fn drag_in_group(
        &mut self,
        g: usize,
        part: PartId,
        icon: IconId,
        xyz: DVec3,
    ) -> Result<PartDrag, ProductError> {
        let member = self.groups[g]
            .member(part)
            .ok_or(ProductError::UnknownPart(part))?;
        // One drag per group: another member's running drag ends here (its
        // icon keeps the dragged target and stays driving).
        let mut others = false;
        for &m in self.groups[g].ids.iter() {
            if m != part
                && let Some(d) = self.parts.get_mut(&m).and_then(Part::as_surface_mut)
                && d.dragging().is_some()
            {
                d.finish_drag();
                others = true;
            }
        }
        if others {
            self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
        }
        let d = self
            .parts
            .get_mut(&part)
            .and_then(Part::as_surface_mut)
            .ok_or(ProductError::UnknownPart(part))?;
        let mut backend = self.groups[g].backend(member);
        let r = d.drag_via(icon, xyz, Some(&mut backend))?;
        self.groups[g].write_back(&mut self.parts, Some(part))?;
        Ok(PartDrag {
            requested: r.requested,
            actual: r.actual,
            report: Some(r.report),
            changed: ChangedParts::shared(self.groups[g].ids.clone()),
        })
    }

    /// Releases a grabbed icon (the part's own release semantics: a load's
    /// deformation is kept, a constraint keeps its target). In a group every
    /// member keeps its current shape as its reference, so nothing springs
    /// back through the joins.
    pub fn release(&mut self, part: PartId, icon: IconId) -> Result<ChangedParts, ProductError> {
        match self.parts.get_mut(&part) {
            None => Err(ProductError::UnknownPart(part)),
            Some(Part::Curve(c)) => {
                c.release(icon)?;
                Ok(ChangedParts::one(part))
            }
            Some(Part::Surface(d)) => {
                d.release(icon)?;
                let Some(&g) = self.group_of.get(&part) else {
                    return Ok(ChangedParts::one(part));
                };
                self.keep_group_shape(part);
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
                self.groups[g].solve(&mut self.parts)?;
                Ok(ChangedParts::shared(self.groups[g].ids.clone()))
            }
        }
    }

    /// A discrete move of an icon's pointer to `xyz`, solved (see
    /// [`Design::move_icon`]). On a part alone it is the part's own move; in
    /// a group, and on a curve part, a drag frame to `xyz` then a release.
    pub fn move_icon(
        &mut self,
        part: PartId,
        icon: IconId,
        xyz: DVec3,
    ) -> Result<ChangedParts, ProductError> {
        if let Some(Part::Surface(d)) = self.parts.get_mut(&part)
            && !self.group_of.contains_key(&part)
        {
            d.move_icon(icon, xyz)?;
            return Ok(ChangedParts::one(part));
        }
        let moved = self.drag(part, icon, xyz)?;
        let released = self.release(part, icon)?;
        Ok(moved.changed.union(&released))
    }

    // ---- joins -----------------------------------------------------------

    /// Joins two surface edges (see [`super::join`]): checks that they fit
    /// (else [`ProductError::Incompatible`], nothing changed), solves the
    /// new group — the least-energy change that makes the edges meet — and
    /// keeps that shape as the members' reference.
    pub fn join(&mut self, spec: JoinSpec) -> Result<(JoinId, ChangedParts), ProductError> {
        let id = JoinId(self.next_join);
        let join = self.check_join(spec)?;
        let changed = self.add_relation(
            |p| {
                p.joins.insert(id, join);
            },
            |p| {
                p.joins.remove(&id);
            },
            spec.a,
        )?;
        self.next_join += 1;
        Ok((id, changed))
    }

    /// Restores a stored join under its id (rebuilding a product): checked
    /// as [`Self::join`], but nothing is solved or baked (see
    /// [`Self::solve_all`]).
    pub fn insert_join(&mut self, id: JoinId, join: Join) -> Result<(), ProductError> {
        if self.joins.contains_key(&id) {
            return Err(ProductError::DuplicateJoin(id));
        }
        let spec = JoinSpec {
            ratio: Some(join.ratio),
            ..join.spec
        };
        let checked = self.check_join(spec)?;
        self.joins.insert(id, checked);
        if let Err(e) = self.regroup() {
            self.joins.remove(&id);
            self.regroup()?;
            return Err(e);
        }
        self.next_join = self.next_join.max(id.0.saturating_add(1));
        Ok(())
    }

    /// Removes a join; the parts keep their current shape.
    pub fn unjoin(&mut self, id: JoinId) -> Result<ChangedParts, ProductError> {
        let join = *self.joins.get(&id).ok_or(ProductError::UnknownJoin(id))?;
        let changed = ChangedParts::from_ids(self.keep_group_shape(join.spec.a));
        self.joins.remove(&id);
        self.regroup()?;
        Ok(changed)
    }

    /// One join.
    pub fn join_of(&self, id: JoinId) -> Option<&Join> {
        self.joins.get(&id)
    }

    /// Every join, by ascending id.
    pub fn joins(&self) -> impl Iterator<Item = (JoinId, &Join)> {
        self.joins.iter().map(|(k, j)| (*k, j))
    }

    // ---- bindings --------------------------------------------------------

    /// Binds a curve part to a line of a surface part (see
    /// [`super::binding`]): checks that they fit (else
    /// [`ProductError::Incompatible`], nothing changed), solves the
    /// surface's group so the line lies on the curve, and keeps that shape.
    pub fn bind(&mut self, spec: BindingSpec) -> Result<(BindingId, ChangedParts), ProductError> {
        let id = BindingId(self.next_binding);
        let binding = self.check_binding(spec)?;
        let changed = self.add_relation(
            |p| {
                p.bindings.insert(id, binding);
            },
            |p| {
                p.bindings.remove(&id);
            },
            spec.surface,
        )?;
        self.next_binding += 1;
        Ok((id, changed))
    }

    /// Restores a stored binding under its id; nothing is solved or baked.
    pub fn insert_binding(&mut self, id: BindingId, spec: BindingSpec) -> Result<(), ProductError> {
        if self.bindings.contains_key(&id) {
            return Err(ProductError::DuplicateBinding(id));
        }
        let checked = self.check_binding(spec)?;
        self.bindings.insert(id, checked);
        if let Err(e) = self.regroup() {
            self.bindings.remove(&id);
            self.regroup()?;
            return Err(e);
        }
        self.next_binding = self.next_binding.max(id.0.saturating_add(1));
        Ok(())
    }

    /// Removes a binding; the surface keeps its current shape.
    pub fn unbind(&mut self, id: BindingId) -> Result<ChangedParts, ProductError> {
        let b = *self
            .bindings
            .get(&id)
            .ok_or(ProductError::UnknownBinding(id))?;
        let changed = ChangedParts::from_ids(self.keep_group_shape(b.spec.surface));
        self.bindings.remove(&id);
        self.regroup()?;
        Ok(changed)
    }

    /// One binding.
    pub fn binding(&self, id: BindingId) -> Option<&Binding> {
        self.bindings.get(&id)
    }

    /// Every binding, by ascending id.
    pub fn bindings(&self) -> impl Iterator<Item = (BindingId, &Binding)> {
        self.bindings.iter().map(|(k, b)| (*k, b))
    }

    // ---- internals -------------------------------------------------------

    fn surface_mut(&mut self, id: PartId) -> Result<&mut Design, ProductError> {
        match self.parts.get_mut(&id) {
            None => Err(ProductError::UnknownPart(id)),
            Some(p) => p.as_surface_mut().ok_or(ProductError::WrongKind {
                part: id,
                expected: PartKind::Surface,
            }),
        }
    }

    fn curve_mut(&mut self, id: PartId) -> Result<&mut CurveDesign, ProductError> {
        match self.parts.get_mut(&id) {
            None => Err(ProductError::UnknownPart(id)),
            Some(p) => p.as_curve_mut().ok_or(ProductError::WrongKind {
                part: id,
                expected: PartKind::Curve,
            }),
        }
    }

    fn surface_ref(&self, id: PartId) -> Result<&Design, ProductError> {
        match self.parts.get(&id) {
            None => Err(ProductError::UnknownPart(id)),
            Some(p) => p.as_surface().ok_or(ProductError::WrongKind {
                part: id,
                expected: PartKind::Surface,
            }),
        }
    }

    fn check_join(&self, spec: JoinSpec) -> Result<Join, ProductError> {
        let a = self.surface_ref(spec.a)?.surface();
        let b = self.surface_ref(spec.b)?.surface();
        Join::new(spec, a, b).map_err(ProductError::Incompatible)
    }

    fn check_binding(&self, spec: BindingSpec) -> Result<Binding, ProductError> {
        let curve = match self.parts.get(&spec.curve) {
            None => return Err(ProductError::UnknownPart(spec.curve)),
            Some(p) => p.as_curve().ok_or(ProductError::WrongKind {
                part: spec.curve,
                expected: PartKind::Curve,
            })?,
        };
        let surface = self.surface_ref(spec.surface)?.surface();
        Binding::new(spec, curve.curve(), surface).map_err(ProductError::Incompatible)
    }

    /// Adds a relation (`add`), regroups, solves the group of `part` and
    /// keeps its shape; on any error undoes it (`undo`) so nothing changed.
    fn add_relation(
        &mut self,
        add: impl FnOnce(&mut Self),
        undo: impl FnOnce(&mut Self),
        part: PartId,
    ) -> Result<ChangedParts, ProductError> {
        add(self);
        let solved = self.regroup().and_then(|()| {
            let g = *self
                .group_of
                .get(&part)
                .ok_or(ProductError::UnknownPart(part))?;
            self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            // Solve into the group's buffer only; members are written once
            // the solve succeeded.
            self.groups[g].solve(&mut self.parts)?;
            Ok(g)
        });
        match solved {
            Ok(g) => {
                let changed = ChangedParts::shared(self.groups[g].ids.clone());
                self.keep_group_shape(part);
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
                Ok(changed)
            }
            Err(e) => {
                undo(self);
                self.regroup()?;
                Err(e)
            }
        }
    }

    /// Bakes the current shape of `part`'s group (or of `part` alone, if a
    /// surface) into the members' references; returns the members.
    fn keep_group_shape(&mut self, part: PartId) -> Vec<PartId> {
        let ids: Vec<PartId> = match self.group_of.get(&part) {
            Some(&g) => self.groups[g].ids.to_vec(),
            None => vec![part],
        };
        for id in &ids {
            if let Some(d) = self.parts.get_mut(id).and_then(Part::as_surface_mut) {
                d.keep_shape();
            }
        }
        ids
    }

    fn solve_surface(&mut self, id: PartId) -> Result<ChangedParts, ProductError> {
        self.last_warning = None;
        let (changed, report) = match self.group_of.get(&id) {
            None => {
                let report = self.surface_mut(id)?.solve()?;
                (ChangedParts::one(id), report)
            }
            Some(&g) => {
                self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
                let report = self.groups[g].solve(&mut self.parts)?;
                (ChangedParts::shared(self.groups[g].ids.clone()), report)
            }
        };
        self.last_warning = report.warning;
        Ok(changed)
    }

    /// The warning of the last [`Self::solve`] of a surface part (with its
    /// group): set when the constraints are dependent and their targets
    /// disagree, so the shape is their least-squares compromise.
    pub fn last_warning(&self) -> Option<SolveWarning> {
        self.last_warning
    }

    fn solve_curve(&mut self, id: PartId) -> Result<ChangedParts, ProductError> {
        self.curve_mut(id)?.solve()?;
        self.follow_curve(id)
    }

    /// The groups holding a binding of curve `curve`.
    fn groups_bound_to(&self, curve: PartId) -> Vec<usize> {
        let mut gs: Vec<usize> = self
            .bindings
            .values()
            .filter(|b| b.spec.curve == curve)
            .filter_map(|b| self.group_of.get(&b.spec.surface).copied())
            .collect();
        gs.sort_unstable();
        gs.dedup();
        gs
    }

    /// Re-solves the surfaces bound to `curve` after it moved.
    fn follow_curve(&mut self, curve: PartId) -> Result<ChangedParts, ProductError> {
        let gs = self.groups_bound_to(curve);
        if gs.is_empty() {
            return Ok(ChangedParts::one(curve));
        }
        let mut ids = vec![curve];
        for g in gs {
            self.groups[g].refresh(&mut self.parts, &self.joins, &self.bindings)?;
            self.groups[g].solve(&mut self.parts)?;
            ids.extend(self.groups[g].ids.iter().copied());
        }
        Ok(ChangedParts::from_ids(ids))
    }

    /// Recomputes the solve groups (connected components of surface parts
    /// under joins, plus bound surfaces) after a relation changed, keeping
    /// unchanged groups (and their factorisations).
    fn regroup(&mut self) -> Result<(), ProductError> {
        // Union-find over the surface parts in a relation.
        let mut parent: BTreeMap<PartId, PartId> = BTreeMap::new();
        fn find(parent: &mut BTreeMap<PartId, PartId>, x: PartId) -> PartId {
            let mut r = x;
            while let Some(&p) = parent.get(&r) {
                if p == r {
                    break;
                }
                r = p;
            }
            parent.insert(x, r);
            r
        }
        for j in self.joins.values() {
            parent.entry(j.spec.a).or_insert(j.spec.a);
            parent.entry(j.spec.b).or_insert(j.spec.b);
            let (ra, rb) = (find(&mut parent, j.spec.a), find(&mut parent, j.spec.b));
            if ra != rb {
                parent.insert(ra.max(rb), ra.min(rb));
            }
        }
        for b in self.bindings.values() {
            parent.entry(b.spec.surface).or_insert(b.spec.surface);
        }
        let keys: Vec<PartId> = parent.keys().copied().collect();
        let mut comps: BTreeMap<PartId, Vec<PartId>> = BTreeMap::new();
        for k in keys {
            let r = find(&mut parent, k);
            comps.entry(r).or_default().push(k);
        }
        let mut old: Vec<Option<SolveGroup>> = std::mem::take(&mut self.groups)
            .into_iter()
            .map(Some)
            .collect();
        let previous = std::mem::take(&mut self.group_of);
        let mut groups = Vec::new();
        let mut group_of = BTreeMap::new();
        for (root, members) in comps {
            let joins: Vec<JoinId> = self
                .joins
                .iter()
                .filter(|(_, j)| find(&mut parent, j.spec.a) == root)
                .map(|(k, _)| *k)
                .collect();
            let bindings: Vec<BindingId> = self
                .bindings
                .iter()
                .filter(|(_, b)| find(&mut parent, b.spec.surface) == root)
                .map(|(k, _)| *k)
                .collect();
            let reuse = old.iter_mut().find(|g| {
                g.as_ref().is_some_and(|g| {
                    *g.ids == members[..] && g.joins == joins && g.bindings == bindings
                })
            });
            let group = match reuse.and_then(Option::take) {
                Some(g) => g,
                None => {
                    let mut g = SolveGroup::new(&self.parts, members.clone(), joins, bindings)?;
                    g.refresh(&mut self.parts, &self.joins, &self.bindings)?;
                    g
                }
            };
            for &m in &members {
                group_of.insert(m, groups.len());
            }
            groups.push(group);
        }
        // A design entering or leaving a group solves its problem afresh.
        for (id, p) in self.parts.iter_mut() {
            if previous.contains_key(id) != group_of.contains_key(id)
                && let Part::Surface(d) = p
            {
                d.mark_problem_dirty();
            }
        }
        self.groups = groups;
        self.group_of = group_of;
        Ok(())
    }
}
