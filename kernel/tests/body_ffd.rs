//! Free-form deformation: identity and affine lattices reproduce exactly,
//! local updates equal full recomputation, outside points stay, curved
//! (non-affine) rest lattices embed by inversion, and B-spline surfaces and
//! curves are refitted within the stated tolerance.

use glam::{DMat3, DVec3};
use vsculpt_kernel::body::{BSplineVolume, Ffd};
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
mod body_support;
use body_support::Rng;

const O: DVec3 = DVec3::new(-1.0, 0.5, 2.0);
const AX: [DVec3; 3] = [
    DVec3::new(2.0, 0.3, 0.0),
    DVec3::new(-0.2, 1.5, 0.1),
    DVec3::new(0.1, -0.3, 1.2),
];

fn inside(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|_| O + AX[0] * rng.next() + AX[1] * rng.next() + AX[2] * rng.next())
        .collect()
}

fn lattices() -> Vec<BSplineVolume> {
    vec![
        // Sederberg–Parry: one Bernstein volume of degree (3, 2, 4).
        BSplineVolume::affine(O, AX, [3, 2, 4], [4, 3, 5]).unwrap(),
        // B-spline variant.
        BSplineVolume::affine(O, AX, [3, 3, 2], [7, 5, 6]).unwrap(),
    ]
}

#[test]
fn identity_lattice_leaves_points_unchanged() {
    let mut rng = Rng(1);
    let pts = inside(&mut rng, 2000);
    for lat in lattices() {
        let ffd = Ffd::new(lat);
        let emb = ffd.embed(&pts, 1e-9).unwrap();
        assert_eq!(emb.outside(), 0);
        let mut out = vec![DVec3::ZERO; pts.len()];
        ffd.deform_all(&emb, &mut out).unwrap();
        for (a, b) in pts.iter().zip(&out) {
            assert!((*a - *b).length() < 1e-12, "{a} -> {b}");
        }
    }
}

#[test]
fn affine_lattice_moves_give_the_affine_map() {
    let mut rng = Rng(2);
    let pts = inside(&mut rng, 2000);
    let a = DMat3::from_cols(
        DVec3::new(1.2, 0.3, -0.1),
        DVec3::new(0.2, 0.8, 0.4),
        DVec3::new(-0.3, 0.1, 1.5),
    );
    let t = DVec3::new(0.7, -2.0, 0.25);
    for lat in lattices() {
        let mut ffd = Ffd::new(lat.clone());
        let emb = ffd.embed(&pts, 1e-9).unwrap();
        ffd.set_lattice(lat.points().iter().map(|p| a * *p + t).collect())
            .unwrap();
        let mut out = vec![DVec3::ZERO; pts.len()];
        ffd.deform_all(&emb, &mut out).unwrap();
        for (x, y) in pts.iter().zip(&out) {
            assert!((a * *x + t - *y).length() < 1e-12);
        }
    }
}

#[test]
fn moving_one_point_recomputes_only_its_support_and_equals_a_full_pass() {
    let mut rng = Rng(3);
    let pts = inside(&mut rng, 20_000);
    let lat = BSplineVolume::affine(O, AX, [3, 3, 3], [8, 8, 8]).unwrap();
    let mut ffd = Ffd::new(lat.clone());
    let emb = ffd.embed(&pts, 1e-9).unwrap();
    let mut out = vec![DVec3::ZERO; pts.len()];
    ffd.deform_all(&emb, &mut out).unwrap();
    let mut touched_total = 0;
    for step in 0..40 {
        let idx = (rng.next() * lat.points().len() as f64) as usize;
        let p = ffd.lattice().points()[idx] + rng.vec(0.3);
        let n = ffd.move_point(idx, p, &emb, &mut out).unwrap();
        touched_total += n;
        let mut full = vec![DVec3::ZERO; pts.len()];
        ffd.deform_all(&emb, &mut full).unwrap();
        assert_eq!(out, full, "step {step}");
    }
    // 8 points, cubic: a point's support is at most 4 of 5 cells per
    // direction, usually fewer; on average far below all the points.
    assert!(touched_total < 40 * pts.len() / 2, "{touched_total}");
    // The centre point (4, 4, 4) of 8³ touches (4/5)³ of the cells at most.
    let centre = lat.index(4, 4, 4);
    let n = ffd
        .move_point(centre, lat.points()[centre] + DVec3::X, &emb, &mut out)
        .unwrap();
    assert!(n < pts.len() * 60 / 100, "{n}");
    assert!(n > 0);
}

#[test]
fn points_outside_the_lattice_keep_their_position() {
    let lat = BSplineVolume::affine(O, AX, [2, 2, 2], [4, 4, 4]).unwrap();
    let mut ffd = Ffd::new(lat.clone());
    let pts = vec![
        O - DVec3::splat(0.5),
        O + AX[0] * 0.5 + AX[1] * 0.5 + AX[2] * 0.5,
    ];
    let emb = ffd.embed(&pts, 1e-9).unwrap();
    assert_eq!(emb.outside(), 1);
    ffd.set_lattice(lat.points().iter().map(|p| *p * 2.0).collect())
        .unwrap();
    let mut out = vec![DVec3::ZERO; 2];
    ffd.deform_all(&emb, &mut out).unwrap();
    assert_eq!(out[0], pts[0]);
    assert!((out[1] - pts[1] * 2.0).length() < 1e-12);
    assert!(ffd.embed(&[DVec3::NAN], 1e-9).is_err());
    assert!(ffd.deform_all(&emb, &mut [DVec3::ZERO; 3]).is_err());
}

