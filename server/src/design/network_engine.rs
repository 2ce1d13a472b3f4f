//! The kernel side of a styling-curve network part (paper 004): a
//! `vsculpt_kernel::network::CurveNetwork` built from a [`NetworkPart`],
//! one patch sampler per face, and each face's sampled (or faired) mesh.
//!
//! An edit ([`NetworkEditDoc`]) changes the engine in place only when the
//! kernel accepts it (a refused edit changes nothing): a moved curve keeps
//! the faces and re-evaluates only the faces whose patch changed (the
//! samplers re-evaluate only the sides whose ribbons changed); an added or
//! removed curve re-derives the faces. A faired face keeps its faired mesh
//! until its patch changes. The meshes of every face, one after another,
//! make the part's mesh frame (kind 3).

use super::error::{CommandError, ErrorKind};
use super::model::MeshData;
use super::part::{
    CurveDoc, FairedFaceDoc, NetworkPart, RibbonHandlesDoc, check_scale, check_twist,
};
use glam::DVec3;
use std::collections::BTreeMap;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector, basis_derivs};
use vsculpt_kernel::fairing::quadric::solve_dense;
use vsculpt_kernel::fairing::{
    Control, FairingError, FairingOptions, Goals, Measure, PointMesh, Progress, Refit,
    RefitOptions, fair_implicit, refit, resolve,
};
use vsculpt_kernel::network::{CurveNetwork, NetworkError, NetworkOptions, Patch, PatchSampler};

/// A face refit for exchange: the B-spline surface and the face's outline
/// in its parameters (counter-clockwise, side k from corner k).
pub type TrimmedRefit = (Refit, Vec<[f64; 2]>);

/// Lattice segments per side of each face's sample mesh (the display and
/// fairing resolution): a five-sided face has 5·(m+1)(m+2)/2 − shared
/// points ≈ 400 at m = 12.
pub const MESH_RESOLUTION: usize = 12;
/// Default sweeps of a fairing run.
pub const DEFAULT_FAIRING_ITERATIONS: usize = 200;
/// Most sweeps of a fairing run.
pub const MAX_FAIRING_ITERATIONS: usize = 100_000;
/// A face's refit for exchange keeps every sample within this fraction of
/// the part's size (its bounding box's diagonal) — 1e-5: 1 µm on 100 mm.
pub const REFIT_TOLERANCE: f64 = 1e-5;

/// The measure fairing goals are given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeasureDoc {
    /// Mean curvature.
    Mean,
    /// Gaussian curvature.
    Gaussian,
    /// Larger principal curvature (the kernel refuses it).
    MaxPrincipal,
    /// Smaller principal curvature (the kernel refuses it).
    MinPrincipal,
}

/// Where fairing goals come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GoalDoc {
    /// One value everywhere.
    Constant(f64),
    /// Harmonic interpolation of the boundary's values.
    FromBoundary,
}

/// A fairing run as the kernel takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FairingDoc {
    /// The face.
    pub face: usize,
    /// The goals' measure.
    pub measure: MeasureDoc,
    /// The goals.
    pub goal: GoalDoc,
    /// Relaxation ω in (0, 2).
    pub relaxation: f64,
    /// Convergence threshold relative to the mesh size.
    pub tolerance: f64,
    /// Most sweeps.
    pub max_iterations: usize,
}

/// One undoable edit of a network part.
#[derive(Clone, Debug, PartialEq)]
pub enum NetworkEditDoc {
    /// Move a control point.
    MovePoint {
        /// Curve index.
        curve: usize,
        /// Control point index.
        index: usize,
        /// Where to.
        xyz: [f64; 3],
    },
    /// Drag the point at `t` of a curve, keeping its meetings.
    DragPoint {
        /// Curve index.
        curve: usize,
        /// Parameter.
        t: f64,
        /// Where to.
        xyz: [f64; 3],
    },
    /// Add a curve.
    AddCurve(CurveDoc),
    /// Remove a curve.
    RemoveCurve(usize),
    /// Fair a face.
    Fair(FairingDoc),
    /// Set a face's faired mesh (a fairing job's result; refused when the
    /// face's mesh has another number of points).
    SetFaired(FairedFaceDoc),
    /// Set side `side` of face `face`'s ribbon handles: its scale (that
    /// side of that face only) and the twist of every edge of the side
    /// (the face across follows, so the join stays G1). `None` keeps one.
    SetRibbon {
        /// The face.
        face: usize,
        /// The side (in the face's order).
        side: usize,
        /// The scale, in [1/10, 10].
        scale: Option<f64>,
        /// The twist in radians, |twist| < π/2.
        twist: Option<f64>,
    },
    /// Set face `face`'s tuning handles: the centre's offset, then one
    /// per corner (n + 1 for n sides); the interior moves, the boundary
    /// and its tangent planes stay.
    SetTuning {
        /// The face.
        face: usize,
        /// The n + 1 offsets.
        handles: Vec<[f64; 3]>,
    },
}

