//! Icons on a design hold what they promise, with the paper's state semantics.

use glam::DVec3;
use vsculpt_kernel::bspline::{BSplineCurve, BSplineSurface, KnotVector};
use vsculpt_kernel::design::{Design, DesignError};
use vsculpt_kernel::energy::SurfaceMaterial;
use vsculpt_kernel::icon::{Anchor, Derivative, IconId, IconSpec, IconState, Role, SensorId};
use vsculpt_kernel::solve::SolveReport;

fn dome() -> BSplineSurface {
    let mut s = BSplineSurface::plane(2.0, 1.5, 12, 10, 3).unwrap();
    for p in s.points_mut() {
        p.z = 0.3 * (1.0 - ((p.x - 1.0) / 1.0).powi(2)) * (1.0 - ((p.y - 0.75) / 0.75).powi(2));
    }
    s
}

fn design() -> Design {
    Design::new(dome(), SurfaceMaterial::default()).unwrap()
}

fn point(u: f64, v: f64, role: Role) -> IconSpec {
    IconSpec {
        anchor: Anchor::Point { u, v },
        role,
        state: IconState::Passive,
        target: None,
    }
}

fn pin_corners(d: &mut Design) -> Vec<IconId> {
    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .iter()
        .map(|&(u, v)| d.add_icon(point(u, v, Role::Position)).unwrap())
        .collect()
}

#[test]
fn a_design_with_no_loads_stays_as_it_is() {
    let mut d = design();
    pin_corners(&mut d);
    let before = d.surface().clone();
    d.solve().unwrap();
    let err = d
        .surface()
        .points()
        .iter()
        .zip(before.points())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(err < 1e-9, "{err}");
}

#[test]
fn every_point_constraint_holds_its_target() {
    let mut d = design();
    pin_corners(&mut d);
    let pos = d.add_icon(point(0.5, 0.5, Role::Position)).unwrap();
    let tan = d
        .add_icon(point(0.25, 0.6, Role::Derivative(Derivative::R)))
        .unwrap();
    let mut derivs = vec![];
    for (k, which) in [
        Derivative::V,
        Derivative::R2,
        Derivative::V2,
        Derivative::RV,
    ]
    .into_iter()
    .enumerate()
    {
        let id = d
            .add_icon(point(0.7, 0.2 + 0.15 * k as f64, Role::Derivative(which)))
            .unwrap();
        derivs.push((id, which));
    }
    let nrm = d.add_icon(point(0.3, 0.3, Role::Normal)).unwrap();
    let p0 = DVec3::new(1.0, 0.75, 0.6);
    d.set_target(pos, p0).unwrap();
    let t = DVec3::new(2.5, 0.0, 0.8);
    d.set_target(tan, t).unwrap();
    let n = DVec3::new(0.3, -0.2, 1.0).normalize();
    d.set_target(nrm, n).unwrap();
    let mut wanted = vec![];
    for (id, which) in &derivs {
        let target = d.icon(*id).unwrap().target + DVec3::new(0.0, 0.0, 0.2);
        d.set_target(*id, target).unwrap();
        wanted.push((*id, *which, target));
    }
    let report = d.solve().unwrap();
    assert!(report.constraint_residual < 1e-9, "{report:?}");
    let s = d.surface();
    assert!((s.point(0.5, 0.5) - p0).length() < 1e-9);
    assert!((s.derivs(0.25, 0.6).u - t).length() < 1e-9);
    let dv = s.derivs(0.3, 0.3);
    assert!(dv.u.dot(n).abs() < 1e-9 && dv.v.dot(n).abs() < 1e-9);
    for (id, which, target) in wanted {
        let (u, v) = match d.icon(id).unwrap().anchor {
            Anchor::Point { u, v } => (u, v),
            _ => unreachable!(),
        };
        let ds = s.derivs(u, v);
        let got = match which {
            Derivative::V => ds.v,
            Derivative::R2 => ds.uu,
            Derivative::V2 => ds.vv,
            Derivative::RV => ds.uv,
            Derivative::R => ds.u,
        };
        assert!(
            (got - target).length() < 1e-8,
            "{which:?}: {got} vs {target}"
        );
    }
    // The position icon sits on its target.
    assert!((d.icon(pos).unwrap().xyz - p0).length() < 1e-9);
}

