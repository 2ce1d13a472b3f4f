//! Network edits: meetings are kept as curves move; an edit that leaves a
//! face open or self-intersecting, or loses a meeting, is refused with a
//! clear error and changes nothing.

use glam::{DVec2, DVec3};
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_kernel::network::demo::{lifted_line, wheel};
use vsculpt_kernel::network::{CurveNetwork, NetworkError, NetworkOptions, Update};

fn wheel_curves(n: usize) -> Vec<BSplineCurve> {
    wheel(n).unwrap().curves().to_vec()
}

#[test]
fn a_curve_that_stops_short_leaves_its_face_open() {
    let mut curves = wheel_curves(5);
    // Spoke 2 (curve 7) stops at 90 % of the way to the outer ring.
    let a = curves[7].points()[0].truncate();
    let b = curves[7].points()[2].truncate();
    curves[7] = lifted_line(a, a.lerp(b, 0.9));
    let err = CurveNetwork::new(curves, NetworkOptions::default()).unwrap_err();
    assert!(
        matches!(err, NetworkError::OpenEnd { curve: 7, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("left open"), "{err}");
}

#[test]
fn dragging_a_curve_off_its_meeting_is_refused_and_changes_nothing() {
    let mut net = wheel(5).unwrap();
    let before = net.clone();
    let mut c = net.curves()[7].clone();
    c.points_mut()[2] += DVec3::new(0.0, 0.0, 0.05);
    let err = net.set_curve(7, c).unwrap_err();
    assert!(
        matches!(err, NetworkError::LostIntersection { a: 7, .. }),
        "{err}"
    );
    assert_eq!(net.curves(), before.curves());
    assert_eq!(net.topology(), before.topology());
}

#[test]
fn moving_a_curve_between_its_meetings_keeps_faces_and_handles() {
    let mut net = wheel(5).unwrap();
    net.set_twist(0, 0.1).unwrap();
    let faces = net.faces().to_vec();
    let mut c = net.curves()[7].clone();
    c.points_mut()[1] += DVec3::new(0.05, -0.02, 0.3);
    assert_eq!(net.set_curve(7, c.clone()).unwrap(), Update::Moved);
    assert_eq!(net.twist(0), Some(0.1));
    assert_eq!(net.faces().len(), faces.len());
    // The patches on the spoke follow the new curve.
    for (f, face) in net.faces().iter().enumerate() {
        for (i, side) in face.sides.iter().enumerate() {
            if side.curve == 7 {
                let p = net.patch(f).unwrap();
                let s = 0.37;
                let t = side.t_start + s * (side.t_end - side.t_start);
                let q = p.point(p.domain().side_point(i, s));
                assert!((q - c.point(t)).length() < 1e-12);
            }
        }
    }
}

#[test]
fn a_face_folded_over_itself_is_refused() {
    let mut net = wheel(5).unwrap();
    let before = net.clone();
    // Pull inner side 0's middle far across the centre face and up, so its
    // ends still meet the same curves but the face's boundary crosses itself.
    // The ends keep their directions (so the corners stay as they were).
    let old = net.curves()[0].clone();
    let (a, m, b) = (old.points()[0], old.points()[1], old.points()[2]);
    let across = -(a + b).truncate() * 2.5;
    let c = BSplineCurve::new(
        KnotVector::clamped_uniform(3, 5).unwrap(),
        vec![
            a,
            a.lerp(m, 0.2),
            DVec3::new(across.x, across.y, 3.0),
            b.lerp(m, 0.2),
            b,
        ],
    )
    .unwrap();
    let err = net.set_curve(0, c).unwrap_err();
    assert!(
        matches!(err, NetworkError::SelfIntersectingFace { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("self-intersecting"));
    assert_eq!(net.curves(), before.curves());
}

#[test]
fn a_curve_crossing_itself_is_refused() {
    let mut curves = wheel_curves(4);
    // A cubic whose control polygon makes it loop: crosses itself once.
    let kv = KnotVector::clamped_uniform(3, 4).unwrap();
    let (a, b) = (curves[8].points()[0], curves[8].points()[2]);
    let d = b - a;
    let side = DVec3::new(-d.y, d.x, 0.0);
    let looped = BSplineCurve::new(kv, vec![a, a + d * 2.0 + side, b - d * 2.0 + side, b]).unwrap();
    curves[8] = looped.clone();
    let err = CurveNetwork::new(curves, NetworkOptions::default()).unwrap_err();
    assert!(
        matches!(err, NetworkError::SelfIntersectingCurve { curve: 8, .. }),
        "{err}"
    );
    let mut net = wheel(4).unwrap();
    assert!(matches!(
        net.set_curve(8, looped),
        Err(NetworkError::SelfIntersectingCurve { curve: 8, .. })
    ));
}

#[test]
fn bad_handles_are_refused() {
    let mut net = wheel(3).unwrap();
    let before = net.clone();
    assert!(net.set_twist(0, f64::NAN).is_err());
    assert!(net.set_twist(99, 0.1).is_err());
    assert!(net.set_scale(0, 0, 0.0).is_err());
    assert!(net.set_scale(0, 9, 1.0).is_err());
    assert!(net.set_tuning(0, vec![DVec3::ZERO; 2]).is_err());
    assert!(
        net.set_tuning(0, vec![DVec3::splat(f64::INFINITY); 4])
            .is_err()
    );
    assert!(net.patch(17).is_err());
    assert_eq!(net.topology(), before.topology());
    assert_eq!(net.tuning(0), before.tuning(0));
    assert_eq!(net.scale(0, 0), Some(1.0));
    let _ = DVec2::ZERO;
}

#[test]
fn two_curves_meeting_twice_make_a_two_sided_face() {
    // Two arcs between the same two points and nothing else.
    let a = DVec2::new(0.0, 0.0);
    let b = DVec2::new(1.0, 0.0);
    let kv = KnotVector::clamped_uniform(2, 3).unwrap();
    let up = BSplineCurve::new(
        kv.clone(),
        vec![a.extend(0.0), DVec3::new(0.5, 0.5, 0.0), b.extend(0.0)],
    )
    .unwrap();
    let down = BSplineCurve::new(
        kv,
        vec![a.extend(0.0), DVec3::new(0.5, -0.5, 0.0), b.extend(0.0)],
    )
    .unwrap();
    let err = CurveNetwork::new(vec![up, down], NetworkOptions::default()).unwrap_err();
    assert!(
        matches!(err, NetworkError::TooFewSides { sides: 2, .. }),
        "{err}"
    );
}
