//! The kernel side of a curve part: a `vsculpt_kernel::curve_design::
//! CurveDesign` (paper 003, eq. 1: a deformable B-spline curve sculpted by
//! the same icons as a surface) built from a [`CurvePart`] for the product
//! engine, which drags it and reads it back (`curve_readback`, `CurveQuery`,
//! `curve_mesh` here). Icons sit at a parameter (`param`) or along a stretch
//! (`span`); their roles are load, position, and the first (R) or second
//! (R2) derivative.

use super::doc::{AnchorDoc, DerivativeDoc, IconRoleDoc, IconStateDoc};
use super::edit::SurfaceQuery;
use super::engine::{IconReadback, kernel_error, state, state_back};
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
        Ok(Self { design, ids })
    }

    /// The kernel design and the map from document icon ids, to hand to a
    /// product.
    pub fn into_parts(self) -> (CurveDesign, BTreeMap<u64, IconId>) {
        (self.design, self.ids)
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
