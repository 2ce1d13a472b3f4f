//! The kernel side of body parts (paper 002): per body part its B-spline
//! volume, its metamorphosis (when it has a morph target) and the shape
//! shown at the current morph time, evaluated for display — the boundary
//! tessellated (six faces, outward) and isoparametric lines at constant
//! u, v, w on the boundary — and encoded as body frames (kind 4).
//!
//! Evaluation happens when a body is built, edited or morphed: inside the
//! design actor's `heavy` sections (off the async threads), never while a
//! frame is published, which only encodes what was evaluated.

use super::body_part::BodyPart;
use super::doc::DesignDoc;
use super::error::{CommandError, ErrorKind};
use super::part::PartBody;
use crate::cad::HexGrid;
use std::collections::BTreeMap;
use vsculpt_kernel::body::display::{BodyDisplay, iso_parameters};
use vsculpt_kernel::body::{BSplineVolume, Dir, Face, Ffd, Morph, Path, VolumeScratch};
use vsculpt_protocol::BodyFrame;

/// Vertices per side of a tessellated boundary face.
pub const FACE_SAMPLES: usize = 17;
/// Isoparametric values per direction.
pub const ISO_PER_DIR: usize = 3;
/// Samples along one isoparametric line.
pub const LINE_SAMPLES: usize = 33;

/// What a viewer draws of a body at one time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyShape {
    /// Lattice size.
    pub counts: [u32; 3],
    /// Lattice points.
    pub lattice: Vec<[f32; 3]>,
    /// Boundary positions.
    pub positions: Vec<[f32; 3]>,
    /// Boundary normals.
    pub normals: Vec<[f32; 3]>,
    /// Boundary triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Per line, the direction held constant.
    pub line_dirs: Vec<u32>,
    /// Line points, [`LINE_SAMPLES`] per line.
    pub line_points: Vec<[f32; 3]>,
    /// The lattice's degrees along u, v, w.
    pub degrees: [u32; 3],
    /// The lattice's knots along u, v, w.
    pub knots: [Vec<f32>; 3],
}

/// The isoparametric lines of `vol` on its boundary: for each direction d
/// and each of [`ISO_PER_DIR`] interior values t, the four curves where
/// the surface d = t meets the faces of the other two directions.
pub fn iso_lines(vol: &BSplineVolume) -> (Vec<u32>, Vec<[f32; 3]>) {
    let dom = vol.domain();
    let mut dirs = Vec::new();
    let mut pts = Vec::new();
    for d in Dir::ALL {
        let (a, b) = d.others();
        for t in iso_parameters(vol, d, ISO_PER_DIR) {
            // On the faces of `a` (running along `b`) and of `b` (along `a`).
            for (fixed, along) in [(a, b), (b, a)] {
                for end in [false, true] {
                    dirs.push(d.index() as u32);
                    let (lo, hi) = dom[along.index()];
                    for s in 0..LINE_SAMPLES {
                        let mut p = [0.0; 3];
                        p[d.index()] = t;
                        let (f0, f1) = dom[fixed.index()];
                        p[fixed.index()] = if end { f1 } else { f0 };
                        p[along.index()] = lo + (hi - lo) * s as f64 / (LINE_SAMPLES - 1) as f64;
                        pts.push(vol.point(p[0], p[1], p[2]).as_vec3().to_array());
                    }
                }
            }
        }
    }
    (dirs, pts)
}

