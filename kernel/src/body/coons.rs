//! Coons bodies 0, 1 and 2 (paper 002 §2.2–2.4), with B-spline boundaries.
//!
//! With λ₀(t) = 1 − t, λ₁(t) = t and the parameters in [0, 1]:
//!
//! * body 0 (trilinear): T(u,v,w) = Σ_ijk λi(u) λj(v) λk(w) C_ijk;
//! * body 1 (12 edge curves): C1 = Σ_ij λi(u)λj(v) C(i,j,w)
//!   + Σ_ik λi(u)λk(w) C(i,v,k) + Σ_jk λj(v)λk(w) C(u,j,k) − 2T;
//! * body 2 (6 faces): C2 = D − C1 − T with
//!   D = Σ_i λi(u) X_i(v,w) + Σ_j λj(v) Y_j(u,w) + Σ_k λk(w) Z_k(u,v).
//!
//! These are Gordon's Boolean sums of the linear blends in u, v, w (the
//! paper's −2T and D − C1 − T are their inclusion–exclusion terms).
//!
//! Every boundary curve and face is normalised to [0, 1] and brought to one
//! common spline space per direction ([`super::space`]), so corners and
//! edges shared by several boundaries correspond control point by control
//! point. **Which source wins:** they must agree within the tolerance given
//! to the constructor (max distance between corresponding control points,
//! which bounds the distance between the curves); the mismatch found is kept
//! ([`Body1::mismatch`], [`Body2::mismatch`]), and then one source is
//! copied into the others: for body 1 each corner is the u-edge's end; for
//! body 2 the u- and v-edges are the w-faces' (Z_k) rows and the w-edges
//! the u-faces' (X_i) rows.
//!
//! **Exact conversion.** In a spline space of degree ≥ 1 the linear
//! functions are exact: t = Σ ξ_r N_r(t) with ξ_r the Greville abscissae.
//! So every term of the Boolean sum is a tensor-product B-spline on the
//! common spaces, and the volume's control points are the Boolean sum
//! applied to control points with λ evaluated at Greville abscissae
//! ([`Body2::to_volume`]). A Coons patch of four curves is built the same way
//! ([`coons_patch`]).

// The blends are written with the indices of the formulas (i, j, k ∈ {0, 1}
// index several arrays and the λ's at once); iterators would hide that.
#![allow(clippy::needless_range_loop)]

use glam::DVec3;

use super::space::{common_knots, curve_to, normalized_curve, normalized_surface, surface_to};
use super::{BSplineVolume, BodyError};
use crate::bspline::{BSplineCurve, BSplineSurface, KnotVector, greville};

fn lam(i: usize, t: f64) -> f64 {
    if i == 0 { 1.0 - t } else { t }
}

/// Trilinear interpolation of the 8 points `c[i][j][k]` (paper 002's T).
pub fn trilinear(c: &[[[DVec3; 2]; 2]; 2], u: f64, v: f64, w: f64) -> DVec3 {
    let mut s = DVec3::ZERO;
    for (i, ci) in c.iter().enumerate() {
        for (j, cij) in ci.iter().enumerate() {
            for (k, p) in cij.iter().enumerate() {
                s += *p * (lam(i, u) * lam(j, v) * lam(k, w));
            }
        }
    }
    s
}

/// Coons body 0: the trilinear solid of 8 corners `corners[i][j][k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Body0 {
    /// The corner at (u, v, w) = (i, j, k).
    pub corners: [[[DVec3; 2]; 2]; 2],
}

impl Body0 {
    /// x(u, v, w) for (u, v, w) ∈ [0, 1]³.
    pub fn point(&self, u: f64, v: f64, w: f64) -> DVec3 {
        trilinear(&self.corners, u, v, w)
    }

    /// The same solid as a degree (1, 1, 1) B-spline volume (its control
    /// points are the corners).
    pub fn to_volume(&self) -> Result<BSplineVolume, BodyError> {
        let kv = KnotVector::clamped_uniform(1, 2)?;
        let mut pts = Vec::with_capacity(8);
        for ci in &self.corners {
            for cij in ci {
                pts.extend_from_slice(cij);
            }
        }
        Ok(BSplineVolume::new(kv.clone(), kv.clone(), kv, pts)?)
    }
}

fn curve_end(c: &BSplineCurve, end: usize) -> DVec3 {
    if end == 0 {
        c.points()[0]
    } else {
        c.points()[c.points().len() - 1]
    }
}

