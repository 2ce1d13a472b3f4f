//! The kernel side of a whole design: a `vsculpt_kernel::product::Product`
//! holding one kernel design per part (surface or curve) and the relations
//! between them (joins solved jointly, curves that surfaces follow), built
//! from the document, driven by drags, read back per part. Document icon ids
//! map to kernel icon ids per part here; every kernel error becomes a
//! [`CommandError`] with a stable kind.
//!
//! A drag on a part with no relation is exactly that part's own drag (the
//! product forwards it), so it costs what it costs alone; a joined part
//! drags its whole group; dragging a curve moves the surfaces that follow it.

use super::curve_engine::{CurveEngine, CurveQuery, curve_mesh, curve_readback};
use super::doc::DesignDoc;
use super::dsm_engine::DsmEngine;
use super::edit::SurfaceQuery;
use super::engine::{DesignQuery, Engine, IconReadback, kernel_error, readback, surface_mesh};
use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use super::part::{ContinuityDoc, EdgeDoc, IsoLineDoc, PartBody, RelationDoc, RelationKind};
use super::spring_band::spring_to_band;
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::icon::{IconId, Role};
use vsculpt_kernel::product::{
    BindingId, BindingSpec, ChangedParts, Continuity, Edge, IsoLine, Join, JoinId, JoinSpec, Part,
    PartId, Product, ProductError,
};
use vsculpt_kernel::solve::SolveWarning;

mod icon_edit;

/// What a client is told when a solve met its constraints only in the
/// least-squares sense.
pub fn warning_text(w: SolveWarning) -> String {
    match w {
        SolveWarning::Dependent { dropped, residual } => format!(
            "the constraints contradict each other ({dropped} dependent equations): the shape misses them by up to {residual:.3e} (least-squares compromise)"
        ),
    }
}

/// Every part's kernel design, the relations, and the id maps.
pub struct ProductEngine {
    product: Product,
    /// Per part: document icon id → kernel icon id.
    ids: BTreeMap<u64, BTreeMap<u64, IconId>>,
    /// Per relation id: the kernel join or binding.
    relations: BTreeMap<u64, KernelRelation>,
    /// Per part: the icon grabbed and where it was at the grab.
    grabbed: BTreeMap<u64, (u64, DVec3)>,
    /// The DSM parts (paper 001), meshed outside the kernel product.
    dsm: DsmEngine,
}

#[derive(Clone, Copy, Debug)]
enum KernelRelation {
    Join(JoinId),
    Binding(BindingId),
}

/// A kernel product error as a command error.
pub fn product_error(e: ProductError) -> CommandError {
    match e {
        ProductError::Design(d) => kernel_error(d),
        ProductError::Incompatible(m) => CommandError::new(ErrorKind::Incompatible, m),
        ProductError::UnknownPart(p) => {
            CommandError::new(ErrorKind::UnknownPart, format!("no part {}", p.0))
        }
        other => CommandError::new(ErrorKind::Incompatible, other.to_string()),
    }
}

fn edge(e: EdgeDoc) -> Edge {
    match e {
        EdgeDoc::UMin => Edge::UMin,
        EdgeDoc::UMax => Edge::UMax,
        EdgeDoc::VMin => Edge::VMin,
        EdgeDoc::VMax => Edge::VMax,
    }
}

fn join_spec(kind: &RelationKind, ratio: Option<f64>) -> Option<JoinSpec> {
    match kind {
        RelationKind::Join {
            a,
            edge_a,
            b,
            edge_b,
            continuity,
            reversed,
            ..
        } => Some(JoinSpec {
            a: PartId(*a),
            edge_a: edge(*edge_a),
            b: PartId(*b),
            edge_b: edge(*edge_b),
            reversed: *reversed,
            continuity: match continuity {
                ContinuityDoc::G0 => Continuity::G0,
                ContinuityDoc::G1 => Continuity::G1,
            },
            ratio,
        }),
        RelationKind::Binding { .. } | RelationKind::Ffd { .. } => None,
    }
}

fn binding_spec(kind: &RelationKind) -> Option<BindingSpec> {
    match kind {
        RelationKind::Binding {
            curve,
            surface,
            line,
            reversed,
        } => Some(BindingSpec {
            curve: PartId(*curve),
            surface: PartId(*surface),
            line: match line {
                IsoLineDoc::U(x) => IsoLine::U(*x),
                IsoLineDoc::V(x) => IsoLine::V(*x),
            },
            reversed: *reversed,
        }),
        RelationKind::Join { .. } | RelationKind::Ffd { .. } => None,
    }
}

fn ids_of(c: &ChangedParts) -> Vec<u64> {
    c.iter().map(|p| p.0).collect()
}

/// A kernel part and its map from document icon ids.
type KernelPart = (Part, BTreeMap<u64, IconId>);

