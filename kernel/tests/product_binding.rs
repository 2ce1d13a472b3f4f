//! A curve part bound to a surface part: the surface's parameter line is
//! the curve, checked at 200 points along it (between knots and control
//! points), after binding and after every frame of a drag of the curve.

mod product_support;

use glam::DVec3;
use product_support::*;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::curve_design::CurveRole;
use vsculpt_kernel::icon::Role;
use vsculpt_kernel::product::{
    BindingSpec, ChangedParts, Continuity, Edge, IsoLine, JoinSpec, PartId, Product, ProductError,
    iso_curve, map_parameter,
};

/// The largest distance between the curve and the surface's line at 200
/// points, relative to the model's size.
fn line_gap(p: &Product, spec: &BindingSpec) -> f64 {
    let s = p.surface(spec.surface).unwrap().surface();
    let c = p.curve(spec.curve).unwrap().curve();
    let (t0, t1) = c.domain();
    let mut gap = 0.0f64;
    for k in 0..200 {
        let t = t0 + (t1 - t0) * (k as f64 + 0.37) / 200.0;
        let on_line = map_parameter(c.knots(), spec.line.knots(s), spec.reversed, t);
        gap = gap.max((spec.line.point(s, on_line) - c.point(t)).length());
    }
    gap / model_size(p)
}

fn moved(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

/// A surface pinned at its corners and a curve on its v knots over [0, 3]
/// (an affine reparameterisation), lifted off the line u = 0.4.
fn scene(reversed: bool) -> (Product, PartId, PartId, BindingSpec) {
    let mut p = Product::new();
    let s = panel(0.0, 8, v_knots(1.0), 0.0, 0.1);
    let line = IsoLine::U(0.4);
    let on = iso_curve(&s, line).unwrap();
    let surface = p.add_part(surface_part(s));
    p.edit_surface(surface, |d| {
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            d.add_icon(point(u, v, Role::Position))?;
        }
        Ok(())
    })
    .unwrap();
    let mut pts: Vec<DVec3> = on
        .points()
        .iter()
        .enumerate()
        .map(|(j, q)| *q + DVec3::new(0.03 * j as f64, 0.0, 0.08))
        .collect();
    let knots: Vec<f64> = on.knots().knots().iter().map(|t| 3.0 * t).collect();
    let mut knots = KnotVector::new(3, knots).unwrap();
    if reversed {
        pts.reverse();
        let k: Vec<f64> = knots.knots().iter().rev().map(|t| 3.0 - t).collect();
        knots = KnotVector::new(3, k).unwrap();
    }
    let curve = p.add_part(curve_part(knots, pts));
    let spec = BindingSpec {
        curve,
        surface,
        line,
        reversed,
    };
    (p, surface, curve, spec)
}

#[test]
fn a_bound_surface_follows_its_curve_at_200_points_after_every_drag_frame() {
    for reversed in [false, true] {
        let (mut p, surface, curve, spec) = scene(reversed);
        assert!(
            line_gap(&p, &spec) > 0.01,
            "the curve starts off the surface"
        );
        let before = p.control_points(surface).unwrap().to_vec();
        let (id, changed) = p.bind(spec).unwrap();
        assert_eq!(changed, ChangedParts::one(surface));
        assert_eq!(p.binding(id).unwrap().spec, spec);
        let gap = line_gap(&p, &spec);
        assert!(gap < 1e-9, "bound: {gap:e}");
        assert!(moved(&before, p.control_points(surface).unwrap()) > 0.05);
        // Drag the curve's middle (a position icon) and one end (a load).
        let (t0, t1) = p.curve(curve).unwrap().curve().domain();
        for (t, role, step) in [
            (
                0.5 * (t0 + t1),
                CurveRole::Position,
                DVec3::new(0.0, 0.01, 0.04),
            ),
            (
                t0 + 0.1 * (t1 - t0),
                CurveRole::Load,
                DVec3::new(0.0, 0.0, -0.05),
            ),
        ] {
            let icon = p.edit_curve(curve, |d| d.add_icon(t, role)).unwrap();
            assert_eq!(icon.changed, ChangedParts::from_ids([surface, curve]));
            let icon = icon.value;
            let start = p.curve(curve).unwrap().icon(icon).unwrap().xyz;
            let shape = p.control_points(surface).unwrap().to_vec();
            for k in 1..=6 {
                let r = p.drag(curve, icon, start + step * k as f64).unwrap();
                assert_eq!(r.changed, ChangedParts::from_ids([surface, curve]));
                let gap = line_gap(&p, &spec);
                assert!(gap < 1e-9, "reversed {reversed}, frame {k}: {gap:e}");
            }
            p.release(curve, icon).unwrap();
            assert!(line_gap(&p, &spec) < 1e-9);
            assert!(
                moved(&shape, p.control_points(surface).unwrap()) > 1e-2,
                "the surface follows the curve"
            );
        }
        // An edit of the curve (a new target) re-solves the surface too.
        let e = p
            .edit_curve(curve, |d| {
                let id = d.add_icon(0.3 * t1 + 0.7 * t0, CurveRole::Position)?;
                let t = d.icon(id).unwrap().target + DVec3::Z * 0.1;
                d.set_target(id, t)
            })
            .unwrap();
        assert_eq!(e.changed, ChangedParts::from_ids([surface, curve]));
        assert!(line_gap(&p, &spec) < 1e-9);
        // Icons on the surface still work with the binding held.
        let pull = p
            .edit_surface(surface, |d| d.add_icon(point(0.7, 0.5, Role::Load)))
            .unwrap()
            .value;
        let at = p.surface(surface).unwrap().icon(pull).unwrap().xyz;
        for k in 1..=3 {
            p.drag(surface, pull, at + DVec3::Z * 0.05 * k as f64)
                .unwrap();
            assert!(line_gap(&p, &spec) < 1e-9);
        }
        p.release(surface, pull).unwrap();
        // Unbinding keeps the shape; the curve then moves alone.
        let shape = p.control_points(surface).unwrap().to_vec();
        p.unbind(id).unwrap();
        p.solve(surface).unwrap();
        assert!(moved(&shape, p.control_points(surface).unwrap()) < 1e-9);
        let icon = p.curve(curve).unwrap().icons().next().unwrap().id;
        let r = p.drag(curve, icon, DVec3::new(0.4, 0.5, 1.0)).unwrap();
        assert_eq!(r.changed, ChangedParts::one(curve));
        assert!(line_gap(&p, &spec) > 1e-3);
    }
}