/// The boundary row of a surface: along its first parameter (`along_u`) at
/// v = `end`, or along its second at u = `end` (0 or 1 of the domain).
pub fn surface_edge(s: &BSplineSurface, along_u: bool, end: usize) -> BSplineCurve {
    let (nu, nv) = (s.nu(), s.nv());
    if along_u {
        let j = if end == 0 { 0 } else { nv - 1 };
        let pts = (0..nu).map(|i| s.points()[s.index(i, j)]).collect();
        BSplineCurve::new(s.u_knots().clone(), pts).expect("a surface row is a curve")
    } else {
        let i = if end == 0 { 0 } else { nu - 1 };
        let pts = (0..nv).map(|j| s.points()[s.index(i, j)]).collect();
        BSplineCurve::new(s.v_knots().clone(), pts).expect("a surface row is a curve")
    }
}

fn max_dist(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

/// The Coons patch of four curves as an exact B-spline surface over [0, 1]²:
/// `u_curves[j]` is the boundary at v = j (parameter u), `v_curves[i]` the
/// boundary at u = i (parameter v). Corners must meet within `tolerance`
/// (the u-curves' ends win).
pub fn coons_patch(
    u_curves: [&BSplineCurve; 2],
    v_curves: [&BSplineCurve; 2],
    tolerance: f64,
) -> Result<BSplineSurface, BodyError> {
    let ku = common_knots(&[u_curves[0].knots(), u_curves[1].knots()])?;
    let kv = common_knots(&[v_curves[0].knots(), v_curves[1].knots()])?;
    let cu = [curve_to(u_curves[0], &ku)?, curve_to(u_curves[1], &ku)?];
    let cv = [curve_to(v_curves[0], &kv)?, curve_to(v_curves[1], &kv)?];
    let mut corner = [[DVec3::ZERO; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            corner[i][j] = curve_end(&cu[j], i);
            let d = (curve_end(&cv[i], j) - corner[i][j]).length();
            if d > tolerance || d.is_nan() {
                return Err(BodyError::Incompatible {
                    what: format!("patch corner ({i}, {j})"),
                    distance: d,
                    tolerance,
                });
            }
        }
    }
    let (gu, gv) = (greville(&ku), greville(&kv));
    let mut pts = Vec::with_capacity(gu.len() * gv.len());
    for (a, &xi) in gu.iter().enumerate() {
        for (b, &eta) in gv.iter().enumerate() {
            let mut p = DVec3::ZERO;
            for j in 0..2 {
                p += cu[j].points()[a] * lam(j, eta);
            }
            for i in 0..2 {
                p += cv[i].points()[b] * lam(i, xi);
            }
            for i in 0..2 {
                for j in 0..2 {
                    p -= corner[i][j] * (lam(i, xi) * lam(j, eta));
                }
            }
            pts.push(p);
        }
    }
    Ok(BSplineSurface::new(ku, kv, pts)?)
}

/// The 12 edge curves of a Coons body 1, each over [0, 1] after
/// normalisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Edges {
    /// `u[j][k]` = C(u, j, k): along u at v = j, w = k.
    pub u: [[BSplineCurve; 2]; 2],
    /// `v[i][k]` = C(i, v, k): along v at u = i, w = k.
    pub v: [[BSplineCurve; 2]; 2],
    /// `w[i][j]` = C(i, j, w): along w at u = i, v = j.
    pub w: [[BSplineCurve; 2]; 2],
}

/// Coons body 1: the Boolean sum of bilinear blends of 12 compatible edge
/// curves (paper 002 §2.3).
#[derive(Clone, Debug, PartialEq)]
pub struct Body1 {
    edges: Edges,
    corners: [[[DVec3; 2]; 2]; 2],
    mismatch: f64,
}