/// The kernel part of `body` (its control points as stored) and its icon
/// id map; `None` for a body part (paper 002), which lives in the model's
/// body engines, outside the product.
fn kernel_part(body: &PartBody) -> Result<Option<KernelPart>, CommandError> {
    Ok(Some(match body {
        PartBody::Surface(s) => {
            let (d, ids) = Engine::build_unsolved(s)?.into_parts();
            (Part::Surface(d), ids)
        }
        PartBody::Curve(c) => {
            let (d, ids) = CurveEngine::build_unsolved(c)?.into_parts();
            (Part::Curve(d), ids)
        }
        // Network, DSM and body parts live outside the kernel product
        // (their own engines: network_engine, DsmEngine, body_engine).
        PartBody::Network(_) | PartBody::Dsm(_) | PartBody::Body(_) => return Ok(None),
    }))
}

impl ProductEngine {
    /// The product of `doc`, every shape as stored (nothing solved: stored
    /// shapes were solved when stored, so a reload is exact).
    pub fn build_unsolved(doc: &DesignDoc) -> Result<Self, CommandError> {
        let mut product = Product::new();
        let mut ids = BTreeMap::new();
        let mut dsm = DsmEngine::default();
        for p in &doc.parts {
            if let PartBody::Dsm(d) = &p.body {
                dsm.insert(p.id, d)?;
                continue;
            }
            let Some((part, map)) = kernel_part(&p.body)? else {
                continue;
            };
            product
                .insert_part(PartId(p.id), part)
                .map_err(product_error)?;
            ids.insert(p.id, map);
        }
        let mut e = Self {
            product,
            ids,
            relations: BTreeMap::new(),
            grabbed: BTreeMap::new(),
            dsm,
        };
        for r in &doc.relations {
            e.insert_relation(r)?;
        }
        Ok(e)
    }

    /// Restores a stored relation (nothing solved).
    fn insert_relation(&mut self, r: &RelationDoc) -> Result<(), CommandError> {
        if let RelationKind::Join { ratio, .. } = &r.kind
            && let Some(spec) = join_spec(&r.kind, Some(*ratio))
        {
            let id = JoinId(r.id);
            self.product
                .insert_join(
                    id,
                    Join {
                        spec,
                        ratio: *ratio,
                    },
                )
                .map_err(product_error)?;
            self.relations.insert(r.id, KernelRelation::Join(id));
        } else if let Some(spec) = binding_spec(&r.kind) {
            let id = BindingId(r.id);
            self.product
                .insert_binding(id, spec)
                .map_err(product_error)?;
            self.relations.insert(r.id, KernelRelation::Binding(id));
        }
        Ok(())
    }

    /// Makes a new relation (the kernel solves: joined edges meet, a bound
    /// surface takes the curve); returns the relation as stored (a join's
    /// ratio filled in) and the parts that moved.
    pub fn relate(
        &mut self,
        id: u64,
        kind: &RelationKind,
    ) -> Result<(RelationKind, Vec<u64>), CommandError> {
        if let Some(spec) = join_spec(kind, None) {
            let (jid, changed) = self.product.join(spec).map_err(product_error)?;
            let ratio = self.product.join_of(jid).map_or(1.0, |j| j.ratio);
            self.relations.insert(id, KernelRelation::Join(jid));
            let mut stored = kind.clone();
            if let RelationKind::Join { ratio: r, .. } = &mut stored {
                *r = ratio;
            }
            return Ok((stored, ids_of(&changed)));
        }
        let spec = binding_spec(kind).ok_or_else(|| {
            CommandError::new(ErrorKind::Incompatible, "not a relation the kernel knows")
        })?;
        let (bid, changed) = self.product.bind(spec).map_err(product_error)?;
        self.relations.insert(id, KernelRelation::Binding(bid));
        Ok((kind.clone(), ids_of(&changed)))
    }

    /// Removes relation `id`; the parts keep their shapes.
    pub fn unrelate(&mut self, id: u64) -> Result<Vec<u64>, CommandError> {
        let changed = match self.relations.remove(&id) {
            Some(KernelRelation::Join(j)) => self.product.unjoin(j),
            Some(KernelRelation::Binding(b)) => self.product.unbind(b),
            None => {
                return Err(CommandError::new(
                    ErrorKind::UnknownRelation,
                    format!("no relation {id}"),
                ));
            }
        }
        .map_err(product_error)?;
        Ok(ids_of(&changed))
    }

    /// Adds a new part (bare: a part starts without icons; nothing moves).
    pub fn add_part(&mut self, id: u64, body: &PartBody) -> Result<(), CommandError> {
        if let PartBody::Dsm(d) = body {
            return self.dsm.insert(id, d);
        }
        let Some((part, map)) = kernel_part(body)? else {
            return Ok(());
        };
        self.product
            .insert_part(PartId(id), part)
            .map_err(product_error)?;
        self.ids.insert(id, map);
        Ok(())
    }