#[test]
fn curve_and_region_constraints_interpolate() {
    let mut d = design();
    pin_corners(&mut d);
    let uv = BSplineCurve::new(
        KnotVector::clamped_uniform(2, 3).unwrap(),
        vec![
            DVec3::new(0.2, 0.3, 0.0),
            DVec3::new(0.5, 0.8, 0.0),
            DVec3::new(0.8, 0.4, 0.0),
        ],
    )
    .unwrap();
    let curve = d
        .add_icon(IconSpec {
            anchor: Anchor::Curve(uv.clone()),
            role: Role::Position,
            state: IconState::Passive,
            target: None,
        })
        .unwrap();
    let lift = DVec3::new(0.0, 0.0, 0.25);
    let c0 = d.icon(curve).unwrap().target;
    d.set_target(curve, c0 + lift).unwrap();
    let report = d.solve().unwrap();
    assert!(report.constraint_residual < 1e-8, "{report:?}");
    let s = d.surface().clone();
    // Every sample of the curve moved by `lift`, and points between samples nearly so.
    let before = dome();
    for k in 0..=40 {
        let p = uv.point(k as f64 / 40.0);
        let moved = s.point(p.x, p.y) - before.point(p.x, p.y);
        assert!((moved - lift).length() < 0.02, "curve at {k}: {moved}");
    }
    for &(u, v) in d.icon(curve).unwrap().samples() {
        assert!((s.point(u, v) - before.point(u, v) - lift).length() < 1e-8);
    }
    // A region (on a fresh design: it must not fight the curve for control points).
    let mut d = design();
    pin_corners(&mut d);
    let region = d
        .add_icon(IconSpec {
            anchor: Anchor::Region {
                u0: 0.4,
                v0: 0.35,
                u1: 0.6,
                v1: 0.6,
                inside: true,
            },
            role: Role::Position,
            state: IconState::Passive,
            target: None,
        })
        .unwrap();
    let r0 = d.icon(region).unwrap().target;
    d.set_target(region, r0 - lift).unwrap();
    let report = d.solve().unwrap();
    assert!(report.constraint_residual < 1e-8, "{report:?}");
    let s = d.surface();
    // The whole rectangle moves with its handle (a 41 × 41 grid over it,
    // edges included): the region holds its control points, not samples.
    for i in 0..=40 {
        for j in 0..=40 {
            let (u, v) = (0.4 + 0.2 * i as f64 / 40.0, 0.35 + 0.25 * j as f64 / 40.0);
            let off = (s.point(u, v) - before.point(u, v) + lift).length();
            assert!(off < 1e-12, "inside the region at ({u}, {v}): {off:e}");
        }
    }
}

#[test]
fn loads_push_the_way_the_force_points_and_harder_pushes_further() {
    let mut lift = vec![];
    for pull in [0.05, 0.1] {
        let mut d = design();
        d.set_adaptive_spring(false);
        pin_corners(&mut d);
        let load = d.add_icon(point(0.5, 0.5, Role::Load)).unwrap();
        let start = d.icon(load).unwrap().xyz;
        let rep = d.drag(load, start + DVec3::new(0.0, 0.0, pull)).unwrap();
        let moved = rep.actual - start;
        assert!(moved.z > 0.0, "{moved}");
        // The dome is symmetric about x = 1 (u = 0.5): no sideways motion there.
        assert!(
            moved.x.abs() < 1e-6 && moved.y.abs() < 1e-3 * moved.z,
            "{moved}"
        );
        lift.push(moved.z);
        // Plastic: released, the shape stays and the load is passive.
        let shape = d.surface().clone();
        d.release(load).unwrap();
        assert_eq!(d.icon(load).unwrap().state, IconState::Passive);
        d.solve().unwrap();
        let err = d
            .surface()
            .points()
            .iter()
            .zip(shape.points())
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        assert!(err < 1e-9, "kept after release: {err}");
    }
    assert!((lift[1] / lift[0] - 2.0).abs() < 1e-6, "linear: {lift:?}");
}