impl Body1 {
    /// A body from its 12 edges (any degrees, knots and domains); every
    /// corner must be met by its three edges within `tolerance`.
    pub fn new(edges: Edges, tolerance: f64) -> Result<Self, BodyError> {
        let pick = |e: &[[BSplineCurve; 2]; 2]| -> Result<[[BSplineCurve; 2]; 2], BodyError> {
            let k = common_knots(&[
                e[0][0].knots(),
                e[0][1].knots(),
                e[1][0].knots(),
                e[1][1].knots(),
            ])?;
            Ok([
                [curve_to(&e[0][0], &k)?, curve_to(&e[0][1], &k)?],
                [curve_to(&e[1][0], &k)?, curve_to(&e[1][1], &k)?],
            ])
        };
        let mut e = Edges {
            u: pick(&edges.u)?,
            v: pick(&edges.v)?,
            w: pick(&edges.w)?,
        };
        let mut corners = [[[DVec3::ZERO; 2]; 2]; 2];
        let mut mismatch: f64 = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    let c = curve_end(&e.u[j][k], i);
                    let dv = (curve_end(&e.v[i][k], j) - c).length();
                    let dw = (curve_end(&e.w[i][j], k) - c).length();
                    let d = dv.max(dw);
                    if d > tolerance || d.is_nan() {
                        return Err(BodyError::Incompatible {
                            what: format!("corner ({i}, {j}, {k})"),
                            distance: d,
                            tolerance,
                        });
                    }
                    mismatch = mismatch.max(d);
                    corners[i][j][k] = c;
                }
            }
        }
        // The u-edges' ends win: copy them into the v- and w-edges.
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    let c = corners[i][j][k];
                    set_end(&mut e.v[i][k], j, c);
                    set_end(&mut e.w[i][j], k, c);
                }
            }
        }
        Ok(Self {
            edges: e,
            corners,
            mismatch,
        })
    }

    /// The edges (normalised, in their common spaces).
    pub fn edges(&self) -> &Edges {
        &self.edges
    }

    /// The 8 vertices C_ijk.
    pub fn corners(&self) -> &[[[DVec3; 2]; 2]; 2] {
        &self.corners
    }

    /// The largest corner mismatch found at construction.
    pub fn mismatch(&self) -> f64 {
        self.mismatch
    }

    /// C1(u, v, w) by the paper's formula, (u, v, w) ∈ [0, 1]³.
    pub fn point(&self, u: f64, v: f64, w: f64) -> DVec3 {
        let e = &self.edges;
        let mut s = DVec3::ZERO;
        for i in 0..2 {
            for j in 0..2 {
                s += e.w[i][j].point(w) * (lam(i, u) * lam(j, v));
            }
        }
        for i in 0..2 {
            for k in 0..2 {
                s += e.v[i][k].point(v) * (lam(i, u) * lam(k, w));
            }
        }
        for j in 0..2 {
            for k in 0..2 {
                s += e.u[j][k].point(u) * (lam(j, v) * lam(k, w));
            }
        }
        s - trilinear(&self.corners, u, v, w) * 2.0
    }

    /// The six boundary faces: the Coons patches of their four edges, in
    /// [`Body2`]'s layout (`[X_0, X_1], [Y_0, Y_1], [Z_0, Z_1]`).
    pub fn faces(&self) -> Result<[[BSplineSurface; 2]; 3], BodyError> {
        let e = &self.edges;
        let t = f64::INFINITY; // corners already agree exactly
        let x = |i: usize| coons_patch([&e.v[i][0], &e.v[i][1]], [&e.w[i][0], &e.w[i][1]], t);
        let y = |j: usize| coons_patch([&e.u[j][0], &e.u[j][1]], [&e.w[0][j], &e.w[1][j]], t);
        let z = |k: usize| coons_patch([&e.u[0][k], &e.u[1][k]], [&e.v[0][k], &e.v[1][k]], t);
        Ok([[x(0)?, x(1)?], [y(0)?, y(1)?], [z(0)?, z(1)?]])
    }

    /// The same solid as one B-spline volume, exactly (Boolean sum on
    /// control points with Greville abscissae).
    pub fn to_volume(&self) -> Result<BSplineVolume, BodyError> {
        let e = &self.edges;
        let (ku, kv, kw) = (e.u[0][0].knots(), e.v[0][0].knots(), e.w[0][0].knots());
        let (gu, gv, gw) = (greville(ku), greville(kv), greville(kw));
        let mut pts = Vec::with_capacity(gu.len() * gv.len() * gw.len());
        for (a, &xi) in gu.iter().enumerate() {
            for (b, &eta) in gv.iter().enumerate() {
                for (c, &zeta) in gw.iter().enumerate() {
                    pts.push(
                        edge_sum(e, [a, b, c], [xi, eta, zeta])
                            - trilinear(&self.corners, xi, eta, zeta) * 2.0,
                    );
                }
            }
        }
        Ok(BSplineVolume::new(ku.clone(), kv.clone(), kw.clone(), pts)?)
    }
}

