//! The live model of one design as its actor holds it: the document (the
//! persisted truth) plus one kernel engine per part built from it. Edits
//! produce a new document; only the parts an edit touches rebuild and solve;
//! only when that succeeds does the model switch, so a refused edit changes
//! nothing. Drags go straight to the part's engine (no rebuild, no refactor,
//! no other part touched).

use super::body_engine::BodyEngines;
pub use super::doc::DesignDoc;
pub use super::doc::{AnchorDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, SurfaceDoc};
pub use super::edit::{Created, Edit, MaterialEdit, PartEdit};
use super::engine::Engine;
use super::error::{CommandError, ErrorKind};
use super::ffd_binding::DsmFfds;
use super::morph_follow::MorphMeshes;
use super::network_engine::{NetworkEngine, NetworkEngines};
use super::part::{PartBody, RelationKind, SurfacePart};
use super::product_engine::ProductEngine;
use crate::cad::IgesSurface;
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;

/// A tessellation for mesh export.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals.
    pub normals: Vec<[f32; 3]>,
    /// Triangle indices.
    pub indices: Vec<u32>,
}

/// One geometry frame of one part, encoded once for every client.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// The design revision at which this part last changed.
    pub rev: u64,
    /// The binary WebSocket frame.
    pub frame: axum::body::Bytes,
    /// The same shape as a drag-stream frame, for the clients that asked
    /// for the stream (see [`super::drag_stream`]).
    pub stream: Option<super::drag_stream::StreamFrame>,
    /// The same mesh frame as a mesh delta from the part's previous frame,
    /// for the clients that asked (`mesh_delta=1`) and hold that frame
    /// (see [`super::dsm_delta`]).
    pub mesh_delta: Option<super::dsm_delta::MeshDeltaFrame>,
    /// `frame` deflated, for the clients that asked (`deflate=1`).
    pub deflated: super::deflated_frame::DeflatedFrame,
    /// `frame` flagged as a joiner's snapshot shape, deflated (the compact
    /// join of a client that asked for `deflate=1`).
    pub snapshot_deflated: super::deflated_frame::DeflatedFrame,
}

impl Geometry {
    /// A part's frame at `rev` with its drag-stream form, if any.
    pub fn new(
        rev: u64,
        frame: axum::body::Bytes,
        stream: Option<super::drag_stream::StreamFrame>,
    ) -> Self {
        Self {
            rev,
            frame,
            stream,
            mesh_delta: None,
            deflated: Default::default(),
            snapshot_deflated: Default::default(),
        }
    }
}

/// The newest frame of every part: what the actor publishes (latest wins
/// per part; a writer sends the parts whose `rev` it has not sent).
#[derive(Clone, Debug, Default)]
pub struct GeometrySet {
    /// Frames by part id.
    pub parts: BTreeMap<u64, Arc<Geometry>>,
}

/// Icon ids and where they are on the solved shape.
type IconPositions = Vec<(u64, DVec3)>;

/// Document + the kernel product of its parts.
pub struct DesignModel {
    doc: DesignDoc,
    engine: ProductEngine,
    /// The network parts' engines (outside the kernel product).
    networks: NetworkEngines,
    /// The body parts' volumes and displayed shapes (paper 002).
    bodies: BodyEngines,
    /// The deformed meshes of DSM parts bound to bodies (`ffd_binding`).
    ffds: DsmFfds,
    /// Those meshes as a morphing body carries them (`morph_follow`).
    morphs: MorphMeshes,
    /// The solve warning of the last edit (see [`Self::edit_warning`]).
    warning: Option<String>,
    /// Whether icon and material edits of surface parts are applied to the
    /// live kernel design (`product_engine::icon_edit`) or, when off, by
    /// rebuilding the part from its document.
    in_place: bool,
    /// The last idle settle failed: not tried again before the next edit
    /// (the next solve refactors anyway).
    settle_failed: bool,
}

fn unknown_part(part: u64) -> CommandError {
    CommandError::new(ErrorKind::UnknownPart, format!("no part {part}"))
}

