//! Free-form deformation of other parts by a body part (paper 002,
//! issue 13): the `ffd` relation ties a surface, curve or DSM part to a
//! body part, which then deforms it.
//!
//! Choices made here (protocol/README.md, `relate`):
//! * **Binding** embeds the part: every control point (a DSM part: every
//!   vertex of its mesh) is inverted into the body's parameter space
//!   (`kernel::body::invert`, or the closed form for an affine box). A point
//!   outside the body refuses the binding, naming the first such point and
//!   where it is; nothing changes.
//! * **Surface and curve parts** are deformed by moving their control
//!   points, stored in the document: at every change of the body's lattice
//!   (`body_edit`; undo and redo give back stored documents) each control
//!   point x is embedded in the lattice *before* the change, p = B_old⁻¹(x),
//!   and moved to x + B_new(p) − B_old(p). This composes (B_new ∘ B_old⁻¹
//!   after B_old ∘ B_rest⁻¹ is B_new ∘ B_rest⁻¹), so a part reshaped by its
//!   own icons between two lattice edits follows from where it is. The
//!   identity lattice moves nothing (exactly), an affine lattice move is
//!   affine on the points (to the inversion's residual: rounding for an
//!   affine box), and a point outside the moved lattice point's support
//!   does not move at all (B-spline locality).
//!   Moving control points is an *approximation* of the deformed surface
//!   φ∘S (a polynomial of much higher degree): no refit is done; the
//!   deviation is measured in `server/tests/body_ffd.rs` against the
//!   second-order bound ½·sup‖D²φ‖·Σᵢ Nᵢ(s)‖Pᵢ − S(s)‖². A control point
//!   that the part's own edits moved outside the body keeps its position
//!   (Sederberg–Parry's convention).
//! * **Icons of a bound surface or curve**: the FFD moves the part's shape
//!   (its rest shape for the solver) and the targets of its position and
//!   load icons with the same map; first-derivative (tangent) targets by
//!   its derivative Dφ and normal targets by Dφ⁻ᵀ, both at the icon's
//!   point ([`follow_vectors`]); second-derivative targets are kept.
//!   The part is then rebuilt and solved with its icons and relations.
//! * **DSM parts** are derived from their DSM data, so the deformation is
//!   applied to the mesh, from the body's lattice when the part was bound
//!   (stored in the relation as `rest`): each vertex x maps to
//!   B(u, v, w) + (x − B_rest(u, v, w)), which is B(u, v, w) up to the
//!   inversion residual (zero for an affine box), exactly x for the
//!   identity lattice. A change of one lattice point recomputes only the
//!   vertices in its support ([`Ffd::move_point_listed`]); the normals are
//!   recomputed from the deformed triangles around them only (each
//!   triangle's cross product once, kept per triangle). A DSM edit re-meshes and
//!   re-embeds; vertices outside the rest body then keep their positions.
//! * **Morph playback** carries bound parts along for display
//!   (`morph_follow`); the document keeps them as the body's lattice left
//!   them.
//! * **Exports** of a bound DSM part (`?part=`) deform the mesh made for the
//!   export the same way ([`deform_export`]): the body's stored lattice, so
//!   what is exported is what the document holds (morph time 0).
//! * **Unbinding** (`unrelate`, or deleting the body, which unbinds): a
//!   surface or curve keeps its deformed shape; a DSM mesh shows its own
//!   shape again. A part follows one body at most.

use super::body_part::LatticeDoc;
use super::doc::{DerivativeDoc, DesignDoc, IconDoc, IconRoleDoc};
use super::dsm_engine::DsmEngine;
use super::error::{CommandError, ErrorKind};
use super::ffd_frame::FfdFrame;
use super::part::{PartBody, RelationKind};
use glam::{DMat3, DVec3};
use std::collections::BTreeMap;
use vsculpt_kernel::body::{BSplineVolume, Embedding, Ffd, Inverter};
use vsculpt_kernel::dsm::Mesh;
use vsculpt_protocol::dsm::DsmData;

