//! Adaptive dual contouring ([`mesh_adaptive`]): closed 2-manifold meshes with
//! the right topology, every vertex on the level set, the surface between
//! vertices within the stated tolerance (measured by Newton projection of
//! points inside every triangle onto the level set), and far fewer triangles
//! than the uniform mesher's where the surface is flat.

use glam::DVec3;
use vsculpt_kernel::dsm::*;

#[path = "dsm_support/mod.rs"]
mod dsm_support;
use dsm_support::mesh_checks::{
    assert_box_reproduced, assert_closed_manifold, min_triangle_quality,
};
use dsm_support::{ring_of_charges, sphere_model};

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

/// A group's level set E = 0 (f = D_e) of a model of density primitives
/// alone: value and gradient of f at x.
fn density_field(m: &Model) -> impl Fn(DVec3) -> (f64, DVec3) + '_ {
    move |x| {
        let j = m.density_jet(0, x);
        (j.value, j.grad)
    }
}

/// Every vertex on the level set f = 1 to 1e-6 of `size`, every interior
/// point within `tol` of it (Newton projection); returns the largest interior
/// distance.
fn assert_on_level_set(m: &Model, mesh: &Mesh, size: f64, tol: f64) -> f64 {
    let f = density_field(m);
    for v in &mesh.positions {
        let (val, g) = f(*v);
        let dev = (val - 1.0).abs() / g.length();
        assert!(dev <= 1e-6 * size, "vertex deviation {dev}");
    }
    let mut worst: f64 = 0.0;
    for p in interior_points(mesh) {
        let d = newton_distance(p, 1.0, &f).expect("Newton converges near the surface");
        worst = worst.max(d);
    }
    assert!(
        worst <= tol,
        "interior point {worst} from the surface (tolerance {tol})"
    );
    worst
}

#[test]
fn adaptive_sphere_is_closed_manifold_on_the_level_set_within_tolerance() {
    let (c, d, a) = (DVec3::new(0.3, -0.1, 0.2), 8.0, 1.5);
    let m = sphere_model(c, d, a, 1.0);
    let r0 = d.ln() / a;
    for cells in [40usize, 96] {
        let opts = AdaptiveOptions::new(cells);
        let (mesh, st) = mesh_adaptive(&m, opts).unwrap();
        let h = Grid::for_model(&m, cells).unwrap().h;
        assert_eq!(mesh.euler_characteristic(), 2, "at {cells}");
        assert_closed_manifold(&mesh);
        assert!(min_triangle_quality(&mesh) > 0.01);
        // Coarse leaves where the sphere is flat enough: larger than a cell.
        assert!(st.largest_surface_leaf >= 4, "{st:?}");
        let worst = assert_on_level_set(&m, &mesh, 2.0 * r0, opts.tolerance * h);
        for (v, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(((*v - c).length() - r0).abs() <= 1e-6 * 2.0 * r0);
            assert!(n.dot((*v - c).normalize()) > 1.0 - 1e-9, "normal {n}");
        }
        // The analytic distance agrees with the Newton projection.
        let exact = interior_points(&mesh)
            .iter()
            .map(|p| ((*p - c).length() - r0).abs())
            .fold(0.0, f64::max);
        assert!((exact - worst).abs() <= 1e-9 * r0, "{exact} vs {worst}");
        // Triangles wind outwards.
        for t in &mesh.triangles {
            let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
            assert!((p1 - p0).cross(p2 - p0).dot((p0 + p1 + p2) / 3.0 - c) > 0.0);
        }
        let (uniform, _) = vsculpt_kernel::dsm::mesh(&m, MeshOptions { cells }).unwrap();
        assert!(
            3 * mesh.triangles.len() < uniform.triangles.len(),
            "{} vs uniform {}",
            mesh.triangles.len(),
            uniform.triangles.len()
        );
    }
}

#[test]
fn adaptive_torus_like_group_has_euler_characteristic_zero() {
    // The ring of 16 sphere-based primitives of the uniform mesher's test.
    let m = ring_of_charges();
    for tolerance in [0.25, 0.5] {
        let opts = AdaptiveOptions {
            tolerance,
            ..AdaptiveOptions::new(64)
        };
        let (mesh, st) = mesh_adaptive(&m, opts).unwrap();
        let h = Grid::for_model(&m, 64).unwrap().h;
        assert_eq!(mesh.euler_characteristic(), 0, "tolerance {tolerance}");
        assert_closed_manifold(&mesh);
        assert!(st.coarse_surface_leaves > 0);
        assert_on_level_set(&m, &mesh, 8.0, tolerance * h);
    }
}

