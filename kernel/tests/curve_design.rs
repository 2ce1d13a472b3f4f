//! Icons on a deformable curve (paper 003 sculpts curves too).

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_kernel::curve_design::{CurveDesign, CurveRole};
use vsculpt_kernel::energy::CurveMaterial;
use vsculpt_kernel::icon::{IconId, IconState};

fn batten(beta: f64) -> CurveDesign {
    let kv = KnotVector::clamped_uniform(3, 12).unwrap();
    let pts = (0..12)
        .map(|i| DVec3::new(i as f64 / 11.0 * 4.0, 0.0, 0.0))
        .collect();
    let c = BSplineCurve::new(kv, pts).unwrap();
    CurveDesign::new(
        c,
        CurveMaterial {
            beta,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn constraints_hold_on_a_curve() {
    let mut d = batten(1.0);
    let a = d.add_icon(0.0, CurveRole::Position).unwrap();
    let b = d.add_icon(1.0, CurveRole::Position).unwrap();
    let m = d.add_icon(0.5, CurveRole::Position).unwrap();
    let tan = d.add_icon(0.25, CurveRole::Tangent).unwrap();
    d.set_target(m, DVec3::new(2.0, 0.5, 0.0)).unwrap();
    d.set_target(tan, DVec3::new(4.0, 1.0, 0.0)).unwrap();
    let r = d.solve().unwrap();
    assert!(r.constraint_residual < 1e-9, "{r:?}");
    assert!((d.curve().point(0.5) - DVec3::new(2.0, 0.5, 0.0)).length() < 1e-9);
    assert!((d.curve().derivs(0.25).d1 - DVec3::new(4.0, 1.0, 0.0)).length() < 1e-9);
    assert!(d.curve().point(0.0).length() < 1e-9);
    assert!((d.icon(a).unwrap().xyz).length() < 1e-9);
    assert!((d.icon(b).unwrap().xyz - DVec3::new(4.0, 0.0, 0.0)).length() < 1e-9);
    // A sleeping constraint has no effect.
    let before = d.curve().clone();
    let s = d.add_icon(0.8, CurveRole::Position).unwrap();
    d.set_target(s, DVec3::new(3.0, 9.0, 9.0)).unwrap();
    d.set_state(s, IconState::Sleeping).unwrap();
    d.solve().unwrap();
    let gap = (0..=20)
        .map(|k| (d.curve().point(k as f64 / 20.0) - before.point(k as f64 / 20.0)).length())
        .fold(0.0, f64::max);
    assert!(gap < 1e-9);
}

#[test]
fn a_load_bends_the_batten_toward_the_hand_and_the_spring_adapts() {
    for beta in [0.01, 1.0, 100.0] {
        let mut d = batten(beta);
        d.add_icon(0.0, CurveRole::Position).unwrap();
        d.add_icon(1.0, CurveRole::Position).unwrap();
        let load = d.add_icon(0.5, CurveRole::Load).unwrap();
        d.set_kappa(1e-4).unwrap();
        let start = d.icon(load).unwrap().xyz;
        let hand = start + DVec3::new(0.0, 0.2, 0.0);
        let mut ratio = 0.0;
        for _ in 0..30 {
            let actual = d.drag(load, hand).unwrap();
            assert!(actual.y > 0.0, "bends toward the hand");
            ratio = (actual - start).length() / 0.2;
            if (0.8..=1.2).contains(&ratio) {
                break;
            }
        }
        assert!((0.8..=1.2).contains(&ratio), "β = {beta}: {ratio}");
        let kept = d.curve().clone();
        d.release(load).unwrap();
        d.solve().unwrap();
        assert!(
            (d.curve().point(0.5) - kept.point(0.5)).length() < 1e-9,
            "plastic"
        );
    }
}

fn max_gap(a: &BSplineCurve, b: &BSplineCurve) -> f64 {
    (0..=40)
        .map(|k| (a.point(k as f64 / 40.0) - b.point(k as f64 / 40.0)).length())
        .fold(0.0, f64::max)
}

#[test]
fn a_curve_design_is_a_value_snapshot_and_restore_round_trip() {
    let mut d = batten(1.0);
    d.add_icon(0.0, CurveRole::Position).unwrap();
    d.add_icon(1.0, CurveRole::Position).unwrap();
    let load = d.add_icon(0.5, CurveRole::Load).unwrap();
    d.solve().unwrap();
    let before = d.snapshot();
    // Sculpt: a load drag, released (plastic), and a new tangent icon.
    d.drag(load, DVec3::new(2.0, 0.8, 0.0)).unwrap();
    d.release(load).unwrap();
    d.add_icon(0.25, CurveRole::Tangent).unwrap();
    d.solve().unwrap();
    let after = d.snapshot();
    assert_ne!(after, before);
    assert!(
        max_gap(&after.curve, &before.curve) > 0.05,
        "the load moved the curve"
    );
    // Undo: exactly the old value, and solving it again keeps the old shape.
    d.restore(&before).unwrap();
    assert_eq!(d.snapshot(), before);
    d.solve().unwrap();
    assert!(max_gap(d.curve(), &before.curve) < 1e-12);
    // Redo.
    d.restore(&after).unwrap();
    assert_eq!(d.snapshot(), after);
    assert_eq!(d.icons().count(), 4);
    // A fresh design from the snapshot is the same value.
    let e = CurveDesign::from_snapshot(&after).unwrap();
    assert_eq!(e.snapshot(), after);
    // Bad snapshots are refused and change nothing.
    let mut bad = after.clone();
    bad.icons[0].t = 7.0;
    assert!(CurveDesign::from_snapshot(&bad).is_err());
    assert!(d.restore(&bad).is_err());
    let mut bad = after.clone();
    bad.reference[3].x = f64::NAN;
    assert!(d.restore(&bad).is_err());
    assert_eq!(d.snapshot(), after);
}

#[test]
fn removing_or_moving_an_icon_releases_what_it_held() {
    let mut d = batten(1.0);
    d.add_icon(0.0, CurveRole::Position).unwrap();
    d.add_icon(1.0, CurveRole::Position).unwrap();
    let pin = d.add_icon(0.5, CurveRole::Position).unwrap();
    let reference = d.curve().clone();
    d.set_target(pin, DVec3::new(2.0, 1.0, 0.0)).unwrap();
    d.solve().unwrap();
    assert!((d.curve().point(0.5) - DVec3::new(2.0, 1.0, 0.0)).length() < 1e-9);
    // Moved along the curve, the pin holds the curve where it now is.
    d.set_parameter(pin, 0.3).unwrap();
    let held = d.curve().point(0.3);
    d.solve().unwrap();
    assert!((d.curve().point(0.3) - held).length() < 1e-9);
    assert!((d.icon(pin).unwrap().xyz - held).length() < 1e-9);
    assert!(d.set_parameter(pin, 1.5).is_err());
    assert!(d.set_parameter(pin, f64::NAN).is_err());
    // Deleted, nothing holds the displacement: the curve relaxes to its
    // reference (a constraint's pull is elastic; only loads are plastic).
    let removed = d.remove_icon(pin).unwrap();
    assert_eq!(removed.id, pin);
    d.solve().unwrap();
    assert!(max_gap(d.curve(), &reference) < 1e-9);
    assert!(d.remove_icon(pin).is_err());
}

#[test]
fn sensors_drive_icons_and_states_keep_the_papers_semantics() {
    use vsculpt_kernel::icon::SensorId;
    let mut d = batten(1.0);
    d.add_icon(0.0, CurveRole::Position).unwrap();
    d.add_icon(1.0, CurveRole::Position).unwrap();
    let pin = d.add_icon(0.5, CurveRole::Position).unwrap();
    let glove = SensorId("glove-1".into());
    d.bind_sensor(pin, glove.clone()).unwrap();
    assert_eq!(d.icon(pin).unwrap().state, IconState::Driving);
    assert_eq!(d.icon(pin).unwrap().sensors, vec![glove.clone()]);
    d.drag(pin, DVec3::new(2.0, 0.6, 0.0)).unwrap();
    d.unbind_sensor(pin, &glove).unwrap();
    // Released: passive, no sensors, and it still holds where it was put.
    let icon = d.icon(pin).unwrap();
    assert_eq!(icon.state, IconState::Passive);
    assert!(icon.sensors.is_empty());
    d.solve().unwrap();
    assert!((d.curve().point(0.5) - DVec3::new(2.0, 0.6, 0.0)).length() < 1e-9);
    // A passive load follows the curve; going to sleep, an icon holds
    // nothing and its target is re-taken from the curve.
    let load = d.add_icon(0.8, CurveRole::Load).unwrap();
    d.set_target(pin, DVec3::new(2.0, 0.9, 0.0)).unwrap();
    d.solve().unwrap();
    assert!((d.icon(load).unwrap().xyz - d.curve().point(0.8)).length() < 1e-12);
    let shape = d.curve().clone();
    d.set_state(pin, IconState::Sleeping).unwrap();
    assert!((d.icon(pin).unwrap().target - d.curve().point(0.5)).length() < 1e-12);
    d.solve().unwrap();
    // Nothing else pulls: the curve relaxes to its reference, not held at 0.9.
    assert!((d.curve().point(0.5) - shape.point(0.5)).length() > 0.1);
    assert!(d.bind_sensor(IconId(99), glove.clone()).is_err());
}

#[test]
fn an_interval_constraint_keeps_its_span_and_an_interval_load_pulls_it() {
    let mut d = batten(1.0);
    d.add_icon(0.0, CurveRole::Position).unwrap();
    d.add_icon(1.0, CurveRole::Position).unwrap();
    let span = d.add_interval(0.55, 0.3, CurveRole::Position).unwrap();
    let icon = d.icon(span).unwrap().clone();
    assert_eq!(icon.span, Some((0.3, 0.55)));
    assert!(icon.samples.len() >= 3, "{:?}", icon.samples);
    assert_eq!(icon.shape.len(), icon.samples.len());
    // Lift the span: every sample moves by the lift (the shape is kept).
    let lift = DVec3::new(0.0, 0.5, 0.2);
    d.set_target(span, icon.target + lift).unwrap();
    let r = d.solve().unwrap();
    assert!(r.constraint_residual < 1e-9, "{r:?}");
    for (&t, &p) in icon.samples.iter().zip(&icon.shape) {
        assert!((d.curve().point(t) - (p + lift)).length() < 1e-9, "t = {t}");
    }
    // Between samples the span follows nearly as well; outside it, the
    // batten bends smoothly back to its pinned ends.
    assert!((d.curve().point(0.42) - (icon_point(&icon, 0.42) + lift)).length() < 0.02);
    assert!(d.curve().point(0.9).y < lift.y);
    assert!((d.icon(span).unwrap().xyz - (icon.xyz + lift)).length() < 1e-9);

    // An interval load pulls the whole span toward the hand, plastically.
    let mut d = batten(1.0);
    d.add_icon(0.0, CurveRole::Position).unwrap();
    d.add_icon(1.0, CurveRole::Position).unwrap();
    let load = d.add_interval(0.6, 0.8, CurveRole::Load).unwrap();
    let grabbed = d.icon(load).unwrap().xyz;
    let hand = grabbed + DVec3::new(0.0, 1.0, 0.0);
    let reached = d.drag(load, hand).unwrap();
    assert!(reached.y > 0.2, "pulled toward the hand: {reached}");
    for t in [0.6, 0.65, 0.7, 0.75, 0.8] {
        assert!(
            d.curve().point(t).y > 0.1,
            "t = {t}: {}",
            d.curve().point(t)
        );
    }
    assert!(d.curve().point(0.1).y < d.curve().point(0.7).y);
    d.release(load).unwrap();
    let kept = d.curve().clone();
    d.solve().unwrap();
    assert!(
        max_gap(d.curve(), &kept) < 1e-9,
        "released: the shape stays"
    );
    assert_eq!(d.reference(), kept.points());
    // A value like any other.
    let snap = d.snapshot();
    let e = CurveDesign::from_snapshot(&snap).unwrap();
    assert_eq!(e.snapshot(), snap);
}

/// Where an icon's span pointed before it moved: its shape, interpolated
/// linearly between samples.
fn icon_point(icon: &vsculpt_kernel::curve_design::CurveIcon, t: f64) -> DVec3 {
    let k = icon.samples.iter().rposition(|&s| s <= t).unwrap();
    let (t0, t1) = (icon.samples[k], icon.samples[k + 1]);
    icon.shape[k].lerp(icon.shape[k + 1], (t - t0) / (t1 - t0))
}

#[test]
fn bad_interval_icons_are_refused_and_change_nothing() {
    let mut d = batten(1.0);
    let snap = d.snapshot();
    assert!(d.add_interval(0.2, 0.2, CurveRole::Position).is_err());
    assert!(d.add_interval(0.2, 1.5, CurveRole::Load).is_err());
    assert!(d.add_interval(f64::NAN, 0.5, CurveRole::Load).is_err());
    assert!(d.add_interval(0.2, 0.4, CurveRole::Tangent).is_err());
    assert_eq!(d.snapshot(), snap);
    let span = d.add_interval(0.2, 0.4, CurveRole::Position).unwrap();
    assert!(d.set_role(span, CurveRole::Second).is_err());
    assert!(
        d.set_parameter(span, 0.95).is_err(),
        "the span would leave the curve"
    );
    d.set_parameter(span, 0.5).unwrap();
    let (a, b) = d.icon(span).unwrap().span.unwrap();
    assert!(
        (a - 0.4).abs() < 1e-12 && (b - 0.6).abs() < 1e-12,
        "({a}, {b})"
    );
}
