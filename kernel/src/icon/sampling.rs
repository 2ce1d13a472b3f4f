//! Where an icon touches the surface: the (u,v) sample points of its anchor.
//!
//! A point anchor is one sample. A curve is sampled uniformly in its own
//! parameter with one sample per two surface knot spans it crosses, plus one
//! (at least 2, at most 48): enough to pin the curve between samples to a
//! small fraction of the deformation, and few enough that the samples stay
//! independent. Denser samples make S nearly singular: on the paper's
//! 81 × 159 surface a curve across 47 spans sampled once per span gave an
//! equilibrated S of condition ~1e15, 15 dropped directions and a curve held
//! only to 1e-6; once per two spans gives ~3e10, none dropped, held to
//! 1e-12 (`tests/design.rs`). A region is sampled on a grid of one sample per
//! knot span (at most 8 × 8 inside; outside, a 12 × 12 grid over the whole
//! domain minus the rectangle). Samples carry equal weights summing to one.

use super::Anchor;
use crate::bspline::BSplineSurface;

/// Why an anchor cannot be placed on a surface.
#[derive(Clone, Debug, PartialEq)]
pub enum AnchorError {
    /// A parameter is NaN, infinite or outside the surface's domain.
    OutOfDomain(f64, f64),
    /// A region with no area, or a curve of no length.
    Degenerate(&'static str),
}

fn inside(s: &BSplineSurface, u: f64, v: f64) -> Result<(), AnchorError> {
    if s.contains(u, v) {
        Ok(())
    } else {
        Err(AnchorError::OutOfDomain(u, v))
    }
}

/// Typical knot-span size of the surface along u and v.
fn span_size(s: &BSplineSurface) -> (f64, f64) {
    let ((u0, u1), (v0, v1)) = s.domain();
    let nu = s.u_knots().spans().len().max(1) as f64;
    let nv = s.v_knots().spans().len().max(1) as f64;
    ((u1 - u0) / nu, (v1 - v0) / nv)
}

fn count(extent: f64, span: f64, max: usize) -> usize {
    ((extent / span).ceil() as usize + 1).clamp(2, max)
}

/// The (u,v) samples of `anchor` on `surface`, or why it does not fit.
pub fn samples(anchor: &Anchor, surface: &BSplineSurface) -> Result<Vec<(f64, f64)>, AnchorError> {
    match anchor {
        Anchor::Point { u, v } => {
            inside(surface, *u, *v)?;
            Ok(vec![(*u, *v)])
        }
        Anchor::Curve(curve) => {
            // The curve lies in the convex hull of its control points.
            for p in curve.points() {
                inside(surface, p.x, p.y)?;
            }
            let (du, dv) = span_size(surface);
            let mut uv_len = 0.0;
            let (t0, t1) = curve.domain();
            let mut prev = curve.point(t0);
            for k in 1..=64 {
                let p = curve.point(t0 + (t1 - t0) * k as f64 / 64.0);
                uv_len += (((p.x - prev.x) / du).powi(2) + ((p.y - prev.y) / dv).powi(2)).sqrt();
                prev = p;
            }
            if uv_len < 1e-9 {
                return Err(AnchorError::Degenerate("curve has no length in (u,v)"));
            }
            let n = count(uv_len, 2.0, 48);
            let ((u0, u1), (v0, v1)) = surface.domain();
            Ok((0..n)
                .map(|k| {
                    let p = curve.point(t0 + (t1 - t0) * k as f64 / (n - 1) as f64);
                    (p.x.clamp(u0, u1), p.y.clamp(v0, v1))
                })
                .collect())
        }
        Anchor::Region {
            u0,
            v0,
            u1,
            v1,
            inside: within,
        } => {
            inside(surface, *u0, *v0)?;
            inside(surface, *u1, *v1)?;
            let (a0, a1) = (u0.min(*u1), u0.max(*u1));
            let (b0, b1) = (v0.min(*v1), v0.max(*v1));
            if a1 - a0 < 1e-9 || b1 - b0 < 1e-9 {
                return Err(AnchorError::Degenerate("region has no area"));
            }
            let (du, dv) = span_size(surface);
            if *within {
                let nu = count(a1 - a0, du, 8);
                let nv = count(b1 - b0, dv, 8);
                let mut out = Vec::with_capacity(nu * nv);
                for i in 0..nu {
                    for j in 0..nv {
                        let u = a0 + (a1 - a0) * i as f64 / (nu - 1) as f64;
                        let v = b0 + (b1 - b0) * j as f64 / (nv - 1) as f64;
                        out.push((u, v));
                    }
                }
                Ok(out)
            } else {
                let ((s0, s1), (t0, t1)) = surface.domain();
                let (nu, nv) = (12, 12);
                let mut out = Vec::new();
                for i in 0..nu {
                    for j in 0..nv {
                        let u = s0 + (s1 - s0) * (i as f64 + 0.5) / nu as f64;
                        let v = t0 + (t1 - t0) * (j as f64 + 0.5) / nv as f64;
                        if !(u >= a0 && u <= a1 && v >= b0 && v <= b1) {
                            out.push((u, v));
                        }
                    }
                }
                if out.is_empty() {
                    return Err(AnchorError::Degenerate("region covers the whole surface"));
                }
                Ok(out)
            }
        }
    }
}