#[test]
fn drag_frames_match_discrete_moves() {
    let mut a = design();
    pin_corners(&mut a);
    let id = a.add_icon(point(0.4, 0.6, Role::Position)).unwrap();
    let mut b = Design::from_snapshot(&a.snapshot()).unwrap();
    let target = a.icon(id).unwrap().target + DVec3::new(0.1, -0.05, 0.3);
    for k in 1..=5 {
        a.drag(
            id,
            a.icon(id).unwrap().target * 0.0
                + target * (k as f64 / 5.0)
                + b.icon(id).unwrap().target * (1.0 - k as f64 / 5.0),
        )
        .unwrap();
    }
    b.move_icon(id, target).unwrap();
    let err = a
        .surface()
        .points()
        .iter()
        .zip(b.surface().points())
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
    assert!(err < 1e-9, "{err}");
    assert_eq!(a.icon(id).unwrap().state, IconState::Driving);
    a.release(id).unwrap();
    assert_eq!(a.icon(id).unwrap().state, IconState::Passive);
    // A released constraint keeps holding its dragged target.
    a.solve().unwrap();
    assert!((a.surface().point(0.4, 0.6) - target).length() < 1e-9);
}

#[test]
fn sleeping_icons_have_no_effect_and_follow_the_surface() {
    let mut with = design();
    let mut without = design();
    for d in [&mut with, &mut without] {
        pin_corners(d);
    }
    let sleeper = with.add_icon(point(0.6, 0.4, Role::Position)).unwrap();
    with.set_state(sleeper, IconState::Sleeping).unwrap();
    with.set_target(sleeper, DVec3::new(5.0, 5.0, 5.0)).unwrap();
    let passive_load = with.add_icon(point(0.3, 0.7, Role::Load)).unwrap();
    for d in [&mut with, &mut without] {
        let id = d.add_icon(point(0.5, 0.5, Role::Position)).unwrap();
        let t = d.icon(id).unwrap().target + DVec3::new(0.0, 0.0, 0.2);
        d.set_target(id, t).unwrap();
        d.solve().unwrap();
    }
    assert_eq!(with.surface().points(), without.surface().points());
    // Sleeping and passive-load icons were re-placed on the moved surface.
    assert!((with.icon(sleeper).unwrap().xyz - with.surface().point(0.6, 0.4)).length() < 1e-12);
    assert!(
        (with.icon(passive_load).unwrap().xyz - with.surface().point(0.3, 0.7)).length() < 1e-12
    );
    assert!((with.surface().point(0.3, 0.7) - dome().point(0.3, 0.7)).length() > 1e-3);
}

#[test]
fn switching_role_and_state_is_one_call() {
    let mut d = design();
    pin_corners(&mut d);
    let id = d.add_icon(point(0.5, 0.5, Role::Load)).unwrap();
    d.set_role(id, Role::Position).unwrap();
    let p = d.icon(id).unwrap().target + DVec3::new(0.0, 0.0, 0.1);
    d.set_target(id, p).unwrap();
    d.solve().unwrap();
    assert!((d.surface().point(0.5, 0.5) - p).length() < 1e-9);
    d.set_role(id, Role::Normal).unwrap();
    let n = d.icon(id).unwrap().target;
    assert!((n - d.surface().normal(0.5, 0.5)).length() < 1e-12);
    d.set_role(id, Role::Derivative(Derivative::V)).unwrap();
    d.set_state(id, IconState::Sleeping).unwrap();
    assert_eq!(d.icon(id).unwrap().state, IconState::Sleeping);
    d.bind_sensor(id, SensorId("right-hand".into())).unwrap();
    assert_eq!(d.icon(id).unwrap().state, IconState::Driving);
    d.unbind_sensor(id, &SensorId("right-hand".into())).unwrap();
    assert_eq!(d.icon(id).unwrap().state, IconState::Passive);
    // Derivative and normal roles need a point.
    let region = d
        .add_icon(IconSpec {
            anchor: Anchor::Region {
                u0: 0.1,
                v0: 0.1,
                u1: 0.3,
                v1: 0.3,
                inside: true,
            },
            role: Role::Load,
            state: IconState::Passive,
            target: None,
        })
        .unwrap();
    assert!(matches!(
        d.set_role(region, Role::Normal),
        Err(DesignError::Unsupported(_))
    ));
}

