//! Lattices of bodies: continuity across shared faces measured for C0, C1
//! and C2 joints (made by knot multiplicity), shared points moved in every
//! body, and the five-body chair (C1, C0 sharp, C2, C1 joints, checked
//! against an independent Cox–de Boor).

use glam::DVec3;
use vsculpt_kernel::body::demo::{CHAIR_CONTINUITY, CHAIR_CUTS, chair, chair_part, chair_strip};
use vsculpt_kernel::body::{BSplineVolume, BodyError, BodyLattice, Dir, Face, check_injective};
use vsculpt_kernel::bspline::KnotVector;
mod body_support;
use body_support::Rng;

/// A curved cubic volume whose u-knot 0.5 has multiplicity `mult`.
fn with_knot(mult: usize) -> BSplineVolume {
    let mut ku = vec![0.0; 4];
    ku.extend([0.25]);
    ku.extend(std::iter::repeat_n(0.5, mult));
    ku.extend([0.75]);
    ku.extend([1.0; 4]);
    let ku = KnotVector::new(3, ku).unwrap();
    let nu = ku.num_ctrl();
    let kv = KnotVector::clamped_uniform(3, 4).unwrap();
    let kw = KnotVector::clamped_uniform(2, 3).unwrap();
    let mut rng = Rng(42);
    let mut pts = Vec::new();
    for i in 0..nu {
        for j in 0..4 {
            for k in 0..3 {
                let base = DVec3::new(i as f64 / (nu - 1) as f64 * 3.0, j as f64, k as f64);
                pts.push(base + DVec3::new(rng.next(), rng.next(), rng.next()) * 0.3);
            }
        }
    }
    BSplineVolume::new(ku, kv, kw, pts).unwrap()
}

#[test]
fn continuity_is_measured_for_c0_c1_c2_joints() {
    for (mult, expected) in [(3, 0), (2, 1), (1, 2)] {
        let v = with_knot(mult);
        let lat = BodyLattice::split(&v, Dir::U, &[0.5]).unwrap();
        assert_eq!(lat.bodies().len(), 2);
        let c = lat.continuity(0, 9).unwrap();
        assert!(c.position < 1e-12, "mult {mult}: {c:?}");
        // The random control points make the next derivative jump.
        match expected {
            0 => assert!(c.first > 1e-3, "{c:?}"),
            1 => assert!(c.first < 1e-10 && c.second > 1e-3, "{c:?}"),
            _ => assert!(c.first < 1e-10 && c.second < 1e-8, "{c:?}"),
        }
        assert_eq!(c.order(1e-8), Some(expected), "mult {mult}: {c:?}");
        // Independent: central differences of the unsplit volume across u = 0.5.
        let h = 1e-5;
        let jump = (v.derivs(0.5 + h, 0.3, 0.6).d[0] - v.derivs(0.5 - h, 0.3, 0.6).d[0]).length();
        if expected == 0 {
            assert!(jump > 1e-3);
        } else {
            assert!(jump < 1e-3);
        }
    }
}

#[test]
fn a_displaced_face_breaks_c0_and_the_joint_refuses_it() {
    let v = with_knot(1);
    let (l, r) = v.split(Dir::U, 0.5).unwrap();
    let mut r2 = r.clone();
    let idx = r2.face_indices(Face {
        dir: Dir::U,
        end: false,
    })[5];
    r2.set_point(idx, r2.points()[idx] + DVec3::Z * 0.01)
        .unwrap();
    let mut lat = BodyLattice::new(vec![l.clone(), r2]);
    match lat.join(
        0,
        Face {
            dir: Dir::U,
            end: true,
        },
        1,
        Face {
            dir: Dir::U,
            end: false,
        },
        1e-6,
    ) {
        Err(BodyError::Incompatible { distance, .. }) => assert!((distance - 0.01).abs() < 1e-12),
        other => panic!("{other:?}"),
    }
    // Joined with a loose tolerance, the second body takes the first's face.
    lat.join(
        0,
        Face {
            dir: Dir::U,
            end: true,
        },
        1,
        Face {
            dir: Dir::U,
            end: false,
        },
        0.1,
    )
    .unwrap();
    assert!(lat.continuity(0, 7).unwrap().position < 1e-12);
    // Faces of other knots cannot be joined.
    let mut lat = BodyLattice::new(vec![l, with_knot(2)]);
    assert!(
        lat.join(
            0,
            Face {
                dir: Dir::U,
                end: true
            },
            1,
            Face {
                dir: Dir::V,
                end: false
            },
            1.0
        )
        .is_err()
    );
}

/// Cox–de Boor with derivatives, written here independently of the kernel:
/// the `deriv`-th derivative of N_{i,p} at `t`, as the limit from the left
/// (`left`) or from the right (0/0 = 0).
fn basis(knots: &[f64], i: usize, p: usize, t: f64, deriv: usize, left: bool) -> f64 {
    if deriv > p {
        return 0.0;
    }
    if p == 0 {
        let (a, b) = (knots[i], knots[i + 1]);
        let inside = if left {
            a < t && t <= b
        } else {
            a <= t && t < b
        };
        // The clamped end: the last non-empty span is closed on the right.
        let last = !left && t == b && b == *knots.last().unwrap() && a < b;
        return if inside || last { 1.0 } else { 0.0 };
    }
    let div = |x: f64, y: f64| if y == 0.0 { 0.0 } else { x / y };
    let (ti, tip, ti1, tip1) = (knots[i], knots[i + p], knots[i + 1], knots[i + p + 1]);
    if deriv == 0 {
        div(t - ti, tip - ti) * basis(knots, i, p - 1, t, 0, left)
            + div(tip1 - t, tip1 - ti1) * basis(knots, i + 1, p - 1, t, 0, left)
    } else {
        let pf = p as f64;
        div(pf, tip - ti) * basis(knots, i, p - 1, t, deriv - 1, left)
            - div(pf, tip1 - ti1) * basis(knots, i + 1, p - 1, t, deriv - 1, left)
    }
}