/// Evaluates everything a viewer draws of `vol`.
pub fn evaluate(vol: &BSplineVolume, display: &mut BodyDisplay) -> BodyShape {
    display.update(vol);
    let mut shape = BodyShape {
        counts: vol.counts().map(|c| c as u32),
        lattice: vol
            .points()
            .iter()
            .map(|p| p.as_vec3().to_array())
            .collect(),
        degrees: vol.degrees().map(|p| p as u32),
        knots: Dir::ALL.map(|d| vol.knots(d).knots().iter().map(|&x| x as f32).collect()),
        ..Default::default()
    };
    for face in &display.faces {
        let base = shape.positions.len() as u32;
        shape.positions.extend_from_slice(&face.positions);
        shape.normals.extend_from_slice(&face.normals);
        shape.triangles.extend(
            face.indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    let (dirs, pts) = iso_lines(vol);
    shape.line_dirs = dirs;
    shape.line_points = pts;
    shape
}

/// One body part's volume, morph and evaluated shape.
pub struct BodyEngine {
    part: BodyPart,
    volume: BSplineVolume,
    morph: Option<Morph>,
    t: f64,
    shown: BSplineVolume,
    /// At t > 0: the lattice from the morph's source (the body on the
    /// common lattice) to the body shown, which carries the parts bound to
    /// the body along (`morph_follow`).
    follow: Option<Ffd>,
    display: BodyDisplay,
    shape: BodyShape,
}

impl BodyEngine {
    /// Builds and evaluates `part` at morph time `t` (0 without a target).
    pub fn build(part: &BodyPart, t: f64) -> Result<Self, CommandError> {
        let volume = part.lattice.checked_volume()?;
        let morph = match &part.morph_target {
            Some(target) => Some(
                Morph::new(&volume, &target.checked_volume()?, Path::Eased).map_err(|e| {
                    CommandError::new(
                        ErrorKind::InvalidValue,
                        format!("the morph target does not correspond: {e}"),
                    )
                })?,
            ),
            None => None,
        };
        let t = if morph.is_some() { t } else { 0.0 };
        let mut e = Self {
            part: part.clone(),
            shown: volume.clone(),
            volume,
            follow: morph.as_ref().map(|m| Ffd::new(m.source().clone())),
            morph,
            t,
            display: BodyDisplay::new(0, FACE_SAMPLES),
            shape: BodyShape::default(),
        };
        e.evaluate();
        Ok(e)
    }

    fn evaluate(&mut self) {
        match &self.morph {
            Some(m) if self.t > 0.0 => m.at_into(self.t, &mut self.shown),
            _ => self.shown = self.volume.clone(),
        }
        if let Some(f) = &mut self.follow
            && self.morph.is_some()
            && self.t > 0.0
        {
            // Same lattice as the source (the morph's common lattice).
            let _ = f.set_lattice(self.shown.points().to_vec());
        }
        self.shape = evaluate(&self.shown, &mut self.display);
    }

    /// The deformation the metamorphosis applies at the time shown to what
    /// is bound to this body: `None` at t = 0 (or without a morph target),
    /// where bound parts are shown as they are. Its rest lattice is the
    /// body on the morph's common lattice, its current lattice the body
    /// shown, so a point x inside the body goes to B_t(B₀⁻¹(x)).
    pub fn follow(&self) -> Option<&Ffd> {
        self.follow.as_ref().filter(|_| self.t > 0.0)
    }

    /// Shows the body at morph time `t` ∈ [0, 1].
    pub fn set_time(&mut self, t: f64) -> Result<(), CommandError> {
        if self.morph.is_none() {
            return Err(CommandError::new(
                ErrorKind::Unsupported,
                "this body has no morph target",
            ));
        }
        if !t.is_finite() || !(0.0..=1.0).contains(&t) {
            return Err(CommandError::new(
                ErrorKind::InvalidValue,
                "the morph time must lie in [0, 1]",
            ));
        }
        self.t = t;
        self.evaluate();
        Ok(())
    }

    /// The morph time shown.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The volume shown (the body, or the morph at the current time).
    pub fn shown(&self) -> &BSplineVolume {
        &self.shown
    }

    /// The evaluated shape.
    pub fn shape(&self) -> &BodyShape {
        &self.shape
    }

    /// The body frame of this shape.
    pub fn frame(&self, design: u64, part: u64, revision: u64, flags: u16) -> Option<Vec<u8>> {
        let s = &self.shape;
        BodyFrame {
            design,
            part,
            revision,
            flags,
            t: self.t as f32,
            counts: s.counts,
            lattice: s.lattice.clone(),
            positions: s.positions.clone(),
            normals: s.normals.clone(),
            triangles: s.triangles.clone(),
            line_samples: LINE_SAMPLES as u32,
            line_dirs: s.line_dirs.clone(),
            line_points: s.line_points.clone(),
            degrees: s.degrees,
            knots: s.knots.clone(),
        }
        .encode()
        .ok()
    }
}

/// The body engines of a design's body parts, kept in step with its
/// document: a part rebuilds only when its body changed.
#[derive(Default)]
pub struct BodyEngines {
    engines: BTreeMap<u64, BodyEngine>,
}

impl BodyEngines {
    /// Rebuilds the engines of `doc`'s body parts that changed (keeping
    /// their morph time), drops those of parts gone. On an error nothing
    /// changes.
    pub fn sync(&mut self, doc: &DesignDoc) -> Result<(), CommandError> {
        // First build what changed (self untouched on an error), then swap.
        let mut built = BTreeMap::new();
        for p in &doc.parts {
            let PartBody::Body(b) = &p.body else { continue };
            match self.engines.get(&p.id) {
                Some(e) if e.part == *b => {}
                prior => {
                    let t = prior.map_or(0.0, |e| e.t);
                    built.insert(p.id, BodyEngine::build(b, t)?);
                }
            }
        }
        let mut old = std::mem::take(&mut self.engines);
        for p in &doc.parts {
            if let PartBody::Body(_) = &p.body
                && let Some(e) = built.remove(&p.id).or_else(|| old.remove(&p.id))
            {
                self.engines.insert(p.id, e);
            }
        }
        Ok(())
    }

    /// The engine of body part `part`.
    pub fn get(&self, part: u64) -> Option<&BodyEngine> {
        self.engines.get(&part)
    }

    /// The morph deformation of body part `part` at the time shown (see
    /// [`BodyEngine::follow`]).
    pub fn follow(&self, part: u64) -> Option<&Ffd> {
        self.engines.get(&part).and_then(BodyEngine::follow)
    }

    /// Shows body part `part` at morph time `t`.
    pub fn set_time(&mut self, part: u64, t: f64) -> Result<(), CommandError> {
        self.engines
            .get_mut(&part)
            .ok_or_else(|| {
                CommandError::new(ErrorKind::UnknownPart, format!("no body part {part}"))
            })?
            .set_time(t)
    }
}

/// Cells per knot span and direction of a body's hexahedral grid.
pub const HEX_CELLS_PER_SPAN: usize = 4;

/// The hexahedral grid of `vol`'s interior: [`HEX_CELLS_PER_SPAN`] cells
/// per knot span and direction (at least 4 per direction) at uniform
/// parameters, with det J (the interior distribution) at every point.
pub fn hex_grid(vol: &BSplineVolume) -> HexGrid {
    let dom = vol.domain();
    let n = Dir::ALL.map(|d| (vol.knots(d).spans().len() * HEX_CELLS_PER_SPAN).max(4));
    let mut grid = HexGrid {
        scalar_name: "det_J".into(),
        ..Default::default()
    };
    let mut s = VolumeScratch::default();
    for a in 0..=n[0] {
        for b in 0..=n[1] {
            for c in 0..=n[2] {
                let t = [(a, 0), (b, 1), (c, 2)]
                    .map(|(x, d)| dom[d].0 + (dom[d].1 - dom[d].0) * x as f64 / n[d] as f64);
                let e = vol.eval(&mut s, t, 1);
                grid.points.push(e.p.to_array());
                grid.scalar.push(e.det());
            }
        }
    }
    let id = |a: usize, b: usize, c: usize| ((a * (n[1] + 1) + b) * (n[2] + 1) + c) as u64;
    for a in 0..n[0] {
        for b in 0..n[1] {
            for c in 0..n[2] {
                grid.cells.push([
                    id(a, b, c),
                    id(a + 1, b, c),
                    id(a + 1, b + 1, c),
                    id(a, b + 1, c),
                    id(a, b, c + 1),
                    id(a + 1, b, c + 1),
                    id(a + 1, b + 1, c + 1),
                    id(a, b + 1, c + 1),
                ]);
            }
        }
    }
    grid
}

/// A boundary face's name (`u_min` … `w_max`), for exports that name faces.
pub fn face_name(face: Face) -> &'static str {
    match (face.dir, face.end) {
        (Dir::U, false) => "u_min",
        (Dir::U, true) => "u_max",
        (Dir::V, false) => "v_min",
        (Dir::V, true) => "v_max",
        (Dir::W, false) => "w_min",
        (Dir::W, true) => "w_max",
    }
}
