//! A product of 3 surfaces and 2 curves: each part edited alone changes
//! only itself; a part with no relation drags exactly as the same design
//! alone; incompatible edges and lines are refused with the documented
//! error and change nothing; removing a part removes its relations.

mod product_support;

use glam::DVec3;
use product_support::*;
use vsculpt_kernel::bspline::KnotVector;
use vsculpt_kernel::curve_design::CurveRole;
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::Role;
use vsculpt_kernel::product::{
    BindingSpec, ChangedParts, Continuity, Edge, IsoLine, JoinSpec, Part, PartId, PartKind,
    Product, ProductError,
};

struct Scene {
    p: Product,
    a: PartId,
    b: PartId,
    c: PartId,
    line: PartId,
    arc: PartId,
}

/// A and B fit along A's UMax / B's UMin; C has 9 control points along v
/// (fits neither). `line` is a cubic curve on A's v knots (bindable along
/// A's u lines); `arc` a quadratic one.
fn scene() -> Scene {
    let mut p = Product::new();
    let a = p.add_part(surface_part(panel(0.0, 8, v_knots(1.0), 0.0, 0.1)));
    let b = p.add_part(surface_part(panel(1.05, 6, v_knots(2.0), 0.12, -0.2)));
    let c = p.add_part(surface_part(panel(
        -1.2,
        5,
        KnotVector::clamped_uniform(3, 9).unwrap(),
        0.0,
        0.0,
    )));
    let line = p.add_part(curve_part(
        v_knots(1.0),
        (0..7)
            .map(|j| DVec3::new(0.5, j as f64 / 6.0, 0.3))
            .collect(),
    ));
    let arc = p.add_part(curve_part(
        KnotVector::clamped_uniform(2, 5).unwrap(),
        (0..5)
            .map(|j| {
                let t = j as f64 / 4.0 * std::f64::consts::PI;
                DVec3::new(t.cos(), t.sin(), 1.0)
            })
            .collect(),
    ));
    Scene {
        p,
        a,
        b,
        c,
        line,
        arc,
    }
}

#[test]
fn each_part_is_edited_alone_and_reports_only_itself() {
    let Scene {
        mut p,
        a,
        b,
        c,
        line,
        arc,
    } = scene();
    assert_eq!(p.len(), 5);
    assert_eq!(p.part(line).unwrap().kind(), PartKind::Curve);
    assert_eq!(p.part(c).unwrap().kind(), PartKind::Surface);
    for (k, s) in [a, b, c].into_iter().enumerate() {
        let before = all_points(&p);
        let (u, v) = (0.5, 0.5 * p.surface(s).unwrap().surface().domain().1.1);
        let want = p.surface(s).unwrap().surface().point(u, v)
            + DVec3::new(0.0, 0.0, 0.1 + k as f64 * 0.05);
        let e = p
            .edit_surface(s, |d| {
                let id = d.add_icon(point(u, v, Role::Position))?;
                d.set_target(id, want)?;
                Ok(id)
            })
            .unwrap();
        assert_eq!(e.changed, ChangedParts::one(s));
        let got = p.surface(s).unwrap().surface().point(u, v);
        assert!((got - want).length() < 1e-9, "part {s:?}: {got} vs {want}");
        for (id, pts) in &before {
            if *id != s {
                assert_eq!(p.control_points(*id).unwrap(), &pts[..], "{id:?} untouched");
            }
        }
    }
    for cv in [line, arc] {
        let before = all_points(&p);
        let e = p
            .edit_curve(cv, |d| {
                let id = d.add_icon(0.5, CurveRole::Position)?;
                let t = d.icon(id).unwrap().target + DVec3::new(0.0, 0.0, 0.2);
                d.set_target(id, t)?;
                Ok((id, t))
            })
            .unwrap();
        assert_eq!(e.changed, ChangedParts::one(cv));
        let got = p.curve(cv).unwrap().curve().point(0.5);
        assert!(
            (got - e.value.1).length() < 1e-9,
            "{got} vs {:?}",
            e.value.1
        );
        for (id, pts) in &before {
            if *id != cv {
                assert_eq!(p.control_points(*id).unwrap(), &pts[..]);
            }
        }
        // A drag frame on a curve moves only that curve (nothing bound).
        let r = p.drag(cv, e.value.0, e.value.1 + DVec3::X * 0.1).unwrap();
        assert_eq!(r.changed, ChangedParts::one(cv));
        p.release(cv, e.value.0).unwrap();
    }
    // Wrong kinds and unknown parts are refused.
    assert_eq!(
        p.edit_curve(a, |_| Ok(())).unwrap_err(),
        ProductError::WrongKind {
            part: a,
            expected: PartKind::Curve
        }
    );
    assert_eq!(
        p.edit_surface(PartId(99), |_| Ok(())).unwrap_err(),
        ProductError::UnknownPart(PartId(99))
    );
    // A refused part edit changes nothing.
    let before = all_points(&p);
    assert!(
        p.edit_surface(a, |d| d.add_icon(point(3.0, 0.5, Role::Position)))
            .is_err()
    );
    assert_eq!(all_points(&p), before);
    assert_eq!(p.surface(a).unwrap().icons().count(), 1);
    // A closure failing half-way on a curve leaves nothing behind either.
    let n = p.curve(line).unwrap().icons().count();
    assert!(
        p.edit_curve(line, |d| {
            d.add_icon(0.2, CurveRole::Position)?;
            d.add_icon(7.0, CurveRole::Position)
        })
        .is_err()
    );
    assert_eq!(p.curve(line).unwrap().icons().count(), n);
    assert_eq!(all_points(&p), before);
}

