//! A product is rebuilt from its parts' snapshots, joins and bindings
//! (what a server stores): the rebuilt product solves to the same shapes
//! and goes on dragging as the original does.

mod product_support;

use glam::DVec3;
use product_support::*;
use vsculpt_kernel::curve_design::{CurveDesign, CurveRole};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::icon::Role;
use vsculpt_kernel::product::{
    BindingSpec, Continuity, Edge, IsoLine, JoinSpec, Part, Product, ProductError, iso_curve,
};

fn gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

#[test]
fn a_product_rebuilt_from_parts_joins_and_bindings_solves_to_the_same_shapes() {
    let mut p = Product::new();
    let a = p.add_part(surface_part(panel(0.0, 8, v_knots(1.0), 0.0, 0.1)));
    let b = p.add_part(surface_part(panel(1.05, 6, v_knots(2.0), 0.12, -0.2)));
    let lone = p.add_part(surface_part(panel(-2.0, 6, v_knots(1.0), 0.0, 0.0)));
    let on = iso_curve(p.surface(a).unwrap().surface(), IsoLine::U(0.3)).unwrap();
    let curve = p.add_part(curve_part(on.knots().clone(), on.points().to_vec()));
    let (jid, _) = p
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
    let spec = BindingSpec {
        curve,
        surface: a,
        line: IsoLine::U(0.3),
        reversed: false,
    };
    let (bid, _) = p.bind(spec).unwrap();
    // Sculpt: a constraint dragged on B, a load on the lone part, the curve.
    let pin = p
        .edit_surface(b, |d| d.add_icon(point(0.5, 1.0, Role::Position)))
        .unwrap()
        .value;
    let at = p.surface(b).unwrap().icon(pin).unwrap().xyz;
    p.drag(b, pin, at + DVec3::Z * 0.2).unwrap();
    p.release(b, pin).unwrap();
    let load = p
        .edit_surface(lone, |d| d.add_icon(point(0.5, 0.5, Role::Load)))
        .unwrap()
        .value;
    let at = p.surface(lone).unwrap().icon(load).unwrap().xyz;
    p.drag(lone, load, at + DVec3::Z * 0.3).unwrap();
    p.release(lone, load).unwrap();
    let ci = p
        .edit_curve(curve, |d| d.add_icon(0.5, CurveRole::Position))
        .unwrap()
        .value;
    let at = p.curve(curve).unwrap().icon(ci).unwrap().xyz;
    p.drag(curve, ci, at + DVec3::new(0.0, 0.05, 0.15)).unwrap();
    p.release(curve, ci).unwrap();
    let shapes = all_points(&p);

    // What a server stores: each part's snapshot, the joins, the bindings.
    let mut q = Product::new();
    for (id, part) in p.parts() {
        let rebuilt = match part {
            Part::Surface(d) => Part::Surface(Design::from_snapshot(&d.snapshot()).unwrap()),
            Part::Curve(c) => Part::Curve(CurveDesign::from_snapshot(&c.snapshot()).unwrap()),
        };
        q.insert_part(id, rebuilt).unwrap();
    }
    for (id, join) in p.joins() {
        q.insert_join(id, *join).unwrap();
    }
    for (id, binding) in p.bindings() {
        q.insert_binding(id, binding.spec).unwrap();
    }
    assert_eq!(
        q.insert_join(jid, *p.join_of(jid).unwrap()).unwrap_err(),
        ProductError::DuplicateJoin(jid)
    );
    assert_eq!(
        q.insert_binding(bid, spec).unwrap_err(),
        ProductError::DuplicateBinding(bid)
    );
    q.solve_all().unwrap();
    let size = model_size(&q);
    for (id, pts) in &shapes {
        let g = gap(pts, q.control_points(*id).unwrap());
        assert!(g < 1e-9 * size, "part {id:?} moved by {g:e} on rebuild");
    }
    assert_eq!(q.solved_with(a), p.solved_with(a));
    assert_eq!(q.join_of(jid), p.join_of(jid));
    // Both go on alike: the same drag frame gives the same shapes.
    for prod in [&mut p, &mut q] {
        let at = prod.surface(b).unwrap().icon(pin).unwrap().xyz;
        prod.drag(b, pin, at + DVec3::Y * 0.05).unwrap();
    }
    for id in shapes.keys() {
        let g = gap(
            p.control_points(*id).unwrap(),
            q.control_points(*id).unwrap(),
        );
        assert!(g < 1e-9 * size, "part {id:?}: {g:e}");
    }
    // New ids continue after the restored ones.
    let n = q.add_part(surface_part(panel(5.0, 5, v_knots(1.0), 0.0, 0.0)));
    assert!(shapes.keys().all(|k| k.0 < n.0));
}

