//! Union of bodies (paper 002 §3) as a set operation on their boundaries.
//!
//! Every body's six faces are sampled into a triangle mesh (oriented
//! outward); each mesh is then clipped against every other body, keeping
//! what lies outside it. The bodies are exact solids, so a point is
//! classified against a body exactly, not against a tessellation of it:
//! point inversion ([`Inverter`]) finds (u, v, w) with x(u, v, w) = x, and
//!
//! * **inside** — the inversion converges (distance ≤ 1e-9 of the body's
//!   size) at parameters strictly inside the domain;
//! * **on** — it converges on the domain's boundary (a face of the body):
//!   where the two boundaries lie on each other (normals parallel) the
//!   point is interior to the union when the normals oppose, and kept on
//!   one side only (the lower-numbered body's) when they agree; where the
//!   boundaries cross, each triangle at the point is judged by a point of
//!   it just beside the vertex;
//! * **outside** — otherwise (the inversion stops at the nearest boundary
//!   parameter it can reach, off the point).
//!
//! A triangle is clipped polygon by polygon (Sutherland–Hodgman with the
//! classification as the half-space test): outside and on vertices stay,
//! inside ones go, and an edge from inside to outside is cut where it
//! crosses the other body's boundary, found by bisection of the
//! classification to 2⁻⁴⁸ of the edge. Cuts are cached per mesh edge, so
//! neighbouring triangles share them and each body's part of the union is
//! one connected mesh. With the on-face rule above, faces the bodies share
//! (a lattice's joints, the chair) go from both bodies, and a face lying
//! partly on another body's face with the same orientation is cut where
//! they part.
//!
//! What is exact and what is not: vertices are points of the bodies'
//! boundaries (samples, exact) and cuts lie on the other body's boundary to
//! the classification's tolerance (1e-9 of its size) and on this body's
//! boundary to its chord error; where bodies are bounded by planes (affine
//! lattices) the union is exact to that tolerance. The seam between two
//! bodies is cut on each side separately; the pieces are then welded into
//! one closed, manifold mesh ([`super::weld`]: copies of a vertex merged,
//! each side's seam vertices inserted into the other side's seam edges,
//! what is left open — where three bodies meet — fanned shut; checked,
//! and where that leaves it broken, each seam's two border loops zipped
//! by a strip). Before clipping, each body's samples are refined locally
//! where another body crosses a triangle without any of its corners
//! changing side (`subdivide`: an edge crossed twice, a pocket, a sharp
//! edge of the other body piercing it), new vertices on the exact faces.
//! What that leaves — a body still poking deep through the inside of a
//! sampled triangle without containing any of its vertices, or a mesh
//! that cannot be welded — is refused: [`BodyError::TooCoarse`] — sample
//! finer than the features that meet.

use glam::DVec3;

use super::subdivide::resolve;
use super::weld::{Pieces, WeldReport, weld};
use super::{BSplineVolume, BodyError, Dir, Face, Inverter, VolumeScratch};

/// Vertices closer than this, relative to the diagonal of the bodies' box,
/// are one when the pieces are welded (10× the classification's
/// tolerance: the copies of a vertex along body edges and shared faces
/// differ by rounding, cuts by the classification's tolerance).
pub const WELD: f64 = 1e-8;

/// Bisection steps for a cut: 2⁻⁴⁸ of the edge length.
const CUT_STEPS: usize = 48;

/// How far towards a triangle's centre the point is taken that decides
/// which side of another body the triangle leaves a crossing vertex on.
const NEAR: f64 = 1e-3;

/// The boundary of a union of bodies as a triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UnionMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles (indices into `positions`), counter-clockwise seen from
    /// outside the union.
    pub triangles: Vec<[usize; 3]>,
    /// For each triangle, the body whose boundary it lies on.
    pub body: Vec<usize>,
    /// What welding the bodies' pieces into one closed mesh did.
    pub weld: WeldReport,
    /// Vertices inserted by local subdivision where another body crossed a
    /// sampled triangle unseen by its corners (`subdivide`).
    pub subdivided: usize,
}

impl UnionMesh {
    /// The total area of the triangles.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| self.normal(t).length() / 2.0)
            .sum()
    }

    /// The volume enclosed, by the divergence theorem (Σ p₀ · (p₁ × p₂) / 6
    /// over the triangles): the union's volume when the triangles cover its
    /// boundary outward.
    pub fn enclosed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    fn normal(&self, t: &[usize; 3]) -> DVec3 {
        let [a, b, c] = t.map(|i| self.positions[i]);
        (b - a).cross(c - a)
    }
}

