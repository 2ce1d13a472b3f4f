//! A deformable B-spline curve sculpted by icons — the batten of spline
//! lofting, and paper 003's curve sculpting. Point icons (load, position, R,
//! R2) act at one parameter; interval icons (load, position) along a span of
//! the curve, as curve icons do on a surface: a constraint keeps the span's
//! shape (moved rigidly by its target), a load pulls the whole span. The same solver and the
//! same semantics as [`crate::design::Design`] (plastic loads, passive
//! constraints holding, sleeping icons inert and re-placed), with the curve
//! energy ∫ α|w_u|² + β|w_uu|² of the displacement from a reference curve.
//! A curve design is a value too: [`CurveDesign::snapshot`] and
//! [`CurveDesign::restore`] serve undo, redo and commit as for surfaces.

use std::collections::BTreeMap;

use glam::DVec3;

use crate::bspline::BSplineCurve;
use crate::design::DesignError;
use crate::energy::{CurveMaterial, Stiffness};
use crate::icon::{IconId, IconState, SensorId, centroid, curve_row};
use crate::solve::{Equation, Group, Load, Problem, SolveReport, Solver};
use crate::spring::{Adaptation, Spring};

/// What a curve icon does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CurveRole {
    /// A load pulled by a spring.
    Load,
    /// The curve passes through the target.
    Position,
    /// The first derivative (R) equals the target.
    Tangent,
    /// The second derivative (R2) equals the target.
    Second,
}

/// An icon on a curve at parameter `t`, or along the span `span`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveIcon {
    /// Its id.
    pub id: IconId,
    /// Its parameter on the curve (an interval icon's middle).
    pub t: f64,
    /// An interval icon's parameter range; `None` for a point icon.
    pub span: Option<(f64, f64)>,
    /// The parameters it acts at: `[t]`, or samples along the span.
    pub samples: Vec<f64>,
    /// The curve at `samples` when the icon last took hold: a constraint
    /// keeps this shape, moved by `target − centroid(shape)`.
    pub shape: Vec<DVec3>,
    /// What it does.
    pub role: CurveRole,
    /// Driving, passive or sleeping.
    pub state: IconState,
    /// Position (of the shape's centroid), derivative vector or a load's
    /// pull point.
    pub target: DVec3,
    /// Its position on the curve (the centroid of its samples), recomputed
    /// after every solve.
    pub xyz: DVec3,
    /// A load's attachment point (the shape's centroid).
    pub attach: DVec3,
    /// The device sensors driving it.
    pub sensors: Vec<SensorId>,
}

/// A curve design as a value: everything that makes it, nothing cached.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveDesignSnapshot {
    /// The current curve.
    pub curve: BSplineCurve,
    /// The reference shape (control points) the energy is measured from.
    pub reference: Vec<DVec3>,
    /// The material.
    pub material: CurveMaterial,
    /// The icons, by id.
    pub icons: Vec<CurveIcon>,
    /// The next icon id.
    pub next_id: u64,
    /// The spring coefficient κ.
    pub kappa: f64,
}

/// A sculptable curve.
#[derive(Debug)]
pub struct CurveDesign {
    curve: BSplineCurve,
    reference: Vec<DVec3>,
    material: CurveMaterial,
    icons: BTreeMap<IconId, CurveIcon>,
    next_id: u64,
    spring: Spring,
    solver: Option<Solver>,
    dirty: bool,
    drag: Option<(IconId, DVec3, DVec3)>,
}

impl CurveDesign {
    /// A design of `curve` with `material`; the curve is its own reference.
    pub fn new(curve: BSplineCurve, material: CurveMaterial) -> Result<Self, DesignError> {
        material.validate()?;
        let len = curve.length();
        Ok(Self {
            reference: curve.points().to_vec(),
            spring: Spring::new(10.0, if len > 0.0 { len } else { 1.0 })
                .map_err(|e| DesignError::Unsupported(e.0))?,
            curve,
            material,
            icons: BTreeMap::new(),
            next_id: 1,
            solver: None,
            dirty: true,
            drag: None,
        })
    }