/// How far from the body a point may be after inversion and still count as
/// inside, relative to the diagonal of the lattice's bounding box.
pub const INSIDE_TOLERANCE: f64 = 1e-9;

fn out_of_range(msg: String) -> CommandError {
    CommandError::new(ErrorKind::InvalidValue, msg)
}

/// The absolute inside tolerance of `vol`.
fn tolerance(vol: &BSplineVolume) -> f64 {
    let (lo, hi) = vol
        .points()
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    INSIDE_TOLERANCE * (hi - lo).length().max(1e-300)
}

/// `points` embedded in `vol`; refused (naming the first point outside, as
/// `what` calls it, and how far from the body it is) unless all are inside.
pub fn embed_all(
    vol: &BSplineVolume,
    points: &[DVec3],
    what: &str,
) -> Result<(Ffd, Embedding), CommandError> {
    let ffd = Ffd::new(vol.clone());
    let emb = ffd
        .embed(points, tolerance(vol))
        .map_err(|e| out_of_range(format!("ffd: {e}")))?;
    if emb.outside() > 0 {
        let i = (0..emb.len())
            .find(|&i| emb.params(i)[0].is_nan())
            .unwrap_or(0);
        let x = points[i];
        let off = Inverter::new(vol)
            .invert(x, tolerance(vol) * 1e-3)
            .map(|r| r.distance)
            .unwrap_or(f64::NAN);
        return Err(out_of_range(format!(
            "{what} {i} at ({:.4}, {:.4}, {:.4}) lies outside the body ({off:.4} from it; {} of {} outside): only geometry inside a body can be bound to it",
            x.x,
            x.y,
            x.z,
            emb.outside(),
            emb.len()
        )));
    }
    Ok((ffd, emb))
}

/// Moves `points` by the change of lattice `old` → `new` (same knots):
/// x + B_new(p) − B_old(p) with p the parameters of x in `old`. Points
/// outside `old` keep their positions.
pub fn follow(
    old: &BSplineVolume,
    new: &BSplineVolume,
    points: &mut [DVec3],
) -> Result<(), CommandError> {
    let kernel = |e: vsculpt_kernel::body::BodyError| out_of_range(format!("ffd: {e}"));
    let before = Ffd::new(old.clone());
    let emb = before.embed(points, tolerance(old)).map_err(kernel)?;
    let mut after = before.clone();
    after.set_lattice(new.points().to_vec()).map_err(kernel)?;
    let mut a = vec![DVec3::ZERO; points.len()];
    let mut b = vec![DVec3::ZERO; points.len()];
    before.deform_all(&emb, &mut a).map_err(kernel)?;
    after.deform_all(&emb, &mut b).map_err(kernel)?;
    for ((x, a), b) in points.iter_mut().zip(&a).zip(&b) {
        *x += *b - *a;
    }
    Ok(())
}

/// The part bound to body `body` by relation kinds in `doc`, with the
/// relation's rest lattice.
fn bound_to(doc: &DesignDoc, body: u64) -> Vec<(u64, Option<&LatticeDoc>)> {
    doc.relations
        .iter()
        .filter_map(|r| match &r.kind {
            RelationKind::Ffd {
                body: b,
                part,
                rest,
            } if *b == body => Some((*part, rest.as_ref())),
            _ => None,
        })
        .collect()
}

/// The surface and curve parts bound to body `body` in `doc`.
pub fn bound_bspline_parts(doc: &DesignDoc, body: u64) -> Vec<u64> {
    bound_to(doc, body)
        .into_iter()
        .filter(|(p, _)| {
            matches!(
                doc.part(*p).map(|p| &p.body),
                Some(PartBody::Surface(_) | PartBody::Curve(_))
            )
        })
        .map(|(p, _)| p)
        .collect()
}

