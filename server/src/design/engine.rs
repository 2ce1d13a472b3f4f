//! The kernel side of a design model: a `vsculpt_kernel::design::Design`
//! (surface, icons, material, the thin-plate solver and the spring model)
//! built from a design document, driven by drags, and read back into the
//! document. Document icon ids map to kernel icon ids here; every kernel
//! error becomes a [`CommandError`] with a stable kind.

use super::doc::{AnchorDoc, DerivativeDoc, EdgeSideDoc, IconRoleDoc, IconStateDoc, MaterialDoc};
use super::edit::SurfaceQuery;
use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use super::part::SurfacePart;
use super::spring_band::spring_to_band;
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::design::{Design, DesignError};
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::{Anchor, Derivative, Edge, IconId, IconSpec, IconState, Role, SensorId};

/// A design's kernel state.
pub struct Engine {
    design: Design,
    /// Document icon id → kernel icon id.
    ids: BTreeMap<u64, IconId>,
    /// The icon being dragged and where it was when grabbed.
    grabbed: Option<(u64, DVec3)>,
}

pub use super::spring_band::{SPRING_BAND, SPRING_ITERATIONS};

pub fn kernel_error(e: DesignError) -> CommandError {
    let kind = match &e {
        DesignError::UnknownIcon(_) => ErrorKind::UnknownIcon,
        DesignError::OutOfDomain(..) => ErrorKind::OutOfDomain,
        DesignError::NotFinite(_) => ErrorKind::NotFinite,
        DesignError::Degenerate(_) | DesignError::Geometry(_) | DesignError::Material(_) => {
            ErrorKind::InvalidValue
        }
        DesignError::Unsupported(_) => ErrorKind::Unsupported,
        DesignError::Solve(_) => ErrorKind::Solver,
    };
    CommandError::new(kind, e.to_string())
}

fn geometry(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, format!("surface: {e}"))
}

/// The kernel material of a document material (the rest term is the
/// kernel's default: the wire has no field for it).
pub fn material(m: &MaterialDoc) -> SurfaceMaterial {
    SurfaceMaterial {
        alpha11: m.alpha11,
        alpha12: m.alpha12,
        alpha22: m.alpha22,
        beta11: m.beta11,
        beta12: m.beta12,
        beta22: m.beta22,
        rest: SurfaceMaterial::default().rest,
    }
}

pub(crate) fn anchor(a: &AnchorDoc) -> Result<Anchor, CommandError> {
    Ok(match a {
        AnchorDoc::Point { u, v } => Anchor::Point { u: *u, v: *v },
        AnchorDoc::Curve { curve } => {
            let kv = KnotVector::new(curve.degree, curve.knots.clone()).map_err(geometry)?;
            let pts = curve
                .points
                .iter()
                .map(|p| DVec3::new(p[0], p[1], 0.0))
                .collect();
            Anchor::Curve(BSplineCurve::new(kv, pts).map_err(geometry)?)
        }
        AnchorDoc::Region {
            u0,
            v0,
            u1,
            v1,
            inside,
        } => Anchor::Region {
            u0: *u0,
            v0: *v0,
            u1: *u1,
            v1: *v1,
            inside: *inside,
        },
        AnchorDoc::Edge { edge, clamped } => Anchor::Edge {
            edge: match edge {
                EdgeSideDoc::UMin => Edge::UMin,
                EdgeSideDoc::UMax => Edge::UMax,
                EdgeSideDoc::VMin => Edge::VMin,
                EdgeSideDoc::VMax => Edge::VMax,
            },
            clamped: *clamped,
        },
        AnchorDoc::Param { .. } | AnchorDoc::Span { .. } => {
            return Err(CommandError::new(
                ErrorKind::InvalidValue,
                "a curve anchor on a surface part",
            ));
        }
    })
}

pub(crate) fn role(r: IconRoleDoc) -> Role {
    match r {
        IconRoleDoc::Load => Role::Load,
        IconRoleDoc::Position => Role::Position,
        IconRoleDoc::Normal => Role::Normal,
        IconRoleDoc::Derivative { which } => Role::Derivative(match which {
            DerivativeDoc::R => Derivative::R,
            DerivativeDoc::V => Derivative::V,
            DerivativeDoc::R2 => Derivative::R2,
            DerivativeDoc::V2 => Derivative::V2,
            DerivativeDoc::RV => Derivative::RV,
        }),
    }
}

pub fn state(s: IconStateDoc) -> IconState {
    match s {
        IconStateDoc::Driving => IconState::Driving,
        IconStateDoc::Passive => IconState::Passive,
        IconStateDoc::Sleeping => IconState::Sleeping,
    }
}

pub fn state_back(s: IconState) -> IconStateDoc {
    match s {
        IconState::Driving => IconStateDoc::Driving,
        IconState::Passive => IconStateDoc::Passive,
        IconState::Sleeping => IconStateDoc::Sleeping,
    }
}

