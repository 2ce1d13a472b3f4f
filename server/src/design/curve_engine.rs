//! The kernel side of a curve part: a `vsculpt_kernel::curve_design::
//! CurveDesign` (paper 003, eq. 1: a deformable B-spline curve sculpted by
//! the same icons as a surface) built from a [`CurvePart`], driven by drags
//! and read back. Icons sit at a parameter (`param`) or along a stretch
//! (`span`); their roles are load, position, and the first (R) or second
//! (R2) derivative.

use super::doc::{AnchorDoc, DerivativeDoc, IconRoleDoc, IconStateDoc};
use super::edit::SurfaceQuery;
use super::engine::{
    IconReadback, SPRING_BAND, SPRING_ITERATIONS, kernel_error, state, state_back,
};
use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use super::part::{CurveMaterialDoc, CurvePart};
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_kernel::curve_design::{CurveDesign, CurveRole};
use vsculpt_kernel::energy::CurveMaterial;
use vsculpt_kernel::icon::{IconId, IconState, SensorId};

/// A curve part's kernel design and the map from document icon ids.
pub struct CurveEngine {
    design: CurveDesign,
    ids: BTreeMap<u64, IconId>,
    grabbed: Option<(u64, DVec3)>,
}

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// The kernel material of a curve part.
pub fn curve_material(m: &CurveMaterialDoc) -> CurveMaterial {
    CurveMaterial {
        alpha: m.alpha,
        beta: m.beta,
        rest: CurveMaterial::default().rest,
    }
}

/// The kernel role of an icon on a curve, or an error for roles a curve
/// does not have (a normal, derivatives along v).
pub fn curve_role(r: IconRoleDoc) -> Result<CurveRole, CommandError> {
    Ok(match r {
        IconRoleDoc::Load => CurveRole::Load,
        IconRoleDoc::Position => CurveRole::Position,
        IconRoleDoc::Derivative {
            which: DerivativeDoc::R,
        } => CurveRole::Tangent,
        IconRoleDoc::Derivative {
            which: DerivativeDoc::R2,
        } => CurveRole::Second,
        _ => {
            return Err(invalid(
                "an icon on a curve is a load, a position, or a derivative R or R2",
            ));
        }
    })
}

impl CurveEngine {
    /// The kernel design of `part`, solved.
    pub fn build(part: &CurvePart) -> Result<Self, CommandError> {
        let mut e = Self::build_unsolved(part)?;
        if !e.ids.is_empty() {
            e.design.solve().map_err(kernel_error)?;
        }
        Ok(e)
    }

    /// The kernel design of `part`, its control points as stored.
    pub fn build_unsolved(part: &CurvePart) -> Result<Self, CommandError> {
        let c = &part.curve;
        let knots = KnotVector::new(c.degree, c.knots.clone())
            .map_err(|e| invalid(format!("curve: {e}")))?;
        let curve = BSplineCurve::new(knots, c.points.iter().map(|p| DVec3::from(*p)).collect())
            .map_err(|e| invalid(format!("curve: {e}")))?;
        let mut design =
            CurveDesign::new(curve, curve_material(&part.material)).map_err(kernel_error)?;
        if let Some(kappa) = part.kappa {
            design.set_kappa(kappa).map_err(kernel_error)?;
        }
        let mut ids = BTreeMap::new();
        for icon in &part.icons {
            let role = curve_role(icon.role)?;
            let kid = match icon.anchor {
                AnchorDoc::Param { t } => design.add_icon(t, role),
                AnchorDoc::Span { t0, t1 } => design.add_interval(t0, t1, role),
                _ => return Err(invalid("an icon on a curve part is a `param` or a `span`")),
            }
            .map_err(kernel_error)?;
            let st = match icon.state {
                IconStateDoc::Driving => IconState::Passive,
                other => state(other),
            };
            design.set_state(kid, st).map_err(kernel_error)?;
            design
                .set_target(kid, DVec3::from(icon.target))
                .map_err(kernel_error)?;
            for sensor in &icon.sensors {
                design
                    .bind_sensor(kid, SensorId(sensor.clone()))
                    .map_err(kernel_error)?;
            }
            ids.insert(icon.id, kid);
        }
        Ok(Self {
            design,
            ids,
            grabbed: None,
        })
    }

    fn kid(&self, icon: u64) -> Result<IconId, CommandError> {
        self.ids
            .get(&icon)
            .copied()
            .ok_or_else(|| CommandError::new(ErrorKind::UnknownIcon, format!("no icon {icon}")))
    }