/// After body `body`'s lattice changed from `old` to what `doc` holds:
/// moves the control points (and position and load icon targets, and the
/// tangent and normal targets: [`follow_vectors`]) of the surface and curve
/// parts bound to it. Returns their ids.
pub fn follow_body(
    doc: &mut DesignDoc,
    body: u64,
    old: &LatticeDoc,
) -> Result<Vec<u64>, CommandError> {
    let parts = bound_bspline_parts(doc, body);
    if parts.is_empty() {
        return Ok(parts);
    }
    let new = match doc.part(body).map(|p| &p.body) {
        Some(PartBody::Body(b)) => b.lattice.volume()?,
        _ => return Ok(Vec::new()),
    };
    let old = old.volume()?;
    for id in &parts {
        let Some(p) = doc.part_mut(*id) else { continue };
        let (points, icons) = match &mut p.body {
            PartBody::Surface(s) => (&mut s.surface.points, &mut s.icons),
            PartBody::Curve(c) => (&mut c.curve.points, &mut c.icons),
            _ => continue,
        };
        let mut xs: Vec<DVec3> = points.iter().map(|p| DVec3::from(*p)).collect();
        let moves = |r: IconRoleDoc| matches!(r, IconRoleDoc::Position | IconRoleDoc::Load);
        xs.extend(
            icons
                .iter()
                .filter(|i| moves(i.role))
                .map(|i| DVec3::from(i.target)),
        );
        follow(&old, &new, &mut xs)?;
        let n = points.len();
        for (p, x) in points.iter_mut().zip(&xs) {
            *p = x.to_array();
        }
        for (i, x) in icons.iter_mut().filter(|i| moves(i.role)).zip(&xs[n..]) {
            i.target = x.to_array();
        }
        follow_vectors(&old, &new, icons);
    }
    Ok(parts)
}

/// The derivative of the lattice change φ(x) = x + B_new(p) − B_old(p),
/// p = B_old⁻¹(x), at `x`: Dφ = J_new(p) · J_old(p)⁻¹. None when `x` is
/// outside the old body or J_old is singular there (its vectors are kept,
/// as a point outside keeps its position).
fn change_jacobian(
    old: &BSplineVolume,
    new: &BSplineVolume,
    inverter: &Inverter,
    x: DVec3,
) -> Option<DMat3> {
    let inv = inverter.invert(x, 1e-3 * tolerance(old)).ok()?;
    if inv.distance > tolerance(old) {
        return None;
    }
    let [u, v, w] = inv.uvw;
    let j_old = old.jacobian(u, v, w);
    let det = j_old.determinant();
    let scale = j_old.x_axis.length() * j_old.y_axis.length() * j_old.z_axis.length();
    if !det.is_finite() || det.abs() <= 1e-12 * scale {
        return None;
    }
    Some(new.jacobian(u, v, w) * j_old.inverse())
}

/// Maps the vector targets of `icons` (on a bound surface or curve) through
/// the lattice change from `old` to `new`, at the point where each icon
/// sits: a first-derivative target (w_u, w_v) is a tangent vector, so
/// t ↦ Dφ t (the chain rule: (φ∘S)_u = Dφ S_u); a normal target is a
/// normal, so n ↦ Dφ⁻ᵀ n, scaled back to its length (the deformed
/// tangents stay orthogonal to it). Second-derivative targets (w_uu, w_vv,
/// w_uv) would need D²φ and the surface's first derivatives there, and
/// are kept.
fn follow_vectors(old: &BSplineVolume, new: &BSplineVolume, icons: &mut [IconDoc]) {
    // Some(true): a normal; Some(false): a tangent; None: not a vector mapped.
    let kind = |r: IconRoleDoc| match r {
        IconRoleDoc::Derivative {
            which: DerivativeDoc::R | DerivativeDoc::V,
        } => Some(false),
        IconRoleDoc::Normal => Some(true),
        _ => None,
    };
    if icons.iter().all(|i| kind(i.role).is_none()) {
        return;
    }
    let inverter = Inverter::new(old);
    for icon in icons {
        let Some(normal) = kind(icon.role) else {
            continue;
        };
        let Some(d) = change_jacobian(old, new, &inverter, DVec3::from(icon.xyz)) else {
            continue;
        };
        let t = DVec3::from(icon.target);
        let mapped = if normal {
            (d.inverse().transpose() * t).normalize_or_zero() * t.length()
        } else {
            d * t
        };
        if mapped.is_finite() && (mapped != DVec3::ZERO || t == DVec3::ZERO) {
            icon.target = mapped.to_array();
        }
    }
}