    /// A design from a snapshot (its icons must lie on the curve).
    pub fn from_snapshot(s: &CurveDesignSnapshot) -> Result<Self, DesignError> {
        let mut d = Self::new(s.curve.clone(), s.material)?;
        if s.reference.len() != s.curve.points().len() || s.reference.iter().any(|p| !p.is_finite())
        {
            return Err(DesignError::NotFinite("reference shape"));
        }
        d.reference = s.reference.clone();
        d.spring =
            Spring::new(s.kappa, d.spring.size()).map_err(|e| DesignError::Unsupported(e.0))?;
        d.next_id = s.next_id;
        for icon in &s.icons {
            if let Some(&t) = std::iter::once(&icon.t)
                .chain(&icon.samples)
                .find(|&&t| !d.curve.knots().contains(t))
            {
                return Err(DesignError::OutOfDomain(t, 0.0));
            }
            if !(icon.target.is_finite()
                && icon.attach.is_finite()
                && icon.shape.iter().all(|p| p.is_finite()))
            {
                return Err(DesignError::NotFinite("icon"));
            }
            if icon.samples.is_empty() || icon.shape.len() != icon.samples.len() {
                return Err(DesignError::Unsupported(format!(
                    "icon {:?}: shape does not match its samples",
                    icon.id
                )));
            }
            d.next_id = d.next_id.max(icon.id.0 + 1);
            let mut icon = icon.clone();
            icon.xyz = centroid_on(&d.curve, &icon.samples);
            d.icons.insert(icon.id, icon);
        }
        Ok(d)
    }

    /// The design as a value.
    pub fn snapshot(&self) -> CurveDesignSnapshot {
        let mut icons: Vec<CurveIcon> = self.icons.values().cloned().collect();
        // A running drag is part of the value: its icon's target is where
        // the pointer is.
        if let Some((id, origin, t)) = self.drag
            && let Some(i) = icons.iter_mut().find(|i| i.id == id)
            && i.role != CurveRole::Load
        {
            i.target = origin + t;
        }
        CurveDesignSnapshot {
            curve: self.curve.clone(),
            reference: self.reference.clone(),
            material: self.material,
            icons,
            next_id: self.next_id,
            kappa: self.spring.kappa(),
        }
    }

    /// Replaces the design by `snapshot` (undo, redo, revert). The
    /// factorisation is kept when knots and material are unchanged. On
    /// error nothing changes.
    pub fn restore(&mut self, snapshot: &CurveDesignSnapshot) -> Result<(), DesignError> {
        let mut next = Self::from_snapshot(snapshot)?;
        if next.curve.knots() == self.curve.knots() && next.material == self.material {
            next.solver = self.solver.take();
        }
        *self = next;
        Ok(())
    }

    /// The current curve.
    pub fn curve(&self) -> &BSplineCurve {
        &self.curve
    }

    /// The reference curve's control points.
    pub fn reference(&self) -> &[DVec3] {
        &self.reference
    }

    /// Every icon, by id.
    pub fn icons(&self) -> impl Iterator<Item = &CurveIcon> {
        self.icons.values()
    }

    /// One icon.
    pub fn icon(&self, id: IconId) -> Option<&CurveIcon> {
        self.icons.get(&id)
    }

    /// The spring model.
    pub fn spring(&self) -> &Spring {
        &self.spring
    }

    /// Sets κ directly.
    pub fn set_kappa(&mut self, kappa: f64) -> Result<(), DesignError> {
        self.spring =
            Spring::new(kappa, self.spring.size()).map_err(|e| DesignError::Unsupported(e.0))?;
        self.dirty = true;
        Ok(())
    }

    /// The parameters an icon acts at: `[t]`, or uniform samples of the span
    /// (one per knot span it crosses, plus one; 2 to 48).
    fn samples_of(&self, t: f64, span: Option<(f64, f64)>) -> Result<Vec<f64>, DesignError> {
        let inside = |t: f64| t.is_finite() && self.curve.knots().contains(t);
        let Some((a, b)) = span else {
            return if inside(t) {
                Ok(vec![t])
            } else {
                Err(DesignError::OutOfDomain(t, 0.0))
            };
        };
        if let Some(bad) = [a, b].into_iter().find(|&x| !inside(x)) {
            return Err(DesignError::OutOfDomain(bad, 0.0));
        }
        if b - a < 1e-9 {
            return Err(DesignError::Degenerate("interval has no length"));
        }
        let (t0, t1) = self.curve.domain();
        let spans = self.curve.knots().spans().len().max(1) as f64;
        let n = (((b - a) / (t1 - t0) * spans).ceil() as usize + 1).clamp(2, 48);
        Ok((0..n)
            .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
            .collect())
    }