/// A snapshot of one face's mesh with a fairing run's settings: what a
/// fairing job runs on, off the design's thread.
#[derive(Clone, Debug, PartialEq)]
pub struct FairingInput {
    /// The face.
    pub face: usize,
    /// Its samples when the snapshot was taken.
    pub points: Vec<DVec3>,
    /// Its triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Which samples are on its boundary.
    pub boundary: Vec<bool>,
    /// The goals.
    pub goal: GoalDoc,
    /// The run's settings.
    pub options: FairingOptions,
}

impl FairingInput {
    /// Runs the fairing (the kernel's global sweeps, [`fair_implicit`]);
    /// `progress` hears of every sweep and may cancel (then the error is
    /// the kernel's `Cancelled`). The same input gives the same result to
    /// the bit wherever it runs.
    pub fn run(
        &self,
        progress: impl FnMut(&Progress) -> Control,
    ) -> Result<FairedFaceDoc, CommandError> {
        self.run_kernel(progress).map_err(fairing_error)
    }

    /// [`Self::run`] with the kernel's error as it is (a job tells a
    /// cancellation from a refusal).
    pub fn run_kernel(
        &self,
        progress: impl FnMut(&Progress) -> Control,
    ) -> Result<FairedFaceDoc, FairingError> {
        let mut mesh = PointMesh::new(
            self.points.clone(),
            self.triangles.clone(),
            self.boundary.clone(),
        )?;
        let goals = match self.goal {
            GoalDoc::Constant(g) => Goals::Constant(g),
            GoalDoc::FromBoundary => Goals::FromBoundary,
        };
        let goals = resolve(&mesh, self.options.measure, &goals)?;
        let report = fair_implicit(&mut mesh, &goals, &self.options, progress)?;
        Ok(FairedFaceDoc {
            face: self.face,
            points: mesh.points.iter().map(|p| p.to_array()).collect(),
            iterations: report.iterations,
            converged: report.converged,
        })
    }
}

fn invalid(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// A kernel network refusal as a command error: unknown indices and bad
/// values are `InvalidValue`, a network that no longer closes is
/// `Incompatible`.
pub fn network_error(e: NetworkError) -> CommandError {
    match e {
        NetworkError::Unknown { .. }
        | NetworkError::BadValue(_)
        | NetworkError::BadTolerance(_) => invalid(e.to_string()),
        other => CommandError::new(ErrorKind::Incompatible, other.to_string()),
    }
}

fn fairing_error(e: FairingError) -> CommandError {
    invalid(format!("fairing: {e}"))
}

/// The kernel curve of a document curve.
pub fn kernel_curve(c: &CurveDoc) -> Result<BSplineCurve, CommandError> {
    c.validate()?;
    let knots =
        KnotVector::new(c.degree, c.knots.clone()).map_err(|e| invalid(format!("curve: {e}")))?;
    BSplineCurve::new(knots, c.points.iter().map(|p| DVec3::from(*p)).collect())
        .map_err(|e| invalid(format!("curve: {e}")))
}

fn curve_doc(c: &BSplineCurve) -> CurveDoc {
    CurveDoc {
        degree: c.degree(),
        knots: c.knots().knots().to_vec(),
        points: c.points().iter().map(|p| p.to_array()).collect(),
    }
}

/// One face's samples: the sampler, its patch, where the samples are.
#[derive(Clone)]
struct FaceMesh {
    sampler: PatchSampler,
    patch: Patch,
    points: Vec<DVec3>,
    /// The fairing run's sweeps and convergence, when faired.
    faired: Option<(usize, bool)>,
    /// Whether the domain's counter-clockwise triangles face away from the
    /// patch normal (then they are flipped for drawing).
    flip: bool,
}

impl FaceMesh {
    fn new(patch: Patch) -> Self {
        let mut sampler = PatchSampler::new(&patch, MESH_RESOLUTION);
        let mut points = Vec::new();
        sampler.evaluate(&patch, &mut points);
        // Orientation: the first interior triangle's normal against the
        // patch's normal at the domain centre.
        let tri = sampler
            .mesh()
            .triangles
            .first()
            .copied()
            .unwrap_or([0, 0, 0]);
        let [a, b, c] = tri.map(|i| points.get(i as usize).copied().unwrap_or_default());
        let flip = (b - a).cross(c - a).dot(patch.normal(glam::DVec2::ZERO)) < 0.0;
        Self {
            sampler,
            patch,
            points,
            faired: None,
            flip,
        }
    }

    fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.sampler
            .mesh()
            .triangles
            .iter()
            .map(move |&[a, b, c]| if self.flip { [a, c, b] } else { [a, b, c] })
    }
}

