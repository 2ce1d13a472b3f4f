//! Lattices of bodies: continuity across shared faces measured for C0, C1
//! and C2 joints (made by knot multiplicity), shared points moved in every
//! body, and the five-body chair.

use glam::DVec3;
use vsculpt_kernel::body::demo::{chair, chair_part};
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

#[test]
fn chair_bodies_are_joined_c0_injective_and_share_moved_points() {
    let mut lat = chair().unwrap();
    assert_eq!(lat.bodies().len(), 5);
    assert_eq!(lat.joints().len(), 4);
    for j in 0..4 {
        let c = lat.continuity(j, 11).unwrap();
        assert!(c.position < 1e-12, "joint {j}: {c:?}");
    }
    for b in lat.bodies() {
        check_injective(b).unwrap();
    }
    // The seat dip moved the backrest's bottom too.
    let rear = &lat.bodies()[chair_part::SEAT_REAR];
    let back = &lat.bodies()[chair_part::BACK];
    assert!((rear.point(0.5, 0.5, 1.0) - back.point(0.5, 0.5, 0.0)).length() < 1e-14);
    assert!(rear.point(0.5, 0.5, 1.0).z < 0.55 - 0.01);
    // A point on the rear seat's front face is shared with the front half;
    // its corner on the top is not shared with anything else but the back.
    let idx = rear.index(0, 1, 1);
    let moved = lat
        .set_point(
            chair_part::SEAT_REAR,
            idx,
            rear.points()[idx] + DVec3::X * 0.01,
        )
        .unwrap();
    assert_eq!(moved.len(), 2);
    let corner = lat.bodies()[chair_part::SEAT_REAR].index(0, 0, 3);
    let p = lat.bodies()[chair_part::SEAT_REAR].points()[corner];
    let moved = lat.set_point(chair_part::SEAT_REAR, corner, p).unwrap();
    // Seat rear, seat front (shared u face) and back (shared w face).
    assert_eq!(moved.len(), 3, "{moved:?}");
    for j in 0..4 {
        assert!(lat.continuity(j, 5).unwrap().position < 1e-12);
    }
}
