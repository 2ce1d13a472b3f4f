//! The live model of one design as its actor holds it: the document (the
//! persisted truth) plus one kernel engine per part built from it. Edits
//! produce a new document; only the parts an edit touches rebuild and solve;
//! only when that succeeds does the model switch, so a refused edit changes
//! nothing. Drags go straight to the part's engine (no rebuild, no refactor,
//! no other part touched).

pub use super::doc::DesignDoc;
pub use super::doc::{AnchorDoc, IconDoc, IconRoleDoc, IconStateDoc, MaterialDoc, SurfaceDoc};
pub use super::edit::{Created, Edit, MaterialEdit, PartEdit};
use super::engine::Engine;
use super::part::{PartBody, SurfacePart};
use super::part_engine::PartEngine;
use std::collections::{BTreeMap, BTreeSet};
use super::error::{CommandError, ErrorKind};
use crate::cad::IgesSurface;
use glam::DVec3;
use std::sync::Arc;

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

/// One geometry frame of one part, encoded once for every client.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// The design revision at which this part last changed.
    pub rev: u64,
    /// The binary WebSocket frame.
    pub frame: axum::body::Bytes,
}

/// The newest frame of every part: what the actor publishes (latest wins
/// per part; a writer sends the parts whose `rev` it has not sent).
#[derive(Clone, Debug, Default)]
pub struct GeometrySet {
    /// Frames by part id.
    pub parts: BTreeMap<u64, Arc<Geometry>>,
}

/// Document + one kernel engine per part.
pub struct DesignModel {
    doc: DesignDoc,
    engines: BTreeMap<u64, PartEngine>,
}

fn unknown_part(part: u64) -> CommandError {
    CommandError::new(ErrorKind::UnknownPart, format!("no part {part}"))
}

impl DesignModel {
    /// Builds the model from a document (validated). The stored shapes are
    /// taken as they are — they were solved when stored — so a reload,
    /// undo or restore gives back exactly the same control points.
    pub fn load(doc: &DesignDoc) -> Result<Self, CommandError> {
        doc.validate()?;
        let mut engines = BTreeMap::new();
        for p in &doc.parts {
            engines.insert(p.id, PartEngine::build_unsolved(&p.body)?);
        }
        let mut m = Self {
            doc: doc.clone(),
            engines,
        };
        m.sync();
        Ok(m)
    }

    /// Copies the kernel's state into the document.
    fn sync(&mut self) {
        self.doc = self.to_doc();
    }