impl DesignModel {
    /// Builds the model from a document (validated). The stored shapes are
    /// taken as they are — they were solved when stored — so a reload,
    /// undo or restore gives back exactly the same control points.
    pub fn load(doc: &DesignDoc) -> Result<Self, CommandError> {
        doc.validate()?;
        let engine = ProductEngine::build_unsolved(doc)?;
        let networks = network_engines(doc)?;
        let mut bodies = BodyEngines::default();
        bodies.sync(doc)?;
        let mut ffds = DsmFfds::default();
        ffds.sync(doc, engine.dsm())?;
        let mut m = Self {
            doc: doc.clone(),
            engine,
            networks,
            bodies,
            ffds,
            morphs: MorphMeshes::default(),
            warning: None,
            in_place: true,
            settle_failed: false,
        };
        m.sync();
        Ok(m)
    }

    /// [`Self::load`] for a document that replaces `current` (undo, redo,
    /// revert, restore, a whole-design replace): the same model, but its
    /// surface parts take `current`'s kernel solvers where knots and
    /// material agree, so their next solve costs what differs rather than
    /// a factorisation and every column. `current` keeps working (its
    /// parts refactor at their next solve).
    pub fn load_replacing(
        doc: &DesignDoc,
        current: &mut DesignModel,
    ) -> Result<Self, CommandError> {
        let mut m = Self::load(doc)?;
        m.engine.adopt_solvers(&mut current.engine);
        Ok(m)
    }

    /// Copies the kernel's state into the document.
    fn sync(&mut self) {
        self.doc = self.to_doc();
    }

    /// The current document: per part, the solved points and, per icon,
    /// position, target, state and sensors. A load's target is normalised
    /// to where it sits (sculpting is plastic: once solved, a load carries
    /// no further pull), so rebuilding from the document never moves the
    /// shape.
    pub fn to_doc(&self) -> DesignDoc {
        let mut d = self.doc.clone();
        let engine = &self.engine;
        for p in &mut d.parts {
            let Some(points) = engine.points(p.id) else {
                continue;
            };
            let points: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
            let kappa = engine.kappa(p.id).filter(|k| k.is_finite());
            match &mut p.body {
                PartBody::Surface(s) => {
                    s.surface.points = points;
                    s.kappa = kappa;
                    s.spring_size = engine.spring_size(p.id).filter(|x| x.is_finite());
                }
                PartBody::Curve(c) => {
                    c.curve.points = points;
                    c.kappa = kappa;
                }
                // Not in the product (no points there): the document (or
                // the part's own engine) is its truth.
                PartBody::Network(_) | PartBody::Dsm(_) | PartBody::Body(_) => {}
            }
            let part = p.id;
            for icon in p.body.icons_mut() {
                if let Some(r) = engine.readback(part, icon.id) {
                    icon.xyz = r.xyz.to_array();
                    // The kernel renormalises a normal's direction; keep the
                    // stored value when they agree to rounding, so a reload
                    // is bit for bit.
                    let stored = DVec3::from(icon.target);
                    if (r.target - stored).length() > 1e-12 * stored.length().max(1.0) {
                        icon.target = r.target.to_array();
                    }
                    icon.state = r.state;
                    icon.sensors = r.sensors;
                    if icon.role == IconRoleDoc::Load {
                        icon.target = icon.xyz;
                    }
                }
            }
        }
        d
    }

    /// The document as last synchronised (cheap; no kernel read-back).
    pub fn doc(&self) -> &DesignDoc {
        &self.doc
    }

