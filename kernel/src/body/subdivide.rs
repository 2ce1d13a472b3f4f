//! Local subdivision of a body's sampled boundary where another body's
//! boundary crosses it between the samples (issue 13, session 10).
//!
//! [`super::union`] clips each body's sampled boundary by classifying its
//! vertices against the other bodies: a triangle is cut only where its
//! vertices lie on different sides. Where the other boundary crosses a
//! triangle without any of its corners changing side, the clip cannot see
//! it, and the two bodies' pieces no longer fit together:
//!
//! * an **edge crossed twice** — both ends outside (or both inside) the
//!   other body, its middle in (out): a turned bar's edge poking through a
//!   spool triangle (the bar's two faces at that edge cross one edge of
//!   the triangle), or the spool's waist between two of a bar's samples;
//! * a **pocket** — the other body pierces the triangle and leaves it
//!   again without crossing any of its edges (a thin bar through a large
//!   triangle).
//!
//! Both are found with the other body's sampled mesh as a locator (an
//! edge crossing its triangles at two or more places; its edges piercing
//! the triangle) and confirmed with the exact classification: a point of
//! this body's **exact** boundary between the crossings (at the mean of
//! the pierce points) must lie on the other side. The edge is then split
//! there (in both triangles that hold it, across a body edge too, so the
//! mesh stays conforming), or the pocket's point is inserted into the
//! triangle (split in three). New vertices are evaluated on the B-spline
//! body's face at parameters interpolated from the triangle's corners, so
//! they lie on the true surface. One split per triangle per round; rounds
//! repeat until nothing is found (at most [`ROUNDS`]). Crossings the
//! locator shows but the exact classification denies (the other mesh's
//! chord error, a crossing through one of its edges counted twice) split
//! nothing.

use std::collections::{HashMap, HashSet};

use glam::DVec3;

use super::union::{Side, Skin, Solid};
use super::{BodyError, Dir, Face, VolumeScratch};

/// Rounds of subdivision at most.
pub const ROUNDS: usize = 12;

type Key = [u64; 3];
type EdgeKey = (Key, Key);
type Cell = (i64, i64, i64);
/// Sides of each skin's vertices against each body, where classified.
pub(super) type Sides = Vec<Vec<Vec<Option<Side>>>>;

/// The identity of a boundary point by its parameters (`+ 0.0` makes −0
/// and 0 one): the copies of a vertex on two faces of a body share it.
fn key(uvw: [f64; 3]) -> Key {
    uvw.map(|t| (t + 0.0).to_bits())
}

fn edge_key(a: [f64; 3], b: [f64; 3]) -> EdgeKey {
    let (ka, kb) = (key(a), key(b));
    if ka <= kb { (ka, kb) } else { (kb, ka) }
}

/// Triangles of a mesh binned by their boxes in cells of the mesh's mean
/// edge length.
struct Grid {
    h: f64,
    cells: HashMap<Cell, Vec<usize>>,
}

/// Cells a query box may cover at most; a longer query is answered with
/// every triangle.
const MAX_CELLS: i64 = 1 << 16;

