//! One part's kernel engine, by kind: the surface engine ([`Engine`]) or the
//! curve engine ([`CurveEngine`]). The model holds one per part and sends
//! each edit or drag only to the part it names, so a drag on one part costs
//! what it costs alone.

use super::curve_engine::CurveEngine;
use super::doc::{AnchorDoc, IconRoleDoc};
use super::edit::SurfaceQuery;
use super::engine::{Engine, IconReadback};
use super::error::CommandError;
use super::model::MeshData;
use super::part::PartBody;
use glam::DVec3;

/// A part's kernel engine.
pub enum PartEngine {
    /// A surface part.
    Surface(Engine),
    /// A curve part.
    Curve(CurveEngine),
}

impl PartEngine {
    /// The engine of `body`, solved.
    pub fn build(body: &PartBody) -> Result<Self, CommandError> {
        Ok(match body {
            PartBody::Surface(s) => PartEngine::Surface(Engine::build(s)?),
            PartBody::Curve(c) => PartEngine::Curve(CurveEngine::build(c)?),
        })
    }

    /// The engine of `body`, its control points as stored.
    pub fn build_unsolved(body: &PartBody) -> Result<Self, CommandError> {
        Ok(match body {
            PartBody::Surface(s) => PartEngine::Surface(Engine::build_unsolved(s)?),
            PartBody::Curve(c) => PartEngine::Curve(CurveEngine::build_unsolved(c)?),
        })
    }

    /// The solved control points.
    pub fn points(&self) -> &[DVec3] {
        match self {
            PartEngine::Surface(e) => e.points(),
            PartEngine::Curve(e) => e.points(),
        }
    }

    /// Where icon `id` is.
    pub fn icon_xyz(&self, id: u64) -> Option<DVec3> {
        match self {
            PartEngine::Surface(e) => e.icon_xyz(id),
            PartEngine::Curve(e) => e.icon_xyz(id),
        }
    }

    /// Icon `id` as the kernel holds it.
    pub fn readback(&self, id: u64) -> Option<IconReadback> {
        match self {
            PartEngine::Surface(e) => e.readback(id),
            PartEngine::Curve(e) => e.readback(id),
        }
    }

    /// The calibrated spring coefficient.
    pub fn kappa(&self) -> f64 {
        match self {
            PartEngine::Surface(e) => e.kappa(),
            PartEngine::Curve(e) => e.kappa(),
        }
    }

    /// Grabs an icon.
    pub fn grab(&mut self, icon: u64) -> Result<(), CommandError> {
        match self {
            PartEngine::Surface(e) => e.grab(icon),
            PartEngine::Curve(e) => e.grab(icon),
        }
    }

    /// A drag frame.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        match self {
            PartEngine::Surface(e) => e.drag(icon, xyz),
            PartEngine::Curve(e) => e.drag(icon, xyz),
        }
    }

    /// Ends a drag.
    pub fn release(&mut self, icon: u64) -> Result<(), CommandError> {
        match self {
            PartEngine::Surface(e) => e.release(icon),
            PartEngine::Curve(e) => e.release(icon),
        }
    }

    /// A tessellation (surface) or polyline (curve) for export.
    pub fn mesh(&self, density: usize) -> Result<MeshData, CommandError> {
        match self {
            PartEngine::Surface(e) => e.mesh(density),
            PartEngine::Curve(e) => e.mesh(density),
        }
    }

    /// The part's geometry as a query for icon placement.
    pub fn query(&self) -> &dyn SurfaceQuery {
        match self {
            PartEngine::Surface(e) => e,
            PartEngine::Curve(e) => e,
        }
    }
}

impl SurfaceQuery for PartEngine {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        self.query().point_at(anchor)
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        self.query().current_target(anchor, role)
    }
}
