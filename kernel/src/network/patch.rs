//! The n-sided patch of a face: Kato's side-based transfinite patch over a
//! regular n-gon, with Wachspress-based side parameters (see [`super::domain`])
//! and the ribbons of [`super::ribbon`]:
//!
//! ```text
//! S(p) = Σ_i R_i(s_i, d_i) · B_i(p) + Σ_k φ_k(p) h_k,
//! B_i = Π_{j≠i} d_j² / Σ_l Π_{j≠l} d_j²
//! ```
//!
//! On side i (d_i = 0) every B_l with l ≠ i carries the factor d_i², so
//! B_i = 1 and all blends have zero gradient there: S = c_i and its tangent
//! plane is spanned by c_i′ and D_i, whose normal is the edge's normal field
//! — the same for the face across, hence G1 along every shared curve. The
//! blends are 0/0 only at the domain's corners, where S is the corner point.
//!
//! **Tuning handles** (the paper's u²v² terms): φ_0 = β/β(centre) and
//! φ_k = n λ_k β/β(centre) for the corners k, with β = Π_j d_j² — zero with
//! its gradient on the whole boundary, so the handle vectors h_0 (centre)
//! and h_1..h_n (towards each corner) move the interior only; they leave
//! the boundary curves and the tangent planes along them unchanged.

use glam::{DVec2, DVec3};

use super::domain::{Domain, SideParams};
use super::jet::{Jet, Scalar, V3};
use super::ribbon::SideRibbon;
use crate::bspline::BasisDerivs;

/// An n-sided patch: a value, evaluated anywhere in its domain.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    domain: Domain,
    sides: Vec<SideRibbon>,
    tuning: Vec<DVec3>,
    beta_centre: f64,
}

/// Blend and tuning weights of one domain point: what a re-evaluation needs
/// besides the ribbons (precomputed by [`super::sampler::PatchSampler`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PointWeights {
    /// The domain corner the point is at, if any.
    pub corner: Option<usize>,
    /// s_i.
    pub s: Vec<f64>,
    /// d_i.
    pub d: Vec<f64>,
    /// B_i.
    pub blend: Vec<f64>,
    /// φ_0 … φ_n.
    pub tuning: Vec<f64>,
}

impl Patch {
    /// A patch from its side ribbons (counter-clockwise, at least 3), with
    /// zero tuning.
    pub fn new(sides: Vec<SideRibbon>) -> Self {
        let n = sides.len();
        let domain = Domain::regular(n);
        let prm = domain.params(0.0, 0.0);
        let beta_centre = prm.d.iter().map(|d| d * d).product();
        Self {
            domain,
            sides,
            tuning: vec![DVec3::ZERO; n + 1],
            beta_centre,
        }
    }

    /// Number of sides.
    pub fn sides(&self) -> usize {
        self.sides.len()
    }

    /// The side ribbons.
    pub fn ribbons(&self) -> &[SideRibbon] {
        &self.sides
    }

    /// The domain polygon.
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The tuning handles h_0 (centre), h_1..h_n (corners).
    pub fn tuning(&self) -> &[DVec3] {
        &self.tuning
    }

    /// Sets the tuning handles (n + 1 finite vectors; the caller checks).
    pub fn set_tuning(&mut self, h: Vec<DVec3>) {
        self.tuning = h;
    }

    /// The weights at domain point `p`.
    pub fn weights(&self, p: DVec2) -> PointWeights {
        let n = self.sides();
        if let Some(k) = self.domain.corner_at(p) {
            return PointWeights {
                corner: Some(k),
                s: vec![0.0; n],
                d: vec![0.0; n],
                blend: vec![0.0; n],
                tuning: vec![0.0; n + 1],
            };
        }
        let prm = self.domain.params(p.x, p.y);
        let (blend, tuning) = self.blends(&prm);
        PointWeights {
            corner: None,
            s: prm.s,
            d: prm.d,
            blend,
            tuning,
        }
    }

    fn blends<S: Scalar>(&self, prm: &SideParams<S>) -> (Vec<S>, Vec<S>) {
        let n = self.sides();
        let d2: Vec<S> = prm.d.iter().map(|d| *d * *d).collect();
        let q: Vec<S> = (0..n)
            .map(|i| {
                let mut prod = S::cst(1.0);
                for (j, x) in d2.iter().enumerate() {
                    if j != i {
                        prod = prod * *x;
                    }
                }
                prod
            })
            .collect();
        let total = q.iter().fold(S::cst(0.0), |a, x| a + *x);
        let blend = q.iter().map(|x| *x / total).collect();
        let beta = d2.iter().fold(S::cst(1.0), |a, x| a * *x) / S::cst(self.beta_centre);
        let mut tuning = vec![beta];
        tuning.extend(prm.lambda.iter().map(|l| beta * *l * S::cst(n as f64)));
        (blend, tuning)
    }

    /// S at the domain point (x, y), generic: `f64` for the point, [`Jet`]
    /// for the point and its exact first derivatives.
    pub fn eval<S: Scalar>(&self, x: S, y: S) -> V3<S> {
        if let Some(k) = self.domain.corner_at(DVec2::new(x.val(), y.val())) {
            return V3::cst(self.sides[k].point(0.0));
        }
        let prm = self.domain.params(x, y);
        let (blend, tuning) = self.blends(&prm);
        let mut scratch = BasisDerivs::default();
        let mut out = V3::cst(DVec3::ZERO);
        for (i, side) in self.sides.iter().enumerate() {
            out = out.plus(side.eval(prm.s[i], prm.d[i], &mut scratch).scale(blend[i]));
        }
        for (h, w) in self.tuning.iter().zip(tuning) {
            if *h != DVec3::ZERO {
                out = out.plus(V3::cst(*h).scale(w));
            }
        }
        out
    }

    /// S(p).
    pub fn point(&self, p: DVec2) -> DVec3 {
        self.eval(p.x, p.y).val()
    }

    /// S(p), ∂S/∂x, ∂S/∂y (exact; zero derivatives at a corner).
    pub fn derivs(&self, p: DVec2) -> (DVec3, DVec3, DVec3) {
        let (x, y) = Jet::variables(p.x, p.y);
        let s = self.eval(x, y);
        (s.val(), s.dx(), s.dy())
    }

    /// The unit normal S_x × S_y at p (oriented like the network's normals).
    pub fn normal(&self, p: DVec2) -> DVec3 {
        let (_, sx, sy) = self.derivs(p);
        sx.cross(sy).normalize()
    }

    /// S from precomputed weights, reusing `scratch`.
    pub fn eval_weights(&self, w: &PointWeights, scratch: &mut BasisDerivs) -> DVec3 {
        if let Some(k) = w.corner {
            return self.sides[k].point(0.0);
        }
        let mut out = DVec3::ZERO;
        for (i, side) in self.sides.iter().enumerate() {
            out += side.eval(w.s[i], w.d[i], scratch).val() * w.blend[i];
        }
        for (h, t) in self.tuning.iter().zip(&w.tuning) {
            out += *h * *t;
        }
        out
    }
}
