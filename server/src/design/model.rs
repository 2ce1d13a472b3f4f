//! The live model of one design as its actor holds it: the document (the
//! persisted truth) plus the kernel engine built from it. Edits produce a new
//! document, the engine rebuilds from it and solves; only when that succeeds
//! does the model switch, so a refused edit changes nothing. Drags go
//! straight to the engine (no rebuild, no refactor).

pub use super::doc::DesignDoc;
pub use super::doc::{AnchorDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, SurfaceDoc};
pub use super::edit::Edit;
use super::engine::Engine;
use super::error::{CommandError, ErrorKind};
use crate::cad::IgesSurface;
use glam::DVec3;

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

/// One geometry frame, encoded once for every client.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// Geometry revision (increases with every published frame).
    pub rev: u64,
    /// The binary WebSocket frame.
    pub frame: axum::body::Bytes,
}

/// Document + kernel engine.
pub struct DesignModel {
    doc: DesignDoc,
    engine: Engine,
}

impl DesignModel {
    /// Builds the model from a document (validated). The stored shape is
    /// taken as it is — it was solved when it was stored — so a reload,
    /// undo or restore gives back exactly the same control points.
    pub fn load(doc: &DesignDoc) -> Result<Self, CommandError> {
        doc.validate()?;
        let engine = Engine::build_unsolved(doc)?;
        let mut m = Self {
            doc: doc.clone(),
            engine,
        };
        m.sync();
        Ok(m)
    }

    /// Copies the kernel's state into the document: solved points and, per
    /// icon, position, target, state and sensors. A load's target is
    /// normalised to where it sits (sculpting is plastic: once solved, a
    /// load carries no further pull), so rebuilding from the document never
    /// moves the shape.
    fn sync(&mut self) {
        self.doc = self.to_doc();
    }

    /// The current document (points as solved).
    pub fn to_doc(&self) -> DesignDoc {
        let mut d = self.doc.clone();
        d.surface.points = self.engine.points().iter().map(|p| p.to_array()).collect();
        let kappa = self.engine.kappa();
        d.kappa = kappa.is_finite().then_some(kappa);
        for icon in &mut d.icons {
            if let Some(r) = self.engine.readback(icon.id) {
                icon.xyz = r.xyz.to_array();
                // The kernel renormalises a normal's direction; keep the
                // stored value when they agree to rounding, so a reload is
                // bit for bit.
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
        d
    }

    /// Applies an edit; returns the created icon's id.
    pub fn apply(&mut self, edit: Edit) -> Result<Option<u64>, CommandError> {
        let current = self.to_doc();
        let (doc, created) = super::edit::apply(&current, &edit, &self.engine)?;
        let engine = Engine::build(&doc)?;
        self.doc = doc;
        self.engine = engine;
        self.sync();
        Ok(created)
    }

    /// The icon with `id`.
    pub fn icon(&self, id: u64) -> Option<&IconDoc> {
        self.doc.icon(id)
    }

    /// An `UnknownIcon` error unless `icon` exists.
    pub fn check_icon(&self, icon: u64) -> Result<(), CommandError> {
        if self.doc.icon(icon).is_none() {
            return Err(CommandError::new(
                ErrorKind::UnknownIcon,
                format!("no icon {icon}"),
            ));
        }
        Ok(())
    }

    /// Grabs `icon`: it becomes driving (the drag's reference is the
    /// current shape).
    pub fn grab(&mut self, icon: u64) -> Result<(), CommandError> {
        self.check_icon(icon)?;
        self.engine.grab(icon)?;
        self.sync();
        Ok(())
    }

    /// A drag frame: icon `icon`'s handle is at `xyz`. Returns where the
    /// icon is on the solved surface.
    pub fn drag(&mut self, icon: u64, xyz: DVec3) -> Result<DVec3, CommandError> {
        self.check_icon(icon)?;
        if !xyz.is_finite() {
            return Err(CommandError::new(
                ErrorKind::NotFinite,
                "coordinates must be finite (no NaN or ∞)",
            ));
        }
        self.engine.drag(icon, xyz)
    }

    /// Ends a drag of `icon`.
    pub fn release(&mut self, icon: u64) -> Result<(), CommandError> {
        self.check_icon(icon)?;
        self.engine.release(icon)?;
        self.sync();
        Ok(())
    }

    /// The encoded geometry frame of revision `rev` of design `design`.
    pub fn geometry(&self, design: u64, rev: u64, drag: bool) -> Geometry {
        let icons: Vec<(u64, DVec3)> = self
            .doc
            .icons
            .iter()
            .map(|i| {
                (
                    i.id,
                    self.engine
                        .icon_xyz(i.id)
                        .unwrap_or_else(|| DVec3::from(i.xyz)),
                )
            })
            .collect();
        Geometry {
            rev,
            frame: crate::convert::geometry_frame(
                design,
                rev,
                drag,
                &self.doc,
                self.engine.points(),
                &icons,
            ),
        }
    }

    /// A tessellation with `density` samples per knot span.
    pub fn mesh(&self, density: usize) -> Result<MeshData, CommandError> {
        self.engine.mesh(density.clamp(1, 32))
    }
}

/// `current` with its surface replaced by `s` (IGES import): icons whose
/// (u, v) fall outside the new domain are dropped; the others keep their
/// parameters and are re-placed on the new surface.
pub fn with_surface(current: &DesignDoc, s: &IgesSurface) -> Result<DesignDoc, CommandError> {
    let surface = SurfaceDoc::from_iges(s);
    surface.validate()?;
    let mut doc = current.clone();
    doc.surface = surface;
    doc.icons
        .retain(|i| i.anchor.validate(&doc.surface).is_ok());
    let engine = Engine::build_unsolved(&doc)?;
    for icon in &mut doc.icons {
        use super::edit::SurfaceQuery;
        icon.xyz = engine.point_at(&icon.anchor);
        icon.target = engine.current_target(&icon.anchor, icon.role);
    }
    Ok(doc)
}