impl Grid {
    fn new(positions: &[DVec3], triangles: &[[usize; 3]]) -> Self {
        let total: f64 = triangles
            .iter()
            .map(|t| positions[t[0]].distance(positions[t[1]]))
            .sum();
        let h = (total / triangles.len().max(1) as f64).max(1e-12);
        let mut grid = Self {
            h,
            cells: HashMap::new(),
        };
        for (i, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|k| positions[k]);
            let (lo, hi) = (grid.cell(a.min(b).min(c)), grid.cell(a.max(b).max(c)));
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    for z in lo.2..=hi.2 {
                        grid.cells.entry((x, y, z)).or_default().push(i);
                    }
                }
            }
        }
        grid
    }

    fn cell(&self, p: DVec3) -> Cell {
        let c = (p / self.h).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    }

    /// The triangles whose cells meet the box [lo, hi], each once.
    fn near(&self, lo: DVec3, hi: DVec3, out: &mut Vec<usize>) {
        out.clear();
        let (a, b) = (self.cell(lo), self.cell(hi));
        let count = (b.0 - a.0 + 1)
            .saturating_mul(b.1 - a.1 + 1)
            .saturating_mul(b.2 - a.2 + 1);
        if count > MAX_CELLS {
            out.extend(self.cells.values().flatten().copied());
        } else {
            for x in a.0..=b.0 {
                for y in a.1..=b.1 {
                    for z in a.2..=b.2 {
                        if let Some(l) = self.cells.get(&(x, y, z)) {
                            out.extend_from_slice(l);
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

/// Where the segment p → q crosses triangle `abc`, its ends strictly on
/// either side of the triangle's plane (touching and coplanar contact are
/// not crossings): the parameter along the segment and the barycentric
/// coordinates of the crossing in the triangle (closed: a crossing
/// through an edge of the triangle counts).
fn crossing(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> Option<(f64, [f64; 3])> {
    let n = (b - a).cross(c - a);
    let (dp, dq) = (n.dot(p - a), n.dot(q - a));
    if !((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0)) {
        return None;
    }
    let t = dp / (dp - dq);
    let x = p.lerp(q, t);
    let (v0, v1, v2) = (b - a, c - a, x - a);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    if den <= 0.0 {
        return None;
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    let u = 1.0 - v - w;
    (u >= 0.0 && v >= 0.0 && w >= 0.0).then_some((t, [u, v, w]))
}

/// What one round inserts into a skin.
enum Split {
    /// Split the edge (its key) at boundary parameters `uvw`, point `x`.
    Edge(EdgeKey, [f64; 3], DVec3),
    /// Insert boundary parameters `uvw`, point `x`, into triangle `t`.
    Inside(usize, [f64; 3], DVec3),
}

/// Strictly in or strictly out.
fn strict(s: Side) -> Option<bool> {
    match s {
        Side::In => Some(true),
        Side::Out => Some(false),
        Side::On(_) => None,
    }
}

/// Subdivides every skin where another body's boundary crosses it unseen
/// by its vertices (see the module doc); `skins[i]` is the boundary of
/// `solids[i]`. Returns the vertices inserted, and the sides found on the
/// way: `[i][j][v]`, vertex v of skin i against body j, where classified.
pub(super) fn resolve(skins: &mut [Skin], solids: &[Solid]) -> Result<(usize, Sides), BodyError> {
    let n = skins.len();
    // sides[i][j][v]: vertex v of skin i against body j.
    let mut sides: Sides = vec![vec![Vec::new(); n]; n];
    let mut inserted = 0;
    for _ in 0..ROUNDS {
        let mut any = false;
        for i in 0..n {
            let mut plan = Vec::new();
            let mut claimed = vec![false; skins[i].triangles.len()];
            let edges = edge_map(&skins[i]);
            for j in (0..n).filter(|&j| j != i) {
                sides[i][j].resize(skins[i].positions.len(), None);
                find(
                    &skins[i],
                    &edges,
                    &solids[i],
                    &solids[j],
                    &skins[j],
                    &mut sides[i][j],
                    &mut claimed,
                    &mut plan,
                )?;
            }
            if !plan.is_empty() {
                any = true;
                inserted += plan.len();
                apply(&mut skins[i], &edges, &solids[i], plan);
            }
        }
        if !any {
            break;
        }
    }
    Ok((inserted, sides))
}

/// The triangles holding each edge of `skin` (by the edge's parameters, so
/// the two copies of an edge along a body edge are one), with the edge's
/// place in the triangle (from corner k to k + 1).
fn edge_map(skin: &Skin) -> HashMap<EdgeKey, Vec<(usize, usize)>> {
    let mut map: HashMap<EdgeKey, Vec<(usize, usize)>> = HashMap::new();
    for (t, tri) in skin.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            map.entry(edge_key(skin.uvw[a], skin.uvw[b]))
                .or_default()
                .push((t, k));
        }
    }
    map
}

fn side_of(
    cache: &mut [Option<Side>],
    other: &Solid,
    skin: &Skin,
    v: usize,
) -> Result<Side, BodyError> {
    if let Some(s) = cache[v] {
        return Ok(s);
    }
    let s = other.side(skin.positions[v])?;
    cache[v] = Some(s);
    Ok(s)
}

/// Finds the splits of `skin` (the boundary of `own`) against `other`
/// (whose sampled boundary is `mesh`), claiming the triangles they touch.
#[allow(clippy::too_many_arguments)]
fn find(
    skin: &Skin,
    edges: &HashMap<EdgeKey, Vec<(usize, usize)>>,
    own: &Solid,
    other: &Solid,
    mesh: &Skin,
    cache: &mut [Option<Side>],
    claimed: &mut [bool],
    plan: &mut Vec<Split>,
) -> Result<(), BodyError> {
    if mesh.triangles.is_empty() {
        return Ok(());
    }
    let grid = Grid::new(&mesh.positions, &mesh.triangles);
    let overlaps = |lo: DVec3, hi: DVec3| !(hi.cmplt(other.lo).any() || lo.cmpgt(other.hi).any());
    let mut s = VolumeScratch::default();
    let mut near = Vec::new();
    let mut seen: HashSet<EdgeKey> = HashSet::new();
    // Edges crossed twice.
    for tri in &skin.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let ek = edge_key(skin.uvw[a], skin.uvw[b]);
            if !seen.insert(ek) {
                continue;
            }
            let (p, q) = (skin.positions[a], skin.positions[b]);
            if !overlaps(p.min(q), p.max(q)) {
                continue;
            }
            let holders = &edges[&ek];
            if holders.iter().any(|&(t, _)| claimed[t]) {
                continue;
            }
            let sa = strict(side_of(cache, other, skin, a)?);
            if sa.is_none() || sa != strict(side_of(cache, other, skin, b)?) {
                continue;
            }
            grid.near(p.min(q), p.max(q), &mut near);
            let mut ts: Vec<f64> = near
                .iter()
                .filter_map(|&t| crossing(p, q, mesh.triangles[t].map(|v| mesh.positions[v])))
                .map(|(t, _)| t)
                .collect();
            if ts.is_empty() {
                continue;
            }
            ts.sort_by(f64::total_cmp);
            // The stretches between crossings (and the ends: where the
            // other mesh's chords and its exact boundary disagree about an
            // end, the mesh shows one crossing of two), widest first; the
            // first whose middle, on the exact boundary, lies on the other
            // side.
            let mut stops = vec![0.0];
            stops.extend(ts);
            stops.push(1.0);
            let mut stretches: Vec<(f64, f64)> = stops
                .windows(2)
                .map(|w| (w[1] - w[0], 0.5 * (w[0] + w[1])))
                .collect();
            stretches.sort_by(|x, y| y.0.total_cmp(&x.0));
            let mut best: Option<(f64, [f64; 3], DVec3)> = None;
            for (gap, mid) in stretches {
                // Stretches thinner than this are crossings counted twice.
                if gap < 1e-9 {
                    break;
                }
                let uvw = lerp3(skin.uvw[a], skin.uvw[b], mid);
                let x = own.volume.eval(&mut s, uvw, 0).p;
                if strict(other.side(x)?).is_some_and(|inside| Some(inside) != sa) {
                    best = Some((gap, uvw, x));
                    break;
                }
            }
            if let Some((_, uvw, x)) = best {
                for &(t, _) in holders {
                    claimed[t] = true;
                }
                plan.push(Split::Edge(ek, uvw, x));
            }
        }
    }
    // Pockets (the other mesh's edges pierce a triangle whose corners all
    // lie on one side) and creases (an edge of the other body pierces a
    // triangle inside).
    for (t, tri) in skin.triangles.iter().enumerate() {
        if claimed[t] {
            continue;
        }
        let corners = tri.map(|v| skin.positions[v]);
        let (lo, hi) = (
            corners[0].min(corners[1]).min(corners[2]),
            corners[0].max(corners[1]).max(corners[2]),
        );
        if !overlaps(lo, hi) {
            continue;
        }
        let s0 = strict(side_of(cache, other, skin, tri[0])?);
        let pocket = s0.is_some()
            && s0 == strict(side_of(cache, other, skin, tri[1])?)
            && s0 == strict(side_of(cache, other, skin, tri[2])?);
        grid.near(lo, hi, &mut near);
        let mut sum = [0.0; 3];
        let mut count = 0usize;
        let mut crease: Option<[f64; 3]> = None;
        for &m in &near {
            let mt = mesh.triangles[m];
            for k in 0..3 {
                let (i, j) = (mt[k], mt[(k + 1) % 3]);
                let (p, q) = (mesh.positions[i], mesh.positions[j]);
                if let Some((_, bary)) = crossing(p, q, corners) {
                    for (s, b) in sum.iter_mut().zip(bary) {
                        *s += b;
                    }
                    count += 1;
                    if crease.is_none()
                        && bary.iter().filter(|&&b| b > CREASE_INSIDE).count() >= 2
                        && along_sharp_edge(other, &mut s, mesh.uvw[i], mesh.uvw[j])
                    {
                        crease = Some(bary);
                    }
                }
            }
        }
        if count == 0 {
            continue;
        }
        let at = |bary: [f64; 3]| {
            let face = skin.face[tri[0]];
            let mut uvw = [0.0; 3];
            for (c, &v) in tri.iter().enumerate() {
                for (u, x) in uvw.iter_mut().zip(skin.uvw[v]) {
                    *u += bary[c] * x;
                }
            }
            // Exactly on the face, whatever the rounding of the combination.
            uvw[face.dir.index()] = skin.uvw[tri[0]][face.dir.index()];
            uvw
        };
        if pocket {
            let uvw = at(sum.map(|s| s / count as f64));
            let x = own.volume.eval(&mut s, uvw, 0).p;
            if strict(other.side(x)?).is_some_and(|inside| Some(inside) != s0) {
                claimed[t] = true;
                plan.push(Split::Inside(t, uvw, x));
                continue;
            }
        }
        // The seam turns sharply where the other body's edge comes through:
        // a vertex there, so that the cut runs through the corner instead of
        // a chord across it.
        let Some(bary) = crease else {
            continue;
        };
        match (0..3).find(|&k| bary[k] <= CREASE_INSIDE) {
            None => {
                let uvw = at(bary);
                let x = own.volume.eval(&mut s, uvw, 0).p;
                claimed[t] = true;
                plan.push(Split::Inside(t, uvw, x));
            }
            // Beside the edge opposite corner k: split that edge there.
            Some(k) => {
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let (wa, wb) = (bary[(k + 1) % 3], bary[(k + 2) % 3]);
                let ek = edge_key(skin.uvw[a], skin.uvw[b]);
                let holders = &edges[&ek];
                if holders.iter().any(|&(h, _)| claimed[h]) {
                    continue;
                }
                let uvw = lerp3(skin.uvw[a], skin.uvw[b], wb / (wa + wb));
                let x = own.volume.eval(&mut s, uvw, 0).p;
                for &(h, _) in holders {
                    claimed[h] = true;
                }
                plan.push(Split::Edge(ek, uvw, x));
            }
        }
    }
    Ok(())
}

/// The angle between two faces' normals above which the body's edge where
/// they meet is a crease (radians: 20°).
const SHARP: f64 = 0.35;

/// How far inside a triangle (every barycentric coordinate above this) the
/// other body's edge must pierce it for a vertex to be put there (nearer
/// an edge or corner, the cut passes within this of the crease).
const CREASE_INSIDE: f64 = 0.05;

/// Whether the segment between boundary parameters `a` and `b` of `body`
/// runs along one of its edges (two parameters at the same end of the
/// domain for both) where its faces meet at an angle: their normals at the
/// segment's middle more than [`SHARP`] apart.
fn along_sharp_edge(body: &Solid, s: &mut VolumeScratch, a: [f64; 3], b: [f64; 3]) -> bool {
    let dom = body.volume.domain();
    let fixed: Vec<Face> = (0..3)
        .filter_map(|k| {
            let (lo, hi) = dom[k];
            let dir = Dir::ALL[k];
            if a[k] == lo && b[k] == lo {
                Some(Face { dir, end: false })
            } else if a[k] == hi && b[k] == hi {
                Some(Face { dir, end: true })
            } else {
                None
            }
        })
        .collect();
    if fixed.len() < 2 {
        return false;
    }
    let mid = lerp3(a, b, 0.5);
    let n = |f: Face, s: &mut VolumeScratch| {
        super::union::face_outward(body.volume, s, f, mid).normalize_or_zero()
    };
    n(fixed[0], s).dot(n(fixed[1], s)) < SHARP.cos()
}

fn lerp3(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * t)
}

/// Carries out `plan` on `skin` (the boundary of `own`): each new point
/// gets one vertex per face it lies on (that face's normal), each edge
/// split in every triangle holding it.
fn apply(
    skin: &mut Skin,
    edges: &HashMap<EdgeKey, Vec<(usize, usize)>>,
    own: &Solid,
    plan: Vec<Split>,
) {
    let mut s = VolumeScratch::default();
    let mut made: HashMap<(Key, Face), usize> = HashMap::new();
    let mut vertex = |skin: &mut Skin, from: usize, uvw: [f64; 3], x: DVec3| {
        let face = skin.face[from];
        if let Some(&v) = made.get(&(key(uvw), face)) {
            return v;
        }
        made.insert((key(uvw), face), skin.positions.len());
        skin.positions.push(x);
        skin.normals
            .push(super::union::face_outward(own.volume, &mut s, face, uvw).normalize_or_zero());
        skin.uvw.push(uvw);
        skin.face.push(face);
        skin.positions.len() - 1
    };
    for split in plan {
        match split {
            Split::Edge(ek, uvw, x) => {
                for &(t, k) in &edges[&ek] {
                    let tri = skin.triangles[t];
                    let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                    let m = vertex(skin, a, uvw, x);
                    skin.triangles[t] = [a, m, c];
                    skin.triangles.push([m, b, c]);
                }
            }
            Split::Inside(t, uvw, x) => {
                let [a, b, c] = skin.triangles[t];
                let m = vertex(skin, a, uvw, x);
                skin.triangles[t] = [a, b, m];
                skin.triangles.push([b, c, m]);
                skin.triangles.push([c, a, m]);
            }
        }
    }
}