/// Σ of the three bilinear edge blends on control points (a, b, c) with the
/// blending parameters at Greville abscissae g.
fn edge_sum(e: &Edges, idx: [usize; 3], g: [f64; 3]) -> DVec3 {
    let [a, b, c] = idx;
    let [xi, eta, zeta] = g;
    let mut p = DVec3::ZERO;
    for i in 0..2 {
        for j in 0..2 {
            p += e.w[i][j].points()[c] * (lam(i, xi) * lam(j, eta));
        }
    }
    for i in 0..2 {
        for k in 0..2 {
            p += e.v[i][k].points()[b] * (lam(i, xi) * lam(k, zeta));
        }
    }
    for j in 0..2 {
        for k in 0..2 {
            p += e.u[j][k].points()[a] * (lam(j, eta) * lam(k, zeta));
        }
    }
    p
}

fn set_end(c: &mut BSplineCurve, end: usize, p: DVec3) {
    let n = c.points().len();
    c.points_mut()[if end == 0 { 0 } else { n - 1 }] = p;
}

/// Which of a face's surface parameters runs along which body direction:
/// X_i(v, w), Y_j(u, w), Z_k(u, v).
const FACE_PARAMS: [(usize, usize); 3] = [(1, 2), (0, 2), (0, 1)];

/// Coons body 2: the Boolean sum of the linear blends of 6 boundary faces
/// (paper 002 §2.4), `faces[d][e]` the face at body parameter d = e
/// (d = 0: X_e(v, w); 1: Y_e(u, w); 2: Z_e(u, v)).
#[derive(Clone, Debug, PartialEq)]
pub struct Body2 {
    faces: [[BSplineSurface; 2]; 3],
    knots: [KnotVector; 3],
    mismatch: f64,
}

impl Body2 {
    /// A body from its six faces (any degrees, knots, domains); faces must
    /// share their common edges within `tolerance` (see the module doc for
    /// which face wins).
    pub fn new(faces: [[BSplineSurface; 2]; 3], tolerance: f64) -> Result<Self, BodyError> {
        let faces = faces.map(|pair| pair.map(|s| normalized_surface(&s)));
        let mut per_dir: [Vec<&KnotVector>; 3] = [vec![], vec![], vec![]];
        for (d, pair) in faces.iter().enumerate() {
            let (p1, p2) = FACE_PARAMS[d];
            for s in pair {
                per_dir[p1].push(s.u_knots());
                per_dir[p2].push(s.v_knots());
            }
        }
        let knots = [
            common_knots(&per_dir[0])?,
            common_knots(&per_dir[1])?,
            common_knots(&per_dir[2])?,
        ];
        let mut f: Vec<[BSplineSurface; 2]> = Vec::with_capacity(3);
        for (d, pair) in faces.iter().enumerate() {
            let (p1, p2) = FACE_PARAMS[d];
            f.push([
                surface_to(&pair[0], &knots[p1], &knots[p2])?,
                surface_to(&pair[1], &knots[p1], &knots[p2])?,
            ]);
        }
        let faces: [[BSplineSurface; 2]; 3] = f.try_into().expect("three pairs");
        let mut body = Self {
            faces,
            knots,
            mismatch: 0.0,
        };
        body.mismatch = body.reconcile(tolerance)?;
        Ok(body)
    }

    /// A body 2 whose faces are the six boundary faces of `volume` (its
    /// interior then follows the Boolean sum, not the volume's own interior
    /// control points).
    pub fn from_volume_faces(volume: &BSplineVolume) -> Result<Self, BodyError> {
        use super::{Dir, Face};
        let f = |dir, end| volume.face(Face { dir, end });
        Self::new(
            [
                [f(Dir::U, false), f(Dir::U, true)],
                [f(Dir::V, false), f(Dir::V, true)],
                [f(Dir::W, false), f(Dir::W, true)],
            ],
            0.0,
        )
    }

