//! Ready-made networks: the bottle of paper 004's third example (six
//! faces, one of them five-sided) and "wheels" (an n-gon ringed by n
//! quadrilaterals) on a quadratic height field, whose curves are exact
//! quadratic Béziers lying on the surface, so every vertex's tangents are
//! coplanar.

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::curve_network::{CurveNetwork, NetworkOptions};
use super::error::NetworkError;
use crate::bspline::{BSplineCurve, KnotVector, interpolate_curve};

/// The bottle's radius at height z: body r = 1 up to z = 1.2, a cosine
/// shoulder to the neck r = 0.4 at z = 2, neck up to z = 2.6.
pub fn bottle_radius(z: f64) -> f64 {
    if z <= 1.2 {
        1.0
    } else if z >= 2.0 {
        0.4
    } else {
        0.4 + 0.3 * (1.0 + (PI * (z - 1.2) / 0.8).cos())
    }
}

/// The bottle surface at (θ, z).
pub fn bottle_point(theta: f64, z: f64) -> DVec3 {
    let r = bottle_radius(z);
    DVec3::new(r * theta.cos(), r * theta.sin(), z)
}

/// The straight (θ, z) segment from `a` to `b` lifted onto the bottle: a
/// cubic B-spline through `intervals + 1` points, chosen so that every
/// meeting point of the bottle's curves is one of them (the curves then
/// meet exactly).
fn lifted(a: DVec2, b: DVec2, intervals: usize) -> BSplineCurve {
    let pts: Vec<DVec3> = (0..=intervals)
        .map(|k| {
            let p = a.lerp(b, k as f64 / intervals as f64);
            bottle_point(p.x, p.y)
        })
        .collect();
    interpolate_curve(&pts, 3).expect("distinct points")
}

/// The front half (θ ∈ [−90°, 90°]) of a bottle: rings at z = 0, 1.2, 2.6,
/// meridians at ±90° (full height) and ±30° (body), and two shoulder
/// diagonals from (±30°, 0.8) to (0°, 1.2). Faces: the five-sided label
/// face, two triangles above it, two side quads and the neck quad (whose
/// lower side passes three T-junctions). Normals face outwards (+x).
pub fn bottle() -> Result<CurveNetwork, NetworkError> {
    let d = |deg: f64| deg.to_radians();
    // Samples every 5° along rings and every 0.05 along meridians.
    let seg = |t0: f64, z0: f64, t1: f64, z1: f64| {
        let k = (((t1 - t0) / 5.0).abs().max(((z1 - z0) / 0.05).abs())).round() as usize;
        lifted(DVec2::new(d(t0), z0), DVec2::new(d(t1), z1), k.max(8))
    };
    let curves = vec![
        seg(-90.0, 0.0, 90.0, 0.0),
        seg(-90.0, 1.2, 90.0, 1.2),
        seg(-90.0, 2.6, 90.0, 2.6),
        seg(-90.0, 0.0, -90.0, 2.6),
        seg(90.0, 0.0, 90.0, 2.6),
        seg(-30.0, 0.0, -30.0, 1.2),
        seg(30.0, 0.0, 30.0, 1.2),
        seg(-30.0, 0.8, 0.0, 1.2),
        seg(30.0, 0.8, 0.0, 1.2),
    ];
    CurveNetwork::new(
        curves,
        NetworkOptions {
            tolerance: 1e-9,
            up: DVec3::X,
        },
    )
}

/// The height field the wheels lie on.
pub fn wheel_height(p: DVec2) -> f64 {
    0.15 * p.x * p.x - 0.1 * p.x * p.y + 0.05 * p.y * p.y + 0.1 * p.x
}

/// The straight segment a→b lifted onto [`wheel_height`]: exactly a
/// quadratic Bézier (the height is quadratic along a line).
pub fn lifted_line(a: DVec2, b: DVec2) -> BSplineCurve {
    let m = (a + b) * 0.5;
    let (za, zb, zm) = (wheel_height(a), wheel_height(b), wheel_height(m));
    let pts = vec![
        a.extend(za),
        m.extend(2.0 * zm - 0.5 * (za + zb)),
        b.extend(zb),
    ];
    BSplineCurve::new(KnotVector::clamped_uniform(2, 3).expect("valid"), pts).expect("finite")
}

/// An `n`-gon of radius 1 ringed by `n` quadrilaterals out to radius 2.2:
/// 3n curves (inner sides, spokes, outer sides), n + 1 faces, the n-gon
/// first among the faces with `n` sides.
pub fn wheel(n: usize) -> Result<CurveNetwork, NetworkError> {
    if n < 3 {
        return Err(NetworkError::BadValue(format!(
            "a wheel needs 3 or more sides, got {n}"
        )));
    }
    let at = |r: f64, k: usize| {
        let a = 2.0 * PI * k as f64 / n as f64 + 0.3;
        DVec2::new(r * a.cos(), r * a.sin())
    };
    let mut curves = Vec::new();
    for k in 0..n {
        curves.push(lifted_line(at(1.0, k), at(1.0, k + 1)));
    }
    for k in 0..n {
        curves.push(lifted_line(at(1.0, k), at(2.2, k)));
    }
    for k in 0..n {
        curves.push(lifted_line(at(2.2, k), at(2.2, k + 1)));
    }
    CurveNetwork::new(curves, NetworkOptions::default())
}