/// Where a point lies with respect to one body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Side {
    In,
    Out,
    /// On the boundary, at parameters `uvw`.
    On([f64; 3]),
}

/// What becomes of a point of one body's boundary when clipped by another.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Fate {
    /// Outside the other body (or on a face both share with the same
    /// orientation, kept on this side).
    Keep,
    /// Inside it, or on a face shared with opposite orientation (interior
    /// to the union), or with the same orientation kept on the other side.
    Drop,
    /// On its boundary where the two boundaries cross: a vertex of the
    /// cut; each triangle at it decides from a point beside it.
    Touch,
}

/// |cos| of the angle between two normals above which faces are taken as
/// lying on each other.
const PARALLEL: f64 = 1.0 - 1e-6;

/// One body ready for classification.
pub(super) struct Solid<'a> {
    pub(super) volume: &'a BSplineVolume,
    inverter: Inverter<'a>,
    /// Distance below which an inversion has converged (model units).
    tolerance: f64,
    /// The box around the control points (the body lies in their hull).
    pub(super) lo: DVec3,
    pub(super) hi: DVec3,
}

impl<'a> Solid<'a> {
    fn new(volume: &'a BSplineVolume) -> Self {
        let (lo, hi) = volume
            .points()
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        let size = (hi - lo).length().max(f64::MIN_POSITIVE);
        let tolerance = 1e-9 * size;
        Self {
            volume,
            inverter: Inverter::new(volume),
            tolerance,
            lo: lo - DVec3::splat(tolerance),
            hi: hi + DVec3::splat(tolerance),
        }
    }

    /// The parameter distance of `uvw` from face (dir, end), relative to the
    /// domain's extent.
    fn gap(&self, uvw: [f64; 3], dir: Dir, end: bool) -> f64 {
        let (a, b) = self.volume.domain()[dir.index()];
        let t = uvw[dir.index()];
        (if end { b - t } else { t - a }) / (b - a)
    }

    /// Where `x` lies with respect to the body (exactly: point inversion).
    pub(super) fn side(&self, x: DVec3) -> Result<Side, BodyError> {
        if !x.is_finite() {
            return Err(BodyError::NonFinite("a point to classify".into()));
        }
        if x.cmplt(self.lo).any() || x.cmpgt(self.hi).any() {
            return Ok(Side::Out);
        }
        let inv = self.inverter.invert(x, 1e-3 * self.tolerance)?;
        if inv.distance > self.tolerance {
            return Ok(Side::Out);
        }
        let depth = Face::ALL
            .iter()
            .map(|f| self.gap(inv.uvw, f.dir, f.end))
            .fold(f64::INFINITY, f64::min);
        Ok(if depth > 1e-9 {
            Side::In
        } else {
            Side::On(inv.uvw)
        })
    }

    /// The unit outward normal at boundary parameters `uvw`; on an edge or
    /// corner (several faces meet), that of the face most nearly parallel
    /// to `n`.
    fn outward(&self, uvw: [f64; 3], n: DVec3) -> DVec3 {
        let mut s = VolumeScratch::default();
        let mut best: Option<(f64, DVec3)> = None;
        for face in Face::ALL {
            if self.gap(uvw, face.dir, face.end) > 1e-9 {
                continue;
            }
            let m = face_outward(self.volume, &mut s, face, uvw).normalize_or_zero();
            let score = n.dot(m).abs();
            if best.is_none_or(|(b, _)| score > b) {
                best = Some((score, m));
            }
        }
        best.map_or(DVec3::ZERO, |(_, m)| m)
    }

    /// The fate of point `x` of another body's boundary with unit outward
    /// normal `n` (see [`Fate`]).
    fn fate(&self, x: DVec3, n: DVec3, keep_shared: bool) -> Result<Fate, BodyError> {
        Ok(self.fate_of(self.side(x)?, n, keep_shared))
    }

    /// The fate of a point on `side` of the body with unit outward normal
    /// `n`.
    fn fate_of(&self, side: Side, n: DVec3, keep_shared: bool) -> Fate {
        match side {
            Side::Out => Fate::Keep,
            Side::In => Fate::Drop,
            Side::On(uvw) => {
                let c = n.dot(self.outward(uvw, n));
                if c > PARALLEL && keep_shared {
                    Fate::Keep
                } else if c.abs() > PARALLEL {
                    Fate::Drop
                } else {
                    Fate::Touch
                }
            }
        }
    }
}