    /// The control points.
    pub fn points(&self) -> &[DVec3] {
        self.design.curve().points()
    }

    /// The curve.
    pub fn curve(&self) -> &BSplineCurve {
        self.design.curve()
    }

    /// Where icon `id` is on the curve.
    pub fn icon_xyz(&self, id: u64) -> Option<DVec3> {
        self.design.icon(*self.ids.get(&id)?).map(|i| i.xyz)
    }

    /// Icon `id` as the kernel holds it.
    pub fn readback(&self, id: u64) -> Option<IconReadback> {
        curve_readback(&self.design, *self.ids.get(&id)?)
    }

    /// The kernel design and the map from document icon ids, to hand to a
    /// product.
    pub fn into_parts(self) -> (CurveDesign, BTreeMap<u64, IconId>) {
        (self.design, self.ids)
    }

    /// The calibrated spring coefficient.
    pub fn kappa(&self) -> f64 {
        self.design.spring().kappa()
    }

    /// Grabs `icon`.
    pub fn grab(&mut self, icon: u64) -> Result<(), CommandError> {
        let kid = self.kid(icon)?;
        let at = self.design.icon(kid).map(|i| i.xyz).unwrap_or_default();
        self.grabbed = Some((icon, at));
        Ok(())
    }

    /// A drag frame; returns where the icon is on the solved curve. A load
    /// is iterated until the spring lands in its band, as on a surface.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        let kid = self.kid(icon)?;
        if self.grabbed.map(|g| g.0) != Some(icon) {
            self.grab(icon)?;
        }
        let from = self.grabbed.map(|g| g.1).unwrap_or_default();
        let is_load = self.design.icon(kid).map(|i| i.role) == Some(CurveRole::Load);
        let mut actual = DVec3::ZERO;
        for _ in 0..SPRING_ITERATIONS {
            actual = self.design.drag(kid, xyz).map_err(kernel_error)?;
            let dx = (xyz - from).length();
            if !is_load || dx < 1e-9 {
                break;
            }
            let ratio = (actual - from).length() / dx;
            if (SPRING_BAND.0..=SPRING_BAND.1).contains(&ratio) {
                break;
            }
        }
        Ok(actual)
    }

    /// Ends a drag.
    pub fn release(&mut self, icon: u64) -> Result<(), CommandError> {
        let kid = self.kid(icon)?;
        if self.grabbed.map(|g| g.0) == Some(icon) {
            self.design.release(kid).map_err(kernel_error)?;
        }
        self.grabbed = None;
        Ok(())
    }

    /// A polyline of the curve with `density` samples per knot span, for
    /// mesh export (positions only; a curve has no faces).
    pub fn mesh(&self, density: usize) -> Result<MeshData, CommandError> {
        Ok(curve_mesh(self.design.curve(), density))
    }
}

/// Kernel icon `kid` of a curve design as the document keeps it.
pub fn curve_readback(design: &CurveDesign, kid: IconId) -> Option<IconReadback> {
    let i = design.icon(kid)?;
    Some(IconReadback {
        xyz: i.xyz,
        target: i.target,
        state: state_back(i.state),
        sensors: i.sensors.iter().map(|s| s.0.clone()).collect(),
    })
}

/// A polyline of `c` with `density` samples per knot span (a curve has no
/// faces: positions only).
pub fn curve_mesh(c: &BSplineCurve, density: usize) -> MeshData {
    let (a, b) = c.domain();
    let n = c.knots().spans().len() * density + 1;
    let positions = (0..n)
        .map(|k| {
            let t = a + (b - a) * k as f64 / (n - 1) as f64;
            c.point(t).as_vec3().to_array()
        })
        .collect();
    MeshData {
        positions,
        normals: Vec::new(),
        indices: Vec::new(),
    }
}

impl SurfaceQuery for CurveEngine {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        CurveQuery(self.design.curve()).point_at(anchor)
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        CurveQuery(self.design.curve()).current_target(anchor, role)
    }
}

/// A curve as a query for icon placement.
pub struct CurveQuery<'a>(pub &'a BSplineCurve);

impl SurfaceQuery for CurveQuery<'_> {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        let [t, _] = anchor.centre();
        self.0.point(t).to_array()
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        let [t, _] = anchor.centre();
        let d = self.0.derivs(t);
        match role {
            IconRoleDoc::Derivative {
                which: DerivativeDoc::R,
            } => d.d1,
            IconRoleDoc::Derivative {
                which: DerivativeDoc::R2,
            } => d.d2,
            _ => d.p,
        }
        .to_array()
    }
}
