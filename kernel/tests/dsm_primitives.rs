//! Density Spatial Model primitives: analytic gradients and Hessians against
//! central differences of the values, and the level set of a single
//! sphere-based primitive against r = ln(D/D_e)/a.

use glam::{DMat3, DVec2, DVec3};
use vsculpt_kernel::dsm::*;

fn rotation() -> Placement {
    let r = DMat3::from_quat(glam::DQuat::from_axis_angle(
        DVec3::new(1.0, 2.0, -0.5).normalize(),
        0.7,
    ));
    Placement::new(r, DVec3::new(0.3, -0.2, 0.1)).unwrap()
}

/// Checks `jet` against central differences of `value` at p: gradient to `tol` and
/// Hessian (differences of the analytic gradient) to `tol`.
fn check(name: &str, value: impl Fn(DVec3) -> f64, jet: impl Fn(DVec3) -> Jet, p: DVec3, tol: f64) {
    let j = jet(p);
    assert!(
        (j.value - value(p)).abs() <= 1e-14 * (1.0 + j.value.abs()),
        "{name}: value {} vs {} at {p}",
        j.value,
        value(p)
    );
    let h = 1e-5;
    let scale = 1.0 + j.grad.length();
    for i in 0..3 {
        let mut e = DVec3::ZERO;
        e[i] = h;
        let g = (value(p + e) - value(p - e)) / (2.0 * h);
        assert!(
            (g - j.grad[i]).abs() <= tol * scale,
            "{name}: d/dx{i} {} vs {g} at {p}",
            j.grad[i]
        );
        let gg = (jet(p + e).grad - jet(p - e).grad) / (2.0 * h);
        let hs = 1.0 + j.hess.col(i).length();
        for k in 0..3 {
            assert!(
                (gg[k] - j.hess.col(i)[k]).abs() <= tol * hs,
                "{name}: H[{k}][{i}] {} vs {} at {p}",
                j.hess.col(i)[k],
                gg[k]
            );
        }
    }
    // The Hessian is symmetric.
    let hm = j.hess;
    assert!(
        (hm - hm.transpose())
            .to_cols_array()
            .iter()
            .all(|v| v.abs() <= 1e-12 * (1.0 + hm.col(0).length())),
        "{name}: symmetric"
    );
}

fn points() -> Vec<DVec3> {
    vec![
        DVec3::new(0.41, 0.23, 0.17),
        DVec3::new(-0.9, 0.35, 0.52),
        DVec3::new(1.7, -1.1, 0.4),
        DVec3::new(0.2, 0.1, -1.9),
        DVec3::new(-1.3, -0.6, 1.25),
    ]
}

#[test]
fn geometric_gradients_and_hessians_match_differences() {
    let shapes = [
        GeometricShape::Sphere { radius: 1.1 },
        GeometricShape::Ellipsoid {
            semi: DVec3::new(1.3, 0.8, 0.6),
        },
        GeometricShape::Box {
            half: DVec3::new(1.0, 0.7, 0.5),
        },
        GeometricShape::Cylinder {
            radius: 0.9,
            half_height: 0.8,
        },
        GeometricShape::Hyperboloid {
            waist: 0.6,
            c: 0.9,
            half_height: 1.2,
        },
    ];
    for s in shapes {
        let g = GeometricPrimitive::new(s, rotation()).unwrap();
        for p in points() {
            check(&format!("{s:?}"), |x| g.value(x), |x| g.jet(x), p, 2e-6);
        }
    }
}

#[test]
fn geometric_boundary_functions_are_one_lipschitz() {
    // |g(p) − g(q)| ≤ |p − q| on random pairs: the interval culling relies on it.
    let shapes = [
        GeometricShape::Ellipsoid {
            semi: DVec3::new(2.0, 0.5, 1.0),
        },
        GeometricShape::Hyperboloid {
            waist: 0.5,
            c: 0.3,
            half_height: 1.5,
        },
        GeometricShape::Box {
            half: DVec3::new(1.0, 0.7, 0.5),
        },
        GeometricShape::Cylinder {
            radius: 0.9,
            half_height: 0.8,
        },
    ];
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
    };
    for s in shapes {
        let mut worst: f64 = 0.0;
        for _ in 0..5000 {
            let p = DVec3::new(rnd(), rnd(), rnd());
            let q = p + DVec3::new(rnd(), rnd(), rnd()) * 0.05;
            worst = worst.max((s.value(p) - s.value(q)).abs() / (p - q).length());
        }
        assert!(worst <= 1.0 + 1e-9, "{s:?}: Lipschitz {worst}");
    }
}

