//! Tensor-product B-spline volumes (trivariate B-spline solids) of any
//! degree (l, m, n) with clamped knots:
//!
//! ```text
//! x(u, v, w) = Σ_i Σ_j Σ_k N_i(u) M_j(v) L_k(w) P_ijk
//! ```
//!
//! Evaluation with first and second derivatives, the Jacobian, the exact
//! isoparametric surfaces at constant u, v or w (paper 002 §2.1) and the six
//! boundary faces. Control points are stored with k (along w) fastest:
//! `points[(i * nv + j) * nw + k]`. The 1-D basis is [`crate::bspline`]'s.

use glam::{DMat3, DVec3};

use super::BodyError;
use crate::bspline::{
    BSplineCurve, BSplineSurface, BasisDerivs, GeometryError, KnotVector, basis_derivs_into,
    greville,
};

/// One parameter direction of a volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dir {
    /// The first parameter, u (index i).
    U = 0,
    /// The second parameter, v (index j).
    V = 1,
    /// The third parameter, w (index k).
    W = 2,
}

impl Dir {
    /// All three directions in order.
    pub const ALL: [Dir; 3] = [Dir::U, Dir::V, Dir::W];

    /// 0, 1 or 2.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The two other directions, in increasing order (the parameters of an
    /// isoparametric surface at constant `self`).
    pub fn others(self) -> (Dir, Dir) {
        match self {
            Dir::U => (Dir::V, Dir::W),
            Dir::V => (Dir::U, Dir::W),
            Dir::W => (Dir::U, Dir::V),
        }
    }
}

/// One of the six boundary faces: the direction held constant and whether
/// at the domain's start (`false`) or end (`true`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Face {
    /// The direction held constant.
    pub dir: Dir,
    /// `false`: at the start of the domain (u = 0 for `Dir::U`); `true`: at its end.
    pub end: bool,
}

impl Face {
    /// The six faces: u = 0, u = 1, v = 0, v = 1, w = 0, w = 1.
    pub const ALL: [Face; 6] = [
        Face {
            dir: Dir::U,
            end: false,
        },
        Face {
            dir: Dir::U,
            end: true,
        },
        Face {
            dir: Dir::V,
            end: false,
        },
        Face {
            dir: Dir::V,
            end: true,
        },
        Face {
            dir: Dir::W,
            end: false,
        },
        Face {
            dir: Dir::W,
            end: true,
        },
    ];
}

/// Position and derivatives of a volume at one parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VolumeDerivs {
    /// x(u, v, w).
    pub p: DVec3,
    /// First derivatives: `d[0]` = x_u, `d[1]` = x_v, `d[2]` = x_w.
    pub d: [DVec3; 3],
    /// Second derivatives: `dd[a][b]` = ∂²x/∂a∂b (symmetric).
    pub dd: [[DVec3; 3]; 3],
}

impl VolumeDerivs {
    /// The Jacobian matrix with columns x_u, x_v, x_w.
    pub fn jacobian(&self) -> DMat3 {
        DMat3::from_cols(self.d[0], self.d[1], self.d[2])
    }

    /// det J = x_u · (x_v × x_w).
    pub fn det(&self) -> f64 {
        self.d[0].dot(self.d[1].cross(self.d[2]))
    }
}

/// Reusable basis storage for allocation-free evaluation in hot loops.
#[derive(Clone, Debug, Default)]
pub struct VolumeScratch {
    b: [BasisDerivs; 3],
}

/// A trivariate tensor-product B-spline volume with clamped knots.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineVolume {
    knots: [KnotVector; 3],
    points: Vec<DVec3>,
}

