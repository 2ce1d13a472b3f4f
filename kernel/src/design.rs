//! A design — surface, icons, material — as a value you edit, solve,
//! snapshot and restore.
//!
//! The energy is that of the displacement from a *reference shape*, so a
//! surface with no loads stays as it is and the solver only ever moves it
//! where an icon asks. Sculpting is plastic: while a load is driven, its
//! spring pulls the surface elastically; when it is released the current
//! shape becomes the new reference and the load carries no more force. A
//! released constraint keeps its new target.
//!
//! The solver (a factored stiffness and the icons' cached columns) lives in
//! the design but is not part of its value: it is rebuilt lazily — numeric
//! refactor on a material change, new columns on an icon change, nothing on
//! a drag frame.

use std::collections::BTreeMap;

use glam::DVec3;
use thiserror::Error;

use crate::analysis::{Tessellation, tessellate};
use crate::bspline::{BSplineSurface, BasisDerivs, GeometryError, basis_derivs_into};
use crate::energy::{MaterialError, Stiffness, StiffnessError, SurfaceMaterial};
use crate::icon::{
    Anchor, AnchorError, Icon, IconId, IconSpec, IconState, Role, SensorId, capture, held_points,
    icon_group, placement,
};
use crate::solve::{Problem, SolveError, SolveReport, Solver};
use crate::spring::{Adaptation, Spring};