#[test]
fn geometric_shapes_contain_what_they_should() {
    let b = GeometricPrimitive::new(
        GeometricShape::Box {
            half: DVec3::new(1.0, 2.0, 3.0),
        },
        Placement::at(DVec3::new(5.0, 0.0, 0.0)),
    )
    .unwrap();
    assert!(b.contains(DVec3::new(5.99, 1.99, -2.99)));
    assert!(!b.contains(DVec3::new(6.01, 0.0, 0.0)));
    let h = GeometricShape::Hyperboloid {
        waist: 1.0,
        c: 2.0,
        half_height: 2.0,
    };
    // ρ² = a² (1 + z²/c²): at z = 2, ρ = √2.
    assert!(h.value(DVec3::new(1.41, 0.0, 1.99)) > 0.0);
    assert!(h.value(DVec3::new(1.42, 0.0, 1.99)) < 0.0);
    assert!(h.value(DVec3::new(0.99, 0.0, 0.0)) > 0.0 && h.value(DVec3::new(1.01, 0.0, 0.0)) < 0.0);
    let e = GeometricShape::Ellipsoid {
        semi: DVec3::new(3.0, 2.0, 1.0),
    };
    assert!(e.value(DVec3::new(2.99, 0.0, 0.0)) > 0.0 && e.value(DVec3::new(0.0, 2.01, 0.0)) < 0.0);
    assert!(
        GeometricPrimitive::new(GeometricShape::Sphere { radius: -1.0 }, Placement::IDENTITY)
            .is_err()
    );
}

fn sheet() -> Sheet {
    let charges = vec![
        Charge {
            at: DVec2::new(0.1, 0.2),
            strength: 3.0,
            reducing: 0.8,
        },
        Charge {
            at: DVec2::new(-0.6, 0.4),
            strength: -1.0,
            reducing: 1.5,
        },
        Charge {
            at: DVec2::new(0.7, -0.5),
            strength: 2.0,
            reducing: 0.6,
        },
    ];
    Sheet {
        distribution: Distribution::new(0.5, charges, 1.0, 1e-15).unwrap(),
        lo: DVec2::new(-3.0, -3.0),
        hi: DVec2::new(3.0, 3.0),
        connect: Some(
            Connecting::to_plane(DVec2::new(-3.0, -3.0), DVec2::new(3.0, 3.0), 1.5).unwrap(),
        ),
    }
}

#[test]
fn density_gradients_and_hessians_match_differences() {
    let prims = vec![
        DensityPrimitive::new(DensityShape::Sphere { radius: 0.0 }, rotation(), 2.0, 1.3).unwrap(),
        DensityPrimitive::new(DensityShape::Sphere { radius: 0.4 }, rotation(), -1.5, 0.9).unwrap(),
        DensityPrimitive::new(
            DensityShape::Pipe {
                radius: 0.0,
                half_length: 3.0,
            },
            rotation(),
            1.7,
            1.1,
        )
        .unwrap(),
        DensityPrimitive::new(
            DensityShape::Pipe {
                radius: 0.3,
                half_length: 3.0,
            },
            rotation(),
            1.7,
            1.1,
        )
        .unwrap(),
        DensityPrimitive::new(DensityShape::Blobby, rotation(), 2.5, 0.7).unwrap(),
        DensityPrimitive::new(DensityShape::Plane(Box::new(sheet())), rotation(), 1.0, 1.2)
            .unwrap(),
        DensityPrimitive::new(
            DensityShape::CylinderMap {
                radius: 1.0,
                sheet: Box::new(sheet()),
            },
            rotation(),
            1.0,
            1.2,
        )
        .unwrap(),
    ];
    for d in &prims {
        for p in points() {
            check(
                &format!("{:?}", d.shape)
                    .chars()
                    .take(40)
                    .collect::<String>(),
                |x| d.value(x, f64::INFINITY),
                |x| d.jet(x, f64::INFINITY),
                p,
                2e-6,
            );
        }
    }
}