impl BSplineVolume {
    /// A volume from its three knot vectors and `nu * nv * nw` finite
    /// control points (k fastest, then j, then i).
    pub fn new(
        u: KnotVector,
        v: KnotVector,
        w: KnotVector,
        points: Vec<DVec3>,
    ) -> Result<Self, GeometryError> {
        let expected = u.num_ctrl() * v.num_ctrl() * w.num_ctrl();
        if points.len() != expected {
            return Err(GeometryError::GridSize {
                expected,
                got: points.len(),
            });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::NonFinitePoint { index });
        }
        Ok(Self {
            knots: [u, v, w],
            points,
        })
    }

    /// The affine solid x = origin + u·axes[0] + v·axes[1] + w·axes[2] over
    /// [0, 1]³ as a volume of the given degrees and control-point counts
    /// (clamped uniform knots): control points at the Greville abscissae,
    /// which is what makes a B-spline lattice reproduce the affine map
    /// exactly (linear precision). With `count = degree + 1` in every
    /// direction this is Sederberg–Parry's undisplaced Bernstein lattice.
    pub fn affine(
        origin: DVec3,
        axes: [DVec3; 3],
        degrees: [usize; 3],
        counts: [usize; 3],
    ) -> Result<Self, BodyError> {
        if !origin.is_finite() || axes.iter().any(|a| !a.is_finite()) {
            return Err(BodyError::NonFinite("affine frame".into()));
        }
        let ku = KnotVector::clamped_uniform(degrees[0], counts[0])?;
        let kv = KnotVector::clamped_uniform(degrees[1], counts[1])?;
        let kw = KnotVector::clamped_uniform(degrees[2], counts[2])?;
        let (gu, gv, gw) = (greville(&ku), greville(&kv), greville(&kw));
        let mut points = Vec::with_capacity(gu.len() * gv.len() * gw.len());
        for &a in &gu {
            for &b in &gv {
                for &c in &gw {
                    points.push(origin + axes[0] * a + axes[1] * b + axes[2] * c);
                }
            }
        }
        Ok(Self::new(ku, kv, kw, points)?)
    }

    /// Control-point counts (nu, nv, nw).
    pub fn counts(&self) -> [usize; 3] {
        [
            self.knots[0].num_ctrl(),
            self.knots[1].num_ctrl(),
            self.knots[2].num_ctrl(),
        ]
    }

    /// Degrees (l, m, n).
    pub fn degrees(&self) -> [usize; 3] {
        [
            self.knots[0].degree(),
            self.knots[1].degree(),
            self.knots[2].degree(),
        ]
    }

    /// The knot vector of direction `d`.
    pub fn knots(&self, d: Dir) -> &KnotVector {
        &self.knots[d.index()]
    }

    /// The storage index of control point (i, j, k).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        let [_, nv, nw] = self.counts();
        (i * nv + j) * nw + k
    }

    /// The (i, j, k) of a storage index.
    pub fn ijk(&self, index: usize) -> [usize; 3] {
        let [_, nv, nw] = self.counts();
        [index / (nv * nw), (index / nw) % nv, index % nw]
    }

    /// All control points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Replaces control point `index` by `p` (finite) without any further
    /// check (see [`crate::body::interior`] for checked edits).
    pub fn set_point(&mut self, index: usize, p: DVec3) -> Result<(), BodyError> {
        if index >= self.points.len() {
            return Err(BodyError::BadIndex {
                index,
                count: self.points.len(),
            });
        }
        if !p.is_finite() {
            return Err(BodyError::NonFinite(format!("control point {index}")));
        }
        self.points[index] = p;
        Ok(())
    }

    /// Mutable control points, for kernel code that keeps them finite.
    pub(crate) fn points_mut_crate(&mut self) -> &mut [DVec3] {
        &mut self.points
    }

    /// Replaces all control points (same count, all finite).
    pub fn set_points(&mut self, points: Vec<DVec3>) -> Result<(), BodyError> {
        if points.len() != self.points.len() {
            return Err(GeometryError::GridSize {
                expected: self.points.len(),
                got: points.len(),
            }
            .into());
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::NonFinitePoint { index }.into());
        }
        self.points = points;
        Ok(())
    }

    /// The parameter domain per direction.
    pub fn domain(&self) -> [(f64, f64); 3] {
        [
            self.knots[0].domain(),
            self.knots[1].domain(),
            self.knots[2].domain(),
        ]
    }

    /// x(u, v, w); parameters are clamped into the domain.
    pub fn point(&self, u: f64, v: f64, w: f64) -> DVec3 {
        self.eval(&mut VolumeScratch::default(), [u, v, w], 0).p
    }

    /// x and all derivatives up to second order; parameters clamped into the
    /// domain. At a knot the derivatives are those of the span starting there
    /// (the domain's end belongs to the last span).
    pub fn derivs(&self, u: f64, v: f64, w: f64) -> VolumeDerivs {
        self.eval(&mut VolumeScratch::default(), [u, v, w], 2)
    }

    /// The Jacobian (columns x_u, x_v, x_w) at (u, v, w).
    pub fn jacobian(&self, u: f64, v: f64, w: f64) -> DMat3 {
        self.eval(&mut VolumeScratch::default(), [u, v, w], 1)
            .jacobian()
    }

    /// Position and derivatives up to `order` (0, 1 or 2; higher is treated
    /// as 2) at `t`, reusing `scratch` (allocation-free once warmed up).
    pub fn eval(&self, scratch: &mut VolumeScratch, t: [f64; 3], order: usize) -> VolumeDerivs {
        let order = order.min(2);
        for ((kv, &td), b) in self.knots.iter().zip(&t).zip(&mut scratch.b) {
            basis_derivs_into(kv, td, order, b);
        }
        self.combine(&scratch.b, order)
    }

    /// Sums control points against precomputed basis values (derivatives up
    /// to `order` ≤ 2 as held by `b`).
    pub fn combine(&self, b: &[BasisDerivs; 3], order: usize) -> VolumeDerivs {
        let [pu, pv, pw] = self.degrees();
        let [_, nv, nw] = self.counts();
        let mut out = VolumeDerivs::default();
        let o = order.min(2);
        for a in 0..=pu {
            let mut cu = [[DVec3::ZERO; 3]; 3]; // cu[dv][dw]: contracted over v and w
            for bj in 0..=pv {
                let base = ((b[0].first + a) * nv + b[1].first + bj) * nw + b[2].first;
                let mut cw = [DVec3::ZERO; 3];
                for ck in 0..=pw {
                    let p = self.points[base + ck];
                    for (dw, c) in cw.iter_mut().enumerate().take(o + 1) {
                        *c += p * b[2].get(dw, ck);
                    }
                }
                for (dv, row) in cu.iter_mut().enumerate().take(o + 1) {
                    let m = b[1].get(dv, bj);
                    for (dw, c) in row.iter_mut().enumerate().take(o + 1 - dv) {
                        *c += cw[dw] * m;
                    }
                }
            }
            let n0 = b[0].get(0, a);
            out.p += cu[0][0] * n0;
            if o >= 1 {
                let n1 = b[0].get(1, a);
                out.d[0] += cu[0][0] * n1;
                out.d[1] += cu[1][0] * n0;
                out.d[2] += cu[0][1] * n0;
                if o >= 2 {
                    let n2 = b[0].get(2, a);
                    out.dd[0][0] += cu[0][0] * n2;
                    out.dd[0][1] += cu[1][0] * n1;
                    out.dd[0][2] += cu[0][1] * n1;
                    out.dd[1][1] += cu[2][0] * n0;
                    out.dd[1][2] += cu[1][1] * n0;
                    out.dd[2][2] += cu[0][2] * n0;
                }
            }
        }
        out.dd[1][0] = out.dd[0][1];
        out.dd[2][0] = out.dd[0][2];
        out.dd[2][1] = out.dd[1][2];
        out
    }

    /// The exact isoparametric surface at `dir` = `t` (clamped into the
    /// domain): a B-spline surface over the two other directions in
    /// increasing order ((v, w) for `Dir::U`, (u, w) for `Dir::V`, (u, v)
    /// for `Dir::W`) with the volume's knots in those directions.
    pub fn iso_surface(&self, dir: Dir, t: f64) -> BSplineSurface {
        let mut b = BasisDerivs::default();
        basis_derivs_into(&self.knots[dir.index()], t, 0, &mut b);
        let (d1, d2) = dir.others();
        let c = self.counts();
        let (n1, n2) = (c[d1.index()], c[d2.index()]);
        let mut pts = Vec::with_capacity(n1 * n2);
        for a in 0..n1 {
            for bb in 0..n2 {
                let mut s = DVec3::ZERO;
                for (r, &nr) in b.row(0).iter().enumerate() {
                    let mut ijk = [0usize; 3];
                    ijk[dir.index()] = b.first + r;
                    ijk[d1.index()] = a;
                    ijk[d2.index()] = bb;
                    s += self.points[self.index(ijk[0], ijk[1], ijk[2])] * nr;
                }
                pts.push(s);
            }
        }
        BSplineSurface::new(
            self.knots[d1.index()].clone(),
            self.knots[d2.index()].clone(),
            pts,
        )
        .expect("sizes and knots come from a valid volume")
    }

    /// The boundary face `face` as an exact B-spline surface (its control
    /// points are the volume's outer layer of control points).
    pub fn face(&self, face: Face) -> BSplineSurface {
        let (a, b) = self.knots[face.dir.index()].domain();
        self.iso_surface(face.dir, if face.end { b } else { a })
    }

    /// The storage indices of the control points on boundary face `face`.
    pub fn face_indices(&self, face: Face) -> Vec<usize> {
        let c = self.counts();
        let fixed = if face.end { c[face.dir.index()] - 1 } else { 0 };
        (0..self.points.len())
            .filter(|&idx| self.ijk(idx)[face.dir.index()] == fixed)
            .collect()
    }

    /// The storage indices of the control points on the boundary edge along
    /// `dir` where the two other directions (in increasing order) are at
    /// their start (`false`) or end (`true`): e.g. `edge_indices(Dir::W,
    /// true, false)` is the edge u = end, v = start. In order along `dir`.
    pub fn edge_indices(&self, dir: Dir, first_end: bool, second_end: bool) -> Vec<usize> {
        let c = self.counts();
        let (d1, d2) = dir.others();
        let o1 = if first_end { c[d1.index()] - 1 } else { 0 };
        let o2 = if second_end { c[d2.index()] - 1 } else { 0 };
        (0..c[dir.index()])
            .map(|r| {
                let mut ijk = [0usize; 3];
                ijk[dir.index()] = r;
                ijk[d1.index()] = o1;
                ijk[d2.index()] = o2;
                self.index(ijk[0], ijk[1], ijk[2])
            })
            .collect()
    }

    /// Whether control point `index` lies on the outer layer of the lattice
    /// (on one of the six boundary faces).
    pub fn is_boundary_point(&self, index: usize) -> bool {
        let c = self.counts();
        let ijk = self.ijk(index);
        (0..3).any(|d| ijk[d] == 0 || ijk[d] + 1 == c[d])
    }

    /// The line of control points along `dir` through the other two indices
    /// `(o1, o2)` (in increasing direction order), as a B-spline curve.
    pub fn line(&self, dir: Dir, o1: usize, o2: usize) -> BSplineCurve {
        let (d1, d2) = dir.others();
        let n = self.counts()[dir.index()];
        let pts = (0..n)
            .map(|r| {
                let mut ijk = [0usize; 3];
                ijk[dir.index()] = r;
                ijk[d1.index()] = o1;
                ijk[d2.index()] = o2;
                self.points[self.index(ijk[0], ijk[1], ijk[2])]
            })
            .collect();
        BSplineCurve::new(self.knots[dir.index()].clone(), pts)
            .expect("a volume's line is a valid curve")
    }

    /// Rebuilds the volume after replacing every line along `dir` by `f` of
    /// it; all results must share one knot vector.
    pub(crate) fn map_lines<F>(&self, dir: Dir, mut f: F) -> Result<Self, BodyError>
    where
        F: FnMut(&BSplineCurve) -> Result<BSplineCurve, BodyError>,
    {
        let (d1, d2) = dir.others();
        let c = self.counts();
        let (n1, n2) = (c[d1.index()], c[d2.index()]);
        let mut lines = Vec::with_capacity(n1 * n2);
        for a in 0..n1 {
            for b in 0..n2 {
                lines.push(f(&self.line(dir, a, b))?);
            }
        }
        let kv = lines[0].knots().clone();
        if lines.iter().any(|l| l.knots() != &kv) {
            return Err(BodyError::Mismatch("lines got different knots".into()));
        }
        let mut counts = c;
        counts[dir.index()] = kv.num_ctrl();
        let mut knots = self.knots.clone();
        knots[dir.index()] = kv;
        let mut points = vec![DVec3::ZERO; counts[0] * counts[1] * counts[2]];
        for a in 0..n1 {
            for b in 0..n2 {
                for (r, &p) in lines[a * n2 + b].points().iter().enumerate() {
                    let mut ijk = [0usize; 3];
                    ijk[dir.index()] = r;
                    ijk[d1.index()] = a;
                    ijk[d2.index()] = b;
                    points[(ijk[0] * counts[1] + ijk[1]) * counts[2] + ijk[2]] = p;
                }
            }
        }
        let [ku, kv, kw] = knots;
        Ok(Self::new(ku, kv, kw, points)?)
    }
}