#[test]
fn a_drag_on_an_unjoined_part_is_the_same_design_dragged_alone() {
    let Scene { mut p, a, b, .. } = scene();
    // Another pair of the product is joined (B to a new panel D): A stays alone.
    let d = p.add_part(surface_part(panel(2.1, 5, v_knots(1.0), 0.0, 0.0)));
    p.join(JoinSpec {
        a: b,
        edge_a: Edge::UMax,
        b: d,
        edge_b: Edge::UMin,
        reversed: false,
        continuity: Continuity::G1,
        ratio: None,
    })
    .unwrap();
    assert_eq!(p.solved_with(a), ChangedParts::one(a));
    let mut alone = Design::new(
        panel(0.0, 8, v_knots(1.0), 0.0, 0.1),
        SurfaceMaterial::default(),
    )
    .unwrap();
    let spec = point(0.3, 0.6, Role::Load);
    let pin = point(0.0, 0.0, Role::Position);
    let ia = p
        .edit_surface(a, |d| {
            d.add_icon(pin.clone())?;
            d.add_icon(spec.clone())
        })
        .unwrap()
        .value;
    alone.add_icon(pin).unwrap();
    let ib = alone.add_icon(spec).unwrap();
    alone.solve().unwrap();
    assert_eq!(ia, ib);
    let start = alone.icon(ib).unwrap().xyz;
    for k in 1..=5 {
        let xyz = start + DVec3::new(0.0, 0.02, 0.05) * k as f64;
        let r1 = p.drag(a, ia, xyz).unwrap();
        let r2 = alone.drag(ib, xyz).unwrap();
        assert_eq!(r1.changed, ChangedParts::one(a));
        assert_eq!(r1.actual, r2.actual);
        assert_eq!(r1.report, Some(r2.report));
        assert_eq!(p.control_points(a).unwrap(), alone.surface().points());
    }
}