    /// Applies an edit; returns what it created and the parts whose shape
    /// changed. Only the parts the edit touches rebuild (with everything
    /// solved with them); on any error nothing changes.
    pub fn apply(&mut self, edit: Edit) -> Result<(Created, Vec<u64>), CommandError> {
        let current = self.to_doc();
        let engine = &self.engine;
        let query = |part: u64| engine.query(part);
        let (mut doc, created) = super::edit::apply(&current, &edit, &query)?;
        doc.validate()?;
        // The kernel state changes in place (only the parts the edit
        // touches are rebuilt, the others keep their factorisations); if
        // the kernel refuses, it is rebuilt from the unchanged document.
        let next = &mut self.engine;
        let networks = &mut self.networks;
        let outcome = (|| -> Result<Vec<u64>, CommandError> {
            Ok(match &edit {
                Edit::Network { part, edit } => {
                    let engine = networks.get_mut(part).ok_or_else(|| unknown_part(*part))?;
                    engine.apply(edit)?;
                    let p = doc.part_mut(*part).ok_or_else(|| unknown_part(*part))?;
                    p.body = PartBody::Network(engine.to_part());
                    vec![*part]
                }
                Edit::CreatePart { .. }
                    if matches!(
                        doc.part(created.part.unwrap_or_default()).map(|p| &p.body),
                        Some(PartBody::Network(_))
                    ) =>
                {
                    let id = created.part.unwrap_or_default();
                    let p = doc.part_mut(id).ok_or_else(|| unknown_part(id))?;
                    let PartBody::Network(n) = &p.body else {
                        return Err(unknown_part(id));
                    };
                    let engine = NetworkEngine::build(n)?;
                    // Stored as the kernel reads it back (exactly reloadable).
                    p.body = PartBody::Network(engine.to_part());
                    networks.insert(id, engine);
                    vec![id]
                }
                Edit::DeletePart { part } if networks.contains_key(part) => {
                    networks.remove(part);
                    Vec::new()
                }
                Edit::Part { part, edit }
                    if self.in_place
                        && let (Some(p), Some(q)) = (current.part(*part), doc.part(*part))
                        && let Some(moved) =
                            next.edit_in_place(*part, edit, &p.body, &q.body, created.icon) =>
                {
                    moved
                }
                Edit::Part { part, .. } | Edit::Dsm { part, .. } => {
                    let p = doc.part(*part).ok_or_else(|| unknown_part(*part))?;
                    let mut moved = next.rebuild_part(*part, &p.body)?;
                    // A body's lattice moved the parts bound to it (their
                    // new shapes are in `doc`): rebuilt and solved.
                    if let PartBody::Body(_) = p.body {
                        for id in super::ffd_binding::bound_bspline_parts(&doc, *part) {
                            let q = doc.part(id).ok_or_else(|| unknown_part(id))?;
                            moved.extend(next.rebuild_part(id, &q.body)?);
                        }
                        moved.sort_unstable();
                        moved.dedup();
                    }
                    moved
                }
                Edit::CreatePart { .. } => {
                    let id = created.part.unwrap_or_default();
                    let p = doc.part(id).ok_or_else(|| unknown_part(id))?;
                    next.add_part(id, &p.body)?;
                    vec![id]
                }
                Edit::DeletePart { part } => next.remove_part(*part)?,
                Edit::SetPart { .. } => Vec::new(),
                Edit::Relate(RelationKind::Ffd { body, part, .. }) => {
                    let id = created.relation.unwrap_or_default();
                    let rest = super::ffd_binding::dsm_rest(&doc, next.dsm(), *body, *part)?;
                    if let Some(r) = doc.relations.iter_mut().find(|r| r.id == id)
                        && let RelationKind::Ffd { rest: stored, .. } = &mut r.kind
                    {
                        *stored = rest;
                    }
                    Vec::new()
                }
                Edit::Unrelate { relation }
                    if current.relations.iter().any(|r| {
                        r.id == *relation && matches!(r.kind, RelationKind::Ffd { .. })
                    }) =>
                {
                    Vec::new()
                }
                Edit::Relate(_) => {
                    let id = created.relation.unwrap_or_default();
                    let r = doc
                        .relations
                        .iter_mut()
                        .find(|r| r.id == id)
                        .ok_or_else(|| {
                            CommandError::new(ErrorKind::UnknownRelation, "lost relation")
                        })?;
                    let (stored, moved) = next.relate(id, &r.kind)?;
                    r.kind = stored;
                    moved
                }
                Edit::Unrelate { relation } => next.unrelate(*relation)?,
            })
        })();
        self.warning = None;
        self.settle_failed = false;
        let outcome = outcome.and_then(|m| self.bodies.sync(&doc).map(|()| m));
        let ffds = &mut self.ffds;
        let dsm = self.engine.dsm();
        let outcome = outcome.and_then(|mut m| {
            m.extend(ffds.sync(&doc, dsm)?);
            m.sort_unstable();
            m.dedup();
            Ok(m)
        });
        let outcome = outcome.and_then(|mut m| {
            let (ffds, dsm) = (&self.ffds, self.engine.dsm());
            m.extend(self.morphs.update(&doc, &self.bodies, |id| {
                ffds.mesh(id).or_else(|| dsm.mesh(id))
            })?);
            m.sort_unstable();
            m.dedup();
            Ok(m)
        });
        let moved = match outcome {
            Ok(m) => m,
            Err(e) => {
                // Every engine back to the unchanged document.
                self.engine = ProductEngine::build_unsolved(&current)?;
                self.networks = network_engines(&current)?;
                self.bodies.sync(&current)?;
                self.ffds.sync(&current, self.engine.dsm())?;
                let (ffds, dsm) = (&self.ffds, self.engine.dsm());
                self.morphs.update(&current, &self.bodies, |id| {
                    ffds.mesh(id).or_else(|| dsm.mesh(id))
                })?;
                return Err(e);
            }
        };
        if let Edit::Part { .. } = edit {
            self.warning = self.engine.solve_warning();
        }
        self.doc = doc;
        self.sync();
        Ok((created, moved))
    }