    /// Removes a part with its relations; returns the parts that changed.
    pub fn remove_part(&mut self, id: u64) -> Result<Vec<u64>, CommandError> {
        if self.dsm.remove(id) || !self.ids.contains_key(&id) {
            // A DSM part, or a body part: not in the product.
            return Ok(Vec::new());
        }
        let removed = self
            .product
            .remove_part(PartId(id))
            .map_err(product_error)?;
        self.ids.remove(&id);
        self.grabbed.remove(&id);
        let gone_joins: Vec<JoinId> = removed.joins.iter().map(|(j, _)| *j).collect();
        let gone_bindings: Vec<BindingId> = removed.bindings.iter().map(|(b, _)| *b).collect();
        self.relations.retain(|_, r| match r {
            KernelRelation::Join(j) => !gone_joins.contains(j),
            KernelRelation::Binding(b) => !gone_bindings.contains(b),
        });
        Ok(ids_of(&removed.changed))
    }

    /// Rebuilds part `id` from `body` (after an edit of its icons or
    /// material) inside its relations, and solves it with everything solved
    /// with it. Returns the parts that moved.
    pub fn rebuild_part(&mut self, id: u64, body: &PartBody) -> Result<Vec<u64>, CommandError> {
        if let PartBody::Dsm(d) = body {
            self.dsm.insert(id, d)?;
            return Ok(vec![id]);
        }
        let Some((part, map)) = kernel_part(body)? else {
            // A body part: its engine rebuilds in the model.
            return Ok(vec![id]);
        };
        let removed = self
            .product
            .remove_part(PartId(id))
            .map_err(product_error)?;
        self.product
            .insert_part(PartId(id), part)
            .map_err(product_error)?;
        for (jid, join) in removed.joins {
            self.product.insert_join(jid, join).map_err(product_error)?;
        }
        for (bid, b) in removed.bindings {
            self.product
                .insert_binding(bid, b.spec)
                .map_err(product_error)?;
        }
        self.ids.insert(id, map);
        self.grabbed.remove(&id);
        let mut moved = ids_of(&self.product.solve(PartId(id)).map_err(product_error)?);
        moved.extend(ids_of(&removed.changed));
        moved.sort_unstable();
        moved.dedup();
        Ok(moved)
    }

    /// Takes the kernel solvers of `old`'s surface parts for the same
    /// parts here (same knots and material: `Product::adopt_solvers`), so
    /// an engine built afresh from a stored document (undo, redo, revert,
    /// restore) solves next through the factorisations it replaces.
    pub fn adopt_solvers(&mut self, old: &mut ProductEngine) {
        self.product.adopt_solvers(&mut old.product);
    }

    /// Whether a part has a pin change whose refactor is deferred (see
    /// [`Self::settle_idle`]).
    pub fn pins_pending(&self) -> bool {
        self.product.pins_pending()
    }

    /// The deferred half of the pin changes applied in place (a region or
    /// edge icon added, removed or switched: the kernel answers them
    /// through the old factor and refactors later): refactors now, for the
    /// design's actor to call when it has nothing else to do, so the next
    /// grab's first frame does not pay it. No shape changes. Returns
    /// whether anything was settled.
    pub fn settle_idle(&mut self) -> Result<bool, CommandError> {
        Ok(!self
            .product
            .settle_pins()
            .map_err(product_error)?
            .is_empty())
    }

    /// The warning of the last solve of a rebuilt part ([`Self::rebuild_part`]),
    /// as the client is told it.
    pub fn solve_warning(&self) -> Option<String> {
        self.product.last_warning().map(warning_text)
    }

    fn kid(&self, part: u64, icon: u64) -> Result<IconId, CommandError> {
        self.ids
            .get(&part)
            .and_then(|m| m.get(&icon))
            .copied()
            .ok_or_else(|| CommandError::new(ErrorKind::UnknownIcon, format!("no icon {icon}")))
    }

    /// A part's control points.
    pub fn points(&self, part: u64) -> Option<&[DVec3]> {
        self.product.control_points(PartId(part))
    }

    /// The drag fast path's cached basis `(start, ρ)` of a surface part's
    /// own solver (read-only; see `Design::drag_basis`).
    pub fn drag_basis(&self, part: u64) -> Option<(&[DVec3], &[f64])> {
        match self.product.part(PartId(part))? {
            Part::Surface(d) => d.drag_basis(),
            Part::Curve(_) => None,
        }
    }

    /// Where icon `icon` of `part` is.
    pub fn icon_xyz(&self, part: u64, icon: u64) -> Option<DVec3> {
        self.readback(part, icon).map(|r| r.xyz)
    }