/// A network part's kernel state and sample meshes.
#[derive(Clone)]
pub struct NetworkEngine {
    net: CurveNetwork,
    faces: Vec<FaceMesh>,
}

impl NetworkEngine {
    /// The engine of `part`: the network (its meetings and faces), every
    /// face's patch sampled, faired faces restored. Refused: curves that
    /// do not close their faces or enclose none, faired meshes that do not
    /// fit their face.
    pub fn build(part: &NetworkPart) -> Result<Self, CommandError> {
        part.validate()?;
        let curves = part
            .curves
            .iter()
            .map(kernel_curve)
            .collect::<Result<Vec<_>, _>>()?;
        let net = CurveNetwork::new(
            curves,
            NetworkOptions {
                tolerance: part.tolerance,
                up: DVec3::from(part.up),
            },
        )
        .map_err(network_error)?;
        if net.faces().is_empty() {
            return Err(network_error(NetworkError::NoFaces));
        }
        let mut net = net;
        set_handles(&mut net, &part.ribbons)?;
        let mut faces: Vec<FaceMesh> = net.patches().into_iter().map(FaceMesh::new).collect();
        let mut seen = std::collections::BTreeSet::new();
        for f in &part.faired {
            let face = faces
                .get_mut(f.face)
                .ok_or_else(|| invalid(format!("faired face {} does not exist", f.face)))?;
            if !seen.insert(f.face) || f.points.len() != face.points.len() {
                return Err(invalid(format!(
                    "faired face {} has {} points, its mesh {}",
                    f.face,
                    f.points.len(),
                    face.points.len()
                )));
            }
            face.points = f.points.iter().map(|p| DVec3::from(*p)).collect();
            face.faired = Some((f.iterations, f.converged));
        }
        Ok(Self { net, faces })
    }

    /// The network.
    pub fn network(&self) -> &CurveNetwork {
        &self.net
    }

    /// The part as the document keeps it.
    pub fn to_part(&self) -> NetworkPart {
        NetworkPart {
            curves: self.net.curves().iter().map(curve_doc).collect(),
            tolerance: self.net.options().tolerance,
            up: self.net.options().up.to_array(),
            faired: self
                .faces
                .iter()
                .enumerate()
                .filter_map(|(k, f)| {
                    let (iterations, converged) = f.faired?;
                    Some(FairedFaceDoc {
                        face: k,
                        points: f.points.iter().map(|p| p.to_array()).collect(),
                        iterations,
                        converged,
                    })
                })
                .collect(),
            ribbons: handles(&self.net),
            icons: Vec::new(),
        }
    }

    /// Applies `edit`; returns the faces whose mesh changed. On an error
    /// nothing changes.
    pub fn apply(&mut self, edit: &NetworkEditDoc) -> Result<Vec<usize>, CommandError> {
        match edit {
            NetworkEditDoc::MovePoint { curve, index, xyz } => {
                let mut c = self.curve(*curve)?.clone();
                let p = c.points_mut().get_mut(*index).ok_or_else(|| {
                    invalid(format!("curve {curve} has no control point {index}"))
                })?;
                *p = finite(*xyz)?;
                self.set_curve(*curve, c)
            }
            NetworkEditDoc::DragPoint { curve, t, xyz } => {
                let c = self.dragged(*curve, *t, finite(*xyz)?)?;
                self.set_curve(*curve, c)
            }
            NetworkEditDoc::AddCurve(c) => {
                let mut curves = self.net.curves().to_vec();
                if curves.len() >= super::part::MAX_NETWORK_CURVES {
                    return Err(invalid(format!(
                        "a network part has at most {} curves",
                        super::part::MAX_NETWORK_CURVES
                    )));
                }
                curves.push(kernel_curve(c)?);
                self.rebuild(curves)
            }
            NetworkEditDoc::RemoveCurve(k) => {
                self.curve(*k)?;
                let mut curves = self.net.curves().to_vec();
                curves.remove(*k);
                self.rebuild(curves)
            }
            NetworkEditDoc::Fair(f) => self.fair(f).map(|()| vec![f.face]),
            NetworkEditDoc::SetFaired(f) => self.set_faired(f).map(|()| vec![f.face]),
            NetworkEditDoc::SetRibbon {
                face,
                side,
                scale,
                twist,
            } => self.set_ribbon(*face, *side, *scale, *twist),
            NetworkEditDoc::SetTuning { face, handles } => self.set_tuning(*face, handles),
        }
    }