/// The outward normal (unnormalised) of `face` of `vol` at `uvw`.
pub(super) fn face_outward(
    vol: &BSplineVolume,
    s: &mut VolumeScratch,
    face: Face,
    uvw: [f64; 3],
) -> DVec3 {
    let d = vol.eval(s, uvw, 1);
    let (a, b) = face.dir.others();
    let n = d.d[a.index()].cross(d.d[b.index()]);
    // Into the body is +x_dir at the start face (det J > 0), −x_dir at the end.
    let inward = if face.end {
        -d.d[face.dir.index()]
    } else {
        d.d[face.dir.index()]
    };
    if n.dot(inward) > 0.0 { -n } else { n }
}

/// The parameters of `per_span` equal steps in every knot span of `dir`.
fn samples(vol: &BSplineVolume, dir: Dir, per_span: usize) -> Vec<f64> {
    let kv = vol.knots(dir);
    let mut out = Vec::new();
    for (_, a, b) in kv.spans() {
        for s in 0..per_span {
            out.push(a + (b - a) * s as f64 / per_span as f64);
        }
    }
    out.push(kv.domain().1);
    out
}

/// One body's part of the union while it is being clipped: vertices with
/// their unit outward normals, boundary parameters and faces, and
/// triangles oriented outward.
#[derive(Default)]
pub(super) struct Skin {
    pub(super) positions: Vec<DVec3>,
    pub(super) normals: Vec<DVec3>,
    /// Each vertex's parameters (a cut's: interpolated along its edge).
    pub(super) uvw: Vec<[f64; 3]>,
    /// Each vertex's face (a vertex on a body edge has a copy per face).
    pub(super) face: Vec<Face>,
    pub(super) triangles: Vec<[usize; 3]>,
}