    /// What `role` holds at an icon now: the centroid of `shape` for a
    /// position or load, the derivative at `t` otherwise.
    fn current(&self, role: CurveRole, t: f64, shape: &[DVec3]) -> DVec3 {
        match role {
            CurveRole::Load | CurveRole::Position => centroid(shape),
            CurveRole::Tangent => self.curve.derivs(t).d1,
            CurveRole::Second => self.curve.derivs(t).d2,
        }
    }

    /// Makes `id` hold (or pull from) the curve as it is now: shape,
    /// attachment and target from the current curve.
    fn take_hold(&mut self, id: IconId) {
        let Some(icon) = self.icons.get(&id) else {
            return;
        };
        let shape: Vec<DVec3> = icon.samples.iter().map(|&t| self.curve.point(t)).collect();
        let target = self.current(icon.role, icon.t, &shape);
        if let Some(icon) = self.icons.get_mut(&id) {
            icon.attach = centroid(&shape);
            icon.xyz = icon.attach;
            icon.target = target;
            icon.shape = shape;
        }
    }

    fn check_role(span: Option<(f64, f64)>, role: CurveRole) -> Result<(), DesignError> {
        if span.is_some() && matches!(role, CurveRole::Tangent | CurveRole::Second) {
            return Err(DesignError::Unsupported(
                "derivative constraints need a point icon".into(),
            ));
        }
        Ok(())
    }

    fn insert(
        &mut self,
        t: f64,
        span: Option<(f64, f64)>,
        role: CurveRole,
    ) -> Result<IconId, DesignError> {
        Self::check_role(span, role)?;
        let samples = self.samples_of(t, span)?;
        let id = IconId(self.next_id);
        self.next_id += 1;
        self.icons.insert(
            id,
            CurveIcon {
                id,
                t,
                span,
                samples,
                shape: Vec::new(),
                role,
                state: IconState::Passive,
                target: DVec3::ZERO,
                xyz: DVec3::ZERO,
                attach: DVec3::ZERO,
                sensors: Vec::new(),
            },
        );
        self.take_hold(id);
        self.dirty = true;
        Ok(id)
    }

    /// Adds a point icon at `t`; its target is the curve's current value.
    pub fn add_icon(&mut self, t: f64, role: CurveRole) -> Result<IconId, DesignError> {
        self.insert(t, None, role)
    }

    /// Adds an interval icon along `[t0, t1]` (a position constraint that
    /// keeps the span's shape, or a load that pulls the whole span); it
    /// starts from the curve as it is.
    pub fn add_interval(
        &mut self,
        t0: f64,
        t1: f64,
        role: CurveRole,
    ) -> Result<IconId, DesignError> {
        let (a, b) = (t0.min(t1), t0.max(t1));
        self.insert(0.5 * (a + b), Some((a, b)), role)
    }

    /// Deletes an icon (ending its drag).
    pub fn remove_icon(&mut self, id: IconId) -> Result<CurveIcon, DesignError> {
        let icon = self.icons.remove(&id).ok_or(DesignError::UnknownIcon(id))?;
        if self.drag.is_some_and(|d| d.0 == id) {
            self.drag = None;
        }
        self.dirty = true;
        Ok(icon)
    }

    /// Moves an icon along the curve so that its parameter (an interval's
    /// middle) is `t`; it then holds (or pulls from) the curve as it is there.
    pub fn set_parameter(&mut self, id: IconId, t: f64) -> Result<(), DesignError> {
        if !t.is_finite() {
            return Err(DesignError::OutOfDomain(t, 0.0));
        }
        let icon = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?;
        let span = icon.span.map(|(a, b)| (a + t - icon.t, b + t - icon.t));
        let samples = self.samples_of(t, span)?;
        self.finish_drag_of(id);
        if let Some(icon) = self.icons.get_mut(&id) {
            icon.t = t;
            icon.span = span;
            icon.samples = samples;
        }
        self.take_hold(id);
        self.dirty = true;
        Ok(())
    }