#[test]
fn bad_input_changes_nothing_and_snapshots_round_trip() {
    let mut d = design();
    pin_corners(&mut d);
    let id = d.add_icon(point(0.5, 0.5, Role::Position)).unwrap();
    d.solve().unwrap();
    let snap = d.snapshot();
    assert!(matches!(
        d.add_icon(point(1.5, 0.5, Role::Load)),
        Err(DesignError::OutOfDomain(..))
    ));
    assert!(matches!(
        d.add_icon(point(f64::NAN, 0.5, Role::Load)),
        Err(DesignError::OutOfDomain(..))
    ));
    assert!(matches!(
        d.set_target(id, DVec3::new(f64::INFINITY, 0.0, 0.0)),
        Err(DesignError::NotFinite(_))
    ));
    assert!(matches!(
        d.drag(id, DVec3::splat(f64::NAN)),
        Err(DesignError::NotFinite(_))
    ));
    assert!(matches!(
        d.move_icon(IconId(999), DVec3::ZERO),
        Err(DesignError::UnknownIcon(_))
    ));
    assert!(matches!(
        d.set_state(IconId(999), IconState::Sleeping),
        Err(DesignError::UnknownIcon(_))
    ));
    let bad = SurfaceMaterial {
        beta11: -1.0,
        ..Default::default()
    };
    assert!(d.set_material(bad).is_err());
    assert_eq!(d.snapshot(), snap);
    // Edit, then restore the snapshot: exactly the old design.
    let t = d.icon(id).unwrap().target + DVec3::Z * 0.2;
    d.move_icon(id, t).unwrap();
    assert_ne!(d.snapshot(), snap);
    d.restore(&snap).unwrap();
    assert_eq!(d.snapshot(), snap);
    d.solve().unwrap();
    assert_eq!(d.surface(), &snap.surface);
}

#[test]
fn the_spring_adapts_into_the_band_on_soft_and_stiff_surfaces() {
    // κ has to change by up to 1e9 from its start (β = 1e6 from κ = 1e-3,
    // β = 1e-4 from κ = 1e3): four steps of at most 100× were not enough
    // (β = 1e6 landed at 0.173).
    for (beta, kappa) in [
        (0.01, 1e-3),
        (1.0, 1e-3),
        (100.0, 1e-3),
        (1e6, 1e-3),
        (1e-4, 1e3),
    ] {
        let m = SurfaceMaterial {
            beta11: beta,
            beta12: beta,
            beta22: beta,
            ..Default::default()
        };
        let mut d = Design::new(dome(), m).unwrap();
        pin_corners(&mut d);
        let load = d.add_icon(point(0.5, 0.5, Role::Load)).unwrap();
        d.set_kappa(kappa).unwrap();
        let start = d.icon(load).unwrap().xyz;
        let hand = start + DVec3::new(0.0, 0.0, 0.1);
        // The adaptation runs inside the frame: the first frame already lands in the band.
        let r = d.drag(load, hand).unwrap();
        let ratio = (r.actual - start).length() / 0.1;
        assert!((0.8..=1.2).contains(&ratio), "β = {beta}: ratio {ratio}");
    }
}

#[test]
fn refining_keeps_shape_and_icons() {
    let mut d = design();
    pin_corners(&mut d);
    let id = d.add_icon(point(0.5, 0.5, Role::Position)).unwrap();
    let t = d.icon(id).unwrap().target + DVec3::Z * 0.1;
    d.move_icon(id, t).unwrap();
    let before = d.surface().clone();
    d.refine().unwrap();
    assert_eq!(d.surface().nu(), before.nu() + 9);
    for k in 0..=20 {
        let (u, v) = (k as f64 / 20.0, 1.0 - k as f64 / 20.0);
        assert!((d.surface().point(u, v) - before.point(u, v)).length() < 1e-12);
    }
    d.solve().unwrap();
    assert!((d.surface().point(0.5, 0.5) - t).length() < 1e-9);
    assert!(d.insert_knot(true, f64::NAN).is_err());
}

