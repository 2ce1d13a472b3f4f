//! The kernel side of a design model: the B-spline surface the icons act
//! on, how a drag moves it, and evaluation for icons and mesh export.
//!
//! This engine uses the kernel's `bspline` layer only. A drag moves the
//! surface point under the dragged icon exactly to the requested position
//! with the smallest change of control points (the minimum-norm solution
//! of `w(u,v) = xyz`, i.e. `ΔP_k = N_k(u,v) Δ / Σ N_k²` over the
//! (p+1)(q+1) control points whose basis functions are non-zero there),
//! relative to the shape at the start of the drag. The kernel's
//! `design::Design` (thin-plate energy, every icon constraint held during
//! the drag) replaces this once it is available; the actor, the document and
//! the wire do not change with it.

use super::doc::{AnchorDoc, DerivativeDoc, DesignDoc, IconRoleDoc};
use super::edit::SurfaceQuery;
use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::bspline::{BSplineSurface, KnotVector, basis_derivs};

/// A design's surface and icon anchors, ready to drag.
pub struct Engine {
    surface: BSplineSurface,
    anchors: BTreeMap<u64, AnchorDoc>,
    /// The control points when the current drag started.
    reference: Option<(u64, Vec<DVec3>)>,
}

fn geometry(e: impl std::fmt::Display) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, format!("surface: {e}"))
}

impl Engine {
    /// Builds the surface of `doc` (knots checked by the kernel).
    pub fn build(doc: &DesignDoc) -> Result<Self, CommandError> {
        Self::build_unsolved(doc)
    }

    /// Builds the surface of `doc` without solving.
    pub fn build_unsolved(doc: &DesignDoc) -> Result<Self, CommandError> {
        let s = &doc.surface;
        let u = KnotVector::new(s.u_degree, s.u_knots.clone()).map_err(geometry)?;
        let v = KnotVector::new(s.v_degree, s.v_knots.clone()).map_err(geometry)?;
        let surface = BSplineSurface::new(u, v, s.dpoints()).map_err(geometry)?;
        Ok(Self {
            surface,
            anchors: doc.icons.iter().map(|i| (i.id, i.anchor.clone())).collect(),
            reference: None,
        })
    }

    /// Current control points.
    pub fn points(&self) -> &[DVec3] {
        self.surface.points()
    }

    /// Where icon `id` is on the surface.
    pub fn icon_xyz(&self, id: u64) -> Option<DVec3> {
        let [u, v] = self.anchors.get(&id)?.centre();
        Some(self.surface.point(u, v))
    }

    /// Starts a drag of `icon` from the current shape.
    pub fn grab(&mut self, icon: u64) -> Result<(), CommandError> {
        if !self.anchors.contains_key(&icon) {
            return Err(CommandError::new(
                ErrorKind::UnknownIcon,
                format!("no icon {icon}"),
            ));
        }
        self.reference = Some((icon, self.surface.points().to_vec()));
        Ok(())
    }

    /// Moves the surface so icon `icon` is at `xyz`; returns where it is.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        if self.reference.as_ref().map(|r| r.0) != Some(icon) {
            self.grab(icon)?;
        }
        let [u, v] = self.anchors[&icon].centre();
        let bu = basis_derivs(self.surface.u_knots(), u, 0);
        let bv = basis_derivs(self.surface.v_knots(), v, 0);
        let (ru, rv) = (bu.row(0), bv.row(0));
        let nv = self.surface.nv();
        let reference = &self
            .reference
            .as_ref()
            .map(|r| &r.1)
            .ok_or_else(|| CommandError::new(ErrorKind::Conflict, "no drag in progress"))?;
        let mut start = DVec3::ZERO;
        let mut norm = 0.0;
        for (a, &wa) in ru.iter().enumerate() {
            for (b, &wb) in rv.iter().enumerate() {
                let w = wa * wb;
                start += reference[(bu.first + a) * nv + bv.first + b] * w;
                norm += w * w;
            }
        }
        if norm <= 0.0 {
            return Err(CommandError::new(
                ErrorKind::Solver,
                "no control point moves this icon",
            ));
        }
        let delta = (xyz - start) / norm;
        let mut points = reference.to_vec();
        for (a, &wa) in ru.iter().enumerate() {
            for (b, &wb) in rv.iter().enumerate() {
                points[(bu.first + a) * nv + bv.first + b] += delta * (wa * wb);
            }
        }
        if !points.iter().all(|p| p.is_finite()) {
            return Err(CommandError::new(ErrorKind::NotFinite, "the drag diverged"));
        }
        self.surface.set_points(points).map_err(geometry)?;
        Ok(self.surface.point(u, v))
    }

    /// Ends the drag; the shape stays.
    pub fn release(&mut self, _icon: u64) -> Result<(), CommandError> {
        self.reference = None;
        Ok(())
    }

    /// A grid tessellation with `density` samples per knot span.
    pub fn mesh(&self, density: usize) -> Result<MeshData, CommandError> {
        let params = |kv: &KnotVector| -> Vec<f64> {
            let mut t = Vec::new();
            for (_, a, b) in kv.spans() {
                for s in 0..density {
                    t.push(a + (b - a) * s as f64 / density as f64);
                }
            }
            t.push(kv.domain().1);
            t
        };
        let us = params(self.surface.u_knots());
        let vs = params(self.surface.v_knots());
        let (m, n) = (us.len(), vs.len());
        let mut mesh = MeshData {
            positions: Vec::with_capacity(m * n),
            normals: Vec::with_capacity(m * n),
            indices: Vec::with_capacity(6 * (m - 1) * (n - 1)),
        };
        for &u in &us {
            for &v in &vs {
                let p = self.surface.point(u, v);
                let q = self.surface.normal(u, v);
                mesh.positions.push([p.x as f32, p.y as f32, p.z as f32]);
                mesh.normals.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        for i in 0..m - 1 {
            for j in 0..n - 1 {
                let a = (i * n + j) as u32;
                let b = a + n as u32;
                mesh.indices.extend([a, b, a + 1, a + 1, b, b + 1]);
            }
        }
        Ok(mesh)
    }
}

impl SurfaceQuery for Engine {
    fn point_at(&self, anchor: &AnchorDoc) -> [f64; 3] {
        let [u, v] = anchor.centre();
        self.surface.point(u, v).to_array()
    }

    fn current_target(&self, anchor: &AnchorDoc, role: IconRoleDoc) -> [f64; 3] {
        let [u, v] = anchor.centre();
        let d = self.surface.derivs(u, v);
        match role {
            IconRoleDoc::Load | IconRoleDoc::Position => d.p,
            IconRoleDoc::Normal => self.surface.normal(u, v),
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
