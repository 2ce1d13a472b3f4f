//! Shape operations of paper §4: round corners with the radius the primitives
//! predict, the literal negative-pipe cove, smooth blending of disjoint primitives
//! through a plane-based primitive with a non-uniform reducing factor, and shape
//! mapping of an equal density surface onto a box face and a cylinder.

use glam::{DMat3, DQuat, DVec2, DVec3};
use vsculpt_kernel::dsm::shape_ops::{map_onto_box_top, map_onto_cylinder, rounded_box};
use vsculpt_kernel::dsm::*;

/// Signed distance of the box of half extents `half` rounded by `r` (negative inside).
fn rounded_box_sdf(q: DVec3, half: DVec3, r: f64) -> f64 {
    let d = q.abs() - (half - DVec3::splat(r));
    d.max(DVec3::ZERO).length() + d.max_element().min(0.0) - r
}

fn placed() -> Placement {
    Placement::new(
        DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.5)),
        DVec3::new(0.4, 0.1, -0.3),
    )
    .unwrap()
}

#[test]
fn round_corners_have_the_predicted_radius() {
    let (half, rho) = (DVec3::new(1.5, 1.0, 0.8), 0.3);
    let pl = placed();
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    m.add(rounded_box(half, pl, rho, 1.0).unwrap()).unwrap();
    // Exact membership: points just inside / outside the rounded box, on edges,
    // vertices and faces.
    let dirs = [
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, -1.0, 1.0),
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(1.0, -1.0, 1.0),
        DVec3::new(-1.0, 1.0, 1.0),
        DVec3::new(0.3, 0.0, 1.0),
        DVec3::new(2.0, 0.1, 0.05),
    ];
    for d in dirs {
        // Walk from the centre along d to the rounded surface (bisection on the analytic SDF).
        let (mut a, mut b) = (0.0, 5.0);
        for _ in 0..200 {
            let t = 0.5 * (a + b);
            if rounded_box_sdf(d.normalize() * t, half, rho) < 0.0 {
                a = t
            } else {
                b = t
            }
        }
        let q = d.normalize() * a;
        assert!(
            m.contains(pl.to_world(q * (1.0 - 1e-9))),
            "inside along {d}"
        );
        assert!(
            !m.contains(pl.to_world(q * (1.0 + 1e-9))),
            "outside along {d}"
        );
    }
    // The mesh: a closed sphere-topology surface on the rounded box.
    let (mesh, _) = mesh(&m, MeshOptions { cells: 48 }).unwrap();
    assert_eq!(mesh.euler_characteristic(), 2);
    let h = 2.0 * half.length() / 48.0;
    let worst = mesh
        .positions
        .iter()
        .map(|v| rounded_box_sdf(pl.to_local(*v), half, rho).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-3 * h,
        "mesh off the rounded box by {worst} (cell {h})"
    );
}

#[test]
fn round_radius_needs_the_influence_to_cover_the_wedge() {
    // With range < (√2 − 1) ρ the edge wedge's far corner survives: a sharp ridge
    // remains at distance ρ + range from the pipe's axis.
    let (half, rho) = (DVec3::splat(1.0), 0.4);
    let mut g = rounded_box(half, Placement::IDENTITY, rho, 1.0).unwrap();
    for p in &mut g.density {
        p.range = 0.1;
    }
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    m.add(g).unwrap();
    // The edge corner region (x, y near 1, z = 0): distance from axis (0.6, 0.6) is
    // 0.4√2 ≈ 0.566 > ρ + 0.1 = 0.5, so it is kept.
    assert!(m.contains(DVec3::new(0.999, 0.999, 0.0)));
    // Between ρ and ρ + range it is removed.
    let p = DVec3::new(0.6, 0.6, 0.0) + DVec3::new(1.0, 1.0, 0.0).normalize() * 0.45;
    assert!(!m.contains(p));
}

#[test]
fn literal_negative_pipe_on_an_edge_cuts_a_cove_of_its_influence_range() {
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    let b = GeometricPrimitive::new(
        GeometricShape::Box {
            half: DVec3::splat(1.0),
        },
        Placement::IDENTITY,
    )
    .unwrap();
    let cove = 0.35;
    let pipe = DensityPrimitive::pipe(
        DVec3::new(1.0, 1.0, -1.5),
        DVec3::new(1.0, 1.0, 1.5),
        -2.0,
        3.0,
    )
    .unwrap()
    .with_range(cove)
    .unwrap();
    m.add(Group {
        geometric: vec![b],
        density: vec![pipe],
        ..Default::default()
    })
    .unwrap();
    let e = DVec3::new(1.0, 1.0, 0.2);
    let dir = DVec3::new(-1.0, -1.0, 0.0).normalize();
    assert!(!m.contains(e + dir * (cove - 1e-9)));
    assert!(m.contains(e + dir * (cove + 1e-9)));
    // The cove is concave: the points on the faces next to the edge are removed too.
    assert!(!m.contains(DVec3::new(1.0 - 1e-6, 1.0 - cove + 1e-6, 0.0)));
}