#[test]
fn undo_across_parts_restores_every_part_and_refuses_what_no_longer_fits() {
    use vsculpt_kernel::product::{PartKind, PartSnapshot};
    let mut p = Product::new();
    let a = p.add_part(surface_part(panel(0.0, 8, v_knots(1.0), 0.0, 0.1)));
    let b = p.add_part(surface_part(panel(1.05, 6, v_knots(2.0), 0.12, -0.2)));
    let on = iso_curve(p.surface(b).unwrap().surface(), IsoLine::U(0.5)).unwrap();
    let curve = p.add_part(curve_part(on.knots().clone(), on.points().to_vec()));
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
    p.bind(BindingSpec {
        curve,
        surface: b,
        line: IsoLine::U(0.5),
        reversed: false,
    })
    .unwrap();
    let version: Vec<_> = p.parts().map(|(id, part)| (id, part.snapshot())).collect();
    let shapes = all_points(&p);
    // Sculpt across the parts: a seam icon on A, the curve.
    let icon = p
        .edit_surface(a, |d| d.add_icon(point(1.0, 0.5, Role::Position)))
        .unwrap()
        .value;
    let at = p.surface(a).unwrap().icon(icon).unwrap().xyz;
    p.drag(a, icon, at + DVec3::Z * 0.2).unwrap();
    p.release(a, icon).unwrap();
    let ci = p
        .edit_curve(curve, |d| d.add_icon(0.5, CurveRole::Position))
        .unwrap()
        .value;
    let at = p.curve(curve).unwrap().icon(ci).unwrap().xyz;
    p.drag(curve, ci, at + DVec3::Z * 0.1).unwrap();
    p.release(curve, ci).unwrap();
    let sculpted = all_points(&p);
    assert!(gap(&shapes[&b], &sculpted[&b]) > 0.05);
    // A snapshot that no longer fits (A refined: 11 × 10 points) is refused.
    let mut refined = Design::from_snapshot(&p.surface(a).unwrap().snapshot()).unwrap();
    refined.refine().unwrap();
    let e = p
        .restore_part(a, &PartSnapshot::Surface(refined.snapshot()))
        .unwrap_err();
    assert!(matches!(e, ProductError::Incompatible(_)), "{e}");
    assert_eq!(
        p.restore_part(curve, &version[0].1).unwrap_err(),
        ProductError::WrongKind {
            part: curve,
            expected: PartKind::Surface
        }
    );
    assert_eq!(all_points(&p), sculpted);
    assert_eq!(p.surface(a).unwrap().icons().count(), 1);
    // Undo: every part back to the version, then one solve.
    for (id, s) in &version {
        p.restore_part(*id, s).unwrap();
    }
    p.solve_all().unwrap();
    for (id, pts) in &shapes {
        let g = gap(pts, p.control_points(*id).unwrap());
        assert!(g < 1e-9 * model_size(&p), "{id:?}: {g:e}");
    }
    assert_eq!(p.surface(a).unwrap().icons().count(), 0);
    assert_eq!(p.curve(curve).unwrap().icons().count(), 0);
    // The group still holds: a new drag keeps the seam and the curve.
    let icon = p
        .edit_surface(b, |d| d.add_icon(point(0.2, 1.0, Role::Position)))
        .unwrap()
        .value;
    let at = p.surface(b).unwrap().icon(icon).unwrap().xyz;
    p.drag(b, icon, at + DVec3::Z * 0.1).unwrap();
    let (sa, sb) = (
        p.surface(a).unwrap().surface(),
        p.surface(b).unwrap().surface(),
    );
    let (g, ang) = seam_gaps(sa, Edge::UMax, sb, Edge::UMin, false, 50);
    assert!(g < 1e-9 * model_size(&p) && ang < 1e-9, "{g} {ang}");
}