    /// The number of sides of face `face`, or a clear error naming how many faces there are.
    fn face_sides(&self, face: usize) -> Result<usize, CommandError> {
        let faces = self.net.faces();
        faces
            .get(face)
            .map(|f| f.sides.len())
            .ok_or_else(|| invalid(format!("no face {face} (the part has {})", faces.len())))
    }

    /// Sets a face's tuning handles (see [`NetworkEditDoc::SetTuning`]);
    /// the face is re-sampled (and loses a fair) when they changed.
    fn set_tuning(
        &mut self,
        face: usize,
        handles: &[[f64; 3]],
    ) -> Result<Vec<usize>, CommandError> {
        let sides = self.face_sides(face)?;
        if handles.len() != sides + 1 {
            return Err(invalid(format!(
                "face {face} has {sides} sides: it takes {} tuning handles (centre, then each corner), not {}",
                sides + 1,
                handles.len()
            )));
        }
        let h = handles
            .iter()
            .map(|p| finite(*p))
            .collect::<Result<Vec<_>, _>>()?;
        let mut net = self.net.clone();
        net.set_tuning(face, h).map_err(network_error)?;
        Ok(self.adopt(net))
    }

    /// Sets a side's ribbon handles (see [`NetworkEditDoc::SetRibbon`]);
    /// the faces whose patch changed are re-sampled (and lose a fair).
    fn set_ribbon(
        &mut self,
        face: usize,
        side: usize,
        scale: Option<f64>,
        twist: Option<f64>,
    ) -> Result<Vec<usize>, CommandError> {
        if scale.is_none() && twist.is_none() {
            return Err(invalid("set_ribbon needs a scale or a twist"));
        }
        let sides = self.face_sides(face)?;
        if side >= sides {
            return Err(invalid(format!(
                "face {face} has no side {side} (it has {sides})"
            )));
        }
        let mut net = self.net.clone();
        if let Some(x) = scale {
            check_scale(x).map_err(invalid)?;
            net.set_scale(face, side, x).map_err(network_error)?;
        }
        if let Some(t) = twist {
            check_twist(t).map_err(invalid)?;
            let edges = net.faces()[face].sides[side].edges.clone();
            for e in edges {
                net.set_twist(e, t).map_err(network_error)?;
            }
        }
        Ok(self.adopt(net))
    }

    fn curve(&self, k: usize) -> Result<&BSplineCurve, CommandError> {
        self.net
            .curves()
            .get(k)
            .ok_or_else(|| invalid(format!("no curve {k}")))
    }

    /// Curve `k` changed: faces keep their structure (only changed patches
    /// are re-sampled) or are re-derived.
    fn set_curve(&mut self, k: usize, c: BSplineCurve) -> Result<Vec<usize>, CommandError> {
        let mut net = self.net.clone();
        net.set_curve(k, c).map_err(network_error)?;
        if net.faces().is_empty() {
            return Err(network_error(NetworkError::NoFaces));
        }
        Ok(self.adopt(net))
    }

    /// Takes `net` (accepted by the kernel): faces of the same structure
    /// are re-sampled only where their patch changed, else every face is
    /// re-derived. Returns the faces whose mesh changed.
    fn adopt(&mut self, net: CurveNetwork) -> Vec<usize> {
        let patches = net.patches();
        let mut changed = Vec::new();
        if patches.len() == self.faces.len()
            && patches
                .iter()
                .zip(&self.faces)
                .all(|(p, f)| p.sides() == f.patch.sides())
        {
            for (i, (p, f)) in patches.into_iter().zip(&mut self.faces).enumerate() {
                if p == f.patch {
                    continue;
                }
                // The sampler re-evaluates only the sides whose ribbon
                // changed where this face uses it; none: the face's samples
                // are as they were (a faired face stays faired).
                let mut points = Vec::new();
                f.sampler.evaluate(&p, &mut points);
                let tuned = p.tuning() != f.patch.tuning();
                f.patch = p;
                if tuned || f.sampler.refreshed().iter().any(|r| *r) {
                    f.points = points;
                    f.faired = None;
                    changed.push(i);
                }
            }
        } else {
            self.faces = patches.into_iter().map(FaceMesh::new).collect();
            changed = (0..self.faces.len()).collect();
        }
        self.net = net;
        changed
    }