/// Checks a new `ffd` relation of `part` to `body` in `doc` (kinds, one
/// body per part, lock) and, for a surface or curve, that its control
/// points lie inside the body.
pub fn check_bind(doc: &DesignDoc, body: u64, part: u64) -> Result<(), CommandError> {
    let incompatible = |m: String| CommandError::new(ErrorKind::Incompatible, m);
    let unknown = |id: u64| CommandError::new(ErrorKind::UnknownPart, format!("no part {id}"));
    let b = doc.part(body).ok_or_else(|| unknown(body))?;
    let PartBody::Body(bp) = &b.body else {
        return Err(incompatible(format!(
            "part {body} is a {}: an ffd relation's `body` must be a body part",
            b.body.kind()
        )));
    };
    let p = doc.part(part).ok_or_else(|| unknown(part))?;
    if p.locked {
        return Err(CommandError::new(
            ErrorKind::Locked,
            format!("part {} ({}) is locked: unlock it first", p.id, p.name),
        ));
    }
    let points: Vec<DVec3> = match &p.body {
        PartBody::Surface(s) => s.surface.points.iter().map(|p| DVec3::from(*p)).collect(),
        PartBody::Curve(c) => c.curve.points.iter().map(|p| DVec3::from(*p)).collect(),
        // Its mesh is checked by the model, which holds it.
        PartBody::Dsm(_) => Vec::new(),
        other => {
            return Err(incompatible(format!(
                "part {part} is a {}: only a surface, curve or dsm part can be bound to a body",
                other.kind()
            )));
        }
    };
    if let Some(r) = doc
        .relations
        .iter()
        .find(|r| matches!(r.kind, RelationKind::Ffd { part: q, .. } if q == part))
    {
        return Err(CommandError::new(
            ErrorKind::Conflict,
            format!(
                "part {part} is bound to a body already (relation {}): unbind it first",
                r.id
            ),
        ));
    }
    if !points.is_empty() {
        embed_all(&bp.lattice.volume()?, &points, "control point")?;
    }
    Ok(())
}

/// One bound DSM part's deformed mesh.
struct DsmFfd {
    body: u64,
    rest: LatticeDoc,
    /// The DSM data its mesh was made from.
    data: DsmData,
    ffd: Ffd,
    emb: Embedding,
    mesh: Mesh,
    /// The triangles around each vertex (CSR: `around[start[v]..start[v + 1]]`).
    start: Vec<u32>,
    around: Vec<u32>,
    /// Per triangle, (b − a) × (c − a) of the deformed mesh (kept current:
    /// a vertex normal sums these).
    cross: Vec<DVec3>,
    /// Per vertex and per triangle, the update that last listed it (`stamp`).
    mark: Vec<u32>,
    tri_mark: Vec<u32>,
    stamp: u32,
    /// Scratch lists of one update: recomputed vertices, their triangles,
    /// the vertices of those triangles.
    listed: Vec<u32>,
    tris: Vec<u32>,
    verts: Vec<u32>,
    /// The mesh frame, kept encoded and patched where an update moved
    /// vertices ([`super::ffd_frame`]).
    frame: FfdFrame,
}