#[test]
fn incompatible_edges_and_lines_are_refused_and_change_nothing() {
    let Scene {
        mut p,
        a,
        b,
        c,
        line,
        arc,
    } = scene();
    let before = all_points(&p);
    let join = |a, ea, b, eb| JoinSpec {
        a,
        edge_a: ea,
        b,
        edge_b: eb,
        reversed: false,
        continuity: Continuity::G1,
        ratio: None,
    };
    // 7 control points along A's UMax against 9 along C's UMin.
    let e = p.join(join(a, Edge::UMax, c, Edge::UMin)).unwrap_err();
    assert!(
        matches!(&e, ProductError::Incompatible(m) if m.contains("7 control points against 9")),
        "{e}"
    );
    // Same count (A's VMax runs along u: 8; a 8-point cubic clamped
    // uniform v for a new panel D), but B's UMin has non-uniform knots.
    let d = p.add_part(surface_part(panel(
        0.0,
        5,
        KnotVector::clamped_uniform(3, 7).unwrap(),
        0.0,
        0.0,
    )));
    let before_d = all_points(&p);
    let e = p.join(join(b, Edge::UMin, d, Edge::UMin)).unwrap_err();
    assert!(
        matches!(&e, ProductError::Incompatible(m) if m.contains("knot")),
        "{e}"
    );
    // Different degree: a quadratic edge against a cubic one.
    let q = p.add_part(surface_part({
        let u = KnotVector::clamped_uniform(2, 8).unwrap();
        let v = KnotVector::clamped_uniform(2, 7).unwrap();
        let mut s = vsculpt_kernel::bspline::BSplineSurface::plane(1.0, 1.0, 8, 7, 2).unwrap();
        s = vsculpt_kernel::bspline::BSplineSurface::new(u, v, s.points().to_vec()).unwrap();
        s
    }));
    let before_q = all_points(&p);
    let e = p.join(join(a, Edge::UMax, q, Edge::UMin)).unwrap_err();
    assert!(
        matches!(&e, ProductError::Incompatible(m) if m.contains("degree 3 against 2")),
        "{e}"
    );
    // A reversed non-symmetric knot vector does not fit itself unreversed.
    let e = p
        .join(JoinSpec {
            reversed: true,
            ..join(a, Edge::UMax, b, Edge::UMin)
        })
        .unwrap_err();
    assert!(
        matches!(&e, ProductError::Incompatible(m) if m.contains("reversed")),
        "{e}"
    );
    // An edge joined to itself; a curve's kind; a line off the surface.
    assert!(matches!(
        p.join(join(a, Edge::UMax, a, Edge::UMax)).unwrap_err(),
        ProductError::Incompatible(_)
    ));
    assert_eq!(
        p.join(join(a, Edge::UMax, line, Edge::UMin)).unwrap_err(),
        ProductError::WrongKind {
            part: line,
            expected: PartKind::Surface
        }
    );
    let bind = |curve, surface, line| BindingSpec {
        curve,
        surface,
        line,
        reversed: false,
    };
    // The quadratic arc does not fit A's cubic u lines; the cubic line
    // does not fit A's v lines (8 uniform points); u = 1.5 is off A.
    for spec in [
        bind(arc, a, IsoLine::U(0.5)),
        bind(line, a, IsoLine::V(0.5)),
        bind(line, a, IsoLine::U(1.5)),
    ] {
        let e = p.bind(spec).unwrap_err();
        assert!(matches!(e, ProductError::Incompatible(_)), "{e}");
    }
    assert_eq!(
        p.bind(bind(a, a, IsoLine::U(0.5))).unwrap_err(),
        ProductError::WrongKind {
            part: a,
            expected: PartKind::Curve
        }
    );
    // Nothing changed: shapes, relations, groups.
    let now = all_points(&p);
    for (id, pts) in before.iter().chain(&before_d).chain(&before_q) {
        assert_eq!(&now[id], pts);
    }
    assert_eq!(p.joins().count(), 0);
    assert_eq!(p.bindings().count(), 0);
    for id in [a, b, c, d, q] {
        assert_eq!(p.solved_with(id), ChangedParts::one(id));
    }
}

#[test]
fn removing_a_joined_part_removes_its_joins_and_bindings() {
    let Scene {
        mut p,
        a,
        b,
        c,
        line,
        ..
    } = scene();
    let (j, _) = p
        .join(JoinSpec {
            a,
            edge_a: Edge::UMax,
            b,
            edge_b: Edge::UMin,
            reversed: false,
            continuity: Continuity::G1,
            ratio: None,
        })
        .unwrap();
    let (bd, _) = p
        .bind(BindingSpec {
            curve: line,
            surface: a,
            line: IsoLine::U(0.5),
            reversed: false,
        })
        .unwrap();
    assert_eq!(p.solved_with(b), ChangedParts::from_ids([a, b]));
    let before = all_points(&p);
    let removed = p.remove_part(a).unwrap();
    assert!(matches!(removed.part, Part::Surface(_)));
    assert_eq!(removed.joins.len(), 1);
    assert_eq!(removed.joins[0].0, j);
    assert_eq!(removed.bindings.len(), 1);
    assert_eq!(removed.bindings[0].0, bd);
    assert_eq!(removed.changed, ChangedParts::one(b));
    assert_eq!(p.joins().count(), 0);
    assert_eq!(p.bindings().count(), 0);
    assert!(p.part(a).is_none());
    assert_eq!(p.remove_part(a).unwrap_err(), ProductError::UnknownPart(a));
    // B is alone again and keeps its shape; the curve does not drive anything.
    assert_eq!(p.solved_with(b), ChangedParts::one(b));
    p.solve(b).unwrap();
    let gap = before[&b]
        .iter()
        .zip(p.control_points(b).unwrap())
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max);
    assert!(gap < 1e-9, "{gap}");
    let id = p
        .edit_curve(line, |d| d.add_icon(0.3, CurveRole::Position))
        .unwrap();
    assert_eq!(id.changed, ChangedParts::one(line));
    // Ids are not reused.
    let n = p.add_part(surface_part(panel(3.0, 5, v_knots(1.0), 0.0, 0.0)));
    assert!(n.0 > c.0 && n != a);
    // A removed curve takes its bindings along.
    let (b2, _) = p
        .bind(BindingSpec {
            curve: line,
            surface: n,
            line: IsoLine::U(0.0),
            reversed: false,
        })
        .unwrap();
    let removed = p.remove_part(line).unwrap();
    assert_eq!(removed.bindings[0].0, b2);
    assert_eq!(removed.changed, ChangedParts::one(n));
    assert_eq!(p.solved_with(n), ChangedParts::one(n));
}
