//! The network's graph and its faces, found automatically.
//!
//! * **Vertices** are clusters of curve–curve meetings within the tolerance
//!   (any two meetings closer than the tolerance are one vertex, so three or
//!   more curves can meet at one vertex). Every curve must end at a vertex
//!   (else [`NetworkError::OpenEnd`]); a curve end closer than the
//!   tolerance to its last vertex counts as ending there.
//! * **Edges** are the curve pieces between consecutive vertices on a curve.
//! * **Embedding by local normals.** A vertex's normal is the cross product
//!   of the two least parallel edge directions leaving it (exact when the
//!   directions are coplanar, as G1 needs; the largest |n·d| of the others is
//!   reported as the vertex's planarity defect). Normals are oriented
//!   consistently by propagation along edges (Hoppe's rule: a neighbour's
//!   normal is flipped when it points against ours), each connected part
//!   seeded at its vertex whose normal is most nearly parallel to `up`, so
//!   that n·up > 0 there.
//! * **Face walk.** At each vertex the leaving half-edges are sorted
//!   counter-clockwise about the normal (angles of their directions in the
//!   tangent plane); the half-edge after u→w is the one clockwise next to
//!   w→u at w, which keeps the face on the left. Every loop is a face or a
//!   hole; a loop whose total turning (corner angles about the vertex
//!   normals plus the turning along each edge) is positive is a face, the
//!   others (the boundary of an open net) are holes.
//! * **Sides.** Consecutive edges of one curve walked in one direction (a
//!   vertex where another curve only touches the side) make one side, so a
//!   T-junction is not a corner.
//! * **Errors.** A loop that walks an edge both ways (a piece hanging into a
//!   face) is an open face; a face whose loop passes a vertex twice, or whose
//!   boundary (24 samples per side projected onto the plane of its mean corner
//!   normal) crosses itself, is self-intersecting; a curve crossing itself is
//!   refused; faces need 3 to [`MAX_SIDES`] sides.

use glam::{DVec2, DVec3};

use super::error::NetworkError;
use super::intersect::{CurveHit, intersections, self_intersections};
use super::jet::V3;
use super::ribbon::{NormalPiece, normal_at};
use crate::bspline::BSplineCurve;

/// The most sides a face may have.
pub const MAX_SIDES: usize = 16;

/// A point where curves meet.
#[derive(Clone, Debug, PartialEq)]
pub struct Vertex {
    /// The mean of the meeting points.
    pub point: DVec3,
    /// The unit normal of the tangent plane (consistently oriented).
    pub normal: DVec3,
    /// (curve, parameter) of every curve through the vertex.
    pub incidences: Vec<(usize, f64)>,
    /// The largest |n·d| over the edge directions d leaving the vertex: 0
    /// when they are coplanar (G1 is possible at the corner).
    pub planarity: f64,
}

/// A curve piece between two consecutive vertices on its curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// The curve.
    pub curve: usize,
    /// Start parameter (t0 < t1).
    pub t0: f64,
    /// End parameter.
    pub t1: f64,
    /// The vertex at t0.
    pub v0: usize,
    /// The vertex at t1.
    pub v1: usize,
}

/// One side of a face: a piece of one curve, walked from `t_start` to
/// `t_end` (either order) with the face on its left about the normals.
#[derive(Clone, Debug, PartialEq)]
pub struct Side {
    /// The curve.
    pub curve: usize,
    /// Where the side starts on the curve.
    pub t_start: f64,
    /// Where it ends.
    pub t_end: f64,
    /// Its edges, in walking order.
    pub edges: Vec<usize>,
    /// The corner vertex it starts at.
    pub start: usize,
    /// The corner vertex it ends at.
    pub end: usize,
}

/// A face: its sides counter-clockwise about the normals.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The sides.
    pub sides: Vec<Side>,
}