impl DsmFfd {
    fn build(
        body: u64,
        rest: &LatticeDoc,
        current: &BSplineVolume,
        data: &DsmData,
        mesh: &Mesh,
    ) -> Result<Self, CommandError> {
        let vol = rest.volume()?;
        let kernel = |e: vsculpt_kernel::body::BodyError| out_of_range(format!("ffd: {e}"));
        let mut ffd = Ffd::new(vol.clone());
        let mut emb = ffd
            .embed(&mesh.positions, tolerance(&vol))
            .map_err(kernel)?;
        emb.carry_residual(&ffd).map_err(kernel)?;
        ffd.set_lattice(current.points().to_vec()).map_err(kernel)?;
        let mut out = mesh.clone();
        ffd.deform_all(&emb, &mut out.positions).map_err(kernel)?;
        renormal(&mut out);
        let n = out.positions.len();
        let mut start = vec![0u32; n + 1];
        for t in &out.triangles {
            for &v in t {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut around = vec![0u32; 3 * out.triangles.len()];
        for (k, t) in out.triangles.iter().enumerate() {
            for &v in t {
                around[fill[v as usize] as usize] = k as u32;
                fill[v as usize] += 1;
            }
        }
        let cross = out
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| out.positions[i as usize]);
                (b - a).cross(c - a)
            })
            .collect();
        Ok(Self {
            body,
            rest: rest.clone(),
            data: data.clone(),
            ffd,
            emb,
            cross,
            mark: vec![0; n],
            tri_mark: vec![0; out.triangles.len()],
            stamp: 0,
            listed: Vec::new(),
            tris: Vec::new(),
            verts: Vec::new(),
            frame: FfdFrame::default(),
            mesh: out,
            start,
            around,
        })
    }

    /// Moves to lattice `current` (same knots as the rest): only the moved
    /// lattice points' supports are recomputed, and the normals of the
    /// vertices that share a triangle with a recomputed vertex (with
    /// `full`, every vertex and normal). Returns how many lattice points
    /// moved.
    fn update(&mut self, current: &BSplineVolume, full: bool) -> Result<usize, CommandError> {
        let kernel = |e: vsculpt_kernel::body::BodyError| out_of_range(format!("ffd: {e}"));
        let moved: Vec<(usize, DVec3)> = current
            .points()
            .iter()
            .zip(self.ffd.lattice().points())
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(i, (a, _))| (i, *a))
            .collect();
        if full && !moved.is_empty() {
            // Every vertex and every normal, as before locality was used
            // (kept to measure against: `DsmFfds::set_full_recompute`).
            self.ffd
                .set_lattice(current.points().to_vec())
                .map_err(kernel)?;
            self.ffd
                .deform_all(&self.emb, &mut self.mesh.positions)
                .map_err(kernel)?;
            renormal(&mut self.mesh);
            self.frame.forget();
            let m = &self.mesh;
            for (c, t) in self.cross.iter_mut().zip(&m.triangles) {
                let [a, b, c3] = t.map(|i| m.positions[i as usize]);
                *c = (b - a).cross(c3 - a);
            }
            return Ok(moved.len());
        }
        self.listed.clear();
        for &(i, p) in &moved {
            self.ffd
                .move_point_listed(i, p, &self.emb, &mut self.mesh.positions, &mut self.listed)
                .map_err(kernel)?;
        }
        if !moved.is_empty() {
            self.renormal_listed();
            // The vertices whose position or normal may have changed: the
            // listed ones and those sharing a triangle with one.
            let listed = self.listed.iter().copied();
            self.frame
                .moved(&self.mesh, listed.chain(self.verts.iter().copied()));
        }
        Ok(moved.len())
    }
}

