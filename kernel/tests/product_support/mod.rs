//! Shared scene and checks for the product tests: panels whose edges fit
//! (or do not), seam measurements at fine grids, an independent dense KKT
//! solve of a joined pair.
#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector, greville};
use vsculpt_kernel::curve_design::CurveDesign;
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::{CurveMaterial, Stiffness, SurfaceMaterial};
use vsculpt_kernel::icon::{Anchor, IconSpec, IconState, Role};
use vsculpt_kernel::product::{Edge, Part, PartId, Product};

/// The v knots shared by the joinable panels: cubic, 7 control points,
/// non-uniform interior knots, over [0, len].
pub fn v_knots(len: f64) -> KnotVector {
    let k = [0.0, 0.0, 0.0, 0.0, 0.2, 0.45, 0.7, 1.0, 1.0, 1.0, 1.0];
    KnotVector::new(3, k.iter().map(|t| t * len).collect()).unwrap()
}

/// A bumpy panel over x ∈ [x0, x0 + 1], y ∈ [0, 1]: `nu` cubic control
/// points along u (domain [0, 1]), `v` along v; z = lift + tilt·(x − x0) +
/// 0.15·sin(π s) sin(π t).
pub fn panel(x0: f64, nu: usize, v: KnotVector, lift: f64, tilt: f64) -> BSplineSurface {
    let u = KnotVector::clamped_uniform(3, nu).unwrap();
    let (gu, gv) = (greville(&u), greville(&v));
    let (v0, v1) = v.domain();
    let mut pts = Vec::new();
    for &s in &gu {
        for &t in &gv {
            let t = (t - v0) / (v1 - v0);
            let z = lift
                + tilt * s
                + 0.15 * (std::f64::consts::PI * s).sin() * (std::f64::consts::PI * t).sin();
            pts.push(DVec3::new(x0 + s, t, z));
        }
    }
    BSplineSurface::new(u, v, pts).unwrap()
}

/// A surface part of `s` with the default material.
pub fn surface_part(s: BSplineSurface) -> Part {
    Part::Surface(Design::new(s, SurfaceMaterial::default()).unwrap())
}

/// A curve part through `points` on `knots`.
pub fn curve_part(knots: KnotVector, points: Vec<DVec3>) -> Part {
    Part::Curve(
        CurveDesign::new(
            BSplineCurve::new(knots, points).unwrap(),
            CurveMaterial::default(),
        )
        .unwrap(),
    )
}

/// A point icon spec.
pub fn point(u: f64, v: f64, role: Role) -> IconSpec {
    IconSpec {
        anchor: Anchor::Point { u, v },
        role,
        state: IconState::Passive,
        target: None,
    }
}

/// Every part's control points.
pub fn all_points(p: &Product) -> BTreeMap<PartId, Vec<DVec3>> {
    p.parts()
        .map(|(id, part)| (id, part.control_points().to_vec()))
        .collect()
}

/// The largest coordinate magnitude over every part (the model's size).
pub fn model_size(p: &Product) -> f64 {
    p.parts()
        .flat_map(|(_, part)| part.control_points().iter())
        .fold(0.0f64, |m, q| m.max(q.abs().max_element()))
}

/// The angle between two unit vectors, robust for tiny angles.
pub fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Over `n` points spread along the seam (edge parameters mapped affinely,
/// mirrored if `reversed`): the largest position gap and normal angle.
pub fn seam_gaps(
    a: &BSplineSurface,
    ea: Edge,
    b: &BSplineSurface,
    eb: Edge,
    reversed: bool,
    n: usize,
) -> (f64, f64) {
    let (ka, kb) = (ea.knots(a), eb.knots(b));
    let (a0, a1) = ka.domain();
    let (b0, b1) = kb.domain();
    let mut gap = 0.0f64;
    let mut ang = 0.0f64;
    for k in 0..n {
        // Irrational offsets so no point sits on a knot.
        let s = (k as f64 + 0.5 + 0.1 * std::f64::consts::SQRT_2) / n as f64;
        let s = s.min(1.0);
        let ta = a0 + s * (a1 - a0);
        let sb = if reversed { 1.0 - s } else { s };
        let tb = b0 + sb * (b1 - b0);
        gap = gap.max((ea.point(a, ta) - eb.point(b, tb)).length());
        ang = ang.max(angle(ea.normal(a, ta), eb.normal(b, tb)));
    }
    (gap, ang)
}

/// The dense symmetric matrix of a stiffness.
pub fn dense(k: &Stiffness) -> Vec<Vec<f64>> {
    let n = k.dim();
    let mut a = vec![vec![0.0; n]; n];
    let lower = k.lower();
    let (cp, ri, v) = (
        lower.symbolic().col_ptr(),
        lower.symbolic().row_idx(),
        lower.val(),
    );
    for c in 0..n {
        for e in cp[c]..cp[c + 1] {
            a[ri[e]][c] = v[e];
            a[c][ri[e]] = v[e];
        }
    }
    a
}

/// min Σ (x − r)ᵀ K (x − r) subject to C x = d for one coordinate, by a
/// dense LU of the KKT system (faer, partial pivoting): independent of the
/// kernel's Schur complement, cached columns and shortcuts.
pub fn dense_kkt(k: &[Vec<f64>], rows: &[(Vec<(usize, f64)>, f64)], r: &[f64]) -> Vec<f64> {
    use faer::linalg::solvers::Solve;
    let n = k.len();
    let m = rows.len();
    let mut a = faer::Mat::<f64>::zeros(n + m, n + m);
    for i in 0..n {
        for j in 0..n {
            a[(i, j)] = k[i][j];
        }
    }
    let mut rhs = faer::Mat::<f64>::zeros(n + m, 1);
    // Unknown δ = x − r: K δ + Cᵀλ = 0, C δ = d − C r.
    for (e, (terms, d)) in rows.iter().enumerate() {
        let mut cr = 0.0;
        for &(i, w) in terms {
            a[(n + e, i)] += w;
            a[(i, n + e)] += w;
            cr += w * r[i];
        }
        rhs[(n + e, 0)] = d - cr;
    }
    let x = a.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| r[i] + x[(i, 0)]).collect()
}