#[test]
fn sphere_based_primitive_level_set_is_the_predicted_sphere() {
    // F = D exp(−a r) = D_e at r = ln(D / D_e) / a.
    let (d, a, de) = (5.0, 1.7, 1.3);
    let c = DVec3::new(0.2, -0.4, 1.0);
    let mut m = Model::new(de, DEFAULT_TAU).unwrap();
    m.add(Group {
        density: vec![DensityPrimitive::sphere(c, d, a).unwrap()],
        ..Default::default()
    })
    .unwrap();
    let r0 = (d / de).ln() / a;
    for dir in [
        DVec3::X,
        DVec3::new(1.0, 1.0, -1.0).normalize(),
        DVec3::new(-0.3, 0.9, 0.1).normalize(),
    ] {
        assert!(m.group_field(0, c + dir * r0).abs() < 1e-12);
        assert!(m.contains(c + dir * (r0 - 1e-9)));
        assert!(!m.contains(c + dir * (r0 + 1e-9)));
    }
}

#[test]
fn negative_density_and_influence_range_cut_exactly() {
    // Inside a uniform solid (eq. 4: E = Σ F), a negative primitive removes exactly
    // its influence range.
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    let b = GeometricPrimitive::new(
        GeometricShape::Box {
            half: DVec3::splat(2.0),
        },
        Placement::IDENTITY,
    )
    .unwrap();
    let neg = DensityPrimitive::sphere(DVec3::new(2.0, 0.0, 0.0), -3.0, 1.0)
        .unwrap()
        .with_range(0.75)
        .unwrap();
    m.add(Group {
        geometric: vec![b],
        density: vec![neg],
        ..Default::default()
    })
    .unwrap();
    assert!(!m.contains(DVec3::new(1.26, 0.0, 0.0)));
    assert!(m.contains(DVec3::new(1.24, 0.0, 0.0)));
    assert!(m.contains(DVec3::new(0.0, 0.0, 1.99)));
}

/// The mesher's normals take F and ∇F without the Hessian
/// (`DensityPrimitive::value_grad`): against central differences of F, and
/// equal to the jet's value and gradient to rounding, for every shape it
/// differentiates itself (shells, line charges, clipped pipes, blobby, placed
/// and rotated) and outside the support (0).
#[test]
fn density_value_and_gradient_match_differences_and_the_jet() {
    let clip = HalfSpace::new(DVec3::new(1.0, 1.0, 0.0), 0.2).unwrap();
    let prims = [
        DensityPrimitive::new(DensityShape::Sphere { radius: 0.4 }, rotation(), 1.7, 2.0).unwrap(),
        DensityPrimitive::new(DensityShape::Sphere { radius: 0.0 }, rotation(), -0.8, 1.3).unwrap(),
        DensityPrimitive::new(
            DensityShape::Pipe {
                radius: 0.3,
                half_length: 1.2,
            },
            rotation(),
            1.1,
            1.5,
        )
        .unwrap()
        .clipped(clip),
        DensityPrimitive::new(DensityShape::Blobby, rotation(), 2.0, 0.9).unwrap(),
    ];
    for (k, d) in prims.iter().enumerate() {
        let range = 2.5;
        for p in points() {
            let (v, g) = d.value_grad(p, range);
            let j = d.jet(p, range);
            assert!(
                (v - j.value).abs() <= 1e-14 * (1.0 + v.abs()),
                "{k}: value at {p}"
            );
            assert!(
                (g - j.grad).length() <= 1e-13 * (1.0 + g.length()),
                "{k}: grad at {p}"
            );
            assert_eq!(v, d.value(p, range), "{k}: value at {p}");
            let h = 1e-6;
            for i in 0..3 {
                let mut e = DVec3::ZERO;
                e[i] = h;
                let fd = (d.value(p + e, range) - d.value(p - e, range)) / (2.0 * h);
                assert!(
                    (fd - g[i]).abs() <= 1e-6 * (1.0 + g.length()),
                    "{k}: d/dx{i} {} vs {fd} at {p}",
                    g[i]
                );
            }
        }
    }
    // Outside the support: 0 and no gradient.
    let far = DVec3::new(9.0, 0.0, 0.0);
    assert_eq!(prims[0].value_grad(far, 2.5), (0.0, DVec3::ZERO));
}