/// The six faces of `vol` sampled `per_span` times per knot span, as
/// triangles oriented outward (degenerate ones dropped). Each face has its
/// own vertices (with that face's normal), so edges of the body are not
/// welded.
fn boundary(vol: &BSplineVolume, per_span: usize) -> Skin {
    let dom = vol.domain();
    let mut s = VolumeScratch::default();
    let mut skin = Skin::default();
    for face in Face::ALL {
        let (da, db) = face.dir.others();
        let (ta, tb) = (samples(vol, da, per_span), samples(vol, db, per_span));
        let fixed = if face.end {
            dom[face.dir.index()].1
        } else {
            dom[face.dir.index()].0
        };
        let param = |x: f64, y: f64| {
            let mut t = [0.0; 3];
            t[face.dir.index()] = fixed;
            t[da.index()] = x;
            t[db.index()] = y;
            t
        };
        let base = skin.positions.len();
        for &x in &ta {
            for &y in &tb {
                let t = param(x, y);
                skin.positions.push(vol.eval(&mut s, t, 0).p);
                skin.normals
                    .push(face_outward(vol, &mut s, face, t).normalize_or_zero());
                skin.uvw.push(t);
                skin.face.push(face);
            }
        }
        let at = |i: usize, j: usize| base + i * tb.len() + j;
        for i in 0..ta.len() - 1 {
            for j in 0..tb.len() - 1 {
                for tri in [
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                    [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                ] {
                    let [p, q, r] = tri.map(|k| skin.positions[k]);
                    let n = (q - p).cross(r - p);
                    if n.length_squared() == 0.0 {
                        continue;
                    }
                    let out: DVec3 = tri.iter().map(|&k| skin.normals[k]).sum();
                    skin.triangles.push(if n.dot(out) >= 0.0 {
                        tri
                    } else {
                        [tri[0], tri[2], tri[1]]
                    });
                }
            }
        }
    }
    skin
}

/// Clips `skin` against `other`: keeps what lies outside it, cutting the
/// triangles that cross its boundary; of faces both share with the same
/// orientation, keeps them when `keep_shared`. `known` holds the sides of
/// the skin's vertices already classified (by the subdivision).
fn clip(
    skin: &mut Skin,
    other: &Solid,
    keep_shared: bool,
    known: &[Option<Side>],
) -> Result<(), BodyError> {
    let mut fates: Vec<Option<Fate>> = vec![None; skin.positions.len()];
    let mut cuts = std::collections::HashMap::<(usize, usize), usize>::new();
    let mut out = Vec::with_capacity(skin.triangles.len());
    let triangles = std::mem::take(&mut skin.triangles);
    for tri in &triangles {
        let mut f = [Fate::Keep; 3];
        for (k, &i) in tri.iter().enumerate() {
            f[k] = match fates[i] {
                Some(x) => x,
                None => {
                    let x = match known.get(i).copied().flatten() {
                        Some(side) => other.fate_of(side, skin.normals[i], keep_shared),
                        None => other.fate(skin.positions[i], skin.normals[i], keep_shared)?,
                    };
                    fates[i] = Some(x);
                    x
                }
            };
        }
        // A vertex where the boundaries cross says nothing of the triangle
        // beside it: the triangle may run into the other body from there.
        // A point just inside the triangle next to the vertex decides.
        let centre = tri.map(|i| skin.positions[i]).iter().sum::<DVec3>() / 3.0;
        for (k, &i) in tri.iter().enumerate() {
            if f[k] == Fate::Touch {
                let near = skin.positions[i].lerp(centre, NEAR);
                f[k] = match other.fate(near, skin.normals[i], keep_shared)? {
                    Fate::Drop => Fate::Drop,
                    _ => Fate::Keep,
                };
            }
        }
        if !f.contains(&Fate::Drop) {
            out.push(*tri);
            continue;
        }
        if !f.contains(&Fate::Keep) {
            continue;
        }
        let mut poly = Vec::with_capacity(4);
        for k in 0..3 {
            let (i, j) = (tri[k], tri[(k + 1) % 3]);
            let (fi, fj) = (f[k], f[(k + 1) % 3]);
            if fi != Fate::Drop {
                poly.push(i);
            }
            if matches!(
                (fi, fj),
                (Fate::Keep, Fate::Drop) | (Fate::Drop, Fate::Keep)
            ) {
                let key = (i.min(j), i.max(j));
                let cut = match cuts.get(&key) {
                    Some(&c) => c,
                    None => {
                        let (keep, drop) = if fi == Fate::Keep { (i, j) } else { (j, i) };
                        let (p, n, s) = crossing(other, skin, keep, drop, keep_shared)?;
                        skin.positions.push(p);
                        skin.normals.push(n);
                        skin.uvw.push(lerp_uvw(skin.uvw[keep], skin.uvw[drop], s));
                        skin.face.push(skin.face[keep]);
                        fates.push(None);
                        cuts.insert(key, skin.positions.len() - 1);
                        skin.positions.len() - 1
                    }
                };
                poly.push(cut);
            }
        }
        for k in 1..poly.len().saturating_sub(1) {
            let t = [poly[0], poly[k], poly[k + 1]];
            let [a, b, c] = t.map(|i| skin.positions[i]);
            if (b - a).cross(c - a).length_squared() > 0.0 {
                out.push(t);
            }
        }
    }
    skin.triangles = out;
    Ok(())
}

fn lerp_uvw(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * s)
}

