//! B-spline volumes: derivatives against finite differences, exact changes
//! of basis (knot insertion, degree elevation, splitting) against the
//! original at random parameters, isoparametric surfaces, point inversion.

use glam::DVec3;
use vsculpt_kernel::body::{BSplineVolume, Dir, Face};
use vsculpt_kernel::bspline::KnotVector;
mod body_support;
use body_support::Rng;

/// A curved cubic × quadratic × cubic volume with a double knot in w.
fn wavy() -> BSplineVolume {
    let ku = KnotVector::new(3, vec![0., 0., 0., 0., 0.3, 0.6, 1., 1., 1., 1.]).unwrap();
    let kv = KnotVector::new(2, vec![0., 0., 0., 0.5, 1., 1., 1.]).unwrap();
    let kw = KnotVector::new(3, vec![0., 0., 0., 0., 0.4, 0.4, 1., 1., 1., 1.]).unwrap();
    let mut pts = Vec::new();
    let mut rng = Rng(7);
    for i in 0..6 {
        for j in 0..4 {
            for k in 0..6 {
                let (x, y, z) = (i as f64 / 5.0, j as f64 / 3.0, k as f64 / 5.0);
                pts.push(
                    DVec3::new(x + 0.2 * z * z, y + 0.1 * x, z + 0.15 * (3.0 * x).sin())
                        + DVec3::new(rng.next(), rng.next(), rng.next()) * 0.03,
                );
            }
        }
    }
    BSplineVolume::new(ku, kv, kw, pts).unwrap()
}

/// Reference evaluation straight from the Cox–de Boor recursion.
fn cox_de_boor(k: &[f64], i: usize, p: usize, t: f64) -> f64 {
    if p == 0 {
        let last = k[k.len() - 1];
        return if (k[i] <= t && t < k[i + 1]) || (t == last && k[i + 1] == last && k[i] < last) {
            1.0
        } else {
            0.0
        };
    }
    let mut s = 0.0;
    if k[i + p] > k[i] {
        s += (t - k[i]) / (k[i + p] - k[i]) * cox_de_boor(k, i, p - 1, t);
    }
    if k[i + p + 1] > k[i + 1] {
        s += (k[i + p + 1] - t) / (k[i + p + 1] - k[i + 1]) * cox_de_boor(k, i + 1, p - 1, t);
    }
    s
}

fn reference_point(v: &BSplineVolume, t: [f64; 3]) -> DVec3 {
    let c = v.counts();
    let mut s = DVec3::ZERO;
    for i in 0..c[0] {
        let a = cox_de_boor(v.knots(Dir::U).knots(), i, v.degrees()[0], t[0]);
        for j in 0..c[1] {
            let b = cox_de_boor(v.knots(Dir::V).knots(), j, v.degrees()[1], t[1]);
            for k in 0..c[2] {
                let g = cox_de_boor(v.knots(Dir::W).knots(), k, v.degrees()[2], t[2]);
                s += v.points()[v.index(i, j, k)] * (a * b * g);
            }
        }
    }
    s
}

#[test]
fn evaluation_matches_cox_de_boor_sum() {
    let v = wavy();
    let mut rng = Rng(3);
    for _ in 0..200 {
        let t = [rng.next(), rng.next(), rng.next()];
        let e = (v.point(t[0], t[1], t[2]) - reference_point(&v, t)).length();
        assert!(e < 1e-13, "{t:?}: {e}");
    }
}

#[test]
fn derivatives_match_finite_differences() {
    let v = wavy();
    let mut rng = Rng(11);
    let h = 1e-6;
    for _ in 0..100 {
        // Stay away from the double knot at w = 0.4 where x_ww jumps.
        let t = [
            0.05 + 0.9 * rng.next(),
            0.05 + 0.9 * rng.next(),
            0.05 + 0.3 * rng.next(),
        ];
        let d = v.derivs(t[0], t[1], t[2]);
        for a in 0..3 {
            let mut tp = t;
            let mut tm = t;
            tp[a] += h;
            tm[a] -= h;
            let fd = (v.point(tp[0], tp[1], tp[2]) - v.point(tm[0], tm[1], tm[2])) / (2.0 * h);
            assert!((fd - d.d[a]).length() < 1e-6, "first {a} at {t:?}");
            let dp = v.derivs(tp[0], tp[1], tp[2]);
            let dm = v.derivs(tm[0], tm[1], tm[2]);
            for b in 0..3 {
                let fd2 = (dp.d[b] - dm.d[b]) / (2.0 * h);
                assert!(
                    (fd2 - d.dd[a][b]).length() < 1e-5 * (1.0 + d.dd[a][b].length()),
                    "second {a}{b} at {t:?}: {fd2} vs {}",
                    d.dd[a][b]
                );
            }
        }
        let j = v.jacobian(t[0], t[1], t[2]);
        assert_eq!(j.x_axis, d.d[0]);
        assert!((d.det() - j.determinant()).abs() < 1e-12);
    }
}