    /// The current document: per part, the solved points and, per icon,
    /// position, target, state and sensors. A load's target is normalised
    /// to where it sits (sculpting is plastic: once solved, a load carries
    /// no further pull), so rebuilding from the document never moves the
    /// shape.
    pub fn to_doc(&self) -> DesignDoc {
        let mut d = self.doc.clone();
        for p in &mut d.parts {
            let Some(engine) = self.engines.get(&p.id) else {
                continue;
            };
            let points: Vec<[f64; 3]> = engine.points().iter().map(|p| p.to_array()).collect();
            let kappa = engine.kappa();
            let kappa = kappa.is_finite().then_some(kappa);
            match &mut p.body {
                PartBody::Surface(s) => {
                    s.surface.points = points;
                    s.kappa = kappa;
                }
                PartBody::Curve(c) => {
                    c.curve.points = points;
                    c.kappa = kappa;
                }
            }
            for icon in p.body.icons_mut() {
                if let Some(r) = engine.readback(icon.id) {
                    icon.xyz = r.xyz.to_array();
                    // The kernel renormalises a normal's direction; keep the
                    // stored value when they agree to rounding, so a reload
                    // is bit for bit.
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
        }
        d
    }

    /// The document as last synchronised (cheap; no kernel read-back).
    pub fn doc(&self) -> &DesignDoc {
        &self.doc
    }

    /// Applies an edit; returns what it created and the parts whose shape
    /// may have changed (rebuilt and solved).
    pub fn apply(&mut self, edit: Edit) -> Result<(Created, Vec<u64>), CommandError> {
        let current = self.to_doc();
        let engines = &self.engines;
        let query = |part: u64| {
            engines
                .get(&part)
                .map(|e| e as &dyn super::edit::SurfaceQuery)
        };
        let (doc, created) = super::edit::apply(&current, &edit, &query)?;
        doc.validate()?;
        let touched: Vec<u64> = match &edit {
            Edit::Part { part, .. } => vec![*part],
            Edit::CreatePart { .. } => created.part.into_iter().collect(),
            Edit::DeletePart { .. } | Edit::SetPart { .. } => Vec::new(),
            Edit::Relate(kind) => kind.parts().to_vec(),
            Edit::Unrelate { relation } => current
                .relations
                .iter()
                .find(|r| r.id == *relation)
                .map(|r| r.kind.parts().to_vec())
                .unwrap_or_default(),
        };
        let mut rebuilt = BTreeMap::new();
        for id in &touched {
            if let Some(p) = doc.part(*id) {
                rebuilt.insert(*id, PartEngine::build(&p.body)?);
            }
        }
        let changed: Vec<u64> = rebuilt.keys().copied().collect();
        self.engines.extend(rebuilt);
        let alive: BTreeSet<u64> = doc.parts.iter().map(|p| p.id).collect();
        self.engines.retain(|id, _| alive.contains(id));
        self.doc = doc;
        self.sync();
        Ok((created, changed))
    }

    /// The icon with `id` and the id of its part.
    pub fn icon(&self, id: u64) -> Option<(u64, &IconDoc)> {
        self.doc.icon(id).map(|(p, i)| (p.id, i))
    }

    /// The part `icon` is on.
    pub fn part_of(&self, icon: u64) -> Option<u64> {
        self.doc.icon(icon).map(|(p, _)| p.id)
    }

    /// Checks that `icon` is on `part` (`UnknownIcon` / `UnknownPart`).
    pub fn check_icon(&self, part: u64, icon: u64) -> Result<(), CommandError> {
        match self.doc.icon(icon) {
            None => Err(CommandError::new(
                ErrorKind::UnknownIcon,
                format!("no icon {icon}"),
            )),
            Some((p, _)) if p.id != part => Err(CommandError::new(
                ErrorKind::UnknownPart,
                format!("icon {icon} is on part {}, not part {part}", p.id),
            )),
            Some(_) => Ok(()),
        }
    }

    /// Checks that `part` exists and is not locked.
    pub fn check_unlocked(&self, part: u64) -> Result<(), CommandError> {
        let p = self.doc.part(part).ok_or_else(|| unknown_part(part))?;
        if p.locked {
            return Err(CommandError::new(
                ErrorKind::Locked,
                format!("part {} ({}) is locked: unlock it first", p.id, p.name),
            ));
        }
        Ok(())
    }

    fn engine_mut(&mut self, part: u64) -> Result<&mut PartEngine, CommandError> {
        self.engines.get_mut(&part).ok_or_else(|| unknown_part(part))
    }

    /// Grabs `icon` on `part`: it becomes driving (the drag's reference is
    /// the current shape). Returns the parts a drag of it moves.
    pub fn grab(&mut self, part: u64, icon: u64) -> Result<Vec<u64>, CommandError> {
        self.check_icon(part, icon)?;
        self.check_unlocked(part)?;
        self.engine_mut(part)?.grab(icon)?;
        self.sync_part(part);
        Ok(vec![part])
    }

    /// A drag frame: icon `icon`'s handle is at `xyz`. Returns where the
    /// icon is on the solved shape and the parts that moved.
    pub fn drag(
        &mut self,
        part: u64,
        icon: u64,
        xyz: DVec3,
    ) -> Result<(DVec3, Vec<u64>), CommandError> {
        self.check_icon(part, icon)?;
        self.check_unlocked(part)?;
        if !xyz.is_finite() {
            return Err(CommandError::new(
                ErrorKind::NotFinite,
                "coordinates must be finite (no NaN or ∞)",
            ));
        }
        let actual = self.engine_mut(part)?.drag(icon, xyz)?;
        Ok((actual, vec![part]))
    }

    /// Ends a drag of `icon` on `part`.
    pub fn release(&mut self, part: u64, icon: u64) -> Result<Vec<u64>, CommandError> {
        self.check_icon(part, icon)?;
        self.engine_mut(part)?.release(icon)?;
        self.sync_part(part);
        Ok(vec![part])
    }

    /// Reads one part back from its engine into the document.
    fn sync_part(&mut self, _part: u64) {
        self.sync();
    }

    /// The encoded geometry frame of `part` at revision `rev`.
    pub fn geometry(&self, design: u64, part: u64, rev: u64, drag: bool) -> Option<Geometry> {
        let p = self.doc.part(part)?;
        let engine = self.engines.get(&part)?;
        let icons: Vec<(u64, DVec3)> = p
            .body
            .icons()
            .iter()
            .map(|i| {
                (
                    i.id,
                    engine.icon_xyz(i.id).unwrap_or_else(|| DVec3::from(i.xyz)),
                )
            })
            .collect();
        Some(Geometry {
            rev,
            frame: crate::convert::geometry_frame(design, rev, drag, p, engine.points(), &icons),
        })
    }

    /// Every part's frame at revision `rev`.
    pub fn geometry_set(&self, design: u64, rev: u64) -> GeometrySet {
        GeometrySet {
            parts: self
                .doc
                .parts
                .iter()
                .filter_map(|p| Some((p.id, Arc::new(self.geometry(design, p.id, rev, false)?))))
                .collect(),
        }
    }

    /// A tessellation with `density` samples per knot span: of `part`, or
    /// of every surface part (the whole product) when `None`.
    pub fn mesh(&self, part: Option<u64>, density: usize) -> Result<MeshData, CommandError> {
        let density = density.clamp(1, 32);
        match part {
            Some(id) => self
                .engines
                .get(&id)
                .ok_or_else(|| unknown_part(id))?
                .mesh(density),
            None => {
                let mut out = MeshData::default();
                for p in &self.doc.parts {
                    if let (PartBody::Surface(_), Some(e)) = (&p.body, self.engines.get(&p.id)) {
                        let m = e.mesh(density)?;
                        let base = out.positions.len() as u32;
                        out.positions.extend(m.positions);
                        out.normals.extend(m.normals);
                        out.indices.extend(m.indices.iter().map(|i| i + base));
                    }
                }
                Ok(out)
            }
        }
    }
}

/// `part` with its surface replaced by `s` (IGES import of one surface
/// into an existing part): icons whose (u, v) fall outside the new domain
/// are dropped; the others keep their parameters and are re-placed on the
/// new surface.
pub fn with_surface(part: &SurfacePart, s: &IgesSurface) -> Result<SurfacePart, CommandError> {
    let surface = SurfaceDoc::from_iges(s);
    surface.validate()?;
    let mut part = part.clone();
    part.surface = surface;
    part.icons
        .retain(|i| i.anchor.validate(&part.surface).is_ok());
    let engine = Engine::build_unsolved(&part)?;
    for icon in &mut part.icons {
        use super::edit::SurfaceQuery;
        icon.xyz = engine.point_at(&icon.anchor);
        icon.target = engine.current_target(&icon.anchor, icon.role);
    }
    Ok(part)
}