/// Vertices, edges, faces and holes of a network.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// The vertices.
    pub vertices: Vec<Vertex>,
    /// The edges.
    pub edges: Vec<Edge>,
    /// The faces.
    pub faces: Vec<Face>,
    /// Loops that are not faces (the boundary of an open net), as half-edges
    /// (2·edge for the edge's direction, 2·edge + 1 against it).
    pub holes: Vec<Vec<usize>>,
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn angle_about(n: DVec3, a: DVec3, b: DVec3) -> f64 {
    n.dot(a.cross(b)).atan2(a.dot(b))
}

impl Topology {
    /// The vertex a half-edge leaves.
    pub fn origin(&self, h: usize) -> usize {
        let e = &self.edges[h / 2];
        if h.is_multiple_of(2) { e.v0 } else { e.v1 }
    }

    /// The vertex a half-edge reaches.
    pub fn dest(&self, h: usize) -> usize {
        self.origin(h ^ 1)
    }

    /// The meetings of every pair of curves: `hits[i][j]` for i < j (empty
    /// for i ≥ j), after checking that no curve crosses itself.
    pub fn pair_hits(
        curves: &[BSplineCurve],
        tol: f64,
    ) -> Result<Vec<Vec<Vec<CurveHit>>>, NetworkError> {
        if !(tol > 0.0 && tol.is_finite()) {
            return Err(NetworkError::BadTolerance(tol));
        }
        for (i, c) in curves.iter().enumerate() {
            check_simple(c, i, tol)?;
        }
        let n = curves.len();
        let mut hits = vec![vec![Vec::new(); n]; n];
        for i in 0..n {
            for j in i + 1..n {
                hits[i][j] = intersections(&curves[i], &curves[j], tol);
            }
        }
        Ok(hits)
    }

