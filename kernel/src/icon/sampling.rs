//! Where an icon touches the surface: the (u,v) sample points of its anchor.
//!
//! A point anchor is one sample. A curve is sampled at its collocation
//! points (per piece where w∘c is one polynomial, as many as determine it:
//! `collocation`), reduced to its identity ([`super::curve_identity`]):
//! the independent samples plus translation-free rows for the rest, so a
//! constraint on them holds the whole curve.
//!
//! Regions and edges are held exactly, by control points ([`held_points`]):
//! their samples are the Greville points of the control points they hold,
//! in the same order.

use glam::DVec3;

use super::{Anchor, Edge, Identity, Role, curve_identity};
use crate::bspline::{BSplineCurve, BSplineSurface, KnotVector, greville};
use crate::quadrature::GaussLegendre;
use crate::solve::ScalarRow;

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

/// Indices of the basis functions of `kv` whose support (t_i, t_{i+p+1})
/// meets the open interval (a, b).
fn meeting(kv: &KnotVector, a: f64, b: f64) -> Vec<usize> {
    let (t, p) = (kv.knots(), kv.degree());
    (0..kv.num_ctrl())
        .filter(|&i| t[i] < b && t[i + p + 1] > a)
        .collect()
}

/// Indices of the basis functions of `kv` whose support lies in [a, b].
fn within(kv: &KnotVector, a: f64, b: f64) -> Vec<bool> {
    let (t, p) = (kv.knots(), kv.degree());
    (0..kv.num_ctrl())
        .map(|i| t[i] >= a && t[i + p + 1] <= b)
        .collect()
}

/// The control points a position constraint on `anchor` holds, when it
/// holds control points rather than samples: a region (inside: every point
/// whose support meets the rectangle; outside: every point whose support
/// meets its complement) or an edge (its row, and the next one when
/// clamped). B-splines are locally linearly independent, so holding the
/// surface on an open set is exactly holding these points. `None` for
/// point and curve anchors.
pub fn held_points(anchor: &Anchor, surface: &BSplineSurface) -> Option<Vec<usize>> {
    let (ku, kv) = (surface.u_knots(), surface.v_knots());
    let (nu, nv) = (surface.nu(), surface.nv());
    match anchor {
        Anchor::Point { .. } | Anchor::Curve(_) => None,
        Anchor::Region {
            u0,
            v0,
            u1,
            v1,
            inside,
        } => {
            let (a0, a1) = (u0.min(*u1), u0.max(*u1));
            let (b0, b1) = (v0.min(*v1), v0.max(*v1));
            let mut out = Vec::new();
            if *inside {
                let iv = meeting(kv, b0, b1);
                for i in meeting(ku, a0, a1) {
                    out.extend(iv.iter().map(|&j| surface.index(i, j)));
                }
            } else {
                let (wu, wv) = (within(ku, a0, a1), within(kv, b0, b1));
                for (i, &in_u) in wu.iter().enumerate() {
                    for (j, &in_v) in wv.iter().enumerate() {
                        if !(in_u && in_v) {
                            out.push(surface.index(i, j));
                        }
                    }
                }
            }
            Some(out)
        }
        Anchor::Edge { edge, clamped } => {
            let rows = if *clamped { 2 } else { 1 };
            let mut out = Vec::new();
            for r in 0..rows {
                match edge {
                    Edge::UMin => out.extend((0..nv).map(|j| surface.index(r, j))),
                    Edge::UMax => out.extend((0..nv).map(|j| surface.index(nu - 1 - r, j))),
                    Edge::VMin => out.extend((0..nu).map(|i| surface.index(i, r))),
                    Edge::VMax => out.extend((0..nu).map(|i| surface.index(i, nv - 1 - r))),
                }
            }
            Some(out)
        }
    }
}

/// What a new or re-captured icon holds on `surface` at its `samples`: the
/// surface points there, or for an icon that holds control points
/// ([`held_points`], position constraints only) the control points. A
/// curve's position constraint also holds the values of its identity's
/// translation-free `rows` ([`Identity`]), after the samples' points.
pub fn capture(
    anchor: &Anchor,
    role: Role,
    samples: &[(f64, f64)],
    rows: &[ScalarRow],
    surface: &BSplineSurface,
) -> Vec<DVec3> {
    match held_points(anchor, surface).filter(|_| role == Role::Position) {
        Some(points) => points.iter().map(|&c| surface.points()[c]).collect(),
        None => {
            let mut out: Vec<DVec3> = samples.iter().map(|&(u, v)| surface.point(u, v)).collect();
            if role == Role::Position {
                out.extend(rows.iter().map(|r| r.apply(surface.points())));
            }
            out
        }
    }
}