#[test]
fn a_curve_taken_from_the_surface_binds_without_moving_it() {
    let mut p = Product::new();
    let s = panel(0.0, 8, v_knots(1.0), 0.0, 0.1);
    let line = IsoLine::V(0.62);
    let on: BSplineCurve = iso_curve(&s, line).unwrap();
    assert!(matches!(
        iso_curve(&s, IsoLine::U(1.5)),
        Err(ProductError::Incompatible(_))
    ));
    for k in 0..50 {
        let t = (k as f64 + 0.3) / 50.0;
        assert!((on.point(t) - s.point(t, 0.62)).length() < 1e-14);
    }
    let surface = p.add_part(surface_part(s.clone()));
    let curve = p.add_part(curve_part(on.knots().clone(), on.points().to_vec()));
    let spec = BindingSpec {
        curve,
        surface,
        line,
        reversed: false,
    };
    p.bind(spec).unwrap();
    assert!(moved(s.points(), p.control_points(surface).unwrap()) < 1e-12);
    assert!(line_gap(&p, &spec) < 1e-12);
}

#[test]
fn a_curve_bound_across_a_joined_pair_holds_both_and_the_seam() {
    let mut p = Product::new();
    let sa: BSplineSurface = panel(0.0, 8, v_knots(1.0), 0.0, 0.1);
    let sb = panel(1.05, 6, v_knots(2.0), 0.12, -0.2);
    let a = p.add_part(surface_part(sa));
    let b = p.add_part(surface_part(sb));
    p.join(JoinSpec {
        a,
        edge_a: Edge::UMax,
        b,
        edge_b: Edge::UMin,
        reversed: false,
        continuity: Continuity::G1,
        ratio: None,
    })
    .unwrap();
    let line = IsoLine::U(0.5);
    let on = iso_curve(p.surface(b).unwrap().surface(), line).unwrap();
    let curve = p.add_part(curve_part(on.knots().clone(), on.points().to_vec()));
    let spec = BindingSpec {
        curve,
        surface: b,
        line,
        reversed: false,
    };
    let (_, changed) = p.bind(spec).unwrap();
    assert_eq!(changed, ChangedParts::from_ids([a, b]));
    let icon = p
        .edit_curve(curve, |d| d.add_icon(1.0, CurveRole::Position))
        .unwrap()
        .value;
    let start = p.curve(curve).unwrap().icon(icon).unwrap().xyz;
    let a0 = p.control_points(a).unwrap().to_vec();
    for k in 1..=5 {
        let r = p
            .drag(curve, icon, start + DVec3::Z * 0.04 * k as f64)
            .unwrap();
        assert_eq!(r.changed, ChangedParts::from_ids([a, b, curve]));
        assert!(line_gap(&p, &spec) < 1e-9);
        let (gap, ang) = seam_gaps(
            p.surface(a).unwrap().surface(),
            Edge::UMax,
            p.surface(b).unwrap().surface(),
            Edge::UMin,
            false,
            50,
        );
        assert!(gap < 1e-9 * model_size(&p) && ang < 1e-9, "{gap} {ang}");
    }
    assert!(
        moved(&a0, p.control_points(a).unwrap()) > 1e-2,
        "A follows through the seam"
    );
}
