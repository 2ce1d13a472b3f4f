//! Coons bodies 0, 1, 2: boundary reproduction against the input curves and
//! faces, the reductions body 2 → body 1 → body 0, and the exact B-spline
//! volume conversion against direct evaluation of the Boolean sum.

// Corner and face indices are those of the paper's formulas.
#![allow(clippy::needless_range_loop)]

use glam::DVec3;
use vsculpt_kernel::body::elevate::elevate_surface;
use vsculpt_kernel::body::refine::refine_surface;
use vsculpt_kernel::body::{BSplineVolume, Body0, Body1, Body2, BodyError, Dir, Edges, Face};
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
mod body_support;
use body_support::Rng;

/// Independent trilinear formula: nested linear interpolation.
fn lerp3(c: &[[[DVec3; 2]; 2]; 2], u: f64, v: f64, w: f64) -> DVec3 {
    let l = |a: DVec3, b: DVec3, t: f64| a + (b - a) * t;
    let x = |i: usize| {
        l(
            l(c[i][0][0], c[i][0][1], w),
            l(c[i][1][0], c[i][1][1], w),
            v,
        )
    };
    l(x(0), x(1), u)
}

fn random_corners(rng: &mut Rng) -> [[[DVec3; 2]; 2]; 2] {
    let mut c = [[[DVec3::ZERO; 2]; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            for k in 0..2 {
                c[i][j][k] = DVec3::new(i as f64, j as f64, k as f64) * 2.0 + rng.vec(0.6);
            }
        }
    }
    c
}

/// A curve from `a` to `b` over the domain [t0, t1] with wiggly interior
/// control points.
fn edge(
    rng: &mut Rng,
    a: DVec3,
    b: DVec3,
    degree: usize,
    n: usize,
    t0: f64,
    t1: f64,
) -> BSplineCurve {
    let kv = KnotVector::clamped_uniform(degree, n).unwrap();
    let knots: Vec<f64> = kv.knots().iter().map(|k| t0 + (t1 - t0) * k).collect();
    let kv = KnotVector::new(degree, knots).unwrap();
    let pts = (0..n)
        .map(|r| {
            let s = r as f64 / (n - 1) as f64;
            if r == 0 {
                a
            } else if r == n - 1 {
                b
            } else {
                a + (b - a) * s + rng.vec(0.5)
            }
        })
        .collect();
    BSplineCurve::new(kv, pts).unwrap()
}

fn at(c: &BSplineCurve, s: f64) -> DVec3 {
    let (a, b) = c.domain();
    c.point(a + (b - a) * s)
}

fn random_edges(rng: &mut Rng, c: &[[[DVec3; 2]; 2]; 2]) -> Edges {
    let mut mk =
        |p: DVec3, q: DVec3, deg: usize, n: usize, t1: f64| edge(rng, p, q, deg, n, 0.0, t1);
    Edges {
        u: [
            [
                mk(c[0][0][0], c[1][0][0], 3, 5, 1.0),
                mk(c[0][0][1], c[1][0][1], 2, 4, 2.0),
            ],
            [
                mk(c[0][1][0], c[1][1][0], 3, 6, 1.0),
                mk(c[0][1][1], c[1][1][1], 1, 3, 3.0),
            ],
        ],
        v: [
            [
                mk(c[0][0][0], c[0][1][0], 2, 3, 1.0),
                mk(c[0][0][1], c[0][1][1], 2, 5, 1.0),
            ],
            [
                mk(c[1][0][0], c[1][1][0], 3, 4, 0.5),
                mk(c[1][0][1], c[1][1][1], 2, 4, 1.0),
            ],
        ],
        w: [
            [
                mk(c[0][0][0], c[0][0][1], 3, 7, 1.0),
                mk(c[0][1][0], c[0][1][1], 3, 4, 1.0),
            ],
            [
                mk(c[1][0][0], c[1][0][1], 2, 5, 1.0),
                mk(c[1][1][0], c[1][1][1], 3, 5, 4.0),
            ],
        ],
    }
}

#[test]
fn body0_reproduces_its_vertices_and_is_trilinear() {
    let mut rng = Rng(1);
    let c = random_corners(&mut rng);
    let b = Body0 { corners: c };
    let vol = b.to_volume().unwrap();
    for i in 0..2 {
        for j in 0..2 {
            for k in 0..2 {
                let t = [i as f64, j as f64, k as f64];
                assert!((b.point(t[0], t[1], t[2]) - c[i][j][k]).length() < 1e-15);
                assert!((vol.point(t[0], t[1], t[2]) - c[i][j][k]).length() < 1e-15);
            }
        }
    }
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        let want = lerp3(&c, u, v, w);
        assert!((b.point(u, v, w) - want).length() < 1e-14);
        assert!((vol.point(u, v, w) - want).length() < 1e-14);
    }
}