/// Why an edit was refused. A refused edit changes nothing.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum DesignError {
    /// No icon with that id.
    #[error("no icon {0:?}")]
    UnknownIcon(IconId),
    /// A (u,v) outside the surface's domain.
    #[error("({0}, {1}) is outside the surface's domain")]
    OutOfDomain(f64, f64),
    /// A NaN or infinite value.
    #[error("{0} is not finite")]
    NotFinite(&'static str),
    /// The anchor has no length or area.
    #[error("degenerate anchor: {0}")]
    Degenerate(&'static str),
    /// The role does not fit the anchor (derivative and normal constraints
    /// need a point), or the edit does not fit the icon.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The surface data is invalid.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The material is invalid.
    #[error(transparent)]
    Material(#[from] MaterialError),
    /// The solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

impl From<AnchorError> for DesignError {
    fn from(e: AnchorError) -> Self {
        match e {
            AnchorError::OutOfDomain(u, v) => DesignError::OutOfDomain(u, v),
            AnchorError::Degenerate(what) => DesignError::Degenerate(what),
        }
    }
}

impl From<StiffnessError> for DesignError {
    fn from(e: StiffnessError) -> Self {
        match e {
            StiffnessError::Material(m) => DesignError::Material(m),
            other => DesignError::Solve(SolveError::Stiffness(other)),
        }
    }
}

/// A design as a value: everything that makes it, nothing cached.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignSnapshot {
    /// The current surface.
    pub surface: BSplineSurface,
    /// The reference shape (control points) the energy is measured from.
    pub reference: Vec<DVec3>,
    /// The material.
    pub material: SurfaceMaterial,
    /// The icons, by id.
    pub icons: Vec<Icon>,
    /// The next icon id.
    pub next_id: u64,
    /// The spring coefficient κ.
    pub kappa: f64,
}

/// The result of a drag frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragReport {
    /// The solver's report.
    pub report: SolveReport,
    /// Where the pointer asked the icon to go.
    pub requested: DVec3,
    /// Where the icon is on the solved surface.
    pub actual: DVec3,
}

#[derive(Debug, Clone, Copy)]
struct ActiveDrag {
    id: IconId,
    origin: DVec3,
    t: DVec3,
    /// The icon's surface position when grabbed (for the spring ratio).
    grabbed_at: DVec3,
}

/// Solves a design's problem somewhere else than in its own solver: a
/// design joined to others is solved jointly ([`crate::product`]).
pub(crate) trait SolveBackend {
    /// Solves for `design`'s control points into `out` (its length is the
    /// design's). `problem_changed`: [`Design::problem`] may differ from the
    /// last call's; `drag`: the running drag's group key and (load-scaled)
    /// input.
    fn solve(
        &mut self,
        design: &Design,
        problem_changed: bool,
        drag: Option<(u64, DVec3)>,
        out: &mut [DVec3],
    ) -> Result<SolveReport, DesignError>;
}

/// Most adaptation steps of the spring in one drag frame. Each step scales
/// κ by at most 100 (see [`crate::spring`]), so 16 steps span the whole
/// range [κ_min, κ_max] = [1e-6, 1e9] twice over; each costs one fast drag
/// solve (3N multiply-adds).
pub const SPRING_STEPS: usize = 16;

/// A sculptable design.
#[derive(Debug)]
pub struct Design {
    surface: BSplineSurface,
    reference: Vec<DVec3>,
    material: SurfaceMaterial,
    icons: BTreeMap<IconId, Icon>,
    next_id: u64,
    spring: Spring,
    adaptive: bool,
    /// The spring stiffness the solver's load gains were built with; a
    /// running load drag is scaled by k / built_k.
    built_k: f64,
    solver: Option<Solver>,
    problem_dirty: bool,
    drag: Option<ActiveDrag>,
    revision: u64,
    /// The previous control points, reused as the next solve's output buffer.
    scratch: Vec<DVec3>,
    /// Basis scratch (u, v) for re-placing icons without allocating.
    basis: (BasisDerivs, BasisDerivs),
}

impl Design {
    /// A design of `surface` with `material`, no icons; the surface is its
    /// own reference shape.
    pub fn new(surface: BSplineSurface, material: SurfaceMaterial) -> Result<Self, DesignError> {
        material.validate()?;
        let area = surface.area();
        let spring = Spring::new(10.0, if area > 0.0 { area } else { 1.0 })
            .map_err(|e| DesignError::Unsupported(e.0))?;
        Ok(Self {
            reference: surface.points().to_vec(),
            surface,
            material,
            icons: BTreeMap::new(),
            next_id: 1,
            built_k: spring.stiffness(),
            spring,
            adaptive: true,
            solver: None,
            problem_dirty: true,
            drag: None,
            revision: 0,
            scratch: Vec::new(),
            basis: Default::default(),
        })
    }

    /// A design from a snapshot (icons' samples are recomputed; icons that
    /// no longer fit the surface are an error).
    pub fn from_snapshot(s: &DesignSnapshot) -> Result<Self, DesignError> {
        let mut d = Self::new(s.surface.clone(), s.material)?;
        if s.reference.len() != s.surface.points().len()
            || s.reference.iter().any(|p| !p.is_finite())
        {
            return Err(DesignError::NotFinite("reference shape"));
        }
        d.reference = s.reference.clone();
        d.next_id = s.next_id;
        d.spring =
            Spring::new(s.kappa, d.spring.size()).map_err(|e| DesignError::Unsupported(e.0))?;
        for icon in &s.icons {
            let mut icon = icon.clone();
            let placed = placement(&icon.anchor, &d.surface)?;
            icon.samples = placed.samples;
            icon.identity = placed.rows;
            let rows =
                if icon.role == Role::Position && held_points(&icon.anchor, &d.surface).is_none() {
                    icon.identity.len()
                } else {
                    0
                };
            if icon.shape.len() != icon.samples.len() + rows {
                return Err(DesignError::Unsupported(format!(
                    "icon {:?}: shape does not match its anchor",
                    icon.id
                )));
            }
            d.next_id = d.next_id.max(icon.id.0 + 1);
            d.icons.insert(icon.id, icon);
        }
        Ok(d)
    }

    /// The design as a value.
    pub fn snapshot(&self) -> DesignSnapshot {
        DesignSnapshot {
            surface: self.surface.clone(),
            reference: self.reference.clone(),
            material: self.material,
            icons: self.icons.values().cloned().collect(),
            next_id: self.next_id,
            kappa: self.spring.kappa(),
        }
    }

    /// Replaces the design by `snapshot` (undo, redo, revert, restore). The
    /// factorisation is kept when knots and material are unchanged.
    pub fn restore(&mut self, snapshot: &DesignSnapshot) -> Result<(), DesignError> {
        let mut next = Self::from_snapshot(snapshot)?;
        let same_layout = next.surface.u_knots() == self.surface.u_knots()
            && next.surface.v_knots() == self.surface.v_knots()
            && next.material == self.material;
        if same_layout {
            next.solver = self.solver.take();
        }
        next.revision = self.revision + 1;
        next.adaptive = self.adaptive;
        *self = next;
        Ok(())
    }

    /// The current surface.
    pub fn surface(&self) -> &BSplineSurface {
        &self.surface
    }

    /// The reference shape's control points.
    pub fn reference(&self) -> &[DVec3] {
        &self.reference
    }

    /// The material.
    pub fn material(&self) -> SurfaceMaterial {
        self.material
    }

    /// The spring model.
    pub fn spring(&self) -> &Spring {
        &self.spring
    }

    /// Whether drags adapt the spring's κ (on by default).
    pub fn set_adaptive_spring(&mut self, on: bool) {
        self.adaptive = on;
    }

    /// Sets the size S the spring's stiffness κS scales with (the
    /// surface's area when the design was made, [`Self::new`]): a host that
    /// rebuilds a design from a stored shape sets the size the design had,
    /// so its loads pull as they did (the area of the shape as it is now
    /// would differ after a pull). Finite and > 0.
    pub fn set_spring_size(&mut self, size: f64) -> Result<(), DesignError> {
        if !(size.is_finite() && size > 0.0) {
            return Err(DesignError::NotFinite("spring size"));
        }
        if size != self.spring.size() {
            self.spring.set_size(size);
            self.problem_dirty = true;
        }
        Ok(())
    }

    /// Sets κ directly.
    pub fn set_kappa(&mut self, kappa: f64) -> Result<(), DesignError> {
        self.spring =
            Spring::new(kappa, self.spring.size()).map_err(|e| DesignError::Unsupported(e.0))?;
        self.problem_dirty = true;
        Ok(())
    }

    /// Increases with every change of shape.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Every icon, by id.
    pub fn icons(&self) -> impl Iterator<Item = &Icon> {
        self.icons.values()
    }

    /// One icon.
    pub fn icon(&self, id: IconId) -> Option<&Icon> {
        self.icons.get(&id)
    }

    /// The icon being dragged, if any.
    pub fn dragging(&self) -> Option<IconId> {
        self.drag.map(|d| d.id)
    }

    fn icon_mut(&mut self, id: IconId) -> Result<&mut Icon, DesignError> {
        self.icons.get_mut(&id).ok_or(DesignError::UnknownIcon(id))
    }

    fn check_role(anchor: &Anchor, role: Role) -> Result<(), DesignError> {
        if matches!(role, Role::Derivative(_) | Role::Normal)
            && !matches!(anchor, Anchor::Point { .. })
        {
            return Err(DesignError::Unsupported(
                "derivative and normal constraints need a point anchor".into(),
            ));
        }
        Ok(())
    }

    /// An outside-region constraint holds its patch: its target never moves.
    fn check_movable(icon: &Icon) -> Result<(), DesignError> {
        if let (Anchor::Region { inside: false, .. }, Role::Position) = (&icon.anchor, icon.role) {
            return Err(DesignError::Unsupported(
                "an outside region holds its patch; it cannot be moved or dragged".into(),
            ));
        }
        Ok(())
    }

    /// The surface's current value of what `role` constrains at the handle
    /// `anchor_uv` (for a load: where its spring is attached).
    fn current_target(&self, role: Role, anchor_uv: (f64, f64)) -> DVec3 {
        let d = self.surface.derivs(anchor_uv.0, anchor_uv.1);
        match role {
            Role::Load | Role::Position => d.p,
            Role::Normal => self.surface.normal(anchor_uv.0, anchor_uv.1),
            Role::Derivative(k) => match k.orders() {
                (1, 0) => d.u,
                (0, 1) => d.v,
                (2, 0) => d.uu,
                (0, 2) => d.vv,
                _ => d.uv,
            },
        }
    }

    /// Adds an icon; its target defaults to the surface's current value at
    /// its handle. A load always starts attached where the surface is (its
    /// target is the handle's surface point, whatever `spec.target` says):
    /// a new load carries no force.
    pub fn add_icon(&mut self, spec: IconSpec) -> Result<IconId, DesignError> {
        Self::check_role(&spec.anchor, spec.role)?;
        if let Some(t) = spec.target
            && !t.is_finite()
        {
            return Err(DesignError::NotFinite("target"));
        }
        let placed = placement(&spec.anchor, &self.surface)?;
        let shape = capture(
            &spec.anchor,
            spec.role,
            &placed.samples,
            &placed.rows,
            &self.surface,
        );
        let id = IconId(self.next_id);
        let (hu, hv) = spec.anchor.handle_uv();
        let handle = self.surface.point(hu, hv);
        let mut icon = Icon {
            id,
            anchor: spec.anchor,
            role: spec.role,
            state: spec.state,
            sensors: Vec::new(),
            xyz: handle,
            target: DVec3::ZERO,
            shape,
            handle,
            samples: placed.samples,
            identity: placed.rows,
        };
        icon.target = match spec.target {
            Some(t) if icon.role != Role::Load => t,
            _ => self.current_target(icon.role, icon.handle_uv()),
        };
        if icon.role == Role::Normal {
            icon.target = icon
                .target
                .try_normalize()
                .ok_or(DesignError::NotFinite("normal"))?;
        }
        self.next_id += 1;
        self.icons.insert(id, icon);
        self.problem_dirty = true;
        Ok(id)
    }

    /// Deletes an icon (ending its drag).
    pub fn remove_icon(&mut self, id: IconId) -> Result<Icon, DesignError> {
        let icon = self.icons.remove(&id).ok_or(DesignError::UnknownIcon(id))?;
        if self.dragging() == Some(id) {
            self.drag = None;
        }
        self.problem_dirty = true;
        Ok(icon)
    }

    /// Re-anchors an icon; it then holds (or pulls from) the surface as it is
    /// along the new anchor.
    pub fn set_anchor(&mut self, id: IconId, anchor: Anchor) -> Result<(), DesignError> {
        let role = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .role;
        Self::check_role(&anchor, role)?;
        let placed = placement(&anchor, &self.surface)?;
        let shape = capture(&anchor, role, &placed.samples, &placed.rows, &self.surface);
        self.finish_drag_of(id);
        let mut icon = self.icons[&id].clone();
        icon.anchor = anchor;
        icon.samples = placed.samples;
        icon.identity = placed.rows;
        icon.shape = shape;
        let (hu, hv) = icon.handle_uv();
        icon.handle = self.surface.point(hu, hv);
        icon.xyz = icon.handle;
        icon.target = self.current_target(role, (hu, hv));
        self.icons.insert(id, icon);
        self.problem_dirty = true;
        Ok(())
    }

    /// Switches constraint ↔ load, position ↔ tangent ↔ normal in one call.
    /// The new role starts from the surface as it is (no jump).
    pub fn set_role(&mut self, id: IconId, role: Role) -> Result<(), DesignError> {
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        Self::check_role(&icon.anchor, role)?;
        self.finish_drag_of(id);
        self.icon_mut(id)?.role = role;
        self.rebase_shape(id);
        let icon = &self.icons[&id];
        let target = self.current_target(role, icon.handle_uv());
        self.icon_mut(id)?.target = target;
        self.problem_dirty = true;
        Ok(())
    }

    /// Switches driving / passive / sleeping. A load leaving the driving
    /// state is released (its deformation is kept).
    pub fn set_state(&mut self, id: IconId, state: IconState) -> Result<(), DesignError> {
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        let was = icon.state;
        if was == state {
            return Ok(());
        }
        if was == IconState::Driving {
            self.release(id)?;
        }
        let is_load = self.icons[&id].role == Role::Load;
        if state == IconState::Sleeping || was == IconState::Sleeping || is_load {
            // Waking up or going to sleep: hold the surface as it is now. A
            // load changing state is re-attached where the surface is: it
            // starts driving with no force.
            self.rebase_shape(id);
            let icon = &self.icons[&id];
            let target = self.current_target(icon.role, icon.handle_uv());
            self.icon_mut(id)?.target = target;
        }
        self.icon_mut(id)?.state = state;
        self.problem_dirty = true;
        Ok(())
    }

    /// Sets an icon's target exactly (see [`Icon`] for what it means per role).
    pub fn set_target(&mut self, id: IconId, target: DVec3) -> Result<(), DesignError> {
        if !target.is_finite() {
            return Err(DesignError::NotFinite("target"));
        }
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        Self::check_movable(icon)?;
        let target = if icon.role == Role::Normal {
            target
                .try_normalize()
                .ok_or(DesignError::NotFinite("normal"))?
        } else {
            target
        };
        self.finish_drag_of(id);
        self.icon_mut(id)?.target = target;
        self.problem_dirty = true;
        Ok(())
    }

    /// What a pointer at `xyz` means for the icon's target: a position (or
    /// a load's pull point) directly; for a derivative constraint the vector
    /// from the icon to the pointer; for a normal constraint the direction
    /// from the icon to the pointer.
    fn pointer_target(&self, icon: &Icon, xyz: DVec3) -> DVec3 {
        match icon.role {
            Role::Position | Role::Load => xyz,
            Role::Derivative(_) | Role::Normal => xyz - icon.xyz,
        }
    }

    /// A discrete move of the pointer to `xyz`, solved: a constraint takes
    /// the new target; a load pulls toward `xyz`, the shape is solved and kept
    /// (plastic) and the load is passive again.
    pub fn move_icon(&mut self, id: IconId, xyz: DVec3) -> Result<SolveReport, DesignError> {
        if !xyz.is_finite() {
            return Err(DesignError::NotFinite("xyz"));
        }
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        let target = self.pointer_target(icon, xyz);
        let before = self.snapshot();
        self.set_target(id, target)?;
        if self.icons[&id].role == Role::Load {
            // A load pulls only while driven: drive it for this solve.
            let icon = self.icon_mut(id)?;
            icon.state = IconState::Driving;
        }
        let result = self.solve();
        match result {
            Ok(report) => {
                if self.icons[&id].role == Role::Load {
                    self.bake();
                    self.rebase_shape(id);
                    let was = before
                        .icons
                        .iter()
                        .find(|i| i.id == id)
                        .map_or(IconState::Passive, |i| i.state);
                    let icon = self.icon_mut(id)?;
                    icon.target = icon.handle;
                    icon.state = was;
                    self.problem_dirty = true;
                }
                Ok(report)
            }
            Err(e) => {
                self.restore(&before)?;
                Err(e)
            }
        }
    }

    /// Binds a sensor; the icon becomes driving.
    pub fn bind_sensor(&mut self, id: IconId, sensor: SensorId) -> Result<(), DesignError> {
        let icon = self.icon_mut(id)?;
        if !icon.sensors.contains(&sensor) {
            icon.sensors.push(sensor);
        }
        if icon.state != IconState::Driving {
            icon.state = IconState::Driving;
            if icon.role == Role::Load {
                // Attached where the surface is: it starts with no force.
                self.rebase_shape(id);
                let icon = self.icon_mut(id)?;
                icon.target = icon.handle;
            }
            self.problem_dirty = true;
        }
        Ok(())
    }

    /// Unbinds a sensor; an icon left with none becomes passive (released).
    pub fn unbind_sensor(&mut self, id: IconId, sensor: &SensorId) -> Result<(), DesignError> {
        let icon = self.icon_mut(id)?;
        icon.sensors.retain(|s| s != sensor);
        if icon.sensors.is_empty() && icon.state == IconState::Driving {
            self.release(id)?;
        }
        Ok(())
    }

    /// Sets the material; the next solve refactors (numerically).
    pub fn set_material(&mut self, material: SurfaceMaterial) -> Result<(), DesignError> {
        material.validate()?;
        if let Some(solver) = &mut self.solver {
            let k = Stiffness::surface(self.surface.u_knots(), self.surface.v_knots(), &material)?;
            solver.refactor(k)?;
        }
        self.material = material;
        self.problem_dirty = true;
        Ok(())
    }

    /// Replaces the surface by a refined one of the same shape (knot
    /// insertion), keeping icons; the reference shape is the refined surface.
    pub fn replace_surface(&mut self, surface: BSplineSurface) -> Result<(), DesignError> {
        let mut icons = BTreeMap::new();
        for (id, icon) in &self.icons {
            let mut icon = icon.clone();
            let placed = placement(&icon.anchor, &surface)?;
            icon.samples = placed.samples;
            icon.identity = placed.rows;
            icon.shape = capture(
                &icon.anchor,
                icon.role,
                &icon.samples,
                &icon.identity,
                &surface,
            );
            let (hu, hv) = icon.handle_uv();
            icon.handle = surface.point(hu, hv);
            icons.insert(*id, icon);
        }
        self.drag = None;
        self.reference = surface.points().to_vec();
        self.spring.set_size(surface.area());
        self.surface = surface;
        self.icons = icons;
        self.solver = None;
        self.problem_dirty = true;
        self.revision += 1;
        Ok(())
    }

    /// The current surface tessellated for clients: `samples_u × samples_v`
    /// vertices (each clamped to 2..=4096) with normals, (u,v), mean and
    /// Gaussian curvature (see [`crate::analysis::tessellate`]).
    pub fn tessellate(&self, samples_u: usize, samples_v: usize) -> Tessellation {
        tessellate(
            &self.surface,
            samples_u.clamp(2, 4096),
            samples_v.clamp(2, 4096),
        )
    }

    /// Halves every knot span (knot insertion): the same shape with four
    /// times the control points, for more detail where it is sculpted next.
    pub fn refine(&mut self) -> Result<(), DesignError> {
        let refined = self.surface.refine_uniform()?;
        self.replace_surface(refined)
    }

    /// Inserts one knot along u or v (the shape is unchanged).
    pub fn insert_knot(&mut self, along_u: bool, t: f64) -> Result<(), DesignError> {
        let refined = if along_u {
            self.surface.insert_knot_u(t)?
        } else {
            self.surface.insert_knot_v(t)?
        };
        self.replace_surface(refined)
    }

    /// Re-captures an icon's held shape and handle point from the surface.
    fn rebase_shape(&mut self, id: IconId) {
        let surface = &self.surface;
        if let Some(icon) = self.icons.get_mut(&id) {
            icon.shape = capture(
                &icon.anchor,
                icon.role,
                &icon.samples,
                &icon.identity,
                surface,
            );
            let (hu, hv) = icon.handle_uv();
            icon.handle = surface.point(hu, hv);
        }
    }

    /// The current shape becomes the reference shape (loads lose their pull).
    fn bake(&mut self) {
        self.reference = self.surface.points().to_vec();
        self.problem_dirty = true;
    }

    /// Takes `other`'s solver — its factorisation of the stiffness and the
    /// columns it keeps — when this design has none yet and both have the
    /// same knots and material (so the same stiffness K): a host that
    /// builds a design afresh from a stored state (undo, redo, restore)
    /// then pays, at its next solve, only what differs between the two
    /// problems (the solver's incremental paths) instead of a
    /// factorisation and every column. `other` is left without a solver
    /// (its next solve factors afresh). Returns whether it was taken.
    pub fn adopt_solver(&mut self, other: &mut Design) -> bool {
        let same = self.solver.is_none()
            && other.solver.is_some()
            && self.material == other.material
            && self.surface.u_knots() == other.surface.u_knots()
            && self.surface.v_knots() == other.surface.v_knots();
        if same {
            self.solver = other.solver.take();
            self.problem_dirty = true;
        }
        same
    }

    /// Whether a change of the pinned control points (a region or edge
    /// icon added, removed or switched) is answered through the factor of
    /// an earlier pinned set (see [`Solver::settle_pins`]): exact, but each
    /// full solve costs a few refinement solves more until settled.
    pub fn pins_pending(&self) -> bool {
        self.solver.as_ref().is_some_and(Solver::pins_pending)
    }

    /// The deferred half of a pin change: refactors the stiffness for the
    /// current pinned set (a numeric refactorisation, ~45 ms at 81 × 159)
    /// when one is pending — for a host to call when idle (between grabs),
    /// off the path of the edit itself. The shape does not change.
    /// `Ok(false)` when nothing was pending.
    pub fn settle_pins(&mut self) -> Result<bool, DesignError> {
        if self.solver.is_none() {
            return Ok(false);
        }
        Ok(self.ensure_solver()?.settle_pins()?)
    }

    fn ensure_solver(&mut self) -> Result<&mut Solver, DesignError> {
        if self.solver.is_none() {
            let k = Stiffness::surface(
                self.surface.u_knots(),
                self.surface.v_knots(),
                &self.material,
            )?;
            self.solver = Some(Solver::new(k)?);
            self.problem_dirty = true;
        }
        if self.problem_dirty {
            let problem = self.problem();
            if let Some(solver) = self.solver.as_mut() {
                solver.set_problem(problem)?;
            }
            self.built_k = self.spring.stiffness();
            self.problem_dirty = false;
        }
        self.solver
            .as_mut()
            .ok_or(DesignError::Unsupported("no solver".into()))
    }

    /// The problem of every active icon (the dragged one at its drag origin).
    pub fn problem(&self) -> Problem {
        let k = self.spring.stiffness();
        Problem {
            groups: self
                .icons
                .values()
                .filter_map(|icon| {
                    let base = match self.drag {
                        Some(d) if d.id == icon.id => d.origin,
                        _ => icon.target,
                    };
                    icon_group(icon, base, &self.surface, k)
                })
                .collect(),
        }
    }

    /// Solves for the shape under every active icon (including the current
    /// drag) and re-places the icons on the surface.
    pub fn solve(&mut self) -> Result<SolveReport, DesignError> {
        self.solve_own()
    }

    /// [`Self::solve`] through `backend` when given (a design solved jointly
    /// with others, [`crate::product`]), else through the design's own solver.
    pub(crate) fn solve_via(
        &mut self,
        backend: Option<&mut (dyn SolveBackend + '_)>,
    ) -> Result<SolveReport, DesignError> {
        let Some(backend) = backend else {
            return self.solve_own();
        };
        let changed = self.problem_dirty;
        if changed {
            self.built_k = self.spring.stiffness();
        }
        let scale = match self.drag {
            Some(a) if self.icons.get(&a.id).is_some_and(|i| i.role == Role::Load) => {
                self.spring.stiffness() / self.built_k
            }
            _ => 1.0,
        };
        let drag = self.drag.map(|d| (d.id.0, d.t * scale));
        let mut out = std::mem::take(&mut self.scratch);
        out.resize(self.reference.len(), DVec3::ZERO);
        let result = backend.solve(self, changed, drag, &mut out);
        let report = match result {
            Ok(r) => r,
            Err(e) => {
                self.scratch = out;
                return Err(e);
            }
        };
        self.problem_dirty = false;
        std::mem::swap(self.surface.points_mut_vec(), &mut out);
        self.scratch = out;
        self.replace_icons();
        self.revision += 1;
        Ok(report)
    }

    /// Takes control points solved elsewhere (a joint solve of joined
    /// parts, [`crate::product`]; finite, as every solver output) and
    /// re-places the icons.
    pub(crate) fn adopt_points(&mut self, points: &[DVec3]) -> Result<(), DesignError> {
        if points.len() != self.surface.points().len() {
            return Err(DesignError::Solve(SolveError::Size {
                expected: self.surface.points().len(),
                got: points.len(),
            }));
        }
        // A joint solve's output is finite (the solver checks its inputs):
        // no second pass over the points on every drag frame.
        self.surface.points_mut().copy_from_slice(points);
        self.replace_icons();
        self.revision += 1;
        Ok(())
    }

    /// The current shape becomes the reference shape (see [`Self::release`]):
    /// a joint solve's result kept as the parts' rest shape, or a host's
    /// edit applied in place as a rebuild from the shape would see it (a
    /// design built from its control points has them as its reference).
    /// Costs no refactor. Does nothing when the shape is the reference to
    /// round-off (every control point within 1e-13 of the shape's extent),
    /// so a solver that proved the last answer optimal for this reference
    /// keeps that proof.
    pub fn keep_shape(&mut self) {
        let points = self.surface.points();
        let extent = points
            .iter()
            .fold(0.0_f64, |m, p| m.max(p.abs().max_element()));
        let off = self
            .reference
            .iter()
            .zip(points)
            .fold(0.0_f64, |m, (r, p)| m.max((*r - *p).abs().max_element()));
        if off > 1e-13 * extent.max(f64::MIN_POSITIVE) || !off.is_finite() {
            self.bake();
        }
    }

    /// Folds a running drag into its icon's target (the icon stays
    /// driving): another part of the same joint group is grabbed.
    pub(crate) fn finish_drag(&mut self) {
        if let Some(d) = self.drag {
            self.finish_drag_of(d.id);
        }
    }

    /// The running drag's icon key and input t (unscaled: what a problem
    /// built now, with the spring's current stiffness, needs).
    pub(crate) fn drag_input(&self) -> Option<(u64, DVec3)> {
        self.drag.map(|d| (d.id.0, d.t))
    }

    /// The next solve rebuilds the problem (the design joined or left a
    /// group solved elsewhere, so its own solver's problem may be stale).
    pub(crate) fn mark_problem_dirty(&mut self) {
        self.problem_dirty = true;
    }

    fn solve_own(&mut self) -> Result<SolveReport, DesignError> {
        let drag = self.drag;
        let load_scale = |d: &Design| -> f64 {
            match d.drag {
                Some(a) if d.icons.get(&a.id).is_some_and(|i| i.role == Role::Load) => {
                    d.spring.stiffness() / d.built_k
                }
                _ => 1.0,
            }
        };
        let reference = std::mem::take(&mut self.reference);
        let mut out = std::mem::take(&mut self.scratch);
        out.resize(reference.len(), DVec3::ZERO);
        let ready = self.ensure_solver().map(|_| ());
        let scale = load_scale(self);
        let result = ready.and_then(|()| {
            let solver = self
                .solver
                .as_mut()
                .ok_or(DesignError::Unsupported("no solver".into()))?;
            Ok(match drag {
                Some(d) => solver.drag(d.id.0, d.t * scale, &reference, &mut out)?,
                None => solver.solve(&reference, &mut out)?,
            })
        });
        self.reference = reference;
        let report = match result {
            Ok(r) => r,
            Err(e) => {
                self.scratch = out;
                return Err(e);
            }
        };
        // The solver's output is finite (its inputs are validated): swap it in.
        std::mem::swap(self.surface.points_mut_vec(), &mut out);
        self.scratch = out;
        self.replace_icons();
        self.revision += 1;
        Ok(report)
    }

    /// Every icon's position (the surface point at its handle) on the
    /// solved surface; allocation-free, it runs on every drag frame.
    fn replace_icons(&mut self) {
        let surface = &self.surface;
        let (bu, bv) = &mut self.basis;
        for icon in self.icons.values_mut() {
            let (u, v) = icon.anchor.handle_uv();
            basis_derivs_into(surface.u_knots(), u, 0, bu);
            basis_derivs_into(surface.v_knots(), v, 0, bv);
            icon.xyz = surface.combine(bu, bv, 0).p;
        }
    }

    /// The drag fast path's cached basis `(start, ρ)` of this design's own
    /// solver (see [`Solver::drag_basis`]); `None` when there is none or the
    /// response is coupled. Read-only: the caller checks that the current
    /// shape is `start + ρ·t` for some `t` before relying on it.
    pub fn drag_basis(&self) -> Option<(&[DVec3], &[f64])> {
        self.solver.as_ref()?.drag_basis()
    }

    /// Grabs an icon: it becomes driving; its drag starts from its current
    /// target (for a load: from where its spring is attached).
    pub fn drag_start(&mut self, id: IconId) -> Result<(), DesignError> {
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        if self.dragging() == Some(id) {
            return Ok(());
        }
        Self::check_movable(icon)?;
        if let Some(other) = self.dragging() {
            self.finish_drag_of(other);
        }
        if self.icons[&id].role == Role::Load {
            // Attach the spring where the surface is now: no jump at the grab.
            self.rebase_shape(id);
            let icon = self.icon_mut(id)?;
            icon.target = icon.handle;
        }
        let origin = self.icons[&id].target;
        let grabbed_at = self.icons[&id].xyz;
        let icon = self.icon_mut(id)?;
        icon.state = IconState::Driving;
        self.drag = Some(ActiveDrag {
            id,
            origin,
            t: DVec3::ZERO,
            grabbed_at,
        });
        self.problem_dirty = true;
        Ok(())
    }

    /// Folds a running drag of `id` into its target (the drag goes on from there).
    fn finish_drag_of(&mut self, id: IconId) {
        if let Some(d) = self.drag
            && d.id == id
        {
            if let Some(icon) = self.icons.get_mut(&id) {
                icon.target = d.origin + d.t;
            }
            self.drag = None;
            self.problem_dirty = true;
        }
    }

    /// A drag frame: the pointer holding `id` is at `xyz`. Answered from the
    /// solver's precomputed columns (no factorisation, no sparse solve) unless
    /// the icon is a normal constraint, whose direction enters S.
    pub fn drag(&mut self, id: IconId, xyz: DVec3) -> Result<DragReport, DesignError> {
        self.drag_via(id, xyz, None)
    }

    /// [`Self::drag`], solved through `backend` when given.
    pub(crate) fn drag_via(
        &mut self,
        id: IconId,
        xyz: DVec3,
        mut backend: Option<&mut dyn SolveBackend>,
    ) -> Result<DragReport, DesignError> {
        if !xyz.is_finite() {
            return Err(DesignError::NotFinite("xyz"));
        }
        if self.dragging() != Some(id) {
            self.drag_start(id)?;
        }
        let icon = &self.icons[&id];
        let target = self.pointer_target(icon, xyz);
        let Some(mut d) = self.drag else {
            return Err(DesignError::Unsupported("no drag".into()));
        };
        if icon.role == Role::Normal {
            self.finish_drag_of(id);
            self.icon_mut(id)?.target = target
                .try_normalize()
                .ok_or(DesignError::NotFinite("normal"))?;
            self.drag_start(id)?;
            let report = self.solve_via(backend.as_deref_mut())?;
            let actual = self.icons[&id].xyz;
            return Ok(DragReport {
                report,
                requested: xyz,
                actual,
            });
        }
        let previous = d.t;
        d.t = target - d.origin;
        self.drag = Some(d);
        let report = match self.solve_via(backend.as_deref_mut()) {
            Ok(r) => r,
            Err(e) => {
                d.t = previous;
                self.drag = Some(d);
                return Err(e);
            }
        };
        self.icon_mut(id)?.target = target;
        let mut report = report;
        let mut actual = self.icons[&id].xyz;
        if self.adaptive && self.icons[&id].role == Role::Load {
            // Paper 003's loop, inside the frame: a load's pull is linear in
            // κ, so re-solving with a new κ is a rescaled drag input — the
            // fast path again, no new columns. It runs until the ratio is in
            // the band, κ is at a bound, or SPRING_STEPS steps.
            for _ in 0..SPRING_STEPS {
                let dx = (xyz - d.grabbed_at).length();
                let dy = (actual - d.grabbed_at).length();
                if !matches!(
                    self.spring.adapt(dx, dy),
                    Adaptation::Raised | Adaptation::Lowered
                ) {
                    break;
                }
                report = self.solve_via(backend.as_deref_mut())?;
                actual = self.icons[&id].xyz;
            }
        }
        Ok(DragReport {
            report,
            requested: xyz,
            actual,
        })
    }

    /// Releases a driven icon: it becomes passive and the shape is kept — a
    /// load's deformation is baked into the reference shape; a constraint
    /// keeps its dragged target.
    pub fn release(&mut self, id: IconId) -> Result<(), DesignError> {
        let role = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .role;
        self.finish_drag_of(id);
        if role == Role::Load {
            self.bake();
            self.rebase_shape(id);
            let icon = self.icon_mut(id)?;
            icon.target = icon.handle;
        }
        let icon = self.icon_mut(id)?;
        if icon.state == IconState::Driving {
            icon.state = IconState::Passive;
        }
        icon.sensors.clear();
        self.problem_dirty = true;
        Ok(())
    }
}