    /// Why the last [`Self::apply`] of an edit to a part's icons or
    /// material met its constraints only in the least-squares sense (they
    /// contradict each other), or `None` when it met them.
    pub fn edit_warning(&self) -> Option<&str> {
        self.warning.as_deref()
    }

    /// The icon with `id` and the id of its part.
    pub fn icon(&self, id: u64) -> Option<(u64, &IconDoc)> {
        self.doc.icon(id).map(|(p, i)| (p.id, i))
    }

    /// The part `icon` is on.
    pub fn part_of(&self, icon: u64) -> Option<u64> {
        self.doc.icon(icon).map(|(p, _)| p.id)
    }

    /// Checks that `icon` is on `part` (`UnknownIcon` / `UnknownPart`).
    pub fn check_icon(&self, part: u64, icon: u64) -> Result<(), CommandError> {
        match self.doc.icon(icon) {
            None => Err(CommandError::new(
                ErrorKind::UnknownIcon,
                format!("no icon {icon}"),
            )),
            Some((p, _)) if p.id != part => Err(CommandError::new(
                ErrorKind::UnknownPart,
                format!("icon {icon} is on part {}, not part {part}", p.id),
            )),
            Some(_) => Ok(()),
        }
    }

    /// Checks that `part` exists and is not locked.
    pub fn check_unlocked(&self, part: u64) -> Result<(), CommandError> {
        let p = self.doc.part(part).ok_or_else(|| unknown_part(part))?;
        if p.locked {
            return Err(CommandError::new(
                ErrorKind::Locked,
                format!("part {} ({}) is locked: unlock it first", p.id, p.name),
            ));
        }
        Ok(())
    }

    /// Grabs `icon` on `part`: it becomes driving (the drag's reference is
    /// the current shape). Returns the parts a drag of it moves.
    pub fn grab(&mut self, part: u64, icon: u64) -> Result<Vec<u64>, CommandError> {
        self.check_icon(part, icon)?;
        self.check_unlocked(part)?;
        self.engine.grab(part, icon)?;
        self.sync();
        Ok(vec![part])
    }

    /// A drag frame: icon `icon`'s handle is at `xyz`. Returns where the
    /// icon is on the solved shape, the parts that moved and the solve's
    /// warning, if any.
    pub fn drag(
        &mut self,
        part: u64,
        icon: u64,
        xyz: DVec3,
    ) -> Result<(DVec3, Vec<u64>, Option<String>), CommandError> {
        self.check_icon(part, icon)?;
        self.check_unlocked(part)?;
        if !xyz.is_finite() {
            return Err(CommandError::new(
                ErrorKind::NotFinite,
                "coordinates must be finite (no NaN or ∞)",
            ));
        }
        self.engine.drag(part, icon, xyz)
    }

    /// Ends a drag of `icon` on `part`.
    pub fn release(&mut self, part: u64, icon: u64) -> Result<Vec<u64>, CommandError> {
        self.check_icon(part, icon)?;
        let moved = self.engine.release(part, icon)?;
        self.sync();
        Ok(moved)
    }