#[test]
fn plane_primitive_with_non_uniform_reducing_factor_blends_two_boxes() {
    // Two disjoint boxes |z| ≤ H; a plane-based primitive of uniform D with
    // h = s(u) ln(D/D_e)/a, s = 1 over the boxes and s_mid between them (Fig. 9).
    let (hgt, a, s_mid): (f64, f64, f64) = (0.8, 2.0, 0.5);
    let de = 1.0;
    let d = de * (a * hgt).exp();
    let mut boxes = Vec::new();
    for x in [-2.0, 2.0] {
        boxes.push(
            GeometricPrimitive::new(
                GeometricShape::Box {
                    half: DVec3::new(1.0, 1.0, hgt),
                },
                Placement::at(DVec3::new(x, 0.0, 0.0)),
            )
            .unwrap(),
        );
    }
    let separate = {
        let mut m = Model::new(de, DEFAULT_TAU).unwrap();
        m.add(Group {
            geometric: boxes.clone(),
            ..Default::default()
        })
        .unwrap();
        mesh(&m, MeshOptions { cells: 40 }).unwrap().0
    };
    assert_eq!(separate.euler_characteristic(), 4, "two spheres");
    let profile = Profile::new(vec![(-1.0, 1.0), (0.0, s_mid), (1.0, 1.0)]).unwrap();
    let sheet = Sheet {
        distribution: Distribution::uniform(d).unwrap(),
        lo: DVec2::new(-3.0, -1.0),
        hi: DVec2::new(3.0, 1.0),
        connect: Some(Connecting::new(profile, Profile::one()).unwrap()),
    };
    let bridge = DensityPrimitive::plane(sheet, Placement::IDENTITY, a).unwrap();
    let mut m = Model::new(de, DEFAULT_TAU).unwrap();
    m.add(Group {
        geometric: boxes,
        density: vec![bridge.clone()],
        ..Default::default()
    })
    .unwrap();
    // The bridge top: h(0) = s_mid H; at the boxes' inner faces h = H with zero slope.
    for (x, h) in [
        (0.0, s_mid * hgt),
        (0.5, hgt * (s_mid + (1.0 - s_mid) * 0.5)),
        (1.0, hgt),
    ] {
        assert!(
            m.contains(DVec3::new(x, 0.3, h - 1e-9)) && !m.contains(DVec3::new(x, 0.3, h + 1e-9)),
            "top at x = {x}"
        );
    }
    let j = bridge.jet(DVec3::new(1.0, 0.0, hgt), f64::INFINITY);
    assert!(
        j.grad.x.abs() < 1e-12 * j.grad.length(),
        "the bridge meets the box top with zero slope"
    );
    let (joined, _) = mesh(&m, MeshOptions { cells: 60 }).unwrap();
    assert_eq!(joined.euler_characteristic(), 2, "one closed surface");
}

fn relief() -> EqualDensitySurface {
    let n = 6;
    let heights: Vec<f64> = (0..n * n)
        .map(|k| 0.2 + 0.1 * ((k % n) as f64 * 0.9).sin() * ((k / n) as f64 * 0.7).cos().abs())
        .collect();
    let net = PassingPointsNet::regular(DVec2::new(-1.0, -1.0), DVec2::splat(0.4), n, n, &heights)
        .unwrap();
    inverse_transform(&net, &InverseOptions::for_net(&net, 3.0))
        .unwrap()
        .0
}

#[test]
fn shape_mapping_onto_a_box_face_and_a_cylinder() {
    let s = relief();
    let (lo, hi) = (DVec2::new(-1.0, -1.0), DVec2::new(1.0, 1.0));
    // Box top.
    let half = DVec3::new(1.2, 1.2, 0.5);
    let pl = placed();
    let bx = GeometricPrimitive::new(GeometricShape::Box { half }, pl).unwrap();
    let top = map_onto_box_top(&s, lo, hi, half, pl).unwrap();
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    m.add(Group {
        geometric: vec![bx],
        density: vec![top],
        ..Default::default()
    })
    .unwrap();
    for uv in [
        DVec2::new(-0.4, 0.2),
        DVec2::new(0.3, -0.5),
        DVec2::new(0.1, 0.1),
    ] {
        let h = s.height(uv).unwrap();
        assert!(h > 0.0);
        let at = |z: f64| pl.to_world(DVec3::new(uv.x, uv.y, half.z + z));
        assert!(
            m.contains(at(h - 1e-9)) && !m.contains(at(h + 1e-9)),
            "box relief at {uv}"
        );
    }
    // Cylinder: u = R θ, v = z, relief radial.
    let radius = 1.0;
    let cyl = GeometricPrimitive::new(
        GeometricShape::Cylinder {
            radius,
            half_height: 1.2,
        },
        pl,
    )
    .unwrap();
    let mapped = map_onto_cylinder(&s, lo, hi, radius, pl).unwrap();
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    m.add(Group {
        geometric: vec![cyl],
        density: vec![mapped],
        ..Default::default()
    })
    .unwrap();
    for uv in [
        DVec2::new(-0.4, 0.2),
        DVec2::new(0.3, -0.5),
        DVec2::new(0.7, 0.6),
    ] {
        let h = s.height(uv).unwrap();
        let th = uv.x / radius;
        let at = |rho: f64| pl.to_world(DVec3::new(rho * th.cos(), rho * th.sin(), uv.y));
        assert!(
            m.contains(at(radius + h - 1e-9)) && !m.contains(at(radius + h + 1e-9)),
            "cylinder relief at {uv}"
        );
    }
    // Away from the mapped patch the cylinder is unchanged.
    let th = 2.5f64;
    assert!(m.contains(pl.to_world(DVec3::new(0.999 * th.cos(), 0.999 * th.sin(), 0.0))));
    assert!(!m.contains(pl.to_world(DVec3::new(1.001 * th.cos(), 1.001 * th.sin(), 0.0))));
    let (mesh, _) = mesh(&m, MeshOptions { cells: 48 }).unwrap();
    assert_eq!(mesh.euler_characteristic(), 2);
}
