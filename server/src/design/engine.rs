//! The kernel side of a design model: the B-spline surface the icons act
//! on, how a drag moves it, and evaluation for icons and mesh export.
//!
//! This engine uses the kernel's `bspline` layer only. A drag moves the
//! surface point under the dragged icon exactly to the requested position
//! with the smallest change of control points, while every active point
//! position constraint keeps its surface point where it is: the
//! minimum-norm solution of `A ΔP = b` (one row of basis values
//! `N_i(u) M_j(v)` per point; `b` = the drag's displacement for the dragged
//! icon, 0 for each pin), `ΔP = Aᵀ (A Aᵀ)⁻¹ b`, relative to the shape at
//! the start of the drag. The kernel's
//! `design::Design` (thin-plate energy, every icon constraint held during
//! the drag) replaces this once it is available; the actor, the document and
//! the wire do not change with it.

use super::doc::{AnchorDoc, DerivativeDoc, DesignDoc, IconRoleDoc, IconStateDoc};
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
    /// Active point position constraints: icon id and (u, v).
    pins: Vec<(u64, [f64; 2])>,
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
        let pins = doc
            .icons
            .iter()
            .filter(|i| i.role == IconRoleDoc::Position && i.state != IconStateDoc::Sleeping)
            .filter_map(|i| match i.anchor {
                AnchorDoc::Point { u, v } => Some((i.id, [u, v])),
                _ => None,
            })
            .collect();
        Ok(Self {
            surface,
            anchors: doc.icons.iter().map(|i| (i.id, i.anchor.clone())).collect(),
            pins,
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

    /// The sparse row of basis values of w(u, v): control-point indices
    /// and weights.
    fn row(&self, u: f64, v: f64) -> (Vec<usize>, Vec<f64>) {
        let bu = basis_derivs(self.surface.u_knots(), u, 0);
        let bv = basis_derivs(self.surface.v_knots(), v, 0);
        let nv = self.surface.nv();
        let mut idx = Vec::new();
        let mut w = Vec::new();
        for (a, &wa) in bu.row(0).iter().enumerate() {
            for (b, &wb) in bv.row(0).iter().enumerate() {
                idx.push((bu.first + a) * nv + bv.first + b);
                w.push(wa * wb);
            }
        }
        (idx, w)
    }

    /// Moves the surface so icon `icon` is at `xyz`; returns where it is.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        if self.reference.as_ref().map(|r| r.0) != Some(icon) {
            self.grab(icon)?;
        }
        let [u, v] = self.anchors[&icon].centre();
        let reference = self
            .reference
            .as_ref()
            .map(|r| r.1.clone())
            .ok_or_else(|| CommandError::new(ErrorKind::Conflict, "no drag in progress"))?;
        // Rows: the dragged point, then every pin that shares a control
        // point with it (others are unaffected by the minimum-norm change).
        let mut rows = vec![self.row(u, v)];
        let start: DVec3 = rows[0]
            .0
            .iter()
            .zip(&rows[0].1)
            .map(|(&k, &w)| reference[k] * w)
            .sum();
        let mut rhs = vec![xyz - start];
        for &(id, [pu, pv]) in &self.pins {
            if id == icon {
                continue;
            }
            let r = self.row(pu, pv);
            if r.0.iter().any(|k| rows[0].0.contains(k)) {
                rows.push(r);
                rhs.push(DVec3::ZERO);
            }
        }
        let lambda = solve_gram(&rows, &rhs).ok_or_else(|| {
            CommandError::new(
                ErrorKind::Solver,
                "the drag contradicts a position constraint at the same point",
            )
        })?;
        let mut points = reference;
        for ((idx, w), l) in rows.iter().zip(&lambda) {
            for (&k, &wk) in idx.iter().zip(w) {
                points[k] += *l * wk;
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

/// Solves `(A Aᵀ) λ = b` for sparse rows `A` (Gauss elimination with
/// partial pivoting on the small Gram matrix); `None` when singular.
fn solve_gram(rows: &[(Vec<usize>, Vec<f64>)], rhs: &[DVec3]) -> Option<Vec<DVec3>> {
    let m = rows.len();
    let dot = |a: &(Vec<usize>, Vec<f64>), b: &(Vec<usize>, Vec<f64>)| -> f64 {
        let mut s = 0.0;
        for (i, &k) in a.0.iter().enumerate() {
            if let Some(j) = b.0.iter().position(|&q| q == k) {
                s += a.1[i] * b.1[j];
            }
        }
        s
    };
    let mut g: Vec<Vec<f64>> = (0..m)
        .map(|i| (0..m).map(|j| dot(&rows[i], &rows[j])).collect())
        .collect();
    let mut b = rhs.to_vec();
    let scale = (0..m).map(|i| g[i][i]).fold(0.0, f64::max);
    for c in 0..m {
        let p = (c..m).max_by(|&x, &y| g[x][c].abs().total_cmp(&g[y][c].abs()))?;
        if g[p][c].abs() <= 1e-12 * scale {
            return None;
        }
        g.swap(c, p);
        b.swap(c, p);
        for r in c + 1..m {
            let f = g[r][c] / g[c][c];
            let pivot = g[c].clone();
            for (gk, pk) in g[r].iter_mut().zip(&pivot).skip(c) {
                *gk -= f * pk;
            }
            let bc = b[c];
            b[r] -= bc * f;
        }
    }
    let mut x = vec![DVec3::ZERO; m];
    for r in (0..m).rev() {
        let mut acc = b[r];
        for k in r + 1..m {
            acc -= x[k] * g[r][k];
        }
        x[r] = acc / g[r][r];
    }
    Some(x)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::doc::IconDoc;

    fn icon(id: u64, u: f64, v: f64, role: IconRoleDoc) -> IconDoc {
        IconDoc {
            id,
            anchor: AnchorDoc::Point { u, v },
            role,
            state: IconStateDoc::Passive,
            xyz: [0.0; 3],
            target: [0.0; 3],
            sensors: Vec::new(),
        }
    }

    #[test]
    fn a_drag_reaches_its_target_and_keeps_nearby_pins() {
        let mut doc = crate::design::demo::plate("t", 16, 12).unwrap();
        doc.icons = vec![
            icon(1, 0.5, 0.5, IconRoleDoc::Position),
            icon(2, 0.53, 0.52, IconRoleDoc::Load),
            icon(3, 0.1, 0.1, IconRoleDoc::Position),
        ];
        let mut e = Engine::build(&doc).unwrap();
        let pin = e.icon_xyz(1).unwrap();
        let far = e.icon_xyz(3).unwrap();
        let start = e.icon_xyz(2).unwrap();
        let target = start + DVec3::new(1.0, -2.0, 10.0);
        let got = e.drag(2, target).unwrap();
        assert!((got - target).length() < 1e-9, "{got} vs {target}");
        assert!((e.icon_xyz(1).unwrap() - pin).length() < 1e-9);
        assert!((e.icon_xyz(3).unwrap() - far).length() < 1e-12);
        // Frames are relative to the grab: a second frame replaces the first.
        let got = e.drag(2, start).unwrap();
        assert!((got - start).length() < 1e-9);
        assert!(
            e.points()
                .iter()
                .zip(doc.surface.dpoints())
                .all(|(a, b)| (*a - b).length() < 1e-9)
        );
    }

    #[test]
    fn dragging_onto_a_pin_is_refused() {
        let mut doc = crate::design::demo::plate("t", 8, 8).unwrap();
        doc.icons = vec![
            icon(1, 0.5, 0.5, IconRoleDoc::Position),
            icon(2, 0.5, 0.5, IconRoleDoc::Load),
        ];
        let mut e = Engine::build(&doc).unwrap();
        let before = e.points().to_vec();
        let err = e.drag(2, DVec3::new(0.0, 0.0, 5.0)).unwrap_err();
        assert_eq!(err.kind, ErrorKind::Solver);
        assert_eq!(e.points(), &before[..]);
    }
}
