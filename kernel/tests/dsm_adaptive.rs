//! Adaptive dual contouring ([`mesh_adaptive`]): closed 2-manifold meshes with
//! the right topology, every vertex on the level set, the surface between
//! vertices within the stated tolerance (measured by Newton projection of
//! points inside every triangle onto the level set), and far fewer triangles
//! than the uniform mesher's where the surface is flat.

use glam::DVec3;
use vsculpt_kernel::dsm::*;

#[path = "dsm_support/mod.rs"]
mod dsm_support;
use dsm_support::mesh_checks::{assert_closed_manifold, min_triangle_quality};

/// The distance from p to the level set f = c of a smooth field (value and
/// gradient), by Newton steps along the gradient until the step is below
/// 1e-13; None if it does not converge in 50 steps.
fn newton_distance(p: DVec3, c: f64, f: impl Fn(DVec3) -> (f64, DVec3)) -> Option<f64> {
    let mut x = p;
    for _ in 0..50 {
        let (v, g) = f(x);
        let step = (v - c) / g.length_squared() * g;
        x -= step;
        if step.length() < 1e-13 {
            return Some((x - p).length());
        }
    }
    None
}

/// Points inside every triangle: the centroid, the edge midpoints and the
/// points halfway from the centroid to each vertex.
fn interior_points(m: &Mesh) -> Vec<DVec3> {
    let mut out = Vec::new();
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let g = (a + b + c) / 3.0;
        out.extend([g, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)]);
        out.extend([a, b, c].map(|v| 0.5 * (g + v)));
    }
    out
}

/// Signed distance to a box of half extents `inner` rounded by `rho` (the
/// rounded box of `shape_ops::rounded_box`: the points within rho of the
/// inner box).
fn rounded_box_distance(p: DVec3, inner: DVec3, rho: f64) -> f64 {
    let q = p.abs() - inner;
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0) - rho
}

#[test]
fn explore() {
    for (name, m) in dsm_support::twenty_primitive_shapes() {
        for cells in [64usize, 128, 256] {
            let mut opts = AdaptiveOptions::new(cells);
            if let Ok(t) = std::env::var("ADAPT_TOL") {
                opts.tolerance = t.parse().unwrap();
            }
            if let Ok(t) = std::env::var("ADAPT_MAX") {
                opts.max_leaf = t.parse().unwrap();
            }
            let t = std::time::Instant::now();
            let (am, st) = mesh_adaptive(&m, opts).unwrap();
            let ta = t.elapsed();
            let grid = Grid::for_model(&m, cells).unwrap();
            let h = grid.h;
            let dev = match name {
                "rounded_box_20" => interior_points(&am)
                    .iter()
                    .map(|&p| rounded_box_distance(p, DVec3::new(1.2, 0.7, 0.5), 0.3).abs())
                    .fold(0.0, f64::max),
                "blobby_20" => interior_points(&am)
                    .iter()
                    .map(|&p| {
                        newton_distance(p, 1.0, |x| {
                            let j = m.density_jet(0, x);
                            (j.value, j.grad)
                        })
                        .unwrap()
                    })
                    .fold(0.0, f64::max),
                _ => f64::NAN,
            };
            println!(
                "{name} {cells}: adaptive {} tris {:?} {st:?} chi {} dev/h {:.3} q {:.3}",
                am.triangles.len(),
                ta,
                am.euler_characteristic(),
                dev / h,
                min_triangle_quality(&am)
            );
            assert_closed_manifold(&am);
        }
    }
}