    /// Folds a running drag of `id` into its target.
    fn finish_drag_of(&mut self, id: IconId) {
        if let Some((d, origin, t)) = self.drag
            && d == id
        {
            self.drag = None;
            if let Some(i) = self.icons.get_mut(&id) {
                i.target = origin + t;
            }
            self.dirty = true;
        }
    }

    /// Binds a sensor; the icon becomes driving.
    pub fn bind_sensor(&mut self, id: IconId, sensor: SensorId) -> Result<(), DesignError> {
        let icon = self
            .icons
            .get_mut(&id)
            .ok_or(DesignError::UnknownIcon(id))?;
        if !icon.sensors.contains(&sensor) {
            icon.sensors.push(sensor);
        }
        if icon.state != IconState::Driving {
            icon.state = IconState::Driving;
            self.dirty = true;
        }
        Ok(())
    }

    /// Unbinds a sensor; an icon left with none is released (passive).
    pub fn unbind_sensor(&mut self, id: IconId, sensor: &SensorId) -> Result<(), DesignError> {
        let icon = self
            .icons
            .get_mut(&id)
            .ok_or(DesignError::UnknownIcon(id))?;
        icon.sensors.retain(|s| s != sensor);
        if icon.sensors.is_empty() && icon.state == IconState::Driving {
            self.release(id)?;
        }
        Ok(())
    }

    /// Switches an icon's role; it starts from the curve as it is.
    pub fn set_role(&mut self, id: IconId, role: CurveRole) -> Result<(), DesignError> {
        let span = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .span;
        Self::check_role(span, role)?;
        self.finish_drag_of(id);
        if let Some(icon) = self.icons.get_mut(&id) {
            icon.role = role;
        }
        self.take_hold(id);
        self.dirty = true;
        Ok(())
    }

    /// Switches an icon's state, with the paper's semantics: an icon
    /// leaving the driving state is released (a load's pull is kept as
    /// shape); going to sleep or waking up, it holds the curve as it is now.
    pub fn set_state(&mut self, id: IconId, state: IconState) -> Result<(), DesignError> {
        let was = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .state;
        if was == state {
            return Ok(());
        }
        if was == IconState::Driving {
            self.release(id)?;
        }
        if state == IconState::Sleeping || was == IconState::Sleeping {
            self.take_hold(id);
        }
        if let Some(icon) = self.icons.get_mut(&id) {
            icon.state = state;
        }
        self.dirty = true;
        Ok(())
    }