    /// Checks and copies shared edges: u-/v-edges from Z faces into X/Y
    /// faces, w-edges from X faces into Y faces. Returns the mismatch.
    fn reconcile(&mut self, tolerance: f64) -> Result<f64, BodyError> {
        let mut worst: f64 = 0.0;
        // (target face, its row (along_u, end), source face, its row)
        let mut pairs = Vec::new();
        for j in 0..2 {
            for k in 0..2 {
                // u-edge C(u,j,k): Z_k along u at v=j; Y_j along u at w=k.
                pairs.push((
                    (1, j),
                    (true, k),
                    (2, k),
                    (true, j),
                    format!("u-edge v={j} w={k}"),
                ));
            }
        }
        for i in 0..2 {
            for k in 0..2 {
                // v-edge C(i,v,k): Z_k along v at u=i; X_i along v at w=k.
                pairs.push((
                    (0, i),
                    (true, k),
                    (2, k),
                    (false, i),
                    format!("v-edge u={i} w={k}"),
                ));
            }
        }
        for i in 0..2 {
            for j in 0..2 {
                // w-edge C(i,j,w): X_i along w at v=j; Y_j along w at u=i.
                pairs.push((
                    (1, j),
                    (false, i),
                    (0, i),
                    (false, j),
                    format!("w-edge u={i} v={j}"),
                ));
            }
        }
        for ((td, te), (talong, tend), (sd, se), (salong, send), what) in pairs {
            let src = surface_edge(&self.faces[sd][se], salong, send);
            let dst = surface_edge(&self.faces[td][te], talong, tend);
            let d = max_dist(src.points(), dst.points());
            if d > tolerance || d.is_nan() {
                return Err(BodyError::Incompatible {
                    what,
                    distance: d,
                    tolerance,
                });
            }
            worst = worst.max(d);
            set_surface_edge(&mut self.faces[td][te], talong, tend, src.points());
        }
        Ok(worst)
    }

    /// The six faces (normalised, on the common spaces).
    pub fn faces(&self) -> &[[BSplineSurface; 2]; 3] {
        &self.faces
    }

    /// The common knot vectors per body direction (u, v, w).
    pub fn knots(&self) -> &[KnotVector; 3] {
        &self.knots
    }

    /// The largest edge mismatch found at construction.
    pub fn mismatch(&self) -> f64 {
        self.mismatch
    }

    /// The 12 edges as the faces carry them (Z rows for u and v, X rows
    /// for w).
    pub fn edges(&self) -> Edges {
        let f = &self.faces;
        let e = |d: usize, s: usize, along: bool, end: usize| surface_edge(&f[d][s], along, end);
        Edges {
            u: [
                [e(2, 0, true, 0), e(2, 1, true, 0)],
                [e(2, 0, true, 1), e(2, 1, true, 1)],
            ],
            v: [
                [e(2, 0, false, 0), e(2, 1, false, 0)],
                [e(2, 0, false, 1), e(2, 1, false, 1)],
            ],
            w: [
                [e(0, 0, false, 0), e(0, 0, false, 1)],
                [e(0, 1, false, 0), e(0, 1, false, 1)],
            ],
        }
    }

    fn corners(edges: &Edges) -> [[[DVec3; 2]; 2]; 2] {
        let mut c = [[[DVec3::ZERO; 2]; 2]; 2];
        for (i, ci) in c.iter_mut().enumerate() {
            for (j, cij) in ci.iter_mut().enumerate() {
                for (k, p) in cij.iter_mut().enumerate() {
                    *p = curve_end(&edges.u[j][k], i);
                }
            }
        }
        c
    }

    /// C2(u, v, w) = D − C1 − T by direct evaluation of faces and edges,
    /// (u, v, w) ∈ [0, 1]³.
    pub fn point(&self, u: f64, v: f64, w: f64) -> DVec3 {
        let f = &self.faces;
        let mut d = DVec3::ZERO;
        for e in 0..2 {
            d += f[0][e].point(v, w) * lam(e, u);
            d += f[1][e].point(u, w) * lam(e, v);
            d += f[2][e].point(u, v) * lam(e, w);
        }
        let edges = self.edges();
        let corners = Self::corners(&edges);
        let t = trilinear(&corners, u, v, w);
        let mut c1 = DVec3::ZERO;
        for i in 0..2 {
            for j in 0..2 {
                c1 += edges.w[i][j].point(w) * (lam(i, u) * lam(j, v));
                c1 += edges.v[i][j].point(v) * (lam(i, u) * lam(j, w));
                c1 += edges.u[i][j].point(u) * (lam(i, v) * lam(j, w));
            }
        }
        c1 -= t * 2.0;
        d - c1 - t
    }