/// The collocation points of a curve on a surface: on every piece where
/// w∘c is one polynomial (a curve span, cut where u(t) or v(t) crosses a
/// surface knot line), q·(p_u + p_v) + 1 Gauss–Legendre points — enough to
/// determine that polynomial.
fn collocation(curve: &BSplineCurve, surface: &BSplineSurface) -> Vec<(f64, f64)> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let (ku, kv) = (surface.u_knots(), surface.v_knots());
    let degree = curve.degree() * (ku.degree() + kv.degree());
    let rule = GaussLegendre::new(degree + 1);
    let lines = |kv: &KnotVector| -> Vec<f64> {
        let (a, b) = kv.domain();
        let mut k: Vec<f64> = kv
            .knots()
            .iter()
            .copied()
            .filter(|&x| x > a && x < b)
            .collect();
        k.dedup();
        k
    };
    let (lu, lv) = (lines(ku), lines(kv));
    let mut out = Vec::new();
    for (_, t0, t1) in curve.knots().spans() {
        let mut cuts = vec![t0, t1];
        let steps = 64;
        for (coord, lines) in [(0usize, &lu), (1, &lv)] {
            let at = |t: f64| curve.point(t)[coord];
            for &line in lines.iter() {
                for k in 0..steps {
                    let (mut a, mut b) = (
                        t0 + (t1 - t0) * k as f64 / steps as f64,
                        t0 + (t1 - t0) * (k + 1) as f64 / steps as f64,
                    );
                    let (fa, fb) = (at(a) - line, at(b) - line);
                    if fa == 0.0 || fa * fb >= 0.0 {
                        continue;
                    }
                    for _ in 0..80 {
                        let m = 0.5 * (a + b);
                        if (at(m) - line) * fa > 0.0 {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    cuts.push(0.5 * (a + b));
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() <= 1e-14 * (t1 - t0));
        for w in cuts.windows(2) {
            for (t, _) in rule.on(w[0], w[1]) {
                let p = curve.point(t);
                out.push((p.x.clamp(u0, u1), p.y.clamp(v0, v1)));
            }
        }
    }
    out
}

/// The (u,v) samples of `anchor` on `surface`, or why it does not fit.
pub fn samples(anchor: &Anchor, surface: &BSplineSurface) -> Result<Vec<(f64, f64)>, AnchorError> {
    placement(anchor, surface).map(|p| p.samples)
}

/// Where `anchor` touches `surface`: its samples and, for a curve, the
/// translation-free rows completing its identity ([`Identity`]); or why it
/// does not fit.
pub fn placement(anchor: &Anchor, surface: &BSplineSurface) -> Result<Identity, AnchorError> {
    let points = |samples: Vec<(f64, f64)>| Identity {
        samples,
        rows: Vec::new(),
    };
    match anchor {
        Anchor::Edge { .. } => {
            if surface.domain() != ((0.0, 1.0), (0.0, 1.0)) {
                return Err(AnchorError::Degenerate(
                    "edge icons need the unit parameter domain",
                ));
            }
            let (gu, gv) = (greville(surface.u_knots()), greville(surface.v_knots()));
            let nv = surface.nv();
            Ok(points(
                held_points(anchor, surface)
                    .unwrap_or_default()
                    .iter()
                    .map(|&c| (gu[c / nv], gv[c % nv]))
                    .collect(),
            ))
        }
        Anchor::Point { u, v } => {
            inside(surface, *u, *v)?;
            Ok(points(vec![(*u, *v)]))
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
            Ok(curve_identity(
                &collocation(curve, surface),
                anchor.handle_uv(),
                surface,
            ))
        }
        Anchor::Region {
            u0,
            v0,
            u1,
            v1,
            inside: _,
        } => {
            inside(surface, *u0, *v0)?;
            inside(surface, *u1, *v1)?;
            let (a0, a1) = (u0.min(*u1), u0.max(*u1));
            let (b0, b1) = (v0.min(*v1), v0.max(*v1));
            if a1 - a0 < 1e-9 || b1 - b0 < 1e-9 {
                return Err(AnchorError::Degenerate("region has no area"));
            }
            let (gu, gv) = (greville(surface.u_knots()), greville(surface.v_knots()));
            let nv = surface.nv();
            let out: Vec<(f64, f64)> = held_points(anchor, surface)
                .unwrap_or_default()
                .iter()
                .map(|&c| (gu[c / nv], gv[c % nv]))
                .collect();
            if out.is_empty() {
                return Err(AnchorError::Degenerate("region covers the whole surface"));
            }
            Ok(points(out))
        }
    }
}
