//! Cross-boundary tangent ribbons: the tangent plane along every edge and,
//! for each side of a face, the cross-boundary derivative that the patch
//! takes on there.
//!
//! * **Normal field along an edge** (shared by the two faces on it, which is
//!   what makes them G1): the end vertices' normals, their angles about the
//!   tangent blended linearly along the edge in a reference frame carried
//!   by the curve ([`NormalPiece`]), plus the edge's **twist handle**
//!   twist·sin(πu) (zero at the vertices, so corners keep their tangent
//!   planes).
//! * **Ribbon of a side** (s ∈ [0, 1] along the side in walking order, face on
//!   the left): R(s, d) = c(s) + d·D(s) with D(s) = σ(s) (a(s) T(s) + b(s) B(s)),
//!   T the unit walking tangent, B = n × T (into the face), a and b linear
//!   in s between the corner values, σ(s) = 1 + (scale − 1) sin(πs) the
//!   side's **scale handle**. The corner values make the ribbons compatible
//!   with the neighbouring sides: D(0) = −c′_prev(1) and D(1) = c′_next(0)
//!   (derivatives with respect to each side's own s), expressed in the
//!   (T, B) frame at the corner. A corner whose angle is 180° or more would
//!   give b ≤ 0; b is kept at least 0.1 |D| there.

use glam::DVec3;

use super::jet::{Scalar, V3};
use crate::bspline::{BSplineCurve, BasisDerivs, basis_derivs_into};

/// The normal field on one edge of a curve: n(u) = cos α(u) U + sin α(u) W
/// in a reference frame carried by the curve, U = unit(a − T(T·a)),
/// W = T × U, for a fixed axis a as far from every tangent of the edge as
/// possible (the smallest-eigenvalue direction of Σ T Tᵀ over 32 samples),
/// α(u) = α0 + u(α1 − α0) + twist·sin(πu), α0 and α1 the end normals'
/// angles (α1 − α0 in (−π, π]). Unlike a blend of the end vectors this stays
/// defined on an edge that turns by 180° (a ring around a bottle's neck).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalPiece {
    /// Start parameter on the curve.
    pub t0: f64,
    /// End parameter.
    pub t1: f64,
    /// The reference axis a.
    pub axis: DVec3,
    /// α0 and α1.
    pub alpha: [f64; 2],
    /// The twist handle (radians at the middle of the edge).
    pub twist: f64,
}

/// (U, W) of the reference frame at the unit tangent `tangent`.
fn reference<S: Scalar>(axis: DVec3, tangent: V3<S>) -> (V3<S>, V3<S>) {
    let a = V3::cst(axis);
    let u = a.minus(tangent.scale(tangent.dot(a))).normalize();
    (u, tangent.cross(u))
}

impl NormalPiece {
    /// The field on `curve` over [t0, t1] from the end normals n0, n1.
    pub fn new(curve: &BSplineCurve, t0: f64, t1: f64, n0: DVec3, n1: DVec3, twist: f64) -> Self {
        let mut cov = glam::DMat3::ZERO;
        for k in 0..=32 {
            let t = curve
                .derivs(t0 + (t1 - t0) * k as f64 / 32.0)
                .d1
                .normalize_or_zero();
            cov += glam::DMat3::from_cols(t * t.x, t * t.y, t * t.z);
        }
        let axis = crate::fairing::eigen3::sym3_eigen(cov).1[0];
        let angle = |t: f64, n: DVec3| {
            let tan = V3::<f64>::cst(curve.derivs(t).d1.normalize());
            let (u, w) = reference(axis, tan);
            n.dot(w.val()).atan2(n.dot(u.val()))
        };
        let a0 = angle(t0, n0);
        let mut a1 = angle(t1, n1);
        let tau = std::f64::consts::TAU;
        while a1 - a0 > std::f64::consts::PI {
            a1 -= tau;
        }
        while a1 - a0 <= -std::f64::consts::PI {
            a1 += tau;
        }
        Self {
            t0,
            t1,
            axis,
            alpha: [a0, a1],
            twist,
        }
    }

    /// The normal `n` at curve parameter `from` (an end of this piece)
    /// carried to the other end in the reference frame: what the other end's
    /// normal should agree with (used to orient normals consistently).
    pub fn carry(&self, curve: &BSplineCurve, from: f64, n: DVec3) -> DVec3 {
        let to = if from == self.t0 { self.t1 } else { self.t0 };
        let frame = |t: f64| {
            let tan = V3::<f64>::cst(curve.derivs(t).d1.normalize());
            let (u, w) = reference(self.axis, tan);
            (u.val(), w.val())
        };
        let (u0, w0) = frame(from);
        let a = n.dot(w0).atan2(n.dot(u0));
        let (u1, w1) = frame(to);
        u1 * a.cos() + w1 * a.sin()
    }
}

/// c(t), c′(t), c″(t) with a reused basis scratch (no allocation once warm).
pub fn curve_derivs(c: &BSplineCurve, t: f64, b: &mut BasisDerivs) -> [DVec3; 3] {
    basis_derivs_into(c.knots(), t, 2, b);
    let mut out = [DVec3::ZERO; 3];
    let pts = c.points();
    for k in 0..=c.degree() {
        let p = pts[b.first + k];
        out[0] += p * b.get(0, k);
        out[1] += p * b.get(1, k);
        out[2] += p * b.get(2, k);
    }
    out
}

