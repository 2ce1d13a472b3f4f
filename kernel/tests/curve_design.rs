//! Icons on a deformable curve (paper 003 sculpts curves too).

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, KnotVector};
use vsculpt_kernel::curve_design::{CurveDesign, CurveRole};
use vsculpt_kernel::energy::CurveMaterial;
use vsculpt_kernel::icon::IconState;

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
