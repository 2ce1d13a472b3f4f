//! A design rebuilt from its document after a pull moves nothing (issue
//! 15: "creating an icon must never move the shape"; the server rebuilds a
//! design from its document at every edit). On flat 100 mm plates of the
//! paper's sizes, four point constraints, a held cubic curve 0.8 mm from
//! one of them and a load are pulled up by a fifth of the plate, released,
//! and the design is built again from its control points and the icons'
//! stored targets, as the server does: no control point may move by more
//! than 1e-9 of the plate's size. Before the curve's handle was a row of
//! its identity, the rebuild found the curve "moved" by the identity's
//! tolerance (~5e-9 mm), and the solve that put it back bent the 20 × 15
//! plate by 1.4e-5 mm; an inside region over the curve, created next, by
//! up to 96 mm on 38 × 32.

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector, greville};
use vsculpt_kernel::design::Design;
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::{Anchor, IconSpec, IconState, Role};

/// The server's flat plate (`server/src/design/demo.rs::plate_part`).
fn plate(nu: usize, nv: usize) -> BSplineSurface {
    let ku = KnotVector::clamped_uniform(3, nu).unwrap();
    let kv = KnotVector::clamped_uniform(3, nv).unwrap();
    let (gu, gv) = (greville(&ku), greville(&kv));
    let pts = gu
        .iter()
        .flat_map(|&s| {
            gv.iter()
                .map(move |&t| DVec3::new(100.0 * s - 50.0, 100.0 * t - 50.0, 0.0))
        })
        .collect();
    BSplineSurface::new(ku, kv, pts).unwrap()
}

fn held() -> BSplineCurve {
    let kv = KnotVector::new(3, vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.]).unwrap();
    let pts = [
        [0.1, 0.12],
        [0.3, 0.3],
        [0.5, 0.05],
        [0.7, 0.35],
        [0.92, 0.15],
    ]
    .iter()
    .map(|p| DVec3::new(p[0], p[1], 0.0))
    .collect();
    BSplineCurve::new(kv, pts).unwrap()
}

fn farthest(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

/// `d` built again from its surface and its icons' stored targets, solved.
fn rebuilt(d: &Design) -> Design {
    let mut e = Design::new(d.surface().clone(), d.material()).unwrap();
    for icon in d.icons() {
        e.add_icon(IconSpec {
            anchor: icon.anchor.clone(),
            role: icon.role,
            state: IconState::Passive,
            target: Some(icon.target),
        })
        .unwrap();
    }
    e.solve().unwrap();
    e
}

#[test]
fn a_rebuild_after_a_pull_moves_nothing_and_a_region_over_the_curve_neither() {
    let size = 100.0 * 2f64.sqrt();
    // The point (0.2, 0.2) is 0.0083 from the curve in (u, v).
    let near = (0..=100_000)
        .map(|i| {
            held()
                .point(i as f64 / 1e5)
                .distance(DVec3::new(0.2, 0.2, 0.0))
        })
        .fold(f64::MAX, f64::min);
    assert!(near < 0.01, "{near}");
    for ((nu, nv), region) in [
        ((20, 15), (0.044, 0.21, 0.433, 0.67)),
        ((38, 32), (0.408, 0.577, 0.153, 0.278)),
        ((42, 40), (0.417, 0.587, 0.136, 0.284)),
    ] {
        let mut d = Design::new(plate(nu, nv), SurfaceMaterial::default()).unwrap();
        let mut add = |anchor, role| {
            d.add_icon(IconSpec {
                anchor,
                role,
                state: IconState::Passive,
                target: None,
            })
            .unwrap()
        };
        for (u, v) in [(0.2, 0.2), (0.8, 0.2), (0.2, 0.8), (0.8, 0.8)] {
            add(Anchor::Point { u, v }, Role::Position);
        }
        add(Anchor::Curve(held()), Role::Position);
        let load = add(Anchor::Point { u: 0.5, v: 0.6 }, Role::Load);
        let from = d.icon(load).unwrap().xyz;
        d.drag_start(load).unwrap();
        for s in 1..=8 {
            d.drag(load, from + DVec3::Z * 0.2 * size * s as f64 / 8.0)
                .unwrap();
        }
        d.release(load).unwrap();
        let bent = d.surface().points().to_vec();
        assert!(farthest(&bent, plate(nu, nv).points()) > 0.05 * size);

        let mut e = rebuilt(&d);
        let moved = farthest(&bent, e.surface().points());
        assert!(
            moved <= 1e-9 * size,
            "{nu}x{nv}: the rebuild moved {moved:e}"
        );

        let (u0, u1, v0, v1) = region;
        e.add_icon(IconSpec {
            anchor: Anchor::Region {
                u0,
                v0,
                u1,
                v1,
                inside: true,
            },
            role: Role::Position,
            state: IconState::Passive,
            target: None,
        })
        .unwrap();
        let report = e.solve().unwrap();
        assert_eq!(report.warning, None);
        let moved = farthest(&bent, e.surface().points());
        assert!(
            moved <= 1e-9 * size,
            "{nu}x{nv}: the region moved {moved:e}"
        );
        let moved = farthest(&bent, rebuilt(&e).surface().points());
        assert!(
            moved <= 1e-9 * size,
            "{nu}x{nv}: its rebuild moved {moved:e}"
        );
    }
}
