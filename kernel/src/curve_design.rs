//! A deformable B-spline curve sculpted by point icons — the batten of
//! spline lofting, and paper 003's curve sculpting. The same solver and the
//! same semantics as [`crate::design::Design`] (plastic loads, passive
//! constraints holding, sleeping icons inert and re-placed), with the curve
//! energy ∫ α|w_u|² + β|w_uu|² of the displacement from a reference curve.

use std::collections::BTreeMap;

use glam::DVec3;

use crate::bspline::BSplineCurve;
use crate::design::DesignError;
use crate::energy::{CurveMaterial, Stiffness};
use crate::icon::{IconId, IconState, curve_row};
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

/// An icon on a curve at parameter `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveIcon {
    /// Its id.
    pub id: IconId,
    /// Its parameter on the curve.
    pub t: f64,
    /// What it does.
    pub role: CurveRole,
    /// Driving, passive or sleeping.
    pub state: IconState,
    /// Position, derivative vector or a load's pull point.
    pub target: DVec3,
    /// Its position on the curve, recomputed after every solve.
    pub xyz: DVec3,
    /// A load's attachment point.
    pub attach: DVec3,
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

    /// The current curve.
    pub fn curve(&self) -> &BSplineCurve {
        &self.curve
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

    fn current(&self, role: CurveRole, t: f64) -> DVec3 {
        let d = self.curve.derivs(t);
        match role {
            CurveRole::Load | CurveRole::Position => d.p,
            CurveRole::Tangent => d.d1,
            CurveRole::Second => d.d2,
        }
    }

    /// Adds an icon at `t`; its target is the curve's current value.
    pub fn add_icon(&mut self, t: f64, role: CurveRole) -> Result<IconId, DesignError> {
        if !self.curve.knots().contains(t) {
            return Err(DesignError::OutOfDomain(t, 0.0));
        }
        let id = IconId(self.next_id);
        self.next_id += 1;
        let p = self.curve.point(t);
        self.icons.insert(
            id,
            CurveIcon {
                id,
                t,
                role,
                state: IconState::Passive,
                target: self.current(role, t),
                xyz: p,
                attach: p,
            },
        );
        self.dirty = true;
        Ok(id)
    }

    /// Switches an icon's role; it starts from the curve as it is.
    pub fn set_role(&mut self, id: IconId, role: CurveRole) -> Result<(), DesignError> {
        let t = self.icons.get(&id).ok_or(DesignError::UnknownIcon(id))?.t;
        let target = self.current(role, t);
        let p = self.curve.point(t);
        let icon = self
            .icons
            .get_mut(&id)
            .ok_or(DesignError::UnknownIcon(id))?;
        icon.role = role;
        icon.target = target;
        icon.attach = p;
        self.dirty = true;
        Ok(())
    }

    /// Switches an icon's state.
    pub fn set_state(&mut self, id: IconId, state: IconState) -> Result<(), DesignError> {
        let icon = self
            .icons
            .get_mut(&id)
            .ok_or(DesignError::UnknownIcon(id))?;
        icon.state = state;
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
                match i.role {
                    CurveRole::Load => g.loads.push(Load {
                        row: curve_row(&self.curve, i.t, 0),
                        force: (base - i.attach) * k,
                        drag_gain: k,
                    }),
                    CurveRole::Position => g.equations.push(Equation::Vector {
                        row: curve_row(&self.curve, i.t, 0),
                        target: base,
                    }),
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
        for icon in self.icons.values_mut() {
            icon.xyz = self.curve.point(icon.t);
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
        let actual = self.curve.point(icon.t);
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
        if let Some((d, origin, t)) = self.drag
            && d == id
        {
            self.drag = None;
            if let Some(i) = self.icons.get_mut(&id) {
                i.target = origin + t;
            }
        }
        if role == CurveRole::Load {
            self.reference = self.curve.points().to_vec();
        }
        let p = self.curve.point(self.icons[&id].t);
        if let Some(i) = self.icons.get_mut(&id) {
            i.state = IconState::Passive;
            if role == CurveRole::Load {
                i.attach = p;
                i.target = p;
            }
        }
        self.dirty = true;
        Ok(())
    }
}