    /// The network engine of a network part.
    pub fn network(&self, part: u64) -> Option<&NetworkEngine> {
        self.networks.get(&part)
    }

    /// Shows body part `part` at morph time `t` (evaluated here: run it
    /// where heavy work may run), carrying the parts bound to it along
    /// (`morph_follow`). Returns the parts whose frames changed: the body
    /// and the parts bound to it.
    pub fn set_morph_time(&mut self, part: u64, t: f64) -> Result<Vec<u64>, CommandError> {
        match self.doc.part(part).map(|p| &p.body) {
            None => return Err(unknown_part(part)),
            Some(PartBody::Body(_)) => {}
            Some(_) => {
                return Err(CommandError::new(
                    ErrorKind::Unsupported,
                    format!("part {part} is not a body: it has no morph"),
                ));
            }
        }
        let before = self.bodies.get(part).map(|e| e.time());
        self.bodies.set_time(part, t)?;
        let (ffds, dsm) = (&self.ffds, self.engine.dsm());
        let updated = self.morphs.update(&self.doc, &self.bodies, |id| {
            ffds.mesh(id).or_else(|| dsm.mesh(id))
        });
        if let Err(e) = updated {
            // Back to the time shown before (its meshes were made for it).
            if let Some(t0) = before {
                self.bodies.set_time(part, t0)?;
            }
            return Err(e);
        }
        let mut moved = vec![part];
        moved.extend(super::morph_follow::bound_parts(&self.doc, part));
        Ok(moved)
    }

    /// Whether an edit left work for idle time ([`Self::settle_idle`]).
    pub fn idle_work(&self) -> bool {
        !self.settle_failed && self.engine.pins_pending()
    }

    /// Does the work an edit deferred to idle time (the refactor after a
    /// pin change applied in place); the shape does not change. Returns
    /// whether there was any.
    pub fn settle_idle(&mut self) -> Result<bool, CommandError> {
        let settled = self.engine.settle_idle();
        self.settle_failed = settled.is_err();
        settled
    }

    /// With `in_place` off, an icon or material edit of a surface part
    /// rebuilds the part from its edited document (a fresh factorisation
    /// and every column of the constrained solve) instead of editing the
    /// live kernel design: the server before issue 15's in-place edits,
    /// kept to measure and test against.
    pub fn set_edit_in_place(&mut self, in_place: bool) {
        self.in_place = in_place;
    }

    /// With `full`, a body's lattice change recomputes every vertex of the
    /// DSM meshes bound to it instead of only the moved points' supports
    /// (`DsmFfds::set_full_recompute`: to measure locality against).
    pub fn set_ffd_full_recompute(&mut self, full: bool) {
        self.ffds.set_full_recompute(full);
    }

    /// The mesh DSM part `part` shows: carried by a morphing body
    /// (`morph_follow`), else deformed by the body it is bound to
    /// (`ffd_binding`), else its own.
    pub fn dsm_mesh(&self, part: u64) -> Option<&vsculpt_kernel::dsm::Mesh> {
        self.morphs
            .mesh(part)
            .or_else(|| self.ffds.mesh(part))
            .or_else(|| self.engine.dsm().mesh(part))
    }