#[test]
fn curved_rest_lattice_embeds_by_inversion() {
    let mut rng = Rng(4);
    let mut lat = BSplineVolume::affine(O, AX, [2, 3, 2], [4, 5, 4]).unwrap();
    let moved: Vec<DVec3> = lat.points().iter().map(|p| *p + rng.vec(0.2)).collect();
    lat.set_points(moved).unwrap();
    let params: Vec<[f64; 3]> = (0..500)
        .map(|_| [rng.next(), rng.next(), rng.next()])
        .collect();
    let pts: Vec<DVec3> = params.iter().map(|t| lat.point(t[0], t[1], t[2])).collect();
    let ffd = Ffd::new(lat);
    let emb = ffd.embed(&pts, 1e-10).unwrap();
    assert_eq!(emb.outside(), 0);
    let mut out = vec![DVec3::ZERO; pts.len()];
    ffd.deform_all(&emb, &mut out).unwrap();
    for (i, (a, b)) in pts.iter().zip(&out).enumerate() {
        assert!((*a - *b).length() < 1e-10);
        let t = emb.params(i);
        for d in 0..3 {
            assert!((t[d] - params[i][d]).abs() < 1e-10);
        }
    }
}

fn wavy_surface() -> BSplineSurface {
    let ku = KnotVector::clamped_uniform(3, 6).unwrap();
    let kv = KnotVector::clamped_uniform(2, 5).unwrap();
    let mut pts = Vec::new();
    for i in 0..6 {
        for j in 0..5 {
            let (s, t) = (0.1 + 0.8 * i as f64 / 5.0, 0.1 + 0.8 * j as f64 / 4.0);
            let h = 0.5 + 0.2 * (3.0 * s).sin() * (2.0 * t).cos();
            pts.push(O + AX[0] * s + AX[1] * t + AX[2] * h);
        }
    }
    BSplineSurface::new(ku, kv, pts).unwrap()
}

#[test]
fn surfaces_and_curves_are_refitted_within_tolerance() {
    let s = wavy_surface();
    let lat = BSplineVolume::affine(O, AX, [3, 3, 3], [5, 5, 5]).unwrap();
    let mut ffd = Ffd::new(lat.clone());
    // Identity: the refit reproduces the surface.
    let (same, err) = ffd.deform_surface(&s, 1e-9).unwrap();
    assert!(err < 1e-12);
    let mut rng = Rng(5);
    for _ in 0..200 {
        let (a, b) = (rng.next(), rng.next());
        assert!((same.point(a, b) - s.point(a, b)).length() < 1e-12);
    }
    // A real deformation: bend the lattice.
    let bent: Vec<DVec3> = lat
        .points()
        .iter()
        .map(|p| {
            *p + DVec3::new(0.0, 0.0, 0.4 * ((p.x - O.x) * 1.5).sin())
                + DVec3::new(0.2 * (p.z - O.z).powi(2), 0.0, 0.0)
        })
        .collect();
    ffd.set_lattice(bent).unwrap();
    let tol = 1e-5;
    let (fit, err) = ffd.deform_surface(&s, tol).unwrap();
    assert!(err <= tol);
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        let (a, b) = (rng.next(), rng.next());
        let want = ffd.deform_point(s.point(a, b), 1e-9);
        worst = worst.max((fit.point(a, b) - want).length());
    }
    assert!(worst <= 2.0 * tol, "{worst}");
    // Moving the points only (not refitting) is visibly worse.
    let naive: Vec<DVec3> = s
        .points()
        .iter()
        .map(|p| ffd.deform_point(*p, 1e-9))
        .collect();
    let naive = BSplineSurface::new(s.u_knots().clone(), s.v_knots().clone(), naive).unwrap();
    let mut naive_err: f64 = 0.0;
    for _ in 0..500 {
        let (a, b) = (rng.next(), rng.next());
        naive_err =
            naive_err.max((naive.point(a, b) - ffd.deform_point(s.point(a, b), 1e-9)).length());
    }
    assert!(naive_err > 10.0 * tol, "{naive_err}");
    // A curve.
    let kc = KnotVector::clamped_uniform(2, 5).unwrap();
    let c = BSplineCurve::new(
        kc,
        (0..5)
            .map(|i| {
                O + AX[0] * (0.1 + 0.2 * i as f64) + AX[1] * 0.5 + AX[2] * (0.3 + 0.1 * i as f64)
            })
            .collect(),
    )
    .unwrap();
    let (fc, err) = ffd.deform_curve(&c, tol).unwrap();
    assert!(err <= tol);
    for _ in 0..200 {
        let t = rng.next();
        assert!((fc.point(t) - ffd.deform_point(c.point(t), 1e-9)).length() <= 2.0 * tol);
    }
}
