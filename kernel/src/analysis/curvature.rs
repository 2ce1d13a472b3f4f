//! Curvature of surfaces and curves, computed exactly from derivatives
//! (do Carmo, *Differential Geometry of Curves and Surfaces*, §3.3).
//!
//! Sign convention: the unit normal is n = w_u × w_v / |w_u × w_v|; the
//! second fundamental form is L = w_uu·n, M = w_uv·n, N = w_vv·n; a normal
//! curvature is positive where the surface bends toward n. So a sphere whose
//! parametrisation makes n point inward has H = +1/r and K = 1/r², and with
//! n outward H = −1/r (K is independent of the orientation).

use glam::DVec3;

use crate::bspline::{CurveDerivs, SurfaceDerivs};

/// The curvatures of a surface at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceCurvature {
    /// Mean curvature H = (κ1 + κ2)/2.
    pub mean: f64,
    /// Gaussian curvature K = κ1 κ2.
    pub gauss: f64,
    /// The larger principal curvature.
    pub k1: f64,
    /// The smaller principal curvature.
    pub k2: f64,
    /// Unit principal direction of κ1 (tangent to the surface).
    pub dir1: DVec3,
    /// Unit principal direction of κ2.
    pub dir2: DVec3,
    /// The unit normal n = w_u × w_v / |w_u × w_v|.
    pub normal: DVec3,
}

/// The surface has no tangent plane here (w_u ∥ w_v or zero).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Degenerate;

/// The unit normal, mean and Gaussian curvature at a point — what a
/// tessellation shades with — without the principal directions: the same
/// values as [`surface_curvature`] at a fraction of the cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingCurvature {
    /// The unit normal n = w_u × w_v / |w_u × w_v|.
    pub normal: DVec3,
    /// Mean curvature H.
    pub mean: f64,
    /// Gaussian curvature K.
    pub gauss: f64,
}

/// The first fundamental form (E, F, G), the unit normal and the second
/// fundamental form (L, M, N) at a point, with H and K from them.
struct Forms {
    e: f64,
    f: f64,
    g: f64,
    l: f64,
    m: f64,
    nn: f64,
    shading: ShadingCurvature,
}

#[inline]
fn forms(d: &SurfaceDerivs) -> Result<Forms, Degenerate> {
    let e = d.u.dot(d.u);
    let f = d.u.dot(d.v);
    let g = d.v.dot(d.v);
    let det = e * g - f * f;
    if !det.is_finite() || det <= 1e-24 * (e * g).max(1e-300) {
        return Err(Degenerate);
    }
    // |w_u × w_v|² = EG − F² (Lagrange's identity).
    let n = d.u.cross(d.v) * det.sqrt().recip();
    let (l, m, nn) = (d.uu.dot(n), d.uv.dot(n), d.vv.dot(n));
    let inv = det.recip();
    Ok(Forms {
        e,
        f,
        g,
        l,
        m,
        nn,
        shading: ShadingCurvature {
            normal: n,
            mean: (e * nn - 2.0 * f * m + g * l) * 0.5 * inv,
            gauss: (l * nn - m * m) * inv,
        },
    })
}

/// Normal, mean and Gaussian curvature from the derivatives at a point
/// (first and second fundamental forms; sign convention above).
#[inline]
pub fn shading_curvature(d: &SurfaceDerivs) -> Result<ShadingCurvature, Degenerate> {
    forms(d).map(|f| f.shading)
}

/// Mean, Gaussian and principal curvatures from the derivatives at a point.
pub fn surface_curvature(d: &SurfaceDerivs) -> Result<SurfaceCurvature, Degenerate> {
    let Forms {
        e,
        f,
        g,
        l,
        m,
        nn,
        shading:
            ShadingCurvature {
                normal: n,
                mean,
                gauss,
            },
    } = forms(d)?;
    let disc = (mean * mean - gauss).max(0.0).sqrt();
    let (k1, k2) = (mean + disc, mean - disc);
    // Principal directions: (L − κE) a + (M − κF) b = 0 (or the second row).
    let dir = |k: f64| -> DVec3 {
        let (a1, b1) = (m - k * f, -(l - k * e));
        let (a2, b2) = (nn - k * g, -(m - k * f));
        let (a, b) = if a1.abs() + b1.abs() >= a2.abs() + b2.abs() {
            (a1, b1)
        } else {
            (a2, b2)
        };
        let t = d.u * a + d.v * b;
        t.try_normalize().unwrap_or_else(|| d.u.normalize_or_zero())
    };
    let dir1 = if disc < 1e-12 * (mean.abs() + 1.0) {
        d.u.normalize_or_zero()
    } else {
        dir(k1)
    };
    let dir2 = n.cross(dir1).normalize_or_zero();
    Ok(SurfaceCurvature {
        mean,
        gauss,
        k1,
        k2,
        dir1,
        dir2,
        normal: n,
    })
}

/// The curvature κ = |c' × c''| / |c'|³ of a curve and its principal
/// (Frenet) normal, pointing toward the centre of curvature; κ = 0 and a
/// zero normal where the curve is straight; `Degenerate` where c' = 0.
pub fn curve_curvature(d: &CurveDerivs) -> Result<(f64, DVec3), Degenerate> {
    let speed = d.d1.length();
    if !speed.is_finite() || speed <= 1e-300 {
        return Err(Degenerate);
    }
    let k = d.d1.cross(d.d2).length() / speed.powi(3);
    let t = d.d1 / speed;
    let normal = (d.d2 - t * d.d2.dot(t)).normalize_or_zero();
    Ok((k, normal))
}