    fn rebuild(&mut self, curves: Vec<BSplineCurve>) -> Result<Vec<usize>, CommandError> {
        let net = CurveNetwork::new(curves, *self.net.options()).map_err(network_error)?;
        if net.faces().is_empty() {
            return Err(network_error(NetworkError::NoFaces));
        }
        self.faces = net.patches().into_iter().map(FaceMesh::new).collect();
        self.net = net;
        Ok((0..self.faces.len()).collect())
    }

    /// Curve `k` with the point at `t` taken to `to` by the smallest change
    /// of its control points (least norm) that keeps c(t_m) fixed at every
    /// meeting parameter t_m of the curve.
    fn dragged(&self, k: usize, t: f64, to: DVec3) -> Result<BSplineCurve, CommandError> {
        let c = self.curve(k)?;
        let (a, b) = c.domain();
        if !(t.is_finite() && t >= a && t <= b) {
            return Err(invalid(format!(
                "t = {t} is outside curve {k}'s [{a}, {b}]"
            )));
        }
        let mut fixed: Vec<f64> = self
            .net
            .topology()
            .vertices
            .iter()
            .flat_map(|v| v.incidences.iter())
            .filter(|(c, _)| *c == k)
            .map(|(_, tm)| *tm)
            .collect();
        fixed.sort_by(f64::total_cmp);
        fixed.dedup();
        let near = 1e-3 * (b - a);
        if let Some(tm) = fixed.iter().find(|tm| (*tm - t).abs() < near) {
            return Err(invalid(format!(
                "t = {t} is at curve {k}'s meeting at t = {tm}: drag a point between meetings"
            )));
        }
        let n = c.points().len();
        let row = |s: f64| {
            let d = basis_derivs(c.knots(), s, 0);
            let mut r = vec![0.0; n];
            for (j, v) in d.row(0).iter().enumerate() {
                if let Some(slot) = r.get_mut(d.first + j) {
                    *slot = *v;
                }
            }
            r
        };
        let mut rows = vec![row(t)];
        rows.extend(fixed.iter().map(|tm| row(*tm)));
        let m = rows.len();
        // (A Aᵀ) y = r, Δ = Aᵀ y, per coordinate.
        let mut gram = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                gram[i * m + j] = rows[i].iter().zip(&rows[j]).map(|(x, y)| x * y).sum();
            }
        }
        let delta = to - c.point(t);
        let mut moved = c.clone();
        for axis in 0..3 {
            let mut g = gram.clone();
            let mut y = vec![0.0; m];
            y[0] = delta[axis];
            if !solve_dense(&mut g, &mut y, m) {
                return Err(invalid(format!(
                    "t = {t} on curve {k} is pinned by its meetings: drag another point"
                )));
            }
            for (j, p) in moved.points_mut().iter_mut().enumerate() {
                p[axis] += rows.iter().zip(&y).map(|(r, yi)| r[j] * yi).sum::<f64>();
            }
        }
        let change = moved
            .points()
            .iter()
            .zip(c.points())
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max);
        if change > 100.0 * delta.length().max(1e-12) || !change.is_finite() {
            return Err(invalid(format!(
                "t = {t} on curve {k} is too close to its meetings: drag a point further from them"
            )));
        }
        Ok(moved)
    }

    /// Fairs a face here and now (the synchronous run; the server runs
    /// fairs as jobs, see `fairing_job`, which apply
    /// [`NetworkEditDoc::SetFaired`] with the same result).
    fn fair(&mut self, f: &FairingDoc) -> Result<(), CommandError> {
        let faired = self.fairing_input(f)?.run(|_| Control::Continue)?;
        self.set_faired(&faired)
    }

    /// What a fairing run of `f` needs, taken from the face as it is now
    /// (a snapshot a job can run on elsewhere); refused here: an unknown
    /// face, a sweep count out of range, goals in another measure than the
    /// mean or Gaussian curvature.
    pub fn fairing_input(&self, f: &FairingDoc) -> Result<FairingInput, CommandError> {
        let face = self
            .faces
            .get(f.face)
            .ok_or_else(|| invalid(format!("no face {}", f.face)))?;
        if !(1..=MAX_FAIRING_ITERATIONS).contains(&f.max_iterations) {
            return Err(invalid(format!(
                "max_iterations must be 1 ..= {MAX_FAIRING_ITERATIONS}"
            )));
        }
        let measure = match f.measure {
            MeasureDoc::Mean => Measure::Mean,
            MeasureDoc::Gaussian => Measure::Gaussian,
            MeasureDoc::MaxPrincipal => Measure::MaxPrincipal,
            MeasureDoc::MinPrincipal => Measure::MinPrincipal,
        };
        if !matches!(measure, Measure::Mean | Measure::Gaussian) {
            return Err(invalid(format!(
                "fairing toward {measure:?} curvature goals is refused: the kernel fairs toward mean- or Gaussian-curvature goals only"
            )));
        }
        let dm = face.sampler.mesh();
        Ok(FairingInput {
            face: f.face,
            points: face.points.clone(),
            triangles: dm.triangles.clone(),
            boundary: dm.boundary.clone(),
            goal: f.goal,
            options: FairingOptions {
                measure,
                relaxation: f.relaxation,
                tolerance: f.tolerance,
                max_iterations: f.max_iterations,
            },
        })
    }

    /// Whether face `input.face` still has the mesh `input` was taken
    /// from (the same points and triangles, bit for bit): then a run on
    /// `input` is exactly the run on the face as it is now.
    pub fn face_is_as(&self, input: &FairingInput) -> bool {
        self.faces.get(input.face).is_some_and(|f| {
            f.points == input.points && f.sampler.mesh().triangles == input.triangles
        })
    }

    fn set_faired(&mut self, f: &FairedFaceDoc) -> Result<(), CommandError> {
        let face = self
            .faces
            .get_mut(f.face)
            .ok_or_else(|| invalid(format!("no face {}", f.face)))?;
        if f.points.len() != face.points.len() {
            return Err(invalid(format!(
                "faired face {} has {} points, its mesh {}",
                f.face,
                f.points.len(),
                face.points.len()
            )));
        }
        let points = f
            .points
            .iter()
            .map(|p| finite(*p))
            .collect::<Result<Vec<_>, _>>()?;
        face.points = points;
        face.faired = Some((f.iterations, f.converged));
        Ok(())
    }

    /// Every face's mesh, faces one after another, with area-weighted
    /// vertex normals — except on the boundary of a patch (not faired),
    /// where the normal is the patch's own (exact): one-sided averages
    /// there would tilt by about curvature × spacing, and zebra stripes or
    /// a curvature map across a shared curve would show a crease that the
    /// patches (G1 along their curves) do not have. At a domain corner,
    /// where the patch's derivatives vanish, the average stays.
    pub fn mesh(&self) -> MeshData {
        let mut out = MeshData::default();
        for f in &self.faces {
            let base = out.positions.len() as u32;
            let mut normals = vec![DVec3::ZERO; f.points.len()];
            for [a, b, c] in f.triangles() {
                let (pa, pb, pc) = (
                    f.points[a as usize],
                    f.points[b as usize],
                    f.points[c as usize],
                );
                let n = (pb - pa).cross(pc - pa);
                for i in [a, b, c] {
                    normals[i as usize] += n;
                }
                out.indices.extend([a + base, b + base, c + base]);
            }
            if f.faired.is_none() {
                let domain = f.sampler.mesh();
                for (i, n) in normals.iter_mut().enumerate() {
                    if domain.boundary.get(i).copied().unwrap_or(false) {
                        let exact = f.patch.normal(domain.points[i]);
                        if exact.is_finite() {
                            *n = exact;
                        }
                    }
                }
            }
            out.positions
                .extend(f.points.iter().map(|p| p.as_vec3().to_array()));
            out.normals.extend(
                normals
                    .iter()
                    .map(|n| n.try_normalize().unwrap_or(DVec3::Z).as_vec3().to_array()),
            );
        }
        out
    }

    /// The mesh frame (kind 3) of every face of part `part`.
    pub fn frame(&self, design: u64, part: u64, rev: u64, drag: bool) -> axum::body::Bytes {
        let m = self.mesh();
        let pos: Vec<[f64; 3]> = m.positions.iter().map(|p| p.map(f64::from)).collect();
        let nor: Vec<[f64; 3]> = m.normals.iter().map(|p| p.map(f64::from)).collect();
        let tris: Vec<[u32; 3]> = m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let flags = if drag {
            vsculpt_protocol::frame::FLAG_DRAG
        } else {
            0
        };
        match vsculpt_protocol::MeshFrame::quantise((design, part, rev), flags, &pos, &nor, &tris)
            .and_then(|f| f.encode())
        {
            Ok(b) => axum::body::Bytes::from(b),
            Err(e) => {
                tracing::error!(design, part, "cannot encode network mesh frame: {e}");
                axum::body::Bytes::new()
            }
        }
    }

    /// Every face's refit for exchange (see [`TrimmedRefit`]): a bicubic B-spline surface fitted
    /// (the kernel's `refit`) to the face's samples at their domain points
    /// mapped from [−1, 1]² to [0, 1]² — a faired face's faired points, an
    /// unfaired face's patch sampled twice as finely as shown — each sample
    /// within [`REFIT_TOLERANCE`] of the part's size; and the face's domain
    /// polygon in those parameters (counter-clockwise, side k from corner
    /// k): the face is the polygon's part of the refit, whose parameter
    /// square also covers the domain's outside.
    pub fn refits(&self) -> Result<Vec<TrimmedRefit>, CommandError> {
        let (lo, hi) = self.faces.iter().flat_map(|f| f.points.iter()).fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(a, b), p| (a.min(*p), b.max(*p)),
        );
        let size = (hi - lo).length();
        let options = RefitOptions {
            tolerance: REFIT_TOLERANCE * size,
            ..RefitOptions::default()
        };
        let to_unit = |p: glam::DVec2| (p + glam::DVec2::ONE) * 0.5;
        self.faces
            .iter()
            .enumerate()
            .map(|(k, f)| {
                let (points, domain) = if f.faired.is_some() {
                    (f.points.clone(), f.sampler.mesh().points.clone())
                } else {
                    let mut fine = PatchSampler::new(&f.patch, 2 * MESH_RESOLUTION);
                    let mut points = Vec::new();
                    fine.evaluate(&f.patch, &mut points);
                    (points, fine.mesh().points.clone())
                };
                let params: Vec<glam::DVec2> = domain.iter().map(|p| to_unit(*p)).collect();
                let fit = refit(&points, &params, &options)
                    .map_err(|e| invalid(format!("face {k} cannot be refitted: {e}")))?;
                let outer = f
                    .patch
                    .domain()
                    .vertices()
                    .iter()
                    .map(|p| to_unit(*p).to_array())
                    .collect();
                Ok((fit, outer))
            })
            .collect()
    }

    /// The part with its meetings and faces.
    pub fn view(&self) -> NetworkView {
        NetworkView::from_network(self.to_part(), &self.net)
    }
}