/// Where the edge from vertex `keep` to vertex `drop` of `skin` leaves
/// what is kept: bisection of the fate, the last point kept (strictly
/// outside, or on a face kept); its normal interpolated; and its
/// parameter along the edge.
fn crossing(
    body: &Solid,
    skin: &Skin,
    keep: usize,
    drop: usize,
    keep_shared: bool,
) -> Result<(DVec3, DVec3, f64), BodyError> {
    let (p, q) = (skin.positions[keep], skin.positions[drop]);
    let (m, n) = (skin.normals[keep], skin.normals[drop]);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..CUT_STEPS {
        let mid = 0.5 * (lo + hi);
        let normal = m.lerp(n, mid).normalize_or_zero();
        // The first point not kept: inside, or on the other boundary (an
        // edge may run along it before it enters).
        if body.fate(p.lerp(q, mid), normal, keep_shared)? != Fate::Keep {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok((p.lerp(q, lo), m.lerp(n, lo).normalize_or_zero(), lo))
}

/// How deep inside another body, relative to its longest edge, the centre
/// of an uncut triangle may lie and still be taken as a corner of that body
/// poking through the triangle (the chord error the union accepts).
const DEEP: f64 = 0.1;

/// How far from `x` (inside `other`) along ±`n` the first point not
/// inside it lies, up to `reach` (bisection to 2⁻²⁰ of the reach).
fn depth(
    other: &Solid,
    x: DVec3,
    n: DVec3,
    reach: f64,
    keep_shared: bool,
) -> Result<f64, BodyError> {
    let mut best = reach;
    for dir in [n, -n] {
        if other.fate(x + dir * reach, dir, keep_shared)? == Fate::Drop {
            continue;
        }
        let (mut lo, mut hi) = (0.0, reach);
        for _ in 0..20 {
            let mid = 0.5 * (lo + hi);
            if other.fate(x + dir * mid, dir, keep_shared)? == Fate::Drop {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        best = best.min(hi);
    }
    Ok(best)
}

/// Refuses a clipped skin with a triangle of samples only (not cut: its
/// vertices are the first `samples`) whose centre lies inside `other`
/// deeper than [`DEEP`] of its longest edge: the
/// other body's boundary crosses its edges twice between the samples (the
/// ends kept, the middle inside), which vertex classification cannot see —
/// the sampling is too coarse there. (A cut triangle whose chord clips a
/// corner of the other body is the chord error the union accepts.)
fn unresolved(
    skin: &Skin,
    samples: usize,
    other: &Solid,
    keep_shared: bool,
) -> Result<(), BodyError> {
    for t in skin
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&i| i < samples))
    {
        let [a, b, c] = t.map(|i| skin.positions[i]);
        let centre = (a + b + c) / 3.0;
        let n = (b - a).cross(c - a).normalize_or_zero();
        let size = [a.distance(b), b.distance(c), c.distance(a)]
            .into_iter()
            .fold(0.0, f64::max);
        if other.fate(centre, n, keep_shared)? == Fate::Drop
            && depth(other, centre, n, size, keep_shared)? > DEEP * size
        {
            return Err(BodyError::TooCoarse {
                per_span: 0,
                reason: format!(
                    "triangle centred at ({:.4}, {:.4}, {:.4}) lies inside",
                    centre.x, centre.y, centre.z
                ),
            });
        }
    }
    Ok(())
}

/// The boundary of the union of `bodies`, each face sampled `per_span`
/// times per knot span (at least 1). Each body must be injective
/// (det J > 0: [`super::check_injective`]) for its inside to be its
/// parameter domain's image. Empty for no bodies.
pub fn union(bodies: &[BSplineVolume], per_span: usize) -> Result<UnionMesh, BodyError> {
    if per_span == 0 {
        return Err(BodyError::Mismatch(
            "a union needs at least one sample per knot span".into(),
        ));
    }
    if bodies
        .iter()
        .any(|b| b.points().iter().any(|p| !p.is_finite()))
    {
        return Err(BodyError::NonFinite("a body's control point".into()));
    }
    let solids: Vec<Solid> = bodies.iter().map(Solid::new).collect();
    let mut mesh = UnionMesh::default();
    let mut skins: Vec<Skin> = bodies.iter().map(|b| boundary(b, per_span)).collect();
    let (refined, known) = resolve(&mut skins, &solids)?;
    for (i, mut skin) in skins.into_iter().enumerate() {
        let samples = skin.positions.len();
        for (j, other) in solids.iter().enumerate() {
            if j != i {
                clip(&mut skin, other, i < j, &known[i][j])?;
            }
        }
        for (j, other) in solids.iter().enumerate() {
            if j != i {
                unresolved(&skin, samples, other, i < j).map_err(|e| match e {
                    BodyError::TooCoarse { reason, .. } => BodyError::TooCoarse {
                        per_span,
                        reason: format!("body {i}'s {reason} body {j}"),
                    },
                    e => e,
                })?;
            }
        }
        let base = mesh.positions.len();
        mesh.positions.extend(skin.positions);
        mesh.body
            .extend(std::iter::repeat_n(i, skin.triangles.len()));
        mesh.triangles
            .extend(skin.triangles.into_iter().map(|t| t.map(|k| k + base)));
    }
    let (lo, hi) = solids
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), s| {
            (l.min(s.lo), h.max(s.hi))
        });
    let size = if bodies.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    };
    let mut pieces = Pieces {
        positions: mesh.positions,
        triangles: mesh.triangles,
        body: mesh.body,
    };
    let report = weld(&mut pieces, WELD * size.max(f64::MIN_POSITIVE))
        .map_err(|reason| BodyError::TooCoarse { per_span, reason })?;
    Ok(UnionMesh {
        positions: pieces.positions,
        triangles: pieces.triangles,
        body: pieces.body,
        weld: report,
        subdivided: refined,
    })
}