#[test]
fn tessellation_samples_the_current_surface() {
    let mut d = design();
    let id = d.add_icon(point(0.5, 0.5, Role::Position)).unwrap();
    d.move_icon(id, DVec3::new(1.0, 0.75, 0.6)).unwrap();
    let t = d.tessellate(5, 0);
    assert_eq!((t.samples_u, t.samples_v), (5, 2));
    assert_eq!(t.positions.len(), 10);
    // Vertex (a, b) sits at u = a/4, v = b on the solved surface.
    for a in 0..5 {
        for b in 0..2 {
            let (u, v) = (a as f64 / 4.0, b as f64);
            let want = d.surface().point(u, v);
            let got = t.positions[a * 2 + b];
            let got = DVec3::new(got[0] as f64, got[1] as f64, got[2] as f64);
            assert!((got - want).length() < 1e-5, "({u}, {v}): {got} vs {want}");
        }
    }
}

/// The paper's scene (bench `sculpt`): a wavy `nu × nv` sheet with four pinned
/// points, a curve constraint and a load dragged up, then released, and a
/// fifth point switched on and lifted. Returns the design and its last
/// solve's report.
fn paper_scene(nu: usize, nv: usize) -> (Design, SolveReport) {
    let (w, h) = (nu as f64 / 10.0, nv as f64 / 10.0);
    let mut s = BSplineSurface::plane(w, h, nu, nv, 3).unwrap();
    for p in s.points_mut() {
        p.z = 0.2
            * w.min(h)
            * (std::f64::consts::PI * p.x / w).sin()
            * (std::f64::consts::PI * p.y / h).sin();
    }
    let mut d = Design::new(s, SurfaceMaterial::default()).unwrap();
    d.set_adaptive_spring(false);
    for (u, v) in [(0.1, 0.1), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)] {
        d.add_icon(point(u, v, Role::Position)).unwrap();
    }
    let line = BSplineCurve::new(
        KnotVector::clamped_uniform(1, 2).unwrap(),
        vec![DVec3::new(0.2, 0.25, 0.0), DVec3::new(0.8, 0.25, 0.0)],
    )
    .unwrap();
    d.add_icon(IconSpec {
        anchor: Anchor::Curve(line),
        role: Role::Position,
        state: IconState::Passive,
        target: None,
    })
    .unwrap();
    let load = d.add_icon(point(0.5, 0.6, Role::Load)).unwrap();
    d.solve().unwrap();
    let start = d.icon(load).unwrap().xyz;
    d.drag(load, start + DVec3::Z * 0.05 * w.min(h)).unwrap();
    d.release(load).unwrap();
    let pin = d.add_icon(point(0.3, 0.7, Role::Position)).unwrap();
    d.set_target(pin, d.icon(pin).unwrap().xyz + DVec3::new(0.0, 0.0, 0.01))
        .unwrap();
    let report = d.solve().unwrap();
    (d, report)
}

#[test]
fn the_papers_scene_holds_every_curve_sample_with_no_equation_dropped() {
    for (nu, nv) in [(20, 15), (81, 159)] {
        let (d, report) = paper_scene(nu, nv);
        // Every equation (four pins, the lifted pin, every curve sample)
        // holds and none was dropped as redundant: the curve's samples are
        // sparse enough for S to stay well conditioned.
        assert!(report.constraint_residual < 1e-9, "{nu}x{nv}: {report:?}");
        assert_eq!(report.rank_deficiency, 0, "{nu}x{nv}: {report:?}");
        let curve = d.icons().nth(4).unwrap();
        assert!(curve.samples().len() >= 2, "{nu}x{nv}");
        // The lifted pin sits on its new target.
        let pin = d.icons().last().unwrap();
        assert!((pin.xyz - pin.target).length() < 1e-9, "{nu}x{nv}");
    }
}