/// A meeting: its point and the (curve, parameter) pairs there.
pub type MeetingView = ([f64; 3], Vec<(usize, f64)>);

/// A network part with what the kernel found of it: where its curves meet
/// and the faces they enclose (what clients are sent).
#[derive(Clone, Debug, PartialEq)]
pub struct NetworkView {
    /// The part.
    pub part: NetworkPart,
    /// Each meeting's point and the (curve, parameter) pairs there.
    pub meetings: Vec<MeetingView>,
    /// Per face, its sides as (curve, t_start, t_end).
    pub faces: Vec<Vec<(usize, f64, f64)>>,
    /// Per face, per side, its ribbon handles (scale, twist): the twist of
    /// the side's first edge (a `set_ribbon` sets every edge of the side).
    pub ribbons: Vec<Vec<(f64, f64)>>,
    /// Per face, its tuning handles (centre, then corners).
    pub tuning: Vec<Vec<[f64; 3]>>,
}

impl NetworkView {
    fn from_network(part: NetworkPart, net: &CurveNetwork) -> Self {
        Self {
            part,
            meetings: net
                .topology()
                .vertices
                .iter()
                .map(|v| (v.point.to_array(), v.incidences.clone()))
                .collect(),
            faces: net
                .faces()
                .iter()
                .map(|f| {
                    f.sides
                        .iter()
                        .map(|s| (s.curve, s.t_start, s.t_end))
                        .collect()
                })
                .collect(),
            ribbons: net
                .faces()
                .iter()
                .enumerate()
                .map(|(f, face)| {
                    face.sides
                        .iter()
                        .enumerate()
                        .map(|(k, s)| {
                            let scale = net.scale(f, k).unwrap_or(1.0);
                            let twist = s.edges.first().and_then(|&e| net.twist(e)).unwrap_or(0.0);
                            (scale, twist)
                        })
                        .collect()
                })
                .collect(),
            tuning: (0..net.faces().len())
                .map(|f| {
                    net.tuning(f)
                        .unwrap_or_default()
                        .iter()
                        .map(|h| h.to_array())
                        .collect()
                })
                .collect(),
        }
    }