    /// The point S(u, v) of surface part `part` as solved now (mid-drag
    /// too): `unknown_part`, `unsupported` for a part that is not a
    /// surface, `out_of_domain` for (u, v) outside its domain.
    pub fn surface_point(&self, part: u64, u: f64, v: f64) -> Result<DVec3, CommandError> {
        let p = self.doc.part(part).ok_or_else(|| unknown_part(part))?;
        let PartBody::Surface(s) = &p.body else {
            return Err(CommandError::new(
                ErrorKind::Unsupported,
                format!(
                    "part {part} is a {} part: (u, v) is for surface parts; give xyz",
                    p.body.kind()
                ),
            ));
        };
        let s = &s.surface;
        if !s.contains(u, v) {
            let ((u0, u1), (v0, v1)) = s.domain();
            return Err(CommandError::new(
                ErrorKind::OutOfDomain,
                format!(
                    "(u, v) = ({u}, {v}) is outside part {part}'s domain [{u0}, {u1}] × [{v0}, {v1}]"
                ),
            ));
        }
        let geometry = |e: vsculpt_kernel::bspline::GeometryError| {
            CommandError::new(ErrorKind::InvalidValue, e.to_string())
        };
        let points = match self.engine.points(part) {
            Some(p) => p.to_vec(),
            None => s.dpoints(),
        };
        let ku = vsculpt_kernel::bspline::KnotVector::new(s.u_degree, s.u_knots.clone())
            .map_err(geometry)?;
        let kv = vsculpt_kernel::bspline::KnotVector::new(s.v_degree, s.v_knots.clone())
            .map_err(geometry)?;
        let surface =
            vsculpt_kernel::bspline::BSplineSurface::new(ku, kv, points).map_err(geometry)?;
        Ok(surface.point(u, v))
    }

    /// The morph deformation that carries part `part` (bound to a body shown
    /// at morph time t > 0), if any.
    fn morph_of(&self, part: u64) -> Option<&vsculpt_kernel::body::Ffd> {
        self.bodies
            .follow(super::morph_follow::body_of(&self.doc, part)?)
    }

    /// The volume body part `part` shows (its morph at the current time).
    pub fn body_volume(&self, part: u64) -> Option<&vsculpt_kernel::body::BSplineVolume> {
        self.bodies.get(part).map(|e| e.shown())
    }

    /// The encoded geometry frame of `part` at revision `rev` (a network
    /// part's: a mesh frame of its patches; a DSM part's: a mesh frame of
    /// its surface; a body's: a body frame).
    pub fn geometry(&self, design: u64, part: u64, rev: u64, drag: bool) -> Option<Geometry> {
        if let Some(n) = self.networks.get(&part) {
            return Some(Geometry::new(rev, n.frame(design, part, rev, drag), None));
        }
        if let Some(frame) = self
            .morphs
            .mesh(part)
            .and_then(|m| super::dsm_engine::mesh_frame(m, design, part, rev, drag, None))
        {
            return Some(Geometry::new(rev, frame, None));
        }
        if let Some((frame, delta)) = self.ffds.frame(design, part, rev, drag) {
            // Kept encoded and patched: the delta comes with the frame.
            let mut g = Geometry::new(rev, frame, None);
            g.mesh_delta = delta;
            return Some(g);
        }
        if let Some(frame) = self.engine.dsm().frame(design, part, rev, drag) {
            return Some(Geometry::new(rev, frame, None));
        }
        if let Some(body) = self.bodies.get(part) {
            let flags = if drag {
                vsculpt_protocol::frame::FLAG_DRAG
            } else {
                0
            };
            return Some(Geometry::new(
                rev,
                body.frame(design, part, rev, flags)?.into(),
                None,
            ));
        }
        let (points, icons) = self.frame_data(part)?;
        let p = self.doc.part(part)?;
        if let Some(follow) = self.morph_of(part) {
            // Carried by a morphing body: what is shown, not what is stored.
            let points = super::morph_follow::carry(follow, points);
            let at: Vec<DVec3> = icons.iter().map(|(_, x)| *x).collect();
            let icons: IconPositions = icons
                .iter()
                .map(|(id, _)| *id)
                .zip(super::morph_follow::carry(follow, &at))
                .collect();
            return Some(Geometry::new(
                rev,
                crate::convert::geometry_frame(design, rev, drag, p, &points, &icons),
                None,
            ));
        }
        Some(Geometry::new(
            rev,
            crate::convert::geometry_frame(design, rev, drag, p, points, &icons),
            None,
        ))
    }