#[test]
fn body1_reproduces_its_twelve_edges_and_converts_exactly() {
    let mut rng = Rng(2);
    let c = random_corners(&mut rng);
    let e = random_edges(&mut rng, &c);
    let b = Body1::new(e.clone(), 1e-12).unwrap();
    assert_eq!(b.mismatch(), 0.0);
    let vol = b.to_volume().unwrap();
    for _ in 0..200 {
        let s = rng.next();
        for i in 0..2 {
            for j in 0..2 {
                let (fi, fj) = (i as f64, j as f64);
                let checks = [
                    (b.point(s, fi, fj), vol.point(s, fi, fj), at(&e.u[i][j], s)),
                    (b.point(fi, s, fj), vol.point(fi, s, fj), at(&e.v[i][j], s)),
                    (b.point(fi, fj, s), vol.point(fi, fj, s), at(&e.w[i][j], s)),
                ];
                for (direct, volume, want) in checks {
                    assert!((direct - want).length() < 1e-12, "edge {i}{j} at {s}");
                    assert!(
                        (volume - want).length() < 1e-12,
                        "volume edge {i}{j} at {s}"
                    );
                }
            }
        }
    }
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((b.point(u, v, w) - vol.point(u, v, w)).length() < 1e-12);
    }
}

#[test]
fn body1_with_straight_edges_is_body0() {
    let mut rng = Rng(3);
    let c = random_corners(&mut rng);
    let line = |a: DVec3, b: DVec3| {
        // A straight cubic edge with uniform speed: Greville control points.
        let kv = KnotVector::clamped_uniform(3, 5).unwrap();
        let g = vsculpt_kernel::bspline::greville(&kv);
        BSplineCurve::new(kv, g.iter().map(|&t| a + (b - a) * t).collect()).unwrap()
    };
    let e = Edges {
        u: [
            [line(c[0][0][0], c[1][0][0]), line(c[0][0][1], c[1][0][1])],
            [line(c[0][1][0], c[1][1][0]), line(c[0][1][1], c[1][1][1])],
        ],
        v: [
            [line(c[0][0][0], c[0][1][0]), line(c[0][0][1], c[0][1][1])],
            [line(c[1][0][0], c[1][1][0]), line(c[1][0][1], c[1][1][1])],
        ],
        w: [
            [line(c[0][0][0], c[0][0][1]), line(c[0][1][0], c[0][1][1])],
            [line(c[1][0][0], c[1][0][1]), line(c[1][1][0], c[1][1][1])],
        ],
    };
    let b = Body1::new(e, 1e-14).unwrap();
    for _ in 0..500 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((b.point(u, v, w) - lerp3(&c, u, v, w)).length() < 1e-13);
    }
}

/// Six compatible faces in different spline spaces: the faces of a wavy
/// volume, re-expressed (elevated, refined) differently per face.
fn varied_faces(rng: &mut Rng) -> [[BSplineSurface; 2]; 3] {
    let ku = KnotVector::new(3, vec![0., 0., 0., 0., 0.3, 0.6, 1., 1., 1., 1.]).unwrap();
    let kv = KnotVector::new(2, vec![0., 0., 0., 0.5, 1., 1., 1.]).unwrap();
    let kw = KnotVector::new(3, vec![0., 0., 0., 0., 0.4, 0.4, 1., 1., 1., 1.]).unwrap();
    let mut pts = Vec::new();
    for i in 0..6 {
        for j in 0..4 {
            for k in 0..6 {
                pts.push(
                    DVec3::new(i as f64 / 5.0, j as f64 / 3.0, k as f64 / 5.0) * 3.0 + rng.vec(0.4),
                );
            }
        }
    }
    let vol = BSplineVolume::new(ku, kv, kw, pts).unwrap();
    let f = |dir, end| vol.face(Face { dir, end });
    let x0 = elevate_surface(&f(Dir::U, false), 1, 0).unwrap();
    let x1 = f(Dir::U, true);
    let y0 = f(Dir::V, false);
    let y0 = refine_surface(
        &y0,
        &KnotVector::new(3, vec![0., 0., 0., 0., 0.3, 0.45, 0.6, 1., 1., 1., 1.]).unwrap(),
        y0.v_knots(),
    )
    .unwrap();
    let y1 = elevate_surface(&f(Dir::V, true), 0, 2).unwrap();
    let z0 = f(Dir::W, false);
    let z1 = f(Dir::W, true);
    [[x0, x1], [y0, y1], [z0, z1]]
}

#[test]
fn body2_reproduces_its_six_faces_and_converts_exactly() {
    let mut rng = Rng(4);
    let faces = varied_faces(&mut rng);
    let b = Body2::new(faces.clone(), 1e-9).unwrap();
    assert!(b.mismatch() < 1e-12, "{}", b.mismatch());
    let vol = b.to_volume().unwrap();
    for _ in 0..300 {
        let (s, t) = (rng.next(), rng.next());
        for e in 0..2 {
            let fe = e as f64;
            let checks = [
                (
                    b.point(fe, s, t),
                    vol.point(fe, s, t),
                    faces[0][e].point(s, t),
                ),
                (
                    b.point(s, fe, t),
                    vol.point(s, fe, t),
                    faces[1][e].point(s, t),
                ),
                (
                    b.point(s, t, fe),
                    vol.point(s, t, fe),
                    faces[2][e].point(s, t),
                ),
            ];
            for (direct, volume, want) in checks {
                assert!((direct - want).length() < 1e-12, "face {e} at ({s}, {t})");
                assert!(
                    (volume - want).length() < 1e-12,
                    "volume face {e} at ({s}, {t})"
                );
            }
        }
    }
    // Body 2 equals its B-spline-volume conversion at 1000 random points.
    let mut worst: f64 = 0.0;
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        worst = worst.max((b.point(u, v, w) - vol.point(u, v, w)).length());
    }
    assert!(worst < 1e-12, "{worst}");
}