    /// The view of a stored part (its network built, no patch sampled);
    /// a part the kernel refuses (it cannot be stored) shows no meetings
    /// or faces.
    pub fn of(part: &NetworkPart) -> Self {
        let net = part
            .curves
            .iter()
            .map(kernel_curve)
            .collect::<Result<Vec<_>, _>>()
            .ok()
            .and_then(|curves| {
                CurveNetwork::new(
                    curves,
                    NetworkOptions {
                        tolerance: part.tolerance,
                        up: DVec3::from(part.up),
                    },
                )
                .ok()
            })
            .and_then(|mut net| set_handles(&mut net, &part.ribbons).ok().map(|()| net));
        match net {
            Some(net) => Self::from_network(part.clone(), &net),
            None => Self {
                part: part.clone(),
                meetings: Vec::new(),
                faces: Vec::new(),
                ribbons: Vec::new(),
                tuning: Vec::new(),
            },
        }
    }
}

/// Sets a stored part's ribbon handles on its network (refused: a face,
/// side or edge the network does not have, a value out of range).
fn set_handles(net: &mut CurveNetwork, h: &RibbonHandlesDoc) -> Result<(), CommandError> {
    h.validate()?;
    for &(f, s, x) in &h.scales {
        net.set_scale(f, s, x).map_err(network_error)?;
    }
    for &(e, t) in &h.twists {
        net.set_twist(e, t).map_err(network_error)?;
    }
    for (f, handles) in &h.tuning {
        let v = handles.iter().map(|p| DVec3::from(*p)).collect();
        net.set_tuning(*f, v).map_err(network_error)?;
    }
    Ok(())
}