    /// The encoded frame of a drag of `part` at revision `rev`, with its
    /// drag-stream form when the drag is on the kernel's fast path
    /// (`previous`: the part's frame published before).
    pub fn drag_geometry(
        &self,
        design: u64,
        part: u64,
        rev: u64,
        previous: Option<&Geometry>,
        streams: &mut super::drag_stream::DragStreams,
    ) -> Option<Geometry> {
        let mut g = self.geometry(design, part, rev, true)?;
        if self.morph_of(part).is_some() {
            // Carried by a morphing body: full frames only.
            return Some(g);
        }
        let (points, icons) = self.frame_data(part)?;
        g.stream = streams.frame(super::drag_stream::DragInput {
            design,
            part,
            revision: rev,
            basis: self.engine.drag_basis(part),
            points,
            icons: &icons,
            previous: previous.map(|p| (p.rev, &p.frame)),
            full: &g.frame,
        });
        Some(g)
    }

    /// A part's control points and icon positions.
    fn frame_data(&self, part: u64) -> Option<(&[DVec3], IconPositions)> {
        let p = self.doc.part(part)?;
        let points = self.engine.points(part)?;
        let icons: Vec<(u64, DVec3)> = p
            .body
            .icons()
            .iter()
            .map(|i| {
                (
                    i.id,
                    self.engine
                        .icon_xyz(part, i.id)
                        .unwrap_or_else(|| DVec3::from(i.xyz)),
                )
            })
            .collect();
        Some((points, icons))
    }

    /// Every part's frame at revision `rev`.
    pub fn geometry_set(&self, design: u64, rev: u64) -> GeometrySet {
        GeometrySet {
            parts: self
                .doc
                .parts
                .iter()
                .filter_map(|p| Some((p.id, Arc::new(self.geometry(design, p.id, rev, false)?))))
                .collect(),
        }
    }

    /// A tessellation with `density` samples per knot span: of `part`, or
    /// of every surface and network part (the whole product) when `None`
    /// (a network's patches at the engine's resolution).
    pub fn mesh(&self, part: Option<u64>, density: usize) -> Result<MeshData, CommandError> {
        let density = density.clamp(1, 32);
        let body_mesh = |id: u64| {
            self.bodies.get(id).map(|b| {
                let s = b.shape();
                MeshData {
                    positions: s.positions.clone(),
                    normals: s.normals.clone(),
                    indices: s.triangles.iter().flatten().copied().collect(),
                }
            })
        };
        match part {
            Some(id) => match (self.networks.get(&id), body_mesh(id)) {
                (Some(n), _) => Ok(n.mesh()),
                (None, Some(m)) => Ok(m),
                (None, None) => self.engine.mesh(id, density),
            },
            None => {
                let mut out = MeshData::default();
                for p in &self.doc.parts {
                    let m = match (&p.body, self.networks.get(&p.id)) {
                        (PartBody::Surface(_), _) => Some(self.engine.mesh(p.id, density)?),
                        (PartBody::Body(_), _) => body_mesh(p.id),
                        (_, Some(n)) => Some(n.mesh()),
                        _ => None,
                    };
                    if let Some(m) = m {
                        let base = out.positions.len() as u32;
                        out.positions.extend(m.positions);
                        out.normals.extend(m.normals);
                        out.indices.extend(m.indices.iter().map(|i| i + base));
                    }
                }
                Ok(out)
            }
        }
    }
}

/// The network engine of every network part of `doc`.
fn network_engines(doc: &DesignDoc) -> Result<NetworkEngines, CommandError> {
    doc.parts
        .iter()
        .filter_map(|p| match &p.body {
            PartBody::Network(n) => Some(NetworkEngine::build(n).map(|e| (p.id, e))),
            _ => None,
        })
        .collect()
}

/// `part` with its surface replaced by `s` (IGES import of one surface
/// into an existing part): icons whose (u, v) fall outside the new domain
/// are dropped; the others keep their parameters and are re-placed on the
/// new surface.
pub fn with_surface(part: &SurfacePart, s: &IgesSurface) -> Result<SurfacePart, CommandError> {
    let surface = SurfaceDoc::from_iges(s);
    surface.validate()?;
    let mut part = part.clone();
    part.surface = surface;
    part.icons
        .retain(|i| i.anchor.validate(&part.surface).is_ok());
    let engine = Engine::build_unsolved(&part)?;
    for icon in &mut part.icons {
        use super::edit::SurfaceQuery;
        icon.xyz = engine.point_at(&icon.anchor);
        icon.target = engine.current_target(&icon.anchor, icon.role);
    }
    Ok(part)
}