    /// Icon `icon` of `part` as the kernel holds it.
    pub fn readback(&self, part: u64, icon: u64) -> Option<IconReadback> {
        let kid = self.kid(part, icon).ok()?;
        match self.product.part(PartId(part))? {
            Part::Surface(d) => readback(d, kid),
            Part::Curve(c) => curve_readback(c, kid),
        }
    }

    /// The size a surface part's spring stiffness scales with
    /// (`Design::set_spring_size`); `None` for other parts.
    pub fn spring_size(&self, part: u64) -> Option<f64> {
        match self.product.part(PartId(part))? {
            Part::Surface(d) => Some(d.spring().size()),
            Part::Curve(_) => None,
        }
    }

    /// A part's calibrated spring coefficient.
    pub fn kappa(&self, part: u64) -> Option<f64> {
        Some(match self.product.part(PartId(part))? {
            Part::Surface(d) => d.spring().kappa(),
            Part::Curve(c) => c.spring().kappa(),
        })
    }

    /// Grabs `icon` of `part` (the drag's reference is where it is now).
    pub fn grab(&mut self, part: u64, icon: u64) -> Result<(), CommandError> {
        let kid = self.kid(part, icon)?;
        if let Some(Part::Surface(_)) = self.product.part(PartId(part)) {
            self.product
                .edit_surface(PartId(part), |d| d.drag_start(kid))
                .map_err(product_error)?;
        }
        let at = self.icon_xyz(part, icon).unwrap_or_default();
        self.grabbed.insert(part, (icon, at));
        Ok(())
    }

    /// A drag frame: `icon`'s handle is at `xyz`. A load is pulled again
    /// until the spring lands in its band (paper 003's adaptive spring).
    /// Returns where the icon is, the parts that moved and, when the solve
    /// could not meet every constraint, why (for the client).
    pub fn drag(
        &mut self,
        part: u64,
        icon: u64,
        xyz: DVec3,
    ) -> Result<(DVec3, Vec<u64>, Option<String>), CommandError> {
        let kid = self.kid(part, icon)?;
        if self.grabbed.get(&part).map(|g| g.0) != Some(icon) {
            self.grab(part, icon)?;
        }
        let from = self.grabbed.get(&part).map(|g| g.1).unwrap_or_default();
        let is_load = match self.product.part(PartId(part)) {
            Some(Part::Surface(d)) => d.icon(kid).map(|i| i.role) == Some(Role::Load),
            Some(Part::Curve(c)) => {
                c.icon(kid).map(|i| i.role) == Some(vsculpt_kernel::curve_design::CurveRole::Load)
            }
            None => false,
        };
        let product = &mut self.product;
        let (actual, (changed, warning)) = spring_to_band(from, xyz, is_load, || {
            let r = product
                .drag(PartId(part), kid, xyz)
                .map_err(product_error)?;
            let warning = r.report.and_then(|r| r.warning).map(warning_text);
            Ok((r.actual, (ids_of(&r.changed), warning)))
        })?;
        Ok((actual, changed, warning))
    }

    /// Ends a drag; returns the parts that moved.
    pub fn release(&mut self, part: u64, icon: u64) -> Result<Vec<u64>, CommandError> {
        let kid = self.kid(part, icon)?;
        let grabbed = self.grabbed.get(&part).map(|g| g.0) == Some(icon);
        let dragging = match self.product.part(PartId(part)) {
            Some(Part::Surface(d)) => d.dragging() == Some(kid),
            _ => grabbed,
        };
        self.grabbed.remove(&part);
        if !dragging {
            return Ok(Vec::new());
        }
        Ok(ids_of(
            &self
                .product
                .release(PartId(part), kid)
                .map_err(product_error)?,
        ))
    }

    /// A tessellation (surface) or polyline (curve) of `part`.
    pub fn mesh(&self, part: u64, density: usize) -> Result<MeshData, CommandError> {
        if let Some(m) = self.dsm.mesh_data(part) {
            return Ok(m);
        }
        match self.product.part(PartId(part)) {
            Some(Part::Surface(d)) => Ok(surface_mesh(d.surface(), density)),
            Some(Part::Curve(c)) => Ok(curve_mesh(c.curve(), density)),
            None => Err(CommandError::new(
                ErrorKind::UnknownPart,
                format!("no part {part}"),
            )),
        }
    }

    /// The DSM parts and their meshes.
    pub fn dsm(&self) -> &DsmEngine {
        &self.dsm
    }

    /// Part `part`'s geometry as a query for icon placement.
    pub fn query(&self, part: u64) -> Option<Box<dyn SurfaceQuery + '_>> {
        Some(match self.product.part(PartId(part))? {
            Part::Surface(d) => Box::new(DesignQuery(d)),
            Part::Curve(c) => Box::new(CurveQuery(c.curve())),
        })
    }
}