/// The handles of `net` that differ from the default.
fn handles(net: &CurveNetwork) -> RibbonHandlesDoc {
    let mut h = RibbonHandlesDoc::default();
    for (f, face) in net.faces().iter().enumerate() {
        for k in 0..face.sides.len() {
            if let Some(x) = net.scale(f, k)
                && x != 1.0
            {
                h.scales.push((f, k, x));
            }
        }
    }
    for e in 0..net.topology().edges.len() {
        if let Some(t) = net.twist(e)
            && t != 0.0
        {
            h.twists.push((e, t));
        }
    }
    for f in 0..net.faces().len() {
        if let Some(t) = net.tuning(f)
            && t.iter().any(|v| *v != DVec3::ZERO)
        {
            h.tuning.push((f, t.iter().map(|v| v.to_array()).collect()));
        }
    }
    h
}

fn finite(p: [f64; 3]) -> Result<DVec3, CommandError> {
    if p.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from(p))
    } else {
        Err(CommandError::new(
            ErrorKind::NotFinite,
            "coordinates must be finite (no NaN or ∞)",
        ))
    }
}

/// The network engines of a design's network parts, by part id.
pub type NetworkEngines = BTreeMap<u64, NetworkEngine>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_control_point_away_from_meetings_re_samples_only_its_face() {
        let part = super::super::network_demo::bottle_part().unwrap();
        let mut e = NetworkEngine::build(&part).unwrap();
        let before: Vec<Vec<DVec3>> = e.faces.iter().map(|f| f.points.clone()).collect();
        let mut xyz = part.curves[0].points[18];
        xyz[0] += 0.05;
        let changed = e
            .apply(&NetworkEditDoc::MovePoint {
                curve: 0,
                index: 18,
                xyz,
            })
            .unwrap();
        // The bottom ring's middle control point is under the label face
        // only (its support ends well before the meetings at ±30°).
        assert_eq!(changed.len(), 1, "{changed:?}");
        let k = changed[0];
        assert!(e.net.faces()[k].sides.iter().any(|s| s.curve == 0));
        for (i, f) in e.faces.iter().enumerate() {
            if i == k {
                assert_ne!(f.points, before[i]);
            } else {
                assert_eq!(f.points, before[i], "face {i} was re-sampled");
            }
        }
    }

    #[test]
    fn a_refused_edit_changes_nothing() {
        let part = super::super::network_demo::bottle_part().unwrap();
        let mut e = NetworkEngine::build(&part).unwrap();
        // The ring's first point is a meeting: moving it loses the meeting.
        let err = e
            .apply(&NetworkEditDoc::MovePoint {
                curve: 0,
                index: 0,
                xyz: [0.0, -1.5, 0.0],
            })
            .unwrap_err();
        assert_eq!(err.kind, ErrorKind::Incompatible, "{err:?}");
        assert_eq!(e.to_part(), part);
    }
}