    /// Sets an icon's target exactly.
    pub fn set_target(&mut self, id: IconId, target: DVec3) -> Result<(), DesignError> {
        if !target.is_finite() {
            return Err(DesignError::NotFinite("target"));
        }
        self.icons
            .get_mut(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .target = target;
        self.dirty = true;
        Ok(())
    }

    fn problem(&self) -> Problem {
        let k = self.spring.stiffness();
        let groups = self
            .icons
            .values()
            .filter(|i| i.state != IconState::Sleeping)
            .map(|i| {
                let base = match self.drag {
                    Some((id, origin, _)) if id == i.id => origin,
                    _ => i.target,
                };
                let mut g = Group {
                    key: i.id.0,
                    ..Group::default()
                };
                // A span shares its pull, or keeps its shape moved rigidly.
                let share = 1.0 / i.samples.len().max(1) as f64;
                let shift = base - centroid(&i.shape);
                match i.role {
                    CurveRole::Load => {
                        for &t in &i.samples {
                            g.loads.push(Load {
                                row: curve_row(&self.curve, t, 0),
                                force: (base - i.attach) * k * share,
                                drag_gain: k * share,
                            });
                        }
                    }
                    CurveRole::Position => {
                        for (&t, &p) in i.samples.iter().zip(&i.shape) {
                            g.equations.push(Equation::Vector {
                                row: curve_row(&self.curve, t, 0),
                                target: p + shift,
                            });
                        }
                    }
                    CurveRole::Tangent => g.equations.push(Equation::Vector {
                        row: curve_row(&self.curve, i.t, 1),
                        target: base,
                    }),
                    CurveRole::Second => g.equations.push(Equation::Vector {
                        row: curve_row(&self.curve, i.t, 2),
                        target: base,
                    }),
                }
                g
            })
            .collect();
        Problem { groups }
    }

    /// Solves under every active icon (and the running drag), re-placing icons.
    pub fn solve(&mut self) -> Result<SolveReport, DesignError> {
        if self.solver.is_none() {
            self.solver = Some(Solver::new(Stiffness::curve(
                self.curve.knots(),
                &self.material,
            )?)?);
            self.dirty = true;
        }
        if self.dirty {
            let problem = self.problem();
            if let Some(s) = self.solver.as_mut() {
                s.set_problem(problem)?;
            }
            self.dirty = false;
        }
        let solver = self
            .solver
            .as_mut()
            .ok_or(DesignError::Unsupported("no solver".into()))?;
        let mut out = vec![DVec3::ZERO; self.reference.len()];
        let report = match self.drag {
            Some((id, _, t)) => solver.drag(id.0, t, &self.reference, &mut out)?,
            None => solver.solve(&self.reference, &mut out)?,
        };
        self.curve.points_mut().copy_from_slice(&out);
        let curve = &self.curve;
        for icon in self.icons.values_mut() {
            icon.xyz = centroid_on(curve, &icon.samples);
        }
        Ok(report)
    }

    /// A drag frame: the pointer holding `id` is at `xyz` (a constraint takes
    /// it as its target, a load pulls toward it). The spring adapts for loads.
    pub fn drag(&mut self, id: IconId, xyz: DVec3) -> Result<DVec3, DesignError> {
        if !xyz.is_finite() {
            return Err(DesignError::NotFinite("xyz"));
        }
        let icon = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .clone();
        if self.drag.map(|d| d.0) != Some(id) {
            if let Some((other, origin, t)) = self.drag.take()
                && let Some(o) = self.icons.get_mut(&other)
            {
                o.target = origin + t;
            }
            let origin = if icon.role == CurveRole::Load {
                icon.attach
            } else {
                icon.target
            };
            self.drag = Some((id, origin, DVec3::ZERO));
            if let Some(i) = self.icons.get_mut(&id) {
                i.state = IconState::Driving;
            }
            self.dirty = true;
        }
        let Some((_, origin, _)) = self.drag else {
            return Err(DesignError::Unsupported("no drag".into()));
        };
        let target = match icon.role {
            CurveRole::Load | CurveRole::Position => xyz,
            CurveRole::Tangent | CurveRole::Second => xyz - icon.xyz,
        };
        self.drag = Some((id, origin, target - origin));
        self.solve()?;
        let actual = self.icons.get(&id).map_or(icon.xyz, |i| i.xyz);
        if icon.role == CurveRole::Load {
            let (dx, dy) = (
                (xyz - icon.attach).length(),
                (actual - icon.attach).length(),
            );
            if matches!(
                self.spring.adapt(dx, dy),
                Adaptation::Raised | Adaptation::Lowered
            ) {
                self.dirty = true;
            }
        }
        Ok(actual)
    }

    /// Releases a driven icon: passive, shape kept (a load's deformation is
    /// baked into the reference curve).
    pub fn release(&mut self, id: IconId) -> Result<(), DesignError> {
        let role = self
            .icons
            .get(&id)
            .ok_or(DesignError::UnknownIcon(id))?
            .role;
        self.finish_drag_of(id);
        if role == CurveRole::Load {
            self.reference = self.curve.points().to_vec();
        }
        if role == CurveRole::Load {
            self.take_hold(id);
        }
        if let Some(i) = self.icons.get_mut(&id) {
            if i.state == IconState::Driving {
                i.state = IconState::Passive;
            }
            i.sensors.clear();
        }
        self.dirty = true;
        Ok(())
    }
}

/// The centroid of `curve` at the parameters `samples`.
fn centroid_on(curve: &BSplineCurve, samples: &[f64]) -> DVec3 {
    centroid(&samples.iter().map(|&t| curve.point(t)).collect::<Vec<_>>())
}