#[test]
fn knot_insertion_elevation_and_split_keep_the_solid() {
    let v = wavy();
    let ins = v
        .insert_knot(Dir::U, 0.45)
        .unwrap()
        .insert_knot(Dir::W, 0.7)
        .unwrap();
    assert_eq!(ins.counts(), [7, 4, 7]);
    let el = v.elevate(Dir::V, 2).unwrap().elevate(Dir::W, 1).unwrap();
    assert_eq!(el.degrees(), [3, 4, 4]);
    // The double knot at w = 0.4 becomes a triple knot (still C1 in degree 4).
    assert_eq!(
        el.knots(Dir::W)
            .knots()
            .iter()
            .filter(|&&k| k == 0.4)
            .count(),
        3
    );
    let (left, right) = v.split(Dir::U, 0.45).unwrap();
    assert_eq!(left.knots(Dir::U).domain(), (0.0, 0.45));
    let mut rng = Rng(5);
    for _ in 0..1000 {
        let t = [rng.next(), rng.next(), rng.next()];
        let p = v.point(t[0], t[1], t[2]);
        assert!((ins.point(t[0], t[1], t[2]) - p).length() < 1e-12);
        assert!(
            (el.point(t[0], t[1], t[2]) - p).length() < 1e-12,
            "elevated at {t:?}"
        );
        let piece = if t[0] <= 0.45 { &left } else { &right };
        assert!((piece.point(t[0], t[1], t[2]) - p).length() < 1e-12);
    }
    assert!(v.insert_knot(Dir::U, 1.5).is_err());
    assert!(v.split(Dir::V, 0.0).is_err());
}

#[test]
fn iso_surfaces_and_faces_are_exact() {
    let v = wavy();
    let mut rng = Rng(9);
    for _ in 0..200 {
        let (a, b, c) = (rng.next(), rng.next(), rng.next());
        assert!((v.iso_surface(Dir::U, a).point(b, c) - v.point(a, b, c)).length() < 1e-13);
        assert!((v.iso_surface(Dir::V, b).point(a, c) - v.point(a, b, c)).length() < 1e-13);
        assert!((v.iso_surface(Dir::W, c).point(a, b) - v.point(a, b, c)).length() < 1e-13);
        let f = v.face(Face {
            dir: Dir::W,
            end: true,
        });
        assert!((f.point(a, b) - v.point(a, b, 1.0)).length() < 1e-13);
    }
}

#[test]
fn point_inversion_round_trips() {
    let v = wavy();
    let mut rng = Rng(13);
    for _ in 0..300 {
        let t = [rng.next(), rng.next(), rng.next()];
        let x = v.point(t[0], t[1], t[2]);
        let inv = v.invert(x, 1e-13).unwrap();
        assert!(inv.distance < 1e-12, "{t:?}: {}", inv.distance);
        for d in 0..3 {
            assert!((inv.uvw[d] - t[d]).abs() < 1e-10, "{t:?} -> {:?}", inv.uvw);
        }
    }
    // A point outside ends on the boundary with its distance reported.
    let far = v.invert(DVec3::new(5.0, 0.5, 0.5), 1e-12).unwrap();
    assert!(far.distance > 3.0);
    assert!(v.invert(DVec3::NAN, 1e-12).is_err());
}

#[test]
fn affine_lattice_is_the_affine_map() {
    let axes = [
        DVec3::new(2.0, 0.1, 0.0),
        DVec3::new(0.3, 1.5, 0.2),
        DVec3::new(0.0, -0.4, 1.0),
    ];
    let o = DVec3::new(-1.0, 0.5, 2.0);
    let v = BSplineVolume::affine(o, axes, [3, 2, 4], [7, 5, 6]).unwrap();
    let mut rng = Rng(17);
    for _ in 0..200 {
        let t = [rng.next(), rng.next(), rng.next()];
        let x = o + axes[0] * t[0] + axes[1] * t[1] + axes[2] * t[2];
        assert!((v.point(t[0], t[1], t[2]) - x).length() < 1e-13);
    }
}

#[test]
fn face_and_edge_indices_hold_the_boundary_points() {
    let v = wavy();
    // The edge u = 1, v = 0 along w is the line x(1, 0, w): its control
    // points are the curve's.
    let e = v.edge_indices(Dir::W, true, false);
    assert_eq!(e.len(), 6);
    let pts: Vec<DVec3> = e.iter().map(|&i| v.points()[i]).collect();
    let c = vsculpt_kernel::bspline::BSplineCurve::new(v.knots(Dir::W).clone(), pts).unwrap();
    let mut rng = Rng(21);
    for _ in 0..50 {
        let w = rng.next();
        assert!((c.point(w) - v.point(1.0, 0.0, w)).length() < 1e-13);
    }
    let f = v.face_indices(Face {
        dir: Dir::V,
        end: true,
    });
    assert_eq!(f.len(), 6 * 6);
    assert!(
        f.iter()
            .all(|&i| v.ijk(i)[1] == 3 && v.is_boundary_point(i))
    );
    assert!(!v.is_boundary_point(v.index(2, 1, 3)));
}