impl DsmFfd {
    /// Recomputes the normals around the vertices the last update listed
    /// (the others cannot change): each triangle touching one gets its
    /// cross product once, then each vertex of those triangles sums its
    /// triangles' (in triangle order, as [`renormal`] does: the same
    /// numbers).
    fn renormal_listed(&mut self) {
        let m = &mut self.mesh;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.mark.fill(0);
            self.tri_mark.fill(0);
            self.stamp = 1;
        }
        let stamp = self.stamp;
        self.tris.clear();
        for &v in &self.listed {
            let (s, e) = (
                self.start[v as usize] as usize,
                self.start[v as usize + 1] as usize,
            );
            for &t in &self.around[s..e] {
                if self.tri_mark[t as usize] != stamp {
                    self.tri_mark[t as usize] = stamp;
                    self.tris.push(t);
                }
            }
        }
        self.verts.clear();
        for &t in &self.tris {
            let tri = m.triangles[t as usize];
            let [a, b, c] = tri.map(|i| m.positions[i as usize]);
            self.cross[t as usize] = (b - a).cross(c - a);
            for w in tri {
                if self.mark[w as usize] != stamp {
                    self.mark[w as usize] = stamp;
                    self.verts.push(w);
                }
            }
        }
        for &v in &self.verts {
            let (s, e) = (
                self.start[v as usize] as usize,
                self.start[v as usize + 1] as usize,
            );
            let mut n = DVec3::ZERO;
            for &t in &self.around[s..e] {
                n += self.cross[t as usize];
            }
            m.normals[v as usize] = n.normalize_or_zero();
        }
    }
}

/// Area-weighted vertex normals of `m`'s triangles.
pub fn renormal(m: &mut Mesh) {
    let mut n = vec![DVec3::ZERO; m.positions.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let f = (b - a).cross(c - a);
        for i in t {
            n[*i as usize] += f;
        }
    }
    for (out, v) in m.normals.iter_mut().zip(n) {
        *out = v.normalize_or_zero();
    }
}

/// The deformed meshes of a design's bound DSM parts.
#[derive(Default)]
pub struct DsmFfds {
    parts: BTreeMap<u64, DsmFfd>,
    /// Recompute every vertex at a lattice change (no locality): only to
    /// measure what locality buys (`server/benches/ffd.rs`).
    full: bool,
}

impl DsmFfds {
    /// With `full`, a lattice change recomputes every vertex and normal of
    /// the bound meshes instead of the moved points' supports (the same
    /// result to rounding; kept to measure locality against).
    pub fn set_full_recompute(&mut self, full: bool) {
        self.full = full;
    }

    /// Brings the deformed meshes in step with `doc` (its `ffd` relations
    /// of DSM parts, its bodies' lattices) and `dsm` (the meshes). Returns
    /// the DSM parts whose mesh as shown changed. On an error nothing
    /// changes.
    pub fn sync(&mut self, doc: &DesignDoc, dsm: &DsmEngine) -> Result<Vec<u64>, CommandError> {
        let mut next = BTreeMap::new();
        let mut changed = Vec::new();
        let mut old = std::mem::take(&mut self.parts);
        let result = (|| {
            for r in &doc.relations {
                let RelationKind::Ffd {
                    body,
                    part,
                    rest: Some(rest),
                } = &r.kind
                else {
                    continue;
                };
                let (Some(PartBody::Dsm(d)), Some(PartBody::Body(b)), Some(mesh)) = (
                    doc.part(*part).map(|p| &p.body),
                    doc.part(*body).map(|p| &p.body),
                    dsm.mesh(*part),
                ) else {
                    continue;
                };
                let current = b.lattice.volume()?;
                let e = match old.remove(part) {
                    Some(mut e) if e.body == *body && e.rest == *rest && e.data == d.dsm => {
                        if e.update(&current, self.full)? > 0 {
                            changed.push(*part);
                        }
                        e
                    }
                    _ => {
                        changed.push(*part);
                        DsmFfd::build(*body, rest, &current, &d.dsm, mesh)?
                    }
                };
                next.insert(*part, e);
            }
            Ok::<(), CommandError>(())
        })();
        if let Err(e) = result {
            // Entries already updated may differ from before: rebuild them
            // from scratch at the next sync rather than keep a half state.
            self.parts.clear();
            return Err(e);
        }
        changed.extend(old.into_keys().filter(|k| doc.part(*k).is_some()));
        self.parts = next;
        Ok(changed)
    }