    /// Moves face control point (a, b) of face `faces[d][e]` to `p`, and the
    /// same point in every other face sharing it (edge points live in two
    /// faces, corners in three), so the faces stay compatible.
    pub fn move_face_point(
        &mut self,
        d: usize,
        e: usize,
        a: usize,
        b: usize,
        p: DVec3,
    ) -> Result<(), BodyError> {
        if d > 2 || e > 1 {
            return Err(BodyError::Mismatch(format!("no face ({d}, {e})")));
        }
        let s = &self.faces[d][e];
        if a >= s.nu() || b >= s.nv() {
            return Err(BodyError::BadIndex {
                index: s.index(a.min(s.nu() - 1), b.min(s.nv() - 1)),
                count: s.points().len(),
            });
        }
        if !p.is_finite() {
            return Err(BodyError::NonFinite("face point".into()));
        }
        // The body lattice index of this point.
        let n = [
            self.knots[0].num_ctrl(),
            self.knots[1].num_ctrl(),
            self.knots[2].num_ctrl(),
        ];
        let mut ijk = [0usize; 3];
        ijk[d] = if e == 0 { 0 } else { n[d] - 1 };
        let (p1, p2) = FACE_PARAMS[d];
        ijk[p1] = a;
        ijk[p2] = b;
        for (fd, pair) in self.faces.iter_mut().enumerate() {
            for (fe, face) in pair.iter_mut().enumerate() {
                let fixed = if fe == 0 { 0 } else { n[fd] - 1 };
                if ijk[fd] == fixed {
                    let (q1, q2) = FACE_PARAMS[fd];
                    let idx = face.index(ijk[q1], ijk[q2]);
                    face.points_mut()[idx] = p;
                }
            }
        }
        Ok(())
    }

    /// The same solid as one B-spline volume on the common spaces, exactly:
    /// the Boolean sum D − C1 − T applied to control points, with the
    /// linear blends' coefficients at the Greville abscissae.
    pub fn to_volume(&self) -> Result<BSplineVolume, BodyError> {
        let f = &self.faces;
        let edges = self.edges();
        let corners = Self::corners(&edges);
        let g = [
            greville(&self.knots[0]),
            greville(&self.knots[1]),
            greville(&self.knots[2]),
        ];
        let mut pts = Vec::with_capacity(g[0].len() * g[1].len() * g[2].len());
        for (a, &xi) in g[0].iter().enumerate() {
            for (b, &eta) in g[1].iter().enumerate() {
                for (c, &zeta) in g[2].iter().enumerate() {
                    let mut d = DVec3::ZERO;
                    for e in 0..2 {
                        d += f[0][e].points()[f[0][e].index(b, c)] * lam(e, xi);
                        d += f[1][e].points()[f[1][e].index(a, c)] * lam(e, eta);
                        d += f[2][e].points()[f[2][e].index(a, b)] * lam(e, zeta);
                    }
                    let t = trilinear(&corners, xi, eta, zeta);
                    let c1 = edge_sum(&edges, [a, b, c], [xi, eta, zeta]) - t * 2.0;
                    pts.push(d - c1 - t);
                }
            }
        }
        let [ku, kv, kw] = self.knots.clone();
        Ok(BSplineVolume::new(ku, kv, kw, pts)?)
    }
}

fn set_surface_edge(s: &mut BSplineSurface, along_u: bool, end: usize, pts: &[DVec3]) {
    let (nu, nv) = (s.nu(), s.nv());
    if along_u {
        let j = if end == 0 { 0 } else { nv - 1 };
        for (i, &p) in pts.iter().enumerate() {
            let idx = s.index(i, j);
            s.points_mut()[idx] = p;
        }
    } else {
        let i = if end == 0 { 0 } else { nu - 1 };
        for (j, &p) in pts.iter().enumerate() {
            let idx = s.index(i, j);
            s.points_mut()[idx] = p;
        }
    }
}

/// The 12 edges of a body from curves over any domain (normalised copies).
pub fn normalized_edges(e: &Edges) -> Edges {
    let n = |c: &BSplineCurve| normalized_curve(c);
    Edges {
        u: [
            [n(&e.u[0][0]), n(&e.u[0][1])],
            [n(&e.u[1][0]), n(&e.u[1][1])],
        ],
        v: [
            [n(&e.v[0][0]), n(&e.v[0][1])],
            [n(&e.v[1][0]), n(&e.v[1][1])],
        ],
        w: [
            [n(&e.w[0][0]), n(&e.w[0][1])],
            [n(&e.w[1][0]), n(&e.w[1][1])],
        ],
    }
}