    /// Builds the topology of `curves` from their meetings (`pair_hits`)
    /// with meeting tolerance `tol`.
    #[allow(clippy::needless_range_loop)] // index arithmetic over parallel arrays
    pub fn build(
        curves: &[BSplineCurve],
        hits: &[Vec<Vec<CurveHit>>],
        tol: f64,
        up: DVec3,
    ) -> Result<Self, NetworkError> {
        // Incidences (curve, t, point), joined by the meetings.
        let mut inc: Vec<(usize, f64, DVec3)> = Vec::new();
        let mut links = Vec::new();
        for i in 0..curves.len() {
            for j in i + 1..curves.len() {
                for h in &hits[i][j] {
                    links.push((inc.len(), inc.len() + 1));
                    inc.push((i, h.s, h.point));
                    inc.push((j, h.t, h.point));
                }
            }
        }
        let mut parent: Vec<usize> = (0..inc.len()).collect();
        for (a, b) in links {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra] = rb;
        }
        for a in 0..inc.len() {
            for b in a + 1..inc.len() {
                if (inc[a].2 - inc[b].2).length() <= tol {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    parent[ra] = rb;
                }
            }
        }
        let mut root_vertex = vec![usize::MAX; inc.len()];
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut sums: Vec<(DVec3, usize)> = Vec::new();
        for a in 0..inc.len() {
            let r = find(&mut parent, a);
            if root_vertex[r] == usize::MAX {
                root_vertex[r] = vertices.len();
                vertices.push(Vertex {
                    point: DVec3::ZERO,
                    normal: DVec3::ZERO,
                    incidences: Vec::new(),
                    planarity: 0.0,
                });
                sums.push((DVec3::ZERO, 0));
            }
            let v = root_vertex[r];
            sums[v].0 += inc[a].2;
            sums[v].1 += 1;
            if !vertices[v].incidences.iter().any(|(c, _)| *c == inc[a].0) {
                vertices[v].incidences.push((inc[a].0, inc[a].1));
            }
        }
        for (v, (s, k)) in vertices.iter_mut().zip(&sums) {
            v.point = *s / *k as f64;
        }
        // Edges along each curve.
        let mut edges = Vec::new();
        for (ci, c) in curves.iter().enumerate() {
            let mut on: Vec<(f64, usize)> = vertices
                .iter()
                .enumerate()
                .filter_map(|(vi, v)| {
                    v.incidences
                        .iter()
                        .find(|(cc, _)| *cc == ci)
                        .map(|(_, t)| (*t, vi))
                })
                .collect();
            on.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (t_min, t_max) = c.domain();
            let free_start = on
                .first()
                .is_none_or(|(_, v)| (c.point(t_min) - vertices[*v].point).length() > tol);
            if free_start {
                return Err(NetworkError::OpenEnd {
                    curve: ci,
                    t: t_min,
                });
            }
            let free_end = on
                .last()
                .is_none_or(|(_, v)| (c.point(t_max) - vertices[*v].point).length() > tol);
            if free_end || on.len() < 2 {
                return Err(NetworkError::OpenEnd {
                    curve: ci,
                    t: t_max,
                });
            }
            for w in on.windows(2) {
                if w[0].1 != w[1].1 {
                    edges.push(Edge {
                        curve: ci,
                        t0: w[0].0,
                        t1: w[1].0,
                        v0: w[0].1,
                        v1: w[1].1,
                    });
                }
            }
        }
        let mut topo = Topology {
            vertices,
            edges,
            faces: Vec::new(),
            holes: Vec::new(),
        };
        let out_dir = |h: usize| -> DVec3 {
            let e = &topo.edges[h / 2];
            let c = &curves[e.curve];
            if h.is_multiple_of(2) {
                c.derivs(e.t0).d1.normalize()
            } else {
                -c.derivs(e.t1).d1.normalize()
            }
        };
        // Half-edges leaving each vertex.
        let nv = topo.vertices.len();
        let mut leaving: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for h in 0..2 * topo.edges.len() {
            leaving[topo.origin(h)].push(h);
        }
        let dirs: Vec<DVec3> = (0..2 * topo.edges.len()).map(out_dir).collect();
        // Normals.
        for v in 0..nv {
            let mut best = (0.0, DVec3::ZERO);
            for (a, &ha) in leaving[v].iter().enumerate() {
                for &hb in &leaving[v][a + 1..] {
                    let x = dirs[ha].cross(dirs[hb]);
                    if x.length() > best.0 {
                        best = (x.length(), x);
                    }
                }
            }
            if best.0 < 1e-8 {
                return Err(NetworkError::DegenerateVertex {
                    point: topo.vertices[v].point,
                });
            }
            let n = best.1 / best.0;
            topo.vertices[v].normal = n;
            topo.vertices[v].planarity = leaving[v]
                .iter()
                .map(|h| n.dot(dirs[*h]).abs())
                .fold(0.0, f64::max);
        }
        // Consistent orientation by propagation.
        let mut seen = vec![false; nv];
        let mut seeds: Vec<usize> = (0..nv).collect();
        seeds.sort_by(|&a, &b| {
            let (na, nb) = (topo.vertices[a].normal, topo.vertices[b].normal);
            nb.dot(up).abs().total_cmp(&na.dot(up).abs())
        });
        for seed in seeds {
            if seen[seed] {
                continue;
            }
            if topo.vertices[seed].normal.dot(up) < 0.0 {
                topo.vertices[seed].normal = -topo.vertices[seed].normal;
            }
            seen[seed] = true;
            let mut stack = vec![seed];
            while let Some(v) = stack.pop() {
                for &h in &leaving[v] {
                    let w = topo.dest(h);
                    if !seen[w] {
                        let e = &topo.edges[h / 2];
                        let c = &curves[e.curve];
                        let (nv0, nv1) = (topo.vertices[e.v0].normal, topo.vertices[e.v1].normal);
                        let piece = NormalPiece::new(c, e.t0, e.t1, nv0, nv1, 0.0);
                        let from = if h.is_multiple_of(2) { e.t0 } else { e.t1 };
                        let carried = piece.carry(c, from, topo.vertices[v].normal);
                        if topo.vertices[w].normal.dot(carried) < 0.0 {
                            topo.vertices[w].normal = -topo.vertices[w].normal;
                        }
                        seen[w] = true;
                        stack.push(w);
                    }
                }
            }
        }
        // Rotation systems.
        let mut rot_pos = vec![0usize; 2 * topo.edges.len()];
        for v in 0..nv {
            let n = topo.vertices[v].normal;
            let e1 = n.any_orthonormal_vector();
            let e2 = n.cross(e1);
            leaving[v].sort_by(|a, b| {
                let aa = dirs[*a].dot(e2).atan2(dirs[*a].dot(e1));
                let bb = dirs[*b].dot(e2).atan2(dirs[*b].dot(e1));
                aa.total_cmp(&bb)
            });
            for (k, h) in leaving[v].iter().enumerate() {
                rot_pos[*h] = k;
            }
        }
        let next = |h: usize| -> usize {
            let tw = h ^ 1;
            let w = topo.origin(tw);
            let l = &leaving[w];
            l[(rot_pos[tw] + l.len() - 1) % l.len()]
        };
        // Walk the loops.
        let mut visited = vec![false; 2 * topo.edges.len()];
        let mut loops = Vec::new();
        for h0 in 0..2 * topo.edges.len() {
            if visited[h0] {
                continue;
            }
            let mut lp = Vec::new();
            let mut h = h0;
            while !visited[h] {
                visited[h] = true;
                lp.push(h);
                h = next(h);
            }
            loops.push(lp);
        }
        let walk_dir = |h: usize, at_end: bool| -> DVec3 {
            let e = &topo.edges[h / 2];
            let c = &curves[e.curve];
            let t = if (h.is_multiple_of(2)) == at_end {
                e.t1
            } else {
                e.t0
            };
            let d = c.derivs(t).d1.normalize();
            if h.is_multiple_of(2) { d } else { -d }
        };
        for lp in loops {
            for &h in &lp {
                if lp.contains(&(h ^ 1)) {
                    let e = &topo.edges[h / 2];
                    return Err(NetworkError::OpenFace {
                        curve: e.curve,
                        t0: e.t0,
                        t1: e.t1,
                    });
                }
            }
            let mut turning = 0.0;
            for (k, &h) in lp.iter().enumerate() {
                let e = &topo.edges[h / 2];
                let c = &curves[e.curve];
                let piece = NormalPiece::new(
                    c,
                    e.t0,
                    e.t1,
                    topo.vertices[e.v0].normal,
                    topo.vertices[e.v1].normal,
                    0.0,
                );
                let samples = 12;
                let mut prev = walk_dir(h, false);
                for j in 1..=samples {
                    let f = j as f64 / samples as f64;
                    let t = if h.is_multiple_of(2) {
                        e.t0 + f * (e.t1 - e.t0)
                    } else {
                        e.t1 - f * (e.t1 - e.t0)
                    };
                    let along = c.derivs(t).d1.normalize();
                    let d = along * if h.is_multiple_of(2) { 1.0 } else { -1.0 };
                    let n = normal_at(std::slice::from_ref(&piece), t, V3::cst(along)).val();
                    turning += angle_about(n, prev, d);
                    prev = d;
                }
                let hn = lp[(k + 1) % lp.len()];
                turning += angle_about(
                    topo.vertices[topo.dest(h)].normal,
                    walk_dir(h, true),
                    walk_dir(hn, false),
                );
            }
            if turning > 0.0 {
                let face = topo.faces.len();
                topo.faces.push(topo.face_of(&lp, face, curves)?);
            } else {
                topo.holes.push(lp);
            }
        }
        if topo.faces.is_empty() {
            return Err(NetworkError::NoFaces);
        }
        Ok(topo)
    }

    /// The sides of the loop `lp` (face number `face`), validated.
    fn face_of(
        &self,
        lp: &[usize],
        face: usize,
        curves: &[BSplineCurve],
    ) -> Result<Face, NetworkError> {
        let mut seen = Vec::new();
        for &h in lp {
            let v = self.origin(h);
            if seen.contains(&v) {
                return Err(NetworkError::SelfIntersectingFace {
                    face,
                    what: format!("passes vertex {v} twice"),
                });
            }
            seen.push(v);
        }
        let same_run = |a: usize, b: usize| {
            self.edges[a / 2].curve == self.edges[b / 2].curve && a % 2 == b % 2
        };
        let m = lp.len();
        let Some(start) = (0..m).find(|&k| !same_run(lp[(k + m - 1) % m], lp[k])) else {
            return Err(NetworkError::TooFewSides { face, sides: 1 });
        };
        let mut sides: Vec<Side> = Vec::new();
        for k in 0..m {
            let h = lp[(start + k) % m];
            let e = &self.edges[h / 2];
            let (ts, te) = if h.is_multiple_of(2) {
                (e.t0, e.t1)
            } else {
                (e.t1, e.t0)
            };
            let continues = k > 0 && same_run(lp[(start + k + m - 1) % m], h);
            if continues {
                let s = sides.last_mut().expect("a side before");
                s.t_end = te;
                s.edges.push(h / 2);
                s.end = self.dest(h);
            } else {
                sides.push(Side {
                    curve: e.curve,
                    t_start: ts,
                    t_end: te,
                    edges: vec![h / 2],
                    start: self.origin(h),
                    end: self.dest(h),
                });
            }
        }
        if sides.len() < 3 {
            return Err(NetworkError::TooFewSides {
                face,
                sides: sides.len(),
            });
        }
        if sides.len() > MAX_SIDES {
            return Err(NetworkError::TooManySides {
                face,
                sides: sides.len(),
                max: MAX_SIDES,
            });
        }
        // The boundary projected onto the plane of the mean corner normal.
        let n = sides
            .iter()
            .map(|s| self.vertices[s.start].normal)
            .sum::<DVec3>()
            .normalize_or_zero();
        if n == DVec3::ZERO {
            return Err(NetworkError::SelfIntersectingFace {
                face,
                what: "has corner normals that cancel".into(),
            });
        }
        let e1 = n.any_orthonormal_vector();
        let e2 = n.cross(e1);
        let per = 24;
        let mut poly = Vec::with_capacity(per * sides.len());
        for s in &sides {
            let c = &curves[s.curve];
            for j in 0..per {
                let t = s.t_start + (s.t_end - s.t_start) * j as f64 / per as f64;
                let p = c.point(t);
                poly.push(DVec2::new(p.dot(e1), p.dot(e2)));
            }
        }
        if let Some((a, b)) = polygon_crossing(&poly) {
            return Err(NetworkError::SelfIntersectingFace {
                face,
                what: format!("crosses itself (sides {} and {})", a / per, b / per),
            });
        }
        Ok(Face { sides })
    }
}

/// The first pair of non-adjacent crossing segments of a closed polygon.
fn polygon_crossing(p: &[DVec2]) -> Option<(usize, usize)> {
    let m = p.len();
    let orient = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    for i in 0..m {
        let (a, b) = (p[i], p[(i + 1) % m]);
        for j in i + 2..m {
            if (j + 1) % m == i {
                continue;
            }
            let (c, d) = (p[j], p[(j + 1) % m]);
            let (o1, o2) = (orient(a, b, c), orient(a, b, d));
            let (o3, o4) = (orient(c, d, a), orient(c, d, b));
            if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
                return Some((i, j));
            }
        }
    }
    None
}

/// Refuses a curve that crosses itself.
pub fn check_simple(c: &BSplineCurve, index: usize, tol: f64) -> Result<(), NetworkError> {
    match self_intersections(c, tol).first() {
        Some(h) => Err(NetworkError::SelfIntersectingCurve {
            curve: index,
            t0: h.s.min(h.t),
            t1: h.s.max(h.t),
        }),
        None => Ok(()),
    }
}