/// What the kernel says of one icon after a solve.
/// Kernel icon `kid` of `design` as the document keeps it.
pub fn readback(design: &Design, kid: IconId) -> Option<IconReadback> {
    let i = design.icon(kid)?;
    Some(IconReadback {
        xyz: i.xyz,
        target: i.target,
        state: state_back(i.state),
        sensors: i.sensors.iter().map(|s| s.0.clone()).collect(),
    })
}

/// A tessellation of `s` with `density` samples per knot span.
pub fn surface_mesh(s: &BSplineSurface, density: usize) -> MeshData {
    let spans = |kv: &KnotVector| kv.spans().len();
    let su = spans(s.u_knots()) * density + 1;
    let sv = spans(s.v_knots()) * density + 1;
    let t = vsculpt_kernel::analysis::tessellate(s, su, sv);
    MeshData {
        positions: t.positions,
        normals: t.normals,
        indices: t.indices,
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct IconReadback {
    /// Position on the surface.
    pub xyz: DVec3,
    /// Target.
    pub target: DVec3,
    /// State.
    pub state: IconStateDoc,
    /// Bound sensors.
    pub sensors: Vec<String>,
}

impl Engine {
    /// Builds the kernel design of `doc` and solves it.
    pub fn build(doc: &SurfacePart) -> Result<Self, CommandError> {
        let mut e = Self::build_unsolved(doc)?;
        if !e.ids.is_empty() {
            e.design.solve().map_err(kernel_error)?;
        }
        Ok(e)
    }

    /// Builds the kernel design of `doc` without solving.
    pub fn build_unsolved(doc: &SurfacePart) -> Result<Self, CommandError> {
        let s = &doc.surface;
        let u = KnotVector::new(s.u_degree, s.u_knots.clone()).map_err(geometry)?;
        let v = KnotVector::new(s.v_degree, s.v_knots.clone()).map_err(geometry)?;
        let surface = BSplineSurface::new(u, v, s.dpoints()).map_err(geometry)?;
        let mut design = Design::new(surface, material(&doc.material)).map_err(kernel_error)?;
        if let Some(kappa) = doc.kappa {
            design.set_kappa(kappa).map_err(kernel_error)?;
        }
        if let Some(size) = doc.spring_size {
            design.set_spring_size(size).map_err(kernel_error)?;
        }
        let mut ids = BTreeMap::new();
        for icon in &doc.icons {
            // A drag does not survive a rebuild: the icon is passive
            // until grabbed again (sensors below make it driving).
            let st = match icon.state {
                IconStateDoc::Driving => IconState::Passive,
                other => state(other),
            };
            let kid = design
                .add_icon(IconSpec {
                    anchor: anchor(&icon.anchor)?,
                    role: role(icon.role),
                    state: st,
                    target: Some(DVec3::from(icon.target)),
                })
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

    /// Current control points.
    pub fn points(&self) -> &[DVec3] {
        self.design.surface().points()
    }

    /// Where icon `id` is on the surface.
    pub fn icon_xyz(&self, id: u64) -> Option<DVec3> {
        self.design.icon(*self.ids.get(&id)?).map(|i| i.xyz)
    }

    /// The kernel's view of icon `id`.
    pub fn readback(&self, id: u64) -> Option<IconReadback> {
        readback(&self.design, *self.ids.get(&id)?)
    }

    /// The kernel design and the map from document icon ids, to hand to a
    /// product.
    pub fn into_parts(self) -> (Design, BTreeMap<u64, IconId>) {
        (self.design, self.ids)
    }

    /// The spring coefficient κ (calibrated by drags, kept across rebuilds).
    pub fn kappa(&self) -> f64 {
        self.design.spring().kappa()
    }

    /// Starts a drag of `icon`.
    pub fn grab(&mut self, icon: u64) -> Result<(), CommandError> {
        let kid = self.kid(icon)?;
        self.design.drag_start(kid).map_err(kernel_error)?;
        let at = self.design.icon(kid).map(|i| i.xyz).unwrap_or_default();
        self.grabbed = Some((icon, at));
        Ok(())
    }

    /// A drag frame; returns where the icon is on the solved surface.
    ///
    /// For a load the kernel adapts the spring's κ by one step per solve
    /// (paper 003: raise κ when Δy/Δx < 0.8, lower it when > 1.2). The
    /// paper repeats until the ratio is inside the band; so does this frame,
    /// at most [`SPRING_ITERATIONS`] solves, so no client ever sees the
    /// surface overshoot while κ calibrates.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        let kid = self.kid(icon)?;
        if self.grabbed.map(|g| g.0) != Some(icon) || self.design.dragging() != Some(kid) {
            self.grab(icon)?;
        }
        let from = self.grabbed.map(|g| g.1).unwrap_or_default();
        let is_load = self.design.icon(kid).map(|i| i.role) == Some(Role::Load);
        let design = &mut self.design;
        let (actual, ()) = spring_to_band(from, xyz, is_load, || {
            Ok((design.drag(kid, xyz).map_err(kernel_error)?.actual, ()))
        })?;
        Ok(actual)
    }

    /// Ends the drag; the shape stays (a load's deformation is baked).
    pub fn release(&mut self, icon: u64) -> Result<(), CommandError> {
        let kid = self.kid(icon)?;
        if self.design.dragging() == Some(kid) {
            self.design.release(kid).map_err(kernel_error)?;
        }
        self.grabbed = None;
        Ok(())
    }

    /// A tessellation with `density` samples per knot span (kernel
    /// `analysis::tessellate`).
    pub fn mesh(&self, density: usize) -> Result<MeshData, CommandError> {
        Ok(surface_mesh(self.design.surface(), density))
    }
}

impl SurfaceQuery for Engine {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        DesignQuery(&self.design).point_at(anchor)
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        DesignQuery(&self.design).current_target(anchor, role)
    }
}

/// A surface design as a query for icon placement.
pub struct DesignQuery<'a>(pub &'a Design);

impl SurfaceQuery for DesignQuery<'_> {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        let [u, v] = anchor.centre();
        self.0.surface().point(u, v).to_array()
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        let [u, v] = anchor.centre();
        let s = self.0.surface();
        let d = s.derivs(u, v);
        match role {
            IconRoleDoc::Load | IconRoleDoc::Position => d.p,
            IconRoleDoc::Normal => s.normal(u, v),
            IconRoleDoc::Derivative { which } => match which {
                DerivativeDoc::R => d.u,
                DerivativeDoc::V => d.v,
                DerivativeDoc::R2 => d.uu,
                DerivativeDoc::V2 => d.vv,
                DerivativeDoc::RV => d.uv,
            },
        }
        .to_array()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::doc::IconDoc;

    fn icon(id: u64, u: f64, v: f64, role: IconRoleDoc, target: DVec3) -> IconDoc {
        IconDoc {
            id,
            anchor: AnchorDoc::Point { u, v },
            role,
            state: IconStateDoc::Passive,
            xyz: [0.0; 3],
            target: target.to_array(),
            sensors: Vec::new(),
        }
    }

    #[test]
    fn a_dragged_constraint_reaches_its_target_and_pins_hold() {
        let mut doc = crate::design::demo::plate_part(16, 12).unwrap();
        let probe = Engine::build_unsolved(&doc).unwrap();
        let at = |u: f64, v: f64| DVec3::from(probe.point_at(&AnchorDoc::Point { u, v }));
        doc.icons = vec![
            icon(1, 0.3, 0.5, IconRoleDoc::Position, at(0.3, 0.5)),
            icon(7, 0.6, 0.5, IconRoleDoc::Position, at(0.6, 0.5)),
            icon(3, 0.9, 0.9, IconRoleDoc::Position, at(0.9, 0.9)),
        ];
        let mut e = Engine::build(&doc).unwrap();
        let pin = e.icon_xyz(1).unwrap();
        let start = e.icon_xyz(7).unwrap();
        let target = start + DVec3::new(0.0, 0.0, 10.0);
        e.grab(7).unwrap();
        let got = e.drag(7, target).unwrap();
        assert!((got - target).length() < 1e-6, "{got} vs {target}");
        assert!((e.icon_xyz(1).unwrap() - pin).length() < 1e-6);
        // The surface between the pins rose: thin-plate, not a spike.
        let mid = DVec3::from(e.point_at(&AnchorDoc::Point { u: 0.45, v: 0.5 }));
        assert!(mid.z > 0.5, "{mid}");
        e.release(7).unwrap();
        assert!(e.points().iter().all(|p| p.is_finite()));
        assert_eq!(e.readback(7).unwrap().state, IconStateDoc::Passive);
    }

    #[test]
    fn unknown_icons_and_bad_values_are_refused() {
        let doc = crate::design::demo::shell_part().unwrap();
        let mut e = Engine::build(&doc).unwrap();
        let before = e.points().to_vec();
        assert_eq!(e.grab(99).unwrap_err().kind, ErrorKind::UnknownIcon);
        assert_eq!(
            e.drag(3, DVec3::new(f64::NAN, 0.0, 0.0)).unwrap_err().kind,
            ErrorKind::NotFinite
        );
        assert_eq!(e.points(), &before[..]);
    }
}

#[cfg(test)]
mod spring_tests {
    use super::*;

    #[test]
    fn a_load_drag_lands_within_the_spring_band_from_the_first_frame() {
        let doc = crate::design::demo::shell_part().unwrap();
        let mut e = Engine::build(&doc).unwrap();
        let load = doc
            .icons
            .iter()
            .find(|i| i.role == IconRoleDoc::Load)
            .unwrap()
            .id;
        let start = e.icon_xyz(load).unwrap();
        e.grab(load).unwrap();
        for k in 1..=5 {
            let want = start + DVec3::new(0.0, 0.0, 2.0 * k as f64);
            let got = e.drag(load, want).unwrap();
            let ratio = (got - start).length() / (want - start).length();
            assert!((0.8..=1.2).contains(&ratio), "frame {k}: ratio {ratio}");
        }
    }
}