    /// Part `id`'s deformed mesh, if it is a bound DSM part.
    pub fn mesh(&self, id: u64) -> Option<&Mesh> {
        self.parts.get(&id).map(|e| &e.mesh)
    }

    /// Part `id`'s deformed mesh frame (kind 3) at revision `rev`, with the
    /// mesh delta (kind 8) from the frame of it handed out before when there
    /// is one ([`super::ffd_frame`]: the frame is kept encoded and patched
    /// where lattice edits moved vertices).
    pub fn frame(
        &self,
        design: u64,
        id: u64,
        rev: u64,
        drag: bool,
    ) -> Option<(axum::body::Bytes, Option<super::dsm_delta::MeshDeltaFrame>)> {
        let e = self.parts.get(&id)?;
        e.frame.frame(&e.mesh, design, id, rev, drag)
    }
}

/// The deformation of DSM part `part`'s export mesh by the body it is bound
/// to in `doc`: (rest lattice, current lattice), or `None` when the part is
/// not bound.
pub fn export_deformation(doc: &DesignDoc, part: u64) -> Option<(LatticeDoc, LatticeDoc)> {
    doc.relations.iter().find_map(|r| match &r.kind {
        RelationKind::Ffd {
            body,
            part: p,
            rest: Some(rest),
        } if *p == part => match doc.part(*body).map(|b| &b.body) {
            Some(PartBody::Body(b)) => Some((rest.clone(), b.lattice.clone())),
            _ => None,
        },
        _ => None,
    })
}

/// Deforms `mesh` (a bound DSM part's mesh made for an export, finer or
/// coarser than the one shown) by the body: each vertex embedded in the
/// `rest` lattice, carrying its inversion residual, and mapped by the
/// `current` lattice — as the mesh shown is; vertices outside the rest
/// body keep their places. Normals are recomputed from the triangles.
pub fn deform_export(
    rest: &LatticeDoc,
    current: &LatticeDoc,
    mesh: &mut Mesh,
) -> Result<(), CommandError> {
    let kernel = |e: vsculpt_kernel::body::BodyError| out_of_range(format!("ffd: {e}"));
    let vol = rest.volume()?;
    let mut ffd = Ffd::new(vol.clone());
    let mut emb = ffd
        .embed(&mesh.positions, tolerance(&vol))
        .map_err(kernel)?;
    emb.carry_residual(&ffd).map_err(kernel)?;
    ffd.set_lattice(current.volume()?.points().to_vec())
        .map_err(kernel)?;
    ffd.deform_all(&emb, &mut mesh.positions).map_err(kernel)?;
    renormal(mesh);
    Ok(())
}

/// The rest lattice a new `ffd` relation of DSM part `part` to `body`
/// stores (the body's lattice now), after checking that every vertex of
/// the part's mesh lies inside the body; `None` for other parts.
pub fn dsm_rest(
    doc: &DesignDoc,
    dsm: &DsmEngine,
    body: u64,
    part: u64,
) -> Result<Option<LatticeDoc>, CommandError> {
    let (Some(PartBody::Dsm(_)), Some(PartBody::Body(b))) = (
        doc.part(part).map(|p| &p.body),
        doc.part(body).map(|p| &p.body),
    ) else {
        return Ok(None);
    };
    if let Some(m) = dsm.mesh(part) {
        embed_all(&b.lattice.volume()?, &m.positions, "mesh vertex")?;
    }
    Ok(Some(b.lattice.clone()))
}