/// The unit normal of the tangent plane at curve parameter `t` (a function
/// of the domain point through `t`), given the curve's unit tangent there.
pub fn normal_at<S: Scalar>(pieces: &[NormalPiece], t: S, tangent: V3<S>) -> V3<S> {
    let tv = t.val();
    let piece = pieces
        .iter()
        .find(|p| tv <= p.t1)
        .unwrap_or_else(|| pieces.last().expect("an edge has a normal piece"));
    let u = (t - S::cst(piece.t0)) / S::cst(piece.t1 - piece.t0);
    let mut alpha = S::cst(piece.alpha[0]) + u * S::cst(piece.alpha[1] - piece.alpha[0]);
    if piece.twist != 0.0 {
        alpha = alpha + (u * S::cst(std::f64::consts::PI)).sin() * S::cst(piece.twist);
    }
    let (uu, ww) = reference(piece.axis, tangent);
    uu.scale(alpha.cos()).plus(ww.scale(alpha.sin()))
}

/// A side's boundary curve and cross-boundary derivative.
#[derive(Clone, Debug, PartialEq)]
pub struct SideRibbon {
    /// The curve (a copy: a patch is a value).
    pub curve: BSplineCurve,
    /// Where the side starts on the curve.
    pub t_start: f64,
    /// Where it ends.
    pub t_end: f64,
    /// The normal field over the side's edges, ordered by t.
    pub pieces: Vec<NormalPiece>,
    /// a at s = 0 and s = 1.
    pub a: [f64; 2],
    /// b at s = 0 and s = 1.
    pub b: [f64; 2],
    /// The scale handle (1: the compatible ribbon).
    pub scale: f64,
}

impl SideRibbon {
    /// c(s), c′(s) (with respect to s) and the walking tangent's frame at s.
    fn frame<S: Scalar>(&self, s: S, scratch: &mut BasisDerivs) -> (V3<S>, V3<S>, V3<S>, V3<S>) {
        let t = self.t_start + s.val() * (self.t_end - self.t_start);
        let derivs = curve_derivs(&self.curve, t, scratch);
        self.frame_from(s, derivs)
    }

    /// The frame at s given c, c′, c″ (with respect to the curve's t) there.
    fn frame_from<S: Scalar>(&self, s: S, [p, d1, d2]: [DVec3; 3]) -> (V3<S>, V3<S>, V3<S>, V3<S>) {
        let dt = self.t_end - self.t_start;
        let t = S::cst(self.t_start) + s * S::cst(dt);
        let c = V3::chain(s, p, d1 * dt);
        let cs = V3::chain(s, d1 * dt, d2 * dt * dt);
        let walk = cs.normalize();
        let along = if dt >= 0.0 {
            walk
        } else {
            walk.scale(S::cst(-1.0))
        };
        let n = normal_at(&self.pieces, t, along);
        (c, cs, walk, n)
    }

    /// The cross-boundary derivative direction data at s: (T, B) frame.
    pub fn frame_at(&self, s: f64) -> (DVec3, DVec3, DVec3) {
        let mut b = BasisDerivs::default();
        let (_, _, t, n) = self.frame::<f64>(s, &mut b);
        (t.val(), n.cross(t).val(), n.val())
    }

    /// R(s, d) = c(s) + d·D(s).
    pub fn eval<S: Scalar>(&self, s: S, d: S, scratch: &mut BasisDerivs) -> V3<S> {
        let t = self.t_start + s.val() * (self.t_end - self.t_start);
        let derivs = curve_derivs(&self.curve, t, scratch);
        self.eval_from(s, d, derivs)
    }

    /// R(s, d) given c, c′, c″ at the curve parameter of s (precomputed
    /// basis values make this a linear combination of control points).
    pub fn eval_from<S: Scalar>(&self, s: S, d: S, derivs: [DVec3; 3]) -> V3<S> {
        let (c, _, t, n) = self.frame_from(s, derivs);
        let bdir = n.cross(t);
        let one = S::cst(1.0);
        let a = S::cst(self.a[0]) * (one - s) + S::cst(self.a[1]) * s;
        let b = S::cst(self.b[0]) * (one - s) + S::cst(self.b[1]) * s;
        let mut dvec = t.scale(a).plus(bdir.scale(b));
        if self.scale != 1.0 {
            let bump = (s * S::cst(std::f64::consts::PI)).sin();
            dvec = dvec.scale(one + S::cst(self.scale - 1.0) * bump);
        }
        c.plus(dvec.scale(d))
    }

    /// c(s).
    pub fn point(&self, s: f64) -> DVec3 {
        self.curve
            .point(self.t_start + s * (self.t_end - self.t_start))
    }

    /// dc/ds.
    pub fn tangent(&self, s: f64) -> DVec3 {
        self.curve
            .derivs(self.t_start + s * (self.t_end - self.t_start))
            .d1
            * (self.t_end - self.t_start)
    }

    /// The tangent-plane normal n(s) of the side (the edge's normal field).
    pub fn normal(&self, s: f64) -> DVec3 {
        self.frame_at(s).2
    }

    /// Sets the corner values from the wanted D(0) and D(1).
    pub fn set_corners(&mut self, d0: DVec3, d1: DVec3) {
        for (k, (s, d)) in [(0.0, d0), (1.0, d1)].into_iter().enumerate() {
            let (t, b, _) = self.frame_at(s);
            self.a[k] = d.dot(t);
            self.b[k] = d.dot(b).max(0.1 * d.length());
        }
    }
}