#[test]
fn adaptive_twenty_primitive_shapes_stay_within_tolerance_with_far_fewer_triangles() {
    let shapes = dsm_support::twenty_primitive_shapes();
    for (name, m) in &shapes[..2] {
        for tolerance in [0.25, 0.5] {
            let cells = 128;
            let opts = AdaptiveOptions {
                tolerance,
                ..AdaptiveOptions::new(cells)
            };
            let (mesh, st) = mesh_adaptive(m, opts).unwrap();
            let (uniform, _) = vsculpt_kernel::dsm::mesh(m, MeshOptions { cells }).unwrap();
            let grid = Grid::for_model(m, cells).unwrap();
            let tol = tolerance * grid.h;
            assert_eq!(mesh.euler_characteristic(), 2, "{name} at {tolerance}");
            assert_closed_manifold(&mesh);
            assert!(
                5 * mesh.triangles.len() < uniform.triangles.len(),
                "{name}: {} vs uniform {} ({st:?})",
                mesh.triangles.len(),
                uniform.triangles.len()
            );
            if *name == "rounded_box_20" {
                // The box of half extents (1.5, 1, 0.8) rounded to 0.3: the
                // points within 0.3 of the inner box (shape_ops' derivation).
                let (inner, rho) = (DVec3::new(1.2, 0.7, 0.5), 0.3);
                for v in &mesh.positions {
                    let d = rounded_box_distance(*v, inner, rho).abs();
                    assert!(d <= 1e-6 * 3.0, "vertex {v} off the surface by {d}");
                }
                let worst = interior_points(&mesh)
                    .iter()
                    .map(|p| rounded_box_distance(*p, inner, rho).abs())
                    .fold(0.0, f64::max);
                assert!(worst <= tol, "{name}: {worst} > {tol}");
            } else {
                assert_on_level_set(m, &mesh, 4.0, tol);
            }
        }
    }
}

#[test]
fn adaptive_geometric_box_keeps_its_sharp_edges() {
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    let (half, at) = (DVec3::new(1.0, 0.6, 0.4), DVec3::new(0.05, 0.03, 0.01));
    let b = GeometricPrimitive::new(GeometricShape::Box { half }, Placement::at(at)).unwrap();
    m.add(Group {
        geometric: vec![b],
        ..Default::default()
    })
    .unwrap();
    let (mesh, st) = mesh_adaptive(&m, AdaptiveOptions::new(64)).unwrap();
    assert_eq!(mesh.euler_characteristic(), 2);
    assert_closed_manifold(&mesh);
    // Flat faces in coarse leaves, edges and corners in one-cell leaves.
    assert!(
        st.largest_surface_leaf >= 8 && st.fine_surface_leaves > 0,
        "{st:?}"
    );
    assert_box_reproduced(&mesh, &b, at, half);
}

/// Leaves of one cell only: the octree's cell, face and edge procedures must
/// give the uniform mesher's quads — the same quads (as vertex positions, to
/// 1e-4 of a cell, in the same cyclic order, so the same orientation), from
/// independent code. Both meshers emit a quad as two consecutive triangles;
/// which diagonal splits it is compared only through the quad (a square's
/// two diagonals tie, and vertices equal to 1e-12 may break the tie apart).
#[test]
fn one_cell_leaves_give_the_uniform_quads() {
    let shapes = dsm_support::twenty_primitive_shapes();
    for (name, m) in &shapes {
        let cells = 40;
        let opts = AdaptiveOptions {
            max_leaf: 1,
            ..AdaptiveOptions::new(cells)
        };
        let (a, st) = mesh_adaptive(m, opts).unwrap();
        let (u, _) = vsculpt_kernel::dsm::mesh(m, MeshOptions { cells }).unwrap();
        assert_eq!(st.coarse_surface_leaves, 0);
        let h = Grid::for_model(m, cells).unwrap().h;
        let quads = |mesh: &Mesh| {
            let q = |i: u32| {
                let p = mesh.positions[i as usize] / (1e-4 * h);
                (p.x.round() as i64, p.y.round() as i64, p.z.round() as i64)
            };
            assert_eq!(mesh.triangles.len() % 2, 0);
            let mut out: Vec<_> = mesh
                .triangles
                .chunks(2)
                .map(|pair| {
                    let (t1, t2) = (pair[0], pair[1]);
                    // The diagonal: the edge of t1 whose ends are both in t2;
                    // t2's third vertex goes between them.
                    let i = (0..3)
                        .find(|&i| t2.contains(&t1[i]) && t2.contains(&t1[(i + 1) % 3]))
                        .expect("a quad's two triangles share its diagonal");
                    let other = *t2.iter().find(|v| !t1.contains(v)).expect("four vertices");
                    let cycle = [t1[i], other, t1[(i + 1) % 3], t1[(i + 2) % 3]].map(q);
                    let r = (0..4).min_by_key(|&k| cycle[k]).unwrap();
                    [0, 1, 2, 3].map(|k| cycle[(r + k) % 4])
                })
                .collect();
            out.sort();
            out
        };
        assert_eq!(a.positions.len(), u.positions.len(), "{name}");
        assert!(quads(&a) == quads(&u), "{name}: quads differ");
    }
}

#[test]
fn bad_adaptive_requests_are_refused() {
    let m = sphere_model(DVec3::ZERO, 2.0, 1.0, 1.0);
    let ok = AdaptiveOptions::new(32);
    assert!(mesh_adaptive(&m, ok).is_ok());
    for bad in [
        AdaptiveOptions {
            tolerance: 0.0,
            ..ok
        },
        AdaptiveOptions {
            tolerance: f64::NAN,
            ..ok
        },
        AdaptiveOptions { max_leaf: 12, ..ok },
        AdaptiveOptions {
            max_leaf: 128,
            ..ok
        },
        AdaptiveOptions { cells: 2, ..ok },
    ] {
        assert!(mesh_adaptive(&m, bad).is_err(), "{bad:?}");
    }
    let empty = Model::new(1.0, DEFAULT_TAU).unwrap();
    assert!(mesh_adaptive(&empty, ok).is_err());
}