/// The `deriv`-th u-derivative of `vol` at (u, v, w) by [`basis`] (one-sided).
fn strip_du(vol: &BSplineVolume, u: f64, v: f64, w: f64, deriv: usize, left: bool) -> DVec3 {
    let [nu, nv, nw] = vol.counts();
    let (ku, kv, kw) = (
        vol.knots(Dir::U).knots(),
        vol.knots(Dir::V).knots(),
        vol.knots(Dir::W).knots(),
    );
    let mut out = DVec3::ZERO;
    for i in 0..nu {
        let a = basis(ku, i, 3, u, deriv, left);
        if a == 0.0 {
            continue;
        }
        for j in 0..nv {
            let b = basis(kv, j, 3, v, 0, false);
            for k in 0..nw {
                let c = basis(kw, k, 3, w, 0, false);
                out += vol.points()[vol.index(i, j, k)] * (a * b * c);
            }
        }
    }
    out
}

#[test]
fn the_chair_s_five_bodies_share_faces_with_c1_c0_c2_c1_joints_and_a_sharp_edge() {
    let strip = chair_strip().unwrap();
    let lat = chair().unwrap();
    assert_eq!(lat.bodies().len(), 5);
    assert_eq!(lat.joints().len(), 4);
    for (b, body) in lat.bodies().iter().enumerate() {
        check_injective(body).unwrap_or_else(|e| panic!("body {b}: {e}"));
    }
    // Every body is its piece of the strip, in the strip's global
    // parameters: against the independent Cox–de Boor at random points.
    let mut rng = Rng(7);
    let bounds = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    for (b, body) in lat.bodies().iter().enumerate() {
        for _ in 0..200 {
            let u = bounds[b] + (bounds[b + 1] - bounds[b]) * rng.next();
            let (v, w) = (rng.next(), rng.next());
            let want = strip_du(&strip, u, v, w, 0, false);
            let got = body.point(u, v, w);
            assert!(
                (got - want).length() < 1e-12,
                "body {b} at {u}: {got} vs {want}"
            );
        }
    }
    // Each joint is exactly C^k: the derivatives up to k agree from both
    // sides of the cut, derivative k + 1 jumps (independent one-sided
    // Cox–de Boor derivatives of the strip), and the lattice's own
    // measurement on the shared face says the same.
    for (j, (&cut, &k)) in CHAIR_CUTS.iter().zip(&CHAIR_CONTINUITY).enumerate() {
        assert_eq!(lat.joints()[j].a.0, j);
        assert_eq!(lat.joints()[j].b.0, j + 1);
        let mut jumps = [0.0f64; 4];
        for &(v, w) in &[(0.0, 0.0), (0.3, 0.7), (0.5, 0.5), (1.0, 1.0), (0.8, 0.1)] {
            for (d, jump) in jumps.iter_mut().enumerate() {
                let l = strip_du(&strip, cut, v, w, d, true);
                let r = strip_du(&strip, cut, v, w, d, false);
                *jump = jump.max((l - r).length());
            }
        }
        for (d, jump) in jumps.iter().enumerate() {
            if d <= k {
                assert!(*jump < 1e-9, "joint {j}: derivative {d} jumps by {jump}");
            } else if d == k + 1 {
                assert!(
                    *jump > 1e-3,
                    "joint {j}: derivative {d} only jumps by {jump}"
                );
            }
        }
        let c = lat.continuity(j, 9).unwrap();
        assert_eq!(
            c.order(1e-8),
            Some(k),
            "joint {j}: {c:?} vs jumps {jumps:?}"
        );
    }
    // The sharp edge: at the seat's front (the triple knot at 2) the strip's
    // centre passes through the corner, and the u-tangents on either side
    // are the leg's (straight up) and the seat's (back, dipping): about 90°
    // apart, where the other joints' tangents agree.
    let corner = strip_du(&strip, 2.0, 0.5, 0.5, 0, true);
    assert!(
        (corner - DVec3::new(0.1, 0.25, 0.42)).length() < 1e-12,
        "{corner}"
    );
    let (up, back) = (
        strip_du(&strip, 2.0, 0.5, 0.5, 1, true).normalize(),
        strip_du(&strip, 2.0, 0.5, 0.5, 1, false).normalize(),
    );
    assert!((up - DVec3::Z).length() < 1e-12, "{up}");
    let angle = up.dot(back).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(
        back.x > 0.95 && (80.0..100.0).contains(&angle),
        "{back}: {angle}°"
    );
    // Shared points: a point of the seat halves' shared face moves in both.
    let mut lat = lat;
    let rear = &lat.bodies()[chair_part::SEAT_REAR];
    let idx = rear.index(0, 1, 2);
    let p = rear.points()[idx] + DVec3::Z * 0.01;
    let moved = lat.set_point(chair_part::SEAT_REAR, idx, p).unwrap();
    assert_eq!(moved.len(), 2, "{moved:?}");
    assert!(lat.continuity(2, 5).unwrap().position < 1e-12);
}