#[test]
fn body2_of_coons_patches_is_body1_and_of_bilinear_faces_is_body0() {
    let mut rng = Rng(5);
    let c = random_corners(&mut rng);
    let b1 = Body1::new(random_edges(&mut rng, &c), 1e-12).unwrap();
    let b2 = Body2::new(b1.faces().unwrap(), 1e-12).unwrap();
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        assert!((b2.point(u, v, w) - b1.point(u, v, w)).length() < 1e-12);
    }
    // Bilinear faces (degree 1, elevated to 2 × 3 so the spaces are not trivial).
    let kv1 = KnotVector::clamped_uniform(1, 2).unwrap();
    let bil = |a: DVec3, b: DVec3, cc: DVec3, d: DVec3| {
        let s = BSplineSurface::new(kv1.clone(), kv1.clone(), vec![a, b, cc, d]).unwrap();
        elevate_surface(&s, 1, 2).unwrap()
    };
    let faces = [
        [
            bil(c[0][0][0], c[0][0][1], c[0][1][0], c[0][1][1]),
            bil(c[1][0][0], c[1][0][1], c[1][1][0], c[1][1][1]),
        ],
        [
            bil(c[0][0][0], c[0][0][1], c[1][0][0], c[1][0][1]),
            bil(c[0][1][0], c[0][1][1], c[1][1][0], c[1][1][1]),
        ],
        [
            bil(c[0][0][0], c[0][1][0], c[1][0][0], c[1][1][0]),
            bil(c[0][0][1], c[0][1][1], c[1][0][1], c[1][1][1]),
        ],
    ];
    let b2 = Body2::new(faces, 1e-12).unwrap();
    let vol = b2.to_volume().unwrap();
    for _ in 0..1000 {
        let (u, v, w) = (rng.next(), rng.next(), rng.next());
        let want = lerp3(&c, u, v, w);
        assert!((b2.point(u, v, w) - want).length() < 1e-12);
        assert!((vol.point(u, v, w) - want).length() < 1e-12);
    }
}

#[test]
fn incompatible_boundaries_are_refused_with_the_distance() {
    let mut rng = Rng(6);
    let mut faces = varied_faces(&mut rng);
    let n = faces[2][1].points().len();
    faces[2][1].points_mut()[n - 1] += DVec3::new(0.0, 0.0, 0.01);
    match Body2::new(faces.clone(), 1e-6) {
        Err(BodyError::Incompatible { distance, .. }) => {
            assert!((distance - 0.01).abs() < 1e-9, "{distance}")
        }
        other => panic!("{other:?}"),
    }
    // Within a looser tolerance it is accepted, the mismatch reported, and
    // the Z face wins: the body's corner is the moved point.
    let b = Body2::new(faces.clone(), 0.1).unwrap();
    assert!((b.mismatch() - 0.01).abs() < 1e-9);
    let corner = faces[2][1].point(1.0, 1.0);
    assert!((b.point(1.0, 1.0, 1.0) - corner).length() < 1e-12);
    let mut rng = Rng(7);
    let c = random_corners(&mut rng);
    let mut e = random_edges(&mut rng, &c);
    e.w[1][1].points_mut()[0] += DVec3::X * 1e-3;
    assert!(matches!(
        Body1::new(e, 1e-6),
        Err(BodyError::Incompatible { .. })
    ));
}

#[test]
fn moving_a_shared_face_point_keeps_faces_compatible() {
    let mut rng = Rng(8);
    let mut b = Body2::new(varied_faces(&mut rng), 1e-9).unwrap();
    // A corner of Z_1 (u = 1, v = 1): shared with X_1 and Y_1.
    let z = &b.faces()[2][1];
    let (a, bb) = (z.nu() - 1, z.nv() - 1);
    let p = DVec3::new(4.0, 4.0, 4.0);
    b.move_face_point(2, 1, a, bb, p).unwrap();
    assert!((b.faces()[0][1].point(1.0, 1.0) - p).length() < 1e-14);
    assert!((b.faces()[1][1].point(1.0, 1.0) - p).length() < 1e-14);
    let vol = b.to_volume().unwrap();
    assert!((vol.point(1.0, 1.0, 1.0) - p).length() < 1e-13);
    // Still a valid body 2: rebuilding with zero tolerance succeeds.
    Body2::new(b.faces().clone(), 0.0).unwrap();
    assert!(b.move_face_point(3, 0, 0, 0, p).is_err());
    assert!(b.move_face_point(0, 0, 0, 0, DVec3::NAN).is_err());
}
